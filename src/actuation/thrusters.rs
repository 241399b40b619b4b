//! Cold-gas thruster layout of the Xu, Wen, Wei (2019) air-bearing simulator (§3.1, Fig. 10):
//! 8 CO₂ nozzles, on/off solenoid valves driven through PWPF ([`super::pwpf`]).
//!
//! The paper states: nozzles 1-1, 2-1, 3-1, 4-1 control position; pairs 1-2 & 3-2 and
//! 2-2 & 4-2, firing together, control attitude; one nozzle gives ≈ 0.05 N; "the two lateral
//! nozzles give a torque of ≈ 0.009 N·m". Fig. 10 itself is not in the extracted text, so the
//! geometry below is **\[derived\]**, chosen to match those statements:
//!
//! Body frame: origin at the centre of mass, x_b forward, y_b left, z_b up (lab z). Four
//! stations at distance `l` on the body axes; station i carries translation nozzle i-1 (thrust
//! through the centre of mass, no torque) and tangential nozzle i-2.
//!
//! | nozzle | position (m) | thrust direction | effect             |
//! |--------|--------------|------------------|--------------------|
//! | 1-1    | (−l, 0)      | +x_b             | +Fx                |
//! | 1-2    | (−l, 0)      | −y_b             | +T (with 3-2)      |
//! | 2-1    | (0, −l)      | +y_b             | +Fy                |
//! | 2-2    | (0, −l)      | −x_b             | −T (with 4-2)      |
//! | 3-1    | (+l, 0)      | −x_b             | −Fx                |
//! | 3-2    | (+l, 0)      | +y_b             | +T (with 1-2)      |
//! | 4-1    | (0, +l)      | −y_b             | −Fy                |
//! | 4-2    | (0, +l)      | +x_b             | −T (with 2-2)      |
//!
//! A rotating pair is a pure couple (zero net force) of torque `2 F l`; with `F = 0.05 N` the
//! paper's 0.009 N·m gives the lever arm `l = 0.009/(2·0.05) = 0.09 m`. Translation and
//! rotation channels are therefore exactly decoupled, and the allocation is per channel:
//! `r_x = Fx/F`, `r_y = Fy/F`, `r_T = T/(2 F l)`, each fed to its own PWPF.
//!
//! **Gas.** Mass flow of one open nozzle `ṁ = F/(I_sp g0)`. The paper gives no I_sp; the
//! default 50 s is a documented choice for CO₂ cold gas (ideal vacuum I_sp of CO₂ is ≈ 61 s
//! at room temperature; small nozzles exhausting to 1 atm on a table deliver less).

use super::pwpf::{Pwpf, PwpfParams};
use nalgebra::Vector2;
use serde::{Deserialize, Serialize};

/// Standard gravity used in the I_sp definition (m/s²).
pub const G0_M_S2: f64 = 9.80665;

/// Nozzle names in the order used by every `[_; 8]` array of this module.
pub const NOZZLE_NAMES: [&str; 8] = ["1-1", "1-2", "2-1", "2-2", "3-1", "3-2", "4-1", "4-2"];

/// One nozzle: where it sits and which way it pushes, body frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Nozzle {
    /// Name as in the paper's Fig. 10 ("1-1" … "4-2").
    pub name: &'static str,
    /// Position of the nozzle in the body frame (m), relative to the centre of mass.
    pub pos_body_m: Vector2<f64>,
    /// Unit thrust direction (force on the vehicle) in the body frame.
    pub dir_body: Vector2<f64>,
}

/// Thruster layout and valve constants (§3.1; lever arm and I_sp \[derived\], see module doc).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ThrusterParams {
    /// Thrust of one open nozzle (N). Paper: ≈ 0.05 N.
    pub thrust_per_nozzle_n: f64,
    /// Distance of every nozzle station from the centre of mass (m). 0.09 m reproduces the
    /// paper's 0.009 N·m per rotating pair.
    pub lever_arm_m: f64,
    /// Specific impulse of the CO₂ cold gas (s). Default 50 s (documented choice).
    pub isp_s: f64,
    /// PWPF constants shared by the three channels (x, y, torque).
    pub pwpf: PwpfParams,
}

impl Default for ThrusterParams {
    fn default() -> Self {
        Self::paper()
    }
}

impl ThrusterParams {
    /// Paper values: 0.05 N per nozzle, 0.09 m lever arm (→ 0.009 N·m per pair), I_sp = 50 s,
    /// typical PWPF constants ([`PwpfParams::typical`]).
    pub fn paper() -> Self {
        Self {
            thrust_per_nozzle_n: 0.05,
            lever_arm_m: 0.09,
            isp_s: 50.0,
            pwpf: PwpfParams::typical(),
        }
    }

    /// The eight nozzles in [`NOZZLE_NAMES`] order (see the module table).
    pub fn nozzles(&self) -> [Nozzle; 8] {
        let l = self.lever_arm_m;
        let v = Vector2::new;
        let mk = |name, pos: Vector2<f64>, dir: Vector2<f64>| Nozzle {
            name,
            pos_body_m: pos,
            dir_body: dir,
        };
        [
            mk("1-1", v(-l, 0.0), v(1.0, 0.0)),
            mk("1-2", v(-l, 0.0), v(0.0, -1.0)),
            mk("2-1", v(0.0, -l), v(0.0, 1.0)),
            mk("2-2", v(0.0, -l), v(-1.0, 0.0)),
            mk("3-1", v(l, 0.0), v(-1.0, 0.0)),
            mk("3-2", v(l, 0.0), v(0.0, 1.0)),
            mk("4-1", v(0.0, l), v(0.0, -1.0)),
            mk("4-2", v(0.0, l), v(1.0, 0.0)),
        ]
    }

    /// Largest force along one body axis (N): one translation nozzle.
    pub fn max_force_n(&self) -> f64 {
        self.thrust_per_nozzle_n
    }

    /// Torque of one rotating pair (N·m): `2 F l`.
    pub fn pair_torque_nm(&self) -> f64 {
        2.0 * self.thrust_per_nozzle_n * self.lever_arm_m
    }

    /// Allocation: body command → normalised channel commands `[r_x, r_y, r_T]`
    /// (dimensionless, unclamped) for the three PWPF channels.
    pub fn channel_commands(&self, force_body_n: Vector2<f64>, torque_nm: f64) -> [f64; 3] {
        let f = self.max_force_n();
        [
            force_body_n.x / f,
            force_body_n.y / f,
            torque_nm / self.pair_torque_nm(),
        ]
    }

    /// Ideal continuous saturation: the body command clipped per channel to what the valves
    /// can give when fully open (|Fx|, |Fy| ≤ F, |T| ≤ 2 F l). Force in N (body), torque N·m.
    pub fn saturate(&self, force_body_n: Vector2<f64>, torque_nm: f64) -> (Vector2<f64>, f64) {
        let f = self.max_force_n();
        let t = self.pair_torque_nm();
        (
            Vector2::new(force_body_n.x.clamp(-f, f), force_body_n.y.clamp(-f, f)),
            torque_nm.clamp(-t, t),
        )
    }

    /// Channel outputs `[U_x, U_y, U_T]` ∈ {−1, 0, 1} → valve states (true = open), in
    /// [`NOZZLE_NAMES`] order. U_x = +1 opens 1-1, −1 opens 3-1; U_y = +1 opens 2-1, −1 opens
    /// 4-1; U_T = +1 opens 1-2 and 3-2, −1 opens 2-2 and 4-2.
    pub fn valves_from_channels(&self, u: [i8; 3]) -> [bool; 8] {
        [
            u[0] > 0,
            u[2] > 0,
            u[1] > 0,
            u[2] < 0,
            u[0] < 0,
            u[2] > 0,
            u[1] < 0,
            u[2] < 0,
        ]
    }

    /// Body force (N) and torque about z (N·m) produced by the open valves:
    /// `Σ F d_i`, `Σ (p_i × F d_i)·z`.
    pub fn wrench_from_valves(&self, valves: &[bool; 8]) -> (Vector2<f64>, f64) {
        let f = self.thrust_per_nozzle_n;
        let mut force = Vector2::zeros();
        let mut torque = 0.0;
        for (n, open) in self.nozzles().iter().zip(valves) {
            if *open {
                let fi = n.dir_body * f;
                force += fi;
                torque += n.pos_body_m.x * fi.y - n.pos_body_m.y * fi.x;
            }
        }
        (force, torque)
    }

    /// CO₂ mass flow of the open valves (kg/s): `n_open · F/(I_sp g0)`.
    pub fn mass_flow_kg_s(&self, valves: &[bool; 8]) -> f64 {
        let n_open = valves.iter().filter(|v| **v).count() as f64;
        n_open * self.thrust_per_nozzle_n / (self.isp_s * G0_M_S2)
    }

    /// Gas used over a step with the valves held (kg).
    pub fn gas_used_kg(&self, valves: &[bool; 8], dt_s: f64) -> f64 {
        self.mass_flow_kg_s(valves) * dt_s
    }
}

/// Three PWPF channels (x, y, torque) driving the eight valves.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ThrusterPwpf {
    /// Channel modulators: `[x, y, torque]`.
    pub channels: [Pwpf; 3],
}

impl ThrusterPwpf {
    /// Three channels at rest with the layout's PWPF constants.
    pub fn new(params: &ThrusterParams) -> Self {
        let m = Pwpf::new(params.pwpf.clone());
        Self {
            channels: [m.clone(), m.clone(), m],
        }
    }

    /// One fixed step: allocate the body command (force N, torque N·m), modulate, and return
    /// the valve states to hold over `[t, t + dt_s)`.
    pub fn step(
        &mut self,
        params: &ThrusterParams,
        force_body_n: Vector2<f64>,
        torque_nm: f64,
        dt_s: f64,
    ) -> [bool; 8] {
        let r = params.channel_commands(force_body_n, torque_nm);
        let u = [
            self.channels[0].step(r[0], dt_s),
            self.channels[1].step(r[1], dt_s),
            self.channels[2].step(r[2], dt_s),
        ];
        params.valves_from_channels(u)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Reference: the paper's numbers — one nozzle 0.05 N, a rotating pair ≈ 0.009 N·m,
    /// computed here from positions and directions (r × F), not from `pair_torque_nm`.
    #[test]
    fn val_xu2019_layout_wrenches() {
        let p = ThrusterParams::paper();
        let tol = 1e-15;
        for u in [[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0]] {
            let (f, t) = p.wrench_from_valves(&p.valves_from_channels(u));
            assert!((f - Vector2::new(u[0] as f64, u[1] as f64) * 0.05).norm() < tol);
            assert!(t.abs() < tol);
        }
        for s in [1i8, -1] {
            let (f, t) = p.wrench_from_valves(&p.valves_from_channels([0, 0, s]));
            assert!(f.norm() < tol, "pair is a pure couple");
            assert!((t - s as f64 * 0.009).abs() < 1e-15, "{t}");
        }
        assert!((p.pair_torque_nm() - 0.009).abs() < 1e-15);
        // Each nozzle appears in exactly one channel state; all names distinct.
        for (i, n) in p.nozzles().iter().enumerate() {
            assert_eq!(n.name, NOZZLE_NAMES[i]);
            assert!((n.dir_body.norm() - 1.0).abs() < 1e-15);
        }
    }

    /// Superposition: the wrench of any channel combination is the sum of the channel
    /// wrenches (channels decoupled), and it matches U·(F, F, 2Fl).
    #[test]
    fn invariant_thruster_channels_decoupled() {
        let p = ThrusterParams::paper();
        for ux in -1..=1 {
            for uy in -1..=1 {
                for ut in -1..=1 {
                    let (f, t) = p.wrench_from_valves(&p.valves_from_channels([ux, uy, ut]));
                    let ef = Vector2::new(ux as f64, uy as f64) * 0.05;
                    assert!((f - ef).norm() < 1e-15);
                    assert!((t - ut as f64 * 0.009).abs() < 1e-15);
                }
            }
        }
    }

    /// Reference: ṁ = F/(I_sp g0) per open nozzle; a pair flows twice that.
    #[test]
    fn val_thruster_gas_flow() {
        let p = ThrusterParams::paper();
        let one = 0.05 / (50.0 * 9.80665);
        let v = p.valves_from_channels([1, 0, 0]);
        assert!((p.mass_flow_kg_s(&v) - one).abs() < 1e-18);
        let v = p.valves_from_channels([1, -1, 1]);
        assert!((p.mass_flow_kg_s(&v) - 4.0 * one).abs() < 1e-18);
        assert!((p.gas_used_kg(&v, 2.0) - 8.0 * one).abs() < 1e-18);
        assert_eq!(p.mass_flow_kg_s(&[false; 8]), 0.0);
    }

    /// Through the PWPF, the time-averaged body force equals F·D(r) on each channel,
    /// D the analytic duty cycle of the modulator. Reference: `PwpfParams::duty_cycle`.
    #[test]
    fn val_thruster_pwpf_average_force() {
        let p = ThrusterParams::paper();
        let mut m = ThrusterPwpf::new(&p);
        let cmd_f = Vector2::new(0.025, -0.04);
        let cmd_t = 0.0045;
        let dt = 1e-4;
        let n = 200_000;
        let (mut sf, mut st) = (Vector2::zeros(), 0.0);
        for _ in 0..n {
            let v = m.step(&p, cmd_f, cmd_t, dt);
            let (f, t) = p.wrench_from_valves(&v);
            sf += f;
            st += t;
        }
        let (af, at) = (sf / n as f64, st / n as f64);
        let d = |r: f64| r.signum() * p.pwpf.duty_cycle(r);
        // 20 s window: partial period + start-up bias ≤ ~1 % of full scale.
        assert!((af.x - 0.05 * d(0.5)).abs() < 0.01 * 0.05, "{}", af.x);
        assert!((af.y - 0.05 * d(-0.8)).abs() < 0.01 * 0.05, "{}", af.y);
        assert!((at - 0.009 * d(0.5)).abs() < 0.01 * 0.009, "{at}");
    }
}
