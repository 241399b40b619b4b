#!/usr/bin/env python3
"""free_drift against Basilisk, side by side on this machine (a benchmark, not a test).

Basilisk (`pip install bsk`, AVS Lab) propagates the same two 6-DOF spacecraft as
`scenes/examples/free_drift.ron` — target 800 kg, J = diag(620, 910, 1080) kg·m²; chaser 300 kg,
J = diag(110, 140, 160) kg·m² — in the same 7178 km orbit with two-body + J2 gravity, at the
same fixed step (0.01 s; Basilisk's default RK4 integrator), for the same number of steps.
rpod's figure is `rpod bench scenes/examples/free_drift.ron` (the whole pipeline: f64 dynamics,
full-geometry monitor with interval bounds, guarantees) measured in the same run. The ratio
printed is rpod steps/s over Basilisk steps/s, for each of `--rounds` rounds (Basilisk, then
rpod, one after the other) and their median: on a shared machine whose speed drifts from
minute to minute, a ratio means something only within a round. Also printed: the ratio of each
one's fastest round, the nearest either came to its speed on an idle machine (a slow phase only
ever slows a run down).

Nothing is installed or downloaded here: without Basilisk the script says so and prints
rpod's figure alone. J2 is given to Basilisk directly (normalised C̄20 = −J2/√5) so that no
gravity file has to be fetched. Set-up, once: `python3 -m venv VENV && VENV/bin/pip install
bsk`, then `VENV/bin/python benches/basilisk_free_drift.py [--steps N] [--rounds N] [--rpod PATH]`.
"""
import argparse
import math
import re
import statistics
import subprocess
import sys
import time

MU = 3.986004418e14
R_E = 6378137.0
J2 = 1.08262668e-3


def rpod_steps_per_s(rpod, steps):
    out = subprocess.run([rpod, "bench", "scenes/examples/free_drift.ron", "--steps", str(steps)],
                         check=True, capture_output=True, text=True).stdout
    m = re.search(r"pipeline\s+(\d+) steps/s", out)
    return float(m.group(1)), out


def rpod_flagship_wall_s(rpod, stepping):
    """Wall seconds of the whole flagship (`summary.json`'s `wall_s`) with `stepping` set."""
    import json
    import tempfile
    with tempfile.TemporaryDirectory() as out:
        subprocess.run([rpod, "run", "scenes/examples/orbit_approach_latch.ron", "--out", out,
                        "--set", f"stepping={stepping}"], check=True, capture_output=True)
        with open(f"{out}/summary.json") as f:
            return json.load(f)["wall_s"]


def basilisk_steps_per_s(steps, dt):
    try:
        from Basilisk.simulation import spacecraft, gravityEffector
        from Basilisk.utilities import SimulationBaseClass, macros, simIncludeGravBody, orbitalMotion
    except ImportError:
        return None
    sim = SimulationBaseClass.SimBaseClass()
    proc = sim.CreateNewProcess("dyn")
    proc.addTask(sim.CreateNewTask("task", macros.sec2nano(dt)))
    grav = simIncludeGravBody.gravBodyFactory()
    earth = grav.createEarth()
    earth.isCentralBody = True
    sh = gravityEffector.SphericalHarmonicsGravityModel()
    sh.muBody = MU
    sh.radEquator = R_E
    sh.cBar = [[1.0], [0.0, 0.0], [-J2 / math.sqrt(5.0), 0.0, 0.0]]
    sh.sBar = [[0.0], [0.0, 0.0], [0.0, 0.0, 0.0]]
    sh.maxDeg = 2
    earth.gravityModel = sh
    el = orbitalMotion.ClassicElements()
    el.a, el.e, el.i, el.Omega, el.omega, el.f = 7178000.0, 0.01, math.radians(30.0), 0.0, 0.0, 0.0
    r, v = orbitalMotion.elem2rv(MU, el)
    bodies = []
    for name, m, j, dr, w in [
        ("target", 800.0, (620.0, 910.0, 1080.0), (0.0, 0.0, 0.0), (1.5, 0.4, -2.0)),
        ("chaser", 300.0, (110.0, 140.0, 160.0), (30.0, 10.0, 0.0), (0.0, 0.0, 0.0)),
    ]:
        sc = spacecraft.Spacecraft()
        sc.ModelTag = name
        sc.hub.mHub = m
        sc.hub.IHubPntBc_B = [[j[0], 0, 0], [0, j[1], 0], [0, 0, j[2]]]
        sc.hub.r_CN_NInit = [r[k] + dr[k] for k in range(3)]
        sc.hub.v_CN_NInit = list(v)
        sc.hub.omega_BN_BInit = [[math.radians(x)] for x in w]
        grav.addBodiesTo(sc)
        sim.AddModelToTask("task", sc)
        bodies.append(sc)
    sim.InitializeSimulation()
    warm = steps // 10
    sim.ConfigureStopTime(macros.sec2nano(warm * dt))
    sim.ExecuteSimulation()
    t0 = time.perf_counter()
    sim.ConfigureStopTime(macros.sec2nano((warm + steps) * dt))
    sim.ExecuteSimulation()
    return steps / (time.perf_counter() - t0)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--steps", type=int, default=20000)
    ap.add_argument("--rpod", default="target/release/rpod")
    ap.add_argument("--rounds", type=int, default=5,
                    help="free_drift: rounds of (Basilisk, rpod) measured one after the other; "
                         "each round's ratio is printed, then their median (a shared machine's "
                         "speed drifts between runs: a ratio is only taken within a round)")
    ap.add_argument("--flagship", action="store_true",
                    help="instead: the whole flagship (2 700 s) against Basilisk propagating "
                         "the two spacecraft for 2 700 s at 0.1 s (the flagship's speed goal)")
    a = ap.parse_args()
    if a.flagship:
        fixed = rpod_flagship_wall_s(a.rpod, "Fixed")
        multi = rpod_flagship_wall_s(a.rpod, "MultiRate()")
        print(f"rpod flagship, 2700 s: Fixed {fixed:.2f} s wall, MultiRate() {multi:.2f} s wall")
        bsk = basilisk_steps_per_s(27000, 0.1)
        if bsk is None:
            print("Basilisk not installed (pip install bsk in a venv): skipped")
            return 0
        print(f"Basilisk, 2 spacecraft, two-body + J2, RK4, 27000 steps of 0.1 s: {27000 / bsk:.2f} s wall")
        print(f"rpod MultiRate / Basilisk wall = {multi / (27000 / bsk):.2f} (goal ≤ 1)")
        return 0
    ratios, best_ours, best_bsk = [], 0.0, 0.0
    for k in range(max(1, a.rounds)):
        bsk = basilisk_steps_per_s(a.steps, 0.01)
        ours, report = rpod_steps_per_s(a.rpod, a.steps)
        if k == 0 or bsk is None:
            print(report.rstrip())
        if bsk is None:
            print("Basilisk not installed (pip install bsk in a venv): skipped")
            return 0
        ratios.append(ours / bsk)
        best_ours, best_bsk = max(best_ours, ours), max(best_bsk, bsk)
        print(f"round {k + 1}: rpod {ours:9.0f} steps/s, Basilisk {bsk:9.0f} steps/s "
              f"({1e6 / bsk:.2f} µs/step; 2 spacecraft, two-body + J2, RK4): "
              f"rpod / Basilisk = {ours / bsk:.2f}")
    ratios.sort()
    print(f"rpod / Basilisk = {statistics.median(ratios):.2f} (steps/s, median of {len(ratios)} "
          f"rounds; {ratios[0]:.2f}-{ratios[-1]:.2f})")
    print(f"rpod / Basilisk = {best_ours / best_bsk:.2f} (each one's fastest round: rpod "
          f"{best_ours:.0f}, Basilisk {best_bsk:.0f} steps/s — the nearest either came to its "
          f"speed on an idle machine)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
