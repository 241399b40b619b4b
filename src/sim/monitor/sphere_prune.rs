//! The bounding-sphere gaps of a tracked body pair's part pairs, carried from step to step, so
//! that the closest-parts search ([`super::closest_parts_pruned`]) computes only the gaps that
//! the bodies' motion since could have brought under the best distance.
//!
//! Each step the search of a tracked pair starts from its warm part pair's distance δ and keeps
//! as candidates the part pairs whose bounding-sphere gap g_ab = |c_a − c_b| − r_a − r_b is
//! below δ (the others cannot be closer). Computing every gap costs n_i·n_j norms a step (180
//! for `free_drift`'s winged bodies, the largest item of its monitor), although between two
//! steps a gap moves by millimetres.
//!
//! **The bound.** Part a's bounding-sphere centre is c_a = x_i + R_i·p_a, with x_i body i's
//! centre of mass, R_i its attitude and p_a fixed in the body. Between a reference pose (x⁰, R⁰)
//! and the pose now,
//!
//! (c_a − c_b) − (c_a⁰ − c_b⁰) = Δ(x_i − x_j) + (R_i − R_i⁰)·p_a − (R_j − R_j⁰)·p_b,
//!
//! and |(R − R⁰)p| = |(R·R⁰ᵀ − I)·R⁰p| ≤ 2·sin(θ/2)·|p|, θ the angle of R·R⁰ᵀ (‖Q − I‖ = 2·sin(θ/2)
//! for a rotation Q). So every gap has moved by at most
//!
//! D = |Δ(x_i − x_j)| + 2·sin(θ_i/2)·ρ_i + 2·sin(θ_j/2)·ρ_j,
//!
//! ρ the largest |p_a| of the body's parts — between the two poses, whatever path joined them
//! (nothing about the motion in between is assumed, so a jump, a contact or a latch is covered).
//! D carries a rounding allowance of 10⁻⁹ of the positions' and radii's scale, far above the
//! f64 rounding of the gaps (a few ulps of the same scale).
//!
//! **What is kept.** At a reference step every gap is computed (the plain loop) and the
//! [`HEAD`] pairs of smallest gap are kept with their gaps, and the smallest gap of the others
//! (`rest_min`). At a later step, if rest_min − D ≥ δ no pair outside the head can be a
//! candidate; a head pair whose kept gap less D is at least δ cannot either; the gaps of the
//! other head pairs are computed exactly as the plain loop computes them. If rest_min − D < δ
//! (or anything is not finite) the step runs the plain loop and takes a new reference.
//!
//! **Exactness.** The candidates — so the search's evaluations in their order, its result and
//! its counters — are those of the plain loop: only pairs proven at or above δ are skipped, and
//! each skipped pair is counted as pruned, as the loop counts it. Where the bound keeps failing
//! (bodies in contact, δ = 0) the reference is retaken only after a growing number of plain
//! steps ([`MAX_BACKOFF`]), so such a pair pays at most a small fraction more than the loop.
//! Tests: this module's (the bound against every pair's exact gap at every step of a tumbling
//! pair and of a fast spin with jumps; the candidates and the pruned count against the plain
//! loop's; non-finite poses and changed part counts); every golden output byte-identical
//! (`tests/golden.rs`, with the monitor's counters).

use super::{BodyPose, PoseSource};
use nalgebra::{UnitQuaternion, Vector3};

/// Pairs of smallest gap kept with their gaps at the reference.
pub const HEAD: usize = 32;

/// Most plain steps between two failed walks before a new reference is taken.
pub const MAX_BACKOFF: u32 = 64;

/// Rounding allowance, relative to the scale of the positions and radii.
const ROUNDING: f64 = 1e-9;

/// One tracked body pair's gaps at its reference step.
#[derive(Debug, Clone, Default)]
pub struct SpherePrune {
    /// Part counts (n_i, n_j) the reference is for (0 before the first).
    n: (usize, usize),
    /// x_i − x_j at the reference, m.
    dx: Vector3<f64>,
    /// Attitudes at the reference.
    q: [UnitQuaternion<f64>; 2],
    /// Largest distance of a part's sphere centre from its body's centre of mass, m.
    rho: [f64; 2],
    /// Scale of positions and radii at the reference, m (for the rounding allowance).
    scale: f64,
    /// (gap at the reference m, part a, part b) of the [`HEAD`] pairs of smallest gap.
    head: Vec<(f64, usize, usize)>,
    /// Smallest gap of the pairs not in `head`, m (+∞ when there are none).
    rest_min: f64,
    /// Every pair's gap at the reference step (scratch for the next reference).
    all: Vec<(f64, usize, usize)>,
    /// Plain steps left before the next reference, after a failed walk.
    wait: u32,
    /// Plain steps to wait after the next failed walk.
    backoff: u32,
}

impl SpherePrune {
    /// How far any part pair's gap can have moved since the reference, with the rounding
    /// allowance, m (NaN or ∞ when the poses are not finite, or before any reference).
    fn moved(&self, now: &[BodyPose; 2]) -> f64 {
        let dx = now[0].0 - now[1].0;
        let turn = |k: usize| {
            let q = now[k].1 * self.q[k].inverse();
            q.quaternion().imag().norm().min(1.0)
        };
        let d = (dx - self.dx).norm() + 2.0 * turn(0) * self.rho[0] + 2.0 * turn(1) * self.rho[1];
        let scale = self.scale + now[0].0.norm() + now[1].0.norm();
        d + ROUNDING * scale
    }

    /// The candidates of the closest-parts loop (pairs with gap below `best`, m, the warm pair
    /// excluded) into `candidates` from the reference, counting each skipped pair in `pruned`;
    /// `gap(a, b)` is the plain loop's gap. False (nothing pushed or counted) when the bound
    /// does not clear the pairs outside the head, or there is no reference: then the caller
    /// runs the plain loop and hands its gaps to [`Self::retake`] if [`Self::wants_reference`].
    #[allow(clippy::too_many_arguments)]
    pub fn walk(
        &mut self,
        now: &[BodyPose; 2],
        (ni, nj): (usize, usize),
        best: f64,
        warm: Option<(usize, usize)>,
        gap: impl Fn(usize, usize) -> f64,
        candidates: &mut Vec<(f64, usize, usize)>,
        pruned: &mut u64,
    ) -> bool {
        if self.wait > 0 {
            self.wait -= 1;
            return false;
        }
        if self.n != (ni, nj) {
            self.n = (0, 0);
            return false;
        }
        let d = self.moved(now);
        // (False for NaN: a bound that is not a number clears nothing.)
        let clears = self.rest_min - d >= best;
        if !clears {
            // The bound is spent: plain steps, then a new reference.
            self.n = (0, 0);
            self.wait = self.backoff;
            self.backoff = (self.backoff * 2).clamp(1, MAX_BACKOFF);
            return false;
        }
        self.backoff = 0;
        let mut warm_in_head = false;
        for &(g, a, b) in &self.head {
            if warm == Some((a, b)) {
                warm_in_head = true;
                continue;
            }
            if g - d >= best {
                *pruned += 1;
                continue;
            }
            let lb = gap(a, b);
            if lb < best {
                candidates.push((lb, a, b));
            } else {
                *pruned += 1;
            }
        }
        let rest = ni * nj - self.head.len();
        let warm_in_rest = !warm_in_head && warm.is_some_and(|(a, b)| a < ni && b < nj);
        *pruned += (rest - usize::from(warm_in_rest)) as u64;
        true
    }

    /// Whether the next plain loop should record its gaps for a new reference.
    pub fn wants_reference(&self) -> bool {
        self.wait == 0 && self.n == (0, 0)
    }

    /// The buffer the plain loop records every pair's gap in (cleared).
    pub fn gaps_buffer(&mut self) -> &mut Vec<(f64, usize, usize)> {
        self.all.clear();
        &mut self.all
    }

    /// A new reference from the plain loop's gaps (in [`Self::gaps_buffer`], every pair of
    /// the `ni` × `nj` parts) at the poses `now` and part poses `pi`, `pj` (world, with
    /// bounding radii).
    pub fn retake<P: PoseSource + ?Sized>(&mut self, now: &[BodyPose; 2], pi: &P, pj: &P) {
        let (ni, nj) = (pi.count(), pj.count());
        if self.all.len() != ni * nj {
            self.n = (0, 0);
            return;
        }
        let reach = |x: &Vector3<f64>, parts: &P| {
            (0..parts.count()).fold((0.0f64, 0.0f64), |(rho, r), a| {
                let (p, rp) = parts.at(a);
                (rho.max((p.translation.vector - x).norm()), r.max(*rp))
            })
        };
        let (rho_i, r_i) = reach(&now[0].0, pi);
        let (rho_j, r_j) = reach(&now[1].0, pj);
        self.dx = now[0].0 - now[1].0;
        self.q = [now[0].1, now[1].1];
        self.rho = [rho_i, rho_j];
        self.scale = 2.0 * (now[0].0.norm() + now[1].0.norm() + rho_i + rho_j) + r_i + r_j;
        let by_gap = |x: &(f64, usize, usize), y: &(f64, usize, usize)| x.0.total_cmp(&y.0);
        self.head.clear();
        if self.all.len() > HEAD {
            self.all.select_nth_unstable_by(HEAD, by_gap);
            self.rest_min = self.all[HEAD..]
                .iter()
                .map(|e| e.0)
                .fold(f64::INFINITY, f64::min);
            // A NaN gap outside the head: no bound holds for it.
            if self.all[HEAD..].iter().any(|e| e.0.is_nan()) {
                self.rest_min = f64::NAN;
            }
            self.head.extend_from_slice(&self.all[..HEAD]);
        } else {
            self.rest_min = f64::INFINITY;
            self.head.extend_from_slice(&self.all);
        }
        if self.rest_min.is_nan() {
            self.n = (0, 0);
            self.wait = self.backoff;
            self.backoff = (self.backoff * 2).clamp(1, MAX_BACKOFF);
        } else {
            self.n = (ni, nj);
        }
    }
}

#[cfg(test)]
mod tests {
    //! References: every pair's bounding-sphere gap computed directly in f64 from the part
    //! poses at each step (the plain loop of `closest_parts`), against which the bound D and
    //! the walk's candidates and pruned count are checked, step by step.
    use super::*;
    use crate::math::rng::Lcg;
    use nalgebra::{Isometry3, Translation3};

    /// Parts of a body: (offset from the centre of mass in the body frame, own rotation,
    /// bounding radius).
    type Parts = Vec<(Vector3<f64>, UnitQuaternion<f64>, f64)>;

    fn parts(rng: &mut Lcg, n: usize, reach: f64) -> Parts {
        (0..n)
            .map(|_| {
                let axis = rng.vec3(1.0);
                (
                    rng.vec3(reach),
                    UnitQuaternion::from_scaled_axis(axis),
                    0.05 + rng.uniform(),
                )
            })
            .collect()
    }

    /// World part poses (isometry, radius) of a body at pose `p`.
    fn world(parts: &Parts, p: &BodyPose) -> Vec<(Isometry3<f64>, f64)> {
        parts
            .iter()
            .map(|(o, q, r)| {
                (
                    Isometry3::from_parts(Translation3::from(p.0 + p.1 * o), p.1 * q),
                    *r,
                )
            })
            .collect()
    }

    fn gap(pi: &[(Isometry3<f64>, f64)], pj: &[(Isometry3<f64>, f64)], a: usize, b: usize) -> f64 {
        (pi[a].0.translation.vector - pj[b].0.translation.vector).norm() - pi[a].1 - pj[b].1
    }

    /// The plain loop: candidates (sorted) and pruned count.
    fn plain(
        pi: &[(Isometry3<f64>, f64)],
        pj: &[(Isometry3<f64>, f64)],
        best: f64,
        warm: Option<(usize, usize)>,
    ) -> (Vec<(f64, usize, usize)>, u64) {
        let (mut c, mut pruned) = (Vec::new(), 0);
        for a in 0..pi.len() {
            for b in 0..pj.len() {
                if warm == Some((a, b)) {
                    continue;
                }
                let g = gap(pi, pj, a, b);
                if g < best {
                    c.push((g, a, b));
                } else {
                    pruned += 1;
                }
            }
        }
        c.sort_by(|x, y| x.0.total_cmp(&y.0).then((x.1, x.2).cmp(&(y.1, y.2))));
        (c, pruned)
    }

    /// Flies two bodies along `path(step) -> poses`, the warm pair and the best distance as
    /// the closest-parts search would have them (the previous step's smallest gap, its gap
    /// plus `over`), and checks at every step: the bound D covers every pair's change since the
    /// reference, and a walk gives the plain loop's candidates and pruned count exactly.
    /// Returns the fraction of steps walked.
    fn fly(
        steps: usize,
        (ni, nj): (usize, usize),
        over: f64,
        path: impl Fn(usize) -> [BodyPose; 2],
    ) -> f64 {
        let mut rng = Lcg(7);
        let (pa, pb) = (parts(&mut rng, ni, 4.0), parts(&mut rng, nj, 2.5));
        let mut sp = SpherePrune::default();
        let mut warm: Option<(usize, usize)> = None;
        let mut reference: Option<Vec<f64>> = None;
        let mut walked = 0;
        for s in 0..steps {
            let now = path(s);
            let (pi, pj) = (world(&pa, &now[0]), world(&pb, &now[1]));
            let best = warm.map_or(f64::INFINITY, |(a, b)| gap(&pi, &pj, a, b) + over);
            // The bound against every pair's gap now, while a reference is held.
            if let Some(r) = &reference
                && sp.n == (ni, nj)
            {
                let d = sp.moved(&now);
                for a in 0..ni {
                    for b in 0..nj {
                        let g = gap(&pi, &pj, a, b);
                        assert!(
                            (g - r[a * nj + b]).abs() <= d,
                            "step {s}, pair ({a}, {b}): gap moved {} > D = {d}",
                            (g - r[a * nj + b]).abs()
                        );
                    }
                }
            }
            let (want, want_pruned) = plain(&pi, &pj, best, warm);
            let (mut got, mut pruned) = (Vec::new(), 0);
            let gap_fn = |a: usize, b: usize| gap(&pi, &pj, a, b);
            if sp.walk(&now, (ni, nj), best, warm, gap_fn, &mut got, &mut pruned) {
                walked += 1;
                got.sort_by(|x, y| x.0.total_cmp(&y.0).then((x.1, x.2).cmp(&(y.1, y.2))));
                assert_eq!(got, want, "step {s}: candidates");
                assert_eq!(pruned, want_pruned, "step {s}: pruned count");
            } else {
                assert!(
                    got.is_empty() && pruned == 0,
                    "step {s}: a failed walk pushed"
                );
                if sp.wants_reference() {
                    let buf = sp.gaps_buffer();
                    for a in 0..ni {
                        for b in 0..nj {
                            buf.push((gap(&pi, &pj, a, b), a, b));
                        }
                    }
                    sp.retake(&now, &pi[..], &pj[..]);
                    reference = Some(
                        (0..ni * nj)
                            .map(|k| gap(&pi, &pj, k / nj, k % nj))
                            .collect(),
                    );
                }
            }
            // The next warm pair: the smallest gap now.
            warm = (0..ni * nj)
                .map(|k| (k / nj, k % nj))
                .min_by(|x, y| gap(&pi, &pj, x.0, x.1).total_cmp(&gap(&pi, &pj, y.0, y.1)));
        }
        walked as f64 / steps as f64
    }

    fn spin(w: Vector3<f64>, t: f64) -> UnitQuaternion<f64> {
        UnitQuaternion::from_scaled_axis(w * t)
    }

    #[test]
    fn a_tumbling_pair_walks_with_the_plain_loops_candidates() {
        // free_drift-like: 12 × 15 parts 30 m apart, both tumbling at up to 3°/s, drifting at
        // 2 cm/s, dt = 10 ms.
        let dt = 0.01;
        let frac = fly(3000, (12, 15), 0.3, |s| {
            let t = s as f64 * dt;
            [
                (
                    Vector3::zeros(),
                    spin(Vector3::new(0.026, 0.007, -0.035), t),
                ),
                (
                    Vector3::new(-8.0, -30.0, 3.0) + Vector3::new(0.0, 0.02, -0.005) * t,
                    spin(Vector3::new(0.0, 0.0, 0.005), t),
                ),
            ]
        });
        assert!(frac > 0.95, "walked on {frac} of the steps");
    }

    #[test]
    fn a_fast_spin_and_jumps_keep_the_candidates_exact() {
        // 100 rad/s about a tilted axis (a turn of 1 rad a step), 2 m apart, a jump of 3 m
        // every 50 steps, and the best distance exactly the warm pair's gap: the bound is
        // spent at once, the walk must never give a wrong candidate set.
        let frac = fly(600, (9, 7), 0.0, |s| {
            let t = s as f64 * 0.01;
            let jump = (s / 50) as f64 * 3.0;
            [
                (Vector3::zeros(), spin(Vector3::new(60.0, 80.0, 0.0), t)),
                (
                    Vector3::new(2.0 + jump, 0.5, 0.0),
                    spin(Vector3::new(0.0, 0.3, 0.0), t),
                ),
            ]
        });
        assert!(frac < 0.5, "walked on {frac} of the steps");
    }

    #[test]
    fn non_finite_poses_or_new_part_counts_never_walk() {
        let mut rng = Lcg(3);
        let (pa, pb) = (parts(&mut rng, 5, 2.0), parts(&mut rng, 4, 2.0));
        let ok: [BodyPose; 2] = [
            (Vector3::zeros(), UnitQuaternion::identity()),
            (Vector3::new(20.0, 0.0, 0.0), UnitQuaternion::identity()),
        ];
        let (pi, pj) = (world(&pa, &ok[0]), world(&pb, &ok[1]));
        let mut sp = SpherePrune::default();
        let (mut c, mut pruned) = (Vec::new(), 0);
        let g = |a: usize, b: usize| gap(&pi, &pj, a, b);
        assert!(!sp.walk(&ok, (5, 4), 10.0, None, g, &mut c, &mut pruned));
        let buf = sp.gaps_buffer();
        for a in 0..5 {
            for b in 0..4 {
                buf.push((g(a, b), a, b));
            }
        }
        sp.retake(&ok, &pi[..], &pj[..]);
        assert!(sp.walk(&ok, (5, 4), 10.0, None, g, &mut c, &mut pruned));
        assert_eq!(pruned, 20);
        for bad in [f64::NAN, f64::INFINITY, 1e308] {
            let far: [BodyPose; 2] = [ok[0], (Vector3::new(bad, 0.0, 0.0), ok[1].1)];
            let (mut c, mut pruned) = (Vec::new(), 0);
            assert!(
                !sp.walk(&far, (5, 4), 10.0, None, g, &mut c, &mut pruned),
                "walked at x = {bad}"
            );
            assert!(c.is_empty() && pruned == 0);
            sp = SpherePrune::default();
            let buf = sp.gaps_buffer();
            for a in 0..5 {
                for b in 0..4 {
                    buf.push((g(a, b), a, b));
                }
            }
            sp.retake(&ok, &pi[..], &pj[..]);
        }
        // A body with another number of parts: no walk, and the next plain loop retakes.
        assert!(!sp.walk(&ok, (5, 3), 10.0, None, g, &mut c, &mut pruned));
        assert!(sp.wants_reference());
        // Too few gaps for the part counts: no reference is taken.
        sp.gaps_buffer().push((1.0, 0, 0));
        sp.retake(&ok, &pi[..], &pj[..]);
        assert!(!sp.walk(&ok, (5, 4), 10.0, None, g, &mut c, &mut pruned));
    }
}
