//! The monitor's convex-hull bracket of a mesh part's distance (the mesh speed goals of docs/performance.md) is
//! sound, is exact where the hull is, and hands over to the exact triangle-mesh query where it
//! is not.
//!
//! References (closed forms, computed here in f64):
//! * the support of a point set in a direction n is max over the points of n·v — a brute-force
//!   scan of every vertex (`HullSupport`'s tree must return a vertex reaching it);
//! * point to axis-aligned box: |p − clamp(p, box)|; a ball of radius r centred at p is that
//!   less r; a convex body above a box's top face whose lowest point (a cube's lowest corner,
//!   from its rotation matrix) lies over the face is at (that point's height − the top);
//! * a latitude–longitude sphere mesh is inscribed in its sphere with a vertex at each pole and
//!   on the ±x axis, so a ball centred on such an axis at D from the centre is at D − R − r;
//! * a U-shaped prism (slot half-width w = 0.5 m, arms' tops at y = 2 m): a ball in the slot is
//!   at w − r (its hull would contain the ball); a ball centred at height h above the mouth's
//!   centre is at √(w² + h²) − r from the arms' inner top edges, while the hull's top is only
//!   h − r away — the hull is not exact there and the exact query must answer;
//! * a ball centred inside a closed box mesh is at (the smallest half-extent − r) from its
//!   triangles (the monitor judges the mesh's surface, as parry's `TriMesh` does).
//!
//! Tolerances: parry works in f32 — a value is within 8 f32 ulps of the pose's scale
//! (|Δc| + both bounding radii: `monitor::F32_REL_TOL`) of the true distance, and an exact mesh
//! query's GJK stops at 1.2e-3 of the distance (`monitor::GJK_REL_TOL`); a bracket from the
//! hull must be at least as narrow. Every certified lower bound must be at or below the
//! closed form, with no tolerance.

mod common;

use bevy_rapier3d::rapier::math::Vector;
use bevy_rapier3d::rapier::prelude as rp;
use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};
use rpod::bench::meshes::{tessellated_box, uv_sphere};
use rpod::math::rng::Lcg;
use rpod::sim::mesh::HullSupport;
use rpod::sim::monitor::{
    self, F32_REL_TOL, GJK_REL_TOL, HullEval, MonitorGeometry, PairEval, PartPiece, QueryCount,
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

/// The U prism of `val_mesh`: outline (x, y) counter-clockwise, extruded over z ∈ [−½, ½];
/// the slot x ∈ [−½, ½], y ∈ [½, 2].
fn u_prism() -> (Vec<[f64; 3]>, Vec<[u32; 3]>) {
    let o = [
        (-1.5, 0.0),
        (1.5, 0.0),
        (1.5, 0.5),
        (1.5, 2.0),
        (0.5, 2.0),
        (0.5, 0.5),
        (-0.5, 0.5),
        (-0.5, 2.0),
        (-1.5, 2.0),
        (-1.5, 0.5),
    ];
    let cap = [
        [0, 1, 2],
        [0, 2, 5],
        [0, 5, 6],
        [0, 6, 9],
        [5, 2, 3],
        [5, 3, 4],
        [9, 6, 7],
        [9, 7, 8],
    ];
    common::closed_prism(&o, &cap)
}

fn iso(p: Vector3<f64>, q: UnitQuaternion<f64>) -> Isometry3<f64> {
    Isometry3::from_parts(Translation3::from(p), q)
}

/// The hull bracket and the monitor's evaluation of part 0 of body 0 at `pa` and part 0 of
/// body 1 at `pb`, with the tolerance of an exact value (GJK's and f32's).
fn evaluate(
    g: &MonitorGeometry,
    pa: &Isometry3<f64>,
    pb: &Isometry3<f64>,
) -> (HullEval, f64, f64, f64) {
    let (ra, rb) = (g.radius[0][0], g.radius[1][0]);
    let hull = monitor::hull_bracket(
        pa,
        (&*g.shapes[0][0], g.hull(0, 0), ra),
        pb,
        (&*g.shapes[1][0], g.hull(1, 0), rb),
        f64::INFINITY,
    );
    let PairEval::Value(value, lower) =
        monitor::pair_eval(g, 0, 0, &(*pa, ra), 1, 0, &(*pb, rb), f64::INFINITY)
    else {
        panic!("nothing clears an infinite level");
    };
    let eps = F32_REL_TOL * ((pa.translation.vector - pb.translation.vector).norm() + ra + rb);
    (hull, value, lower, eps)
}

/// The hull answered alone: its bracket is as narrow as an exact query's.
fn hull_was_exact(h: HullEval, eps: f64) -> bool {
    matches!(h, HullEval::Bracket { lower, upper } if lower >= upper * (1.0 - GJK_REL_TOL) - eps)
}

/// Checks a mesh pair's evaluation against the closed form `d` (see the header).
fn check(g: &MonitorGeometry, pa: &Isometry3<f64>, pb: &Isometry3<f64>, d: f64, what: &str) {
    let (_, value, lower, eps) = evaluate(g, pa, pb);
    assert!(lower <= d, "{what}: lower {lower} above the distance {d}");
    assert!(
        (value - d).abs() <= GJK_REL_TOL * d + eps,
        "{what}: value {value} vs {d}"
    );
    assert!(value - lower <= GJK_REL_TOL * value + 2.0 * eps, "{what}");
}

fn point_box_distance(p: Vector3<f64>, half: Vector3<f64>) -> f64 {
    (p - p.zip_map(&half, |x, h| x.clamp(-h, h))).norm()
}

#[test]
fn val_mesh_hull_support_is_the_brute_force_maximum() {
    let (sv, st) = uv_sphere(1.0, 126, 400);
    let (bv, bt) = tessellated_box([2.0, 2.0, 1.5], [100, 100, 75]);
    let (uv, ut) = u_prism();
    let mut rng = Lcg(7);
    for (name, v, t) in [("sphere", sv, st), ("box", bv, bt), ("U", uv, ut)] {
        let pts: Vec<Vector> = v.iter().map(v32).collect();
        let h = HullSupport::new(&pts).expect("hull");
        assert_eq!(h.len(), v.len());
        let _ = t;
        let mut dirs: Vec<Vector3<f64>> = vec![
            Vector3::x(),
            -Vector3::x(),
            Vector3::y(),
            -Vector3::y(),
            Vector3::z(),
            -Vector3::z(),
            Vector3::new(1.0, 1.0, 1.0),
            Vector3::new(1e-9, -2e-9, 1.0),
        ];
        dirs.extend((0..500).map(|_| rng.vec3(1.0)));
        for d in dirs {
            // The direction as parry hands it (f32), evaluated in f64.
            let d32 = Vector3::new(d.x as f32, d.y as f32, d.z as f32).cast::<f64>();
            let brute = pts
                .iter()
                .map(|p| d32.dot(&Vector3::new(p.x, p.y, p.z).cast::<f64>()))
                .fold(f64::NEG_INFINITY, f64::max);
            let s = h.support_f64(&d32);
            assert_eq!(d32.dot(&s), brute, "{name}: {d:?}");
            let s32 = bevy_rapier3d::parry::shape::SupportMap::local_support_point(
                &h,
                Vector::new(d.x as f32, d.y as f32, d.z as f32),
            );
            assert_eq!(
                d32.dot(&Vector3::new(s32.x, s32.y, s32.z).cast::<f64>()),
                brute
            );
        }
    }
}

#[test]
fn val_mesh_hull_box_mesh_is_exact_against_primitives() {
    // The fly-by target: 2 × 2 × 1.5 m, 100 000 triangles.
    let half = Vector3::new(1.0, 1.0, 0.75);
    let (v, t) = tessellated_box([2.0, 2.0, 1.5], [100, 100, 75]);
    let mesh = trimesh(&v, &t);
    let r = 0.3;
    let ball = (rp::SharedShape::ball(r as f32), r);
    let g = common::one_part_bodies(&[&mesh, &ball]);
    let at = Isometry3::identity();
    for c in [20.0, 1.9, 0.05] {
        for p in [
            Vector3::new(0.2, 0.1, 0.75 + c + r),
            Vector3::new(1.0 + c + r, -0.3, 0.2),
            Vector3::new(1.3 + c, 1.2 + c, 0.9 + c),
        ] {
            let d = point_box_distance(p, half) - r;
            let pb = iso(p, UnitQuaternion::identity());
            let (h, _, _, eps) = evaluate(&g, &at, &pb);
            assert!(hull_was_exact(h, eps), "ball at {p:?}: {h:?}");
            check(&g, &at, &pb, d, &format!("ball at {p:?}"));
        }
    }
    // The fly-by chaser: a 1 m cube at yaw 30°, pitch 20°, roll 10°, its lowest corner c above
    // the top, over the face; the cube on either side (mesh first, then second).
    let cube = (rp::SharedShape::cuboid(0.5, 0.5, 0.5), 0.5 * 3f64.sqrt());
    let q = UnitQuaternion::from_euler_angles(
        10f64.to_radians(),
        20f64.to_radians(),
        30f64.to_radians(),
    );
    let lowest = (0..8)
        .map(|k| {
            let s = |b: usize| if k & b == 0 { -0.5 } else { 0.5 };
            (q * Vector3::new(s(1), s(2), s(4))).z
        })
        .fold(f64::INFINITY, f64::min);
    for (mesh_first, g) in [
        (true, common::one_part_bodies(&[&mesh, &cube])),
        (false, common::one_part_bodies(&[&cube, &mesh])),
    ] {
        for c in [20.0, 1.9, 0.01] {
            let p = Vector3::new(0.3, -0.2, 0.75 + c - lowest);
            let (pa, pb) = if mesh_first {
                (at, iso(p, q))
            } else {
                (iso(p, q), at)
            };
            let (h, _, _, eps) = evaluate(&g, &pa, &pb);
            assert!(hull_was_exact(h, eps), "cube {c} m: {h:?}");
            check(&g, &pa, &pb, c, &format!("cube {c} m above"));
        }
    }
    // Two box meshes, one above the other, 0.4 m apart (the hulls on both sides).
    let small = tessellated_box([1.0, 1.0, 1.0], [10, 10, 10]);
    let small = trimesh(&small.0, &small.1);
    let g = common::one_part_bodies(&[&mesh, &small]);
    let pb = iso(
        Vector3::new(0.6, 0.1, 0.75 + 0.4 + 0.5),
        UnitQuaternion::identity(),
    );
    let (h, _, _, eps) = evaluate(&g, &at, &pb);
    assert!(hull_was_exact(h, eps), "mesh on mesh: {h:?}");
    check(&g, &at, &pb, 0.4, "mesh above mesh");
}

#[test]
fn val_mesh_hull_sphere_mesh_is_exact_at_its_vertices() {
    // The fly-by sphere: 1 m, 100 000 triangles, inscribed, vertices at the poles and on ±x.
    let (v, t) = uv_sphere(1.0, 126, 400);
    let mesh = trimesh(&v, &t);
    let r = 0.25;
    let ball = (rp::SharedShape::ball(r as f32), r);
    let g = common::one_part_bodies(&[&mesh, &ball]);
    let at = Isometry3::identity();
    for dist in [21.25, 3.15, 1.3] {
        for axis in [Vector3::z(), -Vector3::z(), Vector3::x(), -Vector3::y()] {
            let pb = iso(axis * dist, UnitQuaternion::identity());
            let (h, _, _, eps) = evaluate(&g, &at, &pb);
            assert!(hull_was_exact(h, eps), "{axis:?} {dist}: {h:?}");
            check(
                &g,
                &at,
                &pb,
                dist - 1.0 - r,
                &format!("ball on {axis:?} at {dist}"),
            );
        }
    }
}

#[test]
fn val_mesh_hull_concavity_falls_back_to_the_mesh() {
    let (v, t) = u_prism();
    let mesh = trimesh(&v, &t);
    let at = Isometry3::identity();
    // In the slot: inside the hull, no bound from it; the mesh gives w − r.
    let r = 0.3;
    let ball = (rp::SharedShape::ball(r as f32), r);
    let g = common::one_part_bodies(&[&mesh, &ball]);
    let pb = iso(Vector3::new(0.0, 1.25, 0.0), UnitQuaternion::identity());
    let (h, ..) = evaluate(&g, &at, &pb);
    assert_eq!(h, HullEval::None);
    check(&g, &at, &pb, 0.5 - r, "ball in the slot");
    // Above the mouth: the hull's top is h − r away, the arms' edges √(w² + h²) − r.
    let r = 0.1;
    let ball = (rp::SharedShape::ball(r as f32), r);
    let g = common::one_part_bodies(&[&mesh, &ball]);
    for hgt in [0.4, 1.0, 3.0] {
        let pb = iso(
            Vector3::new(0.0, 2.0 + hgt, 0.0),
            UnitQuaternion::identity(),
        );
        let d = 0.5f64.hypot(hgt) - r;
        let (h, _, _, eps) = evaluate(&g, &at, &pb);
        let HullEval::Bracket { lower, upper } = h else {
            panic!("the hulls are apart: {h:?}");
        };
        assert!(lower <= hgt - r + eps && lower < d, "{lower}");
        assert!(upper >= d - eps, "{upper}");
        assert!(
            !hull_was_exact(h, eps),
            "the hull is not exact over the slot"
        );
        check(&g, &at, &pb, d, &format!("ball {hgt} m above the mouth"));
    }
    // Beside an arm's outer face the hull is exact again.
    let pb = iso(
        Vector3::new(1.5 + 0.7 + r, 1.0, 0.0),
        UnitQuaternion::identity(),
    );
    let (h, _, _, eps) = evaluate(&g, &at, &pb);
    assert!(hull_was_exact(h, eps), "{h:?}");
    check(&g, &at, &pb, 0.7, "ball beside the U");
}

#[test]
fn val_mesh_hull_point_inside_a_closed_mesh_is_judged_on_its_triangles() {
    let (v, t) = tessellated_box([2.0, 2.0, 1.5], [20, 20, 15]);
    let mesh = trimesh(&v, &t);
    let r = 0.1;
    let ball = (rp::SharedShape::ball(r as f32), r);
    let g = common::one_part_bodies(&[&mesh, &ball]);
    let at = Isometry3::identity();
    for p in [Vector3::zeros(), Vector3::new(0.5, -0.4, 0.2)] {
        let pb = iso(p, UnitQuaternion::identity());
        let (h, ..) = evaluate(&g, &at, &pb);
        assert_eq!(h, HullEval::None, "inside the hull");
        let d = (1.0 - p.x.abs()).min(1.0 - p.y.abs()).min(0.75 - p.z.abs()) - r;
        check(&g, &at, &pb, d, &format!("ball inside at {p:?}"));
    }
}

#[test]
fn val_mesh_hull_closest_parts_prunes_soundly() {
    // Body 0: a U prism and a box mesh 6 m along x; body 1: a ball over the box mesh. The
    // closest pair is the box mesh's, at the closed form; the certified bound is below it.
    let (uv, ut) = u_prism();
    let u = trimesh(&uv, &ut);
    let (bv, bt) = tessellated_box([2.0, 2.0, 1.5], [20, 20, 15]);
    let bx = trimesh(&bv, &bt);
    let r = 0.2;
    let ball = (rp::SharedShape::ball(r as f32), r);
    let mut g = common::one_part_bodies(&[&u, &ball]);
    let box_pose = iso(Vector3::new(6.0, 0.0, 0.0), UnitQuaternion::identity());
    g.shapes[0].push(bx.0.clone());
    g.pose_body[0].push(box_pose);
    g.radius[0].push(bx.1);
    g.docking[0].push(false);
    g.pieces[0].push(PartPiece::of(&*bx.0, &box_pose, bx.1));
    g.hulls[0].push(monitor::mesh_hull(&*bx.0));
    g.extent_m[0] = 6.0 + bx.1;
    for (p, d) in [
        (Vector3::new(6.1, 0.2, 0.75 + 0.5 + r), 0.5),
        (Vector3::new(4.2, 0.0, 0.0), 0.8 - r),
    ] {
        let mut pi = Vec::new();
        let mut pj = Vec::new();
        g.part_poses(0, &Vector3::zeros(), &UnitQuaternion::identity(), &mut pi);
        g.part_poses(1, &p, &UnitQuaternion::identity(), &mut pj);
        let mut count = QueryCount::default();
        let hit = monitor::closest_parts(
            &g,
            0,
            &pi,
            1,
            &pj,
            &|_, _| true,
            None,
            true,
            &mut Vec::new(),
            &mut Vec::new(),
            &mut count,
        );
        assert_eq!((hit.a, hit.b), (1, 0), "{p:?}");
        let eps = F32_REL_TOL * (6.0 + p.norm() + bx.1 + r);
        assert!(hit.d.lower <= d, "{p:?}: {:?}", hit.d);
        assert!(
            (hit.d.value - d).abs() <= GJK_REL_TOL * d + eps,
            "{p:?}: {:?}",
            hit.d
        );
    }
}
