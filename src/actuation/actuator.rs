//! The actuator between a controller's held [`Command`] and the forces on its body, stepped
//! every simulation step. Bevy-free.
//!
//! - `Ideal` — the command exactly, continuous and unlimited.
//! - `Saturated` — each component clamped to ±its limit in the command's own frame (per-axis
//!   thrust limits), then rotated to the world frame.
//! - `PlanarThrusters` — the eight on/off cold-gas nozzles of the Xu, Wen, Wei (2019) air-bearing
//!   simulator ([`crate::actuation::thrusters`]): the command, turned into body axes with the
//!   *true* attitude unless it is already in body axes, is allocated to three channels (x, y,
//!   torque), each modulated by its own PWPF every step; the open nozzles' forces (each
//!   F·(1 + σ·N(0, 1)) with thrust noise) act in body axes, rotated by the true attitude.
//!   A command with `valves` opens those valves directly (no PWPF).
//!
//! Every actuator accounts the velocity increment ∫|F|/m dt it applied (m/s); thrusters also
//! the propellant, Σ F_i·dt/(I_sp g₀).

use super::pwpf::{Pwpf, PwpfParams};
use super::thrusters::{G0_M_S2, ThrusterParams, ThrusterPwpf};
use crate::control::interface::{ActuationReport, Command, Frame};
use crate::math::rng::GaussianNoise;
use nalgebra::{Matrix3, UnitQuaternion, Vector2, Vector3};
use serde::{Deserialize, Serialize};

/// An actuator, as written in a scene (`actuator: Saturated(max_force_n: (…), …)`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub enum ActuatorSpec {
    /// The command exactly.
    #[default]
    Ideal,
    /// Per-axis limits in the command's frame.
    Saturated {
        /// |F_i| ≤ this per axis, N.
        max_force_n: [f64; 3],
        /// |τ_i| ≤ this per axis, N·m.
        max_torque_nm: [f64; 3],
    },
    /// The Xu, Wen, Wei (2019) nozzle set with PWPF (planar: body x, y force and yaw torque).
    PlanarThrusters {
        /// Nozzle thrust, lever arm, specific impulse and PWPF constants (default: the
        /// paper's, [`ThrusterParams::paper`]).
        #[serde(default)]
        params: ThrusterParams,
        /// Relative thrust noise σ (each open nozzle gives F·(1 + σ·N(0, 1)) per step).
        #[serde(default)]
        thrust_noise: f64,
        /// Seed of the thrust noise.
        #[serde(default)]
        seed: u64,
    },
    /// Three-dimensional reaction-control jets ([`crate::actuation::rcs`]): the command's
    /// force and torque, turned into body axes with the true attitude, are allocated to
    /// non-negative jet thrusts (least error, saturation reported), rounded to the minimum
    /// impulse bits; a command with `valves` fires those jets at full thrust (one flag per jet,
    /// in layout order).
    Rcs {
        /// The jets.
        jets: Vec<super::rcs::JetSpec>,
        /// Specific impulse, s (default 220 s, a hydrazine monopropellant thruster).
        #[serde(default = "rcs_isp")]
        isp_s: f64,
        /// The plumes of these jets load the parts of other bodies they strike
        /// (`sim::plume::PlumeLoadState`; default true). `false` keeps only the geometry (the
        /// `PlumeKeepOff` guarantee), e.g. to study clearance with the struck body unmoved.
        #[serde(default = "yes")]
        plume_loads: bool,
        /// Modulate each jet's allocated thrust through its own PWPF into on/off valve
        /// commands ([`crate::actuation::rcs`], "PWPF"; default none: the mean thrust is
        /// applied). Fields left out take the typical values.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        pwpf: Option<super::pwpf::PwpfParams>,
        /// Raise a `jet_pulse` event in `events.jsonl` when a jet's firing pulse ends (its
        /// start, duration, on-time and impulse; default false), capped per jet and per run
        /// ([`super::rcs::MAX_PULSE_EVENTS_PER_JET`], [`super::rcs::MAX_PULSE_EVENTS_PER_RUN`]).
        #[serde(default, skip_serializing_if = "std::ops::Not::not")]
        firing_events: bool,
    },
}

fn rcs_isp() -> f64 {
    220.0
}

fn yes() -> bool {
    true
}

impl ActuatorSpec {
    /// Checks the numbers: `Err((field, message))` relative to the spec.
    pub fn validate(&self) -> Result<(), (String, String)> {
        match self {
            ActuatorSpec::Ideal => Ok(()),
            ActuatorSpec::Saturated {
                max_force_n,
                max_torque_nm,
            } => {
                for (f, v) in [
                    ("0.max_force_n", max_force_n),
                    ("0.max_torque_nm", max_torque_nm),
                ] {
                    if !v.iter().all(|x| x.is_finite() && *x >= 0.0) {
                        return Err((
                            f.trim_start_matches("0.").to_string(),
                            format!("limits must be finite and ≥ 0, got {v:?}"),
                        ));
                    }
                }
                Ok(())
            }
            ActuatorSpec::Rcs {
                jets, isp_s, pwpf, ..
            } => {
                super::rcs::validate_jets(jets, *isp_s)?;
                if let Some(p) = pwpf {
                    p.check().map_err(|(f, m)| (format!("pwpf.{f}"), m))?;
                }
                Ok(())
            }
            ActuatorSpec::PlanarThrusters {
                params,
                thrust_noise,
                ..
            } => {
                if !(thrust_noise.is_finite() && (0.0..10.0).contains(thrust_noise)) {
                    return Err((
                        "thrust_noise".into(),
                        format!(
                            "must be a relative standard deviation in [0, 10), got {thrust_noise}"
                        ),
                    ));
                }
                let ok = |x: f64| x.is_finite() && x > 0.0 && x < 1e6;
                if !(ok(params.thrust_per_nozzle_n) && ok(params.lever_arm_m) && ok(params.isp_s)) {
                    return Err((
                        "params".into(),
                        "nozzle thrust (N), lever arm (m) and specific impulse (s) must be positive and below 1e6"
                            .into(),
                    ));
                }
                params
                    .pwpf
                    .check()
                    .map_err(|(f, m)| (format!("params.pwpf.{f}"), m))?;
                Ok(())
            }
        }
    }
}

/// The attitudes of the frames a command may be written in, at one step.
#[derive(Debug, Clone, Copy)]
pub struct CommandFrames {
    /// Controlled body, body → world.
    pub body: UnitQuaternion<f64>,
    /// Hill frame → world DCM (orbit scenes).
    pub hill: Option<Matrix3<f64>>,
    /// Target body → world (when the slot names a target).
    pub target_body: Option<UnitQuaternion<f64>>,
}

impl CommandFrames {
    /// A vector of `frame` in world components (`None` when the frame does not exist here).
    pub fn to_world(&self, frame: Frame, v: &Vector3<f64>) -> Option<Vector3<f64>> {
        match frame {
            Frame::World => Some(*v),
            Frame::Body => Some(self.body * v),
            Frame::Hill => self.hill.map(|c| c * v),
            Frame::TargetBody => self.target_body.map(|q| q * v),
        }
    }
}

/// A running actuator.
#[derive(Debug, Clone)]
pub struct Actuator {
    /// The scene's request.
    pub spec: ActuatorSpec,
    /// PWPF channels (thrusters).
    pub pwpf: Option<ThrusterPwpf>,
    /// Valve states this step (thrusters).
    pub valves: [bool; 8],
    /// Cumulative valve-open time per nozzle, s.
    pub valve_open_s: [f64; 8],
    /// Valve openings (off → on transitions) per nozzle.
    pub valve_openings: [u64; 8],
    /// Propellant used so far, kg.
    pub propellant_used_kg: f64,
    /// Velocity increment applied so far, ∫|F|/m dt, m/s.
    pub delta_v_m_s: f64,
    /// Per jet (`Rcs`): on-time, impulse, firings, propellant.
    pub jets: Vec<super::rcs::JetTotals>,
    /// Steps in which the actuator could not meet the command.
    pub saturated_steps: u64,
    /// Per jet (`Rcs` with `pwpf`): the jet's modulator.
    pub jet_pwpf: Vec<Pwpf>,
    /// Firing pulses that ended this step (`Rcs` with `firing_events`; the host drains them).
    pub ended_pulses: Vec<super::rcs::JetPulse>,
    thrust_noise: GaussianNoise,
}

impl Actuator {
    /// A fresh actuator. The thrust noise of `PlanarThrusters` is seeded with
    /// `seed ^ 0x5851_F42D_4C95_7F2D` (so that it differs from a sensor given the same seed).
    pub fn new(spec: ActuatorSpec) -> Self {
        let (pwpf, noise_seed) = match &spec {
            ActuatorSpec::PlanarThrusters { params, seed, .. } => (
                Some(ThrusterPwpf::new(params)),
                *seed ^ 0x5851_F42D_4C95_7F2D,
            ),
            _ => (None, 0),
        };
        let jets = match &spec {
            ActuatorSpec::Rcs { jets, .. } => jets
                .iter()
                .map(|j| super::rcs::JetTotals {
                    name: j.name.clone(),
                    ..Default::default()
                })
                .collect(),
            _ => Vec::new(),
        };
        // One modulator per jet; its minimum on-time also honours the jet's minimum impulse
        // bit (a pulse lasts at least I_min/F_max at full thrust).
        let jet_pwpf = match &spec {
            ActuatorSpec::Rcs {
                jets,
                pwpf: Some(p),
                ..
            } => jets
                .iter()
                .map(|j| {
                    Pwpf::new(PwpfParams {
                        min_on_time_s: p.min_on_time_s.max(j.min_impulse_bit_ns / j.max_thrust_n),
                        ..p.clone()
                    })
                })
                .collect(),
            _ => Vec::new(),
        };
        Self {
            spec,
            pwpf,
            valves: [false; 8],
            valve_open_s: [0.0; 8],
            valve_openings: [0; 8],
            propellant_used_kg: 0.0,
            delta_v_m_s: 0.0,
            jets,
            saturated_steps: 0,
            jet_pwpf,
            ended_pulses: Vec::new(),
            thrust_noise: GaussianNoise::new(noise_seed),
        }
    }

    /// One step: the held command through the actuator. Returns the world-frame force and
    /// torque and what was done; `None` when the command's frame does not exist in this scene
    /// (e.g. `Hill` outside an orbit) — then nothing is applied.
    pub fn step(
        &mut self,
        cmd: &Command,
        frames: &CommandFrames,
        mass_kg: f64,
        dt_s: f64,
    ) -> Option<ActuationReport> {
        let mut report = ActuationReport::default();
        let to_body = |frame: Frame, v: &Vector3<f64>| -> Option<Vector3<f64>> {
            if frame == Frame::Body {
                Some(*v)
            } else {
                Some(frames.body.inverse() * frames.to_world(frame, v)?)
            }
        };
        let (f_world, t_world) = match &self.spec {
            ActuatorSpec::Rcs {
                jets,
                isp_s,
                firing_events,
                ..
            } => {
                use super::rcs;
                let thrust: Vec<f64> = match &cmd.valves {
                    Some(v) => jets
                        .iter()
                        .enumerate()
                        .map(|(k, j)| {
                            if v.get(k).copied().unwrap_or(false) {
                                j.max_thrust_n
                            } else {
                                0.0
                            }
                        })
                        .collect(),
                    None => {
                        let fb = to_body(cmd.force_frame, &cmd.force_n)?;
                        let tb = to_body(cmd.torque_frame, &cmd.torque_nm)?;
                        let w = nalgebra::Vector6::new(fb.x, fb.y, fb.z, tb.x, tb.y, tb.z);
                        let a = rcs::allocate(jets, &w);
                        report.saturated = a.saturated;
                        if self.jet_pwpf.is_empty() {
                            rcs::apply_minimum_impulse(jets, &a.thrust_n, dt_s)
                        } else {
                            // Each jet's demand through its modulator: full thrust or none.
                            jets.iter()
                                .zip(&a.thrust_n)
                                .zip(self.jet_pwpf.iter_mut())
                                .map(|((j, u), m)| {
                                    if m.step_one_sided(u / j.max_thrust_n, dt_s) {
                                        j.max_thrust_n
                                    } else {
                                        0.0
                                    }
                                })
                                .collect()
                        }
                    }
                };
                let mut flags = Vec::with_capacity(jets.len());
                for (k, ((j, t), u)) in jets
                    .iter()
                    .zip(self.jets.iter_mut())
                    .zip(&thrust)
                    .enumerate()
                {
                    let impulse = u * dt_s;
                    let on = impulse > 0.0;
                    if on && !t.firing {
                        t.firings += 1;
                        t.pulse = (0, 0.0, 0.0);
                    }
                    if on {
                        t.pulse.0 += 1;
                        t.pulse.1 += impulse;
                        t.pulse.2 += impulse / j.max_thrust_n;
                    } else if t.firing && *firing_events {
                        self.ended_pulses.push(rcs::JetPulse {
                            jet: k,
                            steps: t.pulse.0,
                            impulse_ns: t.pulse.1,
                            on_time_s: t.pulse.2,
                        });
                    }
                    t.firing = on;
                    t.impulse_ns += impulse;
                    t.on_time_s += impulse / j.max_thrust_n;
                    let dm = impulse / (isp_s * G0_M_S2);
                    t.propellant_kg += dm;
                    self.propellant_used_kg += dm;
                    flags.push(on);
                }
                report.valves = Some(flags);
                let w = rcs::wrench(jets, &thrust);
                report.jet_thrust_n = Some(thrust);
                (
                    frames.body * Vector3::new(w[0], w[1], w[2]),
                    frames.body * Vector3::new(w[3], w[4], w[5]),
                )
            }
            ActuatorSpec::Ideal => (
                frames.to_world(cmd.force_frame, &cmd.force_n)?,
                frames.to_world(cmd.torque_frame, &cmd.torque_nm)?,
            ),
            ActuatorSpec::Saturated {
                max_force_n,
                max_torque_nm,
            } => {
                let clamp = |v: &Vector3<f64>, lim: &[f64; 3], sat: &mut bool| {
                    Vector3::from_fn(|i, _| {
                        let c = v[i].clamp(-lim[i], lim[i]);
                        if c != v[i] {
                            *sat = true;
                        }
                        c
                    })
                };
                let mut sat = false;
                let f = clamp(&cmd.force_n, max_force_n, &mut sat);
                let t = clamp(&cmd.torque_nm, max_torque_nm, &mut sat);
                report.saturated = sat;
                (
                    frames.to_world(cmd.force_frame, &f)?,
                    frames.to_world(cmd.torque_frame, &t)?,
                )
            }
            ActuatorSpec::PlanarThrusters {
                params,
                thrust_noise,
                ..
            } => {
                let valves = match &cmd.valves {
                    Some(v) => std::array::from_fn(|i| v.get(i).copied().unwrap_or(false)),
                    None => {
                        let fb = to_body(cmd.force_frame, &cmd.force_n)?;
                        let tb = to_body(cmd.torque_frame, &cmd.torque_nm)?;
                        let pw = self.pwpf.as_mut().expect("thrusters have PWPF");
                        pw.step(params, fb.xy(), tb.z, dt_s)
                    }
                };
                for (k, open) in valves.iter().enumerate() {
                    if *open {
                        self.valve_open_s[k] += dt_s;
                        if !self.valves[k] {
                            self.valve_openings[k] += 1;
                        }
                    }
                }
                self.valves = valves;
                let (fb, tq, flow) =
                    noisy_wrench(params, &valves, *thrust_noise, &mut self.thrust_noise);
                self.propellant_used_kg += flow * dt_s;
                report.valves = Some(valves.to_vec());
                (
                    frames.body * Vector3::new(fb.x, fb.y, 0.0),
                    Vector3::new(0.0, 0.0, tq),
                )
            }
        };
        if mass_kg > 0.0 {
            self.delta_v_m_s += f_world.norm() / mass_kg * dt_s;
        }
        if report.saturated {
            self.saturated_steps += 1;
        }
        report.force_world_n = f_world;
        report.torque_world_nm = t_world;
        report.propellant_used_kg = self.propellant_used_kg;
        report.delta_v_m_s = self.delta_v_m_s;
        Some(report)
    }
}

/// The nozzle forces of the open valves with thrust noise: body-frame force (N) and torque
/// about z (N·m), and the propellant mass flow, kg/s.
fn noisy_wrench(
    p: &ThrusterParams,
    valves: &[bool; 8],
    sigma: f64,
    noise: &mut GaussianNoise,
) -> (Vector2<f64>, f64, f64) {
    let mut force = Vector2::zeros();
    let mut torque = 0.0;
    let mut flow = 0.0;
    for (n, open) in p.nozzles().iter().zip(valves) {
        if *open {
            let f = p.thrust_per_nozzle_n
                * if sigma > 0.0 {
                    (1.0 + sigma * noise.standard_normal()).max(0.0)
                } else {
                    1.0
                };
            let fi = n.dir_body * f;
            force += fi;
            torque += n.pos_body_m.x * fi.y - n.pos_body_m.y * fi.x;
            flow += f / (p.isp_s * G0_M_S2);
        }
    }
    (force, torque, flow)
}

#[cfg(test)]
mod tests {
    //! References: the clamp by hand; a pure rotation of a body-frame vector; the nozzle
    //! wrenches of the layout (`thrusters::tests`).
    use super::*;

    fn frames() -> CommandFrames {
        CommandFrames {
            body: UnitQuaternion::from_axis_angle(&Vector3::z_axis(), std::f64::consts::FRAC_PI_2),
            hill: Some(Matrix3::identity()),
            target_body: None,
        }
    }

    #[test]
    fn invariant_planar_thrusters_pwpf_constants_are_checked() {
        // The modulator's own rules (`PwpfParams::check`): u_on between u_off and k_m.
        let mut params = ThrusterParams::paper();
        assert!(
            ActuatorSpec::PlanarThrusters {
                params: params.clone(),
                thrust_noise: 0.0,
                seed: 0
            }
            .validate()
            .is_ok()
        );
        params.pwpf.u_on = params.pwpf.k_m * 2.0;
        let e = ActuatorSpec::PlanarThrusters {
            params: params.clone(),
            thrust_noise: 0.0,
            seed: 0,
        }
        .validate()
        .expect_err("u_on above k_m");
        assert_eq!(e.0, "params.pwpf.u_on");
        params.pwpf = PwpfParams::typical();
        params.pwpf.t_m_s = f64::NAN;
        let e = ActuatorSpec::PlanarThrusters {
            params,
            thrust_noise: 0.0,
            seed: 0,
        }
        .validate()
        .expect_err("NaN time constant");
        assert_eq!(e.0, "params.pwpf.t_m_s");
    }

    #[test]
    fn val_actuator_saturation_and_frames() {
        let mut a = Actuator::new(ActuatorSpec::Saturated {
            max_force_n: [1.0, 2.0, 3.0],
            max_torque_nm: [0.1, 0.1, 0.1],
        });
        let cmd = Command::in_frame(
            Frame::Body,
            Vector3::new(5.0, -1.0, -9.0),
            Vector3::new(0.0, 0.0, 0.05),
        );
        let r = a
            .step(&cmd, &frames(), 2.0, 0.5)
            .expect("body frame exists");
        // Clamped to (1, −1, −3) in body axes, then turned 90° about z: (1, 1, −3).
        assert!((r.force_world_n - Vector3::new(1.0, 1.0, -3.0)).norm() < 1e-12);
        assert!(r.saturated);
        assert!((r.delta_v_m_s - 11f64.sqrt() / 2.0 * 0.5).abs() < 1e-12);
        let none = Command::in_frame(Frame::TargetBody, Vector3::x(), Vector3::zeros());
        assert!(
            a.step(&none, &frames(), 2.0, 0.5).is_none(),
            "no target: no frame"
        );
    }

    #[test]
    fn val_actuator_valves_direct() {
        let mut a = Actuator::new(ActuatorSpec::PlanarThrusters {
            params: ThrusterParams::paper(),
            thrust_noise: 0.0,
            seed: 0,
        });
        let mut cmd = Command::zero();
        // Nozzle 1-1 (+x_b) alone: 0.05 N along body x, i.e. world +y after the 90° yaw.
        let mut v = vec![false; 8];
        v[0] = true;
        cmd.valves = Some(v);
        let r = a.step(&cmd, &frames(), 10.0, 0.1).expect("report");
        assert!((r.force_world_n - Vector3::new(0.0, 0.05, 0.0)).norm() < 1e-12);
        assert_eq!(a.valve_openings[0], 1);
        assert!(r.propellant_used_kg > 0.0);
    }
}
