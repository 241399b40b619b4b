//! A user's own law, written outside rpod, registered under a name and flown on the flagship
//! scene `scenes/examples/orbit_approach_latch.ron` to LATCHED:
//!
//! ```sh
//! cargo run --release --example custom_controller -- --out out/custom_controller
//! ```
//!
//! `MyPd` drives the chaser's docking port along the target port's axis toward the seat at a
//! constant closing speed: a PD on the port-to-port error in the target port's frame (its x
//! axis is the approach axis), with no model of the orbit at all — the feedback treats the
//! orbital dynamics as a disturbance. The scene's `Sequencer` keeps its attitude law and its
//! holds; `MyPd` replaces the two glideslope phases through `--set`-style overrides.

use nalgebra::Vector3;
use rpod::control::interface::{Command, Controller, Frame, Observation};
use rpod::control::registry::{BuildError, LawContext, LawParams, register_law};
use rpod::sim::Simulation;
use serde::Deserialize;

/// The law's parameters, as the scene writes them: `MyPd((speed_m_s: 0.1, …))`.
#[derive(Debug, Clone, Deserialize)]
struct MyPdParams {
    /// Closing speed along the axis, m/s.
    speed_m_s: f64,
    /// Stop at this range from the target port, m.
    stop_m: f64,
    /// Natural frequency of the error dynamics, rad/s.
    omega_rad_s: f64,
}

impl LawParams for MyPdParams {
    fn build(&self, ctx: &mut LawContext) -> Result<Box<dyn Controller>, BuildError> {
        if !(self.speed_m_s > 0.0 && self.omega_rad_s > 0.0 && self.stop_m >= 0.0) {
            return Err(BuildError::at(
                "speed_m_s",
                "speed, stop range and ω must be positive",
            ));
        }
        if ctx.ports.is_none() {
            return Err(BuildError::at(
                "",
                "MyPd flies port to port: the entry needs ports",
            ));
        }
        Ok(Box::new(MyPd {
            p: self.clone(),
            mass_kg: ctx.own().mass_kg,
            start: None,
            error: None,
        }))
    }
}

/// The running law: the reference range r(t) = max(r₀ − v t, stop).
struct MyPd {
    p: MyPdParams,
    mass_kg: f64,
    start: Option<(f64, f64)>,
    error: Option<(f64, f64)>,
}

impl Controller for MyPd {
    fn command(&mut self, obs: &Observation) -> Command {
        let Some(ports) = obs.ports else {
            return Command::zero();
        };
        // Chaser port relative to the target port, in the target port frame (x: the axis).
        let (pos, vel) = (ports.rel_port.pos_m, ports.rel_port.vel_m_s);
        let (t0, r0) = *self.start.get_or_insert((obs.t_s, pos.x));
        let r_ref = (r0 - self.p.speed_m_s * (obs.t_s - t0)).max(self.p.stop_m);
        let v_ref = if r_ref > self.p.stop_m {
            -self.p.speed_m_s
        } else {
            0.0
        };
        let w = self.p.omega_rad_s;
        let e = pos - Vector3::new(r_ref, 0.0, 0.0);
        let ed = vel - Vector3::new(v_ref, 0.0, 0.0);
        let a_port = -(e * (w * w) + ed * (2.0 * w));
        self.error = Some((e.norm(), ed.norm()));
        // Back to the world frame with the target port's attitude.
        let a_world = ports.target.att * a_port;
        Command::in_frame(Frame::World, a_world * self.mass_kg, Vector3::zeros())
    }

    /// What the scene's `Settled` exit conditions read.
    fn tracking_error(&self) -> Option<(f64, f64)> {
        self.error
    }
}

fn main() {
    let mut out = std::path::PathBuf::from("out/custom_controller");
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        if a == "--out" {
            out = args.next().expect("--out DIR").into();
        }
    }
    register_law::<MyPdParams>("MyPd").expect("a new name");
    let my_pd = |speed: f64, stop: f64| {
        format!("Some(MyPd((speed_m_s: {speed}, stop_m: {stop}, omega_rad_s: 0.05)))")
    };
    // Phases 1 (approach, to 10 m) and 3 (final, to the seat) of the scene's Sequencer.
    let overrides = [
        format!(
            "controllers.1.params.phases.1.translation={}",
            my_pd(0.1, 10.0)
        ),
        format!(
            "controllers.1.params.phases.3.translation={}",
            my_pd(0.03, 0.2)
        ),
    ];
    let mut sim = Simulation::from_file("scenes/examples/orbit_approach_latch.ron", &overrides)
        .unwrap_or_else(|e| {
            eprintln!("error: {e}");
            std::process::exit(2)
        });
    sim.record_to(&out).expect("output folder");
    sim.run_for(sim.scene.duration_s);
    let latched = sim.docking_state() == Some("LATCHED");
    let cone = sim
        .guarantee("approach_cone_20deg")
        .expect("the scene's cone");
    println!(
        "MyPd: docking {}, approach cone {} (worst margin {:.3} m), min non-docking clearance {:.3} m",
        sim.docking_state().unwrap_or("-"),
        if cone.held { "held" } else { "VIOLATED" },
        cone.worst_margin,
        sim.min_clearance_non_docking_m()
    );
    let summary = sim.finish().expect("outputs written");
    println!(
        "latched at t = {} s; wrote {}",
        summary["docking"]["t_latch_s"],
        out.display()
    );
    std::process::exit(if latched { 0 } else { 1 });
}
