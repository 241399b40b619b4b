//! The finiteness guard: a scene that passes validation but overflows at run time is stopped
//! at the first bad value, with the body, the quantity and the time named, exit code 3, and no
//! output that looks whole (no `summary.json`; the rows before the trip stay as `.partial`,
//! every one finite).
//!
//! References: (1) a free body whose f64 velocity is made NaN (a diverged integrator, set in
//! the test) is at NaN after the next step, so the state check trips after step 1 on `pos_m.x`;
//! (2) a puck moving at 0.1 m/s on a table with a viscous drag of 10¹⁰⁰ N·s/m gets a force of
//! −10⁹⁹ N at t = 0, so the force check trips before the first physics step; (3) on a table
//! tilted 10° a puck at rest gains g·sin 10°·dt = 0.017 m/s in the first step, so the drag of
//! 10¹⁰⁰ N·s/m overflows at the force check of step 1: one good row after t = 0; (4) a free
//! body set moving at 2·10⁵ m/s (finite, beyond the scene limit of 10⁵ m/s for any speed) keeps
//! that velocity (free space: Newton's first law), so the state check trips after the next step
//! on `vel_m_s.x`; (5) a law raising 100 000 events per call has raised exactly 1 100 000 at its
//! eleventh call, past the run's limit of 10⁶, so the guard stops that step (the trip names the
//! step count at its check, 11); an event of 100 kB
//! is kept as its first 1024 characters with its size.

use rpod::scene::load_scene_str;
use rpod::sim::Simulation;
use std::process::Command;

const FLYER: &str = r#"Scene(
    name: "flyer", dt_s: 0.1, duration_s: 10.0, record_every_steps: 1,
    environment: FreeSpace,
    bodies: [(
        name: "probe", role: Chaser, mass_kg: 10.0,
        inertia_kg_m2: (xx: 1.0, yy: 1.0, zz: 1.0),
        initial: (pos_m: (0.0, 0.0, 0.0), vel_m_s: (1.0, 0.0, 0.0)),
        parts: [Bus(name: "bus", shape: Sphere(radius_m: 0.5))],
    )],
)"#;

const TILTED: &str = r#"Scene(
    name: "tilted", dt_s: 0.01, duration_s: 1.0, record_every_steps: 1,
    environment: AirBearing((viscous_drag_n_s_m: 1e100, tilt_deg: (10.0, 0.0))),
    bodies: [(
        name: "puck", role: Chaser, mass_kg: 10.0,
        inertia_kg_m2: (xx: 1.0, yy: 1.0, zz: 1.0),
        initial: (pos_m: (1.0, 1.0, 0.3)),
        parts: [Bus(name: "bus", shape: Cylinder(radius_m: 0.2, length_m: 0.4, axis: PlusZ))],
    )],
)"#;

const PUCK: &str = r#"Scene(
    name: "puck", dt_s: 0.01, duration_s: 1.0,
    environment: AirBearing((viscous_drag_n_s_m: 1e100)),
    bodies: [(
        name: "puck", role: Chaser, mass_kg: 10.0,
        inertia_kg_m2: (xx: 1.0, yy: 1.0, zz: 1.0),
        initial: (pos_m: (1.0, 1.0, 0.3), vel_m_s: (0.1, 0.0, 0.0)),
        parts: [Bus(name: "bus", shape: Cylinder(radius_m: 0.2, length_m: 0.4, axis: PlusZ))],
    )],
)"#;

#[test]
fn val_guard_stops_a_non_finite_state_after_the_next_step() {
    let loaded = load_scene_str(FLYER, "flyer", &[]).unwrap();
    let mut sim = Simulation::new(&loaded).unwrap();
    sim.step(3);
    assert!(sim.guard_trip().is_none());
    let e = sim.app.world().resource::<rpod::sim::Roster>().bodies[0];
    sim.app
        .world_mut()
        .get_mut::<rpod::sim::BodyState>(e)
        .unwrap()
        .vel_m_s
        .x = f64::NAN;
    sim.step(10);
    let trip = sim.guard_trip().cloned().expect("the guard trips");
    assert_eq!(
        (
            trip.check,
            trip.body.as_deref(),
            trip.quantity.as_str(),
            trip.step
        ),
        ("state", Some("probe"), "pos_m.x", 4)
    );
    assert!(trip.value.is_nan());
    assert!(
        trip.to_string()
            .starts_with("non-finite state at t = 0.4 s (step 4): body `probe`")
    );
    // Stepping stops at the trip.
    assert_eq!(sim.steps(), 4);
}

#[test]
fn val_guard_stops_an_overflowing_force_before_the_first_step() {
    let loaded = load_scene_str(PUCK, "puck", &[]).unwrap();
    let mut sim = Simulation::new(&loaded).unwrap();
    sim.step(10);
    let trip = sim.guard_trip().cloned().expect("the guard trips");
    assert_eq!(
        (
            trip.check,
            trip.body.as_deref(),
            trip.quantity.as_str(),
            trip.step
        ),
        ("force", Some("puck"), "force_n.x", 0)
    );
    assert_eq!(trip.value, -1e100 * 0.1);
    assert_eq!(sim.steps(), 0);
    assert!(
        trip.to_string()
            .contains("overflowing force at t = 0 s (step 0): body `puck` force_n.x")
    );
}

#[test]
fn regress_cli_guard_trip_exits_3_and_writes_no_summary() {
    let d = std::env::temp_dir().join(format!("rpod-guard-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    let scene = d.join("tilted.ron");
    std::fs::write(&scene, TILTED).unwrap();
    let out = d.join("out");
    let r = Command::new(env!("CARGO_BIN_EXE_rpod"))
        .arg("run")
        .arg(&scene)
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    assert_eq!(r.status.code(), Some(3));
    let err = String::from_utf8_lossy(&r.stderr);
    assert!(
        err.contains("overflowing force at t = 0.01 s (step 1): body `puck` force_n.x = -"),
        "{err}"
    );
    assert!(!out.join("summary.json").exists());
    assert!(!out.join("trajectory.csv").exists());
    let rows = std::fs::read_to_string(out.join("trajectory.csv.partial")).unwrap();
    // The header, t = 0 and the one good step, every cell finite.
    assert_eq!(rows.lines().count(), 1 + 2, "{rows}");
    for line in rows.lines().skip(1) {
        for c in line.split(',').filter(|c| !c.is_empty()) {
            if let Ok(v) = c.parse::<f64>() {
                assert!(v.is_finite() && v.abs() <= 1e15, "{line}");
            }
        }
    }
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn val_guard_stops_a_state_beyond_the_scene_limits() {
    let loaded = load_scene_str(FLYER, "flyer", &[]).unwrap();
    let mut sim = Simulation::new(&loaded).unwrap();
    sim.step(3);
    let e = sim.app.world().resource::<rpod::sim::Roster>().bodies[0];
    sim.app
        .world_mut()
        .get_mut::<rpod::sim::BodyState>(e)
        .unwrap()
        .vel_m_s
        .x = 2e5;
    sim.step(10);
    let trip = sim.guard_trip().cloned().expect("the guard trips");
    assert_eq!(
        (trip.check, trip.quantity.as_str(), trip.step, trip.limit),
        (
            "state",
            "vel_m_s.x",
            4,
            rpod::scene::validate::MAX_SPEED_M_S
        )
    );
    assert!((trip.value - 2e5).abs() < 1.0, "{}", trip.value);
    assert!(
        trip.to_string()
            .contains("out-of-range state at t = 0.4 s (step 4): body `probe` vel_m_s.x"),
        "{trip}"
    );
}

/// A law that raises `per_call` events of `bytes` characters of data at every call.
#[derive(Debug, Clone, serde::Deserialize)]
struct ChattyParams {
    per_call: usize,
    bytes: usize,
}

struct Chatty(ChattyParams);

impl rpod::control::registry::LawParams for ChattyParams {
    fn build(
        &self,
        _ctx: &mut rpod::control::registry::LawContext,
    ) -> Result<Box<dyn rpod::control::interface::Controller>, rpod::control::registry::BuildError>
    {
        Ok(Box::new(Chatty(self.clone())))
    }
}

impl rpod::control::interface::Controller for Chatty {
    fn command(
        &mut self,
        _obs: &rpod::control::interface::Observation,
    ) -> rpod::control::interface::Command {
        rpod::control::interface::Command::zero()
    }
    fn take_events(&mut self) -> Vec<rpod::control::interface::ControllerEvent> {
        let data = if self.0.bytes > 0 {
            serde_json::json!({ "blob": "x".repeat(self.0.bytes) })
        } else {
            serde_json::json!({})
        };
        (0..self.0.per_call)
            .map(|_| rpod::control::interface::ControllerEvent {
                kind: "chatter".into(),
                data: data.clone(),
            })
            .collect()
    }
}

#[test]
fn val_guard_caps_events_per_event_and_per_run() {
    rpod::control::registry::register_law::<ChattyParams>("ChattyGuardTest").expect("a new name");
    let scene = |per_call: usize, bytes: usize| {
        FLYER.replace(
            "    )],\n)",
            &format!(
                "    )],\n    controllers: [ChattyGuardTest(body: \"probe\", params: (per_call: {per_call}, bytes: {bytes}))],\n)"
            ),
        )
    };
    // One event of 100 kB: kept as its head and its size.
    let loaded = load_scene_str(&scene(1, 100_000), "chatty", &[]).unwrap();
    let mut sim = Simulation::new(&loaded).unwrap();
    sim.step(1);
    let ev = sim.events();
    let big = ev.iter().find(|e| e.kind == "chatter").expect("raised");
    let want = serde_json::to_string(&serde_json::json!({ "blob": "x".repeat(100_000) }))
        .unwrap()
        .len();
    assert_eq!(big.data["truncated_bytes"], want);
    assert_eq!(
        big.data["head"].as_str().unwrap().chars().count(),
        rpod::sim::EVENT_HEAD_CHARS
    );
    assert!(sim.guard_trip().is_none());
    // 100 000 events per call: the eleventh call (t = 1 s, in the step that ends at step 11)
    // passes the limit of 10⁶; the guard stops that step.
    let loaded = load_scene_str(&scene(100_000, 0), "chatty", &[]).unwrap();
    let mut sim = Simulation::new(&loaded).unwrap();
    sim.step(20);
    let trip = sim.guard_trip().cloned().expect("the guard trips");
    assert_eq!(
        (trip.check, trip.step, trip.value),
        ("events", 11, 1_100_000.0)
    );
    assert_eq!(sim.steps(), 11);
    assert!(
        trip.to_string()
            .starts_with("too many events at t = 1.1 s (step 11)"),
        "{trip}"
    );
}
