//! Guarantees: named invariants evaluated by the monitor every step (Bevy-free).
//!
//! A guarantee returns a signed **margin**: positive while it holds, negative when violated, in
//! the unit it names (metres for distances). A scene registers guarantees (min distance, keep-out
//! sphere); a controller registers its own (e.g. "chaser inside the corridor"), written against
//! [`MonitorView`], which carries the f64 truth of every body and the full-geometry distances.
//!
//! # Judged on intervals, not only at samples
//! A guarantee that says how fast its margin can change ([`Guarantee::rate_bound`], from the
//! bounds on the bodies' motion over the step that [`MotionBounds`] gives) is judged on the whole
//! step interval: with |m′| ≤ L, min over [t₀, t₁] of m ≥ (m(t₀) + m(t₁) − L·dt)/2, and where that
//! bound does not clear what the verdict needs, the monitor bisects the step, evaluating
//! [`Guarantee::margin`] on the bodies' path inside it (`sim::motion`), until the violation is
//! found or excluded ([`crate::geometry::bounds`]). The status then records the worst margin
//! *including between samples*, with its time and whether it was found at a sample or inside an
//! interval, and the first violation to a time tolerance. A guarantee without a rate bound is
//! judged at the samples only and says so ([`GuaranteeStatus::judged`] = `"samples only"`):
//! between samples it is not known to hold.
//!
//! # Open registration
//! A scene's `guarantees` entries name registered kinds ([`registry`]): the built-in kinds
//! ([`builtin`]) and a user crate's ([`register_guarantee`]) are read, checked (located errors)
//! and built the same way; a law's own guarantees ([`crate::control::Controller::guarantees`])
//! and a Python callable (`Simulation.add_guarantee`) implement the same [`Guarantee`] trait.

pub mod builtin;
pub mod registry;
pub mod requirements;

pub use registry::{GuaranteeParams, GuaranteeSpec, register_guarantee};

use crate::geometry::bounds::Bracket;
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
    /// Certified lower bound of `distance_m` (parry's GJK stops at a relative tolerance and
    /// works in f32; this is the separating-axis gap along the witness direction, less the f32
    /// rounding of the relative pose), m.
    pub lower_m: f64,
    /// Time of this evaluation, s (a pair beyond the monitor's horizon keeps its last one).
    pub t_s: f64,
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
    /// The reference orbit at `t_s` (orbit scenes; `None` elsewhere).
    pub reference: Option<ReferenceView>,
    /// Every `Rcs` actuator's jets and which of them fire over the current step (empty
    /// without jets). The flags are constant over a step: the actuator sets them before the
    /// physics step and they hold until the next one.
    pub jets: &'a [JetsView<'a>],
}

/// One `Rcs` actuator's jets as the monitor sees them over the current step.
#[derive(Debug, Clone, Copy)]
pub struct JetsView<'a> {
    /// The body the jets are on (scene order).
    pub body: usize,
    /// The layout (positions from the centre of mass, body frame).
    pub jets: &'a [crate::actuation::rcs::JetSpec],
    /// Per jet: it delivers a non-zero impulse in the current step.
    pub firing: &'a [bool],
}

/// The reference orbit of an orbit scene at one instant: the ECI state of the world frame's
/// origin (whose Hill frame the scene's `Hill` quantities use).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ReferenceView {
    /// Position, ECI, m.
    pub pos_eci_m: Vector3<f64>,
    /// Velocity, ECI, m/s.
    pub vel_eci_m_s: Vector3<f64>,
}

impl ReferenceView {
    /// The reference's Hill frame at this instant (rate r×v/|r|²).
    pub fn hill(&self) -> crate::orbit::lvlh::LocalFrame {
        crate::orbit::lvlh::LocalFrame::new(
            crate::orbit::lvlh::LocalFrameKind::Hill,
            &self.pos_eci_m,
            &self.vel_eci_m_s,
        )
    }
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

/// Bounds on every body's motion over one step (the monitor's `sim::motion::StepMotion`
/// implements it), in the world frame. Every bound holds on the whole step interval.
pub trait MotionBounds {
    /// The step, s.
    fn dt_s(&self) -> f64;
    /// Bound on the speed of body i's centre of mass, m/s.
    fn speed_bound(&self, i: usize) -> f64;
    /// Bound on |v_i − v_j| (centres of mass), m/s.
    fn rel_speed_bound(&self, i: usize, j: usize) -> f64;
    /// Bound on body i's angular speed, rad/s.
    fn omega_bound(&self, i: usize) -> f64;
    /// Radius about body i's centre of mass of a sphere holding all its parts, m.
    fn extent_m(&self, i: usize) -> f64;
    /// Bound on |r_i − r_j| (centres of mass), m.
    fn separation_bound(&self, i: usize, j: usize) -> f64;
    /// Bound on the rate of change of the full-geometry distance between bodies i and j:
    /// |v_i − v_j| + Ω_i R_i + Ω_j R_j, m/s.
    fn distance_rate_bound(&self, i: usize, j: usize) -> f64 {
        self.rel_speed_bound(i, j)
            + self.omega_bound(i) * self.extent_m(i)
            + self.omega_bound(j) * self.extent_m(j)
    }
    /// Bound on the rate of change of body i's centre of mass expressed in body j's axes
    /// (about j's centre of mass): |v_i − v_j| + Ω_j·|r_i − r_j|, m/s.
    fn rel_speed_in_body_bound(&self, i: usize, j: usize) -> f64 {
        self.rel_speed_bound(i, j) + self.omega_bound(j) * self.separation_bound(i, j)
    }
    /// Bound on the angular speed of the reference orbit's Hill frame over the step, rad/s
    /// (orbit scenes; `None` elsewhere, or when the step is too long to bound it; see
    /// [`crate::orbit::lvlh::hill_rate_bound_rad_s`]).
    fn hill_rate_bound_rad_s(&self) -> Option<f64> {
        None
    }
}

/// What a guarantee's margin reads besides the bodies' states (so the monitor knows which
/// full-geometry distances to compute when it evaluates the margin between samples).
#[derive(Debug, Clone, PartialEq)]
pub enum Reads {
    /// Body states only (point-mass guarantees).
    Bodies,
    /// Body states and the distances of these body pairs.
    Pairs(Vec<(usize, usize)>),
    /// Anything in the view (every pair the monitor tracks).
    Everything,
}

/// A named invariant.
///
/// Only `name` and `margin` are required. A guarantee that can bound the rate of change of its
/// margin over a step overrides [`Guarantee::rate_bound`] (and [`Guarantee::reads`], so that
/// evaluations between samples compute only what it reads); it is then judged on the whole
/// interval. Without it, it is judged at the samples only, and the outputs say so.
pub trait Guarantee: Send + Sync {
    /// Name shown in outputs.
    fn name(&self) -> &str;
    /// Unit of the margin (e.g. `m`).
    fn unit(&self) -> &str {
        "m"
    }
    /// Signed margin: ≥ 0 held, < 0 violated.
    fn margin(&self, view: &MonitorView) -> f64;
    /// The margin with a certified lower bound (default: the margin, exact). A margin built
    /// on a full-geometry distance uses the distance's certified lower bound
    /// ([`PairDistance::lower_m`]).
    fn margin_bracket(&self, view: &MonitorView) -> Bracket {
        Bracket::exact(self.margin(view))
    }
    /// A bound on |d margin / dt| over the step that `motion` describes, or `None` if the
    /// margin cannot be bounded between samples (then it is judged at the samples only).
    fn rate_bound(&self, motion: &dyn MotionBounds) -> Option<f64> {
        let _ = motion;
        None
    }
    /// The margin is the full-geometry distance between two bodies less a constant, exactly
    /// as [`Guarantee::margin_bracket`] computes it: `Some((a, b, offset_m))` means
    /// margin = d(a, b) − offset_m (and bracket lower = lower_m − offset_m). The monitor may
    /// then judge it between samples with per-part-pair rate bounds instead of
    /// [`Guarantee::rate_bound`] (`sim::monitor::search_parts`), so that a body turning fast
    /// does not force refinement where its parts far from the other body are (default `None`).
    fn distance_margin(&self) -> Option<(usize, usize, f64)> {
        None
    }
    /// What the margin reads (default: everything in the view).
    fn reads(&self) -> Reads {
        Reads::Everything
    }
    /// Absolute tolerance of the margin, in its unit: the interval search stops refining once
    /// the worst margin is known to within max(this, 0.1 % of its size) (default 1e-6).
    fn tolerance(&self) -> f64 {
        1e-6
    }
    /// A value the margin can never go below, whatever the motion (default −∞: none). A
    /// margin built on a distance has one (a distance is never negative): a lower bound
    /// below it is raised to it, and once the worst margin is within the refinement
    /// tolerance of it the interval search has nothing left to prove (no refinement while two
    /// bodies stay in contact, latched or not).
    fn margin_floor(&self) -> f64 {
        f64::NEG_INFINITY
    }
    /// What a `guarantee_violated` / `guarantee_restored` event names besides the margin
    /// (e.g. the jet and the part of a plume keep-off), from the view where the change was
    /// found; added to the event as `detail` (default: nothing).
    fn detail(&self, view: &MonitorView) -> Option<serde_json::Value> {
        let _ = view;
        None
    }
    /// The margin also reads inputs that are constant over a step and change only at its
    /// start (the jets firing in it, [`MonitorView::jets`]). The monitor then evaluates the
    /// margin again at the step's start with this step's inputs — the sample there was taken
    /// with the previous step's — so that the interval judgement starts from the margin that
    /// holds on the step (default `false`).
    fn step_inputs(&self) -> bool {
        false
    }
    /// A lower bound of the margin over the whole current step known from the step's inputs
    /// alone (e.g. no jet fires, so no plume can strike), or `None` (default). The monitor
    /// takes it into its interval bound, so a margin that sits at such a floor is proven,
    /// not left unresolved.
    fn step_floor(&self, view: &MonitorView) -> Option<f64> {
        let _ = view;
        None
    }
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
    fn margin_bracket(&self, v: &MonitorView) -> Bracket {
        v.pair(self.a, self.b)
            .map_or(Bracket::exact(f64::INFINITY), |p| Bracket {
                value: p.distance_m - self.min_m,
                lower: p.lower_m - self.min_m,
            })
    }
    /// The full-geometry distance changes at most at |v_a − v_b| + Ω_a R_a + Ω_b R_b.
    fn rate_bound(&self, m: &dyn MotionBounds) -> Option<f64> {
        Some(m.distance_rate_bound(self.a, self.b))
    }
    /// The distance is never negative: the margin is at least −`min_m`.
    fn margin_floor(&self) -> f64 {
        -self.min_m
    }
    /// margin = d(a, b) − `min_m`.
    fn distance_margin(&self) -> Option<(usize, usize, f64)> {
        Some((self.a, self.b, self.min_m))
    }
    fn reads(&self) -> Reads {
        Reads::Pairs(vec![(self.a.min(self.b), self.a.max(self.b))])
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
    /// |r_body − r_around| changes at most at |v_body − v_around|.
    fn rate_bound(&self, m: &dyn MotionBounds) -> Option<f64> {
        Some(m.rel_speed_bound(self.body, self.around))
    }
    fn reads(&self) -> Reads {
        Reads::Bodies
    }
}

/// What the monitor found about a margin on one step interval [t₀, t₁] (times absolute, s).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct IntervalFinding {
    /// Smallest margin found on the interval (ends included).
    pub min_value: f64,
    /// Where, s.
    pub min_t_s: f64,
    /// The smallest margin was found strictly inside the interval (not at a sample).
    pub inside: bool,
    /// Certified lower bound of the margin over the interval.
    pub lower: f64,
    /// The margin first went below zero in [t_lo, t_hi] (s), if it did on this interval
    /// while it was ≥ 0 at t₀.
    pub first_violation_s: Option<(f64, f64)>,
    /// The margin came back to ≥ 0 in [t_lo, t_hi] (s) after a violation inside the interval.
    pub restored_s: Option<(f64, f64)>,
    /// The search could neither exclude nor find a violation to its tolerance.
    pub unresolved: bool,
    /// Margin evaluations between the samples.
    pub evals: u32,
}

/// A change of a guarantee's state, for the event log.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StatusChange {
    /// When, s (to the refinement's time tolerance for interval-judged guarantees).
    pub t_s: f64,
    /// Time tolerance of `t_s`: the change happened in [t_s, t_s + t_tol_s], s.
    pub t_tol_s: f64,
    /// `true`: violated; `false`: holds again.
    pub violated: bool,
    /// Margin at the sample that revealed it, or the smallest found inside the interval.
    pub margin: f64,
    /// Found at a sample (`false`) or inside an interval (`true`).
    pub inside: bool,
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
    /// `"interval"`: judged on every step interval, between samples included; `"samples only"`:
    /// the guarantee gives no rate bound, so it is judged at the samples and is not known to
    /// hold between them.
    pub judged: &'static str,
    /// `"held"` (proven on every interval, or at every sample when judged at samples only),
    /// `"violated"`, or `"unresolved"` (no violation found, but the certified lower bound dips
    /// below zero by less than the evaluations' precision: not proven to hold).
    pub verdict: &'static str,
    /// Where the worst margin was found: `"sample"` or `"interval"` (between samples).
    pub worst_margin_found: &'static str,
    /// Certified lower bound of the margin over the whole run (interval-judged guarantees;
    /// the worst sample otherwise).
    pub worst_margin_lower: f64,
    /// Where the first violation was found: `"sample"` or `"interval"`.
    pub first_violation_found: Option<&'static str>,
    /// Time tolerance of `first_violation_s`: the margin went below zero in
    /// [first_violation_s, first_violation_s + this], s.
    pub first_violation_tol_s: Option<f64>,
    /// Number of separate violations (entries into a negative margin).
    pub violations: u64,
    /// Margin evaluations made between samples over the run.
    pub interval_evaluations: u64,
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
            judged: "samples only",
            verdict: "held",
            worst_margin_found: "sample",
            worst_margin_lower: f64::INFINITY,
            first_violation_found: None,
            first_violation_tol_s: None,
            violations: 0,
            interval_evaluations: 0,
        }
    }

    /// Folds in one step [t1_s − dt_s, t1_s] judged on its whole interval: the sample `m1` at
    /// `t1_s` and what the interval search found. Returns the changes (violated / holds again) in time order.
    pub fn update_interval(
        &mut self,
        t1_s: f64,
        m1: f64,
        f: &IntervalFinding,
        dt_s: f64,
    ) -> Vec<StatusChange> {
        self.judged = "interval";
        self.interval_evaluations += u64::from(f.evals);
        let was_ok = self.last_margin >= 0.0;
        self.last_margin = m1;
        if f.min_value < self.worst_margin {
            self.worst_margin = f.min_value;
            self.worst_margin_t_s = f.min_t_s;
            self.worst_margin_found = if f.inside { "interval" } else { "sample" };
        }
        if m1 < self.worst_margin {
            self.worst_margin = m1;
            self.worst_margin_t_s = t1_s;
            self.worst_margin_found = "sample";
        }
        self.worst_margin_lower = self.worst_margin_lower.min(f.lower).min(m1);
        let mut out = Vec::new();
        let went_negative = f.min_value < 0.0 || m1 < 0.0;
        if was_ok && went_negative {
            // Not located (the search did not run): somewhere in the step.
            let (t_lo, t_hi) = f.first_violation_s.unwrap_or((t1_s - dt_s, t1_s));
            let inside = m1 >= 0.0 || t_hi < t1_s;
            out.push(StatusChange {
                t_s: t_lo,
                t_tol_s: (t_hi - t_lo).max(0.0),
                violated: true,
                margin: if m1 < 0.0 { m1 } else { f.min_value },
                inside,
            });
            self.violations += 1;
            if self.first_violation_s.is_none() {
                self.first_violation_s = Some(t_lo);
                self.first_violation_found = Some(if inside { "interval" } else { "sample" });
                self.first_violation_tol_s = Some((t_hi - t_lo).max(0.0));
            }
            if m1 >= 0.0 {
                let (r_lo, r_hi) = f.restored_s.unwrap_or((t1_s, t1_s));
                out.push(StatusChange {
                    t_s: r_lo,
                    t_tol_s: (r_hi - r_lo).max(0.0),
                    violated: false,
                    margin: m1,
                    inside: true,
                });
            }
        } else if !was_ok && m1 >= 0.0 {
            let (r_lo, r_hi) = f.restored_s.unwrap_or((t1_s, t1_s));
            out.push(StatusChange {
                t_s: r_lo,
                t_tol_s: (r_hi - r_lo).max(0.0),
                violated: false,
                margin: m1,
                inside: r_hi < t1_s,
            });
        }
        if went_negative {
            self.held = false;
            self.verdict = "violated";
        } else if self.verdict != "violated" && (f.unresolved || self.worst_margin_lower < 0.0) {
            self.held = false;
            self.verdict = "unresolved";
        }
        out
    }

    /// Folds in one sample (a guarantee judged at samples only, or the t = 0 sample); returns
    /// `Some(true)` on a new violation, `Some(false)` when a
    /// violated guarantee holds again, `None` otherwise.
    pub fn update(&mut self, t_s: f64, margin: f64) -> Option<bool> {
        let was_ok = self.last_margin >= 0.0;
        self.last_margin = margin;
        if margin < self.worst_margin {
            self.worst_margin = margin;
            self.worst_margin_t_s = t_s;
        }
        self.worst_margin_lower = self.worst_margin_lower.min(margin);
        let ok = margin >= 0.0;
        if !ok {
            self.held = false;
            self.verdict = "violated";
            if self.first_violation_s.is_none() {
                self.first_violation_s = Some(t_s);
                self.first_violation_found = Some("sample");
            }
        }
        if was_ok && !ok {
            self.violations += 1;
        }
        match (was_ok, ok) {
            (true, false) => Some(true),
            (false, true) => Some(false),
            _ => None,
        }
    }
}
