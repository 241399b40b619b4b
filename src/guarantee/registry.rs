//! Open registration of guarantees: a scene's `guarantees` list names each entry's kind by its
//! registered name, as its `controllers` list names laws ([`crate::control::registry`]). This
//! crate registers its kinds (`MinDistance`, `KeepOutSphere`, `ApproachCone` and the RPOD
//! requirement set) through the same [`register_guarantee`] call a user's crate makes; there is
//! no central match to edit. Bevy-free.
//!
//! # A kind
//! A kind is a serde type `P` holding the entry's fields (with `name`), implementing
//! [`GuaranteeParams`]: which bodies it relates ([`GuaranteeParams::bodies`]: they must exist
//! and be different bodies, checked here for every kind), its own checks of the values
//! ([`GuaranteeParams::check`], at load time, so `rpod check` reports them), and the
//! [`Guarantee`] it builds. The scene writes the entry as a struct variant:
//! ```ron
//! guarantees: [KeepOutSphere(name: "keep_out", body: "chaser", around: "target", radius_m: 10.0)]
//! ```
//! Unknown kinds, unknown or missing fields and values a kind rejects are located scene errors
//! (file:line:col, field `guarantees.NAME.FIELD`). Registration is process-wide (a `RwLock`ed
//! map): register before loading the scenes that use the name.

use super::Guarantee;
use crate::control::interface::AsAny;
use crate::control::registry::{BuildError, RegisterError};
use crate::geometry::drawn::DrawnSurface;
use crate::scene::Scene;
use crate::scene::parts::PartCollider;
use serde::de::{self, DeserializeSeed, EnumAccess, VariantAccess, Visitor};
use serde::{Deserialize, Deserializer};
use std::collections::BTreeMap;
use std::fmt;
use std::sync::{LazyLock, RwLock};

/// What a kind sees of the scene when it builds its guarantee (at t = 0).
pub struct GuaranteeContext<'a> {
    /// The scene (validated).
    pub scene: &'a Scene,
    /// Every body's colliders, scene order (body frame: the exact geometry the monitor judges).
    pub parts: &'a [Vec<PartCollider>],
}

impl GuaranteeContext<'_> {
    /// Index of a body by name, or an error at `field`.
    pub fn body(&self, field: &str, name: &str) -> Result<usize, BuildError> {
        body_index(self.scene, field, name)
    }
}

fn body_index(scene: &Scene, field: &str, name: &str) -> Result<usize, BuildError> {
    scene
        .bodies
        .iter()
        .position(|b| b.name == name)
        .ok_or_else(|| BuildError::at(field, format!("no body named `{name}`")))
}

/// The fields of one kind of guarantee, as a scene entry gives them; they build the guarantee.
/// Errors name fields relative to the entry (`radius_m`, `gates.1.0`).
pub trait GuaranteeParams: GuaranteeParamsClone + AsAny + fmt::Debug + Send + Sync {
    /// The guarantee's name (the entry's `name`).
    fn name(&self) -> &str;
    /// The bodies the guarantee relates, as (field, body name). Each must exist and all must
    /// be different bodies (a guarantee between a body and itself is refused for every kind).
    fn bodies(&self) -> Vec<(&'static str, &str)>;
    /// Checks the values against the scene (called when the scene is validated, after the
    /// bodies of [`GuaranteeParams::bodies`] are known to exist and differ).
    fn check(&self, scene: &Scene) -> Result<(), BuildError> {
        let _ = scene;
        Ok(())
    }
    /// The guarantee, from its checked values.
    fn build(&self, ctx: &GuaranteeContext) -> Result<Box<dyn Guarantee>, BuildError>;
    /// The surfaces a viewer should draw for this guarantee (none by default): its zone as the
    /// guarantee itself uses it ([`DrawnSurface`]).
    fn drawn(&self, scene: &Scene) -> Vec<DrawnSurface> {
        let _ = scene;
        Vec::new()
    }
}

/// Cloning boxed parameters (implemented for every `GuaranteeParams + Clone`).
pub trait GuaranteeParamsClone {
    /// A boxed copy.
    fn clone_box(&self) -> Box<dyn GuaranteeParams>;
}

impl<T: GuaranteeParams + Clone + 'static> GuaranteeParamsClone for T {
    fn clone_box(&self) -> Box<dyn GuaranteeParams> {
        Box::new(self.clone())
    }
}

/// One entry of a scene's `guarantees` list: its registered kind and its fields.
pub struct GuaranteeSpec {
    /// The registered kind (`MinDistance`, `PassiveSafety`, a user's).
    pub kind: String,
    /// The fields.
    pub params: Box<dyn GuaranteeParams>,
}

impl Clone for GuaranteeSpec {
    fn clone(&self) -> Self {
        Self {
            kind: self.kind.clone(),
            params: self.params.clone_box(),
        }
    }
}

impl fmt::Debug for GuaranteeSpec {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}({:?})", self.kind, self.params)
    }
}

impl GuaranteeSpec {
    /// The guarantee's name.
    pub fn name(&self) -> &str {
        self.params.name()
    }
    /// The fields as the type `P` of a registered kind, if they are.
    pub fn params<P: 'static>(&self) -> Option<&P> {
        (*self.params).as_any().downcast_ref::<P>()
    }
    /// The surfaces the guarantee asks a viewer to draw (its `drawn` hook).
    pub fn drawn(&self, scene: &Scene) -> Vec<DrawnSurface> {
        self.params.drawn(scene)
    }
    /// The fields as `P`, mutably (to change a loaded scene before a run).
    pub fn params_mut<P: 'static>(&mut self) -> Option<&mut P> {
        (*self.params).as_any_mut().downcast_mut::<P>()
    }
    /// Checks the entry against the scene: the bodies it names exist and differ, then the
    /// kind's own checks. Errors name fields relative to the entry.
    pub fn check(&self, scene: &Scene) -> Result<(), BuildError> {
        let bodies = self.params.bodies();
        for (i, (field, name)) in bodies.iter().enumerate() {
            body_index(scene, field, name)?;
            if let Some((other, _)) = bodies[..i].iter().find(|(_, n)| n == name) {
                return Err(BuildError::at(
                    *field,
                    format!("must name a different body than `{other}`"),
                ));
            }
        }
        self.params.check(scene)
    }
    /// Builds the guarantee.
    pub fn build(&self, ctx: &GuaranteeContext) -> Result<Box<dyn Guarantee>, BuildError> {
        self.check(ctx.scene)?;
        self.params.build(ctx)
    }
}

type ParamsFn = fn(
    &mut dyn erased_serde::Deserializer,
) -> Result<Box<dyn GuaranteeParams>, erased_serde::Error>;

fn de_params<P: GuaranteeParams + for<'de> Deserialize<'de> + 'static>(
    d: &mut dyn erased_serde::Deserializer,
) -> Result<Box<dyn GuaranteeParams>, erased_serde::Error> {
    Ok(Box::new(erased_serde::deserialize::<P>(d)?))
}

static REGISTRY: LazyLock<RwLock<BTreeMap<String, ParamsFn>>> = LazyLock::new(|| {
    let mut m = BTreeMap::new();
    for (name, f) in builtin() {
        m.insert(name.to_string(), f);
    }
    RwLock::new(m)
});

/// The kinds this crate registers: one line per kind.
fn builtin() -> Vec<(&'static str, ParamsFn)> {
    use super::builtin::{ApproachConeParams, KeepOutSphereParams, MinDistanceParams};
    use super::requirements::{
        ClosingSpeedGateParams, KeepOutEllipsoidParams, PassiveSafetyParams,
    };
    #[allow(unused_mut)]
    let mut kinds: Vec<(&'static str, ParamsFn)> = vec![
        ("MinDistance", de_params::<MinDistanceParams>),
        ("KeepOutSphere", de_params::<KeepOutSphereParams>),
        ("ApproachCone", de_params::<ApproachConeParams>),
        ("KeepOutEllipsoid", de_params::<KeepOutEllipsoidParams>),
        ("ClosingSpeedGate", de_params::<ClosingSpeedGateParams>),
        ("PassiveSafety", de_params::<PassiveSafetyParams>),
    ];
    // Needs the full geometry (parry): only with the Bevy + rapier layer.
    #[cfg(feature = "sim")]
    kinds.push((
        "LineOfSight",
        de_params::<super::requirements::LineOfSightParams>,
    ));
    #[cfg(feature = "sim")]
    kinds.push((
        "PlumeKeepOff",
        de_params::<crate::sim::plume::PlumeKeepOffParams>,
    ));
    kinds
}

/// Registers a kind of guarantee under `name`: scene entries `name(field: …, …)` are read as
/// `P` (see the module docs).
pub fn register_guarantee<P: GuaranteeParams + for<'de> Deserialize<'de> + 'static>(
    name: &str,
) -> Result<(), RegisterError> {
    let ok = name.chars().next().is_some_and(|c| c.is_ascii_alphabetic())
        && name.len() <= 64
        && name.chars().all(|c| c.is_ascii_alphanumeric() || c == '_');
    if !ok {
        return Err(RegisterError(format!(
            "a guarantee kind is a RON identifier (a letter, then letters, digits or `_`, at most 64), got `{name}`"
        )));
    }
    let mut reg = REGISTRY.write().unwrap_or_else(|p| p.into_inner());
    if reg.contains_key(name) {
        return Err(RegisterError(format!(
            "a guarantee kind named `{name}` is already registered"
        )));
    }
    reg.insert(name.to_string(), de_params::<P>);
    Ok(())
}

/// The registered kinds, sorted.
pub fn registered() -> Vec<String> {
    REGISTRY
        .read()
        .unwrap_or_else(|p| p.into_inner())
        .keys()
        .cloned()
        .collect()
}

fn lookup(name: &str) -> Option<ParamsFn> {
    REGISTRY
        .read()
        .unwrap_or_else(|p| p.into_inner())
        .get(name)
        .copied()
}

/// A struct variant's content as a deserializer (so a kind's derived `Deserialize` reads
/// `Kind(field: …)` as it would read `(field: …)`).
struct StructVariant<A>(A);

impl<'de, A: VariantAccess<'de>> Deserializer<'de> for StructVariant<A> {
    type Error = A::Error;
    fn deserialize_any<V: Visitor<'de>>(self, v: V) -> Result<V::Value, A::Error> {
        self.0.struct_variant(&[], v)
    }
    fn deserialize_struct<V: Visitor<'de>>(
        self,
        _name: &'static str,
        fields: &'static [&'static str],
        v: V,
    ) -> Result<V::Value, A::Error> {
        self.0.struct_variant(fields, v)
    }
    serde::forward_to_deserialize_any! {
        bool i8 i16 i32 i64 i128 u8 u16 u32 u64 u128 f32 f64 char str string bytes byte_buf
        option unit unit_struct newtype_struct seq tuple tuple_struct map enum identifier
        ignored_any
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
                f.write_str("a guarantee kind")
            }
            fn visit_str<E: de::Error>(self, v: &str) -> Result<String, E> {
                Ok(v.to_string())
            }
        }
        d.deserialize_identifier(V)
    }
}

impl<'de> Deserialize<'de> for GuaranteeSpec {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl<'de> Visitor<'de> for V {
            type Value = GuaranteeSpec;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str(
                    "a guarantee, e.g. `MinDistance(name: \"clear\", a: …, b: …, min_m: …)`",
                )
            }
            fn visit_enum<A: EnumAccess<'de>>(self, data: A) -> Result<GuaranteeSpec, A::Error> {
                let (kind, variant) = data.variant_seed(Identifier)?;
                let Some(f) = lookup(&kind) else {
                    return Err(de::Error::custom(format!(
                        "unknown guarantee kind `{kind}`; registered: {}",
                        registered().join(", ")
                    )));
                };
                let mut erased = <dyn erased_serde::Deserializer>::erase(StructVariant(variant));
                let params = f(&mut erased).map_err(de::Error::custom)?;
                Ok(GuaranteeSpec { kind, params })
            }
        }
        d.deserialize_enum("Guarantee", &[], V)
    }
}
