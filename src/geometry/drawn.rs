//! What a law or a guarantee asks a viewer to draw: its constraint surfaces as plain f64
//! geometry, Bevy-free. A law (or guarantee) describes them through its own hook
//! ([`crate::control::spec::LawSpec::drawn`], [`crate::control::spec::LawParams::drawn`],
//! [`crate::guarantee::registry::GuaranteeParams::drawn`]); the viewer turns each into a
//! translucent mesh without knowing which law it came from, so a user's law draws its own
//! surfaces exactly as the paper laws do.
//!
//! Drawing is for the eye: nothing is checked against these surfaces. A hook should return the
//! very geometry its law or guarantee uses (the viewer's tests check the paper laws' surfaces
//! against their analytic boundaries).

use nalgebra::Vector2;

/// Points on each closed outline a paper law draws (the superquadric and the heart).
pub const OUTLINE_POINTS: usize = 240;

/// One constraint surface.
#[derive(Debug, Clone, PartialEq)]
pub enum DrawnSurface {
    /// A closed counter-clockwise outline in an air-bearing table's plane (lab frame x, y, m),
    /// star-shaped about its first point, drawn as a vertical prism over the table (z from 0 to
    /// `top_m`) and as a line at the height of `curve_body`'s centre of mass.
    TablePrism {
        /// The viewer's legend line (name it, give its numbers with units).
        legend: String,
        /// The outline, lab frame, m.
        outline_lab_m: Vec<Vector2<f64>>,
        /// The point the prism's mesh is placed at (lab frame, m): the shape's own centre.
        centre_lab_m: Vector2<f64>,
        /// Height of the prism's top above the table, m.
        top_m: f64,
        /// The body (scene index) whose centre-of-mass height the outline is drawn at.
        curve_body: Option<usize>,
        /// Colour and opacity, RGBA in 0..1.
        rgba: [f32; 4],
    },
    /// A sphere of `radius_m` about a body's centre of mass.
    SphereAboutBody {
        /// The viewer's legend line.
        legend: String,
        /// Scene index of the body.
        body: usize,
        /// Radius, m.
        radius_m: f64,
        /// Colour and opacity, RGBA in 0..1.
        rgba: [f32; 4],
    },
    /// A surface of revolution about a body's +x axis with its vertex at the body's centre of
    /// mass (e.g. an approach corridor), given by its meridian: (distance along +x, radius), m,
    /// in increasing distance.
    RevolutionAboutBody {
        /// The viewer's legend line.
        legend: String,
        /// Scene index of the body (the surface turns with it).
        body: usize,
        /// Meridian points (x, radius), m, body frame.
        meridian_m: Vec<(f64, f64)>,
        /// Colour and opacity, RGBA in 0..1.
        rgba: [f32; 4],
    },
}

/// Largest coordinate or size a drawn surface may have, m (a scene's positions are limited to
/// [`crate::scene::validate::MAX_POSITION_M`] too): beyond it, or not finite, a surface is not
/// drawn (a hook's 1e308 or NaN would become an infinite f32 mesh).
pub const MAX_DRAWN_M: f64 = crate::scene::validate::MAX_POSITION_M;

impl DrawnSurface {
    /// Every number is finite and within [`MAX_DRAWN_M`] (sizes positive): the viewer draws
    /// only such a surface.
    pub fn is_drawable(&self) -> bool {
        let ok = |x: f64| x.is_finite() && x.abs() <= MAX_DRAWN_M;
        match self {
            Self::TablePrism {
                outline_lab_m,
                centre_lab_m,
                top_m,
                ..
            } => {
                outline_lab_m.len() >= 3
                    && outline_lab_m.iter().all(|p| ok(p.x) && ok(p.y))
                    && ok(centre_lab_m.x)
                    && ok(centre_lab_m.y)
                    && ok(*top_m)
                    && *top_m > 0.0
            }
            Self::SphereAboutBody { radius_m, .. } => ok(*radius_m) && *radius_m > 0.0,
            Self::RevolutionAboutBody { meridian_m, .. } => {
                meridian_m.len() >= 2
                    && meridian_m
                        .iter()
                        .all(|(x, r)| ok(*x) && ok(*r) && *r >= 0.0)
            }
        }
    }

    /// The legend line.
    pub fn legend(&self) -> &str {
        match self {
            Self::TablePrism { legend, .. }
            | Self::SphereAboutBody { legend, .. }
            | Self::RevolutionAboutBody { legend, .. } => legend,
        }
    }
}

/// The meridian of a surface of revolution: `samples + 1` points of `radius_at_m(x)` for x from
/// 0 to `x_end_m`, stopping at the first x where the radius is undefined, not finite or beyond
/// `max_radius_m`.
pub fn meridian(
    radius_at_m: impl Fn(f64) -> Option<f64>,
    x_end_m: f64,
    max_radius_m: f64,
    samples: usize,
) -> Vec<(f64, f64)> {
    let mut out = Vec::new();
    for k in 0..=samples {
        let x = x_end_m * k as f64 / samples.max(1) as f64;
        match radius_at_m(x) {
            Some(r) if r.is_finite() && r <= max_radius_m => out.push((x, r)),
            _ => break,
        }
    }
    out
}
