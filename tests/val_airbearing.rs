//! The air-bearing table (`Environment::AirBearing`, `src/sim/airbearing.rs`) against closed
//! forms, computed here:
//!
//! - Tilt: a free puck on a table tilted by α accelerates at g·sin α along the downhill axis:
//!   x(t) = x₀ + ½ g sin α t² (the f64 step with a held force is exact for a constant force, so
//!   the match is to rounding).
//! - Coulomb friction: a puck sliding at v₀ on a level table with friction μ stops after
//!   v₀²/(2 μ g) in v₀/(μ g) and stays at rest (the stick rule ends the last step exactly at
//!   rest: the discrete distance differs from the closed form by less than μ g dt²).
//! - Viscous drag: v(t) = v₀ e^{−c t/m} (held-force step: first-order, relative error < c·dt/m).
//! - The planar locks: height, roll and pitch stay at their t = 0 values whatever the initial
//!   vertical velocity, and the yaw advances by ω·t.
//! - A puck leaving the table raises `off_table` at the time its centre of mass crosses the
//!   edge (x₀ + v t = edge), and then falls.

use rpod::scene::load_scene_str;
use rpod::sim::Simulation;

const G: f64 = 9.81;

fn puck_scene(env: &str, vel: [f64; 3], rate_deg_s: f64) -> String {
    format!(
        r#"Scene(
    name: "puck", dt_s: 0.01, duration_s: 20.0,
    environment: AirBearing((table_size_m: (2.0, 2.5), {env})),
    bodies: [(
        name: "puck", role: Chaser, mass_kg: 9.0,
        inertia_kg_m2: (xx: 0.04, yy: 0.04, zz: 0.05),
        initial: (pos_m: (0.5, 0.6, 0.06), vel_m_s: ({}, {}, {}),
                  attitude: EulerZyxDeg(yaw: 30.0, pitch: 0.0, roll: 0.0),
                  rate_body_deg_s: (0.0, 0.0, {rate_deg_s})),
        parts: [Bus(name: "bus", shape: Cylinder(radius_m: 0.1, length_m: 0.1, axis: PlusZ))],
    )],
)"#,
        vel[0], vel[1], vel[2]
    )
}

fn sim(text: &str) -> Simulation {
    let loaded = load_scene_str(text, "puck.ron", &[]).unwrap();
    Simulation::new(&loaded).unwrap()
}

#[test]
fn val_airbearing_tilt_accelerates_at_g_sin_alpha() {
    for (ax, ay) in [(0.01, 0.0), (0.0, 0.02), (0.01, -0.015)] {
        let mut s = sim(&puck_scene(
            &format!("tilt_deg: ({ax}, {ay})"),
            [0.0; 3],
            0.0,
        ));
        s.step(1000);
        let t = s.t_s();
        let (a, b) = (f64::to_radians(ax), f64::to_radians(ay));
        let acc = [G * a.sin() * b.cos(), G * b.sin()];
        let p = s.body("puck").unwrap();
        let ex = 0.5 + 0.5 * acc[0] * t * t;
        let ey = 0.6 + 0.5 * acc[1] * t * t;
        eprintln!(
            "tilt ({ax}°, {ay}°): a = ({:.4e}, {:.4e}) m/s²; after {t} s x err {:.2e} m, y err {:.2e} m",
            acc[0],
            acc[1],
            p.pos_m.x - ex,
            p.pos_m.y - ey
        );
        assert!((p.pos_m.x - ex).abs() < 1e-12 && (p.pos_m.y - ey).abs() < 1e-12);
        assert!((p.vel_m_s.x - acc[0] * t).abs() < 1e-13);
        assert!((p.vel_m_s.y - acc[1] * t).abs() < 1e-13);
        assert_eq!(p.pos_m.z, 0.06, "height held by the air film");
    }
}

#[test]
fn val_airbearing_coulomb_friction_stopping_distance() {
    let mu = 0.001;
    let v0 = 0.1;
    let dir = [0.6, 0.8];
    let mut s = sim(&puck_scene(
        &format!("coulomb_friction: {mu}"),
        [v0 * dir[0], v0 * dir[1], 0.0],
        0.0,
    ));
    let d_exact = v0 * v0 / (2.0 * mu * G);
    let t_stop = v0 / (mu * G);
    let mut t_rest = None;
    for _ in 0..1500 {
        s.step(1);
        let p = s.body("puck").unwrap();
        if t_rest.is_none() && p.vel_m_s.norm() == 0.0 {
            t_rest = Some(s.t_s());
        }
    }
    let p = s.body("puck").unwrap();
    let d = ((p.pos_m.x - 0.5).powi(2) + (p.pos_m.y - 0.6).powi(2)).sqrt();
    let dt = 0.01;
    eprintln!(
        "Coulomb μ = {mu}: distance {d:.7} m vs v0²/(2μg) = {d_exact:.7} m; at rest at {:?} s vs {t_stop:.3} s",
        t_rest
    );
    assert!((d - d_exact).abs() < mu * G * dt * dt, "{d} vs {d_exact}");
    let tr = t_rest.expect("came to rest");
    assert!((tr - t_stop).abs() <= dt + 1e-9);
    assert_eq!(p.vel_m_s.norm(), 0.0, "stays at rest (stick)");
    // Direction kept: the friction acts along −v only.
    assert!(((p.pos_m.y - 0.6) / (p.pos_m.x - 0.5) - dir[1] / dir[0]).abs() < 1e-9);
}

#[test]
fn val_airbearing_friction_holds_on_a_shallow_tilt() {
    // μ g > g sin α: a puck at rest stays at rest.
    let mut s = sim(&puck_scene(
        "tilt_deg: (0.01, 0.0), coulomb_friction: 0.001",
        [0.0; 3],
        0.0,
    ));
    s.step(500);
    let p = s.body("puck").unwrap();
    assert_eq!((p.pos_m.x, p.pos_m.y), (0.5, 0.6));
    // μ g < g sin α: it slides at g (sin α − μ cos α).
    let mut s = sim(&puck_scene(
        "tilt_deg: (0.02, 0.0), coulomb_friction: 0.0001",
        [0.0; 3],
        0.0,
    ));
    s.step(1000);
    let a = G * (0.02f64.to_radians().sin() - 1e-4 * 0.02f64.to_radians().cos());
    let p = s.body("puck").unwrap();
    let t = s.t_s();
    assert!((p.pos_m.x - 0.5 - 0.5 * a * t * t).abs() < 1e-12);
}

#[test]
fn val_airbearing_viscous_drag_decay() {
    let c = 0.9;
    let mut s = sim(&puck_scene(
        &format!("viscous_drag_n_s_m: {c}, viscous_drag_nm_s_rad: 0.005"),
        [0.05, 0.0, 0.0],
        10.0,
    ));
    s.step(1000);
    let p = s.body("puck").unwrap();
    let v = 0.05 * (-c * 10.0 / 9.0f64).exp();
    let w = 10f64.to_radians() * (-0.005 * 10.0 / 0.05f64).exp();
    let (ev, ew) = ((p.vel_m_s.x - v) / v, (p.omega_rad_s.z - w) / w);
    eprintln!("viscous: v rel err {ev:.2e}, ω rel err {ew:.2e}");
    assert!(ev.abs() < c * 0.01 / 9.0 && ew.abs() < 0.005 * 0.01 / 0.05);
}

#[test]
fn val_airbearing_planar_locks() {
    // An initial vertical velocity and a yaw rate: the air film holds the height, the locks
    // hold roll and pitch, the yaw advances at the initial rate.
    let mut s = sim(&puck_scene("", [0.01, 0.0, 0.3], 20.0));
    s.step(500);
    let p = s.body("puck").unwrap();
    assert_eq!(p.pos_m.z, 0.06);
    assert_eq!(p.vel_m_s.z, 0.0);
    let (roll, pitch, yaw) = p.att.euler_angles();
    let expect = (30.0 + 20.0 * s.t_s()).to_radians();
    let dyaw = (yaw - expect + std::f64::consts::PI).rem_euclid(2.0 * std::f64::consts::PI)
        - std::f64::consts::PI;
    eprintln!("locks: roll {roll:.1e} pitch {pitch:.1e} yaw err {dyaw:.1e} rad");
    assert!(roll.abs() < 1e-12 && pitch.abs() < 1e-12 && dyaw.abs() < 1e-9);
    assert!((p.pos_m.x - 0.5 - 0.01 * s.t_s()).abs() < 1e-12);
}

#[test]
fn val_airbearing_off_table_event() {
    // Towards +x at 0.5 m/s from x = 0.5 m: the edge (x = 2 m) at t = 3 s.
    let mut s = sim(&puck_scene("", [0.5, 0.0, 0.0], 0.0));
    s.step(400);
    let ev: Vec<_> = s
        .events()
        .into_iter()
        .filter(|e| e.kind == "off_table")
        .collect();
    assert_eq!(ev.len(), 1, "one off_table event");
    assert!((ev[0].t_s - 3.0).abs() <= 0.01 + 1e-9, "at {}", ev[0].t_s);
    let p = s.body("puck").unwrap();
    assert!(
        p.pos_m.z < 0.06 - 0.5 * G * 0.9 * 0.9,
        "falls after leaving: z = {}",
        p.pos_m.z
    );
}

#[test]
fn regress_airbearing_bad_table_input_is_located() {
    let text = puck_scene("tilt_deg: (60.0, 0.0)", [0.0; 3], 0.0);
    let e = load_scene_str(&text, "puck.ron", &[])
        .unwrap_err()
        .to_string();
    assert!(e.contains("tilt_deg") && e.contains("puck.ron:"), "{e}");
    let text = puck_scene("anchored: [\"nobody\"]", [0.0; 3], 0.0);
    let e = load_scene_str(&text, "puck.ron", &[])
        .unwrap_err()
        .to_string();
    assert!(e.contains("anchored") && e.contains("nobody"), "{e}");
    // Starting off the table.
    let text = puck_scene("table_corner_m: (1.0, 1.0)", [0.0; 3], 0.0);
    let loaded = load_scene_str(&text, "puck.ron", &[]).unwrap();
    let e = Simulation::new(&loaded)
        .err()
        .expect("off the table")
        .to_string();
    assert!(e.contains("off the table"), "{e}");
}
