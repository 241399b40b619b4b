//! Actuation: saturation, thruster layouts and allocation, PWPF modulation.

pub mod pwpf;
pub mod thrusters;
