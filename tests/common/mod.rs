//! Closed forms and an independent orbit integrator shared by the integration tests (each test file that uses them names them in
//! its own `//!` header), and the set-up helpers several of them share (closed prisms, monitor
//! geometry of one part per body).

#![allow(dead_code)] // each test file uses its own part

use nalgebra::{Matrix3, Vector3};
use rpod::control::generic::glideslope::Profile;
use rpod::orbit::constants::{J2_EARTH, MU_EARTH_M3_S2, R_EARTH_M};

/// The closed-loop motion of a glideslope flown by a critically damped PD (ω, ζ = 1) with
/// exact CW cancellation and reference feed-forward, along V-bar, from rest at range
/// r_f + d₀: the range error e = s − s_ref obeys ë + 2ωė + ω²e = 0 between the reference's two
/// velocity steps (its start, −d₀/τ or −v, and its arrival, +v_min), so
/// e(t) = v₀ t e^{−ωt} − v_end (t − t_end) e^{−ω(t − t_end)} (the second term after t_end).
pub struct GlideslopeLoop {
    /// The profile.
    pub profile: Profile,
    /// d₀, m.
    pub d0: f64,
    /// ω, rad/s.
    pub omega: f64,
    /// The reference's initial speed, m/s.
    pub v0: f64,
    /// The reference's arrival time, s.
    pub t_end: f64,
    /// The reference's speed just before arrival, m/s.
    pub v_end: f64,
}

impl GlideslopeLoop {
    /// The loop for a profile from d₀.
    pub fn new(profile: Profile, d0: f64, omega: f64) -> Self {
        let v0 = -profile.at(d0, 0.0).1;
        // Arrival: the first time the profile reaches d = 0 (found by bisection on the closed form).
        let (mut lo, mut hi) = (0.0, 1e7);
        for _ in 0..200 {
            let mid = 0.5 * (lo + hi);
            if profile.at(d0, mid).0 > 0.0 {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        let v_end = -profile.at(d0, lo).1;
        Self {
            profile,
            d0,
            omega,
            v0,
            t_end: hi,
            v_end,
        }
    }

    /// (e, ė, ë) at t.
    pub fn error(&self, t: f64) -> (f64, f64, f64) {
        let w = self.omega;
        let f = |v: f64, t: f64| {
            if t <= 0.0 {
                return (0.0, 0.0, 0.0);
            }
            let x = (-w * t).exp();
            (v * t * x, v * (1.0 - w * t) * x, v * w * (w * t - 2.0) * x)
        };
        let a = f(self.v0, t);
        let b = f(-self.v_end, t - self.t_end);
        (a.0 + b.0, a.1 + b.1, a.2 + b.2)
    }

    /// (range − r_f, range rate, range acceleration) of the plant at t.
    pub fn plant(&self, t: f64) -> (f64, f64, f64) {
        let (d, dd, ddd) = self.profile.at(self.d0, t);
        let (e, ed, edd) = self.error(t);
        (d + e, dd + ed, ddd + edd)
    }

    /// ∫₀ᵀ |a| dt with a = (2n ṡ, −s̈, 0) (V-bar: the CW command that keeps x = 0), by the
    /// midpoint rule at `h` s.
    pub fn delta_v(&self, n: f64, t_s: f64, h: f64) -> f64 {
        let mut dv = 0.0;
        let mut t = 0.0;
        while t < t_s {
            let (_, sd, sdd) = self.plant(t + 0.5 * h);
            dv += ((2.0 * n * sd).powi(2) + sdd * sdd).sqrt() * h;
            t += h;
        }
        // The reference's steps are smooth in the plant: no impulses left to add.
        dv
    }
}

/// Two-body (+ J2 when `j2`) gravitational acceleration at ECI position `r`, m/s²: the
/// independent force model of the orbit fidelity tests.
pub fn accel(r: &Vector3<f64>, j2: bool) -> Vector3<f64> {
    let rn = r.norm();
    let mut a = -MU_EARTH_M3_S2 / rn.powi(3) * r;
    if j2 {
        let k = 1.5 * J2_EARTH * MU_EARTH_M3_S2 * R_EARTH_M.powi(2) / rn.powi(5);
        let z2 = 5.0 * (r.z / rn).powi(2);
        a += Vector3::new(
            k * r.x * (z2 - 1.0),
            k * r.y * (z2 - 1.0),
            k * r.z * (z2 - 3.0),
        );
    }
    a
}

/// One classical RK4 step of ṙ = v, v̇ = `accel`(r) over `h` s (an independent integrator).
pub fn rk4(r: &mut Vector3<f64>, v: &mut Vector3<f64>, h: f64, j2: bool) {
    let (k1r, k1v) = (*v, accel(r, j2));
    let (k2r, k2v) = (*v + k1v * (h / 2.0), accel(&(*r + k1r * (h / 2.0)), j2));
    let (k3r, k3v) = (*v + k2v * (h / 2.0), accel(&(*r + k2r * (h / 2.0)), j2));
    let (k4r, k4v) = (*v + k3v * h, accel(&(*r + k3r * h), j2));
    *r += (k1r + k2r * 2.0 + k3r * 2.0 + k4r) * (h / 6.0);
    *v += (k1v + k2v * 2.0 + k3v * 2.0 + k4v) * (h / 6.0);
}

/// Clohessy–Wiltshire state transition (Hill frame: x radial, y along-track, z normal).
pub fn cw(x0: &Vector3<f64>, v0: &Vector3<f64>, n: f64, t: f64) -> Vector3<f64> {
    let (s, c) = ((n * t).sin(), (n * t).cos());
    Vector3::new(
        (4.0 - 3.0 * c) * x0.x + s / n * v0.x + 2.0 / n * (1.0 - c) * v0.y,
        6.0 * (s - n * t) * x0.x + x0.y - 2.0 / n * (1.0 - c) * v0.x
            + (4.0 * s - 3.0 * n * t) / n * v0.y,
        c * x0.z + s / n * v0.z,
    )
}

/// The rotation from ECI to the Hill frame (x radial, y along-track, z orbit normal) of (r, v).
pub fn hill(r: &Vector3<f64>, v: &Vector3<f64>) -> Matrix3<f64> {
    let x = r.normalize();
    let z = r.cross(v).normalize();
    let y = z.cross(&x);
    Matrix3::from_rows(&[x.transpose(), y.transpose(), z.transpose()])
}

/// A closed prism from z = −½ to ½ over the polygon `outline` (counter-clockwise seen from +z),
/// its caps triangulated by `cap` (indices into `outline`, counter-clockwise): the top cap as
/// given, the bottom reversed, each side a pair of triangles; outward normals throughout.
pub fn closed_prism(outline: &[(f64, f64)], cap: &[[u32; 3]]) -> (Vec<[f64; 3]>, Vec<[u32; 3]>) {
    let n = outline.len() as u32;
    let mut v = Vec::new();
    for z in [-0.5, 0.5] {
        for &(x, y) in outline {
            v.push([x, y, z]);
        }
    }
    let mut t = Vec::new();
    for c in cap {
        t.push([c[0] + n, c[1] + n, c[2] + n]);
        t.push([c[0], c[2], c[1]]);
    }
    for k in 0..n {
        let (p, q) = (k, (k + 1) % n);
        t.push([p, q, q + n]);
        t.push([p, q + n, p + n]);
    }
    (v, t)
}

/// Monitor geometry of bodies with one part each, part frames at the body origins: (shape,
/// bounding radius) per body, a triangle mesh's hull support map as the monitor builds it.
pub fn one_part_bodies(
    parts: &[&(bevy_rapier3d::rapier::prelude::SharedShape, f64)],
) -> rpod::sim::monitor::MonitorGeometry {
    use rpod::sim::monitor::{self, MonitorGeometry, PartPiece};
    let mut g = MonitorGeometry::default();
    for (s, r) in parts {
        let pose = nalgebra::Isometry3::identity();
        g.shapes.push(vec![s.clone()]);
        g.pose_body.push(vec![pose]);
        g.radius.push(vec![*r]);
        g.docking.push(vec![false]);
        g.com_body_m.push(Vector3::zeros());
        g.extent_m.push(*r);
        g.aabb_extent_m.push(3f64.sqrt() * r);
        g.has_docking.push(false);
        g.pieces.push(vec![PartPiece::of(&**s, &pose, *r)]);
        g.hulls.push(vec![monitor::mesh_hull(&**s)]);
    }
    g
}

/// Closest point of triangle (a, b, c) to p (Ericson, Real-Time Collision Detection §5.1.5).
pub fn closest_on_triangle(
    p: Vector3<f64>,
    a: Vector3<f64>,
    b: Vector3<f64>,
    c: Vector3<f64>,
) -> Vector3<f64> {
    let (ab, ac, ap) = (b - a, c - a, p - a);
    let (d1, d2) = (ab.dot(&ap), ac.dot(&ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return a;
    }
    let bp = p - b;
    let (d3, d4) = (ab.dot(&bp), ac.dot(&bp));
    if d3 >= 0.0 && d4 <= d3 {
        return b;
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        return a + ab * (d1 / (d1 - d3));
    }
    let cp = p - c;
    let (d5, d6) = (ab.dot(&cp), ac.dot(&cp));
    if d6 >= 0.0 && d5 <= d6 {
        return c;
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        return a + ac * (d2 / (d2 - d6));
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
    }
    let denom = 1.0 / (va + vb + vc);
    a + ab * (vb * denom) + ac * (vc * denom)
}
