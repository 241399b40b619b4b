//! A rigid stack: bodies held together by a rigid latch, flown over one step as one rigid body
//! in f64 (multi-rate stepping's long step of a latched stack, `sim::multirate`).
//!
//! # The model
//! The members keep their poses relative to the first member (its body frame is the stack's
//! frame): member k's centre of mass at c_k from the stack's centre of mass and its attitude
//! rel_k relative to the first member's, both taken at t₀. The stack's mass is M = Σm_k, its
//! centre of mass X = Σm_k x_k / M, its velocity V = Σm_k v_k / M (the linear momentum over M,
//! exactly), its inertia about X in the stack frame J = Σ R_k J_k R_kᵀ + m_k(|c_k|²·1 − c_k c_kᵀ)
//! (parallel axes), its angular momentum about X (world) L = Σ q_k J_k q_k⁻¹ ω_k +
//! m_k (x_k − X) × (v_k − V), and its angular velocity ω = q J⁻¹ q⁻¹ L. A latch that is rigid
//! conserves both momenta: whatever relative motion the members had at t₀ (the joint solver's
//! residue) is absorbed as the latch would absorb it, and [`residual`] measures it.
//!
//! Over a step of h with every member's force, gravity and torque held (the fixed step holds
//! them too): X by velocity Verlet with the mass-weighted mean of the members' gravity at their
//! positions at t₀ and at the step's end, the held forces exactly; the attitude by
//! [`super::rigid::rotate_rk4`] with J and the total torque about X
//! (T = Σ τ_k + (x_k − X) × (F_k + G_k)); the members placed rigidly at the end, with
//! v_k = V + ω × (x_k − X) and ω_k = ω. What holds member k to the stack over the step is its
//! momentum change less what its own forces gave it: m_k (v_k(h) − v_k(0)) − (F_k + G_k)·h.

use super::rigid::rotate_rk4;
use nalgebra::{Matrix3, UnitQuaternion, Vector3};

/// One member of a stack at the start of a step.
#[derive(Debug, Clone)]
pub struct Member {
    /// Mass, kg.
    pub mass_kg: f64,
    /// Inertia about its centre of mass, body axes, kg·m².
    pub inertia_kg_m2: Matrix3<f64>,
    /// Centre of mass, world, m.
    pub pos_m: Vector3<f64>,
    /// Centre-of-mass velocity, world, m/s.
    pub vel_m_s: Vector3<f64>,
    /// Attitude, body → world.
    pub att: UnitQuaternion<f64>,
    /// Angular velocity, world, rad/s.
    pub omega_rad_s: Vector3<f64>,
    /// Held force other than gravity, world, N.
    pub force_n: Vector3<f64>,
    /// Gravity on it at t₀, world, N.
    pub gravity_n: Vector3<f64>,
    /// Held torque about its centre of mass, world, N·m.
    pub torque_nm: Vector3<f64>,
}

/// A member's state at the end of the step.
#[derive(Debug, Clone, PartialEq)]
pub struct MemberEnd {
    /// Centre of mass, world, m.
    pub pos_m: Vector3<f64>,
    /// Centre-of-mass velocity, world, m/s.
    pub vel_m_s: Vector3<f64>,
    /// Attitude, body → world.
    pub att: UnitQuaternion<f64>,
    /// Angular velocity, world, rad/s.
    pub omega_rad_s: Vector3<f64>,
}

/// The stack as one rigid body at t₀ (see the module documentation).
#[derive(Debug, Clone)]
pub struct Composite {
    /// M, kg.
    pub mass_kg: f64,
    /// X, world, m.
    pub com_m: Vector3<f64>,
    /// V, world, m/s.
    pub vel_m_s: Vector3<f64>,
    /// The stack frame (the first member's attitude).
    pub att: UnitQuaternion<f64>,
    /// J about X, stack frame, kg·m².
    pub inertia_kg_m2: Matrix3<f64>,
    /// Its inverse.
    pub inertia_inv: Matrix3<f64>,
    /// L about X, world, N·m·s.
    pub momentum_nms: Vector3<f64>,
    /// ω, world, rad/s.
    pub omega_rad_s: Vector3<f64>,
    /// Per member: c_k, stack frame, m.
    pub offsets_m: Vec<Vector3<f64>>,
    /// Per member: its attitude relative to the stack frame.
    pub rel_att: Vec<UnitQuaternion<f64>>,
}

/// The stack's rigid-body quantities at t₀; `None` for no members, a mass that is not
/// positive and finite, or an inertia that cannot be inverted.
pub fn composite(members: &[Member]) -> Option<Composite> {
    let first = members.first()?;
    let mass: f64 = members.iter().map(|m| m.mass_kg).sum();
    if !(mass.is_finite() && mass > 0.0) {
        return None;
    }
    let com = members
        .iter()
        .map(|m| m.pos_m * m.mass_kg)
        .sum::<Vector3<f64>>()
        / mass;
    let vel = members
        .iter()
        .map(|m| m.vel_m_s * m.mass_kg)
        .sum::<Vector3<f64>>()
        / mass;
    let att = first.att;
    let inv = att.inverse();
    let mut j = Matrix3::zeros();
    let mut l = Vector3::zeros();
    let mut offsets = Vec::with_capacity(members.len());
    let mut rel = Vec::with_capacity(members.len());
    for m in members {
        // Renormalised: a product with a quaternion a rounding off unit norm would double
        // that error at every step.
        let r = UnitQuaternion::new_normalize((inv * m.att).into_inner());
        let c = inv * (m.pos_m - com);
        let rm = r.to_rotation_matrix().into_inner();
        j += rm * m.inertia_kg_m2 * rm.transpose()
            + (Matrix3::identity() * c.norm_squared() - c * c.transpose()) * m.mass_kg;
        let w_b = m.att.inverse() * m.omega_rad_s;
        l +=
            m.att * (m.inertia_kg_m2 * w_b) + (m.pos_m - com).cross(&(m.vel_m_s - vel)) * m.mass_kg;
        offsets.push(c);
        rel.push(r);
    }
    let j_inv = j.try_inverse()?;
    let omega = att * (j_inv * (inv * l));
    Some(Composite {
        mass_kg: mass,
        com_m: com,
        vel_m_s: vel,
        att,
        inertia_kg_m2: j,
        inertia_inv: j_inv,
        momentum_nms: l,
        omega_rad_s: omega,
        offsets_m: offsets,
        rel_att: rel,
    })
}

/// The members' motion relative to the rigid stack at t₀: the largest departure of a member's
/// centre-of-mass velocity from the rigid motion's, m/s, and of its angular velocity from the
/// stack's, rad/s. Both are zero for a stack already moving rigidly.
pub fn residual(members: &[Member], c: &Composite) -> (f64, f64) {
    members.iter().fold((0.0_f64, 0.0_f64), |(dv, dw), m| {
        let rigid = c.vel_m_s + c.omega_rad_s.cross(&(m.pos_m - c.com_m));
        (
            dv.max((m.vel_m_s - rigid).norm()),
            dw.max((m.omega_rad_s - c.omega_rad_s).norm()),
        )
    })
}

/// The members' states after a step of `h_s` of the stack flown as one rigid body (see the
/// module documentation); `accel_m_s2` is the gravity field's acceleration at a world position
/// at the step's end (zero in free space). `None` where [`composite`] is.
pub fn fly(
    members: &[Member],
    accel_m_s2: impl Fn(&Vector3<f64>) -> Vector3<f64>,
    h_s: f64,
) -> Option<Vec<MemberEnd>> {
    let c = composite(members)?;
    let m = c.mass_kg;
    let force: Vector3<f64> = members.iter().map(|k| k.force_n).sum();
    let grav0: Vector3<f64> = members.iter().map(|k| k.gravity_n).sum();
    let torque: Vector3<f64> = members
        .iter()
        .map(|k| k.torque_nm + (k.pos_m - c.com_m).cross(&(k.force_n + k.gravity_n)))
        .sum();
    let (a_c, a_g0) = (force / m, grav0 / m);
    let com1 = c.com_m + c.vel_m_s * h_s + (a_g0 + a_c) * (0.5 * h_s * h_s);
    let (att1, omega1) = rotate_rk4(
        &c.att,
        &c.omega_rad_s,
        &torque,
        &c.inertia_kg_m2,
        &c.inertia_inv,
        h_s,
    );
    let pos1: Vec<Vector3<f64>> = c.offsets_m.iter().map(|o| com1 + att1 * o).collect();
    let a_g1 = members
        .iter()
        .zip(&pos1)
        .map(|(k, x)| accel_m_s2(x) * k.mass_kg)
        .sum::<Vector3<f64>>()
        / m;
    let vel1 = c.vel_m_s + (a_g0 + a_g1) * (0.5 * h_s) + a_c * h_s;
    Some(
        pos1.iter()
            .zip(&c.rel_att)
            .map(|(x, r)| MemberEnd {
                pos_m: *x,
                vel_m_s: vel1 + omega1.cross(&(x - com1)),
                att: UnitQuaternion::new_normalize((att1 * r).into_inner()),
                omega_rad_s: omega1,
            })
            .collect(),
    )
}

#[cfg(test)]
mod tests {
    //! References: conservation of linear and angular momentum and of kinetic energy for a
    //! torque-free stack in free space (exact laws), the rigid relative pose kept exactly, and
    //! the closed form of a spin about a principal axis (angle ω·t).
    use super::*;

    fn member(mass: f64, j: [f64; 3], x: [f64; 3], v: [f64; 3], w: [f64; 3]) -> Member {
        Member {
            mass_kg: mass,
            inertia_kg_m2: Matrix3::from_diagonal(&Vector3::from(j)),
            pos_m: Vector3::from(x),
            vel_m_s: Vector3::from(v),
            att: UnitQuaternion::from_euler_angles(0.1, -0.2, 0.3),
            omega_rad_s: Vector3::from(w),
            force_n: Vector3::zeros(),
            gravity_n: Vector3::zeros(),
            torque_nm: Vector3::zeros(),
        }
    }

    fn as_members(prev: &[Member], ends: &[MemberEnd]) -> Vec<Member> {
        prev.iter()
            .zip(ends)
            .map(|(m, e)| Member {
                pos_m: e.pos_m,
                vel_m_s: e.vel_m_s,
                att: e.att,
                omega_rad_s: e.omega_rad_s,
                ..m.clone()
            })
            .collect()
    }

    fn energy(c: &Composite) -> f64 {
        0.5 * c.mass_kg * c.vel_m_s.norm_squared() + 0.5 * c.omega_rad_s.dot(&c.momentum_nms)
    }

    #[test]
    fn a_torque_free_stack_keeps_its_momenta_energy_and_shape() {
        // Two members moving rigidly together (the second's velocity from the first's
        // rotation), tumbling at about 0.05 rad/s.
        let w = [0.02, -0.03, 0.035];
        let a = member(
            800.0,
            [620.0, 910.0, 1080.0],
            [0.0, 0.0, 0.0],
            [0.01, 0.0, 0.0],
            w,
        );
        let x_b = Vector3::new(1.57, 0.02, -0.01);
        let v_b = Vector3::new(0.01, 0.0, 0.0) + Vector3::from(w).cross(&x_b);
        let mut b = member(300.0, [110.0, 140.0, 160.0], x_b.into(), v_b.into(), w);
        b.att = a.att * UnitQuaternion::from_euler_angles(0.0, 0.0, std::f64::consts::PI);
        let mut ms = vec![a, b];
        let c0 = composite(&ms).expect("stack");
        let (dv, dw) = residual(&ms, &c0);
        assert!(dv < 1e-15 && dw < 1e-15, "{dv} {dw}");
        let sep0 = (ms[0].pos_m - ms[1].pos_m).norm();
        let rel0 = ms[0].att.inverse() * ms[1].att;
        for _ in 0..1000 {
            let ends = fly(&ms, |_| Vector3::zeros(), 0.1).expect("stack");
            ms = as_members(&ms, &ends);
        }
        let c1 = composite(&ms).expect("stack");
        let p = |c: &Composite| c.vel_m_s * c.mass_kg;
        assert!((p(&c1) - p(&c0)).norm() < 1e-12);
        // RK4 conserves L and E to its local error: 1000 steps of 0.005 rad.
        assert!((c1.momentum_nms - c0.momentum_nms).norm() < 1e-9 * c0.momentum_nms.norm());
        assert!((energy(&c1) - energy(&c0)).abs() < 1e-9 * energy(&c0));
        assert!(((ms[0].pos_m - ms[1].pos_m).norm() - sep0).abs() < 1e-12);
        assert!((ms[0].att.inverse() * ms[1].att).angle_to(&rel0) < 1e-12);
        let (dv, dw) = residual(&ms, &c1);
        assert!(dv < 1e-12 && dw < 1e-12, "{dv} {dw}");
    }

    #[test]
    fn a_stack_spinning_about_a_principal_axis_turns_by_omega_t() {
        // Two equal cubes side by side on x, spinning about z through the common centre of
        // mass: a principal axis of the stack, so the spin stays about z at its rate.
        let w = 0.2;
        let j = [10.0, 10.0, 10.0];
        let mut a = member(100.0, j, [-1.0, 0.0, 0.0], [0.0, -w, 0.0], [0.0, 0.0, w]);
        let mut b = member(100.0, j, [1.0, 0.0, 0.0], [0.0, w, 0.0], [0.0, 0.0, w]);
        a.att = UnitQuaternion::identity();
        b.att = UnitQuaternion::identity();
        let mut ms = vec![a, b];
        let (n, h) = (100, 0.05);
        for _ in 0..n {
            let ends = fly(&ms, |_| Vector3::zeros(), h).expect("stack");
            ms = as_members(&ms, &ends);
        }
        let angle = w * h * f64::from(n);
        let expect = Vector3::new(angle.cos(), angle.sin(), 0.0);
        // RK4 on the quaternion kinematics of a constant-rate turn errs by O((ω·h)⁵) a step:
        // 100 steps of 0.01 rad leave a few 1e-12 (measured 4.4e-12).
        assert!((ms[1].pos_m - expect).norm() < 1e-10, "{:?}", ms[1].pos_m);
        assert!((ms[0].pos_m + expect).norm() < 1e-10);
        assert!((ms[1].att.angle() - angle).abs() < 1e-10);
    }

    #[test]
    fn held_forces_move_the_centre_of_mass_exactly_and_load_the_members() {
        // A push of 3 N on one member of a stack at rest: the stack accelerates at 3/M, and
        // the other member is held with m_b·3/M (the latch load), through its centre of mass.
        let mut a = member(200.0, [50.0; 3], [0.0, 0.0, 0.0], [0.0; 3], [0.0; 3]);
        let b = member(100.0, [20.0; 3], [2.0, 0.0, 0.0], [0.0; 3], [0.0; 3]);
        a.force_n = Vector3::new(3.0, 0.0, 0.0);
        let ms = vec![a, b];
        let h = 0.1;
        let ends = fly(&ms, |_| Vector3::zeros(), h).expect("stack");
        let acc = 3.0 / 300.0;
        assert!((ends[0].pos_m.x - 0.5 * acc * h * h).abs() < 1e-15);
        let load_b = (ends[1].vel_m_s - ms[1].vel_m_s) * 100.0 / h;
        assert!((load_b - Vector3::new(100.0 * acc, 0.0, 0.0)).norm() < 1e-12);
    }
}
