//! The steps of the [`super::distances`] system, in its order: the body views
//! ([`refresh_views`]), the tracked pairs ([`tracked_pairs`], [`pair_slot`]), each tracked
//! pair's sample and closest approach over the step ([`track_pair`], [`refine_over_step`]), the
//! closest tracked pair ([`closest_tracked`]), the closest pair of a trajectory row when no
//! tracked pair is within the horizon ([`row_closest`]), and the closest approach over the run
//! ([`update_overall`]).

use super::super::broadphase::BroadPhase;
use super::super::motion::StepMotion;
use super::super::{BodyState, MonitorState, NamedPairs, PairMin, Roster, SimBody};
use super::{
    DistanceScratch, LazyPoses, MAX_MIN_EVALS, MonitorGeometry, PER_PART_MIN_GAIN, PartPairHit,
    QueryCount, closest_parts, closest_parts_pruned, min_distance_tolerance_m, pair_at,
    pair_rate_gain, sample_tolerance_m, search_parts,
};
use crate::geometry::bounds::{
    Bracket, MinSearch, interval_lower_bound, minimize, provable_tolerance,
};
use crate::guarantee::{BodyView, PairDistance};
use bevy::prelude::*;
use nalgebra::Vector3;

/// What every step of one [`super::distances`] run reads.
pub(super) struct Step<'a> {
    /// The monitor's geometry.
    pub geo: &'a MonitorGeometry,
    /// The bodies' paths over the last step.
    pub motion: &'a StepMotion,
    /// Simulated time now, s.
    pub t: f64,
    /// The step's number.
    pub step: u64,
}

/// The monitor's body views (`mon.bodies`) set to the bodies' states now, in roster order
/// (built when their number changes).
pub(super) fn refresh_views(
    mon: &mut MonitorState,
    roster: &Roster,
    bodies: &Query<(&SimBody, &BodyState)>,
) {
    let n = roster.bodies.len();
    if mon.bodies.len() != n {
        mon.bodies = roster
            .bodies
            .iter()
            .map(|be| {
                let (b, s) = bodies.get(*be).expect("roster body");
                BodyView {
                    name: b.name.clone(),
                    pos_m: s.pos_m,
                    vel_m_s: s.vel_m_s,
                    att: s.att,
                    omega_rad_s: s.omega_rad_s,
                }
            })
            .collect();
    }
    for (k, be) in roster.bodies.iter().enumerate() {
        let (_, s) = bodies.get(*be).expect("roster body");
        let v = &mut mon.bodies[k];
        v.pos_m = s.pos_m;
        v.vel_m_s = s.vel_m_s;
        v.att = s.att;
        v.omega_rad_s = s.omega_rad_s;
    }
}

/// The pairs (i < j) tracked this step, sorted, into `v` (its allocation reused): every pair of
/// the `n` bodies when all are tracked; else the broad phase's near pairs whose bounding
/// spheres are within the horizon, and the pairs a guarantee names.
pub(super) fn tracked_pairs(
    bp: &BroadPhase,
    named: &NamedPairs,
    n: usize,
    v: &mut Vec<(usize, usize)>,
) {
    v.clear();
    if bp.all_pairs {
        v.extend((0..n).flat_map(|i| (i + 1..n).map(move |j| (i, j))));
    } else {
        v.extend(
            bp.near
                .iter()
                .copied()
                .filter(|(i, j)| bp.sphere_gap(*i, *j) <= bp.horizon_m),
        );
        v.extend(named.0.iter().copied());
        v.sort_unstable();
        v.dedup();
    }
}

/// The slot k of pair (i, j) in `mon.pairs`, `mon.min_per_pair` and
/// `mon.min_clearance_per_pair`, so that the tracked pairs keep a stable order: a pair joins
/// the list when first tracked (at `t`, s, with no distance yet) and keeps its place.
pub(super) fn pair_slot(mon: &mut MonitorState, (i, j): (usize, usize), t: f64) -> usize {
    if let Some(k) = mon.pair_index.get(&(i, j)) {
        return *k;
    }
    let k = mon.pairs.len();
    mon.pair_index.insert((i, j), k);
    mon.pairs.push(PairDistance {
        a: i,
        b: j,
        distance_m: f64::INFINITY,
        part_a: 0,
        part_b: 0,
        clearance_m: f64::INFINITY,
        lower_m: f64::INFINITY,
        t_s: f64::NAN,
    });
    mon.min_per_pair.push(PairMin {
        distance_m: f64::INFINITY,
        part_a: 0,
        part_b: 0,
        t_s: t,
        inside: false,
        tolerance_m: 0.0,
    });
    mon.min_clearance_per_pair.push(f64::INFINITY);
    k
}

/// Body b's world part poses for this step in `sc.poses[b]`, computed once per step from its
/// view in `views`.
fn ensure_part_poses(s: &Step, views: &[BodyView], b: usize, sc: &mut DistanceScratch) {
    if sc.poses[b].0 != s.step {
        let v = &views[b];
        let (pos, att) = (v.pos_m, v.att);
        s.geo.part_poses(b, &pos, &att, &mut sc.poses[b].1);
        sc.poses[b].0 = s.step;
    }
}

/// Body b's part poses for this step computed on first use (`sc.lazy[b]`, emptied at each new
/// step).
fn ensure_lazy_poses(s: &Step, b: usize, sc: &mut DistanceScratch) {
    let n = s.geo.pose_body[b].len();
    let (stamp, cells) = &mut sc.lazy[b];
    if *stamp != s.step || cells.len() != n {
        if cells.len() == n {
            cells.iter_mut().for_each(|c| {
                c.take();
            });
        } else {
            *cells = (0..n).map(|_| std::cell::OnceCell::new()).collect();
        }
        *stamp = s.step;
    }
}

/// One tracked pair (i, j) in slot k: its sample now (the distance with its certified lower
/// bound, the closest parts, and the clearance of the parts other than two docking parts, when
/// two docking parts are the closest), its closest approach over the run judged on
/// [t − dt, t] ([`refine_over_step`]), and its smallest clearance.
pub(super) fn track_pair(
    s: &Step,
    mon: &mut MonitorState,
    sc: &mut DistanceScratch,
    count: &mut QueryCount,
    (i, j): (usize, usize),
    k: usize,
) {
    let (geo, t) = (s.geo, s.t);
    for b in [i, j] {
        ensure_lazy_poses(s, b, sc);
    }
    let prev = mon.pairs[k].clone();
    let fresh_prev = prev.t_s.is_finite();
    let warm = fresh_prev.then_some((prev.part_a, prev.part_b));
    if sc.prune.len() <= k {
        sc.prune.resize_with(k + 1, Default::default);
    }
    let (vi, vj) = (&mon.bodies[i], &mon.bodies[j]);
    let hit = {
        let li = LazyPoses::new(geo, i, (&vi.pos_m, &vi.att), &sc.lazy[i].1);
        let lj = LazyPoses::new(geo, j, (&vj.pos_m, &vj.att), &sc.lazy[j].1);
        closest_parts_pruned(
            geo,
            i,
            &li,
            j,
            &lj,
            warm,
            &mut sc.candidates,
            &mut sc.evaluated,
            count,
            (&mut sc.prune[k], [(vi.pos_m, vi.att), (vj.pos_m, vj.att)]),
        )
    };
    let (dock_i, dock_j) = (&geo.docking[i], &geo.docking[j]);
    let clearance = if geo.has_docking[i] && geo.has_docking[j] && dock_i[hit.a] && dock_j[hit.b] {
        for b in [i, j] {
            ensure_part_poses(s, &mon.bodies, b, sc);
        }
        let (pi, pj) = (&sc.poses[i].1, &sc.poses[j].1);
        closest_parts(
            geo,
            i,
            pi,
            j,
            pj,
            &|a, b| !(dock_i[a] && dock_j[b]),
            None,
            false,
            &mut sc.candidates,
            &mut sc.evaluated,
            count,
        )
        .d
        .value
    } else {
        hit.d.value
    };
    mon.pairs[k] = PairDistance {
        a: i,
        b: j,
        distance_m: hit.d.value,
        part_a: hit.a,
        part_b: hit.b,
        clearance_m: clearance,
        lower_m: hit.d.lower,
        t_s: t,
    };
    // The closest approach over the run, judged on [t − dt, t].
    let w = mon.min_per_pair[k].distance_m;
    let mut best = PairMin {
        distance_m: hit.d.value,
        part_a: hit.a,
        part_b: hit.b,
        t_s: t,
        inside: false,
        tolerance_m: sample_tolerance_m(&hit.d),
    };
    let dt = s.motion.dt_s;
    if s.motion.ready && fresh_prev && (prev.t_s - (t - dt)).abs() <= 1e-9 * t.max(1.0) {
        let (inside, faceted) = refine_over_step(s, mon, sc, count, (i, j), (&prev, &hit), w);
        // A spinning faceted cone is judged to its own tolerance, sample or not.
        best.tolerance_m = best.tolerance_m.max(faceted);
        if let Some(inside) = inside {
            best = inside;
        }
    }
    if !mon.min_per_pair[k].distance_m.is_finite() || best.distance_m < w {
        mon.min_per_pair[k] = best;
    }
    let c = &mut mon.min_clearance_per_pair[k];
    *c = c.min(clearance);
}

/// Between the previous sample `prev` (at t − dt) and this one `hit` of pair (i, j), the
/// distance is at least (d(t₀) + d(t₁) − S·dt)/2 with S the pair's distance-rate bound; where
/// that could undercut the closest approach so far `w` (m) by more than its tolerance (where
/// that does not clear, at least [`faceted_tolerance`], returned when it widened it), the
/// step is searched on the bodies' paths ([`closest_in_step`]). Counts the search's
/// evaluations and its certified lower bound in `mon`; returns the closest approach inside the
/// step if it is below this sample's distance.
#[allow(clippy::too_many_arguments)]
fn refine_over_step(
    s: &Step,
    mon: &mut MonitorState,
    sc: &mut DistanceScratch,
    count: &mut QueryCount,
    (i, j): (usize, usize),
    (prev, hit): (&PairDistance, &PartPairHit),
    w: f64,
) -> (Option<PairMin>, f64) {
    let (t, dt) = (s.t, s.motion.dt_s);
    let rate = s.motion.distance_rate_bound(i, j);
    let d0 = Bracket {
        value: prev.distance_m,
        lower: prev.lower_m,
    };
    // A distance is never negative: a threshold at or under zero (the pair has touched
    // already) is cleared by every sub-interval, whatever the rate bound (no refinement
    // while two bodies stay in contact, latched or not).
    // A closest pair whose certified lower bound is farther below its value than the
    // tolerance (a mesh part's, d·GJK_REL_TOL below; a faceted cone against a wall,
    // where the gap along GJK's witness direction falls short of the distance) could
    // never have the tolerance proved: the search would spend its budget every step
    // and still not prove it. Its tolerance is twice its own bracket's width (the bound
    // stays certified; only how close the recorded closest approach is to the true one
    // changes, by that width, and the summary's `tolerance_m` says so).
    let base = provable_tolerance(&hit.d, &d0);
    let thr_with = |slack: f64| {
        move |b: f64| {
            let w = w.min(b);
            let t = w - min_distance_tolerance_m(w).max(slack);
            if t <= 0.0 { f64::NEG_INFINITY } else { t }
        }
    };
    let quick = interval_lower_bound(d0.lower, hit.d.lower, rate, dt).max(0.0);
    if quick >= thr_with(base)(hit.d.value) {
        return (None, 0.0);
    }
    // Only a step the usual tolerance does not clear at once asks whether a spinning faceted
    // cone sets a wider one.
    let (faceted, gain) = faceted_tolerance(s, sc, (i, j), hit);
    let used = if faceted > base { faceted } else { 0.0 };
    let slack = base.max(faceted);
    let thr = thr_with(slack);
    if quick >= thr(hit.d.value) {
        return (None, used);
    }
    let (r, parts) = closest_in_step(s, sc, count, (i, j), (d0, hit, rate), thr, gain);
    let (pa, pb) = parts.unwrap_or((prev.part_a, prev.part_b));
    mon.interval_evals += u64::from(r.evals);
    let mut inside = None;
    if r.value < hit.d.value && r.t < dt {
        inside = Some(PairMin {
            distance_m: r.value,
            part_a: pa,
            part_b: pb,
            t_s: t - dt + r.t,
            inside: r.t > 0.0,
            tolerance_m: min_distance_tolerance_m(r.value).max(slack),
        });
    }
    mon.min_lower_m = mon.min_lower_m.min(r.lower.max(0.0));
    (inside, used)
}

/// The tolerance of the closest approach of pair (i, j) when its closest parts `hit` include a
/// faceted solid of revolution turning fast about its axis (the docking cone spinning with
/// the chaser), m: 2s + L′_pq·dt/2, with s the parts' summed offsets ([`super::Faceted`]) and
/// L′_pq the pair's rate through its solid of revolution ([`super::PairRate`]); else 0. The
/// facets then move faster than any affordable bisection resolves (at 100 rad/s, 12 m/s: the
/// distance dips by up to s five times a step), and the bound through the solid of revolution
/// ([`super::PairRate::interval_lower`]) over a whole step is s + L′·dt/2 below the samples'
/// lower bounds, which are themselves up to s below the true distance: that is what the bound
/// proves without bisecting the step, as the closest pair's own bracket sets the tolerance of
/// a pair GJK cannot resolve ([`crate::geometry::bounds::provable_tolerance`]). Used only when
/// what the spin adds to the pair's rate over half the step, (L_pq − L′_pq)·dt/2, exceeds
/// it, and only on a step the usual tolerance does not clear at once; a slow cone keeps the
/// 0.1 % tolerance. The bound stays certified; only how close the recorded closest approach is
/// to the true one changes, and `min_distance.tolerance_m` says by how much (2.1 mm for the
/// docking cone at 100 rad/s: s = 0.58 mm, L′ = 0.18 m/s, nearly all of it the allowance for
/// RK4's departure from Euler's equations on the two other axes).
fn faceted_tolerance(
    s: &Step,
    sc: &mut DistanceScratch,
    (i, j): (usize, usize),
    hit: &PartPairHit,
) -> (f64, Option<(f64, f64)>) {
    let off = |b: usize, p: usize| {
        s.geo.pieces[b]
            .get(p)
            .and_then(|x| x.faceted)
            .map_or(0.0, |f| f.offset_m)
    };
    let offset = off(i, hit.a) + off(j, hit.b);
    // What the spin adds to the pair's rate is at most the bodies' rotation terms.
    let m = s.motion;
    let spin = m.omega_bound(i) * m.extent_m[i] + m.omega_bound(j) * m.extent_m[j];
    if offset <= 0.0 || 0.5 * spin * m.dt_s <= 2.0 * offset {
        return (0.0, None);
    }
    let gain = pair_rate_gain(s.geo, s.motion, i, j, (hit.a, hit.b), sc);
    let pair_rate = gain.0;
    let nj = s.geo.shapes[j].len();
    let Some(r) = sc.rates.get(hit.a * nj + hit.b) else {
        return (0.0, Some(gain));
    };
    let tol = 2.0 * offset + 0.5 * r.revolved_m_s * s.motion.dt_s;
    // What the spin about the axis adds to the pair's rate over half the step must exceed it:
    // a pair whose rate is its drift gains nothing from the solid of revolution.
    let tol = if 0.5 * (pair_rate - r.revolved_m_s) * s.motion.dt_s > tol {
        tol
    } else {
        0.0
    };
    (tol, Some(gain))
}

/// The search for the closest approach of pair (i, j) over the step, from the brackets `d0`
/// (at t − dt) and of `hit` (now) to the threshold `thr`: the per-part-pair bounds
/// ([`search_parts`]) for a body turning fast (the bodies' rate bound at least
/// [`PER_PART_MIN_GAIN`] times that of the closest part pair), else the bodies' bound
/// ([`minimize`] with the pair's distance-rate bound `rate`, m/s). Returns the search and the
/// closest parts where its minimum was found, if that was at an evaluated point. `gain`: the
/// pair's [`pair_rate_gain`] if the caller has just computed it (its rates still in `sc`).
fn closest_in_step(
    s: &Step,
    sc: &mut DistanceScratch,
    count: &mut QueryCount,
    (i, j): (usize, usize),
    (d0, hit, rate): (Bracket, &PartPairHit, f64),
    thr: impl Fn(f64) -> f64,
    gain: Option<(f64, f64)>,
) -> (MinSearch, Option<(usize, usize)>) {
    let (geo, motion) = (s.geo, s.motion);
    let dt = motion.dt_s;
    // A body turning fast: the per-part-pair bounds (`search_parts`).
    let (pair_rate, body_rate) =
        gain.unwrap_or_else(|| pair_rate_gain(geo, motion, i, j, (hit.a, hit.b), sc));
    if body_rate >= PER_PART_MIN_GAIN * pair_rate {
        let (r, parts) = search_parts(
            geo,
            motion,
            i,
            j,
            (d0, hit.d),
            0.0,
            thr,
            MAX_MIN_EVALS,
            Some((hit.a, hit.b)),
            sc,
            count,
        );
        (r, parts)
    } else {
        let mut at = (hit.a, hit.b);
        let mut parts_at = Vec::new();
        let r = minimize(dt, d0, hit.d, rate, thr, MAX_MIN_EVALS, dt * 1e-9, |tau| {
            let h = pair_at(geo, motion, i, j, tau, Some(at), sc, count);
            at = (h.a, h.b);
            parts_at.push((tau, h.a, h.b));
            h.d
        });
        let parts = parts_at.iter().find(|p| p.0 == r.t).map(|p| (p.1, p.2));
        (r, parts)
    }
}

/// The closest pair now (`mon.closest`): the first smallest among the pairs sampled at `t`
/// (s), in list order.
pub(super) fn closest_tracked(mon: &mut MonitorState, t: f64) {
    let mut closest: Option<usize> = None;
    for (k, p) in mon.pairs.iter().enumerate() {
        if p.t_s == t && closest.is_none_or(|c| p.distance_m < mon.pairs[c].distance_m) {
            closest = Some(k);
        }
    }
    mon.closest = closest.map(|k| mon.pairs[k].clone());
}

/// For a trajectory row, when no tracked pair is within the horizon, the closest pair may be
/// any: a best-first search over the broad phase's candidates (their bounding-sphere gaps as
/// lower bounds), starting from the last row's closest pair, replaces `mon.closest` with the
/// closest pair found.
pub(super) fn row_closest(
    s: &Step,
    mon: &mut MonitorState,
    sc: &mut DistanceScratch,
    count: &mut QueryCount,
    bp: &BroadPhase,
) {
    let (geo, t) = (s.geo, s.t);
    let mut best = mon.closest.as_ref().map_or(f64::INFINITY, |p| p.distance_m);
    if best <= bp.horizon_m {
        return;
    }
    let mut found: Option<PairDistance> = None;
    let mut cands = Vec::new();
    if let Some((i, j)) = mon.row_closest_pair {
        cands.push((f64::NEG_INFINITY, i, j));
    }
    let x: Vec<Vector3<f64>> = mon.bodies.iter().map(|b| b.pos_m).collect();
    let mut swept = false;
    let mut k = 0;
    while k < cands.len() || !swept {
        if k == cands.len() {
            cands.extend(bp.closest_candidates(&x, &geo.extent_m, best));
            swept = true;
            continue;
        }
        let (lb, i, j) = cands[k];
        k += 1;
        if lb >= best {
            break;
        }
        for b in [i, j] {
            ensure_part_poses(s, &mon.bodies, b, sc);
        }
        let hit = closest_parts(
            geo,
            i,
            &sc.poses[i].1,
            j,
            &sc.poses[j].1,
            &|_, _| true,
            None,
            false,
            &mut sc.candidates,
            &mut sc.evaluated,
            count,
        );
        if hit.d.value < best || found.is_none() && hit.d.value <= best {
            best = hit.d.value;
            found = Some(PairDistance {
                a: i,
                b: j,
                distance_m: hit.d.value,
                part_a: hit.a,
                part_b: hit.b,
                clearance_m: hit.d.value,
                lower_m: hit.d.lower,
                t_s: t,
            });
        }
    }
    if let Some(f) = &found {
        mon.row_closest_pair = Some((f.a, f.b));
    }
    if found.is_some() {
        mon.closest = found;
    }
}

/// The closest approach over the run (`mon.overall` and its pair): the closest pair now (at
/// `t`, s) if it is closer, then any pair's closest approach found inside a step (interval
/// minima can undercut the sampled overall minimum).
pub(super) fn update_overall(mon: &mut MonitorState, t: f64) {
    if let Some(c) = mon.closest.clone()
        && mon
            .overall
            .as_ref()
            .is_none_or(|o| c.distance_m < o.distance_m)
    {
        // The pair's own record of this sample may carry a wider tolerance (a spinning
        // faceted cone's, `faceted_tolerance`).
        let own = mon
            .pair_index
            .get(&(c.a, c.b))
            .and_then(|k| mon.min_per_pair.get(*k))
            .filter(|m| m.t_s == t && !m.inside && m.distance_m == c.distance_m)
            .map_or(0.0, |m| m.tolerance_m);
        mon.overall = Some(PairMin {
            distance_m: c.distance_m,
            part_a: c.part_a,
            part_b: c.part_b,
            t_s: t,
            inside: false,
            tolerance_m: sample_tolerance_m(&Bracket {
                value: c.distance_m,
                lower: c.lower_m,
            })
            .max(own),
        });
        mon.overall_pair = (c.a, c.b);
    }
    let mut under: Option<usize> = None;
    for (k, m) in mon.min_per_pair.iter().enumerate() {
        let cur = under.map_or(mon.overall.as_ref().map(|o| o.distance_m), |u| {
            Some(mon.min_per_pair[u].distance_m)
        });
        if m.inside && cur.is_none_or(|o| m.distance_m < o) {
            under = Some(k);
        }
    }
    if let Some(k) = under {
        mon.overall_pair = (mon.pairs[k].a, mon.pairs[k].b);
        mon.overall = Some(mon.min_per_pair[k].clone());
    }
}
