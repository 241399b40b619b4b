//! The fixed-step schedule is unambiguous: no two systems of `SimStep` that access the same
//! data (a `Wrench`, a `BodyState`, a resource) run without an order between them, in any kind
//! of scene (orbit with controllers and a docking mechanism, air-bearing table, Sun–Earth L2,
//! plume loads, multi-rate stepping, a disturbance added after the first steps — the systems
//! a scene does not use are put in the schedule only when it needs them). An unordered pair
//! would make the order of floating-point sums — and so the outputs — depend on how systems
//! were inserted.
//!
//! Reference: Bevy's own ambiguity detection (`ScheduleGraph::conflicting_systems`), run on the
//! built schedule of each scene.

use rpod::control::registry::{BodyWrench, Disturbance, DisturbanceContext};
use rpod::sim::{Simulation, schedule_ambiguities};
use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};

fn ambiguities(scene: &str) -> Vec<String> {
    let mut sim = Simulation::from_file(scene, &[]).expect("scene loads");
    schedule_ambiguities(&mut sim.app)
}

/// A disturbance that adds nothing and counts its calls: it puts the controller host's
/// systems in the schedule, which call it once a step.
struct Counted(Arc<AtomicU64>);

impl Disturbance for Counted {
    fn wrenches(&mut self, _: &DisturbanceContext, _: &mut Vec<BodyWrench>) {
        self.0.fetch_add(1, Ordering::Relaxed);
    }
}

#[test]
fn regress_schedule_has_no_ambiguities_with_systems_added_as_needed() {
    let mut found = Vec::new();
    // Multi-rate stepping: the planner's system.
    let mut sim = Simulation::from_file(
        "scenes/examples/orbit_approach_latch.ron",
        &["stepping=MultiRate()".into()],
    )
    .expect("scene loads");
    found.extend(schedule_ambiguities(&mut sim.app));
    // A scene without controllers, then a disturbance after ten steps: the host's systems.
    let mut sim = Simulation::from_file("scenes/examples/free_drift.ron", &[]).expect("loads");
    sim.step(10);
    let calls = Arc::new(AtomicU64::new(0));
    sim.add_disturbance(Box::new(Counted(calls.clone())));
    found.extend(schedule_ambiguities(&mut sim.app));
    sim.step(7);
    assert_eq!(
        calls.load(Ordering::Relaxed),
        7,
        "called once a step once added"
    );
    assert!(
        found.is_empty(),
        "unordered systems in SimStep:\n{}",
        found.join("\n")
    );
}

#[test]
fn regress_schedule_has_no_ambiguities() {
    let scenes = [
        "scenes/examples/orbit_approach_latch.ron", // controllers (Sequencer), docking, orbit, J2
        "scenes/examples/docking_aligned.ron",      // docking mechanism, compliant contact
        "scenes/examples/free_drift.ron",           // no controllers
        "scenes/papers/xu2019/xu2019_simulation.ron", // air-bearing table, sensor
        "scenes/papers/zhang2018/zhang2018_pair.ron", // Sun–Earth L2 frame
        "scenes/papers/guo2016/guo2016_corridor.ron", // a paper law's guarantees (post-step diagnostics)
        "scenes/examples/orbit_approach_plume.ron",   // RCS jets whose plumes load the target
    ];
    let mut found = Vec::new();
    for s in scenes {
        for a in ambiguities(s) {
            found.push(format!("{s}: {a}"));
        }
    }
    assert!(
        found.is_empty(),
        "unordered systems in SimStep (order them with .before/.after or a SystemSet):\n{}",
        found.join("\n")
    );
}
