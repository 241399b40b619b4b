//! Artificial-potential-function rendezvous and docking on an air-bearing table:
//! Xu, Wen, Wei (2019), eqs (12)–(16), Table 2.
//!
//! State `x_c = (x, y, θ)` of the chaser in the lab frame of the table (m, m, rad), planar
//! dynamics `ẍ = Fx/m, ÿ = Fy/m, θ̈ = T/I_z` (eq 3). Potential (eq 12)
//! `φ_tot = φ_a + Σ_i φ_r,i`, with
//!
//! ```text
//! φ_a   = ½ k_a r_cdᵀ Q_a r_cd                                   (13)
//! φ_r,i = ½ k_r r_cdᵀ Q_i r_cd / (exp(r_coiᵀ P_i r_coi) − 1)       (14)
//! u     = −(∇φ_tot + k ẋ_c)                                       (16)
//! ```
//!
//! `r_cd = x_c − x_d` (θ component wrapped to (−π, π]); `r_coi = d_i (cos α_i, sin α_i, 0)` is
//! the radial-distance vector to obstacle i (eqs 6, 9): `d_i` the radial distance, `α_i` the
//! polar angle of the chaser about the shape's centre. Obstacle 1 is the superquadric
//! ([`crate::geometry::superquadric`], shape matrices `Q_e, P_e`), obstacle 2 the heart
//! keep-out ([`crate::geometry::heart`], `Q_x, P_x`). Table 2: `k_a = k_r = 1`,
//! `k = diag(10, 10, 0.5)`, `Q_a = diag(0.8, 0.8, 0.1)`, `Q_e = diag(0.02, 0.02, 0)`,
//! `P_e = diag(15, 15, 0)`, `Q_x = diag(0.02, 0.02, 0)`, `P_x = diag(5, 5, 0)`. With unit
//! `k_a`, `Q_a` has units N/m (position) and N·m/rad (attitude); `k` N·s/m and N·m·s/rad.
//!
//! Choices where the paper is silent or inconsistent (documented, selectable):
//!
//! - **Radial distance to the superquadric** ([`RadialForm`]): the published eq (8)
//!   (`PaperEq8`, never zero on the boundary off the axes) or the exact ray intersection
//!   (`Exact`). The heart has one form: eq (11) with its third branch's sign corrected
//!   ([`crate::geometry::heart`]).
//! - **Gradient** ([`GradientForm`]): the paper prints (after eq 15)
//!   `∇φ = k_a Q_a r_cd + Σ k_r {Q r_cd (e−1) − r_cdᵀQ r_cd · e · P r_co}/(e−1)²`, `e = exp(r_coᵀ P r_co)`,
//!   which is the gradient only if `∂r_co/∂x_c = I` (a point obstacle): for a radial distance
//!   it keeps the radial part and drops the tangential one (`PaperPrinted`). `True` uses the
//!   exact gradient `J = ∂r_co/∂x_c = e_ρ ∇dᵀ + (d/ρ) e_α e_αᵀ`, so `∇φ_r` carries `Jᵀ P r_co`;
//!   with `PaperEq8` distances this true gradient is unbounded near the obstacle's axes
//!   (eq 8 has `|cos α|^{1/s}`), so `True` is meant to go with `Exact`.
//! - The terms are summed over the two constraints (eq 12 writes `Σ_{i=0}^{n}`, the gradient
//!   `Σ_{i=1}^{n}`; there are n = 2 constraints).
//! - Angle error wrapped to (−π, π]. At a radial distance of exactly zero the barrier is
//!   infinite and the command non-finite; callers monitor distances.
//! - The controller uses the measured lab-frame velocity it is given (the paper's vision
//!   system gives poses only; how velocity was obtained is not stated).
//!
//! Fig. 13's claims are tested below against an independent RK4 integration of eq (3).
//! Findings (numbers printed by the tests, `--nocapture`):
//! - Ideal force, paper scenario: both the as-published law (eq 8, printed ∇) and the exact
//!   one keep radial distances > 0 (obstacle ≥ 0.120 / 0.137 m, heart ≥ 0.050 m, the goal's own
//!   value) and reach the goal (within 1 cm and 1° after 57.7 s / 51.6 s). Peak force ≈ 0.9 N.
//! - 0.05 N nozzles through PWPF at 25 Hz vision: x and y lag early (50 % settling +5.5 s in
//!   x, +4.9 s in y), as the paper says, but the thrust-limited run overtakes the unlimited
//!   one after ≈ 20–35 s (90 % settling 7.7 s earlier in x, 4.1 s in y). Attitude lags
//!   (+0.6 s at 50 %), it does not lead (the paper blames its lead on I_z, which this model
//!   does not perturb). A continuously saturated run reproduces the PWPF run to ≈ 0.1 s:
//!   saturation, not modulation, explains the difference.
//! - The eq (8) potential is no barrier: with its true gradient the chaser crosses the
//!   obstacle; with the printed gradient a start, centre and goal on one line give a trap.
//!   V = φ_tot + kinetic energy rises by up to 1e-3 J per 10 ms step under the printed law;
//!   it never rises under the exact law (Lyapunov).

use crate::geometry::heart::HeartParams;
use crate::geometry::superquadric::{RadialForm, SuperquadricParams};
use nalgebra::{Matrix2, Vector2, Vector3};
use serde::{Deserialize, Serialize};

/// Which gradient of φ_tot the control law uses (see the module doc).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum GradientForm {
    /// The formula printed after eq (15): radial distance vector treated as if
    /// `∂r_co/∂x_c = I`.
    PaperPrinted,
    /// The exact gradient of φ_tot (chain rule through the radial distance).
    True,
}

/// Controller constants (Table 2), goal (Table 1), constraint shapes and the two modelling
/// choices. All matrices are diagonal, as in Table 2: `[x, y, θ]` entries.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Xu2019Params {
    /// Attractive gain `k_a` (dimensionless).
    pub k_a: f64,
    /// Repulsive gain `k_r` (dimensionless).
    pub k_r: f64,
    /// Damping `k` diagonal (N·s/m, N·s/m, N·m·s/rad).
    pub k_damp_diag: [f64; 3],
    /// Attractive shape `Q_a` diagonal (N/m, N/m, N·m/rad).
    pub q_a_diag: [f64; 3],
    /// Obstacle repulsive shape `Q_e` diagonal (N/m, N/m, N·m/rad).
    pub q_e_diag: [f64; 3],
    /// Obstacle barrier shape `P_e` diagonal (1/m², 1/m², unused third entry).
    pub p_e_diag: [f64; 3],
    /// Heart repulsive shape `Q_x` diagonal (N/m, N/m, N·m/rad).
    pub q_x_diag: [f64; 3],
    /// Heart barrier shape `P_x` diagonal (1/m², 1/m², unused third entry).
    pub p_x_diag: [f64; 3],
    /// Desired position `x_d, y_d` in the lab frame (m).
    pub goal_pos_lab_m: [f64; 2],
    /// Desired attitude `θ_d` (rad), about lab z from lab x.
    pub goal_theta_rad: f64,
    /// The superquadric obstacle.
    pub obstacle: SuperquadricParams,
    /// The heart-shaped target keep-out.
    pub heart: HeartParams,
    /// Radial distance form for the superquadric.
    pub radial_form: RadialForm,
    /// Gradient form used by the control law.
    pub gradient_form: GradientForm,
}

impl Default for Xu2019Params {
    fn default() -> Self {
        Self::paper()
    }
}

impl Xu2019Params {
    /// As published: Table 1–2 values, eq (8) radial distance, the printed gradient.
    pub fn paper() -> Self {
        Self {
            k_a: 1.0,
            k_r: 1.0,
            k_damp_diag: [10.0, 10.0, 0.5],
            q_a_diag: [0.8, 0.8, 0.1],
            q_e_diag: [0.02, 0.02, 0.0],
            p_e_diag: [15.0, 15.0, 0.0],
            q_x_diag: [0.02, 0.02, 0.0],
            p_x_diag: [5.0, 5.0, 0.0],
            goal_pos_lab_m: [0.25, 1.4],
            goal_theta_rad: 90f64.to_radians(),
            obstacle: SuperquadricParams::paper(),
            heart: HeartParams::paper(),
            radial_form: RadialForm::PaperEq8,
            gradient_form: GradientForm::PaperPrinted,
        }
    }

    /// Table 1–2 values with the exact radial distance and the true gradient of φ_tot.
    pub fn exact() -> Self {
        Self {
            radial_form: RadialForm::Exact,
            gradient_form: GradientForm::True,
            ..Self::paper()
        }
    }
}

/// The paper's experiment set-up (§3, Table 1): simulator mass properties and start pose.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Xu2019Setup {
    /// Chaser simulator mass (kg). Paper: ≈ 9 kg.
    pub mass_kg: f64,
    /// Chaser moment of inertia about z (kg·m²). Paper: ≈ 0.05 kg·m² (measured).
    pub iz_kg_m2: f64,
    /// Initial position in the lab frame (m). Paper: (0.809, 0.224).
    pub start_pos_lab_m: [f64; 2],
    /// Initial attitude (rad). Paper: 7°.
    pub start_theta_rad: f64,
    /// Vision pose period (s). Paper: 0.04 s.
    pub vision_period_s: f64,
}

impl Default for Xu2019Setup {
    fn default() -> Self {
        Self::paper()
    }
}

impl Xu2019Setup {
    /// Paper values: 9 kg, 0.05 kg·m², start (0.809 m, 0.224 m, 7°) at rest, vision 25 Hz.
    pub fn paper() -> Self {
        Self {
            mass_kg: 9.0,
            iz_kg_m2: 0.05,
            start_pos_lab_m: [0.809, 0.224],
            start_theta_rad: 7f64.to_radians(),
            vision_period_s: 0.04,
        }
    }
}

/// What the controller sees (lab frame of the table).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Xu2019Observation {
    /// Time of the measurement (s).
    pub t_s: f64,
    /// Measured position `(x_m, y_m)` (m).
    pub pos_lab_m: Vector2<f64>,
    /// Measured attitude θ about lab z from lab x (rad).
    pub theta_rad: f64,
    /// Velocity `(ẋ, ẏ)` (m/s).
    pub vel_lab_m_s: Vector2<f64>,
    /// Angular rate θ̇ (rad/s).
    pub omega_rad_s: f64,
}

/// The command of eq (16).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Xu2019Command {
    /// Force `(Fx_n, Fy_n)` in the lab frame (N).
    pub force_lab_n: Vector2<f64>,
    /// Torque about z (N·m) (same in lab and body frames).
    pub torque_nm: f64,
    /// The same force in the chaser body frame (N), rotated by −θ_measured: for the
    /// thruster allocation.
    pub force_body_n: Vector2<f64>,
}

/// The eq (16) control law.
#[derive(Debug, Clone, PartialEq)]
pub struct Xu2019Potential {
    /// Constants and choices.
    pub params: Xu2019Params,
}

use crate::control::sensor::wrap_pi;

/// One repulsor as the law sees it: `(Q diag, P diag, r_co (m), ∂r_co/∂p)`.
type Repulsor = ([f64; 3], [f64; 3], Vector2<f64>, Matrix2<f64>);

/// Radial-distance vector `r_co` (2-D part, m), its Jacobian wrt the lab position, given the
/// distance `d`, its gradient, and the offset `q` from the shape centre.
fn radial_vector(q: Vector2<f64>, d: f64, grad_d: Vector2<f64>) -> (Vector2<f64>, Matrix2<f64>) {
    let rho = q.norm();
    if rho < 1e-15 {
        return (Vector2::zeros(), Matrix2::identity());
    }
    let e_rho = q / rho;
    let e_alpha = Vector2::new(-e_rho.y, e_rho.x);
    let jac = e_rho * grad_d.transpose() + e_alpha * e_alpha.transpose() * (d / rho);
    (e_rho * d, jac)
}

impl Xu2019Potential {
    /// A controller with the given constants.
    pub fn new(params: Xu2019Params) -> Self {
        Self { params }
    }

    /// `r_cd = x_c − x_d` for a pose `(x m, y m, θ rad)`, angle wrapped.
    pub fn pose_error(&self, pose: Vector3<f64>) -> Vector3<f64> {
        let p = &self.params;
        Vector3::new(
            pose.x - p.goal_pos_lab_m[0],
            pose.y - p.goal_pos_lab_m[1],
            wrap_pi(pose.z - p.goal_theta_rad),
        )
    }

    /// Radial distances used by the law (m): `(obstacle, heart)`. Obstacle in the chosen
    /// [`RadialForm`]; heart signed (negative inside).
    pub fn radial_distances_m(&self, pos_lab_m: Vector2<f64>) -> (f64, f64) {
        (
            self.params
                .obstacle
                .radial_distance_m(pos_lab_m, self.params.radial_form),
            self.params.heart.radial_distance_m(pos_lab_m),
        )
    }

    /// The two repulsors: (q diag, p diag, r_co, J) for obstacle and heart.
    fn repulsors(&self, pos: Vector2<f64>) -> [Repulsor; 2] {
        let p = &self.params;
        let (d_o, g_o) = p.obstacle.radial_distance_with_gradient(pos, p.radial_form);
        let (r_o, j_o) = radial_vector(pos - p.obstacle.centre(), d_o, g_o);
        let (d_h, g_h) = p.heart.radial_distance_with_gradient(pos);
        let (r_h, j_h) = radial_vector(pos - p.heart.centre(), d_h, g_h);
        [
            (p.q_e_diag, p.p_e_diag, r_o, j_o),
            (p.q_x_diag, p.p_x_diag, r_h, j_h),
        ]
    }

    /// Total potential φ_tot (eq 12–14) at a pose `(x m, y m, θ rad)` (J when Q_a is in N/m).
    pub fn potential(&self, pose: Vector3<f64>) -> f64 {
        let p = &self.params;
        let r = self.pose_error(pose);
        let quad = |q: &[f64; 3]| q[0] * r.x * r.x + q[1] * r.y * r.y + q[2] * r.z * r.z;
        let mut phi = 0.5 * p.k_a * quad(&p.q_a_diag);
        for (q, pm, rco, _) in self.repulsors(pose.xy()) {
            let e = pm[0] * rco.x * rco.x + pm[1] * rco.y * rco.y;
            phi += 0.5 * p.k_r * quad(&q) / e.exp_m1();
        }
        phi
    }

    /// ∇φ_tot at a pose, `(∂/∂x N, ∂/∂y N, ∂/∂θ N·m)`, in the chosen [`GradientForm`].
    pub fn gradient(&self, pose: Vector3<f64>) -> Vector3<f64> {
        let p = &self.params;
        let r = self.pose_error(pose);
        let qv = |q: &[f64; 3]| Vector3::new(q[0] * r.x, q[1] * r.y, q[2] * r.z);
        let mut g = qv(&p.q_a_diag) * p.k_a;
        for (q, pm, rco, jac) in self.repulsors(pose.xy()) {
            let prco = Vector2::new(pm[0] * rco.x, pm[1] * rco.y);
            let e_arg = rco.dot(&prco);
            let em1 = e_arg.exp_m1();
            let e = em1 + 1.0;
            let rqr = r.dot(&qv(&q));
            // ∂E/∂p with E = r_coᵀ P r_co: 2 Jᵀ P r_co (true) or 2 P r_co (printed, J = I).
            let de = match p.gradient_form {
                GradientForm::True => jac.transpose() * prco * 2.0,
                GradientForm::PaperPrinted => prco * 2.0,
            };
            let num_q = qv(&q) * em1;
            let num_p = Vector3::new(de.x, de.y, 0.0) * (0.5 * rqr * e);
            g += (num_q - num_p) * (p.k_r / (em1 * em1));
        }
        g
    }

    /// Eq (16): `u = −(∇φ_tot + k ẋ_c)` from a measured pose and velocity.
    pub fn command(&self, obs: &Xu2019Observation) -> Xu2019Command {
        let k = &self.params.k_damp_diag;
        let pose = Vector3::new(obs.pos_lab_m.x, obs.pos_lab_m.y, obs.theta_rad);
        let g = self.gradient(pose);
        let u = -(g + Vector3::new(
            k[0] * obs.vel_lab_m_s.x,
            k[1] * obs.vel_lab_m_s.y,
            k[2] * obs.omega_rad_s,
        ));
        let force_lab_n = u.xy();
        let (s, c) = obs.theta_rad.sin_cos();
        let force_body_n = Vector2::new(
            c * force_lab_n.x + s * force_lab_n.y,
            -s * force_lab_n.x + c * force_lab_n.y,
        );
        Xu2019Command {
            force_lab_n,
            torque_nm: u.z,
            force_body_n,
        }
    }
}

/// Which variant of the law a scene flies.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
pub enum LawForm {
    /// As published ([`Xu2019Params::paper`]): eq (8) radial distance, printed gradient.
    #[default]
    Paper,
    /// Exact radial distance and true gradient ([`Xu2019Params::exact`]).
    Exact,
}

// The scene binding (scene entry, `LawSpec`, disturbances, the simulation adapter) and the
// tests live in their own files; every public item stays reachable at its old path.
mod scene;
pub use scene::*;

#[cfg(test)]
mod tests;
