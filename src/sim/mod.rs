//! The Bevy layer: a scene becomes a Bevy [`App`] whose `SimStep` schedule runs, every fixed
//! step, the stages Sense → Control → Actuate → Environment → Physics (rapier) → Monitor →
//! Record, each a [`SystemSet`] chained explicitly.
//!
//! # One plugin per feature
//! [`Simulation::new`] adds, in this order: [`PipelinePlugin`] (the schedule, the [`Stage`] and
//! [`Order`] sets, the core systems), [`guard::GuardPlugin`], [`environment::EnvironmentPlugin`],
//! then, where the scene has them, [`overlap::OverlapPlugin`], [`docking::DockingPlugin`],
//! [`airbearing::AirBearingPlugin`], and [`controllers::ControllersPlugin`]. Each plugin's doc
//! comment names what it owns and the sets its systems run in; systems of different features
//! that write the same data are ordered through [`Order`] (`tests/schedule.rs` fails on any
//! unordered pair). A plugin's fallible part (checks against the scene and the built bodies,
//! with located errors) is its constructor; `Plugin::build` only inserts and registers.
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
//! Each `App::update` advances exactly [`StepBudget`] fixed steps, never by the wall clock; the
//! same scene gives byte-identical outputs on every run. With `stepping: Fixed` (the default)
//! `SimStep` runs once per fixed step; with `MultiRate` one run of `SimStep` may cover several
//! ([`multirate`]: [`Clock::span`], planned at the head of the Actuate stage).

pub mod airbearing;
pub mod broadphase;
pub mod build;
pub mod contact_model;
pub mod controllers;
pub mod docking;
pub mod environment;
pub mod guard;
pub mod mesh;
pub mod monitor;
pub mod motion;
pub mod multirate;
pub mod output;
pub mod overlap;
pub mod plume;
pub mod snapshot;

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

impl Stage {
    /// Every stage, in pipeline order.
    pub const ALL: [Stage; 7] = [
        Stage::Sense,
        Stage::Control,
        Stage::Actuate,
        Stage::Environment,
        Stage::Physics,
        Stage::Monitor,
        Stage::Record,
    ];
}

/// The order, inside a stage, of the systems of different features that write the same data
/// (a body's `Wrench`, the event log, the docking state). Every such pair is ordered through
/// these sets, so the order of floating-point sums — part of a run's bit-exact result — is
/// stated here rather than left to insertion order (`tests/schedule.rs` fails on any unordered
/// pair).
#[derive(SystemSet, Debug, Clone, PartialEq, Eq, Hash)]
pub enum Order {
    /// Actuate, before anything acts: the step's length ([`multirate::plan_step`]; the
    /// controllers have run, their commands are held over it).
    Plan,
    /// Actuate, then: a docking mechanism's forces (the magnet).
    MechanismForces,
    /// Actuate, then: the controllers' commands.
    ControllerForces,
    /// Actuate, last: the plume impingement loads of the jets the controllers fire.
    PlumeForces,
    /// Environment, first: an air-bearing table's forces (film, friction, tilt).
    TableForces,
    /// Environment, then: gravity (differential, J2, gravity gradient).
    Gravity,
    /// Monitor, first (after an air-bearing table's planar constraint, which runs before it):
    /// the controllers' post-step diagnostics (they read the docking state the step started
    /// with: the mechanism is updated below).
    PostStepDiagnostics,
    /// Monitor: full-geometry distances and contacts.
    Geometry,
    /// Monitor: mechanism states from the contacts (capture, latch).
    Mechanism,
    /// Monitor, last: guarantees (margins, verdicts, their events).
    Guarantees,
}

/// Simulated clock. `step` counts completed fixed steps; `t_s = step · dt_s` (never
/// accumulated). A pipeline step spans `span` fixed steps: always 1 with `stepping: Fixed`;
/// with `MultiRate`, [`multirate::plan_step`] sets it each step (see [`multirate`]).
#[derive(Resource, Debug, Clone)]
pub struct Clock {
    /// Completed fixed steps.
    pub step: u64,
    /// Fixed step, s.
    pub dt_s: f64,
    /// Fixed steps the current pipeline step covers (≥ 1).
    pub span: u64,
}

impl Clock {
    /// A clock at t = 0 stepping by `dt_s`, one fixed step per pipeline step.
    pub fn new(dt_s: f64) -> Self {
        Self {
            step: 0,
            dt_s,
            span: 1,
        }
    }
    /// Simulated time, s.
    pub fn t_s(&self) -> f64 {
        self.step as f64 * self.dt_s
    }
    /// Length of the current pipeline step, s: `span · dt_s` (exactly `dt_s` when span = 1).
    pub fn h_s(&self) -> f64 {
        if self.span == 1 {
            self.dt_s
        } else {
            self.span as f64 * self.dt_s
        }
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

pub use crate::environment::GravityField;
pub use environment::{Env, OrbitEnv};

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

impl From<&BodyState> for crate::control::interface::BodyObs {
    /// The truth as a controller sees it, without gravity (zero).
    fn from(s: &BodyState) -> Self {
        Self::new(s.pos_m, s.vel_m_s, s.att, s.omega_rad_s, Vector3::zeros())
    }
}

impl BodyState {
    /// Yaw about the world z axis: the angle of the body x axis from world x, rad (on an
    /// air-bearing table, the lab frame's θ).
    pub fn yaw_rad(&self) -> f64 {
        crate::control::sensor::yaw_of(&self.att)
    }

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
    /// Their margin (with its certified lower bound) at the last sample, same order.
    pub last: Vec<crate::geometry::bounds::Bracket>,
    /// The rate bound each was judged with over the last step (`None`: at the sample only),
    /// same order (read by [`multirate::plan_step`]).
    pub last_rate: Vec<Option<f64>>,
    /// Exact parry calls made by the interval searches of guarantees over the run.
    pub interval_queries: u64,
}

impl Guarantees {
    /// Whether a guarantee from outside the scene's list (a law's, a user's) may join: its
    /// name follows the one name rule of every scene name (or joins up to 4 such names with
    /// `.`, as a law composes `capture.p.e` from body names) and is not taken (it becomes two
    /// `trajectory.csv` columns and a key of `summary.json`), its unit is 1 to 16 of
    /// A-Z a-z 0-9 _ /.
    pub fn admissible(&self, g: &dyn Guarantee) -> Result<(), String> {
        if let Some(p) = crate::scene::validate::composed_name_problem(g.name()) {
            return Err(format!("guarantee name: {p}"));
        }
        if self.status.iter().any(|s| s.name == g.name()) {
            return Err(format!("a guarantee named `{}` already exists", g.name()));
        }
        let unit = g.unit();
        if unit.is_empty()
            || unit.len() > 16
            || !unit
                .chars()
                .all(|c| c.is_ascii_alphanumeric() || "_/".contains(c))
        {
            return Err(format!(
                "guarantee `{}`: unit {unit:?} must be 1 to 16 of A-Z a-z 0-9 _ /",
                g.name()
            ));
        }
        Ok(())
    }

    /// Registers a guarantee (checked by [`Guarantees::admissible`] where it does not come
    /// from the validated scene).
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
    /// Bytes of event data raised (JSON), for the run's limit
    /// ([`guard::MAX_EVENT_BYTES_PER_RUN`]).
    pub bytes: u64,
}

/// Most bytes of JSON one event's data may hold; a larger one (a law's huge diagnostic, a
/// condition written out in full) is kept as its first [`EVENT_HEAD_CHARS`] characters with
/// `truncated_bytes`, so one event cannot flood `events.jsonl`.
pub const MAX_EVENT_DATA_BYTES: usize = 16 << 10;

/// Characters kept of an event's data beyond [`MAX_EVENT_DATA_BYTES`].
pub const EVENT_HEAD_CHARS: usize = 1024;

impl EventLog {
    /// Raises an event.
    pub fn push(&mut self, t_s: f64, kind: &str, data: serde_json::Value) {
        let mut data = match data {
            serde_json::Value::Object(m) => m,
            _ => serde_json::Map::new(),
        };
        let len = serde_json::to_string(&data).map_or(0, |j| j.len());
        if len > MAX_EVENT_DATA_BYTES {
            let head: String = serde_json::to_string(&data)
                .unwrap_or_default()
                .chars()
                .take(EVENT_HEAD_CHARS)
                .collect();
            data = serde_json::Map::new();
            data.insert("truncated_bytes".into(), len.into());
            data.insert("head".into(), head.into());
        }
        self.bytes += len.min(MAX_EVENT_DATA_BYTES) as u64 + kind.len() as u64 + 24;
        // A kind is a short word (`contact_start`); a law's may be anything: at most 64
        // characters are kept.
        let kind: String = kind.chars().take(64).collect();
        self.pending.push(Event { t_s, kind, data });
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

/// Runs `SimStep` until the budget's fixed steps are done (the `Update` system): once per
/// fixed step with `stepping: Fixed`; with `MultiRate` a pipeline step may cover several, never
/// past the budget ([`multirate::SpanCap`]).
fn advance(world: &mut World) {
    let n = world.resource::<StepBudget>().0;
    let start = world.resource::<Clock>().step;
    // The schedule is taken out of `Schedules` once for the whole budget, not once a step
    // (`run_schedule` moves it out of the map and back every call).
    world.schedule_scope(SimStep, |world, schedule| {
        loop {
            let done = world.resource::<Clock>().step - start;
            if done >= n {
                break;
            }
            world.resource_mut::<multirate::SpanCap>().0 = n - done;
            schedule.run(world);
            if world.resource::<guard::Guard>().trip().is_some() {
                break;
            }
        }
    });
    world.resource_mut::<StepBudget>().0 = 0;
}

/// Environment: the gravity field on every body; in orbit, the gravity-gradient torque.
fn environment_gravity(env: Res<Env>, mut q: Query<(&SimBody, &BodyState, &mut Wrench)>) {
    let gravity = env.gravity();
    let orbit = env.orbit();
    for (b, s, mut w) in &mut q {
        if let Some(g) = gravity {
            w.gravity_n += g.accel_m_s2(&s.pos_m) * b.mass_kg;
        }
        if let Some(o) = orbit
            && o.gravity_gradient
        {
            let r = o.reference.state().0 + s.pos_m;
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

pub use crate::math::rigid::rotate_rk4;

/// rapier is stepped while the axis-aligned boxes of two bodies' colliders can be within this
/// of each other during the step, m: rapier's broad phase pairs colliders whose boxes, grown by
/// its prediction distance (0.02 m) and its tree's change-detection skin (0.04 m a side),
/// overlap. Stepping rapier from well before a pair can exist there keeps rapier's state, when
/// the pair does come near, the same as if it had stepped all along — so skipping free flight
/// does not change a single output byte (checked on every bundled scene against the outputs of
/// the build that stepped rapier every step) — except where a first contact opens several
/// collider pairs at once (the `geng2015_*` scenes: bus, antenna and port parts): rapier
/// optimises its BVH incrementally every step (frame-indexed sub-tree rotation), so the tree,
/// and the order in which it reports the new pairs to the solver, depend on how many steps it
/// took; the first-contact impulse then differs in the last digits (13.03 vs 13.19 N·s in
/// `geng2015_m1_linear`), whatever this margin (tried 0.25, 1 and 10 m). Runs stay
/// deterministic; `monitor: (rapier_every_step: true)` steps rapier every step as before.
pub const RAPIER_ENGAGE_M: f64 = 1.0;

/// rapier makes contact points for colliders closer than its prediction distance (0.02 m by
/// default) at the start of its step; a pair closer than this (90 % of it) is left to rapier, m.
pub const RAPIER_SEES_M: f64 = 0.018;

/// A step is split at the time the swept test finds a pair's gap at or below this (half of
/// rapier's 0.02 m prediction distance), so that rapier, stepping the rest, sees the contact, m.
pub const SPLIT_GAP_M: f64 = 0.01;

/// Bookkeeping of the f64 → rapier hand-over (see `physics_step`).
#[derive(Resource, Debug, Clone, Default)]
pub struct RapierSync {
    /// Per body: rapier's copy of its state is older than the f64 truth (free flight since
    /// the last rapier step); written just before rapier next steps.
    pub stale: Vec<bool>,
    /// Steps in which rapier stepped.
    pub rapier_steps: u64,
    /// Steps in which no pair could come near: rapier was not stepped.
    pub skipped_steps: u64,
    /// Steps split at a time of impact found by the swept test.
    pub split_steps: u64,
    /// Start of the last split step's rapier part (absolute time, s), if the last step was split.
    pub last_split_s: Option<f64>,
    /// rapier stepped in the last step (its contact pairs are current).
    pub stepped: bool,
    /// Exact parry calls of the swept tests over the run.
    pub swept_queries: u64,
    /// Step rapier every step, free flight included (scene `monitor.rapier_every_step`).
    pub every_step: bool,
}

/// Scratch buffers of the physics step.
#[derive(Default)]
pub struct PhysicsScratch {
    /// Per body, in scene order: the state at the start of the step.
    start: Vec<BodyState>,
    /// Per body: the f64 free-flight end state.
    free_end: Vec<BodyState>,
    /// Pair evaluation buffers.
    dist: monitor::DistanceScratch,
    /// The swept test's body pairs (kept between steps for its allocation).
    pairs: Vec<(usize, usize)>,
    /// Per body: touching another or jointed at the start of the step (kept likewise).
    attached: Vec<bool>,
}

impl guarantee_bounds::MotionBounds for motion::StepMotion {
    fn dt_s(&self) -> f64 {
        self.dt_s
    }
    fn speed_bound(&self, i: usize) -> f64 {
        motion::StepMotion::speed_bound(self, i)
    }
    fn rel_speed_bound(&self, i: usize, j: usize) -> f64 {
        motion::StepMotion::rel_speed_bound(self, i, j)
    }
    fn omega_bound(&self, i: usize) -> f64 {
        motion::StepMotion::omega_bound(self, i)
    }
    fn extent_m(&self, i: usize) -> f64 {
        self.extent_m[i]
    }
    fn separation_bound(&self, i: usize, j: usize) -> f64 {
        motion::StepMotion::separation_bound(self, i, j)
    }
    fn distance_rate_bound(&self, i: usize, j: usize) -> f64 {
        motion::StepMotion::distance_rate_bound(self, i, j)
    }
}

/// The step's motion bounds with the bound on the Hill frame's rate (orbit scenes).
struct FrameMotion<'a> {
    motion: &'a motion::StepMotion,
    /// The reference orbit, for the Hill frame's rate bound (computed on first use, once a
    /// step: most guarantees never ask for it).
    orbit: Option<&'a OrbitEnv>,
    hill_rate_rad_s: std::cell::OnceCell<Option<f64>>,
    /// Set when a bound that rests on the bodies' rotation was read (an angular-speed bound,
    /// or a full-geometry distance rate): in a step that turns a body by more than
    /// [`motion::UNDER_RESOLVED_TURN_RAD`] such a bound is not proven.
    rotation_read: std::cell::Cell<bool>,
}

impl guarantee_bounds::MotionBounds for FrameMotion<'_> {
    fn dt_s(&self) -> f64 {
        self.motion.dt_s
    }
    fn speed_bound(&self, i: usize) -> f64 {
        self.motion.speed_bound(i)
    }
    fn rel_speed_bound(&self, i: usize, j: usize) -> f64 {
        self.motion.rel_speed_bound(i, j)
    }
    fn omega_bound(&self, i: usize) -> f64 {
        self.rotation_read.set(true);
        self.motion.omega_bound(i)
    }
    fn extent_m(&self, i: usize) -> f64 {
        self.motion.extent_m[i]
    }
    fn separation_bound(&self, i: usize, j: usize) -> f64 {
        self.motion.separation_bound(i, j)
    }
    fn distance_rate_bound(&self, i: usize, j: usize) -> f64 {
        self.rotation_read.set(true);
        self.motion.distance_rate_bound(i, j)
    }
    fn hill_rate_bound_rad_s(&self) -> Option<f64> {
        *self.hill_rate_rad_s.get_or_init(|| {
            self.orbit.and_then(|o| {
                let (r, v) = o.reference.state();
                let g = o.reference.gravity();
                crate::orbit::lvlh::hill_rate_bound_rad_s(&r, &v, self.motion.dt_s, g)
            })
        })
    }
}

mod guarantee_bounds {
    pub use crate::guarantee::MotionBounds;
}

/// Writes a body's f64 state into rapier (pose, velocities).
fn write_rapier(rb: &mut rp::RigidBody, b: &SimBody, s: &BodyState) {
    let pose = s.body_pose(&b.com_body_m);
    rb.set_position(conv::pose(&pose), false);
    rb.set_linvel(conv::v(&s.vel_m_s), false);
    rb.set_angvel(conv::v(&s.omega_rad_s), false);
}

/// Steps rapier `substeps` times with a step of `h_s` in total.
fn step_rapier(phys: &mut Physics, h_s: f64, dt_s: f64) {
    let substeps = phys.substeps;
    let full = phys.world.integration_parameters.dt;
    if h_s != dt_s {
        phys.world.integration_parameters.dt = (h_s / f64::from(substeps)) as f32;
    }
    for _ in 0..substeps {
        phys.world.step();
    }
    phys.world.integration_parameters.dt = full;
}

/// What the physics step reads and writes (the system's parameters, one per resource).
#[derive(bevy::ecs::system::SystemParam)]
struct PhysicsStep<'w, 's> {
    phys: ResMut<'w, Physics>,
    clock: ResMut<'w, Clock>,
    env: ResMut<'w, Env>,
    q: Query<
        'w,
        's,
        (
            &'static SimBody,
            &'static mut BodyState,
            &'static mut Wrench,
        ),
    >,
    contact: ResMut<'w, monitor::ContactState>,
    motion: ResMut<'w, motion::StepMotion>,
    bp: ResMut<'w, broadphase::BroadPhase>,
    sync: ResMut<'w, RapierSync>,
    mon: Res<'w, MonitorState>,
    geo: Res<'w, monitor::MonitorGeometry>,
    roster: Res<'w, Roster>,
    compliant: Option<ResMut<'w, contact_model::CompliantContact>>,
    mr: Option<Res<'w, multirate::MultiRate>>,
}

/// A body has a joint in rapier.
fn jointed(world: &rp::PhysicsWorld, h: rp::RigidBodyHandle) -> bool {
    world.impulse_joints.attached_joints(h).next().is_some()
}

/// A body's state at the end of the step under the compliant docking contact, if it
/// sub-stepped the body (`sub`: [`contact_model::CompliantContact::pre_step`]'s result).
fn substepped_state(sub: &Option<contact_model::Substepped>, k: usize) -> Option<BodyState> {
    sub.as_ref()
        .and_then(|v| v.iter().find(|(i, _)| *i == k).map(|(_, s)| s.clone()))
}

/// The step's motion bookkeeping before the free flight: the per-body constants on the first
/// step, the last step's paths kept (as `motion.prev`), this step's emptied; the scratch
/// emptied.
fn prepare_motion(p: &mut PhysicsStep, sc: &mut PhysicsScratch) {
    let n = p.roster.bodies.len();
    if p.motion.paths.len() != n {
        p.motion.paths = Vec::with_capacity(n);
        p.motion.extent_m = p.geo.extent_m.clone();
        p.motion.lambda_kg_m2 = p
            .roster
            .bodies
            .iter()
            .map(|e| motion::principal_moments(&p.q.get(*e).expect("body").0.inertia_kg_m2))
            .collect();
        p.motion.axes_body = p
            .roster
            .bodies
            .iter()
            .map(|e| motion::principal_axes(&p.q.get(*e).expect("body").0.inertia_kg_m2))
            .collect();
        p.sync.stale = vec![true; n];
    }
    sc.start.clear();
    sc.free_end.clear();
    if p.motion.ready {
        // The last step's paths become `prev`; the buffers of the step before it are reused
        // for this step's (emptied below), not allocated anew.
        let m = &mut *p.motion;
        match m.prev.as_deref_mut() {
            Some(prev) => {
                std::mem::swap(&mut prev.0, &mut m.paths);
                std::mem::swap(&mut prev.1, &mut m.free_before);
            }
            None => {
                let paths = std::mem::replace(&mut p.motion.paths, Vec::with_capacity(n));
                let free = std::mem::take(&mut p.motion.free_before);
                p.motion.prev = Some(Box::new((paths, free)));
            }
        }
    }
    p.motion.paths.clear();
    // Every body's entry None (in place when the length is right: no copy of a `None` path).
    if p.motion.free_before.len() == n {
        p.motion.free_before.iter_mut().for_each(|f| *f = None);
    } else {
        p.motion.free_before.clear();
        p.motion.free_before.resize(n, None);
    }
}

/// Hands every body's wrench to rapier (used if it steps).
fn apply_wrenches(
    world: &mut rp::PhysicsWorld,
    q: &Query<(&SimBody, &mut BodyState, &mut Wrench)>,
) {
    for (b, _, w) in q.iter() {
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

/// Step 1 of [`physics_step`]: the f64 free flight of every body over `dt` from `t0`, in
/// scene order (velocity Verlet for gravity, the held force exactly, the rotation by
/// [`rotate_rk4`]; a body the compliant contact sub-stepped takes its end state), into
/// `sc.start`, `sc.free_end` and `motion.paths`; the broad phase follows the paths.
fn free_flight(
    p: &mut PhysicsStep,
    sc: &mut PhysicsScratch,
    substepped: &Option<contact_model::Substepped>,
    t0: f64,
    dt: f64,
) {
    let gravity = p.env.gravity();
    let mut under_resolved = false;
    for e in &p.roster.bodies {
        let (b, s, w) = p.q.get(*e).expect("roster body");
        let a_g0 = w.gravity_n / b.mass_kg;
        let a_c = w.force_n / b.mass_kg;
        let v0 = s.vel_m_s;
        let mut end = s.clone();
        end.pos_m += v0 * dt + (a_g0 + a_c) * (0.5 * dt * dt);
        let a_g1 = match gravity {
            Some(g) => g.accel_m_s2(&end.pos_m),
            None => Vector3::zeros(),
        };
        end.vel_m_s = v0 + (a_g0 + a_g1) * (0.5 * dt) + a_c * dt;
        let (att, omega) = rotate_rk4(
            &s.att,
            &s.omega_rad_s,
            &w.torque_nm,
            &b.inertia_kg_m2,
            &b.inertia_inv,
            dt,
        );
        end.att = att;
        end.omega_rad_s = omega;
        let turn = s.att.angle_to(&att);
        if turn > motion::UNDER_RESOLVED_TURN_RAD {
            under_resolved = true;
            if turn > p.motion.max_turn_rad.0 {
                p.motion.max_turn_rad = (turn, b.index);
            }
        }
        let path = match substepped_state(substepped, b.index) {
            // Sub-stepped under the compliant contact: its end state, and (as for a step
            // rapier takes) a straight line plus constant-rate rotation between the ends.
            Some(sub) => {
                end = sub;
                motion::BodyPath::straight(s, &end, dt)
            }
            None => motion::BodyPath::free(
                s,
                a_g0 + a_c,
                w.torque_nm,
                b,
                p.motion.lambda_kg_m2[b.index],
                (&end.pos_m, &end.att, &end.omega_rad_s),
                dt,
            ),
        };
        p.motion.paths.push(path);
        sc.start.push(s.clone());
        sc.free_end.push(end);
    }
    p.motion.t0_s = t0;
    p.motion.dt_s = dt;
    p.motion.ready = true;
    p.motion.under_resolved_steps += u64::from(under_resolved);
    p.motion.under_resolved = under_resolved;
    p.bp.update(&p.motion);
}

/// A body as a member of a latched stack ([`crate::math::stack`]) in state `s`, with the
/// wrench held on it (none: no force, gravity or torque).
pub(crate) fn stack_member(
    b: &SimBody,
    s: &BodyState,
    w: Option<&Wrench>,
) -> crate::math::stack::Member {
    let w = w.cloned().unwrap_or_default();
    crate::math::stack::Member {
        mass_kg: b.mass_kg,
        inertia_kg_m2: b.inertia_kg_m2,
        pos_m: s.pos_m,
        vel_m_s: s.vel_m_s,
        att: s.att,
        omega_rad_s: s.omega_rad_s,
        force_n: w.force_n,
        gravity_n: w.gravity_n,
        torque_nm: w.torque_nm,
    }
}

/// What held one member of a latched stack over a step: (body, impulse, N·s; angular impulse
/// about its centre of mass, N·m·s).
type HeldBy = (usize, Vector3<f64>, Vector3<f64>);

/// Step 1b of [`physics_step`] under a latched stack's long step (`members`, planned by
/// [`multirate::plan_step`]): the stack flown as one rigid body ([`crate::math::stack::fly`])
/// replaces its members' free-flight ends; their paths are the straight line and constant-rate
/// rotation between their committed poses, as for a step rapier takes; the broad phase follows.
/// Returns, per member, what held it to the stack over the step: (body, impulse, N·s; angular
/// impulse about its centre of mass, N·m·s), for [`commit`]'s caller to record as rapier's
/// joint impulses are; `None` (nothing changed) where [`crate::math::stack::fly`] has no
/// composite.
fn stack_flight(
    p: &mut PhysicsStep,
    sc: &mut PhysicsScratch,
    members: [usize; 2],
    dt: f64,
) -> Option<Vec<HeldBy>> {
    let ms = members.map(|k| {
        let (b, _, w) = p.q.get(p.roster.bodies[k]).expect("stack member");
        stack_member(b, &sc.start[k], Some(w))
    });
    let env = &*p.env;
    // The planner built the same composite from the same states (positive masses, inertias
    // positive-definite by validation), so `None` is not expected; if it came, the step would
    // be rapier's, joint and all, as without a stack.
    let ends = crate::math::stack::fly(&ms, |x| env.accel_m_s2(x), dt)?;
    let mut held = Vec::with_capacity(2);
    for ((k, m), e) in members.iter().zip(&ms).zip(&ends) {
        let j = &m.inertia_kg_m2;
        let end = BodyState {
            pos_m: e.pos_m,
            vel_m_s: e.vel_m_s,
            att: e.att,
            omega_rad_s: e.omega_rad_s,
        };
        let impulse = (end.vel_m_s - m.vel_m_s) * m.mass_kg - (m.force_n + m.gravity_n) * dt;
        let angular = monitor::angular_momentum(&end.att, j, &end.omega_rad_s)
            - monitor::angular_momentum(&m.att, j, &m.omega_rad_s)
            - m.torque_nm * dt;
        p.motion.paths[*k] = motion::BodyPath::straight(&sc.start[*k], &end, dt);
        sc.free_end[*k] = end;
        held.push((*k, impulse, angular));
    }
    p.bp.update(&p.motion);
    Some(held)
}

/// Interior evaluations the swept test's per-part search may spend on one pair in one step
/// before it falls back to the search on the bodies' bound ([`sweep_pair`]).
const SWEEP_PART_EVALS: u32 = 1;

/// What the swept test found for one pair of bodies in free flight.
struct PairSweep {
    /// Their collider boxes may come within [`RAPIER_ENGAGE_M`] during the step.
    engage: bool,
    /// The first time into the step their gap is at most [`SPLIT_GAP_M`], s.
    hit_s: Option<f64>,
}

/// The swept test of one pair (i, j) over the step (see [`physics_step`], step 2): whether
/// rapier must step, and the time of impact inside the step if there is one.
fn sweep_pair(
    p: &PhysicsStep,
    sc: &mut PhysicsScratch,
    count: &mut monitor::QueryCount,
    (i, j): (usize, usize),
    t0: f64,
    dt: f64,
) -> PairSweep {
    let (geo, motion) = (&*p.geo, &*p.motion);
    let rate = motion.distance_rate_bound(i, j);
    let sep0 = (sc.start[i].pos_m - sc.start[j].pos_m).norm();
    let travel = (motion.speed_bound(i) + motion.speed_bound(j)) * dt;
    let engage = sep0 - geo.aabb_extent_m[i] - geo.aabb_extent_m[j] - travel <= RAPIER_ENGAGE_M;
    let none = PairSweep {
        engage,
        hit_s: None,
    };
    // Lower bound at t₀: the monitor's certified distance if it has one for t₀, else the
    // bounding spheres about the centres of mass.
    let lb0 = match p.mon.pair_index.get(&(i, j)).map(|k| &p.mon.pairs[*k]) {
        Some(pd) if pd.t_s == t0 => pd.lower_m,
        _ => sep0 - geo.extent_m[i] - geo.extent_m[j],
    };
    if lb0 - rate * dt > SPLIT_GAP_M {
        return none;
    }
    // The parts' bounds alone (no closest pair sought) for a body turning fast — its turn
    // moves a point by more than the split gap within the step, and more than the bodies'
    // relative motion does: a chaser spinning at 100 rad/s about its docking axis, its panels
    // in their slabs and its cone's solid of revolution at rest, is cleared without one exact
    // query.
    let turn = motion.omega_bound(i) * geo.extent_m[i] + motion.omega_bound(j) * geo.extent_m[j];
    if turn * dt > SPLIT_GAP_M
        && rate >= monitor::PER_PART_MIN_GAIN * motion.rel_speed_bound(i, j)
        && monitor::parts_stay_above(
            geo,
            motion,
            i,
            j,
            SPLIT_GAP_M,
            SWEEP_PART_EVALS,
            &mut sc.dist,
        )
    {
        return none;
    }
    let d0 = monitor::pair_at(geo, motion, i, j, 0.0, None, &mut sc.dist, count);
    if d0.d.value <= RAPIER_SEES_M {
        return none; // rapier sees it at the start of its step
    }
    if d0.d.lower - rate * dt > SPLIT_GAP_M {
        return none;
    }
    // A body turning fast: the per-part-pair bounds (`monitor::search_parts`) may prove the
    // gap above the split gap over the whole step where the bodies' bound cannot (a chaser
    // spinning at 100 rad/s: its panels' tips move at 240 m/s, its cone's solid of
    // revolution not at all). Proven: no time of impact. Not proven within the budget: the
    // search below, on the bodies' bound, as before.
    let (pair_rate, body_rate) =
        monitor::pair_rate_gain(geo, motion, i, j, (d0.a, d0.b), &mut sc.dist);
    if body_rate >= monitor::PER_PART_MIN_GAIN * pair_rate {
        let d1 = monitor::pair_at(
            geo,
            motion,
            i,
            j,
            dt,
            Some((d0.a, d0.b)),
            &mut sc.dist,
            count,
        );
        let (r, _) = monitor::search_parts(
            geo,
            motion,
            i,
            j,
            (d0.d, d1.d),
            0.0,
            |_| SPLIT_GAP_M,
            SWEEP_PART_EVALS,
            Some((d0.a, d0.b)),
            &mut sc.dist,
            count,
        );
        if !r.exhausted && r.lower > SPLIT_GAP_M {
            return none;
        }
    }
    let mut warm = Some((d0.a, d0.b));
    let mut f = |tau: f64| {
        let h = monitor::pair_at(geo, motion, i, j, tau, warm, &mut sc.dist, count);
        warm = Some((h.a, h.b));
        h.d
    };
    // Conservative advancement to the split gap, then bisection for the first time at or
    // below it (CA alone crawls where the rate bound is loose, e.g. a spinning panel).
    let Some((t_ca, d_ca)) =
        crate::geometry::bounds::advance_to(dt, d0.d, rate, SPLIT_GAP_M, 0.0, 16, &mut f)
    else {
        return none;
    };
    let hit_s = if d_ca.value <= SPLIT_GAP_M {
        Some(t_ca)
    } else {
        let d1 = f(dt);
        let rest = dt - t_ca;
        match crate::geometry::bounds::first_below(
            rest,
            d_ca,
            d1,
            rate,
            SPLIT_GAP_M,
            dt * 1e-6,
            64,
            |u| f(t_ca + u),
        ) {
            crate::geometry::bounds::Crossing::Never => None,
            crate::geometry::bounds::Crossing::At { t_hi, .. } => Some(t_ca + t_hi),
            crate::geometry::bounds::Crossing::Unresolved { t_lo } => Some(t_ca + t_lo),
        }
    };
    PairSweep { engage, hit_s }
}

/// Step 2 of [`physics_step`]: the swept test over the near pairs of bodies in free flight
/// (neither `attached`, not both sub-stepped by the compliant contact): whether some pair
/// makes rapier step, and the earliest time of impact inside the step.
fn swept_test(
    p: &mut PhysicsStep,
    sc: &mut PhysicsScratch,
    attached: &[bool],
    substepped: &Option<contact_model::Substepped>,
    t0: f64,
    dt: f64,
) -> (bool, Option<f64>) {
    let n = p.roster.bodies.len();
    let mut pairs = std::mem::take(&mut sc.pairs);
    pairs.clear();
    if p.bp.all_pairs {
        pairs.extend((0..n).flat_map(|i| (i + 1..n).map(move |j| (i, j))));
    } else {
        pairs.extend(p.bp.near.iter().copied());
    }
    let mut engage = false;
    let mut split: Option<f64> = None;
    let mut count = monitor::QueryCount::default();
    for &(i, j) in &pairs {
        if attached[i] || attached[j] {
            continue;
        }
        // The compliant contact owns the docking pair's motion this step.
        if substepped_state(substepped, i).is_some() && substepped_state(substepped, j).is_some() {
            continue;
        }
        let sweep = sweep_pair(p, sc, &mut count, (i, j), t0, dt);
        engage |= sweep.engage;
        if let Some(th) = sweep.hit_s {
            engage = true;
            split = Some(split.map_or(th, |s: f64| s.min(th)));
        }
    }
    p.sync.swept_queries += count.exact;
    sc.pairs = pairs;
    (engage, split)
}

/// Step 3 of [`physics_step`], when rapier steps: rapier's copy of every body in free flight
/// since its last step written from the f64 truth, then one step of `dt` — or, split at `split`
/// s into the step, the bodies rapier holds stepped to it, the free bodies placed on their
/// paths at it, and the rest of the step.
fn run_rapier(
    p: &mut PhysicsStep,
    attached: &[bool],
    any_attached: bool,
    split: Option<f64>,
    t0: f64,
    dt: f64,
) {
    for (k, e) in p.roster.bodies.iter().enumerate() {
        if p.sync.stale[k] {
            let (b, s, _) = p.q.get(*e).expect("body");
            if let Some(rb) = p.phys.world.bodies.get_mut(b.handle) {
                write_rapier(rb, b, s);
            }
            p.sync.stale[k] = false;
        }
    }
    p.sync.rapier_steps += 1;
    let step_dt = p.clock.dt_s;
    match split {
        Some(tc) if tc > 0.0 => {
            p.sync.split_steps += 1;
            p.sync.last_split_s = Some(t0 + tc);
            if any_attached || p.phys.world.impulse_joints.iter().next().is_some() {
                step_rapier(&mut p.phys, tc, step_dt);
            }
            for (k, e) in p.roster.bodies.iter().enumerate() {
                if attached[k] {
                    continue;
                }
                let b = p.q.get(*e).expect("body").0;
                let s = p.motion.paths[k].state_at(tc);
                if let Some(rb) = p.phys.world.bodies.get_mut(b.handle) {
                    write_rapier(rb, b, &s);
                }
            }
            step_rapier(&mut p.phys, dt - tc, step_dt);
        }
        _ => step_rapier(&mut p.phys, dt, step_dt),
    }
    p.contact.refresh_touching(&p.phys.world);
}

/// Step 4 of [`physics_step`]: bodies touching another or jointed (when rapier `stepped`) take
/// rapier's state, their contact impulse measured and their path made straight; the others
/// commit their f64 free-flight end state. Every wrench is cleared.
fn commit(
    p: &mut PhysicsStep,
    sc: &PhysicsScratch,
    was_attached: &[bool],
    substepped: &Option<contact_model::Substepped>,
    stepped: bool,
    t0: f64,
    dt: f64,
) {
    let world = &mut p.phys.world;
    for e in &p.roster.bodies {
        let (b, mut s, mut w) = p.q.get_mut(*e).expect("body");
        let k = b.index;
        let attached = stepped
            && (p.contact.touching.get(k).copied().unwrap_or(false) || jointed(world, b.handle));
        if attached {
            let Some(rb) = world.bodies.get(b.handle) else {
                continue;
            };
            contact_model::note_rapier_held(p.compliant.as_deref_mut(), substepped, k);
            let pose = rb.position();
            let att = conv::naq(pose.rotation);
            s.att = att;
            s.pos_m = conv::na(pose.translation) + att * b.com_body_m;
            let v_new = conv::na(rb.linvel());
            // The contact (and joint) impulse on this body: its momentum change less what the
            // applied forces gave it over the step.
            p.contact.body_impulse[k] =
                (v_new - sc.start[k].vel_m_s) * b.mass_kg - (w.force_n + w.gravity_n) * dt;
            s.vel_m_s = v_new;
            s.omega_rad_s = conv::na(rb.angvel());
            // … and its angular impulse about the centre of mass.
            let st = &sc.start[k];
            p.contact.body_angular_impulse[k] =
                monitor::angular_momentum(&s.att, &b.inertia_kg_m2, &s.omega_rad_s)
                    - monitor::angular_momentum(&st.att, &b.inertia_kg_m2, &st.omega_rad_s)
                    - w.torque_nm * dt;
            if !was_attached[k] {
                p.motion.free_before[k] = Some(p.motion.paths[k].clone());
            }
            match p.sync.last_split_s {
                Some(ts) if !was_attached[k] => p.motion.paths[k].split_then_straight(ts - t0, &s),
                _ => p.motion.paths[k] = motion::BodyPath::straight(&sc.start[k], &s, dt),
            }
        } else {
            p.contact.body_impulse[k] = Vector3::zeros();
            p.contact.body_angular_impulse[k] = Vector3::zeros();
            *s = sc.free_end[k].clone();
            p.sync.stale[k] = true;
        }
        *w = Wrench::default();
    }
}

/// Physics: the environment advanced to the step's end, then (see the steps below) the f64
/// free flight of every body, the swept test for contacts within the step, rapier only where a
/// contact is possible, then the f64 truth committed.
///
/// Free flight, in f64: with a_g(x) the differential gravity and a_c the held force per mass,
/// x₁ = x₀ + v₀·dt + ½(a_g(x₀) + a_c)·dt², v₁ = v₀ + ½(a_g(x₀) + a_g(x₁))·dt + a_c·dt
/// (velocity Verlet for gravity, exact for the held force: second order), and the rotation by
/// [`rotate_rk4`]. rapier's own free-flight rotation (f32, implicit gyroscopic step) loses
/// 1.7 % of the kinetic energy of a tumbling body over 600 s (`tests/val_tumbling.rs` measures
/// it), so in free flight rapier only detects contacts; its result is overwritten by the f64
/// state.
///
/// Each step, in order:
/// 1. The f64 free-flight end state of every body, and its path over the step
///    ([`motion::BodyPath`]); the broad phase's spheres follow ([`broadphase::BroadPhase`])
///    ([`free_flight`]).
/// 2. For every near pair of bodies in free flight, the swept test: the distance over the step
///    is at least d(t₀) − S·dt (S the pair's distance-rate bound); where that is not clear of
///    [`RAPIER_ENGAGE_M`], the exact distance at t₀ and, if rapier would not see the pair at
///    the start of its step (gap above [`SPLIT_GAP_M`]), conservative advancement and then
///    bisection along the paths for the first time the gap is at most [`SPLIT_GAP_M`]: a time
///    of impact inside the step ([`swept_test`], [`sweep_pair`]).
/// 3. rapier: not stepped at all when no pair is within [`RAPIER_ENGAGE_M`], no body touches
///    and no joint exists (rapier's state is written from the f64 truth only when it steps
///    next: [`RapierSync`]); split at the earliest time of impact — rapier-driven bodies are
///    stepped to it, the free bodies placed on their paths at it, and rapier steps the rest,
///    so the impact happens in rapier, where contacts are resolved and recorded; else one
///    ordinary step ([`run_rapier`]).
/// 4. Bodies touching another or jointed take rapier's state (and their contact impulse is
///    measured); the others commit their f64 free-flight end state — the path is the same
///    whether or not the step was split ([`commit`]).
fn physics_step(mut p: PhysicsStep, mut scratch: Local<PhysicsScratch>) {
    // The step's length: dt_s, or a multiple of it that `multirate::plan_step` proved free.
    let dt = p.clock.h_s();
    let t0 = p.clock.t_s();
    let sc = &mut *scratch;
    // The environment moves to t + dt first: gravity at the new positions needs it.
    p.env.advance(dt);
    prepare_motion(&mut p, sc);
    // The wrenches go to rapier first (used if it steps); then the compliant docking contact
    // sub-steps the docking pair in f64 while it can touch (and adds its mean wrench to
    // rapier's forces, for a step in which rapier holds one of the bodies).
    apply_wrenches(&mut p.phys.world, &p.q);
    let PhysicsStep {
        compliant, q, phys, ..
    } = &mut p;
    let substepped = compliant.as_deref_mut().and_then(|c| {
        c.t_step_s = t0;
        c.pre_step(q, &mut phys.world, dt)
    });
    // 1. f64 free flight of every body, in scene order; a latched stack on a long step flown
    // as one rigid body.
    free_flight(&mut p, sc, &substepped, t0, dt);
    let members =
        p.mr.as_deref()
            .and_then(|m| m.stack)
            .filter(|_| p.clock.span > 1);
    let held = members.and_then(|m| stack_flight(&mut p, sc, m, dt));
    let stack = held.is_some();
    // Bodies touching another or jointed when the step starts: rapier holds them (a stack's
    // members are held by the stack, and kept out of the swept test: the planner proved every
    // other body out of rapier's reach of them).
    let mut attached = std::mem::take(&mut sc.attached);
    attached.clear();
    attached.extend(p.roster.bodies.iter().map(|e| {
        let b = p.q.get(*e).expect("body").0;
        p.contact.touching.get(b.index).copied().unwrap_or(false)
            || jointed(&p.phys.world, b.handle)
    }));
    let any_attached = attached.iter().any(|a| *a);
    // 2. The swept test; rapier keeps stepping while its own broad phase still pairs any
    // colliders (not under a stack's long step, which the planner proved clear of contact).
    let (near, split) = swept_test(&mut p, sc, &attached, &substepped, t0, dt);
    let engage = if stack {
        near
    } else {
        p.sync.every_step
            || any_attached
            || p.phys.world.impulse_joints.iter().next().is_some()
            || p.phys.world.narrow_phase.contact_pairs().next().is_some()
            || near
    };
    // 3. rapier.
    let stepped = engage || split.is_some();
    p.sync.last_split_s = None;
    if stepped {
        run_rapier(&mut p, &attached, any_attached, split, t0, dt);
    } else {
        p.sync.skipped_steps += 1;
        p.contact.touching.iter_mut().for_each(|t| *t = false);
    }
    p.sync.stepped = stepped;
    // 4. Commit; a stack's members then record what held them, as rapier's joint impulses are.
    commit(&mut p, sc, &attached, &substepped, stepped, t0, dt);
    sc.attached = attached;
    for (k, impulse, angular) in held.into_iter().flatten() {
        p.contact.body_impulse[k] = impulse;
        p.contact.body_angular_impulse[k] = angular;
    }
    p.clock.step += p.clock.span;
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
    /// Position of each tracked body pair (i < j) in `pairs`.
    pub pair_index: std::collections::HashMap<(usize, usize), usize, monitor::memo::KeyHash>,
    /// The closest pair at the last step (tracked or not).
    pub closest: Option<PairDistance>,
    /// The closest approach of any pair over the run (to the tolerance of
    /// [`monitor::min_distance_tolerance_m`]), and its pair.
    pub overall: Option<PairMin>,
    /// Bodies of `overall`.
    pub overall_pair: (usize, usize),
    /// Distance evaluations made between samples over the run.
    pub interval_evals: u64,
    /// Smallest certified lower bound met on a refined interval, m.
    pub min_lower_m: f64,
    /// The closest pair found at the last row by the search over every pair (horizon mode).
    pub row_closest_pair: Option<(usize, usize)>,
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
    /// Found between two samples (by the interval search), not at a step.
    pub inside: bool,
    /// How far the recorded distance may be above the true closest approach, m: the search's
    /// tolerance, max(1 µm, 0.1 % of the distance), or — where the closest pair's certified
    /// lower bound is farther below its value — the bracket's width at a sample, twice it for
    /// the interval search ([`monitor::min_distance_tolerance_m`]).
    pub tolerance_m: f64,
}

/// Body pairs that guarantees name (always tracked by the monitor), i < j.
#[derive(Resource, Debug, Clone, Default)]
pub struct NamedPairs(pub Vec<(usize, usize)>);

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

/// Interior margin evaluations allowed per guarantee per step.
const MAX_GUARANTEE_EVALS: u32 = 256;

/// Interior margin evaluations allowed, on a step whose rotation is under-resolved
/// ([`motion::UNDER_RESOLVED_TURN_RAD`]), to look for a violation of a guarantee whose rate
/// bound reads the rotation (it cannot be judged held there: `unresolved` unless a margin
/// below zero is found), before the worst margin is refined with [`MAX_GUARANTEE_EVALS`].
///
/// Where 32 comes from: the search looks for a margin below zero (threshold 0, not the worst
/// margin's refinement) and stops at the first one. Measured: the plate of
/// `tests/val_spin_bounds.rs` sweeping through a ball between two samples of a 100 rad/s spin
/// (below zero ≈ 2.5 ms of the 10 ms step) is found at the first evaluation; on the
/// `rpod bench --cliffs` spin (`docking_aligned`, 100 rad/s, 1 910 such steps) every search
/// ended within 7 evaluations (clear of zero: 1, 3 or 7; 1 306 of them at 3). 32 is over four
/// times the most any of them needed — room for a bisection about five levels deep (31
/// evaluations fill a step to 1/32 of its width when every piece needs splitting) — and 1/8 of
/// the budget a proven step may spend. A violation the search does not land on is not missed
/// silently: the step stays `unresolved`.
const UNRESOLVED_LOOK_EVALS: u32 = 32;

/// A positive worst margin is refined until its certified lower bound is within this fraction
/// of it (or zero is proven): what matters there is the proof that it holds.
pub const POSITIVE_MARGIN_REL_TOL: f64 = 0.1;

/// A negative worst margin (a violation) is refined to this fraction of its size.
pub const NEGATIVE_MARGIN_REL_TOL: f64 = 1e-3;

/// Time tolerance of refined violation and restoration times, as a fraction of the step
/// (2⁻¹⁶: 0.15 µs at dt = 10 ms).
pub const EVENT_TIME_TOL: f64 = 1.0 / 65_536.0;

/// Margin evaluations allowed to locate one violation or restoration time.
const MAX_CROSSING_EVALS: u32 = 256;

/// The first step whose rotation the rate bounds do not cover: said once, as an event, with
/// the step that would (the count is in summary.json's monitor).
fn note_under_resolved(
    t: f64,
    motion: &motion::StepMotion,
    mon: &MonitorState,
    log: &mut EventLog,
) {
    if motion.under_resolved && motion.under_resolved_steps == 1 {
        let (turn, body) = motion.max_turn_rad;
        let name = mon.bodies.get(body).map_or("", |b| b.name.as_str());
        log.push(
            t,
            "rotation_under_resolved",
            serde_json::json!({
                "body": name,
                "turn_rad": turn,
                "limit_rad": motion::UNDER_RESOLVED_TURN_RAD,
                "dt_s_to_resolve": motion.dt_s * motion::UNDER_RESOLVED_TURN_RAD / turn,
                "consequence": "guarantees whose rate bound rests on the rotation are unresolved over such steps, never held",
            }),
        );
    }
}

/// The reference orbit `back_s` from its current time (negative: earlier), in orbit scenes.
fn reference_at(orbit: Option<&OrbitEnv>, back_s: f64) -> Option<crate::guarantee::ReferenceView> {
    orbit.map(|o| {
        // (A step of zero leaves the orbit as it is: no copy for it.)
        let (p, v) = if back_s == 0.0 {
            o.reference.state()
        } else {
            let mut r = o.reference.clone();
            r.step(back_s);
            r.state()
        };
        crate::guarantee::ReferenceView {
            pos_eci_m: p,
            vel_eci_m_s: v,
        }
    })
}

/// A guarantee without a rate bound, judged at the sample (margin `m` at `view.t_s`): its
/// verdict, and an event if it changed.
fn judge_at_sample(
    inv: &dyn Guarantee,
    st: &mut GuaranteeStatus,
    view: &MonitorView,
    m: f64,
    log: &mut EventLog,
) {
    let t = view.t_s;
    if let Some(violated) = st.update(t, m) {
        let kind = if violated {
            "guarantee_violated"
        } else {
            "guarantee_restored"
        };
        let mut e = serde_json::json!({"name": st.name, "margin": m, "unit": st.unit});
        if let Some(d) = inv.detail(view) {
            e["detail"] = d;
        }
        log.push(t, kind, e);
    }
}

/// One guarantee with a rate bound, judged over one step.
struct IntervalCase<'g> {
    /// The guarantee.
    inv: &'g dyn Guarantee,
    /// What its margin reads (the pairs evaluated at τ into the step), asked of the guarantee
    /// only when a margin inside the step is evaluated ([`IntervalCase::reads`]).
    reads: std::cell::OnceCell<crate::guarantee::Reads>,
    /// Its margin at t₀: the last sample's, or re-evaluated under this step's inputs if it
    /// reads them ([`Guarantee::step_inputs`]).
    m0: crate::geometry::bounds::Bracket,
    /// Its margin at the sample t.
    m1: crate::geometry::bounds::Bracket,
    /// Its rate bound over the step, margin unit/s.
    rate: f64,
    /// The rate bound rests on a rotation the step under-resolves (it cannot be held).
    rotation_unproven: bool,
}

impl IntervalCase<'_> {
    /// What the margin reads ([`Guarantee::reads`], asked once).
    fn reads(&self) -> &crate::guarantee::Reads {
        self.reads.get_or_init(|| self.inv.reads())
    }
}

/// What the guarantees are judged on over the step [t₀, t] (t₀ = t − dt): the monitor's sample
/// at t, the bodies' paths over the step, and the buffers and counts of the evaluations inside
/// it.
struct StepJudge<'a> {
    /// The sample at t.
    view: MonitorView<'a>,
    /// The monitor's results at t.
    mon: &'a MonitorState,
    /// The bodies' paths over the step.
    motion: &'a motion::StepMotion,
    /// The monitor's geometry.
    geo: &'a monitor::MonitorGeometry,
    /// The orbital environment (orbit scenes): the reference at τ.
    orbit: Option<&'a OrbitEnv>,
    /// Bodies at τ into the step (the last evaluation's).
    bodies_at: Vec<BodyView>,
    /// The pairs a guarantee reads, at τ into the step.
    pairs_at: Vec<PairDistance>,
    /// Distance buffers of the evaluations at τ.
    scratch: &'a mut monitor::DistanceScratch,
    /// Distance buffers of the per-part searches.
    part_scratch: &'a mut monitor::DistanceScratch,
    /// Exact queries of the evaluations at τ.
    count: monitor::QueryCount,
    /// Exact queries of the per-part searches.
    part_count: monitor::QueryCount,
}

impl StepJudge<'_> {
    /// The step's start t₀, s.
    fn t0(&self) -> f64 {
        self.view.t_s - self.motion.dt_s
    }

    /// The bodies, and the pairs `reads` names, at τ into the step (their queries counted only
    /// if `counted`: an event's detail is not part of the judgement's cost).
    fn fill(&mut self, reads: &crate::guarantee::Reads, tau: f64, counted: bool) {
        use crate::guarantee::Reads;
        let t0 = self.t0();
        let (mon, motion, geo) = (self.mon, self.motion, self.geo);
        let mut uncounted = monitor::QueryCount::default();
        let count = if counted {
            &mut self.count
        } else {
            &mut uncounted
        };
        if self.bodies_at.len() != mon.bodies.len() {
            self.bodies_at = mon.bodies.clone();
        }
        for (v, p) in self.bodies_at.iter_mut().zip(&motion.paths) {
            let s = p.state_at(tau);
            v.pos_m = s.pos_m;
            v.vel_m_s = s.vel_m_s;
            v.att = s.att;
            v.omega_rad_s = s.omega_rad_s;
        }
        self.pairs_at.clear();
        let list: Vec<(usize, usize)> = match reads {
            Reads::Bodies => Vec::new(),
            Reads::Pairs(l) => l.clone(),
            Reads::Everything => mon.pairs.iter().map(|p| (p.a, p.b)).collect(),
        };
        for (i, j) in list {
            let warm = mon.pair_index.get(&(i, j)).map(|k| {
                let p = &mon.pairs[*k];
                (p.part_a, p.part_b)
            });
            let h = monitor::pair_at(geo, motion, i, j, tau, warm, self.scratch, count);
            self.pairs_at.push(PairDistance {
                a: i,
                b: j,
                distance_m: h.d.value,
                part_a: h.a,
                part_b: h.b,
                clearance_m: h.d.value,
                lower_m: h.d.lower,
                t_s: t0 + tau,
            });
        }
    }

    /// The view at τ into the step (after [`StepJudge::fill`]).
    fn view_at(&self, tau: f64) -> MonitorView<'_> {
        MonitorView {
            t_s: self.t0() + tau,
            bodies: &self.bodies_at,
            pairs: &self.pairs_at,
            reference: reference_at(self.orbit, tau - self.motion.dt_s),
            jets: self.view.jets,
        }
    }

    /// A guarantee's margin at τ into the step.
    fn margin_at(
        &mut self,
        inv: &dyn Guarantee,
        reads: &crate::guarantee::Reads,
        tau: f64,
    ) -> crate::geometry::bounds::Bracket {
        self.fill(reads, tau, true);
        inv.margin_bracket(&self.view_at(tau))
    }

    /// The case of guarantee `inv` over the step: its margin at t₀ (`last`, the last sample's,
    /// or re-evaluated under this step's inputs) and at t (`m1`), its rate bound.
    fn case<'g>(
        &mut self,
        inv: &'g dyn Guarantee,
        last: crate::geometry::bounds::Bracket,
        m1: crate::geometry::bounds::Bracket,
        rate: f64,
        rotation_unproven: bool,
    ) -> IntervalCase<'g> {
        let reads = std::cell::OnceCell::new();
        let m0 = if inv.step_inputs() {
            self.margin_at(inv, reads.get_or_init(|| inv.reads()), 0.0)
        } else {
            last
        };
        IntervalCase {
            inv,
            reads,
            m0,
            m1,
            rate,
            rotation_unproven,
        }
    }

    /// The search inside the step for the smallest margin, to the threshold `thr` (see
    /// [`check_guarantees`]): over the per-part-pair bounds for a distance margin with a body
    /// turning fast ([`monitor::search_parts`]), else by bisection on the margin's rate bound;
    /// on an under-resolved step, first only a look for a margin below zero (or below the worst
    /// so far `w`, once violated).
    fn search(
        &mut self,
        c: &IntervalCase,
        thr: &dyn Fn(f64) -> f64,
        w: f64,
    ) -> crate::geometry::bounds::MinSearch {
        let (t, dt) = (self.view.t_s, self.motion.dt_s);
        // A margin that is a distance less a constant, with a body turning fast: the
        // per-part-pair bounds (`monitor::search_parts`).
        let per_part = c.inv.distance_margin().and_then(|(a, b, offset)| {
            let (i, j) = (a.min(b), a.max(b));
            let p = &self.mon.pairs[*self.mon.pair_index.get(&(i, j))?];
            if p.t_s != t {
                return None;
            }
            let (pair_rate, body_rate) = monitor::pair_rate_gain(
                self.geo,
                self.motion,
                i,
                j,
                (p.part_a, p.part_b),
                self.part_scratch,
            );
            (body_rate >= monitor::PER_PART_MIN_GAIN * pair_rate).then_some((
                i,
                j,
                offset,
                (p.part_a, p.part_b),
            ))
        });
        let mut search = |thr: &dyn Fn(f64) -> f64, budget: u32| match per_part {
            Some((i, j, offset, warm)) => {
                monitor::search_parts(
                    self.geo,
                    self.motion,
                    i,
                    j,
                    (c.m0, c.m1),
                    offset,
                    thr,
                    budget,
                    Some(warm),
                    self.part_scratch,
                    &mut self.part_count,
                )
                .0
            }
            None => crate::geometry::bounds::minimize(
                dt,
                c.m0,
                c.m1,
                c.rate,
                thr,
                budget,
                dt * 1e-9,
                |tau| self.margin_at(c.inv, c.reads(), tau),
            ),
        };
        if c.rotation_unproven {
            // Nothing this search finds can make the step held (its rate bound is not
            // proven): it only looks, on a small budget, for a margin below zero (or below
            // the worst so far, once violated) — a real margin at a real pose. Only when it
            // finds one is the worst margin refined as on any other step.
            let below = w.min(0.0);
            let look = |b: f64| {
                if b < below {
                    f64::NEG_INFINITY
                } else {
                    thr(b).min(0.0)
                }
            };
            let r = search(&look, UNRESOLVED_LOOK_EVALS);
            if r.value < below {
                let mut full = search(thr, MAX_GUARANTEE_EVALS);
                full.evals += r.evals;
                full
            } else {
                r
            }
        } else {
            search(thr, MAX_GUARANTEE_EVALS)
        }
    }

    /// The judgement of a case over the step (see [`check_guarantees`]): the smallest margin
    /// and its certified lower bound, refined where the verdict needs it (the worst margin so
    /// far is `w`), then the first violation and the restoration located. `was_ok`: the last
    /// sample held.
    fn finding(
        &mut self,
        c: &IntervalCase,
        w: f64,
        was_ok: bool,
    ) -> crate::guarantee::IntervalFinding {
        use crate::geometry::bounds::{Crossing, first_below, interval_lower_bound};
        let (t, dt) = (self.view.t_s, self.motion.dt_s);
        let t0 = t - dt;
        let (m0, m1, rate) = (c.m0, c.m1, c.rate);
        let floor = c.inv.margin_floor();
        // A margin whose samples' certified brackets are wider than the refinement tolerance
        // (a distance margin of a faceted cone a few centimetres from a slot wall: GJK's
        // bracket, 1.2e-3 of the distance, against 1e-3 of a sub-millimetre violation) could
        // never have that tolerance proved: its tolerance is at least
        // [`crate::geometry::bounds::provable_tolerance`] of the step's end brackets, as the
        // closest approach's is. Zero, the verdict's threshold, is unchanged.
        let provable = crate::geometry::bounds::provable_tolerance(&m0, &m1);
        let abs_tol = if provable.is_finite() {
            c.inv.tolerance().max(provable)
        } else {
            c.inv.tolerance()
        };
        let thr = |b: f64| {
            let x = w.min(b);
            let t = if x >= 0.0 {
                (x - abs_tol.max(POSITIVE_MARGIN_REL_TOL * x)).max(0.0)
            } else {
                x - abs_tol.max(NEGATIVE_MARGIN_REL_TOL * x.abs())
            };
            // The margin never goes below its floor: every sub-interval clears a threshold at
            // or under it, whatever its rate bound says.
            if t <= floor { f64::NEG_INFINITY } else { t }
        };
        let mut finding = crate::guarantee::IntervalFinding {
            min_value: m1.value,
            min_t_s: t,
            inside: false,
            lower: interval_lower_bound(m0.lower, m1.lower, rate, dt).max(floor),
            first_violation_s: None,
            restored_s: None,
            unresolved: false,
            evals: 0,
        };
        if c.inv.step_inputs() && m0.value < finding.min_value {
            // Only a margin re-evaluated at t₀ under this step's inputs can be below both the
            // sample at t₁ and what the search finds: it holds just after t₀.
            finding.min_value = m0.value;
            finding.min_t_s = t0;
            finding.inside = true;
        }
        // A floor the step's inputs give (see `Guarantee::step_floor`).
        let floor = floor.max(c.inv.step_floor(&self.view).unwrap_or(f64::NEG_INFINITY));
        finding.lower = finding.lower.max(floor);
        if finding.lower < thr(m1.value) {
            let r = self.search(c, &thr, w);
            if r.value < finding.min_value && r.t > 0.0 && r.t < dt {
                finding.min_value = r.value;
                finding.min_t_s = t0 + r.t;
                finding.inside = true;
            }
            finding.lower = r.lower.max(floor);
            finding.evals += r.evals;
        }
        let t_tol = dt * EVENT_TIME_TOL;
        let went_negative = finding.min_value < 0.0 || m1.value < 0.0;
        if was_ok && m0.value < 0.0 {
            // Violated from the step's start (the step's inputs changed there).
            finding.first_violation_s = Some((t0, t0));
        }
        let mut eval = |tau: f64| self.margin_at(c.inv, c.reads(), tau);
        if m0.value >= 0.0 && went_negative {
            let cr = first_below(dt, m0, m1, rate, 0.0, t_tol, MAX_CROSSING_EVALS, &mut eval);
            finding.first_violation_s = match cr {
                Crossing::At { t_lo, t_hi } => Some((t0 + t_lo, t0 + t_hi)),
                Crossing::Unresolved { t_lo } => Some((t0 + t_lo, t)),
                Crossing::Never => None,
            };
        }
        if m1.value >= 0.0 && (m0.value < 0.0 || finding.min_value < 0.0) {
            // The last time it was below zero: the first, going backwards from t₁.
            let cr = first_below(dt, m1, m0, rate, 0.0, t_tol, MAX_CROSSING_EVALS, |u| {
                eval(dt - u)
            });
            finding.restored_s = match cr {
                Crossing::At { t_lo, t_hi } => Some((t - t_hi, t - t_lo)),
                Crossing::Unresolved { t_lo } => Some((t0, t - t_lo)),
                Crossing::Never => None,
            };
        }
        finding.unresolved = !went_negative && (finding.lower < 0.0 || c.rotation_unproven);
        finding
    }

    /// The verdict of a case from its finding, and an event for every change (with the
    /// guarantee's detail where the new state is known to hold).
    fn report(
        &mut self,
        c: &IntervalCase,
        st: &mut GuaranteeStatus,
        finding: &crate::guarantee::IntervalFinding,
        log: &mut EventLog,
    ) {
        let (t, dt) = (self.view.t_s, self.motion.dt_s);
        let t0 = t - dt;
        for ch in st.update_interval(t, c.m1.value, finding, dt) {
            let kind = if ch.violated {
                "guarantee_violated"
            } else {
                "guarantee_restored"
            };
            let mut e = serde_json::json!({"name": st.name, "margin": ch.margin, "unit": st.unit,
                "found": if ch.inside { "interval" } else { "sample" },
                "t_tol_s": ch.t_tol_s, "t_step_s": t});
            // The detail where the new state is known to hold: the end of the time bracket.
            // (Its queries are not counted: the counts report the judgement's cost.)
            let tau = (ch.t_s + ch.t_tol_s - t0).clamp(0.0, dt);
            self.fill(c.reads(), tau, false);
            if let Some(d) = c.inv.detail(&self.view_at(tau)) {
                e["detail"] = d;
            }
            log.push(ch.t_s, kind, e);
        }
    }
}

/// Evaluates guarantees: at the step's sample and, for a guarantee with a rate bound, on the
/// whole interval since the last one.
///
/// With |m′| ≤ L over the step, the margin is at least (m(t₀) + m(t₁) − L·dt)/2 on it. If that
/// does not clear what the verdict needs — while the worst margin W so far is positive,
/// max(0, W − max([`Guarantee::tolerance`], [`POSITIVE_MARGIN_REL_TOL`]·W)) (zero proves the
/// guarantee still holds); once violated, W less max(tolerance, [`NEGATIVE_MARGIN_REL_TOL`]·|W|);
/// the tolerance at least twice the width of the step's end brackets (no search could prove
/// less) — the step is bisected on the bodies' paths
/// ([`crate::geometry::bounds::minimize`]). A violation found (at the sample or inside) is
/// then located: the first time the margin is below zero, bracketed to
/// [`EVENT_TIME_TOL`]·dt ([`crate::geometry::bounds::first_below`]), and, if it holds again by
/// the end of the step, the time it came back. A guarantee without a rate bound is judged at
/// the samples only. On a step whose rotation is under-resolved, a guarantee whose rate bound
/// reads the rotation cannot be held: its search only looks for a violation (threshold 0, at
/// most [`UNRESOLVED_LOOK_EVALS`] evaluations) and refines as above only once it finds one.
///
/// In order, per guarantee: its margin at the sample and its rate bound; without one,
/// [`judge_at_sample`]; with one, its [`IntervalCase`], then [`StepJudge::finding`] (the
/// search, [`StepJudge::search`], and the crossings) and [`StepJudge::report`].
#[allow(clippy::too_many_arguments)] // a Bevy system: one parameter per resource
fn check_guarantees(
    clock: Res<Clock>,
    mon: Res<MonitorState>,
    mut g: ResMut<Guarantees>,
    mut log: ResMut<EventLog>,
    motion: Res<motion::StepMotion>,
    geo: Res<monitor::MonitorGeometry>,
    mut scratch: Local<monitor::DistanceScratch>,
    mut part_scratch: Local<monitor::DistanceScratch>,
    env: Res<Env>,
    host: Option<Res<controllers::ControllerHost>>,
) {
    use crate::geometry::bounds::Bracket;
    let t = clock.t_s();
    note_under_resolved(t, &motion, &mon, &mut log);
    let jets = jets_view(host.as_deref());
    let orbit = env.orbit();
    let mut judge = StepJudge {
        view: MonitorView {
            t_s: t,
            bodies: &mon.bodies,
            pairs: &mon.pairs,
            reference: reference_at(orbit, 0.0),
            jets: &jets,
        },
        mon: &mon,
        motion: &motion,
        geo: &geo,
        orbit,
        bodies_at: Vec::new(),
        pairs_at: Vec::new(),
        scratch: &mut scratch,
        part_scratch: &mut part_scratch,
        count: monitor::QueryCount::default(),
        part_count: monitor::QueryCount::default(),
    };
    let frame_motion = FrameMotion {
        motion: &motion,
        orbit,
        hill_rate_rad_s: std::cell::OnceCell::new(),
        rotation_read: std::cell::Cell::new(false),
    };
    let g = &mut *g;
    g.last.resize(g.list.len(), Bracket::exact(f64::INFINITY));
    g.last_rate.resize(g.list.len(), None);
    for k in 0..g.list.len() {
        let inv = &*g.list[k];
        let m1 = inv.margin_bracket(&judge.view);
        frame_motion.rotation_read.set(false);
        let rate = if motion.ready {
            inv.rate_bound(&frame_motion)
        } else {
            None
        };
        // A rate bound resting on rotation is not proven in a step that turns a body by more
        // than UNDER_RESOLVED_TURN_RAD (the RK4 allowance is argued below that).
        let rotation_unproven = motion.under_resolved && frame_motion.rotation_read.get();
        g.last_rate[k] = rate;
        let st = &mut g.status[k];
        match rate {
            None => judge_at_sample(inv, st, &judge.view, m1.value, &mut log),
            Some(rate) => {
                let was_ok = g.last[k].value >= 0.0;
                let case = judge.case(inv, g.last[k], m1, rate, rotation_unproven);
                let finding = judge.finding(&case, st.worst_margin, was_ok);
                judge.report(&case, st, &finding, &mut log);
            }
        }
        g.last[k] = m1;
    }
    g.interval_queries += judge.count.exact + judge.part_count.exact;
}

/// Every `Rcs` actuator's jets and their firing flags over the current step, for
/// [`MonitorView::jets`] (a slot whose command frame was missing fires nothing).
pub(crate) fn jets_view(
    host: Option<&controllers::ControllerHost>,
) -> Vec<crate::guarantee::JetsView<'_>> {
    let Some(host) = host else {
        return Vec::new();
    };
    host.slots
        .iter()
        .filter_map(|s| match &s.actuator.spec {
            crate::actuation::actuator::ActuatorSpec::Rcs { jets, .. } => {
                Some(crate::guarantee::JetsView {
                    body: s.body,
                    jets,
                    firing: s.report.valves.as_deref().unwrap_or(&[]),
                })
            }
            _ => None,
        })
        .collect()
}

/// The core of the pipeline, added first: the `SimStep` schedule with its chained [`Stage`]s
/// and the [`Order`] sets inside Actuate, Environment and Monitor (every feature plugin puts its
/// systems in these sets), the core's systems and the `Update` system that steps the schedule.
///
/// Systems, by set: `environment_gravity` in [`Order::Gravity`]; `physics_step` (which
/// advances the environment) in [`Stage::Physics`]; [`monitor::distances`] then
/// [`monitor::contacts`] in [`Order::Geometry`]; `check_guarantees` in [`Order::Guarantees`];
/// [`output::record`] in [`Stage::Record`]; `advance` in `Update`. Two more are added only
/// with the resource they need, by the scene's build: [`multirate::plan_step`] in
/// [`Order::Plan`] with a `MultiRate` stepping, [`plume::plume_forces`] in
/// [`Order::PlumeForces`] with plumed jets (a system that is there runs, or asks its run
/// condition, every step: each is a run of the executor's bookkeeping and a fetch of each of
/// its resources, measurable at `free_drift`'s 4 µs a step). Several read the scene's
/// [`Env`], which [`environment::EnvironmentPlugin`] inserts. It replaces any `SimStep`
/// schedule, so it is added before every other plugin that puts systems there.
#[derive(Debug, Clone, Copy, Default)]
pub struct PipelinePlugin;

impl Plugin for PipelinePlugin {
    fn build(&self, app: &mut App) {
        let mut schedule = Schedule::new(SimStep);
        // One thread: the stages are a chain and their systems ordered (no two may run
        // together), so Bevy's multi-threaded executor, the default when the `viewer` feature
        // turns on `bevy/multi_threaded`, would only hand each system to a pool thread and park
        // this one until it is done — measured on free_drift, 5.6× the wall time of this
        // executor (17 600 against 99 100 steps/s), the same outputs byte for byte.
        schedule.set_executor(bevy::ecs::schedule::SingleThreadedExecutor::new());
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
        schedule.configure_sets((
            (
                Order::Plan,
                Order::MechanismForces,
                Order::ControllerForces,
                Order::PlumeForces,
            )
                .chain()
                .in_set(Stage::Actuate),
            (Order::TableForces, Order::Gravity)
                .chain()
                .in_set(Stage::Environment),
            (
                Order::PostStepDiagnostics,
                Order::Geometry,
                Order::Mechanism,
                Order::Guarantees,
            )
                .chain()
                .in_set(Stage::Monitor),
        ));
        schedule.add_systems((
            environment_gravity.in_set(Order::Gravity),
            physics_step.in_set(Stage::Physics),
            (
                monitor::distances,
                monitor::contacts.run_if(monitor::contacts_wanted),
            )
                .chain()
                .in_set(Order::Geometry),
            check_guarantees.in_set(Order::Guarantees),
            output::record
                .run_if(output::record_wanted)
                .in_set(Stage::Record),
        ));
        app.add_schedule(schedule);
        app.add_systems(Update, advance);
    }
}

/// Every pair of `SimStep` systems that access the same data (a component, a resource or the
/// whole world) with no order between them, as `"system_a <-> system_b: [data, ...]"` — Bevy's
/// ambiguity detection. A pair in this list could run in either order, and with it the sums of
/// forces and so the outputs could change between builds: the pipeline keeps the list empty
/// (`tests/schedule.rs`). Call it before the first step (the check runs while the schedule is
/// built); the schedule is then built with the default settings, ready to step.
pub fn schedule_ambiguities(app: &mut App) -> Vec<String> {
    use bevy::ecs::schedule::{LogLevel, ScheduleBuildSettings};
    app.world_mut()
        .resource_scope(|world, mut schedules: Mut<Schedules>| {
            let Some(schedule) = schedules.get_mut(SimStep) else {
                return Vec::new();
            };
            let default = schedule.get_build_settings();
            schedule.set_build_settings(ScheduleBuildSettings {
                ambiguity_detection: LogLevel::Error,
                ..default.clone()
            });
            let found = match schedule.initialize(world) {
                Ok(_) => Vec::new(),
                Err(_) => {
                    let graph = schedule.graph();
                    graph
                        .conflicting_systems()
                        .to_string(graph, world.components())
                        .map(|(a, b, data)| {
                            let data: Vec<String> = data.iter().map(|d| d.to_string()).collect();
                            format!("{a} <-> {b}: [{}]", data.join(", "))
                        })
                        .collect()
                }
            };
            schedule.set_build_settings(default);
            found
        })
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
