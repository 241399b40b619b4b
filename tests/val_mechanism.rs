//! Docking mechanism features (docs/mechanisms.md) against independent references.
//!
//! - Capture rate limits: the decision is a comparison, so its reference is the limit itself:
//!   a rate equal to the limit is accepted, the next f64 above it refused, for each of the
//!   three rates, and the refusal names the rate. In a run, the chaser rolling about the
//!   docking axis is refused when the limit lies 1e-9 (relative) below the relative angular
//!   rate the latch saw at the step it engaged in an otherwise identical run, and latches at
//!   the same step when the limit lies 1e-9 above it (the runs are deterministic, so the two
//!   differ only by the limit; 1e-9 is far above rounding, 1e-16, and far below the rate's
//!   change from one step to the next, ~1e-5 relative from the contact friction).
//! - Bad input: NaN and negative limits are located errors, and `rpod run` exits 2.

use rpod::scene::{CaptureRates, load_scene_file};
use rpod::sim::Simulation;
use rpod::sim::docking::{DockState, Docking, PortGeometry, capture_rate_violation};
use std::process::Command;

fn sim(name: &str, set: &[String]) -> Simulation {
    let loaded = load_scene_file(format!("scenes/examples/{name}.ron").as_ref(), set).unwrap();
    Simulation::new(&loaded).unwrap()
}

fn dock(s: &Simulation) -> Docking {
    s.app.world().resource::<Docking>().clone()
}

#[test]
fn val_capture_rate_limit_is_exact() {
    let lim = CaptureRates::default();
    // The defaults are the IDSS values (the angular one as the magnitude of the per-axis box).
    assert_eq!(lim.max_axial_rate_m_s, 0.10);
    assert_eq!(lim.max_lateral_rate_m_s, 0.04);
    assert!((lim.max_angular_rate_deg_s - 0.2 * 3f64.sqrt()).abs() < 1e-15);
    let at = |a: f64, l: f64, w: f64| PortGeometry {
        axial_rate_m_s: a,
        lateral_rate_m_s: l,
        angular_rate_deg_s: w,
        ..Default::default()
    };
    let (a, l, w) = (
        lim.max_axial_rate_m_s,
        lim.max_lateral_rate_m_s,
        lim.max_angular_rate_deg_s,
    );
    // At the limits (the axial rate either sign): accepted.
    assert!(capture_rate_violation(&lim, &at(a, l, w)).is_none());
    assert!(capture_rate_violation(&lim, &at(-a, l, w)).is_none());
    for (g, name) in [
        (at(a.next_up(), l, w), "axial_rate_m_s"),
        (at(-a.next_up(), l, w), "axial_rate_m_s"),
        (at(a, l.next_up(), w), "lateral_rate_m_s"),
        (at(a, l, w.next_up()), "angular_rate_deg_s"),
        (at(a, l, f64::NAN), "angular_rate_deg_s"),
    ] {
        let (payload, why) = capture_rate_violation(&lim, &g).expect("refused");
        assert_eq!(payload["rate"], name, "{why}");
        assert!(why.contains(name), "{why}");
    }
}

/// docking_aligned with the chaser rolling about the docking axis at `roll_deg_s` and the
/// angular rate limit `limit_deg_s`, run for 40 s.
fn rolling(roll_deg_s: f64, limit_deg_s: f64) -> Simulation {
    let mut s = sim(
        "docking_aligned",
        &[
            format!("bodies.chaser.initial.rate_body_deg_s=({roll_deg_s}, 0.0, 0.0)"),
            format!("docking.latch.capture_rates=(max_angular_rate_deg_s: {limit_deg_s:e})"),
        ],
    );
    s.step(4000);
    s
}

#[test]
fn val_capture_refuses_a_rolling_chaser_exactly_above_the_limit() {
    // The aligned approach without roll latches, within every default limit.
    let mut s = sim("docking_aligned", &[]);
    s.step(4000);
    let d = dock(&s);
    assert_eq!(d.state, DockState::Latched, "{}", d.reason);
    let [ax, lat, w] = d.latch_rates.expect("rates at the latch");
    println!("aligned: rates at the latch {ax:e} m/s, {lat:e} m/s, {w:e} deg/s");
    assert!(d.refusals == 0);

    // Rolling at 2 deg/s with the limit out of the way: latched; the rate it latched at.
    let free = rolling(2.0, 1e3);
    let d = dock(&free);
    assert_eq!(d.state, DockState::Latched, "{}", d.reason);
    let t_latch = d.t_latch_s.unwrap();
    let w_latch = d.latch_rates.unwrap()[2];
    println!("rolling 2 deg/s: latched at {t_latch} s at {w_latch} deg/s");
    // The roll survives the approach (axisymmetric contact; the tip's friction on the back
    // plate removes little in the 0.2 s dwell).
    assert!((w_latch - 2.0).abs() < 0.1, "{w_latch}");

    // With the default limit (0.346 deg/s): refused, never latched, the reason names the rate.
    let s = rolling(2.0, CaptureRates::default().max_angular_rate_deg_s);
    let d = dock(&s);
    assert_eq!(d.state, DockState::SoftCapture, "{}", d.reason);
    assert!(d.reason.contains("angular_rate_deg_s"), "{}", d.reason);
    let refused: Vec<_> = s
        .events()
        .into_iter()
        .filter(|e| e.kind == "capture_refused")
        .collect();
    // (Again each time the cone reseats after a slight rebound off the back plate.)
    assert!(!refused.is_empty());
    assert!(
        refused
            .iter()
            .all(|e| e.data["rate"] == "angular_rate_deg_s"),
        "{refused:?}"
    );
    assert_eq!(refused[0].t_s, t_latch);

    // Limit just below the rate at the latch step: refused at that step.
    let s = rolling(2.0, w_latch * (1.0 - 1e-9));
    let first = s
        .events()
        .into_iter()
        .find(|e| e.kind == "capture_refused")
        .expect("refused");
    assert_eq!(first.t_s, t_latch);
    assert_eq!(first.data["value"].as_f64().unwrap(), w_latch);
    assert_ne!(dock(&s).t_latch_s, Some(t_latch));
    // … just above: latched at the same step.
    let s = rolling(2.0, w_latch * (1.0 + 1e-9));
    assert_eq!(dock(&s).t_latch_s, Some(t_latch));
    assert_eq!(dock(&s).refusals, 0);
}

#[test]
fn val_capture_rate_limits_bad_input_is_located() {
    for (v, words) in [
        // NaN is refused by the shared number check before the mechanism's own validation.
        ("NaN", "NaN is not a finite number"),
        ("-0.1", "positive number of deg/s, got -0.1"),
        ("0.0", "positive number of deg/s"),
    ] {
        let e = load_scene_file(
            "scenes/examples/docking_aligned.ron".as_ref(),
            &[format!(
                "docking.latch.capture_rates=(max_angular_rate_deg_s: {v})"
            )],
        )
        .unwrap_err();
        assert_eq!(
            e.field, "docking.latch.capture_rates.max_angular_rate_deg_s",
            "{e}"
        );
        assert!(e.line > 0 && e.col > 0, "{e}");
        assert!(e.message.contains(words), "{e}");
    }
    let out = std::env::temp_dir().join(format!("rpod-mech-bad-{}", std::process::id()));
    let r = Command::new(env!("CARGO_BIN_EXE_rpod"))
        .args([
            "run",
            "scenes/examples/docking_aligned.ron",
            "--set",
            "docking.latch.capture_rates=(max_axial_rate_m_s: -1.0)",
            "--out",
        ])
        .arg(&out)
        .output()
        .unwrap();
    assert_eq!(r.status.code(), Some(2));
    let err = String::from_utf8_lossy(&r.stderr);
    assert!(
        err.contains("docking.latch.capture_rates.max_axial_rate_m_s"),
        "{err}"
    );
    assert!(!out.exists());
}

/// The compliant latch of the tests: k = 1e7 N/m, k_θ = 1e6 N·m/rad, damping ratio ≈ 0.05
/// on the pair's reduced mass (218 kg) and reduced roll inertia (93 kg·m²).
const LATCH: &str = "docking.latch.joint=Compliant((stiffness_n_m: 1e7, damping_n_s_m: 4.67e3, rot_stiffness_nm_rad: 1e6, rot_damping_nm_s_rad: 1e3))";

/// Peak |k·x + c·ẋ| of m·ẍ + c·ẋ + k·x = 0 from x = 0, ẋ = v0 (closed form, sampled at
/// 1 µs over three periods).
fn oscillator_peak(m: f64, k: f64, c: f64, v0: f64) -> f64 {
    let w0 = (k / m).sqrt();
    let z = c / (2.0 * (k * m).sqrt());
    let wd = w0 * (1.0 - z * z).sqrt();
    let mut peak: f64 = 0.0;
    let t_end = 3.0 * std::f64::consts::TAU / w0;
    let mut t = 0.0;
    while t < t_end {
        let e = (-z * w0 * t).exp();
        let x = v0 / wd * e * (wd * t).sin();
        let v = v0 * e * ((wd * t).cos() - z * w0 / wd * (wd * t).sin());
        peak = peak.max((k * x + c * v).abs());
        t += 1e-6;
    }
    peak
}

#[test]
fn val_compliant_latch_loads_converge_in_dt_and_match_the_oscillator() {
    // Aligned approach from 5 cm, the chaser rolling at 0.3 deg/s about the docking axis
    // (inside the default limit): the latch catches the cone rebounding off the back plate
    // (axial rate v0) and rolling (rate w0). The axial force passes through both centres of
    // mass and the roll is about principal axes on the same line, so the interface force is
    // the 1-D oscillator of the reduced mass and the moment that of the reduced roll inertia.
    let m_r = 300.0 * 800.0 / 1100.0;
    let i_r = 110.0 * 620.0 / 730.0;
    let mut peaks = Vec::new();
    for dt in [1e-3, 5e-4] {
        let mut s = sim(
            "docking_aligned",
            &[
                LATCH.into(),
                "bodies.chaser.initial.pos_m=(1.62, 0.0, 0.0)".into(),
                "bodies.chaser.initial.rate_body_deg_s=(0.3, 0.0, 0.0)".into(),
                format!("dt_s={dt}"),
            ],
        );
        s.step(s.steps_for(4.0));
        let d = dock(&s);
        assert_eq!(d.state, DockState::Latched, "{}", d.reason);
        let il = d.interface.clone().expect("compliant latch loads");
        let [v0, _, w0] = d.latch_rates.unwrap();
        let f_ref = oscillator_peak(m_r, 1e7, 4.67e3, v0);
        let m_ref = oscillator_peak(i_r, 1e6, 1e3, w0.to_radians());
        println!(
            "dt {dt} s: latch at {:?} s, v0 {v0:.5e} m/s, w0 {w0:.4} deg/s; peak force {:.3} N (closed form {f_ref:.3} N), peak moment {:.4} N·m (closed form {m_ref:.4} N·m)",
            d.t_latch_s, il.peak_force_n, il.peak_moment_nm
        );
        // The oscillators: 1 % (ours: the sub-steps resolve each period in at least the
        // contact's sub-steps per period, and the loads are sampled at sub-step ends).
        assert!((il.peak_force_n / f_ref - 1.0).abs() < 0.01);
        assert!((il.peak_moment_nm / m_ref - 1.0).abs() < 0.01);
        peaks.push((il.peak_force_n, il.peak_moment_nm));
    }
    // Convergence in dt: within 10 % between 1 and 0.5 ms (our convergence criterion, docs/mechanisms.md).
    let (a, b) = (peaks[0], peaks[1]);
    assert!((a.0 / b.0 - 1.0).abs() < 0.1, "{peaks:?}");
    assert!((a.1 / b.1 - 1.0).abs() < 0.1, "{peaks:?}");
}

#[test]
fn val_compliant_latch_bad_input_is_located() {
    for (set, field) in [
        (
            "docking.latch.joint=Compliant((stiffness_n_m: -1.0, damping_n_s_m: 1.0, rot_stiffness_nm_rad: 1.0, rot_damping_nm_s_rad: 1.0))",
            "docking.latch.joint.stiffness_n_m",
        ),
        (
            "docking.latch.joint=Compliant((stiffness_n_m: 1.0, damping_n_s_m: 0.0, rot_stiffness_nm_rad: 1.0, rot_damping_nm_s_rad: 1.0))",
            "docking.latch.joint.damping_n_s_m",
        ),
    ] {
        let e = load_scene_file(
            "scenes/examples/docking_aligned.ron".as_ref(),
            &[set.into()],
        )
        .unwrap_err();
        assert_eq!(e.field, field, "{e}");
        assert!(e.line > 0 && e.message.contains("positive"), "{e}");
    }
    let e = load_scene_file(
        "scenes/examples/docking_aligned.ron".as_ref(),
        &[LATCH.into(), "docking.contact=Rigid".into()],
    )
    .unwrap_err();
    assert_eq!(e.field, "docking.latch.joint", "{e}");
}

/// Separation speed of the pair from the springs' energy E = ½(F + F_pre)·L shared by the
/// two masses with zero total momentum: v_rel = √(2E/m_r), v_c = v_rel·m_t/(m_c + m_t),
/// v_t = −v_rel·m_c/(m_c + m_t).
fn separation_closed_form(f: f64, f_pre: f64, l: f64, m_c: f64, m_t: f64) -> (f64, f64, f64) {
    let e = 0.5 * (f + f_pre) * l;
    let m_r = m_c * m_t / (m_c + m_t);
    let v_rel = (2.0 * e / m_r).sqrt();
    (v_rel, v_rel * m_t / (m_c + m_t), -v_rel * m_c / (m_c + m_t))
}

fn check_undock(set: &[String]) {
    let mut s = sim("undock_depart", set);
    let sep = s.scene.docking.clone().unwrap().separation.unwrap();
    s.step(s.steps_for(120.0));
    let d = dock(&s);
    assert_eq!(d.state, DockState::Released, "{}", d.reason);
    assert_eq!(d.t_release_s, Some(2.0));
    let (v_rel, v_c, v_t) =
        separation_closed_form(sep.force_n, sep.preload_n, sep.stroke_m, 300.0, 800.0);
    let (vel, t_end) = d.separation_end.expect("the springs reached their stops");
    let c = s.body("chaser").unwrap();
    let t = s.body("target").unwrap();
    println!(
        "{set:?}: springs extended at {t_end} s; relative {:.6} m/s (closed form {v_rel:.6}); chaser {:.6} m/s ({v_c:.6}), target {:.6} m/s ({v_t:.6}); centres of mass {:.2} m apart",
        vel[0],
        c.vel_m_s.x,
        t.vel_m_s.x,
        (c.pos_m - t.pos_m).norm()
    );
    // The separation speed: 0.5 % (the sub-steps cross the end of the stroke within 0.5 % of
    // it, and the force there is the preload: an energy error below 0.5 %·F_pre·L/E).
    assert!((vel[0] / v_rel - 1.0).abs() < 5e-3, "{vel:?} vs {v_rel}");
    assert!((c.vel_m_s.x / v_c - 1.0).abs() < 5e-3);
    assert!((t.vel_m_s.x / v_t - 1.0).abs() < 5e-3);
    // Momentum: the springs are internal forces (rapier's f32 joint held the pair before).
    let p = c.vel_m_s * 300.0 + t.vel_m_s * 800.0;
    assert!(p.norm() < 1e-6 * 300.0 * v_c, "momentum {p}");
    // Along the docking axis only.
    assert!(c.vel_m_s.y.abs() + c.vel_m_s.z.abs() < 1e-9 && c.omega_rad_s.norm() < 1e-9);
    // Nothing touched after the release, nothing collided, ≥ 10 m apart, every guarantee held.
    assert_eq!(d.loads.impact_count, 0);
    assert_eq!(d.loads.contact_duration_s, 0.0);
    assert!(s.contacts().first_collision_s.is_none());
    assert!(s.contacts().active.is_empty());
    assert!(s.min_clearance_non_docking_m() > 0.0);
    // Apart by at least 10 m: the centres of mass, less the bodies' bounding extents along the
    // docking axis (target: 0.82 m to its port's slot face; chaser: 0.5 m bus to port plus the
    // 0.25 m cone, and 0.8 m of bus and wings behind it are not in between; a conservative
    // 1.6 m in all).
    assert!((c.pos_m - t.pos_m).norm() - 1.6 > 10.0);
    for g in &s.guarantees().status {
        assert!(g.held, "{} violated at {:?}", g.name, g.first_violation_s);
    }
}

#[test]
fn val_undock_separation_speed_matches_spring_energy_and_momentum() {
    // Rigid latch (the scene's), then the compliant latch.
    check_undock(&[]);
    check_undock(&[LATCH.into()]);
}

#[test]
fn val_release_when_not_docked_is_an_event_and_bad_scenes_are_located() {
    let mut s = sim("docking_aligned", &[]);
    assert!(s.release_docking("test"));
    s.step(1);
    let ev: Vec<_> = s
        .events()
        .into_iter()
        .filter(|e| e.kind == "docking_release_ignored")
        .collect();
    assert_eq!(ev.len(), 1);
    assert!(
        ev[0].data["reason"]
            .as_str()
            .unwrap()
            .contains("not docked")
    );
    assert_ne!(dock(&s).state, DockState::Released);
    // Scene errors: not seated at the start; bad separation springs; release without a mechanism.
    let e = load_scene_file(
        "scenes/examples/undock_depart.ron".as_ref(),
        &["bodies.chaser.initial.pos_m=(1.6, 0.0, 0.0)".into()],
    )
    .and_then(|l| Simulation::new(&l).map(|_| ()))
    .unwrap_err();
    assert_eq!(e.field, "docking.start_latched", "{e}");
    assert!(e.message.contains("not seated"), "{e}");
    for (set, field) in [
        (
            "docking.separation=Some((stroke_m: 0.0, force_n: 40.0, preload_n: 20.0))",
            "docking.separation.stroke_m",
        ),
        (
            "docking.separation=Some((stroke_m: 0.05, force_n: -1.0, preload_n: 0.0))",
            "docking.separation.force_n",
        ),
        (
            "docking.separation=Some((stroke_m: 0.05, force_n: 40.0, preload_n: 50.0))",
            "docking.separation.preload_n",
        ),
        ("docking.contact=Rigid", "docking.separation"),
    ] {
        let e = load_scene_file("scenes/examples/undock_depart.ron".as_ref(), &[set.into()])
            .unwrap_err();
        assert_eq!(e.field, field, "{e}");
        assert!(e.line > 0, "{e}");
    }
    let e = load_scene_file(
        "scenes/examples/undock_depart.ron".as_ref(),
        &["docking=None".into()],
    )
    .and_then(|l| Simulation::new(&l).map(|_| ()))
    .unwrap_err();
    assert!(e.field.contains("release_docking"), "{e}");
}
