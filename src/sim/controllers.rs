//! The one generic controller host: every controller of a scene — paper law, generic law,
//! user law, Python callable — runs through these four systems (see
//! [`crate::control::interface`] for the contract).
//!
//! - **Sense** ([`host_sense`]): the f64 truth of every body ([`BodyObs`], with the scene's
//!   gravity at each centre of mass), then each slot's sensor.
//! - **Control** ([`host_control`]): at t = 0 and every `period_steps` after, the observation is
//!   built and [`Controller::command`] called; the command is held. Events the law raises go to
//!   `events.jsonl` with the step's time.
//! - **Actuate** ([`host_actuate`]): every step the held command is turned into the world frame
//!   with this step's frames and passed through the slot's [`Actuator`]; the result is added to
//!   the body's [`Wrench`] (on an air-bearing table only the in-plane force and the yaw torque:
//!   the film carries the rest). Then the scenario's disturbances. Then each law's diagnostics
//!   ([`DiagnosticsAt::Actuated`]).
//! - **Monitor** ([`host_post_step`]): diagnostics after the physics
//!   ([`DiagnosticsAt::PostStep`]) for the laws that ask for them (added only then).
//!
//! A scene without controllers or disturbances gets none of these systems.
//!
//! Entries of the scene's `controllers` list are built in scene order by [`install`]; more
//! can be added to a built [`crate::sim::Simulation`] with `add_controller` before recording
//! starts.

use super::output::Diagnostics;
use super::{BodyState, Clock, Env, EventLog, Guarantees, Roster, Wrench};
use crate::actuation::Actuator;
use crate::actuation::actuator::CommandFrames;
use crate::control::interface::{
    ActuationReport, BodyInfo, BodyObs, Command, Controller, DiagnosticsAt, DockingObs, Frame,
    GuaranteeObs, MeasuredFrame, Measurement, Needs, Observation, PortsObs, RelativeObs, port_pose,
    ports_obs, relative_obs,
};
use crate::control::navfilter::RelKalman;
use crate::control::registry::{BuildContext, BuildError, Disturbance, DisturbanceContext, Slot};
use crate::control::sensor::{Sensor, SensorTruth};
use crate::environment::EnvObs;
use crate::orbit::lvlh::{LocalFrame, LocalFrameKind};
use crate::scene::{LoadedScene, SceneError};
use bevy::prelude::*;
use nalgebra::{UnitQuaternion, Vector3};
use std::collections::BTreeMap;

/// A port in its body frame: (origin, unit outward axis), m.
pub type PortFrame = (Vector3<f64>, Vector3<f64>);

/// One controller the host runs.
pub struct HostedSlot {
    /// Registered kind.
    pub kind: String,
    /// Controlled body.
    pub body: usize,
    /// Target.
    pub target: Option<usize>,
    /// Steps between calls.
    pub period_steps: u64,
    /// Port frames in the body frames: ((chaser origin, axis), (target origin, axis)).
    pub ports: Option<(PortFrame, PortFrame)>,
    /// The sensor.
    pub sensor: Option<Sensor>,
    /// The actuator.
    pub actuator: Actuator,
    /// The law.
    pub law: Box<dyn Controller>,
    /// The command held until the next call.
    pub held: Command,
    /// What the actuator did this step.
    pub report: ActuationReport,
    /// Calls so far.
    pub calls: u64,
    /// The latest delivered measurement (with a navigation filter: its estimate).
    pub measured: Option<Measurement>,
    /// The sensor's navigation filter, when it has one.
    pub nav: Option<NavSlot>,
    /// What the law reads.
    pub needs: Needs,
    /// The relative state and ports of the current truth (what `needs` asks for).
    derived: (Option<RelativeObs>, Option<PortsObs>),
    /// First diagnostics column (the slot's columns are contiguous).
    first_col: usize,
    /// Number of diagnostics columns.
    n_cols: usize,
    /// When the law wants diagnostics.
    at: &'static [DiagnosticsAt],
    /// A command frame was missing (reported once).
    frame_warned: bool,
}

/// A slot's navigation filter ([`crate::control::navfilter`]) and its columns.
pub struct NavSlot {
    /// The filter.
    pub filter: RelKalman,
    /// First of its [`NAV_COLUMNS`] columns.
    first_col: usize,
    /// Hill-from-world rotation at the start of the current step (for the applied force).
    hill_from_world: UnitQuaternion<f64>,
}

/// The navigation filter's `trajectory.csv` columns, after `nav.BODY.` (Hill frame; the
/// estimate at the start of the step, after that step's delivery): the estimate, the square
/// roots of its covariance's diagonal, its error (estimate − truth) and the latest raw
/// measurement's error against the current truth.
pub const NAV_COLUMNS: [&str; 18] = [
    "est_x_m",
    "est_y_m",
    "est_z_m",
    "est_vx_m_s",
    "est_vy_m_s",
    "est_vz_m_s",
    "sigma_x_m",
    "sigma_y_m",
    "sigma_z_m",
    "sigma_vx_m_s",
    "sigma_vy_m_s",
    "sigma_vz_m_s",
    "err_x_m",
    "err_y_m",
    "err_z_m",
    "raw_err_x_m",
    "raw_err_y_m",
    "raw_err_z_m",
];

/// Every controller of the simulation and the scenario's disturbances.
#[derive(Resource, Default)]
pub struct ControllerHost {
    /// Controllers, in installation order (hosted by `Simulation::add_controller` or a
    /// scene's `controllers`, which also put the host's systems in the schedule).
    pub slots: Vec<HostedSlot>,
    /// Disturbances, in installation order (added by `Simulation::add_disturbance`, which also
    /// puts the host's systems in the schedule).
    pub disturbances: Vec<Box<dyn Disturbance>>,
    /// Bodies' constants.
    pub info: Vec<BodyInfo>,
    /// Bodies' truth at the start of the current step (refreshed in Sense).
    pub truth: Vec<BodyObs>,
    guarantees: Vec<GuaranteeObs>,
    /// The environment at the start of the current step (refreshed in Sense).
    env_now: EnvObs,
    docking_now: Option<DockingObs>,
    wrench_buf: Vec<crate::control::registry::BodyWrench>,
    planar: bool,
    /// Some law reads the gravity at the bodies.
    gravity: bool,
    /// `jet_pulse` events raised so far in the run, all jets together.
    jet_pulse_events: u64,
    /// `host_sense`, `host_control` and `host_actuate` are in the schedule.
    scheduled: bool,
    /// `host_post_step` is in the schedule.
    post_step_scheduled: bool,
}

impl ControllerHost {
    /// The `k`-th controller whose law is a `T`.
    pub fn law<T: 'static>(&self, k: usize) -> Option<&T> {
        self.slots
            .iter()
            .filter_map(|s| (*s.law).as_any().downcast_ref::<T>())
            .nth(k)
    }
    /// The `k`-th slot whose law is a `T`.
    pub fn slot_of<T: 'static>(&self, k: usize) -> Option<&HostedSlot> {
        self.slots
            .iter()
            .filter(|s| (*s.law).as_any().is::<T>())
            .nth(k)
    }
    /// Per controller: kind, body, target, period, calls, the velocity increment its actuator
    /// applied (∫|F|/m dt, m/s) and the propellant it used (thrusters, kg) — for `summary.json`.
    pub fn summary(&self) -> serde_json::Value {
        let name = |i: usize| self.info.get(i).map(|b| b.name.clone());
        serde_json::Value::Array(
            self.slots
                .iter()
                .map(|s| {
                    let mut v = serde_json::json!({
                        "kind": s.kind,
                        "body": name(s.body),
                        "target": s.target.and_then(name),
                        "period_steps": s.period_steps,
                        "calls": s.calls,
                        "delta_v_m_s": s.actuator.delta_v_m_s,
                        "propellant_used_kg": s.actuator.propellant_used_kg,
                    });
                    // RCS jets: per-jet totals and the steps the command could not be met.
                    if !s.actuator.jets.is_empty()
                        && let Some(o) = v.as_object_mut()
                    {
                        o.insert("jets".into(), serde_json::json!(s.actuator.jets));
                        o.insert(
                            "saturated_steps".into(),
                            serde_json::json!(s.actuator.saturated_steps),
                        );
                    }
                    v
                })
                .collect(),
        )
    }

    /// The `k`-th disturbance of type `T`.
    pub fn disturbance<T: 'static>(&self, k: usize) -> Option<&T> {
        self.disturbances
            .iter()
            .filter_map(|d| (**d).as_any().downcast_ref::<T>())
            .nth(k)
    }
}

/// The environment as controllers see it, from the app's resources (a copy of [`Env::now`];
/// force-free space without an [`Env`]).
pub fn env_of_world(world: &World) -> EnvObs {
    world
        .get_resource::<Env>()
        .map(|e| e.now.clone())
        .unwrap_or_default()
}

/// What [`EnvRefs::now`] gives in an app without an environment.
static FREE_SPACE: EnvObs = EnvObs::FreeSpace;

/// The environment resources a host system reads.
#[derive(bevy::ecs::system::SystemParam)]
pub struct EnvRefs<'w> {
    env: Option<Res<'w, Env>>,
    docking: Option<Res<'w, super::docking::Docking>>,
}

impl EnvRefs<'_> {
    /// The environment now.
    fn now(&self) -> &EnvObs {
        self.env.as_deref().map_or(&FREE_SPACE, |e| &e.now)
    }
    /// The environment, if the app has one (its gravity field).
    fn env(&self) -> Option<&Env> {
        self.env.as_deref()
    }
    fn docking(&self) -> Option<DockingObs> {
        self.docking.as_ref().map(|d| DockingObs {
            state: d.state.name(),
            magnet_on: d.magnet_on,
            gap_m: d.geometry.gap_m,
            axial_error_m: d.geometry.axial_error_m,
            lateral_m: d.geometry.lateral_m,
            misalignment_deg: d.geometry.misalignment_deg,
        })
    }
}

/// Bodies' constants from the scene.
pub fn body_info(scene: &crate::scene::Scene) -> Vec<BodyInfo> {
    scene
        .bodies
        .iter()
        .enumerate()
        .map(|(index, b)| BodyInfo {
            index,
            name: b.name.clone(),
            role: b.role,
            mass_kg: b.mass_kg,
            inertia_kg_m2: b.inertia_kg_m2.matrix(),
            com_body_m: Vector3::from(b.com_m),
            ports: b
                .ports
                .iter()
                .map(|p| {
                    (
                        p.name.clone(),
                        Vector3::from(p.pos_m),
                        Vector3::from(p.axis).normalize(),
                    )
                })
                .collect(),
        })
        .collect()
}

/// Refreshes `truth` from the bodies' f64 states (the gravity, from `env`, only if some law
/// reads it).
fn refresh_truth(
    truth: &mut Vec<BodyObs>,
    roster: &Roster,
    states: &Query<&BodyState>,
    env: Option<&Env>,
) {
    truth.clear();
    for e in &roster.bodies {
        let s = states.get(*e).expect("roster body");
        let g = env.map_or_else(Vector3::zeros, |env| env.accel_m_s2(&s.pos_m));
        truth.push(BodyObs::new(s.pos_m, s.vel_m_s, s.att, s.omega_rad_s, g));
    }
}

/// The relative state and ports a slot needs, from `truth`.
fn derive(
    slot: &HostedSlot,
    info: &[BodyInfo],
    truth: &[BodyObs],
    env: &EnvObs,
) -> (Option<RelativeObs>, Option<PortsObs>) {
    let Some(t) = slot.target else {
        return (None, None);
    };
    let relative = slot
        .needs
        .relative
        .then(|| relative_obs(&truth[slot.body], &truth[t], env.reference()));
    let ports = match slot.ports {
        Some((pc, pt)) if slot.needs.ports => Some(ports_of(info, truth, slot.body, t, &pc, &pt)),
        _ => None,
    };
    (relative, ports)
}

/// Refreshes every slot's derived observation fields.
fn refresh_derived(host: &mut ControllerHost, env: &EnvObs) {
    for k in 0..host.slots.len() {
        let d = derive(&host.slots[k], &host.info, &host.truth, env);
        host.slots[k].derived = d;
    }
}

/// What an observation borrows from a slot (its own fields, so the slot's law can be borrowed
/// mutably beside it).
#[derive(Clone, Copy)]
struct SlotView<'a> {
    body: usize,
    target: Option<usize>,
    derived: &'a (Option<RelativeObs>, Option<PortsObs>),
    measured: &'a Option<Measurement>,
}

/// The observation of one slot.
#[allow(clippy::too_many_arguments)]
fn observation<'a>(
    slot: SlotView<'a>,
    clock: &Clock,
    info: &'a [BodyInfo],
    truth: &'a [BodyObs],
    env: &'a EnvObs,
    docking: Option<DockingObs>,
    guarantees: &'a [GuaranteeObs],
) -> Observation<'a> {
    Observation {
        t_s: clock.t_s(),
        step: clock.step,
        dt_s: clock.dt_s,
        body: slot.body,
        target: slot.target,
        info,
        bodies: truth,
        env,
        relative: slot.derived.0.as_ref(),
        ports: slot.derived.1.as_ref(),
        measured: slot.measured.as_ref(),
        docking,
        guarantees,
    }
}

/// A [`SlotView`] of a slot by field borrows (so that `slot.law` stays free to borrow).
macro_rules! view {
    ($s:expr) => {
        SlotView {
            body: $s.body,
            target: $s.target,
            derived: &$s.derived,
            measured: &$s.measured,
        }
    };
}

fn ports_of(
    info: &[BodyInfo],
    truth: &[BodyObs],
    body: usize,
    target: usize,
    pc: &(Vector3<f64>, Vector3<f64>),
    pt: &(Vector3<f64>, Vector3<f64>),
) -> PortsObs {
    let c = port_pose(&info[body], &truth[body], &pc.0, &pc.1);
    let t = port_pose(&info[target], &truth[target], &pt.0, &pt.1);
    ports_obs(c, t, &truth[target])
}

/// The truth a slot's sensor measures, in its frame.
fn sensor_truth(
    frame: MeasuredFrame,
    slot: &HostedSlot,
    info: &[BodyInfo],
    truth: &[BodyObs],
    env: &EnvObs,
) -> Option<SensorTruth> {
    let own = &truth[slot.body];
    match frame {
        MeasuredFrame::World => Some(SensorTruth {
            pos_m: own.pos_m,
            vel_m_s: own.vel_m_s,
            att: own.att,
            omega_rad_s: own.omega_rad_s,
        }),
        MeasuredFrame::Hill => {
            let t = slot.target?;
            let rel = relative_obs(own, &truth[t], env.reference());
            let (h, c, w) = (
                rel.hill?,
                rel.dcm_world_from_hill?,
                rel.hill_rate_world_rad_s?,
            );
            let q = UnitQuaternion::from_matrix(&c.transpose());
            Some(SensorTruth {
                pos_m: h.pos_m,
                vel_m_s: h.vel_m_s,
                att: q * own.att,
                omega_rad_s: c.transpose() * (own.omega_rad_s - w),
            })
        }
        MeasuredFrame::TargetBody => {
            let t = slot.target?;
            let rel = relative_obs(own, &truth[t], env.reference());
            let inv = truth[t].att.inverse();
            Some(SensorTruth {
                pos_m: rel.target_body.pos_m,
                vel_m_s: rel.target_body.vel_m_s,
                att: inv * own.att,
                omega_rad_s: inv * (own.omega_rad_s - truth[t].omega_rad_s),
            })
        }
        MeasuredFrame::Port => {
            let t = slot.target?;
            let (pc, pt) = slot.ports?;
            let p = ports_of(info, truth, slot.body, t, &pc, &pt);
            Some(SensorTruth {
                pos_m: p.rel_port.pos_m,
                vel_m_s: p.rel_port.vel_m_s,
                att: p.rel_att,
                omega_rad_s: p.target.att.inverse() * (own.omega_rad_s - truth[t].omega_rad_s),
            })
        }
    }
}

/// Sense: the truth of every body, then each sensor.
pub fn host_sense(
    clock: Res<Clock>,
    roster: Res<Roster>,
    states: Query<&BodyState>,
    refs: EnvRefs,
    mut host: ResMut<ControllerHost>,
    mut diag: ResMut<Diagnostics>,
) {
    if host.slots.is_empty() && host.disturbances.is_empty() {
        return;
    }
    let host = &mut *host;
    let env = refs.env().filter(|_| host.gravity);
    refresh_truth(&mut host.truth, &roster, &states, env);
    // Taken out of the host while the slots are borrowed, put back below.
    let mut env = std::mem::take(&mut host.env_now);
    env.assign(refs.now());
    if let EnvObs::SunEarthL2 { centre, states_rot } = &mut env {
        states_rot.extend(
            host.truth
                .iter()
                .map(|b| centre.world_to_rot(&b.pos_m, &b.vel_m_s)),
        );
    }
    host.docking_now = refs.docking();
    refresh_derived(host, &env);
    let t = clock.t_s();
    for k in 0..host.slots.len() {
        let Some(frame) = host.slots[k].sensor.as_ref().map(|s| s.spec.frame) else {
            continue;
        };
        let truth = sensor_truth(frame, &host.slots[k], &host.info, &host.truth, &env);
        let slot = &mut host.slots[k];
        if let (Some(truth), Some(sensor)) = (truth, slot.sensor.as_mut()) {
            let raw = sensor.step(t, clock.dt_s, &truth);
            match slot.nav.as_mut() {
                None => slot.measured = raw,
                Some(nav) => {
                    let own = &host.truth[slot.body];
                    let mass = host.info[slot.body].mass_kg;
                    slot.measured =
                        nav_step(nav, raw, &truth, own, mass, &slot.report, &clock, &mut diag);
                }
            }
        }
    }
    host.env_now = env;
}

/// One step of a slot's navigation filter: the prediction over the previous step with the
/// force its actuator applied, the update with a fresh delivery, the columns; returns what the
/// law reads (the estimate as a `Hill` measurement; before the first delivery, nothing).
#[allow(clippy::too_many_arguments)]
fn nav_step(
    nav: &mut NavSlot,
    raw: Option<Measurement>,
    truth: &SensorTruth,
    own: &BodyObs,
    mass_kg: f64,
    report: &ActuationReport,
    clock: &Clock,
    diag: &mut Diagnostics,
) -> Option<Measurement> {
    let step = clock.step;
    if step > 0 {
        let a = nav.hill_from_world * (report.force_world_n / mass_kg);
        nav.filter.propagate(step - 1, a);
    }
    // The Hill sensor's truth carries the body's attitude in the Hill frame: q·own.att.
    nav.hill_from_world = truth.att * own.att.inverse();
    if let Some(m) = raw.filter(|m| m.fresh) {
        let exposure = (m.t_s / clock.dt_s - 1e-9).ceil().max(0.0) as u64;
        nav.filter.update(exposure.min(step), step, m.pos_m);
    }
    let out = &mut diag.values[nav.first_col..nav.first_col + NAV_COLUMNS.len()];
    let est = nav.filter.estimate();
    match est {
        Some((_, x, p)) => {
            for i in 0..6 {
                out[i] = x[i];
                out[6 + i] = p[(i, i)].max(0.0).sqrt();
            }
            for i in 0..3 {
                out[12 + i] = x[i] - truth.pos_m[i];
            }
        }
        None => out[..15].fill(f64::NAN),
    }
    match raw {
        Some(m) => {
            for i in 0..3 {
                out[15 + i] = m.pos_m[i] - truth.pos_m[i];
            }
        }
        None => out[15..].fill(f64::NAN),
    }
    let (_, x, _) = est?;
    let m = raw?;
    Some(Measurement {
        t_s: clock.t_s(),
        delivered_s: clock.t_s(),
        fresh: m.fresh,
        frame: MeasuredFrame::Hill,
        pos_m: x.fixed_rows::<3>(0).into_owned(),
        vel_m_s: x.fixed_rows::<3>(3).into_owned(),
        att: m.att,
        omega_rad_s: m.omega_rad_s,
        yaw_rad: None,
    })
}

/// Control: each law at its period; the command is held.
pub fn host_control(
    clock: Res<Clock>,
    guarantees: Res<Guarantees>,
    mut host: ResMut<ControllerHost>,
    mut log: ResMut<EventLog>,
    mut dock_cmds: Option<ResMut<super::docking::DockingCommands>>,
) {
    if host.slots.is_empty() {
        return;
    }
    let host = &mut *host;
    if host.guarantees.len() != guarantees.status.len() {
        host.guarantees = guarantees
            .status
            .iter()
            .map(|s| GuaranteeObs {
                name: s.name.clone(),
                unit: s.unit.clone(),
                margin: s.last_margin,
            })
            .collect();
    }
    for (g, s) in host.guarantees.iter_mut().zip(&guarantees.status) {
        g.margin = s.last_margin;
    }
    let env = &host.env_now;
    let docking = host.docking_now;
    let t = clock.t_s();
    for slot in host.slots.iter_mut() {
        if !clock.step.is_multiple_of(slot.period_steps) {
            continue;
        }
        let obs = observation(
            view!(slot),
            &clock,
            &host.info,
            &host.truth,
            env,
            docking,
            &host.guarantees,
        );
        slot.held = slot.law.command(&obs);
        slot.calls += 1;
        for e in slot.law.take_events() {
            if e.kind == crate::control::generic::sequencer::DOCKING_RELEASE_EVENT
                && let Some(d) = dock_cmds.as_deref_mut()
            {
                d.release.push(format!("controller event {}", e.data));
            }
            log.push(t, &e.kind, e.data);
        }
    }
}

/// Actuate: held commands through the actuators into the wrenches; disturbances; diagnostics.
pub fn host_actuate(
    clock: Res<Clock>,
    roster: Res<Roster>,
    mut wrenches: Query<&mut Wrench>,
    mut host: ResMut<ControllerHost>,
    mut diag: ResMut<Diagnostics>,
    mut log: ResMut<EventLog>,
) {
    if host.slots.is_empty() && host.disturbances.is_empty() {
        return;
    }
    let ControllerHost {
        slots,
        disturbances,
        info,
        truth,
        guarantees,
        env_now,
        docking_now,
        planar,
        wrench_buf,
        jet_pulse_events,
        ..
    } = &mut *host;
    let env = &*env_now;
    let dt = clock.h_s();
    for (index, slot) in slots.iter_mut().enumerate() {
        let own = &truth[slot.body];
        let uses_hill =
            slot.held.force_frame == Frame::Hill || slot.held.torque_frame == Frame::Hill;
        let hill = if uses_hill {
            slot.derived
                .0
                .and_then(|r| r.dcm_world_from_hill)
                .or_else(|| {
                    env.reference().map(|(r, v)| {
                        let (p, q) = slot
                            .target
                            .map_or((r, v), |t| (r + truth[t].pos_m, v + truth[t].vel_m_s));
                        LocalFrame::new(LocalFrameKind::Hill, &p, &q)
                            .dcm_frame_from_eci
                            .transpose()
                    })
                })
        } else {
            None
        };
        let frames = CommandFrames {
            body: own.att,
            hill,
            target_body: slot.target.map(|t| truth[t].att),
        };
        let mass = info[slot.body].mass_kg;
        match slot.actuator.step(&slot.held, &frames, mass, dt) {
            Some(r) => slot.report = r,
            None => {
                slot.report = ActuationReport::default();
                if !slot.frame_warned {
                    slot.frame_warned = true;
                    log.push(
                        clock.t_s(),
                        "controller_frame_unavailable",
                        serde_json::json!({"body": info[slot.body].name, "kind": slot.kind,
                            "reason": "the command's frame does not exist in this scene (Hill needs an orbit, TargetBody a target): nothing applied"}),
                    );
                }
                continue;
            }
        }
        if !slot.actuator.ended_pulses.is_empty() {
            jet_pulse_log(
                &mut slot.actuator,
                index,
                &info[slot.body].name,
                &clock,
                jet_pulse_events,
                &mut log,
            );
        }
        if let Ok(mut w) = wrenches.get_mut(roster.bodies[slot.body]) {
            let (f, t) = (slot.report.force_world_n, slot.report.torque_world_nm);
            if *planar {
                super::airbearing::add_planar(&mut w, &f, &t);
            } else {
                w.force_n += f;
                w.torque_nm += t;
            }
        }
    }
    if !disturbances.is_empty() {
        let ctx = DisturbanceContext {
            t_s: clock.t_s(),
            dt_s: dt,
            step: clock.step,
            info,
            bodies: truth,
            env,
        };
        for d in disturbances.iter_mut() {
            wrench_buf.clear();
            d.wrenches(&ctx, wrench_buf);
            for bw in wrench_buf.iter() {
                if let Ok(mut w) = wrenches.get_mut(roster.bodies[bw.body]) {
                    if let Some(f) = bw.force_n {
                        w.force_n += f;
                    }
                    if let Some(t) = bw.torque_nm {
                        w.torque_nm += t;
                    }
                }
            }
        }
    }
    write_diagnostics(
        slots,
        info,
        truth,
        guarantees,
        DiagnosticsAt::Actuated,
        &clock,
        env,
        *docking_now,
        &mut diag,
    );
}

/// Raises a `jet_pulse` event for each firing pulse of `actuator`'s jets that ended this step
/// (the pulse ran over the `steps` steps before this one: from `start_s` to now), within the
/// caps: [`crate::actuation::rcs::MAX_PULSE_EVENTS_PER_JET`] per jet and
/// [`crate::actuation::rcs::MAX_PULSE_EVENTS_PER_RUN`] for the run,
/// each cap announced once by a `jet_pulse_events_capped` event. Drains the actuator's list.
fn jet_pulse_log(
    actuator: &mut Actuator,
    controller: usize,
    body: &str,
    clock: &Clock,
    run_count: &mut u64,
    log: &mut EventLog,
) {
    use crate::actuation::rcs::{MAX_PULSE_EVENTS_PER_JET, MAX_PULSE_EVENTS_PER_RUN};
    let t = clock.t_s();
    for p in std::mem::take(&mut actuator.ended_pulses) {
        let Some(totals) = actuator.jets.get_mut(p.jet) else {
            continue;
        };
        if *run_count > MAX_PULSE_EVENTS_PER_RUN || totals.pulse_events > MAX_PULSE_EVENTS_PER_JET {
            continue;
        }
        if *run_count == MAX_PULSE_EVENTS_PER_RUN {
            *run_count += 1;
            log.push(
                t,
                "jet_pulse_events_capped",
                serde_json::json!({"scope": "run", "events": MAX_PULSE_EVENTS_PER_RUN,
                    "reason": "later pulses of every jet are counted in summary.json's jets only"}),
            );
            continue;
        }
        if totals.pulse_events == MAX_PULSE_EVENTS_PER_JET {
            totals.pulse_events += 1;
            log.push(
                t,
                "jet_pulse_events_capped",
                serde_json::json!({"scope": "jet", "body": body, "controller": controller,
                    "jet": totals.name, "events": MAX_PULSE_EVENTS_PER_JET,
                    "reason": "later pulses of this jet are counted in summary.json's jets only"}),
            );
            continue;
        }
        totals.pulse_events += 1;
        *run_count += 1;
        let start_step = clock.step.saturating_sub(p.steps);
        log.push(
            t,
            "jet_pulse",
            serde_json::json!({"body": body, "controller": controller, "jet": totals.name,
                "start_s": start_step as f64 * clock.dt_s,
                "duration_s": p.steps as f64 * clock.dt_s,
                "on_time_s": p.on_time_s, "impulse_ns": p.impulse_ns}),
        );
    }
}

/// Writes the diagnostics of every slot that wants them at `at`, straight into its columns
/// (a slot's columns are contiguous: `host_slot` registers them together).
#[allow(clippy::too_many_arguments)]
fn write_diagnostics(
    slots: &mut [HostedSlot],
    info: &[BodyInfo],
    truth: &[BodyObs],
    guarantees: &[GuaranteeObs],
    at: DiagnosticsAt,
    clock: &Clock,
    env: &EnvObs,
    docking: Option<DockingObs>,
    diag: &mut Diagnostics,
) {
    for slot in slots.iter_mut() {
        if slot.n_cols == 0 || !slot.at.contains(&at) {
            continue;
        }
        let obs = observation(view!(slot), clock, info, truth, env, docking, guarantees);
        let out = &mut diag.values[slot.first_col..slot.first_col + slot.n_cols];
        slot.law.diagnostics(at, &obs, &slot.report, out);
    }
}

/// Monitor: diagnostics after the physics, for the laws that want them.
pub fn host_post_step(
    clock: Res<Clock>,
    roster: Res<Roster>,
    states: Query<&BodyState>,
    refs: EnvRefs,
    mut host: ResMut<ControllerHost>,
    mut diag: ResMut<Diagnostics>,
) {
    let host = &mut *host;
    let env = refs.env().filter(|_| host.gravity);
    refresh_truth(&mut host.truth, &roster, &states, env);
    // The environment after the physics (an L2 snapshot's `states_rot` is empty here).
    let env = refs.now();
    refresh_derived(host, env);
    write_diagnostics(
        &mut host.slots,
        &host.info,
        &host.truth,
        &host.guarantees,
        DiagnosticsAt::PostStep,
        &clock,
        env,
        refs.docking(),
        &mut diag,
    );
}

/// Hosts one slot: columns, guarantees, the t = 0 diagnostics. Errors are messages (duplicate
/// column names).
pub fn host_slot(world: &mut World, slot: Slot) -> Result<usize, String> {
    let Slot {
        kind,
        body,
        target,
        period_steps,
        sensor,
        actuator,
        ports,
        mut law,
    } = slot;
    let (names, port_frames) = {
        let host = world.resource::<ControllerHost>();
        let info = &host.info;
        if body >= info.len() || target.is_some_and(|t| t >= info.len()) {
            return Err(format!("controller `{kind}`: body index out of range"));
        }
        let port_frames = match (&ports, target) {
            (Some((p, q)), Some(t)) => {
                let a = info[body]
                    .port(p)
                    .ok_or_else(|| format!("body `{}` has no port `{p}`", info[body].name))?;
                let b = info[t]
                    .port(q)
                    .ok_or_else(|| format!("body `{}` has no port `{q}`", info[t].name))?;
                Some((a, b))
            }
            _ => None,
        };
        (law.columns(), port_frames)
    };
    let nav_names: Vec<String> = match sensor.as_ref().and_then(|s| s.filter.as_ref()) {
        Some(_) => {
            let b = &world.resource::<ControllerHost>().info[body].name;
            NAV_COLUMNS.iter().map(|c| format!("nav.{b}.{c}")).collect()
        }
        None => Vec::new(),
    };
    let column_of = |world: &mut World, names: &[String]| -> Result<Vec<usize>, String> {
        let mut diag = world.resource_mut::<Diagnostics>();
        let mut cols = Vec::with_capacity(names.len());
        for n in names {
            if diag.contains(n) {
                return Err(format!(
                    "controller `{kind}`: column `{n}` is already written by another controller or mechanism"
                ));
            }
            cols.push(diag.column(n));
        }
        Ok(cols)
    };
    let cols = column_of(world, &names)?;
    let nav = match sensor
        .as_ref()
        .and_then(|s| s.filter.as_ref().map(|f| (s, f)))
    {
        Some((s, f)) => {
            let dt = world.resource::<Clock>().dt_s;
            // The reference's state at its own time (the filter's step k is at k·dt).
            let filter = world
                .get_resource::<Env>()
                .and_then(Env::orbit)
                .and_then(|o| {
                    let (r, v) = o.reference.state();
                    RelKalman::for_reference(f, &r, &v, o.reference.t_s(), dt, s.position_noise_m)
                })
                .ok_or_else(|| {
                    format!("controller `{kind}`: the sensor's filter runs on the CW or Yamanaka–Ankersen model and needs an orbit environment (a bound, elliptic reference orbit)")
                })?;
            let first_col = column_of(world, &nav_names)?.first().copied().unwrap_or(0);
            Some(NavSlot {
                filter,
                first_col,
                hill_from_world: UnitQuaternion::identity(),
            })
        }
        None => None,
    };
    {
        let mut g = world.resource_mut::<Guarantees>();
        for gu in law.guarantees() {
            g.admissible(gu.as_ref())
                .map_err(|e| format!("controller `{kind}`: {e}"))?;
            g.register(gu);
        }
    }
    let at = law.diagnostics_at();
    let needs = law.needs();
    let mut slot = HostedSlot {
        kind,
        body,
        target,
        period_steps: period_steps.max(1),
        ports: port_frames,
        sensor: sensor.map(Sensor::new),
        actuator: Actuator::new(actuator),
        law,
        held: Command::zero(),
        report: ActuationReport::default(),
        calls: 0,
        measured: None,
        nav,
        needs,
        derived: (None, None),
        first_col: cols.first().copied().unwrap_or(0),
        n_cols: cols.len(),
        at,
        frame_warned: false,
    };
    debug_assert!(
        cols.windows(2).all(|w| w[1] == w[0] + 1),
        "contiguous columns"
    );
    // The t = 0 row: diagnostics of the initial state.
    if slot.n_cols > 0 && slot.at.contains(&DiagnosticsAt::Start) {
        world.resource_scope(|world, mut host: Mut<ControllerHost>| {
            let clock = world.resource::<Clock>().clone();
            let roster = world.resource::<Roster>().clone();
            let env = world.get_resource::<Env>();
            let mut truth = Vec::new();
            for e in &roster.bodies {
                let s = world.get::<BodyState>(*e).expect("roster body");
                let g = env.map_or_else(Vector3::zeros, |env| env.accel_m_s2(&s.pos_m));
                truth.push(BodyObs::new(s.pos_m, s.vel_m_s, s.att, s.omega_rad_s, g));
            }
            let env = env_of_world(world);
            let guarantees: Vec<GuaranteeObs> = Vec::new();
            slot.derived = derive(&slot, &host.info, &truth, &env);
            let obs = observation(
                view!(slot),
                &clock,
                &host.info,
                &truth,
                &env,
                None,
                &guarantees,
            );
            let mut buf = vec![f64::NAN; slot.n_cols];
            slot.law
                .diagnostics(DiagnosticsAt::Start, &obs, &slot.report, &mut buf);
            let mut diag = world.resource_mut::<Diagnostics>();
            diag.values[slot.first_col..slot.first_col + slot.n_cols].copy_from_slice(&buf);
            host.truth = truth;
        });
    }
    let mut host = world.resource_mut::<ControllerHost>();
    host.gravity |= slot.needs.gravity;
    host.slots.push(slot);
    let k = host.slots.len() - 1;
    schedule_host_systems(world)?;
    Ok(k)
}

/// Puts the host's per-step systems in `SimStep` once there is something to host
/// (`host_sense`, `host_control`, `host_actuate`), and `host_post_step` once a law asks for
/// post-step diagnostics; a no-op when they are there. A system that is in the schedule runs,
/// or asks its run condition, every step — a run of the executor's bookkeeping and a fetch of
/// each of its resources —, so a scene without controllers or disturbances has none of them.
/// Fails only if the schedule is not in the world (it is taken out while it runs, and nothing
/// hosts a controller then).
pub(crate) fn schedule_host_systems(world: &mut World) -> Result<(), String> {
    use super::{SimStep, Stage};
    let (main, post) = {
        let h = world.resource::<ControllerHost>();
        let hosting = !(h.slots.is_empty() && h.disturbances.is_empty());
        let post = h
            .slots
            .iter()
            .any(|s| s.n_cols > 0 && s.at.contains(&DiagnosticsAt::PostStep));
        (hosting && !h.scheduled, post && !h.post_step_scheduled)
    };
    if !(main || post) {
        return Ok(());
    }
    let mut schedules = world.resource_mut::<Schedules>();
    let Some(schedule) = schedules.get_mut(SimStep) else {
        return Err("the pipeline's schedule is not in the world (it is running)".into());
    };
    if main {
        schedule.add_systems((
            // After the L2 frame is brought to this step (an empty set outside L2 scenes).
            host_sense
                .in_set(Stage::Sense)
                .after(super::environment::EnvironmentSense),
            host_control.in_set(Stage::Control),
            host_actuate.in_set(super::Order::ControllerForces),
        ));
    }
    if post {
        schedule.add_systems(host_post_step.in_set(super::Order::PostStepDiagnostics));
    }
    let mut h = world.resource_mut::<ControllerHost>();
    h.scheduled |= main;
    h.post_step_scheduled |= post;
    Ok(())
}

/// The controller host: owns the [`ControllerHost`] resource and four systems, put in the
/// schedule with the first controller or disturbance (a scene without either has none of
/// them): `host_sense` in [`super::Stage::Sense`] (after
/// [`super::environment::EnvironmentSense`]), `host_control` in [`super::Stage::Control`],
/// `host_actuate` in [`super::Order::ControllerForces`] (a controller's force is added after the
/// docking mechanism's: the order of floating-point sums is part of a run's bit-exact result),
/// and, once a law asks for post-step diagnostics, `host_post_step` in
/// [`super::Order::PostStepDiagnostics`]. Add it after the pipeline, the environment, the
/// docking mechanism and the table; the scene's controllers are then hosted by [`install`],
/// and more by `Simulation::add_controller` / `add_disturbance`.
#[derive(Debug, Clone)]
pub struct ControllersPlugin {
    /// Bodies' constants, scene order.
    info: Vec<BodyInfo>,
    /// Air-bearing scene: forces act in the table's plane.
    planar: bool,
}

impl ControllersPlugin {
    /// The host of a scene's bodies.
    pub fn new(scene: &crate::scene::Scene) -> Self {
        Self {
            info: body_info(scene),
            planar: matches!(scene.environment, crate::scene::Environment::AirBearing(_)),
        }
    }
}

impl Plugin for ControllersPlugin {
    fn build(&self, app: &mut App) {
        app.insert_resource(ControllerHost {
            info: self.info.clone(),
            planar: self.planar,
            ..Default::default()
        });
        // The per-step systems are added with the first controller or disturbance
        // (`schedule_host_systems`).
    }
}

/// Adds the [`ControllersPlugin`] and hosts the scene's `controllers`, in scene order. Called
/// after the pipeline, the docking mechanism and the environment exist, before t = 0 is
/// monitored.
pub fn install(app: &mut App, loaded: &LoadedScene) -> Result<(), SceneError> {
    let scene = &loaded.scene;
    let plugin = ControllersPlugin::new(scene);
    let info = plugin.info.clone();
    app.add_plugins(plugin);
    let world = app.world_mut();
    let initial: Vec<BodyObs> = {
        let roster = world.resource::<Roster>().clone();
        let env = world.get_resource::<Env>();
        roster
            .bodies
            .iter()
            .map(|e| {
                let s = world.get::<BodyState>(*e).expect("roster body");
                let g = env.map_or_else(Vector3::zeros, |env| env.accel_m_s2(&s.pos_m));
                BodyObs::new(s.pos_m, s.vel_m_s, s.att, s.omega_rad_s, g)
            })
            .collect()
    };
    let mut shared = BTreeMap::new();
    for (i, spec) in scene.controllers.iter().enumerate() {
        let path = format!("controllers.{i}");
        let locate = |e: BuildError| {
            let p = if e.absolute {
                e.field.clone()
            } else if e.field.is_empty() {
                path.clone()
            } else {
                format!("{path}.{}", e.field)
            };
            loaded.error_at(&p, e.message)
        };
        let built = {
            let env = env_of_world(world);
            let mut ctx = BuildContext::new(scene, i, &info, &initial, &env, &mut shared);
            spec.build(&mut ctx).map_err(locate)?
        };
        for slot in built.slots {
            host_slot(world, slot).map_err(|m| loaded.error_at(&path, m))?;
        }
        world
            .resource_mut::<ControllerHost>()
            .disturbances
            .extend(built.disturbances);
    }
    Ok(())
}
