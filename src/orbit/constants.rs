//! Physical constants (SI units) used across the orbit models.

/// Earth's gravitational parameter μ, m³/s² (EGM96 / WGS-84 value).
pub const MU_EARTH_M3_S2: f64 = 3.986_004_418e14;
/// Earth's equatorial radius used with J2, m (WGS-84).
pub const R_EARTH_M: f64 = 6_378_137.0;
/// Earth's second zonal harmonic J2 (dimensionless, EGM96 unnormalised).
pub const J2_EARTH: f64 = 1.082_626_68e-3;
