//! Modified Rodrigues parameters (MRP) with the shadow set, as used by Guo, Song, Li (2016),
//! eqs (10)–(18) and (21).
//!
//! # Convention (read this before using any function here)
//! - An MRP `σ` describes the attitude of a frame B relative to a reference frame N:
//!   `σ = q_v / (1 + q_0) = e tan(φ/4)` (eq 10), `e` the Euler axis, `φ` the rotation angle.
//! - [`dcm_from_mrp`] returns the **passive** direction-cosine matrix `R(σ)` of eq (17),
//!   **B-from-N**: `v_B = R(σ) v_N` (components of one physical vector in the two frames).
//! - nalgebra link: if `q: UnitQuaternion<f64>` is the orientation of B in N in the usual
//!   nalgebra/Bevy sense (**body→reference**: `v_N = q * v_B`), then
//!   `σ = q.imag() / (1 + q.w)` and `R(σ) = q.to_rotation_matrix().matrix().transpose()`.
//!   [`mrp_from_quat`] / [`quat_from_mrp`] use exactly this mapping (tested).
//! - Kinematics (eqs 11–12): `σ̇ = G(σ) ω`, with `ω` the angular velocity of B relative to N
//!   expressed in B axes (rad/s).
//! - Shadow set: `σ^S = −σ/|σ|²` describes the same rotation; [`mrp_short`] switches to it when
//!   `|σ| > 1`, so the returned set has `|σ| ≤ 1` (rotation angle ≤ 180°).
//!
//! MRPs are dimensionless (they are `tan(φ/4)`, not an angle in rad).

use nalgebra::{Matrix3, UnitQuaternion, Vector3};

/// Skew-symmetric (cross-product) matrix: `skew(a) b = a × b`.
pub fn skew(a: &Vector3<f64>) -> Matrix3<f64> {
    Matrix3::new(0.0, -a.z, a.y, a.z, 0.0, -a.x, -a.y, a.x, 0.0)
}

/// Shadow MRP `σ^S = −σ/|σ|²` (same rotation, angle φ − 2π·sign). Returns `σ` unchanged for
/// `σ = 0` (the shadow of the identity is at infinity).
pub fn mrp_shadow(sigma: &Vector3<f64>) -> Vector3<f64> {
    let n2 = sigma.norm_squared();
    if n2 == 0.0 { *sigma } else { -sigma / n2 }
}

/// The short MRP set: `σ` if `|σ| ≤ 1`, its shadow otherwise (`|result| ≤ 1`).
pub fn mrp_short(sigma: &Vector3<f64>) -> Vector3<f64> {
    if sigma.norm_squared() > 1.0 {
        mrp_shadow(sigma)
    } else {
        *sigma
    }
}

/// MRP of the orientation `q` (body→reference: `v_ref = q * v_body`), short set (`|σ| ≤ 1`).
/// Uses `q` or `−q`, whichever has `w ≥ 0`, so the result never needs the shadow switch.
pub fn mrp_from_quat(q: &UnitQuaternion<f64>) -> Vector3<f64> {
    let (w, v) = if q.w >= 0.0 {
        (q.w, q.imag())
    } else {
        (-q.w, -q.imag())
    };
    v / (1.0 + w)
}

/// Orientation quaternion (body→reference) of the MRP `σ` (any set): the inverse of
/// [`mrp_from_quat`]. `q_0 = (1−|σ|²)/(1+|σ|²)`, `q_v = 2σ/(1+|σ|²)`.
pub fn quat_from_mrp(sigma: &Vector3<f64>) -> UnitQuaternion<f64> {
    let s2 = sigma.norm_squared();
    let d = 1.0 + s2;
    let v = sigma * (2.0 / d);
    UnitQuaternion::from_quaternion(nalgebra::Quaternion::new((1.0 - s2) / d, v.x, v.y, v.z))
}

/// Passive DCM `R(σ)` of eq (17), **B-from-N**: `v_B = R(σ) v_N`.
/// `R = I − 4(1−σᵀσ)/(1+σᵀσ)² σ× + 8 σ×σ×/(1+σᵀσ)²`.
pub fn dcm_from_mrp(sigma: &Vector3<f64>) -> Matrix3<f64> {
    let s2 = sigma.norm_squared();
    let d2 = (1.0 + s2) * (1.0 + s2);
    let sx = skew(sigma);
    Matrix3::identity() - sx * (4.0 * (1.0 - s2) / d2) + sx * sx * (8.0 / d2)
}

/// MRP (short set) of a passive DCM `dcm_b_from_n` (`v_B = dcm v_N`); inverse of
/// [`dcm_from_mrp`]. Goes through nalgebra's robust rotation-matrix → quaternion conversion.
pub fn mrp_from_dcm(dcm_b_from_n: &Matrix3<f64>) -> Vector3<f64> {
    let rot = nalgebra::Rotation3::from_matrix_unchecked(dcm_b_from_n.transpose());
    mrp_from_quat(&UnitQuaternion::from_rotation_matrix(&rot))
}

/// Composition: returns `σ` with `R(σ) = R(σ2) R(σ1)`, i.e. `σ1` = A relative to N, `σ2` = B
/// relative to A, result = B relative to N (Schaub & Junkins, Analytical Mechanics of Space
/// Systems, eq 3.158):
/// `σ = [(1−|σ1|²)σ2 + (1−|σ2|²)σ1 − 2 σ2×σ1] / [1 + |σ1|²|σ2|² − 2 σ1·σ2]`.
/// Returned as the short set. When the denominator vanishes (composite angle exactly 360°)
/// the same rotation is computed through quaternions instead.
pub fn mrp_compose(sigma2: &Vector3<f64>, sigma1: &Vector3<f64>) -> Vector3<f64> {
    let s1 = sigma1.norm_squared();
    let s2 = sigma2.norm_squared();
    let den = 1.0 + s1 * s2 - 2.0 * sigma1.dot(sigma2);
    let num = sigma2 * (1.0 - s1) + sigma1 * (1.0 - s2) - sigma2.cross(sigma1) * 2.0;
    if den.abs() < 1e-9 * (1.0 + s1 * s2) {
        // R(σ2)R(σ1) = R_a(q2)ᵀR_a(q1)ᵀ = R_a(q1 q2)ᵀ with R_a the active matrix.
        return mrp_from_quat(&(quat_from_mrp(sigma1) * quat_from_mrp(sigma2)));
    }
    mrp_short(&(num / den))
}

/// Relative (error) MRP of eq (14): `σ_e` with `R(σ_e) = R(σ) R(σ_d)ᵀ` (eq 16), i.e. the attitude
/// of the body B relative to the desired frame D, both `σ` (B/N) and `σ_d` (D/N) given relative
/// to the same frame N:
/// `σ_e = [(1−|σ_d|²)σ − (1−|σ|²)σ_d + 2σ×σ_d] / [1 + |σ|²|σ_d|² + 2σ_dᵀσ]`.
/// The extracted paper text reads `(1 − σᵀσ_d)σ_d` and `1 + σᵀσ σ_dᵀσ_d …` in places; the
/// formula above is the standard one (Schaub & Junkins eq 3.160), checked against quaternions
/// in the tests. Returned as the short set (`|σ_e| ≤ 1`). Equals `mrp_compose(σ, −σ_d)`.
pub fn mrp_relative(sigma: &Vector3<f64>, sigma_d: &Vector3<f64>) -> Vector3<f64> {
    mrp_compose(sigma, &(-sigma_d))
}

/// Kinematics matrix of eqs (12)/(21): `G(σ) = ¼[(1−σᵀσ)I + 2σ× + 2σσᵀ]`, `σ̇ = G(σ) ω`.
pub fn mrp_g(sigma: &Vector3<f64>) -> Matrix3<f64> {
    let s2 = sigma.norm_squared();
    (Matrix3::identity() * (1.0 - s2) + skew(sigma) * 2.0 + sigma * sigma.transpose() * 2.0) * 0.25
}

/// Closed-form inverse `G⁻¹(σ) = 16 Gᵀ(σ) / (1+σᵀσ)²` (since `GᵀG = (1+σᵀσ)²/16 · I`);
/// `ω = G⁻¹(σ) σ̇` (eq 18).
pub fn mrp_g_inv(sigma: &Vector3<f64>) -> Matrix3<f64> {
    let d = 1.0 + sigma.norm_squared();
    mrp_g(sigma).transpose() * (16.0 / (d * d))
}

/// Time derivative `Ġ(σ, σ̇) = ¼[−2(σᵀσ̇)I + 2σ̇× + 2(σ̇σᵀ + σσ̇ᵀ)]`.
pub fn mrp_g_dot(sigma: &Vector3<f64>, sigma_dot: &Vector3<f64>) -> Matrix3<f64> {
    let sd = sigma.dot(sigma_dot);
    (Matrix3::identity() * (-2.0 * sd)
        + skew(sigma_dot) * 2.0
        + (sigma_dot * sigma.transpose() + sigma * sigma_dot.transpose()) * 2.0)
        * 0.25
}

/// Time derivative of the inverse, `d/dt G⁻¹ = −G⁻¹ Ġ G⁻¹` (written `Ġ⁻¹` in eq 22).
pub fn mrp_g_inv_dot(sigma: &Vector3<f64>, sigma_dot: &Vector3<f64>) -> Matrix3<f64> {
    let gi = mrp_g_inv(sigma);
    -gi * mrp_g_dot(sigma, sigma_dot) * gi
}

#[cfg(test)]
mod tests {
    //! MRP algebra against independent references: nalgebra quaternions and rotation matrices
    //! (composition, DCM, shadow set) and central finite differences of the exact rotation
    //! (kinematics).
    use super::*;

    use crate::math::rng::Lcg;

    /// Angle between two orientations, rad (sign of q irrelevant).
    fn angle_between(a: &UnitQuaternion<f64>, b: &UnitQuaternion<f64>) -> f64 {
        a.angle_to(b)
    }

    #[test]
    fn invariant_mrp_quat_dcm_consistency() {
        // Reference: nalgebra's active rotation matrix of q (body→ref); the passive B-from-N DCM
        // of eq (17) must be its transpose, and σ = e tan(φ/4).
        let mut rng = Lcg(1);
        for _ in 0..200 {
            let q = rng.quat();
            let s = mrp_from_quat(&q);
            assert!(s.norm() <= 1.0 + 1e-15);
            let r_ref = q.to_rotation_matrix().matrix().transpose();
            assert!((dcm_from_mrp(&s) - r_ref).abs().max() < 1e-14);
            // Euler axis/angle form of eq (10)
            if let Some((axis, ang)) = q.axis_angle() {
                let ang = if ang > std::f64::consts::PI {
                    ang - 2.0 * std::f64::consts::PI
                } else {
                    ang
                };
                assert!((s - axis.into_inner() * (ang / 4.0).tan()).norm() < 1e-12);
            }
            assert!(angle_between(&quat_from_mrp(&s), &q) < 1e-12);
            assert!((mrp_from_dcm(&r_ref) - s).norm() < 1e-12);
            // DCM is orthonormal with det +1
            let r = dcm_from_mrp(&s);
            assert!((r * r.transpose() - Matrix3::identity()).abs().max() < 1e-14);
            assert!((r.determinant() - 1.0).abs() < 1e-14);
        }
        // A pure +90° rotation about z: the body x axis points along reference y, so the
        // reference y axis has body components (1, 0, 0).
        let q = UnitQuaternion::from_axis_angle(&Vector3::z_axis(), std::f64::consts::FRAC_PI_2);
        let s = mrp_from_quat(&q);
        assert!((s - Vector3::new(0.0, 0.0, (std::f64::consts::PI / 8.0).tan())).norm() < 1e-15);
        assert!((dcm_from_mrp(&s) * Vector3::y() - Vector3::x()).norm() < 1e-15);
    }

    #[test]
    fn invariant_mrp_shadow_same_rotation() {
        // Reference: the DCM of eq (17) and the quaternion; the shadow set must give the same.
        let mut rng = Lcg(2);
        for _ in 0..200 {
            let s = rng.vec3(3.0);
            if s.norm() < 1e-3 {
                continue;
            }
            let sh = mrp_shadow(&s);
            assert!((dcm_from_mrp(&s) - dcm_from_mrp(&sh)).abs().max() < 1e-12);
            assert!(angle_between(&quat_from_mrp(&s), &quat_from_mrp(&sh)) < 1e-7);
            let short = mrp_short(&s);
            assert!(short.norm() <= 1.0);
            assert!((dcm_from_mrp(&short) - dcm_from_mrp(&s)).abs().max() < 1e-12);
        }
    }

    #[test]
    fn invariant_mrp_composition_eq14_vs_quaternions() {
        // Reference: quaternion products. R(σ2)R(σ1) passive ↔ q1*q2 (body→ref orientations);
        // eq (14) R(σe) = R(σ)R(σd)ᵀ ↔ qd⁻¹ * q.
        let mut rng = Lcg(3);
        for _ in 0..500 {
            let q1 = rng.quat();
            let q2 = rng.quat();
            let s1 = mrp_from_quat(&q1);
            let s2 = mrp_from_quat(&q2);
            let c = mrp_compose(&s2, &s1);
            assert!(c.norm() <= 1.0 + 1e-12);
            assert!(angle_between(&quat_from_mrp(&c), &(q1 * q2)) < 1e-7);
            assert!(
                (dcm_from_mrp(&c) - dcm_from_mrp(&s2) * dcm_from_mrp(&s1))
                    .abs()
                    .max()
                    < 1e-12
            );
            // also with long (shadow) inputs
            let c2 = mrp_compose(&mrp_shadow(&s2), &mrp_shadow(&s1));
            assert!((dcm_from_mrp(&c2) - dcm_from_mrp(&c)).abs().max() < 1e-9);

            let q = q1;
            let qd = q2;
            let se = mrp_relative(&mrp_from_quat(&q), &mrp_from_quat(&qd));
            assert!(angle_between(&quat_from_mrp(&se), &(qd.inverse() * q)) < 1e-7);
            let r_e =
                dcm_from_mrp(&mrp_from_quat(&q)) * dcm_from_mrp(&mrp_from_quat(&qd)).transpose();
            assert!((dcm_from_mrp(&se) - r_e).abs().max() < 1e-12);
        }
        // 360° composite: denominator vanishes, quaternion fallback must still be right.
        let s = Vector3::new(1.0, 0.0, 0.0); // 180° about x
        let c = mrp_compose(&s, &s);
        assert!(c.norm() < 1e-12);
        assert!(mrp_relative(&s, &s).norm() < 1e-15);
    }

    #[test]
    fn invariant_mrp_kinematics_vs_finite_difference() {
        // Reference: exact rotation propagation. With ω constant in body axes over a short
        // interval, q(t) = q0 * exp(ω t / 2) (body→ref convention: body-frame rate multiplies
        // on the right); σ̇ from a central difference of σ(q(±dt)) must equal G(σ)ω (eq 11).
        // The central-difference truncation error is O(dt² |σ⃛|) ~ 1e-10 at dt = 1e-5.
        let mut rng = Lcg(4);
        let dt = 1e-5;
        for _ in 0..200 {
            let q0 = rng.quat();
            let w = rng.vec3(2.0);
            let s0 = mrp_from_quat(&q0);
            let qp = q0 * UnitQuaternion::from_scaled_axis(w * dt);
            let qm = q0 * UnitQuaternion::from_scaled_axis(-w * dt);
            let sp = mrp_from_quat(&qp);
            let sm = mrp_from_quat(&qm);
            if (sp - sm).norm() > 1.0 {
                continue; // shadow switch between the two samples: no derivative there
            }
            let sdot_fd = (sp - sm) / (2.0 * dt);
            let g = mrp_g(&s0);
            assert!(
                (sdot_fd - g * w).norm() < 1e-8 * (1.0 + w.norm()),
                "{sdot_fd} {}",
                g * w
            );
            // inverse
            assert!((mrp_g_inv(&s0) * g - Matrix3::identity()).abs().max() < 1e-13);
            // Ġ and d/dt G⁻¹ against central differences along σ(t)
            let sdot = g * w;
            let gd_fd = (mrp_g(&sp) - mrp_g(&sm)) / (2.0 * dt);
            assert!((mrp_g_dot(&s0, &sdot) - gd_fd).abs().max() < 1e-8);
            let gid_fd = (mrp_g_inv(&sp) - mrp_g_inv(&sm)) / (2.0 * dt);
            assert!((mrp_g_inv_dot(&s0, &sdot) - gid_fd).abs().max() < 1e-7);
        }
    }

    #[test]
    fn invariant_skew_cross_product() {
        // Reference: nalgebra's cross product.
        let mut rng = Lcg(5);
        let a = rng.vec3(3.0);
        let b = rng.vec3(3.0);
        assert!((skew(&a) * b - a.cross(&b)).norm() < 1e-15);
        assert!((skew(&a) + skew(&a).transpose()).abs().max() == 0.0);
    }
}
