//! Physical validation of a parsed scene. Each failure names the field path (bodies and parts
//! by name) so the loader can point at its line and column.

use super::{
    AttitudeSpec, BodySpec, Environment, GuaranteeSpec, OrbitSpec, PartSpec, Scene, ShapeSpec, V3,
};
use crate::orbit::constants::R_EARTH_M;

type Check = Result<(), (String, String)>;

fn fail(path: impl Into<String>, msg: impl Into<String>) -> Check {
    Err((path.into(), msg.into()))
}

fn positive(path: &str, v: f64, unit: &str) -> Check {
    if !(v.is_finite() && v > 0.0) {
        return fail(
            path,
            format!("must be a positive number of {unit}, got {v}"),
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

/// Checks a scene; on failure returns `(field path, message)`.
pub fn validate(s: &Scene) -> Check {
    if s.name.trim().is_empty() {
        return fail("name", "must not be empty");
    }
    positive("dt_s", s.dt_s, "seconds")?;
    positive("duration_s", s.duration_s, "seconds")?;
    if s.physics_substeps == 0 {
        return fail("physics_substeps", "must be at least 1");
    }
    if s.record_every_steps == 0 {
        return fail("record_every_steps", "must be at least 1");
    }
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
            }
            OrbitSpec::State { r_eci_m, v_eci_m_s } => {
                finite3("environment.reference.r_eci_m", r_eci_m)?;
                finite3("environment.reference.v_eci_m_s", v_eci_m_s)?;
                let r = nalgebra::Vector3::from(*r_eci_m).norm();
                if r <= R_EARTH_M {
                    return fail(
                        "environment.reference.r_eci_m",
                        format!("|r| = {r:.0} m is inside the Earth"),
                    );
                }
            }
        },
        Environment::FreeSpace => {}
        Environment::AirBearing(t) => {
            for k in 0..2 {
                positive(
                    &format!("environment.0.table_size_m.{k}"),
                    t.table_size_m[k],
                    "metres",
                )?;
                if !(t.table_corner_m[k].is_finite()) {
                    return fail(
                        format!("environment.0.table_corner_m.{k}"),
                        "must be finite",
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
            positive(
                "environment.0.table_thickness_m",
                t.table_thickness_m,
                "metres",
            )?;
            positive("environment.0.gravity_m_s2", t.gravity_m_s2, "m/s²")?;
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
    if s.bodies.is_empty() {
        return fail("bodies", "a scene needs at least one body");
    }
    for (i, b) in s.bodies.iter().enumerate() {
        if s.bodies[..i].iter().any(|o| o.name == b.name) {
            return fail(
                format!("bodies.{i}.name"),
                format!("duplicate body name `{}`", b.name),
            );
        }
        validate_body(b)?;
    }
    if let Some(d) = &s.docking {
        validate_docking(s, d)?;
    }
    if let Some(h) = s.monitor.horizon_m {
        positive("monitor.horizon_m", h, "metres")?;
    }
    for g in &s.guarantees {
        let p = format!("guarantees.{}", g.name());
        let body_exists = |n: &str| s.bodies.iter().any(|b| b.name == n);
        match g {
            GuaranteeSpec::MinDistance { a, b, min_m, .. } => {
                for (f, n) in [("a", a), ("b", b)] {
                    if !body_exists(n) {
                        return fail(format!("{p}.{f}"), format!("no body named `{n}`"));
                    }
                }
                if a == b {
                    return fail(format!("{p}.b"), "must name a different body than `a`");
                }
                if !(min_m.is_finite() && *min_m >= 0.0) {
                    return fail(format!("{p}.min_m"), "must be ≥ 0 m");
                }
            }
            GuaranteeSpec::KeepOutSphere {
                body,
                around,
                radius_m,
                ..
            } => {
                for (f, n) in [("body", body), ("around", around)] {
                    if !body_exists(n) {
                        return fail(format!("{p}.{f}"), format!("no body named `{n}`"));
                    }
                }
                positive(&format!("{p}.radius_m"), *radius_m, "metres")?;
            }
            GuaranteeSpec::ApproachCone {
                body,
                around,
                port,
                half_angle_deg,
                from_range_m,
                to_range_m,
                ..
            } => {
                for (f, n) in [("body", body), ("around", around)] {
                    if !body_exists(n) {
                        return fail(format!("{p}.{f}"), format!("no body named `{n}`"));
                    }
                }
                if body == around {
                    return fail(
                        format!("{p}.around"),
                        "must name a different body than `body`",
                    );
                }
                let has_port = s
                    .bodies
                    .iter()
                    .find(|b| &b.name == around)
                    .is_some_and(|b| b.ports.iter().any(|q| &q.name == port));
                if !has_port {
                    return fail(
                        format!("{p}.port"),
                        format!("body `{around}` has no port `{port}`"),
                    );
                }
                if !(half_angle_deg.is_finite() && *half_angle_deg > 0.0 && *half_angle_deg < 90.0)
                {
                    return fail(
                        format!("{p}.half_angle_deg"),
                        format!("must be an angle in (0, 90) deg, got {half_angle_deg}"),
                    );
                }
                positive(&format!("{p}.from_range_m"), *from_range_m, "metres")?;
                if !(to_range_m.is_finite() && *to_range_m >= 0.0 && to_range_m < from_range_m) {
                    return fail(
                        format!("{p}.to_range_m"),
                        format!(
                            "must be ≥ 0 m and below from_range_m ({from_range_m} m), got {to_range_m}"
                        ),
                    );
                }
            }
        }
    }
    Ok(())
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
    if b.name.trim().is_empty() || b.name.contains(['.', ',', '"', ' ']) {
        return fail(
            format!("{p}.name"),
            "must be non-empty, without spaces, dots, commas or quotes",
        );
    }
    positive(&format!("{p}.mass_kg"), b.mass_kg, "kilograms")?;
    if !(b.friction.is_finite() && b.friction >= 0.0) {
        return fail(format!("{p}.friction"), "must be ≥ 0");
    }
    if !(b.restitution.is_finite() && (0.0..=1.0).contains(&b.restitution)) {
        return fail(format!("{p}.restitution"), "must be in [0, 1]");
    }
    finite3(&format!("{p}.com_m"), &b.com_m)?;
    let j = b.inertia_kg_m2.matrix();
    if j.iter().any(|v| !v.is_finite()) {
        return fail(format!("{p}.inertia_kg_m2"), "must be finite");
    }
    let eig = j.symmetric_eigenvalues();
    let mut ev: Vec<f64> = eig.iter().copied().collect();
    ev.sort_by(f64::total_cmp);
    if ev[0] <= 0.0 {
        return fail(
            format!("{p}.inertia_kg_m2"),
            format!(
                "inertia tensor must be positive definite; principal moments {:.6}, {:.6}, {:.6} kg·m²",
                ev[0], ev[1], ev[2]
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
    finite3(&format!("{p}.initial.pos_m"), &b.initial.pos_m)?;
    finite3(&format!("{p}.initial.vel_m_s"), &b.initial.vel_m_s)?;
    finite3(
        &format!("{p}.initial.rate_body_deg_s"),
        &b.initial.rate_body_deg_s,
    )?;
    validate_attitude(&format!("{p}.initial.attitude"), &b.initial.attitude)?;
    for (i, port) in b.ports.iter().enumerate() {
        let pp = format!("{p}.ports.{}", port.name);
        if b.ports[..i].iter().any(|o| o.name == port.name) {
            return fail(format!("{p}.ports.{i}.name"), "duplicate port name");
        }
        finite3(&format!("{pp}.pos_m"), &port.pos_m)?;
        let n = nalgebra::Vector3::from(port.axis).norm();
        if !(n.is_finite() && n > 1e-9) {
            return fail(format!("{pp}.axis"), "must be a non-zero direction");
        }
    }
    if b.parts.is_empty() {
        return fail(format!("{p}.parts"), "a body needs at least one part");
    }
    for (i, part) in b.parts.iter().enumerate() {
        let pp = format!("{p}.parts.{}", part.name());
        if part.name().is_empty() || part.name().contains(['.', ',', '"', ' ', '|']) {
            return fail(
                format!("{pp}.name"),
                "must be non-empty, without spaces, dots, commas, bars or quotes",
            );
        }
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
            }
        }
        ShapeSpec::Cylinder {
            radius_m, length_m, ..
        } => {
            positive(&format!("{path}.radius_m"), *radius_m, "metres")?;
            positive(&format!("{path}.length_m"), *length_m, "metres")?;
        }
        ShapeSpec::Sphere { radius_m } => {
            positive(&format!("{path}.radius_m"), *radius_m, "metres")?
        }
        ShapeSpec::SuperquadricPrism {
            a_m,
            b_m,
            s,
            height_m,
            segments,
        } => {
            positive(&format!("{path}.a_m"), *a_m, "metres")?;
            positive(&format!("{path}.b_m"), *b_m, "metres")?;
            positive(&format!("{path}.height_m"), *height_m, "metres")?;
            if !(s.is_finite() && *s >= 0.5) {
                return fail(
                    format!("{path}.s"),
                    format!("the exponent must be ≥ 0.5 (a convex cross-section), got {s}"),
                );
            }
            if *segments < 8 {
                return fail(
                    format!("{path}.segments"),
                    format!("at least 8 boundary points, got {segments}"),
                );
            }
        }
    }
    Ok(())
}

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
            finite3(&format!("{pp}.pos_m"), pos_m)?;
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
            finite3(&format!("{pp}.root_m"), root_m)?;
            if direction.vector().dot(&width_axis.vector()).abs() > 0.5 {
                return fail(
                    format!("{pp}.width_axis"),
                    "must be perpendicular to `direction`",
                );
            }
            if !(boom_length_m.is_finite() && *boom_length_m >= 0.0) {
                return fail(format!("{pp}.boom_length_m"), "must be ≥ 0 m");
            }
            if *boom_length_m > 0.0 {
                positive(&format!("{pp}.boom_radius_m"), *boom_radius_m, "metres")?;
            }
            if *panel_count == 0 {
                return fail(format!("{pp}.panel_count"), "must be at least 1");
            }
            positive(&format!("{pp}.panel_size_m.0"), panel_size_m[0], "metres")?;
            positive(&format!("{pp}.panel_size_m.1"), panel_size_m[1], "metres")?;
            positive(
                &format!("{pp}.panel_thickness_m"),
                *panel_thickness_m,
                "metres",
            )?;
            if !(panel_gap_m.is_finite() && *panel_gap_m >= 0.0) {
                return fail(format!("{pp}.panel_gap_m"), "must be ≥ 0 m");
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
            positive(&format!("{pp}.base_radius_m"), *base_radius_m, "metres")?;
            positive(&format!("{pp}.tip_radius_m"), *tip_radius_m, "metres")?;
            positive(&format!("{pp}.length_m"), *length_m, "metres")?;
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
            positive(&format!("{pp}.mouth_radius_m"), *mouth_radius_m, "metres")?;
            positive(&format!("{pp}.throat_radius_m"), *throat_radius_m, "metres")?;
            positive(&format!("{pp}.depth_m"), *depth_m, "metres")?;
            positive(&format!("{pp}.wall_m"), *wall_m, "metres")?;
            if throat_radius_m > mouth_radius_m {
                return fail(
                    format!("{pp}.throat_radius_m"),
                    "must not exceed mouth_radius_m (the slot is a funnel)",
                );
            }
            if *segments < 6 {
                return fail(format!("{pp}.segments"), "must be at least 6");
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
    if !(d.seat_depth_m.is_finite() && d.seat_depth_m >= 0.0) {
        return fail("docking.seat_depth_m", "must be ≥ 0 m");
    }
    positive("docking.mouth_radius_m", d.mouth_radius_m, "metres")?;
    let m = &d.magnet;
    if !(m.f0_n.is_finite() && m.f0_n >= 0.0) {
        return fail("docking.magnet.f0_n", "must be ≥ 0 N");
    }
    positive("docking.magnet.g0_m", m.g0_m, "metres")?;
    if !(m.max_force_n.is_finite() && m.max_force_n >= 0.0) {
        return fail("docking.magnet.max_force_n", "must be ≥ 0 N");
    }
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
