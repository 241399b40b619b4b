//! Differential-game barrier for formation collision avoidance near the Sun–Earth L2 point, after
//! Zhang, He, Lü, Wang (2018), *Research on flight collision avoidance control on the Sun–Earth
//! libration points based on barrier theory*, J. Northwestern Polytechnical Univ. 36(2):252–257.
//!
//! Two spacecraft, P (the paper's 追赶星, "pursuer") and E (目标星, "evader"), fly in the plane
//! of the Sun–EMB rotating frame `rot` of [`crate::orbit::l2`], each with a thrust of fixed
//! magnitude F in a commanded direction (v for P, u for E, angles from +X towards +Y). The game
//! state is the paper's eight-vector, in the order of its Hamiltonian (3):
//! `x = [Xp, Yp, Vxp, Vyp, Xe, Ye, Vxe, Vye]` (m, m/s, frame `rot`); the costate
//! `γ = [γ1 … γ8]` uses the same order. The target (collision) set is D = {‖r_e − r_p‖ ≤ l},
//! eq (2).
//!
//! # What is implemented, equation by equation
//! * eq (1) → [`dynamics`], with the drift of [`Drift`] (the L2 model, or force-free as in the
//!   paper's Section 3, which neglects gravity because the spacecraft are close).
//! * eq (3) → [`hamiltonian`], [`h0`]; eqs (6), (8) → [`v_star_rad`], [`u_star_rad`]; eq (9)
//!   → [`hamiltonian_star`].
//! * ∂D, its normal and eq (12) → [`boundary_state`], [`gamma_on_boundary`],
//!   [`boundary_value`]; NUP / UP / BUP → [`classify_boundary`], [`bup_state`].
//! * eqs (13)–(16), the retrograde path equations from the BUP → [`retrograde_path`];
//!   eq (17) (the force-free barrier) is checked in the tests.
//! * Capture/escape classification of any state → [`closest_approach`], [`barrier_function_m`],
//!   [`classify_state`].
//! * Avoidance during reconfiguration → [`AvoidanceController`], [`PlannedManeuver`]; the
//!   closed-loop simulator the reproduction and the validation use (`simulate_reconfiguration`,
//!   `collision_course_plan`, `boundary_value_history`) is reproduction code, in
//!   `crate::reproduce::zhang2018_sim` (feature `sim`).
//! * How a scene asks for the law → [`Zhang2018Spec`] (fixed thrust, planned maneuver in `rot`,
//!   avoidance on/off, l, margin); the ECS wiring (floating origin at the formation centre,
//!   capture guarantee) is in `scene.rs`.
//!
//! # Corrections of the printed text (typos and inconsistencies)
//! * ∂D parametrisation: printed Y_e(t̃) = s2 + l **cos** s5; corrected to s2 + l sin s5
//!   (as eq (15) has it).
//! * Eq (15): printed V_ye*(0) = s3; corrected to s4 (as the parametrisation of ∂D has it).
//! * Tangency condition (11): printed −γ5 l cos s5 + γ6 l cos s5 = 0; the derivative of
//!   (s1 + l cos s5, s2 + l sin s5) w.r.t. s5 gives −γ5 l sin s5 + γ6 l cos s5 = 0.
//! * Normalisation of γ on ∂D: printed 1/√8 per component in the normal vector and in (12), but
//!   (10)–(11) demand γᵀγ = 1 and γ1²+…+γ4² = ½, and the initial conditions of (13) use ½. With
//!   1/√8 the norm would be 1/√2. We use ½ everywhere ([`gamma_on_boundary`]), so (12) reads
//!   H = ½[Q sin(s5 + a) − (F_p/M_p + F_e/M_e)].
//! * (12): a = arctan(A/B) is evaluated as atan2(A, B) so that Q sin(s5 + a) = A cos s5 + B sin s5
//!   holds in every quadrant.
//! * (7): printed d²H_p/dv² = −(γ3 sin v* + γ4 cos v*); the second derivative of
//!   (F/M)(γ3 cos v + γ4 sin v) is −(F/M)(γ3 cos v + γ4 sin v), which at v* equals
//!   (F/M)√(γ3² + γ4²) > 0.
//! * Eq (13): "sin Y_p" means sin(s5)·Y_p. Beyond that the printed costate equations freeze
//!   γ3, γ4 (γ7, γ8) at cos s5, sin s5 inside the gravity terms, use ‖r‖^{9/2} where the
//!   gravity gradient gives 3μ/‖r‖⁵, use r_p in E's equations, and carry the sign of the
//!   forward-time adjoint. We integrate the exact retrograde path equations instead:
//!   dx/dτ = −f(x, u*, v*), dγ/dτ = +∂H/∂x (τ = t̃ − t, backward time), with the drift's
//!   analytic Jacobian and the controls recomputed from γ at every stage.
//! * Eq (16) integrates the positions as if the velocities were constant; with thrust they are
//!   not. It holds for the *relative* motion in the adversarial game with equal thrust
//!   accelerations, where the optimal thrusts cancel (see below), and that is what the test of
//!   eq (17) checks.
//! * Roles. (4) says max_u min_v, but (8) as printed *minimises* H_e (so does (6) for H_p), and
//!   (9) and (12) are the values with both minimising. With the paper's γ on ∂D, whose position
//!   part points into D, minimising H means steering away from a collision: (6) makes P thrust
//!   away from E and (8) makes E thrust away from P. We keep (6) and (8) exactly as printed
//!   ([`PursuerRole::PaperCooperative`]: both avoid, the value is (9)/(12)) and add the
//!   adversarial game of Isaacs, in which P maximises H ([`v_pursuit_rad`],
//!   [`PursuerRole::Adversarial`]): the worst case for E, used by the classifier and the
//!   avoidance law. E's direction is always (8).
//! * UP/NUP labels: the paper's case 1) (H > 0: collision cannot be avoided) is called NUP and
//!   case 2) UP. In Isaacs' (standard) usage the usable part is where termination (here:
//!   collision) can be forced; [`BoundaryClass`] keeps the standard meaning, so the paper's
//!   labels of cases 1) and 2) are swapped. The paper also states the cases for "the whole ∂D";
//!   they depend on s5, so we classify point by point.
//! * Units in H. The paper's γ has nonzero velocity components, so (12) adds a velocity
//!   (m/s) to accelerations (m/s²): implicitly with a time scale of 1 s. We keep the paper's
//!   form in SI (numbers in m/s and m/s²); the sign of H, which is all the paper uses, depends on
//!   that scale.
//! * Thrust F: the paper gives none; [`Zhang2018Params::paper`] uses 1 N for both spacecraft.
//!
//! # Capture region (method)
//! For the adversarial game with F_p/M_p ≤ F_e/M_e, E can cancel P's thrust, so under the
//! saddle-point play the *relative* motion is thrust-free. In the force-free model the relative
//! path is then a straight line and the retrograde paths from the BUP (‖ρ‖ = l, ρ̇ ⟂ ρ) are the
//! lines tangent to the circle ‖ρ‖ = l: the barrier is {miss distance of the relative line = l,
//! closest approach ahead}. A state is in the capture region iff the relative line enters the
//! disc (or the pair is already in D): [`closest_approach`] gives the miss distance in closed
//! form, [`barrier_function_m`] = miss − l (≤ 0: capture). The escape side is exact for any P:
//! on the barrier the normal's velocity part is t_ca·m̂ (m̂: predicted miss direction), and E
//! thrusting along m̂ makes d(miss)/dt ≥ 0 whatever P does. The capture side assumes P may
//! react to E's current thrust (the upper value; with equal F/M P then cancels it): a P that
//! reacts to the state only does not catch an E that brakes along the line of sight (the test
//! `invariant_zhang2018_barrier_is_semipermeable` pins this: 100 m inside the barrier, the
//! braking E passes at 7.1 km). For E's safety — the use made here — only the escape side
//! matters. With the L2 drift, [`classify_state`]
//! propagates both spacecraft thrust-free (the saddle play leaves the relative motion unchanged
//! up to third-order gravity-gradient terms of the common displacement) and takes the minimum
//! separation over a horizon. With F_p/M_p > F_e/M_e this test is not a barrier (P wins
//! eventually) and should not be used.

use crate::orbit::l2::{L2Params, L2State};
use nalgebra::{Matrix2, SVector, Vector2, Vector4};

/// Game state `[Xp, Yp, Vxp, Vyp, Xe, Ye, Vxe, Vye]`, m and m/s, frame `rot`.
pub type GameState = SVector<f64, 8>;
/// Costate `[γ1 … γ8]`, same order as [`GameState`] (dimensionless in the paper's normalisation).
pub type Costate = SVector<f64, 8>;

/// The thrust-free acceleration each spacecraft feels.
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub enum Drift {
    /// Planar Sun–EMB rotating-frame model of [`crate::orbit::l2`] (eq (1), corrected).
    L2(L2Params),
    /// No gravity, no frame terms (the paper's Section 3 simplification).
    ForceFree,
}

impl Drift {
    /// Drift acceleration of a single-spacecraft state `[X, Y, Vx, Vy]`, m/s², frame `rot`.
    pub fn accel_rot_m_s2(&self, s: &L2State) -> Vector2<f64> {
        match self {
            Drift::L2(p) => p.drift_accel_rot_m_s2(s),
            Drift::ForceFree => Vector2::zeros(),
        }
    }

    /// Jacobians (∂a/∂r 1/s², ∂a/∂v 1/s) of the drift acceleration.
    pub fn jacobian(&self, s: &L2State) -> (Matrix2<f64>, Matrix2<f64>) {
        match self {
            Drift::L2(p) => p.drift_jacobian(s),
            Drift::ForceFree => (Matrix2::zeros(), Matrix2::zeros()),
        }
    }

    /// One RK4 step of a single spacecraft with a thrust acceleration held over the step.
    pub fn rk4_step(&self, s: &L2State, thrust_rot_m_s2: &Vector2<f64>, dt_s: f64) -> L2State {
        let f = |x: &L2State| {
            let a = self.accel_rot_m_s2(x) + thrust_rot_m_s2;
            Vector4::new(x[2], x[3], a[0], a[1])
        };
        let k1 = f(s);
        let k2 = f(&(s + k1 * (0.5 * dt_s)));
        let k3 = f(&(s + k2 * (0.5 * dt_s)));
        let k4 = f(&(s + k3 * dt_s));
        s + (k1 + k2 * 2.0 + k3 * 2.0 + k4) * (dt_s / 6.0)
    }
}

/// Which way P steers in the game.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum PursuerRole {
    /// P maximises H (thrusts towards the collision): the adversarial game of Isaacs, the worst
    /// case for E.
    Adversarial,
    /// P minimises H, eq (6) as printed (thrusts away from E): the value is eq (9)/(12).
    PaperCooperative,
}

/// Parameters of the game and of the avoidance law (SI).
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Zhang2018Params {
    /// Mass of P, kg.
    pub mass_p_kg: f64,
    /// Mass of E, kg.
    pub mass_e_kg: f64,
    /// Thrust magnitude of P, N.
    pub thrust_p_n: f64,
    /// Thrust magnitude of E, N.
    pub thrust_e_n: f64,
    /// Critical (capture) distance l, m.
    pub capture_radius_m: f64,
    /// Avoidance margin: E switches to the evasive direction when the barrier function
    /// (miss distance − l) falls below this, m.
    pub avoidance_margin_m: f64,
    /// Drift model.
    pub drift: Drift,
}

impl Default for Zhang2018Params {
    fn default() -> Self {
        Self::paper()
    }
}

impl Zhang2018Params {
    /// Section 3: both 2000 kg, l = 5 km, the L2 model of Table 1. Not in the paper (chosen):
    /// F = 1 N for both (0.5 mm/s²) and an avoidance margin of 1 km.
    pub fn paper() -> Self {
        Self {
            mass_p_kg: 2000.0,
            mass_e_kg: 2000.0,
            thrust_p_n: 1.0,
            thrust_e_n: 1.0,
            capture_radius_m: 5000.0,
            avoidance_margin_m: 1000.0,
            drift: Drift::L2(L2Params::paper()),
        }
    }

    /// F_p/M_p, m/s².
    pub fn alpha_p_m_s2(&self) -> f64 {
        self.thrust_p_n / self.mass_p_kg
    }

    /// F_e/M_e, m/s².
    pub fn alpha_e_m_s2(&self) -> f64 {
        self.thrust_e_n / self.mass_e_kg
    }
}

/// Section 3 initial states in the L2-centred frame `l2c` (km and m/s of the paper → SI).
pub fn paper_initial_state_l2c() -> GameState {
    GameState::from_column_slice(&[
        87_028_508.409,
        -24_739_512.629,
        8.995_877,
        121.605_675,
        87_028_618.409,
        -23_268_613.245,
        8.285_877,
        120.924_877,
    ])
}

/// Section 3 initial states in `rot` (the `l2c` states shifted by the L2 abscissa).
pub fn paper_initial_state_rot(l2: &L2Params) -> GameState {
    let mut x = paper_initial_state_l2c();
    let x_l2 = l2.l2_x_rot_m();
    x[0] += x_l2;
    x[4] += x_l2;
    x
}

/// P's state `[Xp, Yp, Vxp, Vyp]`.
pub fn p_state(x: &GameState) -> L2State {
    x.fixed_rows::<4>(0).into_owned()
}

/// E's state `[Xe, Ye, Vxe, Vye]`.
pub fn e_state(x: &GameState) -> L2State {
    x.fixed_rows::<4>(4).into_owned()
}

/// The game state of P's and E's states.
pub(crate) fn join(p: &L2State, e: &L2State) -> GameState {
    let mut x = GameState::zeros();
    x.fixed_rows_mut::<4>(0).copy_from(p);
    x.fixed_rows_mut::<4>(4).copy_from(e);
    x
}

/// The unit vector at `angle_rad` from +X towards +Y.
pub(crate) fn dir(angle_rad: f64) -> Vector2<f64> {
    Vector2::new(angle_rad.cos(), angle_rad.sin())
}

/// Relative position ρ = r_e − r_p, m.
pub fn rel_pos_m(x: &GameState) -> Vector2<f64> {
    Vector2::new(x[4] - x[0], x[5] - x[1])
}

/// Relative velocity w = v_e − v_p, m/s.
pub fn rel_vel_m_s(x: &GameState) -> Vector2<f64> {
    Vector2::new(x[6] - x[2], x[7] - x[3])
}

/// Eq (1): ẋ = f(x, u, v) with E's thrust direction `u_rad` and P's `v_rad`.
pub fn dynamics(params: &Zhang2018Params, x: &GameState, u_rad: f64, v_rad: f64) -> GameState {
    let (p, e) = (p_state(x), e_state(x));
    let ap = params.drift.accel_rot_m_s2(&p) + dir(v_rad) * params.alpha_p_m_s2();
    let ae = params.drift.accel_rot_m_s2(&e) + dir(u_rad) * params.alpha_e_m_s2();
    GameState::from_column_slice(&[p[2], p[3], ap[0], ap[1], e[2], e[3], ae[0], ae[1]])
}

/// Eq (3): H = γ·f(x, u, v).
pub fn hamiltonian(
    params: &Zhang2018Params,
    x: &GameState,
    gamma: &Costate,
    u_rad: f64,
    v_rad: f64,
) -> f64 {
    gamma.dot(&dynamics(params, x, u_rad, v_rad))
}

/// H0 of eq (3): the control-free part γ·f(x, thrust off).
pub fn h0(params: &Zhang2018Params, x: &GameState, gamma: &Costate) -> f64 {
    let (p, e) = (p_state(x), e_state(x));
    let ap = params.drift.accel_rot_m_s2(&p);
    let ae = params.drift.accel_rot_m_s2(&e);
    gamma.dot(&GameState::from_column_slice(&[
        p[2], p[3], ap[0], ap[1], e[2], e[3], ae[0], ae[1],
    ]))
}

/// Eq (6): P's direction, sin v* = −γ4/√(γ3²+γ4²), cos v* = −γ3/√(γ3²+γ4²): the minimiser of
/// H_p, rad.
pub fn v_star_rad(gamma: &Costate) -> f64 {
    (-gamma[3]).atan2(-gamma[2])
}

/// Eq (8): E's direction, sin u* = −γ8/√(γ7²+γ8²), cos u* = −γ7/√(γ7²+γ8²): the minimiser of
/// H_e (the printed formula; see the module doc on roles), rad.
pub fn u_star_rad(gamma: &Costate) -> f64 {
    (-gamma[7]).atan2(-gamma[6])
}

/// P's direction in the adversarial game: the maximiser of H_p, (cos v, sin v) ∥ (γ3, γ4), rad.
pub fn v_pursuit_rad(gamma: &Costate) -> f64 {
    gamma[3].atan2(gamma[2])
}

/// P's optimal direction for a role, rad.
pub fn pursuer_direction_rad(role: PursuerRole, gamma: &Costate) -> f64 {
    match role {
        PursuerRole::Adversarial => v_pursuit_rad(gamma),
        PursuerRole::PaperCooperative => v_star_rad(gamma),
    }
}

/// H at the optimal directions: eq (9) for [`PursuerRole::PaperCooperative`],
/// H0 + (F_p/M_p)√(γ3²+γ4²) − (F_e/M_e)√(γ7²+γ8²) for the adversarial game.
pub fn hamiltonian_star(
    params: &Zhang2018Params,
    x: &GameState,
    gamma: &Costate,
    role: PursuerRole,
) -> f64 {
    let gp = (gamma[2] * gamma[2] + gamma[3] * gamma[3]).sqrt();
    let ge = (gamma[6] * gamma[6] + gamma[7] * gamma[7]).sqrt();
    let sp = match role {
        PursuerRole::Adversarial => 1.0,
        PursuerRole::PaperCooperative => -1.0,
    };
    h0(params, x, gamma) + sp * params.alpha_p_m_s2() * gp - params.alpha_e_m_s2() * ge
}

/// The normal on ∂D used by the paper, with the consistent normalisation ½ (γᵀγ = 1):
/// ½(cos s5, sin s5, cos s5, sin s5, −cos s5, −sin s5, −cos s5, −sin s5). Its position part
/// points into D.
pub fn gamma_on_boundary(s5_rad: f64) -> Costate {
    let (s, c) = s5_rad.sin_cos();
    Costate::from_column_slice(&[c, s, c, s, -c, -s, -c, -s]) * 0.5
}

/// A point of ∂D: P at `p` (the paper's s1…s4), E at r_p + l(cos s5, sin s5) with velocity
/// v_p + `rel_vel_rot_m_s` (the paper's parametrisation is the case `rel_vel = 0`, with the
/// corrections Y_e = s2 + l sin s5 and V_ye = s4).
pub fn boundary_state(
    p: &L2State,
    s5_rad: f64,
    capture_radius_m: f64,
    rel_vel_rot_m_s: &Vector2<f64>,
) -> GameState {
    let e = Vector4::new(
        p[0] + capture_radius_m * s5_rad.cos(),
        p[1] + capture_radius_m * s5_rad.sin(),
        p[2] + rel_vel_rot_m_s[0],
        p[3] + rel_vel_rot_m_s[1],
    );
    join(p, &e)
}

/// Line-of-sight angle s5 = atan2(Ye − Yp, Xe − Xp) of a state, rad.
pub fn los_angle_s5_rad(x: &GameState) -> f64 {
    let r = rel_pos_m(x);
    r[1].atan2(r[0])
}

/// The terms of eq (12) at a state.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct BoundaryValue {
    /// Q of eq (12) (mixed m/s + m/s², see the module doc).
    pub q: f64,
    /// a of eq (12), rad.
    pub a_rad: f64,
    /// s5 (line-of-sight angle of the state), rad.
    pub s5_rad: f64,
    /// H = ½[Q sin(s5 + a) − (F_p/M_p + F_e/M_e)] (cooperative, as printed) or
    /// ½[Q sin(s5 + a) + F_p/M_p − F_e/M_e] (adversarial).
    pub h: f64,
}

/// Eq (12) evaluated at the state's own line of sight s5 (as the paper does along its scenario
/// for Fig. 2): A = V_xp − V_xe + a0_xp − a0_xe, B likewise in y, Q = √(A²+B²),
/// a = atan2(A, B). Equals [`hamiltonian_star`] with γ = [`gamma_on_boundary`] (s5).
pub fn boundary_value(params: &Zhang2018Params, x: &GameState, role: PursuerRole) -> BoundaryValue {
    let (p, e) = (p_state(x), e_state(x));
    let d0 = params.drift.accel_rot_m_s2(&p) - params.drift.accel_rot_m_s2(&e);
    let a_term = p[2] - e[2] + d0[0];
    let b_term = p[3] - e[3] + d0[1];
    let q = a_term.hypot(b_term);
    let a_rad = a_term.atan2(b_term);
    let s5_rad = los_angle_s5_rad(x);
    let thrust = match role {
        PursuerRole::PaperCooperative => -(params.alpha_p_m_s2() + params.alpha_e_m_s2()),
        PursuerRole::Adversarial => params.alpha_p_m_s2() - params.alpha_e_m_s2(),
    };
    BoundaryValue {
        q,
        a_rad,
        s5_rad,
        h: 0.5 * (q * (s5_rad + a_rad).sin() + thrust),
    }
}

/// Classification of a point of ∂D (standard/Isaacs meaning; the paper swaps UP and NUP).
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum BoundaryClass {
    /// Usable part, H* > 0: the state is driven into D (collision) whatever the avoiding side
    /// does. The paper's case 1) (which it calls NUP).
    Up,
    /// Non-usable part, H* < 0: the avoiding side keeps the state out of D. The paper's
    /// case 2) (which it calls UP).
    Nup,
    /// Boundary of the usable part, |H*| ≤ tolerance: where the barrier starts (case 3).
    Bup,
}

/// Classifies a state on (or projected along its line of sight onto) ∂D by the sign of
/// eq (12); `tol` is in the units of H (see the module doc).
pub fn classify_boundary(
    params: &Zhang2018Params,
    x: &GameState,
    role: PursuerRole,
    tol: f64,
) -> BoundaryClass {
    let h = boundary_value(params, x, role).h;
    if h > tol {
        BoundaryClass::Up
    } else if h < -tol {
        BoundaryClass::Nup
    } else {
        BoundaryClass::Bup
    }
}

/// A BUP point: P at `p`, E on ∂D at angle s5, relative velocity `w_t_m_s` along the tangent
/// (−sin s5, cos s5) plus the radial part that makes H* = 0 (H* is affine in it with slope −½;
/// the Coriolis term of a radial velocity has no radial component). In the force-free
/// adversarial game with equal accelerations the radial part is 0.
pub fn bup_state(
    params: &Zhang2018Params,
    p: &L2State,
    s5_rad: f64,
    w_t_m_s: f64,
    role: PursuerRole,
) -> GameState {
    let l = params.capture_radius_m;
    let t_hat = Vector2::new(-s5_rad.sin(), s5_rad.cos());
    let x0 = boundary_state(p, s5_rad, l, &(t_hat * w_t_m_s));
    let g = gamma_on_boundary(s5_rad);
    let h = hamiltonian_star(params, &x0, &g, role);
    let w = t_hat * w_t_m_s + dir(s5_rad) * (2.0 * h);
    boundary_state(p, s5_rad, l, &w)
}

/// ∂H/∂x at given directions (the right-hand side of the retrograde costate equations).
pub fn costate_rate(params: &Zhang2018Params, x: &GameState, gamma: &Costate) -> Costate {
    let mut out = Costate::zeros();
    for k in [0usize, 4] {
        let s: L2State = x.fixed_rows::<4>(k).into_owned();
        let (g, c) = params.drift.jacobian(&s);
        let gp = Vector2::new(gamma[k], gamma[k + 1]);
        let gv = Vector2::new(gamma[k + 2], gamma[k + 3]);
        let dr = g.transpose() * gv;
        let dv = gp + c.transpose() * gv;
        out[k] = dr[0];
        out[k + 1] = dr[1];
        out[k + 2] = dv[0];
        out[k + 3] = dv[1];
    }
    out
}

/// One sample of a retrograde path.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RetroSample {
    /// Backward time τ = t̃ − t, s.
    pub tau_s: f64,
    /// State on the path.
    pub x: GameState,
    /// Costate on the path.
    pub gamma: Costate,
    /// E's optimal direction u*(γ), eq (8), rad.
    pub u_rad: f64,
    /// P's optimal direction for the role, rad.
    pub v_rad: f64,
    /// H at the optimal directions (constant along an exact path: H is autonomous).
    pub h_star: f64,
}

/// Retrograde path equations (13)–(15), corrected: from `x0` on ∂D (normally a BUP point) with
/// γ(0) = `gamma0` (normally [`gamma_on_boundary`]), integrates dx/dτ = −f(x, u*, v*),
/// dγ/dτ = +∂H/∂x with RK4, sampled every `dtau_s` for `steps` samples after the start
/// (internally sub-stepped at h = min(dtau, max(1 s, τ/20))). Returns `steps + 1` samples.
pub fn retrograde_path(
    params: &Zhang2018Params,
    x0: &GameState,
    gamma0: &Costate,
    role: PursuerRole,
    dtau_s: f64,
    steps: usize,
) -> Vec<RetroSample> {
    type Z = SVector<f64, 16>;
    let rhs = |z: &Z| -> Z {
        let x: GameState = z.fixed_rows::<8>(0).into_owned();
        let g: Costate = z.fixed_rows::<8>(8).into_owned();
        let u = u_star_rad(&g);
        let v = pursuer_direction_rad(role, &g);
        let mut out = Z::zeros();
        out.fixed_rows_mut::<8>(0)
            .copy_from(&(-dynamics(params, &x, u, v)));
        out.fixed_rows_mut::<8>(8)
            .copy_from(&costate_rate(params, &x, &g));
        out
    };
    let sample = |tau: f64, z: &Z| {
        let x: GameState = z.fixed_rows::<8>(0).into_owned();
        let g: Costate = z.fixed_rows::<8>(8).into_owned();
        RetroSample {
            tau_s: tau,
            x,
            gamma: g,
            u_rad: u_star_rad(&g),
            v_rad: pursuer_direction_rad(role, &g),
            h_star: hamiltonian_star(params, &x, &g, role),
        }
    };
    let mut z = Z::zeros();
    z.fixed_rows_mut::<8>(0).copy_from(x0);
    z.fixed_rows_mut::<8>(8).copy_from(gamma0);
    let mut out = Vec::with_capacity(steps + 1);
    out.push(sample(0.0, &z));
    let mut tau = 0.0;
    for k in 0..steps {
        let tau_next = (k + 1) as f64 * dtau_s;
        while tau < tau_next {
            // Sub-steps: the costate's velocity part grows like (1 + τ/1 s) from ∂D, so near
            // τ = 0 its time scale is ~1 s; h = max(1 s, τ/20) keeps RK4 accurate there and
            // costs ~20·ln(τ/1 s) extra steps in all.
            let h = (tau_next - tau).min((0.05 * tau).max(1.0));
            let k1 = rhs(&z);
            let k2 = rhs(&(z + k1 * (0.5 * h)));
            let k3 = rhs(&(z + k2 * (0.5 * h)));
            let k4 = rhs(&(z + k3 * h));
            z += (k1 + k2 * 2.0 + k3 * 2.0 + k4) * (h / 6.0);
            tau = if h == tau_next - tau {
                tau_next
            } else {
                tau + h
            };
        }
        out.push(sample((k + 1) as f64 * dtau_s, &z));
    }
    out
}

/// Closest approach of the thrust-free, force-free relative motion (a straight line).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ClosestApproach {
    /// Time to closest approach, s (0 if the pair is receding).
    pub t_ca_s: f64,
    /// Separation at closest approach (miss distance), m.
    pub miss_m: f64,
    /// Direction of ρ = r_e − r_p at closest approach (the BUP angle s5 of the barrier path
    /// through the state when miss = l), rad.
    pub s5_ca_rad: f64,
}

/// Closed-form closest approach of the line ρ + w t, t ≥ 0.
pub fn closest_approach(x: &GameState) -> ClosestApproach {
    let rho = rel_pos_m(x);
    let w = rel_vel_m_s(x);
    let w2 = w.norm_squared();
    let t = if w2 > 0.0 {
        (-rho.dot(&w) / w2).max(0.0)
    } else {
        0.0
    };
    let m = rho + w * t;
    ClosestApproach {
        t_ca_s: t,
        miss_m: m.norm(),
        s5_ca_rad: m[1].atan2(m[0]),
    }
}

/// Barrier function of the adversarial game with equal (or E-dominated) accelerations, force-free
/// relative motion: miss distance − l, m. ≤ 0: capture region; > 0: escape region; = 0: on the
/// barrier (the lines tangent to the circle of eq (17)).
pub fn barrier_function_m(params: &Zhang2018Params, x: &GameState) -> f64 {
    closest_approach(x).miss_m - params.capture_radius_m
}

/// Capture or escape region.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum StateClass {
    /// P can force the separation to ≤ l (or it already is).
    Capture,
    /// E can keep the separation > l against any P.
    Escape,
}

/// Classifies a state of the adversarial game (requires F_p/M_p ≤ F_e/M_e): propagates both
/// spacecraft thrust-free under the drift with RK4 step `dt_s` over `horizon_s` and takes the
/// minimum separation, refined inside each step by the closed-form line. Returns the class and
/// the closest approach found (time from now, minimum separation, direction).
pub fn classify_state(
    params: &Zhang2018Params,
    x: &GameState,
    horizon_s: f64,
    dt_s: f64,
) -> (StateClass, ClosestApproach) {
    let mut p = p_state(x);
    let mut e = e_state(x);
    let mut best = ClosestApproach {
        t_ca_s: 0.0,
        miss_m: f64::INFINITY,
        s5_ca_rad: 0.0,
    };
    let steps = (horizon_s / dt_s).ceil() as usize;
    for k in 0..steps {
        let ca = closest_approach(&join(&p, &e));
        let t_local = ca.t_ca_s.min(dt_s);
        let m = rel_pos_m(&join(&p, &e)) + rel_vel_m_s(&join(&p, &e)) * t_local;
        if m.norm() < best.miss_m {
            best = ClosestApproach {
                t_ca_s: k as f64 * dt_s + t_local,
                miss_m: m.norm(),
                s5_ca_rad: m[1].atan2(m[0]),
            };
        }
        p = params.drift.rk4_step(&p, &Vector2::zeros(), dt_s);
        e = params.drift.rk4_step(&e, &Vector2::zeros(), dt_s);
    }
    let class = if best.miss_m <= params.capture_radius_m {
        StateClass::Capture
    } else {
        StateClass::Escape
    };
    (class, best)
}

/// One segment of a planned thrust-direction schedule.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ThrustSegment {
    /// Start time, s.
    pub t_start_s: f64,
    /// End time (exclusive), s.
    pub t_end_s: f64,
    /// Thrust direction (angle from +X of `rot`), rad.
    pub dir_rad: f64,
}

/// A planned maneuver: thrust on in the listed segments, off elsewhere.
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PlannedManeuver {
    /// Segments, non-overlapping.
    pub segments: Vec<ThrustSegment>,
}

impl PlannedManeuver {
    /// Commanded direction at time `t_s` (None: thrust off), rad.
    pub fn dir_at(&self, t_s: f64) -> Option<f64> {
        self.segments
            .iter()
            .find(|s| t_s >= s.t_start_s && t_s < s.t_end_s)
            .map(|s| s.dir_rad)
    }
}

/// E's command from the avoidance law.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct EvaderCommand {
    /// Thrust direction (None: thrust off), rad, frame `rot`.
    pub dir_rad: Option<f64>,
    /// Whether the evasive direction (8) is in use.
    pub engaged: bool,
    /// Barrier function (miss − l) at this state, m.
    pub barrier_m: f64,
}

/// Barrier-based avoidance for E. E flies its plan; when the barrier function falls below the
/// margin with the closest approach still ahead, E switches to u* of eq (8) with γ the normal
/// of ∂D at the predicted closest-approach angle s5 ([`gamma_on_boundary`]), i.e. it thrusts
/// along the predicted miss vector. (In the force-free game E's costate (γ7, γ8) stays parallel
/// to its value on ∂D along the barrier path, so this is the exact u*; the differential L2
/// drift over the time to go rotates it by ≲ n·t_ca.) It returns to the plan when the barrier
/// function exceeds twice the margin or the closest approach has passed (hysteresis).
/// Prediction by [`closest_approach`] (force-free relative line; the differential drift is
/// ~10⁻⁷ m/s² here against thrusts of ~10⁻⁴ m/s²).
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AvoidanceController {
    /// Game parameters (l, margin).
    pub params: Zhang2018Params,
    /// Engagement state.
    pub engaged: bool,
}

impl AvoidanceController {
    /// A disengaged controller.
    pub fn new(params: Zhang2018Params) -> Self {
        Self {
            params,
            engaged: false,
        }
    }

    /// E's thrust direction given the game state and E's planned direction.
    pub fn evader_command(&mut self, x: &GameState, planned_dir_rad: Option<f64>) -> EvaderCommand {
        let ca = closest_approach(x);
        let b = ca.miss_m - self.params.capture_radius_m;
        let m = self.params.avoidance_margin_m;
        if self.engaged {
            if b > 2.0 * m || ca.t_ca_s <= 0.0 {
                self.engaged = false;
            }
        } else if b < m && ca.t_ca_s > 0.0 {
            self.engaged = true;
        }
        let dir_rad = if self.engaged {
            Some(u_star_rad(&gamma_on_boundary(ca.s5_ca_rad)))
        } else {
            planned_dir_rad
        };
        EvaderCommand {
            dir_rad,
            engaged: self.engaged,
            barrier_m: b,
        }
    }
}

// The scene binding (scene entry, `LawSpec`, disturbances, the simulation adapter) and the
// tests live in their own files; every public item stays reachable at its old path.
mod scene;
pub use scene::*;

#[cfg(test)]
mod tests;
