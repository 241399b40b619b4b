//! The fixed-step schedule is unambiguous: no two systems of `SimStep` that access the same
//! data (a `Wrench`, a `BodyState`, a resource) run without an order between them, in any kind
//! of scene (orbit with controllers and a docking mechanism, air-bearing table, Sun–Earth L2,
//! a Python-style law added at run time). An unordered pair would make the order of floating-
//! point sums — and so the outputs — depend on how systems were inserted.
//!
//! Reference: Bevy's own ambiguity detection (`ScheduleGraph::conflicting_systems`), run on the
//! built schedule of each scene.

use rpod::sim::{Simulation, schedule_ambiguities};

fn ambiguities(scene: &str) -> Vec<String> {
    let mut sim = Simulation::from_file(scene, &[]).expect("scene loads");
    schedule_ambiguities(&mut sim.app)
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
