"""A Gymnasium environment for the last metres of a docking: ``rpod.gym.DockingEnv``, registered
as ``rpod/Docking-v0``.

Unlike point-mass docking environments, the agent flies the full spacecraft: the chaser's bus,
solar wings and docking cone against the target's bus, wings and slot, with rapier's contact,
the compliant cone–slot contact, the electromagnet and the latch of the scene, and the
interval-sound monitor's clearance guarantee. The physics is the scene's; the environment only
chooses the start, the action's full scale, the observation's scale and the reward.

Observation (``float64``, 12 numbers, each divided by its entry of ``obs_scale``; target port
frame: x along the target port's outward axis, the approach axis):

====  ====================  ==========================================================  =====
0–2   ``rel_pos_m``         chaser port origin relative to the target port origin, m     1 m
3–5   ``rel_vel_m_s``       its velocity seen in the target port frame, m/s              0.1
6–8   ``att_err_rad``       rotation vector from the facing attitude (chaser port axis    0.1
                            opposite the target's) to the chaser port frame, rad
9–11  ``rel_omega_rad_s``   chaser angular velocity less the target's, target port axes,  0.02
                            rad/s
====  ====================  ==========================================================  =====

(last column: the default scale, so that a docking's values are of order one for a neural
network; ``info["state"]`` has the same quantities unscaled, in SI units.)

Action (``float32``, 6 numbers in [−1, 1]): force along the chaser's body axes as a fraction of
``max_force_n``, torque about its body axes as a fraction of ``max_torque_nm``, held for one
control period (``control_period_s``) through rpod's controller host (a Python law in the
pipeline, as ``Simulation.add_controller``). An action must be 6 finite real numbers (any shape
with 6 elements is refused unless it is ``(6,)``); values outside [−1, 1] are clipped to it, as
an agent's Gaussian samples are (Stable-Baselines3 clips them before ``step`` too).

Reward per step (the terms are also in ``info["reward_terms"]``), d = distance from the chaser
port to the seat point (the target port origin plus ``seat_depth_m`` along its axis), m, and
θ = the misalignment of the port axes, rad:

- ``progress`` = ``w_progress`` · (d_before − d_after);
- ``align`` = ``w_align`` · (θ_before − θ_after) (both are differences of a potential, so they
  reward getting closer and better aligned without changing which policy is best);
- ``fuel`` = −``w_fuel`` · (|a_F|₁ + |a_τ|₁)/6 · Δt (the action's mean magnitude over the period);
- ``margin`` = −``w_margin`` · Δt · Σ max(0, −margin) over the scene's guarantees at the step's
  end (in each guarantee's unit: metres for the bundled scene's 5 cm clearance, which the cone
  and slot themselves enter in the last centimetres of a docking);
- ``collision`` = −``r_collision`` once (a contact that is not cone on slot), terminates;
- ``latch`` = +``r_latch`` when the mechanism docks (LATCHED; HARD_DOCKED with a SoftCapture
  mechanism: ``docked_state``), terminates (``info["is_success"]``);
- ``missed`` = −``r_missed`` when the mechanism reports MISSED, or when the chaser port strays
  farther than ``max_range_m`` from the seat (``info["departed"]``), terminates.

Truncated at ``duration_s`` (default: the scene's), that is after ``max_episode_steps``
steps (also the registered ``spec.max_episode_steps``). ``step`` after the end of an episode,
before the first ``reset`` or after ``close`` raises ``gymnasium.error.ResetNeeded``.
``reset(seed=…)`` draws the start uniformly within the ranges (constructor, ``set_ranges``, or
this reset's ``options``); the same seed gives the same episode, bit for bit.
``render_mode="rgb_array"``: ``render()`` returns an orthographic picture of every part
(``Simulation.render``); ``"human"`` is refused (no window from Python: record the frames, or a
run for ``rpod replay``).
"""

from __future__ import annotations

import copy
import math
from typing import Any, Dict, Optional, Tuple

import numpy as np

try:
    import gymnasium as gym
    from gymnasium import spaces
    from gymnasium.error import ResetNeeded
except ImportError as e:  # pragma: no cover - exercised only without gymnasium
    raise ImportError("rpod.gym needs gymnasium: pip install 'rpod[gym]'") from e

from . import scenes
from ._rpod import Simulation

#: The bundled scene ``docking_aligned``.
DEFAULT_SCENE = scenes.path("docking_aligned")

#: Default observation scale: position 1 m, velocity 0.1 m/s, attitude error 0.1 rad, rate
#: 0.02 rad/s (a docking's values are then of order one).
DEFAULT_OBS_SCALE = (1.0, 0.1, 0.1, 0.02)

_RANGES = ("start_range_m", "lateral_m", "yaw_deg", "closing_speed_m_s")


def _qmul(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    aw, ax, ay, az = a
    bw, bx, by, bz = b
    return np.array(
        [
            aw * bw - ax * bx - ay * by - az * bz,
            aw * bx + ax * bw + ay * bz - az * by,
            aw * by - ax * bz + ay * bw + az * bx,
            aw * bz + ax * by - ay * bx + az * bw,
        ]
    )


def _qconj(q: np.ndarray) -> np.ndarray:
    return np.array([q[0], -q[1], -q[2], -q[3]])


def _qrot(q: np.ndarray, v: np.ndarray) -> np.ndarray:
    return _qmul(_qmul(q, np.array([0.0, *v])), _qconj(q))[1:]


def _rotvec(q: np.ndarray) -> np.ndarray:
    if q[0] < 0.0:
        q = -q
    s = float(np.linalg.norm(q[1:]))
    if s < 1e-12:
        return 2.0 * q[1:]
    return q[1:] * (2.0 * np.arctan2(s, q[0]) / s)


#: Chaser port frame → target port frame when facing: a half turn about the port frames' z.
_FACING = np.array([0.0, 0.0, 0.0, 1.0])


def _finite(name: str, x: Any, lo: float = -math.inf, hi: float = math.inf) -> float:
    """A real number within [lo, hi], or a ValueError naming the argument."""
    if isinstance(x, (bool, np.bool_)) or not isinstance(x, (int, float, np.integer, np.floating)):
        raise TypeError(f"{name} must be a real number, got {type(x).__name__} {x!r}")
    v = float(x)
    if not (math.isfinite(v) and lo <= v <= hi):
        raise ValueError(f"{name} must be a finite number in [{lo:g}, {hi:g}], got {x!r}")
    return v


def _range(name: str, r: Any, lo: float, hi: float) -> Tuple[float, float]:
    """A (low, high) pair of finite numbers with lo ≤ low ≤ high ≤ hi."""
    try:
        a, b = r
    except (TypeError, ValueError):
        raise ValueError(f"{name}: a (low, high) pair, got {r!r}") from None
    a = _finite(f"{name}[0]", a, lo, hi)
    b = _finite(f"{name}[1]", b, lo, hi)
    if a > b:
        raise ValueError(f"{name}: low {a} above high {b}")
    return (a, b)


#: Limits of the start ranges: (low, high) of each bound (a chaser port at least 1 cm above the
#: seat and at most 100 m away; an offset within 10 m; a yaw error within ±90°; a closing
#: speed within ±1 m/s).
_RANGE_LIMITS = {
    "start_range_m": (0.01, 100.0),
    "lateral_m": (-10.0, 10.0),
    "yaw_deg": (-90.0, 90.0),
    "closing_speed_m_s": (-1.0, 1.0),
}


class _HeldAction:
    """The law the controller host calls every control period: the current command (it holds no
    reference to the environment, so an environment and its simulation are freed together)."""

    __slots__ = ("command",)

    def __init__(self) -> None:
        self.command = {"force_n": np.zeros(3), "torque_nm": np.zeros(3), "frame": "body"}

    def __call__(self, obs: dict) -> dict:
        return self.command


class DockingEnv(gym.Env):
    """The final approach to a docking port, on rpod's full geometry and mechanism.

    Parameters (ranges are (low, high), drawn uniformly at every reset):

    - ``scene``: the scene file (default: the bundled ``docking_aligned``); it must have a
      ``docking`` mechanism; its chaser and target are the mechanism's.
    - ``start_range_m``: chaser port distance above the seat along the target port axis, m.
    - ``lateral_m``: offset of the chaser across the axis (world y and z), m.
    - ``yaw_deg``: chaser yaw error about the facing attitude, deg.
    - ``closing_speed_m_s``: initial closing speed along the axis, m/s.
    - ``max_force_n``, ``max_torque_nm``: the action's full scale (body axes).
    - ``control_period_s``: one environment step (a whole number of scene steps).
    - ``duration_s``: the episode's length (default: the scene's duration).
    - ``max_range_m``: the episode ends as a miss when the chaser port is farther than this
      from the seat, m.
    - ``obs_scale``: the four divisors of the observation (position m, velocity m/s, attitude
      rad, rate rad/s).
    - reward weights as in the module docs; ``render_mode``: None or ``"rgb_array"``.
    - ``stepping``: the scene's ``stepping`` for every episode (docs/multirate.md):
      ``"MultiRate()"`` by default — steps longer than ``dt_s`` only where the monitor proves
      that no contact can begin and no guarantee margin can change sign, the control period's
      boundaries kept exact — about 1.8× the environment steps per second of ``"Fixed"`` with
      random actions, every result within the multi-rate tolerances of the fixed-step run;
      ``"Fixed"`` for the scene's fixed step everywhere; None for the scene's own setting. A
      reset's ``options["set"]`` may still override it.
    """

    metadata = {"render_modes": ["rgb_array"], "render_fps": 2}

    def __init__(
        self,
        scene: Optional[str] = None,
        start_range_m: Tuple[float, float] = (0.5, 1.5),
        lateral_m: Tuple[float, float] = (-0.05, 0.05),
        yaw_deg: Tuple[float, float] = (-3.0, 3.0),
        closing_speed_m_s: Tuple[float, float] = (0.0, 0.02),
        max_force_n: float = 5.0,
        max_torque_nm: float = 0.2,
        control_period_s: float = 0.5,
        duration_s: Optional[float] = None,
        max_range_m: float = 3.0,
        obs_scale: Tuple[float, float, float, float] = DEFAULT_OBS_SCALE,
        w_progress: float = 1.0,
        w_align: float = 1.0,
        w_fuel: float = 0.01,
        w_margin: float = 1.0,
        r_collision: float = 10.0,
        r_latch: float = 10.0,
        r_missed: float = 5.0,
        render_mode: Optional[str] = None,
        stepping: Optional[str] = "MultiRate()",
    ):
        super().__init__()
        if render_mode == "human":
            raise ValueError(
                "render_mode='human' is not offered: rpod opens no window from Python. Use "
                "render_mode='rgb_array' (render() returns an image of every part; "
                "gymnasium.wrappers.RecordVideo writes videos), or record a run with "
                "rpod.Simulation(..., out_dir=…) and watch it with `rpod replay`."
            )
        if render_mode not in (None, "rgb_array"):
            raise ValueError(f"render_mode: None or 'rgb_array', got {render_mode!r}")
        self.render_mode = render_mode
        self.scene = str(scene) if scene is not None else DEFAULT_SCENE
        self.ranges: Dict[str, Tuple[float, float]] = {}
        self.set_ranges(
            start_range_m=start_range_m,
            lateral_m=lateral_m,
            yaw_deg=yaw_deg,
            closing_speed_m_s=closing_speed_m_s,
        )
        self.max_force_n = _finite("max_force_n", max_force_n, 0.0, 1e6)
        self.max_torque_nm = _finite("max_torque_nm", max_torque_nm, 0.0, 1e6)
        if self.max_force_n <= 0.0 or self.max_torque_nm <= 0.0:
            raise ValueError("max_force_n and max_torque_nm must be positive")
        self.max_range_m = _finite("max_range_m", max_range_m, 0.0, 1e3)
        try:
            scale = [_finite(f"obs_scale[{i}]", s, 0.0, 1e6) for i, s in enumerate(obs_scale)]
        except TypeError:
            raise TypeError(f"obs_scale: 4 positive numbers, got {obs_scale!r}") from None
        if len(scale) != 4 or min(scale) <= 0.0:
            raise ValueError(f"obs_scale: 4 positive numbers, got {obs_scale!r}")
        self.obs_scale = tuple(scale)
        self._scale = np.repeat(np.array(scale), 3)
        self.w = dict(
            progress=_finite("w_progress", w_progress, -1e6, 1e6),
            align=_finite("w_align", w_align, -1e6, 1e6),
            fuel=_finite("w_fuel", w_fuel, -1e6, 1e6),
            margin=_finite("w_margin", w_margin, -1e6, 1e6),
        )
        self.r = dict(
            collision=_finite("r_collision", r_collision, -1e6, 1e6),
            latch=_finite("r_latch", r_latch, -1e6, 1e6),
            missed=_finite("r_missed", r_missed, -1e6, 1e6),
        )

        if stepping is not None and not isinstance(stepping, str):
            raise TypeError(f"stepping: a string ('MultiRate()', 'Fixed') or None, got {stepping!r}")
        self._stepping = {} if stepping is None else {"stepping": stepping}
        # The scene, loaded once here (a SceneError now, not at the first reset; a bad
        # `stepping` too).
        probe = Simulation(self.scene, set=self._stepping, record=False)
        dock = probe.docking()
        if not dock:
            raise ValueError(f"{self.scene}: DockingEnv needs a scene with a docking mechanism")
        # The state a successful docking ends in with this scene's mechanism: LATCHED for the
        # cone and slot, HARD_DOCKED for the soft-capture mechanism.
        self.docked_state = dock["docked_state"]
        self.dt_s = probe.dt_s
        self.control_period_s = _finite("control_period_s", control_period_s, 0.0, 1e6)
        n = self.control_period_s / self.dt_s
        if not (round(n) >= 1 and abs(n - round(n)) <= 1e-9 * n):
            raise ValueError(
                f"control_period_s must be a whole number (≥ 1) of the scene's steps "
                f"dt_s = {self.dt_s} s, got {control_period_s!r}"
            )
        self._steps_per_action = int(round(n))
        self.duration_s = (
            probe.duration_s
            if duration_s is None
            else _finite("duration_s", duration_s, 0.0, 1e7)
        )
        if self.duration_s < self.control_period_s:
            raise ValueError(
                f"duration_s ({self.duration_s} s) is shorter than one control period "
                f"({self.control_period_s} s)"
            )
        #: Steps of an episode before truncation.
        self.max_episode_steps = int(math.ceil(self.duration_s / self.control_period_s - 1e-9))
        self.metadata = dict(self.metadata, render_fps=1.0 / self.control_period_s)

        self._names = (dock["chaser"], dock["chaser_port"], dock["target"], dock["target_port"])
        self._seat_depth_m = float(dock["seat_depth_m"])
        t = probe.state(self._names[2])
        rel = probe.port_relative(*self._names)
        self._target_port_pos = np.asarray(rel["target"]["pos_m"])
        self._target_port_axis = np.asarray(rel["target"]["axis"])
        # Chaser centre of mass relative to its port, in the world frame at the scene's start.
        c = probe.state(self._names[0])
        self._com_from_port = np.asarray(c["pos_m"]) - np.asarray(rel["chaser"]["pos_m"])
        self._target_pos = np.asarray(t["pos_m"])
        self.params = self._parameters(probe, dock)

        # Bounds: 1 km, 100 m/s, π rad, 100 rad/s (far beyond any docking; not clipped).
        hi = np.array([1e3] * 3 + [1e2] * 3 + [np.pi] * 3 + [1e2] * 3) / self._scale
        self.observation_space = spaces.Box(-hi, hi, dtype=np.float64)
        self.action_space = spaces.Box(-1.0, 1.0, shape=(6,), dtype=np.float32)
        self.sim: Optional[Simulation] = None
        self._held = _HeldAction()
        self._needs_reset = True
        self._steps = 0
        self._view: Optional[dict] = None

    # -- parameters a policy needs ------------------------------------------------------------
    def _parameters(self, sim: Simulation, dock: dict) -> dict:
        chaser = sim.body_info(self._names[0])
        target = sim.body_info(self._names[2])
        spec = dock["spec"]

        def body(b: dict, port: str) -> dict:
            return {
                "name": b["name"],
                "mass_kg": b["mass_kg"],
                "inertia_kg_m2": b["inertia_kg_m2"],
                "com_body_m": b["com_body_m"],
                "bounding_radius_m": b["bounding_radius_m"],
                "port": port,
                "port_pos_body_m": b["ports"][port]["pos_body_m"],
                "port_axis_body": b["ports"][port]["axis_body"],
            }

        return {
            "chaser": body(chaser, self._names[1]),
            "target": body(target, self._names[3]),
            "max_force_n": self.max_force_n,
            "max_torque_nm": self.max_torque_nm,
            "control_period_s": self.control_period_s,
            "dt_s": self.dt_s,
            "duration_s": self.duration_s,
            "seat_depth_m": self._seat_depth_m,
            "mouth_radius_m": dock["mouth_radius_m"],
            "latch": spec["latch"],
            "magnet": spec["magnet"],
            "contact_model": dock["contact_model"],
            "obs_scale": self.obs_scale,
            "frames": {
                "observation": "target port frame: x along the target port's outward axis "
                "(the approach axis), origin at the target port",
                "action": "chaser body axes (force through the centre of mass, torque)",
                "att_err": "rotation vector from the facing attitude to the chaser port "
                "frame, chaser port axes",
            },
        }

    def set_ranges(self, **ranges: Tuple[float, float]) -> None:
        """Changes start ranges for the following resets (a curriculum): any of
        ``start_range_m``, ``lateral_m``, ``yaw_deg``, ``closing_speed_m_s``."""
        for k, r in ranges.items():
            if k not in _RANGES:
                raise KeyError(f"unknown range {k!r} (one of {', '.join(_RANGES)})")
            self.ranges[k] = _range(k, r, *_RANGE_LIMITS[k])

    # -- observation ----------------------------------------------------------------------------
    def _observe(self) -> np.ndarray:
        rel = self.sim.port_relative(*self._names)
        q_t = np.asarray(rel["target"]["quat_wxyz"])
        err = _qmul(_qconj(_FACING), np.asarray(rel["rel_quat_wxyz"]))
        w = np.asarray(rel["chaser_omega_rad_s"]) - np.asarray(rel["target_omega_rad_s"])
        w_port = _qrot(_qconj(q_t), w)
        self._rel = rel
        self._raw = np.concatenate(
            [np.asarray(rel["rel_pos_m"]), np.asarray(rel["rel_vel_m_s"]), _rotvec(err), w_port]
        ).astype(np.float64)
        return self._raw / self._scale

    def _state(self) -> dict:
        r = self._raw
        return {
            "rel_pos_m": r[0:3].copy(),
            "rel_vel_m_s": r[3:6].copy(),
            "att_err_rad": r[6:9].copy(),
            "rel_omega_rad_s": r[9:12].copy(),
        }

    def _distance(self) -> float:
        p = np.asarray(self._rel["rel_pos_m"])
        return float(math.sqrt((p[0] - self._seat_depth_m) ** 2 + p[1] ** 2 + p[2] ** 2))

    # -- Gymnasium API --------------------------------------------------------------------------
    def reset(self, *, seed: Optional[int] = None, options: Optional[dict] = None):
        """Starts an episode. ``options`` (optional): any of the four ranges for this reset
        only, and ``set``: scene overrides as in ``rpod.Simulation(set=…)`` (a domain
        randomisation: ``{"bodies.chaser.mass_kg": 280.0}``)."""
        super().reset(seed=seed)
        options = dict(options or {})
        overrides_extra = options.pop("set", None) or {}
        if not isinstance(overrides_extra, dict):
            raise TypeError("options['set'] must be a dict of scene overrides")
        ranges = dict(self.ranges)
        for k in list(options):
            if k not in _RANGES:
                raise KeyError(f"unknown reset option {k!r} (set, {', '.join(_RANGES)})")
            ranges[k] = _range(k, options.pop(k), *_RANGE_LIMITS[k])
        rng = self.np_random
        g = {k: float(rng.uniform(*v)) for k, v in ranges.items() if k != "lateral_m"}
        lat_y = float(rng.uniform(*ranges["lateral_m"]))
        lat_z = float(rng.uniform(*ranges["lateral_m"]))
        axis = self._target_port_axis
        port = self._target_port_pos + axis * (self._seat_depth_m + g["start_range_m"])
        port = port + np.array([0.0, lat_y, lat_z])
        com = port + self._com_from_port
        vel = -axis * g["closing_speed_m_s"]
        body = f"bodies.{self._names[0]}"
        overrides = {
            **self._stepping,
            f"{body}.initial.pos_m": "({!r}, {!r}, {!r})".format(*map(float, com)),
            f"{body}.initial.vel_m_s": "({!r}, {!r}, {!r})".format(*map(float, vel)),
            f"{body}.initial.attitude": (
                "EulerZyxDeg(yaw: {!r}, pitch: 0.0, roll: 0.0)".format(180.0 + g["yaw_deg"])
            ),
        }
        overrides.update(overrides_extra)
        # The previous episode's simulation is released first.
        self.sim = None
        self._needs_reset = True
        sim = Simulation(self.scene, set=overrides, record=False)
        self._held = _HeldAction()
        sim.add_controller(self._held, body=self._names[0], period_s=self.control_period_s)
        self.sim = sim
        self._needs_reset = False
        self._steps = 0
        self._view = None
        obs = self._observe()
        self._d = self._distance()
        self._theta = float(self._rel["misalignment_rad"])
        info = {
            "start": g,
            "lateral_m": (lat_y, lat_z),
            "state": self._state(),
            "params": copy.deepcopy(self.params),
        }
        return obs, info

    def _action(self, action: Any) -> np.ndarray:
        a = np.asarray(action)
        if a.dtype.kind not in "fiu":
            raise TypeError(
                f"action must be real numbers (float or int), got dtype {a.dtype} ({action!r})"
            )
        if a.shape != (6,):
            raise ValueError(f"action must have shape (6,), got {a.shape}")
        a = a.astype(np.float64)
        if not np.all(np.isfinite(a)):
            raise ValueError(f"action must be finite, got {action!r}")
        return np.clip(a, -1.0, 1.0)

    def step(self, action):
        if self._needs_reset or self.sim is None:
            raise ResetNeeded(
                "call reset(): the episode has ended (terminated or truncated), the "
                "environment was closed, or it was never reset"
            )
        a = self._action(action)
        self._held.command = {
            "force_n": a[:3] * self.max_force_n,
            "torque_nm": a[3:] * self.max_torque_nm,
            "frame": "body",
        }
        try:
            self.sim.step(self._steps_per_action)
        except BaseException:
            # The run stopped at a step that failed: this episode cannot go on.
            self._needs_reset = True
            raise
        self._steps += 1
        obs = self._observe()
        d = self._distance()
        theta = float(self._rel["misalignment_rad"])
        m = self.sim.monitor()
        dt = self._steps_per_action * self.dt_s
        terms = {
            "progress": self.w["progress"] * (self._d - d),
            "align": self.w["align"] * (self._theta - theta),
            "fuel": -self.w["fuel"] * float(np.abs(a).sum()) / 6.0 * dt,
            "margin": -self.w["margin"]
            * dt
            * sum(max(0.0, -g["margin"]) for g in m["guarantees"]),
            "collision": 0.0,
            "latch": 0.0,
            "missed": 0.0,
        }
        self._d = d
        self._theta = theta
        terminated = False
        state = m["docking_state"]
        departed = False
        if m["first_collision_s"] is not None:
            terms["collision"] = -self.r["collision"]
            terminated = True
        if state == self.docked_state:
            terms["latch"] = self.r["latch"]
            terminated = True
        elif state == "MISSED":
            terms["missed"] = -self.r["missed"]
            terminated = True
        elif d > self.max_range_m and not terminated:
            terms["missed"] = -self.r["missed"]
            departed = True
            terminated = True
        truncated = (not terminated) and self._steps >= self.max_episode_steps
        info = {
            "t_s": self.sim.t_s,
            "docking_state": state,
            "is_success": state == self.docked_state,
            "departed": departed,
            "distance_to_seat_m": d,
            "misalignment_rad": theta,
            "min_distance_m": m["min_distance_m"],
            "state": self._state(),
            "reward_terms": terms,
        }
        if terminated or truncated:
            self._needs_reset = True
        return obs, float(sum(terms.values())), terminated, truncated, info

    def render(self):
        """The scene now as an RGB array (height 360, width 480) with ``render_mode="rgb_array"``:
        seen from the side of the approach, a little from above and from the chaser's side (the
        slot's face and the cone visible; world z up), the framing fixed for the episode so
        that a video does not zoom."""
        if self.render_mode is None:
            gym.logger.warn(
                "render() without a render_mode: make the environment with "
                "render_mode='rgb_array'"
            )
            return None
        if self.sim is None:
            raise ResetNeeded("call reset() before render()")
        look = (-0.35, 1.0, -0.45)
        if self._view is None:
            # Every part at the start, with room for the chaser to move: the fitted width
            # grown by a third (the chaser starts at most 1.5 m from the seat).
            fit = self.sim.render(480, 360, look_dir=look, up=(0.0, 0.0, 1.0), fit_only=True)
            self._view = {"centre_m": fit["centre_m"], "span_m": fit["span_m"] * 4.0 / 3.0}
        return self.sim.render(480, 360, look_dir=look, up=(0.0, 0.0, 1.0), **self._view)

    def close(self):
        """Releases the simulation (a later ``reset`` starts a new one)."""
        self.sim = None
        self._needs_reset = True
        super().close()


gym.register(
    id="rpod/Docking-v0",
    entry_point="rpod.gym:DockingEnv",
    # 40 s of the bundled scene at the default 0.5 s control period (the environment also
    # truncates itself at its own max_episode_steps, whatever the wrapper says).
    max_episode_steps=80,
)
