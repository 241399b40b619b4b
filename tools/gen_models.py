#!/usr/bin/env python3
"""Writes the glTF models under assets/models/ (run from the repository root; stdlib only).

hga_dish.gltf — a high-gain antenna: a paraboloid reflector z = r²/(4f) of radius 0.30 m and
depth 0.06 m (f = 0.375 m), and a feed post (radius 15 mm) carrying a 50 mm sub-reflector
disc at 0.085 m. Model frame: +z is the boresight, the origin is the reflector's vertex,
metres. Two meshes of one primitive each (reflector, feed). The whole model fits in a
cylinder of radius 0.30 m and length 0.085 m about +z, so it sits inside the 0.30 m × 0.10 m
cylinder collider of `free_drift`'s antenna, which the monitor checks.
"""
import base64
import json
import math
import struct

R, DEPTH = 0.30, 0.06
F = R * R / (4.0 * DEPTH)
RINGS, SEGS = 12, 48
POST_R, POST_H, SUB_R, POST_SEGS = 0.015, 0.085, 0.05, 16


def reflector():
    pos, nrm, idx = [(0.0, 0.0, 0.0)], [(0.0, 0.0, 1.0)], []
    for i in range(1, RINGS + 1):
        r = R * i / RINGS
        for k in range(SEGS):
            a = 2.0 * math.pi * k / SEGS
            x, y = r * math.cos(a), r * math.sin(a)
            pos.append((x, y, r * r / (4.0 * F)))
            n = (-x / (2.0 * F), -y / (2.0 * F), 1.0)
            m = math.sqrt(sum(c * c for c in n))
            nrm.append(tuple(c / m for c in n))
    ring = lambda i, k: 1 + (i - 1) * SEGS + (k % SEGS)
    for k in range(SEGS):
        idx += [0, ring(1, k), ring(1, k + 1)]
    for i in range(1, RINGS):
        for k in range(SEGS):
            a, b, c, d = ring(i, k), ring(i, k + 1), ring(i + 1, k), ring(i + 1, k + 1)
            idx += [a, c, d, a, d, b]
    return pos, nrm, idx


def feed():
    pos, nrm, idx = [], [], []
    for k in range(POST_SEGS):
        a = 2.0 * math.pi * k / POST_SEGS
        c, s = math.cos(a), math.sin(a)
        for z in (0.0, POST_H):
            pos.append((POST_R * c, POST_R * s, z))
            nrm.append((c, s, 0.0))
    for k in range(POST_SEGS):
        a0, a1 = 2 * k, 2 * ((k + 1) % POST_SEGS)
        idx += [a0, a1, a0 + 1, a1, a1 + 1, a0 + 1]
    centre = len(pos)
    pos.append((0.0, 0.0, POST_H))
    nrm.append((0.0, 0.0, -1.0))
    for k in range(SEGS):
        a = 2.0 * math.pi * k / SEGS
        pos.append((SUB_R * math.cos(a), SUB_R * math.sin(a), POST_H))
        nrm.append((0.0, 0.0, -1.0))
    for k in range(SEGS):
        idx += [centre, centre + 1 + (k + 1) % SEGS, centre + 1 + k]
    return pos, nrm, idx


def main():
    blob = bytearray()
    views, accessors, meshes = [], [], []

    def add(data, fmt, target):
        while len(blob) % 4:
            blob.append(0)
        off = len(blob)
        for d in data:
            blob.extend(struct.pack(fmt, *d) if isinstance(d, tuple) else struct.pack(fmt, d))
        views.append({"buffer": 0, "byteOffset": off, "byteLength": len(blob) - off, "target": target})
        return len(views) - 1

    for name, (pos, nrm, idx), mat in (("reflector", reflector(), 0), ("feed", feed(), 1)):
        vp = add(pos, "<3f", 34962)
        accessors.append({
            "bufferView": vp, "componentType": 5126, "count": len(pos), "type": "VEC3",
            "min": [min(p[i] for p in pos) for i in range(3)],
            "max": [max(p[i] for p in pos) for i in range(3)],
        })
        vn = add(nrm, "<3f", 34962)
        accessors.append({"bufferView": vn, "componentType": 5126, "count": len(nrm), "type": "VEC3"})
        vi = add(idx, "<H", 34963)
        accessors.append({"bufferView": vi, "componentType": 5123, "count": len(idx), "type": "SCALAR"})
        a = len(accessors)
        meshes.append({"name": name, "primitives": [{
            "attributes": {"POSITION": a - 3, "NORMAL": a - 2}, "indices": a - 1, "material": mat}]})

    gltf = {
        "asset": {"version": "2.0", "generator": "rpod tools/gen_models.py"},
        "scene": 0,
        "scenes": [{"name": "hga_dish", "nodes": [0]}],
        "nodes": [
            {"name": "hga_dish", "children": [1, 2]},
            {"name": "reflector", "mesh": 0},
            {"name": "feed", "mesh": 1},
        ],
        "meshes": meshes,
        "materials": [
            {"name": "reflector_paint", "doubleSided": True, "pbrMetallicRoughness": {
                "baseColorFactor": [0.93, 0.93, 0.90, 1.0], "metallicFactor": 0.0, "roughnessFactor": 0.7}},
            {"name": "feed_dark", "doubleSided": True, "pbrMetallicRoughness": {
                "baseColorFactor": [0.25, 0.25, 0.28, 1.0], "metallicFactor": 0.4, "roughnessFactor": 0.5}},
        ],
        "accessors": accessors,
        "bufferViews": views,
        "buffers": [{"byteLength": len(blob),
                     "uri": "data:application/octet-stream;base64," + base64.b64encode(bytes(blob)).decode()}],
    }
    with open("assets/models/hga_dish.gltf", "w") as f:
        json.dump(gltf, f, indent=1)
        f.write("\n")


if __name__ == "__main__":
    main()
