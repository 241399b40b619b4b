//! Control laws and the interface every law flies through, Bevy-free.
//!
//! - [`interface`]: the [`Controller`] trait — an [`Observation`] in, a [`Command`] out, at the
//!   controller's own period — and the frames and types around it.
//! - [`spec`]: the extension points a law implements and is given ([`spec::LawSpec`],
//!   [`spec::LawParams`], [`spec::BuildContext`], [`spec::Slot`], [`spec::Disturbance`], …);
//!   every law depends on it, not on the registry.
//! - [`registry`]: the list of built-in laws and open registration by name; a scene's
//!   `controllers` list selects laws by the name they were registered under
//!   ([`ControllerSpec`]).
//! - [`sensor`]: a relative-navigation sensor (rate, noise, latency, seed) any law can use.
//! - One folder per paper law ([`guo2016`], [`xu2015`], [`geng2015`], [`xu2019`],
//!   [`zhang2018`]): the law in `mod.rs`, its scene binding (entry, controller, disturbances)
//!   in `scene.rs`, its unit tests in `tests.rs`.

pub mod builtin;
pub mod generic;
pub mod geng2015;
pub mod guo2016;
pub mod interface;
pub mod navfilter;
pub mod registry;
pub mod sensor;
pub mod spec;
pub mod xu2015;
pub mod xu2019;
pub mod zhang2018;

pub use interface::{Command, Controller, Frame, Observation};
pub use registry::{ControllerSpec, register_law, register_spec};
