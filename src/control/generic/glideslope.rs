//! `Glideslope`: an approach along an axis — the target port's axis, V-bar or R-bar — with an
//! exponential profile (closing rate proportional to the remaining range) or at constant speed,
//! tracked like [`super::hill`] (PD with CW cancellation, or LQR).
//!
//! ```ron
//! Glideslope(body: "chaser", target: "target", period_s: 0.1,
//!            params: (axis: TargetPort, to_range_m: 10.0,
//!                     profile: Exponential(time_constant_s: 150.0, min_speed_m_s: 0.02),
//!                     gains: Pd(natural_frequency_rad_s: 0.08, damping_ratio: 1.0)))
//! ```
//!
//! With the entry's `sensor`, it flies on the measured relative state as `HillPd` does
//! ([`super::hill::point_state`]: `axis: TargetPort` reads a `Port` or `Hill` measurement, the other
//! axes a `Hill`, `TargetBody` or `World` one).
//!
//! # The reference
//! With û the approach axis (Hill frame; for `TargetPort` the target port's outward axis, the
//! range measured from the port's origin to the chaser's port; otherwise from the target's
//! centre of mass to the chaser's), r₀ the range along û at the law's first call and r_f =
//! `to_range_m`, d = r − r_f follows
//! - `Exponential(τ, v_min)`: ḋ = −d/τ while d/τ > v_min, i.e. d(t) = d₀ e^{−t/τ}, then
//!   ḋ = −v_min (the switch at d_s = τ·v_min keeps the speed continuous) until d = 0;
//! - `ConstantSpeed(v)`: ḋ = −v until d = 0;
//!
//! then holds r_f. The reference point is r(t)·û on the axis (no lateral offset), its
//! velocity ṙ·û and acceleration r̈·û. A start already at or inside r_f holds r_f.
//!
//! # Δv of the ideal approach (what the tests compare with)
//! Along V-bar (û = ∓ŷ) the CW model needs a_x = −2n ẏ to keep x = 0 and a_y = ÿ, so a perfect
//! tracker spends, from rest: d₀/τ (the initial velocity step) + √(4n² + τ⁻²)(d₀ − d_s)
//! (exponential part) + 2n d_s (constant-speed part) + v_min (the final stop)
//! ([`ideal_delta_v_m_s`]).

use super::hill::{ControlPoint, point_state};
use super::{TranslationFeedback, TranslationGains, target_mean_motion, unique_prefix};
use crate::control::interface::{
    ActuationReport, Command, Controller, DiagnosticsAt, Frame, Observation,
};
use crate::control::spec::{BuildError, Commands, LawContext, LawParams};
use nalgebra::Vector3;
use serde::{Deserialize, Serialize};

/// The approach axis.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub enum ApproachAxis {
    /// The target port's outward axis; ranges from the port's origin to the chaser's port.
    TargetPort,
    /// −ŷ (behind the target on the V-bar).
    VBarBehind,
    /// +ŷ (ahead on the V-bar).
    VBarAhead,
    /// −x̂ (below, Earth side, on the R-bar).
    RBarBelow,
    /// +x̂ (above, on the R-bar).
    RBarAbove,
    /// A Hill-frame direction (normalised).
    Hill([f64; 3]),
}

/// The range profile.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub enum Profile {
    /// ḋ = −d/τ, never slower than `min_speed_m_s` (then constant speed to the end).
    Exponential {
        /// τ, s.
        time_constant_s: f64,
        /// v_min, m/s (0: a pure exponential that never arrives).
        #[serde(default)]
        min_speed_m_s: f64,
    },
    /// ḋ = −v.
    ConstantSpeed {
        /// v, m/s.
        speed_m_s: f64,
    },
}

impl Profile {
    /// (d, ḋ, d̈) at time `t` after the start, from d₀ > 0.
    pub fn at(&self, d0: f64, t: f64) -> (f64, f64, f64) {
        if d0 <= 0.0 {
            return (0.0, 0.0, 0.0);
        }
        let linear = |d_start: f64, t: f64, v: f64| {
            if v <= 0.0 {
                (d_start, 0.0, 0.0)
            } else if t * v >= d_start {
                (0.0, 0.0, 0.0)
            } else {
                (d_start - v * t, -v, 0.0)
            }
        };
        match *self {
            Profile::ConstantSpeed { speed_m_s } => linear(d0, t, speed_m_s),
            Profile::Exponential {
                time_constant_s: tau,
                min_speed_m_s: vmin,
            } => {
                let d_s = tau * vmin;
                if d0 <= d_s {
                    return linear(d0, t, vmin);
                }
                let t_s = if vmin > 0.0 {
                    tau * (d0 / d_s).ln()
                } else {
                    f64::INFINITY
                };
                if t < t_s {
                    let d = d0 * (-t / tau).exp();
                    (d, -d / tau, d / (tau * tau))
                } else {
                    linear(d_s, t - t_s, vmin)
                }
            }
        }
    }
}

/// Δv of a perfect V-bar approach from rest (see the module docs), m/s; `n` the mean motion.
pub fn ideal_delta_v_m_s(profile: &Profile, d0: f64, n: f64) -> f64 {
    match *profile {
        Profile::ConstantSpeed { speed_m_s: v } => v + 2.0 * n * d0 + v,
        Profile::Exponential {
            time_constant_s: tau,
            min_speed_m_s: vmin,
        } => {
            let d_s = (tau * vmin).min(d0);
            let start = if d0 > d_s { d0 / tau } else { vmin };
            start + (4.0 * n * n + 1.0 / (tau * tau)).sqrt() * (d0 - d_s) + 2.0 * n * d_s + vmin
        }
    }
}

/// Parameters of `Glideslope`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GlideslopeParams {
    /// The approach axis.
    pub axis: ApproachAxis,
    /// Final range r_f along the axis, m.
    pub to_range_m: f64,
    /// The range profile.
    pub profile: Profile,
    /// Feedback gains.
    pub gains: TranslationGains,
}

impl LawParams for GlideslopeParams {
    fn commands(&self) -> Commands {
        Commands::Force
    }

    fn build(&self, ctx: &mut LawContext) -> Result<Box<dyn Controller>, BuildError> {
        if !(self.to_range_m.is_finite() && (0.0..1e9).contains(&self.to_range_m)) {
            return Err(BuildError::at(
                "to_range_m",
                format!(
                    "must be a range in m, ≥ 0 and below 1e9, got {}",
                    self.to_range_m
                ),
            ));
        }
        match self.profile {
            Profile::Exponential {
                time_constant_s,
                min_speed_m_s,
            } => {
                if !(time_constant_s.is_finite() && time_constant_s > 0.0 && time_constant_s < 1e9)
                {
                    return Err(BuildError::at(
                        "profile.0.time_constant_s",
                        format!("must be a positive time in s below 1e9, got {time_constant_s}"),
                    ));
                }
                if !(min_speed_m_s.is_finite() && (0.0..1e4).contains(&min_speed_m_s)) {
                    return Err(BuildError::at(
                        "profile.0.min_speed_m_s",
                        format!("must be a speed in m/s, ≥ 0 and below 1e4, got {min_speed_m_s}"),
                    ));
                }
            }
            Profile::ConstantSpeed { speed_m_s } => {
                if !(speed_m_s.is_finite() && speed_m_s > 0.0 && speed_m_s < 1e4) {
                    return Err(BuildError::at(
                        "profile.0.speed_m_s",
                        format!("must be a positive speed in m/s below 1e4, got {speed_m_s}"),
                    ));
                }
            }
        }
        if let ApproachAxis::Hill(v) = self.axis
            && !(v.iter().all(|x| x.is_finite()) && Vector3::from(v).norm() > 1e-9)
        {
            return Err(BuildError::at(
                "axis.0",
                format!("must be a finite non-zero direction, got {v:?}"),
            ));
        }
        self.gains
            .validate()
            .map_err(|(f, m)| BuildError::at(format!("gains.{f}"), m))?;
        if ctx.target.is_none() {
            return Err(BuildError::at_root(
                format!("controllers.{}.target", ctx.build.index),
                "Glideslope approaches a target: give the entry's `target`",
            ));
        }
        if self.axis == ApproachAxis::TargetPort && ctx.ports.is_none() {
            return Err(BuildError::at(
                "axis",
                "`TargetPort` needs the entry's `port` and `target_port` (or a docking mechanism between the two bodies)",
            ));
        }
        let orbit = ctx.build.env.reference().is_some();
        if !orbit && self.axis != ApproachAxis::TargetPort {
            return Err(BuildError::at(
                "axis",
                "V-bar, R-bar and Hill axes need an `Orbit` environment; use `TargetPort`",
            ));
        }
        let n = ctx
            .build
            .env
            .reference()
            .map_or(0.0, |(r, v)| super::mean_motion_rad_s(&r, &v));
        let point = if self.axis == ApproachAxis::TargetPort {
            ControlPoint::Port
        } else {
            ControlPoint::CentreOfMass
        };
        let sensed = super::hill::sensed(ctx, "Glideslope", point)?;
        Ok(Box::new(Glideslope {
            sensed,
            params: self.clone(),
            feedback: TranslationFeedback::new(&self.gains, n, ctx.period_s()),
            prefix: unique_prefix(ctx, "glideslope"),
            start: None,
            mass_kg: ctx.own().mass_kg,
            last: [f64::NAN; 8],
            error: None,
        }))
    }
}

/// The running `Glideslope` law.
#[derive(Debug, Clone)]
pub struct Glideslope {
    /// It flies on the entry's sensor ([`point_state`]).
    pub sensed: bool,
    /// Its parameters.
    pub params: GlideslopeParams,
    /// Its feedback.
    pub feedback: TranslationFeedback,
    prefix: String,
    /// (t₀ s, d₀ m) of the profile.
    start: Option<(f64, f64)>,
    mass_kg: f64,
    last: [f64; 8],
    error: Option<(f64, f64)>,
}

impl Glideslope {
    /// The approach axis in the frame of the controlled point's state.
    fn axis(&self, obs: &Observation, frame: Frame) -> Vector3<f64> {
        let hill = |v: [f64; 3]| Vector3::from(v).normalize();
        match self.params.axis {
            ApproachAxis::VBarBehind => -Vector3::y(),
            ApproachAxis::VBarAhead => Vector3::y(),
            ApproachAxis::RBarBelow => -Vector3::x(),
            ApproachAxis::RBarAbove => Vector3::x(),
            ApproachAxis::Hill(v) => hill(v),
            ApproachAxis::TargetPort => {
                let a = obs.ports.map_or(Vector3::x(), |p| p.target.axis());
                match (frame, obs.relative.and_then(|r| r.dcm_world_from_hill)) {
                    (Frame::Hill, Some(c)) => c.transpose() * a,
                    _ => a,
                }
            }
        }
    }

    /// The profile's (range, range rate) at `t_s` (None before the first call).
    pub fn reference_range(&self, t_s: f64) -> Option<(f64, f64)> {
        let (t0, d0) = self.start?;
        let (d, dd, _) = self.params.profile.at(d0, t_s - t0);
        Some((self.params.to_range_m + d, dd))
    }
}

impl Controller for Glideslope {
    fn command(&mut self, obs: &Observation) -> Command {
        let point = if self.params.axis == ApproachAxis::TargetPort {
            ControlPoint::Port
        } else {
            ControlPoint::CentreOfMass
        };
        let Some(s) = point_state(obs, point, self.sensed) else {
            return Command::zero();
        };
        let u = self.axis(obs, s.frame);
        let r_now = s.pos_m.dot(&u);
        let rf = self.params.to_range_m;
        let (t0, d0) = *self.start.get_or_insert((obs.t_s, (r_now - rf).max(0.0)));
        let (d, dd, ddd) = self.params.profile.at(d0, obs.t_s - t0);
        let (x_ref, v_ref, a_ref) = (u * (rf + d), u * dd, u * ddd);
        let n = target_mean_motion(obs);
        let a = self.feedback.accel(
            n,
            &s.pos_m,
            &s.vel_m_s,
            &x_ref,
            &v_ref,
            &a_ref,
            &s.com_pos_m,
            &s.com_vel_m_s,
        );
        let e = s.pos_m - x_ref;
        let ed = s.vel_m_s - v_ref;
        self.error = Some((e.norm(), ed.norm()));
        self.last = [
            rf + d,
            dd,
            r_now,
            s.vel_m_s.dot(&u),
            (e - u * e.dot(&u)).norm(),
            a.x,
            a.y,
            a.z,
        ];
        Command::in_frame(s.frame, a * self.mass_kg, Vector3::zeros())
    }

    fn columns(&self) -> Vec<String> {
        let p = &self.prefix;
        vec![
            format!("{p}.range_ref_m"),
            format!("{p}.range_rate_ref_m_s"),
            format!("{p}.range_m"),
            format!("{p}.range_rate_m_s"),
            format!("{p}.lateral_err_m"),
            format!("{p}.accel_cmd_x_m_s2"),
            format!("{p}.accel_cmd_y_m_s2"),
            format!("{p}.accel_cmd_z_m_s2"),
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

    fn tracking_error(&self) -> Option<(f64, f64)> {
        self.error
    }

    fn needs(&self) -> crate::control::interface::Needs {
        crate::control::interface::Needs {
            relative: true,
            ports: self.params.axis == ApproachAxis::TargetPort,
            gravity: false,
        }
    }
}

#[cfg(test)]
mod tests {
    //! References: the closed forms of the profile (d₀e^{−t/τ}, then linear), continuity of
    //! d and ḋ at the switch, and the Δv integral by quadrature of the ideal CW command.
    use super::*;

    #[test]
    fn val_glideslope_profile_closed_form() {
        let p = Profile::Exponential {
            time_constant_s: 100.0,
            min_speed_m_s: 0.05,
        };
        let d0 = 90.0;
        let (d, dd, ddd) = p.at(d0, 30.0);
        assert!((d - 90.0 * (-0.3f64).exp()).abs() < 1e-12);
        assert!((dd + d / 100.0).abs() < 1e-15 && (ddd - d / 1e4).abs() < 1e-15);
        // The switch at d_s = τ v_min = 5 m, t_s = τ ln(18).
        let ts = 100.0 * 18f64.ln();
        let before = p.at(d0, ts - 1e-9);
        let after = p.at(d0, ts + 1e-9);
        assert!((before.0 - after.0).abs() < 1e-9 && (before.1 - after.1).abs() < 1e-9);
        // Arrival at t_s + d_s/v_min = t_s + 100 s.
        assert_eq!(p.at(d0, ts + 100.0 + 1e-6).0, 0.0);
        assert!(p.at(d0, ts + 99.0).0 > 0.0);
    }

    /// The closed-form Δv against a quadrature of |a| = √((2nẏ)² + ÿ²) along the ideal
    /// profile, plus the two velocity steps.
    #[test]
    fn val_glideslope_delta_v_quadrature() {
        let n = 0.00106;
        for p in [
            Profile::Exponential {
                time_constant_s: 120.0,
                min_speed_m_s: 0.03,
            },
            Profile::ConstantSpeed { speed_m_s: 0.05 },
        ] {
            let d0 = 90.0;
            let h = 1e-3;
            let mut dv = 0.0;
            let mut t = 0.0;
            loop {
                let (d, dd, ddd) = p.at(d0, t + 0.5 * h);
                if d == 0.0 {
                    break;
                }
                dv += ((2.0 * n * dd).powi(2) + ddd * ddd).sqrt() * h;
                t += h;
            }
            let start = -p.at(d0, 0.0).1;
            let stop = -p.at(d0, t - h).1;
            let quad = start + dv + stop;
            let closed = ideal_delta_v_m_s(&p, d0, n);
            assert!((quad - closed).abs() < 1e-4 * closed, "{quad} vs {closed}");
        }
    }
}
