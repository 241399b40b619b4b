//! Rotations and small helpers: modified Rodrigues parameters with the shadow set,
//! quaternion/DCM conventions, skew matrices.

pub mod mrp;
pub mod rng;
pub mod rot;
