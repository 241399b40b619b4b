"""rpod.gym.DockingEnv: Gymnasium's own checker, the episode's semantics (step after the end
raises until reset, max_episode_steps, close releases), arguments refused in the constructor,
actions validated, the parameters a policy needs in reset's info (against the scene file),
pictures, seeded determinism, random actions end in a collision, a miss or truncation (never an
exception), and a scripted approach latches.

References: the scene file docking_aligned.ron (masses, inertias, seat depth, latch and magnet
values), Gymnasium's API (gymnasium.error.ResetNeeded, TimeLimit, env_checker)."""

import gc
import math
import weakref

import numpy as np
import pytest

gym = pytest.importorskip("gymnasium")

from gymnasium.error import ResetNeeded  # noqa: E402
from gymnasium.utils.env_checker import check_env  # noqa: E402

import rpod  # noqa: E402
import rpod.gym  # noqa: E402,F401  (registers rpod/Docking-v0)
from rpod.gym import DEFAULT_SCENE, DockingEnv  # noqa: E402


def test_check_env_passes_with_pictures():
    env = gym.make("rpod/Docking-v0", render_mode="rgb_array").unwrapped
    check_env(env)


def test_spec_max_episode_steps_matches_the_environment():
    env = gym.make("rpod/Docking-v0")
    assert env.spec.max_episode_steps == env.unwrapped.max_episode_steps
    assert env.unwrapped.max_episode_steps == round(
        env.unwrapped.duration_s / env.unwrapped.control_period_s
    )


def episode(env, seed, steps):
    obs, _ = env.reset(seed=seed)
    rng = np.random.default_rng(seed)
    out = [obs]
    for _ in range(steps):
        obs, r, term, trunc, info = env.step(rng.uniform(-1, 1, 6).astype(np.float32))
        out.append(np.append(obs, r))
        if term or trunc:
            break
    return np.array(out[1:]), out[0]


def test_reset_with_a_seed_gives_identical_episodes():
    env = DockingEnv()
    a, a0 = episode(env, 7, 30)
    b, b0 = episode(env, 7, 30)
    assert np.array_equal(a0, b0) and np.array_equal(a, b)
    c, c0 = episode(env, 8, 5)
    assert not np.array_equal(a0, c0)


def test_random_actions_end_in_collision_miss_or_truncation():
    env = DockingEnv(max_force_n=20.0)
    obs, _ = env.reset(seed=3)
    rng = np.random.default_rng(3)
    for k in range(10_000):
        obs, r, term, trunc, info = env.step(rng.uniform(-1, 1, 6))
        assert np.all(np.isfinite(obs)) and np.isfinite(r)
        if term or trunc:
            break
    assert term or trunc
    t = info["reward_terms"]
    if term:
        assert t["collision"] < 0 or t["missed"] < 0 or t["latch"] > 0
    else:
        assert info["t_s"] == pytest.approx(env.duration_s)


def scripted_action(state, params):
    """Closes at min(4 cm/s, 0.08·(x − 0.2 m)) along the target port axis (aiming 5 cm past the
    seat, a gentle push through the latch dwell), PD across it (ω = 0.1 rad/s, ζ = 1), PD on the
    attitude error; in the chaser's body axes (it faces the target: a half turn about z)."""
    p, v = state["rel_pos_m"], state["rel_vel_m_s"]
    att, w = state["att_err_rad"], state["rel_omega_rad_s"]
    m = params["chaser"]["mass_kg"]
    v_ref = -min(0.04, 0.08 * (p[0] - 0.2))
    f = np.empty(3)
    f[0] = -m * 0.5 * (v[0] - v_ref)
    f[1:] = -m * (0.01 * p[1:] + 0.2 * v[1:])
    f_body = np.array([-f[0], -f[1], f[2]])
    # the attitude error is in the chaser port (= body) axes, the rates in port axes
    w_body = np.array([-w[0], -w[1], w[2]])
    tau_body = -(40.0 * att + 300.0 * w_body)
    return np.clip(np.concatenate([f_body / params["max_force_n"],
                                   tau_body / params["max_torque_nm"]]), -1, 1)


def scripted_episode(env, seed):
    obs, info = env.reset(seed=seed)
    params, total = info["params"], 0.0
    for _ in range(env.max_episode_steps):
        obs, r, term, trunc, info = env.step(scripted_action(info["state"], params))
        total += r
        if term or trunc:
            return info, total, term, trunc
    raise AssertionError("the episode did not end at max_episode_steps")


def test_a_scripted_approach_latches_and_step_after_it_raises():
    env = DockingEnv()
    info, total, term, trunc = scripted_episode(env, 1)
    assert info["docking_state"] == "LATCHED" and info["is_success"], info
    assert term and not trunc
    assert info["reward_terms"]["latch"] == 10.0 and total > 10.0
    # Stepping on after the latch would keep paying +10: it raises until reset.
    for _ in range(2):
        with pytest.raises(ResetNeeded):
            env.step(np.zeros(6))
    env.reset(seed=2)
    env.step(np.zeros(6))


def scripted_track(env, seed):
    """The scripted episode's chaser port position (target port frame, m) after every step,
    its end state, and the number of steps."""
    obs, info = env.reset(seed=seed)
    params, track = info["params"], []
    for k in range(env.max_episode_steps):
        obs, r, term, trunc, info = env.step(scripted_action(info["state"], params))
        track.append(np.asarray(info["state"]["rel_pos_m"]))
        if term or trunc:
            return np.array(track), info, k + 1
    raise AssertionError("the episode did not end at max_episode_steps")


def test_multi_rate_default_is_within_the_multirate_tolerances_of_fixed():
    # The environment steps with `MultiRate()` by default; the same scripted episodes with
    # `Fixed` (the scene's every-step run) are the reference. Tolerances: docs/scene-format.md's
    # for multi-rate against fixed-step runs (positions within 1 mm, the same docking
    # outcome, the latch within one control period: here the same step or the next).
    multi, fixed = DockingEnv(), DockingEnv(stepping="Fixed")
    assert multi.sim is None and fixed.sim is None
    long_steps, states = 0, []
    for seed in (1, 4):
        a, ia, na = scripted_track(multi, seed)
        long_steps += multi.sim.summary()["stepping"]["long_steps"]
        b, ib, nb = scripted_track(fixed, seed)
        assert "stepping" not in fixed.sim.summary()  # a fixed-step run's summary
        assert ia["docking_state"] == ib["docking_state"], (seed, ia, ib)
        states.append(ia["docking_state"])
        assert abs(na - nb) <= 1, (na, nb)
        n = min(na, nb)
        err = np.max(np.abs(a[:n] - b[:n]))
        print(f"seed {seed}: {na} and {nb} steps, largest position difference {err:.3g} m")
        assert err <= 1e-3, err
    # Seed 1 latches, seed 4 is still attracting at 40 s (its scripted law is slow there).
    assert states == ["LATCHED", "ATTRACTING"], states
    # ... and it did take long steps (else this compares Fixed with itself).
    assert long_steps > 0


def test_stepping_none_keeps_the_scene_s_own_and_bad_values_are_refused():
    env = DockingEnv(stepping=None)
    env.reset(seed=0)
    env.step(np.zeros(6))
    assert "stepping" not in env.sim.summary()  # docking_aligned's own: Fixed
    with pytest.raises(TypeError):
        DockingEnv(stepping=3)
    with pytest.raises(rpod.SceneError):
        DockingEnv(stepping="Sometimes()")


def test_truncation_at_max_episode_steps_then_step_raises():
    env = DockingEnv(duration_s=2.0, control_period_s=0.5)
    assert env.max_episode_steps == 4
    env.reset(seed=0)
    ends = [env.step(np.zeros(6))[2:4] for _ in range(4)]
    assert ends == [(False, False)] * 3 + [(False, True)]
    assert env.sim.t_s == pytest.approx(2.0)
    with pytest.raises(ResetNeeded):
        env.step(np.zeros(6))


def test_step_before_reset_and_after_close_raise():
    env = DockingEnv()
    with pytest.raises(ResetNeeded):
        env.step(np.zeros(6))
    env.reset(seed=0)
    env.close()
    assert env.sim is None
    with pytest.raises(ResetNeeded):
        env.step(np.zeros(6))
    env.reset(seed=0)  # a closed environment can start again
    env.step(np.zeros(6))


def test_close_and_del_release_the_simulation():
    # The law hosted in the simulation holds no reference to the environment: dropping the
    # environment frees both (no cycle through the Rust side, which the collector cannot see).
    env = DockingEnv()
    env.reset(seed=0)
    env.step(np.zeros(6))
    ref = weakref.ref(env)
    del env
    gc.collect()
    assert ref() is None


@pytest.mark.parametrize(
    "kw, err",
    [
        (dict(control_period_s=0.013), ValueError),
        (dict(control_period_s=0.0), ValueError),
        (dict(control_period_s=math.nan), ValueError),
        (dict(control_period_s="0.1"), TypeError),
        (dict(max_force_n=-1.0), ValueError),
        (dict(max_torque_nm=math.inf), ValueError),
        (dict(start_range_m=(1.0, 0.5)), ValueError),
        (dict(start_range_m=(0.0, 0.5)), ValueError),
        (dict(lateral_m=(math.nan, 0.1)), ValueError),
        (dict(yaw_deg=5.0), ValueError),
        (dict(obs_scale=(1.0, 0.0, 1.0, 1.0)), ValueError),
        (dict(obs_scale=(1.0, 1.0)), ValueError),
        (dict(duration_s=0.1), ValueError),
        (dict(w_progress=math.nan), ValueError),
        (dict(render_mode="ascii"), ValueError),
        (dict(scene="/no/such/scene.ron"), rpod.SceneError),
        (dict(scene=rpod.scenes.path("free_drift")), ValueError),  # no docking mechanism
    ],
)
def test_bad_constructor_arguments_are_refused_in_the_constructor(kw, err):
    with pytest.raises(err):
        DockingEnv(**kw)


def test_human_render_mode_is_refused_with_a_reason():
    with pytest.raises(ValueError, match="rgb_array"):
        DockingEnv(render_mode="human")


@pytest.mark.parametrize(
    "action, err",
    [
        (np.zeros((2, 3)), ValueError),
        (np.zeros(5), ValueError),
        (np.zeros((1, 6)), ValueError),
        (np.full(6, np.nan), ValueError),
        (np.array([np.inf, 0, 0, 0, 0, 0]), ValueError),
        (np.array([-np.inf, 0, 0, 0, 0, 0]), ValueError),
        (np.zeros(6, dtype=complex), TypeError),
        (np.array(["a"] * 6), TypeError),
        (None, TypeError),
    ],
)
def test_bad_actions_are_refused_consistently(action, err):
    env = DockingEnv()
    env.reset(seed=0)
    with pytest.raises(err):
        env.step(action)
    env.step(np.zeros(6))  # the episode goes on: a refused action changed nothing


def test_out_of_range_actions_are_clipped_as_documented():
    a, b = DockingEnv(), DockingEnv()
    a.reset(seed=4)
    b.reset(seed=4)
    big = np.array([3.0, -7.0, 1.5, -2.0, 9.0, -1.0])
    oa = a.step(big)[0]
    ob = b.step(np.clip(big, -1, 1))[0]
    assert np.array_equal(oa, ob)
    assert a.step([0, 0, 0, 0, 0, 0])[0].shape == (12,)  # a list of 6 numbers is an action


def test_reset_info_has_the_parameters_of_the_scene():
    env = DockingEnv()
    _, info = env.reset(seed=0)
    p = info["params"]
    # docking_aligned.ron: chaser 300 kg, inertia diag(110, 140, 160); target 800 kg; port at
    # x = 0.5 m body on the chaser, 0.82 m on the target; seat depth 0.25 m; latch tolerances
    # 5 mm, 3 cm, 5°, dwell 0.2 s; magnet f0 2 N, g0 5 cm, cap 5 N, on within 10 cm.
    assert p["chaser"]["mass_kg"] == 300.0 and p["target"]["mass_kg"] == 800.0
    assert np.array_equal(p["chaser"]["inertia_kg_m2"], np.diag([110.0, 140.0, 160.0]))
    assert np.array_equal(p["chaser"]["port_pos_body_m"], [0.5, 0.0, 0.0])
    assert np.array_equal(p["target"]["port_pos_body_m"], [0.82, 0.0, 0.0])
    assert p["seat_depth_m"] == 0.25 and p["mouth_radius_m"] == 0.15
    latch = p["latch"]
    assert (latch["axial_tolerance_m"], latch["lateral_tolerance_m"],
            latch["angle_tolerance_deg"], latch["dwell_s"]) == (0.005, 0.03, 5.0, 0.2)
    mag = p["magnet"]
    assert (mag["f0_n"], mag["g0_m"], mag["max_force_n"], mag["activation_distance_m"]) == (
        2.0, 0.05, 5.0, 0.1)
    assert p["max_force_n"] == env.max_force_n and p["max_torque_nm"] == env.max_torque_nm
    assert "target port frame" in p["frames"]["observation"]
    # The observation is the unscaled state over obs_scale.
    s = info["state"]
    raw = np.concatenate([s["rel_pos_m"], s["rel_vel_m_s"], s["att_err_rad"],
                          s["rel_omega_rad_s"]])
    assert np.allclose(env.reset(seed=0)[0], raw / np.repeat(env.obs_scale, 3), rtol=0,
                       atol=0)


def test_reset_options_override_ranges_and_scene_values():
    env = DockingEnv()
    _, info = env.reset(seed=0, options={"start_range_m": (1.0, 1.0), "yaw_deg": (0.0, 0.0),
                                         "set": {"bodies.chaser.mass_kg": 280.0}})
    assert info["start"]["start_range_m"] == 1.0
    assert info["state"]["rel_pos_m"][0] == pytest.approx(1.25, abs=1e-9)
    assert env.sim.body_info("chaser")["mass_kg"] == 280.0
    with pytest.raises(KeyError):
        env.reset(options={"start_rnage_m": (1.0, 1.0)})
    with pytest.raises(rpod.SceneError):
        env.reset(options={"set": {"bodies.chaser.mass_kg": -1.0}})


def test_render_rgb_array_shows_both_bodies():
    env = DockingEnv(render_mode="rgb_array")
    env.reset(seed=0)
    img = env.render()
    assert img.shape == (360, 480, 3) and img.dtype == np.uint8
    colours = {tuple(c) for c in img.reshape(-1, 3)[::7]}
    assert len(colours) > 10  # shaded faces of several parts, not a blank frame
    # The cone (orange-red: red well above green and blue) and the slot (green) are visible.
    r, g, b = (img[..., i].astype(int) for i in range(3))
    assert np.any((r > 2 * g) & (r > 2 * b) & (r > 60))
    assert np.any((g > 2 * r) & (g > b) & (g > 60))
    frame2 = env.render()
    assert np.array_equal(img, frame2)  # same state, same picture


def test_bundled_default_scene():
    assert DEFAULT_SCENE == rpod.scenes.path("docking_aligned")
