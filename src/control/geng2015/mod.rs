//! Geng, Chen, Liang (2015), "Relative position and attitude coupled control based on modified
//! twisting algorithm", J. Harbin Inst. Technol. 47(11) (doi 10.11918/j.issn.0367-6234.2015.11.002).
//!
//! Coupled port-to-port relative dynamics (paper eq 1, model of Chen & Geng 2014) controlled by
//! the standard twisting laws T1 (eq 5, s = e) and T2 (eq 6, s = ė + λe with an integral
//! twisting term) and the modified twisting laws M1 (eq 11) and M2 (eq 13) that add linear terms.
//!
//! # Model \[derived\]
//! The paper's eq 1 takes its model from Chen & Geng 2014 without stating it; this is an
//! equivalent derived from rigid-body kinematics, checked against inertial finite differences in
//! the tests.
//!
//! State x = [ρ; q_rv]:
//! - ρ = r_s + A_sᵀ p_s − r_t − A_tᵀ p_t: chaser port minus target port, expressed in the frame
//!   chosen by [`RhoFrame`] (A = inertial→body DCM, p = port in its own body frame). The paper
//!   writes f(*) in the orbital frame F_o: [`RhoFrame::TargetHill`], the default (x radial,
//!   y along-track, z orbit normal — the axis order inferred from Table 2's larger y gains; the
//!   target's orbital frame differs from the chaser's by ~5 µrad at the 36.6 m start). The other
//!   reading, target body axes ([`RhoFrame::TargetBody`]), fails: with the 4.7 °/s tumble that
//!   frame starts with |ρ̇| ≈ 3 m/s and needs centripetal/Coriolis accelerations above a_max,
//!   and every law loses the ports in it (test `regress_geng2015_target_body_rho_frame_saturates`).
//!   Port frames have the axes of their body (the paper gives port positions only).
//! - q_r = q_t⁻¹ ⊗ q_s (Hamilton, body→inertial quaternions), i.e. A(q_r) = A_s A_tᵀ maps target
//!   axes to chaser axes; canonicalised to q_r0 ≥ 0 (the short way round).
//! - ω_r = ω_s − A(q_r) ω_t in chaser axes, so that q̇_rv = G ω_r with G = ½(q_r0 I + [q_rv×]).
//!   The paper defines ω_r = ω_bt − ω_bs; ours is its negative, chosen so G is the plain
//!   Hamilton kinematics matrix.
//!
//! ë = sys(x, ẋ) + B u + Δ with u = [F (N); T (N·m)] in chaser body axes and
//! B = [[A_Fs/m_s, −A_Fs[p_s×]J_s⁻¹], [0, G J_s⁻¹]], A_Fs = A_F A_sᵀ (= A_rᵀ in target axes).
//! B is block upper-triangular, so B⁻¹ = [[m_s A_Fsᵀ, m_s[p_s×]G⁻¹], [0, J_s G⁻¹]] in closed form
//! with G⁻¹ = 2(q_r0 I − [q_rv×] + q_rv q_rvᵀ/q_r0). det G = q_r0/8: B⁻¹ grows like 2/q_r0 near a
//! 180° relative rotation (the q_rv-state singularity); the controller floors q_r0 at
//! [`Q_R0_FLOOR`] and the actuator limits bound the command.
//!
//! The target is modelled torque-free in sys (ω̇_t = −J_t⁻¹ ω_t×J_tω_t); gravity is point-mass μ
//! (as the paper's f(*)); disturbances (a_d, T_d, T_g) are not compensated — they form Δ
//! ([`disturbance_effect`]).
//!
//! # Laws (signs for ë = sys + B u + Δ; x_d constant, so ẋ_d = ẍ_d = 0)
//! - T1: u = B⁻¹[−sys − α1 sgn s − β1 sgn ṡ], s = e, ṡ = ė.
//! - M1: u = B⁻¹[−sys − M1 sgn s − M2 sgn ṡ − M3 s − M4 ṡ], s = e.
//! - T2: u = B⁻¹[−sys − λė + w], ẇ = −α2 sgn s − β2 sgn ṡ, s = ė + λe.
//! - M2: u = B⁻¹[−sys − λė + ν], ν̇ = −K1 sgn s − K2 sgn ṡ − K3 s − K4 ṡ, s = ė + λe.
//!
//! sgn is the pure sign (no boundary layer). u is saturated per axis at m_s·a_max and T_max
//! (the paper's "a·a_max/|a| on a saturated axis" is a per-axis clip). The controller is called
//! at the caller's period and its command held; the paper does not give its step, and 50 ms
//! reproduces Table 3's rotation columns for T1 and M1 (tests), so use 50 ms to compare with the
//! paper. For T2/M2, ṡ = ë + λė is not measured; [`SdotEstimate`] chooses between the integral
//! state (default: ṡ = w or ν, i.e. the commanded ṡ with Δ = 0) and the backward difference of
//! s. With the difference (the true, saturated ṡ) M2's linear terms wind up during the saturated
//! approach from 36.6 m and the loop diverges (test `regress_geng2015_m2_windup_…`). The paper
//! has no anti-windup and none is added.
use nalgebra::{Matrix3, Matrix6, UnitQuaternion, Vector3, Vector6};
use serde::{Deserialize, Serialize};

use crate::orbit::constants::MU_EARTH_M3_S2;

/// Smallest q_r0 used when inverting G (B⁻¹ ∝ 1/q_r0): beyond ~179.9° relative rotation the
/// inverse is evaluated at this floor instead of blowing up.
pub const Q_R0_FLOOR: f64 = 1e-3;

/// Pure sign as in the paper: −1, 0 or +1 (sgn(0) = 0, unlike `f64::signum`).
pub fn sgn(x: f64) -> f64 {
    if x > 0.0 {
        1.0
    } else if x < 0.0 {
        -1.0
    } else {
        0.0
    }
}

fn sgn6(v: &Vector6<f64>) -> Vector6<f64> {
    v.map(sgn)
}

pub use crate::math::mrp::skew;

/// Which of the four laws of the paper.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum Geng2015Law {
    /// Standard twisting, s = e (eq 5).
    T1,
    /// Standard twisting, s = ė + λe, integral twisting term w (eq 6).
    T2,
    /// Modified twisting, s = e, plus linear terms M3 s + M4 ṡ (eq 11).
    M1,
    /// Modified twisting, s = ė + λe, integral term ν with K3 s + K4 ṡ (eq 13).
    M2,
}

/// Frame in which ρ, ρ̇ are expressed (see module docs).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum RhoFrame {
    /// Target orbital (Hill) frame: x radial out, y along-track, z orbit normal. The paper's
    /// F_o choice (up to chaser vs target orbit, ~µrad here); the axis order is inferred from
    /// Table 2, whose larger y gains (α1, α2, M3, M4) fit the along-track separation.
    TargetHill,
    /// Target body axes (the other reading of the paper's frame, \[derived\]).
    TargetBody,
}

/// Inertial state of one rigid body (any non-rotating Earth-centred frame, e.g. ECI).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BodyStateEci {
    /// Centre-of-mass position from the Earth's centre, ECI, m.
    pub pos_eci_m: Vector3<f64>,
    /// Centre-of-mass velocity, ECI, m/s.
    pub vel_eci_m_s: Vector3<f64>,
    /// Attitude: rotates body-frame vectors into ECI (so A = inertial→body DCM = its transpose).
    pub att_body_to_eci: UnitQuaternion<f64>,
    /// Angular velocity w.r.t. inertial space, body axes, rad/s.
    pub rate_body_rad_s: Vector3<f64>,
}

/// Observation handed to the controller (perfect state estimate, as in the paper §3.1).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Geng2015Obs {
    /// Time, s (used for the integral terms of T2/M2 and the ṡ difference).
    pub t_s: f64,
    /// Chaser (servicing spacecraft S).
    pub chaser: BodyStateEci,
    /// Target (non-cooperative tumbling spacecraft T).
    pub target: BodyStateEci,
}

/// Table 2 gains, one diagonal per vector (channels x, y, z of ρ then q_rv 1..3).
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Geng2015Gains {
    /// T1 α1 (m/s² | 1/s²).
    pub t1_alpha: [f64; 6],
    /// T1 β1.
    pub t1_beta: [f64; 6],
    /// T2 λ (1/s).
    pub t2_lambda: [f64; 6],
    /// T2 α2 (m/s³ | 1/s³).
    pub t2_alpha: [f64; 6],
    /// T2 β2.
    pub t2_beta: [f64; 6],
    /// M1 gain M1 (on sgn s).
    pub m1_m1: [f64; 6],
    /// M1 gain M2 (on sgn ṡ).
    pub m1_m2: [f64; 6],
    /// M1 gain M3 (on s, 1/s²).
    pub m1_m3: [f64; 6],
    /// M1 gain M4 (on ṡ, 1/s).
    pub m1_m4: [f64; 6],
    /// M2 λ (1/s).
    pub m2_lambda: [f64; 6],
    /// M2 K1 (on sgn s).
    pub m2_k1: [f64; 6],
    /// M2 K2 (on sgn ṡ).
    pub m2_k2: [f64; 6],
    /// M2 K3 (on s, 1/s²).
    pub m2_k3: [f64; 6],
    /// M2 K4 (on ṡ, 1/s).
    pub m2_k4: [f64; 6],
}

impl Geng2015Gains {
    /// Table 2 as printed. The extracted table shifts the row labels (λ, α2, β2 sit beside
    /// "T2"/"M1"; M1..M4 beside "M1"/"M2"); we read them in the order of eqs 5, 6, 11, 13.
    pub fn paper() -> Self {
        Self {
            t1_alpha: [0.020, 0.24, 0.020, 1.9e-3, 0.82e-3, 0.82e-3],
            t1_beta: [0.018, 0.23, 0.018, 1.6e-3, 0.72e-3, 0.72e-3],
            t2_lambda: [0.5; 6],
            t2_alpha: [0.080, 0.515, 0.080, 0.0095, 0.0084, 0.0084],
            t2_beta: [0.075, 0.510, 0.075, 0.0090, 0.0080, 0.0080],
            m1_m1: [6.0e-3, 6.0e-3, 6.0e-3, 3.5e-5, 8.2e-5, 6.0e-5],
            m1_m2: [5.0e-3, 5.0e-3, 5.0e-3, 2.0e-5, 7.5e-5, 4.0e-5],
            m1_m3: [0.06, 0.08, 0.06, 0.09, 0.1, 0.20],
            m1_m4: [0.50, 0.60, 0.50, 0.55, 0.4, 0.55],
            m2_lambda: [0.5; 6],
            m2_k1: [9.5e-2, 9.5e-2, 9.5e-2, 3.8e-4, 3.5e-4, 3.5e-4],
            m2_k2: [8.0e-2, 8.0e-2, 8.0e-2, 2.6e-4, 2.5e-4, 2.5e-4],
            m2_k3: [0.28, 0.28, 0.30, 0.3, 0.2, 0.2],
            m2_k4: [1.50, 1.60, 1.60, 1.5, 1.0, 1.0],
        }
    }

    /// (twisting α, twisting β) of a law: the gains the twisting condition α − D > β > D is
    /// about (α1/β1, α2/β2, M1/M2, K1/K2).
    pub fn twisting_pair(&self, law: Geng2015Law) -> (Vector6<f64>, Vector6<f64>) {
        let v = |a: &[f64; 6]| Vector6::from_column_slice(a);
        match law {
            Geng2015Law::T1 => (v(&self.t1_alpha), v(&self.t1_beta)),
            Geng2015Law::T2 => (v(&self.t2_alpha), v(&self.t2_beta)),
            Geng2015Law::M1 => (v(&self.m1_m1), v(&self.m1_m2)),
            Geng2015Law::M2 => (v(&self.m2_k1), v(&self.m2_k2)),
        }
    }
}

/// Plant and actuator parameters the controller uses (paper §3.1 values from `paper()`).
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Geng2015Params {
    /// Chaser mass m_s, kg.
    pub chaser_mass_kg: f64,
    /// Chaser inertia J_s about its CoM, body axes, kg·m².
    pub chaser_inertia_kg_m2: Matrix3<f64>,
    /// Target inertia J_t about its CoM, body axes, kg·m² (for the torque-free model in sys).
    pub target_inertia_kg_m2: Matrix3<f64>,
    /// Chaser docking port P_s in chaser body axes, m.
    pub chaser_port_body_m: Vector3<f64>,
    /// Target docking port P_t in target body axes, m.
    pub target_port_body_m: Vector3<f64>,
    /// Gravitational parameter used in sys, m³/s².
    pub mu_m3_s2: f64,
    /// Per-axis control acceleration limit a_max (force limit m_s·a_max), m/s².
    pub accel_max_m_s2: f64,
    /// Per-axis control torque limit T_max, N·m.
    pub torque_max_nm: f64,
    /// Frame of ρ, ρ̇.
    pub rho_frame: RhoFrame,
    /// Desired constant ρ_d (x_d = [ρ_d; 0]), m in `rho_frame`; zero = ports coincide.
    pub rho_des_m: Vector3<f64>,
    /// How T2/M2 obtain ṡ = ë + λė (not measured; the paper is silent).
    pub sdot_estimate: SdotEstimate,
    /// Table 2 gains.
    pub gains: Geng2015Gains,
}

/// Source of ṡ for the s = ė + λe laws (T2, M2).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum SdotEstimate {
    /// Backward difference of s between calls: the true ṡ = w + Δ (saturation included), one
    /// sample late.
    BackwardDifference,
    /// The model value ṡ = w (T2) or ν (M2), i.e. the commanded ṡ with Δ taken as zero.
    IntegralState,
}

impl Geng2015Params {
    /// Paper §3.1: m_s = 240 kg, J_s = diag(45.6, 47.3, 46.9), J_t = diag(67.6, 57.6, 57.6),
    /// P_s = [−0.75, 0, 0] m, P_t = [0.50, 0, 0] m, a_max = 0.2 m/s², T_max = 0.8 N·m.
    pub fn paper() -> Self {
        Self {
            chaser_mass_kg: 240.0,
            chaser_inertia_kg_m2: Matrix3::from_diagonal(&Vector3::new(45.6, 47.3, 46.9)),
            target_inertia_kg_m2: Matrix3::from_diagonal(&Vector3::new(67.6, 57.6, 57.6)),
            chaser_port_body_m: Vector3::new(-0.75, 0.0, 0.0),
            target_port_body_m: Vector3::new(0.50, 0.0, 0.0),
            mu_m3_s2: MU_EARTH_M3_S2,
            accel_max_m_s2: 0.2,
            torque_max_nm: 0.8,
            rho_frame: RhoFrame::TargetHill,
            rho_des_m: Vector3::zeros(),
            sdot_estimate: SdotEstimate::IntegralState,
            gains: Geng2015Gains::paper(),
        }
    }
}

/// Point-mass gravity acceleration at `pos_eci_m`, m/s².
pub fn gravity_m_s2(mu_m3_s2: f64, pos_eci_m: &Vector3<f64>) -> Vector3<f64> {
    let r = pos_eci_m.norm();
    -mu_m3_s2 / (r * r * r) * pos_eci_m
}

/// Target orbital (Hill) frame: x = r̂ (radial out), z = ĥ (orbit normal), y = z × x
/// (along-track). Returns (ECI→frame DCM, frame angular velocity in frame axes rad/s, its
/// Keplerian derivative rad/s²): ω = [0, 0, h/r²], ω̇ = [0, 0, −2h(r·v)/r⁴].
pub fn hill_frame(
    pos_eci_m: &Vector3<f64>,
    vel_eci_m_s: &Vector3<f64>,
) -> (Matrix3<f64>, Vector3<f64>, Vector3<f64>) {
    let h = pos_eci_m.cross(vel_eci_m_s);
    let r = pos_eci_m.norm();
    let x = pos_eci_m / r;
    let z = h.normalize();
    let y = z.cross(&x);
    let a = Matrix3::from_rows(&[x.transpose(), y.transpose(), z.transpose()]);
    let hn = h.norm();
    let w = Vector3::new(0.0, 0.0, hn / (r * r));
    let wdot = Vector3::new(0.0, 0.0, -2.0 * hn * pos_eci_m.dot(vel_eci_m_s) / r.powi(4));
    (a, w, wdot)
}

/// Port-to-port relative state and the pieces of the coupled model.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PortRelState {
    /// ρ: chaser port minus target port, in the ρ frame, m.
    pub rho_m: Vector3<f64>,
    /// ρ̇: derivative of ρ taken in the ρ frame, m/s.
    pub rho_dot_m_s: Vector3<f64>,
    /// q_r = q_t⁻¹ ⊗ q_s (chaser w.r.t. target), canonical q_r0 ≥ 0.
    pub q_r: UnitQuaternion<f64>,
    /// ω_r = ω_s − A(q_r) ω_t, chaser axes, rad/s.
    pub omega_r_rad_s: Vector3<f64>,
    /// A(q_r) = A_s A_tᵀ (target axes → chaser axes).
    pub a_r: Matrix3<f64>,
    /// A_F: ECI → ρ frame.
    pub a_f: Matrix3<f64>,
    /// ρ-frame angular velocity w.r.t. inertial, ρ-frame axes, rad/s.
    pub omega_f_rad_s: Vector3<f64>,
    /// Its model derivative, rad/s².
    pub omega_f_dot_rad_s2: Vector3<f64>,
}

impl PortRelState {
    /// x = [ρ; q_rv].
    pub fn x(&self) -> Vector6<f64> {
        let v = self.q_r.imag();
        Vector6::new(self.rho_m.x, self.rho_m.y, self.rho_m.z, v.x, v.y, v.z)
    }
    /// ẋ = [ρ̇; G ω_r].
    pub fn x_dot(&self) -> Vector6<f64> {
        let qd = g_matrix(&self.q_r) * self.omega_r_rad_s;
        let r = self.rho_dot_m_s;
        Vector6::new(r.x, r.y, r.z, qd.x, qd.y, qd.z)
    }
}

/// G = ½(q_r0 I + [q_rv×]) (q̇_rv = G ω_r).
pub fn g_matrix(q_r: &UnitQuaternion<f64>) -> Matrix3<f64> {
    0.5 * (Matrix3::identity() * q_r.w + skew(&q_r.imag()))
}

/// G⁻¹ = 2(q0 I − [v×] + v vᵀ/q0) for a unit quaternion, with q0 floored at [`Q_R0_FLOOR`].
pub fn g_inverse(q_r: &UnitQuaternion<f64>) -> Matrix3<f64> {
    let v = q_r.imag();
    let q0 = if q_r.w.abs() < Q_R0_FLOOR {
        Q_R0_FLOOR.copysign(if q_r.w == 0.0 { 1.0 } else { q_r.w })
    } else {
        q_r.w
    };
    2.0 * (Matrix3::identity() * q0 - skew(&v) + v * v.transpose() / q0)
}

/// Port-to-port relative state from the two inertial body states (module docs for definitions).
pub fn relative_state(p: &Geng2015Params, obs: &Geng2015Obs) -> PortRelState {
    let (s, t) = (&obs.chaser, &obs.target);
    let a_s = s
        .att_body_to_eci
        .to_rotation_matrix()
        .into_inner()
        .transpose();
    let a_t = t
        .att_body_to_eci
        .to_rotation_matrix()
        .into_inner()
        .transpose();
    let (ws, wt) = (s.rate_body_rad_s, t.rate_body_rad_s);
    let (ps, pt) = (p.chaser_port_body_m, p.target_port_body_m);
    let rho_i = s.pos_eci_m + a_s.transpose() * ps - t.pos_eci_m - a_t.transpose() * pt;
    let rho_i_dot = s.vel_eci_m_s + a_s.transpose() * ws.cross(&ps)
        - t.vel_eci_m_s
        - a_t.transpose() * wt.cross(&pt);
    let (a_f, w_f, w_f_dot) = match p.rho_frame {
        RhoFrame::TargetHill => hill_frame(&t.pos_eci_m, &t.vel_eci_m_s),
        RhoFrame::TargetBody => {
            let jt = p.target_inertia_kg_m2;
            let jt_inv = jt.try_inverse().unwrap_or_else(Matrix3::zeros);
            (a_t, wt, -(jt_inv * wt.cross(&(jt * wt))))
        }
    };
    let rho = a_f * rho_i;
    let rho_dot = a_f * rho_i_dot - w_f.cross(&rho);
    let mut q_r = t.att_body_to_eci.inverse() * s.att_body_to_eci;
    if q_r.w < 0.0 {
        q_r = UnitQuaternion::new_unchecked(-q_r.into_inner());
    }
    let a_r = a_s * a_t.transpose();
    PortRelState {
        rho_m: rho,
        rho_dot_m_s: rho_dot,
        q_r,
        omega_r_rad_s: ws - a_r * wt,
        a_r,
        a_f,
        omega_f_rad_s: w_f,
        omega_f_dot_rad_s2: w_f_dot,
    }
}

/// The coupled model ë = sys + B u (+ Δ): returns (relative state, sys, B) with sys in
/// [m/s²; 1/s²] and u = [F_body_N; T_body_Nm].
pub fn port_model(
    p: &Geng2015Params,
    obs: &Geng2015Obs,
) -> (PortRelState, Vector6<f64>, Matrix6<f64>) {
    let rel = relative_state(p, obs);
    let (s, t) = (&obs.chaser, &obs.target);
    let a_s = s
        .att_body_to_eci
        .to_rotation_matrix()
        .into_inner()
        .transpose();
    let a_t = t
        .att_body_to_eci
        .to_rotation_matrix()
        .into_inner()
        .transpose();
    let (ws, wt) = (s.rate_body_rad_s, t.rate_body_rad_s);
    let (ps, pt) = (p.chaser_port_body_m, p.target_port_body_m);
    let (js, jt) = (p.chaser_inertia_kg_m2, p.target_inertia_kg_m2);
    let js_inv = js.try_inverse().unwrap_or_else(Matrix3::zeros);
    let jt_inv = jt.try_inverse().unwrap_or_else(Matrix3::zeros);
    let ws_dot0 = -(js_inv * ws.cross(&(js * ws)));
    let wt_dot0 = -(jt_inv * wt.cross(&(jt * wt)));
    let (rho, rho_dot, w_f, w_f_dot) = (
        rel.rho_m,
        rel.rho_dot_m_s,
        rel.omega_f_rad_s,
        rel.omega_f_dot_rad_s2,
    );
    // Translation (ρ frame).
    let acc_i = gravity_m_s2(p.mu_m3_s2, &s.pos_eci_m) - gravity_m_s2(p.mu_m3_s2, &t.pos_eci_m)
        + a_s.transpose() * (ws_dot0.cross(&ps) + ws.cross(&ws.cross(&ps)))
        - a_t.transpose() * (wt_dot0.cross(&pt) + wt.cross(&wt.cross(&pt)));
    let sys_t = rel.a_f * acc_i
        - 2.0 * w_f.cross(&rho_dot)
        - w_f_dot.cross(&rho)
        - w_f.cross(&w_f.cross(&rho));
    // Rotation (q_rv).
    let g = g_matrix(&rel.q_r);
    let qv = rel.q_r.imag();
    let wr = rel.omega_r_rad_s;
    let awt = rel.a_r * wt;
    let sys_r = -0.25 * wr.norm_squared() * qv + g * (ws_dot0 + wr.cross(&awt) - rel.a_r * wt_dot0);
    let sys = Vector6::new(sys_t.x, sys_t.y, sys_t.z, sys_r.x, sys_r.y, sys_r.z);
    let a_fs = rel.a_f * a_s.transpose();
    let mut b = Matrix6::zeros();
    b.fixed_view_mut::<3, 3>(0, 0)
        .copy_from(&(a_fs / p.chaser_mass_kg));
    b.fixed_view_mut::<3, 3>(0, 3)
        .copy_from(&(-(a_fs * skew(&ps) * js_inv)));
    b.fixed_view_mut::<3, 3>(3, 3).copy_from(&(g * js_inv));
    (rel, sys, b)
}

/// Closed-form B⁻¹ = [[m_s A_Fsᵀ, m_s[p_s×]G⁻¹], [0, J_s G⁻¹]] (G⁻¹ floored, see
/// [`g_inverse`]); `a_fs` = A_F A_sᵀ.
pub fn b_inverse(
    p: &Geng2015Params,
    a_fs: &Matrix3<f64>,
    q_r: &UnitQuaternion<f64>,
) -> Matrix6<f64> {
    let gi = g_inverse(q_r);
    let m = p.chaser_mass_kg;
    let mut bi = Matrix6::zeros();
    bi.fixed_view_mut::<3, 3>(0, 0)
        .copy_from(&(m * a_fs.transpose()));
    bi.fixed_view_mut::<3, 3>(0, 3)
        .copy_from(&(m * skew(&p.chaser_port_body_m) * gi));
    bi.fixed_view_mut::<3, 3>(3, 3)
        .copy_from(&(p.chaser_inertia_kg_m2 * gi));
    bi
}

/// Per-channel diagnostics of the last command.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Geng2015Diag {
    /// Tracking error e = x − x_d, [m; –].
    pub e: Vector6<f64>,
    /// ė, [m/s; 1/s].
    pub e_dot: Vector6<f64>,
    /// Sliding variable s (e for T1/M1, ė + λe for T2/M2).
    pub s: Vector6<f64>,
    /// ṡ used in the switching terms (ė for T1/M1; backward difference of s for T2/M2).
    pub s_dot: Vector6<f64>,
    /// Integral state w (T2) or ν (M2), [m/s²; 1/s²]; zero for T1/M1.
    pub integral: Vector6<f64>,
    /// Commanded u = [F; T] before saturation, chaser body, [N; N·m].
    pub u_unsat: Vector6<f64>,
    /// Applied u after per-axis saturation, [N; N·m].
    pub u: Vector6<f64>,
}

/// One of T1/T2/M1/M2 (twisting and modified twisting) with its integral state: the law itself,
/// called by the scene binding [`Geng2015Loop`] (which is the
/// [`Controller`](crate::control::Controller)).
#[derive(Debug, Clone)]
pub struct Geng2015Twisting {
    /// Which law.
    pub law: Geng2015Law,
    /// Parameters.
    pub params: Geng2015Params,
    integral: Vector6<f64>,
    last: Option<(f64, Vector6<f64>)>,
    diag: Geng2015Diag,
}

impl Geng2015Twisting {
    /// New controller with zero integral state.
    pub fn new(law: Geng2015Law, params: Geng2015Params) -> Self {
        Self {
            law,
            params,
            integral: Vector6::zeros(),
            last: None,
            diag: Geng2015Diag::default(),
        }
    }

    /// Clear the integral state and the ṡ memory.
    pub fn reset(&mut self) {
        self.integral = Vector6::zeros();
        self.last = None;
    }

    /// Diagnostics of the last [`Self::command`].
    pub fn diagnostics(&self) -> &Geng2015Diag {
        &self.diag
    }

    /// Command (force_body_n, torque_body_nm) in chaser body axes, saturated per axis at
    /// m_s·a_max and T_max (the paper's a·a_max/|a| rule on a saturated axis).
    ///
    /// x_d is constant (ẋ_d = ẍ_d = 0). For T2/M2, ṡ comes from `params.sdot_estimate` (the
    /// difference needs a previous call; the first call uses w or ν); the integral state is
    /// advanced by backward Euler over the interval since the previous call (none on the first
    /// call or if `obs.t_s` did not advance).
    pub fn command(&mut self, obs: &Geng2015Obs) -> (Vector3<f64>, Vector3<f64>) {
        let p = &self.params;
        let g = &p.gains;
        let d6 = |a: &[f64; 6]| Matrix6::from_diagonal(&Vector6::from_column_slice(a));
        let (rel, sys, _b) = port_model(p, obs);
        let mut x_d = Vector6::zeros();
        x_d.fixed_rows_mut::<3>(0).copy_from(&p.rho_des_m);
        let e = rel.x() - x_d;
        let e_dot = rel.x_dot();
        let dt = self.last.map(|(t, _)| obs.t_s - t).unwrap_or(0.0);
        let (s, s_dot, v) = match self.law {
            Geng2015Law::T1 | Geng2015Law::M1 => {
                let v = if self.law == Geng2015Law::T1 {
                    -d6(&g.t1_alpha) * sgn6(&e) - d6(&g.t1_beta) * sgn6(&e_dot)
                } else {
                    -d6(&g.m1_m1) * sgn6(&e)
                        - d6(&g.m1_m2) * sgn6(&e_dot)
                        - d6(&g.m1_m3) * e
                        - d6(&g.m1_m4) * e_dot
                };
                (e, e_dot, -sys + v)
            }
            Geng2015Law::T2 | Geng2015Law::M2 => {
                let lam = if self.law == Geng2015Law::T2 {
                    d6(&g.t2_lambda)
                } else {
                    d6(&g.m2_lambda)
                };
                let s = e_dot + lam * e;
                let s_dot = match (p.sdot_estimate, self.last) {
                    (SdotEstimate::BackwardDifference, Some((_, s_prev))) if dt > 0.0 => {
                        (s - s_prev) / dt
                    }
                    _ => self.integral,
                };
                let rate = if self.law == Geng2015Law::T2 {
                    -d6(&g.t2_alpha) * sgn6(&s) - d6(&g.t2_beta) * sgn6(&s_dot)
                } else {
                    -d6(&g.m2_k1) * sgn6(&s)
                        - d6(&g.m2_k2) * sgn6(&s_dot)
                        - d6(&g.m2_k3) * s
                        - d6(&g.m2_k4) * s_dot
                };
                if dt > 0.0 {
                    self.integral += dt * rate;
                }
                (s, s_dot, -sys - lam * e_dot + self.integral)
            }
        };
        if dt > 0.0 || self.last.is_none() {
            self.last = Some((obs.t_s, s));
        }
        let a_s = obs
            .chaser
            .att_body_to_eci
            .to_rotation_matrix()
            .into_inner()
            .transpose();
        let bi = b_inverse(p, &(rel.a_f * a_s.transpose()), &rel.q_r);
        let u_unsat = bi * v;
        let f_max = p.chaser_mass_kg * p.accel_max_m_s2;
        let u = Vector6::from_fn(|i, _| {
            let lim = if i < 3 { f_max } else { p.torque_max_nm };
            u_unsat[i].clamp(-lim, lim)
        });
        self.diag = Geng2015Diag {
            e,
            e_dot,
            s,
            s_dot,
            integral: self.integral,
            u_unsat,
            u,
        };
        (
            Vector3::new(u[0], u[1], u[2]),
            Vector3::new(u[3], u[4], u[5]),
        )
    }
}

// ---------------------------------------------------------------------------------------------
// Disturbances (paper §1, §3.1) and the twisting bounds of §2.1–2.3.
// ---------------------------------------------------------------------------------------------

/// Time profile of a disturbance acceleration a_d (paper §1).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum AccelDisturbanceForm {
    /// a_d0 (1 + k_d t): "bounded linear growth" in the paper, but no bound is given, so it
    /// grows without limit here (×101 at 200 s with k_d = 0.5).
    Linear,
    /// a_d0 [1 + cos(k_d t)].
    Cosine,
    /// a_d0 [1 + sin(k_d t)].
    Sine,
}

/// a_d(t) in the body axes of the body it acts on, m/s².
pub fn accel_disturbance_m_s2(
    form: AccelDisturbanceForm,
    a_d0_m_s2: &Vector3<f64>,
    k_d_per_s: f64,
    t_s: f64,
) -> Vector3<f64> {
    let f = match form {
        AccelDisturbanceForm::Linear => 1.0 + k_d_per_s * t_s,
        AccelDisturbanceForm::Cosine => 1.0 + (k_d_per_s * t_s).cos(),
        AccelDisturbanceForm::Sine => 1.0 + (k_d_per_s * t_s).sin(),
    };
    a_d0_m_s2 * f
}

/// T_d(t) = scale·[3cos(ω°t)+1, 1.5 sin(ω°t)+3cos(ω°t), 3 sin(ω°t)+1] N·m, body axes (paper
/// scale 1.5e−5; ω° = orbital rate, we use the mean motion).
pub fn torque_disturbance_nm(scale_nm: f64, omega_orbit_rad_s: f64, t_s: f64) -> Vector3<f64> {
    let (s, c) = (omega_orbit_rad_s * t_s).sin_cos();
    scale_nm * Vector3::new(3.0 * c + 1.0, 1.5 * s + 3.0 * c, 3.0 * s + 1.0)
}

/// Gravity-gradient torque T_g = 3μ/r³ Z0 × J Z0 in body axes (Z0 = unit geocentric vector in
/// body axes), N·m.
pub fn gravity_gradient_torque_nm(
    mu_m3_s2: f64,
    pos_eci_m: &Vector3<f64>,
    att_body_to_eci: &UnitQuaternion<f64>,
    inertia_kg_m2: &Matrix3<f64>,
) -> Vector3<f64> {
    let r = pos_eci_m.norm();
    let z0 = att_body_to_eci.inverse_transform_vector(&(pos_eci_m / r));
    3.0 * mu_m3_s2 / (r * r * r) * z0.cross(&(inertia_kg_m2 * z0))
}

/// The paper's disturbance set (§3.1): a_d forms and amplitudes, T_d, T_g on both bodies.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Geng2015Disturbances {
    /// k_d, 1/s (paper 0.5).
    pub k_d_per_s: f64,
    /// a_td0, target body axes, m/s².
    pub target_accel0_m_s2: Vector3<f64>,
    /// a_sd0, chaser body axes, m/s².
    pub chaser_accel0_m_s2: Vector3<f64>,
    /// Form of a_td.
    pub target_form: AccelDisturbanceForm,
    /// Form of a_sd.
    pub chaser_form: AccelDisturbanceForm,
    /// Scale of T_d, N·m (paper 1.5e−5), applied to both bodies.
    pub torque_scale_nm: f64,
    /// ω° in T_d, rad/s.
    pub omega_orbit_rad_s: f64,
}

impl Geng2015Disturbances {
    /// Table 3 first case: a_d = a_d0(1 + 0.5 t) on both bodies.
    pub fn paper_linear(omega_orbit_rad_s: f64) -> Self {
        Self {
            k_d_per_s: 0.5,
            target_accel0_m_s2: Vector3::new(2.5e-5, 4.0e-5, 3.8e-5),
            chaser_accel0_m_s2: Vector3::new(2.0e-5, 4.2e-5, 3.5e-5),
            target_form: AccelDisturbanceForm::Linear,
            chaser_form: AccelDisturbanceForm::Linear,
            torque_scale_nm: 1.5e-5,
            omega_orbit_rad_s,
        }
    }
    /// Table 3 second case: a_td = a_td0[1 + cos 0.5t], a_sd = a_sd0[1 + sin 0.5t].
    pub fn paper_periodic(omega_orbit_rad_s: f64) -> Self {
        Self {
            target_form: AccelDisturbanceForm::Cosine,
            chaser_form: AccelDisturbanceForm::Sine,
            ..Self::paper_linear(omega_orbit_rad_s)
        }
    }
    /// (accel m/s², torque N·m) on the target at time t, target body axes (T_td + T_tg).
    pub fn target(
        &self,
        mu: f64,
        p: &Geng2015Params,
        t_s: f64,
        b: &BodyStateEci,
    ) -> (Vector3<f64>, Vector3<f64>) {
        let a = accel_disturbance_m_s2(
            self.target_form,
            &self.target_accel0_m_s2,
            self.k_d_per_s,
            t_s,
        );
        let tq = torque_disturbance_nm(self.torque_scale_nm, self.omega_orbit_rad_s, t_s)
            + gravity_gradient_torque_nm(
                mu,
                &b.pos_eci_m,
                &b.att_body_to_eci,
                &p.target_inertia_kg_m2,
            );
        (a, tq)
    }
    /// (accel m/s², torque N·m) on the chaser at time t, chaser body axes (T_sd + T_sg).
    pub fn chaser(
        &self,
        mu: f64,
        p: &Geng2015Params,
        t_s: f64,
        b: &BodyStateEci,
    ) -> (Vector3<f64>, Vector3<f64>) {
        let a = accel_disturbance_m_s2(
            self.chaser_form,
            &self.chaser_accel0_m_s2,
            self.k_d_per_s,
            t_s,
        );
        let tq = torque_disturbance_nm(self.torque_scale_nm, self.omega_orbit_rad_s, t_s)
            + gravity_gradient_torque_nm(
                mu,
                &b.pos_eci_m,
                &b.att_body_to_eci,
                &p.chaser_inertia_kg_m2,
            );
        (a, tq)
    }
}

/// Δ of ë = sys + B u + Δ produced by disturbance accelerations/torques (each in its own body
/// axes) — the paper's δ = [ϑ1; ϑ2] (eqs 2–3) in our sign convention.
pub fn disturbance_effect(
    p: &Geng2015Params,
    obs: &Geng2015Obs,
    chaser_accel_body_m_s2: &Vector3<f64>,
    chaser_torque_body_nm: &Vector3<f64>,
    target_accel_body_m_s2: &Vector3<f64>,
    target_torque_body_nm: &Vector3<f64>,
) -> Vector6<f64> {
    let rel = relative_state(p, obs);
    let js_inv = p
        .chaser_inertia_kg_m2
        .try_inverse()
        .unwrap_or_else(Matrix3::zeros);
    let jt_inv = p
        .target_inertia_kg_m2
        .try_inverse()
        .unwrap_or_else(Matrix3::zeros);
    let rs = obs.chaser.att_body_to_eci.to_rotation_matrix().into_inner();
    let rt = obs.target.att_body_to_eci.to_rotation_matrix().into_inner();
    let ws = js_inv * chaser_torque_body_nm;
    let wt = jt_inv * target_torque_body_nm;
    let mut dt = rel.a_f
        * (rs * (chaser_accel_body_m_s2 + ws.cross(&p.chaser_port_body_m))
            - rt * (target_accel_body_m_s2 + wt.cross(&p.target_port_body_m)));
    if p.rho_frame == RhoFrame::TargetBody {
        // The ρ frame itself is spun up by the target torque: the −ω̇_F × ρ term.
        dt -= wt.cross(&rel.rho_m);
    }
    let dr = g_matrix(&rel.q_r) * (ws - rel.a_r * wt);
    Vector6::new(dt.x, dt.y, dt.z, dr.x, dr.y, dr.z)
}

/// Per-channel bounds of Δ (D, used by T1/M1 whose closed loop sees δ itself, eq 12) and of
/// its derivative (χ, used by T2/M2 whose closed loop sees δ̇, eqs 7 and 14).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DisturbanceBounds {
    /// D_i ≥ |δ_i| over the horizon, [m/s²; 1/s²].
    pub d: Vector6<f64>,
    /// χ_i ≥ |δ̇_i| over the horizon, [m/s³; 1/s³].
    pub chi: Vector6<f64>,
}

/// Rate and orbit envelope the bounds assume.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BoundEnvelope {
    /// Horizon over which the linear a_d is bounded, s.
    pub horizon_s: f64,
    /// Semi-major axis, m, and eccentricity of the (common) orbit: r_min, ṙ_max, θ̇_max.
    pub semi_major_axis_m: f64,
    /// Eccentricity.
    pub eccentricity: f64,
    /// Largest |ω_s|, rad/s.
    pub chaser_rate_max_rad_s: f64,
    /// Largest |ω_t|, rad/s.
    pub target_rate_max_rad_s: f64,
    /// Largest |ρ|, m (enters only with [`RhoFrame::TargetBody`]: −J_t⁻¹T_t × ρ).
    pub rho_max_m: f64,
    /// Largest |ρ̇|, m/s (same).
    pub rho_dot_max_m_s: f64,
}

/// Conservative bounds D, χ (our reconstruction of the paper's |ϑ̇|_max, which mixes vectors
/// and maxima): any component of a rotated vector is bounded by its norm, |J⁻¹T| ≤ |T|/λ_min(J),
/// |T_g| ≤ 3μ/r³ (λ_max−λ_min)/2 and |Ṫ_g| ≤ 3μ/r³ (λ_max−λ_min)(|ω| + θ̇) + 9μṙ/r⁴ (λ_max−λ_min)/2.
/// The same value is returned for the three translational and the three rotational channels.
pub fn disturbance_bounds(
    p: &Geng2015Params,
    dist: &Geng2015Disturbances,
    env: &BoundEnvelope,
) -> DisturbanceBounds {
    let mu = p.mu_m3_s2;
    let (a, e) = (env.semi_major_axis_m, env.eccentricity);
    let r_min = a * (1.0 - e);
    let slr = a * (1.0 - e * e);
    let h = (mu * slr).sqrt();
    let rdot_max = (mu / slr).sqrt() * e;
    let thdot_max = h / (r_min * r_min);
    let kd = dist.k_d_per_s.abs();
    let acc = |form: AccelDisturbanceForm, a0: &Vector3<f64>| match form {
        AccelDisturbanceForm::Linear => (a0.norm() * (1.0 + kd * env.horizon_s), a0.norm() * kd),
        _ => (2.0 * a0.norm(), a0.norm() * kd),
    };
    let (as_max, as_dot) = acc(dist.chaser_form, &dist.chaser_accel0_m_s2);
    let (at_max, at_dot) = acc(dist.target_form, &dist.target_accel0_m_s2);
    let sc = dist.torque_scale_nm;
    let w0 = dist.omega_orbit_rad_s.abs();
    let td_max = sc * (16.0f64 + 11.25 + 16.0).sqrt();
    let td_dot = sc * w0 * (9.0f64 + 11.25 + 9.0).sqrt();
    let torque = |j: &Matrix3<f64>, rate: f64| {
        let ev = j.symmetric_eigenvalues();
        let spread = ev.max() - ev.min();
        let k = 3.0 * mu / r_min.powi(3);
        let tg = k * spread / 2.0;
        let tg_dot = k * spread * (rate + thdot_max) + k * 3.0 * rdot_max / r_min * spread / 2.0;
        (td_max + tg, td_dot + tg_dot, 1.0 / ev.min())
    };
    let (ts, ts_dot, js_inv) = torque(&p.chaser_inertia_kg_m2, env.chaser_rate_max_rad_s);
    let (tt, tt_dot, jt_inv) = torque(&p.target_inertia_kg_m2, env.target_rate_max_rad_s);
    let (ps, pt) = (p.chaser_port_body_m.norm(), p.target_port_body_m.norm());
    let (frame_rate, target_rot) = match p.rho_frame {
        RhoFrame::TargetHill => (thdot_max, env.target_rate_max_rad_s + thdot_max),
        RhoFrame::TargetBody => (env.target_rate_max_rad_s, 0.0),
    };
    let chaser_rot = env.chaser_rate_max_rad_s + frame_rate;
    let xs = as_max + ps * js_inv * ts;
    let xt = at_max + pt * jt_inv * tt;
    let (frame_d, frame_chi) = match p.rho_frame {
        RhoFrame::TargetHill => (0.0, 0.0),
        RhoFrame::TargetBody => (
            jt_inv * tt * env.rho_max_m,
            jt_inv * (tt_dot * env.rho_max_m + tt * env.rho_dot_max_m_s),
        ),
    };
    let d_t = xs + xt + frame_d;
    let chi_t = frame_chi
        + as_dot
        + ps * js_inv * ts_dot
        + chaser_rot * xs
        + at_dot
        + pt * jt_inv * tt_dot
        + target_rot * xt;
    let wr = env.chaser_rate_max_rad_s + env.target_rate_max_rad_s;
    let d_r = 0.5 * (js_inv * ts + jt_inv * tt);
    let chi_r = 0.25 * wr * (js_inv * ts + jt_inv * tt)
        + 0.5 * (js_inv * ts_dot + jt_inv * tt_dot + wr * jt_inv * tt);
    DisturbanceBounds {
        d: Vector6::new(d_t, d_t, d_t, d_r, d_r, d_r),
        chi: Vector6::new(chi_t, chi_t, chi_t, chi_r, chi_r, chi_r),
    }
}

/// Twisting finite-time condition per channel, α_i − D_i > β_i > D_i (§2.1).
pub fn twisting_condition(
    alpha: &Vector6<f64>,
    beta: &Vector6<f64>,
    bound: &Vector6<f64>,
) -> [bool; 6] {
    std::array::from_fn(|i| alpha[i] - bound[i] > beta[i] && beta[i] > bound[i])
}

fn sym2_eigs(a: f64, b: f64, c: f64) -> (f64, f64) {
    let m = 0.5 * (a + c);
    let r = (0.25 * (a - c) * (a - c) + b * b).sqrt();
    (m - r, m + r)
}

/// The strict Lyapunov function W(x, y) of eq (9) for ẋ = y, ẏ = −α sgn x − β sgn y − r1 x −
/// r2 y + μ.
pub fn lyapunov_w(alpha: f64, gamma: f64, r1: f64, r2: f64, x: f64, y: f64) -> f64 {
    let a = 2f64.sqrt() / 6.0 * r1.sqrt() * r2;
    let b = r1.sqrt() / 2f64.sqrt();
    let c = r1 * r2 * r2 / 36.0 + 0.25 * r1 * r1;
    let ax = x.abs();
    let v = alpha * alpha * x * x
        + gamma * ax.powf(1.5) * sgn(x) * y
        + alpha * ax * y * y
        + 0.25 * y.powi(4);
    v + (a * x * x + b * x * y).powi(2)
        + c * x.powi(4)
        + alpha * r1 * ax.powi(3)
        + 0.4 * gamma * r2 * ax.powf(2.5)
}

/// Eq (10): T_f = 4 H_max^{3/4} / H_min · W^{1/4}(x0, y0), s, for the modified twisting loop (8)
/// with |μ| ≤ D. `None` when the premises fail: α − β − D > 0, β > D, r1, r2 > 0,
/// 0 < γ < 4√2/3 (β − D)√α and P0 = [[α², γ/2], [γ/2, α]] positive definite.
#[allow(clippy::too_many_arguments)]
pub fn convergence_time_bound_s(
    alpha: f64,
    beta: f64,
    d: f64,
    gamma: f64,
    r1: f64,
    r2: f64,
    x0: f64,
    y0: f64,
) -> Option<f64> {
    let ok = alpha - beta - d > 0.0
        && beta > d
        && r1 > 0.0
        && r2 > 0.0
        && gamma > 0.0
        && gamma < 4.0 * 2f64.sqrt() / 3.0 * (beta - d) * alpha.sqrt()
        && alpha.powi(3) > 0.25 * gamma * gamma;
    if !ok {
        return None;
    }
    let (_, p0_max) = sym2_eigs(alpha * alpha, 0.5 * gamma, alpha);
    let (q_min, _) = sym2_eigs(2.0 * alpha * (beta - d), -0.75 * gamma, beta - d);
    if q_min <= 0.0 {
        return None;
    }
    let h_max = [
        p0_max + gamma * r2 / 5.0,
        r1 * r2 * r2 / 12.0 + 0.25 * r1 * r1 + r1 * r2 / 6.0,
        0.25,
        0.5 * alpha * r1 + 0.1 * gamma * r2,
        0.25 * r1 + r1 * r2 / 12.0,
    ]
    .into_iter()
    .fold(f64::MIN, f64::max);
    let g = alpha - beta - d;
    let h_min = [
        gamma * g / 15.0,
        r1 * r2 * g / 3.0,
        q_min / 12.0,
        gamma * r1 / 15.0,
        r1 * (beta - d) / 3.0,
        4.0 * alpha * r2 / 15.0,
    ]
    .into_iter()
    .fold(f64::MAX, f64::min);
    Some(4.0 * h_max.powf(0.75) / h_min * lyapunov_w(alpha, gamma, r1, r2, x0, y0).powf(0.25))
}

// The scene binding (scene entry, `LawSpec`, disturbances, the simulation adapter) and the
// tests live in their own files; every public item stays reachable at its old path.
mod scene;
pub use scene::*;

#[cfg(test)]
mod tests;
