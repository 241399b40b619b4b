//! The scene's original guarantee kinds, registered like any other
//! ([`super::registry::register_guarantee`]): `MinDistance`, `KeepOutSphere`, `ApproachCone`.

use super::registry::{GuaranteeContext, GuaranteeParams};
use super::{Guarantee, KeepOutSphere, MinDistance};
use crate::control::registry::BuildError;
use crate::scene::Scene;
use crate::scene::validate::{MAX_POSITION_M, in_range, positive};
use nalgebra::Vector3;
use serde::Deserialize;

/// A scene check's `(field, message)` as an error relative to the entry.
pub(crate) fn rel((field, message): (String, String)) -> BuildError {
    BuildError::at(field, message)
}

/// `MinDistance`: the full-geometry minimum distance between two bodies stays ≥ `min_m`
/// (margin = distance − min_m, m; judged between samples from the distance's rate bound).
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MinDistanceParams {
    /// Guarantee name.
    pub name: String,
    /// First body.
    pub a: String,
    /// Second body.
    pub b: String,
    /// Required clearance, m.
    pub min_m: f64,
}

impl GuaranteeParams for MinDistanceParams {
    fn name(&self) -> &str {
        &self.name
    }
    fn bodies(&self) -> Vec<(&'static str, &str)> {
        vec![("a", &self.a), ("b", &self.b)]
    }
    fn check(&self, _scene: &Scene) -> Result<(), BuildError> {
        if !(self.min_m.is_finite() && self.min_m >= 0.0 && self.min_m <= MAX_POSITION_M) {
            return Err(BuildError::at(
                "min_m",
                format!("must be from 0 to {MAX_POSITION_M:e} m"),
            ));
        }
        Ok(())
    }
    fn build(&self, ctx: &GuaranteeContext) -> Result<Box<dyn Guarantee>, BuildError> {
        Ok(Box::new(MinDistance {
            name: self.name.clone(),
            a: ctx.body("a", &self.a)?,
            b: ctx.body("b", &self.b)?,
            min_m: self.min_m,
        }))
    }
}

/// `KeepOutSphere`: the centre of mass of `body` stays outside a sphere of `radius_m` about
/// the centre of mass of `around` (margin = |r| − radius, m; judged between samples from the
/// relative speed).
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct KeepOutSphereParams {
    /// Guarantee name.
    pub name: String,
    /// The body whose centre of mass is checked.
    pub body: String,
    /// The body at the sphere's centre.
    pub around: String,
    /// Sphere radius, m.
    pub radius_m: f64,
}

impl GuaranteeParams for KeepOutSphereParams {
    fn name(&self) -> &str {
        &self.name
    }
    fn bodies(&self) -> Vec<(&'static str, &str)> {
        vec![("body", &self.body), ("around", &self.around)]
    }
    fn check(&self, _scene: &Scene) -> Result<(), BuildError> {
        in_range(
            "radius_m",
            self.radius_m,
            (f64::MIN_POSITIVE, MAX_POSITION_M),
            "m",
        )
        .map_err(rel)
    }
    fn build(&self, ctx: &GuaranteeContext) -> Result<Box<dyn Guarantee>, BuildError> {
        Ok(Box::new(KeepOutSphere {
            name: self.name.clone(),
            body: ctx.body("body", &self.body)?,
            around: ctx.body("around", &self.around)?,
            radius_m: self.radius_m,
        }))
    }
    fn drawn(&self, scene: &Scene) -> Vec<crate::geometry::drawn::DrawnSurface> {
        let Some(body) = scene.bodies.iter().position(|b| b.name == self.around) else {
            return Vec::new();
        };
        vec![crate::geometry::drawn::DrawnSurface::SphereAboutBody {
            legend: format!(
                "keep-out {} (yellow): {} m about {}",
                self.name, self.radius_m, self.around
            ),
            body,
            radius_m: self.radius_m,
            rgba: [1.0, 0.85, 0.2, 0.1],
        }]
    }
}

/// `ApproachCone`: while `body`'s centre of mass is between `to_range_m` and `from_range_m`
/// from the port `port` of `around`, every point of every part of `body` stays inside the cone
/// with its apex at the port, its axis the port's outward axis and half-angle
/// `half_angle_deg` (margin = the clearance to the cone's wall, m, inside the range band;
/// positive outside it, continuous across its edges; see [`crate::geometry::approach_cone`]).
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ApproachConeParams {
    /// Guarantee name.
    pub name: String,
    /// The body that approaches.
    pub body: String,
    /// The body with the port.
    pub around: String,
    /// The port (its origin is the apex).
    pub port: String,
    /// Half-angle, deg (0 < α < 90).
    pub half_angle_deg: f64,
    /// The cone applies from this range (centre of mass to apex) inwards, m.
    pub from_range_m: f64,
    /// … down to this range, m (default 0).
    #[serde(default)]
    pub to_range_m: f64,
}

impl GuaranteeParams for ApproachConeParams {
    fn name(&self) -> &str {
        &self.name
    }
    fn bodies(&self) -> Vec<(&'static str, &str)> {
        vec![("body", &self.body), ("around", &self.around)]
    }
    fn check(&self, scene: &Scene) -> Result<(), BuildError> {
        let around = &self.around;
        let port = &self.port;
        let has_port = scene
            .bodies
            .iter()
            .find(|b| &b.name == around)
            .is_some_and(|b| b.ports.iter().any(|q| &q.name == port));
        if !has_port {
            return Err(BuildError::at(
                "port",
                format!("body `{around}` has no port `{port}`"),
            ));
        }
        let a = self.half_angle_deg;
        if !(a.is_finite() && a > 0.0 && a < 90.0) {
            return Err(BuildError::at(
                "half_angle_deg",
                format!("must be an angle in (0, 90) deg, got {a}"),
            ));
        }
        positive("from_range_m", self.from_range_m, "metres").map_err(rel)?;
        let (to, from) = (self.to_range_m, self.from_range_m);
        if !(to.is_finite() && to >= 0.0 && to < from) {
            return Err(BuildError::at(
                "to_range_m",
                format!("must be ≥ 0 m and below from_range_m ({from} m), got {to}"),
            ));
        }
        Ok(())
    }
    fn build(&self, ctx: &GuaranteeContext) -> Result<Box<dyn Guarantee>, BuildError> {
        let b = ctx.body("body", &self.body)?;
        let a = ctx.body("around", &self.around)?;
        let (port_m, axis) = crate::scene::parts::port_frame(&ctx.scene.bodies[a], &self.port)
            .ok_or_else(|| {
                BuildError::at(
                    "port",
                    format!("body `{}` has no port `{}`", self.around, self.port),
                )
            })?;
        Ok(Box::new(crate::geometry::approach_cone::ApproachCone {
            name: self.name.clone(),
            body: b,
            body_com_m: Vector3::from(ctx.scene.bodies[b].com_m),
            points: crate::geometry::approach_cone::SupportSet::new(
                ctx.parts[b]
                    .iter()
                    .map(crate::geometry::approach_cone::support_points)
                    .collect(),
                &Vector3::from(ctx.scene.bodies[b].com_m),
            ),
            around: a,
            around_com_m: Vector3::from(ctx.scene.bodies[a].com_m),
            port_m,
            axis,
            half_angle_rad: self.half_angle_deg.to_radians(),
            from_range_m: self.from_range_m,
            to_range_m: self.to_range_m,
        }))
    }
}
