//! Actuation: saturation, thruster layouts and allocation, PWPF modulation; [`actuator`] is
//! what every controller's command passes through.

pub use actuator::{Actuator, ActuatorSpec};

pub mod actuator;
pub mod plume_load;
pub mod pwpf;
pub mod rcs;
pub mod thrusters;
