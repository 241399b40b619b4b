//! The monitor's memo of a mesh pair's exact distance (`sim::monitor::memo`, the mesh cost
//! near the example vehicle's docking collar) is certified: every bracket it gives holds the
//! distance to the triangles, at the pose it was computed for and at any later pose.
//!
//! References (independent, f64):
//! * brute force over every triangle: the distance of a ball (centre c, radius r) to a
//!   triangle mesh is min over its triangles of |c − closest point of the triangle| − r, the
//!   closest point by the Voronoi regions of the triangle (Ericson, *Real-Time Collision
//!   Detection*, 5.1.5), written out here;
//! * a rigid motion moves a point p by |rel₁·p − rel₀·p| (computed directly for sampled points
//!   within the bounding radius, on and inside its sphere), which the memo's displacement bound
//!   must cover; a pure translation moves every point by |Δt| exactly.
//!
//! The concave part is a docking collar as `tools/gen_target_truss.py` writes it (an annulus
//! about x, radii 0.26–0.34 m, 6 cm thick, 64 segments): a ball on its axis is equally close to
//! every triangle of the inner rim, and its convex hull (a disc) is not exact there.
//!
//! Tolerances: parry works in f32 — values within 8 f32 ulps of the pose's scale
//! (`monitor::F32_REL_TOL`) and GJK's 1.2e-3 of the distance (`monitor::GJK_REL_TOL`); the
//! lower bounds are checked against the brute force with no tolerance but the f32 rounding of
//! the vertices (the reference uses the f32 vertices the mesh holds).

mod common;

use bevy_rapier3d::rapier::math::Vector;
use bevy_rapier3d::rapier::prelude as rp;
use nalgebra::{Isometry3, Point3, Translation3, UnitQuaternion, Vector3};
use rpod::math::rng::Lcg;
use rpod::sim::monitor::memo::{self, displacement_bound_m};
use rpod::sim::monitor::{self, F32_REL_TOL, GJK_REL_TOL, PairEval};

/// A uniform draw in [a, b).
trait UniformIn {
    fn uniform_in(&mut self, a: f64, b: f64) -> f64;
}

impl UniformIn for Lcg {
    fn uniform_in(&mut self, a: f64, b: f64) -> f64 {
        a + (b - a) * self.uniform()
    }
}

/// The collar: (vertices as the f32 mesh holds them, in f64; triangles).
fn collar() -> (Vec<[f64; 3]>, Vec<[u32; 3]>) {
    let seg = 64usize;
    let mut v = Vec::new();
    for x in [-0.03f64, 0.03] {
        for r in [0.26f64, 0.34] {
            for k in 0..seg {
                let t = 2.0 * std::f64::consts::PI * k as f64 / seg as f64;
                let p = [x, r * t.cos(), r * t.sin()];
                v.push(p.map(|c| f64::from(c as f32)));
            }
        }
    }
    let id = |e: usize, i: usize, k: usize| ((e * 2 + i) * seg + k % seg) as u32;
    let mut t = Vec::new();
    let mut quad = |a, b, c, d| {
        t.push([a, b, c]);
        t.push([a, c, d]);
    };
    for k in 0..seg {
        quad(id(1, 1, k), id(0, 1, k), id(0, 1, k + 1), id(1, 1, k + 1));
        quad(id(0, 0, k), id(1, 0, k), id(1, 0, k + 1), id(0, 0, k + 1));
        quad(id(0, 0, k), id(0, 0, k + 1), id(0, 1, k + 1), id(0, 1, k));
        quad(id(1, 0, k), id(1, 1, k), id(1, 1, k + 1), id(1, 0, k + 1));
    }
    (v, t)
}

fn shape_of(v: &[[f64; 3]], t: &[[u32; 3]]) -> (rp::SharedShape, f64) {
    let r = v
        .iter()
        .map(|p| Vector3::from(*p).norm())
        .fold(0.0, f64::max)
        * (1.0 + 1e-6);
    let pts = v
        .iter()
        .map(|p| Vector::new(p[0] as f32, p[1] as f32, p[2] as f32))
        .collect();
    (rp::SharedShape::trimesh(pts, t.to_vec()).expect("mesh"), r)
}

/// Brute force: distance of a ball (centre `c` in the mesh's frame, radius `r`) to the mesh.
fn ball_to_mesh(v: &[[f64; 3]], t: &[[u32; 3]], c: Vector3<f64>, r: f64) -> f64 {
    t.iter()
        .map(|tri| {
            let [a, b, d] = tri.map(|i| Vector3::from(v[i as usize]));
            (c - common::closest_on_triangle(c, a, b, d)).norm()
        })
        .fold(f64::INFINITY, f64::min)
        - r
}

fn iso(p: Vector3<f64>, q: UnitQuaternion<f64>) -> Isometry3<f64> {
    Isometry3::from_parts(Translation3::from(p), q)
}

fn random_rotation(rng: &mut Lcg, max_angle: f64) -> UnitQuaternion<f64> {
    let axis = Vector3::new(
        rng.uniform_in(-1.0, 1.0),
        rng.uniform_in(-1.0, 1.0),
        rng.uniform_in(-1.0, 1.0),
    );
    let axis = if axis.norm() < 1e-3 {
        Vector3::x()
    } else {
        axis
    };
    UnitQuaternion::from_scaled_axis(axis.normalize() * rng.uniform_in(0.0, max_angle))
}

fn eps(pa: &Isometry3<f64>, pb: &Isometry3<f64>, ra: f64, rb: f64) -> f64 {
    F32_REL_TOL * ((pa.translation.vector - pb.translation.vector).norm() + ra + rb)
}

#[test]
fn val_mesh_memo_exact_is_the_brute_force_minimum() {
    let (v, t) = collar();
    let (mesh, rm) = shape_of(&v, &t);
    let r = 0.04;
    let ball = rp::SharedShape::ball(r as f32);
    let mut rng = Lcg(26);
    let mut on_axis = 0;
    for k in 0..200 {
        // Centres on the axis (every rim triangle equally close), in the hole, over the
        // faces, beside the outer wall; the mesh posed anywhere, on either side of the pair.
        let c_mesh = match k % 4 {
            0 => Vector3::new(rng.uniform_in(0.08, 2.0), 0.0, 0.0),
            1 => Vector3::new(rng.uniform_in(-0.5, 0.5), rng.uniform_in(-0.2, 0.2), 0.0),
            2 => Vector3::new(
                rng.uniform_in(0.1, 0.6),
                rng.uniform_in(0.2, 0.4),
                rng.uniform_in(-0.1, 0.1),
            ),
            _ => Vector3::new(rng.uniform_in(-0.02, 0.02), 0.0, rng.uniform_in(0.4, 0.8)),
        };
        let truth = ball_to_mesh(&v, &t, c_mesh, r);
        if truth <= 1e-3 {
            continue;
        }
        on_axis += usize::from(k % 4 == 0);
        let pm = iso(
            Vector3::new(
                rng.uniform_in(-50.0, 50.0),
                rng.uniform_in(-50.0, 50.0),
                rng.uniform_in(-5.0, 5.0),
            ),
            random_rotation(&mut rng, std::f64::consts::PI),
        );
        let pb = iso(
            (pm * Point3::from(c_mesh)).coords,
            random_rotation(&mut rng, 3.0),
        );
        let e = eps(&pm, &pb, rm, r);
        for mesh_first in [true, false] {
            let ev = if mesh_first {
                memo::mesh_exact(&pm, (&*mesh, rm), &pb, (&*ball, r))
            } else {
                memo::mesh_exact(&pb, (&*ball, r), &pm, (&*mesh, rm))
            }
            .expect("a mesh and a ball");
            assert!(
                ev.lower_m <= truth,
                "case {k}: lower {} above the brute force {truth}",
                ev.lower_m
            );
            assert!(
                ev.value_m >= truth - e && ev.value_m <= truth * (1.0 + GJK_REL_TOL) + e,
                "case {k}: value {} against {truth}",
                ev.value_m
            );
            // Tight: as narrow as an exact query's own tolerance (what the monitor accepts as
            // a value), from the triangles' gaps alone.
            assert!(
                ev.lower_m >= ev.value_m * (1.0 - GJK_REL_TOL) - e,
                "case {k}: bracket [{}, {}] wider than GJK's tolerance",
                ev.lower_m,
                ev.value_m
            );
            // The witnesses are points of the parts at the value's distance.
            let (wa, wb) = (ev.witness_a, ev.witness_b);
            let (pa, pbb) = if mesh_first { (pm, pb) } else { (pb, pm) };
            let d_w = (pa * wa - pbb * wb).norm();
            assert!((d_w - ev.value_m).abs() <= e, "case {k}: witnesses {d_w}");
        }
    }
    assert!(on_axis >= 40, "{on_axis} cases on the axis");
}

#[test]
fn val_mesh_memo_displacement_bound_holds_for_every_point() {
    let mut rng = Lcg(2612);
    for k in 0..2000 {
        let rb = rng.uniform_in(0.01, 3.0);
        let rel0 = iso(
            Vector3::new(
                rng.uniform_in(-20.0, 20.0),
                rng.uniform_in(-20.0, 20.0),
                rng.uniform_in(-20.0, 20.0),
            ),
            random_rotation(&mut rng, std::f64::consts::PI),
        );
        let small = k % 2 == 0;
        let step = if small { 1e-3 } else { 1.0 };
        let rel1 = iso(
            rel0.translation.vector
                + Vector3::new(
                    rng.uniform_in(-step, step),
                    rng.uniform_in(-step, step),
                    rng.uniform_in(-step, step),
                ),
            random_rotation(&mut rng, if small { 1e-3 } else { std::f64::consts::PI })
                * rel0.rotation,
        );
        let bound = displacement_bound_m(&rel0, &rel1, rb);
        for _ in 0..50 {
            let dir = random_rotation(&mut rng, std::f64::consts::PI) * Vector3::x();
            let len = if rng.uniform_in(0.0, 1.0) < 0.5 {
                rb
            } else {
                rng.uniform_in(0.0, rb)
            };
            let p = Point3::from(dir * len);
            let moved = (rel1 * p - rel0 * p).norm();
            assert!(moved <= bound, "case {k}: a point moved {moved} > {bound}");
        }
    }
    // A pure translation moves every point by |Δt|.
    let rel0 = iso(Vector3::new(1.0, 2.0, 3.0), UnitQuaternion::identity());
    let rel1 = iso(Vector3::new(1.3, 2.4, 3.0), UnitQuaternion::identity());
    let b = displacement_bound_m(&rel0, &rel1, 0.7);
    assert!((b - 0.5).abs() <= 1e-12, "{b}");
}

#[test]
fn val_mesh_memo_advanced_bracket_holds_the_distance() {
    let (v, t) = collar();
    let (mesh, rm) = shape_of(&v, &t);
    let r = 0.03;
    let ball = rp::SharedShape::ball(r as f32);
    let mut rng = Lcg(7);
    let pm = Isometry3::identity();
    for k in 0..100 {
        let c0 = Vector3::new(
            rng.uniform_in(0.1, 1.5),
            rng.uniform_in(-0.1, 0.1),
            rng.uniform_in(-0.1, 0.1),
        );
        // The ball's frame: its centre at c0, turned; the memo bounds b's points within rb of
        // its origin (the ball's centre is its origin).
        let pb0 = iso(c0, random_rotation(&mut rng, 3.0));
        let e0 = memo::mesh_exact(&pm, (&*mesh, rm), &pb0, (&*ball, r)).expect("pair");
        for _ in 0..20 {
            let s = rng.uniform_in(1e-5, 0.05);
            let pb1 = iso(
                c0 + Vector3::new(
                    rng.uniform_in(-s, s),
                    rng.uniform_in(-s, s),
                    rng.uniform_in(-s, s),
                ),
                random_rotation(&mut rng, 0.5) * pb0.rotation,
            );
            let truth = ball_to_mesh(&v, &t, pb1.translation.vector, r);
            let (lower, upper) = e0.advance(&pm.inv_mul(&pb1), r);
            let e = eps(&pm, &pb1, rm, r);
            assert!(lower <= truth, "case {k}: lower {lower} above {truth}");
            assert!(upper >= truth - e, "case {k}: upper {upper} below {truth}");
            assert!(lower <= upper);
        }
    }
}

#[test]
fn val_mesh_memo_pair_eval_along_the_axis_is_certified_and_reuses_it() {
    // A ball flies down the collar's axis at 3 cm/s (0.3 mm per 0.01 s step) with a small
    // lateral wobble and its frame turning, from 1.5 m to the hole: the hull (a disc) is not
    // exact on the axis, so every answer comes from the triangles or from the memo.
    let (v, t) = collar();
    let mesh = shape_of(&v, &t);
    let r = 0.03;
    let ball = (rp::SharedShape::ball(r as f32), r);
    let g = common::one_part_bodies(&[&mesh, &ball]);
    let pm = Isometry3::identity();
    let (mut from_memo, mut steps, mut cleared) = (0, 0, 0);
    for k in 0..4500 {
        let x = 1.5 - 3e-4 * k as f64;
        let wobble = 2e-3 * (k as f64 * 0.01).sin();
        let c = Vector3::new(x, wobble, -wobble);
        let pb = iso(
            c,
            UnitQuaternion::from_scaled_axis(Vector3::new(0.02, 0.0, 0.01) * (k as f64 * 0.01)),
        );
        let truth = ball_to_mesh(&v, &t, c, r);
        let e = eps(&pm, &pb, mesh.1, r);
        // The level of another, closer pair (the slot's) in the monitor's own query.
        match monitor::pair_eval(&g, 0, 0, &(pm, mesh.1), 1, 0, &(pb, r), 0.5 * truth) {
            PairEval::Clear(l) => {
                assert!(
                    l <= truth && l >= 0.5 * truth,
                    "step {k}: cleared at {l}, truth {truth}"
                );
                cleared += 1;
            }
            PairEval::Value(..) => panic!("step {k}: the pair is far above the level"),
        }
        let PairEval::Value(value, lower) =
            monitor::pair_eval(&g, 0, 0, &(pm, mesh.1), 1, 0, &(pb, r), f64::INFINITY)
        else {
            panic!("nothing clears an infinite level");
        };
        assert!(lower <= truth, "step {k}: lower {lower} above {truth}");
        assert!(value >= truth - e, "step {k}: value {value} below {truth}");
        assert!(
            lower >= value * (1.0 - GJK_REL_TOL) - e,
            "step {k}: bracket [{lower}, {value}] wider than an exact query's"
        );
        let fresh = memo::mesh_exact(&pm, (&*mesh.0, mesh.1), &pb, (&*ball.0, r)).expect("pair");
        from_memo += usize::from(value.to_bits() != fresh.value_m.to_bits());
        steps += 1;
    }
    assert_eq!(g.memo.len(), 1);
    assert_eq!(cleared, steps);
    // Most steps are answered by the memo (moving straight at the rim, the lower bound drops
    // by the displacement while the distance drops by nearly as much).
    assert!(
        from_memo * 2 > steps,
        "{from_memo} of {steps} steps from the memo"
    );
}

/// A faceted docking cone as `DockingCone` builds it (32 sides, base radius 0.12 m at the
/// origin, tip radius 0.03 m at 0.25 m along x): its points.
fn cone_points() -> Vec<Vector3<f64>> {
    let mut pts = Vec::new();
    for k in 0..32 {
        let t = 2.0 * std::f64::consts::PI * k as f64 / 32.0;
        let (c, s) = (t.cos(), t.sin());
        pts.push(Vector3::new(0.0, 0.12 * c, 0.12 * s).map(|x| f64::from(x as f32)));
        pts.push(Vector3::new(0.25, 0.03 * c, 0.03 * s).map(|x| f64::from(x as f32)));
    }
    pts
}

#[test]
fn val_mesh_memo_axis_bound_holds_for_every_point_and_rolls_by_the_radius() {
    let cone_pts = cone_points();
    let cone = rp::SharedShape::convex_hull(
        &cone_pts
            .iter()
            .map(|p| Vector::new(p.x as f32, p.y as f32, p.z as f32))
            .collect::<Vec<_>>(),
    )
    .expect("cone");
    let cuboid = rp::SharedShape::cuboid(0.5, 0.2, 0.1);
    let mut corners = Vec::new();
    for sx in [-0.5, 0.5] {
        for sy in [-0.2, 0.2] {
            for sz in [-0.1, 0.1] {
                corners.push(Vector3::new(sx, sy, sz));
            }
        }
    }
    let ball = rp::SharedShape::ball(0.3);
    let radius = |pts: &[Vector3<f64>]| pts.iter().map(|p| p.norm()).fold(0.0, f64::max);
    let cases: [(&rp::SharedShape, Vec<Vector3<f64>>, f64); 3] = [
        (&cone, cone_pts.clone(), radius(&cone_pts)),
        (&cuboid, corners.clone(), radius(&corners)),
        (&ball, Vec::new(), 0.3),
    ];
    let mut rng = Lcg(4242);
    for k in 0..3000 {
        let (shape, pts, rb) = &cases[k % 3];
        let rel0 = iso(
            Vector3::new(
                rng.uniform_in(-5.0, 5.0),
                rng.uniform_in(-5.0, 5.0),
                rng.uniform_in(-5.0, 5.0),
            ),
            random_rotation(&mut rng, std::f64::consts::PI),
        );
        let big = k % 2 == 0;
        let rel1 = iso(
            rel0.translation.vector
                + Vector3::new(
                    rng.uniform_in(-1e-3, 1e-3),
                    rng.uniform_in(-1e-3, 1e-3),
                    rng.uniform_in(-1e-3, 1e-3),
                ),
            random_rotation(&mut rng, if big { std::f64::consts::PI } else { 1e-3 })
                * rel0.rotation,
        );
        let bound = memo::displacement_bound_axis_m(&rel0, &rel1, (&***shape, *rb));
        assert!(bound <= displacement_bound_m(&rel0, &rel1, *rb) + 1e-15);
        // Every vertex, convex combinations of four, and (a ball) points on its surface.
        let mut samples: Vec<Vector3<f64>> = pts.clone();
        for _ in 0..40 {
            if pts.is_empty() {
                let dir = random_rotation(&mut rng, std::f64::consts::PI) * Vector3::x();
                samples.push(dir * 0.3);
            } else {
                let w: Vec<f64> = (0..4).map(|_| rng.uniform_in(0.0, 1.0)).collect();
                let sum: f64 = w.iter().sum();
                let mut p = Vector3::zeros();
                for (wi, _) in w.iter().zip(0..4) {
                    let v =
                        pts[(rng.uniform_in(0.0, pts.len() as f64) as usize).min(pts.len() - 1)];
                    p += v * (wi / sum);
                }
                samples.push(p);
            }
        }
        for p in samples {
            let p = Point3::from(p);
            let moved = (rel1 * p - rel0 * p).norm();
            assert!(moved <= bound, "case {k}: a point moved {moved} > {bound}");
        }
    }
    // A pure roll of the cone about its own axis by θ: 2·sin(θ/2)·0.12 m (its base radius), not
    // its bounding radius (0.2518 m).
    let rel0 = iso(
        Vector3::new(0.3, -1.2, 0.5),
        UnitQuaternion::from_euler_angles(0.3, -0.7, 1.1),
    );
    let theta: f64 = 0.05;
    let rel1 = iso(
        rel0.translation.vector,
        rel0.rotation * UnitQuaternion::from_scaled_axis(Vector3::x() * theta),
    );
    let b = memo::displacement_bound_axis_m(&rel0, &rel1, (&*cone, radius(&cone_pts)));
    let closed = 2.0 * (theta / 2.0).sin() * f64::from(0.12f32);
    assert!((b - closed).abs() <= 1e-9, "{b} against {closed}");
}
