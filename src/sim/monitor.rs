//! The safety monitor: every step, the exact minimum distance between every pair of bodies'
//! full geometry (parry, with bounding-sphere pruning), the closest part pair, and rapier's
//! contacts named by part — docking contact (both parts docking parts) or collision.

use super::{BodyState, Clock, EventLog, MonitorState, Part, Roster, SimBody, conv};
use crate::guarantee::{BodyView, PairDistance};
use bevy::prelude::*;
use bevy_rapier3d::parry::query;
use bevy_rapier3d::rapier::math::Pose;
use bevy_rapier3d::rapier::prelude as rp;
use nalgebra::Isometry3;
use std::collections::{BTreeMap, HashMap};

/// Who a collider is.
#[derive(Debug, Clone)]
pub struct ColliderRef {
    /// Body index.
    pub body: usize,
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
/// distance: those are not contacts).
fn touching(pair: &rp::ContactPair) -> bool {
    pair.has_any_active_contact()
        && pair
            .manifolds
            .iter()
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

/// Buffers the distance system reuses from step to step.
#[derive(Default)]
pub struct DistanceScratch {
    /// World pose and bounding radius of every part, per body.
    poses: Vec<Vec<(Isometry3<f64>, f64)>>,
    /// Shapes, per body (cloned handles, fetched once).
    shapes: Vec<Vec<rp::SharedShape>>,
    /// (lower bound, part a, part b) for the current body pair.
    candidates: Vec<(f64, usize, usize)>,
}

/// Monitor system: full-geometry distances for every body pair.
///
/// For each body pair, the closest part pair of the previous step is computed exactly first
/// (temporal coherence); then every other part pair whose bounding-sphere lower bound
/// |c_a − c_b| − r_a − r_b is below the best distance so far, in increasing order of that
/// bound. The result is the exact minimum (to parry's tolerance) with few exact queries.
pub fn distances(
    roster: Res<Roster>,
    clock: Res<Clock>,
    bodies: Query<(&SimBody, &BodyState)>,
    parts: Query<&Part>,
    mut mon: ResMut<MonitorState>,
    mut scratch: Local<DistanceScratch>,
) {
    let t = clock.t_s();
    let n = roster.bodies.len();
    let sc = &mut *scratch;
    if sc.shapes.len() != n {
        sc.shapes = roster
            .parts
            .iter()
            .map(|pes| {
                pes.iter()
                    .map(|e| parts.get(*e).expect("part").shape.clone())
                    .collect()
            })
            .collect();
        sc.poses = roster
            .parts
            .iter()
            .map(|pes| Vec::with_capacity(pes.len()))
            .collect();
    }
    if mon.bodies.len() != n {
        mon.bodies = roster
            .bodies
            .iter()
            .map(|be| {
                let (b, s) = bodies.get(*be).expect("roster body");
                BodyView {
                    name: b.name.clone(),
                    pos_m: s.pos_m,
                    vel_m_s: s.vel_m_s,
                    att: s.att,
                    omega_rad_s: s.omega_rad_s,
                }
            })
            .collect();
    }
    for (k, be) in roster.bodies.iter().enumerate() {
        let (b, s) = bodies.get(*be).expect("roster body");
        let v = &mut mon.bodies[k];
        v.pos_m = s.pos_m;
        v.vel_m_s = s.vel_m_s;
        v.att = s.att;
        v.omega_rad_s = s.omega_rad_s;
        let body_pose = s.body_pose(&b.com_body_m);
        let poses = &mut sc.poses[k];
        poses.clear();
        for pe in &roster.parts[k] {
            let p = parts.get(*pe).expect("roster part");
            poses.push((body_pose * p.pose_body, p.bound_radius_m));
        }
    }
    let first = mon.pairs.len() != n * (n - 1) / 2;
    if first {
        mon.pairs.clear();
        mon.min_per_pair.clear();
        mon.min_clearance_per_pair.clear();
    }
    let (mut exact, mut pruned) = (0u64, 0u64);
    let mut k = 0;
    for i in 0..n {
        for j in i + 1..n {
            let (pi, pj) = (&sc.poses[i], &sc.poses[j]);
            let dock_i = &mon.part_docking[i];
            let dock_j = &mon.part_docking[j];
            let any_docking_pair = dock_i.iter().any(|d| *d) && dock_j.iter().any(|d| *d);
            let shapes = &sc.shapes;
            let candidates = &mut sc.candidates;
            // Closest part pair among those `keep` accepts, warm-started from `warm`.
            let mut closest = |keep: &dyn Fn(usize, usize) -> bool,
                               warm: Option<(usize, usize)>| {
                let query = |a: usize, b: usize| {
                    shape_distance(&pi[a].0, &*shapes[i][a], &pj[b].0, &*shapes[j][b])
                };
                let warm = warm.filter(|(a, b)| keep(*a, *b));
                let (mut best, mut ba, mut bb) = match warm {
                    Some((a, b)) => {
                        exact += 1;
                        (query(a, b), a, b)
                    }
                    None => (f64::INFINITY, 0, 0),
                };
                candidates.clear();
                for (a, (pa, ra)) in pi.iter().enumerate() {
                    for (b, (pb, rb)) in pj.iter().enumerate() {
                        if !keep(a, b) || warm == Some((a, b)) {
                            continue;
                        }
                        let lb = (pa.translation.vector - pb.translation.vector).norm() - ra - rb;
                        if lb < best {
                            candidates.push((lb, a, b));
                        } else {
                            pruned += 1;
                        }
                    }
                }
                candidates
                    .sort_unstable_by(|x, y| x.0.total_cmp(&y.0).then((x.1, x.2).cmp(&(y.1, y.2))));
                for (c, &(lb, a, b)) in candidates.iter().enumerate() {
                    if lb >= best {
                        pruned += (candidates.len() - c) as u64;
                        break;
                    }
                    let d = query(a, b);
                    exact += 1;
                    if d < best {
                        (best, ba, bb) = (d, a, b);
                    }
                }
                (best, ba, bb)
            };
            let warm = (!first).then(|| (mon.pairs[k].part_a, mon.pairs[k].part_b));
            let (best, ba, bb) = closest(&|_, _| true, warm);
            let clearance = if any_docking_pair && dock_i[ba] && dock_j[bb] {
                closest(&|a, b| !(dock_i[a] && dock_j[b]), None).0
            } else {
                best
            };
            let pd = PairDistance {
                a: i,
                b: j,
                distance_m: best,
                part_a: ba,
                part_b: bb,
                clearance_m: clearance,
            };
            let pm = super::PairMin {
                distance_m: best,
                part_a: ba,
                part_b: bb,
                t_s: t,
            };
            if first {
                mon.pairs.push(pd);
                mon.min_per_pair.push(pm);
                mon.min_clearance_per_pair.push(clearance);
            } else {
                mon.pairs[k] = pd;
                if best < mon.min_per_pair[k].distance_m {
                    mon.min_per_pair[k] = pm;
                }
                let c = &mut mon.min_clearance_per_pair[k];
                *c = c.min(clearance);
            }
            k += 1;
        }
    }
    mon.exact_queries += exact;
    mon.pruned_pairs += pruned;
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
pub fn contacts(
    phys: Res<super::Physics>,
    clock: Res<Clock>,
    mut cs: ResMut<ContactState>,
    mut log: ResMut<EventLog>,
    compliant: Option<Res<super::contact_model::CompliantContact>>,
) {
    let t = clock.t_s();
    let dt = clock.dt_s;
    let cs = &mut *cs;
    cs.points.clear();
    cs.step_pairs.clear();
    // (pair key) → (docking, body a, body b, rapier's raw normal impulse)
    let mut now: BTreeMap<(String, String), (bool, usize, usize, f64)> = BTreeMap::new();
    for pair in phys.world.narrow_phase.contact_pairs() {
        if !touching(pair) {
            continue;
        }
        let (Some(a), Some(b)) = (
            cs.colliders.get(&pair.collider1),
            cs.colliders.get(&pair.collider2),
        ) else {
            continue;
        };
        if a.body == b.body {
            continue;
        }
        let raw: f64 = pair
            .manifolds
            .iter()
            .flat_map(|m| m.points.iter())
            .map(|p| p.data.impulse.max(0.0) as f64)
            .sum();
        let docking = a.docking && b.docking;
        let swapped = (a.body, &a.full_name) > (b.body, &b.full_name);
        let (key, ba, bb) = if !swapped {
            ((a.full_name.clone(), b.full_name.clone()), a.body, b.body)
        } else {
            ((b.full_name.clone(), a.full_name.clone()), b.body, a.body)
        };
        // rapier's normal points from collider 1 to collider 2 and pushes collider 2 along it.
        let sign = if swapped { -1.0 } else { 1.0 };
        if let (Some(c1), Some(c2)) = (
            phys.world.colliders.get(pair.collider1),
            phys.world.colliders.get(pair.collider2),
        ) {
            for m in pair.solver_manifolds() {
                let n = conv::na(m.data.normal) * sign;
                for p in &m.points {
                    if !(p.dist <= 0.0 || p.data.impulse > 0.0) {
                        continue;
                    }
                    let p1 = conv::na(c1.position().transform_point(p.local_p1));
                    let p2 = conv::na(c2.position().transform_point(p.local_p2));
                    let j = f64::from(p.data.impulse.max(0.0));
                    cs.points.push(PointRow {
                        t_s: t,
                        a: key.0.clone(),
                        b: key.1.clone(),
                        compliant: false,
                        point_m: (p1 + p2) * 0.5,
                        normal_on_b: n,
                        depth_m: -f64::from(p.dist),
                        normal_force_n: j / dt,
                        normal_impulse_ns: j,
                        force_on_b_n: n * (j / dt),
                    });
                }
            }
        }
        let e = now.entry(key).or_insert((docking, ba, bb, 0.0));
        e.3 += raw;
    }
    let mut raw_per_body = vec![0.0; cs.body_impulse.len()];
    for (_, ba, bb, raw) in now.values() {
        raw_per_body[*ba] += raw;
        raw_per_body[*bb] += raw;
    }
    // The compliant model's pairs: (impulse on b, peak force) per key.
    let mut given: BTreeMap<(String, String), (nalgebra::Vector3<f64>, f64)> = BTreeMap::new();
    if let Some(cc) = &compliant {
        for st in &cc.step {
            let p = &cc.pairs[st.pair];
            now.entry(p.names.clone())
                .or_insert((true, cc.indices.0, cc.indices.1, 0.0));
            given.insert(p.names.clone(), (st.impulse_on_b_ns, st.peak_force_n));
        }
        let t0 = t - dt;
        for smp in &cc.samples {
            let p = &cc.pairs[smp.pair];
            cs.points.push(PointRow {
                t_s: t0 + smp.t_in_step_s,
                a: p.names.0.clone(),
                b: p.names.1.clone(),
                compliant: true,
                point_m: smp.point_m,
                normal_on_b: smp.normal_on_b,
                depth_m: smp.depth_m,
                normal_force_n: smp.normal_force_n,
                normal_impulse_ns: smp.normal_force_n * smp.h_s,
                force_on_b_n: smp.force_on_b_n,
            });
        }
    }
    let share = |body: usize, raw: f64, cs: &ContactState| {
        if raw_per_body[body] > 0.0 {
            cs.body_impulse[body].norm() * raw / raw_per_body[body]
        } else {
            0.0
        }
    };
    // Ended contacts.
    let ended: Vec<(String, String)> = cs
        .active
        .keys()
        .filter(|k| !now.contains_key(*k))
        .cloned()
        .collect();
    for k in ended {
        let c = cs.active.remove(&k).expect("active");
        log.push(
            t,
            "contact_end",
            serde_json::json!({"a": k.0, "b": k.1, "docking": c.docking,
                "duration_s": t - c.start_s, "peak_force_n": c.peak_force_n, "impulse_ns": c.impulse_ns}),
        );
    }
    for (k, (docking, ba, bb, raw)) in now {
        // Impulse magnitude, peak force, and the impulse vectors on the two parts.
        let (impulse, force, on_a, on_b) = match given.get(&k) {
            Some((j, peak)) => (j.norm(), *peak, -j, *j),
            None => {
                let impulse = 0.5 * (share(ba, raw, cs) + share(bb, raw, cs));
                let on = |body: usize| {
                    if raw_per_body[body] > 0.0 {
                        cs.body_impulse[body] * (raw / raw_per_body[body])
                    } else {
                        nalgebra::Vector3::zeros()
                    }
                };
                (impulse, impulse / dt, on(ba), on(bb))
            }
        };
        if !cs.active.contains_key(&k) {
            cs.first_contact_s.get_or_insert(t);
            log.push(
                t,
                "contact_start",
                serde_json::json!({"a": k.0, "b": k.1, "docking": docking}),
            );
            if !docking {
                cs.first_collision_s.get_or_insert(t);
                cs.collisions.push((t, k.0.clone(), k.1.clone()));
                log.push(t, "collision", serde_json::json!({"a": k.0, "b": k.1}));
            }
            cs.active.insert(
                k.clone(),
                ActiveContact {
                    start_s: t,
                    docking,
                    peak_force_n: 0.0,
                    impulse_ns: 0.0,
                },
            );
        }
        let c = cs.active.get_mut(&k).expect("active");
        c.peak_force_n = c.peak_force_n.max(force);
        c.impulse_ns += impulse;
        let cum = cs
            .cumulative_impulse_ns
            .entry(k.clone())
            .or_insert_with(|| CumulativeImpulse {
                docking,
                ..Default::default()
            });
        cum.magnitude_ns += impulse;
        cum.on_b_ns += on_b;
        for (name, vec) in [(&k.0, on_a), (&k.1, on_b)] {
            let s = cs.per_part.entry(name.clone()).or_default();
            s.peak_force_n = s.peak_force_n.max(force);
            s.total_impulse_ns += impulse;
            for (n, v) in s.net_impulse_ns.iter_mut().zip(vec.iter()) {
                *n += v;
            }
        }
        cs.step_pairs.push(StepPair {
            key: k,
            docking,
            bodies: (ba, bb),
            impulse_on_b_ns: on_b,
            peak_force_n: force,
        });
    }
}
