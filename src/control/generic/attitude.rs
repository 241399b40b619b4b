//! `Attitude`: quaternion-feedback attitude control — hold an inertial attitude, hold LVLH
//! (the body's own Hill frame, or its target's), or align the body's docking port with the
//! target's port while matching the target's rate.
//!
//! ```ron
//! Attitude(body: "chaser", target: "target", period_s: 0.1,
//!          actuator: Saturated(max_force_n: (0.0, 0.0, 0.0), max_torque_nm: (2.0, 2.0, 2.0)),
//!          params: (mode: AlignPort, natural_frequency_rad_s: 0.3, damping_ratio: 0.9))
//! ```
//!
//! It flies on the true attitude: a `sensor` on an `Attitude` entry is a located error (in a
//! `Sequencer`, the entry's sensor feeds the translation laws only).
//!
//! # The law
//! With q the attitude (body → world), q_d the desired one, q_e = q_d⁻¹ q = (q_w, q_v) the error
//! (its vector part in body axes to first order), ω the body rate and ω_d the desired rate, both
//! in body axes (ω_d = q⁻¹ ω_d,world), ω_e = ω − ω_d and J the inertia:
//! τ = −2ω_n² J sgn(q_w) q_v − 2ζω_n J ω_e + ω × Jω − J(ω_e × ω_d)   (body axes).
//! The first two terms give, per axis and for small errors (q_v ≈ θ/2), θ̈ + 2ζω_n θ̇ + ω_n²θ = 0;
//! the last two cancel the gyroscopic torque and the transport of a constant desired rate
//! (Wie, *Space Vehicle Dynamics and Control*, §7.3). sgn(q_w) takes the short way round.
//!
//! # Desired attitudes
//! - `Inertial(attitude)`: q_d = `attitude` (body → world), ω_d = 0.
//! - `Lvlh(attitude, of)`: q_d = (Hill → world)·`attitude` (body → Hill), ω_d = the Hill frame's
//!   rate r×v/|r|², of the body's own orbit (`of: Own`) or its target's (`of: Target`).
//! - `AlignPort`: the body's port frame turned π about the target port frame's y axis (port x
//!   axes anti-parallel, y parallel: facing, roll matched), ω_d = the target's rate.

use crate::control::interface::{
    ActuationReport, Command, Controller, DiagnosticsAt, Frame, Observation, port_axes,
};
use crate::control::spec::{BuildError, Commands, LawContext, LawParams};
use crate::orbit::lvlh::{LocalFrame, LocalFrameKind};
use crate::scene::AttitudeSpec;
use nalgebra::{Matrix3, Rotation3, UnitQuaternion, Vector3};
use serde::{Deserialize, Serialize};

/// Whose Hill frame `Lvlh` holds.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
pub enum LvlhOf {
    /// The controlled body's own orbit.
    #[default]
    Own,
    /// The target's orbit.
    Target,
}

/// What attitude to hold.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub enum AttitudeMode {
    /// A fixed attitude, body → world.
    Inertial {
        /// The attitude.
        attitude: AttitudeSpec,
    },
    /// A fixed attitude in a Hill frame, body → Hill.
    Lvlh {
        /// The attitude in the Hill frame (default: body axes on the Hill axes).
        #[serde(default)]
        attitude: AttitudeSpec,
        /// Whose Hill frame.
        #[serde(default)]
        of: LvlhOf,
    },
    /// The body's port facing the target's port, roll matched, at the target's rate.
    AlignPort,
}

/// Parameters of `Attitude`.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AttitudeParams {
    /// What to hold.
    pub mode: AttitudeMode,
    /// ω_n of the error dynamics, rad/s.
    pub natural_frequency_rad_s: f64,
    /// ζ.
    pub damping_ratio: f64,
}

impl LawParams for AttitudeParams {
    fn commands(&self) -> Commands {
        Commands::Torque
    }

    fn build(&self, ctx: &mut LawContext) -> Result<Box<dyn Controller>, BuildError> {
        ctx.no_sensor(
            "Attitude",
            "it flies on the true attitude (in a Sequencer, the entry's sensor feeds the translation laws)",
        )?;
        let w = self.natural_frequency_rad_s;
        if !(w.is_finite() && w > 0.0 && w < 1e3) {
            return Err(BuildError::at(
                "natural_frequency_rad_s",
                format!("must be a positive rate in rad/s below 1e3, got {w}"),
            ));
        }
        let z = self.damping_ratio;
        if !(z.is_finite() && (0.0..1e3).contains(&z)) {
            return Err(BuildError::at(
                "damping_ratio",
                format!("must be ≥ 0 (and below 1e3), got {z}"),
            ));
        }
        let orbit = ctx.build.env.reference().is_some();
        match &self.mode {
            AttitudeMode::Inertial { attitude } => check_attitude(attitude, "mode.0.attitude")?,
            AttitudeMode::Lvlh { attitude, of } => {
                check_attitude(attitude, "mode.0.attitude")?;
                if !orbit {
                    return Err(BuildError::at(
                        "mode",
                        "`Lvlh` needs an `Orbit` environment",
                    ));
                }
                if *of == LvlhOf::Target && ctx.target.is_none() {
                    return Err(BuildError::at_root(
                        format!("controllers.{}.target", ctx.build.index),
                        "`Lvlh(of: Target)` needs the entry's `target`",
                    ));
                }
            }
            AttitudeMode::AlignPort => {
                if ctx.ports.is_none() {
                    return Err(BuildError::at(
                        "mode",
                        "`AlignPort` needs the entry's `target`, `port` and `target_port` (or a docking mechanism between the two bodies)",
                    ));
                }
            }
        }
        let own = ctx.own();
        let port_in_body = match (&self.mode, &ctx.ports) {
            (AttitudeMode::AlignPort, Some((p, _))) => {
                let (_, axis) = own.port(p).expect("checked by LawEntry::build");
                port_axes(&axis)
            }
            _ => UnitQuaternion::identity(),
        };
        Ok(Box::new(Attitude {
            params: self.clone(),
            inertia_kg_m2: own.inertia_kg_m2,
            port_in_body,
            prefix: super::unique_prefix(ctx, "attitude"),
            last: [f64::NAN; 5],
        }))
    }
}

fn check_attitude(a: &AttitudeSpec, field: &str) -> Result<(), BuildError> {
    let ok = match a {
        AttitudeSpec::Quat { w, x, y, z } => {
            [w, x, y, z].iter().all(|v| v.is_finite()) && (w * w + x * x + y * y + z * z) > 1e-12
        }
        AttitudeSpec::EulerZyxDeg { yaw, pitch, roll } => [yaw, pitch, roll]
            .iter()
            .all(|v| v.is_finite() && v.abs() < 1e6),
    };
    if ok {
        Ok(())
    } else {
        Err(BuildError::at(
            field,
            "must be a finite, non-zero quaternion or finite Euler angles in deg",
        ))
    }
}

/// The running `Attitude` law.
#[derive(Debug, Clone)]
pub struct Attitude {
    /// Its parameters.
    pub params: AttitudeParams,
    inertia_kg_m2: Matrix3<f64>,
    port_in_body: UnitQuaternion<f64>,
    prefix: String,
    last: [f64; 5],
}

impl Attitude {
    /// The desired attitude (body → world) and rate (world axes), if the observation has what
    /// the mode needs.
    pub fn desired(&self, obs: &Observation) -> Option<(UnitQuaternion<f64>, Vector3<f64>)> {
        match &self.params.mode {
            AttitudeMode::Inertial { attitude } => Some((attitude.to_quat(), Vector3::zeros())),
            AttitudeMode::Lvlh { attitude, of } => {
                let (r, v) = obs.env.reference()?;
                let b = match of {
                    LvlhOf::Own => obs.own(),
                    LvlhOf::Target => obs.target_state()?,
                };
                let f = LocalFrame::new(LocalFrameKind::Hill, &(r + b.pos_m), &(v + b.vel_m_s));
                let hill_to_world = UnitQuaternion::from_rotation_matrix(
                    &Rotation3::from_matrix_unchecked(f.dcm_frame_from_eci.transpose()),
                );
                Some((hill_to_world * attitude.to_quat(), f.omega_eci_rad_s))
            }
            AttitudeMode::AlignPort => {
                let p = obs.ports?;
                let facing = p.target.att
                    * UnitQuaternion::from_axis_angle(&Vector3::y_axis(), std::f64::consts::PI);
                let t = obs.target_state()?;
                Some((facing * self.port_in_body.inverse(), t.omega_rad_s))
            }
        }
    }
}

impl Controller for Attitude {
    fn command(&mut self, obs: &Observation) -> Command {
        let Some((q_d, w_d_world)) = self.desired(obs) else {
            return Command::zero();
        };
        let own = obs.own();
        let q = own.att;
        let q_e = q_d.inverse() * q;
        let (qw, qv) = (q_e.w, q_e.imag());
        let sign = if qw < 0.0 { -1.0 } else { 1.0 };
        let w = own.rate_body_rad_s;
        let w_d = q.inverse() * w_d_world;
        let w_e = w - w_d;
        let j = &self.inertia_kg_m2;
        let (wn, z) = (
            self.params.natural_frequency_rad_s,
            self.params.damping_ratio,
        );
        let tau = -(j * (qv * (2.0 * wn * wn * sign))) - j * (w_e * (2.0 * z * wn))
            + w.cross(&(j * w))
            - j * w_e.cross(&w_d);
        let angle = 2.0 * qv.norm().atan2(qw.abs());
        self.last = [
            angle.to_degrees(),
            w_e.norm().to_degrees(),
            tau.x,
            tau.y,
            tau.z,
        ];
        Command::in_frame(Frame::Body, Vector3::zeros(), tau)
    }

    fn needs(&self) -> crate::control::interface::Needs {
        crate::control::interface::Needs {
            relative: false,
            ports: matches!(self.params.mode, AttitudeMode::AlignPort),
            gravity: false,
        }
    }

    fn columns(&self) -> Vec<String> {
        let p = &self.prefix;
        vec![
            format!("{p}.err_angle_deg"),
            format!("{p}.err_rate_deg_s"),
            format!("{p}.torque_cmd_body_x_nm"),
            format!("{p}.torque_cmd_body_y_nm"),
            format!("{p}.torque_cmd_body_z_nm"),
        ]
    }

    fn diagnostics(
        &mut self,
        _at: DiagnosticsAt,
        _obs: &Observation,
        _act: &ActuationReport,
        out: &mut [f64],
    ) {
        out.copy_from_slice(&self.last);
    }
}
