//! Superquadric (super-ellipse) obstacle of Xu, Wen, Wei (2019), eqs (4)–(8).
//!
//! The obstacle is the closed curve `(x²/a²)^s + (y²/b²)^s = 1` (eq 4) about the centre `o1`,
//! in the lab frame of the air-bearing table (x, y on the table, metres). The paper
//! (Table 1) uses `a = 0.1 m`, `b = 0.2 m`, `s = 4`, `o1 = (0.45, 0.6) m`: a rounded rectangle,
//! 0.2 m wide along x and 0.4 m tall along y. For `s ≥ 1/2` the curve is convex (exponent
//! `2s ≥ 1`), so its [`SuperquadricParams::outline_lab_m`] polygon is a valid convex collider.
//!
//! Three distances from a point M (the chaser's centre of mass) are offered:
//!
//! - [`RadialForm::PaperEq8`] — as published, for reproduction: `|NM| = |o1M − o1N|` (eq 7)
//!   with `o1N = (±a (cos²α)^{1/2s}, ±b (sin²α)^{1/2s})` (eq 8), α the polar angle of M about
//!   o1 and the signs those of cos α, sin α. N lies on the curve but, unless `a = b` and
//!   `s = 1`, *not on the ray o1M*; `|NM|` is a norm, never negative, and it is not zero when
//!   M is on the curve off the axes. The published barrier therefore does not vanish on the
//!   obstacle boundary. It is kept as published, to reproduce the paper; the test
//!   `val_xu2019_eq8_differs_off_axis` shows the difference.
//! - [`RadialForm::Exact`] — the radial distance the paper defines in §2.1: the ray o1M
//!   crosses the curve at `r(α) = [(cos²α/a²)^s + (sin²α/b²)^s]^(−1/2s)`, so the signed
//!   radial distance is `|o1M| − r(α)` (negative inside).
//! - [`SuperquadricParams::euclidean_distance_m`] — the true signed minimum Euclidean distance
//!   to the curve, for the full-geometry monitor (numerical, see its doc).

use nalgebra::{Matrix2, Vector2};
use serde::{Deserialize, Serialize};
use std::f64::consts::PI;

/// Which radial distance to the superquadric a law uses.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum RadialForm {
    /// The paper's eq (8) point N (parametric angle set equal to the polar angle): `|NM|`,
    /// never negative, not zero on the boundary off the axes. For reproduction.
    PaperEq8,
    /// The exact ray–curve intersection `r(α)`: signed `|o1M| − r(α)`, zero on the boundary.
    Exact,
}

/// Superquadric obstacle parameters (eq 4, Table 1). Lab frame, metres.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SuperquadricParams {
    /// Half-width along lab x, `a` (m).
    pub a_m: f64,
    /// Half-height along lab y, `b` (m).
    pub b_m: f64,
    /// Exponent `s` (dimensionless, > 0; ≥ 1/2 for a convex curve, ≥ 1 for a C¹ `r(α)`).
    pub s: f64,
    /// Centre `o1` in the lab frame (m).
    pub centre_lab_m: [f64; 2],
}

impl Default for SuperquadricParams {
    fn default() -> Self {
        Self::paper()
    }
}

/// Signed angle-wrapped polar coordinates of `q` (relative to a centre): (ρ, α, e_ρ, e_α).
fn polar(q: Vector2<f64>) -> (f64, f64, Vector2<f64>, Vector2<f64>) {
    let rho = q.norm();
    let alpha = q.y.atan2(q.x);
    let (s, c) = alpha.sin_cos();
    (rho, alpha, Vector2::new(c, s), Vector2::new(-s, c))
}

impl SuperquadricParams {
    /// The paper's obstacle (Table 1): a = 0.1 m, b = 0.2 m, s = 4, centre (0.45, 0.6) m.
    pub fn paper() -> Self {
        Self {
            a_m: 0.1,
            b_m: 0.2,
            s: 4.0,
            centre_lab_m: [0.45, 0.6],
        }
    }

    /// Centre `o1` as a vector (lab frame, m).
    pub fn centre(&self) -> Vector2<f64> {
        Vector2::new(self.centre_lab_m[0], self.centre_lab_m[1])
    }

    /// Implicit function `(x²/a²)^s + (y²/b²)^s − 1` at a lab point (dimensionless):
    /// negative inside, zero on the curve, positive outside.
    pub fn implicit(&self, p_lab_m: Vector2<f64>) -> f64 {
        let q = p_lab_m - self.centre();
        (q.x * q.x / (self.a_m * self.a_m)).powf(self.s)
            + (q.y * q.y / (self.b_m * self.b_m)).powf(self.s)
            - 1.0
    }

    /// True if the lab point is inside or on the curve.
    pub fn contains(&self, p_lab_m: Vector2<f64>) -> bool {
        self.implicit(p_lab_m) <= 0.0
    }

    /// Exact boundary radius along polar angle α about o1 (m):
    /// `r(α) = [(cos²α/a²)^s + (sin²α/b²)^s]^(−1/2s)`.
    pub fn boundary_radius_m(&self, alpha_rad: f64) -> f64 {
        self.g(alpha_rad).powf(-0.5 / self.s)
    }

    fn g(&self, alpha: f64) -> f64 {
        let (s, c) = alpha.sin_cos();
        (c * c / (self.a_m * self.a_m)).powf(self.s) + (s * s / (self.b_m * self.b_m)).powf(self.s)
    }

    /// d r/dα (m/rad), from `r = g^{−1/2s}`, `g' = 2 s sinα cosα [(sin²α/b²)^{s−1}/b² −
    /// (cos²α/a²)^{s−1}/a²]`.
    pub fn boundary_radius_derivative_m(&self, alpha_rad: f64) -> f64 {
        let (sn, c) = alpha_rad.sin_cos();
        let (a2, b2) = (self.a_m * self.a_m, self.b_m * self.b_m);
        let g = self.g(alpha_rad);
        let dg = 2.0
            * self.s
            * sn
            * c
            * ((sn * sn / b2).powf(self.s - 1.0) / b2 - (c * c / a2).powf(self.s - 1.0) / a2);
        -0.5 / self.s * g.powf(-0.5 / self.s - 1.0) * dg
    }

    /// The paper's eq (8) point `o1N` relative to o1 (m) for polar angle α:
    /// `(sgn(cos α) a (cos²α)^{1/2s}, sgn(sin α) b (sin²α)^{1/2s})`. It lies on the curve.
    pub fn eq8_point_m(&self, alpha_rad: f64) -> Vector2<f64> {
        let (sn, c) = alpha_rad.sin_cos();
        let e = 0.5 / self.s;
        Vector2::new(
            c.signum() * self.a_m * (c * c).powf(e),
            sn.signum() * self.b_m * (sn * sn).powf(e),
        )
    }

    /// d(o1N)/dα for the eq (8) point (m/rad). Infinite on the axes (cos α = 0 or
    /// sin α = 0) when s > 1: `|c|^{1/s}` has an unbounded slope at 0.
    fn eq8_point_derivative_m(&self, alpha_rad: f64) -> Vector2<f64> {
        let (sn, c) = alpha_rad.sin_cos();
        let k = 1.0 / self.s;
        Vector2::new(
            self.a_m * k * c.abs().powf(k - 1.0) * (-sn),
            self.b_m * k * sn.abs().powf(k - 1.0) * c,
        )
    }

    /// Radial distance from a lab point to the curve (m), in the chosen form (see the
    /// module doc). `Exact` is signed (negative inside); `PaperEq8` is `|NM| ≥ 0`.
    pub fn radial_distance_m(&self, p_lab_m: Vector2<f64>, form: RadialForm) -> f64 {
        self.radial_distance_with_gradient(p_lab_m, form).0
    }

    /// Radial distance (m) and its gradient with respect to the lab position (1/1, i.e.
    /// m per m). Exact form: `∇d = e_ρ − (r'(α)/ρ) e_α`. Eq (8) form, with `v = o1M − o1N`:
    /// `∇|v| = (I − e_α N'(α)ᵀ/ρ) v/|v|`, which is unbounded near the curve's axes for
    /// s > 1 (see [`RadialForm::PaperEq8`]); on an axis it is non-finite. At the centre
    /// itself (ρ = 0) the gradient is returned as zero.
    pub fn radial_distance_with_gradient(
        &self,
        p_lab_m: Vector2<f64>,
        form: RadialForm,
    ) -> (f64, Vector2<f64>) {
        let q = p_lab_m - self.centre();
        let (rho, alpha, e_rho, e_alpha) = polar(q);
        match form {
            RadialForm::Exact => {
                let r = self.boundary_radius_m(alpha);
                if rho < 1e-15 {
                    return (-r, Vector2::zeros());
                }
                let dr = self.boundary_radius_derivative_m(alpha);
                (rho - r, e_rho - e_alpha * (dr / rho))
            }
            RadialForm::PaperEq8 => {
                let v = q - self.eq8_point_m(alpha);
                let d = v.norm();
                if rho < 1e-15 || d < 1e-300 {
                    return (d, Vector2::zeros());
                }
                let dn = self.eq8_point_derivative_m(alpha);
                let jac: Matrix2<f64> = Matrix2::identity() - dn * e_alpha.transpose() / rho;
                (d, jac.transpose() * (v / d))
            }
        }
    }

    /// Signed minimum Euclidean distance from a lab point to the curve (m): negative inside.
    ///
    /// Numerical: the curve is parametrised by polar angle, `C(α) = r(α)(cos α, sin α)`;
    /// `|q − C(α)|²` is sampled at 1440 uniform angles and the best sample's bracket
    /// (± one sample spacing) is refined by golden-section search to 1e-13 rad. The result is
    /// the global minimum whenever the nearest curve point lies in the bracket of the best
    /// sample, which holds unless two far-apart curve points are equidistant to within the
    /// sampling error (chord error ≤ ~(Δα·r)²/(8·ρ_curv) ≈ 1e-6 m for the paper's curve);
    /// there either answer is within that error of the true distance.
    pub fn euclidean_distance_m(&self, p_lab_m: Vector2<f64>) -> f64 {
        let q = p_lab_m - self.centre();
        let dist2 = |alpha: f64| {
            let r = self.boundary_radius_m(alpha);
            let (s, c) = alpha.sin_cos();
            (q - Vector2::new(r * c, r * s)).norm_squared()
        };
        const N: usize = 1440;
        let h = 2.0 * PI / N as f64;
        let (mut best_i, mut best) = (0, f64::INFINITY);
        for i in 0..N {
            let d2 = dist2(i as f64 * h);
            if d2 < best {
                best = d2;
                best_i = i;
            }
        }
        let (mut lo, mut hi) = ((best_i as f64 - 1.0) * h, (best_i as f64 + 1.0) * h);
        let gr = 0.5 * (5f64.sqrt() - 1.0);
        let mut x1 = hi - gr * (hi - lo);
        let mut x2 = lo + gr * (hi - lo);
        let (mut f1, mut f2) = (dist2(x1), dist2(x2));
        while hi - lo > 1e-13 {
            if f1 < f2 {
                hi = x2;
                x2 = x1;
                f2 = f1;
                x1 = hi - gr * (hi - lo);
                f1 = dist2(x1);
            } else {
                lo = x1;
                x1 = x2;
                f1 = f2;
                x2 = lo + gr * (hi - lo);
                f2 = dist2(x2);
            }
        }
        let d = best.min(f1).min(f2).sqrt();
        if self.contains(p_lab_m) { -d } else { d }
    }

    /// Closed outline in the lab frame (m): `n` points `o1 + r(α_k)(cos α_k, sin α_k)`,
    /// `α_k = 2πk/n`, counter-clockwise, first point not repeated at the end. Convex for
    /// s ≥ 1/2, so usable as the cross-section of a convex prism collider.
    pub fn outline_lab_m(&self, n: usize) -> Vec<Vector2<f64>> {
        let c = self.centre();
        (0..n)
            .map(|k| {
                let alpha = 2.0 * PI * k as f64 / n as f64;
                let r = self.boundary_radius_m(alpha);
                c + Vector2::new(r * alpha.cos(), r * alpha.sin())
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sq() -> SuperquadricParams {
        SuperquadricParams::paper()
    }

    /// Reference: on the axes the curve is at (±a, 0) and (0, ±b), so a point on the
    /// x axis at distance ρ from o1 is exactly ρ − a from the curve in all three measures.
    #[test]
    fn val_xu2019_superquadric_on_axes() {
        let o = sq();
        let c = o.centre();
        for (dir, half) in [
            (Vector2::new(1.0, 0.0), 0.1),
            (Vector2::new(-1.0, 0.0), 0.1),
            (Vector2::new(0.0, 1.0), 0.2),
            (Vector2::new(0.0, -1.0), 0.2),
        ] {
            for rho in [0.25, 0.5, 1.0] {
                let p = c + dir * rho;
                let exact = rho - half;
                assert!((o.radial_distance_m(p, RadialForm::Exact) - exact).abs() < 1e-14);
                // Eq (8) on the axes: sin(π) rounds to 1.2e-16, and (sin²)^{1/8} magnifies it
                // to N.y = b·1.05e-4 ≈ 2.1e-5 m (cos(π/2) likewise: N.x ≈ 8.8e-6 m), so |NM|
                // is off by ≈ (2.1e-5)²/(2d) ≤ 1.5e-9 m at d = 0.15 m.
                assert!((o.radial_distance_m(p, RadialForm::PaperEq8) - exact).abs() < 3e-9);
                // Nearest point on a convex curve from an axis point outside: the axis
                // vertex, provided the curvature radius there exceeds the distance... For
                // s = 4 the vertex is flat (curvature 0), so the vertex is nearest.
                assert!((o.euclidean_distance_m(p) - exact).abs() < 1e-9, "{p}");
            }
        }
    }

    /// Reference: boundary points satisfy the implicit equation (4); the eq (8) point too.
    #[test]
    fn invariant_superquadric_boundary_on_curve() {
        let o = sq();
        for k in 0..360 {
            let alpha = k as f64 * PI / 180.0 + 0.001;
            let r = o.boundary_radius_m(alpha);
            let p = o.centre() + Vector2::new(r * alpha.cos(), r * alpha.sin());
            assert!(o.implicit(p).abs() < 1e-12);
            assert!(o.radial_distance_m(p, RadialForm::Exact).abs() < 1e-15);
            assert!(o.euclidean_distance_m(p).abs() < 1e-9);
            let n = o.centre() + o.eq8_point_m(alpha);
            assert!(o.implicit(n).abs() < 1e-12);
        }
    }

    /// Off the axes the paper's eq (8) point is not on the ray o1M, so |NM| > 0 on the
    /// boundary itself. Reference: the exact intersection r(α) (zero there).
    #[test]
    fn val_xu2019_eq8_differs_off_axis() {
        let o = sq();
        let alpha = PI / 4.0;
        let r = o.boundary_radius_m(alpha);
        let p = o.centre() + Vector2::new(r * alpha.cos(), r * alpha.sin());
        let d8 = o.radial_distance_m(p, RadialForm::PaperEq8);
        let dx = o.radial_distance_m(p, RadialForm::Exact);
        // N(π/4) = (a·2^{-1/8}, b·2^{-1/8}) = (0.0917, 0.1834); M = r(π/4)(1,1)/√2.
        let n = Vector2::new(0.1, 0.2) * 2f64.powf(-1.0 / 8.0);
        let m = Vector2::new(r, r) / 2f64.sqrt();
        assert!((d8 - (m - n).norm()).abs() < 1e-14);
        assert!(dx.abs() < 1e-15);
        assert!(d8 > 0.05, "eq (8) |NM| on the boundary at 45°: {d8} m");
        // Inside the obstacle, at its centre-ish, eq (8) still gives a positive distance.
        let inside = o.centre() + Vector2::new(0.02, 0.03);
        assert!(o.radial_distance_m(inside, RadialForm::PaperEq8) > 0.0);
        assert!(o.radial_distance_m(inside, RadialForm::Exact) < 0.0);
    }

    /// Reference: brute-force sampling of the implicit curve via the eq (5) parametrisation
    /// (a different parametrisation from the polar one used inside), 2e5 points.
    #[test]
    fn val_xu2019_superquadric_euclidean_vs_brute_force() {
        let o = sq();
        let n = 200_000;
        let pts: Vec<Vector2<f64>> = (0..n)
            .map(|k| o.centre() + o.eq8_point_m(2.0 * PI * k as f64 / n as f64))
            .collect();
        let probes = [
            (0.62, 0.83),
            (0.30, 0.30),
            (0.809, 0.224),
            (0.56, 0.81),
            (0.45, 0.95),
            (0.20, 0.62),
            (0.48, 0.65),
            (0.40, 0.52),
        ];
        for (x, y) in probes {
            let p = Vector2::new(x, y);
            let brute = pts
                .iter()
                .map(|c| (p - c).norm())
                .fold(f64::INFINITY, f64::min);
            let d = o.euclidean_distance_m(p);
            // Brute-force error: half the largest gap between samples (the eq (5) spacing is
            // worst on the flat sides, ≈ 2e-5 m here); the numeric answer can only be ≤ it.
            assert!(d.abs() <= brute + 1e-12, "{p}: {d} vs {brute}");
            assert!(brute - d.abs() < 2e-5, "{p}: {d} vs {brute}");
            // The radial (exact) distance is never shorter than the Euclidean one.
            let dr = o.radial_distance_m(p, RadialForm::Exact);
            assert!(dr.abs() >= d.abs() - 1e-12);
            assert_eq!(dr < 0.0, d < 0.0);
        }
    }

    /// Reference: central finite differences of the distance functions.
    #[test]
    fn val_xu2019_superquadric_gradient_fd() {
        let o = sq();
        let h = 1e-7;
        for (x, y) in [
            (0.62, 0.83),
            (0.809, 0.224),
            (0.2, 0.7),
            (0.5, 0.3),
            (0.3, 1.0),
        ] {
            let p = Vector2::new(x, y);
            for form in [RadialForm::Exact, RadialForm::PaperEq8] {
                let (_, g) = o.radial_distance_with_gradient(p, form);
                let fx = (o.radial_distance_m(p + Vector2::new(h, 0.0), form)
                    - o.radial_distance_m(p - Vector2::new(h, 0.0), form))
                    / (2.0 * h);
                let fy = (o.radial_distance_m(p + Vector2::new(0.0, h), form)
                    - o.radial_distance_m(p - Vector2::new(0.0, h), form))
                    / (2.0 * h);
                // Central-difference error ~ h²·d³/6 + ε/h ≈ 1e-8 at these scales.
                assert!(
                    (g - Vector2::new(fx, fy)).norm() < 1e-6,
                    "{form:?} {p}: {g} vs ({fx},{fy})"
                );
            }
        }
    }

    /// The outline is convex, counter-clockwise, and on the curve.
    #[test]
    fn invariant_superquadric_outline_convex() {
        let o = sq();
        let pts = o.outline_lab_m(256);
        assert_eq!(pts.len(), 256);
        for i in 0..pts.len() {
            let (a, b, c) = (pts[i], pts[(i + 1) % 256], pts[(i + 2) % 256]);
            let cross = (b - a).x * (c - b).y - (b - a).y * (c - b).x;
            // Strictly convex, but near the flat vertices (|y/b|^8 ~ 1e-16) the turn is below
            // rounding of the coordinates (~1e-17 m × 2.5e-3 m): allow that much.
            assert!(cross > -1e-18, "{i}: {cross}");
            assert!(o.implicit(a).abs() < 1e-12);
        }
    }
}
