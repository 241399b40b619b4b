//! Plume keep-off: does a firing jet's plume cone touch the listed parts of another body?
//! Judged on the full geometry (every part's judged shape: primitives, and triangle meshes
//! for mesh parts) with parry's exact `Cone` (a support map, no polygon).
//!
//! A jet's plume ([`crate::actuation::rcs::PlumeSpec`]) is the solid cone with its apex at
//! the nozzle, its axis the exhaust direction (−thrust), half-angle α and length L: parry's
//! `Cone` with half-height L/2 and base radius L·tan α, its apex (local +y) at the nozzle.
//!
//! This is the self-contained check (a function of the poses at one instant). It is not yet a
//! scene guarantee: the open guarantee registry (issue 27) is being built on another branch;
//! `PlumeKeepOff(name, body, around, parts: [...])` is to be registered there, calling
//! [`plume_hits`] on the firing jets each step (see `docs/vehicles.md`).

use super::monitor::shape_distance;
use crate::actuation::rcs::{JetSpec, plume_cone};
use bevy_rapier3d::rapier::prelude as rp;
use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};

/// The plume cone as a parry shape and its pose in the frame its apex and axis are given in.
pub fn plume_shape(
    apex: &Vector3<f64>,
    axis: &Vector3<f64>,
    half_angle_rad: f64,
    length_m: f64,
) -> (rp::SharedShape, Isometry3<f64>) {
    let shape = rp::SharedShape::cone(
        (length_m / 2.0) as f32,
        (length_m * half_angle_rad.tan()) as f32,
    );
    let a = axis.normalize();
    // Local +y (the apex side) onto −axis, so the cone opens along the exhaust.
    let rot = UnitQuaternion::rotation_between(&Vector3::y(), &-a).unwrap_or_else(|| {
        UnitQuaternion::from_axis_angle(&Vector3::x_axis(), std::f64::consts::PI)
    });
    let pose = Isometry3::from_parts(Translation3::from(apex + a * (length_m / 2.0)), rot);
    (shape, pose)
}

/// A plume touching a part.
#[derive(Debug, Clone, PartialEq)]
pub struct PlumeHit {
    /// The jet.
    pub jet: String,
    /// The part struck (`body/collider`).
    pub part: String,
}

/// `*` matches any run of characters (none included); everything else literally.
pub fn glob_match(pattern: &str, name: &str) -> bool {
    let (p, n) = (pattern.as_bytes(), name.as_bytes());
    let (mut i, mut j, mut star, mut mark) = (0, 0, None, 0);
    while j < n.len() {
        if i < p.len() && p[i] == b'*' {
            star = Some(i);
            mark = j;
            i += 1;
        } else if i < p.len() && p[i] == n[j] {
            i += 1;
            j += 1;
        } else if let Some(s) = star {
            i = s + 1;
            mark += 1;
            j = mark;
        } else {
            return false;
        }
    }
    p[i..].iter().all(|c| *c == b'*')
}

/// The clearance between one jet's plume and a part, m (0 when they touch).
/// `jet_frame` is the pose of the frame the jet's position and direction are written in (the
/// firing body's centre-of-mass frame), `part_pose` the part's pose, both in one frame.
pub fn plume_clearance(
    jet: &JetSpec,
    jet_frame: &Isometry3<f64>,
    part_pose: &Isometry3<f64>,
    part: &dyn rp::Shape,
) -> Option<f64> {
    let (apex, axis, alpha, len) = plume_cone(jet)?;
    let (cone, pose) = plume_shape(&apex, &axis, alpha, len);
    Some(shape_distance(&(jet_frame * pose), &*cone, part_pose, part))
}

/// Every (firing jet, listed part) whose plume touches the part. `parts` are the other body's
/// colliders (`body/collider` name, pose, judged shape) in the same frame as `jet_frame`;
/// `patterns` select them by name (globs).
pub fn plume_hits(
    jets: &[JetSpec],
    firing: &[bool],
    jet_frame: &Isometry3<f64>,
    parts: &[(String, Isometry3<f64>, rp::SharedShape)],
    patterns: &[String],
) -> Vec<PlumeHit> {
    let mut out = Vec::new();
    for (j, on) in jets.iter().zip(firing) {
        if !on {
            continue;
        }
        for (name, pose, shape) in parts {
            if !patterns.iter().any(|p| glob_match(p, name)) {
                continue;
            }
            if plume_clearance(j, jet_frame, pose, &**shape).is_some_and(|d| d <= 0.0) {
                out.push(PlumeHit {
                    jet: j.name.clone(),
                    part: name.clone(),
                });
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    //! Reference: the analytic cone-to-box test. A cone with apex at the origin, axis +x,
    //! half-angle α, length L, and an axis-aligned box whose near face is the plane x = s
    //! (0 < s < L) spanning y ∈ [y₀, y₁], z ∈ [z₀, z₁], depth D: the cone's cross-section at
    //! x is the disc of radius x·tan α, widest inside the box at x_m = min(L, s + D); the box
    //! is struck iff the distance ρ from the axis to the rectangle [y₀, y₁] × [z₀, z₁] is below
    //! x_m·tan α (strict: touching at a point is a hit at distance 0, tested away from it by
    //! 1 mm either side); the clearance of a miss is dy·cos α, to GJK's tolerance on the cone's
    //! curved surface (1.5e-4 m at 10 m).
    use super::*;
    use crate::actuation::rcs::PlumeSpec;

    fn jet(alpha_deg: f64, len: f64) -> JetSpec {
        // Thrust along −x: the plume points along +x from the origin.
        JetSpec {
            name: "j1".into(),
            pos_m: [0.0, 0.0, 0.0],
            direction: [-1.0, 0.0, 0.0],
            max_thrust_n: 1.0,
            min_impulse_bit_ns: 0.0,
            plume: Some(PlumeSpec {
                half_angle_deg: alpha_deg,
                length_m: len,
            }),
        }
    }

    fn box_part(
        s: f64,
        depth: f64,
        y: (f64, f64),
        z: (f64, f64),
    ) -> (Isometry3<f64>, rp::SharedShape) {
        let half = Vector3::new(depth / 2.0, (y.1 - y.0) / 2.0, (z.1 - z.0) / 2.0);
        let c = Vector3::new(s + depth / 2.0, (y.0 + y.1) / 2.0, (z.0 + z.1) / 2.0);
        (
            Isometry3::translation(c.x, c.y, c.z),
            rp::SharedShape::cuboid(half.x as f32, half.y as f32, half.z as f32),
        )
    }

    #[test]
    fn val_plume_cone_to_box_hit_and_miss_match_the_closed_form() {
        let (alpha, len) = (15.0f64, 10.0);
        let j = jet(alpha, len);
        let t = alpha.to_radians().tan();
        let id = Isometry3::identity();
        for (s, depth) in [(2.0f64, 0.5), (6.0, 1.0), (9.5, 2.0)] {
            let xm = (s + depth).min(len);
            let rho = xm * t;
            for (dy, hit) in [(-1e-3, true), (1e-3, false)] {
                // A panel beside the axis: its edge nearest the axis at y = ρ + dy.
                let (pose, shape) = box_part(s, depth, (rho + dy, rho + dy + 1.0), (-0.5, 0.5));
                let d = plume_clearance(&j, &id, &pose, &*shape).unwrap();
                assert_eq!(
                    d <= 0.0,
                    hit,
                    "s {s}, edge at {} (ρ {rho}): clearance {d}",
                    rho + dy
                );
                if !hit {
                    // The gap to the cone's wall at x_m: dy·cos α. GJK on the cone's curved
                    // surface stops at ~1e-5 of the shapes' size (10 m here): 1.5e-4 m.
                    assert!(
                        (d - dy * alpha.to_radians().cos()).abs() < 1.5e-4,
                        "s {s}: {d}"
                    );
                }
            }
        }
        // Beyond the plume's length: no hit even on the axis.
        let (pose, shape) = box_part(len + 1e-3, 1.0, (-0.5, 0.5), (-0.5, 0.5));
        assert!(plume_clearance(&j, &id, &pose, &*shape).unwrap() > 0.0);
        // Behind the nozzle: no hit.
        let (pose, shape) = box_part(-2.0, 1.0, (-0.5, 0.5), (-0.5, 0.5));
        assert!(plume_clearance(&j, &id, &pose, &*shape).unwrap() > 0.0);
    }

    #[test]
    fn val_plume_hits_name_jet_and_part_and_follow_globs() {
        let j = jet(10.0, 5.0);
        let (pose, shape) = box_part(2.0, 0.1, (-0.5, 0.5), (-0.5, 0.5));
        let parts = vec![
            ("target/solar_array_py_2".to_string(), pose, shape.clone()),
            (
                "target/bus".to_string(),
                Isometry3::translation(0.0, 5.0, 0.0),
                shape,
            ),
        ];
        let pats = vec!["target/solar_array_*".to_string()];
        let hits = plume_hits(
            std::slice::from_ref(&j),
            &[true],
            &Isometry3::identity(),
            &parts,
            &pats,
        );
        assert_eq!(
            hits,
            vec![PlumeHit {
                jet: "j1".into(),
                part: "target/solar_array_py_2".into()
            }]
        );
        assert!(
            plume_hits(
                std::slice::from_ref(&j),
                &[false],
                &Isometry3::identity(),
                &parts,
                &pats
            )
            .is_empty()
        );
        assert!(glob_match("*", "x") && glob_match("a*c", "abbc") && !glob_match("a*c", "abd"));
    }
}
