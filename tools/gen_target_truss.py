#!/usr/bin/env python3
"""Writes assets/vehicles/target_truss.obj: the example target of docs/vehicles.md.

A spacecraft as a CAD export would give it, one OBJ object per component (each becomes a
collider named by the object, e.g. `target/solar_array_py_2`), in the body frame of the
flagship's target (scenes/examples/orbit_approach_latch.ron), metres:

* `bus`            a 1.6 x 1.5 x 1.5 m box centred on the origin, its faces subdivided;
* `docking_port`   a collar (a ring 0.26-0.34 m in radius, x 0.80-0.86 m) around the +x port,
                   leaving the port's docking slot (a primitive part of the scene) free;
* `truss`          a 3 m square lattice beam (0.4 m wide) from the bus's -x face along -x:
                   4 longerons, battens every 0.5 m and one diagonal per bay face, struts as
                   closed 12-sided tubes (radius 2 cm);
* `dish`           a 2 m paraboloid reflector (focal length 0.8 m, 2 cm thick, closed shell)
                   at the truss end, facing -x;
* `solar_array_py_1..3`, `solar_array_my_1..3`  three 1.2 x 1.0 x 0.03 m panels per wing
                   along +y and -y, 5 cm gaps between panels, 0.5 m from the bus, each a
                   closed box with its faces subdivided into 12 x 10 cells;
* `boom_py`, `boom_my`  the array booms (closed 12-sided tubes, radius 3 cm).

Every object is a closed, outward-oriented triangle mesh. The output is deterministic (fixed
formatting, no randomness): running the script twice gives the same bytes.

Usage: python3 tools/gen_target_truss.py [OUT]   (default: assets/vehicles/target_truss.obj)
"""

import math
import os
import sys


class Obj:
    def __init__(self):
        self.lines = []
        self.nv = 0
        self.nt = 0

    def obj(self, name, verts, tris):
        self.lines.append("o %s" % name)
        for v in verts:
            self.lines.append("v %.6f %.6f %.6f" % v)
        for a, b, c in tris:
            self.lines.append("f %d %d %d" % (a + self.nv + 1, b + self.nv + 1, c + self.nv + 1))
        self.nv += len(verts)
        self.nt += len(tris)


def box(lo, hi, n=(1, 1, 1)):
    """Closed box with each face divided into a grid (n cells per axis); outward triangles.
    Vertices are shared along the edges, so the mesh is watertight."""
    nx, ny, nz = n
    index = {}
    verts = []

    def vid(i, j, k):
        key = (i, j, k)
        if key not in index:
            index[key] = len(verts)
            verts.append((
                lo[0] + (hi[0] - lo[0]) * i / nx,
                lo[1] + (hi[1] - lo[1]) * j / ny,
                lo[2] + (hi[2] - lo[2]) * k / nz,
            ))
        return index[key]

    tris = []

    def quad(a, b, c, d):
        tris.append((a, b, c))
        tris.append((a, c, d))

    for i in range(nx):
        for j in range(ny):
            quad(vid(i, j, 0), vid(i, j + 1, 0), vid(i + 1, j + 1, 0), vid(i + 1, j, 0))  # -z
            quad(vid(i, j, nz), vid(i + 1, j, nz), vid(i + 1, j + 1, nz), vid(i, j + 1, nz))  # +z
    for i in range(nx):
        for k in range(nz):
            quad(vid(i, 0, k), vid(i + 1, 0, k), vid(i + 1, 0, k + 1), vid(i, 0, k + 1))  # -y
            quad(vid(i, ny, k), vid(i, ny, k + 1), vid(i + 1, ny, k + 1), vid(i + 1, ny, k))  # +y
    for j in range(ny):
        for k in range(nz):
            quad(vid(0, j, k), vid(0, j, k + 1), vid(0, j + 1, k + 1), vid(0, j + 1, k))  # -x
            quad(vid(nx, j, k), vid(nx, j + 1, k), vid(nx, j + 1, k + 1), vid(nx, j, k + 1))  # +x
    return verts, tris


def sub(a, b):
    return (a[0] - b[0], a[1] - b[1], a[2] - b[2])


def cross(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def norm(a):
    n = math.sqrt(a[0] ** 2 + a[1] ** 2 + a[2] ** 2)
    return (a[0] / n, a[1] / n, a[2] / n)


def tube(p, q, r, sides=12):
    """Closed tube of radius r from p to q (end caps as fans)."""
    axis = norm(sub(q, p))
    helper = (1.0, 0.0, 0.0) if abs(axis[0]) < 0.9 else (0.0, 1.0, 0.0)
    u = norm(cross(axis, helper))
    w = cross(axis, u)
    verts = []
    for end in (p, q):
        for k in range(sides):
            t = 2.0 * math.pi * k / sides
            c, s = math.cos(t), math.sin(t)
            verts.append(tuple(end[i] + r * (c * u[i] + s * w[i]) for i in range(3)))
    verts.append(p)
    verts.append(q)
    cp, cq = 2 * sides, 2 * sides + 1
    tris = []
    for k in range(sides):
        a, b = k, (k + 1) % sides
        tris.append((a, b, sides + b))
        tris.append((a, sides + b, sides + a))
        tris.append((cp, b, a))
        tris.append((cq, sides + a, sides + b))
    return verts, tris


def merge(parts):
    verts, tris = [], []
    for v, t in parts:
        base = len(verts)
        verts.extend(v)
        tris.extend((a + base, b + base, c + base) for a, b, c in t)
    return verts, tris


def ring(x0, x1, r_in, r_out, segments=64):
    """Closed annular collar about the x axis."""
    verts = []
    for x in (x0, x1):
        for r in (r_in, r_out):
            for k in range(segments):
                t = 2.0 * math.pi * k / segments
                verts.append((x, r * math.cos(t), r * math.sin(t)))
    idx = lambda e, i, k: (e * 2 + i) * segments + k % segments  # noqa: E731
    tris = []

    def quad(a, b, c, d):
        tris.append((a, b, c))
        tris.append((a, c, d))

    for k in range(segments):
        quad(idx(1, 1, k), idx(0, 1, k), idx(0, 1, k + 1), idx(1, 1, k + 1))  # outer wall
        quad(idx(0, 0, k), idx(1, 0, k), idx(1, 0, k + 1), idx(0, 0, k + 1))  # inner wall
        quad(idx(0, 0, k), idx(0, 0, k + 1), idx(0, 1, k + 1), idx(0, 1, k))  # -x face
        quad(idx(1, 0, k), idx(1, 1, k), idx(1, 1, k + 1), idx(1, 0, k + 1))  # +x face
    return verts, tris


def dish(x_vertex, diameter, focal, thickness, az=128, radial=48):
    """Closed paraboloid shell about the x axis opening towards -x: the reflecting surface
    x = x_vertex - rho^2 / (4 f), and a back surface `thickness` behind it (+x), joined at
    the rim; the centre is closed by fans."""
    R = diameter / 2.0
    verts = []
    for layer, dx in ((0, 0.0), (1, thickness)):
        verts.append((x_vertex + dx, 0.0, 0.0))  # centre of the layer
        for i in range(1, radial + 1):
            rho = R * i / radial
            for k in range(az):
                t = 2.0 * math.pi * k / az
                verts.append((x_vertex + dx - rho * rho / (4.0 * focal),
                              rho * math.cos(t), rho * math.sin(t)))
    per = 1 + radial * az
    ring_id = lambda layer, i, k: layer * per + 1 + (i - 1) * az + k % az  # noqa: E731
    tris = []
    for layer, sign in ((0, 1), (1, -1)):
        c = layer * per

        def tri(a, b, d):
            tris.append((a, b, d) if sign > 0 else (a, d, b))

        for k in range(az):
            tri(c, ring_id(layer, 1, k + 1), ring_id(layer, 1, k))
        for i in range(1, radial):
            for k in range(az):
                a, b = ring_id(layer, i, k), ring_id(layer, i, k + 1)
                d, e = ring_id(layer, i + 1, k), ring_id(layer, i + 1, k + 1)
                tri(a, b, e)
                tri(a, e, d)
    for k in range(az):  # rim
        a, b = ring_id(0, radial, k), ring_id(0, radial, k + 1)
        d, e = ring_id(1, radial, k), ring_id(1, radial, k + 1)
        tris.append((a, b, e))
        tris.append((a, e, d))
    return verts, tris


def truss(x0, length, width, r, bay=0.5):
    h = width / 2.0
    corners = [(h, h), (-h, h), (-h, -h), (h, -h)]
    stations = int(round(length / bay))
    parts = []
    x_end = x0 - length
    for y, z in corners:
        parts.append(tube((x0, y, z), (x_end, y, z), r))
    for s in range(stations + 1):
        x = x0 - s * bay
        for k in range(4):
            (y0, z0), (y1, z1) = corners[k], corners[(k + 1) % 4]
            parts.append(tube((x, y0, z0), (x, y1, z1), r))
    for s in range(stations):
        xa, xb = x0 - s * bay, x0 - (s + 1) * bay
        for k in range(4):
            (y0, z0), (y1, z1) = corners[k], corners[(k + 1) % 4]
            if s % 2 == 0:
                parts.append(tube((xa, y0, z0), (xb, y1, z1), r))
            else:
                parts.append(tube((xa, y1, z1), (xb, y0, z0), r))
    return parts


def main():
    out = sys.argv[1] if len(sys.argv) > 1 else os.path.join(
        os.path.dirname(os.path.abspath(__file__)), "..", "assets", "vehicles", "target_truss.obj")
    o = Obj()
    o.lines.append("# target_truss.obj: written by tools/gen_target_truss.py (do not edit)")
    o.obj("bus", *box((-0.8, -0.75, -0.75), (0.8, 0.75, 0.75), (8, 8, 8)))
    o.obj("docking_port", *ring(0.80, 0.86, 0.26, 0.34))
    # The truss's struts are separate closed tubes (they cross at the nodes): one object.
    o.obj("truss", *merge(truss(-0.8, 3.0, 0.4, 0.02)))
    o.obj("dish", *dish(-3.8, 2.0, 0.8, 0.02))
    for side, sgn in (("py", 1.0), ("my", -1.0)):
        y_root = sgn * 0.75
        o.obj("boom_%s" % side, *tube((0.0, y_root, 0.0), (0.0, y_root + sgn * 0.5, 0.0), 0.03))
        for k in range(3):
            inner = 0.75 + 0.5 + k * (1.2 + 0.05)
            y0, y1 = sgn * inner, sgn * (inner + 1.2)
            lo = (-0.015, min(y0, y1), -0.5)
            hi = (0.015, max(y0, y1), 0.5)
            o.obj("solar_array_%s_%d" % (side, k + 1), *box(lo, hi, (1, 12, 10)))
    os.makedirs(os.path.dirname(os.path.abspath(out)), exist_ok=True)
    with open(out, "w", newline="\n") as f:
        f.write("\n".join(o.lines) + "\n")
    print("%s: %d vertices, %d triangles" % (out, o.nv, o.nt))


if __name__ == "__main__":
    main()
