//! The extension points of the control layer: what a law implements and what it is given.
//! A paper law implements [`LawSpec`] (it reads its whole scene entry and builds its
//! [`Slot`]s and [`Disturbance`]s from a [`BuildContext`]); a generic law implements
//! [`LawParams`] (rpod resolves the entry's body, target, period, sensor and actuator into a
//! [`LawContext`]); errors are [`BuildError`]s located at a field of the entry. Bevy-free.
//!
//! The list of built-in laws and the lookup by name are in
//! [`registry`](crate::control::registry), which depends on this module and on the laws; the
//! laws depend on this module only. (The by-name deserialization of [`ControllerSpec`] and
//! [`LawParamsSpec`] is implemented there, next to the lookup it needs.)

use crate::actuation::ActuatorSpec;
use crate::control::interface::{AsAny, BodyInfo, BodyObs, Controller};
use crate::control::sensor::SensorSpec;
use crate::environment::EnvObs;
use crate::geometry::drawn::DrawnSurface;
use crate::scene::Scene;
use std::any::Any;
use std::collections::BTreeMap;
use std::fmt;

/// A scene error raised while building a law: the field path and the message.
#[derive(Debug, Clone, PartialEq)]
pub struct BuildError {
    /// Field path, relative to the controller's entry (`body`, `params.kp_per_s2`, `0.chaser`)
    /// unless `absolute`.
    pub field: String,
    /// The path is from the scene's root (e.g. `environment`).
    pub absolute: bool,
    /// What is wrong.
    pub message: String,
}

impl BuildError {
    /// An error at `field` of the controller's entry.
    pub fn at(field: impl Into<String>, message: impl Into<String>) -> Self {
        Self {
            field: field.into(),
            absolute: false,
            message: message.into(),
        }
    }
    /// An error at a path from the scene's root.
    pub fn at_root(path: impl Into<String>, message: impl Into<String>) -> Self {
        Self {
            field: path.into(),
            absolute: true,
            message: message.into(),
        }
    }
    /// The same error with `prefix.` in front of a relative field.
    pub fn within(mut self, prefix: &str) -> Self {
        if !self.absolute && !prefix.is_empty() {
            self.field = if self.field.is_empty() {
                prefix.to_string()
            } else {
                format!("{prefix}.{}", self.field)
            };
        }
        self
    }
}

impl fmt::Display for BuildError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "field `{}`: {}", self.field, self.message)
    }
}

/// A disturbance a law's scenario applies (a paper's disturbance torque, a target's
/// manoeuvre): world-frame forces and torques on bodies, every step, in the Actuate stage after
/// the controllers' commands.
pub trait Disturbance: AsAny + Send + Sync {
    /// Appends the wrenches of this step to `out` (added in that order).
    fn wrenches(&mut self, ctx: &DisturbanceContext, out: &mut Vec<BodyWrench>);
}

/// What a disturbance may read.
#[derive(Debug, Clone, Copy)]
pub struct DisturbanceContext<'a> {
    /// Time at the start of the step, s.
    pub t_s: f64,
    /// Scene step, s.
    pub dt_s: f64,
    /// Completed steps.
    pub step: u64,
    /// Bodies' constants.
    pub info: &'a [BodyInfo],
    /// Bodies' truth at the start of the step.
    pub bodies: &'a [BodyObs],
    /// The environment.
    pub env: &'a EnvObs,
}

/// A force through a body's centre of mass and/or a torque, world frame. A part that is `None`
/// is not added at all (adding a zero would still change a −0.0 in the sum, and runs are
/// bit-exact).
#[derive(Debug, Clone, Copy)]
pub struct BodyWrench {
    /// Body index.
    pub body: usize,
    /// Force, N.
    pub force_n: Option<nalgebra::Vector3<f64>>,
    /// Torque, N·m.
    pub torque_nm: Option<nalgebra::Vector3<f64>>,
}

/// One controller as the host runs it: which body, how often, through which sensor and
/// actuator, and the law.
pub struct Slot {
    /// Registered kind (the scene's name for it, or e.g. `python`).
    pub kind: String,
    /// Controlled body (index in scene order).
    pub body: usize,
    /// Target (observations relative to it, `Hill`/`TargetBody` command frames).
    pub target: Option<usize>,
    /// Steps between calls (≥ 1; the first call at t = 0).
    pub period_steps: u64,
    /// A sensor whose measurements the observation carries.
    pub sensor: Option<SensorSpec>,
    /// What the command passes through.
    pub actuator: ActuatorSpec,
    /// Ports for the observation: (controlled body's port, target's port). Default: those of
    /// the scene's docking mechanism when it joins this body and its target.
    pub ports: Option<(String, String)>,
    /// The law.
    pub law: Box<dyn Controller>,
}

impl fmt::Debug for Slot {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("Slot")
            .field("kind", &self.kind)
            .field("body", &self.body)
            .field("target", &self.target)
            .field("period_steps", &self.period_steps)
            .field("sensor", &self.sensor)
            .field("actuator", &self.actuator)
            .field("ports", &self.ports)
            .finish_non_exhaustive()
    }
}

/// What one entry of a scene's `controllers` list builds.
#[derive(Default)]
pub struct Built {
    /// Controllers (usually one).
    pub slots: Vec<Slot>,
    /// The scenario's disturbances.
    pub disturbances: Vec<Box<dyn Disturbance>>,
}

/// What a law sees of the scene while it is built (at t = 0).
pub struct BuildContext<'a> {
    /// The scene.
    pub scene: &'a crate::scene::Scene,
    /// Index of the entry in `controllers`.
    pub index: usize,
    /// Bodies' constants, scene order.
    pub info: &'a [BodyInfo],
    /// Bodies' initial truth.
    pub initial: &'a [BodyObs],
    /// The environment at t = 0.
    pub env: &'a EnvObs,
    shared: &'a mut BTreeMap<String, Box<dyn Any + Send + Sync>>,
}

impl<'a> BuildContext<'a> {
    /// A context (the host builds one per entry; `shared` persists across the entries of one
    /// scene).
    pub fn new(
        scene: &'a crate::scene::Scene,
        index: usize,
        info: &'a [BodyInfo],
        initial: &'a [BodyObs],
        env: &'a EnvObs,
        shared: &'a mut BTreeMap<String, Box<dyn Any + Send + Sync>>,
    ) -> Self {
        Self {
            scene,
            index,
            info,
            initial,
            env,
            shared,
        }
    }
    /// Scene step, s.
    pub fn dt_s(&self) -> f64 {
        self.scene.dt_s
    }
    /// Index of a body by name, or an error at `field`.
    pub fn body(&self, field: &str, name: &str) -> Result<usize, BuildError> {
        self.info
            .iter()
            .position(|b| b.name == name)
            .ok_or_else(|| BuildError::at(field, format!("no body named `{name}`")))
    }
    /// A controller period as a whole number of steps (≥ 1), or an error at `field`.
    pub fn period_steps(&self, field: &str, period_s: f64) -> Result<u64, BuildError> {
        let dt = self.scene.dt_s;
        let ratio = period_s / dt;
        let n = ratio.round();
        if !period_s.is_finite() || !(1.0..=1e12).contains(&n) || (ratio - n).abs() > 1e-9 * ratio {
            return Err(BuildError::at(
                field,
                format!(
                    "the period must be a whole number (≥ 1) of scene steps dt_s = {dt} s, got {period_s:?} s"
                ),
            ));
        }
        Ok(n as u64)
    }
    /// State a law kind keeps across its entries in one scene (e.g. a count of instances, a
    /// shared parameter that must agree), created on first use.
    pub fn shared<T: Default + Any + Send + Sync>(&mut self, key: &str) -> &mut T {
        let e = self
            .shared
            .entry(key.to_string())
            .or_insert_with(|| Box::new(T::default()));
        if !e.is::<T>() {
            *e = Box::new(T::default());
        }
        e.downcast_mut::<T>().expect("type checked above")
    }
}

/// A law that reads its own scene entry and builds its slots (the paper laws' form).
pub trait LawSpec: LawSpecClone + AsAny + fmt::Debug + Send + Sync {
    /// The controllers (and disturbances) of this entry.
    fn build(&self, ctx: &mut BuildContext) -> Result<Built, BuildError>;
    /// The constraint surfaces a viewer should draw for this entry (none by default): the
    /// geometry the law itself uses, in f64 ([`DrawnSurface`]).
    fn drawn(&self, _scene: &Scene) -> Vec<DrawnSurface> {
        Vec::new()
    }
}

/// Cloning boxed specs (implemented for every `LawSpec + Clone`).
pub trait LawSpecClone {
    /// A boxed copy.
    fn clone_box(&self) -> Box<dyn LawSpec>;
}

impl<T: LawSpec + Clone + 'static> LawSpecClone for T {
    fn clone_box(&self) -> Box<dyn LawSpec> {
        Box::new(self.clone())
    }
}

/// What a law written against [`register_law`](crate::control::registry::register_law) gets when it is built.
pub struct LawContext<'b, 'a> {
    /// The scene-wide context.
    pub build: &'b mut BuildContext<'a>,
    /// The controlled body.
    pub body: usize,
    /// The target, if the entry names one.
    pub target: Option<usize>,
    /// Steps between calls.
    pub period_steps: u64,
    /// Ports, if the entry names them (or the docking mechanism's).
    pub ports: Option<(String, String)>,
    /// The entry's sensor, if any: a law that reads the relative state flies on its
    /// measurements, and a law that cannot use it refuses it ([`LawContext::no_sensor`]).
    pub sensor: Option<SensorSpec>,
}

impl LawContext<'_, '_> {
    /// The controller period, s.
    pub fn period_s(&self) -> f64 {
        self.period_steps as f64 * self.build.dt_s()
    }
    /// The controlled body's constants.
    pub fn own(&self) -> &BodyInfo {
        &self.build.info[self.body]
    }
    /// The error of a law `kind` that cannot use the entry's sensor (at the entry's `sensor`
    /// field), or `Ok` without one: a configured sensor is never silently ignored.
    pub fn no_sensor(&self, kind: &str, why: &str) -> Result<(), BuildError> {
        match &self.sensor {
            Some(_) => Err(BuildError::at_root(
                format!("controllers.{}.sensor", self.build.index),
                format!("`{kind}` cannot use a sensor: {why}"),
            )),
            None => Ok(()),
        }
    }
}

/// The parameters of a law registered with [`register_law`](crate::control::registry::register_law): they build the controller.
/// Errors name fields relative to `params`.
pub trait LawParams: LawParamsClone + AsAny + fmt::Debug + Send + Sync {
    /// The controller, from its validated parameters.
    fn build(&self, ctx: &mut LawContext) -> Result<Box<dyn Controller>, BuildError>;
    /// What the law's command carries. A `Sequencer` refuses a law in a slot it cannot fill
    /// (a torque-only law as a phase's `translation`, a force-only law as its `attitude`);
    /// for a law that declares both (the default), the part its slot does not use is dropped
    /// and a `sequencer_dropped` event says so the first time it is non-zero in a phase.
    fn commands(&self) -> Commands {
        Commands::ForceAndTorque
    }
    /// The constraint surfaces a viewer should draw for this law flying `body` (scene index)
    /// toward `target` (none by default): the geometry the law itself uses ([`DrawnSurface`]).
    fn drawn(&self, _scene: &Scene, _body: usize, _target: Option<usize>) -> Vec<DrawnSurface> {
        Vec::new()
    }
}

/// What a law's [`Command`](crate::control::interface::Command) carries (see
/// [`LawParams::commands`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Commands {
    /// A force only (its torque is always zero).
    Force,
    /// A torque only (its force is always zero).
    Torque,
    /// Either or both (or valve states).
    ForceAndTorque,
}

/// Cloning boxed parameters (implemented for every `LawParams + Clone`).
pub trait LawParamsClone {
    /// A boxed copy.
    fn clone_box(&self) -> Box<dyn LawParams>;
}

impl<T: LawParams + Clone + 'static> LawParamsClone for T {
    fn clone_box(&self) -> Box<dyn LawParams> {
        Box::new(self.clone())
    }
}

/// The rpod-side fields of a [`register_law`](crate::control::registry::register_law) entry; `params` is the law's.
#[derive(Debug)]
pub struct LawEntry {
    /// Controlled body.
    pub body: String,
    /// Target body.
    pub target: Option<String>,
    /// Controller period, s (default: the scene step).
    pub period_s: Option<f64>,
    /// Sensor.
    pub sensor: Option<SensorSpec>,
    /// Actuator (default `Ideal`).
    pub actuator: ActuatorSpec,
    /// The controlled body's port.
    pub port: Option<String>,
    /// The target's port.
    pub target_port: Option<String>,
    /// The law's parameters.
    pub params: Box<dyn LawParams>,
}

impl Clone for LawEntry {
    fn clone(&self) -> Self {
        Self {
            body: self.body.clone(),
            target: self.target.clone(),
            period_s: self.period_s,
            sensor: self.sensor.clone(),
            actuator: self.actuator.clone(),
            port: self.port.clone(),
            target_port: self.target_port.clone(),
            params: self.params.clone_box(),
        }
    }
}

impl LawEntry {
    /// Resolves the entry into a slot of kind `kind`.
    pub fn build(&self, kind: &str, ctx: &mut BuildContext) -> Result<Built, BuildError> {
        let body = ctx.body("body", &self.body)?;
        let target = match &self.target {
            Some(t) => {
                let i = ctx.body("target", t)?;
                if i == body {
                    return Err(BuildError::at(
                        "target",
                        "the target must be another body than the controlled one",
                    ));
                }
                Some(i)
            }
            None => None,
        };
        let period_steps = match self.period_s {
            Some(p) => ctx.period_steps("period_s", p)?,
            None => 1,
        };
        if let Some(s) = &self.sensor {
            s.validate()
                .and_then(|_| s.check_period(ctx.scene.dt_s))
                .map_err(|(f, m)| BuildError::at(format!("sensor.{f}"), m))?;
            if s.frame != crate::control::interface::MeasuredFrame::World && target.is_none() {
                return Err(BuildError::at(
                    "sensor.frame",
                    "a relative measurement needs the entry's `target`",
                ));
            }
        }
        self.actuator
            .validate()
            .map_err(|(f, m)| BuildError::at(format!("actuator.{f}"), m))?;
        let ports = match (&self.port, &self.target_port) {
            (None, None) => default_ports(ctx, body, target),
            (Some(p), Some(q)) => {
                let Some(t) = target else {
                    return Err(BuildError::at(
                        "target_port",
                        "ports need the entry's `target`",
                    ));
                };
                if ctx.info[body].port(p).is_none() {
                    return Err(BuildError::at(
                        "port",
                        format!("body `{}` has no port `{p}`", ctx.info[body].name),
                    ));
                }
                if ctx.info[t].port(q).is_none() {
                    return Err(BuildError::at(
                        "target_port",
                        format!("body `{}` has no port `{q}`", ctx.info[t].name),
                    ));
                }
                Some((p.clone(), q.clone()))
            }
            (Some(_), None) => {
                return Err(BuildError::at("port", "give `target_port` with `port`"));
            }
            (None, Some(_)) => {
                return Err(BuildError::at(
                    "target_port",
                    "give `port` with `target_port`",
                ));
            }
        };
        if let (ActuatorSpec::PlanarThrusters { .. }, false) =
            (&self.actuator, matches!(ctx.env, EnvObs::AirBearing { .. }))
        {
            return Err(BuildError::at(
                "actuator",
                "`PlanarThrusters` fly a simulator on an air-bearing table: use `AirBearing((...))`",
            ));
        }
        let law = {
            let mut lc = LawContext {
                build: ctx,
                body,
                target,
                period_steps,
                ports: ports.clone(),
                sensor: self.sensor.clone(),
            };
            self.params.build(&mut lc).map_err(|e| e.within("params"))?
        };
        Ok(Built {
            slots: vec![Slot {
                kind: kind.to_string(),
                body,
                target,
                period_steps,
                sensor: self.sensor.clone(),
                actuator: self.actuator.clone(),
                ports,
                law,
            }],
            disturbances: Vec::new(),
        })
    }
}

/// The ports of the scene's docking mechanism when it joins `body` (chaser) and `target`.
pub fn default_ports(
    ctx: &BuildContext,
    body: usize,
    target: Option<usize>,
) -> Option<(String, String)> {
    let d = ctx.scene.docking.as_ref()?;
    let t = target?;
    (ctx.info[body].name == d.chaser && ctx.info[t].name == d.target)
        .then(|| (d.chaser_port.clone(), d.target_port.clone()))
}

/// One entry of a scene's `controllers` list: the registered name and what it read.
pub struct ControllerSpec {
    /// The registered name (`Guo2016`, `HillPd`, a user's).
    pub kind: String,
    /// The entry.
    pub body: ControllerBody,
}

/// The content of a [`ControllerSpec`].
pub enum ControllerBody {
    /// A law that reads its whole entry.
    Spec(Box<dyn LawSpec>),
    /// A [`register_law`](crate::control::registry::register_law) entry.
    Law(Box<LawEntry>),
}

impl Clone for ControllerSpec {
    fn clone(&self) -> Self {
        Self {
            kind: self.kind.clone(),
            body: match &self.body {
                ControllerBody::Spec(s) => ControllerBody::Spec(s.clone_box()),
                ControllerBody::Law(l) => ControllerBody::Law(l.clone()),
            },
        }
    }
}

impl fmt::Debug for ControllerSpec {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match &self.body {
            ControllerBody::Spec(s) => write!(f, "{}({s:?})", self.kind),
            ControllerBody::Law(l) => write!(f, "{}({l:?})", self.kind),
        }
    }
}

impl ControllerSpec {
    /// The entry as the spec type `S` of a [`register_spec`](crate::control::registry::register_spec) law (e.g. a paper law's
    /// `Guo2016Spec`), if it is one.
    pub fn spec<S: 'static>(&self) -> Option<&S> {
        match &self.body {
            ControllerBody::Spec(s) => (**s).as_any().downcast_ref::<S>(),
            ControllerBody::Law(_) => None,
        }
    }
    /// The entry as the spec type `S`, mutably (to change a loaded scene before a run).
    pub fn spec_mut<S: 'static>(&mut self) -> Option<&mut S> {
        match &mut self.body {
            ControllerBody::Spec(s) => (**s).as_any_mut().downcast_mut::<S>(),
            ControllerBody::Law(_) => None,
        }
    }
    /// The parameters as `P` of a [`register_law`](crate::control::registry::register_law) law, if they are.
    pub fn params<P: 'static>(&self) -> Option<&P> {
        match &self.body {
            ControllerBody::Law(l) => (*l.params).as_any().downcast_ref::<P>(),
            ControllerBody::Spec(_) => None,
        }
    }
    /// The constraint surfaces the entry's law asks a viewer to draw (its `drawn` hook; none
    /// for a `register_law` entry whose body is not in the scene).
    pub fn drawn(&self, scene: &Scene) -> Vec<DrawnSurface> {
        match &self.body {
            ControllerBody::Spec(s) => s.drawn(scene),
            ControllerBody::Law(l) => {
                let index = |n: &str| scene.bodies.iter().position(|b| b.name == n);
                match index(&l.body) {
                    Some(body) => {
                        let target = l.target.as_deref().and_then(index);
                        l.params.drawn(scene, body, target)
                    }
                    None => Vec::new(),
                }
            }
        }
    }
    /// Builds the entry's slots.
    pub fn build(&self, ctx: &mut BuildContext) -> Result<Built, BuildError> {
        match &self.body {
            ControllerBody::Spec(s) => s.build(ctx),
            ControllerBody::Law(l) => l.build(&self.kind, ctx),
        }
    }
}

/// A law registered with [`register_law`](crate::control::registry::register_law) written by its parameters only, `Name((…))` —
/// how a [`crate::control::generic::sequencer`] phase names the laws it flies (they share the
/// sequencer entry's body, target, period, sensor and actuator).
pub struct LawParamsSpec {
    /// The registered name.
    pub kind: String,
    /// The parameters.
    pub params: Box<dyn LawParams>,
}

impl Clone for LawParamsSpec {
    fn clone(&self) -> Self {
        Self {
            kind: self.kind.clone(),
            params: self.params.clone_box(),
        }
    }
}

impl fmt::Debug for LawParamsSpec {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}({:?})", self.kind, self.params)
    }
}
