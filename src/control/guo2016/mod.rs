//! Guo, Song, Li (2016), "Attitude and orbit coupled control for non-cooperative rendezvous and
//! docking", Control Theory & Applications: coupled attitude–orbit sliding-mode control with an
//! elliptic-cissoid approach corridor.
//!
//! # Model (eqs 6–28), as implemented
//! State `x = [σ_e; r_e]` (MRP, m), in the **chaser body frame** B:
//! `M ẍ + C ẋ + g = B1 u + B2 d`, `u = [τ; F]` (chaser-body torque N·m, force N).
//! - Attitude (eqs 19–23): `M1 = G⁻ᵀJG⁻¹`,
//!   `C1 = G⁻ᵀ[−(JG⁻¹σ̇_e)×G⁻¹ + J·d(G⁻¹)/dt] + G⁻ᵀ[J ω_r× + ω_r×J − (Jω_r)×]G⁻¹`,
//!   `N1 = G⁻ᵀ(ω_r×Jω_r + J R(σ_e) ω̇_d)`, `ω_r = R(σ_e) ω_d`, all `G = G(σ_e)`.
//!   The paper writes `−G⁻ᵀ[… + J Ġ⁻¹]`; with `Ġ⁻¹ := d(G⁻¹)/dt` the sign is `+` (rederived
//!   from `Jω̇ = −ω×Jω + τ + d_τ`, eq 13; `Ṁ − 2C` skew-symmetric and the model-vs-plant test
//!   confirm it).
//! - Translation (eqs 5–9, 26–27): `M2 = m I`, `C2 = m A(ω) = 2m ω×`,
//!   `g2 = m(D(ω)(r_e + r_d) + f_b)`, `D(ω) = ω×ω× + ω̇×` (the matrix of eq 8; the middle
//!   expression of eq 8 has a sign typo). `ω`, `ω̇`: chaser inertial rate/acceleration, body axes.
//!
//! # Frames and signs (the paper is ambiguous; these are choices)
//! - World = inertial axes (the simulation's world frame).
//! - `r_b` is the **target position relative to the chaser** (`r_t − r_c`, line of sight) in
//!   chaser body axes, so that the paper's `r_d = [2, 0, 0]` m means "the target centre 2 m
//!   ahead on the chaser's docking axis +x_b". Relative to the paper's `r = r_c − r_t` this flips
//!   the sign of `f_b`, `F_b`, `d_b` in eq (5): here `g2 = m(D r_b + f_b)` and the translation
//!   block of `B1 = B2` is `−I` (eq 28 has `+I`). `f_b` is the differential gravity at the
//!   chaser, `g(r_c) − g(r_t)`, in chaser axes (from the observation).
//! - `σ` is the chaser attitude relative to the **docking reference frame D0**: the target body
//!   frame turned by π about target `z` (`x_D0 = −x_t`, `y_D0 = −y_t`, `z_D0 = z_t`). The
//!   paper's `σ_d(t)` (≈ 0) is the desired attitude relative to D0, so at `σ_e = 0`,
//!   `r_e = 0` the chaser sits on the target docking axis (+x_t) 2 m out with its docking port
//!   (+x_b) facing the target. The paper takes σ, σ_d relative to inertial space; the two agree
//!   for an inertially fixed target. For a rotating target, `ω_d` includes the target rate
//!   (from the observation), but `ω̇_d` neglects the target's angular acceleration.
//! - Corridor (eqs 31, 34): `h(r1)` with `r1` the chaser position in target body axes (the
//!   paper's `r1 = R_0^b r_b` for its `r = r_c − r_t`), `ṙ1` its rate seen in the target frame.
//!
//! # Control (eqs 32–33)
//! `S = k1 x + β ẋ`, `β = k2/h² + k3`, `β̇ = −2 k2 ḣ/h³` (analytic `ḣ`),
//! `u = B1⁻¹[Cẋ + g − β⁻¹(k1 Mẋ + β̇ Mẋ + ½ṀS + k_r M S) − k4‖B2‖ sat(S/ε)]`,
//! with `sgn` replaced by the component-wise saturation of boundary-layer width ε (Section 5),
//! `‖B2‖ = 4/(1+|σ_e|²)` its exact spectral norm, and `k_r` an optional linear reaching gain that
//! is **not in the paper** (`paper()` sets it to 0). The closed loop is
//! `MṠ = −½ṀS − k_r M S − β k4‖B2‖sat(S/ε) + β B2 d` (the `k_r` term is divided by β so that
//! its rate does not grow without bound near the wall, which would make any fixed step unstable).
//! `ω̇` inside `g2` is the chaser angular acceleration the commanded torque produces,
//! `J⁻¹(τ − ω×Jω)` (the disturbance torque is unknown): the attitude command is computed
//! first, then the force (this is where the coupling enters).
//! Outside the corridor (`h ≤ 0` or `r1x ∉ (0, 2a)`) the paper's law is undefined; there the
//! barrier is switched off (`β = k3`, `β̇ = 0`) and [`Guo2016Diagnostics::inside`] is false.
//!
//! # Findings (see the tests for the numbers)
//! - With the paper's gains the errors do not converge: the reaching rate of each translational
//!   S component is at most `β k4‖B2‖/m ≈ 2e-4 m/s²` against `|S(0)| ≈ 400 m/s`, so the state
//!   settles on `x ≈ S(0)/k1` (the chaser brakes within ~0.5 s and stays ~44 m from `r_d`).
//!   The disturbance torque also enters the translation rows through `ω̇×r_b`
//!   (`m|r_b||J⁻¹d_τ| ≈ 0.8 N > k4`), which the proof's condition `k4 > ‖d‖` ignores.
//! - `k2/h²` matters only for `h ≲ √k2 ≈ 0.14 m²`, a sub-millimetre layer at the wall: with
//!   the paper's gains k2 = 0.02 and k2 = 0 give the same trajectory (both stay inside). β is
//!   a scalar on the whole error velocity: it slows the chaser, it cannot steer it. With a
//!   reaching gain that makes S → 0, the law sampled at 100 Hz leaves the corridor with or
//!   without the barrier (the held command carries the chaser through the layer; 1 ms and
//!   0.1 ms periods give 1e8–1e10 N spikes). In continuous time (`reproduce::guo2016_ct`,
//!   adaptive stiff integration with an event on h = 0) the body-frame motion stops at the
//!   wall with a finite peak force (~3e6 N); with a fixed desired attitude the corridor then
//!   holds, with the paper's σ_d(t) the turning reference carries the body-fixed line of sight
//!   across the wall ~10 ms later.
//! - The corridor guarantee concerns the centre-of-mass point only.
//!
//! # In the full simulation (the controller in `scene.rs`, `rpod reproduce guo2016`)
//! A scene asks for the law with [`Guo2016Spec`] (mass and inertia from the chaser body). The
//! Section 5 scenes (`scenes/papers/guo2016/guo2016_corridor.ron`, `scenes/papers/guo2016/guo2016_no_avoidance.ron`) give the
//! same numbers as the plant above: final |r_e| = 43.6 m, |σ_e| = 0.085 at 100 s, h > 0
//! throughout with k2 = 0.02 and with k2 = 0 (paths equal to 1e-8 m), no contact. In a
//! seeded campaign of starts inside the corridor with attitude errors up to 40° (reaching
//! variant), 6 of 50 runs left the corridor: `r_e` is defined in chaser axes, so while the
//! attitude error decays the "straight" sliding motion is a curve in the target frame, and the
//! barrier answered with force spikes up to ~1.7e7 N (one run was flung 218 m out and back).

use nalgebra::{Matrix3, SMatrix, SVector, UnitQuaternion, Vector3};

use crate::geometry::cissoid::Cissoid;
use crate::math::mrp::{
    dcm_from_mrp, mrp_from_quat, mrp_g, mrp_g_dot, mrp_g_inv, mrp_g_inv_dot, mrp_relative, skew,
};

/// 6-vector `[attitude (MRP-based); translation (m-based)]`.
pub type Vec6 = SVector<f64, 6>;
/// 6×6 matrix of the coupled model.
pub type Mat6 = SMatrix<f64, 6, 6>;

/// Parameters of the Guo 2016 law (SI units).
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Guo2016Params {
    /// `k1` of eq (32), 1/s (with β dimensionless, `k1/β` is the sliding-surface decay rate).
    pub k1_per_s: f64,
    /// `k2` of eq (32), m⁴ (so that `k2/h²` is dimensionless; `h` is in m²). 0 = no corridor.
    pub k2_m4: f64,
    /// `k3` of eq (32), dimensionless.
    pub k3: f64,
    /// `k4` of eq (33): switching gain, N on the force rows and N·m on the torque rows
    /// (must exceed the disturbance bound ‖d‖).
    pub k4_n: f64,
    /// Boundary-layer width ε of the saturation replacing `sgn S` (units of S). Paper: not
    /// given (Section 5 only says a saturation is used).
    pub boundary_layer: f64,
    /// Optional linear reaching gain `k_r`, 1/s: adds `−β⁻¹k_r M S` (closed loop
    /// `Ṡ = −k_r S + …`). **Not in the paper**
    /// (`paper()` = 0); see the module doc.
    pub reaching_gain_per_s: f64,
    /// Corridor semi-axis `a` (eq 31), m. The corridor ends at the asymptotic plane `x = 2a`.
    pub corridor_a_m: f64,
    /// Corridor opening `tan θ` (eq 30), dimensionless.
    pub corridor_tan_theta: f64,
    /// Chaser mass `m_c`, kg.
    pub chaser_mass_kg: f64,
    /// Chaser inertia `J` about its centre of mass, chaser body axes, kg·m².
    pub chaser_inertia_body_kg_m2: Matrix3<f64>,
    /// Desired target position relative to the chaser `r_d`, chaser body axes, m.
    pub r_d_body_m: Vector3<f64>,
    /// Amplitudes `A_i` of `σ_d,i(t) = A_i sin(t/T_i)` (MRP, dimensionless).
    pub sigma_d_amplitude: Vector3<f64>,
    /// Time constants `T_i` of `σ_d,i(t) = A_i sin(t/T_i)`, s.
    pub sigma_d_time_constant_s: Vector3<f64>,
}

impl Guo2016Params {
    /// Section 5 values: k1 = 9, k2 = 0.02, k3 = 1, k4 = 0.005, a = 25 m, m = 100 kg,
    /// r_d = [2, 0, 0] m, σ_d = 0.001[sin(t/40), sin(t/50), sin(t/60)].
    /// Choices where the paper is silent:
    /// - `tan θ = 5` (θ ≈ 78.7°): r0 = [14.9, 17.1, 37.7] m read as the chaser position in the
    ///   target body frame needs tan θ > 4.265; 5 puts it strictly inside (h(r0) ≈ 642 m²,
    ///   1.31 m from the surface). Any reading that keeps +x as the docking axis gives the
    ///   same bound (|r0| lateral = 41.4 m at x = 14.9 m).
    /// - `J = diag(15, 17, 20)` kg·m²: a ~1 m, 100 kg bus (m·(1²+1²)/12 ≈ 17 kg·m²),
    ///   slightly asymmetric so the gyroscopic coupling is non-zero.
    /// - `ε = 1e-3` (boundary layer), `k_r = 0` (paper law).
    pub fn paper() -> Self {
        Self {
            k1_per_s: 9.0,
            k2_m4: 0.02,
            k3: 1.0,
            k4_n: 0.005,
            boundary_layer: 1e-3,
            reaching_gain_per_s: 0.0,
            corridor_a_m: 25.0,
            corridor_tan_theta: 5.0,
            chaser_mass_kg: 100.0,
            chaser_inertia_body_kg_m2: Matrix3::from_diagonal(&Vector3::new(15.0, 17.0, 20.0)),
            r_d_body_m: Vector3::new(2.0, 0.0, 0.0),
            sigma_d_amplitude: Vector3::new(1e-3, 1e-3, 1e-3),
            sigma_d_time_constant_s: Vector3::new(40.0, 50.0, 60.0),
        }
    }

    /// The corridor of these parameters (target body frame).
    pub fn corridor(&self) -> Cissoid {
        Cissoid::new(self.corridor_a_m, self.corridor_tan_theta)
    }

    /// Desired attitude relative to D0 and its first two time derivatives at `t_s`:
    /// `(σ_d, σ̇_d [1/s], σ̈_d [1/s²])`.
    pub fn sigma_d(&self, t_s: f64) -> (Vector3<f64>, Vector3<f64>, Vector3<f64>) {
        let a = &self.sigma_d_amplitude;
        let tc = &self.sigma_d_time_constant_s;
        let mut s = Vector3::zeros();
        let mut sd = Vector3::zeros();
        let mut sdd = Vector3::zeros();
        for i in 0..3 {
            let arg = t_s / tc[i];
            s[i] = a[i] * arg.sin();
            sd[i] = a[i] * arg.cos() / tc[i];
            sdd[i] = -a[i] * arg.sin() / (tc[i] * tc[i]);
        }
        (s, sd, sdd)
    }
}

impl Default for Guo2016Params {
    fn default() -> Self {
        Self::paper()
    }
}

/// What the simulation gives the law at one control step.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Guo2016Observation {
    /// Time since the start of the run, s (drives σ_d(t)).
    pub t_s: f64,
    /// Chaser attitude, **body→world** (`v_world = q * v_body`, the Bevy `Transform` sense).
    pub q_chaser_body_to_world: UnitQuaternion<f64>,
    /// Target attitude, body→world.
    pub q_target_body_to_world: UnitQuaternion<f64>,
    /// Chaser inertial angular velocity, chaser body axes, rad/s.
    pub rate_chaser_body_rad_s: Vector3<f64>,
    /// Target inertial angular velocity, target body axes, rad/s.
    pub rate_target_body_rad_s: Vector3<f64>,
    /// Chaser centre of mass minus target centre of mass, world axes, m.
    pub pos_rel_world_m: Vector3<f64>,
    /// Inertial time derivative of `pos_rel_world_m`, world axes, m/s.
    pub vel_rel_world_m_s: Vector3<f64>,
    /// Differential gravity `g(r_c) − g(r_t)` (acceleration of the chaser minus that of the
    /// target due to gravity), world axes, m/s². The paper's `f` is two-body; if the simulation
    /// includes J2 here, J2 is compensated instead of being a disturbance.
    pub grav_diff_world_m_s2: Vector3<f64>,
}

/// The law's output.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Guo2016Command {
    /// Force on the chaser centre of mass, chaser body axes, N.
    pub force_body_n: Vector3<f64>,
    /// Torque on the chaser, chaser body axes, N·m.
    pub torque_body_nm: Vector3<f64>,
}

/// Quantities worth logging.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Guo2016Diagnostics {
    /// Corridor function `h(r1)`, m² (> 0 inside; −∞ beyond the asymptotic plane).
    pub h_m2: f64,
    /// `ḣ`, m²/s.
    pub h_dot_m2_s: f64,
    /// Chaser strictly inside the corridor.
    pub inside: bool,
    /// `β = k2/h² + k3` actually used (dimensionless).
    pub beta: f64,
    /// `β̇`, 1/s.
    pub beta_dot_per_s: f64,
    /// Sliding variable `S` of eq (32) `[attitude; translation (m/s)]`.
    pub s: Vec6,
    /// `x = [σ_e; r_e (m)]`.
    pub x: Vec6,
    /// `ẋ = [σ̇_e (1/s); ṙ_e (m/s)]`.
    pub x_dot: Vec6,
    /// Lyapunov function `V1 = ½ SᵀMS` of eq (35).
    pub v1: f64,
    /// Chaser position in target body axes `r1`, m (feed to
    /// [`Cissoid::signed_distance_m`] for the distance to the corridor wall).
    pub r1_target_m: Vector3<f64>,
    /// Chaser angular-velocity error `ω_e = ω − R(σ_e)ω_d`, chaser body axes, rad/s.
    pub omega_e_body_rad_s: Vector3<f64>,
}

/// Attitude and translation kinematics extracted from an observation (eqs 14–18, 5–9).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Guo2016State {
    /// Attitude error MRP `σ_e` (short set).
    pub sigma_e: Vector3<f64>,
    /// `σ̇_e = G(σ_e) ω_e`, 1/s.
    pub sigma_e_dot: Vector3<f64>,
    /// `ω_r = R(σ_e) ω_d`: desired rate in chaser body axes, rad/s.
    pub omega_r_body_rad_s: Vector3<f64>,
    /// `ω̇_d`: desired angular acceleration in desired axes, rad/s².
    pub omega_d_dot_rad_s2: Vector3<f64>,
    /// Chaser inertial rate `ω`, body axes, rad/s.
    pub omega_body_rad_s: Vector3<f64>,
    /// `r_e = r_b − r_d`, chaser body axes, m.
    pub r_e_body_m: Vector3<f64>,
    /// `ṙ_e = ṙ_b` (derivative seen in the chaser body frame), m/s.
    pub r_e_dot_body_m_s: Vector3<f64>,
    /// Differential gravity `f_b`, chaser body axes, m/s².
    pub f_body_m_s2: Vector3<f64>,
    /// Chaser position in target body axes `r1`, m.
    pub r1_target_m: Vector3<f64>,
    /// Rate of `r1` seen in the target frame, target axes, m/s.
    pub r1_dot_target_m_s: Vector3<f64>,
}

impl Guo2016State {
    /// `x = [σ_e; r_e]`.
    pub fn x(&self) -> Vec6 {
        stack(&self.sigma_e, &self.r_e_body_m)
    }
    /// `ẋ = [σ̇_e; ṙ_e]`.
    pub fn x_dot(&self) -> Vec6 {
        stack(&self.sigma_e_dot, &self.r_e_dot_body_m_s)
    }
}

/// The matrices of the coupled model (25)–(28) at one state.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CoupledModel {
    /// Inertia matrix `M` (symmetric positive definite).
    pub m: Mat6,
    /// Its time derivative `Ṁ` (analytic).
    pub m_dot: Mat6,
    /// Coriolis-like matrix `C`.
    pub c: Mat6,
    /// Remaining terms `g`.
    pub g: Vec6,
    /// Input matrix `B1 = B2 = diag(G⁻ᵀ(σ_e), −I)` (−I: line-of-sight sign choice).
    pub b1: Mat6,
}

fn stack(a: &Vector3<f64>, b: &Vector3<f64>) -> Vec6 {
    Vec6::new(a.x, a.y, a.z, b.x, b.y, b.z)
}

fn top(v: &Vec6) -> Vector3<f64> {
    Vector3::new(v[0], v[1], v[2])
}

fn bottom(v: &Vec6) -> Vector3<f64> {
    Vector3::new(v[3], v[4], v[5])
}

fn block_diag(a: &Matrix3<f64>, b: &Matrix3<f64>) -> Mat6 {
    let mut m = Mat6::zeros();
    m.fixed_view_mut::<3, 3>(0, 0).copy_from(a);
    m.fixed_view_mut::<3, 3>(3, 3).copy_from(b);
    m
}

/// Orientation of the docking reference frame D0 relative to the target body:
/// a rotation of π about target z (D0→target, body→reference sense).
pub fn q_d0_to_target() -> UnitQuaternion<f64> {
    UnitQuaternion::from_axis_angle(&Vector3::z_axis(), std::f64::consts::PI)
}

/// Attitude part of the model (eqs 19–23): `(M1, Ṁ1, C1, N1)`.
pub fn attitude_model(
    j_body_kg_m2: &Matrix3<f64>,
    sigma_e: &Vector3<f64>,
    sigma_e_dot: &Vector3<f64>,
    omega_r_body_rad_s: &Vector3<f64>,
    omega_d_dot_rad_s2: &Vector3<f64>,
) -> (Matrix3<f64>, Matrix3<f64>, Matrix3<f64>, Vector3<f64>) {
    let j = j_body_kg_m2;
    let gi = mrp_g_inv(sigma_e);
    let gid = mrp_g_inv_dot(sigma_e, sigma_e_dot);
    let git = gi.transpose();
    let m1 = git * j * gi;
    let m1_dot = gid.transpose() * j * gi + git * j * gid;
    let wr = omega_r_body_rad_s;
    let c1 = git * (-skew(&(j * gi * sigma_e_dot)) * gi + j * gid)
        + git * (j * skew(wr) + skew(wr) * j - skew(&(j * wr))) * gi;
    let r_e = dcm_from_mrp(sigma_e);
    let n1 = git * (wr.cross(&(j * wr)) + j * r_e * omega_d_dot_rad_s2);
    (m1, m1_dot, c1, n1)
}

/// Full coupled model (25)–(28) at a state, given the chaser angular acceleration `ω̇`
/// (body axes, rad/s²) that appears in `D(ω)`.
pub fn coupled_model(
    params: &Guo2016Params,
    st: &Guo2016State,
    omega_dot_body_rad_s2: &Vector3<f64>,
) -> CoupledModel {
    let (m1, m1_dot, c1, n1) = attitude_model(
        &params.chaser_inertia_body_kg_m2,
        &st.sigma_e,
        &st.sigma_e_dot,
        &st.omega_r_body_rad_s,
        &st.omega_d_dot_rad_s2,
    );
    let mc = params.chaser_mass_kg;
    let w = st.omega_body_rad_s;
    let c2 = skew(&w) * (2.0 * mc);
    let d = skew(&w) * skew(&w) + skew(omega_dot_body_rad_s2);
    let g2 = (d * (st.r_e_body_m + params.r_d_body_m) + st.f_body_m_s2) * mc;
    CoupledModel {
        m: block_diag(&m1, &(Matrix3::identity() * mc)),
        m_dot: block_diag(&m1_dot, &Matrix3::zeros()),
        c: block_diag(&c1, &c2),
        g: stack(&n1, &g2),
        b1: block_diag(&mrp_g_inv(&st.sigma_e).transpose(), &(-Matrix3::identity())),
    }
}

/// The Guo 2016 coupled sliding-mode law. Stateless: each call is a pure function of the
/// observation.
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
pub struct Guo2016 {
    /// Parameters.
    pub params: Guo2016Params,
}

impl Guo2016 {
    /// Law with the given parameters.
    pub fn new(params: Guo2016Params) -> Self {
        Self { params }
    }

    /// Kinematics of the observation (see the module doc for frames).
    pub fn state(&self, obs: &Guo2016Observation) -> Guo2016State {
        let p = &self.params;
        // Attitudes: chaser relative to D0, desired relative to D0.
        let q_d0_w = obs.q_target_body_to_world * q_d0_to_target();
        let sigma = mrp_from_quat(&(q_d0_w.inverse() * obs.q_chaser_body_to_world));
        let (sd, sd_dot, sd_ddot) = p.sigma_d(obs.t_s);
        // D0 inertial rate in D0 axes (D0 is fixed to the target).
        let w_d0 = q_d0_to_target().inverse() * obs.rate_target_body_rad_s;
        // Desired-frame rate relative to D0 and to inertial space, desired axes.
        let gdi = mrp_g_inv(&sd);
        let w_dd0 = gdi * sd_dot;
        let w_dd0_dot = gdi * (sd_ddot - mrp_g_dot(&sd, &sd_dot) * w_dd0);
        let r_d_d0 = dcm_from_mrp(&sd);
        let w_d0_in_d = r_d_d0 * w_d0;
        let omega_d = w_dd0 + w_d0_in_d;
        let omega_d_dot = w_dd0_dot - w_dd0.cross(&w_d0_in_d);
        // Error (eqs 14–18).
        let sigma_e = mrp_relative(&sigma, &sd);
        let omega_r = dcm_from_mrp(&sigma_e) * omega_d;
        let w = obs.rate_chaser_body_rad_s;
        let omega_e = w - omega_r;
        let sigma_e_dot = mrp_g(&sigma_e) * omega_e;
        // Translation: line of sight r_b = r_t − r_c in chaser axes.
        let r_bw = obs.q_chaser_body_to_world.inverse();
        let r_b = r_bw * (-obs.pos_rel_world_m);
        let r_b_dot = r_bw * (-obs.vel_rel_world_m_s) - w.cross(&r_b);
        let r_tw = obs.q_target_body_to_world.inverse();
        let r1 = r_tw * obs.pos_rel_world_m;
        let r1_dot = r_tw * obs.vel_rel_world_m_s - obs.rate_target_body_rad_s.cross(&r1);
        Guo2016State {
            sigma_e,
            sigma_e_dot,
            omega_r_body_rad_s: omega_r,
            omega_d_dot_rad_s2: omega_d_dot,
            omega_body_rad_s: w,
            r_e_body_m: r_b - p.r_d_body_m,
            r_e_dot_body_m_s: r_b_dot,
            f_body_m_s2: r_bw * obs.grav_diff_world_m_s2,
            r1_target_m: r1,
            r1_dot_target_m_s: r1_dot,
        }
    }

    /// `β`, `β̇`, `h`, `ḣ`, inside flag for a state.
    fn barrier(&self, st: &Guo2016State) -> (f64, f64, f64, f64, bool) {
        let p = &self.params;
        let c = p.corridor();
        let h = c.h(&st.r1_target_m);
        let h_dot = c.h_dot(&st.r1_target_m, &st.r1_dot_target_m_s);
        let inside = c.inside(&st.r1_target_m);
        if inside {
            (
                p.k2_m4 / (h * h) + p.k3,
                -2.0 * p.k2_m4 * h_dot / (h * h * h),
                h,
                h_dot,
                true,
            )
        } else {
            (p.k3, 0.0, h, h_dot, false)
        }
    }

    /// Command and diagnostics for one observation (eq 33).
    pub fn control(&self, obs: &Guo2016Observation) -> (Guo2016Command, Guo2016Diagnostics) {
        let p = &self.params;
        let st = self.state(obs);
        let (beta, beta_dot, h, h_dot, inside) = self.barrier(&st);
        let x = st.x();
        let xd = st.x_dot();
        let s = x * p.k1_per_s + xd * beta;
        let b2_norm = 4.0 / (1.0 + st.sigma_e.norm_squared());
        let sat = s.map(|v| (v / p.boundary_layer).clamp(-1.0, 1.0));
        let j = &p.chaser_inertia_body_kg_m2;
        let w = st.omega_body_rad_s;

        // Attitude rows first (they do not depend on ω̇).
        let (m1, m1_dot, c1, n1) = attitude_model(
            j,
            &st.sigma_e,
            &st.sigma_e_dot,
            &st.omega_r_body_rad_s,
            &st.omega_d_dot_rad_s2,
        );
        let s_att = top(&s);
        let v_att = c1 * st.sigma_e_dot + n1
            - (m1 * st.sigma_e_dot * (p.k1_per_s + beta_dot) + m1_dot * s_att * 0.5) / beta
            - top(&sat) * (p.k4_n * b2_norm)
            - m1 * s_att * (p.reaching_gain_per_s / beta);
        let torque = mrp_g(&st.sigma_e).transpose() * v_att;

        // ω̇ produced by that torque, then the translation rows.
        let j_inv = j.try_inverse().unwrap_or_else(Matrix3::zeros);
        let w_dot = j_inv * (torque - w.cross(&(j * w)));
        let model = coupled_model(p, &st, &w_dot);
        let mc = p.chaser_mass_kg;
        let s_tr = bottom(&s);
        let v_tr = bottom(&(model.c * xd + model.g))
            - st.r_e_dot_body_m_s * (mc * (p.k1_per_s + beta_dot) / beta)
            - bottom(&sat) * (p.k4_n * b2_norm)
            - s_tr * (mc * p.reaching_gain_per_s / beta);
        let force = -v_tr;

        let v1 = 0.5 * s.dot(&(model.m * s));
        (
            Guo2016Command {
                force_body_n: force,
                torque_body_nm: torque,
            },
            Guo2016Diagnostics {
                h_m2: h,
                h_dot_m2_s: h_dot,
                inside,
                beta,
                beta_dot_per_s: beta_dot,
                s,
                x,
                x_dot: xd,
                v1,
                r1_target_m: st.r1_target_m,
                omega_e_body_rad_s: w - st.omega_r_body_rad_s,
            },
        )
    }
}

// The scene binding (scene entry, `LawSpec`, disturbances, the simulation adapter) and the
// tests live in their own files; every public item stays reachable at its old path.
mod scene;
pub use scene::*;

#[cfg(test)]
mod tests;
