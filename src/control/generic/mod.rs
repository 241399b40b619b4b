//! Generic GNC laws any scene can fly, each one file, registered under its scene name
//! ([`crate::control::register_law`]):
//!
//! | scene name | file | what it does |
//! |---|---|---|
//! | `HillPd` | [`hill`] | position control toward a (moving) hold point in the target's Hill frame: PD with Clohessy–Wiltshire feed-forward, or discrete LQR from the CW model |
//! | `Glideslope` | [`glideslope`] | an approach along an axis (the target port's, V-bar or R-bar): exponential (closing rate ∝ range) or constant speed, tracked like `HillPd` |
//! | `Attitude` | [`attitude`] | quaternion feedback: hold inertial, hold LVLH, or align the controlled body's port with the target's port and match its rate |
//! | `Sequencer` | [`sequencer`] | phases, each naming a translation and an attitude law, with switching conditions (range, time, a guarantee's margin, the docking state); every switch is an event |
//!
//! # The Clohessy–Wiltshire model used by the translation laws
//! In the target's Hill frame (x radial out, y along-track, z orbit normal), with n the mean
//! motion of the target's orbit and a the commanded acceleration:
//! ẍ = 3n²x + 2nẏ + a_x,  ÿ = −2nẋ + a_y,  z̈ = −n²z + a_z
//! (Clohessy & Wiltshire 1960; circular reference). The laws treat the eccentricity and J2 of
//! the real orbit as disturbances that their feedback rejects.

pub mod attitude;
pub mod glideslope;
pub mod hill;
pub mod sequencer;

use crate::control::interface::Observation;
use crate::orbit::constants::MU_EARTH_M3_S2;
use nalgebra::{Matrix3, Vector3};
use serde::{Deserialize, Serialize};

/// The CW acceleration of the free relative motion at Hill position `x` and velocity `v`
/// (the terms a controller cancels or feeds forward), m/s².
pub fn cw_accel_m_s2(n: f64, x: &Vector3<f64>, v: &Vector3<f64>) -> Vector3<f64> {
    Vector3::new(
        3.0 * n * n * x.x + 2.0 * n * v.y,
        -2.0 * n * v.x,
        -n * n * x.z,
    )
}

/// Mean motion of the osculating two-body orbit through (r, v) (ECI), rad/s; 0 when unbound.
pub fn mean_motion_rad_s(r: &Vector3<f64>, v: &Vector3<f64>) -> f64 {
    let inv_a = 2.0 / r.norm() - v.norm_squared() / MU_EARTH_M3_S2;
    if inv_a > 0.0 && inv_a.is_finite() {
        (MU_EARTH_M3_S2 * inv_a.powi(3)).sqrt()
    } else {
        0.0
    }
}

/// The mean motion of the target's orbit at an instant (0 outside an orbit scene, where the
/// Hill frame does not exist and the translation laws act in the world frame instead).
pub fn target_mean_motion(obs: &Observation) -> f64 {
    match (obs.env.reference(), obs.target_state()) {
        (Some((r, v)), Some(t)) => mean_motion_rad_s(&(r + t.pos_m), &(v + t.vel_m_s)),
        (Some((r, v)), None) => mean_motion_rad_s(&r, &v),
        _ => 0.0,
    }
}

/// Feedback gains of a translation law.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub enum TranslationGains {
    /// PD with exact CW cancellation: a = a_ref − f_cw(x, ẋ) − ω²e − 2ζω ė per axis, so the
    /// error obeys ë + 2ζω ė + ω² e = 0 (in the CW model, between samples of a fast enough
    /// controller).
    Pd {
        /// Natural frequency ω of the error dynamics, rad/s.
        natural_frequency_rad_s: f64,
        /// Damping ratio ζ.
        damping_ratio: f64,
    },
    /// Discrete-time LQR on the CW model sampled at the controller period (zero-order hold):
    /// minimises Σ eᵀQe + aᵀRa with Q = diag(q_pos, q_vel), R = diag(r).
    Lqr {
        /// Weights on the position error per Hill axis, 1/m².
        q_pos_per_m2: [f64; 3],
        /// Weights on the velocity error per axis, s²/m².
        q_vel_s2_per_m2: [f64; 3],
        /// Weights on the commanded acceleration per axis, s⁴/m².
        r_s4_per_m2: [f64; 3],
    },
}

impl TranslationGains {
    /// Checks the numbers: `Err((field, message))` relative to the gains.
    pub fn validate(&self) -> Result<(), (String, String)> {
        match self {
            TranslationGains::Pd {
                natural_frequency_rad_s,
                damping_ratio,
            } => {
                if !(natural_frequency_rad_s.is_finite()
                    && *natural_frequency_rad_s > 0.0
                    && *natural_frequency_rad_s < 1e3)
                {
                    return Err((
                        "0.natural_frequency_rad_s".into(),
                        format!(
                            "must be a positive rate in rad/s below 1e3, got {natural_frequency_rad_s}"
                        ),
                    ));
                }
                if !(damping_ratio.is_finite() && (0.0..1e3).contains(damping_ratio)) {
                    return Err((
                        "0.damping_ratio".into(),
                        format!("must be ≥ 0 (and below 1e3), got {damping_ratio}"),
                    ));
                }
                Ok(())
            }
            TranslationGains::Lqr {
                q_pos_per_m2,
                q_vel_s2_per_m2,
                r_s4_per_m2,
            } => {
                for (f, v, strict) in [
                    ("0.q_pos_per_m2", q_pos_per_m2, false),
                    ("0.q_vel_s2_per_m2", q_vel_s2_per_m2, false),
                    ("0.r_s4_per_m2", r_s4_per_m2, true),
                ] {
                    let ok = v.iter().all(|x| {
                        x.is_finite() && *x < 1e12 && if strict { *x > 1e-12 } else { *x >= 0.0 }
                    });
                    if !ok {
                        return Err((
                            f.into(),
                            format!(
                                "weights must be finite, below 1e12 and {}, got {v:?}",
                                if strict { "positive" } else { "≥ 0" }
                            ),
                        ));
                    }
                }
                Ok(())
            }
        }
    }
}

/// A translation feedback ready to run: PD gains or an LQR gain matrix.
#[derive(Debug, Clone)]
pub enum TranslationFeedback {
    /// Per-axis ω² and 2ζω, with exact CW cancellation.
    Pd {
        /// ω², 1/s².
        kp: f64,
        /// 2ζω, 1/s.
        kd: f64,
    },
    /// a = −K_p e − K_d ė (3×3 blocks of the 3×6 LQR gain), plus the CW feed-forward at the
    /// reference.
    Lqr {
        /// Position block, 1/s².
        kp: Matrix3<f64>,
        /// Velocity block, 1/s.
        kd: Matrix3<f64>,
    },
}

impl TranslationFeedback {
    /// The feedback for `gains` at mean motion `n` and controller period `period_s`.
    pub fn new(gains: &TranslationGains, n: f64, period_s: f64) -> Self {
        match gains {
            TranslationGains::Pd {
                natural_frequency_rad_s: w,
                damping_ratio: z,
            } => TranslationFeedback::Pd {
                kp: w * w,
                kd: 2.0 * z * w,
            },
            TranslationGains::Lqr {
                q_pos_per_m2,
                q_vel_s2_per_m2,
                r_s4_per_m2,
            } => {
                let k = hill::lqr_cw_gain(n, period_s, q_pos_per_m2, q_vel_s2_per_m2, r_s4_per_m2);
                TranslationFeedback::Lqr {
                    kp: k.fixed_view::<3, 3>(0, 0).into_owned(),
                    kd: k.fixed_view::<3, 3>(0, 3).into_owned(),
                }
            }
        }
    }

    /// The commanded acceleration (Hill frame, m/s²) for the state (x, ẋ) of the controlled
    /// point, the reference (x_r, ẋ_r, ẍ_r) and the CW state (x_cw, ẋ_cw) of the centre of mass
    /// (the same point, or the centre of mass when the controlled point is a port).
    #[allow(clippy::too_many_arguments)]
    pub fn accel(
        &self,
        n: f64,
        x: &Vector3<f64>,
        v: &Vector3<f64>,
        x_ref: &Vector3<f64>,
        v_ref: &Vector3<f64>,
        a_ref: &Vector3<f64>,
        x_cw: &Vector3<f64>,
        v_cw: &Vector3<f64>,
    ) -> Vector3<f64> {
        let (e, ed) = (x - x_ref, v - v_ref);
        match self {
            TranslationFeedback::Pd { kp, kd } => {
                a_ref - cw_accel_m_s2(n, x_cw, v_cw) - e * *kp - ed * *kd
            }
            TranslationFeedback::Lqr { kp, kd } => {
                // Feed-forward that keeps the reference a solution of the CW model.
                let ref_cw = x_cw - e;
                let ref_cw_v = v_cw - ed;
                a_ref - cw_accel_m_s2(n, &ref_cw, &ref_cw_v) - kp * e - kd * ed
            }
        }
    }
}

/// A column prefix unique per law kind in one scene: `base`, then `base_1`, `base_2`, …
pub fn unique_prefix(ctx: &mut crate::control::spec::LawContext, base: &str) -> String {
    #[derive(Default)]
    struct Count(std::collections::BTreeMap<String, usize>);
    let c = ctx.build.shared::<Count>("generic.prefix");
    let k = c.0.entry(base.to_string()).or_insert(0);
    let p = if *k == 0 {
        base.to_string()
    } else {
        format!("{base}_{k}")
    };
    *k += 1;
    p
}
