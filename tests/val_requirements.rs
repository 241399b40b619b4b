//! The RPOD requirement set (docs/guarantees.md) against closed forms.
//!
//! References (free space unless stated; straight-line motion, so the f64 path is exact):
//! * `KeepOutEllipsoid` fly-by: a target yawed 90° (body x = world y, body y = −world x) with
//!   an ellipsoid of semi-axes (4, 2, 1) m in its body frame; the chaser flies the world line
//!   (−1, y₀ + v t, 0), i.e. the body-frame line (y₀ + v t, 1, 0): inside while
//!   |y₀ + v t| < 4·√(1 − 1/4) = 2√3 m; deepest at y = 0, where s = 1/2 and the margin is
//!   (s − 1)·a_min = −0.5 m.
//! * `ClosingSpeedGate`: a chaser closing at 1 m/s from 20.005 m through gates (30 m, 2 m/s) and
//!   (10 m, 0.5 m/s): margin 2 − 1 = 1 m/s until the range drops below 10 m at t = 10.005 s,
//!   first seen at the sample t = 10.01 s (judged at samples), then 0.5 − 1 = −0.5 m/s.
//! * `PassiveSafety`: a circular orbit (a = 7000 km, no J2); the CW drift from radial offset
//!   x₀ with ẏ₀ = −(3/2) n x₀ is the straight line (x₀, y₀ − (3/2) n x₀ τ, 0), closest approach
//!   |x₀| at τ* = y₀ / ((3/2) n x₀). The margin must lie in [x₀ − R − tol, x₀ − R] with tol =
//!   the guarantee's stated slack: V·Δτ/2 (grid) + the CW linearisation bound B, computed here
//!   from the same published bounds (`cw_drift_speed_bound`, `cw_error_bound_from_cw_max`).
//!   Over the run, the window's closest approach √(x₀² + ((3/2) n x₀ (τ* − H − t))²) reaches R
//!   at t_c; the first violation lies in [t_c − tol/Ḋ, t_c + dt] (Ḋ: its rate at R).
//! * `PassiveSafety`, propagated (elliptic or J2 references): on an eccentric orbit against the
//!   Kepler closed form (Battin's f and g functions) of both bodies; with J2 against an RK4
//!   integration written in the test from Vallado's J2 acceleration; both sampled finely. The
//!   margin must be at most the sampled closest approach less R and at least that less the
//!   grid bound's own slack Δτ·V/2.
//! * `PassiveSafety`, a propagated drift kept and reused (`DriftTrack::reuse`): on the eccentric
//!   orbit above, against the Kepler closed form of both bodies from the later state: after a
//!   coast (the reused margin is sound and as tight as a fresh evaluation's grid slack, its
//!   deviation bound only the integration allowance) and after a velocity kick to the chaser
//!   (the reused margin is still at most the kicked drift's sampled closest approach less R, and
//!   the deviation bound covers the sampled deviation between the kicked and unkicked drifts).
//! * `LineOfSight`: a sensor at x = 0.2 m looking along +x at a point 9.4 m away; a box panel
//!   (half-width 0.2 m in y) crossing the line at 1 m/s from y₀ = −1.205 m blocks it from
//!   t = 1.005 s (margin = |y| − 0.2 m, the segment's signed distance to the panel), deepest
//!   −0.2 m at y = 0.
//!
//! Tolerances: refined event times to the monitor's time tolerance (`t_tol_s`, < 1e-6 s) plus
//! 1e-9 s of f64 rounding (the line of sight may be cut up to 1e-3 s early: parry's GJK
//! precision near contact, 1.2e-3 of the ~1 m features, counted as blocked); margins found between samples to 1e-3 of their size plus 1e-6 m
//! (the interval search's stated refinement), parry's f32 distances to 1e-5 m.

use rpod::orbit::constants::MU_EARTH_M3_S2;
use rpod::scene::load_scene_str;
use rpod::sim::Simulation;
use serde_json::Value;

fn body(name: &str, part: &str, pos: (f64, f64, f64), vel: (f64, f64, f64), extra: &str) -> String {
    format!(
        r#"(name: "{name}", role: Other, mass_kg: 1.0, inertia_kg_m2: (xx: 0.01, yy: 0.01, zz: 0.01),
           initial: (pos_m: ({}, {}, {}), vel_m_s: ({}, {}, {}){extra}),
           parts: [{part}])"#,
        pos.0, pos.1, pos.2, vel.0, vel.1, vel.2
    )
}

const BALL: &str = r#"Bus(name: "ball", shape: Sphere(radius_m: 0.1))"#;

fn free_scene(bodies: &[String], guarantees: &str, duration: f64) -> Simulation {
    let text = format!(
        r#"Scene(name: "req", dt_s: 0.01, duration_s: {duration}, environment: FreeSpace,
           bodies: [{}], guarantees: [{guarantees}])"#,
        bodies.join(",\n")
    );
    let loaded = load_scene_str(&text, "req", &[]).unwrap_or_else(|e| panic!("{e}"));
    Simulation::new(&loaded).unwrap_or_else(|e| panic!("{e}"))
}

fn run(mut sim: Simulation) -> (Simulation, Value) {
    let n = sim.steps_for(sim.scene.duration_s);
    sim.step(n);
    let s = sim.summary();
    (sim, s)
}

fn guarantee<'a>(s: &'a Value, name: &str) -> &'a Value {
    s["guarantees"]
        .as_array()
        .unwrap()
        .iter()
        .find(|g| g["name"] == name)
        .unwrap_or_else(|| panic!("no guarantee {name}"))
}

fn f(v: &Value) -> f64 {
    v.as_f64().unwrap_or_else(|| panic!("not a number: {v}"))
}

fn first_violation_near(g: &Value, want: f64, slack_s: f64) {
    let t = f(&g["first_violation_s"]);
    let tol = f(&g["first_violation_tol_s"]);
    assert!(
        t <= want + slack_s && want <= t + tol + slack_s && tol < 1e-6,
        "first violation {t} +{tol} vs {want}: {g}"
    );
}

#[test]
fn val_keep_out_ellipsoid_flyby_in_the_target_body_frame() {
    let (y0, v) = (-5.0, 1.0);
    let (_, s) = run(free_scene(
        &[
            body(
                "target",
                BALL,
                (0.0, 0.0, 0.0),
                (0.0, 0.0, 0.0),
                ", attitude: EulerZyxDeg(yaw: 90.0, pitch: 0.0, roll: 0.0)",
            ),
            body("chaser", BALL, (-1.0, y0, 0.0), (0.0, v, 0.0), ""),
        ],
        r#"KeepOutEllipsoid(name: "koz", body: "chaser", around: "target",
              semi_axes_m: (4.0, 2.0, 1.0), frame: TargetBody)"#,
        10.0,
    ));
    let g = guarantee(&s, "koz");
    println!("{g}");
    assert_eq!(g["judged"], "interval");
    assert_eq!(g["verdict"], "violated");
    let half = 2.0 * 3.0_f64.sqrt();
    first_violation_near(g, (-half - y0) / v, 1e-9);
    let worst = f(&g["worst_margin"]);
    assert!((worst + 0.5).abs() < 1e-3 * 0.5 + 1e-6, "{worst}");
    assert!((f(&g["worst_margin_t_s"]) - 5.0).abs() < 0.01, "{g}");
    assert_eq!(f(&g["violations"]), 1.0);
    assert!(f(&g["last_margin"]) > 0.0, "restored after the fly-by: {g}");
}

#[test]
fn val_closing_speed_gate_crossed_at_a_known_time() {
    let (_, s) = run(free_scene(
        &[
            body("target", BALL, (0.0, 0.0, 0.0), (0.0, 0.0, 0.0), ""),
            body("chaser", BALL, (20.005, 0.0, 0.0), (-1.0, 0.0, 0.0), ""),
        ],
        r#"ClosingSpeedGate(name: "gates", body: "chaser", around: "target",
              gates: [(30.0, 2.0), (10.0, 0.5)])"#,
        12.0,
    ));
    let g = guarantee(&s, "gates");
    println!("{g}");
    assert_eq!(g["unit"], "m_s");
    assert_eq!(g["judged"], "samples only");
    assert_eq!(g["verdict"], "violated");
    assert!((f(&g["first_violation_s"]) - 10.01).abs() < 1e-9, "{g}");
    assert!((f(&g["worst_margin"]) + 0.5).abs() < 1e-12, "{g}");
}

/// Beyond the outermost gate no gate applies: the margin is the scene's speed limit less the
/// closing speed (finite: the run is not stopped by the guard, as an infinite margin did),
/// then the gate's once inside it. Same straight line as above, from 20.005 m with one gate
/// at 10 m: margin 10⁵ − 1 m/s until t = 10.01 s, then 0.5 − 1 = −0.5 m/s.
#[test]
fn val_closing_speed_gate_beyond_the_outermost_gate_is_finite() {
    let (_, s) = run(free_scene(
        &[
            body("target", BALL, (0.0, 0.0, 0.0), (0.0, 0.0, 0.0), ""),
            body("chaser", BALL, (20.005, 0.0, 0.0), (-1.0, 0.0, 0.0), ""),
        ],
        r#"ClosingSpeedGate(name: "gates", body: "chaser", around: "target",
              gates: [(10.0, 0.5)])"#,
        12.0,
    ));
    let g = guarantee(&s, "gates");
    assert_eq!(g["verdict"], "violated");
    assert!((f(&g["first_violation_s"]) - 10.01).abs() < 1e-9, "{g}");
    assert!((f(&g["worst_margin"]) + 0.5).abs() < 1e-12, "{g}");
    assert!(f(&g["last_margin"]).is_finite(), "{g}");
}

#[test]
fn gates_out_of_order_and_bad_values_are_located_errors() {
    for (gates, field) in [
        ("[(10.0, 0.5), (30.0, 2.0)]", "guarantees.gates.gates.1.0"),
        ("[(30.0, -2.0)]", "guarantees.gates.gates.0.1"),
        ("[]", "guarantees.gates.gates"),
    ] {
        let text = format!(
            r#"Scene(name: "req", dt_s: 0.01, duration_s: 1.0, environment: FreeSpace,
               bodies: [{}, {}],
               guarantees: [ClosingSpeedGate(name: "gates", body: "chaser", around: "target", gates: {gates})])"#,
            body("target", BALL, (0.0, 0.0, 0.0), (0.0, 0.0, 0.0), ""),
            body("chaser", BALL, (5.0, 0.0, 0.0), (0.0, 0.0, 0.0), ""),
        );
        let e = load_scene_str(&text, "req", &[]).unwrap_err();
        assert_eq!(e.field, field, "{e}");
        assert!(e.line > 0, "{e}");
    }
}

fn orbit_scene(chaser: (f64, f64, f64, f64), guarantees: &str, duration: f64, j2: bool) -> String {
    let (x, y, vx, vy) = chaser;
    format!(
        r#"Scene(name: "ps", dt_s: 0.1, duration_s: {duration},
           environment: Orbit(reference: Elements(a_m: 7000000.0, e: 0.0, i_deg: 0.0, raan_deg: 0.0,
                argp_deg: 0.0, true_anomaly_deg: 0.0), j2: {j2}, gravity_gradient: false),
           bodies: [
             (name: "target", role: Target, mass_kg: 500.0, inertia_kg_m2: (xx: 100.0, yy: 100.0, zz: 100.0),
              initial: (frame: Hill, pos_m: (0.0, 0.0, 0.0)),
              parts: [Bus(name: "bus", shape: Box(size_m: (1.0, 1.0, 1.0)))]),
             (name: "chaser", role: Chaser, mass_kg: 100.0, inertia_kg_m2: (xx: 10.0, yy: 10.0, zz: 10.0),
              initial: (frame: Hill, pos_m: ({x}, {y}, 0.0), vel_m_s: ({vx}, {vy}, 0.0)),
              parts: [Bus(name: "bus", shape: Box(size_m: (0.5, 0.5, 0.5)))]),
           ],
           guarantees: [{guarantees}])"#
    )
}

fn sim_of(text: &str) -> Simulation {
    let loaded = load_scene_str(text, "ps", &[]).unwrap_or_else(|e| panic!("{e}"));
    Simulation::new(&loaded).unwrap_or_else(|e| panic!("{e}"))
}

/// The guarantee's stated slack for the straight-line drift: V·Δτ/2 + B.
fn drift_tolerance(x0: f64, y0: f64, n: f64, horizon: f64, dtau: f64) -> f64 {
    let state =
        nalgebra::SVector::<f64, 6>::from_column_slice(&[x0, y0, 0.0, 0.0, -1.5 * n * x0, 0.0]);
    let v = rpod::guarantee::requirements::cw_drift_speed_bound(&state, n);
    // The chaser's largest separation from the reference over the horizon (a straight line:
    // at an end), plus the grid slack, as the guarantee computes it.
    let y_end = y0 - 1.5 * n * x0 * horizon;
    let rho_max = (x0 * x0 + y0.abs().max(y_end.abs()).powi(2)).sqrt() + 0.5 * v * dtau;
    let (_, b) = rpod::orbit::cw::cw_error_bound_from_cw_max(rho_max, 7.0e6, n, horizon).unwrap();
    println!(
        "V = {v} m/s, grid slack {} m, CW bound {b} m",
        0.5 * v * dtau
    );
    0.5 * v * dtau + b
}

#[test]
fn val_passive_safety_cw_flyby_closest_approach() {
    let n = (MU_EARTH_M3_S2 / 7.0e6_f64.powi(3)).sqrt();
    let (x0, y0, r) = (20.0, 30.0, 5.0);
    let vy = -1.5 * n * x0;
    let t_star = y0 / (1.5 * n * x0);
    let (h, grid) = (2000.0, 5.0);
    assert!(t_star < h);
    let sim = sim_of(&orbit_scene(
        (x0, y0, 0.0, vy),
        &format!(
            r#"PassiveSafety(name: "ps", body: "chaser", around: "target", radius_m: Some({r}),
                 horizon_s: {h}, grid_s: {grid})"#
        ),
        1.0,
        false,
    ));
    let g = &sim.guarantees().status[0];
    let tol = drift_tolerance(x0, y0, n, h, grid);
    let want = x0 - r;
    println!(
        "t = 0: margin {} m, closed form {want} m, tolerance {tol} m",
        g.last_margin
    );
    assert!(
        g.last_margin <= want && g.last_margin >= want - tol,
        "{}",
        g.last_margin
    );
    assert_eq!(g.judged, "samples only");
}

#[test]
fn val_passive_safety_violated_when_the_drift_window_reaches_the_closest_approach() {
    let n = (MU_EARTH_M3_S2 / 7.0e6_f64.powi(3)).sqrt();
    let (x0, y0) = (20.0, 30.0);
    let c = 1.5 * n * x0;
    let t_star = y0 / c;
    let (h, grid, t_c) = (600.0, 5.0, 100.0);
    // R such that the window [t, t + H] reaches range R at t = t_c.
    let r = (x0 * x0 + (c * (t_star - h - t_c)).powi(2)).sqrt();
    let (_, s) = run(sim_of(&orbit_scene(
        (x0, y0, 0.0, -c),
        &format!(
            r#"PassiveSafety(name: "ps", body: "chaser", around: "target", radius_m: Some({r}),
                 horizon_s: {h}, grid_s: {grid})"#
        ),
        150.0,
        false,
    )));
    let g = guarantee(&s, "ps");
    println!("R = {r} m: {g}");
    let tol = drift_tolerance(x0, y0, n, h, grid);
    let rate = c * (r * r - x0 * x0).sqrt() / r;
    let t = f(&g["first_violation_s"]);
    assert!(
        t <= t_c + 0.1 + 1e-9 && t >= t_c - tol / rate,
        "{t} vs {t_c} (−{})",
        tol / rate
    );
}

/// `active_from_range_m`: the same fly-by as above, required only from 40 m out. The chaser
/// starts at range √(20² + 30²) = 36.06 m: nothing is required, the margin is 40 − 36.06 m;
/// with the threshold at 30 m the closed-form margin of the fly-by applies again.
#[test]
fn val_passive_safety_applies_only_from_its_range() {
    let n = (MU_EARTH_M3_S2 / 7.0e6_f64.powi(3)).sqrt();
    let (x0, y0, r) = (20.0, 30.0, 5.0);
    let margin = |from: f64| {
        let sim = sim_of(&orbit_scene(
            (x0, y0, 0.0, -1.5 * n * x0),
            &format!(
                r#"PassiveSafety(name: "ps", body: "chaser", around: "target", radius_m: Some({r}),
                 horizon_s: 2000.0, grid_s: 5.0, active_from_range_m: Some({from}))"#
            ),
            1.0,
            false,
        ));
        sim.guarantees().status[0].last_margin
    };
    assert!((margin(40.0) - (40.0 - (x0 * x0 + y0 * y0).sqrt())).abs() < 1e-9);
    let m = margin(30.0);
    let tol = drift_tolerance(x0, y0, n, 2000.0, 5.0);
    assert!(m <= x0 - r && m >= x0 - r - tol, "{m}");
}

/// Advances an absolute ECI state [r; v] (m, m/s) from time t by h s: (state, t, h).
type Propagator<'a> = &'a dyn Fn(&[f64; 6], f64, f64) -> [f64; 6];

/// Closest approach of two thrust-free orbits from absolute ECI states, sampled every `step`
/// s over `horizon` s, with `next` advancing one state by one step (the test's own reference).
fn sampled_min_distance(
    mut b: [f64; 6],
    mut a: [f64; 6],
    horizon: f64,
    step: f64,
    next: Propagator,
) -> f64 {
    let d = |b: &[f64; 6], a: &[f64; 6]| {
        ((b[0] - a[0]).powi(2) + (b[1] - a[1]).powi(2) + (b[2] - a[2]).powi(2)).sqrt()
    };
    let n = (horizon / step).round() as usize;
    let mut min = d(&b, &a);
    for i in 0..n {
        b = next(&b, i as f64 * step, step);
        a = next(&a, i as f64 * step, step);
        min = min.min(d(&b, &a));
    }
    min
}

/// An eccentric, inclined reference (a = 7500 km, e = 0.1, i = 30°) and a chaser 60 m away on
/// a fly-by: the propagated drift's margin against the Kepler closed form (Battin's f and g
/// functions, `kepler_propagate`) sampled every 0.05 s. Sound: margin ≤ d_min − R (to 1e-6 m,
/// the closed form's rounding at 7500 km); tight: margin ≥ d_min − R − Δτ·(V + AΔτ/2)/2 − 1e-6,
/// the grid bound's own slack with V the largest relative speed (A·Δτ ≪ V here, counted as 1 %
/// of V).
#[test]
fn val_passive_safety_propagated_elliptic_against_kepler() {
    use rpod::guarantee::ReferenceView;
    use rpod::guarantee::requirements::{DriftSetup, Zone, propagate_drift};
    use rpod::orbit::kepler::{ClassicalElements, kepler_propagate};
    use rpod::orbit::lvlh::{LocalFrame, LocalFrameKind};
    let el = ClassicalElements {
        a_m: 7.5e6,
        e: 0.1,
        i_rad: 30f64.to_radians(),
        raan_rad: 0.4,
        argp_rad: 1.0,
        true_anomaly_rad: 0.3,
    };
    let (r_ref, v_ref) = el.to_state(MU_EARTH_M3_S2);
    let hill = LocalFrame::new(LocalFrameKind::Hill, &r_ref, &v_ref);
    // Target at the reference; chaser 20 m above, 60 m ahead, drifting back at 0.04 m/s.
    let (pc, vc) = hill.from_local(
        &nalgebra::Vector3::new(20.0, 60.0, 3.0),
        &nalgebra::Vector3::new(0.0, -0.04, 0.0),
    );
    let zero = nalgebra::Vector3::zeros();
    let (radius, horizon, k) = (5.0, 3000.0, 300usize);
    let found = propagate_drift(
        &DriftSetup {
            zone: Zone::Sphere(radius),
            gravity: rpod::orbit::gravity::TWO_BODY,
            horizon_s: horizon,
            intervals: k,
        },
        &ReferenceView {
            pos_eci_m: r_ref,
            vel_eci_m_s: v_ref,
        },
        (&pc, &vc),
        (&zero, &zero),
    );
    let abs = |p: nalgebra::Vector3<f64>, v: nalgebra::Vector3<f64>| {
        let (r, w) = (r_ref + p, v_ref + v);
        [r.x, r.y, r.z, w.x, w.y, w.z]
    };
    let kepler = |x: &[f64; 6], _t: f64, h: f64| {
        let (r, v) = kepler_propagate(
            &nalgebra::Vector3::new(x[0], x[1], x[2]),
            &nalgebra::Vector3::new(x[3], x[4], x[5]),
            h,
            MU_EARTH_M3_S2,
        );
        [r.x, r.y, r.z, v.x, v.y, v.z]
    };
    let d_min = sampled_min_distance(abs(pc, vc), abs(zero, zero), horizon, 0.05, &kepler);
    let want = d_min - radius;
    let slack = horizon / k as f64 * found.speed_bound_m_s * 1.01 / 2.0 + 1e-6;
    println!(
        "margin {} m, Kepler closest approach − R {want} m, slack {slack} m, error estimate {} m",
        found.margin_m, found.cw_error_m
    );
    assert!(found.margin_m <= want + 1e-6, "unsound: {found:?}");
    assert!(found.margin_m >= want - slack, "loose: {found:?}");
    assert!(found.cw_error_m < 1e-4, "{found:?}");
}

/// A kept drift reused 137.3 s later (between grid points), see the header.
#[test]
fn val_passive_safety_reused_drift_is_sound_after_a_coast_and_a_kick() {
    use rpod::guarantee::ReferenceView;
    use rpod::guarantee::requirements::{DriftSetup, Zone, propagate_drift_track};
    use rpod::orbit::kepler::{ClassicalElements, kepler_propagate};
    use rpod::orbit::lvlh::{LocalFrame, LocalFrameKind};
    let el = ClassicalElements {
        a_m: 7.5e6,
        e: 0.1,
        i_rad: 30f64.to_radians(),
        raan_rad: 0.4,
        argp_rad: 1.0,
        true_anomaly_rad: 0.3,
    };
    let (r_ref, v_ref) = el.to_state(MU_EARTH_M3_S2);
    let hill = LocalFrame::new(LocalFrameKind::Hill, &r_ref, &v_ref);
    let (pc, vc) = hill.from_local(
        &nalgebra::Vector3::new(20.0, 60.0, 3.0),
        &nalgebra::Vector3::new(0.0, -0.04, 0.0),
    );
    let zero = nalgebra::Vector3::zeros();
    let (radius, horizon, k, extra) = (5.0, 3000.0, 300usize, 30usize);
    let track = propagate_drift_track(
        &DriftSetup {
            zone: Zone::Sphere(radius),
            gravity: rpod::orbit::gravity::TWO_BODY,
            horizon_s: horizon,
            intervals: k,
        },
        &ReferenceView {
            pos_eci_m: r_ref,
            vel_eci_m_s: v_ref,
        },
        (&pc, &vc),
        (&zero, &zero),
        extra,
    );
    let kepler = |x: &[f64; 6], _t: f64, h: f64| {
        let (r, v) = kepler_propagate(
            &nalgebra::Vector3::new(x[0], x[1], x[2]),
            &nalgebra::Vector3::new(x[3], x[4], x[5]),
            h,
            MU_EARTH_M3_S2,
        );
        [r.x, r.y, r.z, v.x, v.y, v.z]
    };
    let v3 = |x: &[f64; 6], o: usize| nalgebra::Vector3::new(x[o], x[o + 1], x[o + 2]);
    let tau = 137.3;
    let body0 = [
        r_ref.x + pc.x,
        r_ref.y + pc.y,
        r_ref.z + pc.z,
        v_ref.x + vc.x,
        v_ref.y + vc.y,
        v_ref.z + vc.z,
    ];
    let around0 = [r_ref.x, r_ref.y, r_ref.z, v_ref.x, v_ref.y, v_ref.z];
    let (b1, a1) = (kepler(&body0, 0.0, tau), kepler(&around0, 0.0, tau));
    // Coast.
    let (m, dev) = track
        .reuse(
            tau,
            horizon,
            (&v3(&b1, 0), &v3(&b1, 3)),
            (&v3(&a1, 0), &v3(&a1, 3)),
        )
        .expect("reusable after a coast");
    let want = sampled_min_distance(b1, a1, horizon, 0.05, &kepler) - radius;
    let slack = horizon / k as f64 * track.window(0, k).speed_bound_m_s * 1.01 / 2.0 + 1e-6;
    println!("coast: reused {m} m (deviation bound {dev} m), Kepler {want} m, slack {slack} m");
    assert!(m <= want + 1e-6, "unsound after a coast: {m} vs {want}");
    assert!(
        m >= want - slack - dev,
        "loose after a coast: {m} vs {want}"
    );
    assert!(
        dev < 1e-2,
        "a coast's deviation bound is the integration allowance: {dev}"
    );
    // A 3 mm/s kick to the chaser.
    let mut kicked = b1;
    kicked[3] += 0.002;
    kicked[4] -= 0.002;
    kicked[5] += 0.001;
    let (mk, devk) = track
        .reuse(
            tau,
            horizon,
            (&v3(&kicked, 0), &v3(&kicked, 3)),
            (&v3(&a1, 0), &v3(&a1, 3)),
        )
        .expect("reusable after a small kick");
    let want_k = sampled_min_distance(kicked, a1, horizon, 0.05, &kepler) - radius;
    // The sampled deviation of the kicked drift from the unkicked one over the horizon.
    let (mut x, mut y, mut dmax) = (kicked, b1, 0.0f64);
    for i in 0..(horizon / 1.0) as usize {
        x = kepler(&x, i as f64, 1.0);
        y = kepler(&y, i as f64, 1.0);
        dmax = dmax.max((v3(&x, 0) - v3(&y, 0)).norm());
    }
    println!(
        "kick: reused {mk} m (deviation bound {devk} m, sampled deviation {dmax} m), Kepler {want_k} m"
    );
    assert!(
        mk <= want_k + 1e-6,
        "unsound after a kick: {mk} vs {want_k}"
    );
    assert!(
        devk >= dmax,
        "deviation bound {devk} below the sampled {dmax}"
    );
    // Beyond the kept window (30 intervals of 10 s) nothing is reused.
    assert!(
        track
            .reuse(
                301.0,
                horizon,
                (&v3(&b1, 0), &v3(&b1, 3)),
                (&v3(&a1, 0), &v3(&a1, 3))
            )
            .is_none()
    );
    // At τ = 0 with the initial states the window is the fresh evaluation.
    let (m0, d0) = track
        .reuse(
            0.0,
            horizon,
            (&v3(&body0, 0), &v3(&body0, 3)),
            (&v3(&around0, 0), &v3(&around0, 3)),
        )
        .expect("τ = 0");
    assert!((m0 + d0 - track.window(0, k).margin_m).abs() < 1e-12);
}

/// With J2: the same fly-by on a LEO reference (a = 7000 km, e = 0.001, i = 51.6°) against an
/// independent integration in this test (classic RK4 at 0.5 s of each body's absolute state
/// under μ/r² plus J2 written out here, from Vallado 2013 eq. 8-30), sampled every 0.5 s.
/// Bounds as above, with 1e-5 m for the RK4 reference's own error (its step halved changes
/// d_min by less than 1e-7 m).
#[test]
fn val_passive_safety_propagated_j2_against_an_independent_integration() {
    use rpod::guarantee::ReferenceView;
    use rpod::guarantee::requirements::{DriftSetup, Zone, propagate_drift};
    use rpod::orbit::kepler::ClassicalElements;
    use rpod::orbit::lvlh::{LocalFrame, LocalFrameKind};
    let el = ClassicalElements {
        a_m: 7.0e6,
        e: 0.001,
        i_rad: 51.6f64.to_radians(),
        raan_rad: 0.2,
        argp_rad: 0.5,
        true_anomaly_rad: 2.0,
    };
    let (r_ref, v_ref) = el.to_state(MU_EARTH_M3_S2);
    let hill = LocalFrame::new(LocalFrameKind::Hill, &r_ref, &v_ref);
    let (pc, vc) = hill.from_local(
        &nalgebra::Vector3::new(-15.0, 50.0, -4.0),
        &nalgebra::Vector3::new(0.0, -0.02, 0.004),
    );
    let zero = nalgebra::Vector3::zeros();
    let (radius, horizon, k) = (4.0, 2500.0, 250usize);
    let found = propagate_drift(
        &DriftSetup {
            zone: Zone::Sphere(radius),
            gravity: rpod::orbit::gravity::TWO_BODY_J2,
            horizon_s: horizon,
            intervals: k,
        },
        &ReferenceView {
            pos_eci_m: r_ref,
            vel_eci_m_s: v_ref,
        },
        (&pc, &vc),
        (&zero, &zero),
    );
    let abs = |p: nalgebra::Vector3<f64>, v: nalgebra::Vector3<f64>| {
        let (r, w) = (r_ref + p, v_ref + v);
        [r.x, r.y, r.z, w.x, w.y, w.z]
    };
    // Vallado (2013) eq. 8-30: the J2 acceleration, written independently of rpod's gravity.
    let accel = |x: &[f64; 6]| {
        let (mu, j2, re) = (3.986_004_418e14, 1.082_626_68e-3, 6_378_137.0);
        let r = (x[0] * x[0] + x[1] * x[1] + x[2] * x[2]).sqrt();
        let c = 1.5 * j2 * mu * re * re / r.powi(5);
        let zz = 5.0 * x[2] * x[2] / (r * r);
        [
            -mu * x[0] / r.powi(3) - c * x[0] * (1.0 - zz),
            -mu * x[1] / r.powi(3) - c * x[1] * (1.0 - zz),
            -mu * x[2] / r.powi(3) - c * x[2] * (3.0 - zz),
        ]
    };
    let deriv = |x: &[f64; 6]| {
        let a = accel(x);
        [x[3], x[4], x[5], a[0], a[1], a[2]]
    };
    let rk4 = |x: &[f64; 6], _t: f64, h: f64| {
        let add = |x: &[f64; 6], k: &[f64; 6], s: f64| {
            let mut y = *x;
            for i in 0..6 {
                y[i] += s * k[i];
            }
            y
        };
        let k1 = deriv(x);
        let k2 = deriv(&add(x, &k1, h / 2.0));
        let k3 = deriv(&add(x, &k2, h / 2.0));
        let k4 = deriv(&add(x, &k3, h));
        let mut y = *x;
        for i in 0..6 {
            y[i] += h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
        }
        y
    };
    let d_min = sampled_min_distance(abs(pc, vc), abs(zero, zero), horizon, 0.5, &rk4);
    let d_min_half = sampled_min_distance(abs(pc, vc), abs(zero, zero), horizon, 0.25, &rk4);
    println!("RK4 reference: d_min {d_min} m at 0.5 s, {d_min_half} m at 0.25 s");
    assert!((d_min - d_min_half).abs() < 1e-4, "reference not converged");
    let want = d_min.min(d_min_half) - radius;
    let slack = horizon / k as f64 * found.speed_bound_m_s * 1.01 / 2.0 + 1e-5;
    println!(
        "margin {} m, reference closest approach − R {want} m, slack {slack} m, error estimate {} m",
        found.margin_m, found.cw_error_m
    );
    assert!(found.margin_m <= want + 1e-5, "unsound: {found:?}");
    assert!(found.margin_m >= want - slack, "loose: {found:?}");
}

/// A J2 scene is now propagated, not refused: the fly-by above with J2 on. The CW straight-line
/// closest approach x₀ − R moves by at most the CW bound B (nonlinearity) plus the J2
/// differential acceleration's effect over the horizon, ½·G_J2·ρ_max·H² with G_J2 the J2
/// gradient bound at 7000 km ([`gravity_gradient_bound`] less its point-mass part).
#[test]
fn val_passive_safety_with_j2_in_a_scene() {
    use rpod::guarantee::requirements::gravity_gradient_bound;
    use rpod::orbit::gravity::{TWO_BODY, TWO_BODY_J2};
    let n = (MU_EARTH_M3_S2 / 7.0e6_f64.powi(3)).sqrt();
    let (x0, y0, r, h) = (20.0, 30.0, 5.0, 2000.0);
    let sim = sim_of(&orbit_scene(
        (x0, y0, 0.0, -1.5 * n * x0),
        &format!(
            r#"PassiveSafety(name: "ps", body: "chaser", around: "target", radius_m: Some({r}),
                 horizon_s: {h}, grid_s: 5.0)"#
        ),
        1.0,
        true,
    ));
    let g = &sim.guarantees().status[0];
    let rho_max = (x0 * x0 + (y0 - 1.5 * n * x0 * h).powi(2)).sqrt();
    let g_j2 = gravity_gradient_bound(7.0e6, TWO_BODY_J2) - gravity_gradient_bound(7.0e6, TWO_BODY);
    let j2_effect = 0.5 * g_j2 * rho_max * h * h;
    let tol = drift_tolerance(x0, y0, n, h, 5.0) + j2_effect;
    println!(
        "J2: margin {} m, CW closed form {} m, tolerance {tol} m (J2 part {j2_effect} m)",
        g.last_margin,
        x0 - r
    );
    assert!(
        (g.last_margin - (x0 - r)).abs() <= tol,
        "{} vs {}",
        g.last_margin,
        x0 - r
    );
    assert_eq!(g.judged, "samples only");
}

/// `eval_period_s: Some(P)`: the drift is evaluated every P s over H + P, so the window of
/// the violation test above reaches the closest approach up to P earlier: the first violation
/// lies in [t_c − P − tol/Ḋ, t_c + dt].
#[test]
fn val_passive_safety_with_an_evaluation_period() {
    let n = (MU_EARTH_M3_S2 / 7.0e6_f64.powi(3)).sqrt();
    let (x0, y0) = (20.0, 30.0);
    let c = 1.5 * n * x0;
    let t_star = y0 / c;
    let (h, grid, t_c, period) = (600.0, 5.0, 100.0, 10.0);
    let r = (x0 * x0 + (c * (t_star - h - t_c)).powi(2)).sqrt();
    let (_, s) = run(sim_of(&orbit_scene(
        (x0, y0, 0.0, -c),
        &format!(
            r#"PassiveSafety(name: "ps", body: "chaser", around: "target", radius_m: Some({r}),
                 horizon_s: {h}, grid_s: {grid}, eval_period_s: Some({period}))"#
        ),
        150.0,
        false,
    )));
    let g = guarantee(&s, "ps");
    let tol = drift_tolerance(x0, y0, n, h + period, grid);
    let rate = c * (r * r - x0 * x0).sqrt() / r;
    let t = f(&g["first_violation_s"]);
    println!("R = {r} m, P = {period} s: first violation {t} s, t_c = {t_c} s");
    assert!(
        t <= t_c + 0.1 + 1e-9 && t >= t_c - period - tol / rate,
        "{t} vs {t_c} (−{period} − {})",
        tol / rate
    );
}

#[test]
fn passive_safety_bad_periods_and_grids_are_located_errors() {
    for (extra, j2, field) in [
        (
            "eval_period_s: Some(-1.0)",
            false,
            "guarantees.ps.eval_period_s",
        ),
        (
            "eval_period_s: Some(700.0)",
            false,
            "guarantees.ps.eval_period_s",
        ),
        (
            "eval_period_s: Some(NaN)",
            false,
            "guarantees.ps.eval_period_s",
        ),
    ] {
        let e = load_scene_str(
            &orbit_scene(
                (20.0, 30.0, 0.0, 0.0),
                &format!(
                    r#"PassiveSafety(name: "ps", body: "chaser", around: "target", radius_m: Some(5.0),
                 horizon_s: 600.0, grid_s: 5.0, {extra})"#
                ),
                1.0,
                j2,
            ),
            "ps",
            &[],
        )
        .unwrap_err();
        println!("{e}");
        assert_eq!(e.field, field, "{e}");
        assert!(e.line > 0, "{e}");
    }
    // A propagated drift's grid interval is limited (its interval bound).
    let e = load_scene_str(
        &orbit_scene(
            (20.0, 30.0, 0.0, 0.0),
            r#"PassiveSafety(name: "ps", body: "chaser", around: "target", radius_m: Some(5.0),
                 horizon_s: 6000.0, grid_s: 100.0)"#,
            1.0,
            true,
        ),
        "ps",
        &[],
    )
    .unwrap_err();
    println!("{e}");
    assert_eq!(e.field, "guarantees.ps.grid_s", "{e}");
    assert!(e.message.contains("90"), "{e}");
    // Nor may a horizon make every evaluation integrate for seconds: 10⁶ s (11.6 days) on a
    // 90 s grid at 15.3 s sub-steps is 6.7·10⁴ of them.
    let e = load_scene_str(
        &orbit_scene(
            (20.0, 30.0, 0.0, 0.0),
            r#"PassiveSafety(name: "ps", body: "chaser", around: "target", radius_m: Some(5.0),
                 horizon_s: 1e6, grid_s: 90.0)"#,
            1.0,
            true,
        ),
        "ps",
        &[],
    )
    .unwrap_err();
    println!("{e}");
    assert_eq!(e.field, "guarantees.ps.horizon_s", "{e}");
    assert!(e.message.contains("shorten horizon_s"), "{e}");
}

const PANEL: &str = r#"Bus(name: "panel", shape: Box(size_m: (2.0, 0.4, 2.0)))"#;

const TARGET_WITH_PORT: &str = r#"(name: "tgt", role: Other, mass_kg: 1.0, inertia_kg_m2: (xx: 0.2, yy: 0.2, zz: 0.2),
               initial: (pos_m: (10.0, 0.0, 0.0)),
               parts: [Bus(name: "bus", shape: Box(size_m: (1.0, 1.0, 1.0)))],
               ports: [(name: "dock", pos_m: (-0.5, 0.0, 0.0), axis: (-1.0, 0.0, 0.0))])"#;

fn los_scene(panel_y0: f64, sensor_x: f64) -> String {
    format!(
        r#"Scene(name: "los", dt_s: 0.01, duration_s: 2.5, environment: FreeSpace,
           bodies: [{}, {TARGET_WITH_PORT}, {}],
           guarantees: [LineOfSight(name: "los", sensor_body: "cam", position_m: ({sensor_x}, 0.0, 0.0),
              boresight: (1.0, 0.0, 0.0), half_fov_deg: 30.0, range_m: 50.0,
              target: "tgt", port: "dock", standoff_m: 0.1)])"#,
        body("cam", BALL, (0.0, 0.0, 0.0), (0.0, 0.0, 0.0), ""),
        body("panel", PANEL, (5.0, panel_y0, 0.0), (0.0, 1.0, 0.0), ""),
    )
}

#[test]
fn val_line_of_sight_cut_by_a_panel_at_a_known_time() {
    let y0 = -1.205;
    let loaded = load_scene_str(&los_scene(y0, 0.2), "los", &[]).unwrap_or_else(|e| panic!("{e}"));
    let (_, s) = run(Simulation::new(&loaded).unwrap_or_else(|e| panic!("{e}")));
    let g = guarantee(&s, "los");
    println!("{g}");
    assert_eq!(g["judged"], "interval");
    assert_eq!(g["verdict"], "violated");
    // Never late; early by at most parry's GJK precision near contact (it reports touching
    // within GJK_REL_TOL ≈ 1.2e-3 of the ~1 m scale of the closest features: 1 mm, 1e-3 s at
    // 1 m/s), which counts as blocked.
    let (t, want) = (f(&g["first_violation_s"]), -0.2 - y0);
    assert!(t <= want + 1e-9 && want - t < 1e-3, "{t} vs {want}");
    assert!(f(&g["first_violation_tol_s"]) < 1e-6, "{g}");
    let worst = f(&g["worst_margin"]);
    assert!((worst + 0.2).abs() < 1e-3 * 0.2 + 1e-5, "{worst}");
    assert!((f(&g["worst_margin_t_s"]) - (-y0)).abs() < 0.01, "{g}");
    assert!(f(&g["last_margin"]) > 0.0, "clear again: {g}");
}

#[test]
fn line_of_sight_from_inside_a_part_is_a_located_error() {
    let loaded =
        load_scene_str(&los_scene(-1.205, 0.05), "los", &[]).unwrap_or_else(|e| panic!("{e}"));
    let e = Simulation::new(&loaded).err().expect("refused");
    println!("{e}");
    assert_eq!(e.field, "guarantees.los.position_m");
    assert!(e.message.contains("inside part `ball`"), "{e}");
    assert!(e.line > 0);
}

/// In the Hill frame: the chaser placed at Hill (3, −10, 0) m from the target at t = 0, an
/// ellipsoid (5, 20, 5) m: s = √(0.6² + 0.5²), margin (s − 1)·5 m exactly (to the rounding of
/// the Hill ↔ world conversions, 1e-9 m); judged on intervals with the Hill frame's rate bound.
#[test]
fn val_keep_out_ellipsoid_in_the_hill_frame() {
    let mut sim = sim_of(&orbit_scene(
        (3.0, -10.0, 0.0, 0.0),
        r#"KeepOutEllipsoid(name: "koz", body: "chaser", around: "target",
              semi_axes_m: (5.0, 20.0, 5.0), frame: Hill)"#,
        1.0,
        false,
    ));
    let want = ((0.6_f64.powi(2) + 0.5_f64.powi(2)).sqrt() - 1.0) * 5.0;
    let m0 = sim.guarantees().status[0].last_margin;
    assert!((m0 - want).abs() < 1e-9, "{m0} vs {want}");
    sim.step(10);
    let g = &sim.guarantees().status[0];
    assert_eq!(g.judged, "interval");
    assert_eq!(g.verdict, "violated");
}

#[test]
fn keep_out_ellipsoid_in_hill_needs_an_orbit() {
    let text = format!(
        r#"Scene(name: "req", dt_s: 0.01, duration_s: 1.0, environment: FreeSpace,
           bodies: [{}, {}],
           guarantees: [KeepOutEllipsoid(name: "koz", body: "chaser", around: "target",
              semi_axes_m: (5.0, 20.0, 5.0), frame: Hill)])"#,
        body("target", BALL, (0.0, 0.0, 0.0), (0.0, 0.0, 0.0), ""),
        body("chaser", BALL, (5.0, 0.0, 0.0), (0.0, 0.0, 0.0), ""),
    );
    let e = load_scene_str(&text, "req", &[]).unwrap_err();
    assert_eq!(e.field, "guarantees.koz.frame", "{e}");
    assert!(e.message.contains("orbit scene"), "{e}");
}

/// The Hill frame's rate bound over [t − dt, t + dt] holds along an orbit propagated with J2
/// (the scene's own RK8 reference, its exact frame rate |r×v|/r² + the J2 normal term from
/// `frame_rate_eci_exact_rad_s`), sampled every dt/50, for a LEO orbit (e = 0.01) and steps up
/// to 100 s (the scene maximum; there the bound declines).
#[test]
fn hill_rate_bound_holds_along_a_j2_orbit() {
    use rpod::orbit::integrate::ReferenceOrbit;
    use rpod::orbit::kepler::ClassicalElements;
    use rpod::orbit::lvlh::{frame_rate_eci_exact_rad_s, hill_rate_bound_rad_s};
    let el = ClassicalElements {
        a_m: 7_178_000.0,
        e: 0.01,
        i_rad: 30f64.to_radians(),
        raan_rad: 0.0,
        argp_rad: 0.0,
        true_anomaly_rad: 1.0,
    };
    for dt in [0.01, 1.0, 10.0, 100.0] {
        let orbit = ReferenceOrbit::from_elements(&el, rpod::orbit::gravity::TWO_BODY_J2);
        let (r, v) = orbit.state();
        let Some(bound) = hill_rate_bound_rad_s(&r, &v, dt, rpod::orbit::gravity::TWO_BODY_J2)
        else {
            // |v|·dt + g·dt² ≈ 860 km at 100 s: the bound cannot keep |r| above the Earth's
            // radius, so it gives none (the guarantee is then judged at samples only).
            assert_eq!(dt, 100.0);
            println!("dt {dt} s: no bound");
            continue;
        };
        let mut worst: f64 = 0.0;
        for k in -50..=50 {
            let mut o = orbit.clone();
            o.step(dt * k as f64 / 50.0);
            let (rk, vk) = o.state();
            worst = worst.max(frame_rate_eci_exact_rad_s(&rk, &vk, &o.accel_eci_m_s2()).norm());
        }
        println!(
            "dt {dt} s: bound {bound:e} rad/s, largest sampled rate {worst:e} (ratio {})",
            bound / worst
        );
        assert!(worst <= bound, "{worst} > {bound}");
    }
}
