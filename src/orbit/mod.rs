//! Orbit models, all in f64: reference orbit (two-body + J2), relative-motion closed forms,
//! the elliptic relative dynamics of Xu & Hu (2015) and the planar two-centre model of
//! Zhang et al. (2018), and the fixed-step integrators that propagate them.

pub mod constants;
pub mod cw;
pub mod elliptic;
pub mod gravity;
pub mod integrate;
pub mod kepler;
pub mod l2;
pub mod lvlh;
pub mod ya;
