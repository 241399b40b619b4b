//! Xu, Wen, Wei (2019) on the air-bearing twin, against independent references:
//!
//! - Ideal case vs an f64 integration written here: eq (16) evaluated with the crate's
//!   Bevy-free law at each step start (the ideal sensor) and eq (3) advanced exactly for the
//!   held force and torque — the pipeline (scene, table, sensor, actuation, f64 truth) must
//!   reproduce it to rounding until the first contact.
//! - Vision: without noise, the pose the controller receives equals the truth at the exposure
//!   instant k·0.04 s, delivered one latency later; with noise, the residual's standard
//!   deviation matches the scene's σ (χ² bounds on 2 × N samples).
//! - Thrusters: every applied wrench is a sum of 0.05 N nozzle forces (per body axis 0 or
//!   ±0.05 N, torque 0 or ±0.009 N·m), and the gas used equals Σ open nozzles · F/(I_sp g₀) · dt.
//! - Fig. 13 claims (the reproduction, both cases): the experiment lags in x and y; the radial
//!   distances stay positive during the free approach; the goal is reached within 1 cm and
//!   2°; the monitor reports the chaser's cone touching the obstacle prism (a collision the
//!   centre-of-mass constraint cannot see) — the claims.json entries carry these numbers.
//! - Variants: with the law kept active after the magnet the simulation case latches well
//!   inside 2° (the 2.03° of the default is the law switched off plus contact); with the
//!   obstacle body removed (the law keeping its obstacle parameters) the path is bit-identical
//!   to the real run until the first obstacle contact, which is what the contacts change.
//! - Determinism: the same scene gives bit-identical states.

use nalgebra::{Vector2, Vector3};
use rpod::actuation::thrusters::{G0_M_S2, ThrusterParams};
use rpod::control::xu2019::Xu2019Instance;
use rpod::control::xu2019::{Xu2019Observation, Xu2019Params, Xu2019Potential};
use rpod::reproduce::xu2019::{
    EXPERIMENT_SCENE, GOAL_ANGLE_TOL_DEG, GOAL_POS_TOL_M, SIMULATION_SCENE, claims, compute,
};
use rpod::scene::load_scene_str;
use rpod::sim::Simulation;

fn sim(text: &str) -> Simulation {
    let loaded = load_scene_str(text, "xu2019.ron", &[]).unwrap();
    Simulation::new(&loaded).unwrap()
}

#[test]
fn val_xu2019_ideal_case_matches_independent_integration() {
    let mut s = sim(SIMULATION_SCENE);
    let law = Xu2019Potential::new(Xu2019Params::paper());
    let (m, iz, dt) = (9.0, 0.05, 0.005);
    // State (x, y, θ, ẋ, ẏ, θ̇).
    let mut x = [0.809, 0.224, 7f64.to_radians(), 0.0, 0.0, 0.0];
    let n = 1000; // 5 s: before the first contact (the cone reaches the obstacle at 5.5 s)
    for _ in 0..n {
        let u = law.command(&Xu2019Observation {
            t_s: 0.0,
            pos_lab_m: Vector2::new(x[0], x[1]),
            theta_rad: x[2],
            vel_lab_m_s: Vector2::new(x[3], x[4]),
            omega_rad_s: x[5],
        });
        let a = [u.force_lab_n.x / m, u.force_lab_n.y / m, u.torque_nm / iz];
        for k in 0..3 {
            x[k] += x[k + 3] * dt + 0.5 * a[k] * dt * dt;
            x[k + 3] += a[k] * dt;
        }
    }
    s.step(n);
    let c = s.body("chaser").unwrap();
    let (ep, ea) = (
        (c.pos_m.xy() - Vector2::new(x[0], x[1])).norm(),
        (c.yaw_rad() - x[2]).abs(),
    );
    eprintln!("ideal vs independent after 5 s: |Δp| {ep:.2e} m, |Δθ| {ea:.2e} rad");
    assert!(ep < 1e-9 && ea < 1e-9, "{ep} m, {ea} rad");
    assert!(s.contacts().collisions.is_empty());
}

#[test]
fn val_xu2019_vision_latency_and_noise() {
    // No noise: the delivered pose is the truth at the exposure, one latency late.
    let text = EXPERIMENT_SCENE
        .replace("position_noise_m: 0.0005", "position_noise_m: 0.0")
        .replace("angle_noise_deg: 0.2", "angle_noise_deg: 0.0");
    let mut s = sim(&text);
    let mut truth: Vec<(f64, Vector3<f64>)> = Vec::new();
    let c = s.body("chaser").unwrap();
    truth.push((0.0, Vector3::new(c.pos_m.x, c.pos_m.y, c.yaw_rad())));
    let mut checked = 0;
    for _ in 0..1000 {
        s.step(1);
        let t = s.t_s();
        let obs = s.law::<Xu2019Instance>(0).unwrap().observation;
        if let Some(o) = obs {
            // The sensor ran at the start of the step (t − dt): the exposure is the latest
            // k·0.04 s ≤ t − dt − 0.04 s.
            let te = ((t - 0.005 - 0.04) / 0.04 + 1e-9).floor() * 0.04;
            assert!(
                (o.t_s - te).abs() < 1e-9,
                "exposure {} vs {te} at t = {t}",
                o.t_s
            );
            let (_, p) = truth
                .iter()
                .find(|(tt, _)| (tt - te).abs() < 1e-9)
                .expect("truth at exposure");
            assert!((o.pos_lab_m.x - p.x).abs() < 1e-15 && (o.pos_lab_m.y - p.y).abs() < 1e-15);
            assert!((o.theta_rad - p.z).abs() < 1e-15);
            checked += 1;
        }
        let c = s.body("chaser").unwrap();
        truth.push((t, Vector3::new(c.pos_m.x, c.pos_m.y, c.yaw_rad())));
    }
    assert!(checked > 900);
    // Noise: residuals against the truth at the exposure instants.
    let mut s = sim(EXPERIMENT_SCENE
        .replace("latency_s: 0.04", "latency_s: 0.0")
        .as_str());
    let mut res = Vec::new();
    let mut last_t = -1.0;
    for _ in 0..4000 {
        let c = s.body("chaser").unwrap();
        let p = c.pos_m.xy();
        s.step(1);
        let o = s.law::<Xu2019Instance>(0).unwrap().observation;
        if let Some(o) = o
            && o.t_s != last_t
        {
            last_t = o.t_s;
            res.push(o.pos_lab_m.x - p.x);
            res.push(o.pos_lab_m.y - p.y);
        }
    }
    let n = res.len() as f64;
    let sd = (res.iter().map(|r| r * r).sum::<f64>() / n).sqrt();
    eprintln!(
        "vision noise: {} samples, sd {sd:.3e} m (scene 5e-4 m)",
        res.len()
    );
    // χ²: sd within ±5 standard errors (σ/√(2N)).
    assert!((sd - 5e-4).abs() < 5.0 * 5e-4 / (2.0 * n).sqrt());
}

#[test]
fn val_xu2019_thruster_wrench_and_gas() {
    let text = EXPERIMENT_SCENE.replace("thrust_noise: 0.05", "thrust_noise: 0.0");
    let mut s = sim(&text);
    let tp = ThrusterParams::paper();
    let dt = 0.005;
    let mut gas = 0.0;
    let mut open_steps = 0usize;
    for _ in 0..4000 {
        // The nozzle forces are body-fixed, rotated by the attitude at the step start.
        let att = s.body("chaser").unwrap().att;
        s.step(1);
        let c = s.law::<Xu2019Instance>(0).unwrap().clone();
        let fb = att.inverse() * Vector3::new(c.applied.x, c.applied.y, 0.0);
        for f in [fb.x, fb.y] {
            assert!(
                f.abs() < 1e-12 || (f.abs() - 0.05).abs() < 1e-12,
                "body-axis force {f} N is not 0 or ±0.05 N"
            );
        }
        assert!(c.applied.z.abs() < 1e-15 || (c.applied.z.abs() - 0.009).abs() < 1e-15);
        let open = c.valves.iter().filter(|v| **v).count();
        open_steps += open;
        gas += open as f64 * tp.thrust_per_nozzle_n / (tp.isp_s * G0_M_S2) * dt;
        assert!((c.gas_used_kg - gas).abs() <= 1e-12 * gas.max(1e-12));
    }
    eprintln!(
        "20 s of valves: {open_steps} nozzle-steps, gas {:.3} g",
        gas * 1e3
    );
    assert!(open_steps > 0);
}

#[test]
fn val_xu2019_fig13_claims() {
    let r = compute(None).unwrap();
    let cl = claims(&r);
    rpod::report::claims::validate_claims(&cl).unwrap();
    let held = |id: &str| cl.iter().find(|c| c.id == id).expect(id).held;
    for c in &cl {
        eprintln!("[{}] {}: {}", c.held, c.id, c.measured);
    }
    // The paper's lag claim holds on the twin.
    assert!(held("experiment-lags-in-x-and-y"));
    // The 2° goal tolerance is ours. With rapier's rigid cone–slot contact the simulation case
    // failed it (2.03°) when the law is switched off at the magnet; with the compliant contact
    // (e = 0.3) the cone seats at 0.11°. Kept active, it latches inside 0.5° either way.
    assert!(held("simulation-reaches-goal-and-latches"));
    assert!(r.simulation.final_angle_err_deg < 2.0);
    assert!(held("simulation-law-kept-active-reaches-goal-and-latches"));
    assert!(r.simulation_active.final_angle_err_deg < 0.5);
    assert!(
        r.simulation.final_angle_err_deg < 3.0,
        "within the latch's own tolerance"
    );
    for c in &cl {
        assert!(
            c.threshold_source.starts_with("paper: ") || c.threshold_source.starts_with("ours: ")
        );
    }
    // Ghost obstacle: identical until the first obstacle contact of the real run, and the
    // approach without the prism latches.
    for (run, _, ghost) in r.variants() {
        let t_hit = run.obstacle_collisions.first().expect("contact").0;
        let (before, after) = rpod::reproduce::xu2019::path_deviation_m(run, ghost, t_hit);
        eprintln!(
            "{}: ghost vs real before {t_hit:.2} s: {before:.1e} m, after: {after:.3} m",
            run.name
        );
        assert_eq!(before, 0.0);
        assert!(after > 1e-3);
        assert!(ghost.obstacle_collisions.is_empty());
        assert!(held(&format!(
            "{}-ghost-obstacle-reaches-goal-and-latches",
            run.name
        )));
    }
    for run in [&r.simulation, &r.experiment] {
        // During the free approach (before the magnet takes over) the radial distances stay
        // positive, in both forms.
        let n = run.approach_end() + 1;
        assert!(
            run.magnet_on_s.is_some(),
            "{}: the approach reaches the magnet",
            run.name
        );
        let min = |v: &[f64]| v[..n].iter().copied().fold(f64::INFINITY, f64::min);
        assert!(min(&run.radial_obstacle_eq8_m) > 0.0);
        assert!(min(&run.radial_obstacle_exact_m) > 0.0);
        assert!(min(&run.radial_heart_m) > 0.0);
        assert!(held(&format!("{}-radial-distances-positive", run.name)));
        // The goal is reached within the claim's tolerances.
        let t = run.first_at_goal_s.expect("reaches the goal");
        eprintln!(
            "{}: within {GOAL_POS_TOL_M} m & {GOAL_ANGLE_TOL_DEG}° at {t:.1} s",
            run.name
        );
        // The finding: the centre of mass clears the obstacle, the cone does not. The claim
        // says so with the parts named.
        let first = run
            .obstacle_collisions
            .first()
            .expect("the monitor sees it");
        assert!(first.1.contains("chaser/cone") || first.2.contains("chaser/cone"));
        assert!(!held(&format!("{}-no-obstacle-collision", run.name)));
    }
}

#[test]
fn regress_xu2019_deterministic() {
    let run = || {
        let mut s = sim(EXPERIMENT_SCENE);
        s.step(3000);
        let c = s.body("chaser").unwrap();
        (c.pos_m, c.vel_m_s, c.att, c.omega_rad_s)
    };
    assert_eq!(run(), run());
}
