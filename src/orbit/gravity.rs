//! TEMPORARY (replaced by the orbit branch).
use super::constants::*;
use nalgebra::{Matrix3, Vector3};
pub fn accel_earth(r: &Vector3<f64>, with_j2: bool) -> Vector3<f64> {
    let rn = r.norm();
    let mut a = -MU_EARTH_M3_S2 / (rn * rn * rn) * r;
    if with_j2 {
        let z2 = (r.z / rn).powi(2);
        let k = -1.5 * J2_EARTH * MU_EARTH_M3_S2 * R_EARTH_M * R_EARTH_M / rn.powi(5);
        a += Vector3::new(
            k * r.x * (1.0 - 5.0 * z2),
            k * r.y * (1.0 - 5.0 * z2),
            k * r.z * (3.0 - 5.0 * z2),
        );
    }
    a
}
pub fn differential_accel(
    r_ref: &Vector3<f64>,
    r_rel: &Vector3<f64>,
    with_j2: bool,
) -> Vector3<f64> {
    accel_earth(&(r_ref + r_rel), with_j2) - accel_earth(r_ref, with_j2)
}
pub fn gravity_gradient_torque_body(
    r_eci_m: &Vector3<f64>,
    dcm_body_from_world: &Matrix3<f64>,
    j: &Matrix3<f64>,
) -> Vector3<f64> {
    let rb = dcm_body_from_world * r_eci_m;
    let rn = rb.norm();
    3.0 * MU_EARTH_M3_S2 / rn.powi(5) * rb.cross(&(j * rb))
}
