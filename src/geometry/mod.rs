//! Analytic constraint surfaces (f64): the elliptic cissoid corridor (Guo 2016), the
//! superquadric obstacle and heart-shaped keep-out (Xu, Wen, Wei 2019); the approach cone of a
//! docking port checked against a body's full geometry; and sound bounds of a function of time
//! over an interval from its rate bound ([`bounds`], the monitor's between-samples reasoning);
//! what laws and guarantees ask a viewer to draw ([`drawn`]).

pub mod approach_cone;
pub mod bounds;
pub mod cissoid;
pub mod drawn;
pub mod heart;
pub mod mesh;
pub mod revolution;
pub mod superquadric;
