//! The monitor's broad phase: which body pairs can come within the monitor's horizon, so that
//! every other pair costs nothing per step.
//!
//! Each body gets a *fat sphere*: centre c_i, radius r_i = R_i + m_i (R_i its extent about the
//! centre of mass, m_i a travel margin). While the centre of mass stays within m_i of c_i over
//! a step — checked every step on the step's path: |x(t₀) − c_i| + (speed bound)·dt ≤ m_i —
//! all of the body's geometry stays inside the sphere, so for two bodies
//! d_ij ≥ |c_i − c_j| − r_i − r_j. A pair is *near* when that gap is at most the horizon
//! ([`BroadPhase::reach_m`]); every other pair is certified farther than the horizon and is
//! not looked at. A body that may leave its sphere gets a new one centred on its end-of-step
//! position, with a margin of about [`MARGIN_STEPS`] steps of its current speed, and only its
//! pairs are recomputed: a sweep over the spheres sorted by the x of their centres, cut off at
//! the largest radius, so a refresh costs O(log N + k) and a step O(N) plus the refreshes.
//! (Rapier's own broad phase would need its AABBs kept up to date every step, which is the
//! rapier work that free flight skips.)

use super::motion::StepMotion;
use bevy::prelude::*;
use nalgebra::Vector3;
use std::collections::BTreeSet;

/// A refreshed fat sphere's travel margin is this many steps of the body's speed bound (at
/// least [`MIN_MARGIN_M`]).
pub const MARGIN_STEPS: f64 = 50.0;

/// Smallest travel margin, m.
pub const MIN_MARGIN_M: f64 = 0.05;

/// The broad phase's state.
#[derive(Resource, Debug, Clone, Default)]
pub struct BroadPhase {
    /// The monitor's horizon: near pairs within it are tracked, m.
    pub horizon_m: f64,
    /// Pairs whose fat spheres come within this of each other are near, m: the horizon, or
    /// more where the physics stage needs to see pairs whose rapier boxes could overlap.
    pub reach_m: f64,
    /// Every pair is near (small scenes with an infinite horizon): no spheres are kept.
    pub all_pairs: bool,
    /// Fat-sphere centres, per body, m.
    pub centre: Vec<Vector3<f64>>,
    /// Fat-sphere radii (extent + margin), per body, m.
    pub radius: Vec<f64>,
    /// Travel margins, per body, m.
    pub margin: Vec<f64>,
    /// Bodies sorted by the x of their sphere centre.
    order: Vec<usize>,
    /// Near pairs (i < j).
    pub near: BTreeSet<(usize, usize)>,
    /// Sphere refreshes over the run.
    pub refreshes: u64,
}

impl BroadPhase {
    /// A broad phase for `n` bodies with the given horizon (`None`: every pair is near) and
    /// the reach the physics stage needs (`physics_reach_m`).
    pub fn new(n: usize, horizon_m: Option<f64>, physics_reach_m: f64) -> Self {
        Self {
            horizon_m: horizon_m.unwrap_or(f64::INFINITY),
            reach_m: horizon_m.map_or(f64::INFINITY, |h| h.max(physics_reach_m)),
            all_pairs: horizon_m.is_none(),
            centre: vec![Vector3::zeros(); n],
            radius: vec![f64::NAN; n],
            margin: vec![0.0; n],
            order: (0..n).collect(),
            near: BTreeSet::new(),
            refreshes: 0,
        }
    }

    /// Is the pair near (could come within the horizon)?
    pub fn is_near(&self, i: usize, j: usize) -> bool {
        self.all_pairs || self.near.contains(&(i.min(j), i.max(j)))
    }

    /// Certified lower bound of the distance between bodies i and j over the current step
    /// (from the fat spheres), m.
    pub fn sphere_gap(&self, i: usize, j: usize) -> f64 {
        (self.centre[i] - self.centre[j]).norm() - self.radius[i] - self.radius[j]
    }

    /// Brings the spheres up to date with the step's paths: every body whose centre of mass
    /// may leave its sphere during the step gets a new one, and its near pairs are recomputed.
    pub fn update(&mut self, motion: &StepMotion) {
        if self.all_pairs {
            return;
        }
        let n = motion.paths.len();
        let mut moved = Vec::new();
        for i in 0..n {
            let p = &motion.paths[i];
            let fresh = self.radius[i].is_nan();
            if fresh || p.reach_from(&self.centre[i]) > self.margin[i] {
                let speed = p.speed_max();
                let step = (p.x1 - p.x0).norm() + speed * motion.dt_s;
                let m = (speed * motion.dt_s * MARGIN_STEPS)
                    .max(MIN_MARGIN_M)
                    .max(2.0 * step);
                self.centre[i] = p.x1;
                self.margin[i] = m;
                self.radius[i] = motion.extent_m[i] + m;
                moved.push(i);
            }
        }
        if moved.is_empty() {
            return;
        }
        self.refreshes += moved.len() as u64;
        let c = &self.centre;
        self.order
            .sort_by(|a, b| c[*a].x.total_cmp(&c[*b].x).then(a.cmp(b)));
        let r_max = self.radius.iter().copied().fold(0.0, f64::max);
        for &i in &moved {
            self.near.retain(|&(a, b)| a != i && b != i);
        }
        for &i in &moved {
            let lo = self.centre[i].x - self.radius[i] - r_max - self.reach_m;
            let hi = self.centre[i].x + self.radius[i] + r_max + self.reach_m;
            let start = self.order.partition_point(|k| self.centre[*k].x < lo);
            for &j in &self.order[start..] {
                if self.centre[j].x > hi {
                    break;
                }
                if j != i && self.sphere_gap(i, j) <= self.reach_m {
                    self.near.insert((i.min(j), i.max(j)));
                }
            }
        }
    }

    /// Candidate pairs for the closest pair among all bodies at the current positions `x`
    /// (with extents `r`): every pair whose sphere bound |x_i − x_j| − r_i − r_j is below
    /// `best`, found by a sweep along x. Sorted by that bound.
    pub fn closest_candidates(
        &self,
        x: &[Vector3<f64>],
        r: &[f64],
        best: f64,
    ) -> Vec<(f64, usize, usize)> {
        let n = x.len();
        let mut idx: Vec<usize> = (0..n).collect();
        idx.sort_by(|a, b| x[*a].x.total_cmp(&x[*b].x).then(a.cmp(b)));
        let r_max = r.iter().copied().fold(0.0, f64::max);
        let mut out = Vec::new();
        for (k, &i) in idx.iter().enumerate() {
            for &j in &idx[k + 1..] {
                if x[j].x - x[i].x - r[i] - r_max >= best {
                    break;
                }
                let lb = (x[i] - x[j]).norm() - r[i] - r[j];
                if lb < best {
                    out.push((lb, i.min(j), i.max(j)));
                }
            }
        }
        out.sort_by(|a, b| a.0.total_cmp(&b.0).then((a.1, a.2).cmp(&(b.1, b.2))));
        out
    }
}
