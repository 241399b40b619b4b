//! Keplerian target orbit in true anomaly and the nonlinear relative dynamics of
//! Xu & Hu (2015), "Control for relative position of spacecraft rendezvous with a
//! non-cooperative maneuver target", Aerospace Control and Application 41(6), eqs. (1)–(8).
//!
//! The paper's equations were lost in extraction; the form used here is the standard nonlinear
//! relative motion in the target's orbital frame, re-derived below and checked against an
//! inertial two-body integration in the tests.
//!
//! # Frames
//! - ECI: Earth-centred inertial (x to the vernal equinox, z north).
//! - Target orbital frame ("tof", the paper's o-frame): origin at the target's centre of
//!   mass, `z` toward Earth's centre (−r̂), `y` = −orbit normal (−ĥ), `x = y × z`, i.e. the
//!   in-plane transverse direction θ̂ (along-track only at perigee/apogee when e ≠ 0).
//!   The frame rotates with ω = (0, −ḟ, 0) (expressed in itself), ω̇ = (0, −f̈, 0).
//!
//! # Relative dynamics
//! With ρ = (x, y, z) the chaser position relative to the target in the tof,
//! r_t = (0, 0, −R) and r_c = r_t + ρ, the transport theorem gives
//! ρ̈ = −μ r_c/|r_c|³ + μ r_t/R³ + a − 2ω×ρ̇ − ω̇×ρ − ω×(ω×ρ), which expands to
//! ```text
//! ẍ =  2ḟ ż + f̈ z + ḟ² x − μ x / r_c³ + a_x
//! ÿ =  −μ y / r_c³ + a_y
//! z̈ = −2ḟ ẋ − f̈ x + ḟ² z + μ (R − z)/r_c³ − μ/R² + a_z
//! r_c = sqrt(x² + y² + (R − z)²), R = p/(1 + e cos f), ḟ = sqrt(μ p)/R², f̈ = −2 μ e sin f / R³
//! ```
//! where `a = u/m_c − F_t/m_t + d` is every non-gravitational specific force difference
//! (chaser thrust, target maneuver, disturbances), supplied by the caller in the tof.
//!
//! The frame is the one of the target's *unforced* Keplerian orbit (the reference orbit):
//! a target maneuver enters only through `a`; the gravity gradient acting on the target's
//! drift away from its Keplerian orbit (μ/R³ ≈ 1.7e-8 s⁻² at the P1 start, times metres) is
//! neglected, exactly as in the paper's model.
//!
//! # True-anomaly propagation
//! [`EllipticOrbit::true_anomaly_at`] solves Kepler's equation `E − e sin E = M0 + n t` by
//! Newton iteration on the *unwrapped* mean anomaly and maps E → f with the continuous form
//! `f = E + 2 atan2(β sin E, 1 − β cos E)`, β = e/(1 + √(1 − e²)), so f(t) is continuous
//! across revolutions (no 2π jumps) and exact to round-off. Integrating ḟ(f) instead is
//! checked against it in the tests.

use nalgebra::{Matrix3, SVector, Vector3};
use serde::{Deserialize, Serialize};

use crate::orbit::constants::{MU_EARTH_M3_S2, R_EARTH_M};

/// Relative state in the target orbital frame: `[x, y, z] m` then `[ẋ, ẏ, ż] m/s`
/// (velocity taken relative to the rotating frame).
pub type RelStateTof = SVector<f64, 6>;

/// A Keplerian (unforced) target orbit, described in true anomaly.
///
/// Shape: semi-latus rectum `p` and eccentricity `e`; phase: true anomaly at t = 0;
/// orientation (only needed to go to ECI): inclination, RAAN, argument of perigee.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct EllipticOrbit {
    /// Gravitational parameter μ, m³/s².
    pub mu_m3_s2: f64,
    /// Semi-latus rectum p = a (1 − e²), m.
    pub semi_latus_rectum_m: f64,
    /// Eccentricity e, 0 ≤ e < 1 (dimensionless).
    pub eccentricity: f64,
    /// True anomaly at t = 0, rad.
    pub f0_rad: f64,
    /// Inclination i, rad.
    pub inclination_rad: f64,
    /// Right ascension of the ascending node Ω, rad.
    pub raan_rad: f64,
    /// Argument of perigee ω, rad.
    pub arg_perigee_rad: f64,
}

/// Rates of the target orbital frame at one true anomaly.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FrameRates {
    /// Target orbit radius R, m.
    pub radius_m: f64,
    /// True-anomaly rate ḟ, rad/s.
    pub f_dot_rad_s: f64,
    /// True-anomaly acceleration f̈, rad/s².
    pub f_ddot_rad_s2: f64,
}

impl EllipticOrbit {
    /// Orbit about the Earth (μ = [`MU_EARTH_M3_S2`]) from its perigee altitude above
    /// [`R_EARTH_M`] (m) and eccentricity; angles in rad.
    pub fn from_perigee_altitude(
        perigee_altitude_m: f64,
        eccentricity: f64,
        f0_rad: f64,
        inclination_rad: f64,
        raan_rad: f64,
        arg_perigee_rad: f64,
    ) -> Self {
        let r_p = R_EARTH_M + perigee_altitude_m;
        Self {
            mu_m3_s2: MU_EARTH_M3_S2,
            semi_latus_rectum_m: r_p * (1.0 + eccentricity),
            eccentricity,
            f0_rad,
            inclination_rad,
            raan_rad,
            arg_perigee_rad,
        }
    }

    /// The P1 scenario orbit of Xu & Hu (2015) §3: perigee altitude 200 km, e = 0.7,
    /// f0 = −150°, i = 30°, Ω = 60°, ω = 0.
    pub fn xu2015() -> Self {
        Self::from_perigee_altitude(
            200.0e3,
            0.7,
            (-150.0f64).to_radians(),
            30.0f64.to_radians(),
            60.0f64.to_radians(),
            0.0,
        )
    }

    /// Semi-major axis a = p/(1 − e²), m.
    pub fn semi_major_axis_m(&self) -> f64 {
        self.semi_latus_rectum_m / (1.0 - self.eccentricity * self.eccentricity)
    }

    /// Mean motion n = sqrt(μ/a³), rad/s.
    pub fn mean_motion_rad_s(&self) -> f64 {
        let a = self.semi_major_axis_m();
        (self.mu_m3_s2 / (a * a * a)).sqrt()
    }

    /// Orbital period 2π/n, s.
    pub fn period_s(&self) -> f64 {
        std::f64::consts::TAU / self.mean_motion_rad_s()
    }

    /// Orbit radius R(f) = p/(1 + e cos f), m.
    pub fn radius_m(&self, f_rad: f64) -> f64 {
        self.semi_latus_rectum_m / (1.0 + self.eccentricity * f_rad.cos())
    }

    /// True-anomaly rate ḟ = sqrt(μ p)/R², rad/s.
    pub fn f_dot_rad_s(&self, f_rad: f64) -> f64 {
        let r = self.radius_m(f_rad);
        (self.mu_m3_s2 * self.semi_latus_rectum_m).sqrt() / (r * r)
    }

    /// True-anomaly acceleration f̈ = −2 μ e sin f / R³, rad/s².
    pub fn f_ddot_rad_s2(&self, f_rad: f64) -> f64 {
        let r = self.radius_m(f_rad);
        -2.0 * self.mu_m3_s2 * self.eccentricity * f_rad.sin() / (r * r * r)
    }

    /// R, ḟ and f̈ at true anomaly `f_rad`.
    pub fn frame_rates(&self, f_rad: f64) -> FrameRates {
        FrameRates {
            radius_m: self.radius_m(f_rad),
            f_dot_rad_s: self.f_dot_rad_s(f_rad),
            f_ddot_rad_s2: self.f_ddot_rad_s2(f_rad),
        }
    }

    /// True anomaly at time `t_s` after t = 0 (where f = f0), rad, continuous (unwrapped)
    /// in t. Kepler's equation is solved by Newton iteration to round-off.
    pub fn true_anomaly_at(&self, t_s: f64) -> f64 {
        let e = self.eccentricity;
        let e0 = eccentric_from_true(self.f0_rad, e);
        let m0 = e0 - e * e0.sin();
        let m = m0 + self.mean_motion_rad_s() * t_s;
        true_from_eccentric(eccentric_from_mean(m, e), e)
    }

    /// Direction cosine matrix taking tof components to ECI components at true anomaly f
    /// (its columns are the tof axes x = θ̂, y = −ĥ, z = −r̂ written in ECI).
    pub fn dcm_eci_from_tof(&self, f_rad: f64) -> Matrix3<f64> {
        let pqw = self.dcm_eci_from_perifocal();
        let (s, c) = f_rad.sin_cos();
        let r_hat = pqw * Vector3::new(c, s, 0.0);
        let theta_hat = pqw * Vector3::new(-s, c, 0.0);
        let h_hat = pqw.column(2).into_owned();
        Matrix3::from_columns(&[theta_hat, -h_hat, -r_hat])
    }

    /// DCM taking perifocal (P toward perigee, W orbit normal) components to ECI
    /// (the 3-1-3 rotation by −Ω, −i, −ω).
    pub fn dcm_eci_from_perifocal(&self) -> Matrix3<f64> {
        crate::orbit::kepler::dcm_eci_from_perifocal(
            self.raan_rad,
            self.inclination_rad,
            self.arg_perigee_rad,
        )
    }

    /// Target position (m) and velocity (m/s) in ECI at true anomaly f.
    pub fn eci_state(&self, f_rad: f64) -> (Vector3<f64>, Vector3<f64>) {
        let pqw = self.dcm_eci_from_perifocal();
        let (s, c) = f_rad.sin_cos();
        let r = self.radius_m(f_rad);
        let vs = (self.mu_m3_s2 / self.semi_latus_rectum_m).sqrt();
        (
            pqw * Vector3::new(r * c, r * s, 0.0),
            pqw * Vector3::new(-vs * s, vs * (self.eccentricity + c), 0.0),
        )
    }
}

/// Eccentric anomaly E (rad) solving Kepler's equation `E − e sin E = M` for any (unwrapped)
/// mean anomaly M, by Newton iteration started at M + e sin M (converges for 0 ≤ e < 1
/// since the function is monotonic and convex on each half-period).
pub fn eccentric_from_mean(mean_anomaly_rad: f64, e: f64) -> f64 {
    let m = mean_anomaly_rad;
    let mut ecc = if e < 0.8 {
        m + e * m.sin()
    } else {
        // Start on the far side of the half period: Newton then converges monotonically.
        let k = (m / std::f64::consts::TAU).round();
        let m_red = m - k * std::f64::consts::TAU;
        k * std::f64::consts::TAU + std::f64::consts::PI * m_red.signum()
    };
    for _ in 0..60 {
        let g = ecc - e * ecc.sin() - m;
        let step = g / (1.0 - e * ecc.cos());
        ecc -= step;
        if step.abs() <= 1e-15 * (1.0 + ecc.abs()) {
            break;
        }
    }
    ecc
}

/// β = e/(1 + √(1 − e²)), used by the continuous anomaly conversions.
fn beta_of(e: f64) -> f64 {
    e / (1.0 + (1.0 - e * e).sqrt())
}

/// True anomaly (rad) from eccentric anomaly (rad), continuous and unwrapped:
/// f = E + 2 atan2(β sin E, 1 − β cos E).
pub fn true_from_eccentric(ecc_rad: f64, e: f64) -> f64 {
    let b = beta_of(e);
    ecc_rad + 2.0 * (b * ecc_rad.sin()).atan2(1.0 - b * ecc_rad.cos())
}

/// Eccentric anomaly (rad) from true anomaly (rad), continuous and unwrapped:
/// E = f − 2 atan2(β sin f, 1 + β cos f).
pub fn eccentric_from_true(f_rad: f64, e: f64) -> f64 {
    let b = beta_of(e);
    f_rad - 2.0 * (b * f_rad.sin()).atan2(1.0 + b * f_rad.cos())
}

/// Relative acceleration ρ̈ (m/s², tof) of Xu & Hu (2015) eqs. (6)–(8), as re-derived above:
/// full nonlinear two-body differential gravity plus the frame's Coriolis, Euler and
/// centrifugal terms at true anomaly `f_rad`, plus `accel_input_tof_m_s2`
/// (= u/m_c − F_t/m_t + d, m/s², tof). `r_c` is the chaser's distance to Earth's centre.
pub fn relative_accel(
    state_rel: &RelStateTof,
    f_rad: f64,
    orbit: &EllipticOrbit,
    accel_input_tof_m_s2: &Vector3<f64>,
) -> Vector3<f64> {
    let (x, y, z) = (state_rel[0], state_rel[1], state_rel[2]);
    let (vx, vz) = (state_rel[3], state_rel[5]);
    let FrameRates {
        radius_m: r,
        f_dot_rad_s: fd,
        f_ddot_rad_s2: fdd,
    } = orbit.frame_rates(f_rad);
    let mu = orbit.mu_m3_s2;
    let rc = (x * x + y * y + (r - z) * (r - z)).sqrt();
    let k = mu / (rc * rc * rc);
    Vector3::new(
        2.0 * fd * vz + fdd * z + fd * fd * x - k * x,
        -k * y,
        -2.0 * fd * vx - fdd * x + fd * fd * z + k * (r - z) - mu / (r * r),
    ) + accel_input_tof_m_s2
}

/// Time derivative of the relative state, `[ρ̇; ρ̈]` (tof), see [`relative_accel`].
pub fn relative_state_derivative(
    state_rel: &RelStateTof,
    f_rad: f64,
    orbit: &EllipticOrbit,
    accel_input_tof_m_s2: &Vector3<f64>,
) -> RelStateTof {
    let acc = relative_accel(state_rel, f_rad, orbit, accel_input_tof_m_s2);
    RelStateTof::new(
        state_rel[3],
        state_rel[4],
        state_rel[5],
        acc.x,
        acc.y,
        acc.z,
    )
}

/// One classical Runge–Kutta 4 step of the relative dynamics from `t_s` to `t_s + dt_s`.
/// The true anomaly at each stage comes from Kepler's equation
/// ([`EllipticOrbit::true_anomaly_at`]); `accel_input(t_s)` gives the input specific force
/// (m/s², tof) at a stage time, so a zero-order-held thrust plus a time-varying target
/// maneuver are both handled.
pub fn rk4_step_relative(
    state_rel: &RelStateTof,
    t_s: f64,
    dt_s: f64,
    orbit: &EllipticOrbit,
    accel_input: impl Fn(f64) -> Vector3<f64>,
) -> RelStateTof {
    let deriv = |s: &RelStateTof, t: f64| {
        relative_state_derivative(s, orbit.true_anomaly_at(t), orbit, &accel_input(t))
    };
    let h = dt_s;
    let k1 = deriv(state_rel, t_s);
    let k2 = deriv(&(state_rel + k1 * (0.5 * h)), t_s + 0.5 * h);
    let k3 = deriv(&(state_rel + k2 * (0.5 * h)), t_s + 0.5 * h);
    let k4 = deriv(&(state_rel + k3 * h), t_s + h);
    state_rel + (k1 + k2 * 2.0 + k3 * 2.0 + k4) * (h / 6.0)
}

#[cfg(test)]
mod tests {
    //! References: an independent ECI two-body integration (frame built from r × v inside
    //! the test), the Clohessy–Wiltshire closed form, and Keplerian identities.
    use super::*;

    /// Independent ECI two-body dynamics of [r_t, v_t, r_c, v_c] with a chaser specific
    /// force given in the tof; the tof is rebuilt from (r_t, v_t) at every stage.
    fn eci_deriv(s: &SVector<f64, 12>, mu: f64, a_tof: &Vector3<f64>) -> SVector<f64, 12> {
        let rt = Vector3::new(s[0], s[1], s[2]);
        let vt = Vector3::new(s[3], s[4], s[5]);
        let rc = Vector3::new(s[6], s[7], s[8]);
        let vc = Vector3::new(s[9], s[10], s[11]);
        let c = frame_from_rv(&rt, &vt);
        let at = -mu * rt / rt.norm().powi(3);
        let ac = -mu * rc / rc.norm().powi(3) + c * a_tof;
        let mut d = SVector::<f64, 12>::zeros();
        d.fixed_rows_mut::<3>(0).copy_from(&vt);
        d.fixed_rows_mut::<3>(3).copy_from(&at);
        d.fixed_rows_mut::<3>(6).copy_from(&vc);
        d.fixed_rows_mut::<3>(9).copy_from(&ac);
        d
    }

    /// The test's own tof construction: z = −r̂, y = −ĥ, x = y × z (columns, in ECI).
    fn frame_from_rv(r: &Vector3<f64>, v: &Vector3<f64>) -> Matrix3<f64> {
        let z = -r.normalize();
        let y = -r.cross(v).normalize();
        let x = y.cross(&z);
        Matrix3::from_columns(&[x, y, z])
    }

    /// Relative (tof) state from the ECI states: ρ = Cᵀ(r_c − r_t),
    /// ρ̇ = Cᵀ(v_c − v_t) − ω×ρ with ω = ĥ |r × v|/r² (ECI).
    fn rel_from_eci(s: &SVector<f64, 12>) -> RelStateTof {
        let rt = Vector3::new(s[0], s[1], s[2]);
        let vt = Vector3::new(s[3], s[4], s[5]);
        let dr = Vector3::new(s[6] - s[0], s[7] - s[1], s[8] - s[2]);
        let dv = Vector3::new(s[9] - s[3], s[10] - s[4], s[11] - s[5]);
        let c = frame_from_rv(&rt, &vt);
        let w_eci = rt.cross(&vt) / rt.norm_squared();
        let rho = c.transpose() * dr;
        let rho_dot = c.transpose() * (dv - w_eci.cross(&dr));
        RelStateTof::new(rho.x, rho.y, rho.z, rho_dot.x, rho_dot.y, rho_dot.z)
    }

    fn run_eci(
        orbit: &EllipticOrbit,
        x0: &RelStateTof,
        a_tof: &Vector3<f64>,
        dt: f64,
        n: usize,
    ) -> RelStateTof {
        let mu = orbit.mu_m3_s2;
        let (rt, vt) = orbit.eci_state(orbit.f0_rad);
        let c = frame_from_rv(&rt, &vt);
        let w_eci = rt.cross(&vt) / rt.norm_squared();
        let rho = Vector3::new(x0[0], x0[1], x0[2]);
        let rho_dot = Vector3::new(x0[3], x0[4], x0[5]);
        let dr = c * rho;
        let rc = rt + dr;
        let vc = vt + c * rho_dot + w_eci.cross(&dr);
        let mut s = SVector::<f64, 12>::from_iterator(
            rt.iter()
                .chain(vt.iter())
                .chain(rc.iter())
                .chain(vc.iter())
                .copied(),
        );
        for _ in 0..n {
            let k1 = eci_deriv(&s, mu, a_tof);
            let k2 = eci_deriv(&(s + k1 * (0.5 * dt)), mu, a_tof);
            let k3 = eci_deriv(&(s + k2 * (0.5 * dt)), mu, a_tof);
            let k4 = eci_deriv(&(s + k3 * dt), mu, a_tof);
            s += (k1 + k2 * 2.0 + k3 * 2.0 + k4) * (dt / 6.0);
        }
        rel_from_eci(&s)
    }

    fn run_rel(
        orbit: &EllipticOrbit,
        x0: &RelStateTof,
        a_tof: &Vector3<f64>,
        dt: f64,
        n: usize,
    ) -> RelStateTof {
        let mut s = *x0;
        for k in 0..n {
            s = rk4_step_relative(&s, k as f64 * dt, dt, orbit, |_| *a_tof);
        }
        s
    }

    /// The relative dynamics agree with an inertial two-body integration of target and
    /// chaser over 300 s from the P1 initial state (with an initial drift velocity and a
    /// constant tof thrust acceleration, so every term is exercised). Tolerance: the
    /// step-halving estimate of each integration's truncation error plus the ECI round-off
    /// floor (ulp of R ≈ 2.8e7 m is 3.7e-9 m, random-walking over the steps and amplified by
    /// differencing two ECI positions), times a safety factor 10.
    #[test]
    fn val_xu2015_relative_dynamics_vs_inertial_two_body() {
        let orbit = EllipticOrbit::xu2015();
        let x0 = RelStateTof::new(-20.0, 0.0, 5.0, 0.05, -0.02, 0.03);
        let a = Vector3::new(2.0e-3, -1.0e-3, 1.5e-3);
        let (dt, n) = (1.0, 300);
        let eci = run_eci(&orbit, &x0, &a, dt, n);
        let eci_half = run_eci(&orbit, &x0, &a, dt / 2.0, 2 * n);
        let rel = run_rel(&orbit, &x0, &a, dt, n);
        let rel_half = run_rel(&orbit, &x0, &a, dt / 2.0, 2 * n);
        let trunc =
            (eci - eci_half).fixed_rows::<3>(0).norm() + (rel - rel_half).fixed_rows::<3>(0).norm();
        let r = orbit.radius_m(orbit.f0_rad);
        let ulp = r * f64::EPSILON;
        // One ulp per step random-walking in each of the two differenced ECI positions.
        let roundoff = std::f64::consts::SQRT_2 * ulp * ((2 * n) as f64).sqrt();
        let tol_pos = 10.0 * (trunc + roundoff);
        let err_pos = (eci_half - rel_half).fixed_rows::<3>(0).norm();
        let err_vel = (eci_half - rel_half).fixed_rows::<3>(3).norm();
        // Sanity: the motion is not trivial (moved tens of metres).
        assert!((rel - x0).fixed_rows::<3>(0).norm() > 50.0);
        assert!(err_pos < tol_pos, "pos err {err_pos} m, tol {tol_pos} m");
        // Velocity: the same budget divided by the elapsed time scale of one step.
        assert!(err_vel < tol_pos / dt, "vel err {err_vel} m/s");
        assert!(
            tol_pos < 1e-5,
            "tolerance budget unexpectedly loose: {tol_pos} m"
        );
    }

    /// For e = 0 and small separations the model reduces to Clohessy–Wiltshire in this
    /// frame (x along-track, z radial inward): ẍ = 2nż, ÿ = −n²y, z̈ = −2nẋ + 3n²z.
    /// The remainder is the second-order gravity term, bounded by 3μ|ρ|²/R⁴·(3/2)·… — we
    /// assert ≤ 6 μ|ρ|²/R⁴ and that it scales as |ρ|² (ratio 4 on doubling).
    #[test]
    fn val_xu2015_reduces_to_cw() {
        let orbit = EllipticOrbit::from_perigee_altitude(500e3, 0.0, 0.3, 0.5, 1.0, 0.0);
        let r = orbit.radius_m(0.0);
        let n = orbit.mean_motion_rad_s();
        assert!((orbit.f_dot_rad_s(1.234) - n).abs() < 1e-15);
        let cw = |s: &RelStateTof| {
            Vector3::new(
                2.0 * n * s[5],
                -n * n * s[1],
                -2.0 * n * s[3] + 3.0 * n * n * s[2],
            )
        };
        let mu = orbit.mu_m3_s2;
        let mut resid = Vec::new();
        for scale in [10.0, 20.0] {
            let s = RelStateTof::new(0.7 * scale, -0.4 * scale, 0.6 * scale, 0.1, 0.2, -0.3);
            let a = relative_accel(&s, 0.3, &orbit, &Vector3::zeros());
            let d = (a - cw(&s)).norm();
            let rho2 = s.fixed_rows::<3>(0).norm_squared();
            assert!(d <= 6.0 * mu * rho2 / r.powi(4), "remainder {d}");
            resid.push(d);
        }
        let ratio = resid[1] / resid[0];
        assert!(
            (ratio - 4.0).abs() < 0.01,
            "second-order scaling ratio {ratio}"
        );

        // Trajectory: CW closed form (in-plane x,z; out-of-plane y) over 1000 s.
        let x0 = RelStateTof::new(10.0, -5.0, 3.0, 0.01, 0.005, -0.008);
        let t = 1000.0;
        let (s, c) = (n * t).sin_cos();
        let (xx, y0, z0, vx, vy, vz) = (x0[0], x0[1], x0[2], x0[3], x0[4], x0[5]);
        // Fehse's CW solution with x along-track and z radial (toward Earth).
        let x_cw = (4.0 * vx / n - 6.0 * z0) * s - 2.0 * vz / n * c
            + (6.0 * n * z0 - 3.0 * vx) * t
            + (xx + 2.0 * vz / n);
        let z_cw = (2.0 * vx / n - 3.0 * z0) * c + vz / n * s + (4.0 * z0 - 2.0 * vx / n);
        let y_cw = y0 * c + vy / n * s;
        let mut st = x0;
        let dt = 1.0;
        let mut rho_max: f64 = 0.0;
        for k in 0..1000 {
            st = rk4_step_relative(&st, k as f64 * dt, dt, &orbit, |_| Vector3::zeros());
            rho_max = rho_max.max(st.fixed_rows::<3>(0).norm());
        }
        // Nonlinear remainder ≤ 6μ|ρ|²/R⁴ along the path, integrated twice (½ a t²); the CW
        // response to a constant acceleration over n t ≈ 1.1 rad is within 4× of ½ a t².
        let tol = 4.0 * 0.5 * 6.0 * mu * rho_max.powi(2) / r.powi(4) * t * t;
        let err = (st.fixed_rows::<3>(0) - Vector3::new(x_cw, y_cw, z_cw)).norm();
        assert!(err < tol, "CW mismatch {err} m, tol {tol} m");
    }

    /// Kepler solution vs. integrating ḟ(f) with RK4 over one period of the P1 orbit, and
    /// f̈ vs. a central finite difference of ḟ(f(t)).
    #[test]
    fn invariant_true_anomaly_propagation() {
        let orbit = EllipticOrbit::xu2015();
        let period = orbit.period_s();
        let dt = 1.0;
        let n = (period / dt).ceil() as usize;
        let mut f = orbit.f0_rad;
        let mut max_err: f64 = 0.0;
        for k in 0..n {
            let g = |f: f64| orbit.f_dot_rad_s(f);
            let k1 = g(f);
            let k2 = g(f + 0.5 * dt * k1);
            let k3 = g(f + 0.5 * dt * k2);
            let k4 = g(f + dt * k3);
            f += dt / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4);
            max_err = max_err.max((f - orbit.true_anomaly_at((k + 1) as f64 * dt)).abs());
        }
        // RK4 at 1 s across a perigee pass (ḟ up to 1.6e-3 rad/s) is accurate to ~1e-9 rad.
        assert!(max_err < 1e-8, "Kepler vs ḟ-integration: {max_err} rad");
        // After one period f advanced by exactly 2π.
        let f_p = orbit.true_anomaly_at(period);
        assert!((f_p - orbit.f0_rad - std::f64::consts::TAU).abs() < 1e-10);
        // f̈ against a central difference of ḟ along the Kepler solution.
        for t in [0.0, 5000.0, 15000.0, 16000.0] {
            let h = 1e-1;
            let fd = |t: f64| orbit.f_dot_rad_s(orbit.true_anomaly_at(t));
            let fdd_num = (fd(t + h) - fd(t - h)) / (2.0 * h);
            let fdd = orbit.f_ddot_rad_s2(orbit.true_anomaly_at(t));
            assert!(
                (fdd_num - fdd).abs() < 1e-6 * fdd.abs().max(1e-12),
                "t={t}: {fdd_num} vs {fdd}"
            );
        }
    }

    /// ECI state and tof DCM: |r| = R(f), |r × v| = sqrt(μ p), energy −μ/(2a), the DCM is
    /// orthonormal right-handed and equals the r × v construction.
    #[test]
    fn invariant_eci_state_and_frame() {
        let orbit = EllipticOrbit::xu2015();
        for f in [-2.6, 0.0, 1.0, 3.0] {
            let (r, v) = orbit.eci_state(f);
            let mu = orbit.mu_m3_s2;
            assert!((r.norm() - orbit.radius_m(f)).abs() < 1e-6);
            let h = r.cross(&v).norm();
            assert!((h - (mu * orbit.semi_latus_rectum_m).sqrt()).abs() < 1e-12 * h);
            let energy = 0.5 * v.norm_squared() - mu / r.norm();
            assert!((energy + mu / (2.0 * orbit.semi_major_axis_m())).abs() < 1e-9 * energy.abs());
            let c = orbit.dcm_eci_from_tof(f);
            assert!((c.transpose() * c - Matrix3::identity()).norm() < 1e-14);
            assert!((c.determinant() - 1.0).abs() < 1e-14);
            assert!((c - frame_from_rv(&r, &v)).norm() < 1e-14);
            // ḟ = |r × v|/r².
            assert!((orbit.f_dot_rad_s(f) - h / r.norm_squared()).abs() < 1e-15);
        }
    }
}
