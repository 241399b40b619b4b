//! The coupled model and the law against independent references:
//! - Property 1/2 of the paper (M SPD, Ṁ − 2C skew) with Ṁ by central finite differences;
//! - the model (25)–(28) against an independently written plant: rigid-body attitude in
//!   quaternions (q̇ = ½ q ⊗ ω, Euler's equation) and translation in inertial axes
//!   (two-body gravity on both spacecraft), finite-differenced along RK4 trajectories;
//! - closed-loop runs of the Section 5 case in that plant (RK4, 0.01 s, zero-order hold).
use super::*;
use crate::math::mrp::quat_from_mrp;
use crate::orbit::constants::{J2_EARTH, MU_EARTH_M3_S2, R_EARTH_M};
use nalgebra::Quaternion;

use crate::math::rng::Lcg;

// ---------------- independent plant ----------------

fn two_body(r: &Vector3<f64>) -> Vector3<f64> {
    -r * (MU_EARTH_M3_S2 / r.norm().powi(3))
}

fn j2_accel(r: &Vector3<f64>) -> Vector3<f64> {
    // Vallado eq 8-30 (unnormalised J2, z = Earth axis).
    let rn = r.norm();
    let k = -1.5 * J2_EARTH * MU_EARTH_M3_S2 * R_EARTH_M * R_EARTH_M / rn.powi(5);
    let z2 = 5.0 * r.z * r.z / (rn * rn);
    Vector3::new(
        r.x * k * (1.0 - z2),
        r.y * k * (1.0 - z2),
        r.z * k * (3.0 - z2),
    )
}

fn quat_dot(q: &Quaternion<f64>, w_body: &Vector3<f64>) -> Quaternion<f64> {
    q * Quaternion::new(0.0, w_body.x, w_body.y, w_body.z) * 0.5
}

/// Plant state: target orbit, relative motion (inertial axes), chaser and target attitude.
#[derive(Clone, Copy)]
struct Plant {
    rt: Vector3<f64>,
    vt: Vector3<f64>,
    r: Vector3<f64>,
    v: Vector3<f64>,
    qc: Quaternion<f64>,
    wc: Vector3<f64>,
    qt: Quaternion<f64>,
    /// constant target body rate (kinematic: the target's ω̇ is zero)
    wt: Vector3<f64>,
}

struct PlantCfg {
    mass_kg: f64,
    j: Matrix3<f64>,
    j2: bool,
    /// disturbance torque amplitude (paper: 0.001 N·m) and its frequency n, rad/s
    dtau_nm: f64,
    n_rad_s: f64,
}

impl Plant {
    fn deriv(&self, t: f64, cfg: &PlantCfg, u: &Guo2016Command) -> Plant {
        let rc = self.rt + self.r;
        let mut at = two_body(&self.rt);
        let mut ac = two_body(&rc);
        if cfg.j2 {
            at += j2_accel(&self.rt);
            ac += j2_accel(&rc);
        }
        let qc = UnitQuaternion::from_quaternion(self.qc);
        ac += qc * u.force_body_n / cfg.mass_kg;
        let c = (cfg.n_rad_s * t).cos();
        let dtau = Vector3::new(1.0, 2.0, 3.0) * (cfg.dtau_nm * c);
        let jw = cfg.j * self.wc;
        let wdot = cfg.j.try_inverse().unwrap() * (u.torque_body_nm + dtau - self.wc.cross(&jw));
        Plant {
            rt: self.vt,
            vt: at,
            r: self.v,
            v: ac - at,
            qc: quat_dot(&self.qc, &self.wc),
            wc: wdot,
            qt: quat_dot(&self.qt, &self.wt),
            wt: Vector3::zeros(),
        }
    }
    fn add(&self, d: &Plant, h: f64) -> Plant {
        Plant {
            rt: self.rt + d.rt * h,
            vt: self.vt + d.vt * h,
            r: self.r + d.r * h,
            v: self.v + d.v * h,
            qc: self.qc + d.qc * h,
            wc: self.wc + d.wc * h,
            qt: self.qt + d.qt * h,
            wt: self.wt + d.wt * h,
        }
    }
    /// One RK4 step of length h (may be negative) with the command held.
    fn rk4(&self, t: f64, h: f64, cfg: &PlantCfg, u: &Guo2016Command) -> Plant {
        let k1 = self.deriv(t, cfg, u);
        let k2 = self.add(&k1, h / 2.0).deriv(t + h / 2.0, cfg, u);
        let k3 = self.add(&k2, h / 2.0).deriv(t + h / 2.0, cfg, u);
        let k4 = self.add(&k3, h).deriv(t + h, cfg, u);
        let mut n = *self;
        n = n.add(&k1, h / 6.0);
        n = n.add(&k2, h / 3.0);
        n = n.add(&k3, h / 3.0);
        n = n.add(&k4, h / 6.0);
        n.qc = n.qc.normalize();
        n.qt = n.qt.normalize();
        n
    }
    fn obs(&self, t: f64) -> Guo2016Observation {
        Guo2016Observation {
            t_s: t,
            q_chaser_body_to_world: UnitQuaternion::from_quaternion(self.qc),
            q_target_body_to_world: UnitQuaternion::from_quaternion(self.qt),
            rate_chaser_body_rad_s: self.wc,
            rate_target_body_rad_s: self.wt,
            pos_rel_world_m: self.r,
            vel_rel_world_m_s: self.v,
            grav_diff_world_m_s2: two_body(&(self.rt + self.r)) - two_body(&self.rt),
        }
    }
}

/// Section 5 target orbit: a = 7178 km, e = 0.01, Ω = 0, i = π/6, ω = 0, f = 0 (perigee).
fn target_orbit() -> (Vector3<f64>, Vector3<f64>, f64) {
    let (a, e, i) = (7.178e6, 0.01, std::f64::consts::FRAC_PI_6);
    let rp = a * (1.0 - e);
    let vp = (MU_EARTH_M3_S2 * (1.0 + e) / rp).sqrt();
    let n = (MU_EARTH_M3_S2 / (a * a * a)).sqrt();
    (
        Vector3::new(rp, 0.0, 0.0),
        Vector3::new(0.0, vp * i.cos(), vp * i.sin()),
        n,
    )
}

fn random_plant(rng: &mut Lcg) -> Plant {
    let (rt, vt, _) = target_orbit();
    let qt = UnitQuaternion::from_scaled_axis(rng.vec3(2.0));
    // chaser within 60° of the docking attitude, somewhere in the corridor region
    let q_d0 = qt * q_d0_to_target();
    let qc = q_d0 * quat_from_mrp(&rng.vec3(0.15));
    Plant {
        rt,
        vt,
        r: qt
            * Vector3::new(
                10.0 + 5.0 * rng.symmetric(),
                rng.symmetric() * 8.0,
                rng.symmetric() * 8.0,
            ),
        v: rng.vec3(0.3),
        qc: *qc.quaternion(),
        wc: rng.vec3(0.1),
        qt: *qt.quaternion(),
        wt: rng.vec3(0.02),
    }
}

// ---------------- tests ----------------

#[test]
fn invariant_guo2016_m_spd_and_mdot_minus_2c_skew() {
    // Properties 1 and 2 (eq 29) at random states; Ṁ by a central difference of M along
    // σ_e(t) = σ_e + σ̇_e t (step 1e-6, error O(1e-12·|M⃛|)).
    let p = Guo2016Params::paper();
    let law = Guo2016::new(p.clone());
    let mut rng = Lcg(11);
    for _ in 0..100 {
        let plant = random_plant(&mut rng);
        let st = law.state(&plant.obs(rng.symmetric().abs() * 100.0));
        let wdot = rng.vec3(0.05);
        let m = coupled_model(&p, &st, &wdot);
        assert!((m.m - m.m.transpose()).abs().max() < 1e-12 * m.m.abs().max());
        let eig = m.m.symmetric_eigenvalues();
        assert!(eig.min() > 0.0);
        let dt = 1e-6;
        let mut sp = st;
        sp.sigma_e += st.sigma_e_dot * dt;
        let mut sm = st;
        sm.sigma_e -= st.sigma_e_dot * dt;
        let mdot_fd =
            (coupled_model(&p, &sp, &wdot).m - coupled_model(&p, &sm, &wdot).m) / (2.0 * dt);
        let scale = m.m.abs().max() * st.sigma_e_dot.norm().max(1e-3);
        assert!(
            (mdot_fd - m.m_dot).abs().max() < 1e-7 * scale,
            "{mdot_fd} {}",
            m.m_dot
        );
        let k = mdot_fd - m.c * 2.0;
        let ck = m.c.abs().max();
        assert!(
            (k + k.transpose()).abs().max() < 1e-7 * ck,
            "{}",
            k + k.transpose()
        );
    }
}

#[test]
fn val_guo2016_model_vs_rigid_body_plant() {
    // Reference: the independent plant above (quaternion attitude, inertial translation,
    // rotating target). Along an RK4 trajectory with a constant random command,
    // central differences of x and of ẋ (step 1e-3 s; truncation O(dt²·x⃛) ≈ 1e-7) must
    // match the state extraction ẋ and the model ẍ = M⁻¹(B1 u − Cẋ − g).
    let p = Guo2016Params::paper();
    let law = Guo2016::new(p.clone());
    let cfg = PlantCfg {
        mass_kg: p.chaser_mass_kg,
        j: p.chaser_inertia_body_kg_m2,
        j2: false,
        dtau_nm: 0.0,
        n_rad_s: 0.0,
    };
    let mut rng = Lcg(12);
    let dt = 1e-3;
    let mut worst_xd: f64 = 0.0;
    let mut worst_xdd: f64 = 0.0;
    for _ in 0..40 {
        let plant = random_plant(&mut rng);
        let t = rng.symmetric().abs() * 100.0;
        let u = Guo2016Command {
            force_body_n: rng.vec3(2.0),
            torque_body_nm: rng.vec3(0.5),
        };
        let pp = plant.rk4(t, dt, &cfg, &u);
        let pm = plant.rk4(t, -dt, &cfg, &u);
        let s0 = law.state(&plant.obs(t));
        let sp = law.state(&pp.obs(t + dt));
        let sm = law.state(&pm.obs(t - dt));
        let xd_fd = (sp.x() - sm.x()) / (2.0 * dt);
        let xdd_fd = (sp.x_dot() - sm.x_dot()) / (2.0 * dt);
        let e_xd = (xd_fd - s0.x_dot()).norm() / (1.0 + s0.x_dot().norm());
        // true ω̇ of the plant
        let j = p.chaser_inertia_body_kg_m2;
        let wdot = j.try_inverse().unwrap() * (u.torque_body_nm - plant.wc.cross(&(j * plant.wc)));
        let m = coupled_model(&p, &s0, &wdot);
        let uu = stack(&u.torque_body_nm, &u.force_body_n);
        let xdd = m.m.try_inverse().unwrap() * (m.b1 * uu - m.c * s0.x_dot() - m.g);
        let e_xdd = (xdd_fd - xdd).norm() / (1.0 + xdd.norm());
        worst_xd = worst_xd.max(e_xd);
        worst_xdd = worst_xdd.max(e_xdd);
    }
    eprintln!("model vs plant: worst rel. error xdot {worst_xd:.2e}, xddot {worst_xdd:.2e}");
    assert!(worst_xd < 1e-6);
    assert!(worst_xdd < 1e-6);
}

/// What one closed-loop run measured.
#[derive(Debug)]
struct RunSummary {
    min_h_m2: f64,
    min_dist_m: f64,
    first_exit_s: Option<f64>,
    final_r_e_m: f64,
    final_sigma_e: f64,
    s_tr_0: Vector3<f64>,
    s_tr_end: Vector3<f64>,
    /// S_tr(T) predicted by the closed-loop sliding equation integrated alongside
    s_tr_pred: Vector3<f64>,
    v1_0: f64,
    v1_end: f64,
    /// largest step-to-step increase of V1 (should be ≤ 0 up to ZOH effects)
    v1_max_rise: f64,
    max_force_n: f64,
    max_torque_nm: f64,
    /// |ṙ_e(0)|, m/s
    r_e_dot_0_m_s: f64,
    /// |ẋ(T)|
    x_dot_end_norm: f64,
}

/// Section 5 case in the independent plant. Start: r1(0) = [14.9, 17.1, 37.7] m and
/// ṙ1(0) = [0.05, 0.5, −0.24] m/s in the target body frame (= world axes, target
/// inertially fixed); chaser attitude σ(0) = [0.05, −0.05, 0.05] relative to D0
/// (≈ 20° off), ω(0) = 0 (both paper-silent choices). J2 on both spacecraft and
/// d_τ = 0.001[cos nt, 2cos nt, 3cos nt] N·m as in the paper when `disturbed`.
fn run_section5(
    p: &Guo2016Params,
    horizon_s: f64,
    dt: f64,
    sigma0: Vector3<f64>,
    disturbed: bool,
) -> RunSummary {
    let law = Guo2016::new(p.clone());
    let corridor = p.corridor();
    let (rt, vt, n) = target_orbit();
    let cfg = PlantCfg {
        mass_kg: p.chaser_mass_kg,
        j: p.chaser_inertia_body_kg_m2,
        j2: disturbed,
        dtau_nm: if disturbed { 1e-3 } else { 0.0 },
        n_rad_s: n,
    };
    let qc = q_d0_to_target() * quat_from_mrp(&sigma0);
    let mut plant = Plant {
        rt,
        vt,
        r: Vector3::new(14.9, 17.1, 37.7),
        v: Vector3::new(0.05, 0.5, -0.24),
        qc: *qc.quaternion(),
        wc: Vector3::zeros(),
        qt: Quaternion::identity(),
        wt: Vector3::zeros(),
    };
    let steps = (horizon_s / dt).round() as usize;
    let mut sum = RunSummary {
        min_h_m2: f64::INFINITY,
        min_dist_m: f64::INFINITY,
        first_exit_s: None,
        final_r_e_m: 0.0,
        final_sigma_e: 0.0,
        s_tr_0: Vector3::zeros(),
        s_tr_end: Vector3::zeros(),
        s_tr_pred: Vector3::zeros(),
        v1_0: 0.0,
        v1_end: 0.0,
        v1_max_rise: f64::NEG_INFINITY,
        max_force_n: 0.0,
        max_torque_nm: 0.0,
        r_e_dot_0_m_s: 0.0,
        x_dot_end_norm: 0.0,
    };
    let mut v1_prev = f64::NAN;
    for k in 0..=steps {
        let t = k as f64 * dt;
        let (u, d) = law.control(&plant.obs(t));
        sum.min_h_m2 = sum.min_h_m2.min(d.h_m2);
        if k % ((1.0 / dt) as usize).max(1) == 0 {
            sum.min_dist_m = sum
                .min_dist_m
                .min(corridor.signed_distance_m(&d.r1_target_m));
        }
        if !d.inside && sum.first_exit_s.is_none() {
            sum.first_exit_s = Some(t);
        }
        let s_tr = bottom(&d.s);
        if k == 0 {
            sum.s_tr_0 = s_tr;
            sum.s_tr_pred = s_tr;
            sum.v1_0 = d.v1;
            sum.r_e_dot_0_m_s = bottom(&d.x_dot).norm();
        } else {
            sum.v1_max_rise = sum.v1_max_rise.max(d.v1 - v1_prev);
        }
        v1_prev = d.v1;
        sum.v1_end = d.v1;
        sum.s_tr_end = s_tr;
        sum.final_r_e_m = bottom(&d.x).norm();
        sum.final_sigma_e = top(&d.x).norm();
        sum.x_dot_end_norm = d.x_dot.norm();
        sum.max_force_n = sum.max_force_n.max(u.force_body_n.norm());
        sum.max_torque_nm = sum.max_torque_nm.max(u.torque_body_nm.norm());
        if k == steps {
            break;
        }
        // Closed-loop sliding equation for the translation rows (M2 = mI, Ṁ2 = 0):
        // Ṡ_tr = −β k4‖B2‖ sat(S/ε)/m − k_r S  (d_b ≈ 0: differential J2 ~1e-8 m/s²).
        let b2 = 4.0 / (1.0 + top(&d.x).norm_squared());
        let sp = sum.s_tr_pred;
        let rate = sp.map(|v| {
            -d.beta * p.k4_n * b2 * (v / p.boundary_layer).clamp(-1.0, 1.0) / p.chaser_mass_kg
                - p.reaching_gain_per_s * v
        });
        sum.s_tr_pred = sp + rate * dt;
        plant = plant.rk4(t, dt, &cfg, &u);
    }
    sum
}

/// Initial chaser attitude relative to D0 in the paper-gain runs (paper silent): ≈ 20°.
fn sigma0_paper() -> Vector3<f64> {
    Vector3::new(0.05, -0.05, 0.05)
}

#[test]
fn val_guo2016_sliding_equation_in_plant() {
    // Reference: the closed-loop sliding equation the law is built to enforce,
    // M Ṡ = −½ṀS − k_r M S − β k4‖B2‖ sat(S/ε) (eq 35 proof, no disturbance), integrated
    // alongside the independent plant for the translation rows (M2 = m I, Ṁ2 = 0).
    // Paper gains, undisturbed, 100 s. The zero-order hold adds, during the initial
    // ẍ ≈ −k1 ẋ transient, an error ≈ ½ k1 dt |ṙ_e(0)| per component; the tolerance is
    // twice that. V1 = ½SᵀMS must not grow (eq 35) beyond the same ZOH effect.
    let p = Guo2016Params::paper();
    let dt = 0.01;
    let r = run_section5(&p, 100.0, dt, sigma0_paper(), false);
    let tol = p.k1_per_s * dt * r.r_e_dot_0_m_s;
    let err = (r.s_tr_end - r.s_tr_pred).amax();
    eprintln!(
        "sliding eq.: S_tr(0) {:?} S_tr(T) {:?} predicted {:?}, err {err:.3e} tol {tol:.3e}; V1 {:.6e} -> {:.6e} (max rise {:.3e})",
        r.s_tr_0.as_slice(),
        r.s_tr_end.as_slice(),
        r.s_tr_pred.as_slice(),
        r.v1_0,
        r.v1_end,
        r.v1_max_rise
    );
    assert!(err < tol);
    assert!(r.v1_end < r.v1_0);
    // ZOH: per-step V1 rise bounded by S·M·ΔṠ with ΔṠ ~ k1²dt·|ẋ|·dt; use |S|·m·k1·tol·dt.
    assert!(r.v1_max_rise < r.s_tr_0.norm() * p.chaser_mass_kg * p.k1_per_s * tol * dt);
}

#[test]
fn regress_guo2016_paper_gains_section5() {
    // The Section 5 case with the paper's gains, J2 and d_τ, RK4 at 0.01 s, 100 s
    // (the paper's horizon is in its lost figures).
    // Finding 1 (asserted): the errors cannot converge. With k4 = 0.005 the reaching law
    // changes each translational S component by at most β k4‖B2‖/m ≤ 2e-4 m/s² (ε-sat,
    // ‖B2‖ ≤ 4, β ≈ 1), while |S_tr(0)| ≈ 400 m/s; and the disturbance torque enters the
    // translation rows through ω̇×r_b (m|r_b||J⁻¹d_τ| ≈ 0.8 N ≫ k4). On S ≈ S(0) the state
    // settles at x ≈ S(0)/k1, i.e. the chaser stops near where it started.
    // Finding 2 (asserted): h stays > 0 with k2 = 0.02 and also with k2 = 0; the two runs
    // differ by less than the barrier can cause (k2/h_min² ≈ 1e-7 relative change of β).
    let p = Guo2016Params::paper();
    let dt = 0.01;
    let horizon = 100.0;
    let a = run_section5(&p, horizon, dt, sigma0_paper(), true);
    let mut p0 = p.clone();
    p0.k2_m4 = 0.0;
    let b = run_section5(&p0, horizon, dt, sigma0_paper(), true);
    eprintln!("paper gains k2=0.02: {a:?}");
    eprintln!("paper gains k2=0   : {b:?}");
    // reaching bound on |ΔS_tr| over the horizon, plus the d_τ coupling through ω̇×r_b
    let reach = 4.0 * p.k4_n / p.chaser_mass_kg * horizon;
    let j_inv = p.chaser_inertia_body_kg_m2.try_inverse().unwrap();
    let coupling = (j_inv * Vector3::new(1.0, 2.0, 3.0) * 1e-3).norm() * 45.0 * horizon;
    assert!((a.s_tr_end - a.s_tr_0).amax() < reach + coupling);
    let r_e_min = (a.s_tr_0.norm() - (reach + coupling) * 3f64.sqrt()) / p.k1_per_s
        - a.x_dot_end_norm / p.k1_per_s;
    assert!(
        a.final_r_e_m > r_e_min && r_e_min > 1.0,
        "{} {r_e_min}",
        a.final_r_e_m
    );
    assert!(a.first_exit_s.is_none() && a.min_h_m2 > 0.0);
    assert!(b.first_exit_s.is_none() && b.min_h_m2 > 0.0);
    let beta_rel = p.k2_m4 / (a.min_h_m2 * a.min_h_m2);
    assert!((a.final_r_e_m - b.final_r_e_m).abs() < 10.0 * beta_rel * a.final_r_e_m + 1e-9);
}

#[test]
fn regress_guo2016_barrier_crossed_at_1ms_step() {
    // Same variant as below (k_r = 1/s, aligned start) at a 1 ms step, 2.5 s. On the
    // surface βẋ = S − k1x is continuous, so the approach speed v (tens of m/s) must be
    // killed inside the layer h ≲ √k2 (δ ~ mm thick): a deceleration ~v²/δ ~ 1e5–1e6 m/s²
    // over ~δ/v ~ 1e-4 s. No practical fixed step resolves that; the barrier is crossed.
    // Measured: k2 = 0.02 exits at 1.922 s (k2 = 0: 0.511 s) with |F| up to 2.1e7 N; at
    // 0.1 ms it exits at 0.524 s with 8.8e9 N (not run here for time); without σ_d(t)
    // it exits at 0.511 s. Asserted: the chaser leaves the corridor with the barrier on.
    let mut p = Guo2016Params::paper();
    p.reaching_gain_per_s = 1.0;
    let a = run_section5(&p, 2.5, 1e-3, Vector3::zeros(), true);
    p.k2_m4 = 0.0;
    let b = run_section5(&p, 2.5, 1e-3, Vector3::zeros(), true);
    eprintln!(
        "1 ms: k2=0.02 exit {:?} s, max |F| {:.3e} N; k2=0 exit {:?} s, max |F| {:.3e} N",
        a.first_exit_s, a.max_force_n, b.first_exit_s, b.max_force_n
    );
    assert!(a.first_exit_s.is_some() && b.first_exit_s.is_some());
}

#[test]
fn regress_guo2016_reaching_variant_leaves_corridor() {
    // Not the paper's law: with the optional linear reaching gain k_r = 1/s (so that S → 0),
    // start aligned with D0 (σ(0) = 0), J2 and d_τ on, RK4 0.01 s, 20 s.
    // Asserted: the errors converge below |r_e| < 1 cm and |σ_e| < 1e-4 (on S = 0,
    // x decays at k1/β ≈ 9/s), and the law sampled every 0.01 s
    // leaves the corridor with k2 = 0 **and** with k2 = 0.02: the straight line
    // r1(0) → [2,0,0] m crosses the wall for tan θ = 5 (h ≈ −65 m² at its midpoint), and
    // the barrier k2/h² only acts for h ≲ √k2 ≈ 0.14 m² (a sub-millimetre layer) which the
    // held command carries the chaser through. A property of the sampling: in continuous
    // time β → ∞ stops the body-frame motion at the wall (`reproduce::guo2016_ct`).
    let mut p = Guo2016Params::paper();
    p.reaching_gain_per_s = 1.0;
    let a = run_section5(&p, 20.0, 0.01, Vector3::zeros(), true);
    p.k2_m4 = 0.0;
    let b = run_section5(&p, 20.0, 0.01, Vector3::zeros(), true);
    eprintln!("k_r=1 k2=0.02: {a:?}");
    eprintln!("k_r=1 k2=0   : {b:?}");
    for r in [&a, &b] {
        assert!(r.final_r_e_m < 0.01 && r.final_sigma_e < 1e-4);
        assert!(r.first_exit_s.is_some() && r.min_h_m2 < 0.0);
    }
    let c = p.corridor();
    let mid = (Vector3::new(14.9, 17.1, 37.7) + Vector3::new(2.0, 0.0, 0.0)) * 0.5;
    assert!(c.h(&mid) < 0.0);
}

mod scene_spec_tests {
    //! The scene entry against the paper's parameter set and RON text written by hand.
    use super::*;

    #[test]
    fn regress_guo2016_scene_spec_ron_and_paper_values() {
        let text = r#"(chaser: "c", target: "t", k1_per_s: 9.0, k2_m4: 0.02, k3: 1.0, k4_n: 0.005,
            corridor_a_m: 25.0, corridor_tan_theta: 5.0, r_d_body_m: (2.0, 0.0, 0.0),
            sigma_d_amplitude: (0.001, 0.001, 0.001),
            disturbance_torque_amplitude_nm: (0.001, 0.002, 0.003))"#;
        let s: Guo2016Spec = ron::from_str(text).unwrap();
        assert!(s.validate().is_ok());
        let want = Guo2016Spec::paper("c", "t");
        let j = Matrix3::from_diagonal(&Vector3::new(15.0, 17.0, 20.0));
        let (a, b) = (s.params(100.0, j), Guo2016Params::paper());
        assert_eq!(
            serde_json::to_string(&a).unwrap(),
            serde_json::to_string(&b).unwrap()
        );
        assert_eq!(
            serde_json::to_string(&s).unwrap(),
            serde_json::to_string(&want).unwrap()
        );
        // Unknown fields and bad numbers are refused, naming the field.
        assert!(ron::from_str::<Guo2016Spec>(&text.replace("k3:", "k3_typo:")).is_err());
        let mut bad = s.clone();
        bad.corridor_tan_theta = -1.0;
        assert_eq!(bad.validate().unwrap_err().0, "corridor_tan_theta");
        let mut bad = s;
        *bad.sigma_d_time_constant_s = [40.0, 0.0, 60.0];
        assert_eq!(bad.validate().unwrap_err().0, "sigma_d_time_constant_s");
    }
}
