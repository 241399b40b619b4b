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

/// Most vertices in a leaf of [`HullSupport`]'s tree.
const HULL_LEAF: usize = 8;

/// The support map of the convex hull of a mesh part's vertices, for the monitor's hull bracket
/// (`sim::monitor::hull_bracket`).
///
/// The hull H of the vertices contains every triangle, so it contains the mesh M, whether M is
/// closed or not; its support function h_H(n) = max over the vertices v of n·v. No hull is
/// built (nothing to fail on a flat or degenerate mesh, and no vertex a hull algorithm's
/// tolerance could drop): the vertices are kept in a median-split tree of axis-aligned boxes,
/// and the maximum is found by branch and bound — a node whose box's bound
/// Σ_k max(n_k·lo_k, n_k·hi_k) (the maximum of n·x over the box) is at or below the best vertex
/// found is skipped, so the answer is the exact maximising vertex (to f64 rounding, at most
/// [`HULL_SUPPORT_REL_TOL`] of the vertices' distance from the part origin) at a cost near the
/// tree's depth where the mesh is smooth — where parry's `ConvexPolyhedron` scans every vertex.
#[derive(Debug, Clone)]
pub struct HullSupport {
    /// Vertices, part frame, in tree order (f32, as parry's `TriMesh` holds them), m.
    points: Vec<Vector>,
    /// The same in f64, m.
    points_f64: Vec<[f64; 3]>,
    /// The tree (node 0 the root).
    nodes: Vec<HullNode>,
    /// Largest distance of a vertex from the part origin, m.
    radius_m: f64,
    /// The two spheres bracketing the triangles ([`MeshShell`]), when given
    /// ([`HullSupport::with_shell`]).
    shell: Option<MeshShell>,
}

/// A node of [`HullSupport`]'s tree: the box of its vertices `start..end`, and its children
/// (`left == 0` for a leaf).
#[derive(Debug, Clone, Copy)]
struct HullNode {
    lo: [f64; 3],
    hi: [f64; 3],
    start: u32,
    end: u32,
    left: u32,
    right: u32,
}

/// Relative bound on the f64 rounding of [`HullSupport`]'s maximum (1e-12 of the vertices'
/// largest distance from the part origin, against an actual ≤ 4·2⁻⁵³·√3 ≈ 8e-16 for the
/// three-term dot products and box bounds): the hull bracket subtracts it from its lower bound.
pub const HULL_SUPPORT_REL_TOL: f64 = 1e-12;

impl HullSupport {
    /// The support map of the hull of `vertices` (part frame); `None` without a finite vertex.
    pub fn new(vertices: &[Vector]) -> Option<Self> {
        let p64: Vec<[f64; 3]> = vertices
            .iter()
            .map(|v| [f64::from(v.x), f64::from(v.y), f64::from(v.z)])
            .filter(|p| p.iter().all(|c| c.is_finite()))
            .collect();
        if p64.is_empty() || p64.len() > u32::MAX as usize / 2 {
            return None;
        }
        let mut idx: Vec<usize> = (0..p64.len()).collect();
        let mut nodes = Vec::with_capacity(2 * p64.len() / HULL_LEAF + 1);
        Self::build(&p64, &mut idx, 0, &mut nodes);
        let points_f64: Vec<[f64; 3]> = idx.iter().map(|&k| p64[k]).collect();
        let points = points_f64
            .iter()
            .map(|p| Vector::new(p[0] as f32, p[1] as f32, p[2] as f32))
            .collect();
        let radius_m = points_f64
            .iter()
            .map(|p| (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt())
            .fold(0.0, f64::max);
        Some(Self {
            points,
            points_f64,
            nodes,
            radius_m,
            shell: None,
        })
    }

    /// Builds the subtree of the vertices `idx` (at `offset` in tree order); returns its node.
    fn build(p: &[[f64; 3]], idx: &mut [usize], offset: usize, nodes: &mut Vec<HullNode>) -> u32 {
        let mut lo = [f64::INFINITY; 3];
        let mut hi = [f64::NEG_INFINITY; 3];
        for &k in idx.iter() {
            for c in 0..3 {
                lo[c] = lo[c].min(p[k][c]);
                hi[c] = hi[c].max(p[k][c]);
            }
        }
        let me = nodes.len();
        nodes.push(HullNode {
            lo,
            hi,
            start: offset as u32,
            end: (offset + idx.len()) as u32,
            left: 0,
            right: 0,
        });
        if idx.len() > HULL_LEAF {
            let axis = (0..3)
                .max_by(|a, b| (hi[*a] - lo[*a]).total_cmp(&(hi[*b] - lo[*b])))
                .unwrap_or(0);
            let mid = idx.len() / 2;
            idx.select_nth_unstable_by(mid, |a, b| p[*a][axis].total_cmp(&p[*b][axis]));
            let (l, r) = idx.split_at_mut(mid);
            let left = Self::build(p, l, offset, nodes);
            let right = Self::build(p, r, offset + mid, nodes);
            nodes[me].left = left;
            nodes[me].right = right;
        }
        me as u32
    }

    /// The same, with the shell of the mesh's triangles (`None`: none).
    pub fn with_shell(self, shell: Option<MeshShell>) -> Self {
        Self { shell, ..self }
    }

    /// The shell of the mesh's triangles, if given.
    pub fn shell(&self) -> Option<&MeshShell> {
        self.shell.as_ref()
    }

    /// Largest distance of a vertex from the part origin, m.
    pub fn radius_m(&self) -> f64 {
        self.radius_m
    }

    /// Vertices held.
    pub fn len(&self) -> usize {
        self.points.len()
    }

    /// No vertex (never: [`HullSupport::new`] refuses that).
    pub fn is_empty(&self) -> bool {
        self.points.is_empty()
    }

    /// Index (tree order) of a vertex maximising d·v.
    fn support_index(&self, d: [f64; 3]) -> usize {
        let bound = |n: &HullNode| {
            (0..3)
                .map(|k| (d[k] * n.lo[k]).max(d[k] * n.hi[k]))
                .sum::<f64>()
        };
        let mut best = f64::NEG_INFINITY;
        let mut arg = 0;
        // Depth-first, the child with the higher bound first; the tree is at most
        // log2(vertices) + 1 deep and each level leaves at most one node pending.
        let mut stack = [0u32; 80];
        let mut top = 1;
        while top > 0 {
            top -= 1;
            let n = &self.nodes[stack[top] as usize];
            if n.left == 0 {
                for k in n.start as usize..n.end as usize {
                    let p = &self.points_f64[k];
                    let v = d[0] * p[0] + d[1] * p[1] + d[2] * p[2];
                    if v > best {
                        best = v;
                        arg = k;
                    }
                }
                continue;
            }
            let (l, r) = (n.left, n.right);
            let (bl, br) = (
                bound(&self.nodes[l as usize]),
                bound(&self.nodes[r as usize]),
            );
            let (first, bf, second, bs) = if bl >= br {
                (l, bl, r, br)
            } else {
                (r, br, l, bl)
            };
            if bs > best {
                stack[top] = second;
                top += 1;
            }
            if bf > best {
                stack[top] = first;
                top += 1;
            }
        }
        arg
    }

    /// A vertex maximising d·v (part frame, f64), m.
    pub fn support_f64(&self, d: &nalgebra::Vector3<f64>) -> nalgebra::Vector3<f64> {
        let p = self.points_f64[self.support_index([d.x, d.y, d.z])];
        nalgebra::Vector3::new(p[0], p[1], p[2])
    }
}

/// Two spheres about one centre that bracket a mesh part's triangles, for the monitor's far
/// bracket (`sim::monitor::hull_bracket`): every vertex — so every triangle, a convex
/// combination of its corners — lies within `outer_m` of `centre_m`; and where the mesh is
/// closed (every edge, by vertex position, is crossed once each way: an oriented surface
/// without boundary, whatever its manifoldness) with the centre inside it (its winding number
/// there is not 0), no triangle comes within `inner_m` of the centre.
///
/// What it certifies for a point a outside the outer sphere (|a − c| > `outer_m`), so outside
/// the vertices' hull: the distance from a to the triangles is at least |a − c| − `outer_m`
/// and at most |a − c| − `inner_m`. The lower bound: the triangles lie in the outer ball. The
/// upper: the winding number of a closed triangle surface is an integer, constant off the
/// surface, 0 outside the hull; it is not 0 at c, so the segment from a to c meets the
/// surface, at a point s no nearer c than `inner_m` (no triangle is), and
/// |a − s| = |a − c| − |s − c| ≤ |a − c| − `inner_m`. For a round part far away (a sphere
/// mesh: `outer_m − inner_m` is its sagitta) the two agree to well within parry's own
/// precision, with no support or triangle query at all. The same argument holds for two boxes
/// about c (`outer_half_m`, `inner_half_m`): the distance is at least the distance to the
/// outer box and, from outside it, at most the distance to the inner box — exact to 1e-12 for
/// a box-shaped mesh.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MeshShell {
    /// The centre c: the centre of the vertices' axis-aligned box, part frame, m.
    pub centre_m: [f64; 3],
    /// Every vertex is within this of c (padded by [`SHELL_REL_PAD`]), m.
    pub outer_m: f64,
    /// No triangle comes within this of c (shrunk by [`SHELL_REL_PAD`]), m; `None` when the
    /// mesh is not closed, c is not inside it, or c lies on it.
    pub inner_m: Option<f64>,
    /// Half-extents of the vertices' axis-aligned box about c (it holds every triangle), m.
    pub outer_half_m: [f64; 3],
    /// Half-extents of a box about c, the outer box scaled down, that no triangle meets, m;
    /// `None` where `inner_m` is (the same winding argument puts it inside the solid, so the
    /// distance from a part outside the outer box is at most its distance to this box).
    pub inner_half_m: Option<[f64; 3]>,
}

/// Relative padding of [`MeshShell`]'s radii for their f64 rounding (1e-12 of the centre's
/// distance from the part origin plus the outer radius, against an actual error of a few
/// ulps, ≈ 1e-15, of the differences, dot products and square roots that make them).
pub const SHELL_REL_PAD: f64 = 1e-12;

impl MeshShell {
    /// The shell of the triangles `triangles` over `vertices` (part frame, as parry's `TriMesh`
    /// holds them); `None` without a vertex, with a non-finite vertex or an index out of range.
    pub fn new(vertices: &[Vector], triangles: &[[u32; 3]]) -> Option<Self> {
        let p: Vec<[f64; 3]> = vertices
            .iter()
            .map(|v| [f64::from(v.x), f64::from(v.y), f64::from(v.z)])
            .collect();
        if p.is_empty()
            || p.iter().any(|q| q.iter().any(|c| !c.is_finite()))
            || triangles.iter().flatten().any(|&i| i as usize >= p.len())
        {
            return None;
        }
        let mut lo = [f64::INFINITY; 3];
        let mut hi = [f64::NEG_INFINITY; 3];
        for q in &p {
            for k in 0..3 {
                lo[k] = lo[k].min(q[k]);
                hi[k] = hi[k].max(q[k]);
            }
        }
        let c: [f64; 3] = std::array::from_fn(|k| 0.5 * (lo[k] + hi[k]));
        let sub = |a: &[f64; 3], b: &[f64; 3]| [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
        let norm = |a: &[f64; 3]| (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt();
        let outer = p.iter().map(|q| norm(&sub(q, &c))).fold(0.0, f64::max);
        let pad = SHELL_REL_PAD * (norm(&c) + outer);
        let outer_m = outer + pad;
        let inside = closed_by_position(vertices, triangles) && {
            let w = winding_number(&p, triangles, &c);
            w.round() != 0.0 && (w - w.round()).abs() < 0.25
        };
        let inner_m = inside
            .then(|| {
                triangles
                    .iter()
                    .map(|t| point_triangle_distance(&c, t.map(|i| &p[i as usize])))
                    .fold(f64::INFINITY, f64::min)
                    - pad
            })
            .filter(|r| *r > 0.0);
        let half: [f64; 3] = std::array::from_fn(|k| 0.5 * (hi[k] - lo[k]));
        // The inner box: the outer one scaled by σ about c. In coordinates y_k = (x_k − c_k)/h_k
        // it is the cube max_k |y_k| ≤ σ; a triangle meeting it has, on every axis, a point with
        // |y_k| ≤ σ, so σ below max_k (min over the triangle of |y_k|) — 0 on an axis whose
        // coordinate changes sign over the triangle, else its corner nearest 0 — keeps every
        // triangle out. Exact (σ = 1) for a triangle on a face of the box.
        let inner_half_m = inner_m
            .filter(|_| half.iter().all(|h| *h > 0.0))
            .and_then(|_| {
                let sigma = triangles
                    .iter()
                    .map(|t| {
                        (0..3)
                            .map(|k| {
                                let y = t.map(|i| (p[i as usize][k] - c[k]) / half[k]);
                                let (lo, hi) = (
                                    y.iter().copied().fold(f64::INFINITY, f64::min),
                                    y.iter().copied().fold(f64::NEG_INFINITY, f64::max),
                                );
                                if lo <= 0.0 && hi >= 0.0 {
                                    0.0
                                } else {
                                    lo.abs().min(hi.abs())
                                }
                            })
                            .fold(0.0, f64::max)
                    })
                    .fold(f64::INFINITY, f64::min)
                    - SHELL_REL_PAD;
                (sigma > 0.0 && sigma.is_finite()).then(|| half.map(|h| h * sigma))
            });
        Some(Self {
            centre_m: c,
            outer_m,
            inner_m,
            outer_half_m: half,
            inner_half_m,
        })
    }
}

/// Every edge crossed as often one way as the other, vertices identified by position (so a
/// mesh whose vertices are duplicated along seams, as glTF's often are, still counts).
fn closed_by_position(vertices: &[Vector], triangles: &[[u32; 3]]) -> bool {
    use std::collections::HashMap;
    let mut id: HashMap<[u32; 3], u32> = HashMap::with_capacity(vertices.len());
    let canon: Vec<u32> = vertices
        .iter()
        .map(|v| {
            // +0 and −0 are one position.
            let key = [v.x + 0.0, v.y + 0.0, v.z + 0.0].map(f32::to_bits);
            let n = id.len() as u32;
            *id.entry(key).or_insert(n)
        })
        .collect();
    let mut edges: Vec<(u32, u32, i32)> = Vec::with_capacity(3 * triangles.len());
    for t in triangles {
        let c = t.map(|i| canon[i as usize]);
        for k in 0..3 {
            let (a, b) = (c[k], c[(k + 1) % 3]);
            if a != b {
                edges.push((a.min(b), a.max(b), if a < b { 1 } else { -1 }));
            }
        }
    }
    edges.sort_unstable();
    let mut k = 0;
    while k < edges.len() {
        let (a, b) = (edges[k].0, edges[k].1);
        let mut net = 0;
        while k < edges.len() && (edges[k].0, edges[k].1) == (a, b) {
            net += edges[k].2;
            k += 1;
        }
        if net != 0 {
            return false;
        }
    }
    !triangles.is_empty()
}

/// The winding number of the triangles about x: the sum of their signed solid angles seen
/// from x (van Oosterom and Strackee's formula) over 4π.
fn winding_number(p: &[[f64; 3]], triangles: &[[u32; 3]], x: &[f64; 3]) -> f64 {
    let mut sum = 0.0;
    for t in triangles {
        let [a, b, c] = t.map(|i| {
            let q = &p[i as usize];
            nalgebra::Vector3::new(q[0] - x[0], q[1] - x[1], q[2] - x[2])
        });
        let (la, lb, lc) = (a.norm(), b.norm(), c.norm());
        let num = a.dot(&b.cross(&c));
        let den = la * lb * lc + a.dot(&b) * lc + a.dot(&c) * lb + b.dot(&c) * la;
        sum += 2.0 * num.atan2(den);
    }
    sum / (4.0 * std::f64::consts::PI)
}

/// Distance from x to the triangle (a, b, c), f64; never above the true distance by more than
/// rounding (a projection within 1e-9 of the triangle's edges counts as inside, where the plane
/// distance is at most the true one). Degenerate triangles: the distance to their edges.
fn point_triangle_distance(x: &[f64; 3], [a, b, c]: [&[f64; 3]; 3]) -> f64 {
    use nalgebra::Vector3;
    let (x, a, b, c) = (
        Vector3::from(*x),
        Vector3::from(*a),
        Vector3::from(*b),
        Vector3::from(*c),
    );
    let segment = |p: Vector3<f64>, q: Vector3<f64>| {
        let e = q - p;
        let l2 = e.norm_squared();
        let t = if l2 > 0.0 {
            ((x - p).dot(&e) / l2).clamp(0.0, 1.0)
        } else {
            0.0
        };
        (x - (p + e * t)).norm()
    };
    let edges = segment(a, b).min(segment(b, c)).min(segment(c, a));
    let n = (b - a).cross(&(c - a));
    let n2 = n.norm_squared();
    if n2 > 0.0 && n2.is_finite() {
        // Signed areas of x's projection with each edge, relative to the triangle's.
        let inside = [(a, b), (b, c), (c, a)]
            .iter()
            .all(|(p, q)| (q - p).cross(&(x - p)).dot(&n) >= -1e-9 * n2);
        if inside {
            return ((x - a).dot(&n) / n2.sqrt()).abs().min(edges);
        }
    }
    edges
}

impl bevy_rapier3d::parry::shape::SupportMap for HullSupport {
    fn local_support_point(&self, dir: Vector) -> Vector {
        self.points[self.support_index([f64::from(dir.x), f64::from(dir.y), f64::from(dir.z)])]
    }
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
