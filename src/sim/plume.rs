//! Plume keep-off: does a firing jet's plume cone touch the listed parts of another body?
//! Judged on the full geometry (every part's judged shape: primitives, and triangle meshes
//! for mesh parts) against the pyramid circumscribed about the plume cone (256 sides: it
//! contains the cone and exceeds it by 7.5e-5 of its base radius; see [`plume_shape`]).
//!
//! A jet's plume ([`crate::actuation::rcs::PlumeSpec`]) is the solid cone with its apex at
//! the nozzle, its axis the exhaust direction (−thrust), half-angle α and length L.
//!
//! [`plume_hits`] is the check at one instant (mesh parts through the monitor's shell and hull
//! brackets, as the guarantee judges them: [`plume_clearance_bracket`]); [`PlumeKeepOff`] is
//! the scene guarantee
//! `PlumeKeepOff(name, body, around, parts: [...])` built on it (registered like every kind,
//! [`crate::guarantee::registry`]), judged on every step interval (see its docs and
//! `docs/guarantees.md`).

use super::monitor::{F32_REL_TOL, PairEval, pair_eval_shapes, shape_bracket};
use crate::actuation::actuator::ActuatorSpec;
use crate::actuation::rcs::{JetSpec, plume_cone};
use crate::control::ControllerSpec;
use crate::control::registry::{BuildError, ControllerBody};
use crate::geometry::bounds::Bracket;
use crate::guarantee::registry::{GuaranteeContext, GuaranteeParams};
use crate::guarantee::{Guarantee, MonitorView, MotionBounds, Reads};
use crate::scene::Scene;
use bevy_rapier3d::rapier::prelude as rp;
use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};
use serde::Deserialize;
use std::sync::atomic::{AtomicU64, Ordering};

/// Sides of the pyramid that stands for a plume cone ([`plume_shape`]).
pub const PLUME_SIDES: u32 = 256;

/// The plume cone as a parry shape and its pose in the frame its apex and axis are given in.
///
/// The shape is the pyramid circumscribed about the cone: the apex and a regular
/// [`PLUME_SIDES`]-gon whose sides touch the base circle (corners at radius
/// L·tan α / cos(π/N)). It contains the cone, so every distance to it is at most the cone's
/// (never a false clearance), and it exceeds the cone by at most the base radius times
/// 1/cos(π/N) − 1 = 7.5e-5 (0.2 mm for a 10 m, 15° plume). Not parry's `Cone`: its f32 GJK
/// reports false overlaps of a cone and a box centimetres apart (75 of 20 000 poses of a
/// 10 m cone 1 cm from a box in `tests/val_plume.rs`), while the polyhedron gives none there.
/// Made once per (α, L) and shared.
pub fn plume_shape(
    apex: &Vector3<f64>,
    axis: &Vector3<f64>,
    half_angle_rad: f64,
    length_m: f64,
) -> (rp::SharedShape, Isometry3<f64>) {
    use std::collections::BTreeMap;
    use std::sync::{LazyLock, Mutex};
    static CACHE: LazyLock<Mutex<BTreeMap<(u64, u64), rp::SharedShape>>> =
        LazyLock::new(|| Mutex::new(BTreeMap::new()));
    let key = (half_angle_rad.to_bits(), length_m.to_bits());
    let mut cache = CACHE.lock().unwrap_or_else(|p| p.into_inner());
    let shape = cache
        .entry(key)
        .or_insert_with(|| pyramid(half_angle_rad, length_m))
        .clone();
    drop(cache);
    let a = axis.normalize();
    // Local +y (the apex side) onto −axis, so the cone opens along the exhaust.
    let rot = UnitQuaternion::rotation_between(&Vector3::y(), &-a).unwrap_or_else(|| {
        UnitQuaternion::from_axis_angle(&Vector3::x_axis(), std::f64::consts::PI)
    });
    let pose = Isometry3::from_parts(Translation3::from(apex + a * (length_m / 2.0)), rot);
    (shape, pose)
}

/// The circumscribed pyramid of [`plume_shape`], centred on its axis's midpoint, apex on +y.
fn pyramid(half_angle_rad: f64, length_m: f64) -> rp::SharedShape {
    use bevy_rapier3d::rapier::math::Vector as V;
    let n = PLUME_SIDES;
    let h = length_m / 2.0;
    let r = length_m * half_angle_rad.tan() / (std::f64::consts::PI / f64::from(n)).cos();
    let mut pts = vec![V::new(0.0, h as f32, 0.0)];
    for k in 0..n {
        let t = f64::from(k) * std::f64::consts::TAU / f64::from(n);
        pts.push(V::new(
            (r * t.cos()) as f32,
            -h as f32,
            (r * t.sin()) as f32,
        ));
    }
    // Apex and a convex polygon: never degenerate for 0 < α < 90° and L > 0 (validated).
    rp::SharedShape::convex_hull(&pts).unwrap_or_else(|| {
        rp::SharedShape::cone(h as f32, (length_m * half_angle_rad.tan()) as f32)
    })
}

/// A plume touching a part.
#[derive(Debug, Clone, PartialEq)]
pub struct PlumeHit {
    /// The jet.
    pub jet: String,
    /// The part struck (`body/collider`).
    pub part: String,
}

/// `*` matches any run of characters (none included); everything else literally.
pub fn glob_match(pattern: &str, name: &str) -> bool {
    let (p, n) = (pattern.as_bytes(), name.as_bytes());
    let (mut i, mut j, mut star, mut mark) = (0, 0, None, 0);
    while j < n.len() {
        if i < p.len() && p[i] == b'*' {
            star = Some(i);
            mark = j;
            i += 1;
        } else if i < p.len() && p[i] == n[j] {
            i += 1;
            j += 1;
        } else if let Some(s) = star {
            i = s + 1;
            mark += 1;
            j = mark;
        } else {
            return false;
        }
    }
    p[i..].iter().all(|c| *c == b'*')
}

/// Radius about its centre (the axis's midpoint) of the pyramid of [`plume_shape`] for a
/// plume of half-angle α and length L, m: its base corners, at L·tan α / cos(π/N) from the
/// axis and L/2 from the centre, are its farthest points (the apex is L/2 away).
pub fn plume_shape_radius_m(half_angle_rad: f64, length_m: f64) -> f64 {
    let corner =
        length_m * half_angle_rad.tan() / (std::f64::consts::PI / f64::from(PLUME_SIDES)).cos();
    (length_m / 2.0).hypot(corner)
}

/// Bounding radius of a part's judged shape about its own origin (parry's bounding sphere:
/// its centre's distance plus its radius), m.
fn shape_radius_m(shape: &dyn rp::Shape) -> f64 {
    let s = shape.compute_local_bounding_sphere();
    f64::from(s.center().length() + s.radius())
}

/// The clearance between one jet's plume and a part, m, with its certified lower bound (both 0
/// when they touch). `jet_frame` is the pose of the frame the jet's position and direction are
/// written in (the firing body's centre-of-mass frame), `part_pose` the part's pose, both in
/// one frame; `hull` the part's hull support map when it is a triangle mesh
/// ([`super::monitor::mesh_hull`]).
///
/// A part with a support map: parry's distance and the gap along its witness direction
/// ([`shape_bracket`]). A triangle mesh with its hull: the monitor's evaluation
/// ([`pair_eval_shapes`], as [`PlumeKeepOff`] judges it): the mesh's shell or its hull's
/// bracket where that is as narrow as parry's exact query — then no triangle-by-triangle
/// query — else the exact triangle-mesh query; either way within [`super::monitor::GJK_REL_TOL`]
/// of the distance plus the f32 rounding of the pose ([`F32_REL_TOL`] of the pair's scale). A
/// mesh without its hull: the exact triangle-mesh query, its lower bound that value less those
/// tolerances.
pub fn plume_clearance_bracket(
    jet: &JetSpec,
    jet_frame: &Isometry3<f64>,
    part_pose: &Isometry3<f64>,
    part: &dyn rp::Shape,
    hull: Option<&super::mesh::HullSupport>,
) -> Option<Bracket> {
    let (apex, axis, alpha, len) = plume_cone(jet)?;
    let (cone, pose) = plume_shape(&apex, &axis, alpha, len);
    let pose = jet_frame * pose;
    let (ra, rb) = (plume_shape_radius_m(alpha, len), shape_radius_m(part));
    let d = match (hull, part.as_support_map()) {
        (None, Some(_)) => shape_bracket(&pose, &*cone, ra, part_pose, part, rb),
        _ => match pair_eval_shapes(
            &(pose, ra),
            (&*cone, None),
            &(*part_pose, rb),
            (part, hull),
            f64::INFINITY,
        ) {
            PairEval::Value(value, lower) if lower.is_nan() => {
                // No hull: parry's exact query, bracketed by its tolerances.
                let eps = F32_REL_TOL
                    * ((pose.translation.vector - part_pose.translation.vector).norm() + ra + rb);
                Bracket {
                    value,
                    lower: (value * (1.0 - super::monitor::GJK_REL_TOL) - eps).max(0.0),
                }
            }
            PairEval::Value(value, lower) => Bracket {
                value,
                lower: lower.min(value),
            },
            // (Not with an infinite `clear_at`.)
            PairEval::Clear(lower) => Bracket {
                value: lower,
                lower,
            },
        },
    };
    Some(Bracket {
        value: d.value.max(0.0),
        lower: d.lower.clamp(0.0, d.value.max(0.0)),
    })
}

/// The clearance between one jet's plume and a part, m (0 when they touch): the value of
/// [`plume_clearance_bracket`].
pub fn plume_clearance(
    jet: &JetSpec,
    jet_frame: &Isometry3<f64>,
    part_pose: &Isometry3<f64>,
    part: &dyn rp::Shape,
    hull: Option<&super::mesh::HullSupport>,
) -> Option<f64> {
    plume_clearance_bracket(jet, jet_frame, part_pose, part, hull).map(|b| b.value)
}

/// A part [`plume_hits`] checks: `body/collider` name, pose, judged shape, and for a triangle
/// mesh its hull support map ([`super::monitor::mesh_hull`], made once with the part: its
/// distances then go through the monitor's shell and hull brackets).
#[derive(Clone)]
pub struct PlumeTarget {
    /// `body/collider`.
    pub name: String,
    /// Pose, in the frame of the `jet_frame` given to [`plume_hits`].
    pub pose: Isometry3<f64>,
    /// The judged shape.
    pub shape: rp::SharedShape,
    /// Hull support map of a triangle-mesh shape (`None` for a primitive; a mesh without it
    /// is judged by the exact triangle-mesh query alone).
    pub hull: Option<std::sync::Arc<super::mesh::HullSupport>>,
}

impl PlumeTarget {
    /// The part, with its hull support map when its shape is a triangle mesh.
    pub fn new(name: impl Into<String>, pose: Isometry3<f64>, shape: rp::SharedShape) -> Self {
        let hull = super::monitor::mesh_hull(&*shape);
        Self {
            name: name.into(),
            pose,
            shape,
            hull,
        }
    }
}

/// Every (firing jet, listed part) whose plume touches the part. `parts` are the other body's
/// colliders in the same frame as `jet_frame`; `patterns` select them by name (globs). A pair
/// counts as touching when the certified lower bound of its clearance
/// ([`plume_clearance_bracket`]) is 0: a plume within the f32 precision of a part is a hit,
/// never a false clearance (as [`PlumeKeepOff`] counts it).
pub fn plume_hits(
    jets: &[JetSpec],
    firing: &[bool],
    jet_frame: &Isometry3<f64>,
    parts: &[PlumeTarget],
    patterns: &[String],
) -> Vec<PlumeHit> {
    let mut out = Vec::new();
    for (j, on) in jets.iter().zip(firing) {
        if !on {
            continue;
        }
        for p in parts {
            if !patterns.iter().any(|pat| glob_match(pat, &p.name)) {
                continue;
            }
            if plume_clearance_bracket(j, jet_frame, &p.pose, &*p.shape, p.hull.as_deref())
                .is_some_and(|d| d.lower <= 0.0)
            {
                out.push(PlumeHit {
                    jet: j.name.clone(),
                    part: p.name.clone(),
                });
            }
        }
    }
    out
}

/// The impingement load of one jet's plume ([`crate::actuation::plume_load`]) on `parts`
/// (pose, shape; any frame, the jet's `jet_frame` in the same one) at thrust `thrust_n`, with
/// moments about `about`: parry ray casts (solid shapes, so a ray starting inside a part
/// strikes it at 0) from the nozzle along each ray of `rays`, the nearest part within the
/// plume's length taking the ray's flux (the lowest index on a tie). `PartLoad::part` indexes
/// `parts`. Nothing without a plume or thrust.
///
/// **Culling** (the same loads as [`plume_loads_all_rays`], which casts every ray against
/// every part: `tests/val_plume.rs` compares the two on random poses). Each part is enclosed in
/// its shape's bounding sphere (parry's, inflated by [`CULL_REL`] of its radius plus
/// [`CULL_ABS_M`], far above the f32 rounding of the pose, ray and shape). A part whose sphere
/// lies wholly outside the cone or beyond the plume's length is never cast against; for the
/// others, a ray is cast against a part only when it meets the part's sphere within the
/// plume's length and no nearer than the nearest strike found so far (found from the rays
/// within each part's angular cap seen from the nozzle, `ray_masks`). A ray that misses a
/// part's bounding sphere misses the part, and a strike is never nearer than the sphere's
/// entry point, so no strike the plain cast would find is skipped.
pub fn plume_loads(
    jet: &JetSpec,
    thrust_n: f64,
    jet_frame: &Isometry3<f64>,
    parts: &[(Isometry3<f64>, rp::SharedShape)],
    rays: &[crate::actuation::plume_load::PlumeRay],
    about: &Vector3<f64>,
) -> Vec<crate::actuation::plume_load::PartLoad> {
    let Some((apex, axis, alpha, len)) = plume_cone(jet) else {
        return Vec::new();
    };
    if thrust_n <= 0.0 {
        return Vec::new();
    }
    let apex = (jet_frame * nalgebra::Point3::from(apex)).coords;
    // As `plume_loads_all_rays` passes it (the grid's frame is built from it, bit for bit).
    let axis = jet_frame.rotation * axis;
    let unit_axis = axis.normalize();
    // The parts whose inflated bounding sphere (centre, radius) meets the cone.
    let mut cand: Vec<(usize, Vector3<f64>, f64)> = Vec::new();
    for (k, (pose, shape)) in parts.iter().enumerate() {
        let bs = shape.compute_local_bounding_sphere();
        let c = pose
            * nalgebra::Point3::new(
                f64::from(bs.center.x),
                f64::from(bs.center.y),
                f64::from(bs.center.z),
            );
        let r = f64::from(bs.radius) * (1.0 + CULL_REL) + CULL_ABS_M;
        if sphere_meets_cone(&(c.coords - apex), r, &unit_axis, alpha, len) {
            cand.push((k, c.coords, r));
        }
    }
    if cand.is_empty() {
        return Vec::new();
    }
    let masks = ray_masks(rays, &cand, &apex, &unit_axis);
    let words = cand.len().div_ceil(64);
    crate::actuation::plume_load::impingement(
        thrust_n,
        &apex,
        &axis,
        rays,
        len,
        about,
        |i, o, d, max| {
            // Candidates in index order: on a tie the lowest index keeps the ray.
            let mut best: Option<(f64, usize)> = None;
            for (w, bits) in masks[i * words..(i + 1) * words].iter().enumerate() {
                let mut m = *bits;
                while m != 0 {
                    let (k, c, r) = &cand[w * 64 + m.trailing_zeros() as usize];
                    m &= m - 1;
                    // The ray's entry into the sphere: o + d·t, |o + d·t − c| = r.
                    let oc = c - o;
                    let b = oc.dot(d);
                    let q = oc.norm_squared() - b * b;
                    if q > r * r {
                        continue;
                    }
                    let h = (r * r - q).sqrt();
                    let (entry, exit) = (b - h, b + h);
                    if exit < 0.0 || entry > max || best.is_some_and(|x| entry > x.0) {
                        continue;
                    }
                    let (pose, shape) = &parts[*k];
                    if let Some(t) = cast_part(pose, &**shape, o, d, max)
                        && best.is_none_or(|x| t < x.0)
                    {
                        best = Some((t, *k));
                    }
                }
            }
            best
        },
    )
}

/// Per ray of `rays` (cone frame, axis +z), a bit per candidate part (`cand`: index, sphere
/// centre and radius in the frame of `apex` and the unit `axis`), `cand.len().div_ceil(64)`
/// words a ray: set when the ray's direction lies within the part's angular cap seen from the
/// nozzle (the cone of directions that can meet its sphere, widened by 1e-6 rad for the
/// rounding of the ray's direction), or for every ray when the nozzle is inside the sphere.
/// Rays ordered by decreasing cos θ (as [`cone_rays`](crate::actuation::plume_load::cone_rays)
/// makes them) are only scanned over the band of cos θ the cap spans.
fn ray_masks(
    rays: &[crate::actuation::plume_load::PlumeRay],
    cand: &[(usize, Vector3<f64>, f64)],
    apex: &Vector3<f64>,
    axis: &Vector3<f64>,
) -> Vec<u64> {
    const WIDEN_RAD: f64 = 1e-6;
    let words = cand.len().div_ceil(64);
    let mut masks = vec![0u64; rays.len() * words];
    let (x, y) = crate::scene::parts::perpendicular_basis(axis);
    let sorted = rays.windows(2).all(|w| w[0].dir.z >= w[1].dir.z);
    for (n, (_, c, r)) in cand.iter().enumerate() {
        let (word, bit) = (n / 64, 1u64 << (n % 64));
        let v = c - apex;
        let dist = v.norm();
        if dist <= *r {
            for i in 0..rays.len() {
                masks[i * words + word] |= bit;
            }
            continue;
        }
        // The cap's centre in the cone frame, its angular radius β and the band of θ.
        let u = Vector3::new(v.dot(&x), v.dot(&y), v.dot(axis)) / dist;
        let beta = (r / dist).asin() + WIDEN_RAD;
        let cos_beta = beta.cos();
        let theta = u.z.clamp(-1.0, 1.0).acos();
        let (lo, hi) = if sorted {
            let z_max = (theta - beta).max(0.0).cos();
            let z_min = (theta + beta).min(std::f64::consts::PI).cos();
            (
                rays.partition_point(|p| p.dir.z > z_max),
                rays.partition_point(|p| p.dir.z >= z_min),
            )
        } else {
            (0, rays.len())
        };
        for (i, p) in rays.iter().enumerate().take(hi).skip(lo) {
            if p.dir.dot(&u) >= cos_beta {
                masks[i * words + word] |= bit;
            }
        }
    }
    masks
}

/// Relative inflation of a part's bounding sphere in [`plume_loads`]'s culling (f32 rounding
/// of the shape, pose and ray is ~1e-7 relative; this is 1e4 times that).
pub const CULL_REL: f64 = 1e-3;
/// Absolute inflation of a part's bounding sphere in [`plume_loads`]'s culling, m.
pub const CULL_ABS_M: f64 = 1e-3;

/// Whether the sphere of radius `r_m` centred at `c` (relative to the apex) meets the cone
/// of unit axis `axis`, half-angle `alpha_rad` and slant reach `len_m` (the points within
/// `len_m` of the apex at most `alpha_rad` off the axis): false only when it cannot.
fn sphere_meets_cone(
    c: &Vector3<f64>,
    r_m: f64,
    axis: &Vector3<f64>,
    alpha_rad: f64,
    len_m: f64,
) -> bool {
    let dist = c.norm();
    if dist <= r_m {
        return true;
    }
    if dist - r_m > len_m {
        return false;
    }
    // The angle of the centre off the axis less the sphere's angular radius.
    let theta = (c.dot(axis) / dist).clamp(-1.0, 1.0).acos();
    theta - (r_m / dist).asin() <= alpha_rad
}

/// parry's ray cast (solid) of the ray from `o` along unit `d` (the frame of `pose`) against
/// `shape` at `pose`, within `max_m`: the distance, m.
fn cast_part(
    pose: &Isometry3<f64>,
    shape: &dyn rp::Shape,
    o: &Vector3<f64>,
    d: &Vector3<f64>,
    max_m: f64,
) -> Option<f64> {
    use bevy_rapier3d::parry::query::Ray;
    use bevy_rapier3d::rapier::math::Vector as V;
    let lo = pose.inverse_transform_point(&nalgebra::Point3::from(*o));
    let ld = pose.rotation.inverse() * d;
    let ray = Ray::new(
        V::new(lo.x as f32, lo.y as f32, lo.z as f32),
        V::new(ld.x as f32, ld.y as f32, ld.z as f32),
    );
    shape
        .cast_local_ray(&ray, max_m as f32, true)
        .map(f64::from)
}

/// The reference for [`plume_loads`]: the same loads with every ray cast against every part
/// (no culling). Slow; for tests.
pub fn plume_loads_all_rays(
    jet: &JetSpec,
    thrust_n: f64,
    jet_frame: &Isometry3<f64>,
    parts: &[(Isometry3<f64>, rp::SharedShape)],
    rays: &[crate::actuation::plume_load::PlumeRay],
    about: &Vector3<f64>,
) -> Vec<crate::actuation::plume_load::PartLoad> {
    let Some((apex, axis, _, len)) = plume_cone(jet) else {
        return Vec::new();
    };
    if thrust_n <= 0.0 {
        return Vec::new();
    }
    let apex = jet_frame * nalgebra::Point3::from(apex);
    let axis = jet_frame.rotation * axis;
    crate::actuation::plume_load::impingement(
        thrust_n,
        &apex.coords,
        &axis,
        rays,
        len,
        about,
        |_, o, d, max| {
            let mut best: Option<(f64, usize)> = None;
            for (k, (pose, shape)) in parts.iter().enumerate() {
                if let Some(t) = cast_part(pose, &**shape, o, d, max)
                    && best.is_none_or(|b| t < b.0)
                {
                    best = Some((t, k));
                }
            }
            best
        },
    )
}

/// The jets of `body`'s `Rcs` actuators in a scene's controllers (the plumed ones).
fn scene_plumed_jets<'a>(controllers: &'a [ControllerSpec], body: &str) -> Vec<&'a JetSpec> {
    controllers
        .iter()
        .filter_map(|c| match &c.body {
            ControllerBody::Law(l) if l.body == body => match &l.actuator {
                ActuatorSpec::Rcs { jets, .. } => Some(jets),
                _ => None,
            },
            _ => None,
        })
        .flatten()
        .filter(|j| j.plume.is_some())
        .collect()
}

/// Radius about the centre of mass of a sphere holding a jet's plume as it is judged (the
/// pyramid of [`plume_shape`]), m: the nozzle's distance plus the pyramid's farthest point from
/// its apex, a base corner at √(L² + (L·tan α / cos(π/N))²) (the pyramid is the hull of its
/// apex and corners; the cone's slant length L/cos α is 7.5e-5·sin²α of it shorter).
pub fn plume_reach_m(j: &JetSpec) -> f64 {
    plume_cone(j).map_or(0.0, |(apex, _, alpha, len)| {
        let corner = len * alpha.tan() / (std::f64::consts::PI / f64::from(PLUME_SIDES)).cos();
        apex.norm() + len.hypot(corner)
    })
}

/// `PlumeKeepOff(name, body, around, parts: [...])`: no firing jet of `body`'s `Rcs`
/// actuators has its plume cone (half-angle α, length L from the nozzle, [`plume_shape`])
/// touching any listed part of `around`. `parts` are `*` globs matched against the collider
/// names of `around` (`wing_py.panel*`, or with the body: `target/solar_array_*`); each must
/// match at least one collider.
///
/// **Margin (m).** For every plumed jet j and listed part p, d_jp is the signed distance
/// between the cone and the part's judged shape (primitives and triangle meshes; parry's GJK
/// in f32 on the relative pose formed in f64; when they overlap, minus parry's penetration
/// depth, at least the f32 resolution of the pose, so a touch is a violation). While some
/// jet fires, the margin is the minimum of d_jp over the firing jets and the listed parts.
/// While none fires it is the minimum over every plumed jet of max(0, d_jp): the clearance
/// the nearest plume would have if its jet fired, 0 when a plume that is off points at a
/// part (one valve away from a violation) — never negative, so never a violation, and always
/// finite. A jet counts as firing for the whole step in which it delivers any impulse (the
/// actuator's flags: a pulse shorter than the step is counted over all of it —
/// conservative).
///
/// **Between samples.** The firing flags are constant over a step, so on a step the margin is
/// a minimum of distances between two rigid shapes, each fixed on its body: it changes at most
/// at |v_body − v_around| + Ω_body·R_plume + Ω_around·R_around (R_plume: the largest
/// [`plume_reach_m`], R_around: the extent of `around`), which the monitor uses to judge every
/// step interval. At a step's start the flags change, so the margin there is evaluated again
/// under the new flags ([`Guarantee::step_inputs`]).
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PlumeKeepOffParams {
    /// Guarantee name.
    pub name: String,
    /// The body whose jets fire.
    pub body: String,
    /// The body whose parts are kept out of the plumes.
    pub around: String,
    /// Collider name globs of `around`.
    pub parts: Vec<String>,
}

/// The colliders of `around` the patterns select, or the error at `parts.K`.
fn select_parts(
    patterns: &[String],
    around: &str,
    names: &[String],
) -> Result<Vec<usize>, BuildError> {
    if patterns.is_empty() || patterns.len() > 256 {
        return Err(BuildError::at("parts", "from 1 to 256 part patterns"));
    }
    let matches = |p: &str, n: &str| glob_match(p, n) || glob_match(p, &format!("{around}/{n}"));
    for (k, p) in patterns.iter().enumerate() {
        if !names.iter().any(|n| matches(p, n)) {
            return Err(BuildError::at(
                format!("parts.{k}"),
                format!(
                    "`{p}` matches no part of `{around}`; its parts: {}",
                    names.join(", ")
                ),
            ));
        }
    }
    Ok((0..names.len())
        .filter(|i| patterns.iter().any(|p| matches(p, &names[*i])))
        .collect())
}

impl GuaranteeParams for PlumeKeepOffParams {
    fn name(&self) -> &str {
        &self.name
    }
    fn bodies(&self) -> Vec<(&'static str, &str)> {
        vec![("body", &self.body), ("around", &self.around)]
    }
    fn check(&self, scene: &Scene) -> Result<(), BuildError> {
        if scene_plumed_jets(&scene.controllers, &self.body).is_empty() {
            return Err(BuildError::at(
                "body",
                format!(
                    "`{}` has no `Rcs` jet with a plume (a controller on it with actuator `Rcs(jets: [(…, plume: Some((half_angle_deg: …, length_m: …)))])`)",
                    self.body
                ),
            ));
        }
        let around = scene
            .bodies
            .iter()
            .find(|b| b.name == self.around)
            .ok_or_else(|| BuildError::at("around", "no such body"))?;
        let names: Vec<String> = crate::scene::parts::expand_body(around)
            .into_iter()
            .map(|c| c.name)
            .collect();
        select_parts(&self.parts, &self.around, &names).map(|_| ())
    }
    fn build(&self, ctx: &GuaranteeContext) -> Result<Box<dyn Guarantee>, BuildError> {
        let b = ctx.body("body", &self.body)?;
        let a = ctx.body("around", &self.around)?;
        let cols = &ctx.parts[a];
        let names: Vec<String> = cols.iter().map(|c| c.name.clone()).collect();
        let com = Vector3::from(ctx.scene.bodies[a].com_m);
        let mut parts = Vec::new();
        for i in select_parts(&self.parts, &self.around, &names)? {
            let c = &cols[i];
            let shape = super::build::primitive_shape(&c.shape).ok_or_else(|| {
                BuildError::at("parts", format!("part `{}` has no shape to judge", c.name))
            })?;
            parts.push(PlumePart {
                name: format!("{}/{}", self.around, c.name),
                pose_com: Isometry3::from_parts(
                    Translation3::from(-com),
                    UnitQuaternion::identity(),
                ) * c.pose_body,
                radius_m: c.shape.bounding_radius_m(),
                hull: super::monitor::mesh_hull(&*shape),
                shape,
            });
        }
        let reach = scene_plumed_jets(&ctx.scene.controllers, &self.body)
            .into_iter()
            .map(plume_reach_m)
            .fold(0.0, f64::max);
        Ok(Box::new(PlumeKeepOff {
            name: self.name.clone(),
            body: b,
            around: a,
            parts,
            reach_m: AtomicU64::new(reach.to_bits()),
        }))
    }
}

/// A listed part as [`PlumeKeepOff`] judges it.
#[derive(Clone)]
pub struct PlumePart {
    /// `body/collider`.
    pub name: String,
    /// Pose relative to the body's centre of mass, body axes.
    pub pose_com: Isometry3<f64>,
    /// Bounding radius about the shape's origin, m.
    pub radius_m: f64,
    /// The judged shape.
    pub shape: rp::SharedShape,
    /// For a triangle-mesh part, the support map of its vertices' convex hull
    /// ([`super::monitor::mesh_hull`]): its distances go through the monitor's hull bracket
    /// ([`pair_eval_shapes`]) before any triangle-by-triangle query.
    pub hull: Option<std::sync::Arc<super::mesh::HullSupport>>,
}

/// [`PlumeKeepOffParams`] as the monitor checks it.
pub struct PlumeKeepOff {
    /// Name.
    pub name: String,
    /// The body whose jets fire.
    pub body: usize,
    /// The body whose parts are kept out.
    pub around: usize,
    /// The listed parts.
    pub parts: Vec<PlumePart>,
    /// The largest [`plume_reach_m`] of the jets seen (f64 bits): the scene's at build, raised
    /// if a jet added later reaches further, before the rate bound of that step is asked.
    reach_m: AtomicU64,
}

/// The closest (jet, part) of a [`PlumeKeepOff`] evaluation.
#[derive(Debug, Clone, PartialEq)]
pub struct PlumeClosest {
    /// The margin's bracket, m.
    pub margin: Bracket,
    /// Jet name.
    pub jet: String,
    /// `body/collider`.
    pub part: String,
    /// The jet fires over the step.
    pub firing: bool,
}

impl PlumeKeepOff {
    /// The margin and the (jet, part) it comes from; `None` when `body` has no plumed jet in
    /// the view.
    pub fn closest(&self, v: &MonitorView) -> Option<PlumeClosest> {
        let jb = &v.bodies[self.body];
        let ab = &v.bodies[self.around];
        let jet_frame = Isometry3::from_parts(Translation3::from(jb.pos_m), jb.att);
        let around_frame = Isometry3::from_parts(Translation3::from(ab.pos_m), ab.att);
        let part_poses: Vec<Isometry3<f64>> = self
            .parts
            .iter()
            .map(|p| around_frame * p.pose_com)
            .collect();
        // Every (jet, part) with the lower bound of its distance from bounding spheres.
        let mut cones = Vec::new();
        let mut cand = Vec::new();
        let mut reach: f64 = 0.0;
        for jv in v.jets.iter().filter(|j| j.body == self.body) {
            for (k, j) in jv.jets.iter().enumerate() {
                let Some((apex, axis, alpha, len)) = plume_cone(j) else {
                    continue;
                };
                reach = reach.max(plume_reach_m(j));
                let (shape, pose) = plume_shape(&apex, &axis, alpha, len);
                let pose = jet_frame * pose;
                let r = plume_shape_radius_m(alpha, len);
                let firing = jv.firing.get(k).copied().unwrap_or(false);
                cones.push((j.name.as_str(), shape, pose, r, firing));
            }
        }
        // The firing jets; if none fires, every plumed jet, floored at 0.
        let any_firing = cones.iter().any(|c| c.4);
        for (c, (_, _, pose, r, firing)) in cones.iter().enumerate() {
            if any_firing && !firing {
                continue;
            }
            for (p, pp) in self.parts.iter().zip(&part_poses) {
                let lb = (pose.translation.vector - pp.translation.vector).norm() - r - p.radius_m;
                let lb = if *firing { lb } else { lb.max(0.0) };
                cand.push((lb, c, p, pp));
            }
        }
        let seen = f64::from_bits(self.reach_m.load(Ordering::Relaxed));
        if reach > seen {
            self.reach_m.store(reach.to_bits(), Ordering::Relaxed);
        }
        // Exact distances in order of the bound, until the bound passes the best value.
        cand.sort_by(|x, y| x.0.total_cmp(&y.0));
        let mut best: Option<PlumeClosest> = None;
        for (lb, c, p, pp) in cand {
            if best.as_ref().is_some_and(|b| lb >= b.margin.value) {
                break;
            }
            let (jet, cone, pose, r, firing) = &cones[c];
            // A mesh pair whose hull bracket proves it apart by at least the best margin so
            // far (when that is positive) cannot change the margin: its certified lower bound
            // is at least the best value, which is at least the best lower bound. Skip it.
            let clear_at = best
                .as_ref()
                .map(|b| b.margin.value)
                .filter(|v| *v > 0.0)
                .unwrap_or(f64::INFINITY);
            let Some(m) = signed_bracket(
                pose,
                &**cone,
                *r,
                pp,
                (&*p.shape, p.hull.as_deref()),
                p.radius_m,
                clear_at,
            ) else {
                continue;
            };
            let m = if *firing {
                m
            } else {
                Bracket {
                    value: m.value.max(0.0),
                    lower: m.lower.max(0.0),
                }
            };
            match &mut best {
                Some(b) => {
                    b.margin.lower = b.margin.lower.min(m.lower);
                    if m.value < b.margin.value {
                        b.margin.value = m.value;
                        b.jet = jet.to_string();
                        b.part = p.name.clone();
                        b.firing = *firing;
                    }
                }
                None => {
                    best = Some(PlumeClosest {
                        margin: m,
                        jet: jet.to_string(),
                        part: p.name.clone(),
                        firing: *firing,
                    });
                }
            }
        }
        best
    }
}

/// Signed distance between two shapes at f64 poses with a certified lower bound: parry's
/// distance bracket while apart ([`shape_bracket`]: GJK's distance, and the gap between the
/// shapes along its witness direction less the f32 resolution of the pose, which any axis
/// gives as a lower bound whatever GJK's accuracy; for a triangle-mesh `b` with its hull
/// support map `hb`, the monitor's evaluation [`pair_eval_shapes`]: the hull bracket where it
/// is as narrow as parry's exact query, else that query); when they overlap, minus
/// parry's penetration depth, at least that resolution (a touch within the precision is
/// counted as overlap: never reported clear). `None` when the hull bracket proves the pair at
/// least `clear_at` apart (only for a mesh `b`; never with an infinite `clear_at`).
fn signed_bracket(
    pose_a: &Isometry3<f64>,
    a: &dyn rp::Shape,
    ra: f64,
    pose_b: &Isometry3<f64>,
    (b, hb): (&dyn rp::Shape, Option<&super::mesh::HullSupport>),
    rb: f64,
    clear_at: f64,
) -> Option<Bracket> {
    let rel = pose_a.inv_mul(pose_b);
    let eps = F32_REL_TOL * (rel.translation.vector.norm() + ra + rb);
    let d = match hb {
        None => shape_bracket(pose_a, a, ra, pose_b, b, rb),
        Some(h) => match pair_eval_shapes(
            &(*pose_a, ra),
            (a, None),
            &(*pose_b, rb),
            (b, Some(h)),
            clear_at,
        ) {
            PairEval::Clear(_) => return None,
            PairEval::Value(value, lower) => Bracket {
                value,
                lower: lower.min(value),
            },
        },
    };
    if d.value > 0.0 {
        return Some(Bracket {
            value: d.value,
            lower: if d.lower > 0.0 { d.lower } else { -eps },
        });
    }
    let rel32 = super::conv::pose(&rel);
    let depth = match bevy_rapier3d::parry::query::contact(
        &bevy_rapier3d::rapier::math::Pose::IDENTITY,
        a,
        &rel32,
        b,
        0.0,
    ) {
        Ok(Some(c)) => -(c.dist as f64),
        _ => 0.0,
    };
    let value = -depth.max(eps);
    Some(Bracket {
        value,
        lower: value - eps,
    })
}

impl Guarantee for PlumeKeepOff {
    fn name(&self) -> &str {
        &self.name
    }
    /// See [`PlumeKeepOffParams`]. Without a plumed jet of `body` in the view (not possible
    /// for a scene's guarantee: the load refuses it) nothing can strike: the centre-of-mass
    /// range of the two bodies, a finite positive number.
    fn margin(&self, v: &MonitorView) -> f64 {
        self.margin_bracket(v).value
    }
    fn margin_bracket(&self, v: &MonitorView) -> Bracket {
        self.closest(v).map_or_else(
            || Bracket::exact((v.bodies[self.body].pos_m - v.bodies[self.around].pos_m).norm()),
            |c| c.margin,
        )
    }
    /// See [`PlumeKeepOffParams`].
    fn rate_bound(&self, m: &dyn MotionBounds) -> Option<f64> {
        let reach = f64::from_bits(self.reach_m.load(Ordering::Relaxed));
        Some(
            m.rel_speed_bound(self.body, self.around)
                + m.omega_bound(self.body) * reach
                + m.omega_bound(self.around) * m.extent_m(self.around),
        )
    }
    fn reads(&self) -> Reads {
        Reads::Bodies
    }
    /// parry's distances are f32 (≈ 1e-6 relative): refine to 10 µm.
    fn tolerance(&self) -> f64 {
        1e-5
    }
    fn detail(&self, v: &MonitorView) -> Option<serde_json::Value> {
        self.closest(v).map(|c| {
            serde_json::json!({"jet": c.jet, "part": c.part, "jet_firing": c.firing,
                "clearance_m": c.margin.value})
        })
    }
    fn step_inputs(&self) -> bool {
        true
    }
    /// While no jet of `body` fires the margin is ≥ 0 by construction.
    fn step_floor(&self, v: &MonitorView) -> Option<f64> {
        let firing = v.jets.iter().filter(|j| j.body == self.body).any(|j| {
            j.jets
                .iter()
                .zip(j.firing)
                .any(|(jet, on)| *on && jet.plume.is_some())
        });
        (!firing).then_some(0.0)
    }
}

#[cfg(test)]
mod tests {
    //! Reference: the analytic cone-to-box test. A cone with apex at the origin, axis +x,
    //! half-angle α, length L, and an axis-aligned box whose near face is the plane x = s
    //! (0 < s < L) spanning y ∈ [y₀, y₁], z ∈ [z₀, z₁], depth D: the cone's cross-section at
    //! x is the disc of radius x·tan α, widest inside the box at x_m = min(L, s + D); the box
    //! is struck iff the distance ρ from the axis to the rectangle [y₀, y₁] × [z₀, z₁] is below
    //! x_m·tan α (strict: touching at a point is a hit at distance 0, tested away from it by
    //! 1 mm either side); the clearance of a miss is dy·cos α, to parry's f32 GJK error against
    //! the plume pyramid (4e-4 m for 10 m shapes, `tests/val_plume.rs`) plus the pyramid's
    //! excess over the cone (7.6e-5 of the section's radius, [`plume_shape`]).
    use super::*;
    use crate::actuation::rcs::PlumeSpec;

    fn jet(alpha_deg: f64, len: f64) -> JetSpec {
        // Thrust along −x: the plume points along +x from the origin.
        JetSpec {
            name: "j1".into(),
            pos_m: [0.0, 0.0, 0.0],
            direction: [-1.0, 0.0, 0.0],
            max_thrust_n: 1.0,
            min_impulse_bit_ns: 0.0,
            plume: Some(PlumeSpec {
                half_angle_deg: alpha_deg,
                length_m: len,
            }),
        }
    }

    fn box_part(
        s: f64,
        depth: f64,
        y: (f64, f64),
        z: (f64, f64),
    ) -> (Isometry3<f64>, rp::SharedShape) {
        let half = Vector3::new(depth / 2.0, (y.1 - y.0) / 2.0, (z.1 - z.0) / 2.0);
        let c = Vector3::new(s + depth / 2.0, (y.0 + y.1) / 2.0, (z.0 + z.1) / 2.0);
        (
            Isometry3::translation(c.x, c.y, c.z),
            rp::SharedShape::cuboid(half.x as f32, half.y as f32, half.z as f32),
        )
    }

    #[test]
    fn val_plume_cone_to_box_hit_and_miss_match_the_closed_form() {
        let (alpha, len) = (15.0f64, 10.0);
        let j = jet(alpha, len);
        let t = alpha.to_radians().tan();
        let id = Isometry3::identity();
        for (s, depth) in [(2.0f64, 0.5), (6.0, 1.0), (9.5, 2.0)] {
            let xm = (s + depth).min(len);
            let rho = xm * t;
            for (dy, hit) in [(-1e-3, true), (1e-3, false)] {
                // A panel beside the axis: its edge nearest the axis at y = ρ + dy.
                let (pose, shape) = box_part(s, depth, (rho + dy, rho + dy + 1.0), (-0.5, 0.5));
                let d = plume_clearance(&j, &id, &pose, &*shape, None).unwrap();
                assert_eq!(
                    d <= 0.0,
                    hit,
                    "s {s}, edge at {} (ρ {rho}): clearance {d}",
                    rho + dy
                );
                if !hit {
                    // The gap to the cone's wall at x_m: dy·cos α (see the module's reference).
                    assert!(
                        (d - dy * alpha.to_radians().cos()).abs() < 4e-4 + 7.6e-5 * rho,
                        "s {s}: {d}"
                    );
                }
            }
        }
        // Beyond the plume's length: no hit even on the axis.
        let (pose, shape) = box_part(len + 1e-3, 1.0, (-0.5, 0.5), (-0.5, 0.5));
        assert!(plume_clearance(&j, &id, &pose, &*shape, None).unwrap() > 0.0);
        // Behind the nozzle: no hit.
        let (pose, shape) = box_part(-2.0, 1.0, (-0.5, 0.5), (-0.5, 0.5));
        assert!(plume_clearance(&j, &id, &pose, &*shape, None).unwrap() > 0.0);
    }

    #[test]
    fn val_plume_hits_name_jet_and_part_and_follow_globs() {
        let j = jet(10.0, 5.0);
        let (pose, shape) = box_part(2.0, 0.1, (-0.5, 0.5), (-0.5, 0.5));
        let parts = vec![
            PlumeTarget::new("target/solar_array_py_2", pose, shape.clone()),
            PlumeTarget::new("target/bus", Isometry3::translation(0.0, 5.0, 0.0), shape),
        ];
        let pats = vec!["target/solar_array_*".to_string()];
        let hits = plume_hits(
            std::slice::from_ref(&j),
            &[true],
            &Isometry3::identity(),
            &parts,
            &pats,
        );
        assert_eq!(
            hits,
            vec![PlumeHit {
                jet: "j1".into(),
                part: "target/solar_array_py_2".into()
            }]
        );
        assert!(
            plume_hits(
                std::slice::from_ref(&j),
                &[false],
                &Isometry3::identity(),
                &parts,
                &pats
            )
            .is_empty()
        );
        assert!(glob_match("*", "x") && glob_match("a*c", "abbc") && !glob_match("a*c", "abd"));
    }
}

/// Plume impingement loads applied in a run (docs/vehicles.md): for every firing jet of an `Rcs`
/// actuator with a plume, the load of [`plume_loads`] (the model of
/// [`crate::actuation::plume_load`], the default ray grid) on the parts of every other body,
/// added to the struck body's [`super::Wrench`] as a force through its centre of mass and the
/// moment about it, world frame.
///
/// - **Only the struck body.** The reaction on the firing body is not applied: the jet's
///   thrust already is the reaction to the momentum it emits, and the plume's own parts are
///   not cast against (a jet never strikes its own body).
/// - **First order in dt.** The load is computed once per step from the poses at the start of
///   the step and the jets' mean thrust over it, and held over the step like every other
///   force (zero-order hold); a part entering or leaving the plume within a step is counted
///   from the start-of-step geometry.
/// - **On an air-bearing table** a simulator floating on it takes the in-plane force and the
///   torque about the table's normal only ([`super::airbearing::add_planar`], as with the
///   controllers' forces); the air film carries the rest. A body that has run off the table
///   takes the whole load; an anchored one none (the table clears its wrench). The columns and
///   the summary report the whole load the plume puts on the part.
/// - **Switch.** An `Rcs` actuator with `plume_loads: false` applies none (default true).
/// - **No cost while nothing fires.** A step without a firing plumed jet only clears the
///   columns; a scene without plumed jets has no [`PlumeLoadState`] and no columns at all.
///
/// Outputs: per body the total plume force, world frame, in the trajectory columns
/// `BODY.plume_fx_n`, `BODY.plume_fy_n`, `BODY.plume_fz_n` (the load of the step that ends
/// at the row's time); per struck part (`body/collider`) in `summary.json` under
/// `plume_loads`: the peak |F| (N) and the start time of the step it acted over (s), the
/// impulse ∫|F| dt (N·s) and the vector impulse ∫F dt (N·s, world frame).
#[derive(bevy::prelude::Resource)]
pub struct PlumeLoadState {
    /// Every part of every body.
    parts: Vec<LoadPart>,
    /// Indices into `parts` per body.
    body_parts: Vec<Vec<usize>>,
    /// Per body: the largest distance of a part's bounding sphere from the centre of mass, m.
    extent_m: Vec<f64>,
    /// Per body: the columns fx, fy, fz.
    cols: Vec<[usize; 3]>,
    /// Ray grids by half-angle (f64 bits).
    rays: Vec<(u64, Vec<crate::actuation::plume_load::PlumeRay>)>,
    /// Per part: the force of the current step, N (world).
    now: Vec<Vector3<f64>>,
    /// Per part: the running statistics.
    stats: Vec<PartStats>,
    /// The columns hold a nonzero load (cleared on the next step without one).
    dirty: bool,
}

/// A part as the load casts rays against it.
struct LoadPart {
    name: String,
    /// Pose relative to the body's centre of mass, body axes.
    pose_com: Isometry3<f64>,
    radius_m: f64,
    shape: rp::SharedShape,
}

/// Running plume-load statistics of one part.
#[derive(Debug, Clone, Default)]
struct PartStats {
    struck: bool,
    peak_n: f64,
    peak_t_s: f64,
    impulse_abs_ns: f64,
    impulse_ns: Vector3<f64>,
}

/// Installs [`PlumeLoadState`] when some controller's `Rcs` actuator has a jet with a plume
/// (call after the controllers and the bodies are built): its columns start at 0.
pub fn install_loads(app: &mut bevy::prelude::App) {
    let w = app.world();
    let plumed = w
        .get_resource::<super::controllers::ControllerHost>()
        .is_some_and(|h| {
            h.slots.iter().any(|s| match &s.actuator.spec {
                ActuatorSpec::Rcs {
                    jets, plume_loads, ..
                } => *plume_loads && jets.iter().any(|j| j.plume.is_some()),
                _ => false,
            })
        });
    if !plumed {
        return;
    }
    let roster = w.resource::<super::Roster>();
    let mut parts = Vec::new();
    let mut body_parts = Vec::new();
    let mut extent_m = Vec::new();
    for (b, (be, pes)) in roster.bodies.iter().zip(&roster.parts).enumerate() {
        let com = w
            .get::<super::SimBody>(*be)
            .map_or_else(Vector3::zeros, |s| s.com_body_m);
        let to_com = Isometry3::from_parts(Translation3::from(-com), UnitQuaternion::identity());
        let mut idx = Vec::new();
        let mut ext: f64 = 0.0;
        for pe in pes {
            let Some(p) = w.get::<super::Part>(*pe) else {
                continue;
            };
            let pose_com = to_com * p.pose_body;
            ext = ext.max(pose_com.translation.vector.norm() + p.bound_radius_m);
            idx.push(parts.len());
            parts.push(LoadPart {
                name: format!("{}/{}", roster.names[b], p.name),
                pose_com,
                radius_m: p.bound_radius_m,
                shape: p.shape.clone(),
            });
        }
        body_parts.push(idx);
        extent_m.push(ext);
    }
    let names = roster.names.clone();
    let n = parts.len();
    let mut diag = app.world_mut().resource_mut::<super::output::Diagnostics>();
    let cols: Vec<[usize; 3]> = names
        .iter()
        .map(|b| {
            let c = ["fx", "fy", "fz"].map(|a| diag.column(&format!("{b}.plume_{a}_n")));
            for k in c {
                diag.values[k] = 0.0;
            }
            c
        })
        .collect();
    // The loads' system is in the schedule only with its resource (a scene without plumed
    // jets pays nothing for it).
    use bevy::prelude::IntoScheduleConfigs;
    app.add_systems(
        super::SimStep,
        plume_forces.in_set(super::Order::PlumeForces),
    );
    app.insert_resource(PlumeLoadState {
        parts,
        body_parts,
        extent_m,
        cols,
        rays: Vec::new(),
        now: vec![Vector3::zeros(); n],
        stats: vec![PartStats::default(); n],
        dirty: false,
    });
}

impl PlumeLoadState {
    /// `summary.json`'s `plume_loads`: every part struck so far (see [`PlumeLoadState`]).
    pub fn summary(&self) -> serde_json::Value {
        let m: serde_json::Map<String, serde_json::Value> = self
            .parts
            .iter()
            .zip(&self.stats)
            .filter(|(_, s)| s.struck)
            .map(|(p, s)| {
                (
                    p.name.clone(),
                    serde_json::json!({
                        "peak_force_n": s.peak_n,
                        "peak_t_s": s.peak_t_s,
                        "impulse_n_s": s.impulse_abs_ns,
                        "impulse_vector_world_n_s": [s.impulse_ns.x, s.impulse_ns.y, s.impulse_ns.z],
                    }),
                )
            })
            .collect();
        serde_json::Value::Object(m)
    }

    /// The ray grid of a cone of half-angle `alpha_rad` (made once).
    fn rays(&mut self, alpha_rad: f64) -> usize {
        let key = alpha_rad.to_bits();
        if let Some(k) = self.rays.iter().position(|r| r.0 == key) {
            return k;
        }
        use crate::actuation::plume_load::{DEFAULT_RINGS, DEFAULT_SECTORS, cone_rays};
        self.rays
            .push((key, cone_rays(alpha_rad, DEFAULT_RINGS, DEFAULT_SECTORS)));
        self.rays.len() - 1
    }
}

/// Actuate, after the controllers ([`super::Order::PlumeForces`]): the plume loads of the
/// jets firing over this step on the bodies they strike (see [`PlumeLoadState`]).
pub fn plume_forces(
    clock: bevy::prelude::Res<super::Clock>,
    roster: bevy::prelude::Res<super::Roster>,
    host: Option<bevy::prelude::Res<super::controllers::ControllerHost>>,
    state: Option<bevy::prelude::ResMut<PlumeLoadState>>,
    mut diag: bevy::prelude::ResMut<super::output::Diagnostics>,
    table: Option<bevy::prelude::Res<super::airbearing::AirBearing>>,
    mut q: bevy::prelude::Query<(&super::BodyState, &mut super::Wrench)>,
) {
    let (Some(host), Some(mut state)) = (host, state) else {
        return;
    };
    let st = &mut *state;
    // The firing plumed jets: (body, jet, mean thrust).
    let mut firing: Vec<(usize, &JetSpec, f64)> = Vec::new();
    for s in &host.slots {
        let (
            ActuatorSpec::Rcs {
                jets,
                plume_loads: true,
                ..
            },
            Some(u),
        ) = (&s.actuator.spec, s.report.jet_thrust_n.as_deref())
        else {
            continue;
        };
        for (j, u) in jets.iter().zip(u) {
            if *u > 0.0 && j.plume.is_some() {
                firing.push((s.body, j, *u));
            }
        }
    }
    if firing.is_empty() {
        if st.dirty {
            for c in st.cols.iter().flatten() {
                diag.values[*c] = 0.0;
            }
            st.dirty = false;
        }
        return;
    }
    let frames: Vec<Option<Isometry3<f64>>> = roster
        .bodies
        .iter()
        .map(|e| {
            q.get(*e)
                .ok()
                .map(|(s, _)| Isometry3::from_parts(Translation3::from(s.pos_m), s.att))
        })
        .collect();
    let nb = frames.len();
    let mut force = vec![Vector3::zeros(); nb];
    let mut torque = vec![Vector3::zeros(); nb];
    let mut touched: Vec<usize> = Vec::new();
    let mut cast: Vec<(Isometry3<f64>, rp::SharedShape)> = Vec::new();
    let mut cast_idx: Vec<usize> = Vec::new();
    for (fb, j, u) in firing {
        let (Some(Some(jf)), Some((apex, _, alpha, _))) = (frames.get(fb), plume_cone(j)) else {
            continue;
        };
        let reach = plume_reach_m(j);
        let nozzle = jf * nalgebra::Point3::from(apex);
        let ri = st.rays(alpha);
        for (b, bf) in frames.iter().enumerate() {
            let Some(bf) = bf else { continue };
            if b == fb
                || (bf.translation.vector - nozzle.coords).norm()
                    > reach - apex.norm() + st.extent_m[b]
            {
                continue;
            }
            cast.clear();
            cast_idx.clear();
            for &pi in &st.body_parts[b] {
                let p = &st.parts[pi];
                let pose = bf * p.pose_com;
                // The plume lies within its slant length of the nozzle.
                if (pose.translation.vector - nozzle.coords).norm()
                    > reach - apex.norm() + p.radius_m
                {
                    continue;
                }
                cast.push((pose, p.shape.clone()));
                cast_idx.push(pi);
            }
            if cast.is_empty() {
                continue;
            }
            let com = bf.translation.vector;
            for l in plume_loads(j, u, jf, &cast, &st.rays[ri].1, &com) {
                let pi = cast_idx[l.part];
                if st.now[pi] == Vector3::zeros() {
                    touched.push(pi);
                }
                st.now[pi] += l.force_n;
                force[b] += l.force_n;
                torque[b] += l.moment_nm;
            }
        }
    }
    let (t, dt) = (clock.t_s(), clock.h_s());
    touched.sort_unstable();
    touched.dedup();
    for pi in touched {
        let f = std::mem::take(&mut st.now[pi]);
        let s = &mut st.stats[pi];
        let m = f.norm();
        if !s.struck || m > s.peak_n {
            s.peak_n = m;
            s.peak_t_s = t;
        }
        s.struck = true;
        s.impulse_abs_ns += m * dt;
        s.impulse_ns += f * dt;
    }
    for (b, e) in roster.bodies.iter().enumerate() {
        for (k, c) in st.cols[b].iter().enumerate() {
            diag.values[*c] = force[b][k];
        }
        if force[b] == Vector3::zeros() && torque[b] == Vector3::zeros() {
            continue;
        }
        let Ok((_, mut w)) = q.get_mut(*e) else {
            continue;
        };
        // A simulator floating on an air-bearing table takes the in-plane part only.
        if table.as_ref().is_some_and(|t| t.supported[b]) {
            super::airbearing::add_planar(&mut w, &force[b], &torque[b]);
        } else {
            w.force_n += force[b];
            w.torque_nm += torque[b];
        }
    }
    st.dirty = true;
}
