//! Xu & Hu (2015) in the ECS: ACCM vs PD against a maneuvering target on an e = 0.7 orbit
//! (scenes `scenes/papers/xu2015/xu2015_*.ron`, run through `rpod::reproduce::xu2015::run_case`).
//!
//! Independent references:
//! - an f64 integration written here of the paper's relative model in the target orbital
//!   frame (`orbit::elliptic::rk4_step_relative`, RK4 at h = 0.1 s, thrust held in the rotating
//!   frame, maneuver continuous) flown by fresh copies of the same controllers: the ECS run
//!   (inertial world frame, differential gravity on both bodies, velocity Verlet) must follow it;
//! - the PD's quasi-static error under a sinusoidal disturbance (closed form);
//! - the thrust actually applied, recovered from the chaser's f64 momentum change less the
//!   differential gravity (not from the controller's own clamp);
//! - the thrust-authority margins in closed form (5/m_c − |F_t,i|/200);
//! - the moments of the Gaussian measurement noise.
//!
//! Each 300 s run is 3000 steps at dt = 0.1 s (≈ 0.1 s wall); the file runs in a few seconds.

use nalgebra::Vector3;
use rpod::control::xu2015::{
    Accm, AccmParams, ManeuverSpec, Pd, PdParams, Xu2015Observation, dcm_eci_from_tof_state,
};
use rpod::orbit::elliptic::{EllipticOrbit, RelStateTof, rk4_step_relative};
use rpod::reproduce::xu2015::{POINT_MASS_OVERRIDES, run_case, scene_text};
use rpod::scene::load_scene_str;
use rpod::sim::Simulation;

/// Terminal measures of the f64 reference run: (rms, max, samples ξ).
struct RefRun {
    rms_m: f64,
    max_m: f64,
    xi: Vec<Vector3<f64>>,
}

/// The paper's relative model (tof), RK4 at h, the chaser at rest at ξ0 = [−20, 0, 5] m.
fn reference_run(
    mass_chaser_kg: f64,
    mut ctrl: impl FnMut(&Xu2015Observation) -> Vector3<f64>,
) -> RefRun {
    let orbit = EllipticOrbit::xu2015();
    let man = ManeuverSpec::paper();
    let (h, n, m_t) = (0.1, 3000usize, 200.0);
    let goal = Vector3::new(-0.01, 0.0, 0.0);
    // ρ = ξ + aim: the aim offset (−3, 0, 0) is part of the ECS scenes; the model state is ρ.
    let aim = Vector3::new(-3.0, 0.0, 0.0);
    let mut x = RelStateTof::new(-23.0, 0.0, 5.0, 0.0, 0.0, 0.0);
    let (mut se2, mut cnt, mut mx) = (0.0, 0usize, 0.0f64);
    let mut xi = Vec::new();
    for k in 0..n {
        let t = k as f64 * h;
        let p = Vector3::new(x[0], x[1], x[2]) - aim;
        xi.push(p);
        if t >= 200.0 - 1e-9 {
            let e = (p - goal).norm();
            se2 += e * e;
            mx = mx.max(e);
            cnt += 1;
        }
        let u = ctrl(&Xu2015Observation {
            t_s: t,
            pos_tof_m: p,
        });
        x = rk4_step_relative(&x, t, h, &orbit, |ts| {
            u / mass_chaser_kg - man.force_tof_n(ts) / m_t
        });
    }
    RefRun {
        rms_m: (se2 / cnt as f64).sqrt(),
        max_m: mx,
        xi,
    }
}

/// f64 reference with fresh copies of the scene's controller.
fn reference_for(file: &str, mass_chaser_kg: f64) -> RefRun {
    if file.contains("accm") {
        let mut c = Accm::new(AccmParams::paper());
        reference_run(mass_chaser_kg, |o| c.update(o).force_tof_n)
    } else {
        let mut c = Pd::new(PdParams::paper());
        reference_run(mass_chaser_kg, |o| c.update(o).force_tof_n)
    }
}

use rpod::reproduce::xu2015::model_difference_bound_m_s2;

/// 90 and 100 kg: the ECS run reproduces the f64 relative-model run, and ACCM is more accurate
/// than PD over the last 100 s at comparable thrust.
/// - ECS vs f64: the plants differ by at most δa (see [`model_difference_bound_m_s2`]),
///   a fraction ε = δa / (peak maneuver acceleration) of the disturbance that sets the terminal
///   error; the terminal RMS may differ by a few ε: asserted within 10 ε (measured ≈ 3.5e−6
///   relative, ε ≈ 1.4e−5).
/// - PD: its quasi-static error under the maneuver is e_i = F_t,i m_c / (m_t m_nom k_p); the
///   per-axis terminal peak must match within 5 % (dynamic factor |1 + iωk_d/k_p − ω²/k_p| − 1
///   ≤ 1e−3 at ω ≤ 0.1 rad/s; the rest is the 0.1 s sampling of the peak and saturation).
/// - Comparable thrust: RMS |u| of the two runs within 1 %.
#[test]
fn val_xu2015_accm_vs_pd_terminal_accuracy() {
    let pd = PdParams::paper();
    for m_c in [100.0, 90.0] {
        let sfx = if m_c == 100.0 { "" } else { "_m90" };
        let mut runs = Vec::new();
        for law in ["accm", "pd"] {
            let file = format!("xu2015_{law}{sfx}.ron");
            let run = run_case(&file, &[], None).expect("runs");
            let r = reference_for(&file, m_c);
            let eps =
                model_difference_bound_m_s2(0.1, m_c) / (ManeuverSpec::paper().peak_n().x / 200.0);
            let rel = (run.terminal_rms_m() - r.rms_m).abs() / r.rms_m;
            println!(
                "{file}: ECS rms {:.4e} m max {:.4e} m | f64 rms {:.4e} m max {:.4e} m | rel {rel:.2e} (ε {eps:.2e}) | rms thrust {:.4} N",
                run.terminal_rms_m(),
                run.terminal_max_m(),
                r.rms_m,
                r.max_m,
                run.rms_thrust_n()
            );
            assert!(
                rel < 10.0 * eps,
                "{file}: ECS vs f64 terminal rms {rel} > 10 ε = {}",
                10.0 * eps
            );
            assert!(((run.terminal_max_m() - r.max_m) / r.max_m).abs() < 10.0 * eps);
            runs.push(run);
        }
        let (a, p) = (&runs[0], &runs[1]);
        assert!(
            a.terminal_rms_m() < p.terminal_rms_m(),
            "{m_c} kg: ACCM rms not better"
        );
        assert!(
            a.terminal_max_m() < p.terminal_max_m(),
            "{m_c} kg: ACCM max not better"
        );
        let dthrust = (a.rms_thrust_n() - p.rms_thrust_n()).abs() / p.rms_thrust_n();
        assert!(dthrust < 0.01, "{m_c} kg: RMS thrust differs by {dthrust}");
        let pred = ManeuverSpec::paper().peak_n() * (m_c / (200.0 * pd.mass_nominal_kg * pd.kp_s2));
        let got = p.terminal_max_axis_m();
        for i in 0..3 {
            let r = got[i] / pred[i];
            assert!((r - 1.0).abs() < 0.05, "PD axis {i} at {m_c} kg: {r}");
        }
    }
}

/// Thrust never above 5 N per tof axis — measured from the physics, not from the law's clamp:
/// the chaser's non-gravitational acceleration is recovered each step from its f64 state,
/// a_c = (v₁ − v₀)/dt − ½(a_g(x₀) + a_g(x₁)) (the velocity-Verlet update inverted, a_g the
/// core's exact differential gravity at the reference states of t₀ and t₁), rotated into the
/// tof of t₀. It must equal the commanded, held thrust to round-off and stay ≤ 5 N. (The
/// 110 kg case flies the point-mass variant: in contact the momentum change includes contact
/// impulses.)
#[test]
fn val_xu2015_thrust_never_above_limit() {
    for (file, m_c, ov) in [
        ("xu2015_accm.ron", 100.0, &[][..]),
        ("xu2015_pd_m110.ron", 110.0, &POINT_MASS_OVERRIDES[..]),
    ] {
        let ov: Vec<String> = ov.iter().map(|s| s.to_string()).collect();
        let loaded = load_scene_str(scene_text(file).unwrap(), file, &ov).unwrap();
        let mut sim = Simulation::new(&loaded).unwrap();
        let dt = loaded.scene.dt_s;
        let n = sim.steps_for(loaded.scene.duration_s);
        let (mut worst, mut dev_max, mut sat) = (0.0f64, 0.0f64, 0usize);
        for _ in 0..n {
            let s0 = sim.body("chaser").unwrap();
            let (r0, v0) = sim.reference_state().unwrap();
            sim.step(1);
            let s1 = sim.body("chaser").unwrap();
            let (r1, _) = sim.reference_state().unwrap();
            let ag0 = rpod::orbit::gravity::differential_accel(
                &r0,
                &s0.pos_m,
                rpod::orbit::gravity::TWO_BODY,
            );
            let ag1 = rpod::orbit::gravity::differential_accel(
                &r1,
                &s1.pos_m,
                rpod::orbit::gravity::TWO_BODY,
            );
            let a_c = (s1.vel_m_s - s0.vel_m_s) / dt - (ag0 + ag1) * 0.5;
            let f_tof = dcm_eci_from_tof_state(&r0, &v0).transpose() * a_c * m_c;
            let cmd = sim
                .law::<rpod::control::xu2015::Xu2015Loop>(0)
                .unwrap()
                .thrust_tof_n;
            worst = worst.max(f_tof.amax());
            dev_max = dev_max.max((f_tof - cmd).amax());
            sat += usize::from(cmd.amax() >= 5.0 - 1e-9);
        }
        println!(
            "{file}: max |F_i| from the physics {worst:.12} N, |F − u| ≤ {dev_max:.2e} N, saturated steps {sat}"
        );
        // Round-off: |v| ≲ 1 m/s, ulp ≈ 2e−16 m/s, divided by dt and times m_c.
        assert!(
            dev_max < 1e-8,
            "applied thrust differs from the command by {dev_max} N"
        );
        assert!(worst <= 5.0 + 1e-8, "{file}: {worst} N");
        assert!(
            sat > 0,
            "{file}: the limit was never reached (test would be vacuous)"
        );
    }
}

/// Thrust authority (registered guarantees `thrust_authority_{x,y,z}`): worst margins over the
/// run equal the closed form 5/m_c − F_max,i/200 m/s² to the sampling of the peak
/// (|sin| ≥ cos(ω dt/2) at the nearest step: error ≤ F_max ω² dt²/8 / 200 ≤ 4e−7 m/s²);
/// held at 90 kg, violated on x only at 110 kg (−4.5e−3 m/s²); at 100 kg the x margin is exactly
/// 0 at the peaks (5/100 = 10/200): `unresolved` between samples, as it must be.
#[test]
fn val_xu2015_thrust_authority_guarantee() {
    let man = ManeuverSpec::paper();
    for (file, m_c) in [
        ("xu2015_accm_m90.ron", 90.0),
        ("xu2015_pd.ron", 100.0),
        ("xu2015_pd_m110.ron", 110.0),
    ] {
        let run = run_case(file, &POINT_MASS_OVERRIDES, None).unwrap();
        for (i, a) in ["x", "y", "z"].iter().enumerate() {
            let g = run
                .guarantee(&format!("thrust_authority_{a}"))
                .expect("registered");
            let worst = g["worst_margin"].as_f64().unwrap();
            let exact = 5.0 / m_c - man.amplitude_n[i] / 200.0;
            let tol = man.amplitude_n[i] * man.omega_rad_s[i].powi(2) * 0.01 / 8.0 / 200.0 + 1e-12;
            assert!(
                (worst - exact).abs() <= tol,
                "{file} {a}: {worst} vs {exact}"
            );
            // Judged between samples (rate bound |A ω|/m_t): at 100 kg the x margin touches 0 at
            // every peak of the manoeuvre, where a rate bound cannot prove it ≥ 0 — the verdict
            // is `unresolved` (the certified lower bound just below 0), never `held`.
            assert_eq!(g["judged"], "interval", "{file} {a}");
            let verdict = g["verdict"].as_str().unwrap();
            if exact.abs() < 1e-12 {
                let lower = g["worst_margin_lower"].as_f64().unwrap();
                assert_eq!(verdict, "unresolved", "{file} {a}");
                assert!((-1e-5..=0.0).contains(&lower), "{file} {a}: {lower}");
            } else {
                assert_eq!(g["held"].as_bool().unwrap(), exact > 0.0, "{file} {a}");
                assert_eq!(verdict, if exact > 0.0 { "held" } else { "violated" });
            }
            assert_eq!(g["unit"], "m_s2");
        }
    }
}

/// +10 % mass: x authority 5/110 < 10/200 m/s². Point-mass reading (aim point 10 m off the
/// target's line, no contact possible): both controllers saturate on x for ≥ 99 % of the last
/// 100 s and lose the target by tens of metres on x while y and z stay at the 100 kg accuracy
/// (their authority holds); PD follows the f64 model within 10 ε, ACCM's saturated limit cycle
/// (bang-bang switching) within 2 % (printed). With real geometry on the target's line (the
/// scenes as written), the excursion toward the target exceeds the 2 m bus-to-bus gap
/// (predicted by the f64 model) and both runs end in a collision, reported by the monitor.
#[test]
fn val_xu2015_plus10pct_mass_loses_target() {
    for file in ["xu2015_accm_m110.ron", "xu2015_pd_m110.ron"] {
        let pm = run_case(file, &POINT_MASS_OVERRIDES, None).unwrap();
        let r = reference_for(file, 110.0);
        let rel = (pm.terminal_rms_m() - r.rms_m).abs() / r.rms_m;
        let ax = pm.terminal_max_axis_m();
        println!(
            "{file} point-mass: rms {:.3} m (f64 {:.3} m, rel {rel:.2e}) axis max {ax:?} m, x saturated {:.3}, collision {:?}",
            pm.terminal_rms_m(),
            r.rms_m,
            pm.terminal_saturation_x(5.0),
            pm.first_collision_s()
        );
        assert!(pm.first_collision_s().is_none());
        assert!(pm.terminal_saturation_x(5.0) >= 0.99);
        assert!(ax.x > 10.0, "x error {}", ax.x);
        let y_z_100 = ManeuverSpec::paper().peak_n() * (110.0 / (200.0 * 100.0 * 14.6));
        assert!(ax.y < 1.05 * y_z_100.y && ax.z < 1.05 * y_z_100.z, "{ax:?}");
        if file.contains("pd") {
            let eps = model_difference_bound_m_s2(0.1, 110.0) / 0.05;
            assert!(rel < 10.0 * eps, "PD 110 kg ECS vs f64 {rel}");
        } else {
            assert!(rel < 0.02, "ACCM 110 kg ECS vs f64 {rel}");
        }
        // Real geometry: contact predicted when ξ_x − goal_x exceeds the bus-to-bus gap
        // 3.01 − 0.6 − 0.4 = 2.01 m (panels: 3.01 − 0.4 − 0.25 = 2.36 m).
        let t_gap =
            r.xi.iter()
                .position(|p| p.x + 0.01 >= 2.01 - 0.2)
                .map(|k| k as f64 * 0.1)
                .expect("the f64 model crosses the gap");
        let geo = run_case(file, &[], None).unwrap();
        let t_col = geo
            .first_collision_s()
            .expect("collision with real geometry");
        println!(
            "{file} real geometry: predicted gap closure ≈ {t_gap:.1} s, first collision {t_col:.1} s, {}",
            geo.summary["collisions"][0]
        );
        assert!(
            (t_col - t_gap).abs() < 2.0,
            "collision at {t_col} s vs gap closure {t_gap} s"
        );
        assert!(
            !geo.guarantee("clearance_0_5m").unwrap()["held"]
                .as_bool()
                .unwrap()
        );
    }
}

/// dt convergence: the same ACCM run at dt = 0.02 s (5 steps per sample) gives the dt = 0.1 s
/// terminal accuracy to within 10 ε(0.1 s) (the dt-dependent plant differences are the frame
/// turn and the maneuver sampling, both bounded by `model_difference_bound_m_s2`).
#[test]
fn val_xu2015_dt_convergence() {
    let a = run_case("xu2015_accm.ron", &[], None).unwrap();
    let b = run_case("xu2015_accm.ron", &["dt_s=0.02"], None).unwrap();
    assert_eq!(b.samples.len(), a.samples.len());
    let eps = model_difference_bound_m_s2(0.1, 100.0) / 0.05;
    let rel = (a.terminal_rms_m() - b.terminal_rms_m()).abs() / b.terminal_rms_m();
    println!(
        "dt 0.1: {:.6e} m, dt 0.02: {:.6e} m, rel {rel:.2e}, ε {eps:.2e}",
        a.terminal_rms_m(),
        b.terminal_rms_m()
    );
    assert!(rel < 10.0 * eps);
}

/// The first measurement is the paper's start ξ0 = [−20, 0, 5] m (the Hill-frame initial state
/// and the aim offset of the scene, through the ECS), and both bodies start aligned with the
/// tof (their body axes are its columns).
#[test]
fn val_xu2015_initial_geometry() {
    let run = run_case("xu2015_accm.ron", &[], None).unwrap();
    let s0 = run.samples[0];
    assert!(
        (s0.meas_tof_m - Vector3::new(-20.0, 0.0, 5.0)).amax() < 1e-9,
        "{:?}",
        s0.meas_tof_m
    );
    let loaded = load_scene_str(scene_text("xu2015_accm.ron").unwrap(), "s", &[]).unwrap();
    let sim = Simulation::new(&loaded).unwrap();
    let (r, v) = sim.reference_state().unwrap();
    let c = dcm_eci_from_tof_state(&r, &v);
    for b in ["chaser", "target"] {
        let att = sim.body(b).unwrap().att.to_rotation_matrix().into_inner();
        assert!((att - c).amax() < 1e-12, "{b}");
    }
}

/// Measurement noise: seeded and deterministic (same scene → identical samples), zero-mean with
/// the configured σ (sample mean and std within 5 standard errors over 3 × 3000 draws).
#[test]
fn invariant_xu2015_measurement_noise() {
    let ov = ["controllers.0.0.sensor=(noise_sigma_m: 0.002, seed: 42)"];
    let a = run_case("xu2015_pd.ron", &ov, None).unwrap();
    let b = run_case("xu2015_pd.ron", &ov, None).unwrap();
    assert!(
        a.samples
            .iter()
            .zip(&b.samples)
            .all(|(x, y)| x.meas_tof_m == y.meas_tof_m && x.thrust_tof_n == y.thrust_tof_n)
    );
    let d: Vec<f64> = a
        .samples
        .iter()
        .flat_map(|s| {
            (s.meas_tof_m - s.xi_tof_m)
                .iter()
                .copied()
                .collect::<Vec<_>>()
        })
        .collect();
    let n = d.len() as f64;
    let mean = d.iter().sum::<f64>() / n;
    let sd = (d.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0)).sqrt();
    let sigma = 0.002;
    assert!(mean.abs() < 5.0 * sigma / n.sqrt(), "mean {mean}");
    assert!(
        (sd - sigma).abs() < 5.0 * sigma / (2.0 * n).sqrt(),
        "sd {sd}"
    );
    let c = run_case(
        "xu2015_pd.ron",
        &["controllers.0.0.sensor=(noise_sigma_m: 0.002, seed: 43)"],
        None,
    )
    .unwrap();
    assert!(a.samples[5].meas_tof_m != c.samples[5].meas_tof_m);
}

/// Bad controller input gives a located scene error, not a panic.
#[test]
fn regress_xu2015_scene_errors() {
    let text = scene_text("xu2015_accm.ron").unwrap();
    let l = load_scene_str(
        text,
        "s.ron",
        &["controllers.0.0.accm.sample_period_s=0.15".into()],
    )
    .unwrap();
    let e = Simulation::new(&l).err().expect("rejected");
    assert_eq!(e.field, "controllers.0.0.accm.sample_period_s");
    assert!(
        // An error in an overridden value is located in the `--set` argument:
        // line 1, the column of the value after `=`.
        e.file == "s.ron (--set controllers.0.0.accm.sample_period_s=0.15)"
            && (e.line, e.col) == (1, 38),
        "{e}"
    );
    let l = load_scene_str(text, "s.ron", &["controllers.0.0.target=\"chaser\"".into()]).unwrap();
    let e = Simulation::new(&l).err().expect("rejected");
    assert_eq!(e.field, "controllers.0.0.target");
    let l = load_scene_str(text, "s.ron", &["controllers.0.0.accm.shift_m=0.2".into()]).unwrap();
    let e = Simulation::new(&l).err().expect("rejected");
    assert!(e.field.ends_with("accm.shift_m") && e.line > 0, "{e}");
}

/// `rpod reproduce xu2015` output contract: claims.json is a JSON array of objects with exactly
/// `id, claim, kind, paper, threshold_source, measured, held, sensitivity`, unique ids; the held
/// flags are the ones the tests above establish (ACCM better than PD at 90/100 kg overall and
/// per axis, thrust ≤ 5 N, authority at 90/100 kg hold; the 110 kg accuracy, either reading of
/// "±10 % mass" and the real-geometry clearance do not; the thrust-limited bound exceeds the
/// 1 cm goal at 110 kg); REPORT.md and every case's outputs exist.
#[test]
fn regress_xu2015_reproduce_outputs() {
    let dir = std::env::temp_dir().join(format!("rpod-xu2015-repro-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    rpod::reproduce::xu2015::run(&dir).expect("reproduce runs");
    let claims: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("claims.json")).unwrap()).unwrap();
    let arr = claims.as_array().expect("array");
    let mut ids = std::collections::BTreeSet::new();
    for c in arr {
        let mut keys: Vec<&String> = c.as_object().unwrap().keys().collect();
        keys.sort();
        assert_eq!(
            keys,
            [
                "claim",
                "held",
                "id",
                "kind",
                "measured",
                "paper",
                "sensitivity",
                "threshold_source"
            ],
            "{c}"
        );
        assert!(ids.insert(c["id"].as_str().unwrap().to_string()));
    }
    let held = |id: &str| {
        arr.iter().find(|c| c["id"] == id).expect(id)["held"]
            .as_bool()
            .unwrap()
    };
    for id in [
        "accm-beats-pd-100kg",
        "accm-beats-pd-90kg",
        "accm-beats-pd-per-axis",
        "thrust-within-5n",
        "authority-90-100kg",
    ] {
        assert!(held(id), "{id}");
    }
    assert!(!held("m110-keeps-accuracy"));
    assert!(!held("target-mass-pm10-keeps-accuracy"));
    assert!(held("m110-bound-exceeds-goal"));
    assert!(!held("m110-real-geometry-clear"));
    // Against the PD tuned at comparable force ACCM is still more accurate.
    for id in ["accm-beats-tuned-pd-100kg", "accm-beats-tuned-pd-90kg"] {
        assert!(held(id), "{id}");
    }
    assert!(dir.join("REPORT.md").exists());
    for case in ["accm_100kg", "pd_110kg_point_mass"] {
        assert!(dir.join("cases").join(case).join("trajectory.csv").exists());
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// The thrust-limited lower bound (the LP of `reproduce::xu2015::x_error_lower_bound`) against
/// a closed form: a constant deficit δ = a_t − a over a window T forces ë = −δ whatever the law,
/// e is then a parabola of spread δT²/8 and the best any law can hold is max|e| = δT²/16
/// (free initial state). The reachable-set test at b = 0.99·δT²/16 must fail, at 1.01× pass;
/// the single-peak chord bound gives the same δT²/16.
#[test]
fn val_xu2015_lower_bound_closed_form() {
    use rpod::reproduce::xu2015::{single_peak_bound_m, tube_feasible};
    let (a, delta, t_win, h): (f64, f64, f64, f64) = (0.04, 0.002, 20.0, 0.1);
    let a_t = |_t: f64| a + delta;
    let exact = delta * t_win * t_win / 16.0;
    let n = (t_win / h).round() as usize;
    assert!(!tube_feasible(&a_t, a, 0.99 * exact, 0.0, h, n, 20.0));
    assert!(tube_feasible(&a_t, a, 1.01 * exact, 0.0, h, n, 20.0));
    let sp = single_peak_bound_m(&a_t, a, 0.0, t_win);
    assert!((sp - exact).abs() < 2e-3 * exact, "{sp} vs {exact}");
    // No deficit: any b > 0 is feasible.
    assert!(tube_feasible(&|_t: f64| 0.9 * a, a, 1e-6, 0.0, h, n, 20.0));
}

/// At 110 kg: the LP bound is at least the single-peak closed form (a relaxation of the same
/// problem), above the 1 cm goal, and below what both laws actually hold (their largest x error
/// over the last 100 s, point-mass variant) — no law can beat it.
#[test]
fn val_xu2015_lower_bound_at_110kg() {
    use rpod::reproduce::xu2015::x_error_lower_bound;
    let b = x_error_lower_bound(110.0, 200.0, 5.0);
    eprintln!(
        "110 kg: bound {:.4} m, single peak {:.4} m, inflation {:.2e} m/s²",
        b.bound_m, b.single_peak_m, b.inflation_m_s2
    );
    assert!(b.bound_m >= b.single_peak_m - 1e-9);
    assert!(b.bound_m > 0.01 && b.bound_m < 1.0);
    assert!(b.inflation_m_s2 < 1e-4 * b.a_max_m_s2);
    for f in ["xu2015_accm_m110.ron", "xu2015_pd_m110.ron"] {
        let r = run_case(f, &POINT_MASS_OVERRIDES, None).unwrap();
        assert!(r.terminal_max_axis_m().x >= b.bound_m, "{f}");
    }
    // With authority to spare (90 kg) nothing is forced.
    assert!(x_error_lower_bound(90.0, 200.0, 5.0).bound_m < 1e-5);
}

/// The tuned PD: in the f64 model at 100 kg it is at least as accurate as the golden-section
/// gains and keeps its RMS thrust within 1 % of ACCM's (the paper's "comparable force"); its
/// worst RMS over 100 and 90 kg is the tuning's.
#[test]
fn val_xu2015_tuned_pd_is_a_fair_baseline() {
    use rpod::control::xu2015::Xu2015Law;
    use rpod::reproduce::xu2015::{relative_model_terminal_with, tune_pd};
    let t = tune_pd(true);
    let mut p = PdParams::paper();
    p.kp_s2 = t.kp_s2;
    p.kd_s = t.kd_s;
    let (rms, _, thr) = relative_model_terminal_with(Xu2015Law::Pd, &p, 100.0, 200.0);
    let rms90 = relative_model_terminal_with(Xu2015Law::Pd, &p, 90.0, 200.0).0;
    eprintln!(
        "tuned PD: ω_n {:.3} ζ {:.3}: {rms:.3e} m RMS (golden {:.3e}), {thr:.3} N RMS (budget {:.3} N)",
        t.omega_n_rad_s, t.zeta, t.golden_rms_m, t.thrust_budget_n
    );
    assert_eq!(rms.max(rms90), t.rms_m);
    assert!(rms <= t.golden_rms_m);
    assert!(thr <= 1.01 * t.thrust_budget_n);
}
