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
//!
//! Tests: `tests/val_spin_bounds.rs` (brute force: each vertex turned about the axis through a
//! grid of angles, measured in f64 against the hull's triangles; shapes that are not faceted
//! revolutions refused).

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
