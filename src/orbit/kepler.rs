//! TEMPORARY (replaced by the orbit branch).
use nalgebra::Vector3;
#[derive(Debug, Clone, Copy)]
pub struct ClassicalElements {
    pub a_m: f64,
    pub e: f64,
    pub i_rad: f64,
    pub raan_rad: f64,
    pub argp_rad: f64,
    pub true_anomaly_rad: f64,
}
impl ClassicalElements {
    pub fn to_state(&self, mu: f64) -> (Vector3<f64>, Vector3<f64>) {
        let p = self.a_m * (1.0 - self.e * self.e);
        let nu = self.true_anomaly_rad;
        let r = p / (1.0 + self.e * nu.cos());
        let rp = Vector3::new(r * nu.cos(), r * nu.sin(), 0.0);
        let vp = Vector3::new(
            -(mu / p).sqrt() * nu.sin(),
            (mu / p).sqrt() * (self.e + nu.cos()),
            0.0,
        );
        let rot = nalgebra::Rotation3::from_axis_angle(&Vector3::z_axis(), self.raan_rad)
            * nalgebra::Rotation3::from_axis_angle(&Vector3::x_axis(), self.i_rad)
            * nalgebra::Rotation3::from_axis_angle(&Vector3::z_axis(), self.argp_rad);
        (rot * rp, rot * vp)
    }
}
