//! The air-bearing lab twin ([`Environment::AirBearing`]): a granite table, simulators floating
//! on it, and the air film's residual effects.
//!
//! # Design: f64 planar truth, rapier locks and the table as a collider
//! The core integrates every body's free flight in f64 and hands the truth to rapier only while
//! bodies touch or are jointed (see [`crate::sim`]). The table keeps that split:
//!
//! - **Support.** The air film carries the normal component of gravity, N = m·g·cos α_x·cos α_y,
//!   exactly; it is not modelled as a contact. Each simulator's centre-of-mass height, roll
//!   and pitch stay at their t = 0 values: every step [`airbearing_constrain`] projects the f64
//!   state onto the plane (z, v_z, ω_x, ω_y, roll, pitch restored) — the "locks" of the f64
//!   integrator — and rapier gets `LockedAxes` (translation z, rotation x and y) so that the
//!   solver keeps the same plane while it is the truth (the docking cone in the slot, the latch
//!   joint, a collision with the obstacle).
//! - **In-plane forces** ([`airbearing_forces`], Environment stage): the in-plane component of
//!   gravity m·(g_x, g_y) from the tilt, viscous drag −c·v and −c_ψ·ω_z, and Coulomb friction
//!   μ·N against the in-plane velocity with a stick rule: when a held force over the step
//!   would reverse the velocity (or hold a body at rest) and the force needed to stop it
//!   exactly is within μ·N, that force is applied instead (the body stops at the step's end,
//!   no chatter). The friction sees the forces added before the Environment stage (control,
//!   thrusters, magnet, plume loads).
//! - **Other forces on a simulator** act in the plane only ([`add_planar`]): the controllers'
//!   forces and the plume impingement loads ([`super::plume::PlumeLoadState`]) give their
//!   in-plane force and their torque about z; the air film carries the out-of-plane force and
//!   the locks the roll/pitch torque.
//! - **The table** is a fixed rapier collider (the top at z = 0, `table_thickness_m` thick) in
//!   an interaction group no simulator belongs to: the air film is a gap, so rapier never
//!   creates a table contact (which would wrongly add friction while rapier is the truth).
//! - **Off the table.** When a simulator's centre of mass leaves the table rectangle, an
//!   `off_table` event is raised, its rapier locks are removed and it falls under the full
//!   gravity vector (the f64 free flight; the fall is not resolved against the table edge).
//! - **Anchored bodies** (an obstacle bolted to the table) are rapier fixed bodies; no forces act
//!   on them and their f64 state is held at t = 0.
//!
//! Why not rapier's own gravity and table contact: a simulator resting on the table would be
//! "in contact" every step, so rapier's f32 solver would be the truth all the time (the f64
//! integrator exists because rapier's free flight drifts, `tests/val_tumbling.rs`), and the
//! contact's friction and compliance would stand in for an air film that has neither. The
//! planar f64 path reproduces the closed forms to rounding (`tests/val_airbearing.rs`).

use super::{BodyState, Clock, EventLog, Physics, Roster, SimBody, SimStep, Stage, Wrench, conv};
use crate::scene::{AirBearingSpec, Environment, LoadedScene, SceneError};
use bevy::prelude::*;
use bevy_rapier3d::rapier::prelude as rp;
use nalgebra::{UnitQuaternion, Vector2, Vector3};

/// The table and the per-body support state.
#[derive(Resource, Debug, Clone)]
pub struct AirBearing {
    /// The scene's table.
    pub spec: AirBearingSpec,
    /// Gravity in the lab frame, m/s².
    pub gravity_lab_m_s2: Vector3<f64>,
    /// Per body (scene order): bolted to the table.
    pub anchored: Vec<bool>,
    /// Per body: still floating on the table (false once it has run off).
    pub supported: Vec<bool>,
    /// Per body: centre-of-mass height held by the air film, m.
    pub height_m: Vec<f64>,
    /// Per body: the roll/pitch part of the attitude at t = 0 (attitude = R_z(ψ) · this).
    pub tilt_att: Vec<UnitQuaternion<f64>>,
    /// Per body: the t = 0 state (anchored bodies are held at it).
    pub initial: Vec<BodyState>,
    /// Per body: when it ran off the table, s.
    pub off_table_s: Vec<Option<f64>>,
    /// The table's rapier collider.
    pub table_collider: rp::ColliderHandle,
}

/// Yaw ψ of an attitude `att = R_z(ψ) · tilt`, rad.
pub fn yaw_rad(att: &UnitQuaternion<f64>, tilt: &UnitQuaternion<f64>) -> f64 {
    let q = att * tilt.inverse();
    // The z-rotation closest to q: ψ = 2·atan2(q_z, q_w).
    2.0 * q.k.atan2(q.w)
}

fn planar_locks() -> rp::LockedAxes {
    rp::LockedAxes::TRANSLATION_LOCKED_Z
        | rp::LockedAxes::ROTATION_LOCKED_X
        | rp::LockedAxes::ROTATION_LOCKED_Y
}

/// The air-bearing table of a scene whose environment is [`Environment::AirBearing`]: owns the
/// [`AirBearing`] resource, the table collider and the rapier locks (planar simulators, fixed
/// anchored bodies), set when it is added, and two systems: `airbearing_forces` in
/// [`super::Order::TableForces`] (Environment: film, friction, tilt) and
/// `airbearing_constrain` in [`Stage::Monitor`] before [`super::Order::PostStepDiagnostics`]
/// (so before the distances: everything the Monitor stage reads sees the constrained state). Add it once the bodies exist, after
/// [`super::PipelinePlugin`].
#[derive(Debug, Clone)]
pub struct AirBearingPlugin {
    /// The table at t = 0 (its collider handle set when the plugin is added).
    table: AirBearing,
}

impl AirBearingPlugin {
    /// The table of the scene's environment (`None` in other environments), checked against
    /// the built bodies (`world` holds the [`Roster`] and the bodies' states at t = 0): located
    /// errors for an unknown anchored body or a simulator that starts off the table.
    pub fn new(world: &World, loaded: &LoadedScene) -> Result<Option<Self>, SceneError> {
        let Environment::AirBearing(spec) = &loaded.scene.environment else {
            return Ok(None);
        };
        let spec = spec.clone();
        let roster = world.resource::<Roster>().clone();
        let n = roster.bodies.len();
        let mut anchored = vec![false; n];
        for (i, name) in spec.anchored.iter().enumerate() {
            let k = roster.names.iter().position(|b| b == name).ok_or_else(|| {
                loaded.error_at(
                    &format!("environment.0.anchored.{i}"),
                    format!("no body named `{name}`"),
                )
            })?;
            anchored[k] = true;
        }
        let mut height_m = Vec::with_capacity(n);
        let mut tilt_att = Vec::with_capacity(n);
        let mut initial = Vec::with_capacity(n);
        for (k, e) in roster.bodies.iter().enumerate() {
            let b = world.get::<SimBody>(*e).expect("body");
            let s = world.get::<BodyState>(*e).expect("state").clone();
            let q = s.att;
            // Split q = R_z(ψ) · tilt with tilt free of yaw about the lab z axis.
            let psi = {
                let x = q * Vector3::x();
                if x.x.abs() + x.y.abs() > 1e-9 {
                    x.y.atan2(x.x)
                } else {
                    0.0
                }
            };
            let rz = UnitQuaternion::from_axis_angle(&Vector3::z_axis(), psi);
            tilt_att.push(rz.inverse() * q);
            height_m.push(s.pos_m.z);
            if !anchored[k] && !spec.on_table(s.pos_m.x, s.pos_m.y) {
                return Err(loaded.error_at(
                    &format!("bodies.{}.initial.pos_m", b.name),
                    format!(
                        "the simulator starts off the table: ({:.3}, {:.3}) m is outside x ∈ [{}, {}] m, y ∈ [{}, {}] m",
                        s.pos_m.x,
                        s.pos_m.y,
                        spec.table_corner_m[0],
                        spec.table_corner_m[0] + spec.table_size_m[0],
                        spec.table_corner_m[1],
                        spec.table_corner_m[1] + spec.table_size_m[1]
                    ),
                ));
            }
            initial.push(s);
        }
        let gravity_lab_m_s2 = spec.gravity_lab_m_s2();
        Ok(Some(Self {
            table: AirBearing {
                spec,
                gravity_lab_m_s2,
                supported: anchored.iter().map(|a| !a).collect(),
                anchored,
                height_m,
                tilt_att,
                initial,
                off_table_s: vec![None; n],
                table_collider: rp::ColliderHandle::invalid(),
            },
        }))
    }
}

impl Plugin for AirBearingPlugin {
    fn build(&self, app: &mut App) {
        let mut table = self.table.clone();
        let handles: Vec<rp::RigidBodyHandle> = {
            let w = app.world();
            let roster = w.resource::<Roster>();
            roster
                .bodies
                .iter()
                .map(|e| w.get::<SimBody>(*e).expect("body").handle)
                .collect()
        };
        let spec = &table.spec;
        table.table_collider = {
            let mut phys = app.world_mut().resource_mut::<Physics>();
            let pw = &mut phys.world;
            for (k, h) in handles.iter().enumerate() {
                if let Some(rb) = pw.bodies.get_mut(*h) {
                    if table.anchored[k] {
                        rb.set_body_type(rp::RigidBodyType::Fixed, true);
                    } else {
                        rb.set_locked_axes(planar_locks(), true);
                    }
                }
            }
            let [w, h] = spec.table_size_m;
            let t = spec.table_thickness_m;
            let centre = Vector3::new(
                spec.table_corner_m[0] + w / 2.0,
                spec.table_corner_m[1] + h / 2.0,
                -t / 2.0,
            );
            let col =
                rp::ColliderBuilder::cuboid((w / 2.0) as f32, (h / 2.0) as f32, (t / 2.0) as f32)
                    .translation(conv::v(&centre))
                    .collision_groups(rp::InteractionGroups::none())
                    .build();
            pw.insert_collider(col, None)
        };
        app.insert_resource(table);
        app.add_systems(SimStep, airbearing_forces.in_set(super::Order::TableForces));
        app.add_systems(
            SimStep,
            airbearing_constrain
                .in_set(Stage::Monitor)
                .before(super::Order::PostStepDiagnostics),
        );
    }
}

/// Adds to a planar simulator's wrench the part of (`force_n`, `torque_nm`) (world = lab
/// frame, N and N·m about the centre of mass) that the table lets act: the in-plane force
/// (x, y) and the torque about the table's normal (z). The air film and the locks carry the
/// rest (the out-of-plane force and the roll/pitch torque). Used for the controllers' forces
/// and the plume loads.
pub fn add_planar(w: &mut Wrench, force_n: &Vector3<f64>, torque_nm: &Vector3<f64>) {
    w.force_n.x += force_n.x;
    w.force_n.y += force_n.y;
    w.torque_nm.z += torque_nm.z;
}

/// The air film's in-plane friction force on a body over one held step, N.
///
/// `v` in-plane velocity (m/s), `f_other` the other in-plane forces held over the step (N),
/// `mu_n` the Coulomb limit μ·N (N), `m` mass (kg), `dt` step (s). Kinetic friction −μN·v̂;
/// when that would reverse the velocity within the step (or the body is at rest) and the force
/// that brings it exactly to rest, −m·v/dt − f_other, is within μN, that force (stick).
pub fn coulomb_force_n(
    v: Vector2<f64>,
    f_other: Vector2<f64>,
    mu_n: f64,
    m: f64,
    dt: f64,
) -> Vector2<f64> {
    if mu_n <= 0.0 {
        return Vector2::zeros();
    }
    let stick = -v * (m / dt) - f_other;
    let speed = v.norm();
    if speed == 0.0 {
        if stick.norm() <= mu_n {
            return stick;
        }
        return -f_other.normalize() * mu_n;
    }
    let kinetic = -v / speed * mu_n;
    let v1 = v + (f_other + kinetic) * (dt / m);
    if v1.dot(&v) <= 0.0 && stick.norm() <= mu_n {
        return stick;
    }
    kinetic
}

/// Environment stage: tilt gravity, viscous drag and Coulomb friction on the simulators;
/// full gravity on bodies that ran off; nothing on anchored bodies.
pub fn airbearing_forces(
    clock: Res<Clock>,
    table: Res<AirBearing>,
    mut q: Query<(&SimBody, &BodyState, &mut Wrench)>,
) {
    let dt = clock.h_s();
    let g = table.gravity_lab_m_s2;
    let sp = &table.spec;
    for (b, s, mut w) in &mut q {
        let k = b.index;
        if table.anchored[k] {
            *w = Wrench::default();
            continue;
        }
        if !table.supported[k] {
            w.force_n += g * b.mass_kg;
            continue;
        }
        let v = s.vel_m_s.xy();
        let mut f = (g * b.mass_kg).xy() - v * sp.viscous_drag_n_s_m;
        w.torque_nm.z -= sp.viscous_drag_nm_s_rad * s.omega_rad_s.z;
        let normal_n = -g.z * b.mass_kg;
        let f_other = w.force_n.xy() + f;
        f += coulomb_force_n(v, f_other, sp.coulomb_friction * normal_n, b.mass_kg, dt);
        w.force_n.x += f.x;
        w.force_n.y += f.y;
    }
}

/// Monitor stage, before the distances: the planar locks on the f64 truth (height, roll,
/// pitch, v_z, ω_x, ω_y), anchored bodies held, and the off-table check.
pub fn airbearing_constrain(
    clock: Res<Clock>,
    mut table: ResMut<AirBearing>,
    mut phys: ResMut<Physics>,
    mut log: ResMut<EventLog>,
    mut q: Query<(&SimBody, &mut BodyState)>,
) {
    let t = clock.t_s();
    for (b, mut s) in &mut q {
        let k = b.index;
        if table.anchored[k] {
            *s = table.initial[k].clone();
        } else if table.supported[k] {
            if !table.spec.on_table(s.pos_m.x, s.pos_m.y) {
                table.supported[k] = false;
                table.off_table_s[k] = Some(t);
                log.push(
                    t,
                    "off_table",
                    serde_json::json!({"body": b.name, "pos_m": [s.pos_m.x, s.pos_m.y]}),
                );
                if let Some(rb) = phys.world.bodies.get_mut(b.handle) {
                    rb.set_locked_axes(rp::LockedAxes::empty(), true);
                }
                continue;
            }
            let psi = yaw_rad(&s.att, &table.tilt_att[k]);
            s.att = UnitQuaternion::from_axis_angle(&Vector3::z_axis(), psi) * table.tilt_att[k];
            s.pos_m.z = table.height_m[k];
            s.vel_m_s.z = 0.0;
            s.omega_rad_s.x = 0.0;
            s.omega_rad_s.y = 0.0;
        } else {
            continue;
        }
        if let Some(rb) = phys.world.bodies.get_mut(b.handle) {
            let pose = s.body_pose(&b.com_body_m);
            rb.set_position(conv::pose(&pose), false);
            rb.set_linvel(conv::v(&s.vel_m_s), false);
            rb.set_angvel(conv::v(&s.omega_rad_s), false);
        }
    }
}
