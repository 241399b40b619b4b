//! Rigid-body rotation in f64: one RK4 step of Euler's equations with quaternion kinematics
//! (the free-flight rotation of the `sim` layer and of the docking platform's ring).

use nalgebra::{Matrix3, UnitQuaternion, Vector3};

/// A step that turns a body by more than this is under-resolved, rad: the monitor's rate bounds
/// rest on RK4 following Euler's equations to a relative 1e-4, argued for |ω|·dt ≤ 0.3 rad
/// (`sim::motion`); over a longer turn no guarantee is held and the step is counted.
pub const UNDER_RESOLVED_TURN_RAD: f64 = 0.3;

/// One RK4 step of Euler's equations J ω̇_b = τ_b − ω_b × J ω_b with quaternion kinematics
/// q̇ = ½ q ⊗ (0, ω_b), in f64; the torque is held constant in the world frame over the step.
/// Returns the new attitude (body → world) and world-frame angular velocity.
pub fn rotate_rk4(
    att: &UnitQuaternion<f64>,
    omega_world: &Vector3<f64>,
    torque_world: &Vector3<f64>,
    j: &Matrix3<f64>,
    j_inv: &Matrix3<f64>,
    dt: f64,
) -> (UnitQuaternion<f64>, Vector3<f64>) {
    use nalgebra::Quaternion;
    let f = |q: &Quaternion<f64>, w: &Vector3<f64>| {
        let qn = UnitQuaternion::from_quaternion(*q);
        let tau_b = qn.inverse() * torque_world;
        let wd = j_inv * (tau_b - w.cross(&(j * w)));
        let qd = q * Quaternion::from_imag(*w) * 0.5;
        (qd, wd)
    };
    let q0 = att.into_inner();
    let w0 = att.inverse() * omega_world;
    let (k1q, k1w) = f(&q0, &w0);
    let (k2q, k2w) = f(&(q0 + k1q * (dt / 2.0)), &(w0 + k1w * (dt / 2.0)));
    let (k3q, k3w) = f(&(q0 + k2q * (dt / 2.0)), &(w0 + k2w * (dt / 2.0)));
    let (k4q, k4w) = f(&(q0 + k3q * dt), &(w0 + k3w * dt));
    let q1 = UnitQuaternion::from_quaternion(q0 + (k1q + k2q * 2.0 + k3q * 2.0 + k4q) * (dt / 6.0));
    let w1 = w0 + (k1w + k2w * 2.0 + k3w * 2.0 + k4w) * (dt / 6.0);
    (q1, q1 * w1)
}
