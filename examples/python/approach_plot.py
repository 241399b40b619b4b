"""Fly the flagship scene (scenes/examples/orbit_approach_latch.ron) with a port-to-port PD law written
in Python, then plot the approach with matplotlib: range to the target port and lateral offset
against time, and the chaser's track in the target's Hill frame.

    pip install './python[examples]'
    python examples/python/approach_plot.py            # writes out/python_approach/

The scene's own Sequencer is replaced by the chaser's attitude law (keeps its port facing the
target's); translation is the Python law (python/tests/laws.py: PortApproach), through the
scene's 5 N per-axis thrust limit.
"""

import os
import pathlib
import sys

import numpy as np

import rpod

ROOT = pathlib.Path(__file__).resolve().parents[2]
sys.path.insert(0, os.fspath(ROOT / "python" / "tests"))
from laws import PortApproach  # noqa: E402

OUT = ROOT / "out" / "python_approach"
ATTITUDE = (
    'Attitude(body: "chaser", target: "target", period_s: 0.1, actuator: Saturated('
    "max_force_n: (0.0, 0.0, 0.0), max_torque_nm: (1.0, 1.0, 1.0)), params: (mode: "
    "AlignPort, natural_frequency_rad_s: 0.3, damping_ratio: 0.9))"
)


def main():
    sim = rpod.Simulation(ROOT / "scenes" / "examples" / "orbit_approach_latch.ron",
                          set={"controllers.1": ATTITUDE}, record=False)
    sim.add_controller(
        PortApproach(), body="chaser", target="target", period_s=0.1,
        actuator="Saturated(max_force_n: (5.0, 5.0, 5.0), max_torque_nm: (0.0, 0.0, 0.0))",
    )
    t, rng, lat, hill = [], [], [], []
    while sim.t_s < sim.duration_s and sim.monitor()["docking_state"] != "LATCHED":
        sim.run_until(sim.t_s + 1.0)
        p = sim.port_relative("chaser", "dock", "target", "dock")["rel_pos_m"]
        t.append(sim.t_s)
        rng.append(p[0])
        lat.append(float(np.hypot(p[1], p[2])))
        hill.append(sim.hill_state("chaser")[:3] - sim.hill_state("target")[:3])
    m = sim.monitor()
    cone = next(g for g in m["guarantees"] if g["name"] == "approach_cone_20deg")
    print(f"docking: {m['docking_state']} at t = {sim.t_s:.1f} s; approach cone "
          f"{cone['verdict']} (worst margin {cone['worst_margin']:.3f} m)")

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    hill = np.array(hill)
    fig, ax = plt.subplots(1, 3, figsize=(15, 4.5))
    ax[0].plot(t, rng)
    ax[0].set(xlabel="t (s)", ylabel="range along the target port axis (m)", yscale="log",
              title="Range to the target port")
    ax[1].plot(t, np.array(lat) * 100.0)
    ax[1].set(xlabel="t (s)", ylabel="lateral offset from the port axis (cm)",
              title="Lateral offset (target port frame)")
    ax[2].plot(hill[:, 1], hill[:, 0])
    ax[2].set(xlabel="Hill y, along-track (m)", ylabel="Hill x, radial (m)",
              title="Chaser relative to the target, Hill frame")
    for a in ax:
        a.grid(True, alpha=0.3)
    fig.tight_layout()
    OUT.mkdir(parents=True, exist_ok=True)
    fig.savefig(OUT / "approach.png", dpi=110)
    print(f"wrote {OUT / 'approach.png'}")


if __name__ == "__main__":
    main()
