//! Translational fidelity of the simulation in orbit.
//!
//! 1. `val_relative_motion_j2_600s`: the chaser's world-frame position (relative to the
//!    reference orbit) against an independent f64 integration (`tests/common`: `rk4`, `accel`) of both the
//!    reference orbit and the chaser's absolute orbit under two-body + J2 (RK4 at 10 ms; its own
//!    error over 600 s is below 1 µm), differenced at the end. Required: < 1 mm after 600 s.
//! 2. `val_cw_circular_300s`: circular orbit, no J2: the chaser follows the Clohessy–Wiltshire
//!    closed form (`tests/common::cw`) in the Hill frame within the linearisation error bound of
//!    `rpod::orbit::cw::cw_linearisation_error_bound` (Taylor remainder of the second-order
//!    gravity term through Duhamel's formula; validated in `orbit::cw` against nonlinear
//!    two-body integration), plus 1e-8 m for the simulation's own integration error (velocity
//!    Verlet, global error of order dt²·n²·ρ·t ≈ 1e-9 m here).

mod common;

use common::{cw, hill, rk4};
use nalgebra::Vector3;
use rpod::orbit::constants::MU_EARTH_M3_S2;

fn scene(e: f64, j2: bool, chaser_hill: [f64; 3], vel_hill: [f64; 3]) -> String {
    format!(
        r#"Scene(
    name: "orbit_fidelity", dt_s: 0.01, duration_s: 600.0,
    environment: Orbit(
        reference: Elements(a_m: 7178000.0, e: {e}, i_deg: 30.0, raan_deg: 10.0, argp_deg: 20.0, true_anomaly_deg: 30.0),
        j2: {j2}, gravity_gradient: true),
    bodies: [
        (name: "target", role: Target, mass_kg: 800.0, inertia_kg_m2: (xx: 620.0, yy: 910.0, zz: 1080.0),
         initial: (frame: Hill, pos_m: (0.0, 0.0, 0.0), rate_body_deg_s: (1.5, 0.4, -2.0)),
         parts: [Bus(name: "bus", shape: Box(size_m: (1.6, 1.5, 1.5)))]),
        (name: "chaser", role: Chaser, mass_kg: 300.0, inertia_kg_m2: (xx: 110.0, yy: 140.0, zz: 160.0),
         initial: (frame: Hill, pos_m: ({}, {}, {}), vel_m_s: ({}, {}, {})),
         parts: [Bus(name: "bus", shape: Box(size_m: (1.0, 1.0, 1.0)))]),
    ],
)"#,
        chaser_hill[0], chaser_hill[1], chaser_hill[2], vel_hill[0], vel_hill[1], vel_hill[2]
    )
}

#[test]
fn val_relative_motion_j2_600s() {
    let text = scene(0.01, true, [-8.0, -40.0, 3.0], [0.02, 0.012, -0.005]);
    let loaded = rpod::scene::load_scene_str(&text, "orbit_fidelity", &[]).unwrap();
    let mut sim = rpod::sim::Simulation::new(&loaded).unwrap();
    let (mut r_ref, mut v_ref) = sim.reference_state().unwrap();
    let c = sim.body("chaser").unwrap();
    let (mut r_c, mut v_c) = (r_ref + c.pos_m, v_ref + c.vel_m_s);
    let t0 = sim.body("target").unwrap();
    let (mut r_t, mut v_t) = (r_ref + t0.pos_m, v_ref + t0.vel_m_s);
    let mut worst: f64 = 0.0;
    for _ in 0..60 {
        sim.step(1000);
        for _ in 0..1000 {
            rk4(&mut r_ref, &mut v_ref, 0.01, true);
            rk4(&mut r_c, &mut v_c, 0.01, true);
            rk4(&mut r_t, &mut v_t, 0.01, true);
        }
        let want = r_c - r_ref;
        let got = sim.body("chaser").unwrap().pos_m;
        worst = worst.max((got - want).norm());
        let got_t = sim.body("target").unwrap().pos_m;
        worst = worst.max((got_t - (r_t - r_ref)).norm());
    }
    let got = sim.body("chaser").unwrap().pos_m;
    let err = (got - (r_c - r_ref)).norm();
    println!("chaser position error after 600 s: {err:e} m (worst over the run {worst:e} m)");
    assert!(err < 1e-3, "chaser position error {err} m after 600 s");
    assert!(worst < 1e-3, "worst position error over the run {worst} m");
}

#[test]
fn val_cw_circular_300s() {
    let x0 = Vector3::new(-8.0, -40.0, 3.0);
    let v0 = Vector3::new(0.02, 0.012, -0.005);
    let text = scene(0.0, false, x0.into(), v0.into());
    let loaded = rpod::scene::load_scene_str(&text, "cw", &[]).unwrap();
    let mut sim = rpod::sim::Simulation::new(&loaded).unwrap();
    let (r0, v_ref0) = sim.reference_state().unwrap();
    let n = (MU_EARTH_M3_S2 / r0.norm().powi(3)).sqrt();
    assert!((v_ref0.norm() - (MU_EARTH_M3_S2 / r0.norm()).sqrt()).abs() < 1e-6);
    let mut rho_max: f64 = x0.norm();
    let mut worst_ratio: f64 = 0.0;
    let mut worst_err: f64 = 0.0;
    for k in 1..=30 {
        sim.step(1000);
        let t = 10.0 * k as f64;
        let (r, v) = sim.reference_state().unwrap();
        let c = sim.body("chaser").unwrap();
        let p = hill(&r, &v) * c.pos_m;
        // Between 10 s samples the separation can exceed the sampled values by ≤ |v|·5 s.
        rho_max = rho_max.max(p.norm() + c.vel_m_s.norm() * 5.0);
        let want = cw(&x0, &v0, n, t);
        let bound = rpod::orbit::cw::cw_linearisation_error_bound(rho_max, r0.norm(), n, t) + 1e-8;
        let err = (p - want).norm();
        worst_err = worst_err.max(err);
        worst_ratio = worst_ratio.max(err / bound);
        assert!(
            err <= bound,
            "t = {t} s: |sim − CW| = {err:e} m > bound {bound:e} m"
        );
    }
    println!("worst |sim − CW| = {worst_err:e} m, worst error/bound = {worst_ratio:.3}");
}
