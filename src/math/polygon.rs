//! Convex polygons in the plane for exact reachable-set propagation of a discretised
//! double integrator (used by the thrust-limited error bound of `reproduce::xu2015`).
//!
//! A [`ConvexPolygon`] is its vertex list in counter-clockwise order. Operations are exact up
//! to f64 rounding: a linear map, the Minkowski sum with an axis-aligned rectangle (convex
//! hull of the translated vertices, Andrew's monotone chain), and clipping by a half-plane
//! (Sutherland–Hodgman on a convex polygon). None of them ever drops a vertex that carries
//! area except by the clip itself, so a propagated polygon contains every state the exact set
//! contains, to rounding.

use nalgebra::{Matrix2, Vector2};

/// A convex polygon, vertices counter-clockwise; empty when it has no vertex.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct ConvexPolygon {
    /// Vertices, counter-clockwise (a degenerate polygon may have 1 or 2).
    pub pts: Vec<Vector2<f64>>,
}

fn cross(o: &Vector2<f64>, a: &Vector2<f64>, b: &Vector2<f64>) -> f64 {
    (a.x - o.x) * (b.y - o.y) - (a.y - o.y) * (b.x - o.x)
}

/// Convex hull (counter-clockwise, collinear points dropped) of a point set.
pub fn convex_hull(mut p: Vec<Vector2<f64>>) -> Vec<Vector2<f64>> {
    p.sort_by(|a, b| a.x.total_cmp(&b.x).then(a.y.total_cmp(&b.y)));
    p.dedup();
    if p.len() < 3 {
        return p;
    }
    let mut h: Vec<Vector2<f64>> = Vec::with_capacity(2 * p.len());
    for pass in 0..2 {
        let start = h.len();
        let iter: Box<dyn Iterator<Item = &Vector2<f64>>> = if pass == 0 {
            Box::new(p.iter())
        } else {
            Box::new(p.iter().rev())
        };
        for q in iter {
            while h.len() >= start + 2 && cross(&h[h.len() - 2], &h[h.len() - 1], q) <= 0.0 {
                h.pop();
            }
            h.push(*q);
        }
        h.pop();
    }
    h
}

impl ConvexPolygon {
    /// The axis-aligned rectangle [x0, x1] × [y0, y1] (empty if x0 > x1 or y0 > y1).
    pub fn rect(x0: f64, x1: f64, y0: f64, y1: f64) -> Self {
        if x0 > x1 || y0 > y1 {
            return Self::default();
        }
        Self {
            pts: convex_hull(vec![
                Vector2::new(x0, y0),
                Vector2::new(x1, y0),
                Vector2::new(x1, y1),
                Vector2::new(x0, y1),
            ]),
        }
    }

    /// Whether the polygon has no point.
    pub fn is_empty(&self) -> bool {
        self.pts.is_empty()
    }

    /// Area (shoelace), m²-like units of the coordinates.
    pub fn area(&self) -> f64 {
        let n = self.pts.len();
        (0..n)
            .map(|i| {
                let (a, b) = (self.pts[i], self.pts[(i + 1) % n]);
                a.x * b.y - a.y * b.x
            })
            .sum::<f64>()
            * 0.5
    }

    /// The image under `z ↦ A z + c` (A with a positive determinant keeps the orientation;
    /// otherwise the hull is rebuilt).
    pub fn map_affine(&self, a: &Matrix2<f64>, c: &Vector2<f64>) -> Self {
        let pts: Vec<Vector2<f64>> = self.pts.iter().map(|p| a * p + c).collect();
        if a.determinant() > 0.0 {
            Self { pts }
        } else {
            Self {
                pts: convex_hull(pts),
            }
        }
    }

    /// Minkowski sum with the rectangle [−ex, ex] × [−ey, ey] (ex, ey ≥ 0).
    pub fn minkowski_rect(&self, ex: f64, ey: f64) -> Self {
        let mut all = Vec::with_capacity(4 * self.pts.len());
        for p in &self.pts {
            for (sx, sy) in [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)] {
                all.push(p + Vector2::new(sx * ex, sy * ey));
            }
        }
        Self {
            pts: convex_hull(all),
        }
    }

    /// Minkowski sum with the segment [−d, d].
    pub fn minkowski_segment(&self, d: &Vector2<f64>) -> Self {
        let mut all = Vec::with_capacity(2 * self.pts.len());
        for p in &self.pts {
            all.push(p - d);
            all.push(p + d);
        }
        Self {
            pts: convex_hull(all),
        }
    }

    /// Intersection with the half-plane {z : n·z ≤ c}.
    pub fn clip(&self, n: &Vector2<f64>, c: f64) -> Self {
        let m = self.pts.len();
        if m == 0 {
            return Self::default();
        }
        let inside = |p: &Vector2<f64>| n.dot(p) <= c;
        let mut out = Vec::with_capacity(m + 2);
        for i in 0..m {
            let (a, b) = (self.pts[i], self.pts[(i + 1) % m]);
            let (ia, ib) = (inside(&a), inside(&b));
            if ia {
                out.push(a);
            }
            if ia != ib {
                let (da, db) = (n.dot(&a) - c, n.dot(&b) - c);
                let s = da / (da - db);
                out.push(a + (b - a) * s);
            }
        }
        Self {
            pts: if out.len() >= 3 {
                convex_hull(out)
            } else {
                out
            },
        }
    }

    /// Smallest and largest x of the polygon (NaN, NaN when empty).
    pub fn x_range(&self) -> (f64, f64) {
        self.pts.iter().fold((f64::NAN, f64::NAN), |(lo, hi), p| {
            (lo.min(p.x), hi.max(p.x))
        })
    }
}

#[cfg(test)]
mod tests {
    //! References: areas and intersections of rectangles and triangles worked by hand.
    use super::*;

    #[test]
    fn val_polygon_rect_map_sum_clip_areas() {
        let r = ConvexPolygon::rect(0.0, 2.0, 0.0, 1.0);
        assert!((r.area() - 2.0).abs() < 1e-15);
        // Shear x += y keeps the area.
        let s = r.map_affine(&Matrix2::new(1.0, 1.0, 0.0, 1.0), &Vector2::new(3.0, 0.0));
        assert!((s.area() - 2.0).abs() < 1e-15);
        assert_eq!(s.x_range(), (3.0, 6.0));
        // Minkowski sum of a 2×1 rectangle with [−½, ½]²: a 3×2 rectangle.
        let m = r.minkowski_rect(0.5, 0.5);
        assert!((m.area() - 6.0).abs() < 1e-15 && m.pts.len() == 4);
        // With the segment [−(1, 0), (1, 0)]: a 4×1 rectangle; with [−(0, 1), (0, 1)]: 2×3.
        assert!((r.minkowski_segment(&Vector2::new(1.0, 0.0)).area() - 4.0).abs() < 1e-15);
        assert!((r.minkowski_segment(&Vector2::new(0.0, 1.0)).area() - 6.0).abs() < 1e-15);
        // Clip x ≤ 1 keeps half; x + y ≤ 1 on the unit square keeps a triangle of area ½.
        assert!((r.clip(&Vector2::new(1.0, 0.0), 1.0).area() - 1.0).abs() < 1e-15);
        let u = ConvexPolygon::rect(0.0, 1.0, 0.0, 1.0);
        let t = u.clip(&Vector2::new(1.0, 1.0), 1.0);
        assert!((t.area() - 0.5).abs() < 1e-15, "{}", t.area());
        assert!(u.clip(&Vector2::new(1.0, 0.0), -0.1).is_empty());
        assert!(ConvexPolygon::rect(1.0, 0.0, 0.0, 1.0).is_empty());
    }
}
