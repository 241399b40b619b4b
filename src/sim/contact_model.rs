//! Compliant docking contact: the cone–slot contact force computed by rpod from
//! parry's contact manifolds with the scene's law ([`crate::contact`]), integrated in f64 with
//! sub-steps only while the docking parts can touch.
//!
//! # Why not rapier's soft contacts
//! rapier 0.35's contact softness is global ([`rp::IntegrationParameters`] carries one natural
//! frequency and damping ratio for every dynamic pair, relative to the pair's effective mass)
//! and acts only on the position-correction (bias) pass: the velocity pass still removes the
//! whole approach speed in one step, so the peak force stays m_eff·v/dt (693 / 3469 / 7910 N at
//! dt = 10 / 2 / 0.5 ms in `docking_aligned`). A physical stiffness in N/m cannot be mapped
//! onto it, so in compliant mode rapier does not see the docking pair at all (collision groups),
//! and this module integrates the two docking bodies itself while their docking parts can touch.
//!
//! # One step
//! 1. Window: for each (chaser docking part, target docking part) pair, the distance at the
//!    step start (bounding spheres first, then parry's exact distance) against a bound on how
//!    far the parts can move relative to each other in the step,
//!    3·(|v_rel| + |ω_a|·R_a + |ω_b|·R_b)·dt + |a_rel|·dt² + 1 mm (the factor 3 allows an
//!    elastic bounce off another pair within the step). No pair within reach: the bodies fly
//!    the usual free-flight step (no cost beyond the bound).
//! 2. Sub-step h = dt/N with N = ⌈dt/h_max⌉: h_max = T/`substeps_per_period`, T = 2π√(m_min/k')
//!    the period at the stiffest the step can reach (k' = dF/dδ at the depth bound of
//!    [`Law::depth_bound_m`], m_min the smallest effective mass any contact point of the pair can
//!    have). The damping needs no bound ([`Law::normal_force_implicit_n`]).
//! 3. Kick–drift–kick on both bodies (velocity Verlet; the rotation drifts torque-free by
//!    [`super::rotate_rk4`]), the commanded, magnet and gravity forces held over the step as in
//!    free flight, the contact wrench evaluated once per sub-step, after the drift, from a fresh
//!    manifold per pair (never a cached one: parry and rapier both keep old normals while a pose
//!    changes little), with the half-step velocities and the damping implicit over the second
//!    half-kick: for the damping, the trapezoidal rule (second order, and stable however stiff
//!    the damping of a contact that starts at rest, λ = x/v₀ with v₀ at its floor).
//! 4. Per pair, the manifold's penetrating points give the depth δ (the deepest point, f64 from
//!    parry's f32 witness points) and the point of application (their depth-weighted centroid);
//!    the normal force follows the law at that point's closing rate; friction is Coulomb's,
//!    capped so that its impulse over a half-kick never reverses the slip there.
//!
//! The forces act equal and opposite at the same point, so the pair's linear momentum is
//! conserved to rounding (`tests/val_docking.rs`). A docking body that rapier also holds (a
//! collision elsewhere, a joint) is rapier's in that step; the model's mean force over the step
//! is then applied to it as an external force. After the latch the model is off (the joint
//! holds the bodies).

use super::monitor::{Faceted, PartPiece};
use super::{BodyState, Part, Physics, Roster, SimBody, Wrench, conv};
use crate::contact::ContactModelSpec;
use crate::contact::Law;
use crate::scene::{LoadedScene, SceneError};
use bevy::prelude::*;
use bevy_rapier3d::parry::query::{
    ContactManifold, DefaultQueryDispatcher, PersistentQueryDispatcher,
};
use bevy_rapier3d::rapier::prelude as rp;
use nalgebra::{Isometry3, Matrix3, Vector3};

/// Sub-steps are capped at this many per step (a scene whose stiffness would need more is
/// refused at load time; the cap only guards against a state the load check did not foresee).
pub const MAX_SUBSTEPS: u32 = 20_000;

/// One part pair the model handles: a docking part of body `a` against one of body `b`
/// (`a` the lower body index, as in the contact bookkeeping).
#[derive(Clone)]
pub struct CompliantPair {
    /// `body/collider` names (a, b).
    pub names: (String, String),
    /// Shapes (a, b).
    pub shapes: (rp::SharedShape, rp::SharedShape),
    /// Part poses in their body frames (a, b).
    pub poses: (Isometry3<f64>, Isometry3<f64>),
    /// Bounding radii about the part origins, m (a, b).
    pub radii: (f64, f64),
    /// Vertices of the shapes in their part frames, m (a, b); see [`shape_vertices`].
    pub vertices: (Vec<Vector3<f64>>, Vec<Vector3<f64>>),
    /// Each part as a faceted solid of revolution, body frame, if it is one (the docking
    /// cone's hull; [`super::monitor::Faceted`]), for the window's reach (a, b).
    pub faceted: (Option<Faceted>, Option<Faceted>),
    /// In contact at the end of the last sub-step.
    pub in_contact: bool,
    /// Normal approach speed when the current contact began, m/s.
    pub impact_speed_m_s: f64,
    /// Peak normal force of the current contact, N.
    pub contact_peak_n: f64,
    /// When the current contact began (interpolated between sub-steps), s.
    pub start_s: f64,
    /// Depth at the end of the last sub-step, m (−∞ when out of the prediction distance).
    pub last_depth_m: f64,
    /// Unclamped normal force at the end of the last sub-step, N (−∞ without penetration).
    pub last_force_n: f64,
    /// Point of application and normal (on b) at the last sub-step in contact.
    pub last_contact: Option<(Vector3<f64>, Vector3<f64>)>,
}

impl CompliantPair {
    /// A pair out of contact: `names` (a, b), and each part's shape, pose in its body frame and
    /// bounding radius about its origin (m).
    pub fn new(
        names: (String, String),
        a: (&rp::SharedShape, &Isometry3<f64>, f64),
        b: (&rp::SharedShape, &Isometry3<f64>, f64),
    ) -> Self {
        CompliantPair {
            names,
            shapes: (a.0.clone(), b.0.clone()),
            poses: (*a.1, *b.1),
            radii: (a.2, b.2),
            vertices: (shape_vertices(a.0), shape_vertices(b.0)),
            faceted: (
                PartPiece::of(&**a.0, a.1, a.2).faceted,
                PartPiece::of(&**b.0, b.1, b.2).faceted,
            ),
            in_contact: false,
            impact_speed_m_s: 0.0,
            contact_peak_n: 0.0,
            start_s: 0.0,
            last_depth_m: f64::NEG_INFINITY,
            last_force_n: f64::NEG_INFINITY,
            last_contact: None,
        }
    }
}

/// What a pair did in one step.
#[derive(Debug, Clone)]
pub struct PairStep {
    /// Index in [`CompliantContact::pairs`].
    pub pair: usize,
    /// Impulse on part `b` over the step (normal and friction), world frame, N·s.
    pub impulse_on_b_ns: Vector3<f64>,
    /// Largest contact force magnitude on `b` within the step, N.
    pub peak_force_n: f64,
    /// In contact at the end of the step.
    pub in_contact_at_end: bool,
}

/// One sub-step sample of one touching pair (for `contact_points.csv`).
#[derive(Debug, Clone)]
pub struct ForceSample {
    /// End of the sub-step, s from the start of the step.
    pub t_in_step_s: f64,
    /// Pair index.
    pub pair: usize,
    /// Point of application, world, m.
    pub point_m: Vector3<f64>,
    /// Unit normal, the direction of the normal force on `b`, world.
    pub normal_on_b: Vector3<f64>,
    /// Depth, m.
    pub depth_m: f64,
    /// Normal force, N.
    pub normal_force_n: f64,
    /// Total contact force on `b` (normal and friction), world, N.
    pub force_on_b_n: Vector3<f64>,
    /// Duration of the sub-step, s.
    pub h_s: f64,
}

/// One completed impact (a contact of one pair from first touch to separation; both times
/// interpolated linearly in depth between sub-steps).
#[derive(Debug, Clone, serde::Serialize)]
pub struct ImpactRecord {
    /// First touch, s.
    pub t_start_s: f64,
    /// Separation time, s.
    pub t_end_s: f64,
    /// Time in contact, s.
    pub duration_s: f64,
    /// Pair (`body/part` names).
    pub a: String,
    /// Second part.
    pub b: String,
    /// Normal approach speed at first touch, m/s.
    pub approach_m_s: f64,
    /// Normal separation speed at the last touch, m/s.
    pub separation_m_s: f64,
    /// Separation over approach.
    pub restitution: f64,
    /// Peak normal force, N.
    pub peak_normal_force_n: f64,
}

/// The model's resource.
#[derive(Resource)]
pub struct CompliantContact {
    /// The law.
    pub law: Law,
    /// The scene's description of it (for outputs).
    pub description: String,
    /// Sub-steps per contact period.
    pub substeps_per_period: u32,
    /// Body entities (a, b), a the lower index.
    pub bodies: (Entity, Entity),
    /// Body indices (a, b).
    pub indices: (usize, usize),
    /// Coulomb coefficient (the average of the two bodies', rapier's default rule).
    pub mu: f64,
    /// The part pairs.
    pub pairs: Vec<CompliantPair>,
    /// Off after the latch.
    pub enabled: bool,
    /// This step: the pairs that touched.
    pub step: Vec<PairStep>,
    /// This step: per sub-step samples of touching pairs.
    pub samples: Vec<ForceSample>,
    /// This step: per sub-step (duration s, total contact force on body `b`, world N) while
    /// any pair touched.
    pub b_force_history: Vec<(f64, Vector3<f64>)>,
    /// This step: time with any pair in contact, s.
    pub step_contact_s: f64,
    /// Impacts completed this step (drained by the docking monitor into events).
    pub impacts: Vec<ImpactRecord>,
    /// Run statistics of the sub-stepping.
    pub stats: SubstepStats,
    /// Simulated time at the start of the current step, s (set by the physics step).
    pub t_step_s: f64,
    /// Mechanism forces between the bodies (latch, separation springs).
    pub link: Link,
    /// This step: what the link did.
    pub link_step: LinkStep,
    /// This step: what the soft-capture platform did (when there is one).
    pub platform_step: PlatformStep,
}

/// A spring–damper latch between the two docking bodies ([`crate::scene::CompliantLatch`]).
#[derive(Debug, Clone)]
pub struct LatchSpring {
    /// The law's coefficients.
    pub spec: crate::scene::CompliantLatch,
    /// The chaser port origin in the chaser's body frame, m.
    pub port_c_body_m: Vector3<f64>,
    /// The chaser's body frame in the target's body frame when the latch caught it.
    pub caught: Isometry3<f64>,
}

/// Separation springs: along the target port axis a_t, at the chaser port origin, the force
/// on the chaser F = (preload + k·(L − x))·a_t for an extension x < L since the release
/// (x = the growth of (p_c − p_t)·a_t), k = (force − preload)/L; none once x reaches L, and
/// from then on never again (the springs rest on their stops). The target gets −F.
#[derive(Debug, Clone)]
pub struct SeparationSpring {
    /// Stroke L, m.
    pub stroke_m: f64,
    /// Force at full compression (x = 0), N.
    pub force_n: f64,
    /// Force at the end of the stroke (x = L), N.
    pub preload_n: f64,
    /// (p_c − p_t)·a_t at the release, m.
    pub x0_m: f64,
    /// Ports in their body frames: chaser origin, target origin and unit axis, m.
    pub ports_body_m: (Vector3<f64>, Vector3<f64>, Vector3<f64>),
}

/// Mechanism forces between the docking bodies, integrated with the contact's sub-steps.
#[derive(Debug, Clone, Default)]
pub struct Link {
    /// The chaser is body `b` of the pair (else `a`).
    pub chaser_is_b: bool,
    /// The compliant latch, while latched.
    pub latch: Option<LatchSpring>,
    /// Separation springs, from the release to the end of their stroke.
    pub separation: Option<SeparationSpring>,
    /// The soft-capture platform, from the capture to the release.
    pub platform: Option<PlatformLink>,
}

/// The soft-capture attenuation platform between the docking bodies
/// ([`crate::contact::platform`]): its base frame P rides on the chaser, its capture ring is
/// held by the capture latches to the target (the ring's pose fixed in the target's body
/// frame: the latches are rigid and the ring's mass and inertia are lumped with the target's),
/// and the legs' loads act on the chaser at P and, equal and opposite, on the target. The
/// retraction shortens every leg's neutral length
/// ([`crate::contact::platform::Platform::loads_retracted`]) at `retraction_rate_m_s` within
/// the step, up to `retraction_max_m`.
#[derive(Debug, Clone)]
pub struct PlatformLink {
    /// The platform.
    pub platform: crate::contact::platform::Platform,
    /// P in the chaser's body frame (origin at the chaser port origin).
    pub port_c_body: Isometry3<f64>,
    /// The ring frame R in the target's body frame.
    pub ring_in_target: Isometry3<f64>,
    /// Retraction at the start of the step, m.
    pub retraction_m: f64,
    /// Retraction rate over the step, m/s (0 or the retraction speed).
    pub retraction_rate_m_s: f64,
    /// Largest retraction, m.
    pub retraction_max_m: f64,
}

impl PlatformLink {
    /// The retraction `tau_s` into the step, m.
    pub fn retraction_at(&self, tau_s: f64) -> f64 {
        (self.retraction_m + self.retraction_rate_m_s * tau_s).min(self.retraction_max_m)
    }

    /// The platform base (from the chaser's state) and the ring (from the target's), world.
    pub fn base_and_ring(
        &self,
        (com_c, sc): (&Vector3<f64>, &BodyState),
        (com_t, st): (&Vector3<f64>, &BodyState),
    ) -> (
        crate::contact::platform::Base,
        crate::contact::platform::RigidState,
    ) {
        let pose = sc.body_pose(com_c) * self.port_c_body;
        let p = pose.translation.vector;
        let base = crate::contact::platform::Base {
            pose,
            vel_m_s: point_vel(sc, &p),
            omega_rad_s: sc.omega_rad_s,
        };
        let r = st.body_pose(com_t) * self.ring_in_target;
        let c = r.translation.vector;
        let ring = crate::contact::platform::RigidState {
            pos_m: c,
            vel_m_s: point_vel(st, &c),
            att: r.rotation,
            omega_rad_s: st.omega_rad_s,
        };
        (base, ring)
    }

    /// The legs' loads `tau_s` into the step.
    pub fn loads(
        &self,
        c: (&Vector3<f64>, &BodyState),
        t: (&Vector3<f64>, &BodyState),
        tau_s: f64,
    ) -> crate::contact::platform::PlatformLoads {
        let (base, ring) = self.base_and_ring(c, t);
        self.platform
            .loads_retracted(&base, &ring, self.retraction_at(tau_s))
    }
}

/// What the link did in one step.
#[derive(Debug, Clone, Copy, Default)]
pub struct LinkStep {
    /// Largest latch force on the chaser at its port within the step, N.
    pub peak_force_n: f64,
    /// Largest latch moment on the chaser about its port within the step, N·m.
    pub peak_moment_nm: f64,
    /// Latch force on the chaser at its port at the end of the step, world, N.
    pub force_end_n: Vector3<f64>,
    /// Latch moment on the chaser about its port at the end of the step, world, N·m.
    pub moment_end_nm: Vector3<f64>,
    /// The separation springs reached the end of their stroke in this step.
    pub separation_ended: bool,
}

/// What the soft-capture platform did in one step.
#[derive(Debug, Clone, Default)]
pub struct PlatformStep {
    /// Largest |leg force| over the sub-steps, N.
    pub peak_leg_force_n: f64,
    /// Largest |leg stroke| over the sub-steps, m.
    pub peak_leg_stroke_m: f64,
    /// The legs at the end of the step.
    pub end: Option<crate::contact::platform::PlatformLoads>,
    /// The ring frame R in the platform frame P at the end of the step.
    pub ring_in_base: Option<Isometry3<f64>>,
}

/// (latch and platform force on the chaser, their moment on it, separation force on it, point
/// p_c, the platform's legs), world.
type LinkWrench = (
    Vector3<f64>,
    Vector3<f64>,
    Vector3<f64>,
    Vector3<f64>,
    Option<crate::contact::platform::PlatformLoads>,
);

/// The link's wrench at one configuration `tau_s` into the step: (latch and platform force on
/// the chaser at p_c, their moment on the chaser about p_c, separation force on the chaser at
/// p_c, p_c, the platform's legs), world frame. The latch and the platform both act at the
/// chaser port origin p_c.
fn link_wrench(
    link: &Link,
    (dc, sc): (&Dyn, &BodyState),
    (dt, st): (&Dyn, &BodyState),
    tau_s: f64,
) -> Option<LinkWrench> {
    let pose_c = sc.body_pose(&dc.com);
    let pose_t = st.body_pose(&dt.com);
    let mut f = Vector3::zeros();
    let mut m = Vector3::zeros();
    let mut fs = Vector3::zeros();
    let mut p_c = None;
    if let Some(l) = &link.latch {
        let p = pose_c.transform_point(&l.port_c_body_m.into()).coords;
        let anchor = (pose_t * l.caught)
            .transform_point(&l.port_c_body_m.into())
            .coords;
        let dv = point_vel(sc, &p) - point_vel(st, &p);
        f = -(p - anchor) * l.spec.stiffness_n_m - dv * l.spec.damping_n_s_m;
        let err = pose_c.rotation * (pose_t.rotation * l.caught.rotation).inverse();
        m = -err.scaled_axis() * l.spec.rot_stiffness_nm_rad
            - (sc.omega_rad_s - st.omega_rad_s) * l.spec.rot_damping_nm_s_rad;
        p_c = Some(p);
    }
    if let Some(sp) = &link.separation {
        let (pc_b, pt_b, at_b) = sp.ports_body_m;
        let p = pose_c.transform_point(&pc_b.into()).coords;
        let pt = pose_t.transform_point(&pt_b.into()).coords;
        let at = pose_t.rotation * at_b;
        let x = (p - pt).dot(&at) - sp.x0_m;
        if x < sp.stroke_m {
            let k = (sp.force_n - sp.preload_n) / sp.stroke_m;
            fs = at * (sp.preload_n + k * (sp.stroke_m - x));
        }
        p_c.get_or_insert(p);
    }
    let mut legs = None;
    if let Some(pl) = &link.platform {
        let l = pl.loads((&dc.com, sc), (&dt.com, st), tau_s);
        f += l.force_on_base_n;
        m += l.moment_on_base_nm;
        p_c.get_or_insert((sc.body_pose(&dc.com) * pl.port_c_body).translation.vector);
        legs = Some(l);
    }
    p_c.map(|p| (f, m, fs, p, legs))
}

/// How much sub-stepping a run needed.
#[derive(Debug, Clone, Copy, Default, serde::Serialize)]
pub struct SubstepStats {
    /// Steps sub-stepped (a docking pair within reach).
    pub steps_substepped: u64,
    /// Sub-steps over the run.
    pub substeps: u64,
    /// Most sub-steps in one step.
    pub max_substeps_per_step: u32,
    /// Steps whose sub-step count hit [`MAX_SUBSTEPS`].
    pub capped_steps: u64,
    /// Steps where a docking body was also held by rapier (a collision elsewhere): the model's
    /// mean wrench was applied as an external force in rapier's step.
    pub rapier_held_steps: u64,
}

/// The new f64 states of the sub-stepped bodies: (body index, state).
pub type Substepped = Vec<(usize, BodyState)>;

/// Per-body integration data.
struct Dyn {
    inv_m: f64,
    j: Matrix3<f64>,
    j_inv_body: Matrix3<f64>,
    com: Vector3<f64>,
    fixed: bool,
    lin_mask: Vector3<f64>,
    rot_mask: Vector3<f64>,
}

impl Dyn {
    fn new(b: &SimBody, rb: Option<&rp::RigidBody>) -> Self {
        let (fixed, locks) = rb.map_or((false, rp::LockedAxes::empty()), |rb| {
            (!rb.is_dynamic(), rb.locked_axes())
        });
        let bit = |f: rp::LockedAxes| if locks.contains(f) { 0.0 } else { 1.0 };
        Dyn {
            inv_m: if fixed { 0.0 } else { 1.0 / b.mass_kg },
            j: b.inertia_kg_m2,
            j_inv_body: if fixed {
                Matrix3::zeros()
            } else {
                b.inertia_inv
            },
            com: b.com_body_m,
            fixed,
            lin_mask: Vector3::new(
                bit(rp::LockedAxes::TRANSLATION_LOCKED_X),
                bit(rp::LockedAxes::TRANSLATION_LOCKED_Y),
                bit(rp::LockedAxes::TRANSLATION_LOCKED_Z),
            ),
            rot_mask: Vector3::new(
                bit(rp::LockedAxes::ROTATION_LOCKED_X),
                bit(rp::LockedAxes::ROTATION_LOCKED_Y),
                bit(rp::LockedAxes::ROTATION_LOCKED_Z),
            ),
        }
    }
    /// World inverse inertia, masked by the rotation locks.
    fn inv_inertia_world(&self, s: &BodyState) -> Matrix3<f64> {
        let r = s.att.to_rotation_matrix().into_inner();
        let m = Matrix3::from_diagonal(&self.rot_mask);
        m * r * self.j_inv_body * r.transpose() * m
    }
    /// Largest eigenvalue bound of the inverse inertia (its Frobenius norm), 1/(kg·m²).
    fn inv_inertia_bound(&self) -> f64 {
        self.j_inv_body.norm()
    }
}

/// Contact geometry of one pair at one configuration.
#[derive(Debug, Clone, Copy)]
struct Geometry {
    point: Vector3<f64>,
    normal: Vector3<f64>,
    depth: f64,
}

/// The contact of a pair at one configuration, from a fresh parry manifold computed with the
/// given prediction distance: the depth δ of the deepest point (negative: the smallest gap,
/// when no point penetrates), the point of application (the depth-weighted centroid of the
/// penetrating points, else the closest point) and the manifold normal (from part `a` to part
/// `b`); `None` when the parts are farther apart than the prediction distance.
fn pair_geometry(
    pair: &CompliantPair,
    body_a: &Isometry3<f64>,
    body_b: &Isometry3<f64>,
    prediction_m: f64,
) -> Option<Geometry> {
    let pa = body_a * pair.poses.0;
    let pb = body_b * pair.poses.1;
    let rel = pa.inv_mul(&pb);
    let mut manifold = ContactManifold::<(), ()>::new();
    DefaultQueryDispatcher
        .contact_manifold_convex_convex(
            &conv::pose(&rel),
            &*pair.shapes.0,
            &*pair.shapes.1,
            None,
            None,
            prediction_m as f32,
            &mut manifold,
        )
        .ok()?;
    if manifold.points.is_empty() {
        return None;
    }
    let n = (pa.rotation * conv::na(manifold.local_n1)).normalize();
    if !n.iter().all(|c| c.is_finite()) {
        return None;
    }
    let (mut wsum, mut wp, mut depth) = (0.0, Vector3::zeros(), f64::NEG_INFINITY);
    let mut closest = Vector3::zeros();
    let mut deepest = (Vector3::zeros(), Vector3::zeros());
    for p in &manifold.points {
        let p1 = pa.transform_point(&conv::na(p.local_p1).into()).coords;
        let p2 = pb.transform_point(&conv::na(p.local_p2).into()).coords;
        // The depth in f64 from parry's f32 witness points (their rounding is fixed to the
        // material points, so the depth evolves smoothly with the f64 poses).
        let d = -(p2 - p1).dot(&n);
        if d > depth {
            depth = d;
            closest = (p1 + p2) * 0.5;
            deepest = (p1, p2);
        }
        if d > 0.0 {
            wsum += d;
            wp += (p1 + p2) * (0.5 * d);
        }
    }
    if depth > 0.0 {
        // parry's polygonal features hold at most four vertices, so a face–face manifold (the
        // cone's 32-sided tip on the back plate) is a subset of the contact polygon and its
        // centroid can sit centimetres off the centre of pressure. The vertices of either
        // shape inside the other, weighted by their depth below the other's contact plane
        // (through the deepest point, normal n), give the whole polygon.
        let (mut vsum, mut vp) = (0.0, Vector3::zeros());
        let rel_inv = rel.inverse();
        for v in &pair.vertices.1 {
            let in_a = rel * nalgebra::Point3::from(*v);
            if pair.shapes.0.contains_local_point(conv::v(&in_a.coords)) {
                let w = pb.transform_point(&(*v).into()).coords;
                let d = (deepest.0 - w).dot(&n);
                if d > 0.0 {
                    vsum += d;
                    vp += w * d;
                }
            }
        }
        for u in &pair.vertices.0 {
            let in_b = rel_inv * nalgebra::Point3::from(*u);
            if pair.shapes.1.contains_local_point(conv::v(&in_b.coords)) {
                let w = pa.transform_point(&(*u).into()).coords;
                let d = (w - deepest.1).dot(&n);
                if d > 0.0 {
                    vsum += d;
                    vp += w * d;
                }
            }
        }
        if vsum > 0.0 {
            wsum = vsum;
            wp = vp;
        }
    }
    Some(Geometry {
        point: if wsum > 0.0 { wp / wsum } else { closest },
        normal: n,
        depth,
    })
}

/// The vertices of a shape, in its own frame (convex hulls and boxes; none for round shapes).
pub fn shape_vertices(shape: &rp::SharedShape) -> Vec<Vector3<f64>> {
    if let Some(c) = shape.as_convex_polyhedron() {
        c.points().iter().map(|p| conv::na(*p)).collect()
    } else if let Some(b) = shape.as_cuboid() {
        let h = conv::na(b.half_extents);
        let mut v = Vec::with_capacity(8);
        for sx in [-1.0, 1.0] {
            for sy in [-1.0, 1.0] {
                for sz in [-1.0, 1.0] {
                    v.push(Vector3::new(sx * h.x, sy * h.y, sz * h.z));
                }
            }
        }
        v
    } else {
        Vec::new()
    }
}

/// The effective mass of the two bodies for an impulse along unit `dir` at world point `p`, kg.
fn effective_mass(
    d: (&Dyn, &Dyn),
    s: (&BodyState, &BodyState),
    ii: (&Matrix3<f64>, &Matrix3<f64>),
    p: &Vector3<f64>,
    dir: &Vector3<f64>,
) -> f64 {
    let term = |dy: &Dyn, st: &BodyState, i: &Matrix3<f64>| {
        let lin = dy.inv_m * dir.component_mul(&dy.lin_mask).dot(dir);
        let rn = (p - st.pos_m).cross(dir);
        lin + rn.dot(&(i * rn))
    };
    let w = term(d.0, s.0, ii.0) + term(d.1, s.1, ii.1);
    if w > 0.0 { 1.0 / w } else { f64::INFINITY }
}

/// Velocity of the material point at `p`.
fn point_vel(s: &BodyState, p: &Vector3<f64>) -> Vector3<f64> {
    s.vel_m_s + s.omega_rad_s.cross(&(p - s.pos_m))
}

/// The contact force on `b` of a pair with geometry `g` (N, world), its normal part (N) and
/// the law's value before the clamp at 0 (N; negative once the surfaces separate).
#[allow(clippy::too_many_arguments)]
fn pair_force(
    law: &Law,
    mu: f64,
    pair: &CompliantPair,
    g: &Geometry,
    d: (&Dyn, &Dyn),
    s: (&BodyState, &BodyState),
    ii: (&Matrix3<f64>, &Matrix3<f64>),
    half_h: f64,
) -> (Vector3<f64>, f64, f64) {
    let v_rel = point_vel(s.1, &g.point) - point_vel(s.0, &g.point);
    let closing = -v_rel.dot(&g.normal);
    // The damping implicit over the coming half-kick (stable however stiff it is).
    let mn = effective_mass(d, s, ii, &g.point, &g.normal);
    let raw = law.normal_force_implicit_n(g.depth, closing, pair.impact_speed_m_s, mn, half_h);
    let fnorm = raw.max(0.0);
    let mut f = g.normal * fnorm;
    let vt = v_rel - g.normal * v_rel.dot(&g.normal);
    let slip = vt.norm();
    if mu > 0.0 && fnorm > 0.0 && slip > 0.0 {
        let t = vt / slip;
        let mt = effective_mass(d, s, ii, &g.point, &t);
        // Coulomb's limit, but never more than stops the slip within the half-kick.
        let ft = (mu * fnorm).min(mt * slip / half_h);
        f -= t * ft;
    }
    (f, fnorm, raw)
}

/// Kicks a body's velocities by force `f` and torque `tau` (world) over `h`, masked by its locks.
fn kick(
    dy: &Dyn,
    s: &mut BodyState,
    ii: &Matrix3<f64>,
    f: &Vector3<f64>,
    tau: &Vector3<f64>,
    h: f64,
) {
    if dy.fixed {
        return;
    }
    s.vel_m_s += f.component_mul(&dy.lin_mask) * (dy.inv_m * h);
    s.omega_rad_s += ii * tau * h;
}

/// One step's integration context.
struct Stepper<'a> {
    law: &'a Law,
    mu: f64,
    pairs: &'a mut [CompliantPair],
    candidates: &'a [usize],
    d: (&'a Dyn, &'a Dyn),
    half_h: f64,
    prediction_m: f64,
    link: &'a Link,
    /// Time into the step of the configuration being evaluated, s (the retraction's clock).
    tau_s: f64,
}

/// Forces of one evaluation: per pair (force on b, normal force, unclamped normal force), and
/// the totals.
struct Forces {
    per_pair: Vec<(Vector3<f64>, f64, f64)>,
    /// Total force on b (a gets the opposite), N.
    on_b: Vector3<f64>,
    /// Torques about the centres of mass of a and b, N·m.
    torque: (Vector3<f64>, Vector3<f64>),
    /// World inverse inertias used.
    ii: (Matrix3<f64>, Matrix3<f64>),
    /// The link's (latch and platform force, their moment, separation force) on the chaser,
    /// world.
    link: (Vector3<f64>, Vector3<f64>, Vector3<f64>),
    /// The platform's legs.
    legs: Option<crate::contact::platform::PlatformLoads>,
    /// The link's force on b, world, N.
    link_on_b: Vector3<f64>,
}

impl Stepper<'_> {
    fn geometry(&self, sa: &BodyState, sb: &BodyState) -> Vec<Option<Geometry>> {
        let (pa, pb) = (sa.body_pose(&self.d.0.com), sb.body_pose(&self.d.1.com));
        let mut g = vec![None; self.pairs.len()];
        for k in self.candidates {
            g[*k] = pair_geometry(&self.pairs[*k], &pa, &pb, self.prediction_m);
        }
        g
    }

    fn forces(&mut self, geo: &[Option<Geometry>], sa: &BodyState, sb: &BodyState) -> Forces {
        let ii = (
            self.d.0.inv_inertia_world(sa),
            self.d.1.inv_inertia_world(sb),
        );
        let mut out = Forces {
            per_pair: vec![(Vector3::zeros(), 0.0, f64::NEG_INFINITY); self.pairs.len()],
            on_b: Vector3::zeros(),
            torque: (Vector3::zeros(), Vector3::zeros()),
            ii,
            link: (Vector3::zeros(), Vector3::zeros(), Vector3::zeros()),
            legs: None,
            link_on_b: Vector3::zeros(),
        };
        let (c, t) = if self.link.chaser_is_b {
            ((self.d.1, sb), (self.d.0, sa))
        } else {
            ((self.d.0, sa), (self.d.1, sb))
        };
        if let Some((f, m, fs, p, legs)) = link_wrench(self.link, c, t, self.tau_s) {
            out.legs = legs;
            let fc = f + fs;
            // On the chaser: fc at p and the couple m; on the target the opposite.
            let tc = (p - c.1.pos_m).cross(&fc) + m;
            let tt = (p - t.1.pos_m).cross(&(-fc)) - m;
            if self.link.chaser_is_b {
                out.on_b += fc;
                out.torque.1 += tc;
                out.torque.0 += tt;
            } else {
                out.on_b -= fc;
                out.torque.0 += tc;
                out.torque.1 += tt;
            }
            out.link = (f, m, fs);
            out.link_on_b = if self.link.chaser_is_b { fc } else { -fc };
        }
        for k in self.candidates {
            let Some(g) = geo[*k].as_ref().filter(|g| g.depth > 0.0) else {
                continue;
            };
            let pair = &mut self.pairs[*k];
            if !pair.in_contact {
                // First touch: the approach speed the Lankarani–Nikravesh λ is based on.
                let v_rel = point_vel(sb, &g.point) - point_vel(sa, &g.point);
                pair.impact_speed_m_s = (-v_rel.dot(&g.normal)).max(0.0);
            }
            let (f, fnorm, raw) = pair_force(
                self.law,
                self.mu,
                pair,
                g,
                self.d,
                (sa, sb),
                (&out.ii.0, &out.ii.1),
                self.half_h,
            );
            out.per_pair[*k] = (f, fnorm, raw);
            out.on_b += f;
            out.torque.0 += (g.point - sa.pos_m).cross(&(-f));
            out.torque.1 += (g.point - sb.pos_m).cross(&f);
        }
        out
    }
}

/// Advances a body's position and attitude by `h` at its current velocities (torque-free
/// rotation).
fn drift(dy: &Dyn, s: &mut BodyState, h: f64) {
    if dy.fixed {
        return;
    }
    s.pos_m += s.vel_m_s * h;
    let (att, om) = super::rotate_rk4(
        &s.att,
        &s.omega_rad_s,
        &Vector3::zeros(),
        &dy.j,
        &dy.j_inv_body,
        h,
    );
    s.att = att;
    s.omega_rad_s = om.component_mul(&dy.rot_mask);
}

/// Held wrenches of the two bodies: (force a, torque a, force b, torque b).
type Held = (Vector3<f64>, Vector3<f64>, Vector3<f64>, Vector3<f64>);

/// Half-kicks both bodies with the held wrenches and the contact forces `f`.
fn kick_both(
    d: (&Dyn, &Dyn),
    s: (&mut BodyState, &mut BodyState),
    held: &Held,
    f: &Forces,
    h: f64,
) {
    kick(
        d.0,
        s.0,
        &f.ii.0,
        &(held.0 - f.on_b),
        &(held.1 + f.torque.0),
        h,
    );
    kick(
        d.1,
        s.1,
        &f.ii.1,
        &(held.2 + f.on_b),
        &(held.3 + f.torque.1),
        h,
    );
}

/// The two docking bodies at the start of a step: their integration data, states, poses, held
/// wrenches, and the relative speed and acceleration the window and the sub-step size bound.
struct StepStart<'a> {
    /// Integration data of a and b.
    d: (Dyn, Dyn),
    /// States of a and b at the start of the step.
    s: (&'a BodyState, &'a BodyState),
    /// Body poses of a and b then, world.
    pose: (Isometry3<f64>, Isometry3<f64>),
    /// The wrenches held over the step.
    held: Held,
    /// |v_b − v_a|, m/s.
    v_rel: f64,
    /// |a_b − a_a| from the held forces, m/s².
    acc_rel: f64,
}

impl<'a> StepStart<'a> {
    /// The bodies a and b (body, state, wrench) as rapier's `world` holds them.
    fn new(
        world: &rp::PhysicsWorld,
        (ba, sa0, wa): (&SimBody, &'a BodyState, &Wrench),
        (bb, sb0, wb): (&SimBody, &'a BodyState, &Wrench),
    ) -> Self {
        let da = Dyn::new(ba, world.bodies.get(ba.handle));
        let db = Dyn::new(bb, world.bodies.get(bb.handle));
        let pose = (sa0.body_pose(&da.com), sb0.body_pose(&db.com));
        let held: Held = (
            (wa.force_n + wa.gravity_n).component_mul(&da.lin_mask),
            wa.torque_nm,
            (wb.force_n + wb.gravity_n).component_mul(&db.lin_mask),
            wb.torque_nm,
        );
        let v_rel = (sb0.vel_m_s - sa0.vel_m_s).norm();
        let acc_rel = (held.2 * db.inv_m - held.0 * da.inv_m).norm();
        StepStart {
            d: (da, db),
            s: (sa0, sb0),
            pose,
            held,
            v_rel,
            acc_rel,
        }
    }

    /// (chaser, target), each (integration data, state at the start of the step).
    fn chaser_target(&self, chaser_is_b: bool) -> ((&Dyn, &BodyState), (&Dyn, &BodyState)) {
        if chaser_is_b {
            ((&self.d.1, self.s.1), (&self.d.0, self.s.0))
        } else {
            ((&self.d.0, self.s.0), (&self.d.1, self.s.1))
        }
    }
}

/// Bounds on one body's angular velocity over a free-flight step under its held torque
/// (Euler's equations, [`super::motion`]): Ω on |ω|, and W_k on its body-frame components along
/// the principal axes e_k (columns of `axes`), each inflated for RK4 as the monitor's paths are
/// ([`super::motion::BodyPath::omega_components`]).
#[derive(Debug, Clone, Copy)]
struct SpinBound {
    /// Ω, rad/s.
    om: f64,
    /// Principal axes, body frame (unit columns).
    axes: Matrix3<f64>,
    /// W_k, rad/s.
    w: [f64; 3],
}

impl SpinBound {
    /// Both bodies' bounds over a step of `dt` (s) from `start`; `None` if either body has a
    /// rotation lock (its constraint torque is not in Euler's equations). A fixed body does
    /// not turn.
    fn pair(start: &StepStart, dt: f64) -> Option<[SpinBound; 2]> {
        let one = |d: &Dyn, s: &BodyState, torque: &Vector3<f64>| {
            if d.fixed {
                return Some(SpinBound {
                    om: 0.0,
                    axes: Matrix3::identity(),
                    w: [0.0; 3],
                });
            }
            if d.rot_mask != Vector3::repeat(1.0) {
                return None;
            }
            let (axes, lam) = super::motion::principal_axes(&d.j);
            let w0b = s.att.inverse() * s.omega_rad_s;
            let jw = d.j * w0b;
            let (l0, two_e) = (jw.norm(), w0b.dot(&jw));
            let tq = torque.norm();
            let om = super::motion::omega_bound_euler(lam, l0, two_e, tq, dt)
                .max(s.omega_rad_s.norm())
                * super::motion::RK4_INFLATION;
            let v = super::motion::omega_components_euler(lam, l0, two_e, tq, dt);
            let slack = (super::motion::RK4_INFLATION - 1.0) * om;
            let mut w = [0.0; 3];
            for (k, wk) in w.iter_mut().enumerate() {
                *wk = (v[k].max(w0b.dot(&axes.column(k)).abs()) + slack).min(om);
            }
            (om.is_finite() && w.iter().all(|x| x.is_finite())).then_some(SpinBound { om, axes, w })
        };
        let (sa, sb) = start.s;
        Some([
            one(&start.d.0, sa, &start.held.1)?,
            one(&start.d.1, sb, &start.held.3)?,
        ])
    }

    /// Bound on |ω_b × x| over the step for a body-frame vector x: min(Ω|x|, Σ_k W_k|e_k × x|).
    fn cross(&self, x: &Vector3<f64>) -> f64 {
        let spread: f64 = (0..3)
            .map(|k| self.w[k] * self.axes.column(k).cross(x).norm())
            .sum();
        (self.om * x.norm()).min(spread)
    }
}

/// The revolved reach of pair `p` over a step of `dt` (s) ([`CompliantContact::window`]):
/// 3·(|v_rel| + T_a + T_b)·dt + |a_rel|·dt² + 1 mm + s_a + s_b, with, for a faceted solid of
/// revolution (centre c on its axis â, radius ρ about c, offset s), T = |ω × (c − x_cm)| +
/// |ω − (ω·â)â|·ρ bounded over the step by `b` ([`SpinBound::cross`]), and for any other part
/// T = |ω₀|·R and s = 0, as in the full reach. Its solid of revolution moves rigidly at
/// v(c) + ω′ × (x − c) (`monitor::part_pair_rates`), and the part is within s of it.
fn revolved_reach(start: &StepStart, p: &CompliantPair, b: &[SpinBound; 2], dt: f64) -> f64 {
    let (sa0, sb0) = start.s;
    let (pose_a, pose_b) = start.pose;
    let side = |f: &Option<Faceted>,
                d: &Dyn,
                s: &BodyState,
                sb: &SpinBound,
                pose: &Isometry3<f64>,
                part: &Isometry3<f64>,
                radius: f64| match f {
        Some(f) => (
            sb.cross(&(f.centre_body_m - d.com)) + sb.cross(&f.axis) * f.radius_m,
            f.offset_m,
        ),
        None => {
            let r = ((pose * part).translation.vector - s.pos_m).norm() + radius;
            (s.omega_rad_s.norm() * r, 0.0)
        }
    };
    let (ta, oa) = side(
        &p.faceted.0,
        &start.d.0,
        sa0,
        &b[0],
        &pose_a,
        &p.poses.0,
        p.radii.0,
    );
    let (tb, ob) = side(
        &p.faceted.1,
        &start.d.1,
        sb0,
        &b[1],
        &pose_b,
        &p.poses.1,
        p.radii.1,
    );
    3.0 * (start.v_rel + ta + tb) * dt + start.acc_rel * dt * dt + 1e-3 + oa + ob
}

/// Per-pair sums over one step (indexed as [`CompliantContact::pairs`]).
struct PairTally {
    /// Impulse on part b, world, N·s.
    impulse: Vec<Vector3<f64>>,
    /// Largest contact force on b, N.
    peak: Vec<f64>,
    /// The pair touched in the step.
    touched: Vec<bool>,
}

impl PairTally {
    /// Adds each candidate pair's impulse over a sub-step of `h` (s), the trapezoidal rule on
    /// the forces at its start and end `f`.
    fn add_impulses(&mut self, candidates: &[usize], f: (&Forces, &Forces), h: f64) {
        for k in candidates {
            let j = (f.0.per_pair[*k].0 + f.1.per_pair[*k].0) * (0.5 * h);
            self.impulse[*k] += j;
            self.touched[*k] |= j.norm() > 0.0;
        }
    }
}

/// What the kick–drift–kick loop leaves for the end of the step.
struct Integrated {
    /// States of a and b at the end of the step.
    s: (BodyState, BodyState),
    /// Per-pair sums.
    tally: PairTally,
    /// Angular impulses of the contact and link forces about the centres of mass of a and b,
    /// world, N·m·s.
    ang: (Vector3<f64>, Vector3<f64>),
    /// The link's impulse on b, world, N·s.
    link_imp_b: Vector3<f64>,
}

/// The end of one sub-step, for the contact bookkeeping ([`track_contacts`]).
struct SubstepEnd<'a> {
    /// Simulated time at the start of the step, s.
    t_step: f64,
    /// End of the sub-step, s from the start of the step.
    t_end: f64,
    /// The sub-step, s.
    h: f64,
    /// Contact geometry per pair then.
    geo: &'a [Option<Geometry>],
    /// The forces then.
    f: &'a Forces,
    /// States of a and b then.
    s: (&'a BodyState, &'a BodyState),
    /// The law's floor on the approach speed of a listed impact, m/s.
    min_impact: f64,
}

impl CompliantContact {
    /// The window check and, when a pair can touch within the step, the sub-stepped motion of
    /// both bodies over `dt`, which the physics step then uses instead of the free-flight update
    /// (or, if rapier holds one of the bodies this step, discards: the model's mean wrench has
    /// then been added to rapier's forces). Called after the wrenches were handed to rapier and
    /// before its step. The phases of the module's "One step": `window`, `substep_count`,
    /// `integrate`, then the step's results.
    pub fn pre_step(
        &mut self,
        q: &Query<(&SimBody, &mut BodyState, &mut Wrench)>,
        world: &mut rp::PhysicsWorld,
        dt: f64,
    ) -> Option<Substepped> {
        self.step.clear();
        self.samples.clear();
        self.b_force_history.clear();
        self.impacts.clear();
        self.step_contact_s = 0.0;
        self.link_step = LinkStep::default();
        self.platform_step = PlatformStep::default();
        let link_on = self.link.latch.is_some()
            || self.link.separation.is_some()
            || self.link.platform.is_some();
        if !self.enabled && !link_on {
            return None;
        }
        let [a, b] = q.get_many([self.bodies.0, self.bodies.1]).ok()?;
        let handles = (a.0.handle, b.0.handle);
        let start = StepStart::new(world, a, b);
        // 1. Window.
        let (candidates, r_max) = self.window(&start, dt);
        if candidates.is_empty() && !link_on {
            return None;
        }
        // 2. Sub-step size.
        let (n, v_bound) = self.substep_count(&start, &candidates, r_max, dt);
        let h = dt / f64::from(n);
        // 3. Kick–drift–kick.
        let run = self.integrate(&start, &candidates, (n, h), v_bound);
        let (sa, sb) = run.s;
        // Per-pair results, and the mean wrench for rapier's step (used only if rapier holds a
        // docking body this step).
        let mut mean_f = self.record_pairs(&run.tally, dt);
        self.end_platform(&start, (&sa, &sb), dt);
        if link_on {
            mean_f += run.link_imp_b / dt;
            self.end_separation(&start, (&sa, &sb));
        }
        if mean_f.norm() > 0.0 {
            add_mean_wrench(world, handles, mean_f, run.ang, dt);
        }
        Some(vec![(self.indices.0, sa), (self.indices.1, sb)])
    }

    /// Phase 1, the window: the pairs that can touch within the step of `dt` (s) — in contact, or whose
    /// bounding spheres' gap and then parry's exact distance are within
    /// 3·(|v_rel| + |ω_a|·R_a + |ω_b|·R_b)·dt + |a_rel|·dt² + 1 mm — and the largest lever arms
    /// (R_a, R_b) of those pairs, m. Every other pair's last depth is reset to −∞.
    ///
    /// A faceted solid of revolution (the docking cone's hull) spinning about its own axis
    /// moves its facets, but its solid of revolution stays put, and that lies within the
    /// part's offset s of it ([`crate::geometry::revolution`]). So a pair is first judged with
    /// the smaller of that reach and [`Self::revolved_reach`]'s, in which such a part's
    /// |ω|·R is replaced by the motion of its solid of revolution and its offset added. If no
    /// pair is then within reach, the bodies fly free over the step (under the held wrenches
    /// only, which the revolved reach bounds). If one is, a contact may act within the step
    /// and change the spin, and every pair is judged again with the reach above alone.
    fn window(&mut self, start: &StepStart, dt: f64) -> (Vec<usize>, (f64, f64)) {
        let (sa0, sb0) = start.s;
        let (pose_a, pose_b) = start.pose;
        let (v_rel, acc_rel) = (start.v_rel, start.acc_rel);
        // A pair in contact makes the step a contact step: the full reach alone.
        let mut spins: Option<Option<[SpinBound; 2]>> =
            self.pairs.iter().any(|p| p.in_contact).then_some(None);
        // Per pair within the full reach by its sphere gap: (index, within the revolved reach
        // (Some) or not yet known (None, its distance not yet computed), full reach, lever arms).
        let mut near: Vec<(usize, Option<bool>, f64, f64, f64)> = Vec::new();
        for (k, p) in self.pairs.iter().enumerate().filter(|_| self.enabled) {
            let ca = pose_a * p.poses.0;
            let cb = pose_b * p.poses.1;
            let ra = (ca.translation.vector - sa0.pos_m).norm() + p.radii.0;
            let rb = (cb.translation.vector - sb0.pos_m).norm() + p.radii.1;
            let reach =
                3.0 * (v_rel + sa0.omega_rad_s.norm() * ra + sb0.omega_rad_s.norm() * rb) * dt
                    + acc_rel * dt * dt
                    + 1e-3;
            if p.in_contact {
                near.push((k, Some(true), reach, ra, rb));
                continue;
            }
            let lb = (ca.translation.vector - cb.translation.vector).norm() - p.radii.0 - p.radii.1;
            if lb > reach {
                continue;
            }
            // The revolved reach drops the spin terms and adds the offsets: it can only be
            // smaller when the spin terms are larger.
            let spin_terms = 3.0 * (sa0.omega_rad_s.norm() * ra + sb0.omega_rad_s.norm() * rb) * dt;
            let offsets =
                p.faceted.0.map_or(0.0, |f| f.offset_m) + p.faceted.1.map_or(0.0, |f| f.offset_m);
            let mut reach_min = reach;
            if offsets > 0.0 && spin_terms > offsets {
                let bounds = *spins.get_or_insert_with(|| SpinBound::pair(start, dt));
                if let Some(b) = bounds {
                    reach_min = reach.min(revolved_reach(start, p, &b, dt));
                }
            }
            if lb > reach_min {
                // Out of the revolved reach: its distance only matters if another pair is in.
                near.push((k, None, reach, ra, rb));
                continue;
            }
            let d = super::monitor::shape_distance(&ca, &*p.shapes.0, &cb, &*p.shapes.1);
            if d <= reach {
                near.push((k, Some(d <= reach_min), reach, ra, rb));
            }
        }
        // No pair within the revolved reach: free flight. Otherwise every pair within the
        // full reach (a contact within the step may change the spin).
        let mut candidates: Vec<usize> = Vec::new();
        let mut r_max: (f64, f64) = (0.0, 0.0);
        if near.iter().any(|n| n.1 == Some(true)) {
            for &(k, within, reach, ra, rb) in &near {
                let keep = within.is_some() || {
                    let p = &self.pairs[k];
                    let (ca, cb) = (pose_a * p.poses.0, pose_b * p.poses.1);
                    super::monitor::shape_distance(&ca, &*p.shapes.0, &cb, &*p.shapes.1) <= reach
                };
                if keep {
                    candidates.push(k);
                    r_max = (r_max.0.max(ra), r_max.1.max(rb));
                }
            }
        }
        for (k, p) in self.pairs.iter_mut().enumerate() {
            if !candidates.contains(&k) {
                p.last_depth_m = f64::NEG_INFINITY;
            }
        }
        (candidates, r_max)
    }

    /// Phase 2, the sub-step count N = ⌈dt/h_max⌉ of a step of `dt` (s), at most [`MAX_SUBSTEPS`] (a
    /// capped step is counted), with the run statistics: h_max is the shortest of dt, the
    /// latch's, the platform's and the separation springs' limits and the contact's period at
    /// the stiffest the step can reach over `substeps_per_period`. Returns N and the bound on
    /// the speed of the candidate pairs' points relative to each other, m/s.
    fn substep_count(
        &mut self,
        start: &StepStart,
        candidates: &[usize],
        r_max: (f64, f64),
        dt: f64,
    ) -> (u32, f64) {
        let (da, db) = (&start.d.0, &start.d.1);
        let (sa0, sb0) = start.s;
        let (pose_a, pose_b) = start.pose;
        let (v_rel, acc_rel) = (start.v_rel, start.acc_rel);
        let w_red = da.inv_m + db.inv_m;
        let m_red = if w_red > 0.0 { 1.0 / w_red } else { 1e30 };
        let m_min = 1.0
            / (w_red
                + r_max.0 * r_max.0 * da.inv_inertia_bound()
                + r_max.1 * r_max.1 * db.inv_inertia_bound())
            .max(1e-30);
        let v_bound = v_rel + sa0.omega_rad_s.norm() * r_max.0 + sb0.omega_rad_s.norm() * r_max.1;
        let depth_now = candidates
            .iter()
            .filter(|k| self.pairs[**k].in_contact)
            .filter_map(|k| pair_geometry(&self.pairs[*k], &pose_a, &pose_b, 0.0))
            .map(|g| g.depth)
            .fold(0.0, f64::max);
        let depth_bound = self
            .law
            .depth_bound_m(m_red, v_bound, m_red * acc_rel)
            .max(2.0 * depth_now);
        let mut h_max = dt;
        let k_loc = self.law.local_stiffness_n_m(depth_bound);
        if let Some(l) = &self.link.latch {
            h_max = self.latch_h_max(h_max, l, start, w_red);
        }
        if let Some(pl) = &self.link.platform {
            h_max = self.platform_h_max(h_max, pl, start, w_red);
        }
        if let Some(sp) = &self.link.separation {
            // The spring's force ends with a step at the end of its stroke: sub-steps short
            // enough to cross it within 0.5 % of the stroke.
            let a = sp.force_n.max(sp.preload_n) * w_red;
            h_max = h_max.min(0.005 * sp.stroke_m / (v_rel + a * dt).max(1e-9));
        }
        if k_loc > 0.0 && !candidates.is_empty() {
            let period = 2.0 * std::f64::consts::PI * (m_min / k_loc).sqrt();
            h_max = h_max.min(period / f64::from(self.substeps_per_period));
        }
        let mut n = (dt / h_max).ceil().max(1.0);
        if n.is_nan() || n > f64::from(MAX_SUBSTEPS) {
            n = f64::from(MAX_SUBSTEPS);
            self.stats.capped_steps += 1;
        }
        let n = n as u32;
        self.stats.steps_substepped += 1;
        self.stats.substeps += u64::from(n);
        self.stats.max_substeps_per_step = self.stats.max_substeps_per_step.max(n);
        (n, v_bound)
    }

    /// `h_max` (s) within the latch's periods: translation at the port (the smallest effective
    /// mass there, `w_red` the pair's summed inverse masses, 1/kg), rotation (the smallest
    /// inertia); explicit damping within a fifth of its time constant.
    fn latch_h_max(&self, h_max: f64, l: &LatchSpring, start: &StepStart, w_red: f64) -> f64 {
        let (da, db) = (&start.d.0, &start.d.1);
        let r = |d: &Dyn, s: &BodyState, port: &Vector3<f64>| {
            (s.body_pose(&d.com).transform_point(&(*port).into()).coords - s.pos_m).norm()
        };
        let ((dc, sc), (dtg, stg)) = start.chaser_target(self.link.chaser_is_b);
        let rc = r(dc, sc, &l.port_c_body_m);
        let port_t = l.caught.transform_point(&l.port_c_body_m.into()).coords;
        let rt = r(dtg, stg, &port_t);
        let m_port = 1.0
            / (w_red + rc * rc * dc.inv_inertia_bound() + rt * rt * dtg.inv_inertia_bound())
                .max(1e-30);
        let i_min = 1.0 / (da.inv_inertia_bound() + db.inv_inertia_bound()).max(1e-30);
        let j = &l.spec;
        let tau = std::f64::consts::TAU;
        h_max
            .min(tau * (m_port / j.stiffness_n_m).sqrt() / f64::from(self.substeps_per_period))
            .min(
                tau * (i_min / j.rot_stiffness_nm_rad).sqrt() / f64::from(self.substeps_per_period),
            )
            .min(0.2 * m_port / j.damping_n_s_m)
            .min(0.2 * i_min / j.rot_damping_nm_s_rad)
    }

    /// `h_max` (s) within the platform's stiffest mode (every leg and its stop together,
    /// K = n·(k + k_stop)) at the smallest effective mass of the pair at any attach point
    /// (lever arms from the centres of mass to the port and ring origins plus the attach
    /// radii; `w_red` the pair's summed inverse masses, 1/kg), and a fifth of the fastest
    /// damping time constant (the damping is explicit).
    fn platform_h_max(&self, h_max: f64, pl: &PlatformLink, start: &StepStart, w_red: f64) -> f64 {
        let ((dc, sc), (dtg, stg)) = start.chaser_target(self.link.chaser_is_b);
        let (base, ring) = pl.base_and_ring((&dc.com, sc), (&dtg.com, stg));
        let rho_b = pl
            .platform
            .legs
            .iter()
            .map(|l| l.base_p_m.norm())
            .fold(0.0_f64, f64::max);
        let rho_r = pl
            .platform
            .legs
            .iter()
            .map(|l| l.ring_r_m.norm())
            .fold(0.0_f64, f64::max);
        let rc = (base.pose.translation.vector - sc.pos_m).norm() + rho_b;
        let rt = (ring.pos_m - stg.pos_m).norm() + rho_r;
        let m_leg = 1.0
            / (w_red + rc * rc * dc.inv_inertia_bound() + rt * rt * dtg.inv_inertia_bound())
                .max(1e-30);
        let sp = &pl.platform.spec;
        let n_legs = pl.platform.legs.len() as f64;
        let k_max = n_legs * (sp.stiffness_n_m + sp.stop_stiffness_n_m);
        h_max
            .min(std::f64::consts::TAU * (m_leg / k_max).sqrt() / f64::from(sp.substeps_per_period))
            .min(0.2 * m_leg / (n_legs * sp.damping_n_s_m))
    }

    /// Phase 3, kick–drift–kick over `n` sub-steps of `h` (s), from the start of the step: the link's
    /// and the platform's loads, each pair's impulse and contact bookkeeping, and this step's
    /// samples, impacts and contact time. `v_bound` (m/s) sets the prediction distance.
    fn integrate(
        &mut self,
        start: &StepStart,
        candidates: &[usize],
        (n, h): (u32, f64),
        v_bound: f64,
    ) -> Integrated {
        let (mut sa, mut sb) = (start.s.0.clone(), start.s.1.clone());
        let npairs = self.pairs.len();
        let mut tally = PairTally {
            impulse: vec![Vector3::zeros(); npairs],
            peak: vec![0.0f64; npairs],
            touched: vec![false; npairs],
        };
        let (mut ang_a, mut ang_b) = (Vector3::zeros(), Vector3::zeros());
        let t_step = self.t_step_s;
        let (law, mu) = (self.law, self.mu);
        let min_impact = law.min_impact_speed_m_s;
        let mut st = Stepper {
            law: &law,
            mu,
            pairs: &mut self.pairs,
            candidates,
            d: (&start.d.0, &start.d.1),
            half_h: 0.5 * h,
            // Enough to see each contact coming one sub-step ahead (its start and end are
            // interpolated from the depths on either side).
            prediction_m: 2.0 * v_bound * h + 1e-6,
            link: &self.link,
            tau_s: 0.0,
        };
        // The force at the start of the step (damping implicit over the first half-kick); then
        // per sub-step: half-kick with it, drift, the force at the new poses from the half-step
        // velocities with its damping implicit over the second half-kick, which makes it the
        // force at the end of the sub-step and the next sub-step's first kick. For the damping
        // this is the trapezoidal rule (second order, A-stable).
        let geo = st.geometry(&sa, &sb);
        let mut f0 = st.forces(&geo, &sa, &sb);
        if let Some(l) = &f0.legs {
            // The legs at the start of the step too (the first step after the capture starts
            // with the dampers' largest force).
            note_legs(&mut self.platform_step, l);
        }
        let mut link_imp_b = Vector3::zeros();
        for i in 0..n {
            let (geo, f1) = substep_motion(&mut st, (&mut sa, &mut sb), &start.held, &f0, (i, h));
            ang_a += (f0.torque.0 + f1.torque.0) * (0.5 * h);
            ang_b += (f0.torque.1 + f1.torque.1) * (0.5 * h);
            link_imp_b += (f0.link_on_b + f1.link_on_b) * (0.5 * h);
            note_link(&mut self.link_step, &f1);
            if let Some(l) = &f1.legs {
                note_legs(&mut self.platform_step, l);
                self.platform_step.end = Some(l.clone());
            }
            tally.add_impulses(candidates, (&f0, &f1), h);
            f0 = f1;
            let end = SubstepEnd {
                t_step,
                t_end: f64::from(i + 1) * h,
                h,
                geo: &geo,
                f: &f0,
                s: (&sa, &sb),
                min_impact,
            };
            if let Some(total) = track_contacts(
                st.pairs,
                candidates,
                &end,
                &mut tally,
                &mut self.samples,
                &mut self.impacts,
            ) {
                self.step_contact_s += h;
                self.b_force_history.push((h, total));
            }
        }
        Integrated {
            s: (sa, sb),
            tally,
            ang: (ang_a, ang_b),
            link_imp_b,
        }
    }

    /// The pairs that touched in the step, in [`Self::step`]; returns the mean contact force on
    /// b over the step of `dt` (s), world, N.
    fn record_pairs(&mut self, tally: &PairTally, dt: f64) -> Vector3<f64> {
        let mut mean_f = Vector3::zeros();
        for k in 0..self.pairs.len() {
            if tally.touched[k] {
                self.step.push(PairStep {
                    pair: k,
                    impulse_on_b_ns: tally.impulse[k],
                    peak_force_n: tally.peak[k],
                    in_contact_at_end: self.pairs[k].in_contact,
                });
                mean_f += tally.impulse[k] / dt;
            }
        }
        mean_f
    }

    /// The platform at the end of the step of `dt` (s), with the end states of a and b: the
    /// ring's pose in P, and the retraction advanced.
    fn end_platform(&mut self, start: &StepStart, (sa, sb): (&BodyState, &BodyState), dt: f64) {
        let (da, db) = (&start.d.0, &start.d.1);
        if let Some(pl) = self.link.platform.as_mut() {
            let (c, t) = if self.link.chaser_is_b {
                ((&db.com, sb), (&da.com, sa))
            } else {
                ((&da.com, sa), (&db.com, sb))
            };
            let (base, ring) = pl.base_and_ring(c, t);
            self.platform_step.ring_in_base = Some(pl.platform.ring_pose_in_base(&base, &ring));
            pl.retraction_m = pl.retraction_at(dt);
        }
    }

    /// Separation springs at the end of their stroke (with the end states of a and b) rest on
    /// their stops from now on.
    fn end_separation(&mut self, start: &StepStart, (sa, sb): (&BodyState, &BodyState)) {
        let (da, db) = (&start.d.0, &start.d.1);
        if let Some(sp) = &self.link.separation {
            let (sc, stg, dc, dtg) = if self.link.chaser_is_b {
                (sb, sa, db, da)
            } else {
                (sa, sb, da, db)
            };
            let (pc_b, pt_b, at_b) = sp.ports_body_m;
            let p = sc.body_pose(&dc.com).transform_point(&pc_b.into()).coords;
            let pose_t = stg.body_pose(&dtg.com);
            let pt = pose_t.transform_point(&pt_b.into()).coords;
            if (p - pt).dot(&(pose_t.rotation * at_b)) - sp.x0_m >= sp.stroke_m {
                self.link.separation = None;
                self.link_step.separation_ended = true;
            }
        }
    }
}

/// The model's mean wrench over the step of `dt` (s) added to rapier's forces on the bodies
/// `handles` (a, b): `mean_f` on b and its opposite on a (N, world), the angular impulses `ang`
/// (N·m·s) over dt as torques. It matters only if rapier holds a docking body this step.
fn add_mean_wrench(
    world: &mut rp::PhysicsWorld,
    handles: (rp::RigidBodyHandle, rp::RigidBodyHandle),
    mean_f: Vector3<f64>,
    (ang_a, ang_b): (Vector3<f64>, Vector3<f64>),
    dt: f64,
) {
    if let Some(rb) = world.bodies.get_mut(handles.0) {
        rb.add_force(conv::v(&(-mean_f)), true);
        rb.add_torque(conv::v(&(ang_a / dt)), true);
    }
    if let Some(rb) = world.bodies.get_mut(handles.1) {
        rb.add_force(conv::v(&mean_f), true);
        rb.add_torque(conv::v(&(ang_b / dt)), true);
    }
}

/// The link's peaks (force N, moment N·m on the chaser at its port) and end values updated with
/// the forces `f1` at the end of a sub-step.
fn note_link(ls: &mut LinkStep, f1: &Forces) {
    ls.peak_force_n = ls.peak_force_n.max(f1.link.0.norm());
    ls.peak_moment_nm = ls.peak_moment_nm.max(f1.link.1.norm());
    ls.force_end_n = f1.link.0;
    ls.moment_end_nm = f1.link.1;
}

/// The platform's leg peaks (|force| N, |stroke| m) updated with the legs `l`.
fn note_legs(ps: &mut PlatformStep, l: &crate::contact::platform::PlatformLoads) {
    for leg in &l.legs {
        ps.peak_leg_force_n = ps.peak_leg_force_n.max(leg.force_n.abs());
        ps.peak_leg_stroke_m = ps.peak_leg_stroke_m.max(leg.stroke_m.abs());
    }
}

/// One sub-step `i` of `h` (s): half-kick both bodies with the held wrenches and the forces
/// `f0`, drift, the contact geometry and forces at the new poses, and the second half-kick with
/// those. Returns that geometry and those forces (the end of the sub-step's).
fn substep_motion(
    st: &mut Stepper,
    (sa, sb): (&mut BodyState, &mut BodyState),
    held: &Held,
    f0: &Forces,
    (i, h): (u32, f64),
) -> (Vec<Option<Geometry>>, Forces) {
    let (da, db) = st.d;
    kick_both((da, db), (&mut *sa, &mut *sb), held, f0, 0.5 * h);
    drift(da, sa, h);
    drift(db, sb, h);
    let geo = st.geometry(sa, sb);
    st.tau_s = f64::from(i + 1) * h;
    let mut f1 = st.forces(&geo, sa, sb);
    if st.link.platform.is_some() {
        // The platform's dampers need the end-of-sub-step velocities: one fixed-point
        // iteration of the implicit half-kick (a trial half-kick with the force at the
        // half-step velocities, then the force at the trial velocities), as
        // `Platform::advance` does, keeps the damping second order. (The docking
        // contact is off while the platform carries the chaser, so only the link's
        // forces are evaluated twice.)
        let (ta, tb) = (sa.clone(), sb.clone());
        kick_both((da, db), (&mut *sa, &mut *sb), held, &f1, 0.5 * h);
        f1 = st.forces(&geo, sa, sb);
        (*sa, *sb) = (ta, tb);
    }
    kick_both((da, db), (sa, sb), held, &f1, 0.5 * h);
    (geo, f1)
}

/// The contact bookkeeping of the candidate pairs at the end of a sub-step `e`: a pair in
/// contact (penetrating and pushing) adds to the tally and the samples, its first touch
/// noting when the contact began; a pair that stopped touching ends its contact, listed as an
/// impact if it began fast enough ([`impact_record`]). Returns the total contact force on b
/// (N, world) if any pair touched.
fn track_contacts(
    pairs: &mut [CompliantPair],
    candidates: &[usize],
    e: &SubstepEnd,
    tally: &mut PairTally,
    samples: &mut Vec<ForceSample>,
    impacts: &mut Vec<ImpactRecord>,
) -> Option<Vector3<f64>> {
    let (t_step, t_end, h) = (e.t_step, e.t_end, e.h);
    let mut total = Vector3::zeros();
    let mut any = false;
    for k in candidates {
        let k = *k;
        let pair = &mut pairs[k];
        let was = pair.in_contact;
        let d_now = e.geo[k].as_ref().map_or(f64::NEG_INFINITY, |g| g.depth);
        let (fv, fnorm, f_raw) = e.f.per_pair[k];
        // In contact: penetrating and pushing (a dashpot's force vanishes before the
        // depth does: the surfaces separate there).
        let is_now = d_now > 0.0 && f_raw > 0.0;
        let frac = crossing_fraction(pair, d_now, f_raw);
        if is_now {
            let g = e.geo[k].as_ref().expect("depth from a geometry");
            if !was {
                pair.start_s = t_step + t_end - h + frac * h;
            }
            any = true;
            tally.touched[k] = true;
            total += fv;
            tally.peak[k] = tally.peak[k].max(fv.norm());
            pair.contact_peak_n = pair.contact_peak_n.max(fnorm);
            pair.in_contact = true;
            pair.last_contact = Some((g.point, g.normal));
            samples.push(ForceSample {
                t_in_step_s: t_end,
                pair: k,
                point_m: g.point,
                normal_on_b: g.normal,
                depth_m: g.depth,
                normal_force_n: fnorm,
                force_on_b_n: fv,
                h_s: h,
            });
        } else if was {
            let t_sep = t_step + t_end - h + frac * h;
            if let Some(imp) = impact_record(pair, t_sep, e.s, e.min_impact) {
                impacts.push(imp);
            }
            pair.contact_peak_n = 0.0;
            pair.in_contact = false;
        }
        pair.last_depth_m = d_now;
        pair.last_force_n = f_raw;
    }
    any.then_some(total)
}

/// Where the contact measure of `pair` crossed zero within this sub-step (fraction of h), from
/// its last values to the depth `d_now` (m) and unclamped force `f_raw` (N) now: the unclamped
/// force while both ends penetrate, else the depth.
fn crossing_fraction(pair: &CompliantPair, d_now: f64, f_raw: f64) -> f64 {
    let crossing = |a0: f64, a1: f64| {
        if a0.is_finite() && a1.is_finite() && a0 != a1 {
            (a0 / (a0 - a1)).clamp(0.0, 1.0)
        } else {
            0.0
        }
    };
    if d_now > 0.0 && pair.last_depth_m > 0.0 {
        crossing(pair.last_force_n, f_raw)
    } else {
        crossing(pair.last_depth_m, d_now)
    }
}

/// The impact of a contact of `pair` that ended at `t_sep` (s), with the states of a and b
/// then: the separation speed is the normal speed at the last point of contact. `None` unless
/// the contact began closing at least at the damping's floor speed `min_impact` (m/s): slower
/// touches of a resting or sliding contact are not listed.
fn impact_record(
    pair: &CompliantPair,
    t_sep: f64,
    (sa, sb): (&BodyState, &BodyState),
    min_impact: f64,
) -> Option<ImpactRecord> {
    let sep = pair
        .last_contact
        .map(|(p, n)| (point_vel(sb, &p) - point_vel(sa, &p)).dot(&n));
    let approach = pair.impact_speed_m_s;
    let sep = sep.filter(|_| approach >= min_impact)?;
    Some(ImpactRecord {
        t_start_s: pair.start_s,
        t_end_s: t_sep,
        duration_s: t_sep - pair.start_s,
        a: pair.names.0.clone(),
        b: pair.names.1.clone(),
        approach_m_s: approach,
        separation_m_s: sep,
        restitution: if approach > 0.0 { sep / approach } else { 0.0 },
        peak_normal_force_n: pair.contact_peak_n,
    })
}

/// Counts a step in which rapier held a body the model had sub-stepped (its result discarded).
pub fn note_rapier_held(c: Option<&mut CompliantContact>, sub: &Option<Substepped>, index: usize) {
    if let (Some(c), Some(v)) = (c, sub)
        && v.iter().any(|(i, _)| *i == index)
    {
        c.stats.rapier_held_steps += 1;
    }
}

/// Collision groups that keep rapier from seeing the compliant pairs: the first body's
/// compliant parts and the second body's skip each other and collide with everything else.
fn collision_groups(first: bool) -> rp::InteractionGroups {
    let (me, other) = if first {
        (rp::Group::GROUP_2, rp::Group::GROUP_3)
    } else {
        (rp::Group::GROUP_3, rp::Group::GROUP_2)
    };
    rp::InteractionGroups::new(me, rp::Group::ALL & !other, rp::InteractionTestMode::And)
}

/// Installs the model for a scene whose docking interface is compliant: every docking part of
/// the chaser against every docking part of the target.
pub fn install(app: &mut App, loaded: &LoadedScene) -> Result<(), SceneError> {
    let Some(spec) = &loaded.scene.docking else {
        return Ok(());
    };
    let ContactModelSpec::Compliant(c) = &spec.contact else {
        return Ok(());
    };
    let roster = app.world().resource::<Roster>().clone();
    let idx = |n: &str| {
        roster
            .names
            .iter()
            .position(|x| x == n)
            .expect("validated body")
    };
    let docking_parts = |bi: usize| -> Vec<String> {
        roster.parts[bi]
            .iter()
            .map(|e| app.world().get::<Part>(*e).expect("part"))
            .filter(|p| p.role.is_docking())
            .map(|p| p.name.clone())
            .collect()
    };
    let (ci, ti) = (idx(&spec.chaser), idx(&spec.target));
    let (pc, pt) = (docking_parts(ci), docking_parts(ti));
    let pc: Vec<&str> = pc.iter().map(String::as_str).collect();
    let pt: Vec<&str> = pt.iter().map(String::as_str).collect();
    install_between(
        app,
        c,
        &crate::contact::describe(&spec.contact),
        (&spec.chaser, &pc),
        (&spec.target, &pt),
    )
    .map_err(|m| loaded.error_at("docking.contact.law", m))
}

/// Compliant contact with `spec` between the named parts (collider names) of two bodies, every
/// part of the first against every part of the second; rapier stops seeing those pairs. The
/// docking interface uses it for its cone and slot; tests use it for any two parts. Fails when
/// a name is unknown or the law is too stiff for the step: a 1 m/s head-on impact of the two
/// bodies' reduced mass must be resolvable within [`MAX_SUBSTEPS`] sub-steps of one step.
pub fn install_between(
    app: &mut App,
    spec: &crate::contact::CompliantSpec,
    description: &str,
    first: (&str, &[&str]),
    second: (&str, &[&str]),
) -> Result<(), String> {
    let roster = app.world().resource::<Roster>().clone();
    let idx = |n: &str| {
        roster
            .names
            .iter()
            .position(|x| x == n)
            .ok_or_else(|| format!("no body `{n}`"))
    };
    let (i1, i2) = (idx(first.0)?, idx(second.0)?);
    if i1 == i2 {
        return Err("compliant contact needs two different bodies".into());
    }
    let parts_of = |bi: usize, names: &[&str]| -> Result<Vec<Part>, String> {
        names
            .iter()
            .map(|n| {
                roster.parts[bi]
                    .iter()
                    .map(|e| app.world().get::<Part>(*e).expect("part"))
                    .find(|p| p.name == *n)
                    .cloned()
                    .ok_or_else(|| format!("body `{}` has no part `{n}`", roster.names[bi]))
            })
            .collect()
    };
    let (p1, p2) = (parts_of(i1, first.1)?, parts_of(i2, second.1)?);
    // The bookkeeping orders a pair by body index.
    let ((ia, pa), (ib, pb)) = if i1 < i2 {
        ((i1, p1), (i2, p2))
    } else {
        ((i2, p2), (i1, p1))
    };
    let mut pairs = Vec::new();
    for a in &pa {
        for b in &pb {
            pairs.push(CompliantPair::new(
                (
                    format!("{}/{}", roster.names[ia], a.name),
                    format!("{}/{}", roster.names[ib], b.name),
                ),
                (&a.shape, &a.pose_body, a.bound_radius_m),
                (&b.shape, &b.pose_body, b.bound_radius_m),
            ));
        }
    }
    let law = Law::from_spec(spec);
    let body = |i: usize| {
        app.world()
            .get::<SimBody>(roster.bodies[i])
            .expect("body")
            .clone()
    };
    let (ba, bb) = (body(ia), body(ib));
    let dt = app.world().resource::<super::Clock>().dt_s;
    let m_red = ba.mass_kg * bb.mass_kg / (ba.mass_kg + bb.mass_kg);
    let d = law.depth_bound_m(m_red, 1.0, 0.0);
    let period = 2.0 * std::f64::consts::PI * (m_red / law.local_stiffness_n_m(d)).sqrt();
    let needed = dt * f64::from(spec.substeps_per_period) / period;
    if needed.is_nan() || needed > f64::from(MAX_SUBSTEPS) {
        return Err(format!(
            "too stiff for dt_s = {dt} s: a 1 m/s impact of the two bodies oscillates with a period of {period:.3e} s and would need {needed:.0} sub-steps per step (at most {MAX_SUBSTEPS}); lower the stiffness or dt_s"
        ));
    }
    let friction = |i: usize| {
        app.world()
            .resource::<Physics>()
            .world
            .bodies
            .get(body(i).handle)
            .and_then(|rb| rb.colliders().first().copied())
            .and_then(|h| app.world().resource::<Physics>().world.colliders.get(h))
            .map_or(0.0, |c| f64::from(c.friction()))
    };
    let mu = 0.5 * (friction(ia) + friction(ib));
    {
        let mut phys = app.world_mut().resource_mut::<Physics>();
        for (parts, first_side) in [(&pa, true), (&pb, false)] {
            for p in parts {
                if let Some(c) = phys.world.colliders.get_mut(p.collider) {
                    c.set_collision_groups(collision_groups(first_side));
                }
            }
        }
    }
    app.insert_resource(CompliantContact {
        law,
        description: description.to_string(),
        substeps_per_period: spec.substeps_per_period,
        bodies: (roster.bodies[ia], roster.bodies[ib]),
        indices: (ia, ib),
        mu,
        pairs,
        enabled: true,
        step: Vec::new(),
        samples: Vec::new(),
        b_force_history: Vec::new(),
        step_contact_s: 0.0,
        impacts: Vec::new(),
        stats: SubstepStats::default(),
        t_step_s: 0.0,
        link: Link::default(),
        link_step: LinkStep::default(),
        platform_step: PlatformStep::default(),
    });
    Ok(())
}

#[cfg(test)]
mod tests {
    //! The window's revolved reach against a dense reference: the docking cone's hull (a
    //! 32-gon frustum, as `DockingCone` builds it) spinning at 100 rad/s about its axis, a
    //! principal axis through the centre of mass — torque-free, so the motion is exactly the
    //! screw x₀ + vτ, exp(ωτ)·q₀ — beside a box at gaps from 0.2 mm to 20 mm. Reference: the
    //! distance by parry at 2 000 instants of the step. Whenever the window would drop the pair
    //! (its gap at the start above the reach), the pair must not touch within the step; and
    //! at a 10 mm gap the revolved reach drops a pair that the full reach (3·|ω|·R·dt = 0.78 m)
    //! keeps.
    use super::*;
    use crate::sim::motion::tests::body;

    #[test]
    fn revolved_reach_never_drops_a_pair_that_touches_within_the_step() {
        let mut pts = Vec::new();
        for k in 0..32 {
            let phi = std::f64::consts::TAU * f64::from(k) / 32.0;
            pts.push(rp::Vector::new(
                0.0,
                (0.12 * phi.cos()) as f32,
                (0.12 * phi.sin()) as f32,
            ));
            pts.push(rp::Vector::new(
                0.25,
                (0.03 * phi.cos()) as f32,
                (0.03 * phi.sin()) as f32,
            ));
        }
        let cone = rp::SharedShape::convex_hull(&pts).expect("hull");
        let cone_pose = Isometry3::translation(0.5, 0.0, 0.0);
        let wall = rp::SharedShape::cuboid(0.1, 0.05, 0.1);
        let j = Matrix3::from_diagonal(&Vector3::new(110.0, 140.0, 160.0));
        let (ba, bb) = (body(j), body(Matrix3::identity() * 1e3));
        let dt = 0.01;
        let mut dropped_at_10mm = false;
        for gap_mm in [0.2, 0.5, 1.0, 2.0, 5.0, 10.0, 20.0] {
            for phase in [0.0, 0.03, 0.05, 0.08] {
                let sa = BodyState {
                    pos_m: Vector3::zeros(),
                    vel_m_s: Vector3::new(0.0, 0.0, 0.0),
                    att: nalgebra::UnitQuaternion::from_scaled_axis(Vector3::x() * phase),
                    omega_rad_s: Vector3::new(100.0, 0.0, 0.0),
                };
                // The box's face 0.12 m + gap from the axis, beside the cone's base.
                let sb = BodyState {
                    pos_m: Vector3::new(0.55, 0.12 + gap_mm * 1e-3 + 0.05, 0.0),
                    vel_m_s: Vector3::new(0.0, -0.01, 0.0),
                    att: nalgebra::UnitQuaternion::identity(),
                    omega_rad_s: Vector3::zeros(),
                };
                let p = CompliantPair::new(
                    ("a/cone".into(), "b/wall".into()),
                    (&cone, &cone_pose, 0.25_f64.hypot(0.12)),
                    (
                        &wall,
                        &Isometry3::identity(),
                        Vector3::new(0.1, 0.05, 0.1).norm(),
                    ),
                );
                assert!(p.faceted.0.is_some());
                let start = StepStart {
                    d: (Dyn::new(&ba, None), Dyn::new(&bb, None)),
                    s: (&sa, &sb),
                    pose: (sa.body_pose(&ba.com_body_m), sb.body_pose(&bb.com_body_m)),
                    held: (
                        Vector3::zeros(),
                        Vector3::zeros(),
                        Vector3::zeros(),
                        Vector3::zeros(),
                    ),
                    v_rel: (sb.vel_m_s - sa.vel_m_s).norm(),
                    acc_rel: 0.0,
                };
                let bounds = SpinBound::pair(&start, dt).expect("no locks");
                let reach = revolved_reach(&start, &p, &bounds, dt);
                let full = 3.0 * (start.v_rel + 100.0 * (0.5 + p.radii.0)) * dt;
                let at = |tau: f64| {
                    let qa =
                        nalgebra::UnitQuaternion::from_scaled_axis(sa.omega_rad_s * tau) * sa.att;
                    let pa = Isometry3::from_parts((sa.pos_m + sa.vel_m_s * tau).into(), qa);
                    let pb = Isometry3::translation(
                        sb.pos_m.x + sb.vel_m_s.x * tau,
                        sb.pos_m.y + sb.vel_m_s.y * tau,
                        sb.pos_m.z,
                    );
                    super::super::monitor::shape_distance(&(pa * cone_pose), &*cone, &pb, &*wall)
                };
                let d0 = at(0.0);
                let min = (0..=2000)
                    .map(|k| at(dt * f64::from(k) / 2000.0))
                    .fold(f64::INFINITY, f64::min);
                if d0 > reach {
                    // Dropped: it must not touch (parry's own f32 tolerance, 1e-6 m).
                    assert!(
                        min > -1e-6,
                        "gap {gap_mm} mm, phase {phase}: d0 {d0} > reach {reach} but min {min}"
                    );
                    assert!(
                        min >= d0 - reach,
                        "gap {gap_mm} mm: moved more than the reach"
                    );
                    if gap_mm == 10.0 {
                        dropped_at_10mm = true;
                    }
                }
                assert!(full > d0, "the full reach keeps every one of these pairs");
            }
        }
        assert!(
            dropped_at_10mm,
            "the revolved reach drops a pair 10 mm away"
        );
    }
}
