//! The approach cone of a docking port, checked against a body's full geometry: every point of
//! every part must lie inside the cone with its apex at the port, its axis the port's outward
//! axis and half-angle α, while the body is in the cone's range band. Bevy-free.
//!
//! # The margin
//! For a point p with axial coordinate a = (p − apex)·û and distance ρ from the axis, the
//! function h(p) = ρ cos α − a sin α is the maximum of n·(p − apex) over the cone's outward
//! unit normals n (max over the azimuth of (−sin α, cos α cos φ, cos α sin φ)): it equals the
//! signed distance to the cone's lateral surface wherever the nearest surface point is on it
//! (inside the cone: −h is the exact clearance to the wall), and it is positive exactly where
//! p is outside (behind the apex it understates the distance, never the sign). h is convex in
//! p (a maximum of linear functions), so its maximum over a convex part is reached at a vertex:
//! - box and convex hull: their vertices, exactly;
//! - sphere: h(centre) + r, exactly (h has unit-norm gradients);
//! - cylinder: the vertices of the circumscribed 32-gon prism (radius r / cos(π/32)), which
//!   contains the cylinder: a conservative (never larger) margin, at most r·(1/cos(π/32) − 1)
//!   = 0.48 % of r below the exact one.
//!
//! c = −max over the body's parts of max h, m: positive inside the cone by that much.
//! The band is `to_range_m` ≤ |r_com − apex| ≤ `from_range_m` (the body's centre of mass);
//! outside it the cone does not apply. With b = min(range − `to_range_m`, `from_range_m` −
//! range) (positive inside the band, minus the distance to it outside), the margin is
//!
//! margin = max(c, −b), m:
//!
//! - inside the band it is negative exactly when c is (a violation of the cone), and equals
//!   c except where a violation is deeper than the distance to the band's edge (then it is
//!   −b: still negative, its size clipped);
//! - outside the band it is positive (at least the distance to the band): the cone is not
//!   violated there;
//! - it is continuous in time and Lipschitz (a maximum of two Lipschitz functions), so the
//!   monitor judges it between samples too ([`ApproachCone::rate_bound`]).

use crate::guarantee::{Guarantee, MonitorView, MotionBounds, Reads};
use crate::scene::parts::{PartCollider, Primitive};
use nalgebra::{Point3, Vector3};

/// Sides of the prism that stands in for a cylinder.
pub const CYLINDER_SIDES: usize = 32;

/// A part's points in its body frame with a radius (0 except for spheres), whose h maximum is
/// the part's (see the module docs).
pub fn support_points(part: &PartCollider) -> Vec<(Vector3<f64>, f64)> {
    let tf = |p: Point3<f64>| (part.pose_body * p).coords;
    match &part.shape {
        Primitive::Cuboid { half_m } => {
            let mut v = Vec::with_capacity(8);
            for sx in [-1.0, 1.0] {
                for sy in [-1.0, 1.0] {
                    for sz in [-1.0, 1.0] {
                        v.push((
                            tf(Point3::new(sx * half_m.x, sy * half_m.y, sz * half_m.z)),
                            0.0,
                        ));
                    }
                }
            }
            v
        }
        Primitive::Ball { radius_m } => vec![(tf(Point3::origin()), *radius_m)],
        Primitive::ConvexHull { points_m } => points_m.iter().map(|p| (tf(*p), 0.0)).collect(),
        // Every point of a triangle is a convex combination of its corners: the vertices.
        Primitive::Mesh { mesh, .. } => mesh.vertices_m.iter().map(|p| (tf(*p), 0.0)).collect(),
        Primitive::Cylinder {
            radius_m,
            half_length_m,
        } => {
            let rc = radius_m / (std::f64::consts::PI / CYLINDER_SIDES as f64).cos();
            let mut v = Vec::with_capacity(2 * CYLINDER_SIDES);
            for k in 0..CYLINDER_SIDES {
                let t = k as f64 * std::f64::consts::TAU / CYLINDER_SIDES as f64;
                for y in [-half_length_m, *half_length_m] {
                    v.push((tf(Point3::new(rc * t.cos(), y, rc * t.sin())), 0.0));
                }
            }
            v
        }
    }
}

/// h(p) of the module docs for a cone with apex `apex`, unit axis `u` and half-angle `alpha`.
pub fn cone_h(
    apex: &Vector3<f64>,
    u: &Vector3<f64>,
    sin_a: f64,
    cos_a: f64,
    p: &Vector3<f64>,
) -> f64 {
    let d = p - apex;
    let a = d.dot(u);
    let rho = (d - u * a).norm();
    rho * cos_a - a * sin_a
}

/// A body's support points ([`support_points`]) grouped by part, each group with the sphere
/// about its centroid that holds its points with their radii, and the sphere about the body's
/// centre of mass holding them all ([`ApproachCone::points_extent_m`]).
///
/// h is 1-Lipschitz (its gradient is a unit vector wherever it has one), so no point of a group
/// with centre c and radius R has h + r above h(c) + R: [`ApproachCone::margin_at`] visits the
/// group with the largest such bound first and skips a group whose bound stays below the largest
/// h + r found so far (by more than a rounding guard). The maximum, and so the margin, is the
/// one a visit of every point gives, bit for bit.
#[derive(Debug, Clone, Default)]
pub struct SupportSet {
    /// Every point (body frame, m) with its radius, m, group after group.
    pub points: Vec<(Vector3<f64>, f64)>,
    /// Per group: centre (body frame), m; radius, m; its points' range in `points`.
    groups: Vec<(Vector3<f64>, f64, std::ops::Range<usize>)>,
    /// max |p − com| + r over the points, m.
    extent_m: f64,
}

impl SupportSet {
    /// The groups (one per part, each from [`support_points`]) of a body whose centre of mass
    /// is at `com_m` (body frame).
    pub fn new(groups: Vec<Vec<(Vector3<f64>, f64)>>, com_m: &Vector3<f64>) -> Self {
        let mut points = Vec::new();
        let mut gs = Vec::with_capacity(groups.len());
        for g in groups {
            if g.is_empty() {
                continue;
            }
            let c = g.iter().map(|(p, _)| p).sum::<Vector3<f64>>() / g.len() as f64;
            let r = g
                .iter()
                .map(|(p, r)| (p - c).norm() + r)
                .fold(0.0, f64::max);
            let start = points.len();
            points.extend(g);
            gs.push((c, r, start..points.len()));
        }
        let extent_m = points
            .iter()
            .map(|(p, r)| (p - com_m).norm() + r)
            .fold(0.0, f64::max);
        Self {
            points,
            groups: gs,
            extent_m,
        }
    }
}

/// Groups at most this many are ordered by their bounds on the stack in
/// [`ApproachCone::margin_at`]; a body with more parts has every point visited.
const MAX_ORDERED_GROUPS: usize = 32;

/// `ApproachCone` as the monitor checks it.
#[derive(Debug, Clone)]
pub struct ApproachCone {
    /// Name.
    pub name: String,
    /// The checked body (index).
    pub body: usize,
    /// Its centre of mass in its body frame, m.
    pub body_com_m: Vector3<f64>,
    /// Its parts' support points (body frame) with radii, grouped by part.
    pub points: SupportSet,
    /// The body carrying the port (index).
    pub around: usize,
    /// Its centre of mass in its body frame, m.
    pub around_com_m: Vector3<f64>,
    /// The port origin in `around`'s body frame, m.
    pub port_m: Vector3<f64>,
    /// The port's unit outward axis in `around`'s body frame.
    pub axis: Vector3<f64>,
    /// Half-angle α, rad.
    pub half_angle_rad: f64,
    /// The cone applies from this range inwards, m.
    pub from_range_m: f64,
    /// … down to this range, m.
    pub to_range_m: f64,
}

impl ApproachCone {
    /// The margin for the body at (com position, attitude) and the port body at its pose, m.
    pub fn margin_at(
        &self,
        body_pos_m: &Vector3<f64>,
        body_att: &nalgebra::UnitQuaternion<f64>,
        around_pos_m: &Vector3<f64>,
        around_att: &nalgebra::UnitQuaternion<f64>,
    ) -> f64 {
        let apex = around_pos_m + around_att * (self.port_m - self.around_com_m);
        let range = (body_pos_m - apex).norm();
        let band = (range - self.to_range_m).min(self.from_range_m - range);
        let u = around_att * self.axis;
        let (s, c) = self.half_angle_rad.sin_cos();
        let mut worst = f64::NEG_INFINITY;
        let at = |p: &Vector3<f64>| body_pos_m + body_att * (p - self.body_com_m);
        // One point past `band` makes the margin −band whatever the others are (a latched
        // or distant body, outside the cone's ranges): the same value, bit for bit.
        let visit = |points: &[(Vector3<f64>, f64)], worst: &mut f64| -> bool {
            for (p, r) in points {
                let h = cone_h(&apex, &u, s, c, &at(p)) + r;
                if h > band {
                    return true;
                }
                *worst = worst.max(h);
            }
            false
        };
        let set = &self.points;
        let n = set.groups.len();
        if !(2..=MAX_ORDERED_GROUPS).contains(&n) {
            if visit(&set.points, &mut worst) {
                return -band;
            }
            return (-worst).max(-band);
        }
        // Each group's bound h(c) + R, largest first (see [`SupportSet`]). The guard covers
        // the rounding of h at a point against the bound's: both are sums of a few products
        // of numbers no larger than the range plus the body's extent.
        let mut bound = [(0.0_f64, 0_usize); MAX_ORDERED_GROUPS];
        let mut guard = 1e-9 * (1.0 + range + set.extent_m);
        for (k, (gc, gr, _)) in set.groups.iter().enumerate() {
            bound[k] = (cone_h(&apex, &u, s, c, &at(gc)) + gr, k);
            guard = guard.max(1e-9 * (at(gc) - apex).norm());
        }
        let bound = &mut bound[..n];
        bound.sort_unstable_by(|x, y| y.0.total_cmp(&x.0).then(x.1.cmp(&y.1)));
        for (b, k) in bound.iter() {
            if *b + guard < worst {
                break; // this group and every later one lie below the maximum found
            }
            if visit(&set.points[set.groups[*k].2.clone()], &mut worst) {
                return -band;
            }
        }
        (-worst).max(-band)
    }

    /// Radius about the body's centre of mass of the sphere holding every support point
    /// (with its radius), m.
    pub fn points_extent_m(&self) -> f64 {
        self.points.extent_m
    }
}

impl Guarantee for ApproachCone {
    fn name(&self) -> &str {
        &self.name
    }
    fn margin(&self, v: &MonitorView) -> f64 {
        let (b, a) = (&v.bodies[self.body], &v.bodies[self.around]);
        self.margin_at(&b.pos_m, &b.att, &a.pos_m, &a.att)
    }
    /// With V = |v_body − v_around|, Ω_a, Ω_b the angular speeds, p = |port − com_around|,
    /// R = [`ApproachCone::points_extent_m`] and S the bound on |r_body − r_around|: the apex
    /// moves at most at |v_a| + Ω_a p, so the range changes at most at V + Ω_a p; a support
    /// point w moves relative to the apex at most at V + Ω_b R + Ω_a p, and the cone's normals
    /// turn at Ω_a, so each h(w) = max_n n·(w − apex) changes at most at
    /// V + Ω_b R + Ω_a p + Ω_a (S + p + R). The margin, a maximum of the two, changes at most
    /// at the larger bound.
    fn rate_bound(&self, m: &dyn MotionBounds) -> Option<f64> {
        let v = m.rel_speed_bound(self.body, self.around);
        let (wa, wb) = (m.omega_bound(self.around), m.omega_bound(self.body));
        let p = (self.port_m - self.around_com_m).norm();
        let r = self.points_extent_m();
        let s = m.separation_bound(self.body, self.around);
        let band = v + wa * p;
        let cone = v + wb * r + wa * p + wa * (s + p + r);
        Some(band.max(cone))
    }
    fn reads(&self) -> Reads {
        Reads::Bodies
    }
}

#[cfg(test)]
mod tests {
    //! References: the cone's signed distance by hand (a point on the axis at a is
    //! −a·sin α inside; a point on the wall is 0); a box's worst corner by enumeration of a
    //! dense grid of its surface points.
    use super::*;
    use nalgebra::{Isometry3, UnitQuaternion};

    fn cube(half: f64) -> PartCollider {
        PartCollider {
            part: "bus".into(),
            name: "bus".into(),
            role: crate::scene::PartRole::Bus,
            shape: Primitive::Cuboid {
                half_m: Vector3::repeat(half),
            },
            pose_body: Isometry3::identity(),
            allow_initial_overlap: false,
        }
    }

    /// The grouped search ([`SupportSet`]) gives the margin of a visit of every point, bit for
    /// bit, on a body of a box, a ball and two cylinders at 2 000 pseudo-random poses across
    /// the band and through the cone's wall. Reference: the plain maximum over every point.
    #[test]
    fn grouped_margin_is_the_margin_of_every_point() {
        let mut parts = vec![cube(0.5)];
        let mut ball = cube(0.0);
        ball.shape = Primitive::Ball { radius_m: 0.3 };
        ball.pose_body = Isometry3::translation(0.0, 0.0, 0.9);
        parts.push(ball);
        for y in [1.2, -1.2] {
            let mut cyl = cube(0.0);
            cyl.shape = Primitive::Cylinder {
                radius_m: 0.05,
                half_length_m: 0.6,
            };
            cyl.pose_body = Isometry3::translation(0.0, y, 0.0);
            parts.push(cyl);
        }
        let com = Vector3::new(0.05, -0.02, 0.1);
        let g = ApproachCone {
            name: "c".into(),
            body: 0,
            body_com_m: com,
            points: SupportSet::new(parts.iter().map(support_points).collect(), &com),
            around: 1,
            around_com_m: Vector3::zeros(),
            port_m: Vector3::new(0.8, 0.0, 0.0),
            axis: Vector3::x(),
            half_angle_rad: 20f64.to_radians(),
            from_range_m: 60.0,
            to_range_m: 3.0,
        };
        let mut rng = crate::math::rng::Lcg(7);
        let (s, c) = g.half_angle_rad.sin_cos();
        for _ in 0..2000 {
            let mut u = || rng.symmetric();
            let x = 40.0 * (u() + 1.0);
            let pos = Vector3::new(x, 0.4 * x * u(), 0.4 * x * u());
            let att = UnitQuaternion::from_euler_angles(3.0 * u(), 3.0 * u(), 3.0 * u());
            let got = g.margin_at(&pos, &att, &Vector3::zeros(), &UnitQuaternion::identity());
            let apex = g.port_m;
            let range = (pos - apex).norm();
            let band = (range - g.to_range_m).min(g.from_range_m - range);
            let worst = g
                .points
                .points
                .iter()
                .map(|(p, r)| cone_h(&apex, &Vector3::x(), s, c, &(pos + att * (p - com))) + r)
                .fold(f64::NEG_INFINITY, f64::max);
            let want = if worst > band {
                -band
            } else {
                (-worst).max(-band)
            };
            assert_eq!(got.to_bits(), want.to_bits(), "{pos:?}: {got} vs {want}");
        }
    }

    #[test]
    fn val_approach_cone_point_distances() {
        let (apex, u) = (Vector3::zeros(), Vector3::x());
        let a = 10f64.to_radians();
        let (s, c) = a.sin_cos();
        assert!((cone_h(&apex, &u, s, c, &Vector3::new(5.0, 0.0, 0.0)) + 5.0 * s).abs() < 1e-12);
        let wall = Vector3::new(5.0 * c, 5.0 * s, 0.0);
        assert!(cone_h(&apex, &u, s, c, &wall).abs() < 1e-12);
        assert!(cone_h(&apex, &u, s, c, &Vector3::new(-1.0, 0.0, 0.0)) > 0.0);
    }

    #[test]
    fn val_approach_cone_box_margin_against_dense_surface() {
        let part = cube(0.5);
        let g = ApproachCone {
            name: "c".into(),
            body: 0,
            body_com_m: Vector3::zeros(),
            points: SupportSet::new(vec![support_points(&part)], &Vector3::zeros()),
            around: 1,
            around_com_m: Vector3::zeros(),
            port_m: Vector3::zeros(),
            axis: Vector3::x(),
            half_angle_rad: 15f64.to_radians(),
            from_range_m: 100.0,
            to_range_m: 0.0,
        };
        let pos = Vector3::new(8.0, 0.7, -0.3);
        let att = UnitQuaternion::from_euler_angles(0.3, -0.2, 0.5);
        let m = g.margin_at(&pos, &att, &Vector3::zeros(), &UnitQuaternion::identity());
        let (s, c) = g.half_angle_rad.sin_cos();
        let mut worst = f64::NEG_INFINITY;
        let k = 40;
        for i in 0..=k {
            for j in 0..=k {
                for face in 0..6 {
                    let (x, y) = (i as f64 / k as f64 - 0.5, j as f64 / k as f64 - 0.5);
                    let p = match face {
                        0 => Vector3::new(0.5, x, y),
                        1 => Vector3::new(-0.5, x, y),
                        2 => Vector3::new(x, 0.5, y),
                        3 => Vector3::new(x, -0.5, y),
                        4 => Vector3::new(x, y, 0.5),
                        _ => Vector3::new(x, y, -0.5),
                    };
                    let w = pos + att * p;
                    worst = worst.max(cone_h(&Vector3::zeros(), &Vector3::x(), s, c, &w));
                }
            }
        }
        // The grid contains the corners: the vertex maximum equals the surface maximum.
        assert!((m + worst).abs() < 1e-12, "{m} vs {}", -worst);
        // Out of the band: not applicable, the margin is at least the distance to the band
        // (100 m out at a range of 200 m; the body is far inside the cone's extension there).
        let far = g.margin_at(
            &Vector3::new(200.0, 0.0, 0.0),
            &att,
            &Vector3::zeros(),
            &UnitQuaternion::identity(),
        );
        assert!(far.is_finite() && far >= 100.0 - 1e-9, "{far}");
        // Across the band's edge the margin is continuous: a body 40° off the axis (far
        // outside the 15° cone) 1 mm inside the band is violated by the clipped −1 mm; 1 mm
        // outside the band the margin is +1 mm.
        let dir = Vector3::new(40f64.to_radians().cos(), 40f64.to_radians().sin(), 0.0);
        let at = |r: f64| {
            g.margin_at(
                &(dir * r),
                &att,
                &Vector3::zeros(),
                &UnitQuaternion::identity(),
            )
        };
        let (m_in, m_out) = (at(100.0 - 1e-3), at(100.0 + 1e-3));
        assert!(
            (m_in + 1e-3).abs() < 1e-9 && (m_out - 1e-3).abs() < 1e-9,
            "{m_in} {m_out}"
        );
    }

    /// Motion bounds of one steady motion (constant velocities and rates): the reference for
    /// the rate-bound test below.
    struct Steady {
        v_rel: f64,
        omega: [f64; 2],
        sep: f64,
    }
    impl crate::guarantee::MotionBounds for Steady {
        fn dt_s(&self) -> f64 {
            1.0
        }
        fn speed_bound(&self, _i: usize) -> f64 {
            self.v_rel
        }
        fn rel_speed_bound(&self, _i: usize, _j: usize) -> f64 {
            self.v_rel
        }
        fn omega_bound(&self, i: usize) -> f64 {
            self.omega[i]
        }
        fn extent_m(&self, _i: usize) -> f64 {
            0.0
        }
        fn separation_bound(&self, _i: usize, _j: usize) -> f64 {
            self.sep
        }
    }

    /// The rate bound holds: the margin sampled every 1 ms along a tumbling, translating body
    /// (through the cone's wall and across the band's edge) around a turning port body never
    /// changes faster than the bound. Reference: finite differences of the margin itself.
    #[test]
    fn invariant_approach_cone_rate_bound_covers_the_margin() {
        let g = ApproachCone {
            name: "c".into(),
            body: 0,
            body_com_m: Vector3::zeros(),
            points: SupportSet::new(vec![support_points(&cube(0.5))], &Vector3::zeros()),
            around: 1,
            around_com_m: Vector3::new(0.1, 0.0, 0.0),
            port_m: Vector3::new(1.0, 0.0, 0.0),
            axis: Vector3::x(),
            half_angle_rad: 15f64.to_radians(),
            from_range_m: 10.0,
            to_range_m: 2.0,
        };
        let (v, w_b, w_a) = (Vector3::new(-0.9, 0.35, 0.1), 0.4, 0.05);
        let p0 = Vector3::new(11.5, -1.5, 0.2);
        let state = |t: f64| {
            let pb = p0 + v * t;
            let qb = UnitQuaternion::from_axis_angle(&Vector3::y_axis(), w_b * t);
            let qa = UnitQuaternion::from_axis_angle(&Vector3::z_axis(), w_a * t);
            g.margin_at(&pb, &qb, &Vector3::zeros(), &qa)
        };
        let bound = g
            .rate_bound(&Steady {
                v_rel: v.norm(),
                omega: [w_b, w_a],
                sep: p0.norm() + 1.0,
            })
            .unwrap();
        let h = 1e-3;
        let mut worst = 0.0f64;
        let mut signs = (false, false);
        for k in 0..12_000 {
            let t = k as f64 * h;
            let (m0, m1) = (state(t), state(t + h));
            worst = worst.max((m1 - m0).abs() / h);
            signs.0 |= m0 < 0.0;
            signs.1 |= m0 > 0.0;
        }
        assert!(signs.0 && signs.1, "the motion must cross the wall");
        assert!(
            worst <= bound,
            "observed rate {worst} above the bound {bound}"
        );
        assert!(
            worst > 0.2 * bound,
            "bound {bound} vs observed {worst}: not vacuous"
        );
    }
}
