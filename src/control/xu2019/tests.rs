use super::*;
use crate::actuation::thrusters::{ThrusterParams, ThrusterPwpf};

/// Reference: central finite differences of `potential` (an independent evaluation of
/// eqs 12–14). The true gradient must match everywhere off the shapes' kinks; the printed
/// gradient matches only the attractive part, and its difference is reported.
#[test]
fn val_xu2019_gradient_vs_finite_differences() {
    let h = 1e-7;
    let fd = |c: &Xu2019Potential, pose: Vector3<f64>| {
        let mut g = Vector3::zeros();
        for i in 0..3 {
            let mut a = pose;
            let mut b = pose;
            a[i] += h;
            b[i] -= h;
            g[i] = (c.potential(a) - c.potential(b)) / (2.0 * h);
        }
        g
    };
    let poses = [
        Vector3::new(0.809, 0.224, 0.12),
        Vector3::new(0.6, 0.75, 1.0),
        Vector3::new(0.58, 0.88, 0.5),
        Vector3::new(0.35, 1.2, 1.4),
        Vector3::new(0.33, 1.45, 1.5),
    ];
    let exact = Xu2019Potential::new(Xu2019Params::exact());
    let eq8_true = Xu2019Potential::new(Xu2019Params {
        gradient_form: GradientForm::True,
        ..Xu2019Params::paper()
    });
    let printed = Xu2019Potential::new(Xu2019Params::paper());
    for pose in poses {
        for c in [&exact, &eq8_true] {
            let (g, f) = (c.gradient(pose), fd(c, pose));
            // Central differences: truncation ~h²·φ''' plus rounding ~ε·φ/h ≈ 1e-8.
            assert!(
                (g - f).norm() < 1e-6 * (1.0 + f.norm()),
                "{pose}: {g} vs {f}"
            );
        }
        let (g, f) = (printed.gradient(pose), fd(&printed, pose));
        eprintln!(
            "pose {:.3?}: printed-gradient error |∇_printed − ∇_fd| = {:.3e} N (|∇| = {:.3e})",
            pose.as_slice(),
            (g - f).norm(),
            f.norm()
        );
    }
}

/// At the goal the gradient vanishes (r_cd = 0 kills every term): an equilibrium.
#[test]
fn invariant_xu2019_goal_is_equilibrium() {
    for p in [Xu2019Params::paper(), Xu2019Params::exact()] {
        let c = Xu2019Potential::new(p.clone());
        let goal = Vector3::new(p.goal_pos_lab_m[0], p.goal_pos_lab_m[1], p.goal_theta_rad);
        assert_eq!(c.gradient(goal), Vector3::zeros());
        assert_eq!(c.potential(goal), 0.0);
    }
}

/// Body-frame force is the lab force rotated by −θ (same norm; θ = 90° maps lab +x to
/// body −y).
#[test]
fn invariant_xu2019_command_frames() {
    let c = Xu2019Potential::new(Xu2019Params::paper());
    let obs = Xu2019Observation {
        t_s: 0.0,
        pos_lab_m: Vector2::new(0.9, 1.4),
        theta_rad: std::f64::consts::FRAC_PI_2,
        vel_lab_m_s: Vector2::zeros(),
        omega_rad_s: 0.0,
    };
    let cmd = c.command(&obs);
    assert!((cmd.force_lab_n.norm() - cmd.force_body_n.norm()).abs() < 1e-15);
    assert!((cmd.force_body_n.x - cmd.force_lab_n.y).abs() < 1e-15);
    assert!((cmd.force_body_n.y + cmd.force_lab_n.x).abs() < 1e-15);
    assert!(
        cmd.force_lab_n.x < 0.0,
        "attraction towards the goal at x = 0.25 m"
    );
}

/// Planar rigid body of eq (3), state (x, y, θ, ẋ, ẏ, θ̇); `u` gives (Fx, Fy, T) in the lab
/// frame for a state. Classic RK4 over one step.
fn rk4(s: &[f64; 6], dt: f64, m: f64, iz: f64, u: &dyn Fn(&[f64; 6]) -> [f64; 3]) -> [f64; 6] {
    let f = |s: &[f64; 6]| {
        let w = u(s);
        [s[3], s[4], s[5], w[0] / m, w[1] / m, w[2] / iz]
    };
    let add = |a: &[f64; 6], k: &[f64; 6], h: f64| {
        let mut o = *a;
        for i in 0..6 {
            o[i] += h * k[i];
        }
        o
    };
    let k1 = f(s);
    let k2 = f(&add(s, &k1, 0.5 * dt));
    let k3 = f(&add(s, &k2, 0.5 * dt));
    let k4 = f(&add(s, &k3, dt));
    let mut o = *s;
    for i in 0..6 {
        o[i] += dt / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
    }
    o
}

struct Run {
    t: Vec<f64>,
    s: Vec<[f64; 6]>,
    min_radial_obs_m: f64,
    min_radial_heart_m: f64,
    min_eucl_obs_m: f64,
    min_eucl_heart_m: f64,
    max_force_n: f64,
    gas_kg: f64,
    last_eucl_pos: Vector2<f64>,
    max_frame_move_m: f64,
}

/// Sampling period of the numerical obstacle Euclidean distance in the runs (s).
const MONITOR_PERIOD_S: f64 = 0.2;

fn start() -> [f64; 6] {
    let su = Xu2019Setup::paper();
    [
        su.start_pos_lab_m[0],
        su.start_pos_lab_m[1],
        su.start_theta_rad,
        0.0,
        0.0,
        0.0,
    ]
}

/// Radial distances and the (closed-form) heart Euclidean distance every step; the
/// numerical obstacle Euclidean distance (≈ 70 µs a call in release, ~1 ms in debug)
/// only when `eucl` is set (5 Hz, `MONITOR_PERIOD_S`). Between two obstacle samples the true distance can drop by at most the displacement
/// since the last sample (the distance is 1-Lipschitz): tracked in `max_frame_move_m`.
fn monitor(c: &Xu2019Potential, run: &mut Run, s: &[f64; 6], eucl: bool) {
    let pos = Vector2::new(s[0], s[1]);
    let (dro, drh) = c.radial_distances_m(pos);
    let dre = c.params.obstacle.radial_distance_m(pos, RadialForm::Exact);
    run.min_radial_obs_m = run.min_radial_obs_m.min(dro).min(dre);
    run.min_radial_heart_m = run.min_radial_heart_m.min(drh);
    run.max_frame_move_m = run.max_frame_move_m.max((pos - run.last_eucl_pos).norm());
    run.min_eucl_heart_m = run
        .min_eucl_heart_m
        .min(c.params.heart.euclidean_distance_m(pos));
    if !eucl {
        return;
    }
    run.last_eucl_pos = pos;
    run.min_eucl_obs_m = run
        .min_eucl_obs_m
        .min(c.params.obstacle.euclidean_distance_m(pos));
}

fn new_run() -> Run {
    Run {
        t: vec![0.0],
        s: vec![start()],
        min_radial_obs_m: f64::INFINITY,
        min_radial_heart_m: f64::INFINITY,
        min_eucl_obs_m: f64::INFINITY,
        min_eucl_heart_m: f64::INFINITY,
        max_force_n: 0.0,
        gas_kg: 0.0,
        last_eucl_pos: Vector2::new(start()[0], start()[1]),
        max_frame_move_m: 0.0,
    }
}

/// Ideal continuous force: the law is evaluated at every RK4 stage with the true state.
/// With `saturate`, the body command is clipped per channel to the fully-open valve
/// wrench (±0.05 N per body axis, ±0.009 N·m), still continuous: saturation alone.
fn ideal_run(c: &Xu2019Potential, dt: f64, t_end: f64, watch: bool, saturate: bool) -> Run {
    let su = Xu2019Setup::paper();
    let tp = ThrusterParams::paper();
    let mut run = new_run();
    let mut s = start();
    let frame = (MONITOR_PERIOD_S / dt).round() as usize;
    monitor(c, &mut run, &s, watch);
    let law = |s: &[f64; 6]| {
        let cmd = c.command(&Xu2019Observation {
            t_s: 0.0,
            pos_lab_m: Vector2::new(s[0], s[1]),
            theta_rad: s[2],
            vel_lab_m_s: Vector2::new(s[3], s[4]),
            omega_rad_s: s[5],
        });
        if saturate {
            let (fb, tq) = tp.saturate(cmd.force_body_n, cmd.torque_nm);
            let (sn, cs) = s[2].sin_cos();
            [cs * fb.x - sn * fb.y, sn * fb.x + cs * fb.y, tq]
        } else {
            [cmd.force_lab_n.x, cmd.force_lab_n.y, cmd.torque_nm]
        }
    };
    let n = (t_end / dt).round() as usize;
    for k in 1..=n {
        let w = law(&s);
        run.max_force_n = run.max_force_n.max(w[0].abs()).max(w[1].abs());
        s = rk4(&s, dt, su.mass_kg, su.iz_kg_m2, &law);
        if watch {
            monitor(c, &mut run, &s, k % frame == 0);
        }
        run.t.push(k as f64 * dt);
        run.s.push(s);
    }
    run
}

/// Thrust-limited run: vision pose every 0.04 s (exact, no noise), velocity by backward
/// difference of successive vision poses, the law held between frames, PWPF channels and
/// valves stepped every `dt` (1 ms), the body-fixed valve wrench rotated with the true θ
/// inside each RK4 stage.
fn pwpf_run(c: &Xu2019Potential, dt: f64, t_end: f64) -> Run {
    let su = Xu2019Setup::paper();
    let tp = ThrusterParams::paper();
    let mut pw = ThrusterPwpf::new(&tp);
    let mut run = new_run();
    let mut s = start();
    monitor(c, &mut run, &s, true);
    let mon = (MONITOR_PERIOD_S / dt).round() as usize;
    let n = (t_end / dt).round() as usize;
    let frame = (su.vision_period_s / dt).round() as usize;
    let mut last_pose: Option<[f64; 3]> = None;
    let mut cmd_body = (Vector2::zeros(), 0.0);
    for k in 0..n {
        if k % frame == 0 {
            let pose = [s[0], s[1], s[2]];
            let (v, w) = match last_pose {
                None => (Vector2::zeros(), 0.0),
                Some(p) => (
                    Vector2::new(pose[0] - p[0], pose[1] - p[1]) / su.vision_period_s,
                    wrap_pi(pose[2] - p[2]) / su.vision_period_s,
                ),
            };
            last_pose = Some(pose);
            let cmd = c.command(&Xu2019Observation {
                t_s: k as f64 * dt,
                pos_lab_m: Vector2::new(pose[0], pose[1]),
                theta_rad: pose[2],
                vel_lab_m_s: v,
                omega_rad_s: w,
            });
            cmd_body = (cmd.force_body_n, cmd.torque_nm);
        }
        let valves = pw.step(&tp, cmd_body.0, cmd_body.1, dt);
        run.gas_kg += tp.gas_used_kg(&valves, dt);
        let (fb, tq) = tp.wrench_from_valves(&valves);
        run.max_force_n = run.max_force_n.max(fb.norm());
        let law = |s: &[f64; 6]| {
            let (sn, cs) = s[2].sin_cos();
            [cs * fb.x - sn * fb.y, sn * fb.x + cs * fb.y, tq]
        };
        s = rk4(&s, dt, su.mass_kg, su.iz_kg_m2, &law);
        monitor(c, &mut run, &s, (k + 1) % mon == 0);
        run.t.push((k + 1) as f64 * dt);
        run.s.push(s);
    }
    run
}

/// First time after which component i stays within `frac` of its total change.
fn settle_time(run: &Run, i: usize, goal: f64, frac: f64) -> f64 {
    let e0 = (run.s[0][i] - goal).abs();
    let mut t = 0.0;
    for (tk, sk) in run.t.iter().zip(&run.s) {
        if (sk[i] - goal).abs() > frac * e0 {
            t = *tk;
        }
    }
    t
}

fn final_errors(c: &Xu2019Potential, run: &Run) -> (f64, f64) {
    let s = run.s.last().unwrap();
    let e = c.pose_error(Vector3::new(s[0], s[1], s[2]));
    (e.xy().norm(), e.z.abs())
}

fn arrival_time(c: &Xu2019Potential, run: &Run, pos_tol_m: f64, ang_tol_rad: f64) -> f64 {
    let mut t = 0.0;
    for (tk, sk) in run.t.iter().zip(&run.s) {
        let e = c.pose_error(Vector3::new(sk[0], sk[1], sk[2]));
        if e.xy().norm() > pos_tol_m || e.z.abs() > ang_tol_rad {
            t = *tk;
        }
    }
    t
}

/// Fig. 13 with ideal continuous force: radial distances to obstacle and heart stay
/// positive, the goal (0.25 m, 1.4 m, 90°) is reached. Both the as-published law (eq 8
/// distance, printed gradient) and the exact one. Reference: an independent RK4 of eq (3)
/// at 10 ms, checked against 5 ms over the first 60 s, the part near the constraints (the step-halving difference bounds the integration
/// error). The convergence bound: near the goal the linearised slowest pole of eq (3)
/// under u = −(Q_a r + k ẋ) is −0.087 1/s (m s² + 10 s + 0.8; the heart term only
/// stiffens it near the goal), so after 150 s the residual of a 1.3 m error is
/// ≤ 1.3·e^{−13} ≈ 3e-6 m; attitude (0.05 s² + 0.5 s + 0.1, slow pole −0.20 1/s) is
/// ≤ 1.45·e^{−30}. We assert 1e-5 m and 1e-5 rad.
#[test]
fn val_xu2019_fig13_ideal_closed_loop() {
    for (name, p) in [
        ("paper (eq 8, printed ∇)", Xu2019Params::paper()),
        ("exact (r(α), true ∇)", Xu2019Params::exact()),
    ] {
        let c = Xu2019Potential::new(p);
        let run = ideal_run(&c, 0.01, 150.0, true, false);
        let half = ideal_run(&c, 0.005, 60.0, false, false);
        let mut max_diff: f64 = 0.0;
        for (a, b) in run.s.iter().zip(half.s.iter().step_by(2)) {
            max_diff = max_diff.max(((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2)).sqrt());
        }
        let (ep, ea) = final_errors(&c, &run);
        eprintln!(
            "[ideal {name}] min radial: obstacle {:.4} m, heart {:.4} m; min Euclidean: \
                 obstacle {:.4} m, heart {:.4} m; final |Δp| {:.2e} m, |Δθ| {:.2e} rad; \
                 within 1 cm & 1° after {:.1} s, 1 mm & 0.1° after {:.1} s; peak |F| {:.3} N; \
                 RK4 dt-halving max diff {:.1e} m; obstacle Euclidean sampled at 5 Hz, max move \
                 between samples {:.4} m",
            run.min_radial_obs_m,
            run.min_radial_heart_m,
            run.min_eucl_obs_m,
            run.min_eucl_heart_m,
            ep,
            ea,
            arrival_time(&c, &run, 0.01, 1f64.to_radians()),
            arrival_time(&c, &run, 0.001, 0.1f64.to_radians()),
            run.max_force_n,
            max_diff,
            run.max_frame_move_m
        );
        // The step-halving difference must be far below the margins it could flip.
        let margin = run.min_radial_obs_m.min(run.min_radial_heart_m);
        assert!(
            max_diff < 1e-3 * margin,
            "integration not converged: {max_diff}"
        );
        assert!(run.min_radial_obs_m > 0.0, "{name}: obstacle radial ≤ 0");
        assert!(run.min_radial_heart_m > 0.0, "{name}: heart radial ≤ 0");
        // Guaranteed between samples: sampled minimum minus the largest inter-sample move.
        let mv = run.max_frame_move_m;
        assert!(run.min_eucl_obs_m - mv > 0.0 && run.min_eucl_heart_m > 0.0);
        assert!(
            ep < 1e-5 && ea < 1e-5,
            "{name}: final error {ep} m, {ea} rad"
        );
    }
}

/// Lyapunov: with the true gradient, V = φ_tot + ½ m |v|² + ½ I_z ω² obeys
/// V̇ = −ẋᵀ k ẋ ≤ 0 along eq (3) under eq (16). Reference: that identity, checked step by
/// step on the paper scenario (exact distance) — V may rise only by the RK4 local error,
/// bounded here by 1e-9·V(0) per step (measured worst rise reported). The printed
/// gradient is not a gradient, so V is not guaranteed to decrease: its worst rise is
/// reported, not asserted.
#[test]
fn invariant_xu2019_lyapunov_true_gradient() {
    let su = Xu2019Setup::paper();
    for p in [Xu2019Params::exact(), Xu2019Params::paper()] {
        let c = Xu2019Potential::new(p);
        let run = ideal_run(&c, 0.01, 60.0, false, false);
        let v = |s: &[f64; 6]| {
            c.potential(Vector3::new(s[0], s[1], s[2]))
                + 0.5 * su.mass_kg * (s[3] * s[3] + s[4] * s[4])
                + 0.5 * su.iz_kg_m2 * s[5] * s[5]
        };
        let v0 = v(&run.s[0]);
        let mut worst: f64 = 0.0;
        for w in run.s.windows(2) {
            worst = worst.max(v(&w[1]) - v(&w[0]));
        }
        eprintln!(
            "[lyapunov {:?}/{:?}] V(0) = {v0:.4} J, V(60 s) = {:.3e} J, worst one-step rise \
                 {worst:.2e} J",
            c.params.radial_form,
            c.params.gradient_form,
            v(run.s.last().unwrap())
        );
        if c.params.gradient_form == GradientForm::True {
            assert!(worst <= 1e-9 * v0, "V rose by {worst} J");
        }
    }
}

/// Which combination of [`RadialForm`] and [`GradientForm`] keeps the chaser out of the
/// obstacle when the attraction is aimed at it. Start 0.5 m out on the lab 45° diagonal
/// through the obstacle centre (upper right), goal 0.5 m out on the opposite side, either
/// exactly collinear with the centre or shifted by (0.1, −0.1) m; heart moved away; ideal
/// continuous force, RK4 at 10 ms for 80 s. The signed exact radial distance is the
/// inside/outside reference (the curve is star-shaped about o1, so its sign is that of
/// the Euclidean distance).
///
/// Asserted, each from an independent argument:
/// - Exact distance + true gradient never enters: V = φ_tot + ½ẋᵀMẋ is non-increasing
///   under u = −(∇φ + kẋ), and φ → ∞ on the whole boundary.
/// - Printed gradient, collinear case: attraction (along the line to the goal) and the
///   radial repulsion (along the line from o1) are collinear on that line, the start is at
///   rest on it, so the motion stays on it and stops in front of the obstacle (a trap),
///   whichever distance form.
/// - Eq (8) distance + its true gradient enters the obstacle: the eq (8) potential is
///   finite on the boundary off the axes (|NM| > 0 there), so it is no barrier.
#[test]
fn val_xu2019_corner_attack_eq8_vs_exact() {
    let su = Xu2019Setup::paper();
    let o = SuperquadricParams::paper();
    let diag = Vector2::new(1.0, 1.0).normalize();
    let start = o.centre() + diag * 0.5;
    let combos = [
        (RadialForm::PaperEq8, GradientForm::PaperPrinted),
        (RadialForm::PaperEq8, GradientForm::True),
        (RadialForm::Exact, GradientForm::PaperPrinted),
        (RadialForm::Exact, GradientForm::True),
    ];
    for off in [0.0, 0.1] {
        let goal = o.centre() - diag * 0.5 + Vector2::new(off, -off);
        for (rf, gf) in combos {
            let c = Xu2019Potential::new(Xu2019Params {
                goal_pos_lab_m: [goal.x, goal.y],
                goal_theta_rad: 0.0,
                heart: HeartParams {
                    centre_lab_m: [5.0, 5.0],
                    ..HeartParams::paper()
                },
                radial_form: rf,
                gradient_form: gf,
                ..Xu2019Params::paper()
            });
            let law = |s: &[f64; 6]| {
                let cmd = c.command(&Xu2019Observation {
                    t_s: 0.0,
                    pos_lab_m: Vector2::new(s[0], s[1]),
                    theta_rad: s[2],
                    vel_lab_m_s: Vector2::new(s[3], s[4]),
                    omega_rad_s: s[5],
                });
                [cmd.force_lab_n.x, cmd.force_lab_n.y, cmd.torque_nm]
            };
            let mut s = [start.x, start.y, 0.0, 0.0, 0.0, 0.0];
            let mut d_min = f64::INFINITY;
            for _ in 0..8_000 {
                s = rk4(&s, 0.01, su.mass_kg, su.iz_kg_m2, &law);
                let p = Vector2::new(s[0], s[1]);
                d_min = d_min.min(o.radial_distance_m(p, RadialForm::Exact));
            }
            let fin = Vector2::new(s[0], s[1]);
            let to_goal = (fin - goal).norm();
            eprintln!(
                "[corner offset {off} m] {rf:?}/{gf:?}: min exact radial distance {d_min:.4} m, \
                     final ({:.3}, {:.3}) m, final distance to goal {to_goal:.3} m",
                fin.x, fin.y
            );
            match (rf, gf, off == 0.0) {
                (RadialForm::Exact, GradientForm::True, _) => {
                    assert!(d_min > 0.0, "exact barrier entered at offset {off}");
                }
                (_, GradientForm::PaperPrinted, true) => {
                    let across = (fin - o.centre()).perp(&diag).abs();
                    assert!(across < 1e-9, "left the symmetry line: {across}");
                    assert!(to_goal > 0.5 && d_min > 0.0, "expected a trap");
                }
                (RadialForm::PaperEq8, GradientForm::True, _) => {
                    assert!(d_min < 0.0, "eq (8) potential expected to leak");
                }
                _ => {}
            }
        }
    }
}

/// Fig. 13, thrust-limited: 0.05 N nozzles through PWPF, vision at 25 Hz. The paper says
/// the experiment lags the (unlimited) simulation in x and y and leads slightly in θ.
/// Reported: 50 % and 90 % settling times per axis for the unlimited, the continuously
/// saturated (±0.05 N, ±0.009 N·m per body channel) and the PWPF runs, and the margins.
/// Asserted: what the physics guarantees — the valve force never exceeds one nozzle per
/// axis, the constraints hold, and the lag in x and y (the unlimited run commands up to
/// ~1 N, 20× the 0.05 N available, so it cannot be matched).
#[test]
fn val_xu2019_fig13_pwpf_lag() {
    let c = Xu2019Potential::new(Xu2019Params::paper());
    let p = &c.params;
    let ideal = ideal_run(&c, 0.01, 100.0, true, false);
    let sat = ideal_run(&c, 0.01, 100.0, true, true);
    let pw = pwpf_run(&c, 0.001, 100.0);
    let goals = [p.goal_pos_lab_m[0], p.goal_pos_lab_m[1], p.goal_theta_rad];
    let mut lag = [0.0; 3];
    for (i, axis) in ["x", "y", "θ"].iter().enumerate() {
        let (i50, i90) = (
            settle_time(&ideal, i, goals[i], 0.5),
            settle_time(&ideal, i, goals[i], 0.1),
        );
        let (p50, p90) = (
            settle_time(&pw, i, goals[i], 0.5),
            settle_time(&pw, i, goals[i], 0.1),
        );
        let (s50, s90) = (
            settle_time(&sat, i, goals[i], 0.5),
            settle_time(&sat, i, goals[i], 0.1),
        );
        lag[i] = p50 - i50;
        eprintln!(
            "[pwpf] {axis}: 50% settle ideal {i50:.2} s, saturated {s50:.2} s, PWPF {p50:.2} s; \
                 90% settle ideal {i90:.2} s, saturated {s90:.2} s, PWPF {p90:.2} s"
        );
    }
    for t in [5.0, 10.0, 20.0, 30.0, 40.0, 60.0] {
        let si = ideal.s[(t / 0.01) as usize];
        let ss = sat.s[(t / 0.01) as usize];
        let sp = pw.s[(t / 0.001) as usize];
        eprintln!(
            "[pwpf] t = {t:>4} s: ideal (x, y, θ) = ({:.3} m, {:.3} m, {:.1}°), saturated \
                 ({:.3} m, {:.3} m, {:.1}°), PWPF ({:.3} m, {:.3} m, {:.1}°)",
            si[0],
            si[1],
            si[2].to_degrees(),
            ss[0],
            ss[1],
            ss[2].to_degrees(),
            sp[0],
            sp[1],
            sp[2].to_degrees()
        );
    }
    let (ep, ea) = final_errors(&c, &pw);
    eprintln!(
        "[pwpf] min radial: obstacle {:.4} m, heart {:.4} m; min Euclidean: obstacle \
             {:.4} m, heart {:.4} m; final |Δp| {:.2e} m, |Δθ| {:.2e} rad; within 1 cm & 1° \
             after {:.1} s; peak valve |F| {:.3} N; CO2 used {:.2} g; ideal peak |F| {:.3} N; \
             max move between obstacle Euclidean samples {:.4} m",
        pw.min_radial_obs_m,
        pw.min_radial_heart_m,
        pw.min_eucl_obs_m,
        pw.min_eucl_heart_m,
        ep,
        ea,
        arrival_time(&c, &pw, 0.01, 1f64.to_radians()),
        pw.max_force_n,
        pw.gas_kg * 1e3,
        ideal.max_force_n,
        pw.max_frame_move_m
    );
    assert!(pw.max_force_n <= 0.05 * 2f64.sqrt() + 1e-15);
    assert!(pw.min_radial_obs_m > 0.0 && pw.min_radial_heart_m > 0.0);
    assert!(lag[0] > 0.0 && lag[1] > 0.0, "no lag in x/y: {lag:?}");
}
