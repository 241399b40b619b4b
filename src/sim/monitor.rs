//! The safety monitor: every step, the exact minimum distance between the full geometry of
//! every tracked pair of bodies (parry, with bounding-sphere pruning) with a certified lower
//! bound, its closest approach over the run judged on the whole step interval (between
//! samples too), the closest pair overall, and rapier's contacts named by part — docking
//! contact (both parts docking parts) or collision — with the time of first touch refined on
//! the step's path.

use super::broadphase::BroadPhase;
use super::motion::StepMotion;
use super::{BodyState, Clock, EventLog, MonitorState, NamedPairs, Part, Roster, SimBody, conv};
use crate::geometry::bounds::{Bracket, interval_lower_bound};
use bevy::prelude::*;
use bevy_rapier3d::parry::query;
use bevy_rapier3d::rapier::math::Pose;
use bevy_rapier3d::rapier::prelude as rp;
use nalgebra::{Isometry3, UnitQuaternion, Vector3};
use sphere_prune::SpherePrune;
use std::collections::{BTreeMap, HashMap};

mod contact_steps;
pub mod memo;
pub mod sphere_prune;
mod tracked;

/// Who a collider is.
#[derive(Debug, Clone)]
pub struct ColliderRef {
    /// Body index.
    pub body: usize,
    /// Collider index within the body (scene order).
    pub part: usize,
    /// `body/collider` name.
    pub full_name: String,
    /// Part role is docking.
    pub docking: bool,
}

/// A contact in progress.
#[derive(Debug, Clone, serde::Serialize)]
pub struct ActiveContact {
    /// Start time, s.
    pub start_s: f64,
    /// Docking contact (both parts docking parts) or collision.
    pub docking: bool,
    /// Peak contact force (magnitude: normal and friction), N.
    pub peak_force_n: f64,
    /// Accumulated contact impulse (sum of the per-step magnitudes), N·s.
    pub impulse_ns: f64,
}

/// Per-part contact totals over the run.
#[derive(Debug, Clone, Default, serde::Serialize)]
pub struct PartContactStats {
    /// Peak normal contact force on this part, N.
    pub peak_force_n: f64,
    /// Sum over steps of the magnitude of the contact impulse on this part, N·s.
    pub total_impulse_ns: f64,
    /// Net contact impulse on this part (vector sum), world frame, N·s.
    pub net_impulse_ns: [f64; 3],
}

/// A part pair's contact impulse accumulated since the start of the run.
#[derive(Debug, Clone, Default)]
pub struct CumulativeImpulse {
    /// Both parts are docking parts.
    pub docking: bool,
    /// Sum over steps of the pair's impulse magnitude, N·s.
    pub magnitude_ns: f64,
    /// Vector sum of the impulse on the pair's second part, world frame, N·s.
    pub on_b_ns: nalgebra::Vector3<f64>,
}

/// One contact point at one instant (a row of `contact_points.csv`).
#[derive(Debug, Clone)]
pub struct PointRow {
    /// Time, s: the end of the step (rigid) or of the sub-step (compliant).
    pub t_s: f64,
    /// First part (`body/collider`).
    pub a: String,
    /// Second part.
    pub b: String,
    /// Computed by the compliant model (else: a rapier contact point).
    pub compliant: bool,
    /// Contact point, world, m (compliant: the point of application).
    pub point_m: nalgebra::Vector3<f64>,
    /// Unit contact normal, the direction of the normal force on `b`, world.
    pub normal_on_b: nalgebra::Vector3<f64>,
    /// Penetration depth, m (negative: a gap, for rapier's speculative points).
    pub depth_m: f64,
    /// Normal force, N (rigid: normal impulse / dt).
    pub normal_force_n: f64,
    /// Normal impulse over the step (rigid) or sub-step (compliant), N·s.
    pub normal_impulse_ns: f64,
    /// Contact force on `b`, world, N (compliant: normal and friction; rigid: the normal part
    /// only, rapier solves friction per manifold).
    pub force_on_b_n: nalgebra::Vector3<f64>,
}

/// What one part pair did in the last step.
#[derive(Debug, Clone)]
pub struct StepPair {
    /// Pair key (`body/collider` names, the lower body index first).
    pub key: (String, String),
    /// Both parts are docking parts.
    pub docking: bool,
    /// Body indices of `key.0` and `key.1`.
    pub bodies: (usize, usize),
    /// Impulse on the second part over the step, world, N·s.
    pub impulse_on_b_ns: nalgebra::Vector3<f64>,
    /// Peak contact force within the step (rigid: |impulse| / dt), N.
    pub peak_force_n: f64,
}

/// Contact bookkeeping.
#[derive(Resource, Debug, Default)]
pub struct ContactState {
    /// Collider → who.
    pub colliders: HashMap<rp::ColliderHandle, ColliderRef>,
    /// Per body index: in contact with another body this step.
    pub touching: Vec<bool>,
    /// Per body index: contact impulse received this step (momentum change less the applied
    /// forces' impulse), world frame, N·s.
    pub body_impulse: Vec<nalgebra::Vector3<f64>>,
    /// Per body index: contact and joint angular impulse received this step about its centre of
    /// mass (angular momentum change less the applied torques' impulse), world frame, N·m·s.
    pub body_angular_impulse: Vec<nalgebra::Vector3<f64>>,
    /// Contacts in progress, keyed by the ordered pair of `body/collider` names.
    pub active: BTreeMap<(String, String), ActiveContact>,
    /// Totals per `body/collider`.
    pub per_part: BTreeMap<String, PartContactStats>,
    /// First contact of any kind, s.
    pub first_contact_s: Option<f64>,
    /// First collision (a contact that is not a docking contact), s.
    pub first_collision_s: Option<f64>,
    /// Time of first touch of the first contact, refined on the step's free-flight paths
    /// ([`touch_time`]), s.
    pub first_touch_s: Option<f64>,
    /// Every collision start: (t_s, part, part).
    pub collisions: Vec<(f64, String, String)>,
    /// Per part pair ever in contact, accumulated over the whole run across restarts, so the
    /// recorder's per-row differences telescope to the run's totals.
    pub cumulative_impulse_ns: BTreeMap<(String, String), CumulativeImpulse>,
    /// The contact points of the last step (rapier's and the compliant model's sub-step
    /// samples), written to `contact_points.csv` every step.
    pub points: Vec<PointRow>,
    /// Every part pair that exchanged an impulse in the last step.
    pub step_pairs: Vec<StepPair>,
}

impl ContactState {
    /// Marks the bodies with an active contact against another body (called right after the
    /// rapier step, before the f64 state update).
    pub fn refresh_touching(&mut self, world: &rp::PhysicsWorld) {
        self.touching.iter_mut().for_each(|t| *t = false);
        for pair in world.narrow_phase.contact_pairs() {
            if !touching(pair) {
                continue;
            }
            let (Some(a), Some(b)) = (
                self.colliders.get(&pair.collider1),
                self.colliders.get(&pair.collider2),
            ) else {
                continue;
            };
            if a.body != b.body {
                let (ia, ib) = (a.body, b.body);
                self.touching[ia] = true;
                self.touching[ib] = true;
            }
        }
    }
}

/// Angular momentum about the centre of mass, world frame: R·J·Rᵀ·ω (J in body axes).
pub fn angular_momentum(
    att: &nalgebra::UnitQuaternion<f64>,
    j_body: &nalgebra::Matrix3<f64>,
    omega_world: &nalgebra::Vector3<f64>,
) -> nalgebra::Vector3<f64> {
    let r = att.to_rotation_matrix().into_inner();
    r * j_body * r.transpose() * omega_world
}

/// A contact pair counts as touching when a contact point is at zero or negative distance or
/// carries a normal impulse (rapier also keeps speculative points within its prediction
/// distance: those are not contacts). A manifold the solver ignores (solver groups off: a pair
/// that overlapped at t = 0 and has not separated yet, see `overlap.rs`) is no contact either.
fn touching(pair: &rp::ContactPair) -> bool {
    pair.has_any_active_contact()
        && pair
            .manifolds
            .iter()
            .filter(|m| {
                m.data
                    .solver_flags
                    .contains(rp::SolverFlags::COMPUTE_IMPULSES)
            })
            .flat_map(|m| m.points.iter())
            .any(|p| p.dist <= 0.0 || p.data.impulse > 0.0)
}

/// Exact minimum distance between two shapes at f64 poses: the relative pose is formed in f64
/// so that parry's f32 works with small numbers whatever the world coordinates.
pub fn shape_distance(
    pose_a: &Isometry3<f64>,
    a: &dyn rp::Shape,
    pose_b: &Isometry3<f64>,
    b: &dyn rp::Shape,
) -> f64 {
    let rel = pose_a.inv_mul(pose_b);
    query::distance(&Pose::IDENTITY, a, &conv::pose(&rel), b).unwrap_or(f32::NAN) as f64
}

/// Relative precision of parry's GJK distance: it stops once its upper and lower bounds agree
/// to √(10·ε_f32) ≈ 1.09e-3 of the distance (parry `query::gjk::closest_points`); we allow
/// 1.2e-3.
pub const GJK_REL_TOL: f64 = 1.2e-3;

/// f32 rounding of a relative pose and of the support points, as a fraction of the pose's
/// scale (|translation| + the two bounding radii): 8 ulps.
pub const F32_REL_TOL: f64 = 8.0 * f32::EPSILON as f64;

/// A distance with a certified lower bound, for two shapes at f64 poses.
///
/// The value is parry's GJK distance (`query::closest_points`' witnesses); the lower bound is
/// the gap between the two shapes along the witness direction n: n·(s_b(−n) − s_a(n)) with s
/// the support points — any axis's gap is at most the distance — less the f32 rounding of the
/// relative pose. A shape without a support map falls back to value·(1 − [`GJK_REL_TOL`]).
pub fn shape_bracket(
    pose_a: &Isometry3<f64>,
    a: &dyn rp::Shape,
    ra: f64,
    pose_b: &Isometry3<f64>,
    b: &dyn rp::Shape,
    rb: f64,
) -> Bracket {
    let rel = pose_a.inv_mul(pose_b);
    let scale = rel.translation.vector.norm() + ra + rb;
    let eps = F32_REL_TOL * scale;
    let rel32 = conv::pose(&rel);
    let fallback = || {
        let d = query::distance(&Pose::IDENTITY, a, &rel32, b).unwrap_or(f32::NAN) as f64;
        Bracket {
            value: d,
            lower: (d * (1.0 - GJK_REL_TOL) - eps).max(0.0),
        }
    };
    if a.as_support_map().is_some() && b.as_support_map().is_some() {
        return memo::convex_exact(pose_a, (a, ra), pose_b, (b, rb)).map_or_else(fallback, |e| {
            Bracket {
                value: e.value_m,
                lower: e.lower_m,
            }
        });
    }
    // No support map (a mesh): the witnesses' distance is parry's distance; no second query.
    match query::closest_points(&Pose::IDENTITY, a, &rel32, b, f32::MAX) {
        Ok(query::ClosestPoints::Intersecting) => Bracket::exact(0.0),
        Ok(query::ClosestPoints::WithinMargin(p1, p2)) => {
            let d = (p2 - p1).length();
            if d.is_nan() || d <= 0.0 {
                return Bracket::exact(0.0);
            }
            let value = d as f64;
            Bracket {
                value,
                lower: (value * (1.0 - GJK_REL_TOL) - eps).max(0.0),
            }
        }
        _ => fallback(),
    }
}

/// Most alternating-projection sweeps [`hull_bracket`] makes to tighten its upper bound.
pub const HULL_UPPER_SWEEPS: usize = 4;

/// What [`hull_bracket`] found for a part pair with a mesh part.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum HullEval {
    /// The hulls' certified gap is at least the caller's `clear_at`: the pair is at least that
    /// far apart (this certified lower bound, m); no point query was made.
    Clear(f64),
    /// A certified lower bound and an achieved upper bound of the pair's distance, m.
    Bracket {
        /// The hulls' certified gap (a lower bound of the mesh distance), m.
        lower: f64,
        /// An upper bound of the pair's distance: the distance of a point of one part to the
        /// other part, or the shell's certified bound ([`super::mesh::MeshShell`]), m.
        upper: f64,
    },
    /// The hulls overlap (or a side has no support map): no bound from them.
    None,
}

/// A certified bracket of the distance between two parts, at least one of them a triangle mesh
/// M (parry `TriMesh`, no support map) with the support map of its vertices' convex hull H
/// ([`super::mesh::HullSupport`]), without a triangle-by-triangle query.
///
/// Lower bound: M ⊂ H (every triangle is a convex combination of its corners), so
/// d(A, M) ≥ d(A, H) for any A, closed mesh or not; GJK between the two support maps (the
/// other part's own, or its hull's when it is a mesh too) gives witnesses p₁, p₂ and the
/// direction n = (p₂ − p₁)/|p₂ − p₁|, and the gap n·(s₂(−n) − s₁(n)) is a lower bound of the
/// hulls' distance (any axis's gap is, as in [`shape_bracket`]) — and so is the gap along the
/// direction of the point pair of the upper bound below, nearer the true direction than GJK's
/// on a curved part; the larger, less the f32 rounding of the relative pose ([`F32_REL_TOL`])
/// and of the hulls' maxima ([`super::mesh::HULL_SUPPORT_REL_TOL`]).
///
/// Upper bound: each side's point near its witness — for a mesh, the point of its triangles
/// closest to its hull's witness (parry's point projection on the `TriMesh`, which its BVH
/// prunes well); for a primitive, its witness itself (a convex combination of its support
/// points, so in it) — is a point w of that part, and the distance from w to the other part
/// (its triangles, or the solid primitive: parry's point query) is at least their distance;
/// the smaller of the two is the upper bound. Where the hull's closest point lies on the mesh
/// (a convex part, or the convex side of a concave one) it agrees with the lower bound to
/// rounding; in a concavity, or inside the hull, it does not, and the caller falls back to the
/// exact mesh query.
///
/// First tier, for a mesh part against a part with a support map: the mesh's shell
/// ([`super::mesh::MeshShell`]: two spheres about its centre, one point projection and one
/// support point on the other part; then, if those are not narrow enough, two boxes about it,
/// two GJK queries against cuboids; `shell_bound`). Where its bracket is already as narrow as
/// the caller's test of an exact value (lower ≥ upper·(1 − [`GJK_REL_TOL`]) − the f32
/// rounding), it is the answer, with no support or triangle query on the mesh (a round part
/// far away: the sphere mesh's shell is 1.1e-4 m thick; a box-shaped part at any distance);
/// otherwise its bounds join the hull's.
///
/// With `clear_at`, a lower bound at or above it is returned as [`HullEval::Clear`] before the
/// point query.
#[allow(clippy::too_many_arguments)]
pub fn hull_bracket(
    pose_a: &Isometry3<f64>,
    (a, ha, ra): (&dyn rp::Shape, Option<&super::mesh::HullSupport>, f64),
    pose_b: &Isometry3<f64>,
    (b, hb, rb): (&dyn rp::Shape, Option<&super::mesh::HullSupport>, f64),
    clear_at: f64,
) -> HullEval {
    use bevy_rapier3d::parry::shape::SupportMap;
    fn side<'s>(
        s: &'s dyn rp::Shape,
        h: Option<&'s super::mesh::HullSupport>,
    ) -> Option<&'s dyn SupportMap> {
        match h {
            Some(h) => Some(h as &dyn SupportMap),
            None => s.as_support_map(),
        }
    }
    let (Some(sa), Some(sb)) = (side(a, ha), side(b, hb)) else {
        return HullEval::None;
    };
    let rel = pose_a.inv_mul(pose_b);
    let scale = rel.translation.vector.norm() + ra + rb;
    // First the shell of a mesh part against a part with a support map: no support or
    // triangle query at all where it is narrow enough (a round part, far away).
    let pair_eps = F32_REL_TOL * scale;
    let (has_shell, shell_lower, shell_upper) =
        match shell_tier(pose_a, (a, ha, ra), pose_b, (b, hb, rb), pair_eps, clear_at) {
            Ok(tier) => tier,
            Err(answer) => return answer,
        };
    let hull_tol = super::mesh::HULL_SUPPORT_REL_TOL
        * (ha.map_or(0.0, |h| h.radius_m()) + hb.map_or(0.0, |h| h.radius_m()));
    let eps = F32_REL_TOL * scale + hull_tol;
    let rel32 = conv::pose(&rel);
    let (ma, mb) = (ha.and(a.as_trimesh()), hb.and(b.as_trimesh()));
    let pair = HullPair {
        a,
        ma,
        b,
        mb,
        sa,
        sb,
        rel32,
        eps,
    };
    let (p1, p2) =
        match query::details::closest_points_support_map_support_map(&rel32, sa, sb, f32::MAX) {
            // p₁ in A's frame, p₂ in B's.
            query::ClosestPoints::WithinMargin(p1, p2) => (p1, p2),
            _ => return HullEval::None,
        };
    let p2a = rel32 * p2;
    let d = (p2a - p1).length();
    if d.is_nan() || d <= 0.0 {
        return HullEval::None;
    }
    let gap = pair.gap_along((p2a - p1) / d).min(f64::from(d));
    let gap = if has_shell {
        gap.max(shell_lower + eps)
    } else {
        gap
    };
    if gap - eps >= clear_at {
        return HullEval::Clear(gap - eps);
    }
    // A point of each part near its witness: a mesh's point closest to its hull's witness,
    // or a primitive's own witness (in it: a convex combination of its support points); the
    // upper bound is the smaller distance of either to the other part.
    if ma.is_none() && mb.is_none() {
        return HullEval::None;
    }
    let (upper, gap) = pair.upper_bound(p1, p2, gap);
    if !upper.is_finite() {
        return HullEval::None;
    }
    let upper = f64::from(upper).min(shell_upper);
    let lower = (gap - eps).max(0.0);
    HullEval::Bracket {
        lower: lower.min(upper),
        upper,
    }
}

/// The first tier of [`hull_bracket`]: for a mesh part against a part with a support map, its
/// shell bracket (`shell_bound`, with the pair's f32 rounding `pair_eps`, m). `Ok` with
/// (whether there is one, its lower bound, its upper bound), m (0 and ∞ without one); `Err`
/// with the answer when the shell already gives it: clear at `clear_at`, m, or a bracket as
/// narrow as the caller's test of an exact value.
fn shell_tier(
    pose_a: &Isometry3<f64>,
    (a, ha, ra): (&dyn rp::Shape, Option<&super::mesh::HullSupport>, f64),
    pose_b: &Isometry3<f64>,
    (b, hb, rb): (&dyn rp::Shape, Option<&super::mesh::HullSupport>, f64),
    pair_eps: f64,
    clear_at: f64,
) -> Result<(bool, f64, f64), HullEval> {
    let shell = match (ha.and_then(|h| h.shell()), hb.and_then(|h| h.shell())) {
        (Some(s), None) if hb.is_none() => {
            shell_bound((pose_b, b, rb), pose_a, s, pair_eps, clear_at)
        }
        (None, Some(s)) if ha.is_none() => {
            shell_bound((pose_a, a, ra), pose_b, s, pair_eps, clear_at)
        }
        _ => None,
    };
    let (shell_lower, shell_upper) = shell.map_or((0.0, f64::INFINITY), |(l, u)| {
        (l.max(0.0), u.unwrap_or(f64::INFINITY))
    });
    if shell.is_some() && shell_lower >= clear_at {
        return Err(HullEval::Clear(shell_lower));
    }
    if shell_lower >= shell_upper * (1.0 - GJK_REL_TOL) - pair_eps {
        return Err(HullEval::Bracket {
            lower: shell_lower.min(shell_upper),
            upper: shell_upper,
        });
    }
    Ok((shell.is_some(), shell_lower, shell_upper))
}

/// Two parts in A's frame, for the hull tier of [`hull_bracket`]: their shapes, their
/// triangles when they are meshes with a hull, their support maps (a mesh's hull's), B's pose
/// in A's frame (f32) and the pair's rounding allowance.
struct HullPair<'s> {
    /// Part A.
    a: &'s dyn rp::Shape,
    /// A's triangles, when it is a mesh with a hull.
    ma: Option<&'s bevy_rapier3d::parry::shape::TriMesh>,
    /// Part B.
    b: &'s dyn rp::Shape,
    /// B's triangles, when it is a mesh with a hull.
    mb: Option<&'s bevy_rapier3d::parry::shape::TriMesh>,
    /// A's support map (its hull's for a mesh).
    sa: &'s dyn bevy_rapier3d::parry::shape::SupportMap,
    /// B's support map (its hull's for a mesh).
    sb: &'s dyn bevy_rapier3d::parry::shape::SupportMap,
    /// B's pose in A's frame.
    rel32: Pose,
    /// The f32 rounding of the relative pose and of the hulls' maxima, m.
    eps: f64,
}

impl HullPair<'_> {
    /// The hulls' gap along a unit direction n (A's frame): n·(s_b(−n) − s_a(n)), m.
    fn gap_along(&self, n: bevy_rapier3d::rapier::math::Vector) -> f64 {
        let (sa, sb, rel32) = (self.sa, self.sb, self.rel32);
        let s1 = sa.local_support_point(n);
        let s2 = rel32 * sb.local_support_point(rel32.rotation.inverse() * -n);
        f64::from(n.dot(s2 - s1))
    }

    /// A point of a part near `p` (its frame): for a mesh `m`, its triangles' point closest to
    /// `p`; for a primitive, `p` itself.
    fn on(
        m: Option<&bevy_rapier3d::parry::shape::TriMesh>,
        p: bevy_rapier3d::rapier::math::Vector,
    ) -> bevy_rapier3d::rapier::math::Vector {
        use bevy_rapier3d::parry::query::PointQuery;
        match m {
            Some(m) => m.project_local_point(p, false).point,
            None => p,
        }
    }

    /// The point of a part closest to w (its frame): the mesh's triangles (its surface, as the
    /// exact query judges it), or the solid primitive.
    fn near(
        s: &dyn rp::Shape,
        m: Option<&bevy_rapier3d::parry::shape::TriMesh>,
        w: bevy_rapier3d::rapier::math::Vector,
    ) -> bevy_rapier3d::rapier::math::Vector {
        use bevy_rapier3d::parry::query::PointQuery;
        match m {
            Some(m) => m.project_local_point(w, false).point,
            None => s.project_local_point(w, true).point,
        }
    }

    /// The point of A closest to `w` (A's frame).
    fn near_a(
        &self,
        w: bevy_rapier3d::rapier::math::Vector,
    ) -> bevy_rapier3d::rapier::math::Vector {
        Self::near(self.a, self.ma, w)
    }

    /// The point of B closest to `w` (both in A's frame).
    fn near_b(
        &self,
        w: bevy_rapier3d::rapier::math::Vector,
    ) -> bevy_rapier3d::rapier::math::Vector {
        let rel32 = self.rel32;
        rel32 * Self::near(self.b, self.mb, rel32.inverse_transform_point(w))
    }

    /// The gap along the direction of a point pair (from ∈ A, to ∈ B, |to − from| = d), often
    /// nearer the true direction than GJK's on a curved part (any direction's gap is a lower
    /// bound): the larger of it and `gap`, m.
    fn along(
        &self,
        from: bevy_rapier3d::rapier::math::Vector,
        to: bevy_rapier3d::rapier::math::Vector,
        d: f32,
        gap: f64,
    ) -> f64 {
        let n = (to - from) / d;
        if d > 0.0 && n.is_finite() {
            gap.max(self.gap_along(n))
        } else {
            gap
        }
    }

    /// Done once the bracket is down to the rounding (as exact as parry's own f32 queries).
    fn settled(&self, upper: f32, gap: f64) -> bool {
        f64::from(upper) - gap <= self.eps
    }

    /// The hull tier's upper bound from GJK's hull witnesses `p1` (A's frame) and `p2` (B's):
    /// each side's point near its witness ([`Self::on`]), its distance to the other part, the
    /// smaller, then up to [`HULL_UPPER_SWEEPS`] alternating projections while they gain;
    /// with the lower bound `gap`, m, raised along each better point pair ([`Self::along`]).
    /// Returns (upper bound, m; gap, m).
    fn upper_bound(
        &self,
        p1: bevy_rapier3d::rapier::math::Vector,
        p2: bevy_rapier3d::rapier::math::Vector,
        gap: f64,
    ) -> (f32, f64) {
        let q1 = Self::on(self.ma, p1);
        let r2 = self.near_b(q1);
        let (mut upper, mut from, mut to) = ((r2 - q1).length(), q1, r2);
        let mut gap = if self.settled(upper, gap) {
            gap
        } else {
            self.along(from, to, upper, gap)
        };
        if !self.settled(upper, gap) {
            let q2 = self.rel32 * Self::on(self.mb, p2);
            let r1 = self.near_a(q2);
            let d2 = (q2 - r1).length();
            if d2 < upper {
                (upper, from, to) = (d2, r1, q2);
                gap = self.along(from, to, upper, gap);
            }
            // Alternating projections (x ← the point of A nearest y, y ← the point of B nearest
            // x) never increase |x − y| and walk a witness that GJK left off the true closest
            // point (on a curved part) towards it: a few, while they gain.
            for _ in 0..HULL_UPPER_SWEEPS {
                if self.settled(upper, gap) {
                    break;
                }
                let x = self.near_a(to);
                let y = self.near_b(x);
                let d = (y - x).length();
                let gains = d < upper * (1.0 - 1e-7);
                if d < upper {
                    (upper, from, to) = (d, x, y);
                    gap = self.along(from, to, upper, gap);
                }
                if !gains {
                    break;
                }
            }
        }
        (upper, gap)
    }
}

/// The hull support map of a triangle-mesh shape, with the shell of its triangles
/// ([`super::mesh::MeshShell`]) ([`MonitorGeometry::hulls`]); `None` for any other shape.
pub fn mesh_hull(shape: &dyn rp::Shape) -> Option<std::sync::Arc<super::mesh::HullSupport>> {
    shape
        .as_trimesh()
        .and_then(|m| {
            super::mesh::HullSupport::new(m.vertices())
                .map(|h| h.with_shell(super::mesh::MeshShell::new(m.vertices(), m.indices())))
        })
        .map(std::sync::Arc::new)
}

/// The shell bracket ([`super::mesh::MeshShell`]) of a mesh part M and a part X (bounding
/// radius `rx`) with a support map: (certified lower bound, certified upper bound when M's
/// shell has an inner sphere or box) of their distance, m; `None` when X has no support map or
/// holds M's centre.
///
/// Spheres: with c M's centre in X's frame (the relative pose in f64) and p parry's projection
/// of c on X (a point of X), n = (c − p)/|c − p|: the gap n·c − h_X(n) (h_X X's support
/// function) is at most the distance from c to X (any direction's is), so the distance from X
/// to the outer ball, thus to M, is at least gap − outer. When that is positive p lies outside
/// the outer ball and the distance from X to M is at most |p − c| − inner (the shell's docs).
/// The lower bound is widened by `eps`, the f32 rounding of X's support point and projection
/// (8 ulps of the pair's scale, [`F32_REL_TOL`]); the upper bound, like the hull bracket's, is
/// a distance from a point of X as parry's f32 gives it (exact to that rounding, which is
/// within every caller's tolerance of a value); c is formed in f64 and the shell's radii carry
/// their own padding.
///
/// Boxes, when the spheres are not yet as narrow as an exact query (lower ≥ upper·(1 −
/// [`GJK_REL_TOL`]) − `eps`) and the lower bound is below `clear_at`: the outer box holds M,
/// so its certified bracket's lower bound with X ([`shape_bracket`]) is one of M's; when that
/// is positive, X's witness lies outside the outer box, so outside M's hull, and its distance
/// to the inner box's witness (a point inside M's solid: the segment between them crosses the
/// surface) is an upper bound. The boxes' half-extents are rounded outwards (outer) and inwards
/// (inner) to f32.
fn shell_bound(
    (pose_x, x, rx): (&Isometry3<f64>, &dyn rp::Shape, f64),
    pose_m: &Isometry3<f64>,
    shell: &super::mesh::MeshShell,
    eps: f64,
    clear_at: f64,
) -> Option<(f64, Option<f64>)> {
    use bevy_rapier3d::parry::shape::Cuboid;
    let sx = x.as_support_map()?;
    let centre = Vector3::from(shell.centre_m);
    let c = pose_x.inv_mul(pose_m) * nalgebra::Point3::from(centre);
    let proj = x.project_local_point(conv::v(&c.coords), true);
    if proj.is_inside {
        return None;
    }
    let p = conv::na(proj.point);
    let to_c = c.coords - p;
    let dist = to_c.norm();
    if !(dist > 0.0 && dist.is_finite()) {
        return None;
    }
    let n = to_c / dist;
    let s = conv::na(sx.local_support_point(conv::v(&n)));
    let mut lower = n.dot(&(c.coords - s)) - shell.outer_m - eps;
    let mut upper = shell
        .inner_m
        .filter(|_| lower > 0.0)
        .map(|inner| dist - inner);
    let narrow = |l: f64, u: Option<f64>| u.is_some_and(|u| l >= u * (1.0 - GJK_REL_TOL) - eps);
    if lower >= clear_at || narrow(lower, upper) {
        return Some((lower, upper));
    }
    // f32 half-extents rounded outwards (up) or inwards (down).
    let round = |h: [f64; 3], up: bool| {
        let r = h.map(|v| {
            let f = v as f32;
            match (up, f64::from(f).total_cmp(&v)) {
                (true, std::cmp::Ordering::Less) => f.next_up(),
                (false, std::cmp::Ordering::Greater) => f.next_down(),
                _ => f,
            }
        });
        Cuboid::new(bevy_rapier3d::rapier::math::Vector::new(r[0], r[1], r[2]))
    };
    let pad = super::mesh::SHELL_REL_PAD * (centre.norm() + shell.outer_m);
    let pose_box = pose_m * nalgebra::Translation3::from(centre);
    let outer_half = shell.outer_half_m.map(|h| h + pad);
    let outer = round(outer_half, true);
    let r_outer = Vector3::from(outer_half).norm();
    let box_lower = shape_bracket(pose_x, x, rx, &pose_box, &outer, r_outer).lower;
    lower = lower.max(box_lower);
    if let Some(h) = shell.inner_half_m.filter(|_| box_lower > 0.0) {
        let inner = round(h, false);
        let r_inner = Vector3::from(h).norm();
        let u = shape_bracket(pose_x, x, rx, &pose_box, &inner, r_inner).value;
        if u.is_finite() {
            upper = Some(upper.map_or(u, |v| v.min(u)));
        }
    }
    Some((lower, upper))
}

/// The parts of every body as the monitor uses them (fetched from the ECS once).
#[derive(Resource, Debug, Clone, Default)]
pub struct MonitorGeometry {
    /// Shapes, per body, per collider.
    pub shapes: Vec<Vec<rp::SharedShape>>,
    /// Collider poses in the body frame.
    pub pose_body: Vec<Vec<Isometry3<f64>>>,
    /// Bounding radii about the collider origins, m.
    pub radius: Vec<Vec<f64>>,
    /// Per body, per collider: a docking part.
    pub docking: Vec<Vec<bool>>,
    /// Centres of mass in the body frames, m.
    pub com_body_m: Vec<Vector3<f64>>,
    /// Per body: radius about its centre of mass of a sphere holding all its parts, m.
    pub extent_m: Vec<f64>,
    /// Per body: it has a docking part.
    pub has_docking: Vec<bool>,
    /// Per body: radius about its centre of mass of a sphere holding the axis-aligned boxes of
    /// all its parts in any attitude (a part's box lies within √3 of its bounding radius), m.
    pub aabb_extent_m: Vec<f64>,
    /// Per body, per collider: the part as its own rate bound sees it ([`PartPiece`]).
    pub pieces: Vec<Vec<PartPiece>>,
    /// Per body, per collider: for a triangle-mesh part, the support map of its vertices'
    /// convex hull ([`super::mesh::HullSupport`], for [`hull_bracket`]); `None` for the other
    /// parts. May be shorter than `shapes` (read as `None`).
    pub hulls: Vec<Vec<Option<std::sync::Arc<super::mesh::HullSupport>>>>,
    /// The last triangle-by-triangle evaluation of each mesh part pair, advanced conservatively
    /// to later poses by [`pair_eval`] ([`memo`]); starts empty.
    pub memo: memo::PairMemo,
}

/// Symmetry of a part about an axis of its own, for the rotation-aware rate bound.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Revolution {
    /// No symmetry used (boxes, convex hulls — faceted cones included — and meshes).
    None,
    /// An exact solid of revolution about the axis through [`PartPiece::centre_body_m`] with
    /// this unit direction, body frame (parry `Cylinder`, `Cone`, `Capsule`).
    Axis(Vector3<f64>),
    /// Symmetric about every axis through its centre (parry `Ball`).
    Any,
}

/// A convex hull that is a faceted solid of revolution
/// ([`crate::geometry::revolution::faceted_revolution`]: the docking cone's 32-gon frustum), as
/// the per-part rate bound uses it: its solid of revolution about the axis through c lies
/// within `offset_m` of the hull, so the hull's distance to any set is at most `offset_m` above
/// that solid's, whose rate ignores a spin about the axis ([`PairRate`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Faceted {
    /// c, a point on the axis (half way along the hull), body frame (as `pose_body`), m.
    pub centre_body_m: Vector3<f64>,
    /// Radius about c of a sphere holding the hull (and so its solid of revolution), m.
    pub radius_m: f64,
    /// Unit axis, body frame.
    pub axis: Vector3<f64>,
    /// How far the solid of revolution reaches beyond the hull, m.
    pub offset_m: f64,
}

/// A part as the per-part rate bound uses it ([`part_pair_rates`]): a point c on the part's
/// symmetry axis (its centre; the collider origin for parts without symmetry), the radius of a
/// sphere about c holding the part, and its symmetry; for a faceted solid of revolution, that
/// too.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PartPiece {
    /// c, in the body frame (relative to the body origin, as `pose_body`), m.
    pub centre_body_m: Vector3<f64>,
    /// Radius about c of a sphere holding the part, m.
    pub radius_m: f64,
    /// Symmetry about an axis through c.
    pub revolution: Revolution,
    /// The hull as a faceted solid of revolution, if it is one.
    pub faceted: Option<Faceted>,
    /// A box holding the part (its local AABB, as parry computes it, grown for rounding), for
    /// the slab bound ([`SlabBound`]).
    pub boxed: PartBox,
}

/// A box holding a part, body frame: centre, axes (unit columns), half extents, m.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PartBox {
    /// Centre, body frame (as `pose_body`), m.
    pub centre_body_m: Vector3<f64>,
    /// Its axes in the body frame (unit columns).
    pub axes: nalgebra::Matrix3<f64>,
    /// Half extents along them, m.
    pub half_m: Vector3<f64>,
}

impl PartBox {
    /// The local AABB of `shape` placed at `pose_body`, its half extents grown by 1e-6
    /// relative and 1e-9 m (the f32 box and the f64 pose).
    pub fn of(shape: &dyn rp::Shape, pose_body: &Isometry3<f64>) -> Self {
        let b = shape.compute_local_aabb();
        let (lo, hi) = (conv::na(b.mins), conv::na(b.maxs));
        let half = (hi - lo) * 0.5;
        Self {
            centre_body_m: (pose_body * nalgebra::Point3::from((lo + hi) * 0.5)).coords,
            axes: *pose_body.rotation.to_rotation_matrix().matrix(),
            half_m: half.map(|h| h * (1.0 + 1e-6) + 1e-9),
        }
    }

    /// (min, max) over the box of u·(x − o), body frame, m.
    pub fn extent_along(&self, u: &Vector3<f64>, o: &Vector3<f64>) -> (f64, f64) {
        let c = u.dot(&(self.centre_body_m - o));
        let r: f64 = (0..3)
            .map(|k| self.half_m[k] * self.axes.column(k).dot(u).abs())
            .sum();
        (c - r, c + r)
    }
}

impl PartPiece {
    /// The piece of a part with shape `shape` at `pose_body` (bounding radius `bound_radius_m`
    /// about the collider origin). Only parry's exact round shapes get an axis: `Ball`,
    /// `Cylinder` and `Cone` (local y, centred on the origin) and `Capsule` (its segment, c its
    /// midpoint); their radii about c come from the shape itself, inflated by 1e-6 relative
    /// for the f32 parameters. A convex hull that is a faceted solid of revolution gets
    /// [`Faceted`] (from its f32 vertices, as parry holds them).
    pub fn of(shape: &dyn rp::Shape, pose_body: &Isometry3<f64>, bound_radius_m: f64) -> Self {
        let boxed = PartBox::of(shape, pose_body);
        let y = pose_body.rotation * Vector3::y();
        let origin = pose_body.translation.vector;
        let grow = 1.0 + 1e-6;
        if let Some(b) = shape.as_ball() {
            return Self {
                centre_body_m: origin,
                radius_m: f64::from(b.radius) * grow,
                revolution: Revolution::Any,
                faceted: None,
                boxed,
            };
        }
        if let Some(c) = shape.as_cylinder() {
            return Self {
                centre_body_m: origin,
                radius_m: f64::from(c.radius).hypot(f64::from(c.half_height)) * grow,
                revolution: Revolution::Axis(y),
                faceted: None,
                boxed,
            };
        }
        if let Some(c) = shape.as_cone() {
            return Self {
                centre_body_m: origin,
                radius_m: f64::from(c.radius).hypot(f64::from(c.half_height)) * grow,
                revolution: Revolution::Axis(y),
                faceted: None,
                boxed,
            };
        }
        if let Some(c) = shape.as_capsule() {
            let (a, b) = (conv::na(c.segment.a), conv::na(c.segment.b));
            let half = (b - a).norm() * 0.5;
            let mid = pose_body * nalgebra::Point3::from((a + b) * 0.5);
            let revolution = if half > 0.0 {
                Revolution::Axis(pose_body.rotation * ((b - a) / (2.0 * half)))
            } else {
                Revolution::Any
            };
            return Self {
                centre_body_m: mid.coords,
                radius_m: (half + f64::from(c.radius)) * grow,
                revolution,
                faceted: None,
                boxed,
            };
        }
        let faceted = shape.as_convex_polyhedron().and_then(|c| {
            let pts: Vec<Vector3<f64>> = c.points().iter().map(|p| conv::na(*p)).collect();
            let f = crate::geometry::revolution::faceted_revolution(&pts)?;
            Some(Faceted {
                centre_body_m: (pose_body * nalgebra::Point3::from(f.centre_m)).coords,
                radius_m: f.radius_m * grow,
                axis: pose_body.rotation * f.axis,
                offset_m: f.offset_m,
            })
        });
        Self {
            centre_body_m: origin,
            radius_m: bound_radius_m,
            revolution: Revolution::None,
            faceted,
            boxed,
        }
    }
}

/// One body's per-part rate terms over a step ([`part_terms`]).
#[derive(Debug, Clone, Default)]
pub struct PartTerms {
    /// Per part: bound on |ω × (c − x_cm)|, the speed of its centre c from the body's rotation,
    /// m/s.
    pub centre_m_s: Vec<f64>,
    /// Per part: bound on the rotation term |ω′|·r of [`part_pair_rates`], m/s.
    pub turn_m_s: Vec<f64>,
    /// Per part: the centre and rotation terms of its solid of revolution when it is a faceted
    /// one ([`Faceted`], its own centre, radius and axis), else the two above summed, m/s.
    pub revolved_m_s: Vec<f64>,
    /// Per part: [`Faceted::offset_m`], else 0, m.
    pub offset_m: Vec<f64>,
}

/// Body i's per-part rate terms over the step (see [`part_pair_rates`]): with W_k the bounds on
/// its body-frame angular velocity's components along its principal axes e_k over the step
/// ([`StepMotion::omega_axes_bound`]) and Ω its angular-speed bound,
/// |ω × (c − x_cm)| = |ω_b × r| ≤ min(Ω|r|, Σ_k W_k|e_k × r|) with r = c − x_cm in the body
/// frame; and the rotation term ρ·min(Ω, Σ_k W_k|e_k × â|) for a part symmetric about the axis
/// â (|ω_b − (ω_b·â)â| = |ω_b × â|), 0 for a ball, ρ·Ω otherwise (ρ: the radius about c);
/// for a faceted solid of revolution, the same two terms of its solid of revolution.
pub fn part_terms(geo: &MonitorGeometry, motion: &StepMotion, i: usize, out: &mut PartTerms) {
    let om = motion.omega_bound(i);
    let (axes, w) = motion.omega_axes_bound(i);
    let spread = |x: &Vector3<f64>| {
        (0..3)
            .map(|k| w[k] * axes.column(k).cross(x).norm())
            .sum::<f64>()
    };
    out.centre_m_s.clear();
    out.turn_m_s.clear();
    out.revolved_m_s.clear();
    out.offset_m.clear();
    for piece in &geo.pieces[i] {
        let r = piece.centre_body_m - geo.com_body_m[i];
        let centre = (om * r.norm()).min(spread(&r));
        out.centre_m_s.push(centre);
        let rot = match piece.revolution {
            Revolution::None => om,
            Revolution::Axis(a) => om.min(spread(&a)),
            Revolution::Any => 0.0,
        };
        out.turn_m_s.push(rot * piece.radius_m);
        match &piece.faceted {
            Some(f) => {
                let r = f.centre_body_m - geo.com_body_m[i];
                out.revolved_m_s
                    .push((om * r.norm()).min(spread(&r)) + om.min(spread(&f.axis)) * f.radius_m);
                out.offset_m.push(f.offset_m);
            }
            None => {
                out.revolved_m_s.push(centre + rot * piece.radius_m);
                out.offset_m.push(0.0);
            }
        }
    }
}

/// A part pair's bounds over the step ([`part_pair_rates`]): the rate L_pq of its distance,
/// and, for a pair with a faceted solid of revolution, the rate L′_pq of the distance with each
/// such part replaced by its solid of revolution and the sum s_pq of their offsets (otherwise
/// L′ = L and s = 0).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PairRate {
    /// L_pq, m/s.
    pub full_m_s: f64,
    /// L′_pq, m/s.
    pub revolved_m_s: f64,
    /// s_pq, m.
    pub offset_m: f64,
}

impl PairRate {
    /// A lower bound of the pair's distance over an interval of `w` (s) whose ends have the
    /// certified lower bounds `la`, `lb` (m): the larger of (la + lb − L·w)/2 and
    /// (la + lb − L′·w)/2 − s (each capped by min(la, lb), [`interval_lower_bound`]). The
    /// second holds because d′ ≤ d ≤ d′ + s for the distance d′ with the solids of revolution
    /// ([`crate::geometry::revolution`]): d′ ≥ la − s and lb − s at the ends, d′ changes at
    /// most at L′, and d ≥ d′. Without a faceted part, exactly the first.
    pub fn interval_lower(&self, la: f64, lb: f64, w: f64) -> f64 {
        let full = interval_lower_bound(la, lb, self.full_m_s, w);
        if self.offset_m > 0.0 {
            full.max(interval_lower_bound(la, lb, self.revolved_m_s, w) - self.offset_m)
        } else {
            full
        }
    }
}

/// A body's centre of mass (world, m) and attitude.
pub type BodyPose = (Vector3<f64>, UnitQuaternion<f64>);

/// The slab bound of a body pair over a step: the gap between two parts' extents along an
/// axis fixed in the faster-turning body (the spinner), a lower bound of their distance
/// (any unit direction separates two sets by at least that gap), that changes slowly while
/// the spinner turns about that axis — a panel spinning about the chaser's docking axis stays
/// in its slab, though its tip moves at 240 m/s.
///
/// With â the spinner's principal axis of the largest component bound W_k (body frame, world
/// â_w = R_s(t)â), a point x of the spinner has â_w·x = â_w·x_s + â·(r − c_s) (r body-fixed),
/// so its parts' extents along â_w move with â_w·x_s alone, at
/// d/dt(â_w·x_s) = (ω_s × â_w)·x_s + â_w·v_s. A point y of the other body moves at
/// v_o + ω_o × (y − x_o), so its extreme along â_w moves at (ω_s × â_w)·y + â_w·ẏ. A gap
/// (either way round) thus changes at most at
///
/// ```text
/// L_slab = max|v_s − v_o| + |ω_s × â|·(max|x_s − x_o| + R_o) + Ω_o·R_o
/// ```
///
/// with |ω_s × â| ≤ Σ_k W_k|e_k × â| ([`StepMotion::omega_axes_bound`]), R_o the other body's
/// extent and Ω_o its angular-speed bound; and the gap of a pair over an interval is at least
/// (g(a) + g(b) − L_slab·w)/2 ([`interval_lower_bound`]). Each part is taken as its box
/// ([`PartBox`]), which holds it: a smaller gap, still a bound.
#[derive(Debug, Clone)]
pub struct SlabBound {
    /// The spinner is body i (else j).
    spinner_is_i: bool,
    /// â, spinner's body frame.
    axis_b: Vector3<f64>,
    /// L_slab, m/s.
    pub rate_m_s: f64,
    /// Per spinner part: (min, max) of â·(r − c_s) over its box, m.
    spinner_extents: Vec<(f64, f64)>,
}

impl SlabBound {
    /// The slab bound of bodies i and j over the step, with the spinner the body of the
    /// larger angular-speed bound. `None` if neither turns.
    pub fn new(geo: &MonitorGeometry, motion: &StepMotion, i: usize, j: usize) -> Option<Self> {
        let spinner_is_i = motion.omega_bound(i) >= motion.omega_bound(j);
        let (sp, ot) = if spinner_is_i { (i, j) } else { (j, i) };
        if motion.omega_bound(sp) <= 0.0 {
            return None;
        }
        let (axes, w) = motion.omega_axes_bound(sp);
        let k = (0..3).max_by(|a, b| w[*a].total_cmp(&w[*b]))?;
        let axis_b: Vector3<f64> = axes.column(k).into();
        let spread: f64 = (0..3)
            .map(|m| w[m] * axes.column(m).cross(&axis_b).norm())
            .sum();
        let spread = spread.min(motion.omega_bound(sp));
        let r_o = geo.extent_m[ot];
        let rate = (motion.rel_speed_bound(i, j)
            + spread * (motion.separation_bound(i, j) + r_o)
            + motion.omega_bound(ot) * r_o)
            * (1.0 + 1e-9);
        let c = geo.com_body_m[sp];
        let spinner_extents = geo.pieces[sp]
            .iter()
            .map(|p| p.boxed.extent_along(&axis_b, &c))
            .collect();
        rate.is_finite().then_some(Self {
            spinner_is_i,
            axis_b,
            rate_m_s: rate,
            spinner_extents,
        })
    }

    /// Every part pair's slab gap with bodies i and j at the poses `at_i`, `at_j` (centre of
    /// mass, attitude; row-major, p of body i by q of body j), m, into `out`: the larger of the
    /// two ways round, each through the parts' boxes.
    pub fn gaps(
        &self,
        geo: &MonitorGeometry,
        (i, j): (usize, usize),
        at_i: &BodyPose,
        at_j: &BodyPose,
        out: &mut Vec<f64>,
    ) {
        let ot = if self.spinner_is_i { j } else { i };
        let ((xs, qs), (xo, qo)) = if self.spinner_is_i {
            (at_i, at_j)
        } else {
            (at_j, at_i)
        };
        let a_w = qs * self.axis_b;
        let u_o = qo.inverse() * a_w;
        let (xs, xo) = (*xs, *xo);
        let (bs, bo) = (a_w.dot(&xs), a_w.dot(&xo));
        let c_o = geo.com_body_m[ot];
        let other: Vec<(f64, f64)> = geo.pieces[ot]
            .iter()
            .map(|p| p.boxed.extent_along(&u_o, &c_o))
            .collect();
        out.clear();
        let gap = |(s_lo, s_hi): (f64, f64), (o_lo, o_hi): (f64, f64)| {
            ((bs + s_lo) - (bo + o_hi)).max((bo + o_lo) - (bs + s_hi))
        };
        if self.spinner_is_i {
            for se in &self.spinner_extents {
                out.extend(other.iter().map(|oe| gap(*se, *oe)));
            }
        } else {
            for oe in &other {
                out.extend(self.spinner_extents.iter().map(|se| gap(*se, *oe)));
            }
        }
    }
}

/// Per part pair (p of body i, q of body j; row-major, p · n_j + q), a bound on the rate of
/// change of the distance between the two parts over the step, m/s:
///
/// ```text
/// L_pq = min( L_ij ,  max|x′_i − x′_j| + |ω_i × (c_p − x_i)| + |ω_j × (c_q − x_j)|
///                     + |ω′_i|·ρ_p + |ω′_j|·ρ_q )
/// ```
///
/// with L_ij the bodies' bound ([`StepMotion::distance_rate_bound`], a bound on the speed of
/// every point of one body relative to the other, so on every part pair's distance too), c the
/// parts' centres and ρ their radii about them ([`PartPiece`]), and ω′ the part's own rotation:
/// ω for a part without symmetry, ω − (ω·â)â for an exact solid of revolution about the axis
/// â through c, nothing for a ball (terms bounded by [`part_terms`]).
///
/// Why: the distance between two sets that move rigidly, P(t) = φ_t(P₀) and Q(t) = ψ_t(Q₀),
/// changes at most at sup |φ̇_t(x) − ψ̇_t(y)| over x ∈ P₀, y ∈ Q₀ (for t₁ < t₂ take the closest
/// pair at t₁ and follow it: d(t₂) ≤ d(t₁) + ∫ |φ̇ − ψ̇|, and the same from t₂ back). A point of
/// P moves at v(c) + ω × (x − c) with |x − c| ≤ ρ: hence the terms. For a solid of revolution
/// about the axis through c with direction â, the motion that matters is the set's: the
/// component (ω·â)â is a rotation of P about its own axis, which maps P onto itself — on P's
/// boundary its velocity (ω·â)â × (x − c) is tangent to the surface (P's boundary is a surface
/// of revolution about that axis: the rotation's velocity field is tangent to every circle about
/// the axis, which lie in the surface), so it moves no boundary point along its normal. Formally,
/// with A(t) the rotation solving Ȧ = [ω′(t)]×A, A(t₀) = R(t₀): A(t)â₀ and â(t) = R(t)â₀
/// solve the same linear equation ẋ = ω′ × x (ω × â = ω′ × â), so they are equal; P(t) depends
/// only on c(t) and â(t), so P(t) = c(t) + A(t)(P₀ − c₀) — a rigid motion of P whose points
/// move at v(c) + ω′ × (x − c). A ball is symmetric about every axis through its centre: ω′ = 0.
/// A faceted hull (a `ConvexHull` cone) is not a solid of revolution: its facets do move along
/// their normals under a spin about its axis, so it keeps the full |ω|·ρ in L_pq; but its solid
/// of revolution lies within [`Faceted::offset_m`] of it, so [`PairRate`] also carries the
/// rate L′_pq with that solid's terms (its own centre, radius and axis, as for an exact solid
/// of revolution) and the offset: a 32-gon cone spinning at 100 rad/s about its axis moves its
/// facets at up to 12 m/s, its solid of revolution not at all, and the offset is 0.58 mm.
/// L′_pq is not capped by L_ij: the solid of revolution may reach beyond the body's extent.
pub fn part_pair_rates(
    geo: &MonitorGeometry,
    motion: &StepMotion,
    i: usize,
    j: usize,
    terms: &mut [PartTerms; 2],
    out: &mut Vec<PairRate>,
) {
    let body = motion.distance_rate_bound(i, j);
    let rel = motion.rel_speed_bound(i, j);
    let [ti, tj] = terms;
    part_terms(geo, motion, i, ti);
    part_terms(geo, motion, j, tj);
    out.clear();
    let grow = 1.0 + 1e-9;
    for p in 0..ti.centre_m_s.len() {
        let a = ti.centre_m_s[p] + ti.turn_m_s[p];
        for q in 0..tj.centre_m_s.len() {
            let l = (rel + a + tj.centre_m_s[q] + tj.turn_m_s[q]) * grow;
            let offset_m = ti.offset_m[p] + tj.offset_m[q];
            out.push(PairRate {
                full_m_s: l.min(body),
                revolved_m_s: (rel + ti.revolved_m_s[p] + tj.revolved_m_s[q]) * grow,
                offset_m,
            });
        }
    }
}

impl MonitorGeometry {
    /// Reads the parts from the world.
    pub fn from_world(world: &mut World) -> Self {
        let roster = world.resource::<Roster>().clone();
        let mut g = Self::default();
        for (k, be) in roster.bodies.iter().enumerate() {
            let com = world.get::<SimBody>(*be).expect("body").com_body_m;
            let mut shapes = Vec::new();
            let mut poses = Vec::new();
            let mut radii = Vec::new();
            let mut dock = Vec::new();
            for pe in &roster.parts[k] {
                let p = world.get::<Part>(*pe).expect("part");
                shapes.push(p.shape.clone());
                poses.push(p.pose_body);
                radii.push(p.bound_radius_m);
                dock.push(p.role.is_docking());
            }
            let extent = poses
                .iter()
                .zip(&radii)
                .map(|(p, r)| (p.translation.vector - com).norm() + r)
                .fold(0.0, f64::max);
            let aabb_extent = poses
                .iter()
                .zip(&radii)
                .map(|(p, r)| (p.translation.vector - com).norm() + 3f64.sqrt() * r)
                .fold(0.0, f64::max);
            g.pieces.push(
                shapes
                    .iter()
                    .zip(&poses)
                    .zip(&radii)
                    .map(|((sh, p), r)| PartPiece::of(&**sh, p, *r))
                    .collect(),
            );
            g.hulls
                .push(shapes.iter().map(|sh| mesh_hull(&**sh)).collect());
            g.aabb_extent_m.push(aabb_extent);
            g.has_docking.push(dock.iter().any(|d| *d));
            g.shapes.push(shapes);
            g.pose_body.push(poses);
            g.radius.push(radii);
            g.docking.push(dock);
            g.com_body_m.push(com);
            g.extent_m.push(extent);
        }
        g
    }

    /// The hull support map of part a of body i, if it is a triangle mesh.
    pub fn hull(&self, i: usize, a: usize) -> Option<&super::mesh::HullSupport> {
        self.hulls.get(i)?.get(a)?.as_deref()
    }

    /// World poses (and bounding radii) of body i's parts, its centre of mass at `pos` with
    /// attitude `att`.
    pub fn part_poses(
        &self,
        i: usize,
        pos: &Vector3<f64>,
        att: &UnitQuaternion<f64>,
        out: &mut Vec<(Isometry3<f64>, f64)>,
    ) {
        let origin = pos - att * self.com_body_m[i];
        let body = Isometry3::from_parts(origin.into(), *att);
        out.clear();
        out.extend(
            self.pose_body[i]
                .iter()
                .zip(&self.radius[i])
                .map(|(p, r)| (body * p, *r)),
        );
    }
}

/// The closest part pair of two bodies found by [`closest_parts`].
#[derive(Debug, Clone, Copy)]
pub struct PartPairHit {
    /// Distance (value, and a certified lower bound when asked for), m.
    pub d: Bracket,
    /// Part of the first body.
    pub a: usize,
    /// Part of the second body.
    pub b: usize,
}

/// Query counters.
#[derive(Debug, Clone, Copy, Default)]
pub struct QueryCount {
    /// Part pairs evaluated ([`pair_eval`]: parry's exact query, or in its place the memo's
    /// or a mesh hull's certified bracket).
    pub exact: u64,
    /// Part pairs not evaluated: skipped by their bounding-sphere bound, or cleared by a
    /// certified lower bound (a mesh hull's, or the memo's advanced one) at or above the best
    /// distance already found.
    pub pruned: u64,
}

/// Closest part pair of bodies i and j among those `keep` accepts, warm-started from `warm`.
///
/// The warm pair is computed exactly first (temporal coherence); then every other part pair
/// whose bounding-sphere lower bound |c_a − c_b| − r_a − r_b is below the best distance so far,
/// in increasing order of that bound. The result is the exact minimum (to parry's tolerance).
/// With `certify`, the lower bound covers every part pair: the best pair's certified bracket
/// ([`shape_bracket`]), every other evaluated pair's value less its GJK and f32 tolerances (or
/// its certified bracket when that could be lower), and the sphere bound of the pruned pairs
/// (all at or above the best value).
#[allow(clippy::too_many_arguments)]
pub fn closest_parts(
    geo: &MonitorGeometry,
    i: usize,
    pi: &[(Isometry3<f64>, f64)],
    j: usize,
    pj: &[(Isometry3<f64>, f64)],
    keep: &dyn Fn(usize, usize) -> bool,
    warm: Option<(usize, usize)>,
    certify: bool,
    candidates: &mut Vec<(f64, usize, usize)>,
    evaluated: &mut Vec<Evaluated>,
    count: &mut QueryCount,
) -> PartPairHit {
    let mut none = None;
    closest_parts_inner(
        geo, i, pi, j, pj, keep, warm, certify, candidates, evaluated, count, &mut none, None,
    )
}

/// [`closest_parts`] over every part pair of a tracked body pair whose bodies' centres of mass
/// and attitudes are `now`, with the bounding-sphere gaps carried in `prune` from a reference
/// step ([`sphere_prune`]): the same candidates, evaluations, result and counters, without
/// computing the gaps the bodies' motion since cannot have brought under the best distance.
#[allow(clippy::too_many_arguments)]
pub fn closest_parts_pruned(
    geo: &MonitorGeometry,
    i: usize,
    pi: &LazyPoses,
    j: usize,
    pj: &LazyPoses,
    warm: Option<(usize, usize)>,
    candidates: &mut Vec<(f64, usize, usize)>,
    evaluated: &mut Vec<Evaluated>,
    count: &mut QueryCount,
    prune: (&mut SpherePrune, [BodyPose; 2]),
) -> PartPairHit {
    closest_parts_inner(
        geo,
        i,
        pi,
        j,
        pj,
        &|_, _| true,
        warm,
        true,
        candidates,
        evaluated,
        count,
        &mut None,
        Some(prune),
    )
}

/// [`closest_parts`], and with `lows` a certified lower bound of every part pair's distance
/// (row-major, p · n_j + q; every pair, whatever `keep` says): the best pair's certified
/// bracket, an evaluated pair's value less its GJK and f32 tolerances, a pruned pair's
/// bounding-sphere gap |c_p − c_q| − r_p − r_q — each raised to the bodies' certified lower
/// bound (no part pair is closer than the bodies). Every part pair is kept; the distance is
/// certified. Used with [`part_pair_rates`].
#[allow(clippy::too_many_arguments)]
pub fn closest_parts_lows(
    geo: &MonitorGeometry,
    i: usize,
    pi: &[(Isometry3<f64>, f64)],
    j: usize,
    pj: &[(Isometry3<f64>, f64)],
    warm: Option<(usize, usize)>,
    candidates: &mut Vec<(f64, usize, usize)>,
    evaluated: &mut Vec<Evaluated>,
    count: &mut QueryCount,
    l: &mut Vec<f64>,
) -> PartPairHit {
    let nj = pj.len();
    let hit = closest_parts_inner(
        geo,
        i,
        pi,
        j,
        pj,
        &|_, _| true,
        warm,
        true,
        candidates,
        evaluated,
        count,
        &mut Some(&mut *l),
        None,
    );
    {
        let scale = |a: usize, b: usize| {
            (pi[a].0.translation.vector - pj[b].0.translation.vector).norm() + pi[a].1 + pj[b].1
        };
        for &(d, known, a, b) in evaluated.iter() {
            let loose = d * (1.0 - GJK_REL_TOL) - F32_REL_TOL * scale(a, b);
            let k = a * nj + b;
            l[k] = l[k].max(loose);
            if !known.is_nan() {
                l[k] = l[k].max(known);
            }
        }
        if hit.d.value.is_finite() {
            let k = hit.a * nj + hit.b;
            l[k] = l[k].max(hit.d.lower);
        }
        for x in l.iter_mut() {
            *x = x.max(hit.d.lower);
        }
    }
    hit
}

/// A part pair evaluated by [`pair_eval`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum PairEval {
    /// Certified to be at least this far apart (at or above the caller's `clear_at`), m.
    Clear(f64),
    /// The distance (parry's value, or a mesh pair's achieved upper bound, m) and, for a pair
    /// with a mesh part, its certified lower bound (NaN for the other pairs: [`shape_bracket`]
    /// gives theirs when it is needed), m.
    Value(f64, f64),
}

/// Widest bracket, relative to its value, that [`pair_eval`] answers from a pair of support
/// maps' kept evaluation (ours: a tenth of the closest approach's tolerance,
/// [`min_distance_tolerance_m`], so a carried value stays well inside what a fresh query reports).
pub const MEMO_REL_WIDTH: f64 = 1e-4;

/// The distance of part a (world pose and bounding radius `pa`) of body i and part b of body j.
///
/// A pair of parts with support maps is parry's exact query with its witnesses and the certified
/// gap along them ([`memo::convex_exact`], as [`shape_bracket`]; a shape parry answers only by
/// distance, [`shape_distance`], with a NaN lower bound). A pair with a triangle-mesh part is first bracketed by its convex hull ([`hull_bracket`]): a
/// certified lower bound at or above `clear_at` prunes it ([`PairEval::Clear`]); a bracket as
/// narrow as parry's own GJK distance — lower ≥ upper·(1 − [`GJK_REL_TOL`]) − the f32 rounding
/// [`F32_REL_TOL`]·(|c_a − c_b| + r_a + r_b), the same bound every caller derives from an exact
/// value — is the answer (value: the upper bound, achieved by a point of one part and its
/// projection on the other's mesh); otherwise (a concavity, a part inside the other's hull) the
/// exact triangle-mesh query ([`memo::mesh_exact`]), its lower bound the largest of its
/// triangles' certified gaps, its value less those tolerances and the hull's. Either way the
/// value is within those tolerances of the true mesh distance.
///
/// Before all that, the pair's last exact query ([`MonitorGeometry::memo`]) is advanced to this
/// pose ([`memo::ExactEval::advance`]: its lower bound less how far any point of part b can have
/// moved in part a's frame, and the distance of its two witness points carried along): a lower
/// bound at or above `clear_at` clears the pair, and a bracket as narrow as above is the answer
/// (value: the carried witnesses' distance). Docking collar (or the primitive cone and slot),
/// chaser latched in the slot: one exact query, then none while the stack stays rigid; in free
/// flight a pair far from the closest is cleared by its advanced bound until the motion since
/// its evaluation eats the margin. A pair's value thus depends on the pose of its last exact
/// query as well as on this one (within the tolerances above; the same in every run of the
/// same scene).
#[allow(clippy::too_many_arguments)]
pub fn pair_eval(
    geo: &MonitorGeometry,
    i: usize,
    a: usize,
    pa: &(Isometry3<f64>, f64),
    j: usize,
    b: usize,
    pb: &(Isometry3<f64>, f64),
    clear_at: f64,
) -> PairEval {
    let (sa, sb) = (&*geo.shapes[i][a], &*geo.shapes[j][b]);
    let (ha, hb) = (geo.hull(i, a), geo.hull(j, b));
    let eps =
        F32_REL_TOL * ((pa.0.translation.vector - pb.0.translation.vector).norm() + pa.1 + pb.1);
    let settled = |lower: f64, upper: f64| lower >= upper * (1.0 - GJK_REL_TOL) - eps;
    // The pair's last exact evaluation, advanced to this pose (a certified bracket, `memo`).
    let key = (i, a, j, b);
    // (Read in place: the kept evaluation is not copied out of the memo.)
    let memo_answer = geo.memo.with(key, |e| {
        // The radii's bound first (cheap), then the turn's axis (tighter for a part rolling
        // about its own axis) only if that does not settle the pair.
        //
        // A mesh pair is cleared by the advanced lower bound, or answered by the bracket when it
        // is as narrow as an exact query's tolerance. A pair of support maps is answered only
        // while its bracket is no wider than twice its fresh evaluation's and than
        // [`MEMO_REL_WIDTH`] of its value (plus the f32 rounding), and farther apart than
        // [`TOUCH_DISTANCE_M`] (touching is parry's to say), and then also when it would
        // clear `clear_at` (the value costs nothing more): its value and lower bound stay as
        // close to the truth as a fresh query's, for the callers' interval bounds and reported
        // distances. That holds in a rigid latched stack. Otherwise (in free flight) a pair of
        // support maps is cleared, as a mesh pair is, when its advanced lower bound is at or
        // above `clear_at` (it cannot be the closest, and the caller keeps only that bound: a
        // tumbling target's far parts, `free_drift` 1.5× faster, outputs byte-identical), and
        // queried again when it is not.
        let convex = ha.is_none() && hb.is_none();
        let width_ok = (e.value_m - e.lower_m).min(MEMO_REL_WIDTH * e.value_m) + eps;
        let decide = |(lower, upper): (f64, f64)| {
            if convex {
                if upper - lower <= width_ok && lower > TOUCH_DISTANCE_M {
                    Some(PairEval::Value(upper, lower))
                } else if lower >= clear_at {
                    Some(PairEval::Clear(lower))
                } else {
                    None
                }
            } else if lower >= clear_at {
                Some(PairEval::Clear(lower))
            } else if settled(lower, upper) {
                Some(PairEval::Value(upper, lower))
            } else {
                None
            }
        };
        let rel = pa.0.inv_mul(&pb.0);
        let rel_inv = rel.inverse();
        let quick = e.advance_quick((&rel, &rel_inv), pa.1, pb.1);
        if let Some(answer) = decide(quick) {
            return Some(answer);
        }
        // The axis bound only where it could decide: every decision asks for a lower bound at
        // least some level, and no turn at all would give the highest it can
        // (`advance_unturned`); where even that decides nothing, the axis bound would not.
        if decide(e.advance_unturned((&rel, &rel_inv), pa.1, pb.1)).is_some() {
            return decide(e.advance_parts((&rel, &rel_inv), (sa, pa.1), (sb, pb.1)));
        }
        None
    });
    if let Some(answer) = memo_answer.flatten() {
        return answer;
    }
    if ha.is_none() && hb.is_none() {
        // Two parts with support maps: parry's query with its witnesses and the certified gap
        // along them, kept for later poses.
        // (Its lower bound is the gap alone, as `shape_bracket`'s: not raised to the value less
        // GJK's tolerance, which holds only when GJK stopped on its tolerance.)
        let Some(e) = memo::convex_exact(&pa.0, (sa, pa.1), &pb.0, (sb, pb.1)) else {
            return pair_eval_shapes(pa, (sa, ha), pb, (sb, hb), clear_at);
        };
        if e.value_m > 0.0 {
            geo.memo.put(key, e);
        }
        return PairEval::Value(e.value_m, e.lower_m);
    }
    let hull_lower = match hull_bracket(&pa.0, (sa, ha, pa.1), &pb.0, (sb, hb, pb.1), clear_at) {
        HullEval::Clear(l) => return PairEval::Clear(l),
        HullEval::Bracket { lower, upper } if settled(lower, upper) => {
            return PairEval::Value(upper, lower);
        }
        HullEval::Bracket { lower, .. } => lower,
        HullEval::None => 0.0,
    };
    // Triangle by triangle, with a tight lower bound and witnesses kept for later poses.
    // Its lower bound: the triangles' smallest gap, or the value less GJK's and f32's
    // tolerances (as every exact value's), or the hull's, whichever is largest.
    if let Some(mut e) = memo::mesh_exact(&pa.0, (sa, pa.1), &pb.0, (sb, pb.1)) {
        let loose = e.value_m * (1.0 - GJK_REL_TOL) - eps;
        e.lower_m = e.lower_m.max(loose).max(hull_lower).min(e.value_m).max(0.0);
        if e.value_m > 0.0 {
            geo.memo.put(key, e);
        }
        return PairEval::Value(e.value_m, e.lower_m);
    }
    let d = shape_distance(&pa.0, sa, &pb.0, sb);
    let loose = d * (1.0 - GJK_REL_TOL) - eps;
    PairEval::Value(d, loose.max(hull_lower).min(d).max(0.0))
}

/// [`pair_eval`] for two shapes given directly (world pose and bounding radius, the shape, its
/// hull support map when it is a triangle mesh: [`mesh_hull`]); the same evaluation, for
/// callers whose shapes are not in [`MonitorGeometry`] (the plume keep-off's pyramid,
/// `super::plume`).
pub fn pair_eval_shapes(
    pa: &(Isometry3<f64>, f64),
    (sa, ha): (&dyn rp::Shape, Option<&super::mesh::HullSupport>),
    pb: &(Isometry3<f64>, f64),
    (sb, hb): (&dyn rp::Shape, Option<&super::mesh::HullSupport>),
    clear_at: f64,
) -> PairEval {
    if ha.is_none() && hb.is_none() {
        return PairEval::Value(shape_distance(&pa.0, sa, &pb.0, sb), f64::NAN);
    }
    let scale = (pa.0.translation.vector - pb.0.translation.vector).norm() + pa.1 + pb.1;
    let eps = F32_REL_TOL * scale;
    let hull_lower = match hull_bracket(&pa.0, (sa, ha, pa.1), &pb.0, (sb, hb, pb.1), clear_at) {
        HullEval::Clear(l) => return PairEval::Clear(l),
        HullEval::Bracket { lower, upper } if lower >= upper * (1.0 - GJK_REL_TOL) - eps => {
            return PairEval::Value(upper, lower);
        }
        HullEval::Bracket { lower, .. } => lower,
        HullEval::None => 0.0,
    };
    let d = shape_distance(&pa.0, sa, &pb.0, sb);
    let loose = d * (1.0 - GJK_REL_TOL) - eps;
    PairEval::Value(d, loose.max(hull_lower).min(d).max(0.0))
}

/// The certified bracket of part a of body i and part b of body j at world poses (with bounding
/// radii) `pa`, `pb`: [`shape_bracket`] for parts with support maps, [`pair_eval`] for a pair
/// with a mesh part.
#[allow(clippy::too_many_arguments)]
pub fn part_bracket(
    geo: &MonitorGeometry,
    i: usize,
    a: usize,
    pa: &(Isometry3<f64>, f64),
    j: usize,
    b: usize,
    pb: &(Isometry3<f64>, f64),
) -> Bracket {
    let (sa, sb) = (&*geo.shapes[i][a], &*geo.shapes[j][b]);
    if geo.hull(i, a).is_none() && geo.hull(j, b).is_none() {
        return shape_bracket(&pa.0, sa, pa.1, &pb.0, sb, pb.1);
    }
    match pair_eval(geo, i, a, pa, j, b, pb, f64::INFINITY) {
        PairEval::Value(value, lower) => Bracket {
            value,
            lower: lower.min(value),
        },
        // (Not with an infinite `clear_at`.)
        PairEval::Clear(lower) => Bracket {
            value: lower,
            lower,
        },
    }
}

/// An evaluated part pair: (value, certified lower bound or NaN — see [`PairEval::Value`] —,
/// part a, part b).
pub type Evaluated = (f64, f64, usize, usize);

/// [`closest_parts`], and with `lows` (when given) every part pair's lower bound, row-major
/// (part a of body i by part b of body j), m: its bounding-sphere gap ([`sphere_lows`]), raised
/// to the certified bound of a pair that a hull cleared. The certified lower bound of the
/// closest pair, with `certify`, is [`certified_lower`]'s.
#[allow(clippy::too_many_arguments)]
fn closest_parts_inner<P: PoseSource + ?Sized>(
    geo: &MonitorGeometry,
    i: usize,
    pi: &P,
    j: usize,
    pj: &P,
    keep: &dyn Fn(usize, usize) -> bool,
    warm: Option<(usize, usize)>,
    certify: bool,
    candidates: &mut Vec<(f64, usize, usize)>,
    evaluated: &mut Vec<Evaluated>,
    count: &mut QueryCount,
    lows: &mut Option<&mut Vec<f64>>,
    mut prune: Option<(&mut SpherePrune, [BodyPose; 2])>,
) -> PartPairHit {
    let (ni, nj) = (pi.count(), pj.count());
    if let Some(l) = lows.as_deref_mut() {
        sphere_lows(pi, pj, l);
    }
    // A pair a hull cleared: its certified bound joins the lows.
    let cleared = |a: usize, b: usize, l: f64, lows: &mut Option<&mut Vec<f64>>| {
        if let Some(ls) = lows.as_deref_mut() {
            ls[a * nj + b] = ls[a * nj + b].max(l);
        }
    };
    let query = |a: usize, b: usize, clear_at: f64| {
        pair_eval(geo, i, a, pi.at(a), j, b, pj.at(b), clear_at)
    };
    let warm = warm.filter(|(a, b)| keep(*a, *b));
    evaluated.clear();
    let (mut best, mut ba, mut bb) = (f64::INFINITY, 0, 0);
    if let Some((a, b)) = warm {
        count.exact += 1;
        match query(a, b, f64::INFINITY) {
            PairEval::Value(d, l) => {
                evaluated.push((d, l, a, b));
                (best, ba, bb) = (d, a, b);
            }
            PairEval::Clear(l) => cleared(a, b, l, lows),
        }
    }
    candidates.clear();
    // The bounding-sphere gap of part pair (a, b), m.
    let gap = |a: usize, b: usize| {
        let (pa, pb) = (pi.at(a), pj.at(b));
        (pa.0.translation.vector - pb.0.translation.vector).norm() - pa.1 - pb.1
    };
    // The gaps carried from the reference step, where their bound holds (`sphere_prune`).
    let walked = prune.as_mut().is_some_and(|(p, now)| {
        p.walk(
            now,
            (ni, nj),
            best,
            warm,
            gap,
            candidates,
            &mut count.pruned,
        )
    });
    if !walked {
        // Every gap, recorded for a new reference where one is wanted.
        let mut record = prune
            .as_mut()
            .filter(|(p, _)| p.wants_reference())
            .map(|(p, _)| p.gaps_buffer());
        for a in 0..ni {
            for b in 0..nj {
                if !keep(a, b) {
                    continue;
                }
                if warm == Some((a, b)) {
                    if let Some(r) = record.as_deref_mut() {
                        r.push((gap(a, b), a, b));
                    }
                    continue;
                }
                let lb = gap(a, b);
                if let Some(r) = record.as_deref_mut() {
                    r.push((lb, a, b));
                }
                if lb < best {
                    candidates.push((lb, a, b));
                } else {
                    count.pruned += 1;
                }
            }
        }
        if record.is_some()
            && let Some((p, now)) = prune.as_mut()
        {
            p.retake(now, pi, pj);
        }
    }
    // Nearest bounding-sphere gap first, ties by part indices: a min-heap pops them in the
    // order a full sort would give, and the search usually stops after a few (every later gap
    // is at least the best distance found), so most candidates are never ordered.
    let mut heap = std::collections::BinaryHeap::from(
        std::mem::take(candidates)
            .into_iter()
            .map(NearestFirst)
            .collect::<Vec<_>>(),
    );
    while let Some(NearestFirst((lb, a, b))) = heap.pop() {
        // No distance is below zero: once a touching pair is found, the rest cannot win (and
        // a later zero would not replace it either).
        if lb >= best || best <= 0.0 {
            count.pruned += heap.len() as u64 + 1;
            break;
        }
        count.exact += 1;
        match query(a, b, best) {
            PairEval::Value(d, l) => {
                evaluated.push((d, l, a, b));
                if d < best {
                    (best, ba, bb) = (d, a, b);
                }
            }
            PairEval::Clear(l) => {
                count.pruned += 1;
                cleared(a, b, l, lows);
            }
        }
    }
    // The scratch vector back to the caller, its allocation kept.
    *candidates = heap.into_vec().into_iter().map(|c| c.0).collect();
    candidates.clear();
    if !certify || !best.is_finite() || best <= 0.0 {
        // (At zero the certified lower bound is zero: 0 ≤ lower ≤ best.)
        return PartPairHit {
            d: Bracket::exact(best),
            a: ba,
            b: bb,
        };
    }
    let lower = certified_lower(geo, (i, pi), (j, pj), evaluated, (ba, bb), count);
    PartPairHit {
        d: Bracket {
            value: best,
            lower: lower.min(best),
        },
        a: ba,
        b: bb,
    }
}

/// A candidate part pair (bounding-sphere gap, m; part a; part b) ordered so that a max-heap
/// pops the smallest gap first, ties by (a, b): the order of a sort by `total_cmp` then (a, b).
#[derive(Debug, Clone, Copy)]
struct NearestFirst((f64, usize, usize));

impl Ord for NearestFirst {
    fn cmp(&self, o: &Self) -> std::cmp::Ordering {
        let (x, y) = (self.0, o.0);
        y.0.total_cmp(&x.0).then((y.1, y.2).cmp(&(x.1, x.2)))
    }
}

impl PartialOrd for NearestFirst {
    fn partial_cmp(&self, o: &Self) -> Option<std::cmp::Ordering> {
        Some(self.cmp(o))
    }
}

impl PartialEq for NearestFirst {
    fn eq(&self, o: &Self) -> bool {
        self.cmp(o) == std::cmp::Ordering::Equal
    }
}

impl Eq for NearestFirst {}

/// Every part pair's bounding-sphere gap |c_a − c_b| − r_a − r_b, m, into `l` (cleared first),
/// row-major: part a of `pi` by part b of `pj` (world poses and bounding radii, m).
fn sphere_lows<P: PoseSource + ?Sized>(pi: &P, pj: &P, l: &mut Vec<f64>) {
    l.clear();
    for a in 0..pi.count() {
        let (pa, ra) = pi.at(a);
        for b in 0..pj.count() {
            let (pb, rb) = pj.at(b);
            l.push((pa.translation.vector - pb.translation.vector).norm() - ra - rb);
        }
    }
}

/// The certified lower bound, m, of the distance of bodies i and j (their parts' world poses
/// and bounding radii `pi`, `pj`) whose closest evaluated part pair is (`ba`, `bb`): that
/// pair's certified bound, lowered to any other evaluated pair's whose value less its GJK and
/// f32 tolerances could be below it (see [`closest_parts`]). A pair's certified bound is the
/// one its evaluation gave (mesh pairs), else its [`shape_bracket`]'s lower bound (one more
/// exact query in `count`).
fn certified_lower<P: PoseSource + ?Sized>(
    geo: &MonitorGeometry,
    (i, pi): (usize, &P),
    (j, pj): (usize, &P),
    evaluated: &[Evaluated],
    (ba, bb): (usize, usize),
    count: &mut QueryCount,
) -> f64 {
    let (si, sj) = (&geo.shapes[i], &geo.shapes[j]);
    // A pair's certified lower bound: the one its evaluation gave (mesh pairs), else its
    // certified bracket.
    let mut certified = |e: &Evaluated| {
        if e.1.is_nan() {
            count.exact += 1;
            let (pa, pb) = (pi.at(e.2), pj.at(e.3));
            shape_bracket(&pa.0, &*si[e.2], pa.1, &pb.0, &*sj[e.3], pb.1).lower
        } else {
            e.1
        }
    };
    let mut lower = evaluated
        .iter()
        .find(|e| (e.2, e.3) == (ba, bb))
        .map_or(0.0, &mut certified);
    for e in evaluated.iter() {
        let (d, _, a, b) = *e;
        if (a, b) == (ba, bb) {
            continue;
        }
        let (pa, pb) = (pi.at(a), pj.at(b));
        let scale = (pa.0.translation.vector - pb.0.translation.vector).norm() + pa.1 + pb.1;
        let loose = d * (1.0 - GJK_REL_TOL) - F32_REL_TOL * scale;
        if loose < lower {
            lower = lower.min(certified(e));
        }
    }
    lower
}

/// World poses and bounding radii of one body's parts.
pub type PartPoses = Vec<(Isometry3<f64>, f64)>;

/// A body's part poses (world pose and bounding radius of each part), as the closest-parts
/// search reads them: all computed ([`PartPoses`]), or computed on first use ([`LazyPoses`]).
pub trait PoseSource {
    /// Parts.
    fn count(&self) -> usize;
    /// Part `a`'s world pose and bounding radius.
    fn at(&self, a: usize) -> &(Isometry3<f64>, f64);
}

impl PoseSource for [(Isometry3<f64>, f64)] {
    fn count(&self) -> usize {
        self.len()
    }
    fn at(&self, a: usize) -> &(Isometry3<f64>, f64) {
        &self[a]
    }
}

/// A body's part poses for one step, each set when first read ([`LazyPoses`]).
pub type LazyCells = Vec<std::cell::OnceCell<(Isometry3<f64>, f64)>>;

/// One body's part poses for one step, each computed when first read, as
/// [`MonitorGeometry::part_poses`] computes it (the same expression: bit for bit the same
/// pose). The closest-parts search of a tracked pair reads a handful of a winged body's parts
/// a step once the bounding-sphere gaps are carried ([`sphere_prune`]).
pub struct LazyPoses<'a> {
    /// Body frame's world pose (its origin, not its centre of mass).
    body: Isometry3<f64>,
    /// Parts' poses in the body frame.
    pose_body: &'a [Isometry3<f64>],
    /// Parts' bounding radii, m.
    radius: &'a [f64],
    /// The poses computed so far this step.
    cells: &'a [std::cell::OnceCell<(Isometry3<f64>, f64)>],
}

impl<'a> LazyPoses<'a> {
    /// Body `b` of `geo` with its centre of mass at `pos` and attitude `att`, its poses kept in
    /// `cells` (emptied by the caller at each new step; one per part).
    pub fn new(
        geo: &'a MonitorGeometry,
        b: usize,
        (pos, att): (&Vector3<f64>, &UnitQuaternion<f64>),
        cells: &'a [std::cell::OnceCell<(Isometry3<f64>, f64)>],
    ) -> Self {
        let origin = pos - att * geo.com_body_m[b];
        Self {
            body: Isometry3::from_parts(origin.into(), *att),
            pose_body: &geo.pose_body[b],
            radius: &geo.radius[b],
            cells,
        }
    }
}

impl PoseSource for LazyPoses<'_> {
    fn count(&self) -> usize {
        self.cells.len()
    }
    fn at(&self, a: usize) -> &(Isometry3<f64>, f64) {
        self.cells[a].get_or_init(|| (self.body * self.pose_body[a], self.radius[a]))
    }
}

/// (body, part) of each side of a contact pair.
type ContactSides = ((usize, usize), (usize, usize));

/// Buffers the monitor reuses from step to step.
#[derive(Default)]
pub struct DistanceScratch {
    /// World pose and bounding radius of every part, per body, and the step they are for.
    poses: Vec<(u64, PartPoses)>,
    /// Part poses at an interior time, two bodies.
    tmp: [Vec<(Isometry3<f64>, f64)>; 2],
    /// (lower bound, part a, part b) for the current body pair.
    candidates: Vec<(f64, usize, usize)>,
    /// Part pairs evaluated for the current body pair.
    evaluated: Vec<Evaluated>,
    /// Per-part rate terms of two bodies ([`part_terms`]).
    terms: [PartTerms; 2],
    /// Per part pair rate bounds of the current body pair ([`part_pair_rates`]).
    rates: Vec<PairRate>,
    /// The tracked pairs' carried bounding-sphere gaps, by pair slot ([`sphere_prune`]).
    prune: Vec<SpherePrune>,
    /// The tracked pairs of the step (kept for its allocation).
    pairs: Vec<(usize, usize)>,
    /// Per body: its part poses computed on first use this step ([`LazyPoses`]), and the step
    /// they are for.
    lazy: Vec<(u64, LazyCells)>,
}

/// A sample of the per-part search ([`search_parts`]): the value (with its certified lower
/// bound), every part pair's certified lower bound, and the closest part pair.
struct PartSample {
    d: Bracket,
    lows: Vec<f64>,
    /// Every part pair's slab gap ([`SlabBound::gaps`]; empty without a slab bound).
    slabs: Vec<f64>,
    parts: (usize, usize),
}

/// The rate bound of the per-part search is worth its bookkeeping when the bodies' bound is at
/// least this many times the bound of the part pair closest at the step's end (a body turning
/// fast about an axis near that pair); else the bodies' bound is used alone.
pub const PER_PART_MIN_GAIN: f64 = 2.0;

/// The per part pair rate bounds of bodies i and j over the step into `sc`
/// ([`part_pair_rates`]); returns the bound of part pair (a, b) and the bodies' bound.
pub fn pair_rate_gain(
    geo: &MonitorGeometry,
    motion: &StepMotion,
    i: usize,
    j: usize,
    (a, b): (usize, usize),
    sc: &mut DistanceScratch,
) -> (f64, f64) {
    part_pair_rates(geo, motion, i, j, &mut sc.terms, &mut sc.rates);
    let nj = geo.shapes[j].len();
    let body = motion.distance_rate_bound(i, j);
    (
        sc.rates.get(a * nj + b).map(|r| r.full_m_s).unwrap_or(body),
        body,
    )
}

/// Every part's pose (and bounding radius) of bodies i and j at τ into the step, on the bodies'
/// paths, into `tmp`.
fn part_poses_at<'a>(
    geo: &MonitorGeometry,
    motion: &StepMotion,
    i: usize,
    j: usize,
    tau: f64,
    tmp: &'a mut [Vec<(Isometry3<f64>, f64)>; 2],
) -> &'a mut [Vec<(Isometry3<f64>, f64)>; 2] {
    let (xi, qi) = motion.paths[i].pose_at(tau);
    let (xj, qj) = motion.paths[j].pose_at(tau);
    let [ti, tj] = &mut *tmp;
    geo.part_poses(i, &xi, &qi, ti);
    geo.part_poses(j, &xj, &qj, tj);
    tmp
}

/// Full-geometry distance of bodies i < j with their centres of mass and attitudes at `poses`,
/// with every part pair's certified lower bound ([`closest_parts_lows`]); the parts' world
/// poses are left in `sc.tmp`.
fn pair_lows_posed(
    geo: &MonitorGeometry,
    (i, j): (usize, usize),
    (pose_i, pose_j): (&BodyPose, &BodyPose),
    warm: Option<(usize, usize)>,
    sc: &mut DistanceScratch,
    count: &mut QueryCount,
    lows: &mut Vec<f64>,
) -> PartPairHit {
    let [ti, tj] = &mut sc.tmp;
    geo.part_poses(i, &pose_i.0, &pose_i.1, ti);
    geo.part_poses(j, &pose_j.0, &pose_j.1, tj);
    closest_parts_lows(
        geo,
        i,
        ti,
        j,
        tj,
        warm,
        &mut sc.candidates,
        &mut sc.evaluated,
        count,
        lows,
    )
}

/// The minimum over the step of f = (distance of bodies i < j) − `offset` by branch and bound
/// with per-part-pair bounds ([`crate::geometry::bounds::minimize_by`]): a sub-interval's bound
/// is min over part pairs pq of (l_pq(a) + l_pq(b) − L_pq·w)/2 − offset, with l_pq the pairs'
/// certified lower bounds at its ends ([`closest_parts_lows`]) and L_pq their rate bounds
/// ([`part_pair_rates`], which `sc` must hold for this pair: [`pair_rate_gain`]) — for a pair
/// with a faceted solid of revolution, the larger of that and its bound through the solid of
/// revolution ([`PairRate::interval_lower`]), and than the pair's slab bound
/// ([`SlabBound`]). `f0`, `f1`:
/// f at the step's ends (the samples' brackets, less the offset); the part pairs' bounds there
/// are evaluated again on the paths (τ = 0 and dt). Returns the search and the closest part
/// pair where its minimum was found, if that was inside the step.
#[allow(clippy::too_many_arguments)]
pub fn search_parts(
    geo: &MonitorGeometry,
    motion: &StepMotion,
    i: usize,
    j: usize,
    (f0, f1): (Bracket, Bracket),
    offset: f64,
    threshold: impl Fn(f64) -> f64,
    max_evals: u32,
    warm: Option<(usize, usize)>,
    sc: &mut DistanceScratch,
    count: &mut QueryCount,
) -> (crate::geometry::bounds::MinSearch, Option<(usize, usize)>) {
    let dt = motion.dt_s;
    let rates = std::mem::take(&mut sc.rates);
    // The bound each pair's lows need for the whole step to clear the threshold at once
    // (distance terms): a pair whose bounding-sphere gap falls short of it is evaluated
    // ([`tighten_lows`]) rather than bisected on that loose gap.
    let thr_root = threshold(f0.value.min(f1.value)) + offset;
    let need: Vec<f64> = rates
        .iter()
        .map(|l| {
            (thr_root + 0.5 * l.full_m_s * dt)
                .min(thr_root + l.offset_m + 0.5 * l.revolved_m_s * dt)
        })
        .collect();
    let slab = SlabBound::new(geo, motion, i, j);
    let slab_need = slab
        .as_ref()
        .map_or(f64::INFINITY, |b| thr_root + 0.5 * b.rate_m_s * dt);
    let mut at = warm;
    let mut sample = |tau: f64, given: Option<Bracket>, at: &mut Option<(usize, usize)>| {
        let mut lows = Vec::new();
        let (pose_i, pose_j) = (motion.paths[i].pose_at(tau), motion.paths[j].pose_at(tau));
        let mut slabs = Vec::new();
        if let Some(b) = &slab {
            b.gaps(geo, (i, j), &pose_i, &pose_j, &mut slabs);
        }
        let skip = |k: usize| slabs.get(k).is_some_and(|g| *g >= slab_need);
        if let Some(g) = given {
            // A step end, whose bracket the caller has: no closest pair sought again. Each
            // pair's low is its bounding-sphere gap, its memo's certified bound (the caller's
            // sample has just refreshed it), and the bodies' certified bound, tightened where
            // that falls short of the whole step's need.
            let [ti, tj] = &mut sc.tmp;
            geo.part_poses(i, &pose_i.0, &pose_i.1, ti);
            geo.part_poses(j, &pose_j.0, &pose_j.1, tj);
            sphere_lows(&ti[..], &tj[..], &mut lows);
            memo_lows(geo, (i, j), &sc.tmp, &mut lows);
            let floor = g.lower + offset;
            for l in lows.iter_mut() {
                *l = l.max(floor);
            }
            tighten_lows(geo, (i, j), &sc.tmp, &[], &need, &skip, &mut lows, count);
            return PartSample {
                d: g,
                lows,
                slabs,
                parts: at.unwrap_or((0, 0)),
            };
        }
        let h = pair_lows_posed(geo, (i, j), (&pose_i, &pose_j), *at, sc, count, &mut lows);
        tighten_lows(
            geo,
            (i, j),
            &sc.tmp,
            &sc.evaluated,
            &need,
            &skip,
            &mut lows,
            count,
        );
        *at = Some((h.a, h.b));
        let d = Bracket {
            value: h.d.value - offset,
            lower: h.d.lower - offset,
        };
        PartSample {
            d: given.unwrap_or(d),
            lows,
            slabs,
            parts: (h.a, h.b),
        }
    };
    let s0 = sample(0.0, Some(f0), &mut at);
    let s1 = sample(dt, Some(f1), &mut at);
    let mut found: Vec<(f64, (usize, usize))> = Vec::new();
    let r = crate::geometry::bounds::minimize_by(
        dt,
        s0,
        s1,
        |s: &PartSample| s.d.value,
        |a: &PartSample, b: &PartSample, w: f64| {
            // Never above the ends' own certified bounds (a pair's bound is at least theirs).
            (parts_bound(a, b, w, &rates, slab.as_ref()) - offset)
                .min(a.d.lower)
                .min(b.d.lower)
        },
        threshold,
        max_evals,
        dt * 1e-9,
        |tau| {
            let s = sample(tau, None, &mut at);
            found.push((tau, s.parts));
            s
        },
    );
    sc.rates = rates;
    let parts = found.iter().find(|p| p.0 == r.t).map(|p| p.1);
    (r, parts)
}

/// Over a sub-interval of `w` (s) whose ends are sampled by `a` and `b`: min over part pairs
/// of the larger of the pair's bound ([`PairRate::interval_lower`]) and its slab bound, m.
fn parts_bound(
    a: &PartSample,
    b: &PartSample,
    w: f64,
    rates: &[PairRate],
    slab: Option<&SlabBound>,
) -> f64 {
    match slab {
        Some(sb) => a
            .lows
            .iter()
            .zip(&b.lows)
            .zip(rates)
            .zip(a.slabs.iter().zip(&b.slabs))
            .map(|(((la, lb), l), (ga, gb))| {
                l.interval_lower(*la, *lb, w)
                    .max(interval_lower_bound(*ga, *gb, sb.rate_m_s, w))
            })
            .fold(f64::INFINITY, f64::min),
        None => a
            .lows
            .iter()
            .zip(&b.lows)
            .zip(rates)
            .map(|((la, lb), l)| l.interval_lower(*la, *lb, w))
            .fold(f64::INFINITY, f64::min),
    }
}

/// Whether the distance of bodies i < j provably stays above `level` (m) over the whole step,
/// from bounds alone: the per-part search of [`search_parts`] with samples that query no
/// part pair — every pair's bounding-sphere gap and slab gap ([`SlabBound`]), with its rates
/// ([`PairRate`]). `false`: not proven within `max_evals` interior samples (which says
/// nothing about the distance). No exact query and no memo entry: where it does not prove
/// the step clear, the caller's search runs exactly as without it. The swept test's first
/// question ([`crate::sim`]).
#[allow(clippy::too_many_arguments)]
pub fn parts_stay_above(
    geo: &MonitorGeometry,
    motion: &StepMotion,
    i: usize,
    j: usize,
    level: f64,
    max_evals: u32,
    sc: &mut DistanceScratch,
) -> bool {
    let dt = motion.dt_s;
    part_pair_rates(geo, motion, i, j, &mut sc.terms, &mut sc.rates);
    let rates = std::mem::take(&mut sc.rates);
    let slab = SlabBound::new(geo, motion, i, j);
    let mut sample = |tau: f64| {
        let (pose_i, pose_j) = (motion.paths[i].pose_at(tau), motion.paths[j].pose_at(tau));
        let [ti, tj] = &mut sc.tmp;
        geo.part_poses(i, &pose_i.0, &pose_i.1, ti);
        geo.part_poses(j, &pose_j.0, &pose_j.1, tj);
        let mut lows = Vec::new();
        sphere_lows(&ti[..], &tj[..], &mut lows);
        let mut slabs = Vec::new();
        if let Some(b) = &slab {
            b.gaps(geo, (i, j), &pose_i, &pose_j, &mut slabs);
        }
        memo_lows(geo, (i, j), &sc.tmp, &mut lows);
        // The bodies' distance is at least every pair's bound.
        let lower = lows
            .iter()
            .enumerate()
            .map(|(k, l)| slabs.get(k).map_or(*l, |g| l.max(*g)))
            .fold(f64::INFINITY, f64::min);
        PartSample {
            d: Bracket {
                value: f64::INFINITY,
                lower,
            },
            lows,
            slabs,
            parts: (0, 0),
        }
    };
    let (s0, s1) = (sample(0.0), sample(dt));
    let r = crate::geometry::bounds::minimize_by(
        dt,
        s0,
        s1,
        |s: &PartSample| s.d.value,
        |a: &PartSample, b: &PartSample, w: f64| {
            parts_bound(a, b, w, &rates, slab.as_ref())
                .min(a.d.lower)
                .min(b.d.lower)
        },
        |_| level,
        max_evals,
        dt * 1e-9,
        sample,
    );
    sc.rates = rates;
    !r.exhausted && r.lower > level
}

/// Raises every part pair's low (m; row-major) to what its memo entry certifies at the parts'
/// world poses `tmp`, read only (nothing evaluated, nothing kept): the kept lower bound less
/// the parts' displacement since ([`memo::ExactEval::advance_quick`]), and for a faceted solid
/// of revolution, less its offset and its axis's displacement
/// ([`memo::ExactEval::advance_revolved`]).
fn memo_lows(
    geo: &MonitorGeometry,
    (i, j): (usize, usize),
    tmp: &[Vec<(Isometry3<f64>, f64)>; 2],
    lows: &mut [f64],
) {
    let [ti, tj] = tmp;
    let nj = tj.len();
    // A faceted part's centre and axis in its own frame, radius and offset.
    let local = |body: usize, p: usize| {
        let f = geo.pieces[body].get(p)?.faceted?;
        let pose = geo.pose_body[body][p];
        Some((
            pose.inverse_transform_point(&nalgebra::Point3::from(f.centre_body_m)),
            pose.rotation.inverse() * f.axis,
            f.radius_m,
            f.offset_m,
        ))
    };
    for (k, l) in lows.iter_mut().enumerate() {
        let (a, b) = (k / nj, k % nj);
        let Some(e) = geo.memo.get((i, a, j, b)) else {
            continue;
        };
        let rel = ti[a].0.inv_mul(&tj[b].0);
        let rel_inv = rel.inverse();
        *l = l.max(e.advance_quick((&rel, &rel_inv), ti[a].1, tj[b].1).0);
        if let Some((c, u, rho, s)) = local(j, b) {
            *l = l.max(e.advance_revolved(&rel, (&c, &u, rho, s)));
        }
        if let Some((c, u, rho, s)) = local(i, a) {
            let swapped =
                memo::ExactEval::new(e.rel_inv, e.value_m, e.lower_m, e.witness_b, e.witness_a);
            *l = l.max(swapped.advance_revolved(&rel_inv, (&c, &u, rho, s)));
        }
    }
}

/// Raises the lows of part pairs that `closest_parts_lows` left at a loose bound (a
/// bounding-sphere gap, or a memo's clearing bound at the best distance) below `need[pq]`, m:
/// each such pair is evaluated ([`pair_eval`], clearing at its need), and its low becomes the
/// certified bound that gives — a clearing bound, or its value less its GJK and f32
/// tolerances (as for the pairs `closest_parts_lows` evaluated), or its certified bracket's
/// lower end. `tmp`: the parts' world poses at the sample; `evaluated`: the pairs already
/// evaluated there; `skip`: pairs another bound clears (their slab gap).
#[allow(clippy::too_many_arguments)]
fn tighten_lows(
    geo: &MonitorGeometry,
    (i, j): (usize, usize),
    tmp: &[Vec<(Isometry3<f64>, f64)>; 2],
    evaluated: &[Evaluated],
    need: &[f64],
    skip: &dyn Fn(usize) -> bool,
    lows: &mut [f64],
    count: &mut QueryCount,
) {
    let [ti, tj] = tmp;
    let nj = tj.len();
    for (k, l) in lows.iter_mut().enumerate() {
        let Some(&n) = need.get(k) else { break };
        if *l >= n {
            continue;
        }
        let (a, b) = (k / nj, k % nj);
        if skip(k) || evaluated.iter().any(|e| e.2 == a && e.3 == b) {
            continue;
        }
        // A pair whose distance is known to be below its need cannot be cleared by any bound:
        // not evaluated (the search bisects it).
        if let Some(e) = geo.memo.get((i, a, j, b)) {
            let rel = ti[a].0.inv_mul(&tj[b].0);
            let (lo, up) = e.advance_quick((&rel, &rel.inverse()), ti[a].1, tj[b].1);
            *l = l.max(lo);
            if up < n || *l >= n {
                continue;
            }
        }
        count.exact += 1;
        match pair_eval(geo, i, a, &ti[a], j, b, &tj[b], n) {
            PairEval::Clear(c) => *l = l.max(c),
            PairEval::Value(d, known) => {
                let scale = (ti[a].0.translation.vector - tj[b].0.translation.vector).norm()
                    + ti[a].1
                    + tj[b].1;
                *l = l.max(d * (1.0 - GJK_REL_TOL) - F32_REL_TOL * scale);
                if !known.is_nan() {
                    *l = l.max(known);
                }
            }
        }
    }
}

#[allow(clippy::too_many_arguments)]
/// Full-geometry distance of bodies i < j at an offset τ into the last step, on the bodies'
/// paths (`sim::motion`), with a certified lower bound.
pub fn pair_at(
    geo: &MonitorGeometry,
    motion: &StepMotion,
    i: usize,
    j: usize,
    tau: f64,
    warm: Option<(usize, usize)>,
    sc: &mut DistanceScratch,
    count: &mut QueryCount,
) -> PartPairHit {
    let [ti, tj] = part_poses_at(geo, motion, i, j, tau, &mut sc.tmp);
    closest_parts(
        geo,
        i,
        ti,
        j,
        tj,
        &|_, _| true,
        warm,
        true,
        &mut sc.candidates,
        &mut sc.evaluated,
        count,
    )
}

/// Tolerance of a tracked closest approach: max(1 µm, 0.1 % of the distance), m.
pub fn min_distance_tolerance_m(d: f64) -> f64 {
    (1e-3 * d.abs()).max(1e-6)
}

/// The tolerance of a closest approach recorded at a sample with bracket `d`:
/// [`min_distance_tolerance_m`], or the bracket's width where that is wider, m.
pub fn sample_tolerance_m(d: &Bracket) -> f64 {
    let width = d.width();
    let tol = min_distance_tolerance_m(d.value);
    if width > tol { width } else { tol }
}

/// Interior evaluations allowed per pair per step for its closest approach.
const MAX_MIN_EVALS: u32 = 48;

/// Monitor system: full-geometry distances of every tracked body pair, their closest
/// approach over the run judged on the whole step interval, and the closest pair overall.
///
/// Tracked pairs (every pair in small scenes; else the pairs a guarantee names and those the
/// broad phase says can be within the horizon) get an exact distance every step, with a
/// certified lower bound. Between two samples the distance is at least
/// (d(t₀) + d(t₁) − S·dt)/2 with S the pair's distance-rate bound (`sim::motion`); where that
/// could undercut the closest approach so far by more than its tolerance
/// ([`min_distance_tolerance_m`]), the step is bisected on the bodies' paths
/// ([`crate::geometry::bounds::minimize`]) and the closest approach recorded where it is,
/// inside the interval if that is where it is.
///
/// Its steps, in order, are in `sim/monitor/tracked.rs`: the body views, each tracked pair's
/// sample and closest approach over the step, the closest tracked pair, the closest pair of a
/// trajectory row when no tracked pair is within the horizon, and the closest approach over
/// the run.
#[allow(clippy::too_many_arguments)] // a Bevy system: one parameter per resource it reads
pub fn distances(
    roster: Res<Roster>,
    clock: Res<Clock>,
    bodies: Query<(&SimBody, &BodyState)>,
    mut mon: ResMut<MonitorState>,
    geo: Res<MonitorGeometry>,
    motion: Res<StepMotion>,
    bp: Res<BroadPhase>,
    named: Res<NamedPairs>,
    rec: Res<super::output::Recorder>,
    mut scratch: Local<DistanceScratch>,
) {
    let every = (rec.every, rec.force_row);
    let t = clock.t_s();
    let n = roster.bodies.len();
    let sc = &mut *scratch;
    let mon = &mut *mon;
    tracked::refresh_views(mon, &roster, &bodies);
    if sc.poses.len() != n {
        sc.poses = vec![(u64::MAX, Vec::new()); n];
    }
    if sc.lazy.len() != n {
        sc.lazy = (0..n).map(|_| (u64::MAX, Vec::new())).collect();
    }
    let step = clock.step;
    let s = tracked::Step {
        geo: &geo,
        motion: &motion,
        t,
        step,
    };
    let mut count = QueryCount::default();
    let mut pairs = std::mem::take(&mut sc.pairs);
    tracked::tracked_pairs(&bp, &named, n, &mut pairs);
    for &(i, j) in &pairs {
        let k = tracked::pair_slot(mon, (i, j), t);
        tracked::track_pair(&s, mon, sc, &mut count, (i, j), k);
    }
    sc.pairs = pairs;
    tracked::closest_tracked(mon, t);
    let row_due = step.is_multiple_of(u64::from(every.0.max(1))) || every.1;
    if !bp.all_pairs && row_due {
        tracked::row_closest(&s, mon, sc, &mut count, &bp);
    }
    tracked::update_overall(mon, t);
    mon.exact_queries += count.exact;
    mon.pruned_pairs += count.pruned;
}

/// Two parts count as touching, for the time of first touch, at this distance, m.
pub const TOUCH_DISTANCE_M: f64 = 1e-4;

/// The time of first touch of a part pair that rapier reports in contact at the end of the
/// step just taken: the first time, on the bodies' unobstructed paths over the step (the f64
/// free flight, or rapier's straight path for a body it already drove), that the two parts are
/// within [`TOUCH_DISTANCE_M`], found by bisection with the rate bound of the paths and
/// bracketed to `EVENT_TIME_TOL`·dt; if they are that close from the step's start, the same
/// search on the step before (rapier flags a contact whose approach just closed the gap one
/// step late). If they never get that close on those paths (rapier's solver acts from its
/// prediction distance on), the end of the step. Returns (time, tolerance).
pub fn touch_time(
    geo: &MonitorGeometry,
    motion: &StepMotion,
    (i, a): (usize, usize),
    (j, b): (usize, usize),
    sc: &mut DistanceScratch,
) -> (f64, f64) {
    use crate::geometry::bounds::{Crossing, first_below};
    let dt = motion.dt_s;
    let t0 = motion.t0_s;
    let tol = dt * super::EVENT_TIME_TOL;
    let mut search = |pi: &super::motion::BodyPath, pj: &super::motion::BodyPath| {
        let rate = super::motion::rel_speed(pi, pj)
            + pi.omega_max_rad_s * geo.extent_m[i]
            + pj.omega_max_rad_s * geo.extent_m[j];
        let mut f = |tau: f64| {
            let (xi, qi) = pi.pose_at(tau);
            let (xj, qj) = pj.pose_at(tau);
            let [ti, tj] = &mut sc.tmp;
            geo.part_poses(i, &xi, &qi, ti);
            geo.part_poses(j, &xj, &qj, tj);
            part_bracket(geo, i, a, &ti[a], j, b, &tj[b])
        };
        let (f0, f1) = (f(0.0), f(dt));
        first_below(dt, f0, f1, rate, TOUCH_DISTANCE_M, tol, 256, &mut f)
    };
    let free = |paths: &[super::motion::BodyPath],
                before: &[Option<super::motion::BodyPath>],
                k: usize| {
        before
            .get(k)
            .and_then(|p: &Option<super::motion::BodyPath>| p.clone())
            .unwrap_or_else(|| paths[k].clone())
    };
    let c = search(motion.free_path(i), motion.free_path(j));
    if let Crossing::At { t_lo: 0.0, .. } = c
        && let Some(prev) = &motion.prev
    {
        // Within the touch distance from the start of this step: they touched in the last one.
        let (pi, pj) = (free(&prev.0, &prev.1, i), free(&prev.0, &prev.1, j));
        match search(&pi, &pj) {
            Crossing::At { t_lo, t_hi } => return (t0 - dt + t_lo, t_hi - t_lo),
            Crossing::Unresolved { t_lo } => return (t0 - dt + t_lo, dt - t_lo),
            Crossing::Never => return (t0, 0.0),
        }
    }
    match c {
        Crossing::At { t_lo, t_hi } => (t0 + t_lo, t_hi - t_lo),
        Crossing::Unresolved { t_lo } => (t0 + t_lo, dt - t_lo),
        Crossing::Never => (t0 + dt, 0.0),
    }
}

/// Run condition of [`contacts`]: whether it has anything to do this step — rapier stepped (its
/// contact pairs are this step's), the compliant docking model is present, a contact is active
/// (it may end) or the last step's points or pairs are still to be cleared. Otherwise the
/// system would find nothing and change nothing; not running it saves its resource fetches.
pub fn contacts_wanted(
    sync: Res<super::RapierSync>,
    cs: Res<ContactState>,
    compliant: Option<Res<super::contact_model::CompliantContact>>,
) -> bool {
    sync.stepped
        || compliant.is_some()
        || !cs.active.is_empty()
        || !cs.points.is_empty()
        || !cs.step_pairs.is_empty()
}

/// Monitor system: rapier's contacts between bodies, named by part, and the compliant docking
/// model's; start/end events, peak force and impulse per part, docking contact vs collision;
/// the per-point rows of `contact_points.csv`.
///
/// For rapier's contacts, the impulse a body received is measured from its momentum (see
/// `physics_step`), which is exact for the step rapier took; rapier's per-point normal impulses
/// (which also carry its position-correction bias) only split it among the part pairs touching
/// that body. Each pair's impulse is the mean of the two bodies' attributions (equal when the
/// pair is the only contact). The compliant model's pairs ([`super::contact_model`]) come with
/// their exact impulses and sub-step peak forces.
///
/// Its steps, in order, are in `sim/monitor/contact_steps.rs`: rapier's touching part pairs
/// and their contact points, each body's raw normal impulse, the compliant model's pairs, the
/// contacts that ended, and per pair in contact its impulse, its start (with the time of first
/// touch, [`touch_time`]) and its totals.
#[allow(clippy::too_many_arguments)] // a Bevy system: one parameter per resource it uses
pub fn contacts(
    phys: Res<super::Physics>,
    clock: Res<Clock>,
    sync: Res<super::RapierSync>,
    geo: Res<MonitorGeometry>,
    motion: Res<StepMotion>,
    mut cs: ResMut<ContactState>,
    mut log: ResMut<EventLog>,
    mut scratch: Local<DistanceScratch>,
    compliant: Option<Res<super::contact_model::CompliantContact>>,
) {
    let t = clock.t_s();
    let dt = clock.h_s();
    let cs = &mut *cs;
    cs.points.clear();
    cs.step_pairs.clear();
    // (pair key) → (docking, body a, body b, rapier's raw normal impulse)
    let mut now = contact_steps::NowPairs::new();
    // (pair key) → (body, part) of each side, for the time of first touch.
    let mut who: BTreeMap<(String, String), ContactSides> = BTreeMap::new();
    contact_steps::rapier_pairs(&phys, sync.stepped, cs, (t, dt), &mut now, &mut who);
    let raw_per_body = contact_steps::raw_per_body(&now, cs.body_impulse.len());
    // The compliant model's pairs: (impulse on b, peak force) per key.
    let mut given = contact_steps::GivenPairs::new();
    if let Some(cc) = &compliant {
        contact_steps::compliant_pairs(cc, (t, dt), &mut now, &mut given, &mut cs.points);
    }
    // Ended contacts.
    contact_steps::end_contacts(cs, &now, &mut log, t);
    for (k, (docking, ba, bb, raw)) in now {
        let imp = contact_steps::pair_impulse(&k, (ba, bb, raw), &given, &raw_per_body, cs, dt);
        if !cs.active.contains_key(&k) {
            let touch = match (motion.ready, who.get(&k)) {
                (true, Some(&(sa, sb))) => touch_time(&geo, &motion, sa, sb, &mut scratch),
                _ => (t, 0.0),
            };
            contact_steps::start_contact(cs, &mut log, &k, docking, t, touch);
        }
        contact_steps::accumulate(cs, k, docking, (ba, bb), &imp);
    }
}
