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
//! After a trip no stage runs any more (each check is the run condition of the stage after it,
//! and the runners of `SimStep` stop at a trip), so nothing of the bad step reaches the
//! recorder; the run stops at once. `rpod run` then exits with code 3, leaves the
//! rows recorded up to the last good step as `*.partial` files and writes no `summary.json`
//! (nothing looks like a whole run); `rpod trials` records the trial's outcome as
//! `NUMERIC_FAILURE` with the trip as its reason.
//!
//! Each check is the run condition of the stage it guards (forces gate Physics, states gate
//! Monitor, outputs gate Record): a stage's condition is evaluated once a step, right before the
//! first of its systems, so after every system of the stages before it — the place of a check
//! between two stages — and a check that trips keeps the stage it gates from running. So the
//! checks stay independent of how the physics step itself is written, and cost no system of
//! their own (each system is a run of the executor's bookkeeping and a fetch of each of its
//! resources, every step: three systems and three conditions were 9 % of `free_drift`'s
//! step). A condition may only read; the first trip is recorded in a write-once cell
//! ([`std::sync::OnceLock`]) of the [`Guard`].

use super::output::Diagnostics;
use super::{
    BodyState, Clock, EventLog, Guarantees, MonitorState, SimBody, SimStep, Stage, Wrench,
};
use crate::scene::validate::{MAX_ORBIT_RADIUS_M, MAX_RATE_DEG_S, MAX_SPEED_M_S};
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
    /// The first value that tripped the guard, set once by the check that found it (each check
    /// is a run condition, which may only read its parameters: hence a write-once cell).
    trip: std::sync::OnceLock<GuardTrip>,
}

impl Guard {
    /// The first value that tripped the guard, if one has.
    pub fn trip(&self) -> Option<&GuardTrip> {
        self.trip.get()
    }
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

/// The guard: owns the [`Guard`] resource and gives three pipeline stages their checks as run
/// conditions (the forces gate [`Stage::Physics`], the states [`Stage::Monitor`], the outputs
/// [`Stage::Record`]): after a trip no stage runs. Added right after
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
    // Each check gates the stage after it; the stages before the first check (Sense to
    // Environment) need none: `SimStep` is run only while the guard is clear (`advance` and
    // `Simulation::step_pipeline` stop at a trip). A check finding the guard already tripped
    // (by an earlier check of the same step) answers false without looking. A set's condition
    // is asked when the executor reaches the first of the set's systems (whether or not that
    // system's own condition then lets it run), so only in a set that has one: each of these
    // stages has a core system of the pipeline (`physics_step`, `distances`, `record`), so
    // every check runs every step (`tests/guard.rs` trips each of the three).
    app.configure_sets(
        SimStep,
        (
            Stage::Physics.run_if(forces_clear),
            Stage::Monitor.run_if(states_clear),
            Stage::Record.run_if(outputs_clear),
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
    // The common case in one test of the three (false for NaN and infinities, as `beyond`).
    if v.x.abs() <= limit && v.y.abs() <= limit && v.z.abs() <= limit && limit.is_finite() {
        return None;
    }
    ["x", "y", "z"]
        .iter()
        .zip(v.iter())
        .find(|(_, x)| beyond(**x, limit))
        .map(|(c, x)| (format!("{quantity}.{c}"), *x, limit))
}

/// Records the first trip: (quantity, value, limit). A later one (none can happen: every check
/// answers false once the guard has tripped) would be dropped.
fn trip(g: &Guard, clock: &Clock, check: &'static str, body: Option<&str>, q: (String, f64, f64)) {
    let _ = g.trip.set(GuardTrip {
        t_s: clock.t_s(),
        step: clock.step,
        check,
        body: body.map(str::to_string),
        quantity: q.0,
        value: q.1,
        limit: q.2,
    });
}

/// The first bad quantity of the first body in scene order that has one (bodies are visited in
/// the query's order, the one of least [`SimBody::index`] kept: the same body as a walk in
/// scene order, without a lookup per body).
fn first_bad_body<'a, T: Component>(
    q: &'a Query<(&SimBody, &T)>,
    bad: impl Fn(&T) -> Option<(String, f64, f64)>,
) -> Option<(&'a SimBody, (String, f64, f64))> {
    let mut first: Option<(&SimBody, (String, f64, f64))> = None;
    for (b, x) in q {
        if first.as_ref().is_some_and(|(f, _)| f.index < b.index) {
            continue;
        }
        if let Some(found) = bad(x) {
            first = Some((b, found));
        }
    }
    first
}

/// The force check, run condition of [`Stage::Physics`]: every body's wrench after the
/// Environment stage. False (Physics and everything after it skipped) at a trip.
fn forces_clear(clock: Res<Clock>, q: Query<(&SimBody, &Wrench)>, g: Res<Guard>) -> bool {
    if g.trip().is_some() {
        return false;
    }
    let found = first_bad_body(&q, |w| {
        first_bad("gravity_n", &w.gravity_n)
            .or_else(|| first_bad("force_n", &w.force_n))
            .or_else(|| first_bad("torque_nm", &w.torque_nm))
    });
    match found {
        Some((b, q)) => {
            trip(&g, &clock, "force", Some(&b.name), q);
            false
        }
        None => true,
    }
}

/// The state check, run condition of [`Stage::Monitor`]: every body's state after the Physics
/// stage. False (Monitor and everything after it skipped) at a trip, or when the guard has
/// already tripped.
fn states_clear(clock: Res<Clock>, q: Query<(&SimBody, &BodyState)>, g: Res<Guard>) -> bool {
    if g.trip().is_some() {
        return false;
    }
    // The same limits as every scene input of the unit (`…_m`, `…_m_s`, `…_rad_s`): a state
    // beyond them is outside what rpod was asked to simulate (a law flown to a multiple of the
    // speed of light, a spin no structure survives).
    let rate_limit_rad_s = MAX_RATE_DEG_S.to_radians();
    let found = first_bad_body(&q, |s| {
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
        first_beyond("pos_m", &s.pos_m, MAX_ORBIT_RADIUS_M)
            .or_else(|| first_beyond("vel_m_s", &s.vel_m_s, MAX_SPEED_M_S))
            .or(att)
            .or_else(|| first_beyond("omega_rad_s", &s.omega_rad_s, rate_limit_rad_s))
    });
    match found {
        Some((b, q)) => {
            trip(&g, &clock, "state", Some(&b.name), q);
            false
        }
        None => true,
    }
}

/// The output check, run condition of [`Stage::Record`]: after the Monitor stage, every pair
/// distance, guarantee margin and diagnostics column, and the run's event counts. False
/// (nothing of the step recorded) at a trip, or when the guard has already tripped.
fn outputs_clear(
    clock: Res<Clock>,
    mon: Res<MonitorState>,
    gs: Res<Guarantees>,
    diag: Res<Diagnostics>,
    log: Res<EventLog>,
    g: Res<Guard>,
) -> bool {
    if g.trip().is_some() {
        return false;
    }
    let name = |k: usize| mon.bodies.get(k).map_or("?", |b| b.name.as_str());
    let found = if let Some(p) = mon.pairs.iter().find(|p| bad(p.distance_m)) {
        let quantity = format!("distance.{}.{}_m", name(p.a), name(p.b));
        Some(("output", (quantity, p.distance_m, GUARD_LIMIT)))
    } else if let Some(s) = gs.status.iter().find(|s| bad(s.last_margin)) {
        let quantity = format!("guarantee.{}.margin_{}", s.name, s.unit);
        Some(("output", (quantity, s.last_margin, GUARD_LIMIT)))
    } else if let Some((n, v)) = diag
        .names
        .iter()
        .zip(&diag.values)
        .find(|(_, v)| v.is_infinite())
    {
        Some(("output", (n.clone(), *v, GUARD_LIMIT)))
    } else if log.count > MAX_EVENTS_PER_RUN {
        let q = ("events raised".to_string(), log.count as f64, 0.0);
        Some(("events", q))
    } else if log.bytes > MAX_EVENT_BYTES_PER_RUN {
        let q = ("event bytes raised".to_string(), log.bytes as f64, 0.0);
        Some(("events", q))
    } else {
        None
    };
    match found {
        Some((check, q)) => {
            trip(&g, &clock, check, None, q);
            false
        }
        None => true,
    }
}
