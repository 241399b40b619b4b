//! What the viewer draws of a spacecraft, made from the same part description as the colliders
//! ([`crate::scene::parts::expand_body`]): one render mesh and one parry shape per collider,
//! so the picture, the contacts and the monitor's distances all see the same geometry.

use crate::scene::parts::{PartCollider, Primitive, expand_body, port_frame};
use crate::scene::{BodyRole, PartRole, Scene};
use bevy::asset::RenderAssetUsages;
use bevy::mesh::{Indices, PrimitiveTopology};
use bevy::prelude::*;
use bevy_rapier3d::parry;
use bevy_rapier3d::rapier::math::Pose;
use bevy_rapier3d::rapier::prelude as rp;
use nalgebra::{Isometry3, Point3, UnitQuaternion, Vector3};

/// One collider of a body, ready to draw and to query.
#[derive(Clone)]
pub struct PartGeom {
    /// `body/collider` name, as the monitor and the outputs spell it.
    pub full_name: String,
    /// The scene part it belongs to.
    pub part: String,
    /// Role (chooses the material).
    pub role: PartRole,
    /// The primitive (body frame via `pose_body`).
    pub shape: Primitive,
    /// Pose of the primitive in the body frame.
    pub pose_body: Isometry3<f64>,
    /// The same primitive as a parry shape (for closest points).
    pub parry: Option<rp::SharedShape>,
}

/// One body's geometry.
#[derive(Clone)]
pub struct BodyGeom {
    /// Name.
    pub name: String,
    /// Role in the scene.
    pub role: BodyRole,
    /// Centre of mass in the body frame, m.
    pub com_body_m: Vector3<f64>,
    /// Colliders.
    pub parts: Vec<PartGeom>,
    /// Docking ports: name, origin and unit axis in the body frame.
    pub ports: Vec<(String, Vector3<f64>, Vector3<f64>)>,
    /// Radius of a sphere about the body origin that holds every part, m.
    pub radius_m: f64,
    /// glTF models drawn instead of the colliders of a part: (part name, model).
    pub models: Vec<(String, crate::scene::ModelSpec)>,
}

impl BodyGeom {
    /// Pose of the body frame in the world for a centre-of-mass position and attitude.
    pub fn body_pose(
        &self,
        com_world_m: &Vector3<f64>,
        att: &UnitQuaternion<f64>,
    ) -> Isometry3<f64> {
        let origin = com_world_m - att * self.com_body_m;
        Isometry3::from_parts(origin.into(), *att)
    }
}

/// A part pair prepared for a parry query in part a's frame.
struct PairQuery {
    shape_a: rp::SharedShape,
    shape_b: rp::SharedShape,
    /// Part a's world pose (f64).
    pose_a: Isometry3<f64>,
    /// Part b's pose in part a's frame (f32, small coordinates).
    pose_b_in_a: Pose,
}

/// The geometry of every body of a scene, scene order.
#[derive(Resource, Clone)]
pub struct SceneGeom {
    /// Bodies.
    pub bodies: Vec<BodyGeom>,
}

impl SceneGeom {
    /// Expands every body of the scene.
    pub fn new(scene: &Scene) -> Self {
        let bodies = scene
            .bodies
            .iter()
            .map(|b| {
                let parts: Vec<PartGeom> = expand_body(b)
                    .into_iter()
                    .map(|pc: PartCollider| PartGeom {
                        full_name: format!("{}/{}", b.name, pc.name),
                        part: pc.part,
                        role: pc.role,
                        parry: crate::sim::build::primitive_shape(&pc.shape),
                        shape: pc.shape,
                        pose_body: pc.pose_body,
                    })
                    .collect();
                let radius_m = parts
                    .iter()
                    .map(|p| p.pose_body.translation.vector.norm() + p.shape.bounding_radius_m())
                    .fold(0.0, f64::max);
                let ports = b
                    .ports
                    .iter()
                    .filter_map(|p| port_frame(b, &p.name).map(|(o, a)| (p.name.clone(), o, a)))
                    .collect();
                BodyGeom {
                    name: b.name.clone(),
                    role: b.role,
                    com_body_m: Vector3::from(b.com_m),
                    parts,
                    ports,
                    radius_m,
                    models: b
                        .parts
                        .iter()
                        .filter_map(|p| p.model().map(|m| (p.name().to_string(), m.clone())))
                        .collect(),
                }
            })
            .collect();
        Self { bodies }
    }

    /// (body index, part index) of a `body/collider` name.
    pub fn find_part(&self, full_name: &str) -> Option<(usize, usize)> {
        self.bodies.iter().enumerate().find_map(|(i, b)| {
            b.parts
                .iter()
                .position(|p| p.full_name == full_name)
                .map(|k| (i, k))
        })
    }

    /// The two parts' shapes, part a's world pose (f64) and part b's pose in part a's frame:
    /// queries run in part a's frame (small coordinates, so f32 stays precise) and map back in
    /// f64. `None` when a body state or a shape is missing.
    fn pair_query(
        &self,
        a: (usize, usize),
        b: (usize, usize),
        bodies: &[(Vector3<f64>, UnitQuaternion<f64>)],
    ) -> Option<PairQuery> {
        let (ba, pa) = (&self.bodies[a.0], &self.bodies[a.0].parts[a.1]);
        let (bb, pb) = (&self.bodies[b.0], &self.bodies[b.0].parts[b.1]);
        let pose_a = ba.body_pose(&bodies.get(a.0)?.0, &bodies[a.0].1) * pa.pose_body;
        let pose_b = bb.body_pose(&bodies.get(b.0)?.0, &bodies[b.0].1) * pb.pose_body;
        Some(PairQuery {
            shape_a: pa.parry.clone()?,
            shape_b: pb.parry.clone()?,
            pose_b_in_a: crate::sim::conv::pose(&pose_a.inv_mul(&pose_b)),
            pose_a,
        })
    }

    /// World-frame closest points between two parts, given the bodies' centre-of-mass
    /// positions and attitudes (`None` when the parts overlap or a shape is missing).
    pub fn closest_points(
        &self,
        a: (usize, usize),
        b: (usize, usize),
        bodies: &[(Vector3<f64>, UnitQuaternion<f64>)],
    ) -> Option<(Vector3<f64>, Vector3<f64>)> {
        let q = self.pair_query(a, b, bodies)?;
        let wa = q.pose_a;
        let res = parry::query::closest_points(
            &Pose::IDENTITY,
            &*q.shape_a,
            &q.pose_b_in_a,
            &*q.shape_b,
            f32::MAX,
        )
        .ok()?;
        match res {
            parry::query::ClosestPoints::WithinMargin(p1, p2) => {
                let p1 = Point3::new(f64::from(p1.x), f64::from(p1.y), f64::from(p1.z));
                let p2 = Point3::new(f64::from(p2.x), f64::from(p2.y), f64::from(p2.z));
                Some(((wa * p1).coords, (wa * p2).coords))
            }
            _ => None,
        }
    }
}

impl SceneGeom {
    /// Contact between two parts: the world point on part `a` and the world unit normal
    /// pointing from `a` to `b` (`None` when they are more than 2 cm apart).
    pub fn contact(
        &self,
        a: (usize, usize),
        b: (usize, usize),
        bodies: &[(Vector3<f64>, UnitQuaternion<f64>)],
    ) -> Option<(Vector3<f64>, Vector3<f64>)> {
        let q = self.pair_query(a, b, bodies)?;
        let wa = q.pose_a;
        let c = parry::query::contact(
            &Pose::IDENTITY,
            &*q.shape_a,
            &q.pose_b_in_a,
            &*q.shape_b,
            0.02,
        )
        .ok()??;
        let p = Point3::new(
            f64::from(c.point1.x),
            f64::from(c.point1.y),
            f64::from(c.point1.z),
        );
        let n = Vector3::new(
            f64::from(c.normal1.x),
            f64::from(c.normal1.y),
            f64::from(c.normal1.z),
        );
        Some(((wa * p).coords, wa.rotation * n))
    }
}

/// A render mesh of a primitive in its own frame (flat-shaded hulls).
pub fn primitive_mesh(p: &Primitive) -> Mesh {
    match p {
        Primitive::Cuboid { half_m } => Mesh::from(Cuboid::new(
            2.0 * half_m.x as f32,
            2.0 * half_m.y as f32,
            2.0 * half_m.z as f32,
        )),
        Primitive::Cylinder {
            radius_m,
            half_length_m,
        } => Cylinder::new(*radius_m as f32, 2.0 * *half_length_m as f32)
            .mesh()
            .resolution(32)
            .build(),
        Primitive::Ball { radius_m } => Sphere::new(*radius_m as f32).mesh().uv(32, 16),
        Primitive::ConvexHull { points_m } => hull_mesh(points_m),
        // The same triangles the monitor judges.
        Primitive::Mesh { mesh, .. } => {
            triangle_mesh((0..mesh.triangles.len()).map(|k| mesh.corners(k)))
        }
    }
}

/// Triangle list of the given triangles, one normal per face (flat shading).
pub fn triangle_mesh(tris: impl Iterator<Item = [Point3<f64>; 3]>) -> Mesh {
    let mut pos: Vec<[f32; 3]> = Vec::new();
    let mut nrm: Vec<[f32; 3]> = Vec::new();
    for t in tris {
        let [a, b, c] = t.map(|p| Vec3::new(p.x as f32, p.y as f32, p.z as f32));
        let n = (b - a).cross(c - a).normalize_or_zero();
        for p in [a, b, c] {
            pos.push(p.to_array());
            nrm.push(n.to_array());
        }
    }
    let idx: Vec<u32> = (0..pos.len() as u32).collect();
    Mesh::new(
        PrimitiveTopology::TriangleList,
        RenderAssetUsages::default(),
    )
    .with_inserted_attribute(Mesh::ATTRIBUTE_POSITION, pos)
    .with_inserted_attribute(Mesh::ATTRIBUTE_NORMAL, nrm)
    .with_inserted_indices(Indices::U32(idx))
}

/// Triangle list of the convex hull of `points`, one normal per face.
pub fn hull_mesh(points: &[Point3<f64>]) -> Mesh {
    let pts: Vec<_> = points
        .iter()
        .map(|p| crate::sim::conv::v(&p.coords))
        .collect();
    let mut pos: Vec<[f32; 3]> = Vec::new();
    let mut nrm: Vec<[f32; 3]> = Vec::new();
    if let Ok((v, tris)) = parry::transformation::try_convex_hull(&pts) {
        for t in tris {
            let [a, b, c] = t.map(|i| Vec3::new(v[i as usize].x, v[i as usize].y, v[i as usize].z));
            let n = (b - a).cross(c - a).normalize_or_zero();
            for p in [a, b, c] {
                pos.push(p.to_array());
                nrm.push(n.to_array());
            }
        }
    }
    let idx: Vec<u32> = (0..pos.len() as u32).collect();
    Mesh::new(
        PrimitiveTopology::TriangleList,
        RenderAssetUsages::default(),
    )
    .with_inserted_attribute(Mesh::ATTRIBUTE_POSITION, pos)
    .with_inserted_attribute(Mesh::ATTRIBUTE_NORMAL, nrm)
    .with_inserted_indices(Indices::U32(idx))
}

/// Base colour, metallic and roughness of a part (so bus, panels, booms, antenna, cone and slot
/// are told apart; the target's bus is gold foil, the chaser's silver).
pub fn part_look(body: BodyRole, role: PartRole) -> (Color, f32, f32) {
    match role {
        PartRole::Bus => match body {
            BodyRole::Target => (Color::srgb(0.85, 0.65, 0.2), 0.6, 0.35),
            BodyRole::Chaser => (Color::srgb(0.8, 0.82, 0.86), 0.6, 0.3),
            BodyRole::Other => (Color::srgb(0.6, 0.5, 0.45), 0.3, 0.6),
        },
        PartRole::Panel => (Color::srgb(0.12, 0.2, 0.6), 0.2, 0.25),
        PartRole::Boom => (Color::srgb(0.55, 0.55, 0.55), 0.5, 0.5),
        PartRole::Antenna => (Color::srgb(0.95, 0.95, 0.92), 0.0, 0.6),
        PartRole::DockingCone => (Color::srgb(0.9, 0.3, 0.15), 0.3, 0.4),
        PartRole::DockingSlot => (Color::srgb(0.2, 0.75, 0.35), 0.3, 0.4),
        PartRole::Other => (Color::srgb(0.7, 0.7, 0.7), 0.2, 0.5),
    }
}

/// f64 isometry → Bevy transform (f32).
pub fn to_transform(p: &Isometry3<f64>) -> Transform {
    let t = p.translation.vector;
    let q = p.rotation.quaternion();
    Transform {
        translation: Vec3::new(t.x as f32, t.y as f32, t.z as f32),
        rotation: Quat::from_xyzw(q.i as f32, q.j as f32, q.k as f32, q.w as f32).normalize(),
        scale: Vec3::ONE,
    }
}

/// f64 vector → Bevy `Vec3`.
pub fn v3(v: &Vector3<f64>) -> Vec3 {
    Vec3::new(v.x as f32, v.y as f32, v.z as f32)
}

/// Arrow scale for forces, N per m: the smallest of 1, 2 or 5 × 10^k N/m that draws `peak_n`
/// at most `max_len_m` long (a round number to read off the panel).
pub fn arrow_scale_n_per_m(peak_n: f64, max_len_m: f64) -> f64 {
    let need = peak_n / max_len_m;
    if !(need.is_finite() && need > 0.0) {
        return 1.0;
    }
    let decade = 10f64.powf(need.log10().floor());
    [1.0, 2.0, 5.0, 10.0]
        .iter()
        .map(|m| m * decade)
        .find(|s| *s >= need * (1.0 - 1e-12))
        .unwrap_or(10.0 * decade)
}

/// Pan step for the free camera, m per pixel of mouse motion: the width of one pixel at
/// `dist_m` from a perspective camera of vertical field of view `fov_y_rad` over a view
/// `height_px` tall, `2 d tan(fov/2) / h` (so the point at that distance follows the cursor).
pub fn pan_m_per_px(dist_m: f32, fov_y_rad: f32, height_px: f32) -> f32 {
    2.0 * dist_m * (0.5 * fov_y_rad).tan() / height_px.max(1.0)
}

#[cfg(test)]
mod tests {
    //! References: the definition of the 1-2-5 ladder; Bevy's own perspective projection
    //! matrix for the pan step; the analytic gap between two parallel box faces for the
    //! closest-points segment and the contact normal.
    use super::*;
    use bevy::camera::CameraProjection;

    #[test]
    fn val_viewer_closest_points_and_contact_between_parallel_box_faces() {
        let p = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("scenes/examples/docking_aligned.ron");
        let scene = crate::scene::load_scene_file(&p, &[]).unwrap().scene;
        let geom = SceneGeom::new(&scene);
        let (ca, cb) = (
            geom.find_part("target/bus").unwrap(),
            geom.find_part("chaser/bus").unwrap(),
        );
        let half_x = |(b, k): (usize, usize)| match &geom.bodies[b].parts[k].shape {
            Primitive::Cuboid { half_m } => half_m.x,
            other => panic!("bus is not a box: {other:?}"),
        };
        // Both bodies unrotated, centres of mass on the x axis: the buses' facing x faces are
        // parallel and overlap in y and z (1.5 m and 1.0 m cubes, centred), so the distance is
        // the gap between the faces.
        let part_x = |(b, k): (usize, usize), com_x: f64| {
            let body = &geom.bodies[b];
            let origin =
                body.body_pose(&Vector3::new(com_x, 0.0, 0.0), &UnitQuaternion::identity());
            (origin * body.parts[k].pose_body).translation.vector.x
        };
        for gap_want in [0.7, 0.01] {
            let com_b = part_x(ca, 0.0) + half_x(ca) + gap_want + half_x(cb) - part_x(cb, 0.0);
            let bodies = [
                (Vector3::zeros(), UnitQuaternion::identity()),
                (Vector3::new(com_b, 0.0, 0.0), UnitQuaternion::identity()),
            ];
            let (pa, pb) = geom.closest_points(ca, cb, &bodies).unwrap();
            assert!(((pb - pa).norm() - gap_want).abs() < 1e-5, "{pa} {pb}");
            assert!((pa.x - (part_x(ca, 0.0) + half_x(ca))).abs() < 1e-5);
            // Contact reports only within 2 cm, with the normal from a to b (+x).
            match geom.contact(ca, cb, &bodies) {
                Some((_, n)) => {
                    assert!(gap_want < 0.02);
                    assert!((n - Vector3::x()).norm() < 1e-6, "{n}");
                }
                None => assert!(gap_want >= 0.02),
            }
        }
    }

    #[test]
    fn regress_viewer_arrow_scale_is_round_and_fits() {
        for (peak, len, want) in [
            (3.2, 1.0, 5.0),
            (5.0, 1.0, 5.0),
            (0.011, 1.0, 0.02),
            (1000.0, 1.0, 1000.0),
            (0.2, 0.05, 5.0),
            (7.0, 0.5, 20.0),
        ] {
            let s = arrow_scale_n_per_m(peak, len);
            assert!(
                (s - want).abs() < 1e-9 * want,
                "{peak} N in {len} m: {s} N/m"
            );
            assert!(peak / s <= len * (1.0 + 1e-9), "arrow longer than {len} m");
            // The next smaller ladder value would overflow the length.
            // (1 → 0.5, 2 → 1, 5 → 2 on the ladder.)
            let mantissa = s / 10f64.powf(s.log10().floor());
            let smaller = if (mantissa - 5.0).abs() < 1e-9 {
                0.4 * s
            } else {
                0.5 * s
            };
            assert!(peak / smaller > len, "{s} N/m is not the smallest fitting");
        }
    }

    #[test]
    fn regress_viewer_pan_step_moves_point_one_pixel() {
        // A point at the pan distance, displaced by N pan steps across the view, projects N
        // pixels from the centre under Bevy's perspective projection.
        let (h, w) = (720.0_f32, 1280.0_f32);
        let proj = PerspectiveProjection {
            fov: std::f32::consts::FRAC_PI_4,
            aspect_ratio: w / h,
            ..default()
        };
        let m = proj.get_clip_from_view();
        for dist in [0.5_f32, 12.0, 3000.0] {
            let k = pan_m_per_px(dist, proj.fov, h);
            for n in [1.0_f32, 37.0, 200.0] {
                let clip = m * Vec4::new(0.0, k * n, -dist, 1.0);
                let px = clip.y / clip.w * h / 2.0;
                assert!(
                    (px - n).abs() < 1e-3 * n.max(1.0),
                    "{dist} m: {px} px for {n}"
                );
                let clip = m * Vec4::new(k * n, 0.0, -dist, 1.0);
                let px = clip.x / clip.w * w / 2.0;
                assert!(
                    (px - n).abs() < 1e-3 * n.max(1.0),
                    "{dist} m: x {px} px for {n}"
                );
            }
        }
    }
}
