"""Guarantees written in Python (`Simulation.add_guarantee`).

Reference: the scene's own Rust `KeepOutSphere` guarantee (free_drift: the chaser's centre of
mass outside 10 m of the target's), whose margin |r_chaser − r_target| − 10 m the Python
callable recomputes from the same f64 states: the two margins agree to the last bit at every
sample (same formula, same doubles; numpy's norm and nalgebra's may round the square root's
argument differently, hence a 1e-12 m tolerance). The relative speed in free_drift stays below
0.1 m/s (initial 0.013 m/s, CW drift over 600 s), so 0.1 m/s is a valid rate bound for the
interval-judged variant.
"""

import math

import numpy as np
import pytest

import rpod
from conftest import scene


def keep_out(view):
    b = view["bodies"]
    return float(np.linalg.norm(b["chaser"]["pos_m"] - b["target"]["pos_m"]) - 10.0)


def test_python_keep_out_matches_the_rust_one(out_dir):
    sim = rpod.Simulation(scene("free_drift.ron"), set={"duration_s": 60.0}, out_dir=out_dir)
    assert sim.add_guarantee(keep_out, "py_keep_out", "m") == 2
    sim.add_guarantee(keep_out, "py_keep_out_interval", "m", rate_bound=0.1)
    for _ in range(6):
        sim.step(100)
        gs = {g["name"]: g for g in sim.monitor()["guarantees"]}
        rust, py = gs["keep_out_10m"], gs["py_keep_out"]
        assert py["margin"] == pytest.approx(rust["margin"], abs=1e-12)
        assert py["margin"] > 20.0
    assert py["judged"] == "samples only" and py["verdict"] == "held"
    assert gs["py_keep_out_interval"]["judged"] == "interval"
    summary = sim.finish()
    names = [g["name"] for g in summary["guarantees"]]
    assert "py_keep_out" in names and "py_keep_out_interval" in names
    header = (out_dir / "trajectory.csv").read_text().splitlines()[0].split(",")
    assert "guarantee.py_keep_out.margin_m" in header


def test_python_guarantee_violation_is_reported():
    sim = rpod.Simulation(scene("free_drift.ron"), record=False)
    # Violated once t > 0.5 s: the first violation is the first sample after it.
    sim.add_guarantee(lambda v: 0.5 - v["t_s"], "deadline", "s")
    sim.step(100)
    g = next(g for g in sim.monitor()["guarantees"] if g["name"] == "deadline")
    assert g["verdict"] == "violated" and not g["held"]
    assert g["first_violation_s"] == pytest.approx(0.51)


def test_raising_guarantee_names_itself():
    sim = rpod.Simulation(scene("free_drift.ron"), record=False)

    def bad(view):
        if view["t_s"] > 0.2:
            raise ZeroDivisionError("my guarantee failed")
        return 1.0

    sim.add_guarantee(bad, "fragile", "m")
    with pytest.raises(rpod.SimulationError, match="fragile") as ei:
        sim.step(100)
    assert isinstance(ei.value.__cause__, ZeroDivisionError)
    with pytest.raises(rpod.SimulationError):
        sim.step()


@pytest.mark.parametrize("value", [math.nan, math.inf])
def test_non_finite_margin_names_the_guarantee(value):
    sim = rpod.Simulation(scene("free_drift.ron"), record=False)
    sim.add_guarantee(lambda v: value if v["t_s"] > 0.1 else 1.0, "nonfinite", "m")
    with pytest.raises(rpod.NumericError, match="nonfinite"):
        sim.step(100)


def test_bad_guarantee_arguments():
    sim = rpod.Simulation(scene("free_drift.ron"), record=False)
    with pytest.raises(TypeError, match="g1"):
        sim.add_guarantee(3.0, "g1", "m")
    with pytest.raises(ValueError, match="rate_bound"):
        sim.add_guarantee(keep_out, "g2", "m", rate_bound=-1.0)
    with pytest.raises(ValueError, match="already exists"):
        sim.add_guarantee(keep_out, "keep_out_10m", "m")
    sim.step()
    with pytest.raises(rpod.SimulationError, match="g4"):
        sim.add_guarantee(keep_out, "g4", "m")


def test_non_float_margin_at_t0_is_raised_by_add_guarantee():
    sim = rpod.Simulation(scene("free_drift.ron"), record=False)
    with pytest.raises(TypeError, match="g3"):
        sim.add_guarantee(lambda v: "no", "g3", "m")
    with pytest.raises(rpod.SimulationError, match="stopped"):
        sim.step()
