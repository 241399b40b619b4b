//! The per-part, rotation-aware distance-rate bounds are sound: nothing hides between two
//! samples of a fast spin.
//!
//! Reference: the true distance between the parts, computed densely — 10⁴ sub-samples per
//! step of the bodies' rigid motion, each an exact parry distance query between the two
//! parts at their poses (`parry::query::distance`, the relative pose formed in f64). The
//! motion is either a closed-form screw (constant velocity, constant angular velocity about a
//! fixed axis: x(τ) = x₀ + vτ, q(τ) = exp(ωτ)·q₀, computed here independently of the monitor's
//! path) or the monitor's own f64 free-flight path (RK4 of Euler's equations under a held
//! torque, `BodyPath::pose_at`), at spins up to 100 rad/s (1 rad a step). Checked:
//! * every part pair's bound L_pq (`part_pair_rates`): on each of 1, 8 and 64 sub-intervals,
//!   the dense minimum of the pair's distance is at least (d(a) + d(b) − L_pq·w)/2 (and, for a
//!   faceted solid of revolution, its bound through its solid of revolution);
//! * every pair's slab gap along the spinning body's axis (`SlabBound`) is at most its
//!   distance at every dense instant, and on the same sub-intervals the dense minimum is at
//!   least the gap's interval bound with L_slab;
//! * the lower bound the monitor reports between the two samples (`search_parts`, as the
//!   closest-approach search and a `MinDistance` guarantee call it) is at most the dense
//!   minimum of the bodies' distance;
//!
//! for boxes, cylinders, cones, balls, a faceted hull and a triangle-mesh part. And a thin
//! plate spinning at 100 rad/s sweeps through a ball between two samples that both show it
//! clear: the search finds the contact inside the step; in a whole run, a `MinDistance`
//! guarantee broken only between samples by such a sweep is found violated, inside the
//! interval, with the closed-form worst margin. Over a step that turns a body more than
//! 0.3 rad, a guarantee resting on the rotation is `unresolved`, never `held`, and its search
//! only looks for a violation: its cost is the closed-form bisection depth to prove zero.
//!
//! And `rpod::geometry::revolution`: a hull found to be a faceted solid of revolution has its
//! solid of revolution within its offset, checked by brute force (every vertex turned through
//! a grid of angles, its distance to the hull's triangles in f64 by `common::closest_on_triangle`,
//! Ericson's region test); shapes that are not (twisted rings, boxes, slot walls, uneven rings,
//! NaN, empty, 1e300) are refused or stay finite.
//!
//! Tolerances: parry works in f32 — a dense value is within 8 f32 ulps of the pose's scale
//! (|translation| + both bounding radii, a few metres: ≈ 4e-6 m) of the true distance, and
//! GJK stops at 1.2e-3 of the distance (`monitor::GJK_REL_TOL`); every comparison allows that
//! much and nothing more.

mod common;

use bevy_rapier3d::parry::query;
use bevy_rapier3d::parry::shape::ConvexPolyhedron;
use bevy_rapier3d::rapier::math::{Pose, Vector};
use bevy_rapier3d::rapier::prelude as rp;
use nalgebra::{Isometry3, Matrix3, Translation3, UnitQuaternion, Vector3};
use rpod::geometry::bounds::{Bracket, interval_lower_bound};
use rpod::geometry::revolution::{FacetedRevolution, faceted_revolution};
use rpod::math::rng::Lcg;
use rpod::scene::{BodyRole, load_scene_str};
use rpod::sim::monitor::{
    self, DistanceScratch, F32_REL_TOL, GJK_REL_TOL, MonitorGeometry, PartPiece, PartTerms,
    QueryCount,
};
use rpod::sim::motion::{BodyPath, StepMotion, principal_axes, principal_moments};
use rpod::sim::{BodyState, SimBody, Simulation, conv};

const DT: f64 = 0.01;
/// Dense sub-samples per step.
const N: usize = 10_000;

/// One part: shape, pose in the body frame, bounding radius about the collider origin.
type PartDef = (rp::SharedShape, Isometry3<f64>, f64);

fn v32(x: f64, y: f64, z: f64) -> Vector {
    Vector::new(x as f32, y as f32, z as f32)
}

/// A faceted cone (32-gon frustum, as `DockingCone` builds it), axis local +x.
fn faceted_cone() -> (rp::SharedShape, f64) {
    let mut pts = Vec::new();
    for k in 0..32 {
        let phi = 2.0 * std::f64::consts::PI * k as f64 / 32.0;
        pts.push(v32(0.0, 0.12 * phi.cos(), 0.12 * phi.sin()));
        pts.push(v32(0.25, 0.03 * phi.cos(), 0.03 * phi.sin()));
    }
    (
        rp::SharedShape::convex_hull(&pts).expect("hull"),
        0.25_f64.hypot(0.03),
    )
}

/// An octahedron of radius 0.15 m as a triangle mesh.
fn mesh_part() -> (rp::SharedShape, f64) {
    let r = 0.15;
    let v = vec![
        v32(r, 0.0, 0.0),
        v32(-r, 0.0, 0.0),
        v32(0.0, r, 0.0),
        v32(0.0, -r, 0.0),
        v32(0.0, 0.0, r),
        v32(0.0, 0.0, -r),
    ];
    let t = vec![
        [0, 2, 4],
        [2, 1, 4],
        [1, 3, 4],
        [3, 0, 4],
        [2, 0, 5],
        [1, 2, 5],
        [3, 1, 5],
        [0, 3, 5],
    ];
    (rp::SharedShape::trimesh(v, t).expect("mesh"), r)
}

fn iso(p: Vector3<f64>, q: UnitQuaternion<f64>) -> Isometry3<f64> {
    Isometry3::from_parts(Translation3::from(p), q)
}

/// The monitor's geometry of bodies made of `parts` (centres of mass at the body origins).
fn geometry(bodies: &[Vec<PartDef>]) -> MonitorGeometry {
    let mut g = MonitorGeometry::default();
    for parts in bodies {
        let com = Vector3::zeros();
        g.shapes.push(parts.iter().map(|p| p.0.clone()).collect());
        g.pose_body.push(parts.iter().map(|p| p.1).collect());
        g.radius.push(parts.iter().map(|p| p.2).collect());
        g.docking.push(vec![false; parts.len()]);
        g.com_body_m.push(com);
        g.extent_m.push(
            parts
                .iter()
                .map(|p| (p.1.translation.vector - com).norm() + p.2)
                .fold(0.0, f64::max),
        );
        g.aabb_extent_m.push(
            parts
                .iter()
                .map(|p| (p.1.translation.vector - com).norm() + 3f64.sqrt() * p.2)
                .fold(0.0, f64::max),
        );
        g.has_docking.push(false);
        g.pieces.push(
            parts
                .iter()
                .map(|p| PartPiece::of(&*p.0, &p.1, p.2))
                .collect(),
        );
        g.hulls
            .push(parts.iter().map(|p| monitor::mesh_hull(&*p.0)).collect());
    }
    g
}

fn sim_body(j: Matrix3<f64>) -> SimBody {
    SimBody {
        index: 0,
        name: "b".into(),
        role: BodyRole::Other,
        handle: rp::RigidBodyHandle::invalid(),
        mass_kg: 1.0,
        inertia_kg_m2: j,
        com_body_m: Vector3::zeros(),
        inertia_inv: j.try_inverse().expect("invertible"),
    }
}

/// How a body moves over the step, and its pose at τ computed by the reference.
enum Motion {
    /// Closed-form screw: x₀ + vτ, exp(ωτ)·q₀.
    Screw {
        x0: Vector3<f64>,
        v: Vector3<f64>,
        q0: UnitQuaternion<f64>,
        w: Vector3<f64>,
    },
    /// The monitor's free-flight path (RK4 under a held torque).
    Free(Box<BodyPath>),
}

impl Motion {
    fn pose(&self, tau: f64) -> (Vector3<f64>, UnitQuaternion<f64>) {
        match self {
            Motion::Screw { x0, v, q0, w } => {
                (x0 + v * tau, UnitQuaternion::from_scaled_axis(w * tau) * q0)
            }
            Motion::Free(p) => p.pose_at(tau),
        }
    }
    fn path(&self) -> BodyPath {
        match self {
            Motion::Screw { x0, v, q0, w } => {
                let s0 = BodyState {
                    pos_m: *x0,
                    vel_m_s: *v,
                    att: *q0,
                    omega_rad_s: *w,
                };
                let (x1, q1) = self.pose(DT);
                let s1 = BodyState {
                    pos_m: x1,
                    vel_m_s: *v,
                    att: q1,
                    omega_rad_s: *w,
                };
                BodyPath::straight(&s0, &s1, DT)
            }
            Motion::Free(p) => (**p).clone(),
        }
    }
}

/// A free-flight path from `s` under the held torque, as `physics_step` builds it.
fn free_path(s: &BodyState, j: Matrix3<f64>, torque: Vector3<f64>) -> BodyPath {
    let b = sim_body(j);
    let (q1, w1) = rpod::sim::rotate_rk4(&s.att, &s.omega_rad_s, &torque, &j, &b.inertia_inv, DT);
    let x1 = s.pos_m + s.vel_m_s * DT;
    BodyPath::free(
        s,
        Vector3::zeros(),
        torque,
        &b,
        principal_moments(&j),
        (&x1, &q1, &w1),
        DT,
    )
}

fn step_motion(
    geo: &MonitorGeometry,
    paths: Vec<BodyPath>,
    inertia: &[Matrix3<f64>],
) -> StepMotion {
    StepMotion {
        t0_s: 0.0,
        dt_s: DT,
        paths,
        extent_m: geo.extent_m.clone(),
        lambda_kg_m2: inertia.iter().map(principal_moments).collect(),
        axes_body: inertia.iter().map(principal_axes).collect(),
        ready: true,
        ..Default::default()
    }
}

/// Parry's distance between part a of body 0 and part b of body 1 at the given body poses,
/// and the f32 scale of the query (|relative translation| + both bounding radii).
fn part_distance(
    geo: &MonitorGeometry,
    (xa, qa): &(Vector3<f64>, UnitQuaternion<f64>),
    a: usize,
    (xb, qb): &(Vector3<f64>, UnitQuaternion<f64>),
    b: usize,
) -> (f64, f64) {
    let pa = iso(*xa, *qa) * geo.pose_body[0][a];
    let pb = iso(*xb, *qb) * geo.pose_body[1][b];
    let rel = pa.inv_mul(&pb);
    let d = query::distance(
        &Pose::IDENTITY,
        &*geo.shapes[0][a],
        &conv::pose(&rel),
        &*geo.shapes[1][b],
    )
    .expect("supported") as f64;
    (
        d,
        rel.translation.vector.norm() + geo.radius[0][a] + geo.radius[1][b],
    )
}

/// Parry's own error on a value d at scale s: the true distance is within this of it.
fn noise(d: f64, scale: f64) -> f64 {
    GJK_REL_TOL * d.abs() + F32_REL_TOL * scale
}

/// Checks one step of two bodies: every part pair's bound on 1, 8 and 64 sub-intervals, and
/// the searches' lower bounds, against the dense reference. Returns (worst slack of a pair's
/// bound: dense minimum less the bound, m; the body pair's dense minimum, m).
fn check_step(label: &str, geo: &MonitorGeometry, motions: &[Motion; 2], inertia: &[Matrix3<f64>]) {
    let motion = step_motion(geo, vec![motions[0].path(), motions[1].path()], inertia);
    let (na, nb) = (geo.shapes[0].len(), geo.shapes[1].len());
    let mut terms = [PartTerms::default(), PartTerms::default()];
    let mut rates = Vec::new();
    monitor::part_pair_rates(geo, &motion, 0, 1, &mut terms, &mut rates);
    let body_rate = motion.distance_rate_bound(0, 1);
    // The dense reference: every part pair at N + 1 times.
    let mut d = vec![Vec::with_capacity(N + 1); na * nb];
    let mut scale: f64 = 0.0;
    for k in 0..=N {
        let tau = DT * k as f64 / N as f64;
        let (pa, pb) = (motions[0].pose(tau), motions[1].pose(tau));
        for a in 0..na {
            for b in 0..nb {
                let (x, s) = part_distance(geo, &pa, a, &pb, b);
                d[a * nb + b].push(x);
                scale = scale.max(s);
            }
        }
    }
    let body: Vec<f64> = (0..=N)
        .map(|k| d.iter().map(|p| p[k]).fold(f64::INFINITY, f64::min))
        .collect();
    let body_min = body.iter().copied().fold(f64::INFINITY, f64::min);
    // 1. Every pair's own bound, at three scales.
    for (pq, dp) in d.iter().enumerate() {
        assert!(
            rates[pq].full_m_s <= body_rate,
            "{label}: pair {pq} rate {:?} above the bodies' {body_rate}",
            rates[pq]
        );
        for pieces in [1, 8, 64] {
            let w = N / pieces;
            for c in 0..pieces {
                let (ka, kb) = (c * w, (c + 1) * w);
                let lo = |x: f64| x - noise(x, scale);
                // The pair's bound as the search takes it: through its solid of revolution
                // too, for a faceted one (`PairRate::interval_lower`).
                let bound =
                    rates[pq].interval_lower(lo(dp[ka]), lo(dp[kb]), DT * w as f64 / N as f64);
                assert!(
                    bound
                        >= interval_lower_bound(
                            lo(dp[ka]),
                            lo(dp[kb]),
                            rates[pq].full_m_s,
                            DT * w as f64 / N as f64
                        )
                );
                let m = dp[ka..=kb].iter().copied().fold(f64::INFINITY, f64::min);
                assert!(
                    m + noise(m, scale) >= bound,
                    "{label}: part pair ({}, {}) on piece {c}/{pieces}: dense minimum {m} below its bound {bound} (rates {:?})",
                    pq / nb,
                    pq % nb,
                    rates[pq]
                );
            }
        }
    }
    // 1b. The slab bound (`SlabBound`): every pair's slab gap is at most its distance at every
    // dense instant (a separating direction), and on 1, 8 and 64 sub-intervals the dense
    // minimum stays above the gap's interval bound with L_slab.
    if let Some(slab) = monitor::SlabBound::new(geo, &motion, 0, 1) {
        let mut gaps: Vec<Vec<f64>> = vec![Vec::with_capacity(N + 1); na * nb];
        let mut g = Vec::new();
        for k in 0..=N {
            let tau = DT * k as f64 / N as f64;
            slab.gaps(
                geo,
                (0, 1),
                &motions[0].pose(tau),
                &motions[1].pose(tau),
                &mut g,
            );
            for (pq, x) in g.iter().enumerate() {
                gaps[pq].push(*x);
            }
        }
        for (pq, (dp, gp)) in d.iter().zip(&gaps).enumerate() {
            for (k, (x, dk)) in gp.iter().zip(dp).enumerate() {
                assert!(
                    *x <= dk + noise(*dk, scale),
                    "{label}: pair {pq} slab gap {x} above its distance {dk} at sample {k}"
                );
            }
            for pieces in [1, 8, 64] {
                let w = N / pieces;
                for c in 0..pieces {
                    let (ka, kb) = (c * w, (c + 1) * w);
                    let bound = interval_lower_bound(
                        gp[ka],
                        gp[kb],
                        slab.rate_m_s,
                        DT * w as f64 / N as f64,
                    );
                    let m = dp[ka..=kb].iter().copied().fold(f64::INFINITY, f64::min);
                    assert!(
                        m + noise(m, scale) >= bound,
                        "{label}: pair {pq} piece {c}/{pieces}: dense minimum {m} below its slab bound {bound} (L_slab {})",
                        slab.rate_m_s
                    );
                }
            }
        }
    }
    // 2. The searches' lower bounds, as the closest approach (0.1 % tolerance, 48
    // evaluations) and a MinDistance of 5 cm (10 % of its margin, 256) call them.
    let mut sc = DistanceScratch::default();
    let mut count = QueryCount::default();
    let d0 = monitor::pair_at(geo, &motion, 0, 1, 0.0, None, &mut sc, &mut count);
    let d1 = monitor::pair_at(geo, &motion, 0, 1, DT, None, &mut sc, &mut count);
    for (offset, rel_tol, evals) in [(0.0, 1e-3, 48), (0.05, 0.1, 256)] {
        let (f0, f1) = (
            Bracket {
                value: d0.d.value - offset,
                lower: d0.d.lower - offset,
            },
            Bracket {
                value: d1.d.value - offset,
                lower: d1.d.lower - offset,
            },
        );
        let w0 = f0.value.min(f1.value);
        let thr = move |b: f64| {
            let w = w0.min(b);
            let t = w - (rel_tol * w.abs()).max(1e-6);
            if t <= -offset { f64::NEG_INFINITY } else { t }
        };
        monitor::pair_rate_gain(geo, &motion, 0, 1, (d1.a, d1.b), &mut sc);
        let (r, _) = monitor::search_parts(
            geo,
            &motion,
            0,
            1,
            (f0, f1),
            offset,
            thr,
            evals,
            Some((d1.a, d1.b)),
            &mut sc,
            &mut count,
        );
        assert!(
            r.lower <= body_min - offset + noise(body_min, scale),
            "{label}: the search's lower bound {} is above the dense minimum {} (offset {offset})",
            r.lower,
            body_min - offset
        );
        // What it found is a distance the bodies really reach (to parry's precision).
        assert!(
            r.value + offset + noise(r.value + offset, scale) >= body_min,
            "{label}: found {} below the dense minimum {body_min}",
            r.value + offset
        );
    }
}

fn random_unit(rng: &mut Lcg) -> Vector3<f64> {
    loop {
        let v = rng.vec3(1.0);
        if v.norm() > 0.1 {
            return v.normalize();
        }
    }
}

/// Random steps: two bodies of five or six parts each (box, cylinder, cone, ball, mesh, and a
/// faceted hull), random poses, drift up to 0.5 m/s, spins of 100 rad/s (about a random axis,
/// or about the axis of body A's cylinder, which passes through its centre of mass) and up to
/// 5 rad/s, on closed-form screws and on RK4 free-flight paths with a torque.
#[test]
fn invariant_part_rate_bounds_hold_under_fast_spins() {
    let mut rng = Lcg(0x5eed_5917);
    let (hull, hull_r) = faceted_cone();
    let (mesh, mesh_r) = mesh_part();
    let inertia = [
        Matrix3::from_diagonal(&Vector3::new(110.0, 140.0, 160.0)),
        Matrix3::new(90.0, 4.0, -3.0, 4.0, 120.0, 6.0, -3.0, 6.0, 150.0),
    ];
    for trial in 0..12 {
        let spin_axis = random_unit(&mut rng);
        let on_axis = trial % 3 == 0;
        let rq = |rng: &mut Lcg| rng.quat();
        // Body A: its cylinder's axis passes through the centre of mass along `spin_axis`
        // in the on-axis trials.
        let cyl_rot = UnitQuaternion::rotation_between(&Vector3::y(), &spin_axis)
            .unwrap_or_else(UnitQuaternion::identity);
        let cyl_pos = if on_axis {
            spin_axis * 0.4
        } else {
            rng.vec3(0.5)
        };
        let a_parts: Vec<PartDef> = vec![
            (
                rp::SharedShape::cuboid(0.3, 0.1, 0.05),
                iso(rng.vec3(0.6), rq(&mut rng)),
                Vector3::new(0.3, 0.1, 0.05).norm(),
            ),
            (
                rp::SharedShape::cylinder(0.2, 0.1),
                iso(cyl_pos, cyl_rot),
                0.2_f64.hypot(0.1),
            ),
            (
                rp::SharedShape::cone(0.15, 0.1),
                iso(rng.vec3(0.6), rq(&mut rng)),
                0.15_f64.hypot(0.1),
            ),
            (
                rp::SharedShape::ball(0.12),
                iso(rng.vec3(0.6), rq(&mut rng)),
                0.12,
            ),
            (mesh.clone(), iso(rng.vec3(0.6), rq(&mut rng)), mesh_r),
        ];
        let b_parts: Vec<PartDef> = vec![
            (
                rp::SharedShape::cuboid(0.5, 0.02, 0.3),
                iso(rng.vec3(0.5), rq(&mut rng)),
                Vector3::new(0.5, 0.02, 0.3).norm(),
            ),
            (
                rp::SharedShape::cylinder(0.1, 0.15),
                iso(rng.vec3(0.5), rq(&mut rng)),
                0.1_f64.hypot(0.15),
            ),
            (
                rp::SharedShape::cone(0.2, 0.08),
                iso(rng.vec3(0.5), rq(&mut rng)),
                0.2_f64.hypot(0.08),
            ),
            (
                rp::SharedShape::ball(0.1),
                iso(rng.vec3(0.5), rq(&mut rng)),
                0.1,
            ),
            (mesh.clone(), iso(rng.vec3(0.5), rq(&mut rng)), mesh_r),
            (hull.clone(), iso(rng.vec3(0.5), rq(&mut rng)), hull_r),
        ];
        let geo = geometry(&[a_parts, b_parts]);
        let qa = rng.quat();
        let qb = rng.quat();
        // Centres 1.2–2.2 m apart: some part pairs near, some far, some may touch.
        let xb = random_unit(&mut rng) * (1.2 + rng.uniform());
        let wa = if on_axis {
            // About the cylinder's axis (world frame): the axis through the centre of mass.
            qa * spin_axis * 100.0
        } else if trial % 3 == 1 {
            spin_axis * 100.0
        } else {
            rng.vec3(20.0)
        };
        let wb = rng.vec3(5.0);
        let (va, vb) = (rng.vec3(0.5), rng.vec3(0.5));
        let motions = if trial % 2 == 0 {
            [
                Motion::Screw {
                    x0: Vector3::zeros(),
                    v: va,
                    q0: qa,
                    w: wa,
                },
                Motion::Screw {
                    x0: xb,
                    v: vb,
                    q0: qb,
                    w: wb,
                },
            ]
        } else {
            let sa = BodyState {
                pos_m: Vector3::zeros(),
                vel_m_s: va,
                att: qa,
                omega_rad_s: wa,
            };
            let sb = BodyState {
                pos_m: xb,
                vel_m_s: vb,
                att: qb,
                omega_rad_s: wb,
            };
            [
                Motion::Free(Box::new(free_path(&sa, inertia[0], rng.vec3(5.0)))),
                Motion::Free(Box::new(free_path(&sb, inertia[1], rng.vec3(5.0)))),
            ]
        };
        check_step(&format!("trial {trial}"), &geo, &motions, &inertia);
    }
}

/// The chaser's inertias (110/140/160 kg·m², and a unit one), the chaser at the origin
/// drifting at 0.02 m/s along −x and spinning at 100 rad/s about x (a principal axis), and a
/// body at rest at `b_pos`.
fn spin_about_x(b_pos: Vector3<f64>) -> ([Matrix3<f64>; 2], BodyState, BodyState) {
    let inertia = [
        Matrix3::from_diagonal(&Vector3::new(110.0, 140.0, 160.0)),
        Matrix3::identity(),
    ];
    let sa = BodyState {
        pos_m: Vector3::zeros(),
        vel_m_s: Vector3::new(-0.02, 0.0, 0.0),
        att: UnitQuaternion::identity(),
        omega_rad_s: Vector3::new(100.0, 0.0, 0.0),
    };
    let sb = BodyState {
        pos_m: b_pos,
        vel_m_s: Vector3::zeros(),
        att: UnitQuaternion::identity(),
        omega_rad_s: Vector3::zeros(),
    };
    (inertia, sa, sb)
}

/// A spin about a principal axis, torque-free, through a round part's axis: the round part's
/// rate is its centre's drift alone, and a box's is not. (The numbers the cliff relies on.)
#[test]
fn invariant_round_parts_on_the_spin_axis_have_no_spin_rate() {
    let geo = geometry(&[
        vec![
            (
                rp::SharedShape::cylinder(0.2, 0.1),
                iso(
                    Vector3::new(0.5, 0.0, 0.0),
                    UnitQuaternion::rotation_between(&Vector3::y(), &Vector3::x()).expect("rot"),
                ),
                0.2_f64.hypot(0.1),
            ),
            (
                rp::SharedShape::cuboid(0.1, 0.1, 0.1),
                iso(Vector3::new(0.5, 0.0, 0.0), UnitQuaternion::identity()),
                0.1 * 3f64.sqrt(),
            ),
            (
                rp::SharedShape::ball(0.1),
                iso(Vector3::new(0.9, 0.0, 0.0), UnitQuaternion::identity()),
                0.1,
            ),
        ],
        vec![(
            rp::SharedShape::ball(0.1),
            iso(Vector3::zeros(), UnitQuaternion::identity()),
            0.1,
        )],
    ]);
    let (inertia, sa, sb) = spin_about_x(Vector3::new(-1.0, 0.0, 0.0));
    let motion = step_motion(
        &geo,
        vec![
            free_path(&sa, inertia[0], Vector3::zeros()),
            free_path(&sb, inertia[1], Vector3::zeros()),
        ],
        &inertia,
    );
    let mut terms = [PartTerms::default(), PartTerms::default()];
    let mut rates = Vec::new();
    monitor::part_pair_rates(&geo, &motion, 0, 1, &mut terms, &mut rates);
    let body = motion.distance_rate_bound(0, 1);
    println!("rates {rates:?}, bodies {body}");
    // Cylinder and ball on the axis: 0.02 m/s of drift plus RK4's 1e-3 relative allowance
    // (of Ω ≈ 100.1 rad/s) on each of the two (zero) off-axis components, times the lever arm:
    // the centre's distance from the axis direction (0.5 m, 0.9 m) and, for the cylinder, its
    // radius about its centre (0.224 m) — 0.165 m/s and 0.200 m/s; 1e-3 relative for the
    // rounding inflations and Ω's own.
    let slack = 2.0 * 1e-3 * 100.1;
    assert!(
        rates[0].full_m_s <= (0.02 + slack * (0.5 + 0.2_f64.hypot(0.1))) * (1.0 + 1e-3),
        "{:?}",
        rates[0]
    );
    assert!(
        rates[2].full_m_s <= (0.02 + slack * 0.9) * (1.0 + 1e-3),
        "{:?}",
        rates[2]
    );
    // The box keeps its own spin: Ω·ρ ≥ 100 × 0.17 m.
    assert!(
        rates[1].full_m_s >= 100.0 * 0.1 * 3f64.sqrt(),
        "{:?}",
        rates[1]
    );
    // None of them is a faceted solid of revolution: no second bound.
    assert!(rates.iter().all(|r| r.offset_m == 0.0));
    // The bodies' bound: Ω times the extent (1.0 m).
    assert!(body >= 100.0 * 1.0, "{body}");
}

/// The docking cone's faceted hull (32-gon frustum, base radius 0.12 m) on the axis of a spin
/// at 100 rad/s about a principal axis, 3 cm from a box: its facets move at up to 12 m/s,
/// its solid of revolution not at all. Against the dense reference (`check_step`: the pair's
/// bound, through its solid of revolution too, on 1, 8 and 64 sub-intervals) on the
/// closed-form screw and on the monitor's RK4 path; and the bound over the whole step is
/// within the hull's offset (0.58 mm) and the drift of the step's ends, where the bound on
/// the facets' own motion is centimetres below.
#[test]
fn val_faceted_cone_spinning_about_its_axis_is_bounded_through_its_solid_of_revolution() {
    let (hull, hull_r) = faceted_cone();
    let geo = geometry(&[
        vec![(
            hull,
            iso(Vector3::new(0.5, 0.0, 0.0), UnitQuaternion::identity()),
            hull_r,
        )],
        vec![(
            rp::SharedShape::cuboid(0.1, 0.05, 0.1),
            iso(Vector3::new(0.55, 0.2, 0.0), UnitQuaternion::identity()),
            Vector3::new(0.1, 0.05, 0.1).norm(),
        )],
    ]);
    let piece = &geo.pieces[0][0];
    let f = piece
        .faceted
        .expect("the hull is a faceted solid of revolution");
    let s0 = 0.12 * (1.0 - (std::f64::consts::PI / 32.0).cos());
    assert!(f.offset_m >= s0 && f.offset_m < 1.01 * s0, "{f:?}");
    assert!((f.axis - Vector3::x()).norm() < 1e-9 || (f.axis + Vector3::x()).norm() < 1e-9);
    let (inertia, sa, sb) = spin_about_x(Vector3::zeros());
    let screw = [
        Motion::Screw {
            x0: sa.pos_m,
            v: sa.vel_m_s,
            q0: sa.att,
            w: sa.omega_rad_s,
        },
        Motion::Screw {
            x0: sb.pos_m,
            v: sb.vel_m_s,
            q0: sb.att,
            w: sb.omega_rad_s,
        },
    ];
    check_step("cone on the spin axis (screw)", &geo, &screw, &inertia);
    // Start half a facet turned, so the samples are not all at a vertex.
    let sa_half = BodyState {
        att: UnitQuaternion::from_scaled_axis(Vector3::x() * (std::f64::consts::PI / 32.0)),
        ..sa.clone()
    };
    let free = [
        Motion::Free(Box::new(free_path(&sa_half, inertia[0], Vector3::zeros()))),
        Motion::Free(Box::new(free_path(&sb, inertia[1], Vector3::zeros()))),
    ];
    check_step("cone on the spin axis (RK4 path)", &geo, &free, &inertia);
    // What the bound gains: over the whole step, from the two ends' values.
    let motion = step_motion(&geo, vec![free[0].path(), free[1].path()], &inertia);
    let mut terms = [PartTerms::default(), PartTerms::default()];
    let mut rates = Vec::new();
    monitor::part_pair_rates(&geo, &motion, 0, 1, &mut terms, &mut rates);
    let r = rates[0];
    println!("{r:?}");
    assert!(r.full_m_s >= 100.0 * 0.12, "{r:?}");
    // Drift 0.02 m/s, and RK4's 1e-3 of Ω on the two other axes times the lever arms of
    // the cone's centre (0.625 m) and radius (0.173 m): 0.18 m/s.
    assert!(r.revolved_m_s < 0.2, "{r:?}");
    let d = |tau: f64| part_distance(&geo, &free[0].pose(tau), 0, &free[1].pose(tau), 0).0;
    let (da, db) = (d(0.0), d(DT));
    let through = r.interval_lower(da, db, DT);
    let full = interval_lower_bound(da, db, r.full_m_s, DT);
    println!("d {da} {db}: bound {through}, facets alone {full}");
    assert!(through >= da.min(db) - f.offset_m - 0.5 * r.revolved_m_s * DT - 1e-12);
    assert!(full < da.min(db) - 0.01);
}

/// A thin plate (1.0 × 0.04 × 0.02 m, 0.4–1.4 m from the axis) spinning at 100 rad/s sweeps
/// through a 5 cm ball at a bearing of 0.37 rad, 0.9 m out, between the samples at 0 and
/// 1 rad: both samples show 0.9·sin(0.37) − 0.07 ≈ 0.26 m and 0.9·sin(0.63) − 0.07 ≈ 0.46 m
/// of clearance; the plate overlaps the ball while it is within asin(0.07/0.9) of its bearing.
#[test]
fn regress_spinning_plate_contact_between_samples_is_found() {
    let geo = geometry(&[
        vec![
            (
                rp::SharedShape::ball(0.1),
                iso(Vector3::zeros(), UnitQuaternion::identity()),
                0.1,
            ),
            (
                rp::SharedShape::cuboid(0.5, 0.02, 0.01),
                iso(Vector3::new(0.9, 0.0, 0.0), UnitQuaternion::identity()),
                Vector3::new(0.5, 0.02, 0.01).norm(),
            ),
        ],
        vec![(
            rp::SharedShape::ball(0.05),
            iso(Vector3::zeros(), UnitQuaternion::identity()),
            0.05,
        )],
    ]);
    let inertia = [
        Matrix3::from_diagonal(&Vector3::new(5.0, 40.0, 45.0)),
        Matrix3::identity(),
    ];
    let bearing = 0.37_f64;
    let motions = [
        Motion::Screw {
            x0: Vector3::zeros(),
            v: Vector3::zeros(),
            q0: UnitQuaternion::identity(),
            w: Vector3::new(0.0, 0.0, 100.0),
        },
        Motion::Screw {
            x0: Vector3::new(0.9 * bearing.cos(), 0.9 * bearing.sin(), 0.0),
            v: Vector3::zeros(),
            q0: UnitQuaternion::identity(),
            w: Vector3::zeros(),
        },
    ];
    let motion = step_motion(&geo, vec![motions[0].path(), motions[1].path()], &inertia);
    let mut sc = DistanceScratch::default();
    let mut count = QueryCount::default();
    let d0 = monitor::pair_at(&geo, &motion, 0, 1, 0.0, None, &mut sc, &mut count);
    let d1 = monitor::pair_at(&geo, &motion, 0, 1, DT, None, &mut sc, &mut count);
    let want0 = 0.9 * bearing.sin() - 0.07;
    assert!((d0.d.value - want0).abs() < 1e-5, "{:?}", d0.d);
    assert!(d1.d.value > 0.4, "{:?}", d1.d);
    // The closest-approach search, from both samples.
    let w0 = d0.d.value.min(d1.d.value);
    let thr = |b: f64| {
        let w = w0.min(b);
        let t = w - (1e-3 * w).max(1e-6);
        if t <= 0.0 { f64::NEG_INFINITY } else { t }
    };
    monitor::pair_rate_gain(&geo, &motion, 0, 1, (d1.a, d1.b), &mut sc);
    let (r, parts) = monitor::search_parts(
        &geo,
        &motion,
        0,
        1,
        (d0.d, d1.d),
        0.0,
        thr,
        48,
        Some((d0.a, d0.b)),
        &mut sc,
        &mut count,
    );
    println!("{r:?} {parts:?}");
    let window = (0.07_f64 / 0.9).asin() / 100.0;
    let t_mid = bearing / 100.0;
    assert!(r.value <= 1e-9, "no contact found: {r:?}");
    assert!(r.lower <= 0.0);
    assert!(
        (r.t - t_mid).abs() <= window,
        "found at {} s, the overlap is {t_mid} ± {window} s",
        r.t
    );
    assert_eq!(parts, Some((1, 0)), "the plate and the ball");
    // The reference agrees: the dense minimum is a contact, and the bounds hold.
    check_step("plate", &geo, &motions, &inertia);
}

/// A whole run: a hub (ball on the spin axis) 0.3 m from a ball of the other body, and a thin
/// plate arm spinning at 100 rad/s that passes 2 cm under a second ball of that body between
/// samples (ball bearing 0.5 rad; samples at every radian). Only the sweep breaks the 5 cm
/// clearance: the guarantee must be violated, found inside an interval, with the closed-form
/// worst margin 0.02 − 0.05 = −0.03 m, and restored; the closest approach is 0.02 m, inside.
#[test]
fn regress_min_distance_broken_only_between_samples_of_a_fast_spin() {
    let (rho, h, r, gap) = (1.5_f64, 0.01_f64, 0.05_f64, 0.02_f64);
    let bearing = 0.5_f64;
    let spinner = format!(
        r#"(name: "spinner", role: Other, mass_kg: 50.0,
           inertia_kg_m2: (xx: 20.0, yy: 30.0, zz: 45.0),
           initial: (pos_m: (0.0, 0.0, 0.0), rate_body_deg_s: (0.0, 0.0, {})),
           parts: [
             Bus(name: "hub", shape: Sphere(radius_m: 0.1)),
             Bus(name: "plate", pos_m: ({}, 0.0, 0.0), shape: Box(size_m: (1.0, 0.3, {}))),
           ])"#,
        100f64.to_degrees(),
        rho,
        2.0 * h
    );
    let balls = format!(
        r#"(name: "balls", role: Other, mass_kg: 1000.0,
           inertia_kg_m2: (xx: 10.0, yy: 10.0, zz: 10.0),
           initial: (pos_m: (0.0, 0.0, 0.0)),
           parts: [
             Bus(name: "near", pos_m: (-0.5, 0.0, 0.0), shape: Sphere(radius_m: 0.1)),
             Bus(name: "swept", pos_m: ({}, {}, {}), shape: Sphere(radius_m: {r})),
           ])"#,
        rho * bearing.cos(),
        rho * bearing.sin(),
        h + r + gap
    );
    let text = format!(
        r#"Scene(name: "spin_sweep", dt_s: {DT}, duration_s: 0.05, environment: FreeSpace,
           monitor: (allow_under_resolved: true),
           bodies: [{spinner}, {balls}],
           guarantees: [MinDistance(name: "clear_5cm", a: "spinner", b: "balls", min_m: 0.05)])"#
    );
    let loaded = load_scene_str(&text, "spin_sweep", &[]).unwrap_or_else(|e| panic!("{e}"));
    let mut sim = Simulation::new(&loaded).unwrap_or_else(|e| panic!("{e}"));
    let n = sim.steps_for(sim.scene.duration_s);
    sim.step(n);
    let s = sim.summary();
    let g = s["guarantees"]
        .as_array()
        .expect("guarantees")
        .iter()
        .find(|g| g["name"] == "clear_5cm")
        .expect("clear_5cm")
        .clone();
    println!("{g}\nmin_distance {}", s["min_distance"]);
    assert_eq!(g["verdict"], "violated", "{g}");
    assert_eq!(g["judged"], "interval");
    assert_eq!(g["first_violation_found"], "interval");
    let worst = g["worst_margin"].as_f64().expect("worst");
    // Refined to 0.1 % of the violation (NEGATIVE_MARGIN_REL_TOL) plus parry's f32 precision.
    assert!(
        (worst - (gap - 0.05)).abs() <= 1e-3 * 0.03 + 1e-5,
        "worst margin {worst}, want {}",
        gap - 0.05
    );
    assert!(g["worst_margin_lower"].as_f64().expect("lower") <= worst);
    assert_eq!(g["worst_margin_found"], "interval");
    // Every sample clears it: the last margin is the hub's 0.3 m less 5 cm.
    let last = g["last_margin"].as_f64().expect("last");
    assert!(last > 0.2, "{last}");
    // The closest approach, found between samples, to its 0.1 % tolerance.
    let d = s["min_distance"]["value_m"].as_f64().expect("min distance");
    assert!((d - gap).abs() <= 1e-3 * gap + 1e-5, "closest approach {d}");
    // No contact happened (the plate passes 2 cm under the ball).
    assert!(s["first_contact_s"].is_null(), "{}", s["first_contact_s"]);
}

/// Soundness beyond the resolved rotation: a body spinning at 100 rad/s far (≈ 2 m) from a
/// ball, with `MinDistance` (its rate bound rests on the spin: Ω·extent) and `KeepOutSphere`
/// (centres of mass only). At dt = 10 ms every step turns the spinner 1 rad, more than the
/// 0.3 rad for which the rate bounds' RK4 allowance is argued (`UNDER_RESOLVED_TURN_RAD`), so
/// `MinDistance` is not proven and must be `unresolved`, never `held`; `KeepOutSphere`, whose
/// bound reads no rotation, is still `held`. At dt = 1 ms (0.1 rad per step) both are `held`.
/// Reference: the geometry (the plate's far corner stays ≥ 1.3 m from the ball at all angles).
#[test]
fn val_guarantee_resting_on_an_under_resolved_rotation_is_not_held() {
    let verdicts = |dt: f64| {
        let text = format!(
            r#"Scene(name: "fast_spin", dt_s: {dt}, duration_s: 0.1, environment: FreeSpace,
               monitor: (allow_under_resolved: true),
               bodies: [
                 (name: "spinner", role: Other, mass_kg: 50.0,
                  inertia_kg_m2: (xx: 20.0, yy: 30.0, zz: 45.0),
                  initial: (pos_m: (0.0, 0.0, 0.0), rate_body_deg_s: (0.0, 0.0, {})),
                  parts: [Bus(name: "plate", pos_m: (0.5, 0.0, 0.0), shape: Box(size_m: (1.0, 0.3, 0.02)))]),
                 (name: "ball", role: Other, mass_kg: 10.0,
                  inertia_kg_m2: (xx: 1.0, yy: 1.0, zz: 1.0),
                  initial: (pos_m: (0.0, 0.0, 2.5)),
                  parts: [Bus(name: "ball", shape: Sphere(radius_m: 0.1))]),
               ],
               guarantees: [
                 MinDistance(name: "clear_1m", a: "spinner", b: "ball", min_m: 1.0),
                 KeepOutSphere(name: "com_2m", body: "spinner", around: "ball", radius_m: 2.0),
               ])"#,
            100f64.to_degrees()
        );
        let loaded = load_scene_str(&text, "fast_spin", &[]).unwrap_or_else(|e| panic!("{e}"));
        let mut sim = Simulation::new(&loaded).unwrap_or_else(|e| panic!("{e}"));
        let n = sim.steps_for(sim.scene.duration_s);
        sim.step(n);
        let s = sim.summary();
        println!(
            "dt {dt}: under-resolved steps {}, {}",
            s["monitor"]["rotation_under_resolved_steps"], s["guarantees"]
        );
        // One event says so, at the first such step, with the step that would resolve it
        // (0.3 rad at 100 rad/s: 3 ms).
        let said: Vec<_> = sim
            .events()
            .iter()
            .filter(|e| e.kind == "rotation_under_resolved")
            .cloned()
            .collect();
        if dt > 0.005 {
            assert_eq!(said.len(), 1, "{said:?}");
            assert_eq!(said[0].data["body"], "spinner");
            let want = 0.3 / 100.0;
            let got = said[0].data["dt_s_to_resolve"].as_f64().expect("dt");
            assert!((got - want).abs() < 1e-3 * want, "{got} vs {want}");
        } else {
            assert!(said.is_empty(), "{said:?}");
        }
        let v = |name: &str| {
            s["guarantees"]
                .as_array()
                .expect("guarantees")
                .iter()
                .find(|g| g["name"] == name)
                .expect("guarantee")["verdict"]
                .as_str()
                .expect("verdict")
                .to_string()
        };
        (
            v("clear_1m"),
            v("com_2m"),
            s["monitor"]["rotation_under_resolved_steps"]
                .as_u64()
                .expect("count"),
        )
    };
    let (d, k, n) = verdicts(0.01);
    assert!(n > 0, "every step turns 1 rad");
    assert_eq!(d, "unresolved");
    assert_eq!(k, "held");
    let (d, k, n) = verdicts(0.001);
    assert_eq!(n, 0);
    assert_eq!(d, "held");
    assert_eq!(k, "held");
}

/// On a step whose rotation is under-resolved the guarantee's interval search only looks for a
/// violation: the plate of the scene above spinning at 100 rad/s (1 rad a step at dt = 10 ms)
/// under a ball on its spin axis at 1.3 m, so the margin of `MinDistance(min_m: 1.0)` is
/// 0.19 m at every angle, while the distance rate bound (≈ 100 m/s over the plate's 1 m reach)
/// does not clear zero on the whole step. Reference: the geometry — the spin axis passes
/// through the plate's inner edge, so the ball's centre is 1.29 m from the plate's top face at
/// all angles, 1.19 m from its surface. The guarantee is `unresolved` (never `held`, never
/// `violated`), its worst margin the closed-form 0.19 m (to parry's f32: 1e-5 m), and the
/// search only proves the margin above zero (docs/verification.md; at most 32 evaluations,
/// `UNRESOLVED_LOOK_EVALS`). Its cost, in closed form: the plate's per-part rate is
/// L = Ω·(0.5 m + ρ) with ρ = |(0.5, 0.15, 0.01)| m = 0.522 m, so L·dt = 1.02 m; a piece of width
/// w clears zero when (0.19 + 0.19 − L·w)/2 ≥ 0, i.e. at w = dt/4: two bisection levels, 3
/// evaluations a step. Refining the worst margin to 10 % (threshold 0.171 m) as on a proven step
/// needs L·w ≤ 0.038 m: five levels, 31 evaluations a step (main before this change: 310 over
/// the 10 steps).
#[test]
fn val_under_resolved_step_only_looks_for_a_violation() {
    let text = format!(
        r#"Scene(name: "fast_spin_near", dt_s: 0.01, duration_s: 0.1, environment: FreeSpace,
           monitor: (allow_under_resolved: true),
           bodies: [
             (name: "spinner", role: Other, mass_kg: 50.0,
              inertia_kg_m2: (xx: 20.0, yy: 30.0, zz: 45.0),
              initial: (pos_m: (0.0, 0.0, 0.0), rate_body_deg_s: (0.0, 0.0, {})),
              parts: [Bus(name: "plate", pos_m: (0.5, 0.0, 0.0), shape: Box(size_m: (1.0, 0.3, 0.02)))]),
             (name: "ball", role: Other, mass_kg: 10.0,
              inertia_kg_m2: (xx: 1.0, yy: 1.0, zz: 1.0),
              initial: (pos_m: (0.0, 0.0, 1.3)),
              parts: [Bus(name: "ball", shape: Sphere(radius_m: 0.1))]),
           ],
           guarantees: [MinDistance(name: "clear_1m", a: "spinner", b: "ball", min_m: 1.0)])"#,
        100f64.to_degrees()
    );
    let loaded = load_scene_str(&text, "fast_spin_near", &[]).unwrap_or_else(|e| panic!("{e}"));
    let mut sim = Simulation::new(&loaded).unwrap_or_else(|e| panic!("{e}"));
    let n = sim.steps_for(sim.scene.duration_s);
    sim.step(n);
    let s = sim.summary();
    let g = s["guarantees"]
        .as_array()
        .expect("guarantees")
        .iter()
        .find(|g| g["name"] == "clear_1m")
        .expect("clear_1m")
        .clone();
    println!("{g}");
    assert_eq!(s["monitor"]["rotation_under_resolved_steps"], n);
    assert_eq!(g["verdict"], "unresolved", "{g}");
    let worst = g["worst_margin"].as_f64().expect("worst");
    assert!((worst - 0.19).abs() <= 1e-5, "worst margin {worst}");
    let evals = g["interval_evaluations"].as_u64().expect("evals");
    assert!(
        evals > 0,
        "the bound does not clear zero: the search must look"
    );
    assert!(evals <= 3 * n, "{evals} evaluations over {n} steps");
}

/// Hostile input (an initial spin past the step's resolution): a scene whose initial spin turns a body by more than
/// `UNDER_RESOLVED_TURN_RAD` (0.3 rad) a step is refused at load, located at the rate field, with
/// the step that would resolve it (0.3 rad / 100 rad/s = 0.003 s), unless the monitor is told
/// to run it anyway. Reference: the turn per step |ω|·dt = 100 rad/s × 0.01 s = 1 rad.
#[test]
fn regress_spin_beyond_the_resolved_turn_is_refused_unless_allowed() {
    let text = |allow: &str| {
        format!(
            r#"Scene(name: "fast_spin_refused", dt_s: 0.01, duration_s: 0.1, environment: FreeSpace,
           {allow}
           bodies: [
             (name: "spinner", role: Other, mass_kg: 50.0,
              inertia_kg_m2: (xx: 20.0, yy: 30.0, zz: 45.0),
              initial: (pos_m: (0.0, 0.0, 0.0), rate_body_deg_s: (0.0, 0.0, {})),
              parts: [Bus(name: "plate", pos_m: (0.5, 0.0, 0.0), shape: Box(size_m: (1.0, 0.3, 0.02)))]),
           ])"#,
            100f64.to_degrees()
        )
    };
    let Err(err) = load_scene_str(&text(""), "fast_spin_refused", &[]) else {
        panic!("a 1 rad step is refused");
    };
    assert_eq!(err.field, "bodies.spinner.initial.rate_body_deg_s", "{err}");
    assert_eq!(err.line, 6, "{err}");
    assert!(err.message.contains("turns the body 1 rad"), "{err}");
    assert!(err.message.contains("dt_s ≤ 0.003 s"), "{err}");
    assert!(
        err.message.contains("allow_under_resolved"),
        "the message names the way to run it anyway: {err}"
    );
    // At the resolving step the same spin is accepted; and allowed, the 1 rad step runs.
    let resolved = text("").replace("dt_s: 0.01,", "dt_s: 0.003,");
    load_scene_str(&resolved, "fast_spin_refused", &[]).unwrap_or_else(|e| panic!("{e}"));
    let allowed = text("monitor: (allow_under_resolved: true),");
    let loaded =
        load_scene_str(&allowed, "fast_spin_refused", &[]).unwrap_or_else(|e| panic!("{e}"));
    Simulation::new(&loaded).unwrap_or_else(|e| panic!("{e}"));
}

// Faceted solids of revolution (`rpod::geometry::revolution`). Reference: brute force. The
// hull's vertices turned about the found axis through a grid of angles, each measured in f64
// against the triangles of the hull's boundary (parry's triangulation; the closest point on
// each triangle by `common::closest_on_triangle`; parry's own point projection, GJK in f32,
// reports 0 for a point 0.5 mm outside a 0.12 m cone, so it is not used): the distance to a
// convex set is convex, so the farthest point of a turned copy of the hull is one of its
// vertices, and the largest of these distances is (to the angle grid) how far the solid of
// revolution reaches beyond the hull. It must stay within the offset, and the offset within
// twice it (the bound is not loose).

/// Two rings of `n` about x at heights 0 and `len`, radii `r0`, `r1`, the second turned by
/// `phase_tip`.
fn frustum(n: usize, r0: f64, r1: f64, len: f64, phase_tip: f64) -> Vec<Vector3<f64>> {
    let mut pts = Vec::new();
    for k in 0..n {
        let phi = std::f64::consts::TAU * k as f64 / n as f64;
        pts.push(Vector3::new(0.0, r0 * phi.cos(), r0 * phi.sin()));
        let phi = phi + phase_tip;
        pts.push(Vector3::new(len, r1 * phi.cos(), r1 * phi.sin()));
    }
    pts
}

/// The largest distance from the hull of `points` (its boundary triangulated by parry,
/// measured in f64) of one of its vertices turned about the found axis by 2π·m/`angles`.
fn brute_offset(points: &[Vector3<f64>], f: &FacetedRevolution, angles: u32) -> f64 {
    let pts: Vec<Vector> = points
        .iter()
        .map(|p| Vector::new(p.x as f32, p.y as f32, p.z as f32))
        .collect();
    let hull = ConvexPolyhedron::from_convex_hull(&pts).expect("hull");
    let (vtx, idx) = hull.to_trimesh();
    let vtx: Vec<Vector3<f64>> = vtx
        .iter()
        .map(|p| Vector3::new(f64::from(p.x), f64::from(p.y), f64::from(p.z)))
        .collect();
    let inner = vtx.iter().sum::<Vector3<f64>>() / vtx.len() as f64;
    // Outward planes (n, h) of the triangles.
    let planes: Vec<(Vector3<f64>, f64)> = idx
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|k| vtx[k as usize]);
            let mut n = (b - a).cross(&(c - a)).normalize();
            if n.dot(&(inner - a)) > 0.0 {
                n = -n;
            }
            (n, n.dot(&a))
        })
        .collect();
    let axis = nalgebra::Unit::new_normalize(f.axis);
    let mut worst: f64 = 0.0;
    for p in &vtx {
        for m in 0..angles {
            let rot = nalgebra::Rotation3::from_axis_angle(
                &axis,
                std::f64::consts::TAU * f64::from(m) / f64::from(angles),
            );
            let q = f.centre_m + rot * (p - f.centre_m);
            if planes.iter().all(|(n, h)| n.dot(&q) <= *h) {
                continue;
            }
            let d = idx
                .iter()
                .map(|t| {
                    let [a, b, c] = t.map(|k| vtx[k as usize]);
                    (q - common::closest_on_triangle(q, a, b, c)).norm()
                })
                .fold(f64::INFINITY, f64::min);
            worst = worst.max(d);
        }
    }
    worst
}

#[test]
fn val_faceted_revolution_of_the_docking_cone_bounds_its_solid_of_revolution() {
    let pts = frustum(32, 0.12, 0.03, 0.25, 0.0);
    let f = faceted_revolution(&pts).expect("a faceted cone");
    assert_eq!(f.facets, 32);
    assert!((f.axis.x.abs() - 1.0).abs() < 1e-12, "{f:?}");
    let s0 = 0.12 * (1.0 - (std::f64::consts::PI / 32.0).cos());
    assert!(f.offset_m >= s0 && f.offset_m < s0 * 1.001, "{f:?}");
    let brute = brute_offset(&pts, &f, 1024);
    // The brute force measures the f32 hull: its rounding, ~1e-8 m here, is the 1e-7.
    assert!(brute <= f.offset_m + 1e-7, "{brute} > {}", f.offset_m);
    assert!(brute > 0.5 * f.offset_m, "{brute} vs {}", f.offset_m);
    // The centre is on the axis, half way along, and the radius holds every vertex.
    assert!((f.centre_m - Vector3::new(0.125, 0.0, 0.0)).norm() < 1e-12);
    assert!(pts.iter().all(|p| (p - f.centre_m).norm() <= f.radius_m));
}

#[test]
fn val_faceted_revolution_of_a_tilted_prism_and_a_pyramid() {
    let rot = nalgebra::Rotation3::from_euler_angles(0.3, -0.7, 1.1);
    let shift = Vector3::new(0.4, -1.0, 2.0);
    let prism: Vec<_> = frustum(6, 0.5, 0.5, 1.2, 0.0)
        .iter()
        .map(|p| rot * p + shift)
        .collect();
    let f = faceted_revolution(&prism).expect("a hexagonal prism");
    assert_eq!(f.facets, 6);
    assert!((f.axis.dot(&(rot * Vector3::x())).abs() - 1.0).abs() < 1e-9);
    let brute = brute_offset(&prism, &f, 384);
    assert!(
        brute <= f.offset_m + 1e-6 && brute > 0.5 * f.offset_m,
        "{brute} {f:?}"
    );
    // A pyramid: one ring of 8 and an apex on the axis.
    let mut pyramid: Vec<_> = frustum(8, 0.3, 0.0, 0.5, 0.0)
        .into_iter()
        .step_by(2)
        .collect();
    pyramid.push(Vector3::new(0.5, 0.0, 0.0));
    let f = faceted_revolution(&pyramid).expect("a pyramid");
    assert_eq!(f.facets, 8);
    let brute = brute_offset(&pyramid, &f, 512);
    assert!(
        brute <= f.offset_m + 1e-6 && brute > 0.5 * f.offset_m,
        "{brute} {f:?}"
    );
}

#[test]
fn invariant_shapes_that_are_not_faceted_revolutions_are_refused() {
    // Rings out of phase (a twisted prism): its slices are not homothetic N-gons.
    assert!(faceted_revolution(&frustum(8, 0.2, 0.2, 0.4, 0.2)).is_none());
    // A box that is not square across any of its axes.
    let mut b = Vec::new();
    for x in [-0.5, 0.5] {
        for y in [-0.3, 0.3] {
            for z in [-0.1, 0.1] {
                b.push(Vector3::new(x, y, z));
            }
        }
    }
    assert!(faceted_revolution(&b).is_none());
    // A slot wall (two corners of each of two rings).
    let wall: Vec<_> = frustum(16, 0.15, 0.15, 0.2, 0.0)
        .into_iter()
        .take(4)
        .collect();
    assert!(faceted_revolution(&wall).is_none());
    // Rings of different counts.
    let mut uneven = frustum(8, 0.2, 0.1, 0.3, 0.0);
    uneven.pop();
    assert!(faceted_revolution(&uneven).is_none());
    // Hostile values.
    assert!(faceted_revolution(&[]).is_none());
    let mut nan = frustum(8, 0.2, 0.1, 0.3, 0.0);
    nan[3].y = f64::NAN;
    assert!(faceted_revolution(&nan).is_none());
    let huge = frustum(8, 1e300, 1e300, 1e300, 0.0);
    if let Some(f) = faceted_revolution(&huge) {
        assert!(f.offset_m.is_finite() && f.radius_m.is_finite());
    }
    let flat = vec![Vector3::zeros(); 12];
    assert!(faceted_revolution(&flat).is_none());
}
