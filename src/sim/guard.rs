//! The runtime finiteness guard: the first non-finite or overflowing force, state or monitor
//! output stops the run, naming the body, the quantity, its value and the simulated time.
//!
//! A scene can pass validation and still overflow downstream: a drag coefficient of 1e300
//! times a speed, a control law that diverges, a gravity model evaluated far from its domain.
//! Without a guard the NaN or infinity flows into rapier (f32), the monitor and the outputs,
//! and the run ends with exit 0 and a file of NaNs. The guard checks, every step:
//!
//! 1. **forces** — after the Environment stage, every body's [`Wrench`] (gravity, other
//!    forces, torque): everything the next physics step will apply;
//! 2. **states** — after the Physics stage, every body's [`BodyState`] (position, velocity,
//!    attitude quaternion, angular velocity);
//! 3. **outputs** — after the Monitor stage, every pair distance, every guarantee margin and
//!    every controller or mechanism column that is infinite (a column may be NaN: it means
//!    "undefined at this step" and is written as an empty cell).
//!
//! A value trips the guard when it is not finite or its magnitude exceeds [`GUARD_LIMIT`]
//! (SI units). The limit is ours: 10¹⁵ m is 7000 astronomical units, 10¹⁵ m/s is 3·10⁶ c,
//! 10¹⁵ N no thruster; no physical scene comes near it, while rapier's f32 arithmetic squares
//! values (a 10¹⁹ number squared overflows f32), so anything past it is already meaningless.
//!
//! After a trip no stage runs any more (each stretch of the step after a check has a run
//! condition, and the runners of `SimStep` stop at a trip), so nothing of the bad step reaches
//! the recorder; the run stops at once. `rpod run` then exits with code 3, leaves the
//! rows recorded up to the last good step as `*.partial` files and writes no `summary.json`
//! (nothing looks like a whole run); `rpod trials` records the trial's outcome as
//! `NUMERIC_FAILURE` with the trip as its reason.
//!
//! The checks are their own systems, ordered between the stages, so they stay independent of
//! how the physics step itself is written.

use super::output::Diagnostics;
use super::{
    BodyState, Clock, EventLog, Guarantees, MonitorState, Roster, SimBody, SimStep, Stage, Wrench,
};
use crate::scene::validate::{MAX_ORBIT_RADIUS_M, MAX_RATE_DEG_S, MAX_SPEED_M_S};
use bevy::ecs::schedule::SystemSet;
use bevy::prelude::*;
use std::fmt;

/// Largest magnitude any checked quantity may reach, SI units.
pub const GUARD_LIMIT: f64 = 1e15;

/// Exit code of `rpod run` when the guard stops a run.
pub const EXIT_NUMERIC_FAILURE: u8 = 3;

/// What tripped the guard.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct GuardTrip {
    /// Simulated time of the check, s.
    pub t_s: f64,
    /// Completed steps at the check.
    pub step: u64,
    /// Which check: `force`, `state` or `output`.
    pub check: &'static str,
    /// The body concerned, if any.
    pub body: Option<String>,
    /// The quantity, with its component and unit (`vel_m_s.x`, `guarantee.g.margin_m`).
    pub quantity: String,
    /// The value found.
    pub value: f64,
    /// The largest magnitude allowed for the quantity (the guard's [`GUARD_LIMIT`], a state's
    /// scene limit, or the run's event limit).
    pub limit: f64,
}

impl fmt::Display for GuardTrip {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.check == "events" {
            return write!(
                f,
                "too many events at t = {} s (step {}): {} = {} (a run may raise at most {} \
                 events and {} MiB of them: see docs/limits.md)",
                self.t_s,
                self.step,
                self.quantity,
                self.value,
                MAX_EVENTS_PER_RUN,
                MAX_EVENT_BYTES_PER_RUN >> 20
            );
        }
        let what = if !self.value.is_finite() {
            "non-finite"
        } else if self.limit < GUARD_LIMIT {
            "out-of-range"
        } else {
            "overflowing"
        };
        write!(
            f,
            "{what} {} at t = {} s (step {}): ",
            self.check, self.t_s, self.step
        )?;
        if let Some(b) = &self.body {
            write!(f, "body `{b}` ")?;
        }
        if self.limit < GUARD_LIMIT {
            write!(
                f,
                "{} = {} (beyond the scene limit of {:e} in magnitude that every input of this \
                 unit is held to)",
                self.quantity, self.value, self.limit
            )
        } else {
            write!(
                f,
                "{} = {} (the guard allows finite values up to {GUARD_LIMIT:e} in magnitude)",
                self.quantity, self.value
            )
        }
    }
}

/// The guard's state: the first trip, if any.
#[derive(Resource, Debug, Default, Clone)]
pub struct Guard {
    /// The first value that tripped the guard.
    pub trip: Option<GuardTrip>,
}

/// The guard's checks, ordered between the pipeline stages.
#[derive(SystemSet, Debug, Clone, PartialEq, Eq, Hash)]
pub enum GuardCheck {
    /// After Environment, before Physics: the wrenches.
    Forces,
    /// After Physics, before Monitor: the states.
    States,
    /// After Monitor, before Record: distances, margins, columns.
    Outputs,
}

/// The stretches of the step between one check and the next, each run only while the guard is
/// clear.
#[derive(SystemSet, Debug, Clone, PartialEq, Eq, Hash)]
enum GuardSegment {
    /// After the force check: Physics, then the state check.
    Physics,
    /// After the state check: Monitor, then the output check.
    Monitor,
    /// After the output check: Record.
    Record,
}

fn clear(g: Res<Guard>) -> bool {
    g.trip.is_none()
}

fn bad(v: f64) -> bool {
    beyond(v, GUARD_LIMIT)
}

fn beyond(v: f64, limit: f64) -> bool {
    !(v.is_finite() && v.abs() <= limit)
}

/// Most events one run may raise (every kind counted).
pub const MAX_EVENTS_PER_RUN: u64 = 1_000_000;

/// Most bytes of event data (`events.jsonl`, and the run's event history in memory) one run may
/// raise.
pub const MAX_EVENT_BYTES_PER_RUN: u64 = 256 << 20;

/// The guard: owns the [`Guard`] resource and the [`GuardCheck`] sets, placed between the
/// pipeline's stages (Forces after Environment, States after Physics, Outputs after Monitor,
/// each before the next stage), with one check system in each. It makes every [`Stage`] and
/// every check run only while no check has tripped. Added right after
/// [`super::PipelinePlugin`] (it configures the pipeline's sets).
#[derive(Debug, Clone, Copy, Default)]
pub struct GuardPlugin;

impl Plugin for GuardPlugin {
    fn build(&self, app: &mut App) {
        install(app);
    }
}

fn install(app: &mut App) {
    app.insert_resource(Guard::default());
    app.configure_sets(
        SimStep,
        (
            GuardCheck::Forces
                .after(Stage::Environment)
                .before(Stage::Physics),
            GuardCheck::States
                .after(Stage::Physics)
                .before(Stage::Monitor),
            GuardCheck::Outputs
                .after(Stage::Monitor)
                .before(Stage::Record),
        ),
    );
    // Each stage after a check runs only while no check has tripped, so the step a check trips
    // in goes no further. A set's condition is evaluated once a step, before the first of its
    // systems; only these checks trip the guard, so between one check and the next its state
    // cannot change, and one condition covers each stretch (`GuardSegment`): Physics and the
    // state check after the force check, Monitor and the output check after the state check,
    // Record after the output check. The sets before the first check (Sense to Environment,
    // and the force check) need none: `SimStep` is run only while the guard is clear
    // (`advance` and `Simulation::step_pipeline` stop at a trip). Each condition is a
    // resource fetch and a run every step, so there are no more of them than that.
    app.configure_sets(
        SimStep,
        (
            (Stage::Physics, GuardCheck::States).in_set(GuardSegment::Physics),
            (Stage::Monitor, GuardCheck::Outputs).in_set(GuardSegment::Monitor),
            Stage::Record.in_set(GuardSegment::Record),
        ),
    );
    for segment in [
        GuardSegment::Physics,
        GuardSegment::Monitor,
        GuardSegment::Record,
    ] {
        app.configure_sets(SimStep, segment.run_if(clear));
    }
    app.add_systems(
        SimStep,
        (
            check_forces.in_set(GuardCheck::Forces),
            check_states.in_set(GuardCheck::States),
            check_outputs.in_set(GuardCheck::Outputs),
        ),
    );
}

/// The first bad component of a named vector quantity (beyond the guard's limit).
fn first_bad(quantity: &str, v: &nalgebra::Vector3<f64>) -> Option<(String, f64, f64)> {
    first_beyond(quantity, v, GUARD_LIMIT)
}

/// The first component of a named vector quantity beyond `limit` (or not finite).
fn first_beyond(
    quantity: &str,
    v: &nalgebra::Vector3<f64>,
    limit: f64,
) -> Option<(String, f64, f64)> {
    ["x", "y", "z"]
        .iter()
        .zip(v.iter())
        .find(|(_, x)| beyond(**x, limit))
        .map(|(c, x)| (format!("{quantity}.{c}"), *x, limit))
}

/// Records the first trip: (quantity, value, limit).
fn trip(
    g: &mut Guard,
    clock: &Clock,
    check: &'static str,
    body: Option<&str>,
    q: (String, f64, f64),
) {
    if g.trip.is_none() {
        g.trip = Some(GuardTrip {
            t_s: clock.t_s(),
            step: clock.step,
            check,
            body: body.map(str::to_string),
            quantity: q.0,
            value: q.1,
            limit: q.2,
        });
    }
}

/// Bodies in scene order (deterministic: the first bad body in scene order is reported).
fn in_order<'a, T: Component>(
    roster: &Roster,
    q: &'a Query<(&SimBody, &T)>,
) -> impl Iterator<Item = (&'a SimBody, &'a T)> {
    roster.bodies.iter().filter_map(|e| q.get(*e).ok())
}

fn check_forces(
    clock: Res<Clock>,
    roster: Res<Roster>,
    q: Query<(&SimBody, &Wrench)>,
    mut g: ResMut<Guard>,
) {
    for (b, w) in in_order(&roster, &q) {
        let found = first_bad("gravity_n", &w.gravity_n)
            .or_else(|| first_bad("force_n", &w.force_n))
            .or_else(|| first_bad("torque_nm", &w.torque_nm));
        if let Some(q) = found {
            trip(&mut g, &clock, "force", Some(&b.name), q);
            return;
        }
    }
}

fn check_states(
    clock: Res<Clock>,
    roster: Res<Roster>,
    q: Query<(&SimBody, &BodyState)>,
    mut g: ResMut<Guard>,
) {
    for (b, s) in in_order(&roster, &q) {
        let quat = s.att.quaternion();
        let att = [
            ("qw", quat.w),
            ("qx", quat.i),
            ("qy", quat.j),
            ("qz", quat.k),
        ]
        .into_iter()
        .find(|(_, v)| !v.is_finite())
        .map(|(n, v)| (format!("attitude.{n}"), v, GUARD_LIMIT));
        // The same limits as every scene input of the unit (`…_m`, `…_m_s`, `…_rad_s`): a
        // state beyond them is outside what rpod was asked to simulate (a law flown to a
        // multiple of the speed of light, a spin no structure survives).
        let rate_limit_rad_s = MAX_RATE_DEG_S.to_radians();
        let found = first_beyond("pos_m", &s.pos_m, MAX_ORBIT_RADIUS_M)
            .or_else(|| first_beyond("vel_m_s", &s.vel_m_s, MAX_SPEED_M_S))
            .or(att)
            .or_else(|| first_beyond("omega_rad_s", &s.omega_rad_s, rate_limit_rad_s));
        if let Some(q) = found {
            trip(&mut g, &clock, "state", Some(&b.name), q);
            return;
        }
    }
}

fn check_outputs(
    clock: Res<Clock>,
    roster: Res<Roster>,
    mon: Res<MonitorState>,
    gs: Res<Guarantees>,
    diag: Res<Diagnostics>,
    log: Res<EventLog>,
    mut g: ResMut<Guard>,
) {
    for p in &mon.pairs {
        if bad(p.distance_m) {
            let q = (
                format!(
                    "distance.{}.{}_m",
                    roster.names.get(p.a).map_or("?", String::as_str),
                    roster.names.get(p.b).map_or("?", String::as_str)
                ),
                p.distance_m,
                GUARD_LIMIT,
            );
            trip(&mut g, &clock, "output", None, q);
            return;
        }
    }
    for s in &gs.status {
        if bad(s.last_margin) {
            let q = (
                format!("guarantee.{}.margin_{}", s.name, s.unit),
                s.last_margin,
                GUARD_LIMIT,
            );
            trip(&mut g, &clock, "output", None, q);
            return;
        }
    }
    for (n, v) in diag.names.iter().zip(&diag.values) {
        if v.is_infinite() {
            trip(&mut g, &clock, "output", None, (n.clone(), *v, GUARD_LIMIT));
            return;
        }
    }
    if log.count > MAX_EVENTS_PER_RUN {
        let q = ("events raised".to_string(), log.count as f64, 0.0);
        trip(&mut g, &clock, "events", None, q);
    } else if log.bytes > MAX_EVENT_BYTES_PER_RUN {
        let q = ("event bytes raised".to_string(), log.bytes as f64, 0.0);
        trip(&mut g, &clock, "events", None, q);
    }
}
