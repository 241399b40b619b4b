//! Guarantees: named invariants evaluated by the monitor every step (Bevy-free).
//!
//! A guarantee returns a signed **margin**: positive while it holds, negative when violated, in
//! the unit it names (metres for distances). A scene registers guarantees (min distance, keep-out
//! sphere); a controller registers its own (e.g. "chaser inside the corridor"), written against
//! [`MonitorView`], which carries the f64 truth of every body and the full-geometry distances.

use nalgebra::{UnitQuaternion, Vector3};
use serde::Serialize;

/// One body's state as the monitor sees it (f64 truth, world frame).
#[derive(Debug, Clone)]
pub struct BodyView {
    /// Body name.
    pub name: String,
    /// Centre-of-mass position, world frame, m.
    pub pos_m: Vector3<f64>,
    /// Centre-of-mass velocity, world frame, m/s.
    pub vel_m_s: Vector3<f64>,
    /// Attitude body → world.
    pub att: UnitQuaternion<f64>,
    /// Angular velocity, world frame, rad/s.
    pub omega_rad_s: Vector3<f64>,
}

/// The closest approach between two bodies' full geometry at one step.
#[derive(Debug, Clone, Serialize)]
pub struct PairDistance {
    /// Index of the first body (scene order).
    pub a: usize,
    /// Index of the second body.
    pub b: usize,
    /// Minimum distance between any part of `a` and any part of `b`, m (0 if touching).
    pub distance_m: f64,
    /// Index (in scene order of colliders) of `a`'s part of the closest pair.
    pub part_a: usize,
    /// Index of `b`'s part of the closest pair.
    pub part_b: usize,
    /// Minimum distance over the part pairs that are not both docking parts (cone/slot), m:
    /// the clearance of everything the mechanism is not meant to touch.
    pub clearance_m: f64,
}

/// What a guarantee may look at.
#[derive(Debug, Clone)]
pub struct MonitorView<'a> {
    /// Simulated time, s.
    pub t_s: f64,
    /// Bodies in scene order.
    pub bodies: &'a [BodyView],
    /// Full-geometry distances for every body pair (a < b).
    pub pairs: &'a [PairDistance],
}

impl MonitorView<'_> {
    /// Index of a body by name.
    pub fn body_index(&self, name: &str) -> Option<usize> {
        self.bodies.iter().position(|b| b.name == name)
    }
    /// The pair distance between bodies `i` and `j`.
    pub fn pair(&self, i: usize, j: usize) -> Option<&PairDistance> {
        let (a, b) = if i < j { (i, j) } else { (j, i) };
        self.pairs.iter().find(|p| p.a == a && p.b == b)
    }
}

/// A named invariant.
pub trait Guarantee: Send + Sync {
    /// Name shown in outputs.
    fn name(&self) -> &str;
    /// Unit of the margin (e.g. `m`).
    fn unit(&self) -> &str {
        "m"
    }
    /// Signed margin: ≥ 0 held, < 0 violated.
    fn margin(&self, view: &MonitorView) -> f64;
}

/// Full-geometry clearance between two bodies: distance − `min_m`.
#[derive(Debug, Clone)]
pub struct MinDistance {
    /// Name.
    pub name: String,
    /// First body index.
    pub a: usize,
    /// Second body index.
    pub b: usize,
    /// Required clearance, m.
    pub min_m: f64,
}

impl Guarantee for MinDistance {
    fn name(&self) -> &str {
        &self.name
    }
    fn margin(&self, v: &MonitorView) -> f64 {
        v.pair(self.a, self.b)
            .map_or(f64::INFINITY, |p| p.distance_m - self.min_m)
    }
}

/// Point-mass keep-out sphere: |r_body − r_around| − radius.
#[derive(Debug, Clone)]
pub struct KeepOutSphere {
    /// Name.
    pub name: String,
    /// Checked body index.
    pub body: usize,
    /// Centre body index.
    pub around: usize,
    /// Radius, m.
    pub radius_m: f64,
}

impl Guarantee for KeepOutSphere {
    fn name(&self) -> &str {
        &self.name
    }
    fn margin(&self, v: &MonitorView) -> f64 {
        (v.bodies[self.body].pos_m - v.bodies[self.around].pos_m).norm() - self.radius_m
    }
}

/// Running record of one guarantee over a run.
#[derive(Debug, Clone, Serialize)]
pub struct GuaranteeStatus {
    /// Name.
    pub name: String,
    /// Unit of the margins.
    pub unit: String,
    /// True if the margin was ≥ 0 at every evaluated step.
    pub held: bool,
    /// First time the margin went negative, s.
    pub first_violation_s: Option<f64>,
    /// Smallest margin seen.
    pub worst_margin: f64,
    /// Time of the smallest margin, s.
    pub worst_margin_t_s: f64,
    /// Margin at the last evaluated step.
    pub last_margin: f64,
}

impl GuaranteeStatus {
    /// A fresh status.
    pub fn new(name: &str, unit: &str) -> Self {
        Self {
            name: name.to_string(),
            unit: unit.to_string(),
            held: true,
            first_violation_s: None,
            worst_margin: f64::INFINITY,
            worst_margin_t_s: 0.0,
            last_margin: f64::INFINITY,
        }
    }

    /// Folds in one evaluation; returns `Some(true)` on a new violation, `Some(false)` when a
    /// violated guarantee holds again, `None` otherwise.
    pub fn update(&mut self, t_s: f64, margin: f64) -> Option<bool> {
        let was_ok = self.last_margin >= 0.0;
        self.last_margin = margin;
        if margin < self.worst_margin {
            self.worst_margin = margin;
            self.worst_margin_t_s = t_s;
        }
        let ok = margin >= 0.0;
        if !ok {
            self.held = false;
            if self.first_violation_s.is_none() {
                self.first_violation_s = Some(t_s);
            }
        }
        match (was_ok, ok) {
            (true, false) => Some(true),
            (false, true) => Some(false),
            _ => None,
        }
    }
}
