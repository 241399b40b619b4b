//! Expansion of a body's parts into named primitive colliders in the body frame (f64,
//! Bevy-free). The simulation turns each [`PartCollider`] into a parry shape; tests use the
//! same description to compute analytic distances.

use super::{BodySpec, PartRole, PartSpec, ShapeSpec};
use nalgebra::{Isometry3, Point3, Rotation3, Translation3, UnitQuaternion, Vector3};

/// Points on each circle of a cone or slot hull.
pub const CIRCLE_SEGMENTS: usize = 32;

/// A convex primitive, in its own frame.
#[derive(Debug, Clone, PartialEq)]
pub enum Primitive {
    /// Box with half-extents along the local axes, m.
    Cuboid {
        /// Half-extents, m.
        half_m: Vector3<f64>,
    },
    /// Solid cylinder along the local y axis (parry's convention), centred on the origin.
    Cylinder {
        /// Radius, m.
        radius_m: f64,
        /// Half length, m.
        half_length_m: f64,
    },
    /// Sphere, m.
    Ball {
        /// Radius, m.
        radius_m: f64,
    },
    /// Convex hull of the given points (local frame), m.
    ConvexHull {
        /// Hull points, m.
        points_m: Vec<Point3<f64>>,
    },
    /// A triangle mesh (one component of a mesh file, vertices in the local frame), judged
    /// exactly; simulated in rapier as its convex decomposition with these parameters. Not
    /// convex in general.
    Mesh {
        /// The component.
        mesh: std::sync::Arc<crate::geometry::mesh::MeshComponent>,
        /// Convex-decomposition parameters.
        decomposition: super::DecompositionSpec,
    },
}

impl Primitive {
    /// Radius of a sphere about the local origin that contains the primitive, m.
    pub fn bounding_radius_m(&self) -> f64 {
        match self {
            Primitive::Cuboid { half_m } => half_m.norm(),
            Primitive::Cylinder {
                radius_m,
                half_length_m,
            } => radius_m.hypot(*half_length_m),
            Primitive::Ball { radius_m } => *radius_m,
            Primitive::ConvexHull { points_m } => {
                points_m.iter().map(|p| p.coords.norm()).fold(0.0, f64::max)
            }
            Primitive::Mesh { mesh, .. } => mesh.bounding_radius_m(),
        }
    }
}

/// One collider of a part.
#[derive(Debug, Clone)]
pub struct PartCollider {
    /// The part it belongs to (as named in the scene).
    pub part: String,
    /// Collider name: the part name, or `PART.panel2`, `PART.boom`, `PART.wall3`, `PART.back`.
    pub name: String,
    /// Role, for the monitor (docking vs collision).
    pub role: PartRole,
    /// Shape in its own frame.
    pub shape: Primitive,
    /// Pose of the shape frame in the body frame.
    pub pose_body: Isometry3<f64>,
    /// May overlap other bodies at t = 0.
    pub allow_initial_overlap: bool,
}

/// Rotation taking local y onto `axis` (for cylinders).
fn y_to(axis: &Vector3<f64>) -> UnitQuaternion<f64> {
    UnitQuaternion::rotation_between(&Vector3::y(), axis).unwrap_or_else(|| {
        // axis = −y: half turn about x.
        UnitQuaternion::from_axis_angle(&Vector3::x_axis(), std::f64::consts::PI)
    })
}

/// An orthonormal pair (u, v) perpendicular to unit `a`, with u × v = a.
pub fn perpendicular_basis(a: &Vector3<f64>) -> (Vector3<f64>, Vector3<f64>) {
    let helper = if a.x.abs() < 0.9 {
        Vector3::x()
    } else {
        Vector3::y()
    };
    let u = (helper - a * a.dot(&helper)).normalize();
    let v = a.cross(&u);
    (u, v)
}

fn iso(pos: Vector3<f64>, rot: UnitQuaternion<f64>) -> Isometry3<f64> {
    Isometry3::from_parts(Translation3::from(pos), rot)
}

fn shape_primitive(shape: &ShapeSpec) -> (Primitive, UnitQuaternion<f64>) {
    match shape {
        ShapeSpec::Box { size_m } => (
            Primitive::Cuboid {
                half_m: Vector3::from(*size_m) / 2.0,
            },
            UnitQuaternion::identity(),
        ),
        ShapeSpec::Cylinder {
            radius_m,
            length_m,
            axis,
        } => (
            Primitive::Cylinder {
                radius_m: *radius_m,
                half_length_m: length_m / 2.0,
            },
            y_to(&axis.vector()),
        ),
        ShapeSpec::Sphere { radius_m } => (
            Primitive::Ball {
                radius_m: *radius_m,
            },
            UnitQuaternion::identity(),
        ),
        ShapeSpec::SuperquadricPrism {
            a_m,
            b_m,
            s,
            height_m,
            segments,
        } => {
            let n = (*segments).max(8) as usize;
            let e = 1.0 / s;
            let mut points_m = Vec::with_capacity(2 * n);
            for k in 0..n {
                // Parametric form (eq 5 of Xu et al. 2019): x = a·sgn(c)|c|^{1/s}, y = b·sgn(s)|s|^{1/s}.
                let t = 2.0 * std::f64::consts::PI * k as f64 / n as f64;
                let (st, ct) = t.sin_cos();
                let x = a_m * ct.signum() * ct.abs().powf(e);
                let y = b_m * st.signum() * st.abs().powf(e);
                for z in [-height_m / 2.0, height_m / 2.0] {
                    points_m.push(nalgebra::Point3::new(x, y, z));
                }
            }
            (
                Primitive::ConvexHull { points_m },
                UnitQuaternion::identity(),
            )
        }
        // Expanded by `expand_part` from the loaded file; a mesh the loader has not read (a
        // scene built without `load_scene_*`) has no colliders to give.
        ShapeSpec::Mesh { .. } => (
            Primitive::ConvexHull {
                points_m: Vec::new(),
            },
            UnitQuaternion::identity(),
        ),
    }
}

/// Port frame (origin, unit outward axis) in the body frame.
pub fn port_frame(body: &BodySpec, port: &str) -> Option<(Vector3<f64>, Vector3<f64>)> {
    body.ports
        .iter()
        .find(|p| p.name == port)
        .map(|p| (Vector3::from(p.pos_m), Vector3::from(p.axis).normalize()))
}

/// All colliders of a body, in scene order.
pub fn expand_body(body: &BodySpec) -> Vec<PartCollider> {
    let mut out = Vec::new();
    for part in &body.parts {
        expand_part(body, part, &mut out);
    }
    out
}

fn expand_part(body: &BodySpec, part: &PartSpec, out: &mut Vec<PartCollider>) {
    let allow = part.allow_initial_overlap();
    let pname = part.name().to_string();
    let mut push = |name: String, role: PartRole, shape: Primitive, pose: Isometry3<f64>| {
        out.push(PartCollider {
            part: pname.clone(),
            name,
            role,
            shape,
            pose_body: pose,
            allow_initial_overlap: allow,
        })
    };
    match part {
        PartSpec::Bus {
            name,
            shape,
            pos_m,
            attitude,
            ..
        }
        | PartSpec::Antenna {
            name,
            shape,
            pos_m,
            attitude,
            ..
        } => {
            let role = if matches!(part, PartSpec::Bus { .. }) {
                PartRole::Bus
            } else {
                PartRole::Antenna
            };
            if let ShapeSpec::Mesh {
                loaded: Some(file),
                decomposition,
                ..
            } = shape
            {
                // One collider per component: named by the part when it is the only one, else
                // by the component (glTF node, OBJ object).
                let single = file.components.len() == 1;
                for c in &file.components {
                    push(
                        if single { name.clone() } else { c.name.clone() },
                        role,
                        Primitive::Mesh {
                            mesh: c.clone(),
                            decomposition: *decomposition,
                        },
                        iso(Vector3::from(*pos_m), attitude.to_quat())
                            * Translation3::from(c.offset_m),
                    );
                }
                return;
            }
            let (prim, local_rot) = shape_primitive(shape);
            push(
                name.clone(),
                role,
                prim,
                iso(Vector3::from(*pos_m), attitude.to_quat() * local_rot),
            );
        }
        PartSpec::SolarWing {
            name,
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
            let d = direction.vector();
            let root = Vector3::from(*root_m);
            let cant = UnitQuaternion::from_axis_angle(
                &nalgebra::Unit::new_normalize(d),
                cant_deg.to_radians(),
            );
            let w = cant * width_axis.vector();
            let n = d.cross(&w);
            let panel_rot = UnitQuaternion::from_rotation_matrix(
                &Rotation3::from_matrix_unchecked(nalgebra::Matrix3::from_columns(&[d, w, n])),
            );
            if *boom_length_m > 0.0 {
                push(
                    format!("{name}.boom"),
                    PartRole::Boom,
                    Primitive::Cylinder {
                        radius_m: *boom_radius_m,
                        half_length_m: boom_length_m / 2.0,
                    },
                    iso(root + d * (boom_length_m / 2.0), y_to(&d)),
                );
            }
            let [len, width] = *panel_size_m;
            for k in 0..*panel_count {
                let inner = boom_length_m + f64::from(k) * (len + panel_gap_m);
                push(
                    format!("{name}.panel{}", k + 1),
                    PartRole::Panel,
                    Primitive::Cuboid {
                        half_m: Vector3::new(len / 2.0, width / 2.0, panel_thickness_m / 2.0),
                    },
                    iso(root + d * (inner + len / 2.0), panel_rot),
                );
            }
        }
        PartSpec::DockingCone {
            name,
            port,
            base_radius_m,
            tip_radius_m,
            length_m,
            ..
        } => {
            let Some((p, a)) = port_frame(body, port) else {
                return;
            };
            let (u, v) = perpendicular_basis(&a);
            let mut pts = Vec::with_capacity(2 * CIRCLE_SEGMENTS);
            for k in 0..CIRCLE_SEGMENTS {
                let phi = 2.0 * std::f64::consts::PI * k as f64 / CIRCLE_SEGMENTS as f64;
                let radial = u * phi.cos() + v * phi.sin();
                pts.push(Point3::from(radial * *base_radius_m));
                pts.push(Point3::from(radial * *tip_radius_m + a * *length_m));
            }
            push(
                name.clone(),
                PartRole::DockingCone,
                Primitive::ConvexHull { points_m: pts },
                iso(p, UnitQuaternion::identity()),
            );
        }
        PartSpec::DockingSlot {
            name,
            port,
            mouth_radius_m,
            throat_radius_m,
            depth_m,
            wall_m,
            segments,
            ..
        } => {
            let Some((p, a)) = port_frame(body, port) else {
                return;
            };
            let (u, v) = perpendicular_basis(&a);
            let n = *segments as usize;
            for k in 0..n {
                let mut pts = Vec::with_capacity(8);
                for j in [k, k + 1] {
                    let phi = 2.0 * std::f64::consts::PI * j as f64 / n as f64;
                    let radial = u * phi.cos() + v * phi.sin();
                    for (h, r) in [(0.0, *throat_radius_m), (*depth_m, *mouth_radius_m)] {
                        // The inner face is the chord between the two angles; push the hull
                        // points out so the chord's midpoint lies on the nominal radius.
                        let r_in = r / (std::f64::consts::PI / n as f64).cos();
                        pts.push(Point3::from(radial * r_in + a * h));
                        pts.push(Point3::from(radial * (r_in + wall_m) + a * h));
                    }
                }
                push(
                    format!("{name}.wall{}", k + 1),
                    PartRole::DockingSlot,
                    Primitive::ConvexHull { points_m: pts },
                    iso(p, UnitQuaternion::identity()),
                );
            }
            let back_r = throat_radius_m + wall_m;
            push(
                format!("{name}.back"),
                PartRole::DockingSlot,
                Primitive::Cylinder {
                    radius_m: back_r / (std::f64::consts::PI / n as f64).cos() + wall_m,
                    half_length_m: wall_m / 2.0,
                },
                iso(p - a * (wall_m / 2.0), y_to(&a)),
            );
        }
    }
}
