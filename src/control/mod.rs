//! Control laws, one file per paper, Bevy-free: each takes an observation and returns a command.

pub mod geng2015;
pub mod guo2016;
pub mod xu2015;
pub mod xu2019;
pub mod zhang2018;
