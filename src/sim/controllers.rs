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
//!   ([`DiagnosticsAt::PostStep`]) for the laws that ask for them.
//!
//! Entries of the scene's `controllers` list are built in scene order by [`install`]; more
//! can be added to a built [`crate::sim::Simulation`] with `add_controller` before recording
//! starts.

use super::output::Diagnostics;
use super::{BodyState, Clock, EventLog, Guarantees, OrbitEnv, Roster, Wrench};
use crate::actuation::Actuator;
use crate::actuation::actuator::CommandFrames;
use crate::control::interface::{
    ActuationReport, BodyInfo, BodyObs, Command, Controller, DiagnosticsAt, DockingObs,
    GuaranteeObs, MeasuredFrame, Measurement, Observation, PortsObs, port_pose, ports_obs,
    relative_obs,
};
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
    /// The latest delivered measurement.
    pub measured: Option<Measurement>,
    /// Diagnostics column indices.
    cols: Vec<usize>,
    /// Scratch for the law's diagnostics.
    buf: Vec<f64>,
    /// When the law wants diagnostics.
    at: &'static [DiagnosticsAt],
    /// A command frame was missing (reported once).
    frame_warned: bool,
}

/// Every controller of the simulation and the scenario's disturbances.
#[derive(Resource, Default)]
pub struct ControllerHost {
    /// Controllers, in installation order.
    pub slots: Vec<HostedSlot>,
    /// Disturbances, in installation order.
    pub disturbances: Vec<Box<dyn Disturbance>>,
    /// Bodies' constants.
    pub info: Vec<BodyInfo>,
    /// Bodies' truth at the start of the current step (refreshed in Sense).
    pub truth: Vec<BodyObs>,
    guarantees: Vec<GuaranteeObs>,
    planar: bool,
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
                    serde_json::json!({
                        "kind": s.kind,
                        "body": name(s.body),
                        "target": s.target.and_then(name),
                        "period_steps": s.period_steps,
                        "calls": s.calls,
                        "delta_v_m_s": s.actuator.delta_v_m_s,
                        "propellant_used_kg": s.actuator.propellant_used_kg,
                    })
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

/// The environment as controllers see it, from the app's resources.
pub fn env_of_world(world: &World) -> EnvObs<'_> {
    if let Some(f) = world.get_resource::<super::environment::L2Frame>() {
        return EnvObs::SunEarthL2 { centre: &f.0 };
    }
    env_from(
        world.get_resource::<OrbitEnv>(),
        world.get_resource::<super::airbearing::AirBearing>(),
    )
}

fn env_from(
    orbit: Option<&OrbitEnv>,
    airbearing: Option<&super::airbearing::AirBearing>,
) -> EnvObs<'static> {
    match (orbit, airbearing) {
        (Some(o), _) => {
            let (r, v) = o.reference.state();
            EnvObs::Orbit {
                r_ref_eci_m: r,
                v_ref_eci_m_s: v,
                j2: o.j2,
            }
        }
        (None, Some(a)) => EnvObs::AirBearing {
            gravity_lab_m_s2: a.gravity_lab_m_s2,
        },
        _ => EnvObs::FreeSpace,
    }
}

/// The environment resources a host system reads.
#[derive(bevy::ecs::system::SystemParam)]
pub struct EnvRefs<'w> {
    orbit: Option<Res<'w, OrbitEnv>>,
    l2: Option<Res<'w, super::environment::L2Frame>>,
    airbearing: Option<Res<'w, super::airbearing::AirBearing>>,
    gravity: Option<Res<'w, super::Gravity>>,
    docking: Option<Res<'w, super::docking::Docking>>,
}

impl EnvRefs<'_> {
    fn env(&self) -> EnvObs<'_> {
        if let Some(f) = &self.l2 {
            return EnvObs::SunEarthL2 { centre: &f.0 };
        }
        env_from(self.orbit.as_deref(), self.airbearing.as_deref())
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

/// Refreshes `truth` from the bodies' f64 states.
fn refresh_truth(
    truth: &mut Vec<BodyObs>,
    roster: &Roster,
    states: &Query<&BodyState>,
    gravity: Option<&super::Gravity>,
) {
    truth.clear();
    for e in &roster.bodies {
        let s = states.get(*e).expect("roster body");
        let g = gravity.map_or_else(Vector3::zeros, |g| g.0.accel_m_s2(&s.pos_m));
        truth.push(BodyObs::new(s.pos_m, s.vel_m_s, s.att, s.omega_rad_s, g));
    }
}

/// The observation of one slot.
#[allow(clippy::too_many_arguments)]
fn observation<'a>(
    slot: &HostedSlot,
    clock: &Clock,
    info: &'a [BodyInfo],
    truth: &'a [BodyObs],
    env: EnvObs<'a>,
    docking: Option<DockingObs>,
    guarantees: &'a [GuaranteeObs],
) -> Observation<'a> {
    let relative = slot
        .target
        .map(|t| relative_obs(&truth[slot.body], &truth[t], env.reference()));
    let ports = match (slot.ports, slot.target) {
        (Some((pc, pt)), Some(t)) => Some(ports_of(info, truth, slot.body, t, &pc, &pt)),
        _ => None,
    };
    Observation {
        t_s: clock.t_s(),
        step: clock.step,
        dt_s: clock.dt_s,
        body: slot.body,
        target: slot.target,
        info,
        bodies: truth,
        env,
        relative,
        ports,
        measured: slot.measured,
        docking,
        guarantees,
    }
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
) {
    if host.slots.is_empty() && host.disturbances.is_empty() {
        return;
    }
    let host = &mut *host;
    refresh_truth(&mut host.truth, &roster, &states, refs.gravity.as_deref());
    let env = refs.env();
    let t = clock.t_s();
    for k in 0..host.slots.len() {
        let Some(frame) = host.slots[k].sensor.as_ref().map(|s| s.spec.frame) else {
            continue;
        };
        let truth = sensor_truth(frame, &host.slots[k], &host.info, &host.truth, &env);
        let slot = &mut host.slots[k];
        if let (Some(truth), Some(sensor)) = (truth, slot.sensor.as_mut()) {
            slot.measured = sensor.step(t, clock.dt_s, &truth);
        }
    }
}

/// Control: each law at its period; the command is held.
pub fn host_control(
    clock: Res<Clock>,
    refs: EnvRefs,
    guarantees: Res<Guarantees>,
    mut host: ResMut<ControllerHost>,
    mut log: ResMut<EventLog>,
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
    let env = refs.env();
    let docking = refs.docking();
    let t = clock.t_s();
    for slot in host.slots.iter_mut() {
        if !clock.step.is_multiple_of(slot.period_steps) {
            continue;
        }
        let obs = observation(
            slot,
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
            log.push(t, &e.kind, e.data);
        }
    }
}

/// Actuate: held commands through the actuators into the wrenches; disturbances; diagnostics.
#[allow(clippy::too_many_arguments)] // a Bevy system: one parameter per resource it reads
pub fn host_actuate(
    clock: Res<Clock>,
    roster: Res<Roster>,
    refs: EnvRefs,
    mut wrenches: Query<&mut Wrench>,
    mut host: ResMut<ControllerHost>,
    mut diag: ResMut<Diagnostics>,
    mut log: ResMut<EventLog>,
) {
    if host.slots.is_empty() && host.disturbances.is_empty() {
        return;
    }
    let host = &mut *host;
    let env = refs.env();
    let reference_hill = env.reference().map(|(r, v)| {
        LocalFrame::new(LocalFrameKind::Hill, &r, &v)
            .dcm_frame_from_eci
            .transpose()
    });
    let dt = clock.dt_s;
    for slot in host.slots.iter_mut() {
        let own = &host.truth[slot.body];
        let hill = match slot.target {
            Some(t) => env.reference().map(|(r, v)| {
                LocalFrame::new(
                    LocalFrameKind::Hill,
                    &(r + host.truth[t].pos_m),
                    &(v + host.truth[t].vel_m_s),
                )
                .dcm_frame_from_eci
                .transpose()
            }),
            None => reference_hill,
        };
        let frames = CommandFrames {
            body: own.att,
            hill,
            target_body: slot.target.map(|t| host.truth[t].att),
        };
        let mass = host.info[slot.body].mass_kg;
        match slot.actuator.step(&slot.held, &frames, mass, dt) {
            Some(r) => slot.report = r,
            None => {
                slot.report = ActuationReport::default();
                if !slot.frame_warned {
                    slot.frame_warned = true;
                    log.push(
                        clock.t_s(),
                        "controller_frame_unavailable",
                        serde_json::json!({"body": host.info[slot.body].name, "kind": slot.kind,
                            "reason": "the command's frame does not exist in this scene (Hill needs an orbit, TargetBody a target): nothing applied"}),
                    );
                }
                continue;
            }
        }
        if let Ok(mut w) = wrenches.get_mut(roster.bodies[slot.body]) {
            let (f, t) = (slot.report.force_world_n, slot.report.torque_world_nm);
            if host.planar {
                w.force_n.x += f.x;
                w.force_n.y += f.y;
                w.torque_nm.z += t.z;
            } else {
                w.force_n += f;
                w.torque_nm += t;
            }
        }
    }
    if !host.disturbances.is_empty() {
        let ctx = DisturbanceContext {
            t_s: clock.t_s(),
            dt_s: dt,
            step: clock.step,
            info: &host.info,
            bodies: &host.truth,
            env,
        };
        for d in host.disturbances.iter_mut() {
            for bw in d.wrenches(&ctx) {
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
    let docking = refs.docking();
    write_diagnostics(
        host,
        DiagnosticsAt::Actuated,
        &clock,
        env,
        docking,
        &mut diag,
    );
}

/// Writes the diagnostics of every slot that wants them at `at`.
fn write_diagnostics(
    host: &mut ControllerHost,
    at: DiagnosticsAt,
    clock: &Clock,
    env: EnvObs,
    docking: Option<DockingObs>,
    diag: &mut Diagnostics,
) {
    for slot in host.slots.iter_mut() {
        if slot.cols.is_empty() || !slot.at.contains(&at) {
            continue;
        }
        let obs = observation(
            slot,
            clock,
            &host.info,
            &host.truth,
            env,
            docking,
            &host.guarantees,
        );
        for (b, c) in slot.buf.iter_mut().zip(&slot.cols) {
            *b = diag.values[*c];
        }
        slot.law.diagnostics(at, &obs, &slot.report, &mut slot.buf);
        for (b, c) in slot.buf.iter().zip(&slot.cols) {
            diag.values[*c] = *b;
        }
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
    if !host
        .slots
        .iter()
        .any(|s| !s.cols.is_empty() && s.at.contains(&DiagnosticsAt::PostStep))
    {
        return;
    }
    let host = &mut *host;
    refresh_truth(&mut host.truth, &roster, &states, refs.gravity.as_deref());
    let env = refs.env();
    let docking = refs.docking();
    write_diagnostics(
        host,
        DiagnosticsAt::PostStep,
        &clock,
        env,
        docking,
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
    let cols = {
        let mut diag = world.resource_mut::<Diagnostics>();
        let mut cols = Vec::with_capacity(names.len());
        for n in &names {
            if diag.names.iter().any(|m| m == n) {
                return Err(format!(
                    "controller `{kind}`: column `{n}` is already written by another controller or mechanism"
                ));
            }
            cols.push(diag.column(n));
        }
        cols
    };
    {
        let mut g = world.resource_mut::<Guarantees>();
        for gu in law.guarantees() {
            g.register(gu);
        }
    }
    let at = law.diagnostics_at();
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
        buf: vec![f64::NAN; cols.len()],
        cols,
        at,
        frame_warned: false,
    };
    // The t = 0 row: diagnostics of the initial state.
    if !slot.cols.is_empty() && slot.at.contains(&DiagnosticsAt::Start) {
        world.resource_scope(|world, mut host: Mut<ControllerHost>| {
            let clock = world.resource::<Clock>().clone();
            let roster = world.resource::<Roster>().clone();
            let gravity = world.get_resource::<super::Gravity>();
            let mut truth = Vec::new();
            for e in &roster.bodies {
                let s = world.get::<BodyState>(*e).expect("roster body");
                let g = gravity.map_or_else(Vector3::zeros, |g| g.0.accel_m_s2(&s.pos_m));
                truth.push(BodyObs::new(s.pos_m, s.vel_m_s, s.att, s.omega_rad_s, g));
            }
            let env = env_of_world(world);
            let guarantees: Vec<GuaranteeObs> = Vec::new();
            let obs = observation(&slot, &clock, &host.info, &truth, env, None, &guarantees);
            slot.law
                .diagnostics(DiagnosticsAt::Start, &obs, &slot.report, &mut slot.buf);
            let mut diag = world.resource_mut::<Diagnostics>();
            for (b, c) in slot.buf.iter().zip(&slot.cols) {
                diag.values[*c] = *b;
            }
            host.truth = truth;
        });
    }
    let mut host = world.resource_mut::<ControllerHost>();
    host.slots.push(slot);
    Ok(host.slots.len() - 1)
}

/// Builds and hosts the scene's `controllers`, in scene order. Called after the pipeline,
/// the docking mechanism and the environment exist, before t = 0 is monitored.
pub fn install(app: &mut App, loaded: &LoadedScene) -> Result<(), SceneError> {
    let scene = &loaded.scene;
    let info = body_info(scene);
    let planar = matches!(scene.environment, crate::scene::Environment::AirBearing(_));
    app.insert_resource(ControllerHost {
        info: info.clone(),
        planar,
        ..Default::default()
    });
    add_systems(app);
    let world = app.world_mut();
    let initial: Vec<BodyObs> = {
        let roster = world.resource::<Roster>().clone();
        let gravity = world.get_resource::<super::Gravity>();
        roster
            .bodies
            .iter()
            .map(|e| {
                let s = world.get::<BodyState>(*e).expect("roster body");
                let g = gravity.map_or_else(Vector3::zeros, |g| g.0.accel_m_s2(&s.pos_m));
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
            let mut ctx = BuildContext::new(scene, i, &info, &initial, env, &mut shared);
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

/// The host's systems, in their stages. Added by [`install`], after the docking mechanism's
/// and the environment's systems, so that within a stage a controller's force is added after
/// theirs (the order of floating-point sums is part of a run's bit-exact result).
fn add_systems(app: &mut App) {
    use super::{SimStep, Stage};
    app.add_systems(
        SimStep,
        (
            host_sense.in_set(Stage::Sense),
            host_control.in_set(Stage::Control),
            host_actuate.in_set(Stage::Actuate),
            host_post_step.in_set(Stage::Monitor),
        ),
    );
}
