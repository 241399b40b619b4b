//! Analytic constraint surfaces (f64): the elliptic cissoid corridor (Guo 2016), the
//! superquadric obstacle and heart-shaped keep-out (Xu, Wen, Wei 2019); the approach cone of a
//! docking port checked against a body's full geometry.

pub mod approach_cone;
pub mod cissoid;
pub mod heart;
pub mod superquadric;
