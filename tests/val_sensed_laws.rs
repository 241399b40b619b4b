//! Laws fly on what they sense (docs/navigation.md): a generic law with a sensor reads the measured
//! relative state, and a sensor a law cannot use is a located error.
//!
//! References: the same law and scene flown on the truth. An ideal sensor (no noise, no
//! latency, velocity measured exactly, sampled every step) delivers the truth's Hill state, so
//! its run must match the truth-fed run to the rounding of the Hill ↔ world round trip the
//! measured path takes (1e-12 relative per step, amplified by at most the closed loop's
//! growth over 60 s: 1e-6 m is six orders above it and five below the noise's effect). A
//! sensor with 0.5 m noise drives the PD (ω = 0.05 rad/s: a 0.5 m error is a 1.25 mm/s²
//! command) away from the truth-fed path by far more than 1 mm within 60 s.

use rpod::sim::Simulation;

const TARGET_ATTITUDE: &str = r#"Attitude(body: "target", period_s: 0.1,
    actuator: Saturated(max_force_n: (0.0, 0.0, 0.0), max_torque_nm: (1.0, 1.0, 1.0)),
    params: (mode: Lvlh(attitude: EulerZyxDeg(yaw: -90.0, pitch: 0.0, roll: 0.0)),
    natural_frequency_rad_s: 0.1, damping_ratio: 1.0))"#;

fn hill_pd(sensor: &str, point: &str) -> String {
    format!(
        r#"HillPd(body: "chaser", target: "target", period_s: 0.1, {sensor}
        actuator: Saturated(max_force_n: (5.0, 5.0, 5.0), max_torque_nm: (0.0, 0.0, 0.0)),
        params: (hold_m: (0.0, -60.0, 0.0), point: {point},
        gains: Pd(natural_frequency_rad_s: 0.05, damping_ratio: 1.0)))"#
    )
}

fn final_chaser(controllers: &str) -> nalgebra::Vector3<f64> {
    let mut sim = Simulation::from_file(
        "scenes/examples/orbit_approach_latch.ron",
        &[
            "duration_s=60.0".to_string(),
            format!("controllers=[{controllers}]"),
        ],
    )
    .unwrap_or_else(|e| panic!("{e}"));
    sim.run_for(60.0);
    sim.body("chaser").expect("chaser").pos_m
}

#[test]
fn a_noisy_sensor_changes_a_generic_laws_trajectory_and_an_ideal_one_does_not() {
    let truth = final_chaser(&format!(
        "{TARGET_ATTITUDE}, {}",
        hill_pd("", "CentreOfMass")
    ));
    let ideal = final_chaser(&format!(
        "{TARGET_ATTITUDE}, {}",
        hill_pd(
            "sensor: Some((frame: Hill, period_s: 0.01, velocity: Ideal)),",
            "CentreOfMass"
        )
    ));
    let noisy = final_chaser(&format!(
        "{TARGET_ATTITUDE}, {}",
        hill_pd(
            "sensor: Some((frame: Hill, period_s: 0.1, latency_s: 1.0, position_noise_m: 0.5, velocity_filter_s: 2.0, seed: 7)),",
            "CentreOfMass"
        )
    ));
    let (d_ideal, d_noisy) = ((ideal - truth).norm(), (noisy - truth).norm());
    println!("ideal sensor vs truth: {d_ideal:e} m; noisy sensor vs truth: {d_noisy} m");
    assert!(d_ideal < 1e-6, "{d_ideal}");
    assert!(d_noisy > 1e-3, "{d_noisy}");
}

fn error(controllers: &str) -> rpod::scene::SceneError {
    Simulation::from_file(
        "scenes/examples/orbit_approach_latch.ron",
        &[format!("controllers=[{controllers}]")],
    )
    .err()
    .expect("refused")
}

#[test]
fn a_sensor_a_law_cannot_use_is_a_located_error() {
    let e = error(&TARGET_ATTITUDE.replace(
        "period_s: 0.1,",
        "period_s: 0.1, sensor: Some((period_s: 0.1)),",
    ));
    println!("{e}");
    assert_eq!(e.field, "controllers.0.sensor", "{e}");
    assert!(e.message.contains("`Attitude` cannot use a sensor"), "{e}");
    assert!(e.line > 0);
    // A port law reads a `Port` measurement, or a `Hill` one carried to the port by the true
    // lever arms (a navigation filter's estimate); a `TargetBody` one it cannot use.
    let e = error(&hill_pd(
        "sensor: Some((frame: TargetBody, period_s: 0.1)),",
        "Port",
    ));
    println!("{e}");
    assert_eq!(e.field, "controllers.0.sensor.frame", "{e}");
    assert!(e.message.contains("`Port`"), "{e}");
}
