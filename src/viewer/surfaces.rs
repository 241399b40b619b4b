//! Constraint surfaces (layer `S`), as plain f64 vertex lists (tested without a window) turned
//! into Bevy meshes. The viewer knows no law: every controller entry and every guarantee
//! describes its own surfaces through its `drawn` hook ([`crate::geometry::drawn`]), and a
//! user's law or guarantee draws its own the same way. The built-in ones:
//!
//! - Xu, Wen, Wei (2019), air-bearing table: the superquadric obstacle and the heart-shaped
//!   keep-out of the target, from the scene's `Xu2019` controller
//!   ([`crate::control::xu2019::Xu2019Spec::params`]: `obstacle`, `heart`). Both laws act on the
//!   chaser's centre of mass in the table plane, so each curve is drawn as a vertical prism over
//!   the table (z from the top, 0, to twice the chaser's initial centre-of-mass height, so the
//!   plane the law works in is at mid-height); the curve itself is also drawn as a line at the
//!   chaser's current centre-of-mass height.
//! - Zhang et al. (2018): the capture sphere of radius l (`capture_radius_m`) about every body's
//!   centre of mass (the law's capture guarantee is `|r_a − r_b| ≥ l` for every pair).
//! - Guo et al. (2016): the cissoid approach corridor in the target's body frame.
//! - Every `KeepOutSphere` guarantee: the sphere of `radius_m` about `around`'s centre of mass.

use crate::geometry::drawn::DrawnSurface;
pub use crate::geometry::drawn::OUTLINE_POINTS;
use crate::scene::Scene;
use bevy::asset::RenderAssetUsages;
use bevy::mesh::{Indices, PrimitiveTopology};
use bevy::prelude::Mesh;
use nalgebra::{Vector2, Vector3};

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

/// The surface of revolution about +x of a meridian (x, radius) in m: `segments` around, one
/// ring per meridian point, normals from the meridian's slope (finite differences). Every
/// vertex is at its ring's radius from the axis.
pub fn revolution(meridian_m: &[(f64, f64)], segments: usize) -> SurfaceMesh {
    let mut m = SurfaceMesh::default();
    let n = meridian_m.len();
    for (i, &(x, r)) in meridian_m.iter().enumerate() {
        let (x0, r0) = meridian_m[i.saturating_sub(1)];
        let (x1, r1) = meridian_m[(i + 1).min(n - 1)];
        let slope = if x1 > x0 { (r1 - r0) / (x1 - x0) } else { 0.0 };
        for j in 0..segments {
            let phi = std::f64::consts::TAU * j as f64 / segments as f64;
            let (c, s) = (phi.cos(), phi.sin());
            m.positions_m.push(Vector3::new(x, r * c, r * s));
            m.normals.push(
                Vector3::new(-slope, c, s)
                    .try_normalize(0.0)
                    .unwrap_or_else(Vector3::y),
            );
        }
    }
    let s = segments as u32;
    for i in 0..n.saturating_sub(1) as u32 {
        for j in 0..s {
            let a = i * s + j;
            let b = i * s + (j + 1) % s;
            let (c, d) = (a + s, b + s);
            m.indices.extend_from_slice(&[a, c, b, b, c, d]);
        }
    }
    m
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
    /// The legend line (from the law's or guarantee's hook).
    pub legend: String,
    /// Where it is.
    pub anchor: Anchor,
    /// Mesh in the anchor's frame.
    pub mesh: SurfaceMesh,
    /// Closed curve in the lab frame (table prisms only), m.
    pub curve_lab_m: Vec<Vector2<f64>>,
    /// The body whose centre-of-mass height the curve is drawn at (table prisms only).
    pub curve_body: Option<usize>,
    /// Drawn from both sides (prisms and surfaces of revolution); a sphere shows its inner
    /// side only.
    pub two_sided: bool,
    /// RGBA colour (alpha: opacity).
    pub rgba: [f32; 4],
}

impl Surface {
    /// A one-line legend for the panel, with units and frame.
    pub fn legend(&self) -> &str {
        &self.legend
    }
}

/// Rings and segments of the sphere meshes.
const SPHERE_RINGS: usize = 24;
const SPHERE_SEGMENTS: usize = 48;
/// Segments around a surface of revolution.
const REVOLUTION_SEGMENTS: usize = 48;

/// The constraint surfaces of a scene (see the module doc); empty when it has none.
pub fn scene_surfaces(scene: &Scene) -> Vec<Surface> {
    let mut drawn: Vec<DrawnSurface> = Vec::new();
    let hooks = scene
        .controllers
        .iter()
        .flat_map(|c| c.drawn(scene))
        .chain(scene.guarantees.iter().flat_map(|g| g.drawn(scene)));
    for d in hooks {
        // Several entries of one law (Zhang 2018's per-pair slots) describe the same surface.
        if !drawn.contains(&d) {
            drawn.push(d);
        }
    }
    drawn.into_iter().filter_map(surface_of).collect()
}

/// The viewer's surface for a law's or guarantee's description (none for one that is not
/// [`DrawnSurface::is_drawable`]: an outline of fewer than three points, a non-positive radius,
/// a meridian of fewer than two points, a number not finite or beyond 1e7 m).
pub fn surface_of(d: DrawnSurface) -> Option<Surface> {
    if !d.is_drawable() {
        return None;
    }
    match d {
        DrawnSurface::TablePrism {
            legend,
            outline_lab_m,
            centre_lab_m,
            top_m,
            curve_body,
            rgba,
        } => {
            let rel: Vec<_> = outline_lab_m.iter().map(|p| p - centre_lab_m).collect();
            Some(Surface {
                legend,
                anchor: Anchor::World(Vector3::new(centre_lab_m.x, centre_lab_m.y, 0.0)),
                mesh: prism(&rel, 0.0, top_m),
                curve_lab_m: outline_lab_m,
                curve_body,
                two_sided: true,
                rgba,
            })
        }
        DrawnSurface::SphereAboutBody {
            legend,
            body,
            radius_m,
            rgba,
        } => Some(Surface {
            legend,
            anchor: Anchor::BodyCom(body),
            mesh: sphere(radius_m, SPHERE_RINGS, SPHERE_SEGMENTS),
            curve_lab_m: Vec::new(),
            curve_body: None,
            two_sided: false,
            rgba,
        }),
        DrawnSurface::RevolutionAboutBody {
            legend,
            body,
            meridian_m,
            rgba,
        } => Some(Surface {
            legend,
            anchor: Anchor::BodyCom(body),
            mesh: revolution(&meridian_m, REVOLUTION_SEGMENTS),
            curve_lab_m: Vec::new(),
            curve_body: None,
            two_sided: true,
            rgba,
        }),
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
        let scene = load("papers/xu2019/xu2019_simulation.ron");
        let surfaces = scene_surfaces(&scene);
        let Some(spec) = scene.controllers[0].spec::<crate::control::xu2019::Xu2019Spec>() else {
            panic!("xu2019 scene has an Xu2019 controller");
        };
        let law = spec.params();
        let named = |prefix: &str| {
            surfaces
                .iter()
                .find(|s| s.legend.starts_with(prefix))
                .expect("surface")
        };
        // The very geometry the law uses: its own parameters, and the outline its hook gives.
        let sq = (named("Xu2019 obstacle"), &law.obstacle);
        let heart = (named("Xu2019 keep-out"), &law.heart);
        assert_eq!(sq.0.curve_lab_m, law.obstacle.outline_lab_m(OUTLINE_POINTS));
        assert_eq!(heart.0.curve_lab_m, law.heart.outline_lab_m(OUTLINE_POINTS));
        let chaser = scene.bodies.iter().position(|b| b.name == spec.chaser);
        assert!(chaser.is_some());
        assert_eq!(sq.0.curve_body, chaser);
        assert_eq!(heart.0.curve_body, chaser);
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
        let scene = load("papers/zhang2018/zhang2018_pair.ron");
        let Some(spec) = scene.controllers[0].spec::<crate::control::zhang2018::Zhang2018Spec>()
        else {
            panic!("zhang2018 scene has a Zhang2018 controller");
        };
        let l = spec.capture_radius_m;
        let caps: Vec<_> = scene_surfaces(&scene)
            .into_iter()
            .filter(|s| s.legend.starts_with("Zhang2018 capture sphere"))
            .collect();
        // One sphere per body, whatever the number of the law's entries (deduplicated).
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
        let scene = load("examples/free_drift.ron");
        let ko: Vec<_> = scene_surfaces(&scene)
            .into_iter()
            .filter(|s| s.legend.starts_with("keep-out "))
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

    #[test]
    fn invariant_viewer_guo2016_corridor_on_the_cissoid() {
        // The corridor a Guo 2016 entry draws: every vertex at the cissoid's radius for its x,
        // to 1e-9 m, in the target's body frame, out to r = a.
        let scene = load("papers/guo2016/guo2016_corridor.ron");
        let Some(spec) = scene.controllers[0].spec::<crate::control::guo2016::Guo2016Spec>() else {
            panic!("guo2016 scene has a Guo2016 controller");
        };
        let cis =
            crate::geometry::cissoid::Cissoid::new(spec.corridor_a_m, spec.corridor_tan_theta);
        let list = scene_surfaces(&scene);
        let cor: Vec<_> = list
            .iter()
            .filter(|s| s.legend.starts_with("Guo2016 corridor"))
            .collect();
        assert_eq!(cor.len(), 1);
        let target = scene.bodies.iter().position(|b| b.name == spec.target);
        assert_eq!(Some(cor[0].anchor), target.map(Anchor::BodyCom));
        let m = &cor[0].mesh;
        assert!(m.positions_m.len() >= 2 * REVOLUTION_SEGMENTS);
        for v in &m.positions_m {
            let r = cis.radius_at_m(v.x).expect("inside the corridor's range");
            let rho = (v.y * v.y + v.z * v.z).sqrt();
            assert!(
                (rho - r).abs() < 1e-9,
                "x {} m: ρ {rho} m, cissoid {r} m",
                v.x
            );
            assert!(rho <= cis.a_m + 1e-12);
        }
        let n = m.positions_m.len() as u32;
        assert!(m.indices.iter().all(|&i| i < n));
    }

    /// A guarantee kind the viewer has never seen (a user's): its hook's sphere is drawn.
    #[derive(Debug, Clone)]
    struct UsersRange;

    impl crate::guarantee::registry::GuaranteeParams for UsersRange {
        fn name(&self) -> &str {
            "users_range"
        }
        fn bodies(&self) -> Vec<(&'static str, &str)> {
            vec![("body", "chaser"), ("around", "target")]
        }
        fn build(
            &self,
            _ctx: &crate::guarantee::registry::GuaranteeContext,
        ) -> Result<Box<dyn crate::guarantee::Guarantee>, crate::control::spec::BuildError>
        {
            Err(crate::control::spec::BuildError::at(
                "",
                "not built in this test",
            ))
        }
        fn drawn(&self, scene: &Scene) -> Vec<DrawnSurface> {
            vec![DrawnSurface::SphereAboutBody {
                legend: "users_range: 45 m".into(),
                body: scene.bodies.len() - 1,
                radius_m: 45.0,
                rgba: [0.0, 1.0, 0.0, 0.1],
            }]
        }
    }

    #[test]
    fn invariant_viewer_draws_a_users_guarantee_through_its_hook() {
        // Reference: the hook's own description — a 45 m sphere about the last body, every
        // vertex at 45 m to 1e-9; a degenerate description (radius 0) draws nothing.
        let mut scene = load("examples/free_drift.ron");
        scene
            .guarantees
            .push(crate::guarantee::registry::GuaranteeSpec {
                kind: "UsersRange".into(),
                params: Box::new(UsersRange),
            });
        let list = scene_surfaces(&scene);
        let s: Vec<_> = list
            .iter()
            .filter(|s| s.legend == "users_range: 45 m")
            .collect();
        assert_eq!(s.len(), 1);
        assert_eq!(s[0].anchor, Anchor::BodyCom(scene.bodies.len() - 1));
        assert!(!s[0].two_sided);
        assert!(
            s[0].mesh
                .positions_m
                .iter()
                .all(|v| (v.norm() - 45.0).abs() < 1e-9)
        );
        // Degenerate or hostile descriptions draw nothing: radius 0, NaN, 1e308; a meridian
        // with an infinite point; an outline with a NaN vertex.
        for radius_m in [0.0, f64::NAN, 1e308, -1.0] {
            let none = surface_of(DrawnSurface::SphereAboutBody {
                legend: String::new(),
                body: 0,
                radius_m,
                rgba: [0.0; 4],
            });
            assert!(none.is_none(), "radius {radius_m}");
        }
        assert!(
            surface_of(DrawnSurface::RevolutionAboutBody {
                legend: String::new(),
                body: 0,
                meridian_m: vec![(0.0, 0.0), (1.0, f64::INFINITY)],
                rgba: [0.0; 4],
            })
            .is_none()
        );
        let square = |v: f64| {
            vec![
                Vector2::new(0.0, 0.0),
                Vector2::new(1.0, 0.0),
                Vector2::new(1.0, v),
                Vector2::new(0.0, 1.0),
            ]
        };
        let prism = |outline_lab_m| DrawnSurface::TablePrism {
            legend: String::new(),
            outline_lab_m,
            centre_lab_m: Vector2::new(0.5, 0.5),
            top_m: 0.3,
            curve_body: None,
            rgba: [0.0; 4],
        };
        assert!(surface_of(prism(square(1.0))).is_some());
        assert!(surface_of(prism(square(f64::NAN))).is_none());
    }
}
