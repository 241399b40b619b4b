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
//!   parameters into a [`Controller`](crate::control::interface::Controller) ([`LawParams::build`]).
//! - [`register_spec::<S>("Name")`](register_spec) — for a law that reads its own entry
//!   (`Name((...))`: the five paper laws keep the scene format of their reproductions) and
//!   builds its slots itself ([`LawSpec::build`]).
//!
//! Unknown names, parameters of the wrong type and values a law rejects are located scene
//! errors (file:line:col, field). Registration is process-wide (a `RwLock`ed map): register
//! before loading the scenes that use the name.

//!
//! The types a law implements and is given (the extension points) are in
//! [`spec`](crate::control::spec); they are re-exported here so their `registry::` paths keep
//! working. This module holds the name table and the lookup (the by-name deserialization of a scene's
//! `controllers` entries); the list of built-in laws is [`builtin`](crate::control::builtin).

use crate::actuation::ActuatorSpec;
use crate::control::sensor::SensorSpec;
pub use crate::control::spec::{
    BodyWrench, BuildContext, BuildError, Built, Commands, ControllerBody, ControllerSpec,
    Disturbance, DisturbanceContext, LawContext, LawEntry, LawParams, LawParamsClone,
    LawParamsSpec, LawSpec, LawSpecClone, Slot, default_ports,
};
use serde::de::{self, DeserializeSeed, EnumAccess, MapAccess, VariantAccess, Visitor};
use serde::{Deserialize, Deserializer};
use std::collections::BTreeMap;
use std::fmt;
use std::sync::{LazyLock, RwLock};

type SpecFn =
    fn(&mut dyn erased_serde::Deserializer) -> Result<Box<dyn LawSpec>, erased_serde::Error>;
type ParamsFn =
    fn(&mut dyn erased_serde::Deserializer) -> Result<Box<dyn LawParams>, erased_serde::Error>;

/// How a registered name reads its scene entry: a law's own spec, or the common entry with
/// `params`.
#[derive(Clone, Copy)]
pub(crate) enum Entry {
    Spec(SpecFn),
    Law(ParamsFn),
}

/// Reads a spec `S` (an [`Entry::Spec`]).
pub(crate) fn de_spec<S: LawSpec + for<'de> Deserialize<'de> + 'static>(
    d: &mut dyn erased_serde::Deserializer,
) -> Result<Box<dyn LawSpec>, erased_serde::Error> {
    Ok(Box::new(erased_serde::deserialize::<S>(d)?))
}

/// Reads parameters `P` (an [`Entry::Law`]).
pub(crate) fn de_params<P: LawParams + for<'de> Deserialize<'de> + 'static>(
    d: &mut dyn erased_serde::Deserializer,
) -> Result<Box<dyn LawParams>, erased_serde::Error> {
    Ok(Box::new(erased_serde::deserialize::<P>(d)?))
}

static REGISTRY: LazyLock<RwLock<BTreeMap<String, Entry>>> = LazyLock::new(|| {
    let mut m = BTreeMap::new();
    for (name, e) in crate::control::builtin::laws() {
        m.insert(name.to_string(), e);
    }
    RwLock::new(m)
});

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
