//! Local orbital frames of the reference orbit and conversions of relative states.
//!
//! Given the reference's inertial state (r, v) (ECI, m, m/s):
//! - [`LocalFrameKind::Hill`] (RSW / Hill / CW frame): x̂ = r̂ (radial, outward),
//!   ẑ = ĥ = (r×v)/|r×v| (orbit normal), ŷ = ẑ × x̂ (along-track, along v for a circular orbit).
//! - [`LocalFrameKind::LvlhNadir`] (CCSDS LVLH, the target orbital frame of Xu & Hu 2015 and
//!   Guo et al. 2016): ẑ = −r̂ (toward the Earth's centre), ŷ = −ĥ (minus orbit normal),
//!   x̂ = ŷ × ẑ (= Hill ŷ). Hence LVLH (x, y, z) = Hill (y, −z, −x).
//!
//! Both triads rotate with the same angular velocity (expressed in ECI)
//! ω = (|h|/r²) ĥ + (r (a·ĥ)/|h|) r̂, where a is the reference's acceleration (Schaub &
//! Junkins, *Analytical Mechanics of Space Systems*, §14.3). For Keplerian motion a ∥ r and
//! ω = r×v/|r|² exactly ([`frame_rate_eci_rad_s`]); with J2 (or thrust) on the reference the
//! orbit plane turns about r̂ and the exact rate needs a ([`frame_rate_eci_exact_rad_s`]):
//! in LEO the J2 term is ~1e-6 rad/s, ~0.1 % of the orbital rate.
//!
//! Relative states: `pos_world_m` / `vel_world_m_s` are the chaser's position and velocity
//! relative to the reference in the world frame (ECI axes, non-rotating; vel is the inertial
//! derivative of pos). In a local frame L with DCM C (L from ECI):
//! ρ_L = C ρ, ρ̇_L = C (ρ̇ − ω × ρ) (the derivative seen in the rotating frame); back:
//! ρ = Cᵀ ρ_L, ρ̇ = Cᵀ ρ̇_L + ω × ρ.

use crate::orbit::gravity::GravityTerm;
use nalgebra::{Matrix3, Vector3};
use serde::{Deserialize, Serialize};

/// Which local orbital frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum LocalFrameKind {
    /// Hill / RSW: x radial out, y along-track, z orbit normal (the Clohessy–Wiltshire frame).
    Hill,
    /// CCSDS LVLH: z toward the Earth's centre, y = −orbit normal, x completes the triad.
    LvlhNadir,
}

/// DCM from ECI to the Hill frame (rows = Hill unit vectors in ECI), given the reference's
/// ECI position `r_ref_eci_m` and velocity `v_ref_eci_m_s`.
pub fn dcm_hill_from_eci(r_ref_eci_m: &Vector3<f64>, v_ref_eci_m_s: &Vector3<f64>) -> Matrix3<f64> {
    let x = r_ref_eci_m.normalize();
    let z = r_ref_eci_m.cross(v_ref_eci_m_s).normalize();
    let y = z.cross(&x);
    Matrix3::from_rows(&[x.transpose(), y.transpose(), z.transpose()])
}

/// DCM from ECI to the LVLH (nadir-pointing, CCSDS) frame (rows = LVLH unit vectors in ECI).
pub fn dcm_lvlh_from_eci(r_ref_eci_m: &Vector3<f64>, v_ref_eci_m_s: &Vector3<f64>) -> Matrix3<f64> {
    dcm_lvlh_from_hill() * dcm_hill_from_eci(r_ref_eci_m, v_ref_eci_m_s)
}

/// Constant DCM from Hill to LVLH: (x, y, z)_LVLH = (y, −z, −x)_Hill.
pub fn dcm_lvlh_from_hill() -> Matrix3<f64> {
    Matrix3::new(0.0, 1.0, 0.0, 0.0, 0.0, -1.0, -1.0, 0.0, 0.0)
}

/// DCM from ECI to the frame `kind`.
pub fn dcm_frame_from_eci(
    kind: LocalFrameKind,
    r_ref_eci_m: &Vector3<f64>,
    v_ref_eci_m_s: &Vector3<f64>,
) -> Matrix3<f64> {
    match kind {
        LocalFrameKind::Hill => dcm_hill_from_eci(r_ref_eci_m, v_ref_eci_m_s),
        LocalFrameKind::LvlhNadir => dcm_lvlh_from_eci(r_ref_eci_m, v_ref_eci_m_s),
    }
}

/// Angular velocity of the local frames for Keplerian reference motion, ECI, rad/s:
/// ω = r×v/|r|².
pub fn frame_rate_eci_rad_s(
    r_ref_eci_m: &Vector3<f64>,
    v_ref_eci_m_s: &Vector3<f64>,
) -> Vector3<f64> {
    r_ref_eci_m.cross(v_ref_eci_m_s) / r_ref_eci_m.norm_squared()
}

/// Exact angular velocity of the local frames, ECI, rad/s, when the reference accelerates with
/// `a_ref_eci_m_s2` (gravity incl. J2, plus any thrust): ω = r×v/|r|² + (r (a·ĥ)/|h|) r̂.
pub fn frame_rate_eci_exact_rad_s(
    r_ref_eci_m: &Vector3<f64>,
    v_ref_eci_m_s: &Vector3<f64>,
    a_ref_eci_m_s2: &Vector3<f64>,
) -> Vector3<f64> {
    let h = r_ref_eci_m.cross(v_ref_eci_m_s);
    let hn = h.norm();
    let r = r_ref_eci_m.norm();
    h / (r * r) + (a_ref_eci_m_s2.dot(&h) / (hn * hn)) * r_ref_eci_m
}

/// A bound on the Hill frame's angular speed over the interval [t − dt, t + dt] of a reference
/// whose ECI state at t is (`r_eci_m`, `v_eci_m_s`), under the gravity model `gravity`
/// (two-body, optionally J2), rad/s; `None` if the interval is too long for the bound (|r| could reach the Earth's radius).
///
/// Derivation. The Hill frame (x̂ = r̂, ẑ = ĥ) turns at ω = (|h|/r²) ẑ + (r a_h/|h|) x̂, with a_h
/// the acceleration along ĥ (only J2 has one). Over |τ| ≤ dt: the acceleration is at most
/// g = μ(1 + 3 J2 R²/r²)/r² ≤ μ(1 + 3 J2)/r_lo² (|a_J2| ≤ 3 J2 μ R²/r⁴ termwise, R ≤ r), so
/// |v| ≤ v_hi = |v(t)| + g dt and |r| ≥ r_lo = |r(t)| − v_hi dt, |r| ≤ r_hi = |r(t)| + v_hi dt
/// (r_lo: a fixed point, verified). |h| = |r × v| ≤
/// r_hi v_hi; central gravity does not change h and J2 changes it at most at r |a_J2|, so
/// |h| ≥ h_lo = |h(t)| − r_hi a_J2,max dt. Hence |ω| ≤ r_hi v_hi / r_lo² + r_hi a_J2,max / h_lo.
pub fn hill_rate_bound_rad_s(
    r_eci_m: &Vector3<f64>,
    v_eci_m_s: &Vector3<f64>,
    dt_s: f64,
    gravity: &[GravityTerm],
) -> Option<f64> {
    use crate::orbit::constants::{J2_EARTH, MU_EARTH_M3_S2 as MU, R_EARTH_M};
    let (r, v) = (r_eci_m.norm(), v_eci_m_s.norm());
    // Each term's share of the bounds below: the point mass is the 1 in (1 + j2_fac); J2 adds
    // j2_fac to |a| and is the only term with an out-of-plane part (a_J2 below). A new term
    // adds its own bound here.
    let j2_fac = if gravity.contains(&GravityTerm::J2) {
        3.0 * J2_EARTH
    } else {
        0.0
    };
    let mut r_lo = r;
    for _ in 0..4 {
        if r_lo <= R_EARTH_M {
            return None;
        }
        let g = MU * (1.0 + j2_fac) / (r_lo * r_lo);
        r_lo = r - (v + g * dt_s) * dt_s;
    }
    // A little below the iterate, then verified: if |r| ≥ r_lo on the interval, the speed
    // bound v_hi it implies keeps |r| ≥ r − v_hi dt ≥ r_lo (continuity closes the argument).
    r_lo = r - 1.01 * (r - r_lo) - 1e-3;
    if r_lo <= R_EARTH_M {
        return None;
    }
    let g = MU * (1.0 + j2_fac) / (r_lo * r_lo);
    let v_hi = v + g * dt_s;
    if r - v_hi * dt_s < r_lo {
        return None;
    }
    let r_hi = r + v_hi * dt_s;
    let a_j2 = j2_fac * MU * R_EARTH_M * R_EARTH_M / r_lo.powi(4);
    let h_lo = r_eci_m.cross(v_eci_m_s).norm() - r_hi * a_j2 * dt_s;
    if h_lo <= 0.0 {
        return None;
    }
    Some(r_hi * v_hi / (r_lo * r_lo) + r_hi * a_j2 / h_lo)
}

/// A local orbital frame at one instant: its attitude and angular velocity.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LocalFrame {
    /// Which frame.
    pub kind: LocalFrameKind,
    /// DCM mapping ECI (world) components to local-frame components.
    pub dcm_frame_from_eci: Matrix3<f64>,
    /// Angular velocity of the frame relative to ECI, in ECI components, rad/s.
    pub omega_eci_rad_s: Vector3<f64>,
}

impl LocalFrame {
    /// Frame of a reference in Keplerian motion (rate r×v/|r|²).
    pub fn new(
        kind: LocalFrameKind,
        r_ref_eci_m: &Vector3<f64>,
        v_ref_eci_m_s: &Vector3<f64>,
    ) -> Self {
        LocalFrame {
            kind,
            dcm_frame_from_eci: dcm_frame_from_eci(kind, r_ref_eci_m, v_ref_eci_m_s),
            omega_eci_rad_s: frame_rate_eci_rad_s(r_ref_eci_m, v_ref_eci_m_s),
        }
    }

    /// Frame with the exact rate for a reference accelerating with `a_ref_eci_m_s2` (use the
    /// reference's total acceleration, e.g. `ReferenceOrbit::accel_eci_m_s2()` with J2).
    pub fn with_accel(
        kind: LocalFrameKind,
        r_ref_eci_m: &Vector3<f64>,
        v_ref_eci_m_s: &Vector3<f64>,
        a_ref_eci_m_s2: &Vector3<f64>,
    ) -> Self {
        LocalFrame {
            kind,
            dcm_frame_from_eci: dcm_frame_from_eci(kind, r_ref_eci_m, v_ref_eci_m_s),
            omega_eci_rad_s: frame_rate_eci_exact_rad_s(r_ref_eci_m, v_ref_eci_m_s, a_ref_eci_m_s2),
        }
    }

    /// Angular velocity of the frame in its own components, rad/s.
    pub fn omega_frame_rad_s(&self) -> Vector3<f64> {
        self.dcm_frame_from_eci * self.omega_eci_rad_s
    }

    /// Relative state (world = ECI axes, inertial derivative) → local frame:
    /// (C ρ, C (ρ̇ − ω×ρ)), m and m/s.
    pub fn to_local(
        &self,
        pos_world_m: &Vector3<f64>,
        vel_world_m_s: &Vector3<f64>,
    ) -> (Vector3<f64>, Vector3<f64>) {
        let c = &self.dcm_frame_from_eci;
        (
            c * pos_world_m,
            c * (vel_world_m_s - self.omega_eci_rad_s.cross(pos_world_m)),
        )
    }

    /// Local-frame relative state → world (ECI axes, inertial derivative):
    /// (Cᵀ ρ_L, Cᵀ ρ̇_L + ω×ρ), m and m/s.
    pub fn from_local(
        &self,
        pos_local_m: &Vector3<f64>,
        vel_local_m_s: &Vector3<f64>,
    ) -> (Vector3<f64>, Vector3<f64>) {
        let ct = self.dcm_frame_from_eci.transpose();
        let pos = ct * pos_local_m;
        (pos, ct * vel_local_m_s + self.omega_eci_rad_s.cross(&pos))
    }

    /// A world-axes vector (force, acceleration, …; no transport term) in local components.
    pub fn vector_to_local(&self, v_world: &Vector3<f64>) -> Vector3<f64> {
        self.dcm_frame_from_eci * v_world
    }

    /// A local-frame vector in world (ECI) components (no transport term).
    pub fn vector_from_local(&self, v_local: &Vector3<f64>) -> Vector3<f64> {
        self.dcm_frame_from_eci.transpose() * v_local
    }
}

#[cfg(test)]
mod tests {
    //! References: orthonormality/handedness of the triads; the defining directions
    //! (r̂, ĥ); central finite differences of the local-frame position of a deputy whose
    //! inertial motion is exact (closed-form Kepler) or RK8-integrated (with J2).
    use super::*;
    use crate::orbit::constants::MU_EARTH_M3_S2 as MU;
    use crate::orbit::gravity::TWO_BODY_J2;
    use crate::orbit::integrate::ReferenceOrbit;
    use crate::orbit::kepler::{ClassicalElements, kepler_propagate};
    use std::f64::consts::PI;

    fn refs() -> Vec<(Vector3<f64>, Vector3<f64>)> {
        let d = PI / 180.0;
        [
            (6_778_137.0, 0.0, 10.0),
            (7_178_000.0, 0.01, 200.0),
            (21_928_790.0, 0.7, -150.0),
        ]
        .iter()
        .map(|&(a, e, f)| {
            ClassicalElements {
                a_m: a,
                e,
                i_rad: 30.0 * d,
                raan_rad: 60.0 * d,
                argp_rad: 15.0 * d,
                true_anomaly_rad: f * d,
            }
            .to_state(MU)
        })
        .collect()
    }

    /// Both DCMs are proper rotations (CᵀC = I, det = +1 to 1e-15); Hill x̂ = r̂, ẑ = ĥ; LVLH
    /// ẑ = −r̂, ŷ = −ĥ; LVLH = (y, −z, −x) of Hill.
    #[test]
    fn invariant_frames_orthonormal_and_oriented() {
        for (r, v) in refs() {
            let h = r.cross(&v).normalize();
            for kind in [LocalFrameKind::Hill, LocalFrameKind::LvlhNadir] {
                let c = dcm_frame_from_eci(kind, &r, &v);
                assert!((c.transpose() * c - Matrix3::identity()).norm() < 1e-15 * 8.0);
                assert!((c.determinant() - 1.0).abs() < 1e-15 * 4.0);
            }
            let ch = dcm_hill_from_eci(&r, &v);
            let cl = dcm_lvlh_from_eci(&r, &v);
            assert!((ch.row(0).transpose() - r.normalize()).norm() < 1e-15);
            assert!((ch.row(2).transpose() - h).norm() < 1e-15);
            assert!(
                ch.row(1).transpose().dot(&v) > 0.0,
                "Hill y along the velocity side"
            );
            assert!((cl.row(2).transpose() + r.normalize()).norm() < 1e-15);
            assert!((cl.row(1).transpose() + h).norm() < 1e-15);
            let p = Vector3::new(1.0, 2.0, 3.0);
            let ph = ch * p;
            assert!((cl * p - Vector3::new(ph.y, -ph.z, -ph.x)).norm() < 1e-14);
        }
    }

    /// to_local ∘ from_local and from_local ∘ to_local are the identity (1e-15 relative).
    #[test]
    fn invariant_relative_state_round_trip() {
        for (r, v) in refs() {
            let a = Vector3::new(1e-3, -2e-3, 5e-3);
            for frame in [
                LocalFrame::new(LocalFrameKind::Hill, &r, &v),
                LocalFrame::with_accel(LocalFrameKind::LvlhNadir, &r, &v, &a),
            ] {
                let p = Vector3::new(120.0, -35.0, 8.0);
                let w = Vector3::new(0.1, 0.02, -0.3);
                let (pl, wl) = frame.to_local(&p, &w);
                let (p2, w2) = frame.from_local(&pl, &wl);
                assert!((p2 - p).norm() < 1e-14 * p.norm());
                assert!((w2 - w).norm() < 1e-14 * (w.norm() + p.norm() * 1e-3));
                let (p3, w3) =
                    frame.to_local(&frame.from_local(&p, &w).0, &frame.from_local(&p, &w).1);
                assert!((p3 - p).norm() < 1e-14 * p.norm() && (w3 - w).norm() < 1e-14 * 2.0);
            }
        }
    }

    /// Velocity transport, two-body: the local-frame velocity from `to_local` equals the
    /// central finite difference of the local-frame position of a deputy, both orbits
    /// propagated exactly (closed form). Step h = 0.05 s: truncation h²/6·|d³ρ_L/dt³|
    /// (≲ 1e-10 m/s here) and rounding ~ulp(7e6 m)/h ≈ 2e-8 m/s: tolerance 1e-7 m/s.
    #[test]
    fn val_velocity_transport_vs_finite_difference() {
        for (r0, v0) in refs() {
            // Deputy 400 m away (all axes) with 0.3 m/s relative velocity, in Hill terms.
            let (rho, rhod) = LocalFrame::new(LocalFrameKind::Hill, &r0, &v0).from_local(
                &Vector3::new(200.0, -300.0, 150.0),
                &Vector3::new(0.1, 0.2, -0.2),
            );
            let (rd0, vd0) = (r0 + rho, v0 + rhod);
            for kind in [LocalFrameKind::Hill, LocalFrameKind::LvlhNadir] {
                for &t in &[0.0, 700.0] {
                    let h = 0.05;
                    let local_pos = |tt: f64| {
                        let (rr, vr) = kepler_propagate(&r0, &v0, tt, MU);
                        let (rd, _) = kepler_propagate(&rd0, &vd0, tt, MU);
                        LocalFrame::new(kind, &rr, &vr)
                            .to_local(&(rd - rr), &Vector3::zeros())
                            .0
                    };
                    let fd = (local_pos(t + h) - local_pos(t - h)) / (2.0 * h);
                    let (rr, vr) = kepler_propagate(&r0, &v0, t, MU);
                    let (rd, vd) = kepler_propagate(&rd0, &vd0, t, MU);
                    let (_, vl) = LocalFrame::new(kind, &rr, &vr).to_local(&(rd - rr), &(vd - vr));
                    assert!(
                        (vl - fd).norm() < 1e-7,
                        "{kind:?} t {t}: {:e}",
                        (vl - fd).norm()
                    );
                }
            }
        }
    }

    /// With J2 on the reference the orbit plane turns about r̂: the exact frame rate
    /// (`with_accel`) matches finite differences of RK8-propagated states (tolerance 1e-7 m/s
    /// as above, plus RK8 rounding), while the Keplerian rate is off by |ω_x ρ| ≈ 1e-6 rad/s ×
    /// 1 km ≈ 1e-3 m/s, which this test must detect.
    #[test]
    fn val_velocity_transport_with_j2_needs_exact_rate() {
        let (r0, v0) = refs()[0];
        let rho = Vector3::new(300.0, -600.0, 700.0);
        let rhod = Vector3::new(0.3, 0.1, -0.4);
        let mut reference = ReferenceOrbit::from_state(r0, v0, TWO_BODY_J2);
        let mut deputy = ReferenceOrbit::from_state(r0 + rho, v0 + rhod, TWO_BODY_J2);
        // Go to the node region where the normal J2 acceleration is large: t = 1500 s.
        reference.step(1500.0);
        deputy.step(1500.0);
        let h = 0.05;
        let local_pos = |dt: f64| {
            let mut a = reference.clone();
            let mut b = deputy.clone();
            a.step(dt);
            b.step(dt);
            let f = LocalFrame::new(LocalFrameKind::Hill, &a.pos_eci_m(), &a.vel_eci_m_s());
            f.to_local(&(b.pos_eci_m() - a.pos_eci_m()), &Vector3::zeros())
                .0
        };
        let fd = (local_pos(h) - local_pos(-h)) / (2.0 * h);
        let (rr, vr) = reference.state();
        let rel = (deputy.pos_eci_m() - rr, deputy.vel_eci_m_s() - vr);
        let exact =
            LocalFrame::with_accel(LocalFrameKind::Hill, &rr, &vr, &reference.accel_eci_m_s2());
        let kepl = LocalFrame::new(LocalFrameKind::Hill, &rr, &vr);
        let err_exact = (exact.to_local(&rel.0, &rel.1).1 - fd).norm();
        let err_kepl = (kepl.to_local(&rel.0, &rel.1).1 - fd).norm();
        eprintln!(
            "J2 transport: exact-rate error {err_exact:e} m/s, Keplerian-rate error {err_kepl:e} m/s, ω_x {:e} rad/s",
            exact.omega_frame_rad_s().x
        );
        assert!(err_exact < 1e-7, "{err_exact:e}");
        assert!(err_kepl > 100.0 * err_exact);
    }

    /// For a circular Keplerian orbit the frame rate is n along the orbit normal (Hill +z,
    /// LVLH −y), n = √(μ/r³), to 1e-15 relative.
    #[test]
    fn invariant_frame_rate_circular() {
        let (r, v) = refs()[0];
        let n = (MU / r.norm().powi(3)).sqrt();
        let fh = LocalFrame::new(LocalFrameKind::Hill, &r, &v).omega_frame_rad_s();
        let fl = LocalFrame::new(LocalFrameKind::LvlhNadir, &r, &v).omega_frame_rad_s();
        assert!((fh - Vector3::new(0.0, 0.0, n)).norm() < 1e-15 * n * 4.0);
        assert!((fl - Vector3::new(0.0, -n, 0.0)).norm() < 1e-15 * n * 4.0);
    }
}
