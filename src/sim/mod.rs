//! The Bevy layer: a scene becomes a Bevy [`App`] whose `SimStep` schedule runs, every fixed
//! step, the stages Sense → Control → Actuate → Environment → Physics (rapier) → Monitor →
//! Record, each a [`SystemSet`] chained explicitly.
//!
//! # Why rapier is driven directly
//! The rapier world ([`Physics`], a `rapier::PhysicsWorld` reached through
//! `bevy_rapier3d::rapier`) is a resource stepped by our own system rather than through
//! bevy_rapier's plugin: the plugin re-synchronises `Transform`s both ways by change detection
//! every step, which would fight the f64 state below and costs more than the rapier step itself.
//! Bodies and parts are still entities ([`SimBody`], [`BodyState`], [`Part`]) that every stage
//! queries; the viewer reads the same components.
//!
//! # f64 truth
//! rapier is f32. Each body carries a [`BodyState`] in f64 (centre-of-mass position and
//! velocity, attitude, angular velocity). While a body is in free flight (no contact, no joint),
//! its state is advanced in f64 (velocity Verlet for gravity, RK4 for the rotation; see
//! `physics_step`) and written back into rapier each step, so f32 rounding does not accumulate
//! (at 50 m the position ulp is 4 µm; over 60 000 steps it would random-walk ~0.3 mm) and the
//! tumble conserves energy. While in contact or jointed, rapier's solver is the truth and the
//! f64 state copies it.
//!
//! # Time
//! `SimStep` runs exactly [`StepBudget`] times per `App::update`, never by the wall clock; the
//! same scene gives byte-identical outputs on every run.

pub mod airbearing;
pub mod build;
pub mod contact_model;
pub mod docking;
pub mod laws;
pub mod monitor;
pub mod output;

use crate::guarantee::{BodyView, Guarantee, GuaranteeStatus, MonitorView, PairDistance};
use crate::scene::{BodyRole, PartRole};
use bevy::ecs::schedule::{ScheduleLabel, SystemSet};
use bevy::prelude::*;
use bevy_rapier3d::rapier::prelude as rp;
use nalgebra::{Isometry3, Matrix3, UnitQuaternion, Vector3};

pub use build::Simulation;

/// The fixed-step schedule.
#[derive(ScheduleLabel, Debug, Clone, PartialEq, Eq, Hash)]
pub struct SimStep;

/// The pipeline stages of one fixed step, in order.
#[derive(SystemSet, Debug, Clone, PartialEq, Eq, Hash)]
pub enum Stage {
    /// Measurements at their own rates.
    Sense,
    /// Control laws (pure functions of observations).
    Control,
    /// Saturation, thruster allocation, PWPF; commands become forces.
    Actuate,
    /// Differential gravity, J2, gravity-gradient torque, friction, tilt.
    Environment,
    /// The rapier step and the f64 state update.
    Physics,
    /// Full-geometry distances, contacts, guarantees.
    Monitor,
    /// Trajectory rows and events.
    Record,
}

/// Simulated clock. `step` counts completed steps; `t_s = step · dt_s` (never accumulated).
#[derive(Resource, Debug, Clone)]
pub struct Clock {
    /// Completed steps.
    pub step: u64,
    /// Fixed step, s.
    pub dt_s: f64,
}

impl Clock {
    /// Simulated time, s.
    pub fn t_s(&self) -> f64 {
        self.step as f64 * self.dt_s
    }
}

/// How many `SimStep`s the next `App::update` runs.
#[derive(Resource, Debug, Clone, Default)]
pub struct StepBudget(pub u64);

/// The rapier world.
#[derive(Resource)]
pub struct Physics {
    /// rapier's bundle of pipeline, sets and parameters.
    pub world: rp::PhysicsWorld,
    /// rapier substeps per step.
    pub substeps: u32,
}

/// The orbital environment: the reference orbit (f64) and the force model toggles.
#[derive(Resource, Debug, Clone)]
pub struct OrbitEnv {
    /// Reference orbit (the world frame's origin), ECI.
    pub reference: crate::orbit::integrate::ReferenceOrbit,
    /// Include J2.
    pub j2: bool,
    /// Apply gravity-gradient torques.
    pub gravity_gradient: bool,
}

/// A gravity field acting on every body's centre of mass, in the world frame. The physics
/// step evaluates it twice per step (velocity Verlet), so it must be a function of position
/// (and of the field's own time, advanced by [`GravityField::advance`]) only.
pub trait GravityField: Send + Sync {
    /// Acceleration at a world position, m/s², at the field's current time.
    fn accel_m_s2(&self, pos_world_m: &Vector3<f64>) -> Vector3<f64>;
    /// Moves the field's time on by `dt_s` (e.g. propagates a reference orbit).
    fn advance(&mut self, dt_s: f64);
}

/// The scene's gravity field, if any (orbit scenes: [`OrbitEnv`]'s differential gravity).
#[derive(Resource)]
pub struct Gravity(pub Box<dyn GravityField>);

impl GravityField for OrbitEnv {
    fn accel_m_s2(&self, pos_world_m: &Vector3<f64>) -> Vector3<f64> {
        crate::orbit::gravity::differential_accel(&self.reference.state().0, pos_world_m, self.j2)
    }
    fn advance(&mut self, dt_s: f64) {
        self.reference.step(dt_s);
    }
}

/// A spacecraft.
#[derive(Component, Debug, Clone)]
pub struct SimBody {
    /// Index in scene order.
    pub index: usize,
    /// Name.
    pub name: String,
    /// Role.
    pub role: BodyRole,
    /// rapier handle.
    pub handle: rp::RigidBodyHandle,
    /// Mass, kg.
    pub mass_kg: f64,
    /// Inertia about the centre of mass, body axes, kg·m².
    pub inertia_kg_m2: Matrix3<f64>,
    /// Centre of mass in the body frame, m.
    pub com_body_m: Vector3<f64>,
    /// Inverse of `inertia_kg_m2`.
    pub inertia_inv: Matrix3<f64>,
}

/// A body's f64 state (the truth the monitor and the outputs use), world frame.
#[derive(Component, Debug, Clone)]
pub struct BodyState {
    /// Centre-of-mass position, m.
    pub pos_m: Vector3<f64>,
    /// Centre-of-mass velocity, m/s.
    pub vel_m_s: Vector3<f64>,
    /// Attitude body → world.
    pub att: UnitQuaternion<f64>,
    /// Angular velocity, world frame, rad/s.
    pub omega_rad_s: Vector3<f64>,
}

impl BodyState {
    /// Pose of the body frame origin in the world.
    pub fn body_pose(&self, com_body_m: &Vector3<f64>) -> Isometry3<f64> {
        let origin = self.pos_m - self.att * com_body_m;
        Isometry3::from_parts(origin.into(), self.att)
    }
}

/// Force and torque to apply this step, world frame, accumulated by Actuate and Environment
/// and consumed by Physics.
///
/// Gravity is kept apart from the other forces because the f64 free-flight update treats the
/// two differently: gravity (a smooth function of position) by velocity Verlet, everything else
/// (commands held over the step, friction) as a zero-order hold.
#[derive(Component, Debug, Clone, Default)]
pub struct Wrench {
    /// Differential gravity force through the centre of mass, N.
    pub gravity_n: Vector3<f64>,
    /// All other forces through the centre of mass, N (held constant over the step).
    pub force_n: Vector3<f64>,
    /// Torque about the centre of mass, N·m.
    pub torque_nm: Vector3<f64>,
}

/// One collider of a body.
#[derive(Component, Clone)]
pub struct Part {
    /// Owning body entity.
    pub body: Entity,
    /// Owning body index.
    pub body_index: usize,
    /// Part name in the scene.
    pub part: String,
    /// Collider name (`part` or `part.panel2` …).
    pub name: String,
    /// Role.
    pub role: PartRole,
    /// rapier collider.
    pub collider: rp::ColliderHandle,
    /// The shape (shared with rapier).
    pub shape: rp::SharedShape,
    /// Pose in the body frame.
    pub pose_body: Isometry3<f64>,
    /// Bounding-sphere radius about the shape origin, m.
    pub bound_radius_m: f64,
}

/// Scene order of bodies, and of parts per body (entities).
#[derive(Resource, Debug, Clone, Default)]
pub struct Roster {
    /// Body entities in scene order.
    pub bodies: Vec<Entity>,
    /// Part entities per body, in scene order.
    pub parts: Vec<Vec<Entity>>,
    /// Body names in scene order.
    pub names: Vec<String>,
}

/// Registered guarantees and their running status.
#[derive(Resource, Default)]
pub struct Guarantees {
    /// The invariants.
    pub list: Vec<Box<dyn Guarantee>>,
    /// Their status, same order.
    pub status: Vec<GuaranteeStatus>,
}

impl Guarantees {
    /// Registers a guarantee.
    pub fn register(&mut self, g: Box<dyn Guarantee>) {
        self.status.push(GuaranteeStatus::new(g.name(), g.unit()));
        self.list.push(g);
    }
}

/// One thing that happened, written to `events.jsonl`.
#[derive(Debug, Clone, serde::Serialize)]
pub struct Event {
    /// Simulated time, s.
    pub t_s: f64,
    /// Kind: `contact_start`, `contact_end`, `collision`, `guarantee_violated`,
    /// `guarantee_restored`, …
    pub kind: String,
    /// Details.
    #[serde(flatten)]
    pub data: serde_json::Map<String, serde_json::Value>,
}

/// Events raised this run (drained by the recorder).
#[derive(Resource, Debug, Default)]
pub struct EventLog {
    /// Not yet written.
    pub pending: Vec<Event>,
    /// Total raised.
    pub count: u64,
}

impl EventLog {
    /// Raises an event.
    pub fn push(&mut self, t_s: f64, kind: &str, data: serde_json::Value) {
        let data = match data {
            serde_json::Value::Object(m) => m,
            _ => serde_json::Map::new(),
        };
        self.pending.push(Event {
            t_s,
            kind: kind.to_string(),
            data,
        });
        self.count += 1;
    }
}

/// Conversions between nalgebra (f64) and rapier's glam (f32).
pub mod conv {
    use bevy_rapier3d::rapier::math::{Pose, Rotation, Vector};
    use nalgebra::{Isometry3, Quaternion, UnitQuaternion, Vector3};

    /// f64 → f32 vector.
    pub fn v(x: &Vector3<f64>) -> Vector {
        Vector::new(x.x as f32, x.y as f32, x.z as f32)
    }
    /// f32 → f64 vector.
    pub fn na(x: Vector) -> Vector3<f64> {
        Vector3::new(x.x as f64, x.y as f64, x.z as f64)
    }
    /// f64 → f32 rotation.
    pub fn q(x: &UnitQuaternion<f64>) -> Rotation {
        Rotation::from_xyzw(x.i as f32, x.j as f32, x.k as f32, x.w as f32).normalize()
    }
    /// f32 → f64 rotation.
    pub fn naq(x: Rotation) -> UnitQuaternion<f64> {
        UnitQuaternion::from_quaternion(Quaternion::new(
            x.w as f64, x.x as f64, x.y as f64, x.z as f64,
        ))
    }
    /// f64 → f32 pose.
    pub fn pose(x: &Isometry3<f64>) -> Pose {
        Pose::from_parts(v(&x.translation.vector), q(&x.rotation))
    }
}

/// Runs `SimStep` as many times as the budget says (the `Update` system).
fn advance(world: &mut World) {
    let n = world.resource::<StepBudget>().0;
    for _ in 0..n {
        world.run_schedule(SimStep);
    }
    world.resource_mut::<StepBudget>().0 = 0;
}

/// Environment: the gravity field on every body; in orbit, the gravity-gradient torque.
fn environment_gravity(
    gravity: Option<Res<Gravity>>,
    orbit: Option<Res<OrbitEnv>>,
    mut q: Query<(&SimBody, &BodyState, &mut Wrench)>,
) {
    for (b, s, mut w) in &mut q {
        if let Some(g) = &gravity {
            w.gravity_n += g.0.accel_m_s2(&s.pos_m) * b.mass_kg;
        }
        if let Some(env) = &orbit
            && env.gravity_gradient
        {
            let r = env.reference.state().0 + s.pos_m;
            let dcm_body_from_world = s.att.inverse().to_rotation_matrix().into_inner();
            let tb = crate::orbit::gravity::gravity_gradient_torque_body(
                &r,
                &dcm_body_from_world,
                &b.inertia_kg_m2,
            );
            w.torque_nm += s.att * tb;
        }
    }
}

/// Keeps the reference orbit used for gravity-gradient torques and frames in step with the
/// gravity field (the field owns its own copy).
fn advance_orbit(mut orbit: Option<ResMut<OrbitEnv>>, clock: Res<Clock>) {
    if let Some(env) = orbit.as_mut() {
        env.reference.step(clock.dt_s);
    }
}

/// One RK4 step of Euler's equations J ω̇_b = τ_b − ω_b × J ω_b with quaternion kinematics
/// q̇ = ½ q ⊗ (0, ω_b), in f64; the torque is held constant in the world frame over the step.
/// Returns the new attitude (body → world) and world-frame angular velocity.
pub fn rotate_rk4(
    att: &UnitQuaternion<f64>,
    omega_world: &Vector3<f64>,
    torque_world: &Vector3<f64>,
    j: &Matrix3<f64>,
    j_inv: &Matrix3<f64>,
    dt: f64,
) -> (UnitQuaternion<f64>, Vector3<f64>) {
    use nalgebra::Quaternion;
    let f = |q: &Quaternion<f64>, w: &Vector3<f64>| {
        let qn = UnitQuaternion::from_quaternion(*q);
        let tau_b = qn.inverse() * torque_world;
        let wd = j_inv * (tau_b - w.cross(&(j * w)));
        let qd = q * Quaternion::from_imag(*w) * 0.5;
        (qd, wd)
    };
    let q0 = att.into_inner();
    let w0 = att.inverse() * omega_world;
    let (k1q, k1w) = f(&q0, &w0);
    let (k2q, k2w) = f(&(q0 + k1q * (dt / 2.0)), &(w0 + k1w * (dt / 2.0)));
    let (k3q, k3w) = f(&(q0 + k2q * (dt / 2.0)), &(w0 + k2w * (dt / 2.0)));
    let (k4q, k4w) = f(&(q0 + k3q * dt), &(w0 + k3w * dt));
    let q1 = UnitQuaternion::from_quaternion(q0 + (k1q + k2q * 2.0 + k3q * 2.0 + k4q) * (dt / 6.0));
    let w1 = w0 + (k1w + k2w * 2.0 + k3w * 2.0 + k4w) * (dt / 6.0);
    (q1, q1 * w1)
}

/// Physics: apply wrenches, step rapier, update the f64 truth, advance the reference orbit and
/// the clock.
///
/// Free flight, in f64: with a_g(x) the differential gravity and a_c the held force per mass,
/// x₁ = x₀ + v₀·dt + ½(a_g(x₀) + a_c)·dt², v₁ = v₀ + ½(a_g(x₀) + a_g(x₁))·dt + a_c·dt
/// (velocity Verlet for gravity, exact for the held force: second order), and the rotation by
/// [`rotate_rk4`]. rapier's own free-flight rotation (f32, implicit gyroscopic step) loses
/// 1.7 % of the kinetic energy of a tumbling body over 600 s (`tests/val_tumbling.rs` measures
/// it), so in free flight rapier only detects contacts; its result is overwritten by the f64
/// state.
fn physics_step(
    mut phys: ResMut<Physics>,
    mut clock: ResMut<Clock>,
    gravity: Option<ResMut<Gravity>>,
    mut q: Query<(&SimBody, &mut BodyState, &mut Wrench)>,
    mut contact: ResMut<monitor::ContactState>,
    mut compliant: Option<ResMut<contact_model::CompliantContact>>,
) {
    let dt = clock.dt_s;
    {
        let world = &mut phys.world;
        for (b, _, w) in &q {
            if let Some(rb) = world.bodies.get_mut(b.handle) {
                // rapier keeps user forces and torques until cleared, and `reset_forces` clears
                // only the forces: without `reset_torques` every torque ever commanded would
                // act again whenever rapier is the truth (contact, latch).
                rb.reset_forces(false);
                rb.reset_torques(false);
                rb.add_force(conv::v(&(w.force_n + w.gravity_n)), true);
                rb.add_torque(conv::v(&w.torque_nm), true);
            }
        }
    }
    // Compliant docking contact: the docking pair sub-stepped in f64 while it can touch.
    let substepped = compliant.as_deref_mut().and_then(|c| {
        c.t_step_s = clock.t_s();
        c.pre_step(&q, &mut phys.world, dt)
    });
    let substeps = phys.substeps;
    for _ in 0..substeps {
        phys.world.step();
    }
    // The gravity field moves to t + dt first: gravity at the new positions needs it.
    let gravity = gravity.map(|mut g| {
        g.0.advance(dt);
        g
    });
    // Which bodies touch something or are jointed: rapier is the truth for those.
    contact.refresh_touching(&phys.world);
    let world = &mut phys.world;
    for (b, mut s, mut w) in &mut q {
        let Some(rb) = world.bodies.get_mut(b.handle) else {
            continue;
        };
        let attached = contact.touching.get(b.index).copied().unwrap_or(false)
            || world
                .impulse_joints
                .attached_joints(b.handle)
                .next()
                .is_some();
        if attached {
            contact_model::note_rapier_held(compliant.as_deref_mut(), &substepped, b.index);
            let pose = rb.position();
            let att = conv::naq(pose.rotation);
            s.att = att;
            s.pos_m = conv::na(pose.translation) + att * b.com_body_m;
            let v_new = conv::na(rb.linvel());
            // The contact (and joint) impulse on this body: its momentum change less what the
            // applied forces gave it over the step; likewise its angular impulse about the
            // centre of mass.
            contact.body_impulse[b.index] =
                (v_new - s.vel_m_s) * b.mass_kg - (w.force_n + w.gravity_n) * dt;
            let l_old = monitor::angular_momentum(&s.att, &b.inertia_kg_m2, &s.omega_rad_s);
            s.vel_m_s = v_new;
            s.omega_rad_s = conv::na(rb.angvel());
            contact.body_angular_impulse[b.index] =
                monitor::angular_momentum(&s.att, &b.inertia_kg_m2, &s.omega_rad_s)
                    - l_old
                    - w.torque_nm * dt;
        } else if let Some((_, new)) = substepped
            .as_ref()
            .and_then(|v| v.iter().find(|(i, _)| *i == b.index))
        {
            contact.body_impulse[b.index] = Vector3::zeros();
            contact.body_angular_impulse[b.index] = Vector3::zeros();
            *s = new.clone();
            rb.set_position(conv::pose(&s.body_pose(&b.com_body_m)), false);
            rb.set_linvel(conv::v(&s.vel_m_s), false);
            rb.set_angvel(conv::v(&s.omega_rad_s), false);
        } else {
            contact.body_impulse[b.index] = Vector3::zeros();
            contact.body_angular_impulse[b.index] = Vector3::zeros();
            let a_g0 = w.gravity_n / b.mass_kg;
            let a_c = w.force_n / b.mass_kg;
            let v0 = s.vel_m_s;
            s.pos_m += v0 * dt + (a_g0 + a_c) * (0.5 * dt * dt);
            let a_g1 = match &gravity {
                Some(g) => g.0.accel_m_s2(&s.pos_m),
                None => Vector3::zeros(),
            };
            s.vel_m_s = v0 + (a_g0 + a_g1) * (0.5 * dt) + a_c * dt;
            let (att, omega) = rotate_rk4(
                &s.att,
                &s.omega_rad_s,
                &w.torque_nm,
                &b.inertia_kg_m2,
                &b.inertia_inv,
                dt,
            );
            s.att = att;
            s.omega_rad_s = omega;
            let pose = s.body_pose(&b.com_body_m);
            rb.set_position(conv::pose(&pose), false);
            rb.set_linvel(conv::v(&s.vel_m_s), false);
            rb.set_angvel(conv::v(&s.omega_rad_s), false);
        }
        *w = Wrench::default();
    }
    clock.step += 1;
}

/// The monitor's running results.
#[derive(Resource, Debug, Clone, Default)]
pub struct MonitorState {
    /// Body views (f64 truth) at the last step.
    pub bodies: Vec<BodyView>,
    /// Pair distances at the last step.
    pub pairs: Vec<PairDistance>,
    /// Smallest distance seen over the run, per pair (same order as `pairs`).
    pub min_per_pair: Vec<PairMin>,
    /// `body/collider` names, per body, in collider order.
    pub part_names: Vec<Vec<String>>,
    /// Per body, per collider: a docking part (cone or slot).
    pub part_docking: Vec<Vec<bool>>,
    /// Smallest non-docking clearance seen over the run, per pair (same order as `pairs`), m.
    pub min_clearance_per_pair: Vec<f64>,
    /// Distance queries made (exact parry calls) over the run.
    pub exact_queries: u64,
    /// Part pairs skipped by bounding-sphere pruning over the run.
    pub pruned_pairs: u64,
}

/// The closest approach of one body pair over a run.
#[derive(Debug, Clone)]
pub struct PairMin {
    /// Distance, m.
    pub distance_m: f64,
    /// Part of the first body.
    pub part_a: usize,
    /// Part of the second body.
    pub part_b: usize,
    /// When, s.
    pub t_s: f64,
}

impl MonitorState {
    /// `body/collider` name of a part.
    pub fn part_name(&self, body: usize, part: usize) -> &str {
        &self.part_names[body][part]
    }
    /// Names of the closest parts of a pair.
    pub fn pair_names(&self, p: &PairDistance) -> (&str, &str) {
        (self.part_name(p.a, p.part_a), self.part_name(p.b, p.part_b))
    }
}

/// Evaluates guarantees.
fn check_guarantees(
    clock: Res<Clock>,
    mon: Res<MonitorState>,
    mut g: ResMut<Guarantees>,
    mut log: ResMut<EventLog>,
) {
    let t = clock.t_s();
    let view = MonitorView {
        t_s: t,
        bodies: &mon.bodies,
        pairs: &mon.pairs,
    };
    let g = &mut *g;
    for (inv, st) in g.list.iter().zip(g.status.iter_mut()) {
        let m = inv.margin(&view);
        match st.update(t, m) {
            Some(true) => log.push(
                t,
                "guarantee_violated",
                serde_json::json!({"name": st.name, "margin": m, "unit": st.unit}),
            ),
            Some(false) => log.push(
                t,
                "guarantee_restored",
                serde_json::json!({"name": st.name, "margin": m, "unit": st.unit}),
            ),
            None => {}
        }
    }
}

/// Adds the pipeline to an app: the `SimStep` schedule with its chained stages and the systems
/// of the core (environment, physics, monitor, guarantees, recorder).
pub fn add_pipeline(app: &mut App) {
    let mut schedule = Schedule::new(SimStep);
    schedule.configure_sets(
        (
            Stage::Sense,
            Stage::Control,
            Stage::Actuate,
            Stage::Environment,
            Stage::Physics,
            Stage::Monitor,
            Stage::Record,
        )
            .chain(),
    );
    schedule.add_systems((
        environment_gravity.in_set(Stage::Environment),
        (physics_step, advance_orbit).chain().in_set(Stage::Physics),
        (monitor::distances, monitor::contacts, check_guarantees)
            .chain()
            .in_set(Stage::Monitor),
        output::record.in_set(Stage::Record),
    ));
    app.add_schedule(schedule);
    app.add_systems(Update, advance);
}

/// Helpers for `rpod bench`.
pub mod bench_support {
    use super::{BodyState, MonitorState, Part, Roster, SimBody, Simulation};
    use bevy_rapier3d::rapier::prelude as rp;
    use nalgebra::Isometry3;

    /// World poses and shapes of the closest part pair of every body pair.
    pub fn closest_pair_shapes(
        sim: &mut Simulation,
        mon: &MonitorState,
    ) -> Vec<(
        Isometry3<f64>,
        rp::SharedShape,
        Isometry3<f64>,
        rp::SharedShape,
    )> {
        let w = sim.app.world_mut();
        let roster = w.resource::<Roster>().clone();
        let find = |w: &bevy::prelude::World, full: &str| {
            let (body, part) = full.split_once('/').expect("body/part");
            let i = roster.names.iter().position(|n| n == body).expect("body");
            let b = w.get::<SimBody>(roster.bodies[i]).expect("body");
            let s = w.get::<BodyState>(roster.bodies[i]).expect("state");
            let pe = roster.parts[i]
                .iter()
                .find(|e| w.get::<Part>(**e).expect("part").name == part)
                .expect("part");
            let p = w.get::<Part>(*pe).expect("part");
            (s.body_pose(&b.com_body_m) * p.pose_body, p.shape.clone())
        };
        mon.pairs
            .iter()
            .map(|p| {
                let (na, nb) = mon.pair_names(p);
                let (pa, a) = find(w, na);
                let (pb, b) = find(w, nb);
                (pa, a, pb, b)
            })
            .collect()
    }
}
