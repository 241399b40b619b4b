//! The single-instant plume check on triangle-mesh parts (`sim::plume::plume_clearance`,
//! `plume_hits`) through the monitor's shell and hull brackets, as `PlumeKeepOff` judges them.
//!
//! References:
//! * the analytic cone-to-box test (as in `sim::plume`'s unit tests): a cone with apex at the
//!   origin, axis +x, half-angle α, length L, and a box whose near face is the plane x = s,
//!   spanning y ∈ [y₀, y₀ + 1], z ∈ [−½, ½], depth D, is struck iff y₀ < x_m·tan α with
//!   x_m = min(L, s + D); a miss's clearance is (y₀ − x_m·tan α)·cos α. Here the box is a
//!   tessellated mesh of it (welded, closed), judged through its hull;
//! * the triangle path: the same part without its hull support map, judged by parry's exact
//!   triangle-mesh query alone (what `plume_clearance` did before; an independent
//!   implementation: parry's BVH and per-triangle GJK), on random plume poses about a box
//!   mesh, a sphere mesh and a concave U prism.
//!
//! Tolerances: the analytic clearance within parry's f32 GJK error against the plume pyramid
//! (4e-4 m for 10 m shapes, `tests/val_plume.rs`) plus the pyramid's excess over the cone
//! (7.6e-5 of the section's radius) plus an exact mesh query's relative precision
//! (`monitor::GJK_REL_TOL` of the distance). Against the triangle path: each path is within
//! GJK_REL_TOL of the distance plus 8 f32 ulps of the pair's scale (`monitor::F32_REL_TOL`),
//! so the two agree within twice that; a pair the triangle path finds touching is a hit on the
//! bracket path (its certified lower bound is 0), and verdicts agree wherever the clearance is
//! beyond that band.

mod common;

use bevy_rapier3d::rapier::math::Vector;
use bevy_rapier3d::rapier::prelude as rp;
use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};
use rpod::actuation::rcs::{JetSpec, PlumeSpec};
use rpod::bench::meshes::{tessellated_box, uv_sphere};
use rpod::math::rng::Lcg;
use rpod::sim::monitor::{F32_REL_TOL, GJK_REL_TOL};
use rpod::sim::plume::{
    PlumeHit, PlumeTarget, plume_clearance, plume_clearance_bracket, plume_hits,
    plume_shape_radius_m,
};

fn v32(p: &[f64; 3]) -> Vector {
    Vector::new(p[0] as f32, p[1] as f32, p[2] as f32)
}

fn trimesh(v: &[[f64; 3]], t: &[[u32; 3]]) -> (rp::SharedShape, f64) {
    let r = v
        .iter()
        .map(|p| Vector3::from(*p).norm())
        .fold(0.0, f64::max)
        * (1.0 + 1e-6);
    (
        rp::SharedShape::trimesh(v.iter().map(v32).collect(), t.to_vec()).expect("mesh"),
        r,
    )
}

/// A jet at `pos` exhausting along `exhaust` (thrust opposite), its plume α (deg), L (m).
fn jet(pos: Vector3<f64>, exhaust: Vector3<f64>, alpha_deg: f64, len: f64) -> JetSpec {
    let d = -exhaust.normalize();
    JetSpec {
        name: "j1".into(),
        pos_m: [pos.x, pos.y, pos.z],
        direction: [d.x, d.y, d.z],
        max_thrust_n: 1.0,
        min_impulse_bit_ns: 0.0,
        plume: Some(PlumeSpec {
            half_angle_deg: alpha_deg,
            length_m: len,
        }),
    }
}

/// The U prism of `val_mesh` (slot x ∈ [−½, ½], y ∈ [½, 2], z ∈ [−½, ½]).
fn u_prism() -> (Vec<[f64; 3]>, Vec<[u32; 3]>) {
    let o = [
        (-1.5, 0.0),
        (1.5, 0.0),
        (1.5, 2.0),
        (0.5, 2.0),
        (0.5, 0.5),
        (-0.5, 0.5),
        (-0.5, 2.0),
        (-1.5, 2.0),
    ];
    let cap = [
        [0, 1, 4],
        [0, 4, 5],
        [1, 2, 3],
        [1, 3, 4],
        [5, 6, 7],
        [5, 7, 0],
    ];
    common::closed_prism(&o, &cap)
}

#[test]
fn val_plume_mesh_cone_to_box_mesh_hit_and_miss_match_the_closed_form() {
    let (alpha, len) = (15.0f64, 10.0);
    let j = jet(Vector3::zeros(), Vector3::x(), alpha, len);
    let t = alpha.to_radians().tan();
    let id = Isometry3::identity();
    for (s, depth) in [(2.0f64, 0.5), (6.0, 1.0), (9.5, 2.0)] {
        let xm = (s + depth).min(len);
        let rho = xm * t;
        // 1 cm cells over the depth, 2 cm over the face.
        let cells = [(depth * 100.0) as usize, 50, 50];
        let (v, tri) = tessellated_box([depth, 1.0, 1.0], cells);
        let (mesh, _) = trimesh(&v, &tri);
        for (dy, hit) in [(-1e-3, true), (1e-3, false)] {
            let y0 = rho + dy;
            let pose = Isometry3::translation(s + depth / 2.0, y0 + 0.5, 0.0);
            let part = PlumeTarget::new("target/panel", pose, mesh.clone());
            assert!(part.hull.is_some(), "a mesh part carries its hull");
            let b = plume_clearance_bracket(&j, &id, &pose, &*mesh, part.hull.as_deref())
                .expect("a plume");
            let hits = plume_hits(
                std::slice::from_ref(&j),
                &[true],
                &id,
                std::slice::from_ref(&part),
                &["target/*".to_string()],
            );
            let what = format!("s {s}, edge at {y0} (ρ {rho}): {b:?}");
            assert_eq!(!hits.is_empty(), hit, "{what}");
            assert_eq!(b.lower <= 0.0, hit, "{what}");
            if hit {
                assert_eq!(
                    hits,
                    vec![PlumeHit {
                        jet: "j1".into(),
                        part: "target/panel".into()
                    }]
                );
            } else {
                let want = dy * alpha.to_radians().cos();
                assert!(
                    (b.value - want).abs() < 4e-4 + 7.6e-5 * rho + GJK_REL_TOL * want,
                    "{what}"
                );
                assert!(b.lower <= want + 4e-4, "{what}");
            }
        }
    }
}

#[test]
fn val_plume_mesh_clearance_matches_the_triangle_path() {
    let (bv, bt) = tessellated_box([2.0, 2.0, 1.5], [40, 40, 30]);
    let (sv, st) = uv_sphere(1.0, 64, 128);
    let (uv, ut) = u_prism();
    let mut rng = Lcg(2026);
    let id = Isometry3::identity();
    let (mut hits, mut misses, mut near) = (0, 0, 0);
    for (name, v, t) in [("box", bv, bt), ("sphere", sv, st), ("U", uv, ut)] {
        let (mesh, rb) = trimesh(&v, &t);
        let with = PlumeTarget::new("target/part", Isometry3::identity(), mesh.clone());
        let hull = with.hull.clone().expect("a mesh");
        for k in 0..120 {
            // The part at a random pose; the nozzle 0.3–15 m from its centre, the plume aimed
            // within 40° of the centre (half of them at the U's slot mouth, its concavity).
            let centre = rng.vec3(3.0);
            let q = UnitQuaternion::from_scaled_axis(rng.vec3(3.0));
            let pose = Isometry3::from_parts(Translation3::from(centre), q);
            let aim = if name == "U" && k % 2 == 0 {
                pose * nalgebra::Point3::new(0.0, 1.5, 0.0)
            } else {
                nalgebra::Point3::from(centre)
            };
            let dist = 0.3 + 14.7 * rng.uniform();
            let nozzle = aim.coords + rng.vec3(1.0).normalize() * (rb + dist);
            let off = UnitQuaternion::from_scaled_axis(rng.vec3(40f64.to_radians()));
            let exhaust = off * (aim.coords - nozzle).normalize();
            let alpha = [5.0, 15.0, 30.0][k % 3];
            let len = [3.0, 10.0][k % 2];
            let j = jet(nozzle, exhaust, alpha, len);
            let tri = plume_clearance_bracket(&j, &id, &pose, &*mesh, None).expect("plume");
            let br = plume_clearance_bracket(&j, &id, &pose, &*mesh, Some(&hull)).expect("plume");
            let ra = plume_shape_radius_m(alpha.to_radians(), len);
            let apex_to_centre = nozzle + exhaust * (len / 2.0) - centre;
            let eps = F32_REL_TOL * (apex_to_centre.norm() + ra + rb);
            let band = 2.0 * (GJK_REL_TOL * tri.value + eps);
            let what = format!("{name} #{k}: triangles {tri:?}, bracket {br:?}");
            assert!((br.value - tri.value).abs() <= band, "{what}");
            assert!(br.lower <= tri.value + eps, "{what}");
            assert_eq!(
                plume_clearance(&j, &id, &pose, &*mesh, Some(&hull)),
                Some(br.value)
            );
            let as_target = |hull| PlumeTarget {
                name: "target/part".into(),
                pose,
                shape: mesh.clone(),
                hull,
            };
            let hit = |target: PlumeTarget| {
                !plume_hits(
                    std::slice::from_ref(&j),
                    &[true],
                    &id,
                    &[target],
                    &["*".into()],
                )
                .is_empty()
            };
            let (hit_br, hit_tri) = (hit(as_target(Some(hull.clone()))), hit(as_target(None)));
            if tri.value <= 0.0 {
                assert!(hit_br, "{what}: a touch the triangles see is a hit");
                hits += 1;
            } else if tri.value > band {
                assert_eq!(hit_br, hit_tri, "{what}");
                assert!(!hit_br, "{what}");
                misses += 1;
            } else {
                near += 1;
            }
        }
    }
    eprintln!("hits {hits}, misses {misses}, within the band {near}");
    // Both verdicts exercised on every shape's poses taken together; few in the band.
    assert!(
        hits >= 40 && misses >= 100 && near <= 10,
        "{hits} {misses} {near}"
    );
}
