//! Open registration of control laws: a scene's `controllers` list names laws by their
//! registered name, and anyone — this crate for its paper and generic laws, a user's crate for
//! theirs — registers a name with the type that reads its parameters. There is no central
//! match to edit: adding a law is its file plus one [`register_law`] (or [`register_spec`])
//! call. Bevy-free.
//!
//! # Two ways to register
//! - [`register_law::<P>("Name")`](register_law) — the usual way. The scene writes
//!   ```ron
//!   Name(body: "chaser", target: "target", period_s: 0.1,
//!        sensor: Some((period_s: 0.1, position_noise_m: 0.01)),   // optional
//!        actuator: Saturated(max_force_n: (2.0, 2.0, 2.0), max_torque_nm: (0.1, 0.1, 0.1)),
//!        port: "dock", target_port: "dock",                        // optional
//!        params: ( /* the fields of P */ ))
//!   ```
//!   and rpod resolves and validates everything but `params` (see [`LawEntry`]); `P` turns its
//!   parameters into a [`Controller`] ([`LawParams::build`]).
//! - [`register_spec::<S>("Name")`](register_spec) — for a law that reads its own entry
//!   (`Name((...))`: the five paper laws keep the scene format of their reproductions) and
//!   builds its slots itself ([`LawSpec::build`]).
//!
//! Unknown names, parameters of the wrong type and values a law rejects are located scene
//! errors (file:line:col, field). Registration is process-wide (a `RwLock`ed map): register
//! before loading the scenes that use the name.

use crate::actuation::ActuatorSpec;
use crate::control::interface::{AsAny, BodyInfo, BodyObs, Controller};
use crate::control::sensor::SensorSpec;
use crate::environment::EnvObs;
use serde::de::{self, DeserializeSeed, EnumAccess, MapAccess, VariantAccess, Visitor};
use serde::{Deserialize, Deserializer};
use std::any::Any;
use std::collections::BTreeMap;
use std::fmt;
use std::sync::{LazyLock, RwLock};

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
    pub env: EnvObs<'a>,
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
    pub env: EnvObs<'a>,
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
        env: EnvObs<'a>,
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

/// What a law written against [`register_law`] gets when it is built.
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

/// The parameters of a law registered with [`register_law`]: they build the controller.
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

/// The rpod-side fields of a [`register_law`] entry; `params` is the law's.
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

type SpecFn =
    fn(&mut dyn erased_serde::Deserializer) -> Result<Box<dyn LawSpec>, erased_serde::Error>;
type ParamsFn =
    fn(&mut dyn erased_serde::Deserializer) -> Result<Box<dyn LawParams>, erased_serde::Error>;

#[derive(Clone, Copy)]
enum Entry {
    Spec(SpecFn),
    Law(ParamsFn),
}

fn de_spec<S: LawSpec + for<'de> Deserialize<'de> + 'static>(
    d: &mut dyn erased_serde::Deserializer,
) -> Result<Box<dyn LawSpec>, erased_serde::Error> {
    Ok(Box::new(erased_serde::deserialize::<S>(d)?))
}

fn de_params<P: LawParams + for<'de> Deserialize<'de> + 'static>(
    d: &mut dyn erased_serde::Deserializer,
) -> Result<Box<dyn LawParams>, erased_serde::Error> {
    Ok(Box::new(erased_serde::deserialize::<P>(d)?))
}

static REGISTRY: LazyLock<RwLock<BTreeMap<String, Entry>>> = LazyLock::new(|| {
    let mut m = BTreeMap::new();
    for (name, e) in builtin() {
        m.insert(name.to_string(), e);
    }
    RwLock::new(m)
});

/// The laws this crate registers: one line per law.
fn builtin() -> Vec<(&'static str, Entry)> {
    use crate::control::{generic, geng2015, guo2016, xu2015, xu2019, zhang2018};
    vec![
        ("Guo2016", Entry::Spec(de_spec::<guo2016::SceneSpec>)),
        ("Geng2015", Entry::Spec(de_spec::<geng2015::SceneSpec>)),
        ("Xu2015", Entry::Spec(de_spec::<xu2015::SceneSpec>)),
        ("Zhang2018", Entry::Spec(de_spec::<zhang2018::SceneSpec>)),
        ("Xu2019", Entry::Spec(de_spec::<xu2019::SceneSpec>)),
        (
            "HillPd",
            Entry::Law(de_params::<generic::hill::HillPdParams>),
        ),
        (
            "Glideslope",
            Entry::Law(de_params::<generic::glideslope::GlideslopeParams>),
        ),
        (
            "Attitude",
            Entry::Law(de_params::<generic::attitude::AttitudeParams>),
        ),
        (
            "Sequencer",
            Entry::Law(de_params::<generic::sequencer::SequencerParams>),
        ),
    ]
}

/// Why a registration was refused.
#[derive(Debug, Clone, PartialEq)]
pub struct RegisterError(pub String);

impl fmt::Display for RegisterError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for RegisterError {}

fn insert(name: &str, e: Entry) -> Result<(), RegisterError> {
    let ok = name.chars().next().is_some_and(|c| c.is_ascii_alphabetic())
        && name.len() <= 64
        && name.chars().all(|c| c.is_ascii_alphanumeric() || c == '_');
    if !ok {
        return Err(RegisterError(format!(
            "a controller name is a RON identifier (a letter, then letters, digits or `_`, at most 64), got `{name}`"
        )));
    }
    let mut reg = REGISTRY.write().unwrap_or_else(|p| p.into_inner());
    if reg.contains_key(name) {
        return Err(RegisterError(format!(
            "a controller named `{name}` is already registered"
        )));
    }
    reg.insert(name.to_string(), e);
    Ok(())
}

/// Registers a law whose scene entry is `Name(body: …, params: (…))` (see the module docs):
/// `P` reads the `params` and builds the controller.
pub fn register_law<P: LawParams + for<'de> Deserialize<'de> + 'static>(
    name: &str,
) -> Result<(), RegisterError> {
    insert(name, Entry::Law(de_params::<P>))
}

/// Registers a law that reads its whole entry, `Name((…))`, and builds its slots itself.
pub fn register_spec<S: LawSpec + for<'de> Deserialize<'de> + 'static>(
    name: &str,
) -> Result<(), RegisterError> {
    insert(name, Entry::Spec(de_spec::<S>))
}

/// The registered names, sorted.
pub fn registered() -> Vec<String> {
    REGISTRY
        .read()
        .unwrap_or_else(|p| p.into_inner())
        .keys()
        .cloned()
        .collect()
}

fn lookup(name: &str) -> Option<Entry> {
    REGISTRY
        .read()
        .unwrap_or_else(|p| p.into_inner())
        .get(name)
        .copied()
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
    /// A [`register_law`] entry.
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
    /// The entry as the spec type `S` of a [`register_spec`] law (e.g. a paper law's
    /// `SceneSpec`), if it is one.
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
    /// The parameters as `P` of a [`register_law`] law, if they are.
    pub fn params<P: 'static>(&self) -> Option<&P> {
        match &self.body {
            ControllerBody::Law(l) => (*l.params).as_any().downcast_ref::<P>(),
            ControllerBody::Spec(_) => None,
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

struct ErasedSeed<F>(F);

impl<'de, T> DeserializeSeed<'de>
    for ErasedSeed<fn(&mut dyn erased_serde::Deserializer) -> Result<T, erased_serde::Error>>
{
    type Value = T;
    fn deserialize<D: Deserializer<'de>>(self, d: D) -> Result<T, D::Error> {
        let mut erased = <dyn erased_serde::Deserializer>::erase(d);
        (self.0)(&mut erased).map_err(de::Error::custom)
    }
}

const ENTRY_FIELDS: &[&str] = &[
    "body",
    "target",
    "period_s",
    "sensor",
    "actuator",
    "port",
    "target_port",
    "params",
];

struct EntryVisitor(ParamsFn);

impl<'de> Visitor<'de> for EntryVisitor {
    type Value = LawEntry;
    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str("a controller entry `(body: …, params: (…))`")
    }
    fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<LawEntry, A::Error> {
        let mut body = None;
        let mut target = None;
        let mut period_s = None;
        let mut sensor = None;
        let mut actuator = None;
        let mut port = None;
        let mut target_port = None;
        let mut params = None;
        fn dup<E: de::Error>(seen: bool, f: &'static str) -> Result<(), E> {
            if seen {
                Err(E::duplicate_field(f))
            } else {
                Ok(())
            }
        }
        while let Some(key) = map.next_key::<String>()? {
            match key.as_str() {
                "body" => {
                    dup(body.is_some(), "body")?;
                    body = Some(map.next_value::<String>()?);
                }
                "target" => {
                    dup(target.is_some(), "target")?;
                    target = Some(map.next_value::<Option<String>>()?);
                }
                "period_s" => {
                    dup(period_s.is_some(), "period_s")?;
                    period_s = Some(map.next_value::<Option<f64>>()?);
                }
                "sensor" => {
                    dup(sensor.is_some(), "sensor")?;
                    sensor = Some(map.next_value::<Option<SensorSpec>>()?);
                }
                "actuator" => {
                    dup(actuator.is_some(), "actuator")?;
                    actuator = Some(map.next_value::<ActuatorSpec>()?);
                }
                "port" => {
                    dup(port.is_some(), "port")?;
                    port = Some(map.next_value::<Option<String>>()?);
                }
                "target_port" => {
                    dup(target_port.is_some(), "target_port")?;
                    target_port = Some(map.next_value::<Option<String>>()?);
                }
                "params" => {
                    dup(params.is_some(), "params")?;
                    params = Some(map.next_value_seed(ErasedSeed(self.0))?);
                }
                other => return Err(de::Error::unknown_field(other, ENTRY_FIELDS)),
            }
        }
        Ok(LawEntry {
            body: body.ok_or_else(|| de::Error::missing_field("body"))?,
            target: target.flatten(),
            period_s: period_s.flatten(),
            sensor: sensor.flatten(),
            actuator: actuator.unwrap_or_default(),
            port: port.flatten(),
            target_port: target_port.flatten(),
            params: params.ok_or_else(|| de::Error::missing_field("params"))?,
        })
    }
}

/// A variant name, read as an identifier (not a quoted string).
struct Identifier;

impl<'de> DeserializeSeed<'de> for Identifier {
    type Value = String;
    fn deserialize<D: Deserializer<'de>>(self, d: D) -> Result<String, D::Error> {
        struct V;
        impl Visitor<'_> for V {
            type Value = String;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str("a controller name")
            }
            fn visit_str<E: de::Error>(self, v: &str) -> Result<String, E> {
                Ok(v.to_string())
            }
        }
        d.deserialize_identifier(V)
    }
}

/// A law registered with [`register_law`] written by its parameters only, `Name((…))` —
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

impl<'de> Deserialize<'de> for LawParamsSpec {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl<'de> Visitor<'de> for V {
            type Value = LawParamsSpec;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str("a law by its parameters, e.g. `HillPd((hold_m: …, gains: …))`")
            }
            fn visit_enum<A: EnumAccess<'de>>(self, data: A) -> Result<LawParamsSpec, A::Error> {
                let (kind, variant) = data.variant_seed(Identifier)?;
                match lookup(&kind) {
                    Some(Entry::Law(f)) => Ok(LawParamsSpec {
                        kind,
                        params: variant.newtype_variant_seed(ErasedSeed(f))?,
                    }),
                    Some(Entry::Spec(_)) => Err(de::Error::custom(format!(
                        "`{kind}` reads a whole controller entry and cannot be named by its parameters here"
                    ))),
                    None => Err(de::Error::custom(format!(
                        "unknown law `{kind}`; registered: {}",
                        registered().join(", ")
                    ))),
                }
            }
        }
        d.deserialize_enum("Law", &[], V)
    }
}

struct SpecVisitor;

impl<'de> Visitor<'de> for SpecVisitor {
    type Value = ControllerSpec;
    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str("a controller, e.g. `HillPd(body: \"chaser\", params: (…))`")
    }
    fn visit_enum<A: EnumAccess<'de>>(self, data: A) -> Result<ControllerSpec, A::Error> {
        let (kind, variant) = data.variant_seed(Identifier)?;
        let Some(entry) = lookup(&kind) else {
            return Err(de::Error::custom(format!(
                "unknown controller `{kind}`; registered: {}",
                registered().join(", ")
            )));
        };
        let body = match entry {
            Entry::Spec(f) => ControllerBody::Spec(variant.newtype_variant_seed(ErasedSeed(f))?),
            Entry::Law(f) => ControllerBody::Law(Box::new(
                variant.struct_variant(ENTRY_FIELDS, EntryVisitor(f))?,
            )),
        };
        Ok(ControllerSpec { kind, body })
    }
}

impl<'de> Deserialize<'de> for ControllerSpec {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        d.deserialize_enum("Controller", &[], SpecVisitor)
    }
}
