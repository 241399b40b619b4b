//! `rpod bench`: steps/s of a scene through the whole pipeline, against the floor measured in
//! the same run — the bare rapier step of the same bodies and colliders, and one bare parry
//! distance query per body pair (the least any exact full-geometry monitor must do) — and the
//! swarm table: N tumbling winged spacecraft in orbit ([`swarm_scene`]), pipeline against bare
//! rapier, and the exact queries per step, for N = 2 … 256; and the cliffs ([`run_cliffs`]):
//! the cases that used to run 5–50× slower than their plain scene, as ratios to it measured in
//! the same run; and the costs of mesh parts and requirements ([`meshes::run_meshes`]).

pub mod meshes;

use crate::scene::{LoadedScene, SceneError, load_scene_file, load_scene_str};
use crate::sim::{Physics, Simulation};
use std::fmt::Write;
use std::path::Path;
use std::time::Instant;

/// One scene measured: wall seconds for `steps` steps of each.
#[derive(Debug, Clone)]
pub struct Measure {
    /// Scene name.
    pub name: String,
    /// Bodies.
    pub bodies: usize,
    /// Steps timed.
    pub steps: u64,
    /// Step, s.
    pub dt_s: f64,
    /// The whole pipeline (no file output: that is I/O, not simulation), s.
    pub pipeline_s: f64,
    /// rapier alone on the same world, s.
    pub rapier_s: f64,
    /// One parry query per tracked body pair at the closest parts, s.
    pub parry_s: f64,
    /// Queries in the parry floor per step.
    pub parry_queries: usize,
    /// Exact parry calls per step made by the monitor (distances, interval searches, swept tests).
    pub exact_per_step: f64,
    /// Fraction of steps in which rapier did not step.
    pub rapier_skipped: f64,
}

/// Measures a loaded scene.
pub fn measure(loaded: &LoadedScene, steps: u64) -> Result<Measure, SceneError> {
    measure_within(loaded, steps / 10, steps, f64::INFINITY)
}

/// Measures a loaded scene over `steps` steps after `warm_up` untimed ones, or over fewer when
/// the pipeline's steps exceed `budget_s` of wall time (then stepped in chunks of a hundredth
/// of `steps` and stopped at the first chunk past the budget; the floors are measured over the
/// steps actually taken, [`Measure::steps`]).
pub fn measure_within(
    loaded: &LoadedScene,
    warm_up: u64,
    steps: u64,
    budget_s: f64,
) -> Result<Measure, SceneError> {
    // 1. The whole pipeline.
    let mut sim = Simulation::new(loaded)?;
    sim.step(warm_up);
    let before = sim.summary();
    let t0 = Instant::now();
    let steps = if budget_s.is_finite() {
        let chunk = (steps / 100).max(1);
        let mut done = 0;
        while done < steps && (done == 0 || t0.elapsed().as_secs_f64() < budget_s) {
            let n = chunk.min(steps - done);
            sim.step(n);
            done += n;
        }
        done
    } else {
        sim.step(steps);
        steps
    };
    let pipeline_s = t0.elapsed().as_secs_f64();
    let after = sim.summary();
    let count = |s: &serde_json::Value| {
        let m = &s["monitor"];
        [
            "exact_queries",
            "guarantee_interval_queries",
            "swept_test_queries",
        ]
        .iter()
        .map(|k| m[*k].as_u64().unwrap_or(0))
        .sum::<u64>()
    };
    let exact_per_step = (count(&after) - count(&before)) as f64 / steps as f64;
    let skipped =
        |s: &serde_json::Value| s["monitor"]["rapier_skipped_steps"].as_u64().unwrap_or(0);
    let rapier_skipped = (skipped(&after) - skipped(&before)) as f64 / steps as f64;

    // 2. Bare rapier: the same world, stepped alone.
    let fresh = Simulation::new(loaded)?;
    let mut world = {
        let mut app = fresh.app;
        app.world_mut()
            .remove_resource::<Physics>()
            .expect("physics")
            .world
    };
    for _ in 0..warm_up {
        world.step();
    }
    let t0 = Instant::now();
    for _ in 0..steps {
        world.step();
    }
    let rapier_s = t0.elapsed().as_secs_f64();

    // 3. Bare parry: the closest part pair of each tracked body pair, at the end of run 1.
    let mon = sim.monitor().clone();
    let parts = crate::sim::bench_support::closest_pair_shapes(&mut sim, &mon);
    let t0 = Instant::now();
    let mut acc = 0.0;
    for _ in 0..steps {
        for (pa, a, pb, b) in &parts {
            acc += crate::sim::monitor::shape_distance(pa, &**a, pb, &**b);
        }
    }
    let parry_s = t0.elapsed().as_secs_f64();
    std::hint::black_box(acc);
    Ok(Measure {
        name: sim.scene.name.clone(),
        bodies: sim.scene.bodies.len(),
        steps,
        dt_s: sim.scene.dt_s,
        pipeline_s,
        rapier_s,
        parry_s,
        parry_queries: parts.len(),
        exact_per_step,
        rapier_skipped,
    })
}

/// Runs the benchmark and returns a printable report.
pub fn run(scene: &Path, steps: u64) -> Result<String, SceneError> {
    let loaded = load_scene_file(scene, &[])?;
    let m = measure(&loaded, steps.max(1000))?;
    let steps = m.steps;
    let per = |s: f64| s / steps as f64 * 1e6;
    let floor_s = m.rapier_s + m.parry_s;
    let mut r = String::new();
    let _ = writeln!(r, "scene {} ({} steps of {} s)", m.name, steps, m.dt_s);
    let _ = writeln!(
        r,
        "pipeline      {:>9.0} steps/s  {:>7.2} µs/step  ({:.0}× real time)",
        steps as f64 / m.pipeline_s,
        per(m.pipeline_s),
        m.dt_s * steps as f64 / m.pipeline_s
    );
    let _ = writeln!(
        r,
        "bare rapier   {:>9.0} steps/s  {:>7.2} µs/step",
        steps as f64 / m.rapier_s,
        per(m.rapier_s)
    );
    let _ = writeln!(
        r,
        "bare parry    {:>9.0} steps/s  {:>7.2} µs/step  ({} queries/step)",
        steps as f64 / m.parry_s,
        per(m.parry_s),
        m.parry_queries
    );
    let _ = writeln!(
        r,
        "ratio pipeline / (rapier + parry) = {:.2}   (pipeline / rapier = {:.2}); monitor made {:.2} exact queries/step; rapier skipped in {:.1} % of steps",
        m.pipeline_s / floor_s,
        m.pipeline_s / m.rapier_s,
        m.exact_per_step,
        100.0 * m.rapier_skipped
    );
    Ok(r)
}

/// RON text of a swarm of `n` tumbling spacecraft in a 7178 km orbit: a 1.5 m bus with two
/// three-panel solar wings each (9 colliders, extent about 5 m), on a cubic grid of 20 m
/// spacing (Hill frame) centred on the reference orbit, drifting at up to 5 mm/s and tumbling
/// at up to 3°/s, both from a fixed pseudo-random sequence of `seed`; a 1 m `MinDistance`
/// between the first two; the monitor's horizon at 5 m (grid neighbours are about 10 m apart,
/// so no pair is tracked but the named one).
pub fn swarm_scene(n: usize, seed: u64) -> String {
    let mut rng =
        crate::math::rng::Lcg(seed.wrapping_mul(2_862_933_555_777_941_757).wrapping_add(3));
    let side = (1..).find(|k: &usize| k * k * k >= n).unwrap_or(1);
    let mut bodies = Vec::new();
    for k in 0..n {
        let (ix, iy, iz) = (k % side, (k / side) % side, k / (side * side));
        let c = |i: usize| (i as f64 - (side as f64 - 1.0) / 2.0) * 20.0;
        let v = rng.vec3(0.005);
        let w = rng.vec3(3.0);
        let (yaw, pitch, roll) = (
            rng.symmetric() * 180.0,
            rng.symmetric() * 80.0,
            rng.symmetric() * 180.0,
        );
        bodies.push(format!(
            r#"(name: "sc{k}", role: Other, mass_kg: 500.0,
      inertia_kg_m2: (xx: 420.0, yy: 610.0, zz: 780.0),
      initial: (frame: Hill, pos_m: ({:.3}, {:.3}, {:.3}), vel_m_s: ({:.6}, {:.6}, {:.6}),
                attitude: EulerZyxDeg(yaw: {yaw:.3}, pitch: {pitch:.3}, roll: {roll:.3}),
                rate_body_deg_s: ({:.4}, {:.4}, {:.4})),
      parts: [
        Bus(name: "bus", shape: Box(size_m: (1.5, 1.5, 1.5))),
        SolarWing(name: "wing_py", root_m: (0.0, 0.75, 0.0), direction: PlusY, width_axis: PlusZ,
                  boom_length_m: 0.4, panel_count: 3, panel_size_m: (1.2, 1.0), panel_gap_m: 0.05),
        SolarWing(name: "wing_my", root_m: (0.0, -0.75, 0.0), direction: MinusY, width_axis: PlusZ,
                  boom_length_m: 0.4, panel_count: 3, panel_size_m: (1.2, 1.0), panel_gap_m: 0.05),
      ])"#,
            c(ix),
            c(iy),
            c(iz),
            v.x,
            v.y,
            v.z,
            w.x,
            w.y,
            w.z
        ));
    }
    let guarantees = if n >= 2 {
        r#"MinDistance(name: "clearance_sc0_sc1", a: "sc0", b: "sc1", min_m: 1.0)"#
    } else {
        ""
    };
    format!(
        r#"// A swarm of {n} tumbling winged spacecraft (written by `rpod swarm {n}`).
Scene(
    name: "swarm_{n}",
    dt_s: 0.01,
    duration_s: 60.0,
    environment: Orbit(
        reference: Elements(a_m: 7178000.0, e: 0.001, i_deg: 51.6, raan_deg: 0.0,
                            argp_deg: 0.0, true_anomaly_deg: 0.0),
        j2: true, gravity_gradient: true,
    ),
    monitor: (horizon_m: Some(5.0)),
    bodies: [
    {}
    ],
    guarantees: [{guarantees}],
)
"#,
        bodies.join(",\n    ")
    )
}

/// The swarm table: for each N, pipeline and bare rapier µs/step, their ratio, and the exact
/// queries per step, as a Markdown table; with the growth rate of the pipeline's cost per
/// step between the smallest and the largest N (log-log slope).
pub fn run_swarm(sizes: &[usize], steps: u64) -> Result<String, SceneError> {
    let mut r = String::new();
    let _ = writeln!(
        r,
        "| N | pipeline steps/s | pipeline µs/step | bare rapier µs/step | pipeline / rapier | exact queries/step | rapier skipped |"
    );
    let _ = writeln!(r, "|---|---|---|---|---|---|---|");
    let mut pts = Vec::new();
    for &n in sizes {
        let text = swarm_scene(n, 1);
        let loaded = load_scene_str(&text, &format!("swarm_{n}"), &[])?;
        let m = measure(&loaded, steps.max(100))?;
        let per = |s: f64| s / m.steps as f64 * 1e6;
        pts.push((n as f64, per(m.pipeline_s)));
        let _ = writeln!(
            r,
            "| {n} | {:.0} | {:.1} | {:.1} | {:.2} | {:.2} | {:.0} % |",
            m.steps as f64 / m.pipeline_s,
            per(m.pipeline_s),
            per(m.rapier_s),
            m.pipeline_s / m.rapier_s,
            m.exact_per_step,
            100.0 * m.rapier_skipped
        );
    }
    if let (Some(a), Some(b)) = (pts.first(), pts.last())
        && b.0 > a.0
    {
        let slope = (b.1 / a.1).ln() / (b.0 / a.0).ln();
        let _ = writeln!(
            r,
            "\npipeline cost per step grows as N^{slope:.2} from N = {} to N = {}",
            a.0, b.0
        );
    }
    Ok(r)
}

/// Steps/s of the whole pipeline over `steps` steps after `skip_steps` untimed ones, and the
/// docking state at the end of the window.
pub fn window_rate(
    loaded: &LoadedScene,
    skip_steps: u64,
    steps: u64,
) -> Result<(f64, Option<&'static str>), SceneError> {
    let mut sim = Simulation::new(loaded)?;
    sim.step(skip_steps);
    let t0 = Instant::now();
    sim.step(steps);
    let wall_s = t0.elapsed().as_secs_f64();
    Ok((steps as f64 / wall_s, sim.docking_state()))
}

/// Steps/s of bare rapier on the scene's world (the floor of the rows of [`run_cliffs`]).
fn rapier_rate(loaded: &LoadedScene, steps: u64) -> Result<f64, SceneError> {
    let fresh = Simulation::new(loaded)?;
    let mut world = {
        let mut app = fresh.app;
        app.world_mut()
            .remove_resource::<Physics>()
            .expect("physics")
            .world
    };
    let t0 = Instant::now();
    for _ in 0..steps {
        world.step();
    }
    Ok(steps as f64 / t0.elapsed().as_secs_f64())
}

/// The attitude law of the cliff cases, as a `--set controllers=…` value: quaternion feedback
/// on the chaser (1 N·m per axis) toward `mode`.
fn chaser_attitude_law(mode: &str) -> String {
    format!(
        "controllers=[Attitude(body: \"chaser\", target: \"target\", period_s: 0.1, \
         actuator: Saturated(max_force_n: (0.0, 0.0, 0.0), max_torque_nm: (1.0, 1.0, 1.0)), \
         params: (mode: {mode}, natural_frequency_rad_s: 0.3, damping_ratio: 0.9))]"
    )
}

/// A whole run of a scene with `stepping` set (no output files): wall seconds, pipeline steps
/// (fixed steps for `Fixed`), fixed steps.
fn whole_run(path: &Path, stepping: &str) -> Result<(f64, u64, u64), SceneError> {
    let loaded = load_scene_file(path, &[format!("stepping={stepping}")])?;
    let mut sim = crate::sim::Simulation::new(&loaded)?;
    let n = sim.steps_for(loaded.scene.duration_s);
    let t0 = std::time::Instant::now();
    sim.step(n);
    let wall = t0.elapsed().as_secs_f64();
    let pipeline = sim.summary()["stepping"]["pipeline_steps"]
        .as_u64()
        .unwrap_or(n);
    Ok((wall, pipeline, n))
}

/// The four `docking_aligned` variants of [`run_cliffs`]: plain, the chaser spinning at
/// 100 rad/s about its docking axis (the monitor told to allow it: it turns 1 rad a step), an
/// `Attitude` law holding yaw 183° through the latch, and an `AlignPort` law in contact.
pub fn cliff_scenes(scenes: &Path) -> Result<[LoadedScene; 4], SceneError> {
    let aligned = scenes.join("docking_aligned.ron");
    let load = |sets: &[String]| load_scene_file(&aligned, sets);
    Ok([
        load(&[])?,
        load(&[
            "bodies.chaser.initial.rate_body_deg_s=(5729.5779513, 0.0, 0.0)".to_string(),
            "monitor=(allow_under_resolved: true)".to_string(),
        ])?,
        load(&[chaser_attitude_law(
            "Inertial(attitude: EulerZyxDeg(yaw: 183.0, pitch: 0.0, roll: 0.0))",
        )])?,
        load(&[chaser_attitude_law("AlignPort")])?,
    ])
}

/// The cliffs (a spinning body, a law through the latch, contact), each a ratio of steps/s to its plain case measured in the same run,
/// with bare rapier on the plain scene's world as the floor, as a Markdown table:
///
/// * spin: `docking_aligned` with the chaser spinning at 100 rad/s about its docking axis, the
///   first 3 s (the cone 0.50–0.44 m above the seat) and 1 s from 15 s (0.20–0.18 m), against
///   the same window without spin (goal ≥ 0.2);
/// * a law through the latch: `docking_aligned` with an `Attitude` law on the chaser holding
///   yaw 183° (3° off the port axis: it latches at 24.8 s and the law then pushes on the
///   stack), 20 s from t = 26 s, against the same window latched without a law (goal ≥ 0.5);
/// * a law in contact: the same with `AlignPort` (the latch is refused at 24.4 s, relative
///   rate 0.83°/s, the cone rebounds and reseats under the law), same window, against the
///   latched plain case;
/// * `free_drift` against bare rapier on its world (goal: 5× Basilisk, see
///   `benches/basilisk_free_drift.py`).
///
/// * multi-rate stepping: `free_drift` and the flagship (`orbit_approach_latch`), each a whole
///   run with `stepping: MultiRate()` against the same run with `Fixed` (fixed steps per wall
///   second, so the rates compare across modes).
///
/// `scenes` is the folder holding `docking_aligned.ron`, `free_drift.ron` and
/// `orbit_approach_latch.ron`.
pub fn run_cliffs(scenes: &Path, steps: u64) -> Result<String, SceneError> {
    let [plain, spin, law_latched, law_contact] = cliff_scenes(scenes)?;
    let mut r = String::new();
    let _ = writeln!(
        r,
        "| case | window | steps/s | plain steps/s | ratio | goal | docking state | bare rapier steps/s |"
    );
    let _ = writeln!(r, "|---|---|---|---|---|---|---|---|");
    let floor = rapier_rate(&plain, 2000)?;
    let state = |s: Option<&str>| s.unwrap_or("-").to_string();
    // Spin: the first 3 s, and 1 s from 15 s (the cone 0.20–0.18 m above the seat).
    for (skip, n, label) in [(10, 300, "0.1–3.1 s"), (1500, 100, "15–16 s")] {
        let (p, ps) = window_rate(&plain, skip, n)?;
        let (x, xs) = window_rate(&spin, skip, n)?;
        let _ = writeln!(
            r,
            "| spin 100 rad/s about the docking axis | {label} | {x:.0} | {p:.0} | {:.3} | ≥ 0.2 | {} / {} | {floor:.0} |",
            x / p,
            state(xs),
            state(ps)
        );
    }
    // A law through the latch, and in contact.
    let (p, ps) = window_rate(&plain, 2600, 2000)?;
    let (x, xs) = window_rate(&law_latched, 2600, 2000)?;
    let _ = writeln!(
        r,
        "| Attitude law (yaw 183°) through the latch | 26–46 s | {x:.0} | {p:.0} | {:.3} | ≥ 0.5 | {} / {} | {floor:.0} |",
        x / p,
        state(xs),
        state(ps)
    );
    let (x, xs) = window_rate(&law_contact, 2600, 2000)?;
    let _ = writeln!(
        r,
        "| AlignPort law in contact (latch refused at 24.4 s) | 26–46 s | {x:.0} | {p:.0} | {:.3} | – | {} / {} | {floor:.0} |",
        x / p,
        state(xs),
        state(ps)
    );
    // free_drift against its floor.
    let fd = load_scene_file(&scenes.join("free_drift.ron"), &[])?;
    let m = measure(&fd, steps.max(1000))?;
    let _ = writeln!(
        r,
        "| free_drift (pipeline vs bare rapier) | {} steps | {:.0} | – | {:.3} of bare rapier | 5× Basilisk | – | {:.0} |",
        m.steps,
        m.steps as f64 / m.pipeline_s,
        m.rapier_s / m.pipeline_s,
        m.steps as f64 / m.rapier_s
    );
    // Multi-rate stepping: whole runs, Fixed against MultiRate() (the scene's own duration).
    for (file, label) in [
        ("free_drift.ron", "free_drift, whole run"),
        ("orbit_approach_latch.ron", "flagship, whole run"),
    ] {
        let (fixed_s, _, steps) = whole_run(&scenes.join(file), "Fixed")?;
        let (multi_s, pipeline, _) = whole_run(&scenes.join(file), "MultiRate()")?;
        let _ = writeln!(
            r,
            "| {label}: stepping MultiRate() against Fixed | {steps} steps ({pipeline} pipeline steps) | {:.0} | {:.0} | {:.2} (wall {multi_s:.2} s against {fixed_s:.2} s) | flagship ≤ Basilisk's wall (`benches/basilisk_free_drift.py --flagship`) | – | – |",
            steps as f64 / multi_s,
            steps as f64 / fixed_s,
            fixed_s / multi_s
        );
    }
    Ok(r)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The cliffs' scene variants load from the bundled scenes (the overrides name fields the
    /// scene format has: a broken override made `rpod bench --cliffs` fail at once).
    #[test]
    fn cliff_scenes_load_with_their_overrides() {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/examples");
        let [plain, spin, latched, contact] = cliff_scenes(&dir).expect("cliff scenes load");
        let rate = |l: &LoadedScene| {
            let b = l
                .scene
                .bodies
                .iter()
                .find(|b| b.name == "chaser")
                .expect("chaser");
            b.initial.rate_body_deg_s[0]
        };
        assert_eq!(rate(&plain), 0.0);
        // 100 rad/s in deg/s.
        assert!((rate(&spin).to_radians() - 100.0).abs() < 1e-6);
        assert!(spin.scene.monitor.allow_under_resolved);
        assert!(!plain.scene.monitor.allow_under_resolved);
        assert_eq!(
            latched.scene.controllers.len(),
            plain.scene.controllers.len() + 1
        );
        assert_eq!(
            contact.scene.controllers.len(),
            plain.scene.controllers.len() + 1
        );
    }
}
