//! The steps of the [`super::contacts`] system, in its order: rapier's touching part pairs and
//! their contact points ([`rapier_pairs`], [`push_rapier_points`]), each body's raw normal
//! impulse ([`raw_per_body`]), the compliant model's pairs and sub-step samples
//! ([`compliant_pairs`]), the contacts that ended ([`end_contacts`]), and per pair in contact:
//! its impulse ([`pair_impulse`]), its start ([`start_contact`]) and its totals
//! ([`accumulate`]).

use super::super::contact_model::CompliantContact;
use super::super::{EventLog, Physics, conv};
use super::{
    ActiveContact, ContactSides, ContactState, CumulativeImpulse, PointRow, StepPair, touching,
};
use bevy_rapier3d::rapier::prelude as rp;
use nalgebra::Vector3;
use std::collections::BTreeMap;

/// A part pair's key: the `body/collider` names, the lower (body, name) first.
pub(super) type PairKey = (String, String);

/// The part pairs in contact this step: (pair key) → (docking, body a, body b, rapier's raw
/// normal impulse summed over the pair's points, N·s).
pub(super) type NowPairs = BTreeMap<PairKey, (bool, usize, usize, f64)>;

/// The compliant model's pairs this step: (pair key) → (impulse on b, world, N·s; peak force, N).
pub(super) type GivenPairs = BTreeMap<PairKey, (Vector3<f64>, f64)>;

/// What one part pair exchanged in the step.
#[derive(Clone, Copy)]
pub(super) struct PairImpulse {
    /// Impulse magnitude, N·s.
    pub impulse: f64,
    /// Peak force, N.
    pub force: f64,
    /// Impulse on the pair's first part, world, N·s.
    pub on_a: Vector3<f64>,
    /// Impulse on the pair's second part, world, N·s.
    pub on_b: Vector3<f64>,
}

/// rapier's touching part pairs between different bodies, into `now` (with their raw normal
/// impulse) and `who` (the (body, part) of each side), and their contact points into
/// `cs.points`. Nothing when rapier did not step (`stepped` false: its contact pairs are an
/// older step's). `t` is the time now, s; `dt` the step, s.
pub(super) fn rapier_pairs(
    phys: &Physics,
    stepped: bool,
    cs: &mut ContactState,
    (t, dt): (f64, f64),
    now: &mut NowPairs,
    who: &mut BTreeMap<PairKey, ContactSides>,
) {
    // When rapier did not step (nothing near), its contact pairs are an older step's.
    let pairs = phys.world.narrow_phase.contact_pairs().filter(|_| stepped);
    for pair in pairs {
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
        let (key, ba, bb, sides) = if !swapped {
            (
                (a.full_name.clone(), b.full_name.clone()),
                a.body,
                b.body,
                ((a.body, a.part), (b.body, b.part)),
            )
        } else {
            (
                (b.full_name.clone(), a.full_name.clone()),
                b.body,
                a.body,
                ((b.body, b.part), (a.body, a.part)),
            )
        };
        who.insert(key.clone(), sides);
        // rapier's normal points from collider 1 to collider 2 and pushes collider 2 along it.
        let sign = if swapped { -1.0 } else { 1.0 };
        push_rapier_points(phys, pair, sign, &key, (t, dt), &mut cs.points);
        let e = now.entry(key).or_insert((docking, ba, bb, 0.0));
        e.3 += raw;
    }
}

/// The contact points of one rapier contact pair that touch or carry an impulse, as rows of
/// `contact_points.csv` under the pair key `key`; `sign` turns rapier's normal (from collider
/// 1 to collider 2) into the normal on the key's second part. `t` is the time now, s; `dt` the
/// step, s (the force is the impulse over it).
fn push_rapier_points(
    phys: &Physics,
    pair: &rp::ContactPair,
    sign: f64,
    key: &PairKey,
    (t, dt): (f64, f64),
    points: &mut Vec<PointRow>,
) {
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
                points.push(PointRow {
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
}

/// Per body index (`n` bodies): the sum of rapier's raw normal impulses of the pairs in `now`
/// that it is part of, N·s.
pub(super) fn raw_per_body(now: &NowPairs, n: usize) -> Vec<f64> {
    let mut raw_per_body = vec![0.0; n];
    for (_, ba, bb, raw) in now.values() {
        raw_per_body[*ba] += raw;
        raw_per_body[*bb] += raw;
    }
    raw_per_body
}

/// The compliant model's pairs that touched this step, into `now` (docking, no rapier impulse)
/// and `given` (their exact impulse and peak force), and its sub-step samples into `points`.
/// `t` is the time now (the step's end), s; `dt` the step, s.
pub(super) fn compliant_pairs(
    cc: &CompliantContact,
    (t, dt): (f64, f64),
    now: &mut NowPairs,
    given: &mut GivenPairs,
    points: &mut Vec<PointRow>,
) {
    for st in &cc.step {
        let p = &cc.pairs[st.pair];
        now.entry(p.names.clone())
            .or_insert((true, cc.indices.0, cc.indices.1, 0.0));
        given.insert(p.names.clone(), (st.impulse_on_b_ns, st.peak_force_n));
    }
    let t0 = t - dt;
    for smp in &cc.samples {
        let p = &cc.pairs[smp.pair];
        points.push(PointRow {
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

/// Ends the active contacts that are not in `now`: removes them from `cs.active` and logs a
/// `contact_end` event at `t`, s, with the contact's duration, peak force and impulse.
pub(super) fn end_contacts(cs: &mut ContactState, now: &NowPairs, log: &mut EventLog, t: f64) {
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
}

/// The part of body `body`'s measured contact impulse magnitude that falls to a pair with
/// rapier's raw normal impulse `raw`, N·s: in proportion to `raw` among the body's pairs
/// (`raw_per_body`); zero if the body's pairs carry no raw impulse.
fn share(raw_per_body: &[f64], body: usize, raw: f64, cs: &ContactState) -> f64 {
    if raw_per_body[body] > 0.0 {
        cs.body_impulse[body].norm() * raw / raw_per_body[body]
    } else {
        0.0
    }
}

/// The impulse of pair `k` over the step: the compliant model's exact one if it is in `given`;
/// else, for rapier's pair between bodies `ba` and `bb` with raw normal impulse `raw`, the mean
/// of the two bodies' shares of their measured impulse ([`share`]), its force over the step
/// `dt`, s, and each body's measured impulse vector scaled by the pair's share of its raw
/// impulse.
pub(super) fn pair_impulse(
    k: &PairKey,
    (ba, bb, raw): (usize, usize, f64),
    given: &GivenPairs,
    raw_per_body: &[f64],
    cs: &ContactState,
    dt: f64,
) -> PairImpulse {
    // Impulse magnitude, peak force, and the impulse vectors on the two parts.
    let (impulse, force, on_a, on_b) = match given.get(k) {
        Some((j, peak)) => (j.norm(), *peak, -j, *j),
        None => {
            let impulse =
                0.5 * (share(raw_per_body, ba, raw, cs) + share(raw_per_body, bb, raw, cs));
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
    PairImpulse {
        impulse,
        force,
        on_a,
        on_b,
    }
}

/// Starts the contact of pair `k` at `t`, s: the first contact, first touch (`t_touch`, s, with
/// its tolerance `t_tol`, s) and, for a collision (not `docking`), the first collision times;
/// the `contact_start` (and `collision`) events; and an empty entry in `cs.active`.
pub(super) fn start_contact(
    cs: &mut ContactState,
    log: &mut EventLog,
    k: &PairKey,
    docking: bool,
    t: f64,
    (t_touch, t_tol): (f64, f64),
) {
    cs.first_contact_s.get_or_insert(t);
    cs.first_touch_s.get_or_insert(t_touch);
    log.push(
        t,
        "contact_start",
        serde_json::json!({"a": k.0, "b": k.1, "docking": docking,
            "t_contact_s": t_touch, "t_tol_s": t_tol}),
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

/// Adds pair `k`'s step (`imp`) to its active contact's peak force and impulse, its cumulative
/// impulse, its two parts' totals, and `cs.step_pairs` (with its `docking` flag and body
/// indices `bodies`).
pub(super) fn accumulate(
    cs: &mut ContactState,
    k: PairKey,
    docking: bool,
    bodies: (usize, usize),
    imp: &PairImpulse,
) {
    let PairImpulse {
        impulse,
        force,
        on_a,
        on_b,
    } = *imp;
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
        bodies,
        impulse_on_b_ns: on_b,
        peak_force_n: force,
    });
}
