//! TEMPORARY (replaced by the orbit branch).
use nalgebra::Vector3;
#[derive(Debug, Clone)]
pub struct ReferenceOrbit {
    pub t_s: f64,
    pub r_eci_m: Vector3<f64>,
    pub v_eci_m_s: Vector3<f64>,
    pub with_j2: bool,
}
impl ReferenceOrbit {
    pub fn from_state(r: Vector3<f64>, v: Vector3<f64>, with_j2: bool) -> Self {
        Self {
            t_s: 0.0,
            r_eci_m: r,
            v_eci_m_s: v,
            with_j2,
        }
    }
    pub fn state(&self) -> (Vector3<f64>, Vector3<f64>) {
        (self.r_eci_m, self.v_eci_m_s)
    }
    pub fn step(&mut self, dt: f64) {
        let f = |r: &Vector3<f64>| super::gravity::accel_earth(r, self.with_j2);
        let (r, v) = (self.r_eci_m, self.v_eci_m_s);
        let (k1r, k1v) = (v, f(&r));
        let (k2r, k2v) = (v + k1v * dt / 2.0, f(&(r + k1r * dt / 2.0)));
        let (k3r, k3v) = (v + k2v * dt / 2.0, f(&(r + k2r * dt / 2.0)));
        let (k4r, k4v) = (v + k3v * dt, f(&(r + k3r * dt)));
        self.r_eci_m = r + (k1r + 2.0 * k2r + 2.0 * k3r + k4r) * dt / 6.0;
        self.v_eci_m_s = v + (k1v + 2.0 * k2v + 2.0 * k3v + k4v) * dt / 6.0;
        self.t_s += dt;
    }
}
