#!/usr/bin/env python3
"""Independent cross-check of rpod's docking mechanism against MuJoCo.

Not part of the default tests: it needs MuJoCo's Python package, installed once at set-up
time into a venv of your own:

    python3 -m venv .venv-mujoco && .venv-mujoco/bin/pip install mujoco numpy
    rpod trials scenes/trials/capture_envelope.ron --out out/envelope
    rpod run scenes/examples/docking_aligned.ron --out out/docking_aligned
    .venv-mujoco/bin/python tools/crosscheck_mujoco.py out/envelope/trials.csv out/docking_aligned/summary.json

What is the same as rpod: the geometry of the mechanism, rebuilt here from the scene's numbers
as in src/scene/parts.rs (the 32-sided cone hull on the chaser's port, the 12 convex wall
pieces of the funnel and the back plate on the target's port, both buses; the solar wings are
left out: no trial of the envelope touches them), the masses and inertias, the magnet law
F = min(F0/(1 + gap/g0)^2, F_max) switched on below 0.1 m and applied at the chaser port with
its reaction on the target, the latch rule (seated within 5 mm axial, 3 cm lateral, 5 deg for
0.2 s), and the outcome rules (MISSED on a collision of other parts or on passing beside the
mouth, JAMMED in contact below 1 mm/s for 5 s, REBOUND when a chaser that touched the slot
separates at the end). What is MuJoCo's own: its contact detection (convex hulls via its
native collision), its soft-constraint solver and contact model (here solref = (-k, -b):
stiffness 3.2e7 N/m and a damping that gives a restitution of about 0.3 for the aligned impact,
comparable with the scene's compliant law), its integrator (1 ms steps) and friction (the
average of the two bodies' coefficients, as rapier's rule).

Prints the outcome-agreement table (markdown) and the aligned impact's impulse and peak force.
"""

import csv
import json
import math
import sys

import mujoco
import numpy as np

SEG = 32
WALLS = 12
PORT_T = np.array([0.82, 0.0, 0.0])
PORT_C = np.array([0.5, 0.0, 0.0])
MOUTH, THROAT, DEPTH, WALL = 0.15, 0.04, 0.2, 0.02
CONE_BASE, CONE_TIP, CONE_LEN = 0.12, 0.03, 0.25
SEAT = 0.25
F0, G0, FMAX, ACT = 2.0, 0.05, 5.0, 0.1
AX_TOL, LAT_TOL, ANG_TOL, DWELL = 0.005, 0.03, 5.0, 0.2
JAM_T, JAM_V, REB_V = 5.0, 1e-3, 1e-5
DT = 0.001
M_C, M_T = 300.0, 800.0
K_CONTACT = 3.2e7  # N/m, on the aligned impact's reduced mass (MuJoCo's solref is per unit mass)


def radial(phi):
    return np.array([0.0, math.cos(phi), math.sin(phi)])


def cone_vertices():
    pts = []
    for k in range(SEG):
        r = radial(2 * math.pi * k / SEG)
        pts.append(PORT_C + r * CONE_BASE)
        pts.append(PORT_C + r * CONE_TIP + np.array([CONE_LEN, 0, 0]))
    return pts


def wall_vertices(k):
    pts = []
    for j in (k, k + 1):
        r = radial(2 * math.pi * j / WALLS)
        for h, rad in ((0.0, THROAT), (DEPTH, MOUTH)):
            r_in = rad / math.cos(math.pi / WALLS)
            pts.append(PORT_T + r * r_in + np.array([h, 0, 0]))
            pts.append(PORT_T + r * (r_in + WALL) + np.array([h, 0, 0]))
    return pts


def mesh(name, pts):
    v = " ".join(f"{p[0]:.9f} {p[1]:.9f} {p[2]:.9f}" for p in pts)
    return f'<mesh name="{name}" vertex="{v}"/>'


def model_xml(friction, damping):
    meshes = [mesh("cone", cone_vertices())] + [mesh(f"wall{k+1}", wall_vertices(k)) for k in range(WALLS)]
    back_r = (THROAT + WALL) / math.cos(math.pi / WALLS) + WALL
    # MuJoCo's negative solref is (stiffness, damping) of the reference acceleration, i.e. per
    # unit of the contact's effective mass: divide by the aligned impact's reduced mass.
    m_red = M_C * M_T / (M_C + M_T)
    sol = f'solref="{-K_CONTACT / m_red} {-damping / m_red}" solimp="0.95 0.95 0.001" friction="{friction} 0.005 0.0001" condim="3"'
    walls = "\n".join(
        f'<geom name="wall{k+1}" type="mesh" mesh="wall{k+1}" contype="1" conaffinity="2" {sol}/>' for k in range(WALLS)
    )
    return f"""
<mujoco>
  <option timestep="{DT}" gravity="0 0 0" integrator="implicitfast" cone="elliptic"/>
  <asset>{''.join(meshes)}</asset>
  <worldbody>
    <body name="target" pos="0 0 0">
      <freejoint/>
      <inertial pos="0 0 0" mass="{M_T}" diaginertia="620 910 1080"/>
      <geom name="tbus" type="box" size="0.8 0.75 0.75" contype="4" conaffinity="8" {sol}/>
      {walls}
      <geom name="back" type="cylinder" fromto="0.80 0 0 0.82 0 0" size="{back_r}" contype="1" conaffinity="2" {sol}/>
    </body>
    <body name="chaser" pos="2.07 0 0">
      <freejoint/>
      <inertial pos="0 0 0" mass="{M_C}" diaginertia="110 140 160"/>
      <geom name="cbus" type="box" size="0.5 0.5 0.5" contype="8" conaffinity="5" {sol}/>
      <geom name="cone" type="mesh" mesh="cone" contype="2" conaffinity="5" {sol}/>
    </body>
  </worldbody>
</mujoco>"""


def quat_rotate(q, v):
    out = np.zeros(3)
    mujoco.mju_rotVecQuat(out, v, q)
    return out


def run_trial(lateral, yaw_deg, vx, target_friction, t_end=50.0, record=False):
    friction = 0.5 * (target_friction + 0.2)
    # Damping of the spring–dashpot that gives e ≈ 0.3 on the aligned impact (m_red ≈ 218 kg):
    # zeta from e = exp(-zeta*pi/sqrt(1 - zeta^2)).
    m_red = M_C * M_T / (M_C + M_T)
    zeta = 0.358
    damping = 2 * zeta * math.sqrt(K_CONTACT * m_red)
    m = mujoco.MjModel.from_xml_string(model_xml(friction, damping))
    d = mujoco.MjData(m)
    ct, cc = m.body("target").id, m.body("chaser").id
    qa = m.jnt_qposadr[m.body_jntadr[cc]]
    va = m.jnt_dofadr[m.body_jntadr[cc]]
    d.qpos[qa : qa + 3] = [2.07, lateral, 0.0]
    h = math.radians(yaw_deg) / 2
    d.qpos[qa + 3 : qa + 7] = [math.cos(h), 0, 0, math.sin(h)]
    d.qvel[va : va + 3] = [vx, 0, 0]
    mujoco.mj_forward(m, d)
    cone, cbus, tbus = m.geom("cone").id, m.geom("cbus").id, m.geom("tbus").id
    slot = {m.geom(f"wall{k+1}").id for k in range(WALLS)} | {m.geom("back").id}
    chaser_geoms = {cone, cbus}
    magnet = False
    touched = False
    seated_since = None
    jam_since = None
    last_contact_t = None
    prev_axial = None
    impulse = np.zeros(3)
    peak = 0.0
    t_first = None
    steps = int(round(t_end / DT))
    for i in range(steps):
        t = i * DT
        pt, pc = d.xpos[ct].copy(), d.xpos[cc].copy()
        qt, qc = d.xquat[ct].copy(), d.xquat[cc].copy()
        at = quat_rotate(qt, np.array([1.0, 0, 0]))
        ac = quat_rotate(qc, np.array([1.0, 0, 0]))
        port_t = pt + quat_rotate(qt, PORT_T)
        port_c = pc + quat_rotate(qc, PORT_C)
        dvec = port_c - port_t
        axial = dvec @ at - SEAT
        lateral_off = np.linalg.norm(dvec - at * (dvec @ at))
        gap = np.linalg.norm(port_c - (port_t + at * SEAT))
        mis = math.degrees(math.acos(max(-1.0, min(1.0, ac @ (-at)))))
        # Relative velocity of the chaser port point.
        vel_c, vel_t = np.zeros(6), np.zeros(6)
        mujoco.mj_objectVelocity(m, d, mujoco.mjtObj.mjOBJ_BODY, cc, vel_c, 0)
        mujoco.mj_objectVelocity(m, d, mujoco.mjtObj.mjOBJ_BODY, ct, vel_t, 0)
        vpc = vel_c[3:] + np.cross(vel_c[:3], port_c - pc)
        vpt = vel_t[3:] + np.cross(vel_t[:3], port_c - pt)
        vrel = vpc - vpt
        axial_rate = vrel @ at
        # Contacts.
        in_contact = False
        for k in range(d.ncon):
            c = d.contact[k]
            g1, g2 = c.geom1, c.geom2
            b1, b2 = m.geom_bodyid[g1], m.geom_bodyid[g2]
            if {b1, b2} != {ct, cc} or c.dist > 0:
                continue
            pair = {g1, g2}
            if cone in pair and pair & slot:
                in_contact = True
            else:
                return ("MISSED", None, impulse, peak, t_first, "collision")
        if in_contact:
            touched = True
            last_contact_t = t
            if t_first is None:
                t_first = t
        docking_contact = last_contact_t is not None and t - last_contact_t <= 0.1 + 1e-9
        if not magnet and gap < ACT:
            magnet = True
        seated = abs(axial) <= AX_TOL and lateral_off <= LAT_TOL and mis <= ANG_TOL
        crossed = prev_axial is not None and prev_axial >= 0
        prev_axial = axial
        if axial < 0 and crossed and lateral_off > MOUTH:
            return ("MISSED", None, impulse, peak, t_first, "passed beside")
        if not touched and axial_rate > REB_V and lateral_off > MOUTH and gap < 1.0:
            return ("MISSED", None, impulse, peak, t_first, "turned away")
        if seated and (docking_contact or seated_since is not None):
            if seated_since is None:
                seated_since = t
            elif t - seated_since >= DWELL - 1e-9:
                return ("LATCHED", t, impulse, peak, t_first, "")
        else:
            seated_since = None
            if docking_contact and np.linalg.norm(vrel) < JAM_V:
                if jam_since is None:
                    jam_since = t
                if t - jam_since >= JAM_T:
                    return ("JAMMED", None, impulse, peak, t_first, "")
            else:
                jam_since = None
        # Magnet: on the chaser port along -a_t, reaction on the target at the same point.
        force = -at * min(F0 / (1 + gap / G0) ** 2, FMAX) if magnet else np.zeros(3)
        vc_before = d.qvel[va : va + 3].copy()
        d.qfrc_applied[:] = 0
        if magnet:
            mujoco.mj_applyFT(m, d, force, np.zeros(3), port_c, cc, d.qfrc_applied)
            mujoco.mj_applyFT(m, d, -force, np.zeros(3), port_c, ct, d.qfrc_applied)
        mujoco.mj_step(m, d)
        # Contact impulse on the chaser: its momentum change less the magnet's.
        dj = (d.qvel[va : va + 3] - vc_before) * M_C - force * DT
        if in_contact or np.linalg.norm(dj) > 1e-9:
            impulse += dj
            peak = max(peak, np.linalg.norm(dj) / DT)
    if touched and axial_rate > REB_V:
        return ("REBOUND", None, impulse, peak, t_first, "")
    return ("TOUCHED_NOT_CAPTURED" if touched else "FREE", None, impulse, peak, t_first, "")


def main():
    trials_csv = sys.argv[1] if len(sys.argv) > 1 else "out/envelope/trials.csv"
    aligned = sys.argv[2] if len(sys.argv) > 2 else "out/docking_aligned/summary.json"
    rows = list(csv.DictReader(open(trials_csv)))
    agree = 0
    print("| trial | lateral m | yaw deg | rpod | MuJoCo | agree |")
    print("| --- | --- | --- | --- | --- | --- |")
    for r in rows:
        lat = float(r["bodies.chaser.initial.pos_m.1"])
        yaw = float(r["bodies.chaser.initial.attitude.yaw"])
        vx = float(r["bodies.chaser.initial.vel_m_s.0"])
        fr = float(r["bodies.target.friction"])
        out, t_latch, *_ = run_trial(lat, yaw, vx, fr)
        ok = out == r["outcome"]
        agree += ok
        extra = f" ({t_latch:.2f} s)" if t_latch else ""
        rl = f" ({float(r['t_latch_s']):.2f} s)" if r["t_latch_s"] else ""
        print(f"| {r['index']} | {lat} | {yaw} | {r['outcome']}{rl} | {out}{extra} | {'yes' if ok else 'no'} |", flush=True)
    print(f"\nagreement: {agree} of {len(rows)}")
    s = json.load(open(aligned))
    c = s["docking"]["contact"]
    out, t_latch, j, peak, t_first, _ = run_trial(0.0, 180.0, -0.02, 0.2, t_end=30.0)
    print("\n| docking_aligned | rpod | MuJoCo |")
    print("| --- | --- | --- |")
    print(f"| outcome | {s['docking']['state']} at {s['docking']['t_latch_s']:.2f} s | {out} at {t_latch:.2f} s |")
    print(f"| first contact, s | {s['docking']['first_docking_contact_s']:.3f} | {t_first:.3f} |")
    print(f"| contact impulse on the chaser up to the latch, N·s | {np.linalg.norm(c['net_impulse_on_chaser_ns']):.3f} | {np.linalg.norm(j):.3f} |")
    print(f"| peak contact force, N | {c['peak_force_n']:.1f} | {peak:.1f} |")


if __name__ == "__main__":
    main()
