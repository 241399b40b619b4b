//! `Rcs` actuator in a scene (docs/vehicles.md).
//!
//! Reference: the closed-form small slew of the `Attitude` law (critically damped,
//! θ(t) = θ₀(1 + ωt)e^{−ωt}, as in `val_generic_laws.rs`), now flown through twelve jets in
//! couples (two per torque sense per axis, 0.5 m lever arms): the allocation of a pure torque
//! is exact (couples exist for every axis and sense), so the slew follows the closed form to
//! the same bound, the couples give no net force (the centre of mass stays put to f64
//! rounding), and the propellant is the jets' total impulse over I_sp g₀. A jet with zero
//! thrust is a located error.

use rpod::scene::load_scene_str;
use rpod::sim::Simulation;

fn jets(max_thrust: f64) -> String {
    let mut s = String::new();
    let l = 0.5;
    // (position, direction) pairs of the six couples.
    let pairs = [
        ([l, 0.0, 0.0], [0.0, 1.0, 0.0]),
        ([-l, 0.0, 0.0], [0.0, -1.0, 0.0]),
        ([l, 0.0, 0.0], [0.0, -1.0, 0.0]),
        ([-l, 0.0, 0.0], [0.0, 1.0, 0.0]),
        ([0.0, l, 0.0], [0.0, 0.0, 1.0]),
        ([0.0, -l, 0.0], [0.0, 0.0, -1.0]),
        ([0.0, l, 0.0], [0.0, 0.0, -1.0]),
        ([0.0, -l, 0.0], [0.0, 0.0, 1.0]),
        ([0.0, 0.0, l], [1.0, 0.0, 0.0]),
        ([0.0, 0.0, -l], [-1.0, 0.0, 0.0]),
        ([0.0, 0.0, l], [-1.0, 0.0, 0.0]),
        ([0.0, 0.0, -l], [1.0, 0.0, 0.0]),
    ];
    for (k, (p, d)) in pairs.iter().enumerate() {
        s.push_str(&format!(
            "(name: \"j{k}\", pos_m: ({:?}, {:?}, {:?}), direction: ({:?}, {:?}, {:?}), max_thrust_n: {max_thrust:?}),\n",
            p[0], p[1], p[2], d[0], d[1], d[2]
        ));
    }
    s
}

fn scene(max_thrust: f64) -> String {
    format!(
        r#"Scene(name: "rcs", dt_s: 0.01, duration_s: 30.0, environment: FreeSpace,
        bodies: [(name: "sc", role: Chaser, mass_kg: 100.0, inertia_kg_m2: (xx: 10.0, yy: 20.0, zz: 30.0),
                  initial: (pos_m: (0.0, 0.0, 0.0), attitude: EulerZyxDeg(yaw: 1.0, pitch: 0.0, roll: 0.0)),
                  parts: [Bus(name: "bus", shape: Sphere(radius_m: 0.5))])],
        controllers: [Attitude(body: "sc", period_s: 0.02,
                      actuator: Rcs(isp_s: 220.0, jets: [{}]),
                      params: (mode: Inertial(attitude: EulerZyxDeg(yaw: 0.0, pitch: 0.0, roll: 0.0)),
                               natural_frequency_rad_s: 0.5, damping_ratio: 1.0))],
    )"#,
        jets(max_thrust)
    )
}

#[test]
fn val_rcs_couples_fly_the_attitude_closed_form() {
    let (w, th0) = (0.5, 1f64.to_radians());
    let loaded = load_scene_str(&scene(1.0), "rcs.ron", &[]).unwrap_or_else(|e| panic!("{e}"));
    let mut sim = Simulation::new(&loaded).unwrap();
    let mut worst = 0.0f64;
    for k in 1..=300 {
        sim.step(10);
        let t = k as f64 * 0.1;
        let (_, _, yaw) = sim.body("sc").unwrap().att.euler_angles();
        let want = th0 * (1.0 + w * t) * (-w * t).exp();
        worst = worst.max((yaw - want).abs());
    }
    // The bound of val_generic_laws' ideal-actuator slew.
    let tol = 0.02 * th0 * w / std::f64::consts::E + 2e-5 * th0;
    let a = &sim.controllers().slots[0].actuator;
    assert!(
        worst < tol,
        "{worst} vs {tol} {} {:?}",
        a.saturated_steps,
        a.jets
    );
    let s = sim.body("sc").unwrap();
    assert!(
        s.pos_m.norm() < 1e-9,
        "couples moved the centre of mass: {}",
        s.pos_m
    );
    let a = &sim.controllers().slots[0].actuator;
    assert_eq!(a.saturated_steps, 0);
    let impulse: f64 = a.jets.iter().map(|j| j.impulse_ns).sum();
    assert!(impulse > 0.0);
    let g0 = 9.80665;
    assert!((a.propellant_used_kg - impulse / (220.0 * g0)).abs() < 1e-12 * impulse);
    // Yaw is about z: only the z couples (j0–j3) fire.
    assert!(
        a.jets[4..].iter().all(|j| j.impulse_ns < 1e-9 * impulse),
        "{:?}",
        a.jets
    );
    let summary = sim.summary();
    assert_eq!(
        summary["controllers"][0]["jets"].as_array().unwrap().len(),
        12
    );
}

#[test]
fn regress_rcs_zero_thrust_is_a_located_error() {
    let e = match load_scene_str(&scene(0.0), "rcs.ron", &[]) {
        Err(e) => e,
        Ok(l) => match Simulation::new(&l) {
            Err(e) => e,
            Ok(_) => panic!("accepted"),
        },
    };
    assert!(e.field.ends_with("jets.0.max_thrust_n"), "{e}");
    assert!(e.line > 0 && e.message.contains("positive"), "{e}");
}
