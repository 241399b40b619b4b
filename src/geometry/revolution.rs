//! Faceted solids of revolution: a convex hull whose vertices lie, to a measured deviation, on
//! regular N-gons about one axis, all N-gons with the same phase (rings), and on that axis
//! (apexes). The docking cone's hull is one (two 32-gon rings), and so is a regular prism.
//! A body spinning about such a part's axis moves its facets along their normals, yet the
//! part's solid of revolution does not move at all: [`FacetedRevolution::offset_m`] bounds how
//! far that solid reaches beyond the hull, so a distance judged on the solid of revolution is
//! within the offset of the hull's (`sim::monitor::part_pair_rates`).
//!
//! # The bound
//! Let q_i be the ideal vertices: ring k's points at the ring's mean height z_k and mean
//! radius r_k, at the angles φ₀ + 2πm/N (φ₀ fitted to all rings). Their hull H′ is
//! {(x, z) : x ∈ f(z)·K}, with K the regular N-gon of circumradius 1 and f the concave upper
//! envelope of the points (z_k, r_k). (⊆: a convex combination Σλ_k(x_k, z_k) with
//! x_k ∈ r_k·K has Σλ_k x_k ∈ (Σλ_k r_k)·K since K is convex and holds 0, and
//! Σλ_k r_k ≤ f(Σλ_k z_k); ⊇ by the same combinations.) Each slice f(z)·K lies in the disc of
//! radius f(z) and holds the disc of radius f(z)·cos(π/N), so the solid of revolution Rev(H′)
//! lies within s₀ = max_k r_k·(1 − cos(π/N)) of H′. With ε the largest distance between a
//! vertex p_i of the real hull H and its ideal q_i, H ⊆ H′ ⊕ B_ε and H′ ⊆ H ⊕ B_ε, and a
//! rotation about the axis maps a ball onto a ball, so
//!
//! ```text
//!     H ⊆ Rev(H) ⊆ H ⊕ B(s₀ + 2ε)
//! ```
//!
//! and for any set Q: d(Rev(H), Q) ≤ d(H, Q) ≤ d(Rev(H), Q) + s₀ + 2ε. Every point of Rev(H)
//! is as far from a point c on the axis as some point of H, so a sphere about c holding H holds
//! Rev(H) too.

use nalgebra::{Matrix3, SymmetricEigen, Vector3};

/// Fewest vertices per ring.
const MIN_FACETS: usize = 3;

/// A convex hull found to be a faceted solid of revolution ([`faceted_revolution`]), in the
/// frame of its points.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FacetedRevolution {
    /// A point on the axis: the middle of the hull's extent along it, m.
    pub centre_m: Vector3<f64>,
    /// Unit direction of the axis.
    pub axis: Vector3<f64>,
    /// The largest distance of a vertex from [`Self::centre_m`], m.
    pub radius_m: f64,
    /// Vertices per ring, N.
    pub facets: usize,
    /// The largest distance ε of a vertex from its ideal position, m.
    pub deviation_m: f64,
    /// s₀ + 2ε: every point of the solid of revolution lies within this of the hull, m.
    pub offset_m: f64,
}

/// The hull of `points` as a faceted solid of revolution (module docs), if its vertices form
/// rings of N ≥ 3 about some axis with one phase, each ring with every angle φ₀ + 2πm/N once,
/// and the result's offset is below a tenth of its radius (a looser one helps no bound). The
/// axes tried: the principal axes of the points' scatter (the axis of a ring of N ≥ 3 is one),
/// then the frame's own axes; the one with the smallest offset is kept. Points within
/// 1e-6 of the points' scale of the axis are apexes; points within that of a ring's first
/// point along the axis share its ring. Non-finite points, or fewer than six: `None`.
pub fn faceted_revolution(points: &[Vector3<f64>]) -> Option<FacetedRevolution> {
    if points.len() < 2 * MIN_FACETS || points.iter().any(|p| !p.iter().all(|x| x.is_finite())) {
        return None;
    }
    let n = points.len() as f64;
    let mean = points.iter().sum::<Vector3<f64>>() / n;
    let cov = points
        .iter()
        .map(|p| (p - mean) * (p - mean).transpose())
        .sum::<Matrix3<f64>>();
    let eig = SymmetricEigen::new(cov);
    let mut axes: Vec<Vector3<f64>> = (0..3).map(|k| eig.eigenvectors.column(k).into()).collect();
    axes.extend([Vector3::x(), Vector3::y(), Vector3::z()]);
    axes.iter()
        .filter_map(|a| about_axis(points, &mean, a))
        .min_by(|x, y| x.offset_m.total_cmp(&y.offset_m))
}

/// [`faceted_revolution`] about the axis through `mean` along `axis` (normalised here).
fn about_axis(
    points: &[Vector3<f64>],
    mean: &Vector3<f64>,
    axis: &Vector3<f64>,
) -> Option<FacetedRevolution> {
    let e = axis.try_normalize(1e-12)?;
    let scale = points
        .iter()
        .map(|p| (p - mean).norm())
        .fold(0.0_f64, f64::max);
    if scale.is_nan() || scale <= 0.0 || !scale.is_finite() {
        return None;
    }
    // (height, radial vector) of every point, by height.
    let mut hr: Vec<(f64, Vector3<f64>)> = points
        .iter()
        .map(|p| {
            let d = p - mean;
            let z = d.dot(&e);
            (z, d - e * z)
        })
        .collect();
    hr.sort_by(|a, b| a.0.total_cmp(&b.0));
    // Rings: runs of points whose heights differ by at most 1e-6 of the scale from the run's
    // first (the cone's f32 vertices round to ~1e-7 of it); apexes: points on the axis.
    let ring_tol = 1e-6 * scale;
    let mut rings: Vec<Vec<(f64, Vector3<f64>)>> = Vec::new();
    let mut apexes: Vec<(f64, Vector3<f64>)> = Vec::new();
    for &(z, r) in &hr {
        if r.norm() <= ring_tol {
            apexes.push((z, r));
            continue;
        }
        match rings.last_mut() {
            Some(ring) if (z - ring[0].0).abs() <= ring_tol => ring.push((z, r)),
            _ => rings.push(vec![(z, r)]),
        }
    }
    let facets = rings.first()?.len();
    if facets < MIN_FACETS || rings.iter().any(|r| r.len() != facets) {
        return None;
    }
    // Phase: the circular mean of N·φ over every ring point, φ about (u, v).
    let u = rings[0][0].1.normalize();
    let v = e.cross(&u);
    let nf = facets as f64;
    let (mut s, mut c) = (0.0, 0.0);
    for &(_, r) in rings.iter().flatten() {
        let phi = r.dot(&v).atan2(r.dot(&u));
        s += (nf * phi).sin();
        c += (nf * phi).cos();
    }
    let phi0 = s.atan2(c) / nf;
    let step = std::f64::consts::TAU / nf;
    let mut deviation: f64 = 0.0;
    let mut r_max: f64 = 0.0;
    for ring in &rings {
        let z = ring.iter().map(|p| p.0).sum::<f64>() / nf;
        let rad = ring.iter().map(|p| p.1.norm()).sum::<f64>() / nf;
        r_max = r_max.max(rad);
        let mut seen = vec![false; facets];
        for &(zi, r) in ring {
            let phi = r.dot(&v).atan2(r.dot(&u));
            let m = ((phi - phi0) / step).round();
            let slot = m.rem_euclid(nf) as usize;
            if seen[slot] {
                return None;
            }
            seen[slot] = true;
            let a = phi0 + m * step;
            let ideal = e * z + (u * a.cos() + v * a.sin()) * rad;
            deviation = deviation.max((e * zi + r - ideal).norm());
        }
    }
    for (_, r) in &apexes {
        deviation = deviation.max(r.norm());
    }
    let offset = r_max * (1.0 - (std::f64::consts::PI / nf).cos()) + 2.0 * deviation;
    let (z_lo, z_hi) = (hr[0].0, hr[hr.len() - 1].0);
    let centre = mean + e * (0.5 * (z_lo + z_hi));
    let radius = points
        .iter()
        .map(|p| (p - centre).norm())
        .fold(0.0_f64, f64::max);
    (offset.is_finite() && offset < 0.1 * radius).then_some(FacetedRevolution {
        centre_m: centre,
        axis: e,
        radius_m: radius,
        facets,
        deviation_m: deviation,
        offset_m: offset,
    })
}

// The brute-force reference measures parry's hull of the points, so these run with the
// simulation (the `sim` feature); the core builds without parry.
#[cfg(all(test, feature = "sim"))]
mod tests {
    //! Reference: brute force. The hull's vertices turned about the found axis through a grid
    //! of angles, each measured in f64 against the triangles of the hull's boundary (parry's
    //! triangulation; its point projection, GJK in f32, reports 0 for a point 0.5 mm outside
    //! a 0.12 m cone, so it is not used): the distance
    //! to a convex set is convex, so the farthest point of a turned copy of the hull is one of
    //! its vertices, and the largest of these distances is (to the angle grid) how far the
    //! solid of revolution reaches beyond the hull. It must stay within the offset, and the
    //! offset within twice it (the bound is not loose).
    use super::*;
    use bevy_rapier3d::parry::math::Vector as V;
    use bevy_rapier3d::parry::shape::ConvexPolyhedron;

    /// Two rings of `n` about x at heights 0 and `len`, radii `r0`, `r1`, the second turned by
    /// `phase_tip`.
    fn frustum(n: usize, r0: f64, r1: f64, len: f64, phase_tip: f64) -> Vec<Vector3<f64>> {
        let mut pts = Vec::new();
        for k in 0..n {
            let phi = std::f64::consts::TAU * k as f64 / n as f64;
            pts.push(Vector3::new(0.0, r0 * phi.cos(), r0 * phi.sin()));
            let phi = phi + phase_tip;
            pts.push(Vector3::new(len, r1 * phi.cos(), r1 * phi.sin()));
        }
        pts
    }

    fn f32v(p: &Vector3<f64>) -> V {
        V::new(p.x as f32, p.y as f32, p.z as f32)
    }

    /// The distance from `q` to the triangle (a, b, c), f64 (closest point by the triangle's
    /// Voronoi regions, Ericson, *Real-Time Collision Detection* §5.1.5).
    fn point_triangle(
        q: &Vector3<f64>,
        a: &Vector3<f64>,
        b: &Vector3<f64>,
        c: &Vector3<f64>,
    ) -> f64 {
        let (ab, ac, ap) = (b - a, c - a, q - a);
        let (d1, d2) = (ab.dot(&ap), ac.dot(&ap));
        if d1 <= 0.0 && d2 <= 0.0 {
            return ap.norm();
        }
        let bp = q - b;
        let (d3, d4) = (ab.dot(&bp), ac.dot(&bp));
        if d3 >= 0.0 && d4 <= d3 {
            return bp.norm();
        }
        let vc = d1 * d4 - d3 * d2;
        if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
            return (q - (a + ab * (d1 / (d1 - d3)))).norm();
        }
        let cp = q - c;
        let (d5, d6) = (ab.dot(&cp), ac.dot(&cp));
        if d6 >= 0.0 && d5 <= d6 {
            return cp.norm();
        }
        let vb = d5 * d2 - d1 * d6;
        if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
            return (q - (a + ac * (d2 / (d2 - d6)))).norm();
        }
        let va = d3 * d6 - d5 * d4;
        if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
            let w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
            return (q - (b + (c - b) * w)).norm();
        }
        let denom = 1.0 / (va + vb + vc);
        (q - (a + ab * (vb * denom) + ac * (vc * denom))).norm()
    }

    /// The largest distance from the hull of `points` (its boundary triangulated by parry,
    /// measured in f64) of one of its vertices turned about the found axis by 2π·m/`angles`.
    fn brute_offset(points: &[Vector3<f64>], f: &FacetedRevolution, angles: u32) -> f64 {
        let pts: Vec<V> = points.iter().map(f32v).collect();
        let hull = ConvexPolyhedron::from_convex_hull(&pts).expect("hull");
        let (vtx, idx) = hull.to_trimesh();
        let vtx: Vec<Vector3<f64>> = vtx
            .iter()
            .map(|p| Vector3::new(f64::from(p.x), f64::from(p.y), f64::from(p.z)))
            .collect();
        let inner = vtx.iter().sum::<Vector3<f64>>() / vtx.len() as f64;
        // Outward planes (n, h) of the triangles.
        let planes: Vec<(Vector3<f64>, f64)> = idx
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|k| vtx[k as usize]);
                let mut n = (b - a).cross(&(c - a)).normalize();
                if n.dot(&(inner - a)) > 0.0 {
                    n = -n;
                }
                (n, n.dot(&a))
            })
            .collect();
        let axis = nalgebra::Unit::new_normalize(f.axis);
        let mut worst: f64 = 0.0;
        for p in &vtx {
            for m in 0..angles {
                let rot = nalgebra::Rotation3::from_axis_angle(
                    &axis,
                    std::f64::consts::TAU * f64::from(m) / f64::from(angles),
                );
                let q = f.centre_m + rot * (p - f.centre_m);
                if planes.iter().all(|(n, h)| n.dot(&q) <= *h) {
                    continue;
                }
                let d = idx
                    .iter()
                    .map(|t| {
                        let [a, b, c] = t.map(|k| vtx[k as usize]);
                        point_triangle(&q, &a, &b, &c)
                    })
                    .fold(f64::INFINITY, f64::min);
                worst = worst.max(d);
            }
        }
        worst
    }

    #[test]
    fn the_docking_cone_hull_is_found_and_its_offset_bounds_its_solid_of_revolution() {
        let pts = frustum(32, 0.12, 0.03, 0.25, 0.0);
        let f = faceted_revolution(&pts).expect("a faceted cone");
        assert_eq!(f.facets, 32);
        assert!((f.axis.x.abs() - 1.0).abs() < 1e-12, "{f:?}");
        let s0 = 0.12 * (1.0 - (std::f64::consts::PI / 32.0).cos());
        assert!(f.offset_m >= s0 && f.offset_m < s0 * 1.001, "{f:?}");
        let brute = brute_offset(&pts, &f, 1024);
        // The brute force measures the f32 hull: its rounding, ~1e-8 m here, is the 1e-7.
        assert!(brute <= f.offset_m + 1e-7, "{brute} > {}", f.offset_m);
        assert!(brute > 0.5 * f.offset_m, "{brute} vs {}", f.offset_m);
        // The centre is on the axis, half way along, and the radius holds every vertex.
        assert!((f.centre_m - Vector3::new(0.125, 0.0, 0.0)).norm() < 1e-12);
        assert!(pts.iter().all(|p| (p - f.centre_m).norm() <= f.radius_m));
    }

    #[test]
    fn a_tilted_prism_and_a_pyramid_are_found_about_their_axes() {
        let rot = nalgebra::Rotation3::from_euler_angles(0.3, -0.7, 1.1);
        let shift = Vector3::new(0.4, -1.0, 2.0);
        let prism: Vec<_> = frustum(6, 0.5, 0.5, 1.2, 0.0)
            .iter()
            .map(|p| rot * p + shift)
            .collect();
        let f = faceted_revolution(&prism).expect("a hexagonal prism");
        assert_eq!(f.facets, 6);
        assert!((f.axis.dot(&(rot * Vector3::x())).abs() - 1.0).abs() < 1e-9);
        let brute = brute_offset(&prism, &f, 384);
        assert!(
            brute <= f.offset_m + 1e-6 && brute > 0.5 * f.offset_m,
            "{brute} {f:?}"
        );
        // A pyramid: one ring of 8 and an apex on the axis.
        let mut pyramid: Vec<_> = frustum(8, 0.3, 0.0, 0.5, 0.0)
            .into_iter()
            .step_by(2)
            .collect();
        pyramid.push(Vector3::new(0.5, 0.0, 0.0));
        let f = faceted_revolution(&pyramid).expect("a pyramid");
        assert_eq!(f.facets, 8);
        let brute = brute_offset(&pyramid, &f, 512);
        assert!(
            brute <= f.offset_m + 1e-6 && brute > 0.5 * f.offset_m,
            "{brute} {f:?}"
        );
    }

    #[test]
    fn shapes_that_are_not_faceted_revolutions_are_refused() {
        // Rings out of phase (a twisted prism): its slices are not homothetic N-gons.
        assert!(faceted_revolution(&frustum(8, 0.2, 0.2, 0.4, 0.2)).is_none());
        // A box that is not square across any of its axes.
        let mut b = Vec::new();
        for x in [-0.5, 0.5] {
            for y in [-0.3, 0.3] {
                for z in [-0.1, 0.1] {
                    b.push(Vector3::new(x, y, z));
                }
            }
        }
        assert!(faceted_revolution(&b).is_none());
        // A slot wall (two corners of each of two rings).
        let wall: Vec<_> = frustum(16, 0.15, 0.15, 0.2, 0.0)
            .into_iter()
            .take(4)
            .collect();
        assert!(faceted_revolution(&wall).is_none());
        // Rings of different counts.
        let mut uneven = frustum(8, 0.2, 0.1, 0.3, 0.0);
        uneven.pop();
        assert!(faceted_revolution(&uneven).is_none());
        // Hostile values.
        assert!(faceted_revolution(&[]).is_none());
        let mut nan = frustum(8, 0.2, 0.1, 0.3, 0.0);
        nan[3].y = f64::NAN;
        assert!(faceted_revolution(&nan).is_none());
        let huge = frustum(8, 1e300, 1e300, 1e300, 0.0);
        if let Some(f) = faceted_revolution(&huge) {
            assert!(f.offset_m.is_finite() && f.radius_m.is_finite());
        }
        let flat = vec![Vector3::zeros(); 12];
        assert!(faceted_revolution(&flat).is_none());
    }
}
