"""A Gymnasium environment for the last metres of a docking: ``rpod.gym.DockingEnv``, registered
as ``rpod/Docking-v0``.

Unlike point-mass docking environments, the agent flies the full spacecraft: the chaser's bus,
solar wings and docking cone against the target's bus, wings and slot, with rapier's contact,
the compliant cone–slot contact, the electromagnet and the latch of the scene, and the
interval-sound monitor's clearance guarantee.

Observation (``float64``, 12 numbers; target port frame: x along the target port's outward
axis, the approach axis):

====  ====================  ==========================================================
0–2   ``rel_pos_m``         chaser port origin relative to the target port origin, m
3–5   ``rel_vel_m_s``       its velocity seen in the target port frame, m/s
6–8   ``att_err_rad``       rotation vector from the facing attitude (chaser port axis
                            opposite the target's) to the chaser port frame, rad
9–11  ``rel_omega_rad_s``   chaser angular velocity less the target's, target port axes,
                            rad/s
====  ====================  ==========================================================

Action (``float32``, 6 numbers in [−1, 1]): force along the chaser's body axes as a fraction of
``max_force_n``, torque about its body axes as a fraction of ``max_torque_nm``, held for one
control period (``control_period_s``) through rpod's controller host (a Python law in the
pipeline, as ``Simulation.add_controller``).

Reward per step (the terms are also in ``info["reward_terms"]``):

- ``progress`` = ``w_progress`` · (d_before − d_after), d = distance from the chaser port to the
  seat point (the target port origin plus ``seat_depth_m`` along its axis), m;
- ``fuel`` = −``w_fuel`` · (|a_F|₁ + |a_τ|₁)/6 · Δt (the action's mean magnitude over the period);
- ``margin`` = −``w_margin`` · Δt · Σ max(0, −margin) over the scene's guarantees at the step's
  end (in each guarantee's unit: metres for the bundled scene's 5 cm clearance, which the cone
  and slot themselves enter in the last centimetres of a docking);
- ``collision`` = −``r_collision`` once (a contact that is not cone on slot), terminates;
- ``latch`` = +``r_latch`` when the mechanism latches, terminates;
- ``missed`` = −``r_missed`` when the mechanism reports MISSED, terminates.

Truncated at the scene's duration. ``reset(seed=…)`` draws the start uniformly within the
ranges the constructor takes; the same seed gives the same episode, bit for bit.
"""

from __future__ import annotations

import os
from typing import Any, Optional

import numpy as np

try:
    import gymnasium as gym
    from gymnasium import spaces
except ImportError as e:  # pragma: no cover - exercised only without gymnasium
    raise ImportError("rpod.gym needs gymnasium: pip install './python[gym]'") from e

from ._rpod import Simulation

_HERE = os.path.dirname(os.path.abspath(__file__))
#: The bundled scene (a copy of the repository's ``scenes/docking_aligned.ron``).
DEFAULT_SCENE = os.path.join(_HERE, "scenes", "docking_aligned.ron")


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


class DockingEnv(gym.Env):
    """The final approach to a docking port, on rpod's full geometry and mechanism.

    Parameters (ranges are (low, high), drawn uniformly at every reset):

    - ``scene``: the scene file (default: the bundled ``docking_aligned.ron``); it must have a
      ``docking`` mechanism; its chaser and target are the mechanism's.
    - ``start_range_m``: chaser port distance above the seat along the target port axis, m.
    - ``lateral_m``: offset of the chaser across the axis (world y and z), m.
    - ``yaw_deg``: chaser yaw error about the facing attitude, deg.
    - ``closing_speed_m_s``: initial closing speed along the axis, m/s.
    - ``max_force_n``, ``max_torque_nm``: the action's full scale.
    - ``control_period_s``: one environment step (a whole number of scene steps).
    - reward weights as in the module docs.
    """

    metadata = {"render_modes": []}

    def __init__(
        self,
        scene: Optional[str] = None,
        start_range_m: tuple = (0.5, 1.5),
        lateral_m: tuple = (-0.05, 0.05),
        yaw_deg: tuple = (-3.0, 3.0),
        closing_speed_m_s: tuple = (0.0, 0.02),
        max_force_n: float = 2.0,
        max_torque_nm: float = 1.0,
        control_period_s: float = 0.1,
        w_progress: float = 1.0,
        w_fuel: float = 0.01,
        w_margin: float = 1.0,
        r_collision: float = 10.0,
        r_latch: float = 10.0,
        r_missed: float = 5.0,
    ):
        super().__init__()
        self.scene = scene or DEFAULT_SCENE
        for name, r in [
            ("start_range_m", start_range_m),
            ("lateral_m", lateral_m),
            ("yaw_deg", yaw_deg),
            ("closing_speed_m_s", closing_speed_m_s),
        ]:
            lo, hi = r
            if not (np.isfinite(lo) and np.isfinite(hi) and lo <= hi):
                raise ValueError(f"{name}: a (low, high) range of finite numbers, got {r!r}")
        if not (0.0 < max_force_n < 1e6 and 0.0 < max_torque_nm < 1e6):
            raise ValueError("max_force_n and max_torque_nm must be positive and below 1e6")
        self.ranges = dict(
            start_range_m=start_range_m,
            lateral_m=lateral_m,
            yaw_deg=yaw_deg,
            closing_speed_m_s=closing_speed_m_s,
        )
        self.max_force_n = float(max_force_n)
        self.max_torque_nm = float(max_torque_nm)
        self.control_period_s = float(control_period_s)
        self.w = dict(progress=w_progress, fuel=w_fuel, margin=w_margin)
        self.r = dict(collision=r_collision, latch=r_latch, missed=r_missed)
        # Bounds: 1 km, 100 m/s, π rad, 100 rad/s (far beyond any docking; not clipped).
        hi = np.array([1e3] * 3 + [1e2] * 3 + [np.pi] * 3 + [1e2] * 3)
        self.observation_space = spaces.Box(-hi, hi, dtype=np.float64)
        self.action_space = spaces.Box(-1.0, 1.0, shape=(6,), dtype=np.float32)
        probe = Simulation(self.scene, record=False)
        dock = probe.docking()
        if not dock:
            raise ValueError(f"{self.scene}: DockingEnv needs a scene with a docking mechanism")
        self._names = (dock["chaser"], dock["chaser_port"], dock["target"], dock["target_port"])
        self._seat_depth_m = float(dock["seat_depth_m"])
        t = probe.state(self._names[2])
        self._target_pos = np.asarray(t["pos_m"])
        self._target_q = np.asarray(t["quat_wxyz"])
        rel = probe.port_relative(*self._names)
        self._target_port_pos = np.asarray(rel["target"]["pos_m"])
        self._target_port_axis = np.asarray(rel["target"]["axis"])
        # Chaser centre of mass relative to its port, in the world frame at the scene's start.
        c = probe.state(self._names[0])
        self._com_from_port = np.asarray(c["pos_m"]) - np.asarray(rel["chaser"]["pos_m"])
        self.dt_s = probe.dt_s
        self.duration_s = probe.duration_s
        self.sim: Optional[Simulation] = None
        self._action = np.zeros(6)

    # The law the controller host calls every control period: the current action.
    def _law(self, obs: dict) -> dict:
        a = self._action
        return {
            "force_n": a[:3] * self.max_force_n,
            "torque_nm": a[3:] * self.max_torque_nm,
            "frame": "body",
        }

    def _seat(self) -> np.ndarray:
        return np.array([self._seat_depth_m, 0.0, 0.0])

    def _observe(self) -> np.ndarray:
        rel = self.sim.port_relative(*self._names)
        q_t = np.asarray(rel["target"]["quat_wxyz"])
        err = _qmul(_qconj(_FACING), np.asarray(rel["rel_quat_wxyz"]))
        w = np.asarray(rel["chaser_omega_rad_s"]) - np.asarray(rel["target_omega_rad_s"])
        w_port = _qrot(_qconj(q_t), w)
        self._rel = rel
        return np.concatenate(
            [np.asarray(rel["rel_pos_m"]), np.asarray(rel["rel_vel_m_s"]), _rotvec(err), w_port]
        ).astype(np.float64)

    def _distance(self) -> float:
        return float(np.linalg.norm(np.asarray(self._rel["rel_pos_m"]) - self._seat()))

    def reset(self, *, seed: Optional[int] = None, options: Optional[dict] = None):
        super().reset(seed=seed)
        rng = self.np_random
        g = {
            k: float(rng.uniform(*v)) for k, v in self.ranges.items() if k != "lateral_m"
        }
        lat_y = float(rng.uniform(*self.ranges["lateral_m"]))
        lat_z = float(rng.uniform(*self.ranges["lateral_m"]))
        axis = self._target_port_axis
        port = self._target_port_pos + axis * (self._seat_depth_m + g["start_range_m"])
        port = port + np.array([0.0, lat_y, lat_z])
        com = port + self._com_from_port
        vel = -axis * g["closing_speed_m_s"]
        overrides = {
            "bodies.chaser.initial.pos_m": "({!r}, {!r}, {!r})".format(*map(float, com)),
            "bodies.chaser.initial.vel_m_s": "({!r}, {!r}, {!r})".format(*map(float, vel)),
            "bodies.chaser.initial.attitude": (
                "EulerZyxDeg(yaw: {!r}, pitch: 0.0, roll: 0.0)".format(180.0 + g["yaw_deg"])
            ),
        }
        if self._names[0] != "chaser":
            overrides = {
                k.replace("bodies.chaser.", f"bodies.{self._names[0]}."): v
                for k, v in overrides.items()
            }
        self.sim = Simulation(self.scene, set=overrides, record=False)
        self._action = np.zeros(6)
        self.sim.add_controller(
            self._law, body=self._names[0], period_s=self.control_period_s
        )
        self._steps_per_action = int(round(self.control_period_s / self.dt_s))
        self._latched = False
        obs = self._observe()
        self._d = self._distance()
        return obs, {"start": g, "lateral_m": (lat_y, lat_z)}

    def step(self, action):
        if self.sim is None:
            raise RuntimeError("call reset() before step()")
        a = np.clip(np.asarray(action, dtype=np.float64).reshape(6), -1.0, 1.0)
        if not np.all(np.isfinite(a)):
            raise ValueError(f"action must be finite, got {action!r}")
        self._action = a
        self.sim.step(self._steps_per_action)
        obs = self._observe()
        d = self._distance()
        m = self.sim.monitor()
        dt = self._steps_per_action * self.dt_s
        terms = {
            "progress": self.w["progress"] * (self._d - d),
            "fuel": -self.w["fuel"] * float(np.abs(a).sum()) / 6.0 * dt,
            "margin": -self.w["margin"]
            * dt
            * sum(max(0.0, -g["margin"]) for g in m["guarantees"]),
            "collision": 0.0,
            "latch": 0.0,
            "missed": 0.0,
        }
        self._d = d
        terminated = False
        state = m["docking_state"]
        if m["first_collision_s"] is not None:
            terms["collision"] = -self.r["collision"]
            terminated = True
        if state == "LATCHED":
            terms["latch"] = self.r["latch"]
            terminated = True
        elif state == "MISSED":
            terms["missed"] = -self.r["missed"]
            terminated = True
        truncated = (not terminated) and self.sim.t_s >= self.duration_s - 0.5 * self.dt_s
        info = {
            "t_s": self.sim.t_s,
            "docking_state": state,
            "distance_to_seat_m": d,
            "min_distance_m": m["min_distance_m"],
            "reward_terms": terms,
        }
        return obs, float(sum(terms.values())), terminated, truncated, info


gym.register(id="rpod/Docking-v0", entry_point="rpod.gym:DockingEnv")
