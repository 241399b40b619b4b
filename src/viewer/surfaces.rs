//! Constraint surfaces (layer `S`), built from the same geometry the laws and guarantees use,
//! as plain f64 vertex lists (tested without a window) turned into Bevy meshes:
//!
//! - Xu, Wen, Wei (2019), air-bearing table: the superquadric obstacle and the heart-shaped
//!   keep-out of the target, from the scene's `Xu2019` controller
//!   ([`crate::control::xu2019::SceneSpec::params`]: `obstacle`, `heart`). Both laws act on the
//!   chaser's centre of mass in the table plane, so each curve is drawn as a vertical prism over
//!   the table (z from the top, 0, to twice the chaser's initial centre-of-mass height, so the
//!   plane the law works in is at mid-height); the curve itself is also drawn as a line at the
//!   chaser's current centre-of-mass height.
//! - Zhang et al. (2018): the capture sphere of radius l (`capture_radius_m`) about every body's
//!   centre of mass (the law's capture guarantee is `|r_a − r_b| ≥ l` for every pair).
//! - Every `KeepOutSphere` guarantee: the sphere of `radius_m` about `around`'s centre of mass.

use crate::geometry::heart::HeartParams;
use crate::geometry::superquadric::SuperquadricParams;
use crate::guarantee::builtin::KeepOutSphereParams;
use crate::scene::{Environment, Scene};
use bevy::asset::RenderAssetUsages;
use bevy::mesh::{Indices, PrimitiveTopology};
use bevy::prelude::Mesh;
use nalgebra::{Vector2, Vector3};

/// Points on each closed curve of a prism (superquadric and heart outlines).
pub const OUTLINE_POINTS: usize = 240;

/// A triangle mesh in f64: positions (m, in the surface's own frame), one normal per vertex,
/// triangle indices.
#[derive(Debug, Clone, Default)]
pub struct SurfaceMesh {
    /// Vertex positions, m.
    pub positions_m: Vec<Vector3<f64>>,
    /// Unit normals, one per vertex.
    pub normals: Vec<Vector3<f64>>,
    /// Triangle list.
    pub indices: Vec<u32>,
}

impl SurfaceMesh {
    /// The render mesh (f32 positions in the surface's frame; draw it two-sided).
    pub fn to_mesh(&self) -> Mesh {
        let f = |v: &Vector3<f64>| [v.x as f32, v.y as f32, v.z as f32];
        Mesh::new(
            PrimitiveTopology::TriangleList,
            RenderAssetUsages::default(),
        )
        .with_inserted_attribute(
            Mesh::ATTRIBUTE_POSITION,
            self.positions_m.iter().map(f).collect::<Vec<_>>(),
        )
        .with_inserted_attribute(
            Mesh::ATTRIBUTE_NORMAL,
            self.normals.iter().map(f).collect::<Vec<_>>(),
        )
        .with_inserted_indices(Indices::U32(self.indices.clone()))
    }
}

/// The vertical prism over a closed counter-clockwise outline (points relative to the prism's
/// origin, m) from `z0_m` to `z1_m`: side walls (one flat normal per edge) and both caps (fans
/// from the outline's first point, which is valid for an outline star-shaped about that point:
/// any convex curve, and the heart, whose first point is its notch). Every vertex is an
/// outline point at z0 or z1.
pub fn prism(outline_m: &[Vector2<f64>], z0_m: f64, z1_m: f64) -> SurfaceMesh {
    let n = outline_m.len();
    let mut m = SurfaceMesh::default();
    if n < 3 {
        return m;
    }
    for i in 0..n {
        let (p, q) = (outline_m[i], outline_m[(i + 1) % n]);
        let e = q - p;
        let nrm = Vector3::new(e.y, -e.x, 0.0)
            .try_normalize(0.0)
            .unwrap_or_else(Vector3::x);
        let base = m.positions_m.len() as u32;
        for (v, z) in [(p, z0_m), (q, z0_m), (p, z1_m), (q, z1_m)] {
            m.positions_m.push(Vector3::new(v.x, v.y, z));
            m.normals.push(nrm);
        }
        m.indices
            .extend_from_slice(&[base, base + 1, base + 2, base + 2, base + 1, base + 3]);
    }
    for (z, up) in [(z0_m, -1.0), (z1_m, 1.0)] {
        let base = m.positions_m.len() as u32;
        for v in outline_m {
            m.positions_m.push(Vector3::new(v.x, v.y, z));
            m.normals.push(Vector3::new(0.0, 0.0, up));
        }
        for i in 1..n as u32 - 1 {
            if up > 0.0 {
                m.indices.extend_from_slice(&[base, base + i, base + i + 1]);
            } else {
                m.indices.extend_from_slice(&[base, base + i + 1, base + i]);
            }
        }
    }
    m
}

/// A sphere of `radius_m` about the origin (latitude–longitude grid: `rings` bands from pole to
/// pole, `segments` around), radial normals. Every vertex is at exactly `radius_m`.
pub fn sphere(radius_m: f64, rings: usize, segments: usize) -> SurfaceMesh {
    let mut m = SurfaceMesh::default();
    for i in 0..=rings {
        let theta = std::f64::consts::PI * i as f64 / rings as f64;
        for j in 0..segments {
            let phi = std::f64::consts::TAU * j as f64 / segments as f64;
            let u = Vector3::new(
                theta.sin() * phi.cos(),
                theta.sin() * phi.sin(),
                theta.cos(),
            );
            m.positions_m.push(u * radius_m);
            m.normals.push(u);
        }
    }
    let s = segments as u32;
    for i in 0..rings as u32 {
        for j in 0..s {
            let a = i * s + j;
            let b = i * s + (j + 1) % s;
            let (c, d) = (a + s, b + s);
            m.indices.extend_from_slice(&[a, c, b, b, c, d]);
        }
    }
    m
}

/// What a constraint surface is.
#[derive(Debug, Clone, PartialEq)]
pub enum SurfaceKind {
    /// Xu 2019 superquadric obstacle (lab frame of the table).
    Superquadric(SuperquadricParams),
    /// Xu 2019 heart-shaped keep-out (lab frame of the table).
    Heart(HeartParams),
    /// Zhang 2018 capture sphere of radius l about a body's centre of mass.
    Capture {
        /// l, m.
        radius_m: f64,
    },
    /// A `KeepOutSphere` guarantee about a body's centre of mass.
    KeepOut {
        /// Guarantee name.
        name: String,
        /// Radius, m.
        radius_m: f64,
    },
}

/// Where a surface sits.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Anchor {
    /// Fixed in the world: the mesh's origin at this world point, m.
    World(Vector3<f64>),
    /// Centred on this body's centre of mass (scene body index), moving with it.
    BodyCom(usize),
}

/// One constraint surface: what it is, where, its mesh (in its own frame) and, for the table
/// prisms, the curve (lab x, y, m) the law's point is kept out of.
#[derive(Debug, Clone)]
pub struct Surface {
    /// What it is.
    pub kind: SurfaceKind,
    /// Where it is.
    pub anchor: Anchor,
    /// Mesh in the anchor's frame.
    pub mesh: SurfaceMesh,
    /// Closed curve in the lab frame (table prisms only), m.
    pub curve_lab_m: Vec<Vector2<f64>>,
    /// RGBA colour (alpha: opacity).
    pub rgba: [f32; 4],
}

impl Surface {
    /// A one-line legend for the panel, with units and frame.
    pub fn legend(&self, scene: &Scene) -> String {
        let body = |a: &Anchor| match a {
            Anchor::BodyCom(i) => scene.bodies.get(*i).map_or("?", |b| b.name.as_str()),
            Anchor::World(_) => "world",
        };
        match &self.kind {
            SurfaceKind::Superquadric(p) => format!(
                "Xu2019 obstacle (magenta): superquadric a {} m, b {} m, s {}, centre ({}, {}) m (lab)",
                p.a_m, p.b_m, p.s, p.centre_lab_m[0], p.centre_lab_m[1]
            ),
            SurfaceKind::Heart(h) => format!(
                "Xu2019 keep-out (orange): heart R1 {} m, R2 {} m, R3 {} m, notch ({}, {}) m (lab)",
                h.r1_m, h.r2_m, h.r3_m, h.centre_lab_m[0], h.centre_lab_m[1]
            ),
            SurfaceKind::Capture { radius_m } => format!(
                "Zhang2018 capture sphere (red): l = {radius_m} m about {}",
                body(&self.anchor)
            ),
            SurfaceKind::KeepOut { name, radius_m } => format!(
                "keep-out {name} (yellow): {radius_m} m about {}",
                body(&self.anchor)
            ),
        }
    }
}

/// Rings and segments of the sphere meshes.
const SPHERE_RINGS: usize = 24;
const SPHERE_SEGMENTS: usize = 48;

/// The constraint surfaces of a scene (see the module doc); empty when it has none.
pub fn scene_surfaces(scene: &Scene) -> Vec<Surface> {
    let mut out = Vec::new();
    let index = |name: &str| scene.bodies.iter().position(|b| b.name == name);
    for c in &scene.controllers {
        if let Some(spec) = c.spec::<crate::control::xu2019::SceneSpec>()
            && matches!(scene.environment, Environment::AirBearing(_))
        {
            let params = spec.params();
            // Prism height: twice the chaser's centre-of-mass height (its plane mid-way).
            let z1 = index(&spec.chaser)
                .map(|i| 2.0 * scene.bodies[i].initial.pos_m[2])
                .filter(|z| *z > 0.0)
                .unwrap_or(0.3);
            let sq = params.obstacle;
            let curve = sq.outline_lab_m(OUTLINE_POINTS);
            out.push(table_prism(
                SurfaceKind::Superquadric(sq.clone()),
                sq.centre(),
                curve,
                z1,
                [1.0, 0.3, 0.75, 0.22],
            ));
            let h = params.heart;
            let curve = h.outline_lab_m(OUTLINE_POINTS);
            out.push(table_prism(
                SurfaceKind::Heart(h.clone()),
                h.centre(),
                curve,
                z1,
                [1.0, 0.55, 0.15, 0.2],
            ));
        } else if let Some(spec) = c.spec::<crate::control::zhang2018::SceneSpec>() {
            // One capture radius per scene (the law checks it): one sphere per body.
            if out
                .iter()
                .any(|s: &Surface| matches!(s.kind, SurfaceKind::Capture { .. }))
            {
                continue;
            }
            for i in 0..scene.bodies.len() {
                out.push(Surface {
                    kind: SurfaceKind::Capture {
                        radius_m: spec.capture_radius_m,
                    },
                    anchor: Anchor::BodyCom(i),
                    mesh: sphere(spec.capture_radius_m, SPHERE_RINGS, SPHERE_SEGMENTS),
                    curve_lab_m: Vec::new(),
                    rgba: [1.0, 0.2, 0.2, 0.12],
                });
            }
        }
    }
    for g in &scene.guarantees {
        if let Some(k) = g.params::<KeepOutSphereParams>()
            && let Some(i) = index(&k.around)
        {
            out.push(Surface {
                kind: SurfaceKind::KeepOut {
                    name: k.name.clone(),
                    radius_m: k.radius_m,
                },
                anchor: Anchor::BodyCom(i),
                mesh: sphere(k.radius_m, SPHERE_RINGS, SPHERE_SEGMENTS),
                curve_lab_m: Vec::new(),
                rgba: [1.0, 0.85, 0.2, 0.1],
            });
        }
    }
    out
}

/// A prism over a lab curve, its mesh relative to `centre` (small f32 coordinates), standing on
/// the table top (z = 0) up to `z1_m`.
fn table_prism(
    kind: SurfaceKind,
    centre: Vector2<f64>,
    curve_lab_m: Vec<Vector2<f64>>,
    z1_m: f64,
    rgba: [f32; 4],
) -> Surface {
    let rel: Vec<_> = curve_lab_m.iter().map(|p| p - centre).collect();
    Surface {
        kind,
        anchor: Anchor::World(Vector3::new(centre.x, centre.y, 0.0)),
        mesh: prism(&rel, 0.0, z1_m),
        curve_lab_m,
        rgba,
    }
}

#[cfg(test)]
mod tests {
    //! Reference: the analytic boundaries — the superquadric's implicit equation
    //! `(x²/a²)^s + (y²/b²)^s = 1` (eq 4), the heart's polar radius `|o2Q|(β)` (eq 11), and
    //! `|r| = radius` for the spheres — evaluated in f64 at every generated vertex.
    use super::*;
    use std::path::Path;

    fn load(name: &str) -> Scene {
        let p = Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("scenes")
            .join(name);
        crate::scene::load_scene_file(&p, &[])
            .expect("scene loads")
            .scene
    }

    fn world_vertex(s: &Surface, v: &Vector3<f64>) -> Vector3<f64> {
        match s.anchor {
            Anchor::World(o) => o + v,
            Anchor::BodyCom(_) => *v,
        }
    }

    #[test]
    fn invariant_viewer_xu2019_prisms_on_the_laws_boundaries() {
        let scene = load("xu2019_simulation.ron");
        let surfaces = scene_surfaces(&scene);
        let Some(spec) = scene.controllers[0].spec::<crate::control::xu2019::SceneSpec>() else {
            panic!("xu2019 scene has an Xu2019 controller");
        };
        let law = spec.params();
        let sq = surfaces
            .iter()
            .find_map(|s| match &s.kind {
                SurfaceKind::Superquadric(p) => Some((s, p)),
                _ => None,
            })
            .expect("superquadric surface");
        let heart = surfaces
            .iter()
            .find_map(|s| match &s.kind {
                SurfaceKind::Heart(p) => Some((s, p)),
                _ => None,
            })
            .expect("heart surface");
        // The very geometry the law uses.
        assert_eq!(sq.1, &law.obstacle);
        assert_eq!(heart.1, &law.heart);
        // Superquadric: every vertex satisfies the implicit equation to 1e-9, at z = 0 or at
        // twice the chaser's centre-of-mass height (0.32 m).
        let (s, p) = sq;
        assert!(s.mesh.positions_m.len() >= 4 * OUTLINE_POINTS);
        for v in &s.mesh.positions_m {
            let w = world_vertex(s, v);
            let f = p.implicit(Vector2::new(w.x, w.y));
            assert!(f.abs() < 1e-9, "vertex {w:?}: implicit − 1 = {f:e}");
            assert!(
                w.z.abs() < 1e-12 || (w.z - 0.32).abs() < 1e-12,
                "z = {}",
                w.z
            );
        }
        // The curve spans the obstacle: x from o1 − a to o1 + a, y from o1 − b to o1 + b.
        let xs = s.mesh.positions_m.iter().map(|v| world_vertex(s, v).x);
        let (lo, hi) = xs.fold((f64::MAX, f64::MIN), |(l, h), x| (l.min(x), h.max(x)));
        assert!((lo - (0.45 - 0.1)).abs() < 1e-12 && (hi - (0.45 + 0.1)).abs() < 1e-12);
        // Heart: every vertex at the boundary radius of eq (11) about the notch, to 1e-9.
        let (s, h) = heart;
        let c = h.centre();
        for v in &s.mesh.positions_m {
            let w = world_vertex(s, v);
            let q = Vector2::new(w.x, w.y) - c;
            let beta = q.y.atan2(q.x);
            let r = h.boundary_radius_m(beta);
            assert!(
                (q.norm() - r).abs() < 1e-9,
                "vertex {w:?}: |o2P| = {} m, |o2Q|(β) = {r} m",
                q.norm()
            );
        }
        // The render mesh is the same vertices (f32 in the surface frame: < 1e-7 m off).
        for s in [sq.0, heart.0] {
            let mesh = s.mesh.to_mesh();
            let Some(bevy::mesh::VertexAttributeValues::Float32x3(pos)) =
                mesh.attribute(Mesh::ATTRIBUTE_POSITION)
            else {
                panic!("positions");
            };
            assert_eq!(pos.len(), s.mesh.positions_m.len());
            for (a, b) in pos.iter().zip(&s.mesh.positions_m) {
                let d = Vector3::new(f64::from(a[0]), f64::from(a[1]), f64::from(a[2])) - b;
                assert!(d.norm() < 1e-7, "f32 vertex {d:?} off");
            }
            let n = s.mesh.positions_m.len() as u32;
            assert!(s.mesh.indices.iter().all(|&i| i < n));
            assert_eq!(s.mesh.indices.len() % 3, 0);
        }
    }

    #[test]
    fn invariant_viewer_capture_and_keep_out_spheres() {
        // Zhang 2018: a sphere of radius l about every body.
        let scene = load("zhang2018_pair.ron");
        let Some(spec) = scene.controllers[0].spec::<crate::control::zhang2018::SceneSpec>() else {
            panic!("zhang2018 scene has a Zhang2018 controller");
        };
        let l = spec.capture_radius_m;
        let caps: Vec<_> = scene_surfaces(&scene)
            .into_iter()
            .filter(|s| matches!(s.kind, SurfaceKind::Capture { .. }))
            .collect();
        assert_eq!(caps.len(), scene.bodies.len());
        for (i, s) in caps.iter().enumerate() {
            assert_eq!(s.anchor, Anchor::BodyCom(i));
            for v in &s.mesh.positions_m {
                assert!(
                    (v.norm() - l).abs() < 1e-9 * l.max(1.0),
                    "|v| = {}",
                    v.norm()
                );
            }
        }
        // free_drift: its KeepOutSphere guarantee (10 m about the target).
        let scene = load("free_drift.ron");
        let ko: Vec<_> = scene_surfaces(&scene)
            .into_iter()
            .filter(|s| matches!(s.kind, SurfaceKind::KeepOut { .. }))
            .collect();
        assert_eq!(ko.len(), 1);
        let target = scene.bodies.iter().position(|b| b.name == "target");
        assert_eq!(ko[0].anchor, Anchor::BodyCom(target.expect("target")));
        assert!(
            ko[0]
                .mesh
                .positions_m
                .iter()
                .all(|v| (v.norm() - 10.0).abs() < 1e-9)
        );
    }
}
