//! Rotations and small helpers: modified Rodrigues parameters with the shadow set,
//! quaternion/DCM conventions, skew matrices; adaptive stiff ODE integration with events
//! ([`ode`]); convex polygons for exact planar reachable sets ([`polygon`]); a latched stack
//! flown as one rigid body ([`stack`]).

pub mod mrp;
pub mod ode;
pub mod polygon;
pub mod rigid;
pub mod rng;
pub mod stack;
pub mod stats;
