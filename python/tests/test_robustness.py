"""rpod.Simulation under the conditions of real Python programs: exceptions that pickle (so a
worker process's error reaches its parent), a second thread, staging folders that do not
outlive their simulation or the interpreter, a failing law that stops the run without writing a
summary as if it were whole, the bundled scenes, pictures of the geometry, and the installed
package (a wheel without a Rust toolchain).

References: the scene files (the chaser's bus is a 1 m cube centred on its centre of mass, its
cone 0.25 m long on a port 0.5 m ahead: the projected extents of a picture), Python's pickle
protocol (an exception's class by qualified name, its args and __dict__), the output contract
(summary.json marks a whole run).
"""

import os
import pathlib
import pickle
import shutil
import subprocess
import sys
import textwrap
import threading

import numpy as np
import pytest

import rpod
from conftest import REPO, SCENES, scene


# -- 1. exceptions that pickle -----------------------------------------------------------------
def test_scene_error_pickles_with_its_attributes():
    with pytest.raises(rpod.SceneError) as ei:
        rpod.Simulation(REPO / "tests" / "broken_scenes" / "negative_mass.ron")
    e = ei.value
    assert type(e).__module__ == "rpod" and type(e).__qualname__ == "SceneError"
    back = pickle.loads(pickle.dumps(e))
    assert type(back) is rpod.SceneError
    assert str(back) == str(e)
    for a in ("file", "line", "column", "field", "message"):
        assert getattr(back, a) == getattr(e, a), a


def test_numeric_and_simulation_errors_pickle():
    sim = rpod.Simulation(scene("docking_aligned.ron"), record=False)
    sim.add_controller(lambda o: {"force_n": [float("nan"), 0, 0]}, body="chaser", period_s=0.1)
    with pytest.raises(rpod.NumericError) as ne:
        sim.step()
    with pytest.raises(rpod.SimulationError) as se:
        sim.step()
    for e in (ne.value, se.value):
        back = pickle.loads(pickle.dumps(e))
        assert type(back) is type(e) and str(back) == str(e)


ASYNC_SCRIPT = textwrap.dedent(
    """
    import sys, gymnasium as gym, rpod, rpod.gym

    def make():
        return rpod.gym.DockingEnv()

    if __name__ == "__main__":
        envs = gym.vector.AsyncVectorEnv([make] * 2, context=sys.argv[1])
        try:
            envs.reset(seed=0, options={"set": {"bodies.chaser.mass_kg": -1.0}})
        except rpod.SceneError as e:
            print("RAISED", type(e).__module__, e.field, e.line > 0)
        else:
            print("NOT RAISED")
        envs.close(terminate=True)
    """
)


@pytest.mark.parametrize("context", ["fork", "spawn", "forkserver"])
def test_async_vector_env_worker_error_reaches_the_parent(context, tmp_path):
    # Before the exceptions pickled, the worker's error never reached the parent's queue and
    # the parent waited forever: a child process with a time limit turns a hang into a failure.
    pytest.importorskip("gymnasium")
    script = tmp_path / "async_error.py"
    script.write_text(ASYNC_SCRIPT)
    r = subprocess.run(
        [sys.executable, str(script), context],
        capture_output=True, text=True, timeout=300, cwd=tmp_path,
    )
    assert "RAISED rpod bodies.chaser.mass_kg True" in r.stdout, (r.stdout, r.stderr[-3000:])


# -- 3. threads --------------------------------------------------------------------------------
def test_use_from_another_thread_raises_simulation_error(capfd):
    sim = rpod.Simulation(scene("docking_aligned.ron"), record=False)
    sim.step(2)
    errors = {}

    def worker():
        for name, call in [
            ("step", lambda: sim.step()),
            ("t_s", lambda: sim.t_s),
            ("state", lambda: sim.state("chaser")),
            ("monitor", lambda: sim.monitor()),
            ("apply", lambda: sim.apply("chaser", force_n=[1.0, 0, 0])),
            ("add_controller", lambda: sim.add_controller(lambda o: None, body="chaser",
                                                          period_s=0.1)),
            ("render", lambda: sim.render(8, 8)),
            ("finish", lambda: sim.finish()),
        ]:
            try:
                call()
                errors[name] = None
            except BaseException as e:  # noqa: BLE001 - the type is what is checked
                errors[name] = e

    t = threading.Thread(target=worker, name="other")
    t.start()
    t.join()
    for name, e in errors.items():
        assert isinstance(e, rpod.SimulationError), (name, e)
        assert 'belongs to thread "MainThread"' in str(e) and '"other"' in str(e), str(e)
    assert "other thread" not in repr(sim)
    # The owner thread still steps it; nothing (no panic, no backtrace) went to stderr.
    sim.step(3)
    assert sim.steps == 5
    out, err = capfd.readouterr()
    assert "panic" not in err.lower() and "backtrace" not in err.lower(), err


def test_a_simulation_made_in_a_thread_works_there_and_is_freed_with_it():
    result = {}

    def worker():
        s = rpod.Simulation(scene("docking_aligned.ron"), record=False)
        s.step(10)
        result["t"] = s.t_s
        result["sim"] = s  # handed to the main thread, which cannot use it

    t = threading.Thread(target=worker)
    t.start()
    t.join()
    assert result["t"] == pytest.approx(0.1)
    with pytest.raises(rpod.SimulationError):
        result["sim"].step()
    del result["sim"]  # collected on another thread: no error, no output


# -- 4. staging folders ------------------------------------------------------------------------
def staging(tmp: pathlib.Path, pid: int):
    return sorted(tmp.glob(f"rpod-python-{pid}-*"))


def test_staging_folder_removed_when_the_simulation_is_dropped(monkeypatch, tmp_path):
    # The staging folder is in the temporary directory (TMPDIR, read when it is made).
    monkeypatch.setenv("TMPDIR", str(tmp_path))
    before = staging(tmp_path, os.getpid())
    sim = rpod.Simulation(scene("docking_aligned.ron"))
    sim.step(50)
    during = staging(tmp_path, os.getpid())
    assert len(during) == len(before) + 1
    # Rows are written as they come (under the output contract's temporary names).
    assert (during[-1] / "trajectory.csv.partial").is_file()
    del sim
    assert staging(tmp_path, os.getpid()) == before


EXIT_SCRIPT = textwrap.dedent(
    """
    import os, rpod
    sim = rpod.Simulation(rpod.scenes.path("docking_aligned"))   # recording, never finished
    sim.step(20)
    keep = [sim]
    print(os.getpid(), flush=True)
    """
)


def test_staging_folder_removed_at_interpreter_exit(tmp_path):
    script = tmp_path / "leave.py"
    script.write_text(EXIT_SCRIPT)
    tmp = tmp_path / "tmp"
    tmp.mkdir()
    r = subprocess.run([sys.executable, str(script)], capture_output=True, text=True,
                       timeout=120, env=dict(os.environ, TMPDIR=str(tmp)), cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    assert list(tmp.iterdir()) == [], list(tmp.iterdir())


def test_finish_into_a_folder_removes_the_staging_folder(monkeypatch, tmp_path):
    monkeypatch.setenv("TMPDIR", str(tmp_path / "tmp"))
    (tmp_path / "tmp").mkdir()
    sim = rpod.Simulation(scene("docking_aligned.ron"), set={"duration_s": 0.2})
    sim.run_until(0.2)
    sim.finish(tmp_path / "out")
    assert list((tmp_path / "tmp").iterdir()) == []
    assert (tmp_path / "out" / "summary.json").is_file()


# -- bad input: a law that fails stops the run; nothing is written as if whole --------------------
@pytest.mark.parametrize(
    "law, err",
    [
        (lambda o: 1 / 0 if o["t_s"] >= 0.3 else None, ZeroDivisionError),
        (lambda o: {"force_n": [1.0, 2.0]} if o["t_s"] >= 0.3 else None, ValueError),
        (lambda o: {"force_n": [float("inf"), 0, 0]} if o["t_s"] >= 0.3 else None,
         rpod.NumericError),
    ],
)
def test_failing_law_stops_the_run_and_no_summary_is_written(law, err, tmp_path):
    out = tmp_path / "run"
    sim = rpod.Simulation(scene("docking_aligned.ron"), out_dir=out)
    sim.add_controller(law, body="chaser", period_s=0.1)
    with pytest.raises(err):
        sim.run_until(2.0)
    assert sim.t_s == pytest.approx(0.31)  # stopped at the step the law failed
    with pytest.raises(rpod.SimulationError, match="stopped"):
        sim.step()
    with pytest.raises(rpod.SimulationError, match="no summary"):
        sim.finish()
    # The rows up to the failure stay, under the contract's temporary name; nothing is whole.
    assert (out / "trajectory.csv.partial").stat().st_size > 0
    assert not (out / "summary.json").exists() and not (out / "trajectory.csv").exists()
    with pytest.raises(rpod.SimulationError, match="finished"):
        sim.finish()


# -- 6. bundled scenes ---------------------------------------------------------------------------
def test_bundled_scenes_are_the_repository_scenes():
    names = rpod.scenes.names()
    # Every scene of the repository (examples under examples/, papers under papers/PAPER/), not the
    # trials files.
    files = {p.stem: p for p in SCENES.rglob("*.ron") if "trials" not in p.relative_to(SCENES).parts}
    assert names == sorted(files)
    for n in names:
        assert pathlib.Path(rpod.scenes.path(n)).read_bytes() == files[n].read_bytes()
    with pytest.raises(KeyError, match="orbit_approach_latch"):
        rpod.scenes.path("../scenes/orbit_approach_latch")
    assert rpod.scenes.path("free_drift.ron") == rpod.scenes.path("free_drift")


def test_readme_example_runs_from_any_folder(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    sim = rpod.Simulation(rpod.scenes.path("orbit_approach_latch"), record=False)
    sim.run_until(1.0)
    assert sim.t_s == pytest.approx(1.0)


# -- pictures ------------------------------------------------------------------------------------
def test_render_shows_the_chaser_at_its_size():
    # Seen from above (looking down −z, world x up the picture), 1 cm per pixel, centred on the
    # chaser's centre of mass (2.07, 0, 0): its bus (1 m cube, y from −0.5 to 0.5 m) spans 100
    # columns in the middle row; along the middle column the parts run from the cone's tip
    # (x = 2.07 − 0.5 − 0.25 = 1.32 m) to the bus's back face (x = 2.57 m): 125 rows.
    sim = rpod.Simulation(scene("docking_aligned.ron"), record=False)
    img = sim.render(200, 200, look_dir=(0, 0, -1), up=(1, 0, 0), centre_m=(2.07, 0, 0),
                     span_m=2.0)
    assert img.shape == (200, 200, 3) and img.dtype == np.uint8
    background = np.array([8, 10, 22], dtype=np.uint8)
    filled = np.any(img != background, axis=2)
    assert abs(int(filled[100].sum()) - 100) <= 1
    assert abs(int(filled[:, 100].sum()) - 125) <= 1
    # x up the picture: the bus's back face 50 rows above the centre, the cone's tip 75 below.
    rows = np.nonzero(filled[:, 100])[0]
    assert abs(int(rows.min()) - 50) <= 1 and abs(int(rows.max()) - 174) <= 1


@pytest.mark.parametrize(
    "kw",
    [dict(width=0), dict(width=5000), dict(look_dir=(0, 0, 0)), dict(up=(0, 1, 0)),
     dict(span_m=float("nan")), dict(span_m=-1.0), dict(centre_m=(float("inf"), 0, 0)),
     dict(look_dir=(1, 2))],
)
def test_render_refuses_bad_views(kw):
    sim = rpod.Simulation(scene("docking_aligned.ron"), record=False)
    args = dict(width=16, height=16, look_dir=(0, 1, 0), up=(0, 0, 1))
    args.update(kw)
    with pytest.raises((ValueError, OverflowError)):
        sim.render(**args)


# -- 7. the installed package --------------------------------------------------------------------
@pytest.mark.skipif(os.environ.get("RPOD_WHEEL_TEST") != "1",
                    reason="only in CI's wheel step (RPOD_WHEEL_TEST=1)")
def test_wheel_installed_without_a_rust_toolchain():
    assert shutil.which("cargo") is None and shutil.which("rustc") is None
    here = pathlib.Path(rpod.__file__).resolve()
    assert "site-packages" in here.parts and REPO not in here.parents, here
    # The scenes are files inside the wheel, not links into a checkout.
    p = pathlib.Path(rpod.scenes.path("docking_aligned"))
    assert not p.is_symlink() and p.resolve().parent == here.parent / "scenes"
