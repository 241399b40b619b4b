"""Laws written in Python for the tests, each the mirror of a Rust law it is compared with."""

import numpy as np


def qrot(q, v):
    """Rotates v by the unit quaternion q = (w, x, y, z)."""
    w, x, y, z = q
    u = np.array([x, y, z])
    t = 2.0 * np.cross(u, v)
    return v + w * t + np.cross(u, t)


class HillPd:
    """The Python twin of rpod's `HillPd` with `Pd` gains and `point: CentreOfMass`
    (src/control/generic/hill.rs): a = −f_cw(x, ẋ) − ω²e − 2ζω ė in the target's Hill frame,
    F = m a. Written with the same floating-point operations in the same order, so the two
    give the same bits."""

    COLUMNS = [
        f"hill_pd.{q}_hill_{a}_{u}"
        for q, u in [("err", "m"), ("err_vel", "m_s"), ("accel_cmd", "m_s2")]
        for a in "xyz"
    ]

    def __init__(self, hold_m, natural_frequency_rad_s, damping_ratio):
        self.hold = np.array(hold_m, dtype=float)
        self.hold_vel = np.zeros(3)
        w, z = natural_frequency_rad_s, damping_ratio
        self.kp = w * w
        self.kd = 2.0 * z * w
        self.t0 = None

    def __call__(self, obs):
        rel = obs["relative"]
        h = rel["hill"]
        n = rel["mean_motion_rad_s"]
        x, v = h["pos_m"], h["vel_m_s"]
        if self.t0 is None:
            self.t0 = obs["t_s"]
        x_ref = self.hold + self.hold_vel * (obs["t_s"] - self.t0)
        v_ref = self.hold_vel
        cw = np.array(
            [3.0 * n * n * x[0] + 2.0 * n * v[1], -2.0 * n * v[0], -n * n * x[2]]
        )
        e = x - x_ref
        ed = v - v_ref
        a = np.zeros(3) - cw - e * self.kp - ed * self.kd
        diag = dict(zip(self.COLUMNS, [*e, *ed, *a]))
        return {
            "force_n": a * obs["mass_kg"],
            "torque_nm": np.zeros(3),
            "frame": "hill",
            "diagnostics": diag,
        }


class PortApproach:
    """A port-to-port PD in the target port frame (x: its outward axis), with no orbit model:
    the reference range closes at `speed1` to `hold_m`, holds there `hold_s`, then closes at
    `speed2` to `stop_m` (below the seat: a gentle push while the latch's dwell runs)."""

    def __init__(self, speed1=0.1, hold_m=10.0, hold_s=120.0, speed2=0.03, stop_m=0.2,
                 omega_rad_s=0.05):
        self.p = (speed1, hold_m, hold_s, speed2, stop_m)
        self.w = omega_rad_s
        self.start = None

    def reference(self, t):
        s1, r1, th, s2, r2 = self.p
        t0, r0 = self.start
        t1 = t0 + (r0 - r1) / s1
        if t < t1:
            return r0 - s1 * (t - t0), -s1
        if t < t1 + th:
            return r1, 0.0
        r = r1 - s2 * (t - t1 - th)
        return (r, -s2) if r > r2 else (r2, 0.0)

    def __call__(self, obs):
        p = obs["ports"]
        pos, vel = p["rel_pos_m"], p["rel_vel_m_s"]
        if self.start is None:
            self.start = (obs["t_s"], float(pos[0]))
        r_ref, v_ref = self.reference(obs["t_s"])
        e = pos - np.array([r_ref, 0.0, 0.0])
        ed = vel - np.array([v_ref, 0.0, 0.0])
        a_port = -(e * self.w**2 + ed * 2.0 * self.w)
        a_world = qrot(p["target"]["quat_wxyz"], a_port)
        return {"force_n": a_world * obs["mass_kg"], "frame": "world"}
