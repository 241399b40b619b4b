//! Heart-shaped target keep-out of Xu, Wen, Wei (2019), eqs (9)–(11).
//!
//! Polar form about the heart centre `o2` (lab frame of the air-bearing table, metres),
//! β the polar angle of the point P about o2 in `[0, 2π)` (eq 11, with the sign of
//! the third branch corrected, below):
//!
//! ```text
//! |o2Q| =  2 R1 sin β    β ∈ [0, π/2]        right half of the circle of radius R1 about (0,  R1)
//!          R2            β ∈ (π/2, 3π/2]     left half of the circle of radius R2 about (0, 0)
//!         −2 R3 sin β    β ∈ (3π/2, 2π)      right half of the circle of radius R3 about (0, −R3)
//! ```
//!
//! The published third branch reads `+2R3 sin β`, which is negative on `(3π/2, 2π)`; the minus
//! sign is meant (a radius is positive, and only then do the arcs join). The paper's values
//! (Table 1): `o2 = (0.2, 1.4) m`, `R2 = 2R1 = 2R3 = 0.2 m`. The three arcs meet continuously
//! when `2R1 = R2 = 2R3`; for other radii the outline closes with straight pieces along the
//! local y axis.
//!
//! The notch (cusp, `|o2Q| = 0` at β = 0) is at the centre and opens along +x: the docking
//! approach. The paper's goal (0.25, 1.4) m sits in the notch, 0.05 m radially from o2 but
//! only ≈ 0.0118 m (Euclidean) from the lobes.
//!
//! The region is star-shaped about o2 (one boundary crossing per ray), and it is the union
//! of three convex half-disks (left radius R2 about o2; right radius R1 about o2 + (0, R1);
//! right radius R3 about o2 − (0, R3)): a collider can be built as a compound of three
//! half-disk prisms. It is not convex itself.

use nalgebra::Vector2;
use serde::{Deserialize, Serialize};
use std::f64::consts::PI;

/// Heart keep-out parameters (eq 11, Table 1). Lab frame, metres.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct HeartParams {
    /// Centre `o2` (the notch) in the lab frame (m).
    pub centre_lab_m: [f64; 2],
    /// Upper right lobe radius `R1` (m).
    pub r1_m: f64,
    /// Left (back) semicircle radius `R2` (m).
    pub r2_m: f64,
    /// Lower right lobe radius `R3` (m).
    pub r3_m: f64,
}

impl Default for HeartParams {
    fn default() -> Self {
        Self::paper()
    }
}

/// Distance from `q` to the half of a circle (centre `c`, radius `r`) on the side
/// `x ≥ c.x` (`right = true`) or `x ≤ c.x`.
fn half_circle_distance(q: Vector2<f64>, c: Vector2<f64>, r: f64, right: bool) -> f64 {
    let v = q - c;
    if (right && v.x >= 0.0) || (!right && v.x <= 0.0) {
        (v.norm() - r).abs()
    } else {
        let top = c + Vector2::new(0.0, r);
        let bot = c - Vector2::new(0.0, r);
        (q - top).norm().min((q - bot).norm())
    }
}

/// Distance from `q` to the segment `[a, b]`.
fn segment_distance(q: Vector2<f64>, a: Vector2<f64>, b: Vector2<f64>) -> f64 {
    let ab = b - a;
    let l2 = ab.norm_squared();
    let t = if l2 > 0.0 {
        ((q - a).dot(&ab) / l2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (q - (a + ab * t)).norm()
}

impl HeartParams {
    /// The paper's keep-out (Table 1): centre (0.2, 1.4) m, R2 = 2R1 = 2R3 = 0.2 m.
    pub fn paper() -> Self {
        Self {
            centre_lab_m: [0.2, 1.4],
            r1_m: 0.1,
            r2_m: 0.2,
            r3_m: 0.1,
        }
    }

    /// Centre `o2` as a vector (lab frame, m).
    pub fn centre(&self) -> Vector2<f64> {
        Vector2::new(self.centre_lab_m[0], self.centre_lab_m[1])
    }

    /// Boundary radius `|o2Q|(β)` of eq (11), corrected sign (m). β in rad, any value
    /// (wrapped to `[0, 2π)`).
    pub fn boundary_radius_m(&self, beta_rad: f64) -> f64 {
        let b = beta_rad.rem_euclid(2.0 * PI);
        if b <= 0.5 * PI {
            2.0 * self.r1_m * b.sin()
        } else if b <= 1.5 * PI {
            self.r2_m
        } else {
            -2.0 * self.r3_m * b.sin()
        }
    }

    /// d|o2Q|/dβ (m/rad), branch-wise: `2R1 cos β`, 0, `−2R3 cos β`. At the notch (β = 0)
    /// the one-sided slopes are `+2R1` and `−2R3` (a kink); the `[0, π/2]` branch is used.
    pub fn boundary_radius_derivative_m(&self, beta_rad: f64) -> f64 {
        let b = beta_rad.rem_euclid(2.0 * PI);
        if b <= 0.5 * PI {
            2.0 * self.r1_m * b.cos()
        } else if b <= 1.5 * PI {
            0.0
        } else {
            -2.0 * self.r3_m * b.cos()
        }
    }

    /// True if the lab point is inside or on the outline (`|o2P| ≤ |o2Q|(β)`).
    pub fn contains(&self, p_lab_m: Vector2<f64>) -> bool {
        let q = p_lab_m - self.centre();
        q.norm() <= self.boundary_radius_m(q.y.atan2(q.x))
    }

    /// Signed radial distance `|o2P| − |o2Q|(β)` (eq 10 along the ray; m), negative inside.
    pub fn radial_distance_m(&self, p_lab_m: Vector2<f64>) -> f64 {
        self.radial_distance_with_gradient(p_lab_m).0
    }

    /// Radial distance (m) and its gradient with respect to the lab position (m/m):
    /// `∇d = e_ρ − (|o2Q|'(β)/ρ) e_β`. Discontinuous across the notch ray (β = 0) where the
    /// outline has a kink; zero gradient returned at the centre itself.
    pub fn radial_distance_with_gradient(&self, p_lab_m: Vector2<f64>) -> (f64, Vector2<f64>) {
        let q = p_lab_m - self.centre();
        let rho = q.norm();
        let beta = q.y.atan2(q.x);
        let r = self.boundary_radius_m(beta);
        if rho < 1e-15 {
            return (rho - r, Vector2::zeros());
        }
        let (s, c) = beta.sin_cos();
        let e_rho = Vector2::new(c, s);
        let e_beta = Vector2::new(-s, c);
        let dr = self.boundary_radius_derivative_m(beta);
        (rho - r, e_rho - e_beta * (dr / rho))
    }

    /// Signed minimum Euclidean distance to the outline (m), negative inside. Exact, closed
    /// form: the minimum over the three half-circles (distance to an arc is `| |q−c| − R |`
    /// when q is on the arc's side of its centre, else the nearer end point) and the two
    /// closing segments (zero length in the paper's case).
    pub fn euclidean_distance_m(&self, p_lab_m: Vector2<f64>) -> f64 {
        let q = p_lab_m - self.centre();
        let (r1, r2, r3) = (self.r1_m, self.r2_m, self.r3_m);
        let d = half_circle_distance(q, Vector2::new(0.0, r1), r1, true)
            .min(half_circle_distance(q, Vector2::zeros(), r2, false))
            .min(half_circle_distance(q, Vector2::new(0.0, -r3), r3, true))
            .min(segment_distance(
                q,
                Vector2::new(0.0, 2.0 * r1),
                Vector2::new(0.0, r2),
            ))
            .min(segment_distance(
                q,
                Vector2::new(0.0, -2.0 * r3),
                Vector2::new(0.0, -r2),
            ));
        if self.contains(p_lab_m) { -d } else { d }
    }

    /// Closed outline in the lab frame (m), counter-clockwise, starting at the notch (the
    /// centre), `n ≥ 3` points spread over the three arcs in proportion to their lengths
    /// (first point not repeated at the end). The closing straight pieces of a non-paper
    /// heart (2R1 ≠ R2) are edges between consecutive points.
    pub fn outline_lab_m(&self, n: usize) -> Vec<Vector2<f64>> {
        let (r1, r2, r3) = (self.r1_m, self.r2_m, self.r3_m);
        let total = r1 + r2 + r3;
        let n1 = ((n as f64 * r1 / total).round() as usize).max(1);
        let n3 = ((n as f64 * r3 / total).round() as usize).max(1);
        let n2 = n.saturating_sub(n1 + n3).max(1);
        let c = self.centre();
        let mut pts = Vec::with_capacity(n1 + n2 + n3);
        // arc (centre, radius, start angle, span), traversed counter-clockwise.
        let arcs = [
            (Vector2::new(0.0, r1), r1, -0.5 * PI, n1),
            (Vector2::zeros(), r2, 0.5 * PI, n2),
            (Vector2::new(0.0, -r3), r3, -0.5 * PI, n3),
        ];
        for (ac, r, a0, k) in arcs {
            for i in 0..k {
                let a = a0 + PI * i as f64 / k as f64;
                pts.push(c + ac + Vector2::new(r * a.cos(), r * a.sin()));
            }
        }
        pts
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn h() -> HeartParams {
        HeartParams::paper()
    }

    /// Reference: eq (11) branches at known angles, e.g. β = π/2 → 2R1 = 0.2,
    /// β = π → R2 = 0.2, β = 3π/2 → 2R3 = 0.2, β = π/6 → 2R1·½ = 0.1, β = 0 → 0 (notch).
    /// Corrected third branch: β = 11π/6 → −2R3 sin β = +0.1 (published sign gives −0.1).
    #[test]
    fn val_xu2019_heart_polar_values() {
        let o = h();
        let cases = [
            (0.0, 0.0),
            (PI / 6.0, 0.1),
            (PI / 2.0, 0.2),
            (PI, 0.2),
            (1.5 * PI, 0.2),
            (11.0 * PI / 6.0, 0.1),
            (-PI / 6.0, 0.1),
        ];
        for (b, r) in cases {
            assert!((o.boundary_radius_m(b) - r).abs() < 1e-15, "β={b}");
        }
        // Continuity at the branch joins (no jump in the paper's radii).
        for b in [0.5 * PI, 1.5 * PI] {
            let e = 1e-9;
            assert!((o.boundary_radius_m(b - e) - o.boundary_radius_m(b + e)).abs() < 1e-9);
        }
    }

    /// Reference: points on the local axes, where the nearest outline point is known.
    /// +x through the notch: radial distance is ρ (|o2Q| = 0) but the Euclidean distance is
    /// to the lobes, √(ρ² + R1²) − R1 (ρ ≤ ... any ρ > 0, nearest lobe point on the line
    /// to the lobe centre (0, ±R1), which lies in the right half). −x: ρ − R2 both.
    /// +y above the top: nearest is the top (0, 2R1): ρ − 0.2 radially and in Euclid.
    #[test]
    fn val_xu2019_heart_on_axes() {
        let o = h();
        let c = o.centre();
        for rho in [0.05, 0.1, 0.3] {
            let p = c + Vector2::new(rho, 0.0);
            assert!((o.radial_distance_m(p) - rho).abs() < 1e-15);
            let eu = (rho * rho + 0.01f64).sqrt() - 0.1;
            assert!((o.euclidean_distance_m(p) - eu).abs() < 1e-15);
        }
        // The goal (0.25, 1.4): 0.05 m radially, 0.0118 m from the lobes.
        let goal = Vector2::new(0.25, 1.4);
        assert!((o.euclidean_distance_m(goal) - (0.0125f64.sqrt() - 0.1)).abs() < 1e-15);
        for rho in [0.25, 0.5] {
            let p = c - Vector2::new(rho, 0.0);
            assert!((o.radial_distance_m(p) - (rho - 0.2)).abs() < 1e-15);
            assert!((o.euclidean_distance_m(p) - (rho - 0.2)).abs() < 1e-15);
            let p = c + Vector2::new(0.0, rho);
            assert!((o.radial_distance_m(p) - (rho - 0.2)).abs() < 1e-15);
            assert!((o.euclidean_distance_m(p) - (rho - 0.2)).abs() < 1e-15);
        }
        // Inside: the lobe centre (0, R1) is R1 from its own arc and from the notch.
        let p = c + Vector2::new(0.0, 0.1);
        assert!((o.euclidean_distance_m(p) + 0.1).abs() < 1e-15);
        assert!((o.radial_distance_m(p) + 0.1).abs() < 1e-15);
    }

    /// Reference: brute force over 3e5 points sampled on the polar form (11) directly
    /// (not the arcs the implementation uses).
    #[test]
    fn val_xu2019_heart_euclidean_vs_brute_force() {
        let o = h();
        let n = 300_000;
        let pts: Vec<Vector2<f64>> = (0..n)
            .map(|k| {
                let b = 2.0 * PI * k as f64 / n as f64;
                let r = o.boundary_radius_m(b);
                o.centre() + Vector2::new(r * b.cos(), r * b.sin())
            })
            .collect();
        for (x, y) in [
            (0.25, 1.4),
            (0.35, 1.2),
            (0.5, 1.45),
            (0.0, 1.0),
            (0.1, 1.7),
            (0.25, 1.45),
            (0.22, 1.33),
            (0.6, 0.9),
        ] {
            let p = Vector2::new(x, y);
            let brute = pts
                .iter()
                .map(|c| (p - c).norm())
                .fold(f64::INFINITY, f64::min);
            let d = o.euclidean_distance_m(p);
            // Sampling gap ≤ R·dβ·2 = 0.2·2π/3e5·2 ≈ 8.4e-6 m: brute exceeds the exact
            // distance by at most half of it.
            assert!(d.abs() <= brute + 1e-12, "{p}: {d} vs {brute}");
            assert!(brute - d.abs() < 5e-6, "{p}: {d} vs {brute}");
            let dr = o.radial_distance_m(p);
            assert!(dr.abs() >= d.abs() - 1e-12);
            assert_eq!(dr < 0.0, d < 0.0, "{p}");
        }
    }

    /// Reference: central finite differences of the radial distance (away from the notch
    /// ray and the centre).
    #[test]
    fn val_xu2019_heart_gradient_fd() {
        let o = h();
        let eps = 1e-7;
        for (x, y) in [(0.35, 1.2), (0.5, 1.5), (0.0, 1.0), (0.1, 1.7), (0.3, 1.3)] {
            let p = Vector2::new(x, y);
            let (_, g) = o.radial_distance_with_gradient(p);
            let fx = (o.radial_distance_m(p + Vector2::new(eps, 0.0))
                - o.radial_distance_m(p - Vector2::new(eps, 0.0)))
                / (2.0 * eps);
            let fy = (o.radial_distance_m(p + Vector2::new(0.0, eps))
                - o.radial_distance_m(p - Vector2::new(0.0, eps)))
                / (2.0 * eps);
            assert!((g - Vector2::new(fx, fy)).norm() < 1e-6, "{p}");
        }
    }

    /// Outline points lie on eq (11) (radial distance zero), count is n, and ordering is
    /// counter-clockwise (positive shoelace area = π(R2² + R1² + R3²)/2 up to the polygon's
    /// chord deficit).
    #[test]
    fn invariant_heart_outline() {
        let o = h();
        let pts = o.outline_lab_m(400);
        assert_eq!(pts.len(), 400);
        for p in &pts {
            assert!(o.euclidean_distance_m(*p).abs() < 1e-14);
        }
        let mut area = 0.0;
        for i in 0..pts.len() {
            let (a, b) = (pts[i], pts[(i + 1) % pts.len()]);
            area += 0.5 * (a.x * b.y - a.y * b.x);
        }
        let exact = 0.5 * PI * (0.04 + 0.01 + 0.01);
        // Chord deficit of a polygon inscribed in an arc: ~ (π/k)²/6 relative, k ≥ 100.
        assert!(
            area > 0.0 && (area - exact).abs() / exact < 2e-3,
            "{area} vs {exact}"
        );
    }
}
