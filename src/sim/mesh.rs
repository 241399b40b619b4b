//! Mesh parts in parry and rapier: the judged shape (a `TriMesh` with its BVH, used for every
//! monitor distance, guarantee margin and overlap check) and the simulated shape (a compound of
//! the convex pieces of parry's V-HACD decomposition, for rapier's contact dynamics), with the
//! decomposition's measured deviation from the mesh.
//!
//! The deviation is measured, not bounded: the largest of (a) the distance to the mesh of
//! points sampled on every piece's triangles (corners, and a barycentric grid of
//! [`DEVIATION_GRID`] divisions per edge), a point inside a closed mesh counting 0, and (b)
//! the distance from every mesh vertex to the union of the pieces (0 inside a piece). Where
//! the pieces bridge a concavity (a) reports how far they stand out of the mesh; where they
//! miss part of it (b) reports how far the mesh stands out of them.

use super::conv;
use crate::geometry::mesh::{Decomposition, MeshComponent, check_closed};
use crate::scene::DecompositionSpec;
use bevy_rapier3d::parry::query::PointQuery;
use bevy_rapier3d::parry::shape::TriMeshFlags;
use bevy_rapier3d::parry::transformation::vhacd::{VHACD, VHACDParameters};
use bevy_rapier3d::rapier::math::{Pose, Vector};
use bevy_rapier3d::rapier::prelude as rp;
use nalgebra::Point3;

/// Divisions per edge of the barycentric grid sampled on each convex piece's triangles.
pub const DEVIATION_GRID: usize = 8;

fn vertices32(m: &MeshComponent) -> Vec<Vector> {
    m.vertices_m.iter().map(|p| conv::v(&p.coords)).collect()
}

/// The judged shape: the triangle mesh (parry `TriMesh`, BVH built), in the part frame.
pub fn judged_shape(m: &MeshComponent) -> Option<rp::SharedShape> {
    rp::SharedShape::trimesh(vertices32(m), m.triangles.clone()).ok()
}

/// The convex decomposition of a component (computed on first use and kept with the loaded
/// mesh, so every run of a scene shares it).
pub fn decomposition<'a>(m: &'a MeshComponent, spec: &DecompositionSpec) -> &'a Decomposition {
    m.decomposition.get_or_init(|| decompose(m, spec))
}

fn decompose(m: &MeshComponent, spec: &DecompositionSpec) -> Decomposition {
    let pts = vertices32(m);
    let params = VHACDParameters {
        concavity: spec.concavity as f32,
        resolution: spec.resolution,
        max_convex_hulls: spec.max_convex_hulls,
        ..VHACDParameters::default()
    };
    let vhacd = VHACD::decompose(&params, &pts, &m.triangles, true);
    let mut hulls: Vec<_> = vhacd
        .compute_exact_convex_hulls(&pts, &m.triangles)
        .into_iter()
        .filter(|(v, t)| v.len() >= 4 && !t.is_empty())
        .map(|(v, t)| {
            (
                v.into_iter()
                    .map(|p| Point3::from(conv::na(p)))
                    .collect::<Vec<_>>(),
                t,
            )
        })
        .collect();
    if hulls.is_empty() {
        // V-HACD found no volume (a flat or open surface): the convex hull of the vertices.
        if let Ok((v, t)) = bevy_rapier3d::parry::transformation::try_convex_hull(&pts) {
            hulls.push((
                v.into_iter().map(|p| Point3::from(conv::na(p))).collect(),
                t,
            ));
        }
    }
    let max_deviation_m = deviation(m, &hulls);
    Decomposition {
        hulls,
        max_deviation_m,
    }
}

/// The pieces as one rapier shape (a compound of convex polyhedra, part frame).
pub fn pieces_shape(d: &Decomposition) -> Option<rp::SharedShape> {
    let parts: Vec<(Pose, rp::SharedShape)> = d
        .hulls
        .iter()
        .filter_map(|(v, t)| {
            let v32: Vec<Vector> = v.iter().map(|p| conv::v(&p.coords)).collect();
            rp::SharedShape::convex_mesh(v32.clone(), t)
                .or_else(|| rp::SharedShape::convex_hull(&v32))
                .map(|s| (Pose::IDENTITY, s))
        })
        .collect();
    (!parts.is_empty()).then(|| rp::SharedShape::compound(parts))
}

/// The simulated shape of a mesh part for rapier.
pub fn simulated_shape(m: &MeshComponent, spec: &DecompositionSpec) -> Option<rp::SharedShape> {
    pieces_shape(decomposition(m, spec))
}

/// The decomposition's deviation from the mesh, m (see the module docs).
fn deviation(m: &MeshComponent, hulls: &[crate::geometry::mesh::ConvexPiece]) -> f64 {
    let closed = check_closed(m).is_ok();
    let flags = if closed {
        TriMeshFlags::ORIENTED | TriMeshFlags::MERGE_DUPLICATE_VERTICES
    } else {
        TriMeshFlags::empty()
    };
    let Ok(mesh) =
        bevy_rapier3d::parry::shape::TriMesh::with_flags(vertices32(m), m.triangles.clone(), flags)
            .or_else(|_| {
                bevy_rapier3d::parry::shape::TriMesh::new(vertices32(m), m.triangles.clone())
            })
    else {
        return f64::NAN;
    };
    let solid = closed && mesh.pseudo_normals().is_some();
    let mut worst = 0.0f64;
    let n = DEVIATION_GRID;
    for (v, tris) in hulls {
        for t in tris {
            let [a, b, c] = t.map(|i| v[i as usize].coords);
            for i in 0..=n {
                for j in 0..=n - i {
                    let (u, w) = (i as f64 / n as f64, j as f64 / n as f64);
                    let p = a + (b - a) * u + (c - a) * w;
                    let q = conv::v(&p);
                    if solid && mesh.contains_local_point(q) {
                        continue;
                    }
                    let proj = mesh.project_local_point(q, false);
                    worst = worst.max(f64::from((proj.point - q).length()));
                }
            }
        }
    }
    if let Some(pieces) = pieces_shape(&Decomposition {
        hulls: hulls.to_vec(),
        max_deviation_m: 0.0,
    }) {
        for p in &m.vertices_m {
            let q = conv::v(&p.coords);
            let proj = pieces.project_local_point(q, true);
            if !proj.is_inside {
                worst = worst.max(f64::from((proj.point - q).length()));
            }
        }
    }
    worst
}

#[cfg(test)]
mod tests {
    //! Reference: a convex mesh is its own decomposition (deviation at f32 rounding); a
    //! U-shaped mesh's pieces must not fill its slot (the convex hull would, deviating by the
    //! slot's depth), and the deviation is what a point sampled at the slot's mouth gives.
    use super::*;
    use nalgebra::Vector3;

    fn cuboid(lo: Vector3<f64>, hi: Vector3<f64>, name: &str) -> MeshComponent {
        let mut v = Vec::new();
        for i in 0..8 {
            v.push(Point3::new(
                if i & 1 == 0 { lo.x } else { hi.x },
                if i & 2 == 0 { lo.y } else { hi.y },
                if i & 4 == 0 { lo.z } else { hi.z },
            ));
        }
        let quads = [
            [0, 2, 3, 1],
            [4, 5, 7, 6],
            [0, 1, 5, 4],
            [2, 6, 7, 3],
            [0, 4, 6, 2],
            [1, 3, 7, 5],
        ];
        let mut t = Vec::new();
        for q in quads {
            t.push([q[0], q[1], q[2]]);
            t.push([q[0], q[2], q[3]]);
        }
        MeshComponent {
            decomposition: Default::default(),
            offset_m: Vector3::zeros(),
            name: name.into(),
            vertices_m: v,
            triangles: t,
        }
    }

    #[test]
    fn convex_mesh_decomposes_into_itself() {
        let m = cuboid(
            Vector3::new(-1.0, -0.5, -0.25),
            Vector3::new(1.0, 0.5, 0.25),
            "b",
        );
        let d = decomposition(&m, &DecompositionSpec::default());
        assert!(!d.hulls.is_empty());
        assert!(d.max_deviation_m < 1e-5, "{}", d.max_deviation_m);
    }
}
