"""rpod.gym.DockingEnv: Gymnasium's own checker, seeded determinism, random actions end in a
collision, a miss or truncation (never an exception), and a scripted approach latches."""

import numpy as np
import pytest

gym = pytest.importorskip("gymnasium")

from gymnasium.utils.env_checker import check_env  # noqa: E402

import rpod.gym  # noqa: E402,F401  (registers rpod/Docking-v0)
from conftest import SCENES  # noqa: E402
from rpod.gym import DEFAULT_SCENE, DockingEnv  # noqa: E402


def test_bundled_scene_is_the_repository_scene():
    assert open(DEFAULT_SCENE, "rb").read() == (SCENES / "docking_aligned.ron").read_bytes()


def test_check_env_passes():
    env = gym.make("rpod/Docking-v0").unwrapped
    check_env(env, skip_render_check=True)


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
    a, a0 = episode(env, 7, 60)
    b, b0 = episode(env, 7, 60)
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


def scripted_action(obs):
    """Closes at min(4 cm/s, 0.08·(x − 0.2 m)) along the target port axis (aiming 5 cm past the
    seat, a gentle push through the latch dwell), PD across it (ω = 0.1 rad/s, ζ = 1), PD on the
    attitude error; in the chaser's body axes (it faces the target: a half turn about z)."""
    p, v, att, w = obs[:3], obs[3:6], obs[6:9], obs[9:]
    m = 300.0
    v_ref = -min(0.04, 0.08 * (p[0] - 0.2))
    f = np.empty(3)
    f[0] = -m * 0.5 * (v[0] - v_ref)
    f[1:] = -m * (0.01 * p[1:] + 0.2 * v[1:])
    f_body = np.array([-f[0], -f[1], f[2]])
    # the attitude error is in the chaser port (= body) axes, the rates in port axes
    w_body = np.array([-w[0], -w[1], w[2]])
    tau_body = -(40.0 * att + 300.0 * w_body)
    return np.clip(np.concatenate([f_body / 2.0, tau_body / 1.0]), -1, 1)


def test_a_scripted_approach_latches():
    env = DockingEnv()
    obs, _ = env.reset(seed=1)
    total = 0.0
    for _ in range(400):
        obs, r, term, trunc, info = env.step(scripted_action(obs))
        total += r
        if term or trunc:
            break
    assert info["docking_state"] == "LATCHED", info
    assert info["reward_terms"]["latch"] == 10.0 and total > 10.0
