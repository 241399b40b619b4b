//! Rotations and small helpers: modified Rodrigues parameters with the shadow set,
//! quaternion/DCM conventions, skew matrices; adaptive stiff ODE integration with events
//! ([`ode`]); convex polygons for exact planar reachable sets ([`polygon`]).

pub mod mrp;
pub mod ode;
pub mod polygon;
pub mod rigid;
pub mod rng;
pub mod stats;
