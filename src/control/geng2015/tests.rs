//! References: an independent f64 inertial simulation written here (two-body gravity,
//! Euler's rigid-body equations, Hamilton quaternion kinematics, RK4), finite differences of
//! its poses, and closed-form algebra. Paper numbers are Table 3.
use super::*;
use nalgebra::{Quaternion, SVector};

type S13 = SVector<f64, 13>;
const MU: f64 = MU_EARTH_M3_S2;

/// Tiny deterministic generator (SplitMix64) for random states.
struct Rng(u64);
impl Rng {
    fn next(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
    }
    fn v3(&mut self, s: f64) -> Vector3<f64> {
        Vector3::new(self.next(), self.next(), self.next()) * s
    }
    fn quat(&mut self) -> UnitQuaternion<f64> {
        UnitQuaternion::from_quaternion(Quaternion::new(
            self.next(),
            self.next(),
            self.next(),
            self.next(),
        ))
    }
}

/// Keplerian elements (a m, e, i, Ω, ω, θ rad) → ECI position, velocity.
fn kepler_to_eci(
    a: f64,
    e: f64,
    i: f64,
    raan: f64,
    argp: f64,
    nu: f64,
) -> (Vector3<f64>, Vector3<f64>) {
    let p = a * (1.0 - e * e);
    let r = p / (1.0 + e * nu.cos());
    let r_pf = Vector3::new(r * nu.cos(), r * nu.sin(), 0.0);
    let v_pf = (MU / p).sqrt() * Vector3::new(-nu.sin(), e + nu.cos(), 0.0);
    let rot = nalgebra::Rotation3::from_axis_angle(&Vector3::z_axis(), raan)
        * nalgebra::Rotation3::from_axis_angle(&Vector3::x_axis(), i)
        * nalgebra::Rotation3::from_axis_angle(&Vector3::z_axis(), argp);
    (rot * r_pf, rot * v_pf)
}

fn pack(b: &BodyStateEci) -> S13 {
    let q = b.att_body_to_eci.quaternion();
    let mut y = S13::zeros();
    y.fixed_rows_mut::<3>(0).copy_from(&b.pos_eci_m);
    y.fixed_rows_mut::<3>(3).copy_from(&b.vel_eci_m_s);
    y[6] = q.w;
    y[7] = q.i;
    y[8] = q.j;
    y[9] = q.k;
    y.fixed_rows_mut::<3>(10).copy_from(&b.rate_body_rad_s);
    y
}
fn unpack(y: &S13) -> BodyStateEci {
    BodyStateEci {
        pos_eci_m: y.fixed_rows::<3>(0).into(),
        vel_eci_m_s: y.fixed_rows::<3>(3).into(),
        att_body_to_eci: UnitQuaternion::from_quaternion(Quaternion::new(y[6], y[7], y[8], y[9])),
        rate_body_rad_s: y.fixed_rows::<3>(10).into(),
    }
}

/// Forces on one body: body-fixed acceleration (control/m + disturbance) and torque, as a
/// function of (t, state).
type Load<'a> = &'a dyn Fn(f64, &BodyStateEci) -> (Vector3<f64>, Vector3<f64>);

/// Rigid body in inertial space: r̈ = −μr/r³ + R a_body; q̇ = ½ q ⊗ ω; J ω̇ = τ − ω × Jω.
fn deriv(t: f64, y: &S13, j: &Matrix3<f64>, load: Load) -> S13 {
    let q = Quaternion::new(y[6], y[7], y[8], y[9]);
    let w: Vector3<f64> = y.fixed_rows::<3>(10).into();
    let r: Vector3<f64> = y.fixed_rows::<3>(0).into();
    let b = BodyStateEci {
        pos_eci_m: r,
        vel_eci_m_s: y.fixed_rows::<3>(3).into(),
        att_body_to_eci: UnitQuaternion::new_normalize(q),
        rate_body_rad_s: w,
    };
    let (acc_b, tq_b) = load(t, &b);
    let acc = -MU / r.norm().powi(3) * r + b.att_body_to_eci * acc_b;
    let qd = q * Quaternion::from_imag(w) * 0.5;
    let wd = j.try_inverse().unwrap() * (tq_b - w.cross(&(j * w)));
    let mut d = S13::zeros();
    d.fixed_rows_mut::<3>(0).copy_from(&b.vel_eci_m_s);
    d.fixed_rows_mut::<3>(3).copy_from(&acc);
    d[6] = qd.w;
    d[7] = qd.i;
    d[8] = qd.j;
    d[9] = qd.k;
    d.fixed_rows_mut::<3>(10).copy_from(&wd);
    d
}

fn rk4(t: f64, y: &S13, h: f64, j: &Matrix3<f64>, load: Load) -> S13 {
    let k1 = deriv(t, y, j, load);
    let k2 = deriv(t + h / 2.0, &(y + k1 * (h / 2.0)), j, load);
    let k3 = deriv(t + h / 2.0, &(y + k2 * (h / 2.0)), j, load);
    let k4 = deriv(t + h, &(y + k3 * h), j, load);
    let mut n = y + (k1 + k2 * 2.0 + k3 * 2.0 + k4) * (h / 6.0);
    let qn = n.fixed_rows::<4>(6).norm();
    n.fixed_rows_mut::<4>(6).scale_mut(1.0 / qn);
    n
}

/// Table 1 initial states: both bodies aligned with their own orbital frame (q_v0 = 0), chaser at rest
/// w.r.t. its orbital frame, target tumbling at [−3, 2, 3] °/s w.r.t. its orbital frame.
fn table1() -> (BodyStateEci, BodyStateEci) {
    let d = std::f64::consts::PI / 180.0;
    let body = |i: f64, raan: f64, nu: f64, rel_rate: Vector3<f64>| {
        let (r, v) = kepler_to_eci(7170.0e3, 0.05, i * d, raan * d, 10.0 * d, nu * d);
        let (a, w, _) = hill_frame(&r, &v);
        let q = UnitQuaternion::from_rotation_matrix(&nalgebra::Rotation3::from_matrix_unchecked(
            a.transpose(),
        ));
        BodyStateEci {
            pos_eci_m: r,
            vel_eci_m_s: v,
            att_body_to_eci: q,
            rate_body_rad_s: rel_rate + w,
        }
    };
    (
        body(15.0, 30.0, 20.0, Vector3::zeros()),
        body(15.0002, 30.0001, 20.0002, Vector3::new(-3.0, 2.0, 3.0) * d),
    )
}

fn random_obs(rng: &mut Rng) -> Geng2015Obs {
    let (mut s, mut t) = table1();
    s.pos_eci_m += rng.v3(20.0);
    s.vel_eci_m_s += rng.v3(0.5);
    s.att_body_to_eci = rng.quat();
    t.att_body_to_eci = rng.quat();
    s.rate_body_rad_s = rng.v3(0.1);
    t.rate_body_rad_s = rng.v3(0.1);
    Geng2015Obs {
        t_s: 0.0,
        chaser: s,
        target: t,
    }
}

fn params(frame: RhoFrame) -> Geng2015Params {
    Geng2015Params {
        rho_frame: frame,
        ..Geng2015Params::paper()
    }
}

#[test]
fn invariant_geng2015_b_inverse() {
    // B·B⁻¹ = I (closed-form block inverse) at random states, both ρ frames; G⁻¹G = I near
    // q_r0 → 0 and the 1/q_r0 growth of ‖G⁻¹‖ (det G = q_r0/8).
    let mut rng = Rng(7);
    for frame in [RhoFrame::TargetHill, RhoFrame::TargetBody] {
        let p = params(frame);
        for _ in 0..200 {
            let obs = random_obs(&mut rng);
            let (rel, _, b) = port_model(&p, &obs);
            if rel.q_r.w < 10.0 * Q_R0_FLOOR {
                continue;
            }
            let a_s = obs
                .chaser
                .att_body_to_eci
                .to_rotation_matrix()
                .into_inner()
                .transpose();
            let bi = b_inverse(&p, &(rel.a_f * a_s.transpose()), &rel.q_r);
            let err = (b * bi - Matrix6::identity()).abs().max();
            assert!(err < 1e-10, "B·B⁻¹ − I = {err}");
            let err2 = (bi * b - Matrix6::identity()).abs().max();
            assert!(err2 < 1e-10, "B⁻¹·B − I = {err2}");
        }
    }
    for q0 in [1e-1f64, 1e-2, 2e-3] {
        let v = Vector3::new(1.0, -2.0, 0.5).normalize() * (1.0 - q0 * q0).sqrt();
        let q = UnitQuaternion::new_unchecked(Quaternion::from_parts(q0, v));
        let gi = g_inverse(&q);
        assert!((gi * g_matrix(&q) - Matrix3::identity()).abs().max() < 1e-10);
        // ‖G⁻¹‖₂ = 2/q0 along v: G v = ½ q0 v.
        let growth = (gi * v).norm() / v.norm();
        assert!((growth - 2.0 / q0).abs() < 1e-9 * growth);
    }
}
/// Advance both bodies by h (may be negative) under body-fixed loads.
fn step_pair(
    t: f64,
    obs: &Geng2015Obs,
    h: f64,
    p: &Geng2015Params,
    ls: Load,
    lt: Load,
) -> Geng2015Obs {
    let ys = rk4(t, &pack(&obs.chaser), h, &p.chaser_inertia_kg_m2, ls);
    let yt = rk4(t, &pack(&obs.target), h, &p.target_inertia_kg_m2, lt);
    Geng2015Obs {
        t_s: t + h,
        chaser: unpack(&ys),
        target: unpack(&yt),
    }
}

#[test]
fn val_geng2015_relative_kinematics() {
    // ρ̇ and q̇_rv = G ω_r against central differences of ρ, q_rv computed from poses
    // propagated by the inertial simulation; q̇_r = ½ q_r ⊗ ω_r; A(q_r) = A_s A_tᵀ.
    // Error budget (h = 2 ms): truncation h²/6·|d³ρ/dt³| ≤ 4e-7 m/s (ω³ρ ≈ 0.3³·60 m/s³),
    // roundoff ulp(7e6 m)/h ≈ 5e-7 m/s → tolerance 5e-6 m/s; q: ~1e-9.
    let mut rng = Rng(11);
    let free: Load = &|_, _| (Vector3::zeros(), Vector3::zeros());
    let h = 2e-3;
    for frame in [RhoFrame::TargetHill, RhoFrame::TargetBody] {
        let p = params(frame);
        for _ in 0..20 {
            let obs = random_obs(&mut rng);
            let rel = relative_state(&p, &obs);
            let fw = relative_state(&p, &step_pair(0.0, &obs, h, &p, free, free));
            let bw = relative_state(&p, &step_pair(0.0, &obs, -h, &p, free, free));
            let rho_fd = (fw.rho_m - bw.rho_m) / (2.0 * h);
            assert!(
                (rho_fd - rel.rho_dot_m_s).norm() < 5e-6,
                "{frame:?} ρ̇ {rho_fd} vs {}",
                rel.rho_dot_m_s
            );
            let q_fd = (fw.q_r.into_inner() - bw.q_r.into_inner()) / (2.0 * h);
            let q_model = rel.q_r.into_inner() * Quaternion::from_imag(rel.omega_r_rad_s) * 0.5;
            assert!(
                (q_fd - q_model).norm() < 1e-8,
                "q̇_r {q_fd:?} vs {q_model:?}"
            );
            let xd = rel.x_dot();
            assert!((Vector3::new(xd[3], xd[4], xd[5]) - q_fd.imag()).norm() < 1e-8);
            let a_s = obs
                .chaser
                .att_body_to_eci
                .to_rotation_matrix()
                .into_inner()
                .transpose();
            let a_t = obs
                .target
                .att_body_to_eci
                .to_rotation_matrix()
                .into_inner()
                .transpose();
            let a_q = rel.q_r.to_rotation_matrix().into_inner().transpose();
            assert!((a_q - a_s * a_t.transpose()).abs().max() < 1e-12);
            assert!(rel.q_r.w >= 0.0);
        }
    }
}

/// ë by a central difference of ẋ over the inertial simulation with the given loads.
fn e_ddot_fd(obs: &Geng2015Obs, p: &Geng2015Params, ls: Load, lt: Load, h: f64) -> Vector6<f64> {
    let fw = relative_state(p, &step_pair(obs.t_s, obs, h, p, ls, lt));
    let bw = relative_state(p, &step_pair(obs.t_s, obs, -h, p, ls, lt));
    (fw.x_dot() - bw.x_dot()) / (2.0 * h)
}

#[test]
fn val_geng2015_model_and_b_finite_difference() {
    // The coupled model ë = sys + B u + Δ against the inertial simulation: (a) each column
    // of B equals [ë(u = e_j) − ë(0)] by central differences of ẋ; (b) the whole right side,
    // with the paper's disturbances (a_d, T_d, T_g) applied to both bodies, equals ë.
    // Error budget (h = 1 ms): truncation h²/6·|x''''| ≤ 1e-7·(ω⁴ρ ≈ 0.17⁴·60) ≈ 5e-9,
    // roundoff ulp(7.5e3 m/s)/(2h) ≈ 5e-10 → 1e-7 (translation), 1e-9 (q_rv).
    let mut rng = Rng(23);
    let h = 1e-3;
    let dist = Geng2015Disturbances::paper_periodic((MU / 7170.0e3f64.powi(3)).sqrt());
    for frame in [RhoFrame::TargetHill, RhoFrame::TargetBody] {
        let p = params(frame);
        let m = p.chaser_mass_kg;
        for k in 0..10 {
            let mut obs = random_obs(&mut rng);
            obs.t_s = 10.0 * k as f64;
            let (_, sys, b) = port_model(&p, &obs);
            let tol = Vector6::new(1e-7, 1e-7, 1e-7, 1e-9, 1e-9, 1e-9);
            let free: Load = &|_, _| (Vector3::zeros(), Vector3::zeros());
            let e0 = e_ddot_fd(&obs, &p, free, free, h);
            for j in 0..6 {
                let mut u = Vector6::zeros();
                u[j] = if j < 3 { 40.0 } else { 0.8 };
                let f = Vector3::new(u[0], u[1], u[2]) / m;
                let tq = Vector3::new(u[3], u[4], u[5]);
                let ls: Load = &move |_, _| (f, tq);
                let col = (e_ddot_fd(&obs, &p, ls, free, h) - e0) / u[j];
                for i in 0..6 {
                    assert!(
                        (col[i] - b[(i, j)]).abs() * u[j] < 2.0 * tol[i],
                        "{frame:?} B[{i},{j}] fd {} model {}",
                        col[i],
                        b[(i, j)]
                    );
                }
            }
            let u = Vector6::from_fn(|i, _| rng.next() * if i < 3 { 48.0 } else { 0.8 });
            let f = Vector3::new(u[0], u[1], u[2]) / m;
            let tq = Vector3::new(u[3], u[4], u[5]);
            let (pc, dc) = (p.clone(), dist.clone());
            let ls = move |t: f64, bs: &BodyStateEci| {
                let (a, tg) = dc.chaser(MU, &pc, t, bs);
                (f + a, tq + tg)
            };
            let (pt, dt) = (p.clone(), dist.clone());
            let lt = move |t: f64, bt: &BodyStateEci| dt.target(MU, &pt, t, bt);
            let e_fd = e_ddot_fd(&obs, &p, &ls, &lt, h);
            let (ac, tc) = dist.chaser(MU, &p, obs.t_s, &obs.chaser);
            let (at, tt) = dist.target(MU, &p, obs.t_s, &obs.target);
            let delta = disturbance_effect(&p, &obs, &ac, &tc, &at, &tt);
            let model = sys + b * u + delta;
            for i in 0..6 {
                assert!(
                    (e_fd[i] - model[i]).abs() < tol[i],
                    "{frame:?} ë[{i}] fd {} model {}",
                    e_fd[i],
                    model[i]
                );
            }
            // Δ is not negligible against the tolerance, so (b) really checks it.
            assert!(delta.fixed_rows::<3>(0).norm() > 10.0 * tol[0]);
        }
    }
}

/// One closed-loop run: samples at the controller period.
struct Run {
    t: Vec<f64>,
    /// [ρ m; ρ̇ m/s] in the ρ frame.
    trans: Vec<Vector6<f64>>,
    /// [relative attitude angles 2·q_rv deg; ω_r deg/s].
    rot: Vec<Vector6<f64>>,
    /// Applied u = [F N; T N·m].
    u: Vec<Vector6<f64>>,
    /// Exact Δ from the applied disturbances.
    delta: Vec<Vector6<f64>>,
    rate_max: (f64, f64),
    rho_max: (f64, f64),
}

/// Closed loop on the Table 1 orbits: chaser under `law` (zero-order hold at `dt`),
/// target uncontrolled and tumbling, the paper's disturbances on both bodies, RK4 at `dt`.
fn closed_loop(law: Geng2015Law, frame: RhoFrame, linear: bool, t_end: f64, dt: f64) -> Run {
    closed_loop_with(law, params(frame), linear, t_end, dt)
}

fn closed_loop_with(law: Geng2015Law, p: Geng2015Params, linear: bool, t_end: f64, dt: f64) -> Run {
    let n = (MU / 7170.0e3f64.powi(3)).sqrt();
    let dist = if linear {
        Geng2015Disturbances::paper_linear(n)
    } else {
        Geng2015Disturbances::paper_periodic(n)
    };
    let mut ctrl = Geng2015Twisting::new(law, p.clone());
    let (s0, t0) = table1();
    let mut obs = Geng2015Obs {
        t_s: 0.0,
        chaser: s0,
        target: t0,
    };
    let steps = (t_end / dt).round() as usize;
    let mut run = Run {
        t: vec![],
        trans: vec![],
        rot: vec![],
        u: vec![],
        delta: vec![],
        rate_max: (0.0, 0.0),
        rho_max: (0.0, 0.0),
    };
    let deg = 180.0 / std::f64::consts::PI;
    for k in 0..steps {
        let t = k as f64 * dt;
        obs.t_s = t;
        let (f, tq) = ctrl.command(&obs);
        let rel = relative_state(&p, &obs);
        let (ac, tc) = dist.chaser(MU, &p, t, &obs.chaser);
        let (at, tt) = dist.target(MU, &p, t, &obs.target);
        run.t.push(t);
        let (r, v) = (rel.rho_m, rel.rho_dot_m_s);
        run.trans.push(Vector6::new(r.x, r.y, r.z, v.x, v.y, v.z));
        let (a, w) = (rel.q_r.imag() * 2.0 * deg, rel.omega_r_rad_s * deg);
        run.rot.push(Vector6::new(a.x, a.y, a.z, w.x, w.y, w.z));
        run.u.push(Vector6::new(f.x, f.y, f.z, tq.x, tq.y, tq.z));
        run.delta
            .push(disturbance_effect(&p, &obs, &ac, &tc, &at, &tt));
        run.rate_max.0 = run.rate_max.0.max(obs.chaser.rate_body_rad_s.norm());
        run.rate_max.1 = run.rate_max.1.max(obs.target.rate_body_rad_s.norm());
        run.rho_max.0 = run.rho_max.0.max(r.norm());
        run.rho_max.1 = run.rho_max.1.max(v.norm());
        let (pc, dc) = (p.clone(), dist.clone());
        let m = p.chaser_mass_kg;
        let ls = move |t: f64, bs: &BodyStateEci| {
            let (a, tg) = dc.chaser(MU, &pc, t, bs);
            (f / m + a, tq + tg)
        };
        let (pt, dtg) = (p.clone(), dist.clone());
        let lt = move |t: f64, bt: &BodyStateEci| dtg.target(MU, &pt, t, bt);
        obs = step_pair(t, &obs, dt, &p, &ls, &lt);
    }
    run
}

/// The paper's accuracy: |mean| + 3σ of each component over [t0, t1].
fn accuracy(t: &[f64], x: &[Vector6<f64>], t0: f64, t1: f64) -> Vector6<f64> {
    let sel: Vec<&Vector6<f64>> = t
        .iter()
        .zip(x)
        .filter(|(t, _)| **t >= t0 && **t <= t1)
        .map(|(_, x)| x)
        .collect();
    let n = sel.len() as f64;
    let mean = sel.iter().fold(Vector6::zeros(), |a, x| a + **x) / n;
    let var = sel.iter().fold(Vector6::zeros(), |a, x| {
        a + (**x - mean).component_mul(&(**x - mean))
    }) / n;
    mean.abs() + var.map(f64::sqrt) * 3.0
}

/// Chattering over [t0, t1] per actuator channel: (sign changes of u per second, reversals of
/// the increment Δu per second, total variation Σ|Δu| per second).
fn chattering(
    t: &[f64],
    u: &[Vector6<f64>],
    t0: f64,
    t1: f64,
) -> (Vector6<f64>, Vector6<f64>, Vector6<f64>) {
    let idx: Vec<usize> = (0..t.len()).filter(|&k| t[k] >= t0 && t[k] <= t1).collect();
    let dur = t1 - t0;
    let (mut sc, mut rev, mut tv) = (Vector6::zeros(), Vector6::zeros(), Vector6::zeros());
    for i in 0..6 {
        let mut last_inc = 0.0;
        for w in idx.windows(2) {
            let (a, b) = (u[w[0]][i], u[w[1]][i]);
            if a * b < 0.0 {
                sc[i] += 1.0;
            }
            let inc = b - a;
            if inc != 0.0 {
                if inc * last_inc < 0.0 {
                    rev[i] += 1.0;
                }
                last_inc = inc;
            }
            tv[i] += inc.abs();
        }
    }
    (sc / dur, rev / dur, tv / dur)
}

fn f6(v: &Vector6<f64>) -> String {
    v.iter()
        .map(|x| format!("{x:.2e}"))
        .collect::<Vec<_>>()
        .join(" ")
}

fn window(law: Geng2015Law) -> (f64, f64) {
    match law {
        Geng2015Law::T1 | Geng2015Law::T2 => (150.0, 200.0),
        Geng2015Law::M1 | Geng2015Law::M2 => (50.0, 100.0),
    }
}

struct Metrics {
    trans: Vector6<f64>,
    rot: Vector6<f64>,
    tv: Vector6<f64>,
    sign_changes: Vector6<f64>,
    final_rho_m: f64,
}

/// Controller period (zero-order hold) and RK4 step of the Table 3 runs, s. The paper does
/// not state it; 50 ms reproduces Table 3's rotation columns for T1 and M1 to ≤ 11 %
/// (ω_r to 3 digits), while 10 ms gives 7–10× smaller errors for T1 (see the report).
const PAPER_DT_S: f64 = 0.05;

/// The eight Table 3 runs (4 laws × 2 disturbance forms, each to the end of its accuracy
/// window), computed once and shared by the tests that read them (≈ 24k RK4 steps: ~0.1 s
/// in release, a few s in debug).
fn paper_run(law: Geng2015Law, linear: bool) -> &'static Run {
    static RUNS: std::sync::OnceLock<Vec<(Geng2015Law, bool, Run)>> = std::sync::OnceLock::new();
    let runs = RUNS.get_or_init(|| {
        let mut v = vec![];
        for linear in [true, false] {
            for law in [
                Geng2015Law::T1,
                Geng2015Law::T2,
                Geng2015Law::M1,
                Geng2015Law::M2,
            ] {
                let (_, t1) = window(law);
                v.push((
                    law,
                    linear,
                    closed_loop(law, RhoFrame::TargetHill, linear, t1, PAPER_DT_S),
                ));
            }
        }
        v
    });
    &runs
        .iter()
        .find(|(l, lin, _)| *l == law && *lin == linear)
        .unwrap()
        .2
}

fn metrics(law: Geng2015Law, linear: bool) -> Metrics {
    let (t0, t1) = window(law);
    let run = paper_run(law, linear);
    let (sc, _, tv) = chattering(&run.t, &run.u, t0, t1);
    let m = Metrics {
        trans: accuracy(&run.t, &run.trans, t0, t1),
        rot: accuracy(&run.t, &run.rot, t0, t1),
        tv,
        sign_changes: sc,
        final_rho_m: run.trans.last().unwrap().fixed_rows::<3>(0).norm(),
    };
    println!(
        "{law:?} linear={linear}: [ρ m; ρ̇ m/s] {}\n   [angle °; ω_r °/s] {}\n   TV/s [N; N·m] {}\n   sign changes/s {:.1?}",
        f6(&m.trans),
        f6(&m.rot),
        f6(&m.tv),
        m.sign_changes.as_slice()
    );
    m
}

/// Table 3 claims on the closed loop (inertial two-body + rigid-body simulation above, RK4 at
/// the 50 ms controller period, Table 1 start ≈ 36.6 m apart, paper disturbances).
#[test]
fn val_geng2015_table3() {
    use Geng2015Law::*;
    // Paper Table 3, linear a_d case, rotation columns: (angle °, ω_r °/s) per axis.
    let paper_rot_t1 = [1.041e-3, 0.480e-3, 0.458e-3, 3.029e-2, 1.328e-2, 1.329e-2];
    let paper_rot_m1 = [3.621e-5, 4.892e-5, 3.537e-5, 6.829e-4, 13.720e-4, 9.098e-4];
    // Position/velocity columns of T1 and M1 (x, y, z), same case.
    let paper_tr_t1 = [2.649e-4, 4.179e-4, 3.613e-4, 0.715e-2, 1.142e-2, 1.134e-2];
    let paper_tr_m1 = [2.734e-5, 2.916e-5, 2.861e-5, 8.052e-4, 8.723e-4, 8.450e-4];
    for linear in [true, false] {
        let [t1, t2, m1, m2] = [T1, T2, M1, M2].map(|l| metrics(l, linear));
        for m in [&t1, &t2, &m1, &m2] {
            // All four laws dock: port separation at the end of the window below 1 mm.
            assert!(m.final_rho_m < 1e-3, "final |ρ| {}", m.final_rho_m);
        }
        for i in 0..6 {
            // The rotational loop does not see a_d, so both cases share the paper's numbers
            // (as in Table 3). T1 and M1 reproduce them within 25 %; position and velocity
            // within a factor 3 (same order of magnitude).
            let r = |meas: f64, paper: f64| meas / paper;
            assert!(
                (r(t1.rot[i], paper_rot_t1[i]) - 1.0).abs() < 0.25,
                "T1 rot[{i}]"
            );
            assert!(
                (r(m1.rot[i], paper_rot_m1[i]) - 1.0).abs() < 0.25,
                "M1 rot[{i}]"
            );
            for (m, pp) in [(&t1, &paper_tr_t1), (&m1, &paper_tr_m1)] {
                let q = r(m.trans[i], pp[i]);
                assert!((1.0 / 3.0..3.0).contains(&q), "trans[{i}] ratio {q}");
            }
        }
        for i in 0..3 {
            // M1 position accuracy ≥ 5× better than T1 (measured 14–19×; paper ≈ 10×).
            assert!(m1.trans[i] * 5.0 < t1.trans[i], "M1 vs T1 ρ[{i}]");
            // M2 better than T2 on position: every axis with the linear a_d; with the
            // periodic a_d only along-track (y): on x and z M2 is 2.2× worse (not asserted).
            if linear || i == 1 {
                assert!(m2.trans[i] < t2.trans[i], "M2 vs T2 ρ[{i}]");
            }
            // M1 better than M2 on position, M2 better than M1 on velocity (Table 3, §2.3):
            // hold on every axis in both cases.
            assert!(m1.trans[i] < m2.trans[i], "M1 vs M2 ρ[{i}]");
            assert!(m2.trans[i + 3] < m1.trans[i + 3], "M2 vs M1 ρ̇[{i}]");
        }
        for i in 0..6 {
            // Much less chattering for M, measured as total variation of the applied
            // command per second: ≥ 5× for M1 vs T1 on every channel, ≥ 5× for M2 vs T2 on
            // the torques, but only 1.2–4.5× on the forces (so only "less" is asserted).
            // Sign changes per second are not clearly lower for M (0–18/s for every law).
            assert!(m1.tv[i] * 5.0 < t1.tv[i], "TV M1 vs T1 [{i}]");
            if i < 3 {
                assert!(m2.tv[i] < t2.tv[i], "TV M2 vs T2 [{i}]");
            } else {
                assert!(m2.tv[i] * 5.0 < t2.tv[i], "TV M2 vs T2 [{i}]");
            }
        }
        println!(
            "ratios T1/M1 {:.1?}, T2/M2 {:.1?}, M1/M2 {:.1?}",
            t1.trans.component_div(&m1.trans).as_slice(),
            t2.trans.component_div(&m2.trans).as_slice(),
            m1.trans.component_div(&m2.trans).as_slice()
        );
    }
}

#[test]
fn regress_geng2015_m2_windup_with_difference_sdot() {
    // With ṡ taken as the backward difference of s (the true ṡ, saturation included), M2's
    // linear K3 s + K4 ṡ integrate while the actuators sit at a_max from the 36 m start:
    // the integral ν winds up and the ports drift apart. This is why the default is
    // `SdotEstimate::IntegralState`. (T2's bounded rate α2 + β2 does not wind up:
    // it converges with either estimate, see val_geng2015_table3 for the default.)
    let p = Geng2015Params {
        sdot_estimate: SdotEstimate::BackwardDifference,
        ..Geng2015Params::paper()
    };
    let run = closed_loop_with(Geng2015Law::M2, p, true, 60.0, PAPER_DT_S);
    let rho = |k: usize| run.trans[k].fixed_rows::<3>(0).norm();
    assert!(
        rho(run.t.len() - 1) > rho(0),
        "M2/difference should not converge"
    );
}

#[test]
fn regress_geng2015_target_body_rho_frame_saturates() {
    // The target-body ρ frame: ρ̇ starts at ≈ |ω_t|·36 m ≈ 3 m/s and the frame's
    // centripetal/Coriolis terms exceed a_max = 0.2 m/s², so T1 (and every law) loses the
    // ports; the paper's orbital frame F_o (TargetHill) does not.
    let run = closed_loop(
        Geng2015Law::T1,
        RhoFrame::TargetBody,
        true,
        100.0,
        PAPER_DT_S,
    );
    let rho = |k: usize| run.trans[k].fixed_rows::<3>(0).norm();
    assert!(rho(run.t.len() - 1) > 2.0 * rho(0));
}

/// Shares the runs of `paper_run` with val_geng2015_table3.
#[test]
fn invariant_geng2015_disturbance_bounds_and_twisting_condition() {
    // (a) The bounds D, χ dominate the exact Δ (from the applied disturbances, validated in
    // val_geng2015_model_and_b_finite_difference) and its central difference, sampled along
    // closed-loop runs. (b) The twisting condition α − D > β > D per channel for the
    // Table 2 gains: D for T1/M1 (closed loop sees δ, eq 12), χ for T2/M2 (sees δ̇, eq 14).
    use Geng2015Law::*;
    let p = Geng2015Params::paper();
    let n = (MU / 7170.0e3f64.powi(3)).sqrt();
    for linear in [true, false] {
        let dist = if linear {
            Geng2015Disturbances::paper_linear(n)
        } else {
            Geng2015Disturbances::paper_periodic(n)
        };
        for law in [T1, T2, M1, M2] {
            let (_, t_end) = window(law);
            let run = paper_run(law, linear);
            let env = BoundEnvelope {
                horizon_s: t_end,
                semi_major_axis_m: 7170.0e3,
                eccentricity: 0.05,
                chaser_rate_max_rad_s: run.rate_max.0,
                target_rate_max_rad_s: run.rate_max.1,
                rho_max_m: run.rho_max.0,
                rho_dot_max_m_s: run.rho_max.1,
            };
            let b = disturbance_bounds(&p, &dist, &env);
            let h = run.t[1] - run.t[0];
            for k in 1..run.t.len() - 1 {
                for i in 0..6 {
                    assert!(run.delta[k][i].abs() <= b.d[i], "{law:?} |Δ{i}| > D");
                    let dd = (run.delta[k + 1][i] - run.delta[k - 1][i]) / (2.0 * h);
                    assert!(dd.abs() <= b.chi[i], "{law:?} |Δ̇{i}| {dd} > χ {}", b.chi[i]);
                }
            }
            let (alpha, beta) = p.gains.twisting_pair(law);
            let bound = if matches!(law, T1 | M1) { b.d } else { b.chi };
            let ok = twisting_condition(&alpha, &beta, &bound);
            println!(
                "linear={linear} {law:?}: D {} χ {} condition {ok:?}",
                f6(&b.d),
                f6(&b.chi)
            );
            // Rotation channels hold for every law and both disturbance forms; T2/M2
            // (bounded δ̇) hold on all channels; the periodic case holds everywhere.
            let expect_all = !linear || matches!(law, T2 | M2);
            if expect_all {
                assert!(ok.iter().all(|&c| c), "{law:?} linear={linear}: {ok:?}");
            } else {
                assert!(ok[3..].iter().all(|&c| c));
                // Finding: a_d0(1 + 0.5t) grows ×51 by 100 s, ×101 by 200 s, so
                // D_trans ≈ 1.2e-4·(1 + 0.5t) m/s² exceeds α − β (2e-3 for T1 x/z,
                // 1e-3 for M1): the condition fails on translation for T1 and M1.
                assert!(!ok[0] && !ok[2], "{law:?}: {ok:?}");
            }
        }
    }
}

#[test]
fn val_geng2015_convergence_time_bound() {
    // Eq (10) against an independent simulation of the scalar loop (8),
    // ẋ = y, ẏ = −α sgn x − β sgn y − r1 x − r2 y + μ(t), |μ| ≤ D, integrated with a fine
    // Euler step (1e-5 s); convergence = entering |x| + |y| < 1e-3. T_f must bound it.
    let (alpha, beta, d, r1, r2) = (2.0f64, 1.0, 0.5, 1.0, 1.0);
    let gamma_max = 4.0 * 2f64.sqrt() / 3.0 * (beta - d) * alpha.sqrt();
    let gamma = 0.5 * gamma_max;
    for (x0, y0) in [(1.0, 0.0), (-2.0, 1.0), (0.5, -3.0)] {
        let tf = convergence_time_bound_s(alpha, beta, d, gamma, r1, r2, x0, y0).unwrap();
        for mu in [
            |t: f64| 0.5 * (3.0 * t).sin(),
            |_t: f64| 0.5,
            |t: f64| -0.5 * (t * 0.7).cos(),
        ] {
            let (mut x, mut y, mut t) = (x0, y0, 0.0);
            let h = 1e-5;
            while x.abs() + y.abs() >= 1e-3 && t < tf {
                let yd = -alpha * sgn(x) - beta * sgn(y) - r1 * x - r2 * y + mu(t);
                x += h * y;
                y += h * yd;
                t += h;
            }
            assert!(t < tf, "converged at {t} s, bound {tf} s");
        }
        // W decreases along the bound: W(x0, y0) > 0 and W is positive definite.
        assert!(lyapunov_w(alpha, gamma, r1, r2, x0, y0) > 0.0);
    }
    // Premises: the bound refuses gains that violate α − β − D > 0 or β > D.
    assert!(convergence_time_bound_s(1.0, 0.8, 0.5, 0.1, 1.0, 1.0, 1.0, 0.0).is_none());
    assert!(convergence_time_bound_s(2.0, 0.4, 0.5, 0.1, 1.0, 1.0, 1.0, 0.0).is_none());
}

#[test]
fn invariant_geng2015_params_serde_roundtrip() {
    // Scene files carry these structs: a JSON round trip keeps every value, and unknown
    // fields are refused.
    let p = Geng2015Params::paper();
    let back: Geng2015Params = serde_json::from_str(&serde_json::to_string(&p).unwrap()).unwrap();
    assert_eq!(back.gains.m2_k4, p.gains.m2_k4);
    assert_eq!(back.chaser_inertia_kg_m2, p.chaser_inertia_kg_m2);
    assert_eq!(back.rho_frame, p.rho_frame);
    let mut v: serde_json::Value = serde_json::to_value(&p).unwrap();
    v["bogus_m"] = serde_json::json!(1.0);
    assert!(serde_json::from_value::<Geng2015Params>(v).is_err());
    let d = Geng2015Disturbances::paper_periodic(1e-3);
    let back: Geng2015Disturbances =
        serde_json::from_str(&serde_json::to_string(&d).unwrap()).unwrap();
    assert_eq!(back.chaser_form, AccelDisturbanceForm::Sine);
}
