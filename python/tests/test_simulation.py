"""rpod.Simulation from Python: scene errors, states against the run's own outputs, forces
applied from Python against the closed form of a free body, Python laws in the pipeline.

References: Newton's second law in free space (a constant force on a free body: x = F t²/2m,
exact for the zero-order hold rpod applies), the trajectory's own `NAME.hill_*` columns, the
Rust law `HillPd` (parity), the CLI's error messages.
"""

import csv
import math

import numpy as np
import pytest

import rpod
from conftest import FLAGSHIP, REPO, scene
from laws import HillPd, PortApproach

TARGET_ATTITUDE = (
    'Attitude(body: "target", period_s: 0.1, '
    "actuator: Saturated(max_force_n: (0.0, 0.0, 0.0), max_torque_nm: (1.0, 1.0, 1.0)), "
    "params: (mode: Lvlh(attitude: EulerZyxDeg(yaw: -90.0, pitch: 0.0, roll: 0.0)), "
    "natural_frequency_rad_s: 0.1, damping_ratio: 1.0))"
)
SATURATED_5N = (
    "Saturated(max_force_n: (5.0, 5.0, 5.0), max_torque_nm: (0.0, 0.0, 0.0))"
)
HILL_PD_RUST = (
    'HillPd(body: "chaser", target: "target", period_s: 0.1, actuator: '
    + SATURATED_5N
    + ", params: (hold_m: (0.0, -60.0, 0.0), point: CentreOfMass, "
    "gains: Pd(natural_frequency_rad_s: 0.05, damping_ratio: 1.0)))"
)


def test_scene_error_attributes_match_the_cli():
    path = REPO / "tests" / "broken_scenes" / "negative_mass.ron"
    with pytest.raises(rpod.SceneError) as ei:
        rpod.Simulation(path)
    e = ei.value
    assert (e.line, e.column, e.field) == (44, 22, "bodies.chaser.mass_kg")
    assert e.file.endswith("negative_mass.ron")
    assert "positive number of kilograms" in e.message
    # The CLI prints `error: ` and this same text (tests/scenes.rs checks the CLI side).
    assert str(e) == f"{e.file}:{e.line}:{e.column}: field `{e.field}`: {e.message}"


def test_bad_override_is_a_located_scene_error():
    with pytest.raises(rpod.SceneError) as ei:
        rpod.Simulation(FLAGSHIP, set={"bodies.chaser.mass_kg": -1.0})
    assert ei.value.field == "bodies.chaser.mass_kg"
    with pytest.raises(rpod.SceneError):
        rpod.Simulation(REPO / "no_such_scene.ron")
    with pytest.raises(TypeError):
        rpod.Simulation(FLAGSHIP, set={"dt_s": [1, 2]})


def test_free_body_under_applied_force_matches_the_closed_form():
    # free_drift is free space: a constant world force F on the chaser for n steps of dt moves
    # it by F (n dt)^2 / 2m exactly under the zero-order hold (velocity Verlet is exact for a
    # constant acceleration), and the velocity changes by F n dt / m.
    sim = rpod.Simulation(scene("docking_aligned.ron"), record=False)
    m = 300.0
    x0 = sim.state("chaser")["pos_m"].copy()
    v0 = sim.state("chaser")["vel_m_s"].copy()
    f = np.array([0.0, 3.0, 0.0])
    n = 100
    for _ in range(n):
        sim.apply("chaser", force_n=f)
        sim.step()
    t = n * sim.dt_s
    s = sim.state("chaser")
    dy = s["pos_m"][1] - x0[1]
    assert dy == pytest.approx(f[1] * t * t / (2 * m), rel=1e-9)
    assert s["vel_m_s"][1] - v0[1] == pytest.approx(f[1] * t / m, rel=1e-9)
    # Held over one step only: nothing applied now, the velocity stays.
    v1 = s["vel_m_s"].copy()
    sim.step(10)
    assert np.allclose(sim.state("chaser")["vel_m_s"], v1, rtol=0, atol=1e-15)


def test_body_frame_torque_turns_the_body():
    sim = rpod.Simulation(scene("docking_aligned.ron"), record=False)
    # The chaser is yawed 180° (body z = world z): a body-frame torque about z spins it about
    # world z at τ t / I_zz.
    for _ in range(50):
        sim.apply("chaser", torque_nm=[0.0, 0.0, 1.6], frame="body")
        sim.step()
    w = sim.state("chaser")["omega_rad_s"]
    assert w[2] == pytest.approx(1.6 * 0.5 / 160.0, rel=1e-9)
    assert abs(w[0]) < 1e-12 and abs(w[1]) < 1e-12


def test_hill_state_matches_the_trajectory_columns(out_dir):
    sim = rpod.Simulation(FLAGSHIP, set={"duration_s": 2.0}, out_dir=out_dir)
    sim.run_until(1.0)
    h = sim.hill_state("chaser")
    sim.finish()
    rows = list(csv.DictReader(open(out_dir / "trajectory.csv")))
    row = next(r for r in rows if float(r["t_s"]) == pytest.approx(1.0))
    cols = ["hill_x_m", "hill_y_m", "hill_z_m", "hill_vx_m_s", "hill_vy_m_s", "hill_vz_m_s"]
    assert [float(row[f"chaser.{c}"]) for c in cols] == list(h)
    assert h[1] == pytest.approx(-101.32, abs=1e-3)


def test_monitor_events_summary_and_outputs(out_dir):
    sim = rpod.Simulation(scene("docking_aligned.ron"))
    sim.run_until(40.0)
    m = sim.monitor()
    assert m["docking_state"] == "LATCHED"
    g = m["guarantees"][0]
    # The scene's 5 cm clearance counts the docking parts too: the cone comes within 5 cm of
    # the slot before it touches, so the guarantee is violated before the first contact.
    assert g["name"] == "clearance_5cm" and g["unit"] == "m"
    assert g["verdict"] == "violated" and g["judged"] == "interval" and not g["held"]
    assert g["first_violation_s"] < m["first_contact_s"]
    assert g["worst_margin"] == pytest.approx(-0.05)
    assert m["first_collision_s"] is None and m["min_clearance_non_docking_m"] > 0.0
    kinds = {e["kind"] for e in sim.events()}
    assert "contact_start" in kinds
    summary = sim.finish(out_dir)
    assert summary["docking"]["state"] == "LATCHED"
    for f in ["trajectory.csv", "events.jsonl", "contacts.csv", "summary.json"]:
        assert (out_dir / f).is_file(), f
    with pytest.raises(rpod.SimulationError):
        sim.step()


def test_python_law_is_byte_identical_to_the_rust_hill_pd(tmp_path):
    common = {"duration_s": 300.0}
    rust = tmp_path / "rust"
    py = tmp_path / "python"
    sim = rpod.Simulation(
        FLAGSHIP, set={**common, "controllers": f"[{TARGET_ATTITUDE}, {HILL_PD_RUST}]"},
        out_dir=rust,
    )
    sim.run_until(300.0)
    sim.finish()
    sim = rpod.Simulation(
        FLAGSHIP, set={**common, "controllers": f"[{TARGET_ATTITUDE}]"}, out_dir=py
    )
    sim.add_controller(
        HillPd((0.0, -60.0, 0.0), 0.05, 1.0), body="chaser", target="target", period_s=0.1,
        actuator=SATURATED_5N, columns=HillPd.COLUMNS,
    )
    sim.run_until(300.0)
    sim.finish()
    for f in ["trajectory.csv", "events.jsonl", "contacts.csv"]:
        assert (rust / f).read_bytes() == (py / f).read_bytes(), f
    # The law did move the chaser: 41.32 m toward the hold point at 60 m.
    rows = list(csv.DictReader(open(py / "trajectory.csv")))
    assert float(rows[-1]["chaser.hill_y_m"]) == pytest.approx(-60.5, abs=0.5)


def test_python_law_with_multi_rate_stepping_is_the_rust_law_s_run(tmp_path):
    # `stepping: MultiRate()`: the Python law's run takes the same long steps as the Rust
    # law's (the binding steps one pipeline step at a time, not one fixed step), bit for bit.
    common = {"duration_s": 300.0, "stepping": "MultiRate()"}
    runs = {}
    for name, controllers in [("rust", f"[{TARGET_ATTITUDE}, {HILL_PD_RUST}]"),
                              ("python", f"[{TARGET_ATTITUDE}]")]:
        sim = rpod.Simulation(
            FLAGSHIP, set={**common, "controllers": controllers}, out_dir=tmp_path / name
        )
        if name == "python":
            sim.add_controller(
                HillPd((0.0, -60.0, 0.0), 0.05, 1.0), body="chaser", target="target",
                period_s=0.1, actuator=SATURATED_5N, columns=HillPd.COLUMNS,
            )
        sim.run_until(300.0)
        runs[name] = sim.finish()
    for f in ["trajectory.csv", "events.jsonl", "contacts.csv"]:
        assert (tmp_path / "rust" / f).read_bytes() == (tmp_path / "python" / f).read_bytes(), f
    st = runs["python"]["stepping"]
    assert st == runs["rust"]["stepping"]
    # 30 000 fixed steps; rows every 100 and calls every 10 bound each step to 0.1 s.
    assert st["long_steps"] > 2000, st
    assert st["pipeline_steps"] < 5000, st


def test_python_pd_flies_the_flagship_to_latched(out_dir):
    attitude = (
        'Attitude(body: "chaser", target: "target", period_s: 0.1, actuator: Saturated('
        "max_force_n: (0.0, 0.0, 0.0), max_torque_nm: (1.0, 1.0, 1.0)), params: (mode: "
        "AlignPort, natural_frequency_rad_s: 0.3, damping_ratio: 0.9))"
    )
    sim = rpod.Simulation(FLAGSHIP, set={"controllers.1": attitude}, out_dir=out_dir)
    law = PortApproach()
    sim.add_controller(
        law, body="chaser", target="target", period_s=0.1,
        actuator="Saturated(max_force_n: (5.0, 5.0, 5.0), max_torque_nm: (0.0, 0.0, 0.0))",
    )
    while sim.t_s < sim.duration_s and sim.monitor()["docking_state"] != "LATCHED":
        sim.run_until(sim.t_s + 10.0)
    m = sim.monitor()
    assert m["docking_state"] == "LATCHED", m
    assert m["first_collision_s"] is None
    cone = next(g for g in m["guarantees"] if g["name"] == "approach_cone_20deg")
    summary = sim.finish()
    t_latch = summary["docking"]["t_latch_s"]
    # 900 s at 0.1 m/s to 10 m, 120 s hold, then 9.8 m at 3 cm/s: the latch a few seconds
    # after the reference reaches the seat depth (0.25 m above the port), ~1350 s.
    assert 1300.0 < t_latch < 1400.0, t_latch
    print(f"latched at {t_latch} s; cone {cone['verdict']}, worst {cone['worst_margin']} m")


def test_exception_in_a_law_is_raised_from_step():
    sim = rpod.Simulation(scene("docking_aligned.ron"), record=False)

    def bad(obs):
        if obs["t_s"] >= 0.5:
            raise ZeroDivisionError("my law failed")
        return None

    sim.add_controller(bad, body="chaser", period_s=0.1)
    with pytest.raises(ZeroDivisionError, match="my law failed"):
        sim.step(1000)
    assert sim.t_s == pytest.approx(0.51)


def test_nan_command_names_body_quantity_and_time():
    sim = rpod.Simulation(scene("docking_aligned.ron"), record=False)
    sim.add_controller(
        lambda obs: {"force_n": [0.0, math.nan, 0.0]} if obs["t_s"] > 1.0 else None,
        body="chaser", period_s=0.1,
    )
    with pytest.raises(rpod.NumericError) as ei:
        sim.run_until(5.0)
    msg = str(ei.value)
    assert "`chaser`" in msg and "force_n[1]" in msg and "t = 1.1" in msg, msg


@pytest.mark.parametrize(
    "ret, err",
    [
        (42, TypeError),
        ({"force_n": [1.0, 2.0]}, ValueError),
        ({"forse_n": [1.0, 2.0, 3.0]}, KeyError),
        ({"force_n": [1.0, 2.0, 3.0], "frame": "lvlh"}, ValueError),
        ({"force_n": [1e308, 0.0, 0.0]}, rpod.NumericError),
        ({"diagnostics": {"undeclared": 1.0}}, KeyError),
    ],
)
def test_bad_commands_are_python_errors(ret, err):
    sim = rpod.Simulation(scene("docking_aligned.ron"), record=False)
    sim.add_controller(lambda obs: ret, body="chaser", period_s=0.01)
    with pytest.raises(err):
        sim.step(5)


def test_bad_arguments_are_python_errors():
    sim = rpod.Simulation(scene("docking_aligned.ron"), record=False)
    with pytest.raises(KeyError):
        sim.state("nobody")
    with pytest.raises(ValueError):
        sim.add_controller(lambda o: None, body="chaser", period_s=0.015)
    with pytest.raises(ValueError):
        sim.add_controller(lambda o: None, body="chaser", period_s=0.1, actuator="Warp(9)")
    with pytest.raises(ValueError):
        sim.hill_state("chaser")  # free space: no reference orbit
    with pytest.raises(rpod.NumericError):
        sim.apply("chaser", force_n=[math.inf, 0, 0])
    with pytest.raises(ValueError):
        sim.run_until(math.nan)
    sim.step()
    with pytest.raises(rpod.SimulationError):
        sim.add_controller(lambda o: None, body="chaser", period_s=0.1)


def test_same_scene_same_bits(tmp_path):
    outs = []
    for k in range(2):
        d = tmp_path / f"run{k}"
        sim = rpod.Simulation(scene("docking_aligned.ron"), set={"duration_s": 5.0})
        sim.add_controller(
            lambda obs: {"force_n": -obs["relative"]["world"]["vel_m_s"] * 10.0},
            body="chaser", target="target", period_s=0.1,
        )
        sim.run_until(5.0)
        sim.finish(d)
        outs.append((d / "trajectory.csv").read_bytes())
    assert outs[0] == outs[1]


def test_finish_into_a_file_keeps_the_run(tmp_path):
    not_a_folder = tmp_path / "file"
    not_a_folder.write_text("x")
    sim = rpod.Simulation(scene("docking_aligned.ron"), set={"duration_s": 0.5})
    sim.run_until(0.5)
    with pytest.raises(OSError, match="not a folder"):
        sim.finish(not_a_folder)
    assert not_a_folder.read_text() == "x"
    summary = sim.finish(tmp_path / "out")
    assert summary["steps"] == 50 and (tmp_path / "out" / "summary.json").is_file()


def test_docked_state_names_each_mechanism_s_end_state():
    """`docking()["docked_state"]`: LATCHED for the cone and slot, HARD_DOCKED for the soft-capture
    mechanism; soft_capture.ron reaches it (its header: HARD_DOCKED at 12.77 s)."""
    cone = rpod.Simulation(rpod.scenes.path("docking_aligned"), record=False)
    assert cone.docking()["docked_state"] == "LATCHED"
    soft = rpod.Simulation(rpod.scenes.path("soft_capture"), record=False)
    dock = soft.docking()
    assert dock["docked_state"] == "HARD_DOCKED"
    assert dock["state"] == "FREE"
    soft.run_until(14.0)
    assert soft.docking()["state"] == soft.docking()["docked_state"]
