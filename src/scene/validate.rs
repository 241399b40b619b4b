//! Physical validation of a parsed scene. Each failure names the field path (bodies and parts
//! by name) so the loader can point at its line and column.
//!
//! # Limits
//! Every count and every physical quantity has a documented range (the constants below, listed
//! in the README): counts so that no scene can exhaust memory or make `rpod check` quadratic in
//! a huge number, magnitudes so that every value stays far inside rapier's f32 range and its
//! products (m·v², I·ω) inside f64. The ranges are ours, chosen to contain every spacecraft and
//! lab testbed with margin (a space station is 4·10⁵ kg and 10⁸ kg·m²; a CubeSat part a few
//! grams); a value outside is refused with its field located.
//!
//! # Names
//! Body, part, port and guarantee names are identifiers: 1 to [`MAX_NAME_LEN`] characters from
//! `A–Z a–z 0–9 _ -`, the first a letter or `_`. Names become CSV column prefixes
//! (`chaser.px_m`), `body/part` labels in `closest_parts` and `contacts.csv`, `--set` path
//! segments (split at `.`, `[`, `]`; a leading digit would read as a list index) and JSON keys:
//! this set keeps every one of those unambiguous without quoting. Names are unique in their
//! list (bodies, parts of a body, ports of a body, guarantees).

use super::{AttitudeSpec, BodySpec, Environment, OrbitSpec, PartSpec, Scene, ShapeSpec, V3};
use crate::orbit::constants::R_EARTH_M;

pub(crate) type Check = Result<(), (String, String)>;

/// Most bodies in a scene.
pub const MAX_BODIES: usize = 64;
/// Most parts on one body.
pub const MAX_PARTS_PER_BODY: usize = 256;
/// Most ports on one body.
pub const MAX_PORTS_PER_BODY: usize = 64;
/// Most colliders in a scene (parts expanded: a wing is a boom and its panels, a slot its
/// walls and back plate).
pub const MAX_COLLIDERS: usize = 4096;
/// Most panels on one solar wing.
pub const MAX_PANELS: u32 = 64;
/// Most wall pieces of a docking slot.
pub const MAX_SLOT_SEGMENTS: u32 = 256;
/// Most boundary points of a superquadric prism end face.
pub const MAX_PRISM_SEGMENTS: u32 = 1024;
/// Most guarantees in a scene.
pub const MAX_GUARANTEES: usize = 256;
/// Most controllers in a scene (a few per body of [`MAX_BODIES`], with room to spare; checking
/// and building stay linear in the count).
pub const MAX_CONTROLLERS: usize = 4096;
/// Most rapier substeps per step.
pub const MAX_SUBSTEPS: u32 = 1000;
/// Longest fixed step, s. The reference orbit and the L2 formation centre are propagated in
/// substeps within each step, so a step of 10¹² s would run for hours inside one step (a hang
/// the fuzz harness found); the bundled scenes use at most 10 s.
pub const MAX_DT_S: f64 = 100.0;
/// Longest `stepping: MultiRate(max_step_s)`, s (a day: past it a reference orbit is not a
/// frame one step can be held in).
pub const MAX_MULTIRATE_STEP_S: f64 = 86_400.0;
/// Shortest fixed step, s (rapier's f32 step must stay a normal, invertible number).
pub const MIN_DT_S: f64 = 1e-6;
/// Most steps in one run (`duration_s / dt_s`): about four hours at the bench's 70 000 steps/s.
pub const MAX_STEPS: f64 = 1e9;
/// Longest body, part, port or guarantee name, characters.
pub const MAX_NAME_LEN: usize = 64;
/// Longest scene name, characters.
pub const MAX_SCENE_NAME_LEN: usize = 128;
/// Mass range, kg.
pub const MASS_RANGE_KG: (f64, f64) = (1e-6, 1e12);
/// Range of each principal moment of inertia, kg·m².
pub const INERTIA_RANGE_KG_M2: (f64, f64) = (1e-12, 1e18);
/// Range of every length of a part (sizes, radii, lengths, depths, thicknesses), m.
pub const SIZE_RANGE_M: (f64, f64) = (1e-6, 1e4);
/// Largest offset inside a body (part positions, ports, wing roots, centre of mass), m.
pub const MAX_BODY_OFFSET_M: f64 = 1e4;
/// Largest initial distance of a body from the world origin, m. rapier stores positions in
/// f32, which resolves r·6·10⁻⁸ m at a distance r (0.6 m here).
pub const MAX_POSITION_M: f64 = 1e7;
/// Largest initial speed, m/s.
pub const MAX_SPEED_M_S: f64 = 1e5;
/// Largest initial rate, deg/s (100 revolutions per second).
pub const MAX_RATE_DEG_S: f64 = 36_000.0;
/// Largest force a scene sets directly (magnet), N.
pub const MAX_FORCE_N: f64 = 1e9;
/// Largest table gravity, m/s².
pub const MAX_GRAVITY_M_S2: f64 = 1e3;
/// Largest reference orbit radius (apogee, or |r|), m.
pub const MAX_ORBIT_RADIUS_M: f64 = 1e10;
/// Largest friction coefficient.
pub const MAX_FRICTION: f64 = 100.0;

/// Checks an identifier name (body, part, port, guarantee); `None` when it is fine.
pub fn name_problem(name: &str) -> Option<String> {
    let n = name.chars().count();
    let mut chars = name.chars();
    let first_ok = chars
        .next()
        .is_some_and(|c| c.is_ascii_alphabetic() || c == '_');
    let rest_ok = name
        .chars()
        .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-');
    if n == 0 || n > MAX_NAME_LEN || !first_ok || !rest_ok {
        return Some(format!(
            "a name is 1 to {MAX_NAME_LEN} characters from A-Z a-z 0-9 _ -, starting with a \
             letter or _, got {name:?}"
        ));
    }
    None
}

/// Checks a name composed by a law or a user of scene names (`capture.p.e`): up to 4 names of
/// the one name rule ([`name_problem`]) joined by `.`; `None` when it is fine. A `.` separates
/// CSV column prefixes, so a composed name stays unambiguous in `trajectory.csv`.
pub fn composed_name_problem(name: &str) -> Option<String> {
    let parts: Vec<&str> = name.split('.').collect();
    if parts.len() > 4 {
        return Some(format!(
            "a composed name is at most 4 names joined by `.`, got {} in {name:?}",
            parts.len()
        ));
    }
    parts.iter().find_map(|p| {
        name_problem(p).map(|m| {
            if parts.len() > 1 {
                format!("in the composed name {name:?}: {m}")
            } else {
                m
            }
        })
    })
}

fn check_name(path: String, name: &str) -> Check {
    match name_problem(name) {
        Some(m) => Err((path, m)),
        None => Ok(()),
    }
}

/// A number for a message: plain in [1e-3, 1e6), else in exponent form (`1e308`, not 309
/// digits).
pub fn num(v: f64) -> String {
    if v == 0.0 || !v.is_finite() || (1e-3..1e6).contains(&v.abs()) {
        format!("{v}")
    } else {
        format!("{v:e}")
    }
}

pub(crate) fn in_range(path: &str, v: f64, (lo, hi): (f64, f64), unit: &str) -> Check {
    if !(v.is_finite() && v >= lo && v <= hi) {
        return fail(
            path,
            format!(
                "must be from {} to {} {unit}, got {}",
                num(lo),
                num(hi),
                num(v)
            ),
        );
    }
    Ok(())
}

fn bounded3(path: &str, v: &V3, max: f64, unit: &str) -> Check {
    finite3(path, v)?;
    // Scaled so that components near f64::MAX do not overflow the norm.
    let big = v.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    let n = if big > 0.0 {
        big * nalgebra::Vector3::from(*v).map(|x| x / big).norm()
    } else {
        0.0
    };
    if n.is_nan() || n > max {
        return fail(
            path,
            format!(
                "magnitude {} {unit} exceeds the limit of {} {unit}",
                num(n),
                num(max)
            ),
        );
    }
    Ok(())
}

fn size(path: &str, v: f64) -> Check {
    in_range(path, v, SIZE_RANGE_M, "m")
}

fn fail(path: impl Into<String>, msg: impl Into<String>) -> Check {
    Err((path.into(), msg.into()))
}

pub(crate) fn positive(path: &str, v: f64, unit: &str) -> Check {
    if !(v.is_finite() && v > 0.0) {
        return fail(
            path,
            format!("must be a positive number of {unit}, got {}", num(v)),
        );
    }
    Ok(())
}

fn finite3(path: &str, v: &V3) -> Check {
    if v.iter().any(|x| !x.is_finite()) {
        return fail(path, "must be finite");
    }
    Ok(())
}

/// Checks a scene; on failure returns `(field path, message)`: the scene's own fields, its
/// stepping, the counts, the environment, the bodies, the docking mechanism, the monitor and the
/// guarantees, in that order (the first failure is the one reported).
pub fn validate(s: &Scene) -> Check {
    validate_header(s)?;
    validate_stepping(s)?;
    validate_counts(s)?;
    validate_environment(s)?;
    validate_bodies(s)?;
    if let Some(d) = &s.docking {
        validate_docking(s, d)?;
    }
    if let Some(h) = s.monitor.horizon_m {
        positive("monitor.horizon_m", h, "metres")?;
    }
    for (i, g) in s.guarantees.iter().enumerate() {
        check_name(format!("guarantees.{i}.name"), g.name())?;
        if s.guarantees[..i].iter().any(|o| o.name() == g.name()) {
            return fail(
                format!("guarantees.{i}.name"),
                format!("duplicate guarantee name `{}`", g.name()),
            );
        }
    }
    for g in &s.guarantees {
        let p = format!("guarantees.{}", g.name());
        g.check(s).map_err(|e| {
            let e = e.within(&p);
            (e.field, e.message)
        })?;
    }
    Ok(())
}

/// The scene's name, step, duration, physics sub-steps and recording interval.
fn validate_header(s: &Scene) -> Check {
    if s.name.trim().is_empty() {
        return fail("name", "must not be empty");
    }
    if s.name.chars().count() > MAX_SCENE_NAME_LEN || s.name.chars().any(char::is_control) {
        return fail(
            "name",
            format!(
                "a scene name is at most {MAX_SCENE_NAME_LEN} characters, without control \
                 characters (newlines, tabs)"
            ),
        );
    }
    positive("dt_s", s.dt_s, "seconds")?;
    if s.dt_s > MAX_DT_S || s.dt_s < MIN_DT_S {
        return fail(
            "dt_s",
            format!(
                "must be from {} s to at most {MAX_DT_S} s, got {}",
                num(MIN_DT_S),
                num(s.dt_s)
            ),
        );
    }
    positive("duration_s", s.duration_s, "seconds")?;
    check_steps("duration_s", s.duration_s, s.dt_s)?;
    if s.physics_substeps == 0 || s.physics_substeps > MAX_SUBSTEPS {
        return fail(
            "physics_substeps",
            format!(
                "must be from 1 to {MAX_SUBSTEPS}, got {}",
                s.physics_substeps
            ),
        );
    }
    if s.record_every_steps == 0 {
        return fail("record_every_steps", "must be at least 1");
    }
    Ok(())
}

/// `stepping: MultiRate(...)`: the longest step and the tolerances.
fn validate_stepping(s: &Scene) -> Check {
    if let crate::scene::Stepping::MultiRate {
        max_step_s,
        tol_m,
        tol_rad,
    } = &s.stepping
    {
        positive("stepping.max_step_s", *max_step_s, "seconds")?;
        if !(*max_step_s >= s.dt_s && *max_step_s <= MAX_MULTIRATE_STEP_S) {
            return fail(
                "stepping.max_step_s",
                format!(
                    "must be from dt_s ({} s) to {} s, got {}",
                    num(s.dt_s),
                    num(MAX_MULTIRATE_STEP_S),
                    num(*max_step_s)
                ),
            );
        }
        for (field, v, lo, hi, unit) in [
            ("stepping.tol_m", *tol_m, 1e-15, 1.0, "m"),
            ("stepping.tol_rad", *tol_rad, 1e-15, 1e-2, "rad"),
        ] {
            if !(v >= lo && v <= hi) {
                return fail(
                    field,
                    format!(
                        "must be from {} {unit} to {} {unit}, got {}",
                        num(lo),
                        num(hi),
                        num(v)
                    ),
                );
            }
        }
    }
    Ok(())
}

/// At most [`MAX_BODIES`] bodies, [`MAX_GUARANTEES`] guarantees, [`MAX_CONTROLLERS`]
/// controllers.
fn validate_counts(s: &Scene) -> Check {
    if s.bodies.len() > MAX_BODIES {
        return fail(
            "bodies",
            format!("at most {MAX_BODIES} bodies, got {}", s.bodies.len()),
        );
    }
    if s.guarantees.len() > MAX_GUARANTEES {
        return fail(
            "guarantees",
            format!(
                "at most {MAX_GUARANTEES} guarantees, got {}",
                s.guarantees.len()
            ),
        );
    }
    if s.controllers.len() > MAX_CONTROLLERS {
        return fail(
            "controllers",
            format!(
                "at most {MAX_CONTROLLERS} controllers, got {}",
                s.controllers.len()
            ),
        );
    }
    Ok(())
}

/// The environment: an orbit above the Earth and below the radius limit, a table's size, tilt,
/// friction and anchored bodies, the L2 model's own checks.
fn validate_environment(s: &Scene) -> Check {
    match &s.environment {
        Environment::Orbit { reference, .. } => match reference {
            OrbitSpec::Elements { a_m, e, .. } => {
                positive("environment.reference.a_m", *a_m, "metres")?;
                if !(e.is_finite() && (0.0..1.0).contains(e)) {
                    return fail(
                        "environment.reference.e",
                        format!("eccentricity must be in [0, 1), got {e}"),
                    );
                }
                if a_m * (1.0 - e) <= R_EARTH_M {
                    return fail(
                        "environment.reference.a_m",
                        format!(
                            "perigee radius {:.0} m is inside the Earth (R = {R_EARTH_M:.0} m)",
                            a_m * (1.0 - e)
                        ),
                    );
                }
                if a_m * (1.0 + e) > MAX_ORBIT_RADIUS_M {
                    return fail(
                        "environment.reference.a_m",
                        format!(
                            "apogee radius {:e} m exceeds the limit of {MAX_ORBIT_RADIUS_M:e} m",
                            a_m * (1.0 + e)
                        ),
                    );
                }
            }
            OrbitSpec::State { r_eci_m, v_eci_m_s } => {
                validate_state_orbit(r_eci_m, v_eci_m_s)?;
            }
        },
        Environment::FreeSpace => {}
        Environment::AirBearing(t) => {
            for k in 0..2 {
                size(
                    &format!("environment.0.table_size_m.{k}"),
                    t.table_size_m[k],
                )?;
                if !(t.table_corner_m[k].is_finite() && t.table_corner_m[k].abs() <= MAX_POSITION_M)
                {
                    return fail(
                        format!("environment.0.table_corner_m.{k}"),
                        format!("must be finite and within {MAX_POSITION_M:e} m of the origin"),
                    );
                }
                if !(t.tilt_deg[k].is_finite() && t.tilt_deg[k].abs() < 45.0) {
                    return fail(
                        format!("environment.0.tilt_deg.{k}"),
                        format!(
                            "a table tilt must be finite and below 45°, got {}",
                            t.tilt_deg[k]
                        ),
                    );
                }
            }
            size("environment.0.table_thickness_m", t.table_thickness_m)?;
            in_range(
                "environment.0.gravity_m_s2",
                t.gravity_m_s2,
                (1e-6, MAX_GRAVITY_M_S2),
                "m/s²",
            )?;
            for (f, v) in [
                ("coulomb_friction", t.coulomb_friction),
                ("viscous_drag_n_s_m", t.viscous_drag_n_s_m),
                ("viscous_drag_nm_s_rad", t.viscous_drag_nm_s_rad),
            ] {
                if !(v.is_finite() && v >= 0.0) {
                    return fail(
                        format!("environment.0.{f}"),
                        format!("must be a finite non-negative number, got {v}"),
                    );
                }
            }
            for (i, n) in t.anchored.iter().enumerate() {
                if !s.bodies.iter().any(|b| &b.name == n) {
                    return fail(
                        format!("environment.0.anchored.{i}"),
                        format!("no body named `{n}`"),
                    );
                }
            }
        }
        Environment::SunEarthL2(spec) => spec
            .validate()
            .map_err(|(f, m)| (format!("environment.0.{f}"), m))?,
    }
    Ok(())
}

/// At least one body; each body's name (unique), its own fields, its initial spin against the
/// step (unless under-resolved spins are allowed), and the scene's collider count.
fn validate_bodies(s: &Scene) -> Check {
    if s.bodies.is_empty() {
        return fail("bodies", "a scene needs at least one body");
    }
    let mut colliders = 0usize;
    for (i, b) in s.bodies.iter().enumerate() {
        check_name(format!("bodies.{i}.name"), &b.name)?;
        if s.bodies[..i].iter().any(|o| o.name == b.name) {
            return fail(
                format!("bodies.{i}.name"),
                format!("duplicate body name `{}`", b.name),
            );
        }
        validate_body(b)?;
        let rate_rad_s = nalgebra::Vector3::from(b.initial.rate_body_deg_s)
            .norm()
            .to_radians();
        let turn_rad = rate_rad_s * s.dt_s;
        if turn_rad > crate::math::rigid::UNDER_RESOLVED_TURN_RAD && !s.monitor.allow_under_resolved
        {
            return fail(
                format!("bodies.{}.initial.rate_body_deg_s", b.name),
                format!(
                    "{} rad/s turns the body {} rad in one step of {} s, more than the {} rad \
                     over which the monitor's rate bounds are proven: no guarantee could be held \
                     and the run would be tens of times slower near contact; use dt_s ≤ {} s, or \
                     set monitor: (allow_under_resolved: true) to run it anyway",
                    num(rate_rad_s),
                    num(turn_rad),
                    num(s.dt_s),
                    num(crate::math::rigid::UNDER_RESOLVED_TURN_RAD),
                    num(crate::math::rigid::UNDER_RESOLVED_TURN_RAD / rate_rad_s)
                ),
            );
        }
        colliders += b.parts.iter().map(collider_count).sum::<usize>();
        if colliders > MAX_COLLIDERS {
            return fail(
                format!("bodies.{}.parts", b.name),
                format!(
                    "the scene has more than {MAX_COLLIDERS} colliders up to this body (parts \
                     expanded: wings into boom and panels, slots into walls and back plate)"
                ),
            );
        }
    }
    Ok(())
}

/// `duration / dt` steps must not exceed [`MAX_STEPS`].
pub fn check_steps(path: &str, duration_s: f64, dt_s: f64) -> Check {
    let steps = duration_s / dt_s;
    if steps.is_nan() || steps > MAX_STEPS {
        return fail(
            path,
            format!(
                "{} s at dt = {} s is {} steps, more than the limit of {MAX_STEPS:e} steps per \
                 run",
                num(duration_s),
                num(dt_s),
                num(steps)
            ),
        );
    }
    Ok(())
}

/// A reference orbit given as an ECI state must be a bound, non-degenerate orbit whose perigee
/// is above the Earth, like one given by elements: r and v not parallel (else there is no orbit
/// plane and the Hill frame is undefined), negative energy (e < 1).
fn validate_state_orbit(r_eci_m: &V3, v_eci_m_s: &V3) -> Check {
    use crate::orbit::constants::MU_EARTH_M3_S2;
    bounded3(
        "environment.reference.r_eci_m",
        r_eci_m,
        MAX_ORBIT_RADIUS_M,
        "m",
    )?;
    bounded3(
        "environment.reference.v_eci_m_s",
        v_eci_m_s,
        MAX_SPEED_M_S,
        "m/s",
    )?;
    let r = nalgebra::Vector3::from(*r_eci_m);
    let v = nalgebra::Vector3::from(*v_eci_m_s);
    let rn = r.norm();
    if rn <= R_EARTH_M {
        return fail(
            "environment.reference.r_eci_m",
            format!("|r| = {rn:.0} m is inside the Earth"),
        );
    }
    let h = r.cross(&v).norm();
    if h.is_nan() || h <= 1e-9 * rn * v.norm() || v.norm() == 0.0 {
        return fail(
            "environment.reference.v_eci_m_s",
            "degenerate orbit: the velocity is zero or parallel to r (a radial trajectory has \
             no orbit plane, so the Hill frame is undefined)",
        );
    }
    let energy = v.norm_squared() / 2.0 - MU_EARTH_M3_S2 / rn;
    if energy >= 0.0 {
        return fail(
            "environment.reference.v_eci_m_s",
            format!(
                "the state is not a bound orbit (specific energy {energy:.1} J/kg ≥ 0: e ≥ 1); \
                 the reference orbit must be an ellipse"
            ),
        );
    }
    let a = -MU_EARTH_M3_S2 / (2.0 * energy);
    let e = (1.0 - h * h / (MU_EARTH_M3_S2 * a)).max(0.0).sqrt();
    if a * (1.0 - e) <= R_EARTH_M {
        return fail(
            "environment.reference.v_eci_m_s",
            format!(
                "perigee radius {:.0} m is inside the Earth (R = {R_EARTH_M:.0} m)",
                a * (1.0 - e)
            ),
        );
    }
    if a * (1.0 + e) > MAX_ORBIT_RADIUS_M {
        return fail(
            "environment.reference.v_eci_m_s",
            format!(
                "apogee radius {:e} m exceeds the limit of {MAX_ORBIT_RADIUS_M:e} m",
                a * (1.0 + e)
            ),
        );
    }
    Ok(())
}

/// Colliders a part expands into (without expanding it).
pub fn collider_count(p: &PartSpec) -> usize {
    match p {
        PartSpec::SolarWing {
            boom_length_m,
            panel_count,
            ..
        } => *panel_count as usize + usize::from(*boom_length_m > 0.0),
        PartSpec::DockingSlot { segments, .. } => *segments as usize + 1,
        _ => 1,
    }
}

fn validate_attitude(path: &str, a: &AttitudeSpec) -> Check {
    match *a {
        AttitudeSpec::Quat { w, x, y, z } => {
            let n = (w * w + x * x + y * y + z * z).sqrt();
            if !(n.is_finite() && n > 1e-9) {
                return fail(path, "quaternion must be finite and non-zero");
            }
        }
        AttitudeSpec::EulerZyxDeg { yaw, pitch, roll } => {
            if ![yaw, pitch, roll].iter().all(|v| v.is_finite()) {
                return fail(path, "angles must be finite");
            }
        }
    }
    Ok(())
}

fn validate_body(b: &BodySpec) -> Check {
    let p = format!("bodies.{}", b.name);
    if b.mass_kg.is_nan() && !b.mass_from_meshes {
        return fail(
            format!("{p}.mass_kg"),
            "missing: state mass_kg and inertia_kg_m2, or set mass_from_meshes: true",
        );
    }
    // Mass properties from meshes are checked once the loader has computed them.
    let mass_pending = b.mass_from_meshes && b.mass_kg.is_nan();
    if !mass_pending {
        validate_mass(&p, b)?;
    }
    bounded3(
        &format!("{p}.initial.pos_m"),
        &b.initial.pos_m,
        MAX_POSITION_M,
        "m",
    )?;
    bounded3(
        &format!("{p}.initial.vel_m_s"),
        &b.initial.vel_m_s,
        MAX_SPEED_M_S,
        "m/s",
    )?;
    bounded3(
        &format!("{p}.initial.rate_body_deg_s"),
        &b.initial.rate_body_deg_s,
        MAX_RATE_DEG_S,
        "deg/s",
    )?;
    validate_body_rest(&p, b)
}

fn validate_mass(p: &str, b: &BodySpec) -> Check {
    positive(&format!("{p}.mass_kg"), b.mass_kg, "kilograms")?;
    if b.inertia_kg_m2.xx.is_nan() && !b.mass_from_meshes {
        return fail(
            format!("{p}.inertia_kg_m2"),
            "missing: state the inertia tensor (or set mass_from_meshes: true)",
        );
    }
    in_range(&format!("{p}.mass_kg"), b.mass_kg, MASS_RANGE_KG, "kg")?;
    if !(b.friction.is_finite() && b.friction >= 0.0 && b.friction <= MAX_FRICTION) {
        return fail(
            format!("{p}.friction"),
            format!("must be from 0 to {MAX_FRICTION}"),
        );
    }
    if !(b.restitution.is_finite() && (0.0..=1.0).contains(&b.restitution)) {
        return fail(format!("{p}.restitution"), "must be in [0, 1]");
    }
    bounded3(&format!("{p}.com_m"), &b.com_m, MAX_BODY_OFFSET_M, "m")?;
    let j = b.inertia_kg_m2.matrix();
    let (lo, hi) = INERTIA_RANGE_KG_M2;
    // Elements beyond the range are refused before the eigen-decomposition, whose products
    // would overflow.
    if j.iter().any(|v| !(v.is_finite() && v.abs() <= hi)) {
        return fail(
            format!("{p}.inertia_kg_m2"),
            format!("every element must be finite and at most {hi:e} kg·m² in magnitude"),
        );
    }
    let eig = j.symmetric_eigenvalues();
    let mut ev: Vec<f64> = eig.iter().copied().collect();
    ev.sort_by(f64::total_cmp);
    if ev.iter().any(|v| !v.is_finite()) || ev[0] <= 0.0 {
        return fail(
            format!("{p}.inertia_kg_m2"),
            format!(
                "inertia tensor must be positive definite; principal moments {:.6}, {:.6}, {:.6} kg·m²",
                ev[0], ev[1], ev[2]
            ),
        );
    }
    if ev[0] < lo {
        return fail(
            format!("{p}.inertia_kg_m2"),
            format!(
                "the smallest principal moment {:e} kg·m² is below the limit of {lo:e} kg·m² \
                 (rapier's f32 solver and the inverse inertia need it)",
                ev[0]
            ),
        );
    }
    // Triangle inequality of a physical body: I1 + I2 ≥ I3 (relative tolerance for rounding).
    if ev[0] + ev[1] < ev[2] * (1.0 - 1e-9) {
        return fail(
            format!("{p}.inertia_kg_m2"),
            format!(
                "principal moments {:.6} + {:.6} < {:.6} kg·m² violate the triangle inequality: no physical body has this inertia",
                ev[0], ev[1], ev[2]
            ),
        );
    }
    Ok(())
}

fn validate_body_rest(p: &str, b: &BodySpec) -> Check {
    validate_attitude(&format!("{p}.initial.attitude"), &b.initial.attitude)?;
    if b.ports.len() > MAX_PORTS_PER_BODY {
        return fail(
            format!("{p}.ports"),
            format!(
                "at most {MAX_PORTS_PER_BODY} ports on a body, got {}",
                b.ports.len()
            ),
        );
    }
    for (i, port) in b.ports.iter().enumerate() {
        check_name(format!("{p}.ports.{i}.name"), &port.name)?;
        let pp = format!("{p}.ports.{}", port.name);
        if b.ports[..i].iter().any(|o| o.name == port.name) {
            return fail(format!("{p}.ports.{i}.name"), "duplicate port name");
        }
        bounded3(&format!("{pp}.pos_m"), &port.pos_m, MAX_BODY_OFFSET_M, "m")?;
        let n = nalgebra::Vector3::from(port.axis).norm();
        if !(n.is_finite() && n > 1e-9) {
            return fail(format!("{pp}.axis"), "must be a non-zero direction");
        }
    }
    if b.parts.is_empty() {
        return fail(format!("{p}.parts"), "a body needs at least one part");
    }
    if b.parts.len() > MAX_PARTS_PER_BODY {
        return fail(
            format!("{p}.parts"),
            format!(
                "at most {MAX_PARTS_PER_BODY} parts on a body, got {}",
                b.parts.len()
            ),
        );
    }
    for (i, part) in b.parts.iter().enumerate() {
        check_name(format!("{p}.parts.{i}.name"), part.name())?;
        let pp = format!("{p}.parts.{}", part.name());
        if b.parts[..i].iter().any(|o| o.name() == part.name()) {
            return fail(format!("{p}.parts.{i}.name"), "duplicate part name");
        }
        validate_part(&pp, b, part)?;
    }
    Ok(())
}

fn validate_shape(path: &str, s: &ShapeSpec) -> Check {
    match s {
        ShapeSpec::Box { size_m } => {
            for (k, v) in size_m.iter().enumerate() {
                positive(&format!("{path}.size_m.{k}"), *v, "metres")?;
                size(&format!("{path}.size_m.{k}"), *v)?;
            }
        }
        ShapeSpec::Cylinder {
            radius_m, length_m, ..
        } => {
            positive(&format!("{path}.radius_m"), *radius_m, "metres")?;
            positive(&format!("{path}.length_m"), *length_m, "metres")?;
            size(&format!("{path}.radius_m"), *radius_m)?;
            size(&format!("{path}.length_m"), *length_m)?;
        }
        ShapeSpec::Sphere { radius_m } => {
            positive(&format!("{path}.radius_m"), *radius_m, "metres")?;
            size(&format!("{path}.radius_m"), *radius_m)?;
        }
        ShapeSpec::SuperquadricPrism {
            a_m,
            b_m,
            s,
            height_m,
            segments,
        } => {
            for (f, v) in [("a_m", a_m), ("b_m", b_m), ("height_m", height_m)] {
                positive(&format!("{path}.{f}"), *v, "metres")?;
                size(&format!("{path}.{f}"), *v)?;
            }
            if !(s.is_finite() && *s >= 0.5 && *s <= 1e6) {
                return fail(
                    format!("{path}.s"),
                    format!(
                        "the exponent must be from 0.5 (a convex cross-section) to 1e6, got {s}"
                    ),
                );
            }
            if !(8..=MAX_PRISM_SEGMENTS).contains(segments) {
                return fail(
                    format!("{path}.segments"),
                    format!("from 8 to {MAX_PRISM_SEGMENTS} boundary points, got {segments}"),
                );
            }
        }
        ShapeSpec::Mesh {
            path: file,
            scale,
            nodes,
            max_triangles,
            decomposition,
            density_kg_m3,
            ..
        } => {
            if file.is_empty() {
                return fail(format!("{path}.path"), "must name a mesh file");
            }
            if crate::geometry::mesh::MeshFormat::of(std::path::Path::new(file)).is_none() {
                return fail(
                    format!("{path}.path"),
                    format!(
                        "`{file}`: unknown mesh extension (expected .obj, .stl, .gltf or .glb)"
                    ),
                );
            }
            if !(scale.is_finite() && *scale > 0.0 && *scale <= 1e6) {
                return fail(
                    format!("{path}.scale"),
                    format!("must be positive and at most 1e6, got {scale}"),
                );
            }
            for (k, n) in nodes.iter().enumerate() {
                if nodes[..k].contains(n) {
                    return fail(
                        format!("{path}.nodes.{k}"),
                        format!("`{n}` is listed twice"),
                    );
                }
            }
            if !(1..=MAX_MESH_TRIANGLES).contains(max_triangles) {
                return fail(
                    format!("{path}.max_triangles"),
                    format!("from 1 to {MAX_MESH_TRIANGLES}, got {max_triangles}"),
                );
            }
            let d = decomposition;
            if !(d.concavity.is_finite() && d.concavity >= 0.0 && d.concavity <= 1.0) {
                return fail(
                    format!("{path}.decomposition.concavity"),
                    format!("must be from 0 to 1, got {}", d.concavity),
                );
            }
            if !(16..=512).contains(&d.resolution) {
                return fail(
                    format!("{path}.decomposition.resolution"),
                    format!("must be from 16 to 512 voxels, got {}", d.resolution),
                );
            }
            if !(1..=4096).contains(&d.max_convex_hulls) {
                return fail(
                    format!("{path}.decomposition.max_convex_hulls"),
                    format!("must be from 1 to 4096, got {}", d.max_convex_hulls),
                );
            }
            if let Some(rho) = density_kg_m3 {
                in_range(&format!("{path}.density_kg_m3"), *rho, (1e-3, 1e5), "kg/m³")?;
            }
        }
    }
    Ok(())
}

/// Most triangles a mesh part may state as its limit.
pub const MAX_MESH_TRIANGLES: u32 = 2_000_000;

fn validate_part(pp: &str, b: &BodySpec, part: &PartSpec) -> Check {
    let port_exists = |n: &str| b.ports.iter().any(|p| p.name == n);
    match part {
        PartSpec::Bus {
            shape,
            pos_m,
            attitude,
            ..
        }
        | PartSpec::Antenna {
            shape,
            pos_m,
            attitude,
            ..
        } => {
            validate_shape(&format!("{pp}.shape"), shape)?;
            bounded3(&format!("{pp}.pos_m"), pos_m, MAX_BODY_OFFSET_M, "m")?;
            validate_attitude(&format!("{pp}.attitude"), attitude)?;
        }
        PartSpec::SolarWing {
            root_m,
            direction,
            width_axis,
            boom_length_m,
            boom_radius_m,
            panel_count,
            panel_size_m,
            panel_thickness_m,
            panel_gap_m,
            cant_deg,
            ..
        } => {
            bounded3(&format!("{pp}.root_m"), root_m, MAX_BODY_OFFSET_M, "m")?;
            if direction.vector().dot(&width_axis.vector()).abs() > 0.5 {
                return fail(
                    format!("{pp}.width_axis"),
                    "must be perpendicular to `direction`",
                );
            }
            if !(boom_length_m.is_finite()
                && *boom_length_m >= 0.0
                && *boom_length_m <= SIZE_RANGE_M.1)
            {
                return fail(
                    format!("{pp}.boom_length_m"),
                    format!("must be from 0 to {:e} m", SIZE_RANGE_M.1),
                );
            }
            if *boom_length_m > 0.0 {
                positive(&format!("{pp}.boom_radius_m"), *boom_radius_m, "metres")?;
                size(&format!("{pp}.boom_radius_m"), *boom_radius_m)?;
            }
            if *panel_count == 0 || *panel_count > MAX_PANELS {
                return fail(
                    format!("{pp}.panel_count"),
                    format!("must be from 1 to {MAX_PANELS}, got {panel_count}"),
                );
            }
            positive(&format!("{pp}.panel_size_m.0"), panel_size_m[0], "metres")?;
            positive(&format!("{pp}.panel_size_m.1"), panel_size_m[1], "metres")?;
            size(&format!("{pp}.panel_size_m.0"), panel_size_m[0])?;
            size(&format!("{pp}.panel_size_m.1"), panel_size_m[1])?;
            positive(
                &format!("{pp}.panel_thickness_m"),
                *panel_thickness_m,
                "metres",
            )?;
            size(&format!("{pp}.panel_thickness_m"), *panel_thickness_m)?;
            if !(panel_gap_m.is_finite() && *panel_gap_m >= 0.0 && *panel_gap_m <= SIZE_RANGE_M.1) {
                return fail(
                    format!("{pp}.panel_gap_m"),
                    format!("must be from 0 to {:e} m", SIZE_RANGE_M.1),
                );
            }
            if !cant_deg.is_finite() {
                return fail(format!("{pp}.cant_deg"), "must be finite");
            }
        }
        PartSpec::DockingCone {
            port,
            base_radius_m,
            tip_radius_m,
            length_m,
            ..
        } => {
            if !port_exists(port) {
                return fail(format!("{pp}.port"), format!("no port named `{port}`"));
            }
            for (f, v) in [
                ("base_radius_m", base_radius_m),
                ("tip_radius_m", tip_radius_m),
                ("length_m", length_m),
            ] {
                positive(&format!("{pp}.{f}"), *v, "metres")?;
                size(&format!("{pp}.{f}"), *v)?;
            }
            if tip_radius_m > base_radius_m {
                return fail(
                    format!("{pp}.tip_radius_m"),
                    "must not exceed base_radius_m",
                );
            }
        }
        PartSpec::DockingSlot {
            port,
            mouth_radius_m,
            throat_radius_m,
            depth_m,
            wall_m,
            segments,
            ..
        } => {
            if !port_exists(port) {
                return fail(format!("{pp}.port"), format!("no port named `{port}`"));
            }
            for (f, v) in [
                ("mouth_radius_m", mouth_radius_m),
                ("throat_radius_m", throat_radius_m),
                ("depth_m", depth_m),
                ("wall_m", wall_m),
            ] {
                positive(&format!("{pp}.{f}"), *v, "metres")?;
                size(&format!("{pp}.{f}"), *v)?;
            }
            if throat_radius_m > mouth_radius_m {
                return fail(
                    format!("{pp}.throat_radius_m"),
                    "must not exceed mouth_radius_m (the slot is a funnel)",
                );
            }
            if !(6..=MAX_SLOT_SEGMENTS).contains(segments) {
                return fail(
                    format!("{pp}.segments"),
                    format!("must be from 6 to {MAX_SLOT_SEGMENTS}, got {segments}"),
                );
            }
        }
    }
    if let Some(m) = part.model() {
        validate_model(&format!("{pp}.model"), m)?;
    }
    Ok(())
}

/// A part's glTF model: a relative `.gltf`/`.glb` path that exists under the assets directory,
/// a finite pose and a positive scale.
fn validate_model(mp: &str, m: &super::ModelSpec) -> Check {
    let rel = std::path::Path::new(&m.path);
    let ext = rel.extension().and_then(|e| e.to_str()).unwrap_or("");
    if !matches!(ext, "gltf" | "glb") {
        return fail(
            format!("{mp}.path"),
            format!("`{}` must name a .gltf or .glb file", m.path),
        );
    }
    if rel.is_absolute()
        || rel
            .components()
            .any(|c| !matches!(c, std::path::Component::Normal(_)))
    {
        return fail(
            format!("{mp}.path"),
            format!(
                "`{}` must be a plain relative path under the assets directory",
                m.path
            ),
        );
    }
    // No symlink on the way: a link under assets/ would let a scene read any file.
    let mut at = super::assets_dir();
    for c in rel.components() {
        at.push(c);
        if std::fs::symlink_metadata(&at).is_ok_and(|m| m.file_type().is_symlink()) {
            return fail(
                format!("{mp}.path"),
                format!(
                    "{} is a symbolic link; models must be plain files under the assets \
                     directory (links are not followed)",
                    at.display()
                ),
            );
        }
    }
    let full = super::assets_dir().join(rel);
    if !full.is_file() {
        return fail(
            format!("{mp}.path"),
            format!(
                "no model file {} (models are read from the repository's assets/, or from \
                 $RPOD_ASSETS when set)",
                full.display()
            ),
        );
    }
    finite3(&format!("{mp}.pos_m"), &m.pos_m)?;
    validate_attitude(&format!("{mp}.attitude"), &m.attitude)?;
    positive(&format!("{mp}.scale"), m.scale, "model units per metre")
}

fn validate_docking(s: &Scene, d: &super::DockingSpec) -> Check {
    let body = |n: &str, f: &str| {
        s.bodies
            .iter()
            .find(|b| b.name == n)
            .ok_or_else(|| (format!("docking.{f}"), format!("no body named `{n}`")))
    };
    let c = body(&d.chaser, "chaser")?;
    let t = body(&d.target, "target")?;
    if d.chaser == d.target {
        return fail("docking.target", "must differ from the chaser");
    }
    for (f, b, role) in [
        ("chaser", c, super::BodyRole::Chaser),
        ("target", t, super::BodyRole::Target),
    ] {
        if b.role != role {
            return fail(
                format!("docking.{f}"),
                format!(
                    "`{}` has role {:?}; the mechanism's {f} must be a body with role {role:?} \
                     (are chaser and target swapped?)",
                    b.name, b.role
                ),
            );
        }
    }
    if !c.ports.iter().any(|p| p.name == d.chaser_port) {
        return fail(
            "docking.chaser_port",
            format!("`{}` has no port `{}`", d.chaser, d.chaser_port),
        );
    }
    if !t.ports.iter().any(|p| p.name == d.target_port) {
        return fail(
            "docking.target_port",
            format!("`{}` has no port `{}`", d.target, d.target_port),
        );
    }
    if !c
        .parts
        .iter()
        .any(|p| matches!(p, PartSpec::DockingCone { port, .. } if *port == d.chaser_port))
    {
        return fail(
            "docking.chaser_port",
            format!(
                "port `{}` of `{}` carries no DockingCone part: the mechanism needs the probe \
                 cone on the chaser port",
                d.chaser_port, d.chaser
            ),
        );
    }
    if !t
        .parts
        .iter()
        .any(|p| matches!(p, PartSpec::DockingSlot { port, .. } if *port == d.target_port))
    {
        return fail(
            "docking.target_port",
            format!(
                "port `{}` of `{}` carries no DockingSlot part: the mechanism needs the slot on \
                 the target port",
                d.target_port, d.target
            ),
        );
    }
    if !(d.seat_depth_m.is_finite() && d.seat_depth_m >= 0.0) {
        return fail("docking.seat_depth_m", "must be ≥ 0 m");
    }
    positive("docking.mouth_radius_m", d.mouth_radius_m, "metres")?;
    let m = &d.magnet;
    for (f, v) in [("f0_n", m.f0_n), ("max_force_n", m.max_force_n)] {
        if !(v.is_finite() && (0.0..=MAX_FORCE_N).contains(&v)) {
            return fail(
                format!("docking.magnet.{f}"),
                format!("must be from 0 to {MAX_FORCE_N:e} N, got {}", num(v)),
            );
        }
    }
    positive("docking.magnet.g0_m", m.g0_m, "metres")?;
    if !(m.activation_distance_m.is_finite() && m.activation_distance_m >= 0.0) {
        return fail("docking.magnet.activation_distance_m", "must be ≥ 0 m");
    }
    let l = &d.latch;
    positive(
        "docking.latch.axial_tolerance_m",
        l.axial_tolerance_m,
        "metres",
    )?;
    positive(
        "docking.latch.lateral_tolerance_m",
        l.lateral_tolerance_m,
        "metres",
    )?;
    positive(
        "docking.latch.angle_tolerance_deg",
        l.angle_tolerance_deg,
        "degrees",
    )?;
    if !(l.dwell_s.is_finite() && l.dwell_s >= 0.0) {
        return fail("docking.latch.dwell_s", "must be ≥ 0 s");
    }
    positive("docking.latch.break_force_n", l.break_force_n, "newtons")?;
    let r = &l.capture_rates;
    for (f, v, unit) in [
        ("max_axial_rate_m_s", r.max_axial_rate_m_s, "m/s"),
        ("max_lateral_rate_m_s", r.max_lateral_rate_m_s, "m/s"),
        ("max_angular_rate_deg_s", r.max_angular_rate_deg_s, "deg/s"),
    ] {
        positive(&format!("docking.latch.capture_rates.{f}"), v, unit)?;
    }
    if let Some(sp) = &d.separation {
        if !matches!(d.contact, crate::contact::ContactModelSpec::Compliant(_)) {
            return fail(
                "docking.separation",
                "separation springs are integrated with the compliant contact's sub-steps: the \
                 docking contact must be Compliant",
            );
        }
        positive("docking.separation.stroke_m", sp.stroke_m, "metres")?;
        if !(sp.force_n.is_finite() && sp.force_n > 0.0 && sp.force_n <= MAX_FORCE_N) {
            return fail(
                "docking.separation.force_n",
                format!(
                    "must be a positive force up to {MAX_FORCE_N:e} N, got {}",
                    num(sp.force_n)
                ),
            );
        }
        if !(sp.preload_n.is_finite() && sp.preload_n >= 0.0 && sp.preload_n <= sp.force_n) {
            return fail(
                "docking.separation.preload_n",
                format!(
                    "must be from 0 N to force_n ({} N), got {}",
                    num(sp.force_n),
                    num(sp.preload_n)
                ),
            );
        }
    }
    if let super::LatchJoint::Compliant(j) = &l.joint {
        if !matches!(d.contact, crate::contact::ContactModelSpec::Compliant(_)) {
            return fail(
                "docking.latch.joint",
                "a Compliant latch is integrated with the compliant contact's sub-steps: the \
                 docking contact must be Compliant too",
            );
        }
        for (f, v, unit) in [
            ("stiffness_n_m", j.stiffness_n_m, "N/m"),
            ("damping_n_s_m", j.damping_n_s_m, "N·s/m"),
            ("rot_stiffness_nm_rad", j.rot_stiffness_nm_rad, "N·m/rad"),
            ("rot_damping_nm_s_rad", j.rot_damping_nm_s_rad, "N·m·s/rad"),
        ] {
            positive(&format!("docking.latch.joint.{f}"), v, unit)?;
        }
    }
    if let super::Mechanism::SoftCapture(sc) = &d.mechanism {
        validate_soft_capture(d, sc)?;
    }
    positive("docking.miss.jam_time_s", d.miss.jam_time_s, "seconds")?;
    positive("docking.miss.jam_speed_m_s", d.miss.jam_speed_m_s, "m/s")?;
    positive(
        "docking.miss.rebound_speed_m_s",
        d.miss.rebound_speed_m_s,
        "m/s",
    )?;
    if let crate::contact::ContactModelSpec::Compliant(c) = &d.contact {
        crate::contact::validate(c).map_err(|(f, m)| (format!("docking.contact.{f}"), m))?;
    }
    Ok(())
}

/// The soft-capture mechanism's values (`docking.mechanism`): the platform through
/// [`crate::contact::platform::Platform::new`] (its error names the field), also retracted by
/// the retracted stroke (the legs must still reach the ring there); positive finite speeds,
/// strokes, times, tolerances and hook coefficients.
fn validate_soft_capture(d: &super::DockingSpec, sc: &super::SoftCaptureSpec) -> Check {
    use crate::contact::platform::Platform;
    const P: &str = "docking.mechanism";
    if !matches!(d.contact, crate::contact::ContactModelSpec::Compliant(_)) {
        return fail(
            P,
            "the soft-capture platform is integrated with the compliant contact's sub-steps: the \
             docking contact must be Compliant",
        );
    }
    if d.start_latched {
        return fail(
            "docking.start_latched",
            "a soft-capture mechanism starts free (start_latched is the cone and slot's)",
        );
    }
    if !matches!(d.latch.joint, super::LatchJoint::Rigid) {
        return fail(
            "docking.latch.joint",
            "with SoftCapture the latch section describes the capture latches; the hooks' joint \
             is docking.mechanism.hooks",
        );
    }
    Platform::new(&sc.platform).map_err(|e| (format!("{P}.platform.{}", e.field), e.why))?;
    positive(&format!("{P}.attenuation_s"), sc.attenuation_s, "seconds")?;
    positive(
        &format!("{P}.retraction_speed_m_s"),
        sc.retraction_speed_m_s,
        "m/s",
    )?;
    positive(
        &format!("{P}.retracted_stroke_m"),
        sc.retracted_stroke_m,
        "metres",
    )?;
    if sc.retracted_stroke_m >= sc.platform.height_m {
        return fail(
            format!("{P}.retracted_stroke_m"),
            format!(
                "must be below the platform height {} m, got {}",
                num(sc.platform.height_m),
                num(sc.retracted_stroke_m)
            ),
        );
    }
    let mut retracted = sc.platform.clone();
    retracted.height_m -= sc.retracted_stroke_m;
    Platform::new(&retracted).map_err(|e| {
        (
            format!("{P}.retracted_stroke_m"),
            format!("retracted by it, {}: {}", e.field, e.why),
        )
    })?;
    positive(
        &format!("{P}.hook_lateral_tolerance_m"),
        sc.hook_lateral_tolerance_m,
        "metres",
    )?;
    positive(
        &format!("{P}.hook_angle_tolerance_deg"),
        sc.hook_angle_tolerance_deg,
        "degrees",
    )?;
    let j = &sc.hooks;
    for (f, v, unit) in [
        ("stiffness_n_m", j.stiffness_n_m, "N/m"),
        ("damping_n_s_m", j.damping_n_s_m, "N·s/m"),
        ("rot_stiffness_nm_rad", j.rot_stiffness_nm_rad, "N·m/rad"),
        ("rot_damping_nm_s_rad", j.rot_damping_nm_s_rad, "N·m·s/rad"),
    ] {
        positive(&format!("{P}.hooks.{f}"), v, unit)?;
    }
    Ok(())
}
