//! Parts of different bodies that overlap at t = 0.
//!
//! # The check
//! Every collider pair of every body pair is tested, pruned first by bounding spheres (a
//! body's sphere about its origin, then each collider's sphere about its shape origin), so
//! that `rpod check` on a scene at the limits ([`MAX_COLLIDERS`](crate::scene::validate::MAX_COLLIDERS))
//! makes millions of cheap sphere tests and only a few exact parry queries. A pair at zero
//! distance (or closer) is refused, located at the second part, unless one of the two parts
//! says `allow_initial_overlap: true`.
//!
//! # What an allowed overlap does
//! rapier resolves a penetration by pushing the bodies apart with a corrective velocity (up to
//! its `max_corrective_velocity`, 3 m/s by default), which is energy from nowhere: a 300 kg
//! chaser started inside a target was thrown out at about 9 m/s in a hostile-input probe. rpod
//! therefore disables the
//! *solver* contact between every collider pair that overlaps at t = 0, until the pair's exact
//! distance (f64 poses, parry) first becomes positive; from then on the pair collides normally.
//! While suppressed the two parts pass through each other: no force acts between them, so
//! kinetic energy and momentum are exactly those of the bodies' free motion
//! (`tests/val_initial_overlap.rs`), and the monitor keeps reporting their distance (zero while
//! they overlap), so a `MinDistance` guarantee between them is violated from t = 0 — the
//! overlap is not hidden, only left unresolved.
//!
//! The suppression uses rapier's per-collider solver groups (32 bits): at most
//! [`MAX_SUPPRESSED`] colliders may start overlapping another body.

use super::monitor::shape_distance;
use super::{BodyState, Part, Physics, Roster, SimBody};
use crate::scene::parts::PartCollider;
use crate::scene::{LoadedScene, Scene, SceneError};
use bevy::prelude::*;
use bevy_rapier3d::rapier::prelude as rp;
use nalgebra::{Isometry3, Vector3};

/// Most colliders whose contacts can be suppressed at once (one solver-group bit each).
pub const MAX_SUPPRESSED: usize = 32;

/// One collider of the t = 0 check: world pose, shape, bounding radius, and whether it may
/// overlap.
pub(crate) struct Probe<'a> {
    /// The scene's description.
    pub collider: &'a PartCollider,
    /// World pose of the shape frame.
    pub pose: Isometry3<f64>,
    /// rapier shape.
    pub shape: rp::SharedShape,
    /// rapier handle.
    pub handle: rp::ColliderHandle,
    /// Part entity.
    pub entity: Entity,
}

/// A collider pair whose solver contact is off until it first separates.
#[derive(Debug, Clone)]
pub struct SuppressedPair {
    /// Body index and part entity of the first collider.
    pub a: (usize, Entity),
    /// Body index and part entity of the second collider.
    pub b: (usize, Entity),
    /// rapier handles.
    pub handles: (rp::ColliderHandle, rp::ColliderHandle),
    /// `body/collider` names.
    pub names: (String, String),
}

/// Pairs still suppressed, with the bit each suppressed collider owns.
#[derive(Resource, Debug, Default, Clone)]
pub struct InitialOverlaps {
    /// Pairs not yet separated.
    pub pairs: Vec<SuppressedPair>,
    /// (collider, its solver-group bit).
    pub bits: Vec<(rp::ColliderHandle, u32)>,
}

/// Checks every collider pair of different bodies at t = 0 (see the module docs). Returns the
/// overlapping pairs that are allowed to overlap; a forbidden overlap is an error located at
/// the second part.
pub(crate) fn check_initial(
    loaded: &LoadedScene,
    probes: &[Vec<Probe>],
) -> Result<Vec<SuppressedPair>, SceneError> {
    let scene: &Scene = &loaded.scene;
    // Bounding sphere of each collider (centre = shape origin) and of each body.
    let spheres: Vec<Vec<(Vector3<f64>, f64)>> = probes
        .iter()
        .map(|ps| {
            ps.iter()
                .map(|p| {
                    (
                        p.pose.translation.vector,
                        p.collider.shape.bounding_radius_m(),
                    )
                })
                .collect()
        })
        .collect();
    let body_sphere: Vec<(Vector3<f64>, f64)> = spheres
        .iter()
        .map(|ss| {
            let c = ss.first().map_or(Vector3::zeros(), |s| s.0);
            let r = ss
                .iter()
                .map(|s| (s.0 - c).norm() + s.1)
                .fold(0.0, f64::max);
            (c, r)
        })
        .collect();
    // A margin for the sphere tests: parry's f32 distance is exact to ~1e-6 relative.
    let near = |a: &(Vector3<f64>, f64), b: &(Vector3<f64>, f64)| {
        (a.0 - b.0).norm() <= (a.1 + b.1) * (1.0 + 1e-6) + 1e-6
    };
    let mut allowed = Vec::new();
    for i in 0..probes.len() {
        for j in i + 1..probes.len() {
            if !near(&body_sphere[i], &body_sphere[j]) {
                continue;
            }
            for (ka, a) in probes[i].iter().enumerate() {
                for (kb, b) in probes[j].iter().enumerate() {
                    if !near(&spheres[i][ka], &spheres[j][kb]) {
                        continue;
                    }
                    let d = shape_distance(&a.pose, &*a.shape, &b.pose, &*b.shape);
                    let (na, nb) = (
                        format!("{}/{}", scene.bodies[i].name, a.collider.name),
                        format!("{}/{}", scene.bodies[j].name, b.collider.name),
                    );
                    if d.is_nan() {
                        return Err(loaded.error_at(
                            &format!("bodies.{}.parts.{}", scene.bodies[j].name, b.collider.part),
                            format!("the distance between `{nb}` and `{na}` cannot be computed"),
                        ));
                    }
                    if d > 0.0 {
                        continue;
                    }
                    if !(a.collider.allow_initial_overlap || b.collider.allow_initial_overlap) {
                        return Err(loaded.error_at(
                            &format!("bodies.{}.parts.{}", scene.bodies[j].name, b.collider.part),
                            format!(
                                "part `{nb}` overlaps `{na}` at t = 0; move it or set \
                                 `allow_initial_overlap: true`"
                            ),
                        ));
                    }
                    allowed.push(SuppressedPair {
                        a: (i, a.entity),
                        b: (j, b.entity),
                        handles: (a.handle, b.handle),
                        names: (na, nb),
                    });
                }
            }
        }
    }
    Ok(allowed)
}

/// Parts allowed to overlap at t = 0 (`allow_initial_overlap`): owns [`InitialOverlaps`] and
/// one system, `release_separated`, after [`super::Stage::Physics`] and before
/// [`super::Stage::Monitor`], which gives a pair its solver contact back once it has separated.
/// Building it turns the solver contact of each pair off (solver groups); add it after
/// [`super::PipelinePlugin`] once [`Physics`] exists. Not added when no pair overlaps.
#[derive(Debug, Clone)]
pub struct OverlapPlugin {
    state: InitialOverlaps,
}

impl OverlapPlugin {
    /// The plugin for the pairs [`check_initial`] allowed (`None` when there are none), or a
    /// located error when more colliders overlap than the solver groups can hold apart.
    pub(crate) fn new(
        loaded: &LoadedScene,
        pairs: Vec<SuppressedPair>,
    ) -> Result<Option<Self>, SceneError> {
        if pairs.is_empty() {
            return Ok(None);
        }
        let mut bits: Vec<(rp::ColliderHandle, u32)> = Vec::new();
        for p in &pairs {
            for (h, name) in [(p.handles.0, &p.names.0), (p.handles.1, &p.names.1)] {
                if !bits.iter().any(|(k, _)| *k == h) {
                    if bits.len() == MAX_SUPPRESSED {
                        let (body, part) = name.split_once('/').unwrap_or((name, ""));
                        let part = part.split('.').next().unwrap_or(part);
                        return Err(loaded.error_at(
                            &format!("bodies.{body}.parts.{part}"),
                            format!(
                                "more than {MAX_SUPPRESSED} colliders overlap another body at \
                                 t = 0 (`{name}` is one too many): rpod can hold the contacts \
                                 of at most {MAX_SUPPRESSED} apart"
                            ),
                        ));
                    }
                    bits.push((h, 1u32 << bits.len()));
                }
            }
        }
        Ok(Some(Self {
            state: InitialOverlaps { pairs, bits },
        }))
    }
}

impl Plugin for OverlapPlugin {
    fn build(&self, app: &mut App) {
        apply_groups(
            &self.state,
            &mut app.world_mut().resource_mut::<Physics>().world,
        );
        app.insert_resource(self.state.clone());
        app.add_systems(
            super::SimStep,
            release_separated
                .after(super::Stage::Physics)
                .before(super::Stage::Monitor),
        );
    }
}

fn apply_groups(state: &InitialOverlaps, pw: &mut rp::PhysicsWorld) {
    for (h, bit) in &state.bits {
        let partners = state
            .pairs
            .iter()
            .filter_map(|p| {
                if p.handles.0 == *h {
                    Some(p.handles.1)
                } else if p.handles.1 == *h {
                    Some(p.handles.0)
                } else {
                    None
                }
            })
            .fold(0u32, |m, o| {
                m | state
                    .bits
                    .iter()
                    .find(|(k, _)| *k == o)
                    .map_or(0, |(_, b)| *b)
            });
        let groups = if partners == 0 {
            rp::InteractionGroups::all()
        } else {
            rp::InteractionGroups::new(
                rp::Group::from_bits_retain(*bit),
                rp::Group::from_bits_retain(!partners),
                rp::InteractionTestMode::And,
            )
        };
        if let Some(c) = pw.colliders.get_mut(*h) {
            c.set_solver_groups(groups);
        }
    }
}

/// After the physics step: a suppressed pair whose exact distance is positive has separated;
/// its contact is switched back on.
fn release_separated(
    mut state: ResMut<InitialOverlaps>,
    mut phys: ResMut<Physics>,
    roster: Res<Roster>,
    bodies: Query<(&SimBody, &BodyState)>,
    parts: Query<&Part>,
) {
    let world_pose = |(bi, pe): (usize, Entity)| {
        let (b, s) = bodies.get(roster.bodies[bi]).ok()?;
        let p = parts.get(pe).ok()?;
        Some((s.body_pose(&b.com_body_m) * p.pose_body, p.shape.clone()))
    };
    let before = state.pairs.len();
    state.pairs.retain(|p| {
        let (Some((pa, sa)), Some((pb, sb))) = (world_pose(p.a), world_pose(p.b)) else {
            return false;
        };
        // NaN (a broken state) keeps the pair suppressed; the finiteness guard stops the run.
        let d = shape_distance(&pa, &*sa, &pb, &*sb);
        d.is_nan() || d <= 0.0
    });
    if state.pairs.len() != before {
        apply_groups(&state, &mut phys.world);
        let live: Vec<rp::ColliderHandle> = state
            .pairs
            .iter()
            .flat_map(|p| [p.handles.0, p.handles.1])
            .collect();
        state.bits.retain(|(h, _)| live.contains(h));
    }
}
