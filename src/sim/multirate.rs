//! Multi-rate stepping (`stepping: MultiRate(…)` in a scene): pipeline steps longer than
//! `dt_s` wherever nothing can happen inside them.
//!
//! # What a long step is
//! A pipeline step covers `span` fixed steps ([`super::Clock::span`]); `t_s = step · dt_s`
//! stays exact because a span is a whole number of fixed steps. Every stage runs once per
//! pipeline step with the step's length h = span·dt_s: the controllers at its start (their
//! command is held over it, as it is held between calls anyway), the actuators' accounting
//! over h, the f64 free flight over h (velocity Verlet and [`super::rotate_rk4`] in one step:
//! the path the monitor judges on is the committed integration, as in a fixed step), the
//! monitor's interval judgements over [t₀, t₀ + h], and the row at its end.
//!
//! # When a step may be long ([`plan_step`], at the head of the Actuate stage)
//! Only when every condition below holds; otherwise the step is `dt_s` and the run is the
//! fixed-step run (the reason is counted in `summary.json`'s `stepping.short_steps_by_reason`).
//! 1. **Nothing keeps per-step state.** No sensor and no navigation filter (they expose and
//!    propagate every fixed step), every controller's actuator `Ideal` or `Saturated` (PWPF,
//!    RCS jets and their plumes modulate every step), no disturbance, no air-bearing table
//!    (friction depends on the velocity) and no L2 frame (it advances in fixed steps); at
//!    most [`MAX_BODIES`] bodies (the pair check below is over every pair).
//! 2. **No scheduled time inside.** The step ends at or before the next call of every
//!    controller, the next trajectory row, the end of the requested run, and
//!    `max_step_s`.
//! 3. **No contact can begin.** No body touches or is jointed (but a latched stack: below),
//!    rapier did not step last step, the compliant contact is idle and the docking mechanism is
//!    `FREE` with its magnet off (or `RELEASED` with its separation complete).
//!    For every pair of bodies, with u_i = |v_i| + A_i·h a bound on body i's centre-of-mass
//!    speed over the step (A_i = |a_g(x_i)| + Σ|F|/m_i: gravity at the start plus the held
//!    forces, after saturation — exactly the acceleration of the free-flight path), the
//!    distance between the spheres holding every part's axis-aligned box in any attitude
//!    stays above [`super::RAPIER_ENGAGE_M`]: d_c − R_i − R_j − (u_i + u_j)·h > 1 m. The
//!    physics stage's own engagement test is then false over the step (it uses the same
//!    spheres and the path's speeds, which u bounds), so rapier does not step, nothing is split
//!    and no contact is missed. The docking ports' gap minus the ports' travel
//!    (u + Ω·lever for each) stays above the magnet's activation distance, so the magnet
//!    switches on at the same fixed step as in the fixed-step run.
//! 4. **No guarantee near its threshold.** Every guarantee was judged on the interval last
//!    step (a rate bound r; a "samples only" guarantee keeps the run at `dt_s`, where it is
//!    sampled) and its certified lower margin exceeds 2·r·h. This is a planning rule, not the
//!    proof: the monitor judges each long step on its whole interval exactly as it judges a
//!    fixed step (lower bounds from the rate bounds over h, searches where they do not clear),
//!    so a verdict stays proven whatever h is.
//! 5. **Error control.** The one-step integration's leading error terms stay within the
//!    scene's tolerances: velocity Verlet's position error |j|·h³/6 ≤ `tol_m`, with |j| a bound
//!    on the jerk of the differential gravity: G(u_i + 5·(|v_ref|/r)·|x_i|) where
//!    G = 3μ/r³·(1 + 10·J2) bounds the gravity-gradient tensor's norm (the J2 term's share is
//!    about 2·J2·(R⊕/r)² ≤ 2.2e-3; 10·J2 = 1.1e-2 covers it) and 5|v_ref|/r its rate of
//!    change (2ω from its rotation, 3|ṙ|/r from its size), r = |r_ref| − |v_ref|·h − |x_i|
//!    the smallest distance from Earth's centre over the step; in free space G = 0. And the
//!    RK4 rotation's: every body turns by at most Ω_i·h ≤ min((120·tol_rad)^(1/5), 0.3 rad),
//!    Ω_i = (|Jω| + (|τ| + τ_gg)·h)/λ_min (angular momentum grows at most at the held torque
//!    plus the gravity-gradient torque bound τ_gg = G·(λ_max − λ_min)).
//!
//! 6. **A latched stack** (the docking mechanism `LATCHED` by its rigid latch, the world's one
//!    joint) flies as one rigid body ([`crate::math::stack`]) instead of in rapier's joint, when:
//!    its first latched step was rapier's (the latch impulse is measured there); no release is
//!    commanded (the mechanism acts on it at the end of the step); the members' motion relative
//!    to the rigid stack at t₀ times h is within `tol_m` and `tol_rad` (the stack removes it,
//!    as a rigid latch would); the latch's load on the chaser, bounded over the step by
//!    m_c·(A + α·|c_c| + Ω²·|c_c|) + |F_c| + |G_c|, stays below the break force, so the latch
//!    cannot break inside the step; and every other body is out of rapier's reach of both
//!    members (conditions 3 and 5 are checked for the stack as one body, its members' speed
//!    bounds u + Ω·|c_k|). The physics stage then does not step rapier; each member's path is
//!    the straight line and constant-rate rotation between its committed poses, as for a step
//!    rapier takes, and what held it (its momentum change less its own forces and torque) is
//!    recorded as rapier's joint impulse is, so the mechanism measures the latch's load as it
//!    does after a rapier step. Between two committed poses the rigid stack's members move on
//!    arcs, not chords: the path departs from them by at most |c_k|·(Ω·h)²/8 (1.6e-9 m for the
//!    flagship's stack at 0.1 s) — the same interpolation the monitor applies to rapier's steps.
//!
//! The longest span meeting 3–6 is found by bisection (each condition only tightens as h
//! grows). Nothing here changes a run with `stepping: Fixed`: the resource is absent and the
//! span stays 1 (h = dt_s exactly: [`super::Clock::h_s`]).

use super::contact_model::CompliantContact;
use super::controllers::ControllerHost;
use super::docking::Docking;
use super::monitor::{ContactState, MonitorGeometry};
use super::motion::{RK4_INFLATION, StepMotion, UNDER_RESOLVED_TURN_RAD};
use super::output::Recorder;
use super::{
    BodyState, Clock, Env, Guarantees, MonitorState, Physics, RapierSync, Roster, SimBody,
};
use crate::actuation::actuator::ActuatorSpec;
use crate::control::interface::Command;
use crate::orbit::constants::{J2_EARTH, MU_EARTH_M3_S2};
use bevy::ecs::system::SystemParam;
use bevy::prelude::*;
use serde::Serialize;
use std::collections::BTreeMap;

/// Fixed steps the current `App::update` may still take (set by the `Update` system before
/// each pipeline step): a long step never passes the end of the requested run.
#[derive(Resource, Debug, Clone, Default)]
pub struct SpanCap(pub u64);

/// Most bodies for which long steps are planned (the pair check is over every pair).
pub const MAX_BODIES: usize = 64;

/// Two bodies within rapier's reach ([`super::RAPIER_ENGAGE_M`] between their bounding spheres)
/// may take a long step only while their certified part-to-part distance at t₀ exceeds this
/// plus [`NEAR_SWEEP_FACTOR`] times the most any of their points can travel over the step, m:
/// twice [`super::RAPIER_SEES_M`], so rapier (stepped over the long step only as a detector:
/// the bodies keep their f64 free flight) sees no contact, and the physics stage's swept test
/// and the compliant model's contact window (three times the step's travel plus 1 mm) find
/// nothing to split or sub-step.
pub const NEAR_CLEAR_M: f64 = 2.0 * super::RAPIER_SEES_M;

/// See [`NEAR_CLEAR_M`]: the compliant contact model's window is three travels wide; one more
/// for the step itself.
pub const NEAR_SWEEP_FACTOR: f64 = 4.0;

/// A scene's `MultiRate` request and the run's record of it (absent with `Fixed`).
#[derive(Resource, Debug, Clone)]
pub struct MultiRate {
    /// Longest span, fixed steps (⌊max_step_s / dt_s⌋, at least 1).
    pub max_span: u64,
    /// Position tolerance of one step's integration, m.
    pub tol_m: f64,
    /// Attitude tolerance of one step's integration, rad.
    pub tol_rad: f64,
    /// What the run did.
    pub stats: MultiRateStats,
    /// The current pipeline step flies a latched stack as one rigid body: its members (scene
    /// order; the first member's frame is the stack's), set by [`plan_step`] for a long step.
    pub stack: Option<[usize; 2]>,
}

impl MultiRate {
    /// From the scene's `stepping`; `None` for `Fixed`.
    pub fn from_scene(stepping: &crate::scene::Stepping, dt_s: f64) -> Option<Self> {
        match stepping {
            crate::scene::Stepping::Fixed => None,
            crate::scene::Stepping::MultiRate {
                max_step_s,
                tol_m,
                tol_rad,
            } => Some(Self {
                // The validated max_step_s is at most a day and dt_s at least 1e-6 s: the
                // quotient fits a u64.
                max_span: ((max_step_s / dt_s) * (1.0 + 1e-12)).floor().max(1.0) as u64,
                tol_m: *tol_m,
                tol_rad: *tol_rad,
                stats: MultiRateStats::default(),
                stack: None,
            }),
        }
    }

    /// `summary.json`'s `stepping`: the request and what the run did.
    pub fn summary(&self, dt_s: f64) -> serde_json::Value {
        serde_json::json!({
            "mode": "multi_rate",
            "max_step_s": self.max_span as f64 * dt_s,
            "tol_m": self.tol_m,
            "tol_rad": self.tol_rad,
            "pipeline_steps": self.stats.pipeline_steps,
            "long_steps": self.stats.long_steps,
            "fixed_steps_in_long_steps": self.stats.fixed_steps_in_long_steps,
            "longest_step_s": self.stats.longest_step_s,
            "short_steps_by_reason": self.stats.short_steps_by_reason,
            "stack_steps": self.stats.stack_steps,
        })
    }

    /// The largest turn one step may give a body, rad: RK4's local error on a rotation by θ
    /// is about θ⁵/120, so θ ≤ (120·tol_rad)^(1/5), and never past the monitor's resolved
    /// limit.
    pub fn max_turn_rad(&self) -> f64 {
        (120.0 * self.tol_rad)
            .powf(0.2)
            .min(UNDER_RESOLVED_TURN_RAD)
    }
}

/// What multi-rate stepping did over a run (`summary.json`'s `stepping`).
#[derive(Debug, Clone, Default, Serialize)]
pub struct MultiRateStats {
    /// Pipeline steps run.
    pub pipeline_steps: u64,
    /// Of those, steps longer than `dt_s`.
    pub long_steps: u64,
    /// Fixed steps covered by long steps.
    pub fixed_steps_in_long_steps: u64,
    /// Longest step taken, s.
    pub longest_step_s: f64,
    /// Steps kept at `dt_s`, by the first condition that kept them there.
    pub short_steps_by_reason: BTreeMap<&'static str, u64>,
    /// Of the long steps, those that flew a latched stack as one rigid body.
    pub stack_steps: u64,
}

/// Everything the planner reads.
#[derive(SystemParam)]
pub struct PlanInputs<'w, 's> {
    clock: ResMut<'w, Clock>,
    cap: Res<'w, SpanCap>,
    mr: Option<ResMut<'w, MultiRate>>,
    host: Option<Res<'w, ControllerHost>>,
    rec: Res<'w, Recorder>,
    roster: Res<'w, Roster>,
    bodies: Query<'w, 's, (&'static SimBody, &'static BodyState)>,
    geo: Res<'w, MonitorGeometry>,
    motion: Res<'w, StepMotion>,
    env: Res<'w, Env>,
    contact: Res<'w, ContactState>,
    sync: Res<'w, RapierSync>,
    phys: Res<'w, Physics>,
    compliant: Option<Res<'w, CompliantContact>>,
    docking: Option<Res<'w, Docking>>,
    dock_cmds: Option<Res<'w, super::docking::DockingCommands>>,
    guarantees: Res<'w, Guarantees>,
    mon: Res<'w, MonitorState>,
    table: Option<Res<'w, super::airbearing::AirBearing>>,
}

/// The norms of a held command's force and torque after the actuator, N and N·m, when the
/// actuator is memoryless (`Ideal`, `Saturated`); `None` for one with per-step state.
fn held_bound(spec: &ActuatorSpec, cmd: &Command) -> Option<(f64, f64)> {
    if cmd.valves.is_some() {
        return None;
    }
    let clamp = |v: &nalgebra::Vector3<f64>, m: &[f64; 3]| {
        nalgebra::Vector3::new(
            v.x.clamp(-m[0], m[0]),
            v.y.clamp(-m[1], m[1]),
            v.z.clamp(-m[2], m[2]),
        )
        .norm()
    };
    match spec {
        ActuatorSpec::Ideal => Some((cmd.force_n.norm(), cmd.torque_nm.norm())),
        ActuatorSpec::Saturated {
            max_force_n,
            max_torque_nm,
        } => Some((
            clamp(&cmd.force_n, max_force_n),
            clamp(&cmd.torque_nm, max_torque_nm),
        )),
        _ => None,
    }
}

/// x > y, false when either is NaN (a NaN bound never clears a condition).
fn above(x: f64, y: f64) -> bool {
    x > y
}

/// One body's bounds over a candidate step.
#[derive(Debug, Clone)]
struct BodyBound {
    /// |v₀|, m/s.
    speed_m_s: f64,
    /// Bound on the path's acceleration, m/s².
    accel_m_s2: f64,
    /// |x₀| (from the world origin, the reference orbit), m.
    offset_m: f64,
    /// |J ω₀|, N·m·s.
    momentum_nms: f64,
    /// Held torque bound plus the gravity-gradient bound, N·m.
    torque_nm: f64,
    /// Smallest and largest principal moments, kg·m².
    lambda: (f64, f64),
    /// Radius holding every part's box in any attitude, m.
    aabb_m: f64,
    /// Radius holding every part, about the centre of mass, m.
    extent_m: f64,
}

/// Pipeline step planning: sets [`Clock::span`] (1 unless every condition of the module
/// documentation holds) and counts the outcome.
pub fn plan_step(mut p: PlanInputs) {
    p.clock.span = 1;
    if p.mr.is_none() {
        return;
    }
    let plan = plan(&p);
    let step_s = p.clock.dt_s;
    let Some(mr) = p.mr.as_deref_mut() else {
        return;
    };
    mr.stack = None;
    let st = &mut mr.stats;
    st.pipeline_steps += 1;
    match plan {
        Ok((k, stack)) if k > 1 => {
            st.long_steps += 1;
            st.fixed_steps_in_long_steps += k;
            st.longest_step_s = st.longest_step_s.max(k as f64 * step_s);
            st.stack_steps += u64::from(stack.is_some());
            p.clock.span = k;
            mr.stack = stack.map(|s| s.members);
        }
        Ok(_) => *st.short_steps_by_reason.entry("schedule").or_default() += 1,
        Err(reason) => *st.short_steps_by_reason.entry(reason).or_default() += 1,
    }
}

/// The span the conditions allow (with the latched stack it flies as one body, if any), or the
/// first reason there is none.
fn plan(p: &PlanInputs) -> Result<(u64, Option<StackFit>), &'static str> {
    let Some(mr) = p.mr.as_deref() else {
        return Ok((1, None));
    };
    let clock = &*p.clock;
    if clock.step == 0 || !p.motion.ready {
        return Err("first step");
    }
    // 1. Features with per-step state.
    let n = p.roster.bodies.len();
    per_step_features(p, n)?;
    // 2. The schedule.
    let (k_max, force_n, torque_nm) = schedule(p, mr, n)?;
    if k_max <= 1 {
        return Ok((1, None));
    }
    // 3. Contact and the mechanism.
    let stack = contact_idle(p)?;
    // 4. Guarantees judged at samples only keep the fixed step.
    let g = &*p.guarantees;
    if g.last_rate.len() != g.list.len() || g.last.len() != g.list.len() {
        return Err("first step");
    }
    if g.last_rate.iter().any(Option::is_none) {
        return Err("guarantee judged at samples only");
    }
    // Per-body bounds at t₀.
    let orbit = match p.env.orbit() {
        Some(o) => {
            let (r, v) = o.reference.state();
            let mu = MU_EARTH_M3_S2;
            (Some(mu), v.norm(), r.norm())
        }
        None => (None, 0.0, f64::INFINITY),
    };
    let bb = body_bounds(p, &force_n, &torque_nm)?;
    let stack = match stack {
        Some(m) => Some(stack_fit(p, m, &force_n, &torque_nm)?),
        None => None,
    };
    let docking = if stack.is_some() {
        None // docked: the magnet is off and the ports are held
    } else {
        docking_reach(p)?
    };
    let centres: Vec<nalgebra::Vector3<f64>> = p
        .roster
        .bodies
        .iter()
        .map(|e| p.bodies.get(*e).map(|(_, s)| s.pos_m))
        .collect::<Result<_, _>>()
        .map_err(|_| "first step")?;
    let fit = Fit {
        mr,
        bb,
        centres,
        docking,
        orbit,
        mon: &p.mon,
        g,
        max_turn: mr.max_turn_rad(),
        dt: clock.dt_s,
        t0: clock.t_s(),
        stack,
    };
    // Bisection for the longest span that fits (every condition tightens as h grows).
    fit.fits(2)?;
    if fit.fits(k_max).is_ok() {
        return Ok((k_max, fit.stack));
    }
    let (mut lo, mut hi) = (2, k_max);
    while hi - lo > 1 {
        let mid = lo + (hi - lo) / 2;
        if fit.fits(mid).is_ok() {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    Ok((lo, fit.stack))
}

/// Condition 1 of the module documentation, the features with per-step state the planner
/// sees in the world: no air-bearing table, no L2 frame, at most [`MAX_BODIES`] bodies (`n`).
fn per_step_features(p: &PlanInputs, n: usize) -> Result<(), &'static str> {
    if p.table.is_some() {
        return Err("air-bearing table");
    }
    if p.env.l2_centre().is_some() {
        return Err("L2 frame");
    }
    if n > MAX_BODIES {
        return Err("more bodies than multirate::MAX_BODIES");
    }
    Ok(())
}

/// Condition 2 of the module documentation (and condition 1's controller features): the
/// longest span the schedule allows (the requested maximum, the run's end, the next
/// trajectory row and every controller's next call), and per body (`n` bodies) the norms of
/// the held forces and torques after the actuators, N and N·m; an error for a disturbance, a
/// sensor or navigation filter, or an actuator with per-step state.
fn schedule(
    p: &PlanInputs,
    mr: &MultiRate,
    n: usize,
) -> Result<(u64, Vec<f64>, Vec<f64>), &'static str> {
    let clock = &*p.clock;
    let mut force_n = vec![0.0; n];
    let mut torque_nm = vec![0.0; n];
    let mut k_max = mr.max_span.min(p.cap.0.max(1));
    let every = u64::from(p.rec.every.max(1));
    k_max = k_max.min(every - clock.step % every);
    if let Some(host) = p.host.as_deref() {
        if !host.disturbances.is_empty() {
            return Err("disturbance");
        }
        for slot in &host.slots {
            if slot.sensor.is_some() || slot.nav.is_some() {
                return Err("sensor or navigation filter");
            }
            let Some((f, t)) = held_bound(&slot.actuator.spec, &slot.held) else {
                return Err("actuator with per-step state (PWPF, RCS)");
            };
            if let (Some(fb), Some(tb)) = (force_n.get_mut(slot.body), torque_nm.get_mut(slot.body))
            {
                *fb += f;
                *tb += t;
            }
            let period = slot.period_steps.max(1);
            k_max = k_max.min(period - clock.step % period);
        }
    }
    Ok((k_max, force_n, torque_nm))
}

/// Condition 3's state at t₀: rapier not stepped every step, no body touching, no joint but a
/// latched stack's ([`latched_stack`], returned), the compliant contact idle, the docking
/// mechanism `FREE` with its magnet off (or `LATCHED`, holding the stack).
fn contact_idle(p: &PlanInputs) -> Result<Option<[usize; 2]>, &'static str> {
    if p.sync.every_step {
        return Err("rapier every step (monitor.rapier_every_step)");
    }
    if p.contact.touching.iter().any(|t| *t) {
        return Err("contact or joint");
    }
    let stack = if p.phys.world.impulse_joints.iter().next().is_some() {
        Some(latched_stack(p)?)
    } else {
        None
    };
    if p.compliant.as_deref().is_some_and(|c| {
        !c.step.is_empty()
            || c.pairs.iter().any(|q| q.in_contact)
            || c.link.latch.is_some()
            || c.link.separation.is_some()
            || c.link.platform.is_some()
    }) {
        return Err("compliant contact");
    }
    if stack.is_none()
        && let Some(d) = p.docking.as_deref()
        && !mechanism_idle(d)
    {
        return Err("docking mechanism active");
    }
    Ok(stack)
}

/// The docking mechanism acts on nothing this step: `FREE` with its magnet off, or `RELEASED`
/// once the separation springs have reached the end of their stroke (`separation_complete`;
/// the magnet pulls in no released state, and the mechanism then only watches for the
/// springs, which are done).
fn mechanism_idle(d: &Docking) -> bool {
    use crate::contact::dock_state::DockState;
    match d.state {
        DockState::Free => !d.magnet_on,
        DockState::Released => d.separation_end.is_some(),
        _ => false,
    }
}

/// Condition 3's latched stack: the world's one joint is the docking mechanism's rigid latch
/// (`LATCHED`, no compliant interface), its first step — the one that stops the bodies'
/// relative motion, whose impulse is the latch impulse — was rapier's, and no release command
/// waits (the mechanism acts on it at the end of this step, which must then be `dt_s`, as in
/// the fixed-step run). The chaser and the target, scene order.
fn latched_stack(p: &PlanInputs) -> Result<[usize; 2], &'static str> {
    let no = "contact or joint";
    if p.dock_cmds
        .as_deref()
        .is_some_and(|c| !c.release.is_empty())
    {
        return Err("docking release commanded");
    }
    let d = p.docking.as_deref().ok_or(no)?;
    let joint = d.joint.ok_or(no)?;
    if d.state != crate::contact::dock_state::DockState::Latched
        || d.interface.is_some()
        || d.loads.latch_impulse_ns.is_none()
        || p.phys.world.impulse_joints.iter().any(|(h, _)| h != joint)
    {
        return Err(no);
    }
    let (cb, _) = p.bodies.get(d.bodies.0).map_err(|_| no)?;
    let (tb, _) = p.bodies.get(d.bodies.1).map_err(|_| no)?;
    let (c, t) = (cb.index, tb.index);
    Ok(if c < t { [c, t] } else { [t, c] })
}

/// A latched stack's bounds at t₀, for a long step that flies it as one rigid body
/// ([`crate::math::stack`]).
#[derive(Debug, Clone)]
struct StackFit {
    /// The members, scene order.
    members: [usize; 2],
    /// The stack as one body: |V|, the acceleration bound Σ(|G_k| + |F_k|)/M, |X|, |L|, the
    /// torque bound Σ(|τ_k| + |c_k|·(|F_k| + |G_k|)) (without the gravity gradient, which
    /// [`Fit::body_rates`]'s rule adds), the principal moments' range; extents unused.
    body: BodyBound,
    /// Per member: |c_k|, m.
    lever_m: [f64; 2],
    /// The members' motion relative to the rigid stack at t₀, m/s and rad/s
    /// ([`crate::math::stack::residual`]).
    residual: (f64, f64),
    /// The chaser: (member slot, mass, kg; bound on its own held force and gravity, N).
    chaser: (usize, f64, f64),
    /// The latch's break force, N.
    break_force_n: f64,
}

/// The latched stack's [`StackFit`] with the held force and torque norms per body (N, N·m).
fn stack_fit(
    p: &PlanInputs,
    members: [usize; 2],
    force_n: &[f64],
    torque_nm: &[f64],
) -> Result<StackFit, &'static str> {
    let no = "contact or joint";
    let d = p.docking.as_deref().ok_or(no)?;
    let mut ms = Vec::with_capacity(2);
    let mut grav = [0.0; 2];
    for (slot, k) in members.iter().enumerate() {
        let e = p.roster.bodies.get(*k).ok_or(no)?;
        let (b, s) = p.bodies.get(*e).map_err(|_| no)?;
        grav[slot] = p.env.accel_m_s2(&s.pos_m).norm() * b.mass_kg;
        ms.push(super::stack_member(b, s, None));
    }
    let c = crate::math::stack::composite(&ms).ok_or(no)?;
    let residual = crate::math::stack::residual(&ms, &c);
    let lever_m = [c.offsets_m[0].norm(), c.offsets_m[1].norm()];
    let lam = super::motion::principal_moments(&c.inertia_kg_m2);
    let lmin = lam.iter().copied().fold(f64::INFINITY, f64::min);
    let lmax = lam.iter().copied().fold(0.0, f64::max);
    let (mut accel, mut torque) = (0.0, 0.0);
    for (slot, k) in members.iter().enumerate() {
        let f = force_n.get(*k).copied().unwrap_or(f64::INFINITY);
        accel += f + grav[slot];
        torque +=
            torque_nm.get(*k).copied().unwrap_or(f64::INFINITY) + lever_m[slot] * (f + grav[slot]);
    }
    let (cb, _) = p.bodies.get(d.bodies.0).map_err(|_| no)?;
    let cslot = usize::from(members[1] == cb.index);
    let cf = force_n.get(cb.index).copied().unwrap_or(f64::INFINITY) + grav[cslot];
    Ok(StackFit {
        members,
        body: BodyBound {
            speed_m_s: c.vel_m_s.norm(),
            accel_m_s2: accel / c.mass_kg,
            offset_m: c.com_m.norm(),
            momentum_nms: c.momentum_nms.norm(),
            torque_nm: torque,
            lambda: (lmin, lmax),
            aabb_m: 0.0,
            extent_m: 0.0,
        },
        lever_m,
        residual,
        chaser: (cslot, ms[cslot].mass_kg, cf),
        break_force_n: d.spec.latch.break_force_n,
    })
}

/// Every body's bounds at t₀ ([`BodyBound`]), in roster order, with the held force and torque
/// norms `force_n`, N, and `torque_nm`, N·m, per body.
fn body_bounds(
    p: &PlanInputs,
    force_n: &[f64],
    torque_nm: &[f64],
) -> Result<Vec<BodyBound>, &'static str> {
    let mut bb = Vec::with_capacity(p.roster.bodies.len());
    for (k, e) in p.roster.bodies.iter().enumerate() {
        let (b, s) = p.bodies.get(*e).map_err(|_| "first step")?;
        let a_g = p
            .env
            .gravity()
            .map_or(0.0, |g| g.accel_m_s2(&s.pos_m).norm());
        let lam = p.motion.lambda_kg_m2.get(k).copied().unwrap_or([0.0; 3]);
        let lmin = lam.iter().copied().fold(f64::INFINITY, f64::min);
        let lmax = lam.iter().copied().fold(0.0, f64::max);
        let w_body = s.att.inverse() * s.omega_rad_s;
        bb.push(BodyBound {
            speed_m_s: s.vel_m_s.norm(),
            accel_m_s2: a_g + force_n[k] / b.mass_kg,
            offset_m: s.pos_m.norm(),
            momentum_nms: (b.inertia_kg_m2 * w_body).norm(),
            torque_nm: torque_nm[k],
            lambda: (lmin, lmax),
            aabb_m: p.geo.aabb_extent_m.get(k).copied().unwrap_or(f64::INFINITY),
            extent_m: p.geo.extent_m.get(k).copied().unwrap_or(f64::INFINITY),
        });
    }
    Ok(bb)
}

/// The docking ports at t₀, when the scene has a docking mechanism: ((chaser index, its port's
/// lever about its centre of mass, m), (target index, lever, m), the ports' gap, m, the
/// magnet's activation distance, m).
type DockReach = ((usize, f64), (usize, f64), f64, f64);

/// The docking ports' [`DockReach`] at t₀, `None` without a docking mechanism.
fn docking_reach(p: &PlanInputs) -> Result<Option<DockReach>, &'static str> {
    Ok(match p.docking.as_deref() {
        Some(d) => {
            let (ce, te) = d.bodies;
            let (cb, cs) = p.bodies.get(ce).map_err(|_| "first step")?;
            let (tb, ts) = p.bodies.get(te).map_err(|_| "first step")?;
            let (geom, _, _) = super::docking::geometry(&d.spec, (cs, cb), (ts, tb), &d.ports);
            Some((
                (cb.index, (d.ports.0.0 - cb.com_body_m).norm()),
                (tb.index, (d.ports.1.0 - tb.com_body_m).norm()),
                geom.gap_m,
                d.spec.magnet.activation_distance_m,
            ))
        }
        None => None,
    })
}

/// One body's (u, speed bound over the step, m/s; Ω, turn-rate bound, rad/s).
type Rates = (f64, f64);

/// What the check of one candidate span reads: the request and the bounds at t₀.
struct Fit<'a> {
    /// The scene's request.
    mr: &'a MultiRate,
    /// Per body, roster order.
    bb: Vec<BodyBound>,
    /// Per body: centre of mass, world, m.
    centres: Vec<nalgebra::Vector3<f64>>,
    /// The docking ports, if any.
    docking: Option<DockReach>,
    /// The reference orbit: (μ, m³/s², when there is gravity; |v_ref|, m/s; |r_ref|, m).
    orbit: (Option<f64>, f64, f64),
    /// The monitor (its certified pair distances at t₀).
    mon: &'a MonitorState,
    /// The guarantees (their last margins and rate bounds).
    g: &'a Guarantees,
    /// Largest turn per step, rad ([`MultiRate::max_turn_rad`]).
    max_turn: f64,
    /// Fixed step, s.
    dt: f64,
    /// Time now, s.
    t0: f64,
    /// The latched stack this step would fly as one rigid body, if any.
    stack: Option<StackFit>,
}

impl Fit<'_> {
    /// Whether a step of k fixed steps meets 3–6; the reason it does not.
    fn fits(&self, k: u64) -> Result<(), &'static str> {
        let h = k as f64 * self.dt;
        let (omega, stack_torque) = self.body_rates(h)?;
        if let Some(s) = &self.stack {
            Self::stack_holds(s, (omega[s.members[0]].1, stack_torque), h, self.mr)?;
        }
        self.pairs_clear(&omega, h)?;
        if let Some(((c, lc), (t, lt), gap, act)) = self.docking {
            let travel = (omega[c].0 + omega[c].1 * lc + omega[t].0 + omega[t].1 * lt) * h;
            if act > 0.0 && !above(gap - travel, act) {
                return Err("docking magnet range");
            }
        }
        for (last, rate) in self.g.last.iter().zip(&self.g.last_rate) {
            let r = rate.unwrap_or(f64::INFINITY);
            if !above(last.lower, 2.0 * r * h) {
                return Err("guarantee near its threshold");
            }
        }
        Ok(())
    }

    /// Condition 5 over a step of `h`, s: per body, (u, speed bound over the step, m/s; Ω,
    /// turn rate bound, rad/s), or an error when a body's position or attitude integration
    /// error would pass the tolerances. The members of a latched stack take the stack's turn
    /// rate and u = the stack's u plus Ω times their lever about its centre of mass. Also the
    /// stack's torque bound, gravity gradient included, N·m (0 without a stack).
    fn body_rates(&self, h: f64) -> Result<(Vec<Rates>, f64), &'static str> {
        let mut omega = Vec::with_capacity(self.bb.len());
        for (k, b) in self.bb.iter().enumerate() {
            if self.stack.as_ref().is_some_and(|s| s.members.contains(&k)) {
                omega.push((0.0, 0.0)); // filled below
            } else {
                let (u, om, _) = self.rate(b, 0.0, h)?;
                omega.push((u, om));
            }
        }
        let mut stack_torque = 0.0;
        if let Some(s) = &self.stack {
            let (_, om, tau) = self.rate(&s.body, s.lever_m[0].max(s.lever_m[1]), h)?;
            let u_com = s.body.speed_m_s + s.body.accel_m_s2 * h;
            for (slot, k) in s.members.iter().enumerate() {
                omega[*k] = (u_com + om * s.lever_m[slot], om);
            }
            stack_torque = tau;
        }
        Ok((omega, stack_torque))
    }

    /// Condition 5 for one body (or a stack, whose points lie within `reach_m` of its centre
    /// of mass) over a step of `h`: (u, the bound on the speed of its points within `reach_m`
    /// over the step, m/s; Ω, rad/s; the torque bound, the gravity gradient's included, N·m).
    fn rate(&self, b: &BodyBound, reach_m: f64, h: f64) -> Result<(f64, f64, f64), &'static str> {
        let (g_grad, ref_speed_m_s, ref_r_m) = self.orbit;
        let offset = b.offset_m + reach_m;
        // G: the gravity-gradient tensor's norm bound at the closest the body comes to
        // Earth's centre over the step; the jerk bound G·(u + 5|v_ref|/r·|x|).
        let g_tensor = match g_grad {
            Some(mu) => {
                let r = ref_r_m - ref_speed_m_s * h - offset;
                if !above(r, 0.0) {
                    return Err("integration tolerance");
                }
                Some((3.0 * mu / (r * r * r) * (1.0 + 10.0 * J2_EARTH), r))
            }
            None => None,
        };
        let tau = b.torque_nm + g_tensor.map_or(0.0, |g| g.0) * (b.lambda.1 - b.lambda.0);
        let om = if b.lambda.0 > 0.0 {
            (b.momentum_nms + tau * h) / b.lambda.0 * RK4_INFLATION
        } else {
            f64::INFINITY
        };
        if !above(self.max_turn, om * h - f64::MIN_POSITIVE) {
            return Err("integration tolerance");
        }
        let u = b.speed_m_s + b.accel_m_s2 * h + om * reach_m;
        let jerk = g_tensor.map_or(0.0, |(g, r)| g * (u + 5.0 * ref_speed_m_s / r * offset));
        if !above(self.mr.tol_m, jerk * h * h * h / 6.0 - f64::MIN_POSITIVE) {
            return Err("integration tolerance");
        }
        Ok((u, om, tau))
    }

    /// A latched stack over a step of `h` with its turn-rate bound `om`, rad/s, and torque bound
    /// `tau` (the held torques' moments and the gravity gradient's, N·m): the members'
    /// relative motion at t₀, which flying them as one body removes, moves them by at most the
    /// scene's tolerances over the step (m, rad); and the latch's load on the chaser stays
    /// below the break force throughout: |F| ≤ m_c·(A + α·|c_c| + Ω²·|c_c|) + |F_c| + |G_c|,
    /// with A the stack's acceleration bound and α ≤ (τ + λ_max·Ω²)/λ_min its angular
    /// acceleration's (Euler's equations).
    fn stack_holds(
        s: &StackFit,
        (om, tau): (f64, f64),
        h: f64,
        mr: &MultiRate,
    ) -> Result<(), &'static str> {
        if !(above(mr.tol_m, s.residual.0 * h) && above(mr.tol_rad, s.residual.1 * h)) {
            return Err("latched stack not rigid");
        }
        let b = &s.body;
        let alpha = (tau + b.lambda.1 * om * om) / b.lambda.0;
        let lever = s.lever_m[s.chaser.0];
        let accel = b.accel_m_s2 + (alpha + om * om) * lever;
        let load = s.chaser.1 * accel + s.chaser.2;
        if !above(s.break_force_n, load) {
            return Err("latch load near its break force");
        }
        Ok(())
    }

    /// Condition 3 over a step of `h`, s, for every pair of bodies with the rates `omega`
    /// ([`Self::body_rates`]): out of rapier's reach, or, within it, the monitor's certified
    /// distance at t₀ less the sweep clear by [`NEAR_CLEAR_M`].
    fn pairs_clear(&self, omega: &[(f64, f64)], h: f64) -> Result<(), &'static str> {
        let (bb, centres, n) = (&self.bb, &self.centres, self.bb.len());
        let member = |k: usize| self.stack.as_ref().is_some_and(|s| s.members.contains(&k));
        for i in 0..n {
            for j in i + 1..n {
                if member(i) && member(j) {
                    continue; // the latch holds them: flown as one body
                }
                let d = (centres[i] - centres[j]).norm() - bb[i].aabb_m - bb[j].aabb_m;
                let travel = (omega[i].0 + omega[j].0) * h;
                if above(d - travel, super::RAPIER_ENGAGE_M) {
                    continue;
                }
                if member(i) || member(j) {
                    // rapier does not step under a stack's long step: out of its reach only.
                    return Err("bodies near");
                }
                // Within rapier's reach: the monitor's certified distance at t₀ between the
                // parts, less what any point of either body can travel, must stay clear.
                let lower = self
                    .mon
                    .pair_index
                    .get(&(i, j))
                    .map(|k| &self.mon.pairs[*k])
                    .filter(|q| q.t_s == self.t0)
                    .map_or(f64::NEG_INFINITY, |q| q.lower_m);
                let sweep = (omega[i].0
                    + omega[i].1 * bb[i].extent_m
                    + omega[j].0
                    + omega[j].1 * bb[j].extent_m)
                    * h;
                if !above(lower - NEAR_SWEEP_FACTOR * sweep, NEAR_CLEAR_M) {
                    return Err("bodies near");
                }
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    //! References: the latch's load on a chaser held at a lever arm by a stack spun up from rest
    //! by a torque (m·α·r with α = τ/λ, the rigid body's own law, so the planner's bound with
    //! λ_min must cover it), and the residual-motion rule against its stated form |Δv|·h ≤ tol.
    use super::*;

    fn request() -> MultiRate {
        MultiRate::from_scene(
            &crate::scene::Stepping::MultiRate {
                max_step_s: 10.0,
                tol_m: 1e-6,
                tol_rad: 1e-8,
            },
            0.01,
        )
        .expect("multi-rate")
    }

    /// A stack at rest: chaser of 300 kg at 1.2 m from the stack's centre of mass, a torque
    /// bound of 1 N·m, principal moments 1 000 and 2 000 kg·m², no force, no gravity.
    fn stack(residual: (f64, f64), break_force_n: f64) -> StackFit {
        StackFit {
            members: [0, 1],
            body: BodyBound {
                speed_m_s: 0.0,
                accel_m_s2: 0.0,
                offset_m: 0.0,
                momentum_nms: 0.0,
                torque_nm: 1.0,
                lambda: (1000.0, 2000.0),
                aabb_m: 0.0,
                extent_m: 0.0,
            },
            lever_m: [0.45, 1.2],
            residual,
            chaser: (1, 300.0, 0.0),
            break_force_n,
        }
    }

    #[test]
    fn latch_load_bound_covers_the_rigid_body_load_and_refuses_near_the_break_force() {
        let mr = request();
        let h = 0.1;
        // From rest, torque 1 N·m about the axis of the smallest moment: α = 1e-3 rad/s², the
        // chaser at 1.2 m needs 300 × 1e-3 × 1.2 = 0.36 N from the latch (ω stays ~0 over
        // the step: its centripetal part is 300 × (1e-4)² × 1.2, negligible). The bound is
        // exactly that here (ω = 0 in it too), so a break force just above holds and just
        // below refuses.
        let load = 300.0 * (1.0 / 1000.0) * 1.2;
        assert!(Fit::stack_holds(&stack((0.0, 0.0), load * 1.001), (0.0, 1.0), h, &mr).is_ok());
        assert_eq!(
            Fit::stack_holds(&stack((0.0, 0.0), load * 0.999), (0.0, 1.0), h, &mr),
            Err("latch load near its break force")
        );
        // A NaN break force never clears.
        assert!(Fit::stack_holds(&stack((0.0, 0.0), f64::NAN), (0.0, 1.0), h, &mr).is_err());
    }

    #[test]
    fn residual_motion_is_removed_only_within_the_scene_tolerances() {
        let mr = request();
        let h = 0.1;
        // |Δv|·h against tol_m = 1e-6 m, |Δω|·h against tol_rad = 1e-8 rad.
        assert!(Fit::stack_holds(&stack((0.99e-5, 0.99e-7), 1e3), (0.0, 1.0), h, &mr).is_ok());
        for r in [(1.01e-5, 0.0), (0.0, 1.01e-7), (f64::NAN, 0.0)] {
            assert_eq!(
                Fit::stack_holds(&stack(r, 1e3), (0.0, 1.0), h, &mr),
                Err("latched stack not rigid"),
                "{r:?}"
            );
        }
    }
}
