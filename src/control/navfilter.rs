//! A generic relative-navigation filter: a linear Kalman filter on the Clohessy–Wiltshire
//! relative model (circular reference orbit) or the Yamanaka–Ankersen one (elliptic reference
//! orbit), fed by a sensor's noisy relative position, that any law with a sensor flies
//! on instead of the raw measurement (`sensor: Some((frame: Hill, …, filter: Some(Kalman(…))))`).
//! Bevy-free, deterministic (its only randomness is the sensor's seeded noise).
//!
//! # Model
//! State x = [r; ṙ], the controlled body's centre of mass relative to the target's, in the
//! target's Hill frame (x radial out, y along-track, z orbit normal; velocity seen in the
//! rotating frame), m and m/s. Between steps of the scene (`dt_s`):
//!
//! ẋ = A(t) x + B a + G w,   B = G = [0; I], a the acceleration the controller's actuator
//! applied during the step (known: F/m, the world force turned into the Hill frame of the
//! step's start, held over the step), w white acceleration noise of power spectral density q
//! per axis (`accel_psd_m2_s3`, m²/s³). A(t) is
//! - circular reference (osculating e below [`crate::orbit::kepler::E_CIRCULAR_TOL`] at load,
//!   every `Elements(e: 0.0)` scene): the CW model ([`super::generic::hill::cw_continuous`], n
//!   the mean motion of the reference orbit at load), time-invariant;
//! - elliptic reference: the linearised Tschauner–Hempel equations about the Keplerian orbit
//!   osculating the reference at load, whose transition matrix is the Yamanaka–Ankersen closed
//!   form ([`crate::orbit::ya`]; it lives in the target orbital frame (θ̂, −ĥ, −r̂) and is mapped
//!   to this Hill frame by the constant rotation (x, y, z)_tof = (y, −z, −x)_Hill,
//!   [`crate::orbit::ya::tof_to_hill`]); the true anomaly at each step from Kepler's equation.
//!
//! Discretised over a step h:
//! - CW, exactly: Φ = e^{Ah}, Γ = ∫₀ʰ e^{As} ds B (zero-order hold), and
//!   Q_d = ∫₀ʰ e^{As} G q Gᵀ e^{Aᵀs} ds by Van Loan's method (the exponential of
//!   [[−A, GqGᵀ], [0, Aᵀ]]·h, whose blocks give Φ⁻¹Q_d and Φᵀ);
//! - elliptic, per step k (Φ varies with the true anomaly): Φ_k = Φ(t_k+1, t_k) in closed form,
//!   Γ_k = ∫ Φ(t_k+1, s) B ds and Q_d,k = ∫ Φ(t_k+1, s) G q Gᵀ Φ(t_k+1, s)ᵀ ds over the step —
//!   the same integrals as the CW ones, evaluated by 5-point Gauss–Legendre quadrature of the
//!   closed-form Φ on sub-intervals of at most 0.05 rad of true anomaly at perigee
//!   ([`ya_step`]): the integrands are analytic with time scale 1/ḟ, so the quadrature's
//!   relative error is of order (0.05)¹⁰/10! ≈ 3e-20, below round-off (tested against a
//!   Simpson quadrature of the closed form, as the CW Q_d is).
//!
//! What q must cover: everything the model leaves out — the J2 of the real orbit (and, for the
//! CW model, its eccentricity), the target's own thrust, contact and magnet forces, the lever
//! arms of a rotating body. A bias a_u that persists for τ seconds adds about a_u²·τ of
//! velocity variance; q ≥ a_u²/τ_c·τ² is a conservative rule (the scene comments state the
//! number they chose).
//!
//! Measurement: z = H x + v, H = [I 0], v ~ N(0, σ²I) with σ the sensor's `position_noise_m`.
//! The sensor's velocity (differenced from the same noisy positions, hence correlated with
//! them) is not used: with a filter the velocity is the filter's. Update in Joseph form,
//! P⁺ = (I − KH) P (I − KH)ᵀ + K R Kᵀ, which stays symmetric positive definite.
//!
//! # Latency, honestly
//! A measurement exposed at step k_e reaches the filter at a later step (the sensor's
//! `latency_s`). The filter keeps its posterior at the last exposure (the *anchor*) and the
//! accelerations applied since; a delivery advances the anchor through the recorded steps to
//! k_e, updates it there with the measurement, and re-predicts to the current step with the
//! recorded accelerations. For this linear model that is exactly the filter that would have
//! received the measurement without delay; what the law sees is the prediction to now, whose
//! covariance includes the growth over the latency.
//!
//! # Initialisation
//! At the first delivery: r̂ = z, ṙ̂ = 0, P = diag(σ², …, `initial_vel_sigma_m_s`²…), at the
//! exposure; before it the law has no measurement and commands nothing.

use crate::control::generic::hill::cw_continuous;
use crate::orbit::elliptic::EllipticOrbit;
use crate::orbit::ya::ya_stm_hill;
use nalgebra::{SMatrix, SVector, Vector3};
use serde::{Deserialize, Serialize};
use std::collections::VecDeque;
use std::ops::SubAssign;

/// 6×6 matrix.
pub type M6 = SMatrix<f64, 6, 6>;
/// 6-vector.
pub type V6 = SVector<f64, 6>;

/// A navigation filter a sensor can feed (`filter: Some(Kalman(…))` on a sensor).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub enum NavFilterSpec {
    /// The linear Kalman filter on the CW or Yamanaka–Ankersen model (this module).
    Kalman {
        /// Power spectral density of the white acceleration noise per Hill axis, m²/s³.
        accel_psd_m2_s3: f64,
        /// Standard deviation of the initial velocity per axis, m/s (the initial position's is
        /// the sensor's noise).
        initial_vel_sigma_m_s: f64,
    },
}

impl NavFilterSpec {
    /// The acceleration noise's power spectral density per Hill axis, m²/s³.
    pub fn accel_psd(&self) -> f64 {
        let NavFilterSpec::Kalman {
            accel_psd_m2_s3, ..
        } = self;
        *accel_psd_m2_s3
    }

    /// Checks the numbers: `Err((field, message))` relative to the filter.
    pub fn validate(&self) -> Result<(), (String, String)> {
        let NavFilterSpec::Kalman {
            accel_psd_m2_s3,
            initial_vel_sigma_m_s,
        } = self;
        if !(accel_psd_m2_s3.is_finite() && *accel_psd_m2_s3 > 0.0 && *accel_psd_m2_s3 < 1e6) {
            return Err((
                "accel_psd_m2_s3".into(),
                format!(
                    "must be a positive spectral density in m²/s³ (below 1e6), got {accel_psd_m2_s3}"
                ),
            ));
        }
        if !(initial_vel_sigma_m_s.is_finite()
            && *initial_vel_sigma_m_s > 0.0
            && *initial_vel_sigma_m_s < 1e6)
        {
            return Err((
                "initial_vel_sigma_m_s".into(),
                format!(
                    "must be a positive standard deviation in m/s (below 1e6), got {initial_vel_sigma_m_s}"
                ),
            ));
        }
        Ok(())
    }
}

/// The CW model over one step `h_s`: (Φ, Γ, Q_d) for acceleration noise density `q` (m²/s³).
pub fn cw_step(n: f64, h_s: f64, q: f64) -> (M6, SMatrix<f64, 6, 3>, M6) {
    let (a, b) = crate::control::generic::hill::cw_discrete(n, h_s);
    let (ac, _) = cw_continuous(n);
    // Van Loan: exp([[−A, GqGᵀ], [0, Aᵀ]] h) = [[·, Φ⁻¹Q_d], [0, Φᵀ]].
    let mut m = SMatrix::<f64, 12, 12>::zeros();
    m.fixed_view_mut::<6, 6>(0, 0).copy_from(&(-ac * h_s));
    for i in 3..6 {
        m[(i, 6 + i)] = q * h_s;
    }
    m.fixed_view_mut::<6, 6>(6, 6)
        .copy_from(&(ac.transpose() * h_s));
    let e = m.exp();
    let qd = a * e.fixed_view::<6, 6>(0, 6);
    (a, b, (qd + qd.transpose()) * 0.5)
}

/// 5-point Gauss–Legendre nodes on [−1, 1] and their weights.
const GAUSS_LEGENDRE_5: [(f64, f64); 5] = [
    (0.0, 0.568_888_888_888_888_9),
    (-0.538_469_310_105_683_1, 0.478_628_670_499_366_5),
    (0.538_469_310_105_683_1, 0.478_628_670_499_366_5),
    (-0.906_179_845_938_664, 0.236_926_885_056_189_1),
    (0.906_179_845_938_664, 0.236_926_885_056_189_1),
];

/// Largest true-anomaly advance (at the perigee rate) of one quadrature sub-interval of
/// [`ya_step`], rad.
pub const YA_QUADRATURE_ANOMALY_RAD: f64 = 0.05;

/// The Yamanaka–Ankersen model over the step from `t0_s` (time of `orbit`, whose t = 0 is at
/// its `f0_rad`) to `t0_s + h_s`, Hill frame: (Φ, Γ, Q_d) for acceleration noise density `q`
/// (m²/s³), the input held constant in the Hill frame over the step. Γ and Q_d are the
/// integrals of Φ(t₁, s)·[0; I] and Φ(t₁, s)[0; I] q [0 I]Φ(t₁, s)ᵀ over s, by 5-point
/// Gauss–Legendre quadrature on ⌈ḟ_p h / [`YA_QUADRATURE_ANOMALY_RAD`]⌉ equal sub-intervals
/// (ḟ_p the perigee rate).
pub fn ya_step(orbit: &EllipticOrbit, t0_s: f64, h_s: f64, q: f64) -> (M6, SMatrix<f64, 6, 3>, M6) {
    let t1 = t0_s + h_s;
    let phi = ya_stm_hill(orbit, t0_s, t1);
    let fdot_p = orbit.f_dot_rad_s(0.0);
    let m = (fdot_p * h_s / YA_QUADRATURE_ANOMALY_RAD).ceil().max(1.0) as usize;
    let w = h_s / m as f64;
    let mut gam = SMatrix::<f64, 6, 3>::zeros();
    let mut qd = M6::zeros();
    for i in 0..m {
        let mid = t0_s + (i as f64 + 0.5) * w;
        for (x, wt) in GAUSS_LEGENDRE_5 {
            let s = mid + 0.5 * w * x;
            let g = ya_stm_hill(orbit, s, t1)
                .fixed_view::<6, 3>(0, 3)
                .into_owned();
            let c = 0.5 * w * wt;
            gam += g * c;
            qd += g * g.transpose() * (c * q);
        }
    }
    (phi, gam, (qd + qd.transpose()) * 0.5)
}

/// The relative model a filter propagates with.
#[derive(Debug, Clone)]
enum Model {
    /// Circular reference: one (Φ, Γ, Q_d) for every step ([`cw_step`]).
    Cw(Box<(M6, SMatrix<f64, 6, 3>, M6)>),
    /// Elliptic reference: (Φ, Γ, Q_d) of step k from [`ya_step`] at t = t_step0_s + k·dt_s of
    /// the orbit's time.
    Elliptic {
        orbit: EllipticOrbit,
        t_step0_s: f64,
        dt_s: f64,
        q: f64,
    },
}

/// A running relative-navigation Kalman filter (CW or Yamanaka–Ankersen model).
#[derive(Debug, Clone)]
pub struct RelKalman {
    model: Model,
    /// Measurement variance per axis, m².
    r_m2: f64,
    init_vel_var: f64,
    /// Posterior at the last exposure: (step, state, covariance).
    anchor: Option<(u64, V6, M6)>,
    /// Accelerations applied at steps ≥ the anchor's, in order: (step, Hill acceleration m/s²).
    history: VecDeque<(u64, Vector3<f64>)>,
    /// The estimate predicted to the current step: (step, state, covariance).
    now: Option<(u64, V6, M6)>,
    /// The normalised innovation squared of the last update (χ²(3) for a consistent filter).
    pub last_nis: Option<f64>,
}

impl RelKalman {
    /// A filter on the CW model (circular reference) for mean motion `n` (rad/s), scene step
    /// `dt_s`, sensor noise σ `position_noise_m` and the spec's numbers.
    pub fn new(spec: &NavFilterSpec, n: f64, dt_s: f64, position_noise_m: f64) -> Self {
        let (phi, gam, qd) = cw_step(n, dt_s, spec.accel_psd());
        Self::with_model(spec, Model::Cw(Box::new((phi, gam, qd))), position_noise_m)
    }

    /// A filter on the Yamanaka–Ankersen model about the Keplerian `orbit`, step k spanning
    /// the orbit's times t_step0_s + k·dt_s to t_step0_s + (k+1)·dt_s (s); σ and the spec as
    /// for [`RelKalman::new`].
    pub fn new_elliptic(
        spec: &NavFilterSpec,
        orbit: EllipticOrbit,
        t_step0_s: f64,
        dt_s: f64,
        position_noise_m: f64,
    ) -> Self {
        let model = Model::Elliptic {
            orbit,
            t_step0_s,
            dt_s,
            q: spec.accel_psd(),
        };
        Self::with_model(spec, model, position_noise_m)
    }

    /// The filter for the reference orbit's inertial state (`r_eci_m`, `v_eci_m_s`, m and m/s,
    /// μ = Earth's) at time `t_ref_s` of a scene whose step k starts at k·`dt_s`: the CW model
    /// if that orbit is circular (osculating e below [`crate::orbit::kepler::E_CIRCULAR_TOL`],
    /// mean motion from its energy as the laws compute it), else the Yamanaka–Ankersen model
    /// about the Keplerian orbit osculating it. `None` if the orbit is not elliptic.
    pub fn for_reference(
        spec: &NavFilterSpec,
        r_eci_m: &Vector3<f64>,
        v_eci_m_s: &Vector3<f64>,
        t_ref_s: f64,
        dt_s: f64,
        position_noise_m: f64,
    ) -> Option<Self> {
        use crate::orbit::constants::MU_EARTH_M3_S2;
        use crate::orbit::kepler::{ClassicalElements, E_CIRCULAR_TOL};
        let n = crate::control::generic::mean_motion_rad_s(r_eci_m, v_eci_m_s);
        if !(n > 0.0 && n.is_finite()) {
            return None;
        }
        let el = ClassicalElements::from_state(r_eci_m, v_eci_m_s, MU_EARTH_M3_S2);
        if el.e.is_nan() || el.e >= 1.0 {
            return None;
        }
        if el.e >= E_CIRCULAR_TOL {
            let orbit = EllipticOrbit {
                mu_m3_s2: MU_EARTH_M3_S2,
                semi_latus_rectum_m: el.a_m * (1.0 - el.e * el.e),
                eccentricity: el.e,
                f0_rad: el.true_anomaly_rad,
                inclination_rad: el.i_rad,
                raan_rad: el.raan_rad,
                arg_perigee_rad: el.argp_rad,
            };
            return Some(Self::new_elliptic(
                spec,
                orbit,
                -t_ref_s,
                dt_s,
                position_noise_m,
            ));
        }
        Some(Self::new(spec, n, dt_s, position_noise_m))
    }

    /// True when the filter runs the Yamanaka–Ankersen (elliptic) model.
    pub fn is_elliptic(&self) -> bool {
        matches!(self.model, Model::Elliptic { .. })
    }

    fn with_model(spec: &NavFilterSpec, model: Model, position_noise_m: f64) -> Self {
        let NavFilterSpec::Kalman {
            initial_vel_sigma_m_s,
            ..
        } = spec;
        Self {
            model,
            r_m2: position_noise_m * position_noise_m,
            init_vel_var: initial_vel_sigma_m_s * initial_vel_sigma_m_s,
            anchor: None,
            history: VecDeque::new(),
            now: None,
            last_nis: None,
        }
    }

    /// The prediction over step `step` with the acceleration `a` held.
    fn predict(&self, step: u64, x: &V6, p: &M6, a: &Vector3<f64>) -> (V6, M6) {
        let step_matrices;
        let (phi, gam, qd) = match &self.model {
            Model::Cw(m) => (&m.0, &m.1, &m.2),
            Model::Elliptic {
                orbit,
                t_step0_s,
                dt_s,
                q,
            } => {
                step_matrices = ya_step(orbit, t_step0_s + step as f64 * dt_s, *dt_s, *q);
                (&step_matrices.0, &step_matrices.1, &step_matrices.2)
            }
        };
        let x1 = phi * x + gam * a;
        let p1 = phi * p * phi.transpose() + qd;
        (x1, (p1 + p1.transpose()) * 0.5)
    }

    /// Records the acceleration `accel_hill_m_s2` applied over step `step` (from t = step·dt to
    /// the next step) and predicts the current estimate over it.
    pub fn propagate(&mut self, step: u64, accel_hill_m_s2: Vector3<f64>) {
        if self.anchor.is_none() {
            return;
        }
        self.history.push_back((step, accel_hill_m_s2));
        if let Some((k, x, p)) = self.now
            && k == step
        {
            let (x1, p1) = self.predict(k, &x, &p, &accel_hill_m_s2);
            self.now = Some((k + 1, x1, p1));
        }
    }

    /// A measurement `z_m` (Hill position) exposed at step `exposure_step`, delivered at step
    /// `now_step` (≥ the exposure).
    pub fn update(&mut self, exposure_step: u64, now_step: u64, z_m: Vector3<f64>) {
        let h_r = self.r_m2;
        let (x, p) = match self.anchor {
            None => {
                let mut x = V6::zeros();
                x.fixed_rows_mut::<3>(0).copy_from(&z_m);
                let mut p = M6::zeros();
                for i in 0..3 {
                    p[(i, i)] = h_r;
                    p[(i + 3, i + 3)] = self.init_vel_var;
                }
                self.last_nis = None;
                (x, p)
            }
            Some((ka, mut x, mut p)) => {
                // Advance the anchor to the exposure through the recorded steps.
                let mut k = ka;
                while let Some(&(s, a)) = self.history.front() {
                    if s >= exposure_step {
                        break;
                    }
                    self.history.pop_front();
                    if s != k {
                        continue;
                    }
                    (x, p) = self.predict(k, &x, &p, &a);
                    k += 1;
                }
                // Update: H = [I 0].
                let hp = p.fixed_view::<3, 6>(0, 0).into_owned();
                let s = p.fixed_view::<3, 3>(0, 0) + nalgebra::Matrix3::identity() * h_r;
                let Some(s_inv) = s.try_inverse() else {
                    return;
                };
                let nu = z_m - x.fixed_rows::<3>(0);
                self.last_nis = Some((nu.transpose() * s_inv * nu)[(0, 0)]);
                let kg = hp.transpose() * s_inv;
                let x1 = x + kg * nu;
                let mut ikh = M6::identity();
                ikh.fixed_view_mut::<6, 3>(0, 0).sub_assign(&kg);
                let p1 = ikh * p * ikh.transpose() + kg * kg.transpose() * h_r;
                (x1, (p1 + p1.transpose()) * 0.5)
            }
        };
        // Drop what precedes the exposure (first delivery: everything recorded before it).
        while self
            .history
            .front()
            .is_some_and(|&(s, _)| s < exposure_step)
        {
            self.history.pop_front();
        }
        self.anchor = Some((exposure_step, x, p));
        // Re-predict to now with the recorded accelerations.
        let (mut k, mut xn, mut pn) = (exposure_step, x, p);
        for &(s, a) in &self.history {
            if s != k || k >= now_step {
                break;
            }
            (xn, pn) = self.predict(k, &xn, &pn, &a);
            k += 1;
        }
        self.now = Some((k, xn, pn));
    }

    /// The current estimate: (step it is for, state [r; ṙ] Hill m and m/s, covariance).
    pub fn estimate(&self) -> Option<(u64, V6, M6)> {
        self.now
    }

    /// The posterior at the last exposure: (step, state, covariance).
    pub fn anchor(&self) -> Option<(u64, V6, M6)> {
        self.anchor
    }
}

#[cfg(test)]
mod tests {
    //! References, all computed here independently of the filter's code:
    //! - the CW state-transition matrix in closed form (Clohessy & Wiltshire 1960), and the
    //!   process noise Q_d = ∫ Φ(s) G q Gᵀ Φ(s)ᵀ ds by composite Simpson quadrature of it
    //!   (2000 intervals: relative error ~1e-13 on these smooth integrands);
    //! - the steady prior covariance as the stabilising solution of the discrete Riccati
    //!   equation X = Φ X Φᵀ − Φ X Hᵀ (H X Hᵀ + R)⁻¹ H X Φᵀ + Q, by the structured doubling
    //!   algorithm (Chu, Fan, Lin 2005), not by iterating the filter's recursion;
    //! - a truth simulated with the closed-form STM and Cholesky-sampled process noise, its initial
    //!   velocity drawn from the filter's prior.
    //! - elliptic model: Γ and Q_d against a composite Simpson quadrature (2000 intervals) of
    //!   the closed-form Yamanaka–Ankersen Φ (itself tested against an RK4 integration of the
    //!   linearised equations in `orbit::ya`), and against the CW step at e = 0;
    //! - elliptic truth (e = 0.1, starting 100 m away near perigee): the *nonlinear* relative
    //!   dynamics of `orbit::elliptic` (Xu & Hu 2015, tested against an inertial two-body
    //!   integration) integrated by RK4 in 0.01 s sub-steps, with the continuous white
    //!   acceleration noise entered by Euler–Maruyama (a velocity kick √(q·δ)·N(0, 1) per axis
    //!   and sub-step: its covariance over a step differs from the exact one by O(ḟδ) ≈ 1e-5
    //!   relative). The nonlinear truth rather than the linear model itself so the test is
    //!   independent of the closed form being filtered; at ≤ 200 m the neglected gravity term is
    //!   ≤ 3μρ²/R⁴ ≈ 2e-8 m/s², which over 300 s moves a state by ≤ 1 mm against the filter's
    //!   σ of centimetres (a NEES change of ~1e-3 per degree of freedom, far inside the bounds).
    //!
    //! Consistency bounds are chi-square quantiles ([`crate::math::stats::chi2_quantile`],
    //! itself tested against tables): for M independent runs the summed NEES at one time is
    //! χ²(6M); the summed NIS of one run over K updates is χ²(3K) (the innovations of a
    //! consistent filter are white). Two-sided 99 % intervals: a correct filter fails each
    //! check with probability 1 %, and the seeds are fixed, so the outcome is reproducible.
    use super::*;
    use crate::math::rng::GaussianNoise;
    use crate::math::stats::chi2_quantile;

    const N: f64 = 0.001_1; // rad/s, a low Earth orbit
    const DT: f64 = 0.1;

    fn stm(n: f64, t: f64) -> M6 {
        let (s, c) = (n * t).sin_cos();
        #[rustfmt::skip]
        let m = M6::from_row_slice(&[
            4.0 - 3.0 * c, 0.0, 0.0, s / n, 2.0 * (1.0 - c) / n, 0.0,
            6.0 * (s - n * t), 1.0, 0.0, -2.0 * (1.0 - c) / n, 4.0 * s / n - 3.0 * t, 0.0,
            0.0, 0.0, c, 0.0, 0.0, s / n,
            3.0 * n * s, 0.0, 0.0, c, 2.0 * s, 0.0,
            -6.0 * n * (1.0 - c), 0.0, 0.0, -2.0 * s, 4.0 * c - 3.0, 0.0,
            0.0, 0.0, -n * s, 0.0, 0.0, c,
        ]);
        m
    }

    fn qd_quadrature(n: f64, h: f64, q: f64) -> M6 {
        let k = 2000;
        let f = |s: f64| {
            let p = stm(n, s);
            let g = p.fixed_view::<6, 3>(0, 3).into_owned();
            g * g.transpose() * q
        };
        let dx = h / k as f64;
        let mut sum = f(0.0) + f(h);
        for i in 1..k {
            sum += f(i as f64 * dx) * if i % 2 == 1 { 4.0 } else { 2.0 };
        }
        sum * (dx / 3.0)
    }

    /// Structured doubling for X = Aᵀ X (I + G X)⁻¹ A + H, here with A = Φᵀ, G = Hᵀ R⁻¹ H
    /// (H = [I 0]) and H = Q: the filter's prior Riccati equation.
    fn dare_sda(phi: &M6, q: &M6, r: f64) -> M6 {
        let mut g = M6::zeros();
        for i in 0..3 {
            g[(i, i)] = 1.0 / r;
        }
        let (mut a, mut gk, mut hk) = (phi.transpose(), g, *q);
        for _ in 0..60 {
            let w = (M6::identity() + gk * hk)
                .try_inverse()
                .expect("invertible");
            let a1 = a * w * a;
            let g1 = gk + a * w * gk * a.transpose();
            let h1 = hk + a.transpose() * hk * w * a;
            a = a1;
            gk = (g1 + g1.transpose()) * 0.5;
            hk = (h1 + h1.transpose()) * 0.5;
        }
        hk
    }

    fn spec(q: f64) -> NavFilterSpec {
        NavFilterSpec::Kalman {
            accel_psd_m2_s3: q,
            initial_vel_sigma_m_s: 0.1,
        }
    }

    /// The discretisation: Φ against the closed-form STM, Q_d against the quadrature.
    #[test]
    fn val_cw_discretisation() {
        let (phi, _, qd) = cw_step(N, 1.0, 1e-6);
        assert!((phi - stm(N, 1.0)).amax() < 1e-12);
        let qr = qd_quadrature(N, 1.0, 1e-6);
        assert!((qd - qr).amax() < 1e-12 * qr.amax(), "{qd} vs {qr}");
    }

    /// Steady state: measuring every 10 steps (T = 1 s) with no latency, the filter's prior
    /// covariance at an exposure converges to the DARE solution for (Φ(T), Q_d(T), σ²I), and
    /// its posterior to X − X Hᵀ (H X Hᵀ + R)⁻¹ H X. Tolerance 1e-8 relative: the quadrature's
    /// 1e-13 amplified by the Riccati map, far below any physics but far above round-off.
    #[test]
    fn val_kalman_steady_covariance_is_the_riccati_solution() {
        let (q, sigma) = (1e-6, 0.5);
        let mut f = RelKalman::new(&spec(q), N, DT, sigma);
        let mut prior = M6::zeros();
        for k in 0..40_000u64 {
            if k > 0 {
                f.propagate(k - 1, Vector3::zeros());
            }
            if k % 10 == 0 {
                if let Some((_, _, p)) = f.estimate() {
                    prior = p;
                }
                f.update(k, k, Vector3::new(1.0, 2.0, 3.0));
            }
        }
        let x = dare_sda(&stm(N, 1.0), &qd_quadrature(N, 1.0, q), sigma * sigma);
        let rel = (prior - x).amax() / x.amax();
        assert!(rel < 1e-8, "prior vs DARE: {rel:e}\n{prior}\n{x}");
        let s = x.fixed_view::<3, 3>(0, 0) + nalgebra::Matrix3::identity() * sigma * sigma;
        let xh = x.fixed_view::<6, 3>(0, 0).into_owned();
        let post = x - xh * s.try_inverse().expect("spd") * xh.transpose();
        let (_, _, pa) = f.anchor().expect("updated");
        let rel = (pa - post).amax() / post.amax();
        assert!(rel < 1e-8, "posterior vs DARE: {rel:e}");
    }

    /// A truth from the closed-form STM with process noise sampled from the quadrature Q_d,
    /// a known thrust profile, σ = 0.5 m measurements every 1 s delivered 0.5 s late.
    /// Returns per run the NEES of the estimate (predicted to now) at the end and the NIS of
    /// each update.
    /// The known thrust acceleration of the consistency runs at step k (Hill frame, m/s²).
    fn accel(k: u64) -> Vector3<f64> {
        let t = k as f64 * DT;
        Vector3::new(1e-4 * (0.01 * t).sin(), -2e-4, 5e-5 * (0.03 * t).cos())
    }

    /// The sensor of the consistency runs at step k: every 10th step it exposes the true Hill
    /// position `r_hill` plus N(0, σ² I) noise; a measurement reaches the filter
    /// `latency_steps` after its exposure, and the update's NIS is kept.
    #[allow(clippy::too_many_arguments)]
    fn sense_and_update(
        f: &mut RelKalman,
        pending: &mut VecDeque<(u64, Vector3<f64>)>,
        g: &mut GaussianNoise,
        k: u64,
        r_hill: &Vector3<f64>,
        sigma: f64,
        latency_steps: u64,
        nis: &mut Vec<f64>,
    ) {
        if k.is_multiple_of(10) {
            let z = r_hill
                + Vector3::new(
                    g.standard_normal(),
                    g.standard_normal(),
                    g.standard_normal(),
                ) * sigma;
            pending.push_back((k, z));
        }
        while pending
            .front()
            .is_some_and(|&(ke, _)| ke + latency_steps <= k)
        {
            let (ke, z) = pending.pop_front().expect("front");
            f.update(ke, k, z);
            if let Some(v) = f.last_nis {
                nis.push(v);
            }
        }
    }

    fn monte_carlo(runs: u64, steps: u64) -> (Vec<f64>, Vec<f64>) {
        let (q, sigma, latency_steps) = (1e-6, 0.5, 5u64);
        let phi = stm(N, DT);
        let qd = qd_quadrature(N, DT, q);
        let l = qd.cholesky().expect("Q_d positive definite").l();
        let (_, gam) = crate::control::generic::hill::cw_discrete(N, DT);
        let (mut nees, mut nis) = (Vec::new(), Vec::new());
        for run in 0..runs {
            let mut g = GaussianNoise::new(1000 + run);
            // The initial velocity drawn from the filter's prior N(0, 0.1² I) so the prior is
            // the truth's distribution (the position's prior is the first measurement's).
            let mut x = V6::from_column_slice(&[10.0, -100.0, 2.0, 0.0, 0.0, 0.0]);
            for i in 3..6 {
                x[i] = 0.1 * g.standard_normal();
            }
            let mut f = RelKalman::new(&spec(q), N, DT, sigma);
            let mut pending: VecDeque<(u64, Vector3<f64>)> = VecDeque::new();
            for k in 0..steps {
                if k > 0 {
                    f.propagate(k - 1, accel(k - 1));
                }
                let r_true = x.fixed_rows::<3>(0).into_owned();
                sense_and_update(
                    &mut f,
                    &mut pending,
                    &mut g,
                    k,
                    &r_true,
                    sigma,
                    latency_steps,
                    &mut nis,
                );
                if k + 1 == steps {
                    let (ks, xe, p) = f.estimate().expect("estimating");
                    assert_eq!(ks, k, "the estimate is for the current step");
                    let e = xe - x;
                    nees.push((e.transpose() * p.try_inverse().expect("spd") * e)[(0, 0)]);
                }
                let w = l * V6::from_fn(|_, _| g.standard_normal());
                x = phi * x + gam * accel(k) + w;
            }
        }
        (nees, nis)
    }

    /// The elliptic step: Γ and Q_d against Simpson quadratures of the closed-form Φ over a
    /// 1 s step at perigee and at apogee of an e = 0.1 orbit (relative 1e-12: the Simpson
    /// error at 2000 intervals is ~(ḟh/2000)⁴ ≈ 1e-25, the rest round-off of sums of 2000 terms);
    /// and at e = 0 the step equals the CW one ([`cw_step`]) to the same relative 1e-12.
    #[test]
    fn val_ya_step_discretisation() {
        use crate::orbit::elliptic::EllipticOrbit;
        use crate::orbit::ya::ya_stm_hill;
        let (h, q) = (1.0, 1e-6);
        let o = EllipticOrbit::from_perigee_altitude(500e3, 0.1, -0.3, 0.5, 1.0, 0.3);
        for t0 in [0.0, 0.5 * o.period_s()] {
            let (phi, gam, qd) = ya_step(&o, t0, h, q);
            assert!((phi - ya_stm_hill(&o, t0, t0 + h)).amax() < 1e-15);
            let k = 2000;
            let dx = h / k as f64;
            let (mut g_ref, mut q_ref) = (SMatrix::<f64, 6, 3>::zeros(), M6::zeros());
            for i in 0..=k {
                let w = if i == 0 || i == k {
                    1.0
                } else if i % 2 == 1 {
                    4.0
                } else {
                    2.0
                } * dx
                    / 3.0;
                let s = t0 + i as f64 * dx;
                let g = ya_stm_hill(&o, s, t0 + h)
                    .fixed_view::<6, 3>(0, 3)
                    .into_owned();
                g_ref += g * w;
                q_ref += g * g.transpose() * (q * w);
            }
            assert!(
                (gam - g_ref).amax() < 1e-12 * g_ref.amax(),
                "{gam} vs {g_ref}"
            );
            assert!(
                (qd - q_ref).amax() < 1e-12 * q_ref.amax(),
                "{qd} vs {q_ref}"
            );
        }
        let c = EllipticOrbit::from_perigee_altitude(500e3, 0.0, 0.2, 0.5, 1.0, 0.0);
        let (phi, gam, qd) = ya_step(&c, 123.0, h, q);
        let (phi_c, gam_c, qd_c) = cw_step(c.mean_motion_rad_s(), h, q);
        assert!((phi - phi_c).amax() < 1e-12 * phi_c.amax());
        assert!((gam - gam_c).amax() < 1e-12 * gam_c.amax());
        assert!((qd - qd_c).amax() < 1e-12 * qd_c.amax());
    }

    /// An elliptic truth (see the header): returns per run the NEES at the end and the NIS of
    /// each update, for the YA filter (`elliptic`) or a CW filter at the orbit's mean motion
    /// (eccentricity left to the process noise).
    fn monte_carlo_elliptic(runs: u64, steps: u64, elliptic: bool) -> (Vec<f64>, Vec<f64>) {
        use crate::orbit::elliptic::{EllipticOrbit, rk4_step_relative};
        use crate::orbit::lvlh::dcm_lvlh_from_hill;
        let (q, sigma, latency_steps, sub) = (1e-6, 0.5, 5u64, 10usize);
        let o = EllipticOrbit::from_perigee_altitude(500e3, 0.1, -0.3, 0.5, 1.0, 0.3);
        let p = dcm_lvlh_from_hill(); // tof from Hill
        let delta = DT / sub as f64;
        let kick = (q * delta).sqrt();
        let (mut nees, mut nis) = (Vec::new(), Vec::new());
        for run in 0..runs {
            let mut g = GaussianNoise::new(5000 + run);
            let mut r = p * Vector3::new(10.0, -100.0, 2.0);
            let mut v = p * Vector3::new(
                0.1 * g.standard_normal(),
                0.1 * g.standard_normal(),
                0.1 * g.standard_normal(),
            );
            let mut f = if elliptic {
                RelKalman::new_elliptic(&spec(q), o, 0.0, DT, sigma)
            } else {
                RelKalman::new(&spec(q), o.mean_motion_rad_s(), DT, sigma)
            };
            let mut pending: VecDeque<(u64, Vector3<f64>)> = VecDeque::new();
            for k in 0..steps {
                if k > 0 {
                    f.propagate(k - 1, accel(k - 1));
                }
                let r_hill = p.transpose() * r;
                sense_and_update(
                    &mut f,
                    &mut pending,
                    &mut g,
                    k,
                    &r_hill,
                    sigma,
                    latency_steps,
                    &mut nis,
                );
                if k + 1 == steps {
                    let (ks, xe, pc) = f.estimate().expect("estimating");
                    assert_eq!(ks, k);
                    let vh = p.transpose() * v;
                    let x =
                        V6::from_column_slice(&[r_hill.x, r_hill.y, r_hill.z, vh.x, vh.y, vh.z]);
                    let e = xe - x;
                    nees.push((e.transpose() * pc.try_inverse().expect("spd") * e)[(0, 0)]);
                }
                let a_tof = p * accel(k);
                for j in 0..sub {
                    let t = k as f64 * DT + j as f64 * delta;
                    let st = crate::orbit::elliptic::RelStateTof::new(r.x, r.y, r.z, v.x, v.y, v.z);
                    let st = rk4_step_relative(&st, t, delta, &o, |_| a_tof);
                    r = Vector3::new(st[0], st[1], st[2]);
                    v = Vector3::new(st[3], st[4], st[5])
                        + Vector3::new(
                            g.standard_normal(),
                            g.standard_normal(),
                            g.standard_normal(),
                        ) * kick;
                }
            }
        }
        (nees, nis)
    }

    /// The YA filter on the elliptic (e = 0.1) nonlinear truth: NEES summed over 200 runs at
    /// t = 300 s within the two-sided 99 % interval of χ²(1200), NIS over all updates within
    /// that of χ²(3K), as for the CW filter on its own truth. A CW filter on the same truth
    /// (eccentricity as process noise, same q) is printed for comparison.
    #[test]
    fn val_ya_kalman_consistency_on_an_elliptic_truth() {
        for elliptic in [true, false] {
            let (nees, nis) = monte_carlo_elliptic(200, 3000, elliptic);
            let m = nees.len() as f64;
            let sum: f64 = nees.iter().sum();
            let (lo, hi) = (chi2_quantile(0.005, 6.0 * m), chi2_quantile(0.995, 6.0 * m));
            let k = nis.len() as f64;
            let s: f64 = nis.iter().sum();
            let (lo3, hi3) = (chi2_quantile(0.005, 3.0 * k), chi2_quantile(0.995, 3.0 * k));
            let name = if elliptic { "YA" } else { "CW" };
            println!(
                "{name}: NEES sum {sum:.1} in [{lo:.1}, {hi:.1}] ({m} runs); NIS sum {s:.1} in [{lo3:.1}, {hi3:.1}] ({k} updates)"
            );
            if elliptic {
                assert!(lo < sum && sum < hi, "NEES sum {sum} outside [{lo}, {hi}]");
                assert!(lo3 < s && s < hi3, "NIS sum {s} outside [{lo3}, {hi3}]");
            }
        }
    }

    /// NEES over 200 independent runs (at t = 300 s, 2.5 s after the last exposure: the
    /// prediction across the latency is tested too) within the two-sided 99 % chi-square
    /// interval of 6·200 degrees of freedom; NIS over all updates within that of 3·K.
    #[test]
    fn val_kalman_consistency_nees_nis() {
        let (nees, nis) = monte_carlo(200, 3000);
        let m = nees.len() as f64;
        let sum: f64 = nees.iter().sum();
        let (lo, hi) = (chi2_quantile(0.005, 6.0 * m), chi2_quantile(0.995, 6.0 * m));
        println!("NEES sum {sum:.1} in [{lo:.1}, {hi:.1}] ({m} runs)");
        assert!(
            lo < sum && sum < hi,
            "NEES sum {sum} outside [{lo}, {hi}] (6M = {})",
            6.0 * m
        );
        // Every update but each run's first (the initialisation, which has no innovation).
        let k = nis.len() as f64;
        let s: f64 = nis.iter().sum();
        let (lo, hi) = (chi2_quantile(0.005, 3.0 * k), chi2_quantile(0.995, 3.0 * k));
        println!("NIS sum {s:.1} in [{lo:.1}, {hi:.1}] ({k} updates)");
        assert!(
            lo < s && s < hi,
            "NIS sum {s} outside [{lo}, {hi}] (3K = {})",
            3.0 * k
        );
    }
}
