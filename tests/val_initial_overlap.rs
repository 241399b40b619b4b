//! `allow_initial_overlap`: parts that start inside each other are not pushed apart (rapier's
//! depenetration would add kinetic energy from nowhere: a 300 kg chaser started 10 cm inside a
//! target left at metres per second); their contact stays off until they first separate, then
//! they collide normally. The monitor keeps reporting their distance.
//!
//! Reference: conservation laws. No force acts between the bodies in free space, so each
//! body's velocity, the total momentum and the kinetic energy are those at t = 0, exactly
//! (the f64 free flight of a force-free body is exact); the separation time follows from the
//! geometry: the boxes' half sizes 0.8 m + 0.5 m = 1.3 m, the chaser starts at 1.2 m moving out
//! at 1 cm/s, so the faces part at t = 10 s.

use rpod::scene::load_scene_str;
use rpod::sim::Simulation;
use rpod::sim::overlap::InitialOverlaps;

fn scene(vx: f64) -> String {
    format!(
        r#"Scene(
    name: "overlap", dt_s: 0.01, duration_s: 20.0,
    environment: FreeSpace,
    bodies: [
        (name: "target", role: Target, mass_kg: 800.0,
         inertia_kg_m2: (xx: 620.0, yy: 910.0, zz: 1080.0),
         initial: (pos_m: (0.0, 0.0, 0.0)),
         parts: [Bus(name: "bus", shape: Box(size_m: (1.6, 1.6, 1.6)))]),
        (name: "chaser", role: Chaser, mass_kg: 300.0,
         inertia_kg_m2: (xx: 110.0, yy: 140.0, zz: 160.0),
         initial: (pos_m: (1.2, 0.0, 0.0), vel_m_s: ({vx:?}, 0.0, 0.0)),
         parts: [Bus(name: "bus", shape: Box(size_m: (1.0, 1.0, 1.0)), allow_initial_overlap: true)]),
    ],
    guarantees: [MinDistance(name: "apart", a: "chaser", b: "target", min_m: 0.01)],
)"#
    )
}

fn energy_momentum(sim: &Simulation) -> (f64, nalgebra::Vector3<f64>) {
    let (t, c) = (sim.body("target").unwrap(), sim.body("chaser").unwrap());
    let e = 0.5 * 800.0 * t.vel_m_s.norm_squared() + 0.5 * 300.0 * c.vel_m_s.norm_squared();
    (e, t.vel_m_s * 800.0 + c.vel_m_s * 300.0)
}

#[test]
fn invariant_initial_overlap_creates_no_energy_at_rest() {
    let loaded = load_scene_str(&scene(0.0), "overlap", &[]).unwrap();
    let mut sim = Simulation::new(&loaded).unwrap();
    for _ in 0..10 {
        sim.step(100);
        let (e, p) = energy_momentum(&sim);
        assert_eq!(e, 0.0, "kinetic energy appeared at t = {} s", sim.t_s());
        assert_eq!(p.norm(), 0.0);
        // Still overlapping, and the monitor says so.
        assert!(sim.monitor().pairs[0].distance_m <= 0.0);
    }
    let g = &sim.guarantees().status[0];
    assert!(g.first_violation_s == Some(0.0), "{g:?}");
}

#[test]
fn invariant_initial_overlap_separates_without_changing_the_motion() {
    let loaded = load_scene_str(&scene(0.01), "overlap", &[]).unwrap();
    let mut sim = Simulation::new(&loaded).unwrap();
    let (e0, p0) = energy_momentum(&sim);
    let mut separated_at = None;
    for _ in 0..2000 {
        sim.step(1);
        let (e, p) = energy_momentum(&sim);
        assert!(
            (e - e0).abs() <= 1e-15 * e0,
            "energy {e} ≠ {e0} at t = {}",
            sim.t_s()
        );
        assert!((p - p0).norm() <= 1e-15 * p0.norm());
        let left = sim.app.world().resource::<InitialOverlaps>().pairs.len();
        if left == 0 && separated_at.is_none() {
            separated_at = Some(sim.t_s());
        }
    }
    // The faces part at t = 10 s; the contact is back on within a step of it.
    let t = separated_at.expect("the pair separated");
    assert!((t - 10.0).abs() <= 0.011, "separated at {t} s");
    assert!(sim.monitor().pairs[0].distance_m > 0.09);
}
