//! # rpod — a testbed for spacecraft rendezvous, proximity operations and docking
//!
//! rpod flies *your* control law against the real geometry of two spacecraft (bus, solar
//! wings, docking cone and slot) on a real physics engine, and tells you whether its avoidance
//! guarantee held against the full geometry and whether the docking mechanism captured.
//!
//! ## Quickstart: your own law, in your own crate
//!
//! A law is a [`control::Controller`]: an [`control::Observation`] in (f64 truth or sensor
//! measurements, in the world, Hill, target-body and port frames), a [`control::Command`] out
//! (force and torque in a stated frame, or thruster valves), called at its own period and held
//! in between. Register its parameters under a name and a scene can fly it:
//!
//! ```no_run
//! use nalgebra::Vector3;
//! use rpod::control::interface::{Command, Controller, Frame, Observation};
//! use rpod::control::registry::{BuildError, LawContext, LawParams, register_law};
//! use rpod::sim::Simulation;
//!
//! /// Hill-frame PD toward a hold point: `MyPd((hold_m: (0.0, -30.0, 0.0), kp: 1e-3, kd: 0.05))`.
//! #[derive(Debug, Clone, serde::Deserialize)]
//! struct MyPdParams { hold_m: [f64; 3], kp: f64, kd: f64 }
//!
//! struct MyPd { p: MyPdParams, mass_kg: f64 }
//!
//! impl LawParams for MyPdParams {
//!     fn build(&self, ctx: &mut LawContext) -> Result<Box<dyn Controller>, BuildError> {
//!         if self.kp <= 0.0 { return Err(BuildError::at("kp", "must be positive")); }
//!         Ok(Box::new(MyPd { p: self.clone(), mass_kg: ctx.own().mass_kg }))
//!     }
//! }
//!
//! impl Controller for MyPd {
//!     fn command(&mut self, obs: &Observation) -> Command {
//!         let Some(rel) = obs.relative.and_then(|r| r.hill) else { return Command::zero() };
//!         let e = rel.pos_m - Vector3::from(self.p.hold_m);
//!         let a = -(e * self.p.kp + rel.vel_m_s * self.p.kd);
//!         Command::in_frame(Frame::Hill, a * self.mass_kg, Vector3::zeros())
//!     }
//! }
//!
//! #[test]
//! fn my_pd_holds_clear_of_the_target() {
//!     register_law::<MyPdParams>("MyPd").unwrap();
//!     // A scene entry: MyPd(body: "chaser", target: "target", period_s: 0.1,
//!     //                     actuator: Saturated(...), params: (hold_m: ..., kp: ..., kd: ...))
//!     let mut sim = Simulation::from_file("my_scene.ron", &[]).unwrap();
//!     sim.run_for(600.0);
//!     assert!(sim.guarantee("clearance_1m").unwrap().held);
//!     assert!(sim.min_clearance_non_docking_m() > 1.0);
//!     assert_eq!(sim.docking_state(), None);
//! }
//! ```
//!
//! A law can also be added to a built simulation without a scene entry
//! ([`sim::Simulation::add_controller`] with a [`control::registry::Slot`]), declare diagnostic
//! columns and register guarantees ([`control::Controller::columns`],
//! [`control::Controller::guarantees`]). `examples/custom_controller.rs` flies a user law on the
//! flagship scene `scenes/examples/orbit_approach_latch.ron` to LATCHED and writes the standard outputs.
//! rpod's own generic laws (`HillPd`, `Glideslope`, `Attitude`, `Sequencer`) are in
//! [`control::generic`], one file each; the five paper laws in `control::<paper>`.
//!
//! ## Layers
//! - Bevy-free scientific core, f64, unit-tested alone: [`math`], [`orbit`], [`geometry`],
//!   [`environment`], [`control`], [`actuation`], [`contact`], [`scene`], [`guarantee`],
//!   [`report`].
//! - `sim` feature: the Bevy + rapier layer that turns a scene into a fixed-step `App`
//!   ([`sim::Simulation`]): Sense → Control → Actuate → Environment → rapier → Monitor → Record.
//! - `viewer` feature: `viewer`, the window (`rpod view`, `rpod replay`).

#![warn(missing_docs)]

pub mod actuation;
#[cfg(feature = "sim")]
pub mod bench;
pub mod contact;
pub mod control;
pub mod environment;
pub mod geometry;
pub mod guarantee;
pub mod math;
pub mod orbit;
pub mod report;
#[cfg(feature = "sim")]
pub mod reproduce;
pub mod scene;
#[cfg(feature = "sim")]
pub mod sim;
#[cfg(feature = "sim")]
pub mod trials;
#[cfg(feature = "viewer")]
pub mod viewer;
