//! The monitor's shell bracket of a mesh part (`sim::mesh::MeshShell`, the first tier of
//! `monitor::hull_bracket`): two spheres about the mesh's centre, every triangle within the
//! outer one and, for a closed mesh holding its centre, none inside the inner one. It must be
//! sound (lower ≤ the distance to the triangles ≤ upper) and, where it answers alone, as
//! narrow as an exact query.
//!
//! References (computed here in f64, independently of the code under test):
//! * outer radius: the largest distance of a vertex from the centre of the vertices' box —
//!   for the latitude–longitude sphere mesh its radius R (every vertex on the sphere), for the
//!   2 × 2 × 1.5 m box mesh its half-diagonal √(1 + 1 + 0.75²);
//! * inner radius of a closed mesh holding its centre: the distance from the centre to the
//!   nearest triangle, by the brute-force scan below; for a convex mesh also the smallest
//!   distance to a face's plane, |n·(a − c)|/|n| (a convex polyhedron is the intersection of
//!   its faces' half-spaces) — 0.75 m for the box mesh;
//! * the distance from a ball (centre P, radius r) to a mesh: a brute-force scan of every
//!   triangle for the closest point to P (Ericson's region test, written out here) less r;
//!   along an axis through a vertex of the sphere mesh it is D − R − r in closed form (the
//!   mesh lies in the ball of radius R, and the vertex on the axis reaches it); a cube whose
//!   lowest corner is h straight above the sphere mesh's top vertex is h from it (the mesh lies
//!   below the top's plane, the corner is h from the vertex);
//! * ball to box mesh: |P − clamp(P, box)| − r;
//! * the inner box (the outer box scaled about the centre until no triangle meets it): for the
//!   box mesh the box itself; for any mesh no triangle meets it — parry's own cuboid–triangle
//!   intersection test on every triangle (the box shrunk by 1e-5 of itself, above f32's
//!   resolution); on a closed concave mesh (a plus-shaped prism, its centre inside) random
//!   balls' brackets hold the brute-force distance.
//!
//! Tolerances: parry works in f32 — a value is within 8 f32 ulps of the pose's scale (|Δc| +
//! both bounding radii: `monitor::F32_REL_TOL`) of the true distance, and an exact mesh query's
//! GJK stops at 1.2e-3 of the distance (`monitor::GJK_REL_TOL`); the bracket must be at least
//! as narrow. Certified lower bounds must be at or below the reference with no tolerance but
//! the reference's own f64 rounding (1e-12 m).

mod common;

use bevy_rapier3d::rapier::math::Vector;
use bevy_rapier3d::rapier::prelude as rp;
use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};
use rpod::bench::meshes::{tessellated_box, uv_sphere};
use rpod::math::rng::Lcg;
use rpod::sim::mesh::MeshShell;
use rpod::sim::monitor::{self, F32_REL_TOL, GJK_REL_TOL, HullEval, PairEval};

/// No triangle meets the inner box (shrunk by 1e-5 of itself): parry's intersection test.
fn inner_box_meets_no_triangle(pts: &[Vector], t: &[[u32; 3]], s: &MeshShell) -> bool {
    use bevy_rapier3d::parry::query::intersection_test;
    use bevy_rapier3d::parry::shape::{Cuboid, Triangle};
    use bevy_rapier3d::rapier::math::Pose;
    let Some(h) = s.inner_half_m else {
        return true;
    };
    let cube = Cuboid::new(Vector::new(
        (h[0] * (1.0 - 1e-5)) as f32,
        (h[1] * (1.0 - 1e-5)) as f32,
        (h[2] * (1.0 - 1e-5)) as f32,
    ));
    let c = Vector::new(
        s.centre_m[0] as f32,
        s.centre_m[1] as f32,
        s.centre_m[2] as f32,
    );
    t.iter().all(|k| {
        let [a, b, d] = k.map(|i| pts[i as usize] - c);
        !intersection_test(
            &Pose::IDENTITY,
            &cube,
            &Pose::IDENTITY,
            &Triangle::new(a, b, d),
        )
        .unwrap_or(true)
    })
}

/// A plus-shaped prism (arms of half-width 0.3 m reaching ±1.5 m in x and y, z ∈ [−½, ½]),
/// closed, its centre inside: concave at the four inner corners.
fn plus_prism() -> (Vec<[f64; 3]>, Vec<[u32; 3]>) {
    let o = [
        (0.3, -1.5),
        (0.3, -0.3),
        (1.5, -0.3),
        (1.5, 0.3),
        (0.3, 0.3),
        (0.3, 1.5),
        (-0.3, 1.5),
        (-0.3, 0.3),
        (-1.5, 0.3),
        (-1.5, -0.3),
        (-0.3, -0.3),
        (-0.3, -1.5),
    ];
    let cap = [
        [10, 1, 4],
        [10, 4, 7],
        [11, 0, 1],
        [11, 1, 10],
        [1, 2, 3],
        [1, 3, 4],
        [7, 4, 5],
        [7, 5, 6],
        [9, 10, 7],
        [9, 7, 8],
    ];
    common::closed_prism(&o, &cap)
}

fn v32(p: &[f64; 3]) -> Vector {
    Vector::new(p[0] as f32, p[1] as f32, p[2] as f32)
}

/// The mesh as the monitor holds it: parry `TriMesh`, its bounding radius about the origin.
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

/// The vertices as parry holds them (f32), back in f64.
fn as_f32(v: &[[f64; 3]]) -> Vec<Vector3<f64>> {
    v.iter()
        .map(|p| {
            let q = v32(p);
            Vector3::new(f64::from(q.x), f64::from(q.y), f64::from(q.z))
        })
        .collect()
}

/// Brute force: the distance from p to the nearest triangle.
fn point_mesh_distance(p: Vector3<f64>, v: &[Vector3<f64>], t: &[[u32; 3]]) -> f64 {
    t.iter()
        .map(|k| {
            let [a, b, c] = k.map(|i| v[i as usize]);
            (p - common::closest_on_triangle(p, a, b, c)).norm()
        })
        .fold(f64::INFINITY, f64::min)
}

/// The smallest distance from c to a face plane (convex meshes).
fn min_plane_distance(c: Vector3<f64>, v: &[Vector3<f64>], t: &[[u32; 3]]) -> f64 {
    t.iter()
        .map(|k| {
            let [a, b, d] = k.map(|i| v[i as usize]);
            let n = (b - a).cross(&(d - a));
            (n.dot(&(a - c)) / n.norm()).abs()
        })
        .fold(f64::INFINITY, f64::min)
}

fn iso(p: Vector3<f64>, q: UnitQuaternion<f64>) -> Isometry3<f64> {
    Isometry3::from_parts(Translation3::from(p), q)
}

/// The hull bracket and the monitor's evaluation of a mesh at the origin (hull support map and
/// shell: `monitor::mesh_hull`) and a primitive at `pb`, and the f32 tolerance of the pair.
fn evaluate(
    mesh: &(rp::SharedShape, f64),
    other: &(rp::SharedShape, f64),
    pb: &Isometry3<f64>,
) -> (HullEval, f64, f64, f64) {
    let hull = monitor::mesh_hull(&*mesh.0).expect("a mesh");
    let at = Isometry3::identity();
    let h = monitor::hull_bracket(
        &at,
        (&*mesh.0, Some(&*hull), mesh.1),
        pb,
        (&*other.0, None, other.1),
        f64::INFINITY,
    );
    let PairEval::Value(value, lower) = monitor::pair_eval_shapes(
        &(at, mesh.1),
        (&*mesh.0, Some(&*hull)),
        &(*pb, other.1),
        (&*other.0, None),
        f64::INFINITY,
    ) else {
        panic!("nothing clears an infinite level");
    };
    let eps = F32_REL_TOL * (pb.translation.vector.norm() + mesh.1 + other.1);
    (h, value, lower, eps)
}

/// The bracket alone is as narrow as an exact query.
fn narrow(h: HullEval, eps: f64) -> bool {
    matches!(h, HullEval::Bracket { lower, upper } if lower >= upper * (1.0 - GJK_REL_TOL) - eps)
}

/// Sound and as precise as an exact query against the reference distance `d`.
fn check(value: f64, lower: f64, eps: f64, d: f64, what: &str) {
    assert!(lower <= d + 1e-12, "{what}: lower {lower} above {d}");
    assert!(value >= d - eps, "{what}: value {value} below {d}");
    assert!(
        (value - d).abs() <= GJK_REL_TOL * d + eps,
        "{what}: value {value} vs {d}"
    );
}

#[test]
fn val_mesh_shell_radii_match_the_closed_forms() {
    // The fly-by sphere: every vertex on the unit sphere, convex, centre inside.
    let (v, t) = uv_sphere(1.0, 126, 400);
    let p = as_f32(&v);
    let pts: Vec<Vector> = v.iter().map(v32).collect();
    let s = MeshShell::new(&pts, &t).expect("shell");
    assert_eq!(s.centre_m, [0.0; 3]);
    let outer = p.iter().map(|q| q.norm()).fold(0.0, f64::max);
    assert!(s.outer_m >= outer && s.outer_m <= outer + 1e-11, "{s:?}");
    // The brute-force scan is the definition; the planes agree with it to the f32 rounding of
    // the vertices (which bends each planar cell of the mesh by ~1e-8 rad: 1e-11 m here).
    let inner = point_mesh_distance(Vector3::zeros(), &p, &t);
    let got = s.inner_m.expect("closed, centre inside");
    assert!(got <= inner && got >= inner - 1e-11, "{got} vs {inner}");
    let planes = min_plane_distance(Vector3::zeros(), &p, &t);
    assert!((planes - inner).abs() < 1e-10, "{planes} vs {inner}");
    // The sagitta of the thinnest band: R(1 − cos) of half a cell's diagonal, about 1e-4.
    assert!(s.outer_m - got < 2e-4, "{s:?}");
    // Its inner box: a cube inside the inscribed one (half-side R/√3), meeting no triangle.
    assert_eq!(s.outer_half_m, [1.0; 3]);
    let h = s.inner_half_m.expect("inner box");
    assert!(h[0] == h[1] && h[1] == h[2], "{h:?}");
    assert!(h[0] > 0.5 && h[0] < 1.0 / 3f64.sqrt(), "{h:?}");
    assert!(inner_box_meets_no_triangle(&pts, &t, &s));

    // The box mesh: half-diagonal and the smallest half-extent; also with its vertices
    // unwelded (each face its own copies, as a glTF's seams), and turned inside out.
    let (v, t) = tessellated_box([2.0, 2.0, 1.5], [20, 20, 15]);
    let pts: Vec<Vector> = v.iter().map(v32).collect();
    let diag = (1.0f64 + 1.0 + 0.75 * 0.75).sqrt();
    let flipped: Vec<[u32; 3]> = t.iter().map(|k| [k[0], k[2], k[1]]).collect();
    let mut loose_v = Vec::new();
    let mut loose_t = Vec::new();
    for k in &t {
        let n = loose_v.len() as u32;
        loose_v.extend(k.map(|i| pts[i as usize]));
        loose_t.push([n, n + 1, n + 2]);
    }
    for (what, pv, pt) in [
        ("welded", &pts, &t),
        ("inside out", &pts, &flipped),
        ("unwelded", &loose_v, &loose_t),
    ] {
        let s = MeshShell::new(pv, pt).expect("shell");
        assert_eq!(s.centre_m, [0.0; 3], "{what}");
        assert!((s.outer_m - diag).abs() < 1e-11, "{what}: {s:?}");
        let inner = s.inner_m.expect("closed");
        assert!(inner <= 0.75 && inner > 0.75 - 1e-11, "{what}: {inner}");
        assert_eq!(s.outer_half_m, [1.0, 1.0, 0.75], "{what}");
        let h = s.inner_half_m.expect("inner box");
        for (got, want) in h.iter().zip([1.0, 1.0, 0.75]) {
            assert!(*got <= want && *got > want * (1.0 - 1e-11), "{what}: {h:?}");
        }
    }

    // Not closed (one triangle gone): no inner sphere. Centre outside the solid (the U
    // prism's box centre (0, 1, 0) lies in its slot): none either.
    let s = MeshShell::new(&pts, &t[1..]).expect("shell");
    assert_eq!((s.inner_m, s.inner_half_m), (None, None));
    assert!((s.outer_m - diag).abs() < 1e-11);
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
    let mut uv = Vec::new();
    for z in [-0.5, 0.5] {
        for (x, y) in o {
            uv.push(v32(&[x, y, z]));
        }
    }
    let n = o.len() as u32;
    let cap = [
        [0, 1, 4],
        [0, 4, 5],
        [1, 2, 3],
        [1, 3, 4],
        [5, 6, 7],
        [5, 7, 0],
    ];
    let mut ut = Vec::new();
    for c in cap {
        ut.push([c[0] + n, c[1] + n, c[2] + n]);
        ut.push([c[0], c[2], c[1]]);
    }
    for k in 0..n {
        let (p, q) = (k, (k + 1) % n);
        ut.push([p, q, q + n]);
        ut.push([p, q + n, p + n]);
    }
    let s = MeshShell::new(&uv, &ut).expect("shell");
    assert_eq!(s.centre_m, [0.0, 1.0, 0.0]);
    assert_eq!(
        s.inner_m, None,
        "the centre is in the slot, outside the solid"
    );
}

#[test]
fn val_mesh_shell_sphere_bracket_is_sound_against_the_triangles() {
    let (v, t) = uv_sphere(1.0, 126, 400);
    let p = as_f32(&v);
    let mesh = trimesh(&v, &t);
    let mut rng = Lcg(26);
    // Along vertex axes (closed form D − 1 − r) and in random directions (brute force), from
    // nearly touching to far; the shell answers alone wherever its width (≈ 1e-4 m) is within
    // an exact query's precision, GJK_REL_TOL of the distance.
    let mut answered = 0;
    let mut cases = Vec::new();
    for axis in [Vector3::x(), -Vector3::x(), Vector3::y(), -Vector3::z()] {
        for gap in [0.02, 0.2, 1.9, 20.0, 200.0] {
            cases.push((axis, gap, 0.25, true));
        }
    }
    for _ in 0..60 {
        let dir = rng.vec3(1.0).normalize();
        let gap = 10f64.powf(-1.5 + 3.5 * rng.uniform());
        cases.push((dir, gap, 0.05 + rng.uniform(), false));
    }
    for (dir, gap, r, on_axis) in cases {
        let ball = (rp::SharedShape::ball(r as f32), r);
        let centre = dir * (1.0 + gap + r);
        let d = if on_axis {
            gap
        } else {
            point_mesh_distance(centre, &p, &t) - r
        };
        let pb = iso(centre, UnitQuaternion::identity());
        let (h, value, lower, eps) = evaluate(&mesh, &ball, &pb);
        let what = format!("ball r {r} at {centre:?}");
        check(value, lower, eps, d, &what);
        if let HullEval::Bracket { lower, upper } = h {
            assert!(
                lower <= d + 1e-12 && upper >= d - eps,
                "{what}: {h:?} vs {d}"
            );
        }
        if gap >= 0.2 {
            assert!(narrow(h, eps), "{what}: {h:?}");
            answered += 1;
        }
    }
    assert!(answered > 40, "{answered}");
}

#[test]
fn val_mesh_shell_cube_over_the_sphere_mesh_is_the_corner_height() {
    // The fly-by's closest approach: the cube (yaw 30°, pitch 20°, roll 10°) with its lowest
    // corner h straight above the top vertex (0, 1, 0).
    let (v, t) = uv_sphere(1.0, 126, 400);
    let mesh = trimesh(&v, &t);
    let cube = (rp::SharedShape::cuboid(0.5, 0.5, 0.5), 0.5 * 3f64.sqrt());
    let q = UnitQuaternion::from_euler_angles(
        10f64.to_radians(),
        20f64.to_radians(),
        30f64.to_radians(),
    );
    let lowest = (0..8)
        .map(|k| {
            let s = |b: usize| if k & b == 0 { -0.5 } else { 0.5 };
            q * Vector3::new(s(1), s(2), s(4))
        })
        .min_by(|a, b| a.y.total_cmp(&b.y))
        .expect("corners");
    for h in [0.5, 1.9, 20.0, 300.0] {
        let pb = iso(Vector3::new(0.0, 1.0 + h, 0.0) - lowest, q);
        let (hb, value, lower, eps) = evaluate(&mesh, &cube, &pb);
        check(value, lower, eps, h, &format!("cube {h} m above"));
        assert!(narrow(hb, eps), "{h}: {hb:?}");
    }
}

#[test]
fn val_mesh_shell_box_mesh_far_and_near_against_the_closed_form() {
    // Spheres 1.6 and 0.75 m: narrow enough only beyond ~700 m; the boxes (outer: the box;
    // inner: the box less 1e-12 of itself) are narrow at every distance here, and the hull
    // would be too (its bracket is exact on a convex mesh). Sound anywhere.
    let half = Vector3::new(1.0, 1.0, 0.75);
    let (v, t) = tessellated_box([2.0, 2.0, 1.5], [20, 20, 15]);
    let mesh = trimesh(&v, &t);
    let r = 0.3;
    let ball = (rp::SharedShape::ball(r as f32), r);
    let mut rng = Lcg(3);
    for k in 0..80 {
        let dist = 10f64.powf(-1.0 + 4.0 * f64::from(k) / 80.0);
        let dir = rng.vec3(1.0).normalize();
        let centre = dir * (dist + 2.0);
        let d = (centre - centre.zip_map(&half, |x, h| x.clamp(-h, h))).norm() - r;
        let pb = iso(centre, UnitQuaternion::identity());
        let (h, value, lower, eps) = evaluate(&mesh, &ball, &pb);
        check(value, lower, eps, d, &format!("ball at {centre:?}"));
        assert!(narrow(h, eps), "{centre:?}: {h:?}");
    }
    // Not closed: only the outer sphere's lower bound; still sound and exact via the hull.
    let mesh = trimesh(&v, &t[1..]);
    for dist in [2.0, 2000.0] {
        let centre = Vector3::new(0.3, -0.2, 0.75 + r + dist);
        let pb = iso(centre, UnitQuaternion::identity());
        let (_, value, lower, eps) = evaluate(&mesh, &ball, &pb);
        check(value, lower, eps, dist, &format!("open mesh, {dist} m"));
    }
}

#[test]
fn val_mesh_shell_concave_closed_mesh_is_bracketed_soundly() {
    // The plus prism: inner sphere 0.3·√2 (the inner corners' edges), inner box the central
    // column scaled to 0.2 of the outer box (its arms' inner faces, 0.3 of 1.5 across).
    let (v, t) = plus_prism();
    let pts: Vec<Vector> = v.iter().map(v32).collect();
    let s = MeshShell::new(&pts, &t).expect("shell");
    let inner = s.inner_m.expect("closed, centre inside");
    assert!((inner - 0.3 * 2f64.sqrt()).abs() < 1e-7, "{inner}");
    let h = s.inner_half_m.expect("inner box");
    for (got, want) in h.iter().zip([0.3, 0.3, 0.1]) {
        assert!((got - want).abs() < 1e-7, "{h:?}");
    }
    assert!(inner_box_meets_no_triangle(&pts, &t, &s));
    // Random balls, in the arms' concave corners and far off: the bracket holds the
    // brute-force distance (the exact query answers where neither shell nor hull is narrow).
    let p = as_f32(&v);
    let mesh = trimesh(&v, &t);
    let mut rng = Lcg(12);
    for k in 0..200 {
        let r = 0.05 + 0.2 * rng.uniform();
        let centre = if k % 2 == 0 {
            // Over an inner corner, between two arms.
            let q = [(1.0, 1.0), (-1.0, 1.0), (-1.0, -1.0), (1.0, -1.0)][k % 4];
            let a = 0.6 + 1.2 * rng.uniform();
            Vector3::new(q.0 * a, q.1 * a, rng.symmetric())
        } else {
            rng.vec3(1.0).normalize() * (2.0 + 10f64.powf(3.0 * rng.uniform()))
        };
        let d = point_mesh_distance(centre, &p, &t) - r;
        if d <= 0.01 {
            continue;
        }
        let ball = (rp::SharedShape::ball(r as f32), r);
        let pb = iso(centre, UnitQuaternion::identity());
        let (hb, value, lower, eps) = evaluate(&mesh, &ball, &pb);
        let what = format!("ball r {r} at {centre:?}: {hb:?}");
        check(value, lower, eps, d, &what);
        if let HullEval::Bracket { lower, upper } = hb {
            assert!(lower <= d + 1e-12 && upper >= d - eps, "{what} vs {d}");
        }
    }
}
