//! A mesh pair's distance advanced conservatively from its last exact evaluation.
//!
//! Where a part pair with a triangle mesh is not settled by the mesh's convex hull
//! ([`super::hull_bracket`]: a concavity, or a part inside the other's hull — the docking
//! collar of the example vehicle around the chaser's cone, every triangle of its rim equally
//! close), the monitor evaluates it triangle by triangle ([`mesh_exact`]) and keeps the result
//! ([`PairMemo`]): the relative pose, a certified lower bound and the witness points (a
//! point of each part, in its own frame). At any later relative pose of the same two parts:
//!
//! * **lower bound**: the distance is 1-Lipschitz in a rigid displacement of either set, and
//!   a point p of part b (|p| ≤ r_b about its origin) moves, in part a's frame, by
//!   |(t₁ − t₀) + (R₁ − R₀)p| ≤ |t₁ − t₀| + 2·sin(θ/2)·r_b (θ the angle of R₁R₀ᵀ:
//!   ‖R₁R₀ᵀ − I‖ = 2 sin(θ/2)); so d₁ ≥ l₀ − that displacement ([`displacement_bound_m`]);
//! * **upper bound**: the two witness points are points of the parts; carried along with them,
//!   their distance at the new pose is a distance achieved by the two parts.
//!
//! The monitor uses the pair as cleared when that lower bound clears the level it asks for, and
//! as a value when the bracket is as narrow as an exact query's own tolerance
//! ([`super::GJK_REL_TOL`], [`super::F32_REL_TOL`]); otherwise it evaluates again. Nothing is
//! assumed about how the parts moved in between: the bound is between two poses, whatever path
//! joined them.
//!
//! [`mesh_exact`] is the triangle-by-triangle evaluation with a *tight* certified lower bound,
//! as parry's `TriMesh` distance traverses its BVH (best first, a node pruned by the distance
//! of its box to the other part's box): each triangle against the other part by GJK, its
//! certified gap along the witness direction n, n·(s_b(−n) − s_tri(n)) — any axis's gap is at
//! most the distance, and a triangle's support is exact (its three corners) —, and along the
//! direction from the triangle's point nearest the other part's witness (an exact point
//! projection: nearer the true direction than GJK's where GJK stops early), the lower bound
//! the smallest gap over the triangles evaluated (a pruned node's box is at least the best
//! distance found, so no pruned triangle is closer), less the f32 rounding of the relative pose.
//! Tests: `tests/val_mesh_memo.rs` (brute force over every triangle in f64, closed forms).

use super::{F32_REL_TOL, conv};
use bevy_rapier3d::parry::bounding_volume::Aabb;
use bevy_rapier3d::parry::partitioning::BvhNode;
use bevy_rapier3d::parry::query;
use bevy_rapier3d::parry::query::PointQuery;
use bevy_rapier3d::parry::shape::{SupportMap, TriMesh};
use bevy_rapier3d::rapier::math::{Real, Vector};
use bevy_rapier3d::rapier::prelude as rp;
use nalgebra::{Isometry3, Point3, Vector3};
use std::cell::Cell;
use std::collections::HashMap;
use std::sync::Mutex;

/// A part pair's last triangle-by-triangle evaluation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ExactEval {
    /// Pose of part b's frame in part a's frame at the evaluation.
    pub rel: Isometry3<f64>,
    /// Its inverse (a's frame in b's), computed once ([`ExactEval::new`]).
    pub rel_inv: Isometry3<f64>,
    /// The distance found (the witnesses' distance), m.
    pub value_m: f64,
    /// Certified lower bound of the distance to the triangles, m.
    pub lower_m: f64,
    /// Witness point of part a, in a's frame, m.
    pub witness_a: Point3<f64>,
    /// Witness point of part b, in b's frame, m.
    pub witness_b: Point3<f64>,
}

/// Relative rounding allowed on the f64 displacement bound (of |t| and r_b): far below f32's.
const F64_SLACK: f64 = 64.0 * f64::EPSILON;

/// An upper bound of how far any point of part b (within `rb_m` of its frame's origin) moves,
/// in part a's frame, between the relative poses `rel0` and `rel1` (b's frame in a's), m:
/// |t₁ − t₀| + 2·sin(θ/2)·r_b with θ the angle of R₁R₀ᵀ, plus the f64 rounding.
pub fn displacement_bound_m(rel0: &Isometry3<f64>, rel1: &Isometry3<f64>, rb_m: f64) -> f64 {
    let (dt, slack) = translation_and_slack(rel0, rel1, rb_m);
    let chord = 2.0 * half_turn(rel0, rel1).0 * rb_m;
    dt + chord + slack
}

/// A displacement bound's translation term |t₁ − t₀| and its rounding allowance
/// F64_SLACK·(|t₀| + |t₁| + r), m: shared by every displacement bound (and by
/// [`ExactEval::advance_unturned`]), so that they are the same floating-point terms.
fn translation_and_slack(rel0: &Isometry3<f64>, rel1: &Isometry3<f64>, r_m: f64) -> (f64, f64) {
    let dt = (rel1.translation.vector - rel0.translation.vector).norm();
    let scale = rel0.translation.vector.norm() + rel1.translation.vector.norm() + r_m;
    (dt, F64_SLACK * scale)
}

/// sin(θ/2) of the turn R₁R₀ᵀ between the rotations of `rel0` and `rel1` (θ in [0, π]) and its
/// unit axis (`None` for no turn), from the turn's unit quaternion (w, v): |v| = sin(θ/2), no
/// trigonometry.
fn half_turn(rel0: &Isometry3<f64>, rel1: &Isometry3<f64>) -> (f64, Option<Vector3<f64>>) {
    let turn = rel1.rotation * rel0.rotation.inverse();
    let v = turn.quaternion().imag();
    let s = v.norm();
    let axis = (s > 0.0 && s.is_finite()).then(|| v / s);
    (s.min(1.0), axis)
}

/// Largest distance of a point of `shape` (its own frame) from the line through its origin
/// along the unit vector `u`, m, where it is cheap and exact: the vertices of a convex
/// polyhedron or a box (the distance from a line is convex, so a vertex reaches its maximum
/// over the solid), a ball's radius. `None` for other shapes (meshes included).
pub fn axis_radius_m(shape: &dyn rp::Shape, u: &Vector3<f64>) -> Option<f64> {
    // Squared distances, one square root at the end: the norm is the square root of the
    // squared norm and the square root is correctly rounded and monotone, so this is the
    // largest norm bit for bit.
    let off2 = |p: Vector| {
        let p = conv::na(p);
        (p - u * p.dot(u)).norm_squared()
    };
    if let Some(c) = shape.as_convex_polyhedron() {
        return Some(
            c.points()
                .iter()
                .map(|p| off2(*p))
                .fold(0.0, f64::max)
                .sqrt(),
        );
    }
    if let Some(b) = shape.as_cuboid() {
        let h = b.half_extents;
        let mut m = 0.0f64;
        for sx in [-1.0, 1.0] {
            for sy in [-1.0, 1.0] {
                for sz in [-1.0, 1.0] {
                    m = m.max(off2(Vector::new(sx * h.x, sy * h.y, sz * h.z)));
                }
            }
        }
        return Some(m.sqrt());
    }
    shape.as_ball().map(|b| f64::from(b.radius))
}

/// [`displacement_bound_m`] with the rotation's axis: a point p of part b moves by
/// |(t₁ − t₀) + (Q − I)R₀p| with Q = R₁R₀ᵀ, and |(Q − I)x| = 2·sin(θ/2)·(x's distance from Q's
/// axis u), so the turn moves part b's points by at most 2·sin(θ/2)·ρ with ρ the largest
/// distance of a point of b from the line along R₀ᵀu through its origin ([`axis_radius_m`];
/// `rb_m` where that is not known). A part turning about its own axis (a docking cone rolling)
/// moves by its radius about that axis times the turn, not its bounding radius.
pub fn displacement_bound_axis_m(
    rel0: &Isometry3<f64>,
    rel1: &Isometry3<f64>,
    (b, rb_m): (&dyn rp::Shape, f64),
) -> f64 {
    let (dt, slack) = translation_and_slack(rel0, rel1, rb_m);
    let chord = match half_turn(rel0, rel1) {
        (sin_half, Some(u)) => {
            let ub = rel0.rotation.inverse() * u;
            let rho = axis_radius_m(b, &ub).map_or(rb_m, |r| r.min(rb_m));
            2.0 * sin_half * rho
        }
        _ => 0.0,
    };
    dt + chord + slack
}

impl ExactEval {
    /// An evaluation at the relative pose `rel` (b's frame in a's): its value and certified
    /// lower bound, m, and the witness points (a's in a's frame, b's in b's).
    pub fn new(
        rel: Isometry3<f64>,
        value_m: f64,
        lower_m: f64,
        witness_a: Point3<f64>,
        witness_b: Point3<f64>,
    ) -> Self {
        Self {
            rel,
            rel_inv: rel.inverse(),
            value_m,
            lower_m,
            witness_a,
            witness_b,
        }
    }

    /// The certified bracket (lower, upper) of the pair's distance at the relative pose `rel`
    /// (b's frame in a's), part b within `rb_m` of its origin, m.
    pub fn advance(&self, rel: &Isometry3<f64>, rb_m: f64) -> (f64, f64) {
        self.advance_by(rel, displacement_bound_m(&self.rel, rel, rb_m))
    }

    /// [`Self::advance`] on whichever side bounds the motion better (part b's points moving in
    /// a's frame, within `rb_m` of b's origin, or a's in b's, within `ra_m`): no look at the
    /// shapes, a few multiplications. [`Self::advance_parts`] is tighter for a part turning
    /// about an axis of its own.
    /// `rel_inv` is `rel.inverse()` (the caller computes it once for both advances).
    pub fn advance_quick(
        &self,
        (rel, rel_inv): (&Isometry3<f64>, &Isometry3<f64>),
        ra_m: f64,
        rb_m: f64,
    ) -> (f64, f64) {
        let moved_b = displacement_bound_m(&self.rel, rel, rb_m);
        let moved_a = displacement_bound_m(&self.rel_inv, rel_inv, ra_m);
        self.advance_by(rel, moved_b.min(moved_a))
    }

    /// The bracket [`Self::advance_parts`] would give if neither part had turned relative to
    /// the other (its chord term zero): its lower bound is at least that of
    /// [`Self::advance_parts`] and its upper bound the same, so a decision that needs a higher
    /// lower bound than this one's cannot be reached with the turn's axis either (the same
    /// floating-point terms as [`displacement_bound_axis_m`], whose rounding is monotone).
    /// `rel_inv` is `rel.inverse()`; `ra_m`, `rb_m` the parts' bounding radii.
    pub fn advance_unturned(
        &self,
        (rel, rel_inv): (&Isometry3<f64>, &Isometry3<f64>),
        ra_m: f64,
        rb_m: f64,
    ) -> (f64, f64) {
        let floor = |rel0: &Isometry3<f64>, rel1: &Isometry3<f64>, r_m: f64| {
            let (dt, slack) = translation_and_slack(rel0, rel1, r_m);
            dt + 0.0 + slack
        };
        let moved_b = floor(&self.rel, rel, rb_m);
        let moved_a = floor(&self.rel_inv, rel_inv, ra_m);
        self.advance_by(rel, moved_b.min(moved_a))
    }

    /// [`Self::advance`] with the rotation's axis, on whichever side bounds the motion better
    /// (part b's points moving in a's frame, or a's in b's: the distance is the same):
    /// [`displacement_bound_axis_m`].
    /// `rel_inv` is `rel.inverse()`.
    pub fn advance_parts(
        &self,
        (rel, rel_inv): (&Isometry3<f64>, &Isometry3<f64>),
        a: (&dyn rp::Shape, f64),
        b: (&dyn rp::Shape, f64),
    ) -> (f64, f64) {
        let moved_b = displacement_bound_axis_m(&self.rel, rel, b);
        let moved_a = displacement_bound_axis_m(&self.rel_inv, rel_inv, a);
        self.advance_by(rel, moved_b.min(moved_a))
    }

    /// A certified lower bound of the pair's distance at the relative pose `rel` (b's frame in
    /// a's) when part b is a faceted solid of revolution with centre `c` and unit axis `u` (in
    /// b's frame), radius `rho_m` about c and offset `s_m` ([`crate::geometry::revolution`]), m:
    /// the lower bound kept, less s, less how far the solid of revolution moved in a's frame —
    /// |c₁ − c₀| + 2·sin(φ/2)·ρ with φ the angle between the axis's two directions. (The
    /// relative turn is a turn Q taking one axis to the other after a turn about the axis,
    /// which maps the solid of revolution onto itself; Q moves its points by at most that.)
    /// So d₁ ≥ d(Rev₁) ≥ d(Rev₀) − moved ≥ l₀ − s − moved. A cone spinning about its own axis
    /// keeps its bound but for s, however far it turned.
    pub fn advance_revolved(
        &self,
        rel: &Isometry3<f64>,
        (c, u, rho_m, s_m): (&Point3<f64>, &Vector3<f64>, f64, f64),
    ) -> f64 {
        let (c0, c1) = (self.rel * c, rel * c);
        let (u0, u1) = (self.rel.rotation * u, rel.rotation * u);
        // 2·sin(φ/2) = |u₁ − u₀| for unit vectors.
        let moved = (c1 - c0).norm() + (u1 - u0).norm() * rho_m;
        let scale = self.rel.translation.vector.norm() + rel.translation.vector.norm() + rho_m;
        self.lower_m - s_m - moved - F64_SLACK * scale
    }

    /// The bracket at `rel` when no point of either part moved more than `moved_m` relative to
    /// the other since the evaluation.
    fn advance_by(&self, rel: &Isometry3<f64>, moved_m: f64) -> (f64, f64) {
        let lower = self.lower_m - moved_m;
        let upper = (self.witness_a - rel * self.witness_b).norm();
        (lower.max(0.0).min(upper), upper)
    }
}

/// Most part pairs a [`PairMemo`] keeps: a scene's limits allow 64 bodies of 256 parts (about
/// 10⁸ part pairs), so the cache is bounded; a pair evaluated once the memo is full is simply
/// not kept (it is evaluated exactly each time, as without the memo). 65 536 entries are about
/// 10 MB.
pub const PAIR_MEMO_MAX_PAIRS: usize = 1 << 16;

/// The last exact evaluation of each part pair (body i, part a, body j, part b) — mesh pairs
/// and pairs of parts with support maps —, kept by the monitor between queries. A clone starts
/// empty (the entries are only a cache: any of them is a certificate at any pose, and none is
/// needed). At most [`PAIR_MEMO_MAX_PAIRS`] pairs.
#[derive(Default)]
pub struct PairMemo(Mutex<HashMap<PairKey, ExactEval, KeyHash>>);

/// A part pair: (body i, part a, body j, part b).
pub type PairKey = (usize, usize, usize, usize);

/// The memo's hash of its small integer keys: a multiply-and-rotate mix per word (as rustc's
/// FxHash), deterministic and a few times cheaper than the default SipHash, which guards
/// against keys chosen by an adversary — these are part indices, not input.
#[derive(Default, Clone, Copy)]
pub struct KeyHasher(u64);

impl std::hash::Hasher for KeyHasher {
    fn finish(&self) -> u64 {
        self.0
    }

    fn write(&mut self, bytes: &[u8]) {
        for b in bytes {
            self.write_u64(u64::from(*b));
        }
    }

    fn write_u64(&mut self, x: u64) {
        self.0 = (self.0.rotate_left(5) ^ x).wrapping_mul(0x51_7c_c1_b7_27_22_0a_95);
    }

    fn write_usize(&mut self, x: usize) {
        self.write_u64(x as u64);
    }
}

/// [`KeyHasher`] as a `HashMap`'s hasher (also the monitor's pair index,
/// [`crate::sim::MonitorState::pair_index`]: small integer keys, looked up a few times a step).
pub type KeyHash = std::hash::BuildHasherDefault<KeyHasher>;

impl Clone for PairMemo {
    fn clone(&self) -> Self {
        Self::default()
    }
}

impl std::fmt::Debug for PairMemo {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "PairMemo({} pairs)", self.len())
    }
}

impl PairMemo {
    /// The kept evaluation of a pair, if any.
    pub fn get(&self, key: PairKey) -> Option<ExactEval> {
        self.0.lock().ok()?.get(&key).copied()
    }

    /// `f` applied to the kept evaluation of a pair, if any, read in place (no copy of it; the
    /// memo is locked while `f` runs, so `f` must not use the memo).
    pub fn with<R>(&self, key: PairKey, f: impl FnOnce(&ExactEval) -> R) -> Option<R> {
        self.0.lock().ok()?.get(&key).map(f)
    }

    /// Keeps (or replaces) a pair's evaluation; a new pair is not kept once
    /// [`PAIR_MEMO_MAX_PAIRS`] are.
    pub fn put(&self, key: PairKey, e: ExactEval) {
        if let Ok(mut m) = self.0.lock()
            && (m.len() < PAIR_MEMO_MAX_PAIRS || m.contains_key(&key))
        {
            m.insert(key, e);
        }
    }

    /// Pairs kept.
    pub fn len(&self) -> usize {
        self.0.lock().map_or(0, |m| m.len())
    }

    /// No pair kept.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

/// The distance of two parts with support maps (part a at `pa`, within `ra_m` of its origin;
/// part b at `pb`, within `rb_m`) with its certified lower bound and witness points: parry's
/// `closest_points` (GJK, or its closed forms) at the relative pose formed in f64, and the gap
/// along the witness direction n, n·(s_b(−n) − s_a(n)) with s the support points — any axis's
/// gap is at most the distance — less the f32 rounding of the relative pose,
/// [`F32_REL_TOL`]·(|t_rel| + r_a + r_b). `None` when either part has no support map or parry
/// finds no answer. Touching or overlapping parts give 0 (witnesses at the origins: not to be
/// carried).
pub fn convex_exact(
    pa: &Isometry3<f64>,
    (a, ra_m): (&dyn rp::Shape, f64),
    pb: &Isometry3<f64>,
    (b, rb_m): (&dyn rp::Shape, f64),
) -> Option<ExactEval> {
    let (sa, sb) = (a.as_support_map()?, b.as_support_map()?);
    let rel = pa.inv_mul(pb);
    let eps = F32_REL_TOL * (rel.translation.vector.norm() + ra_m + rb_m);
    let rel32 = conv::pose(&rel);
    let touching = ExactEval::new(rel, 0.0, 0.0, Point3::origin(), Point3::origin());
    // Two boxes: parry's own box–box closest points (separating axes, then a projection), the
    // ones its `distance` measures, so that the value is the one `query::distance` gives;
    // every other pair through the dispatcher (GJK, or its closed forms for balls), as there.
    let points = match (a.as_cuboid(), b.as_cuboid()) {
        (Some(ca), Some(cb)) => {
            match query::details::closest_points_cuboid_cuboid(&rel32, ca, cb, Real::MAX) {
                // (Points in each box's own frame: the second into a's.)
                query::ClosestPoints::WithinMargin(p1, p2) => {
                    query::ClosestPoints::WithinMargin(p1, rel32 * p2)
                }
                other => other,
            }
        }
        _ => query::closest_points(&rp::Pose::IDENTITY, a, &rel32, b, Real::MAX).ok()?,
    };
    match points {
        query::ClosestPoints::Intersecting => Some(touching),
        query::ClosestPoints::WithinMargin(p1, p2) => {
            let d = (p2 - p1).length();
            if d.is_nan() || d <= 0.0 {
                return Some(touching);
            }
            let n = (p2 - p1) / d;
            let sa_n = sa.local_support_point(n);
            let sb_n = rel32 * sb.local_support_point(rel32.rotation.inverse() * -n);
            let gap = f64::from(n.dot(sb_n - sa_n));
            let value = f64::from(d);
            Some(ExactEval::new(
                rel,
                value,
                (gap.min(value) - eps).max(0.0),
                Point3::from(conv::na(p1)),
                Point3::from(conv::na(rel32.inverse_transform_point(p2))),
            ))
        }
        query::ClosestPoints::Disjoint => None,
    }
}

/// The distance of part a (at `pa`, within `ra_m` of its origin) and part b (at `pb`, within
/// `rb_m`), one of them a triangle mesh and the other a shape with a support map, triangle by
/// triangle with a tight certified lower bound and the witness points (see the module's
/// documentation). `None` for any other pair of shapes. Touching or overlapping parts give 0
/// (and witnesses at the origin of each part: not to be carried).
pub fn mesh_exact(
    pa: &Isometry3<f64>,
    (a, ra_m): (&dyn rp::Shape, f64),
    pb: &Isometry3<f64>,
    (b, rb_m): (&dyn rp::Shape, f64),
) -> Option<ExactEval> {
    // m: the mesh side, s: the other; `rel` is s's frame in m's.
    let (m, pm, s_shape, ps, mesh_is_a) = match (a.as_trimesh(), b.as_trimesh()) {
        (Some(m), None) => (m, pa, b, pb, true),
        (None, Some(m)) => (m, pb, a, pa, false),
        _ => return None,
    };
    let s = s_shape.as_support_map()?;
    let rel = pm.inv_mul(ps);
    let rel32 = conv::pose(&rel);
    let eps = F32_REL_TOL * (rel.translation.vector.norm() + ra_m + rb_m);
    let (value, lower, wm, ws) = trimesh_support_map(m, &rel32, s_shape, s)?;
    let value = f64::from(value);
    let lower = (f64::from(lower) - eps).max(0.0).min(value);
    let (wm, ws) = (Point3::from(conv::na(wm)), Point3::from(conv::na(ws)));
    let (witness_a, witness_b) = if mesh_is_a { (wm, ws) } else { (ws, wm) };
    Some(ExactEval::new(
        pa.inv_mul(pb),
        value,
        lower,
        witness_a,
        witness_b,
    ))
}

/// Triangle mesh `m` against the support map `s` (shape `s_shape`) at `rel` (s's frame in m's),
/// in f32: (the best triangle's distance, the smallest certified gap over the triangles
/// evaluated, the witness on m in m's frame, the witness on s in s's frame).
fn trimesh_support_map(
    m: &TriMesh,
    rel: &rp::Pose,
    s_shape: &dyn rp::Shape,
    s: &dyn SupportMap,
) -> Option<(Real, Real, Vector, Vector)> {
    // As parry's `distance_to_shape`: a node's cost is the distance between its box and the
    // other part's box (their Minkowski difference's distance to the origin), a lower bound of
    // every triangle in it.
    let s_box = s_shape.compute_aabb(rel);
    let shift = -s_box.center();
    let margin = s_box.half_extents();
    let lowest = Cell::new(Real::INFINITY);
    let inv = rel.rotation.inverse();
    let best = m.bvh().find_best(
        Real::MAX,
        |node: &BvhNode, _| {
            Aabb {
                mins: node.mins() + shift - margin,
                maxs: node.maxs() + shift + margin,
            }
            .distance_to_origin()
        },
        |id, _| {
            let tri = m.triangle(id);
            // parry's own pair query (GJK, or its closed forms for balls), both witnesses in
            // the mesh's frame.
            match query::closest_points(&rp::Pose::IDENTITY, &tri, rel, s_shape, Real::MAX).ok()? {
                query::ClosestPoints::WithinMargin(p1, p2m) => {
                    let d = (p2m - p1).length();
                    if !d.is_finite() || d <= 0.0 {
                        lowest.set(0.0);
                        return Some((0.0, (Vector::ZERO, Vector::ZERO)));
                    }
                    let gap_along = |n: Vector| {
                        let s_far = *rel * s.local_support_point(inv * -n);
                        n.dot(s_far - tri.local_support_point(n))
                    };
                    let mut gap = gap_along((p2m - p1) / d);
                    // Also along the direction from the triangle's point nearest the other
                    // part's witness (exact: a point projection), often nearer the true one
                    // than GJK's (any direction's gap is a lower bound).
                    let q = tri.project_local_point(p2m, true).point;
                    let dq = (p2m - q).length();
                    if dq > 0.0 && dq.is_finite() {
                        gap = gap.max(gap_along((p2m - q) / dq));
                    }
                    let gap = gap.min(d);
                    lowest.set(lowest.get().min(gap));
                    Some((d, (p1, rel.inverse_transform_point(p2m))))
                }
                query::ClosestPoints::Intersecting => {
                    lowest.set(0.0);
                    Some((0.0, (Vector::ZERO, Vector::ZERO)))
                }
                query::ClosestPoints::Disjoint => None,
            }
        },
    )?;
    let (_, (d, (p1, p2))) = best;
    Some((d, lowest.get().min(d), p1, p2))
}
