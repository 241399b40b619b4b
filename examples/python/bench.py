"""Python in the loop, measured: steps per second of the flagship scene with its chaser flown
by HillPd called every step (period = dt = 10 ms), as rpod's Rust law and as the Python twin
(python/tests/laws.py: HillPd, the same bits), in one run; and Gymnasium steps per second of
rpod.gym.DockingEnv with random actions (one env step = control_period_s / dt_s scene steps,
50 at the defaults).

    python examples/python/bench.py [--seconds S]
"""

import argparse
import os
import pathlib
import sys
import time

import numpy as np

import rpod
import rpod.gym
from rpod.gym import DockingEnv

ROOT = pathlib.Path(__file__).resolve().parents[2]
sys.path.insert(0, os.fspath(ROOT / "python" / "tests"))
from laws import HillPd  # noqa: E402
from test_simulation import SATURATED_5N, TARGET_ATTITUDE  # noqa: E402

FLAGSHIP = ROOT / "scenes" / "examples" / "orbit_approach_latch.ron"


def rust_entry(period):
    return (
        f'HillPd(body: "chaser", target: "target", period_s: {period}, actuator: {SATURATED_5N}, '
        "params: (hold_m: (0.0, -60.0, 0.0), point: CentreOfMass, "
        "gains: Pd(natural_frequency_rad_s: 0.05, damping_ratio: 1.0)))"
    )


def steps_per_s(make, seconds):
    sim = make()
    n = int(round(seconds / sim.dt_s))
    t0 = time.perf_counter()
    sim.step(n)
    return n / (time.perf_counter() - t0)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--seconds", type=float, default=100.0, help="simulated seconds per run")
    a = ap.parse_args()
    period = 0.01

    def rust():
        return rpod.Simulation(
            FLAGSHIP, record=False,
            set={"controllers": f"[{TARGET_ATTITUDE}, {rust_entry(period)}]"},
        )

    def python():
        s = rpod.Simulation(FLAGSHIP, record=False, set={"controllers": f"[{TARGET_ATTITUDE}]"})
        s.add_controller(HillPd((0.0, -60.0, 0.0), 0.05, 1.0), body="chaser", target="target",
                         period_s=period, actuator=SATURATED_5N, columns=HillPd.COLUMNS)
        return s

    def bare():
        return rpod.Simulation(FLAGSHIP, record=False, set={"controllers": f"[{TARGET_ATTITUDE}]"})

    r = [steps_per_s(rust, a.seconds) for _ in range(3)]
    p = [steps_per_s(python, a.seconds) for _ in range(3)]
    b = [steps_per_s(bare, a.seconds) for _ in range(3)]
    rr, pp, bb = max(r), max(p), max(b)
    print(f"flagship, HillPd every step ({a.seconds:g} s simulated, best of 3):")
    print(f"  no chaser law            {bb:10.0f} steps/s")
    print(f"  Rust HillPd              {rr:10.0f} steps/s")
    print(f"  Python HillPd            {pp:10.0f} steps/s   ratio Python/Rust = {pp / rr:.3f}")

    env = DockingEnv()
    spa = env._steps_per_action
    env.reset(seed=0)
    rng = np.random.default_rng(0)
    n, t0 = 0, time.perf_counter()
    while time.perf_counter() - t0 < 10.0:
        _, _, term, trunc, _ = env.step(rng.uniform(-1, 1, 6))
        n += 1
        if term or trunc:
            env.reset()
    dt = time.perf_counter() - t0
    print(f"rpod/Docking-v0 random actions: {n / dt:.1f} env steps/s "
          f"({spa * n / dt:.0f} scene steps/s; resets included)")
    # The env's own cost: 60 zero-action env steps against the same simulation stepped
    # 60 × spa scene steps directly (same start, same law inside), best of 3 each.
    def env_steps():
        env.reset(seed=0)
        t0 = time.perf_counter()
        for _ in range(60):
            env.step(np.zeros(6))
        return time.perf_counter() - t0

    def sim_steps():
        env.reset(seed=0)
        t0 = time.perf_counter()
        env.sim.step(60 * spa)
        return time.perf_counter() - t0

    te = min(env_steps() for _ in range(3))
    ts = min(sim_steps() for _ in range(3))
    print(f"  env step = {spa} scene steps: {te / 60 * 1e3:.3f} ms against "
          f"{ts / 60 * 1e3:.3f} ms stepping the simulation directly (env/direct = {te / ts:.3f})")


if __name__ == "__main__":
    main()
