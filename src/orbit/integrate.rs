//! Fixed-step explicit Runge–Kutta integrators over `SVector<f64, N>` states (classic RK4 and
//! the 8th-order Dormand–Prince DOP853 method used at a fixed step), and the
//! [`ReferenceOrbit`]: the f64 inertial orbit (two-body + optional J2) that the world frame of
//! an orbit scene rides on.
//!
//! DOP853: Hairer, Nørsett & Wanner, *Solving Ordinary Differential Equations I* (2nd ed.),
//! §II.10, code `dop853.f`; 12 stages, 8th-order solution (the embedded 5th/3rd-order error
//! estimators and the dense output are not needed at a fixed step and are omitted).
//! Coefficients are the published `dop853.f` values (30 significant digits, rounded to f64 by
//! the compiler). Their consistency (row sums = nodes, Σb = 1) and the 8th order itself are
//! checked in the tests (`invariant_rk_order_by_step_halving`).

use nalgebra::{SVector, Vector3, Vector6};
use serde::{Deserialize, Serialize};

use crate::orbit::constants::MU_EARTH_M3_S2;
use crate::orbit::gravity::{GravityTerm, accel_earth, differential_accel, earth_gravity};
use crate::orbit::kepler::ClassicalElements;

/// One classic 4th-order Runge–Kutta step of x' = f(t, x) from (`t_s`, `x`) over `h_s`.
pub fn rk4_step<const N: usize>(
    f: &mut impl FnMut(f64, &SVector<f64, N>) -> SVector<f64, N>,
    t_s: f64,
    x: &SVector<f64, N>,
    h_s: f64,
) -> SVector<f64, N> {
    let k1 = f(t_s, x);
    let k2 = f(t_s + 0.5 * h_s, &(x + 0.5 * h_s * k1));
    let k3 = f(t_s + 0.5 * h_s, &(x + 0.5 * h_s * k2));
    let k4 = f(t_s + h_s, &(x + h_s * k3));
    x + (h_s / 6.0) * (k1 + 2.0 * k2 + 2.0 * k3 + k4)
}

/// Number of stages of the DOP853 8th-order solution.
const S8: usize = 12;

/// DOP853 nodes c_i (c_1 = 0, c_12 = 1).
#[allow(clippy::excessive_precision)]
const C8: [f64; S8] = [
    0.0,
    0.526001519587677318785587544488e-01,
    0.789002279381515978178381316732e-01,
    0.118350341907227396726757197510e+00,
    0.281649658092772603273242802490e+00,
    0.333333333333333333333333333333e+00,
    0.25e+00,
    0.307692307692307692307692307692e+00,
    0.651282051282051282051282051282e+00,
    0.6e+00,
    0.857142857142857142857142857142e+00,
    1.0,
];

/// DOP853 coupling coefficients a_ij (row i = stage, j < i).
#[allow(clippy::excessive_precision)]
const A8: [[f64; S8]; S8] = {
    let mut a = [[0.0; S8]; S8];
    a[1][0] = 5.26001519587677318785587544488e-2;

    a[2][0] = 1.97250569845378994544595329183e-2;
    a[2][1] = 5.91751709536136983633785987549e-2;

    a[3][0] = 2.95875854768068491816892993775e-2;
    a[3][2] = 8.87627564304205475450678981324e-2;

    a[4][0] = 2.41365134159266685502369798665e-1;
    a[4][2] = -8.84549479328286085344864962717e-1;
    a[4][3] = 9.24834003261792003115737966543e-1;

    a[5][0] = 3.7037037037037037037037037037e-2;
    a[5][3] = 1.70828608729473871279604482173e-1;
    a[5][4] = 1.25467687566822425016691814123e-1;

    a[6][0] = 3.7109375e-2;
    a[6][3] = 1.70252211019544039314978060272e-1;
    a[6][4] = 6.02165389804559606850219397283e-2;
    a[6][5] = -1.7578125e-2;

    a[7][0] = 3.70920001185047927108779319836e-2;
    a[7][3] = 1.70383925712239993810214054705e-1;
    a[7][4] = 1.07262030446373284651809199168e-1;
    a[7][5] = -1.53194377486244017527936158236e-2;
    a[7][6] = 8.27378916381402288758473766002e-3;

    a[8][0] = 6.24110958716075717114429577812e-1;
    a[8][3] = -3.36089262944694129406857109825e0;
    a[8][4] = -8.68219346841726006818189891453e-1;
    a[8][5] = 2.75920996994467083049415600797e1;
    a[8][6] = 2.01540675504778934086186788979e1;
    a[8][7] = -4.34898841810699588477366255144e1;

    a[9][0] = 4.77662536438264365890433908527e-1;
    a[9][3] = -2.48811461997166764192642586468e0;
    a[9][4] = -5.90290826836842996371446475743e-1;
    a[9][5] = 2.12300514481811942347288949897e1;
    a[9][6] = 1.52792336328824235832596922938e1;
    a[9][7] = -3.32882109689848629194453265587e1;
    a[9][8] = -2.03312017085086261358222928593e-2;

    a[10][0] = -9.3714243008598732571704021658e-1;
    a[10][3] = 5.18637242884406370830023853209e0;
    a[10][4] = 1.09143734899672957818500254654e0;
    a[10][5] = -8.14978701074692612513997267357e0;
    a[10][6] = -1.85200656599969598641566180701e1;
    a[10][7] = 2.27394870993505042818970056734e1;
    a[10][8] = 2.49360555267965238987089396762e0;
    a[10][9] = -3.0467644718982195003823669022e0;

    a[11][0] = 2.27331014751653820792359768449e0;
    a[11][3] = -1.05344954667372501984066689879e1;
    a[11][4] = -2.00087205822486249909675718444e0;
    a[11][5] = -1.79589318631187989172765950534e1;
    a[11][6] = 2.79488845294199600508499808837e1;
    a[11][7] = -2.85899827713502369474065508674e0;
    a[11][8] = -8.87285693353062954433549289258e0;
    a[11][9] = 1.23605671757943030647266201528e1;
    a[11][10] = 6.43392746015763530355970484046e-1;
    a
};

/// DOP853 weights b_i of the 8th-order solution.
#[allow(clippy::excessive_precision)]
const B8: [f64; S8] = [
    5.42937341165687622380535766363e-2,
    0.0,
    0.0,
    0.0,
    0.0,
    4.45031289275240888144113950566e0,
    1.89151789931450038304281599044e0,
    -5.8012039600105847814672114227e0,
    3.1116436695781989440891606237e-1,
    -1.52160949662516078556178806805e-1,
    2.01365400804030348374776537501e-1,
    4.47106157277725905176885569043e-2,
];

/// One 8th-order Runge–Kutta step (DOP853 tableau at a fixed step, 12 evaluations of `f`)
/// of x' = f(t, x) from (`t_s`, `x`) over `h_s`. Local error O(h⁹), global O(h⁸).
pub fn rk8_step<const N: usize>(
    f: &mut impl FnMut(f64, &SVector<f64, N>) -> SVector<f64, N>,
    t_s: f64,
    x: &SVector<f64, N>,
    h_s: f64,
) -> SVector<f64, N> {
    let mut k = [SVector::<f64, N>::zeros(); S8];
    for i in 0..S8 {
        let mut xi = *x;
        for j in 0..i {
            if A8[i][j] != 0.0 {
                xi += (h_s * A8[i][j]) * k[j];
            }
        }
        k[i] = f(t_s + C8[i] * h_s, &xi);
    }
    let mut incr = SVector::<f64, N>::zeros();
    for i in 0..S8 {
        if B8[i] != 0.0 {
            incr += B8[i] * k[i];
        }
    }
    x + h_s * incr
}

/// Fixed-step method selector for [`propagate_fixed`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum RkMethod {
    /// Classic 4th-order Runge–Kutta ([`rk4_step`]).
    Rk4,
    /// 8th-order DOP853 tableau at a fixed step ([`rk8_step`]).
    Rk8,
}

/// Integrate x' = f(t, x) from (`t0_s`, `x0`) over `duration_s` in `n_steps` equal steps of
/// `method`; returns x(t0 + duration). The time of step k is t0 + k·h (no accumulated sum).
pub fn propagate_fixed<const N: usize>(
    method: RkMethod,
    f: &mut impl FnMut(f64, &SVector<f64, N>) -> SVector<f64, N>,
    t0_s: f64,
    x0: &SVector<f64, N>,
    duration_s: f64,
    n_steps: usize,
) -> SVector<f64, N> {
    let n = n_steps.max(1);
    let h = duration_s / n as f64;
    let mut x = *x0;
    for k in 0..n {
        let t = t0_s + k as f64 * h;
        x = match method {
            RkMethod::Rk4 => rk4_step(f, t, &x, h),
            RkMethod::Rk8 => rk8_step(f, t, &x, h),
        };
    }
    x
}

/// Time derivative of the inertial state [r; v] (ECI, m and m/s) under Earth gravity
/// (the terms of `gravity`, in order): [v; a(r)].
pub fn orbit_rhs(x: &Vector6<f64>, gravity: &[GravityTerm]) -> Vector6<f64> {
    let r = Vector3::new(x[0], x[1], x[2]);
    let a = accel_earth(&r, gravity);
    Vector6::new(x[3], x[4], x[5], a.x, a.y, a.z)
}

/// Sub-step rule of [`ReferenceOrbit::step`]: the largest sub-step advances the true anomaly by
/// at most this angle at perigee, rad (1°). With the 8th-order method this keeps the
/// truncation error below f64 rounding (tests: energy drift < 1e-13 relative per orbit at
/// e = 0.7; a circular LEO orbit takes 360 sub-steps per revolution, 15.8 s each).
pub const MAX_SUBSTEP_ANOMALY_RAD: f64 = std::f64::consts::PI / 180.0;

/// The reference orbit of an orbit scene: time and f64 inertial state (ECI position and
/// velocity of the origin of the world frame), propagated under a gravity model (a list of
/// [`GravityTerm`]s: two-body, optionally J2) with the 8th-order method. The world frame is non-rotating with ECI axes, its
/// origin at [`ReferenceOrbit::pos_eci_m`]; a body at world position ρ feels
/// [`ReferenceOrbit::differential_accel`]`(ρ)` (the world frame's own acceleration removed).
#[derive(Debug, Clone, PartialEq)]
pub struct ReferenceOrbit {
    t_s: f64,
    pos_eci_m: Vector3<f64>,
    vel_eci_m_s: Vector3<f64>,
    gravity: Vec<GravityTerm>,
    max_substep_s: f64,
}

impl ReferenceOrbit {
    /// Reference orbit starting at t = 0 from an inertial state (ECI, m and m/s).
    /// The maximum sub-step is fixed here from the initial osculating orbit:
    /// h_max = [`MAX_SUBSTEP_ANOMALY_RAD`] / ḟ_peri, with ḟ_peri = √(μ(1+e)/r_p³) the true-anomaly
    /// rate at perigee (r_p = a(1 − e)). Panics (debug) if the orbit is not elliptic.
    pub fn from_state(
        pos_eci_m: Vector3<f64>,
        vel_eci_m_s: Vector3<f64>,
        gravity: &[GravityTerm],
    ) -> Self {
        let el = ClassicalElements::from_state(&pos_eci_m, &vel_eci_m_s, MU_EARTH_M3_S2);
        let rp = el.a_m * (1.0 - el.e);
        let fdot_peri = (MU_EARTH_M3_S2 * (1.0 + el.e) / (rp * rp * rp)).sqrt();
        ReferenceOrbit {
            t_s: 0.0,
            pos_eci_m,
            vel_eci_m_s,
            gravity: gravity.to_vec(),
            max_substep_s: MAX_SUBSTEP_ANOMALY_RAD / fdot_peri,
        }
    }

    /// Reference orbit starting at t = 0 from classical elements (μ = Earth's).
    pub fn from_elements(elements: &ClassicalElements, gravity: &[GravityTerm]) -> Self {
        let (r, v) = elements.to_state(MU_EARTH_M3_S2);
        Self::from_state(r, v, gravity)
    }

    /// Advance by `dt_s` (> 0 or < 0) with the 8th-order method, in n = ⌈|dt|/h_max⌉ equal
    /// sub-steps (a single step for a simulation's fixed dt ≲ h_max ≈ 16 s in LEO).
    pub fn step(&mut self, dt_s: f64) {
        if dt_s == 0.0 {
            return;
        }
        let n = (dt_s.abs() / self.max_substep_s).ceil().max(1.0) as usize;
        let h = dt_s / n as f64;
        let gravity = &self.gravity;
        let mut f = |_t: f64, x: &Vector6<f64>| orbit_rhs(x, gravity);
        let mut x = self.state_vector();
        for k in 0..n {
            x = rk8_step(&mut f, self.t_s + k as f64 * h, &x, h);
        }
        self.pos_eci_m = Vector3::new(x[0], x[1], x[2]);
        self.vel_eci_m_s = Vector3::new(x[3], x[4], x[5]);
        self.t_s += dt_s;
    }

    /// (position m, velocity m/s), ECI, at [`ReferenceOrbit::t_s`].
    pub fn state(&self) -> (Vector3<f64>, Vector3<f64>) {
        (self.pos_eci_m, self.vel_eci_m_s)
    }

    /// State as a 6-vector [r; v] (ECI, m, m/s).
    pub fn state_vector(&self) -> Vector6<f64> {
        let (r, v) = (self.pos_eci_m, self.vel_eci_m_s);
        Vector6::new(r.x, r.y, r.z, v.x, v.y, v.z)
    }

    /// Time since the start, s.
    pub fn t_s(&self) -> f64 {
        self.t_s
    }

    /// Position of the reference (the world origin), ECI, m.
    pub fn pos_eci_m(&self) -> Vector3<f64> {
        self.pos_eci_m
    }

    /// Velocity of the reference, ECI, m/s.
    pub fn vel_eci_m_s(&self) -> Vector3<f64> {
        self.vel_eci_m_s
    }

    /// The gravity model's terms (of the orbit and of [`ReferenceOrbit::differential_accel`]).
    pub fn gravity(&self) -> &[GravityTerm] {
        &self.gravity
    }

    /// Largest sub-step used by [`ReferenceOrbit::step`], s.
    pub fn max_substep_s(&self) -> f64 {
        self.max_substep_s
    }

    /// Gravitational acceleration of the reference itself, ECI, m/s².
    pub fn accel_eci_m_s2(&self) -> Vector3<f64> {
        accel_earth(&self.pos_eci_m, &self.gravity)
    }

    /// Differential gravity on a body at `pos_world_m` (world = ECI axes, origin at the
    /// reference), m/s²: a(r_ref + ρ) − a(r_ref), same force model as the reference orbit.
    /// Multiply by the body's mass for the external force, N.
    pub fn differential_accel(&self, pos_world_m: &Vector3<f64>) -> Vector3<f64> {
        differential_accel(&self.pos_eci_m, pos_world_m, &self.gravity)
    }

    /// Osculating classical elements of the current state (μ = Earth's).
    pub fn elements(&self) -> ClassicalElements {
        ClassicalElements::from_state(&self.pos_eci_m, &self.vel_eci_m_s, MU_EARTH_M3_S2)
    }
}

/// Serialisable initial condition of a reference orbit.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub enum OrbitInit {
    /// Classical elements (μ = Earth's).
    Elements(ClassicalElements),
    /// Inertial state, ECI.
    State {
        /// Position, ECI, m.
        pos_eci_m: [f64; 3],
        /// Velocity, ECI, m/s.
        vel_eci_m_s: [f64; 3],
    },
}

/// Serialisable parameters of a [`ReferenceOrbit`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ReferenceOrbitParams {
    /// Initial condition at t = 0.
    pub init: OrbitInit,
    /// Include Earth's J2 (orbit and differential gravity): the model [`earth_gravity`] selects.
    pub with_j2: bool,
}

impl ReferenceOrbitParams {
    /// Build the reference orbit at t = 0.
    pub fn build(&self) -> ReferenceOrbit {
        match &self.init {
            OrbitInit::Elements(el) => {
                ReferenceOrbit::from_elements(el, earth_gravity(self.with_j2))
            }
            OrbitInit::State {
                pos_eci_m,
                vel_eci_m_s,
            } => ReferenceOrbit::from_state(
                Vector3::from(*pos_eci_m),
                Vector3::from(*vel_eci_m_s),
                earth_gravity(self.with_j2),
            ),
        }
    }
}

#[cfg(test)]
mod tests {
    //! References: quadrature order conditions of the DOP853 weights; the empirical order of
    //! convergence against the closed-form Kepler solution (`kepler_propagate`); conservation
    //! of energy (two-body and two-body + J2 potential) and angular momentum (all components
    //! for two-body, the polar component for J2, which is axially symmetric); the secular J2
    //! nodal regression rate dΩ/dt = −(3/2) n J2 (R_E/p)² cos i (Vallado eq. 9-41).
    use super::*;
    use crate::orbit::constants::{J2_EARTH, R_EARTH_M};
    use crate::orbit::gravity::{TWO_BODY, TWO_BODY_J2, potential_energy_per_mass};
    use crate::orbit::kepler::{kepler_propagate, mean_motion, wrap_pi};
    use std::f64::consts::{PI, TAU};

    const D: f64 = PI / 180.0;

    fn leo_circular() -> ClassicalElements {
        ClassicalElements {
            a_m: 6_778_137.0,
            e: 0.0,
            i_rad: 51.6 * D,
            raan_rad: 30.0 * D,
            argp_rad: 0.0,
            true_anomaly_rad: 10.0 * D,
        }
    }
    /// Guo et al. (2016) target orbit (a = 7178 km, e = 0.01).
    fn p0_orbit() -> ClassicalElements {
        ClassicalElements {
            a_m: 7_178_000.0,
            e: 0.01,
            i_rad: 45.0 * D,
            raan_rad: 10.0 * D,
            argp_rad: 20.0 * D,
            true_anomaly_rad: 0.0,
        }
    }
    /// Xu & Hu (2015) target orbit (perigee altitude 200 km, e = 0.7, i 30°, Ω 60°, f0 −150°).
    fn p1_orbit() -> ClassicalElements {
        ClassicalElements {
            a_m: (R_EARTH_M + 200e3) / 0.3,
            e: 0.7,
            i_rad: 30.0 * D,
            raan_rad: 60.0 * D,
            argp_rad: 0.0,
            true_anomaly_rad: -150.0 * D,
        }
    }

    fn energy(x: &Vector6<f64>, gravity: &[GravityTerm]) -> f64 {
        let r = Vector3::new(x[0], x[1], x[2]);
        let v = Vector3::new(x[3], x[4], x[5]);
        0.5 * v.norm_squared() + potential_energy_per_mass(&r, gravity)
    }
    fn ang_mom(x: &Vector6<f64>) -> Vector3<f64> {
        Vector3::new(x[0], x[1], x[2]).cross(&Vector3::new(x[3], x[4], x[5]))
    }

    /// Tableau consistency: Σ_j a_ij = c_i, and the quadrature conditions Σ b_i c_i^k = 1/(k+1)
    /// for k = 0..7 (necessary for order 8), to 1e-14 (30-digit constants rounded to f64).
    #[test]
    fn invariant_dop853_tableau_consistency() {
        for i in 0..S8 {
            let s: f64 = A8[i].iter().sum();
            let scale: f64 = A8[i].iter().map(|a| a.abs()).sum::<f64>().max(1.0);
            assert!(
                (s - C8[i]).abs() < 4.0 * f64::EPSILON * scale,
                "row {i}: {s} vs {}",
                C8[i]
            );
        }
        for k in 0..8 {
            let q: f64 = (0..S8).map(|i| B8[i] * C8[i].powi(k)).sum();
            assert!((q - 1.0 / f64::from(k + 1)).abs() < 1e-14, "k {k}: {q}");
        }
    }

    /// Empirical order: integrate one revolution of a Kepler orbit (μ = 1, a = 1, e = 0.1) with
    /// N, 2N, 4N steps; the error against `kepler_propagate` falls by 2^p with p ≈ 8 for RK8
    /// and p ≈ 4 for RK4 (step sizes chosen so errors stay ≫ rounding, ~1e-15).
    #[test]
    fn invariant_rk_order_by_step_halving() {
        let mu = 1.0;
        let r0 = Vector3::new(0.9, 0.0, 0.0); // perigee of a = 1, e = 0.1
        let v0 = Vector3::new(0.0, (mu * 1.1 / 0.9_f64).sqrt(), 0.0);
        let x0 = Vector6::new(r0.x, r0.y, r0.z, v0.x, v0.y, v0.z);
        let t_end = TAU;
        let (rt, vt) = kepler_propagate(&r0, &v0, t_end, mu);
        let mut f = |_t: f64, x: &Vector6<f64>| {
            let r = Vector3::new(x[0], x[1], x[2]);
            let a = -mu / r.norm().powi(3) * r;
            Vector6::new(x[3], x[4], x[5], a.x, a.y, a.z)
        };
        let mut err = |m: RkMethod, n: usize| {
            let x = propagate_fixed(m, &mut f, 0.0, &x0, t_end, n);
            (Vector3::new(x[0], x[1], x[2]) - rt).norm()
                + (Vector3::new(x[3], x[4], x[5]) - vt).norm()
        };
        let e8: Vec<f64> = [20, 40, 80]
            .iter()
            .map(|&n| err(RkMethod::Rk8, n))
            .collect();
        let e4: Vec<f64> = [400, 800, 1600]
            .iter()
            .map(|&n| err(RkMethod::Rk4, n))
            .collect();
        let p8 = [(e8[0] / e8[1]).log2(), (e8[1] / e8[2]).log2()];
        let p4 = [(e4[0] / e4[1]).log2(), (e4[1] / e4[2]).log2()];
        eprintln!("RK8 errors {e8:?} orders {p8:?}; RK4 errors {e4:?} orders {p4:?}");
        // Rounding over 80 steps is ~1e-14 here: the finest error must stay well above it.
        assert!(
            e8[2] > 1e-13,
            "errors must stay above rounding for the order to be measurable"
        );
        // The observed order approaches 8 from below as h → 0 (measured 7.74, 7.88).
        for p in p8 {
            assert!((7.5..8.5).contains(&p), "RK8 observed order {p}");
        }
        for p in p4 {
            assert!((3.8..4.3).contains(&p), "RK4 observed order {p}");
        }
    }

    /// ReferenceOrbit (RK8, 1° sub-steps) vs closed-form Kepler over one revolution, for a
    /// circular LEO, the P0 orbit (e = 0.01) and the P1 orbit (e = 0.7). Truncation is below
    /// rounding at this step; rounding of a ~7e6 m position (ulp ≈ 1e-9 m) over 360 sub-steps,
    /// amplified along-track by the period's sensitivity to energy (~3π per orbit), gives a
    /// bound ~ 360·1e-9·10 ≈ 4e-6 m·(a/7e6 m): tolerance 1e-12·a·(steps)/(1−e).
    #[test]
    fn val_rk8_vs_kepler_one_orbit() {
        for el in [leo_circular(), p0_orbit(), p1_orbit()] {
            let mut orbit = ReferenceOrbit::from_elements(&el, TWO_BODY);
            let (r0, v0) = orbit.state();
            let t = el.period_s(MU_EARTH_M3_S2);
            orbit.step(t);
            let (r, v) = orbit.state();
            let (rk, vk) = kepler_propagate(&r0, &v0, t, MU_EARTH_M3_S2);
            let n_sub = (t / orbit.max_substep_s()).ceil();
            let tol_r = 1e-12 * el.a_m * n_sub / (1.0 - el.e);
            let err_r = (r - rk).norm();
            let err_v = (v - vk).norm();
            eprintln!(
                "e {}: {} sub-steps, |Δr| {err_r:e} m, |Δv| {err_v:e} m/s",
                el.e, n_sub
            );
            assert!(err_r < tol_r, "e {}: {err_r:e} m (tol {tol_r:e})", el.e);
            assert!(err_v < tol_r * mean_motion(el.a_m, MU_EARTH_M3_S2) * 10.0 / (1.0 - el.e));
        }
    }

    /// Two-body: energy and angular momentum conserved over one revolution to < 1e-10
    /// relative (1e-10 of the energy is 0.7 mm of semi-major axis at 7178 km, far below the
    /// relative-motion tolerances built on the reference); measured ~1e-14 at the ReferenceOrbit
    /// step rule (1° of true anomaly at perigee: 15.8 s for the LEO, 0.47 s at P1's perigee).
    #[test]
    fn invariant_two_body_energy_momentum() {
        for el in [leo_circular(), p0_orbit(), p1_orbit()] {
            let mut orbit = ReferenceOrbit::from_elements(&el, TWO_BODY);
            let x0 = orbit.state_vector();
            orbit.step(el.period_s(MU_EARTH_M3_S2));
            let x1 = orbit.state_vector();
            let de =
                ((energy(&x1, TWO_BODY) - energy(&x0, TWO_BODY)) / energy(&x0, TWO_BODY)).abs();
            let dh = (ang_mom(&x1) - ang_mom(&x0)).norm() / ang_mom(&x0).norm();
            eprintln!("two-body e {}: rel energy {de:e}, rel |Δh| {dh:e}", el.e);
            assert!(de < 1e-10 && dh < 1e-10);
        }
    }

    /// Two-body + J2 is conservative and axially symmetric: energy v²/2 + V(r) (V incl. the J2
    /// potential) and h_z are conserved over 3 revolutions to < 1e-10 relative, while h_x, h_y
    /// change by O(J2) (the orbit plane precesses).
    #[test]
    fn invariant_j2_energy_and_polar_momentum() {
        for el in [leo_circular(), p1_orbit()] {
            let mut orbit = ReferenceOrbit::from_elements(&el, TWO_BODY_J2);
            let x0 = orbit.state_vector();
            orbit.step(3.0 * el.period_s(MU_EARTH_M3_S2));
            let x1 = orbit.state_vector();
            let de = ((energy(&x1, TWO_BODY_J2) - energy(&x0, TWO_BODY_J2))
                / energy(&x0, TWO_BODY_J2))
            .abs();
            let h0 = ang_mom(&x0);
            let h1 = ang_mom(&x1);
            let dhz = (h1.z - h0.z).abs() / h0.norm();
            let dhxy = (h1 - h0).xy().norm() / h0.norm();
            eprintln!(
                "J2 e {}: rel energy {de:e}, rel Δh_z {dhz:e}, rel Δh_xy {dhxy:e}",
                el.e
            );
            assert!(de < 1e-10 && dhz < 1e-10);
            assert!(dhxy > 1e-4, "J2 must precess the orbit plane");
        }
    }

    /// J2 nodal regression over 10 revolutions of a circular LEO (51.6°) matches the secular
    /// rate −(3/2) n J2 (R_E/a)² cos i to 3 %. Osculating-Ω short-period terms have amplitude
    /// ~(3/4) J2 (R_E/a)² ≈ 7e-4 rad, i.e. < 2 % of the 10-revolution drift (≈ 5e-2 rad).
    #[test]
    fn val_j2_nodal_regression() {
        let el = leo_circular();
        let mut orbit = ReferenceOrbit::from_elements(&el, TWO_BODY_J2);
        let om0 = orbit.elements().raan_rad;
        let t = 10.0 * el.period_s(MU_EARTH_M3_S2);
        orbit.step(t);
        let drift = wrap_pi(orbit.elements().raan_rad - om0);
        let n = mean_motion(el.a_m, MU_EARTH_M3_S2);
        let want = -1.5 * n * J2_EARTH * (R_EARTH_M / el.a_m).powi(2) * el.i_rad.cos() * t;
        eprintln!("nodal drift over 10 rev: {drift:e} rad vs secular {want:e} rad");
        assert!(((drift - want) / want).abs() < 0.03);
    }

    /// Stepping 600 s at once or in 36,000 steps of 1/60 s (a simulation's fixed dt) gives the
    /// same state up to rounding: worst case one rounding of |r| (ulp ≈ 9.3e-10 m) per step,
    /// 36,000 × 9.3e-10 ≈ 3.4e-5 m.
    #[test]
    fn invariant_reference_orbit_step_size_independent() {
        let mut a = ReferenceOrbit::from_elements(&p0_orbit(), TWO_BODY_J2);
        let mut b = a.clone();
        a.step(600.0);
        for _ in 0..36_000 {
            b.step(1.0 / 60.0);
        }
        let err = (a.pos_eci_m() - b.pos_eci_m()).norm();
        let ulp = f64::EPSILON * a.pos_eci_m().norm();
        eprintln!(
            "600 s in one call vs 36000 calls: |Δr| {err:e} m, Δt {:e} s",
            a.t_s() - b.t_s()
        );
        assert!(err < 36_000.0 * ulp, "{err:e}");
        assert!((a.t_s() - b.t_s()).abs() < 36_000.0 * f64::EPSILON * 600.0);
    }

    /// Params round-trip through JSON and reject unknown fields.
    #[test]
    fn invariant_reference_orbit_params_serde() {
        let p = ReferenceOrbitParams {
            init: OrbitInit::Elements(p1_orbit()),
            with_j2: true,
        };
        let s = serde_json::to_string(&p).unwrap();
        let q: ReferenceOrbitParams = serde_json::from_str(&s).unwrap();
        assert_eq!(p, q);
        assert_eq!(
            q.build().state(),
            ReferenceOrbit::from_elements(&p1_orbit(), TWO_BODY_J2).state()
        );
        let bad = s.replace("\"with_j2\"", "\"with_j3\":1,\"with_j2\"");
        assert!(serde_json::from_str::<ReferenceOrbitParams>(&bad).is_err());
    }
}
