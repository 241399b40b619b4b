//! `rpod bench`: steps/s of a scene through the whole pipeline, against the floor measured in
//! the same run — the bare rapier step of the same bodies and colliders, and one bare parry
//! distance query per body pair (the least any exact full-geometry monitor must do).

use crate::scene::{SceneError, load_scene_file};
use crate::sim::{Physics, Simulation};
use std::fmt::Write;
use std::path::Path;
use std::time::Instant;

/// Runs the benchmark and returns a printable report.
pub fn run(scene: &Path, steps: u64) -> Result<String, SceneError> {
    let loaded = load_scene_file(scene, &[])?;
    let steps = steps.max(1000);

    // 1. The whole pipeline (no file output: that is I/O, not simulation).
    let mut sim = Simulation::new(&loaded)?;
    sim.step(steps / 10); // warm-up
    let t0 = Instant::now();
    sim.step(steps);
    let pipeline_s = t0.elapsed().as_secs_f64();
    let exact_per_step = sim.monitor().exact_queries as f64 / sim.steps() as f64;

    // 2. Bare rapier: the same world, stepped alone.
    let fresh = Simulation::new(&loaded)?;
    let mut world = {
        let mut app = fresh.app;
        app.world_mut()
            .remove_resource::<Physics>()
            .expect("physics")
            .world
    };
    for _ in 0..steps / 10 {
        world.step();
    }
    let t0 = Instant::now();
    for _ in 0..steps {
        world.step();
    }
    let rapier_s = t0.elapsed().as_secs_f64();

    // 3. Bare parry: the closest part pair of each body pair, at the poses of the end of run 1.
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

    let per = |s: f64| s / steps as f64 * 1e6;
    let floor_s = rapier_s + parry_s;
    let mut r = String::new();
    let _ = writeln!(
        r,
        "scene {} ({} steps of {} s)",
        sim.scene.name, steps, sim.scene.dt_s
    );
    let _ = writeln!(
        r,
        "pipeline      {:>9.0} steps/s  {:>7.2} µs/step  ({:.0}× real time)",
        steps as f64 / pipeline_s,
        per(pipeline_s),
        sim.scene.dt_s * steps as f64 / pipeline_s
    );
    let _ = writeln!(
        r,
        "bare rapier   {:>9.0} steps/s  {:>7.2} µs/step",
        steps as f64 / rapier_s,
        per(rapier_s)
    );
    let _ = writeln!(
        r,
        "bare parry    {:>9.0} steps/s  {:>7.2} µs/step  ({} queries/step)",
        steps as f64 / parry_s,
        per(parry_s),
        parts.len()
    );
    let _ = writeln!(
        r,
        "ratio pipeline / (rapier + parry) = {:.2}   (pipeline / rapier = {:.2}); monitor made {:.2} exact queries/step",
        pipeline_s / floor_s,
        pipeline_s / rapier_s,
        exact_per_step
    );
    Ok(r)
}
