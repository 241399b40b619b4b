//! The monitor's memo for pairs of parts with support maps (`sim::monitor::memo::convex_exact`,
//! `monitor::pair_eval`; the latched stack's cost): a kept evaluation answers a later pose
//! only with a certified bracket no wider than a fresh query's, and never near touch; it clears
//! a pair for a caller only with a lower bound that holds the closed form.
//!
//! References (independent, closed forms in f64):
//! * a ball (centre p in a box's frame, radius r) and a box (half extents h): the distance is
//!   |p − clamp(p, −h, h)| − r (the box's closest point is the clamp);
//! * two boxes with parallel axes: per axis the gap gᵢ = max(0, |cᵢ| − (hᵃᵢ + hᵇᵢ)), the distance
//!   |g| (the Minkowski difference is the box of half extents hᵃ + hᵇ).
//!
//! Tolerances: parry works in f32 — within 8 f32 ulps of the pose's scale
//! (`monitor::F32_REL_TOL`, |t_rel| + r_a + r_b) — and GJK stops within 1.2e-3 of the distance
//! (`monitor::GJK_REL_TOL`). Lower bounds are checked against the closed forms with only the f32
//! rounding as slack; values may exceed the truth by GJK's tolerance and f32's, never fall below
//! it by more than f32's.
//!
//! The filter in front of the turn's-axis bracket (`ExactEval::advance_unturned`) is checked
//! against that bracket itself at random poses: its lower bound never below, its upper bound
//! equal (a property of the two formulas, no reference needed).

mod common;

use bevy_rapier3d::rapier::prelude as rp;
use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};
use rpod::sim::monitor::memo::{self, PAIR_MEMO_MAX_PAIRS};
use rpod::sim::monitor::{
    self, F32_REL_TOL, GJK_REL_TOL, MEMO_REL_WIDTH, PairEval, TOUCH_DISTANCE_M,
};

fn iso(p: Vector3<f64>, q: UnitQuaternion<f64>) -> Isometry3<f64> {
    Isometry3::from_parts(Translation3::from(p), q)
}

/// 8 f32 ulps of the pair's scale.
fn eps(pa: &Isometry3<f64>, pb: &Isometry3<f64>, ra: f64, rb: f64) -> f64 {
    F32_REL_TOL * ((pa.translation.vector - pb.translation.vector).norm() + ra + rb)
}

/// Ball (centre `p` in the box's frame, radius `r`) to a box of half extents `h`, m.
fn ball_box(p: Vector3<f64>, h: Vector3<f64>, r: f64) -> f64 {
    let q = Vector3::new(
        p.x.clamp(-h.x, h.x),
        p.y.clamp(-h.y, h.y),
        p.z.clamp(-h.z, h.z),
    );
    (p - q).norm() - r
}

/// Two boxes with parallel axes, centres `c` apart, half extents `ha`, `hb`, m.
fn box_box(c: Vector3<f64>, ha: Vector3<f64>, hb: Vector3<f64>) -> f64 {
    let g = c.abs() - ha - hb;
    g.map(|x| x.max(0.0)).norm()
}

fn cuboid(h: Vector3<f64>) -> (rp::SharedShape, f64) {
    (
        rp::SharedShape::cuboid(h.x as f32, h.y as f32, h.z as f32),
        h.norm(),
    )
}

#[test]
fn val_pair_memo_convex_exact_brackets_the_closed_forms() {
    let h = Vector3::new(0.4, 0.25, 0.6);
    let (bx, rbx) = cuboid(h);
    let r = 0.07;
    let ball = rp::SharedShape::ball(r as f32);
    let hb = Vector3::new(0.1, 0.3, 0.05);
    let (bx2, rbx2) = cuboid(hb);
    let mut rng = rpod::math::rng::Lcg(29);
    for k in 0..400 {
        // Ball centres around the box (faces, edges, corners), 1 mm to 2 m out.
        let dir = Vector3::new(
            rng.uniform() - 0.5,
            rng.uniform() - 0.5,
            rng.uniform() - 0.5,
        )
        .normalize();
        let p = dir * (0.8 + 2.0 * rng.uniform());
        let truth = ball_box(p, h, r);
        if truth <= 1e-3 {
            continue;
        }
        let pa = Isometry3::identity();
        let pb = iso(p, UnitQuaternion::from_scaled_axis(dir * (k as f64)));
        let e = memo::convex_exact(&pa, (&*bx, rbx), &pb, (&*ball, r)).expect("support maps");
        let tol = eps(&pa, &pb, rbx, r);
        assert!(e.lower_m <= truth, "k {k}: lower {} > {truth}", e.lower_m);
        assert!(
            e.value_m >= truth - tol,
            "k {k}: value {} < {truth}",
            e.value_m
        );
        assert!(
            e.value_m <= truth * (1.0 + GJK_REL_TOL) + tol,
            "k {k}: value {} vs {truth}",
            e.value_m
        );
        // The witnesses are on the parts and their distance is the value.
        let wb = pa.inverse() * pb * e.witness_b;
        assert!(((wb - e.witness_a).norm() - e.value_m).abs() <= tol);
        assert!(
            ball_box(e.witness_a.coords, h, 0.0) <= tol,
            "witness a off the box"
        );
        assert!(
            ((wb.coords - p).norm() - r).abs() <= tol,
            "witness b off the ball"
        );

        // Two boxes, parallel axes: the value is parry's own box–box distance, bit for bit.
        let c = dir * (1.0 + 2.0 * rng.uniform());
        let truth = box_box(c, h, hb);
        if truth <= 1e-3 {
            continue;
        }
        let pb = iso(c, UnitQuaternion::identity());
        let e = memo::convex_exact(&pa, (&*bx, rbx), &pb, (&*bx2, rbx2)).expect("support maps");
        let tol = eps(&pa, &pb, rbx, rbx2);
        assert!(
            e.lower_m <= truth,
            "k {k}: box lower {} > {truth}",
            e.lower_m
        );
        assert!((e.value_m - truth).abs() <= truth * GJK_REL_TOL + tol);
        let d = monitor::shape_distance(&pa, &*bx, &pb, &*bx2);
        assert_eq!(
            e.value_m.to_bits(),
            d.to_bits(),
            "k {k}: not parry's distance"
        );
    }
}

#[test]
fn val_pair_memo_latched_pair_is_answered_by_the_memo_and_certified() {
    // A ball held 2 cm off a box face (a cone held in its slot), its pose jittering by up to
    // 10 nm and 1e-8 rad per step as a latched joint's does, for 2 000 steps: one fresh query,
    // then the memo, every bracket holding the closed form.
    let h = Vector3::new(0.4, 0.25, 0.6);
    let r = 0.07;
    let parts = [cuboid(h), (rp::SharedShape::ball(r as f32), r)];
    let g = common::one_part_bodies(&[&parts[0], &parts[1]]);
    let pa = Isometry3::identity();
    let base = Vector3::new(0.0, h.y + r + 0.02, 0.1);
    let mut rng = rpod::math::rng::Lcg(7);
    let mut from_memo = 0;
    for k in 0..2000 {
        let jitter = Vector3::new(rng.uniform(), rng.uniform(), rng.uniform()) * 1e-8;
        let p = base + jitter;
        let q = UnitQuaternion::from_scaled_axis(Vector3::new(1e-8 * rng.uniform(), 0.0, 0.0));
        let pb = iso(p, q);
        let truth = ball_box(p, h, r);
        let tol = eps(&pa, &pb, parts[0].1, r);
        let PairEval::Value(value, lower) =
            monitor::pair_eval(&g, 0, 0, &(pa, parts[0].1), 1, 0, &(pb, r), f64::INFINITY)
        else {
            panic!("nothing clears an infinite level");
        };
        assert!(lower <= truth, "step {k}: lower {lower} above {truth}");
        assert!(
            value >= truth - tol,
            "step {k}: value {value} below {truth}"
        );
        assert!(
            value - lower <= MEMO_REL_WIDTH * value + 2.0 * tol + 1e-9,
            "step {k}: bracket [{lower}, {value}] wider than allowed"
        );
        let direct = memo::convex_exact(&pa, (&*parts[0].0, parts[0].1), &pb, (&*parts[1].0, r))
            .expect("support maps");
        if k == 0 {
            assert_eq!(
                value.to_bits(),
                direct.value_m.to_bits(),
                "the first query is fresh"
            );
        }
        from_memo += usize::from(value.to_bits() != direct.value_m.to_bits());
    }
    assert_eq!(g.memo.len(), 1);
    // The carried witnesses' distance differs from a fresh f32 query in the last bits: most
    // steps are answered by the memo (a step where both agree to the bit counts as fresh).
    assert!(from_memo > 1000, "{from_memo} of 2000 steps from the memo");
}

#[test]
fn val_pair_memo_moving_pair_is_queried_fresh_and_touch_is_parrys() {
    // Free flight: the ball moves 1 mm per step towards the box face from 0.5 m, until it
    // touches, spinning 0.1 rad per step about its centre (the distance does not see the spin;
    // the memo's displacement bound must: 2·sin(0.05)·0.07 m ≈ 7 mm a step). A kept evaluation
    // never answers (the motion widens its bracket past a fresh query's), so every value is the
    // fresh query's bit for bit; below the touch distance the memo is not used either.
    let h = Vector3::new(0.4, 0.25, 0.6);
    let r = 0.07;
    let parts = [cuboid(h), (rp::SharedShape::ball(r as f32), r)];
    let g = common::one_part_bodies(&[&parts[0], &parts[1]]);
    let pa = Isometry3::identity();
    for k in 0..=500 {
        let gap = 0.5 - 1e-3 * k as f64;
        let p = Vector3::new(0.05, h.y + r + gap, -0.1);
        let spin = UnitQuaternion::from_scaled_axis(Vector3::new(0.3, 1.0, 0.2).normalize() * 0.1);
        let pb = iso(p, spin.powf(k as f64));
        let direct = memo::convex_exact(&pa, (&*parts[0].0, parts[0].1), &pb, (&*parts[1].0, r))
            .expect("support maps");
        let PairEval::Value(value, _) =
            monitor::pair_eval(&g, 0, 0, &(pa, parts[0].1), 1, 0, &(pb, r), f64::INFINITY)
        else {
            panic!("nothing clears an infinite level");
        };
        assert_eq!(value.to_bits(), direct.value_m.to_bits(), "step {k}");
        // Held still near touch: the repeat is parry's again, not the memo's.
        if gap <= TOUCH_DISTANCE_M {
            let PairEval::Value(again, _) =
                monitor::pair_eval(&g, 0, 0, &(pa, parts[0].1), 1, 0, &(pb, r), f64::INFINITY)
            else {
                panic!("nothing clears an infinite level");
            };
            assert_eq!(again.to_bits(), direct.value_m.to_bits());
        }
    }
}

#[test]
fn val_pair_memo_far_pair_is_cleared_only_by_its_certified_bound() {
    // The moving, spinning ball of the test above, asked as a caller asks a candidate pair:
    // with the best distance found so far (`clear_at`) 5 cm under this pair's true distance
    // (the pair cannot be the closest), the kept evaluation clears it while its advanced lower
    // bound stays at or above that level — the bound certified against the closed form — and
    // the pair is queried afresh (bit for bit parry's) when it does not. With `clear_at` 1 mm
    // above the truth nothing may clear it: a clear there would be a false certificate.
    let h = Vector3::new(0.4, 0.25, 0.6);
    let r = 0.07;
    let parts = [cuboid(h), (rp::SharedShape::ball(r as f32), r)];
    let pa = Isometry3::identity();
    for (below_m, expect_clears) in [(0.05, true), (-1e-3, false)] {
        let g = common::one_part_bodies(&[&parts[0], &parts[1]]);
        let (mut cleared, mut fresh) = (0, 0);
        for k in 0..=400 {
            let gap = 0.5 - 1e-3 * k as f64;
            let p = Vector3::new(0.05, h.y + r + gap, -0.1);
            let spin =
                UnitQuaternion::from_scaled_axis(Vector3::new(0.3, 1.0, 0.2).normalize() * 0.01);
            let pb = iso(p, spin.powf(k as f64));
            let truth = ball_box(p, h, r);
            let clear_at = truth - below_m;
            let tol = eps(&pa, &pb, parts[0].1, r);
            match monitor::pair_eval(&g, 0, 0, &(pa, parts[0].1), 1, 0, &(pb, r), clear_at) {
                PairEval::Clear(l) => {
                    assert!(l >= clear_at, "step {k}: cleared at {l} under {clear_at}");
                    assert!(l <= truth, "step {k}: bound {l} above the truth {truth}");
                    cleared += 1;
                }
                PairEval::Value(value, lower) => {
                    let direct =
                        memo::convex_exact(&pa, (&*parts[0].0, parts[0].1), &pb, (&*parts[1].0, r))
                            .expect("support maps");
                    assert!(lower <= truth, "step {k}: lower {lower} above {truth}");
                    assert!(
                        value >= truth - tol,
                        "step {k}: value {value} under {truth}"
                    );
                    fresh += usize::from(value.to_bits() == direct.value_m.to_bits());
                }
            }
        }
        if expect_clears {
            // The level falls with the truth (1 mm a step); the bound also loses the spin's
            // chord, 0.01 rad × 0.07 m = 0.7 mm a step since its evaluation, so the 5 cm last
            // about 70 steps: a fresh query, then about 70 steps cleared.
            assert!(cleared > 350, "{cleared} of 401 steps cleared");
            assert!((4..=10).contains(&fresh), "{fresh} fresh queries");
        } else {
            assert_eq!(cleared, 0, "a clear above the truth");
        }
    }
}

#[test]
fn val_pair_memo_is_bounded() {
    // Hostile scenes (64 bodies of 256 parts) cannot grow the cache past its limit.
    let m = memo::PairMemo::default();
    let e = memo::convex_exact(
        &Isometry3::identity(),
        (&*rp::SharedShape::ball(0.1), 0.1),
        &iso(Vector3::new(1.0, 0.0, 0.0), UnitQuaternion::identity()),
        (&*rp::SharedShape::ball(0.1), 0.1),
    )
    .expect("balls");
    for k in 0..PAIR_MEMO_MAX_PAIRS + 100 {
        m.put((k % 64, k / 64, 1, 2), e);
    }
    assert_eq!(m.len(), PAIR_MEMO_MAX_PAIRS);
    // A kept pair is still updated.
    m.put((0, 0, 1, 2), e);
    assert_eq!(m.len(), PAIR_MEMO_MAX_PAIRS);
}

#[test]
fn val_pair_memo_unturned_bracket_bounds_the_axis_bracket() {
    // `pair_eval` asks the turn's-axis bracket (`advance_parts`) only where the bracket with
    // no turn at all (`advance_unturned`) could decide: that is sound only if, at every pose,
    // the unturned lower bound is at least the axis one and the upper bounds are equal (every
    // decision needs a lower bound at least some level, for a fixed upper bound). Checked on
    // a box–box pair and a cone–box pair (the docking cone's convex hull, whose axis bound is
    // the tight one) at 2 000 random later poses each, turns up to π.
    let (bx, rbx) = cuboid(Vector3::new(0.6, 0.3, 0.2));
    let ring = |r: f64, x: f64| {
        (0..32).map(move |k| {
            let a = k as f64 * std::f64::consts::TAU / 32.0;
            rp::Vector::new(x as f32, (r * a.cos()) as f32, (r * a.sin()) as f32)
        })
    };
    let pts: Vec<rp::Vector> = ring(0.15, 0.0).chain(ring(0.04, 0.25)).collect();
    let cone = rp::SharedShape::convex_hull(&pts).expect("cone hull");
    let rcone = 0.26;
    let mut rng = rpod::math::rng::Lcg(11);
    for (a, ra) in [(&bx, rbx), (&cone, rcone)] {
        let pa = iso(Vector3::zeros(), UnitQuaternion::identity());
        let pb = iso(Vector3::new(1.5, 0.2, -0.1), UnitQuaternion::identity());
        let e = memo::convex_exact(&pa, (&**a, ra), &pb, (&*bx, rbx)).expect("support maps");
        for _ in 0..2000 {
            let r: Vec<f64> = (0..10).map(|_| rng.uniform() - 0.5).collect();
            let axis = Vector3::new(r[0], r[1], r[2]);
            let angle = std::f64::consts::PI * (r[3] + 0.5);
            let q = UnitQuaternion::from_axis_angle(&nalgebra::Unit::new_normalize(axis), angle);
            let move_a = iso(Vector3::new(r[4], r[5], r[6]) * 0.4, q);
            let pb1 = iso(
                pb.translation.vector + Vector3::new(r[7], r[8], r[9]) * 0.4,
                UnitQuaternion::identity(),
            );
            let rel = move_a.inv_mul(&pb1);
            let rel_inv = rel.inverse();
            let (lo_u, up_u) = e.advance_unturned((&rel, &rel_inv), ra, rbx);
            let (lo_x, up_x) = e.advance_parts((&rel, &rel_inv), (&**a, ra), (&*bx, rbx));
            assert_eq!(up_u, up_x, "upper bounds differ");
            assert!(
                lo_u >= lo_x,
                "unturned lower {lo_u} below the axis bound's {lo_x}"
            );
        }
    }
}
