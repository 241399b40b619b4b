//! TEMPORARY (replaced by the orbit branch).
use nalgebra::{Matrix3, Vector3};
/// Rows: Hill axes in ECI.
pub fn hill_dcm(r: &Vector3<f64>, v: &Vector3<f64>) -> Matrix3<f64> {
    let x = r.normalize();
    let z = r.cross(v).normalize();
    let y = z.cross(&x);
    Matrix3::from_rows(&[x.transpose(), y.transpose(), z.transpose()])
}
