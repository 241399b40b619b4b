//! Scene files: serde types, loading with `file:line:col` errors, `--set` overrides, and
//! physical validation. Bevy-free.
//!
//! A scene is RON. Every numeric field carries its unit in its name (`mass_kg`, `rate_body_deg_s`,
//! `size_m`); unknown fields are rejected. Frames:
//! - **world**: non-rotating, axes parallel to the Earth-centred inertial frame (orbit scenes),
//!   origin riding on the reference orbit (the target's unforced orbit);
//! - **hill**: the reference orbit's Hill frame at t = 0 (x radial out, y along-track,
//!   z orbit normal), same origin;
//! - **body**: each spacecraft's own frame, in which its parts, centre of mass, inertia and ports
//!   are given.
//!
//! Attitudes are body-to-frame rotations: `v_frame = q · v_body`.

pub mod load;
pub mod parts;
pub mod validate;

pub use load::{LoadedScene, SceneError, load_scene_file, load_scene_str};

use serde::{Deserialize, Serialize};

/// Three components, as written in a scene: `(x, y, z)`.
pub type V3 = [f64; 3];

/// A complete scene.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Scene {
    /// Scene name, written to the outputs.
    pub name: String,
    /// Fixed control/physics step, s.
    pub dt_s: f64,
    /// Default simulated duration, s (`rpod run --duration` overrides).
    pub duration_s: f64,
    /// rapier substeps per step (each of `dt_s / substeps`).
    #[serde(default = "one")]
    pub physics_substeps: u32,
    /// Write one trajectory row every this many steps (1 = every step).
    #[serde(default = "ten")]
    pub record_every_steps: u32,
    /// Where the spacecraft fly.
    pub environment: Environment,
    /// The spacecraft.
    pub bodies: Vec<BodySpec>,
    /// Invariants the monitor checks every step.
    #[serde(default)]
    pub guarantees: Vec<GuaranteeSpec>,
    /// Control laws flying the bodies (each names the bodies it acts on).
    #[serde(default)]
    pub controllers: Vec<crate::control::ControllerSpec>,
    /// The docking mechanism between a chaser port and a target port, if any.
    #[serde(default)]
    pub docking: Option<DockingSpec>,
    /// How far the monitor looks (which body pairs it tracks); see [`MonitorSpec`].
    #[serde(default)]
    pub monitor: MonitorSpec,
    /// How the pipeline steps: `Fixed` (the default: every step is `dt_s`) or `MultiRate(…)`
    /// (longer steps where nothing can happen; see [`Stepping`]).
    #[serde(default)]
    pub stepping: Stepping,
}

/// How the pipeline steps (`crate::sim::multirate`).
///
/// `dt_s` is always the finest step. With `MultiRate`, a pipeline step covers several fixed
/// steps when the monitor's bounds prove that no contact can begin (every pair stays more than
/// `sim::RAPIER_ENGAGE_M` apart), no docking magnet can switch on and no guarantee's margin can
/// reach zero within it, no controller call and no trajectory row falls inside it, and the
/// leading error terms of the one-step free-flight integration over it are within `tol_m` and
/// `tol_rad`. Near contact, and wherever a feature keeps per-step state (sensors, navigation
/// filters, PWPF and RCS jets, disturbances, air-bearing tables, the L2 frame), it steps at
/// `dt_s` exactly as `Fixed` does. `Fixed` reproduces earlier runs byte for byte.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub enum Stepping {
    /// Every pipeline step is `dt_s`.
    #[default]
    Fixed,
    /// Steps of a whole number of `dt_s`, as long as proven free (see [`Stepping`]).
    MultiRate {
        /// Longest pipeline step, s (default 10 s).
        #[serde(default = "default_max_step_s")]
        max_step_s: f64,
        /// Largest estimated position error of one step's free-flight integration, m
        /// (default 1e-6 m): the leading term |j|·h³/6 of velocity Verlet, |j| the bound on
        /// the jerk of the differential gravity.
        #[serde(default = "default_tol_m")]
        tol_m: f64,
        /// Largest estimated attitude error of one step's RK4 rotation, rad (default 1e-8
        /// rad): the step turns a body by at most (120·tol_rad)^(1/5).
        #[serde(default = "default_tol_rad")]
        tol_rad: f64,
    },
}

fn default_max_step_s() -> f64 {
    10.0
}

fn default_tol_m() -> f64 {
    1e-6
}

fn default_tol_rad() -> f64 {
    1e-8
}

/// Which body pairs the monitor tracks exactly.
///
/// Tracked pairs get an exact full-geometry distance every step, a closest approach over the
/// run (judged between samples too) and a line in `pairs.csv` per recorded row. Pairs a
/// guarantee names are always tracked; any other pair is tracked while it can be within
/// `horizon_m` (the broad phase certifies every other pair farther than that, so it costs
/// nothing). The closest pair overall (`min_distance_m`, `closest_parts`) is exact at every
/// row whatever the horizon.
#[derive(Debug, Clone, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MonitorSpec {
    /// Horizon, m. Default: none (every pair tracked) for scenes of at most
    /// [`MonitorSpec::ALL_PAIRS_MAX_BODIES`] bodies, 10 m above.
    #[serde(default)]
    pub horizon_m: Option<f64>,
    /// Step rapier every step, free flight included (default: only while some pair can come
    /// within 1 m or touches; see `sim::RAPIER_ENGAGE_M`). Outputs are then byte-identical to
    /// builds before free flight skipped rapier, also where a first contact opens several
    /// collider pairs at once.
    #[serde(default)]
    pub rapier_every_step: bool,
    /// Run a scene whose initial spin turns a body by more than
    /// `math::rigid::UNDER_RESOLVED_TURN_RAD` (0.3 rad) in one step (default false: such a scene
    /// is refused with the step that would resolve it). Over such steps no guarantee resting on
    /// the rotation can be held (they are `unresolved`), and near contact the run is tens of
    /// times slower than without the spin.
    #[serde(default)]
    pub allow_under_resolved: bool,
}

impl MonitorSpec {
    /// Up to this many bodies, every pair is tracked unless a horizon is given.
    pub const ALL_PAIRS_MAX_BODIES: usize = 8;
    /// Default horizon for larger scenes, m.
    pub const DEFAULT_HORIZON_M: f64 = 10.0;

    /// The horizon in force for a scene of `n` bodies (`None`: every pair).
    pub fn horizon_for(&self, n: usize) -> Option<f64> {
        match self.horizon_m {
            Some(h) => Some(h),
            None if n <= Self::ALL_PAIRS_MAX_BODIES => None,
            None => Some(Self::DEFAULT_HORIZON_M),
        }
    }
}

/// The docking mechanism: an electromagnet in the chaser's cone, an iron plate in the target's
/// slot, and a latch that engages when the cone seats.
///
/// Geometry: with p_c, a_c the chaser port origin and outward axis and p_t, a_t the target's
/// (world frame), the *seat point* is p_seat = p_t + a_t·`seat_depth_m`; the gap is
/// |p_c − p_seat|; the axial error is (p_c − p_t)·a_t − `seat_depth_m` (positive: not yet in);
/// the lateral offset is the part of p_c − p_t perpendicular to a_t; the misalignment is the
/// angle between a_c and −a_t.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DockingSpec {
    /// Chaser body.
    pub chaser: String,
    /// Chaser port (the cone stands on it).
    pub chaser_port: String,
    /// Target body.
    pub target: String,
    /// Target port (the slot is built around it).
    pub target_port: String,
    /// Depth of the chaser port origin above the target port origin, along a_t, when seated, m.
    pub seat_depth_m: f64,
    /// Radius of the slot's mouth, m (used to judge a miss).
    pub mouth_radius_m: f64,
    /// The electromagnet (default: none, [`MagnetSpec::default`]).
    #[serde(default)]
    pub magnet: MagnetSpec,
    /// The latch. With [`Mechanism::SoftCapture`] these are the capture latches: they engage
    /// when the capture ring is within `axial_tolerance_m` of its seat (the capture range),
    /// `lateral_tolerance_m` and `angle_tolerance_deg`, and the rates are within
    /// `capture_rates`; `break_force_n` is the interface force beyond which they let go;
    /// `dwell_s` and `joint` do not apply.
    pub latch: LatchSpec,
    /// When a run gives up.
    #[serde(default)]
    pub miss: MissSpec,
    /// The cone–slot contact: `Compliant((law: …, dissipation: …))` (the default, with the
    /// values documented in [`crate::contact`]) or `Rigid` (rapier's impulses).
    #[serde(default)]
    pub contact: crate::contact::ContactModelSpec,
    /// Start latched: the chaser must be seated within the latch tolerances at t = 0 (checked
    /// when the scene loads); the latch closes before the first step. For undocking scenes.
    #[serde(default)]
    pub start_latched: bool,
    /// Separation springs between the ports, compressed while latched, that push the vehicles
    /// apart when the latch is released (needs the `Compliant` contact, whose sub-steps
    /// integrate them).
    #[serde(default)]
    pub separation: Option<SeparationSpec>,
    /// Which mechanism: `ConeSlot` (the default: the latch holds the seated cone) or
    /// `SoftCapture((...))`, a capture ring on an attenuation platform ([`SoftCaptureSpec`]).
    #[serde(default)]
    pub mechanism: Mechanism,
}

/// The docking mechanism type.
#[derive(Debug, Clone, Default, Serialize, Deserialize)]
pub enum Mechanism {
    /// Probe cone, funnel slot, magnet and latch (`docs/mechanisms.md`).
    #[default]
    ConeSlot,
    /// Soft capture: the capture latches hold the chaser's capture ring to the target's ring,
    /// the chaser hangs on the attenuation platform's legs, the platform retracts, and the
    /// structural hooks close (`SOFT_CAPTURED → RETRACTED → HARD_DOCKED`).
    SoftCapture(Box<SoftCaptureSpec>),
}

/// A soft-capture mechanism on the chaser port (the platform frame P: origin the chaser port
/// origin, +z its axis, +x the body +x turned by the shortest rotation from body +z onto the
/// port axis; see [`crate::contact::platform`]). The guide petals are the `DockingCone` (on the
/// chaser port) and the `DockingSlot` funnel (on the target port), ordinary docking parts in
/// compliant contact; the capture conditions are `docking.latch`'s (see [`DockingSpec::latch`]).
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SoftCaptureSpec {
    /// The attenuation platform (capture ring on its legs).
    pub platform: crate::contact::platform::PlatformSpec,
    /// Time from the capture to the start of the retraction (the legs attenuate the motion), s.
    pub attenuation_s: f64,
    /// Retraction speed (the ring drawn toward the chaser port along the platform axis), m/s.
    pub retraction_speed_m_s: f64,
    /// Retraction at which the platform stops retracting (event `RETRACTED`), m.
    pub retracted_stroke_m: f64,
    /// The hooks close when, retracted, the chaser port is within this of the target port
    /// axis, m …
    pub hook_lateral_tolerance_m: f64,
    /// … and its axis within this of −a_t, deg.
    pub hook_angle_tolerance_deg: f64,
    /// The structural hooks: a stiff spring–damper joint (as the compliant latch) closed where
    /// the chaser is when they engage.
    pub hooks: CompliantLatch,
}
/// Separation springs (all of them together, acting along the target port axis at the chaser
/// port origin): the force falls linearly from `force_n` at full compression to `preload_n`
/// at the end of the stroke, where they rest on their stops. Energy released:
/// ½·(`force_n` + `preload_n`)·`stroke_m`.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SeparationSpec {
    /// Stroke, m.
    pub stroke_m: f64,
    /// Force at full compression, N.
    pub force_n: f64,
    /// Force at the end of the stroke (the preload the stops hold), N.
    pub preload_n: f64,
}

/// Electromagnet: attractive force F(gap) = min(F0 / (1 + gap/g0)², F_max) on the chaser port,
/// along −a_t (into the slot), with the equal and opposite reaction on the target at the same
/// point. The default is no magnet (zero force, never switched on).
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MagnetSpec {
    /// Force at zero gap before the cap, N.
    pub f0_n: f64,
    /// Gap scale g0, m.
    pub g0_m: f64,
    /// Cap, N.
    pub max_force_n: f64,
    /// The magnet switches on automatically when the gap falls below this, m (0: never).
    pub activation_distance_m: f64,
    /// Switched on from t = 0 (a command), whatever the gap.
    #[serde(default)]
    pub on_at_start: bool,
}

impl Default for MagnetSpec {
    fn default() -> Self {
        Self {
            f0_n: 0.0,
            g0_m: 1.0,
            max_force_n: 0.0,
            activation_distance_m: 0.0,
            on_at_start: false,
        }
    }
}

/// Latch: engages (a rapier fixed joint) when the cone has stayed seated for `dwell_s`.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LatchSpec {
    /// Seated when |axial error| ≤ this, m.
    pub axial_tolerance_m: f64,
    /// … and lateral offset ≤ this, m.
    pub lateral_tolerance_m: f64,
    /// … and misalignment ≤ this, deg.
    pub angle_tolerance_deg: f64,
    /// Time seated before the latch engages (soft capture), s.
    #[serde(default = "dwell")]
    pub dwell_s: f64,
    /// The latch breaks when the joint force exceeds this, N.
    pub break_force_n: f64,
    /// Relative rates beyond which the latch refuses to engage (default: the IDSS initial
    /// contact conditions, see [`CaptureRates`]).
    #[serde(default)]
    pub capture_rates: CaptureRates,
    /// What holds the latched bodies: `Rigid` (the default, a rapier fixed joint) or
    /// `Compliant((...))`, a stiff spring–damper ([`CompliantLatch`]).
    #[serde(default)]
    pub joint: LatchJoint,
}

/// The latch joint.
#[derive(Debug, Clone, Default, Serialize, Deserialize)]
pub enum LatchJoint {
    /// A rapier fixed joint: stops the relative motion within one step, so its peak load is an
    /// impulse over dt and depends on the step.
    #[default]
    Rigid,
    /// A spring–damper between the chaser port frame and where the latch caught it in the
    /// target's frame, integrated in f64 with the compliant contact's sub-steps (the scene's
    /// contact must be `Compliant`): its loads converge in dt.
    Compliant(CompliantLatch),
}

/// A compliant latch: on the chaser, at its port origin p_c, the force
/// F = −k·Δx − c·Δv and the moment M = −k_θ·θ − c_θ·Δω, where Δx is p_c less the point where the
/// latch caught it (carried by the target), Δv the velocity of the chaser's material point at
/// p_c less the target's there, θ the rotation vector from the caught attitude to the present
/// one and Δω = ω_c − ω_t (world frame); the target gets −F at p_c and −M.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CompliantLatch {
    /// k, N/m.
    pub stiffness_n_m: f64,
    /// c, N·s/m.
    pub damping_n_s_m: f64,
    /// k_θ, N·m/rad.
    pub rot_stiffness_nm_rad: f64,
    /// c_θ, N·m·s/rad.
    pub rot_damping_nm_s_rad: f64,
}

fn dwell() -> f64 {
    0.2
}

/// Capture rate limits: the latch engages only when, at the end of the dwell, the relative
/// motion of the chaser port with respect to the target port is within all three, else it
/// stays open (the mechanism keeps waiting while seated) and an event names the rate.
///
/// Rates, world frame, taken at the chaser port origin p_c with a_t the target port axis:
/// - axial: |v_rel·a_t|, v_rel the chaser's velocity at p_c less the target's material point
///   velocity there;
/// - lateral: |v_rel − (v_rel·a_t)·a_t|;
/// - angular: |ω_c − ω_t| (the magnitude of the relative angular velocity vector, all axes).
///
/// Defaults: the International Docking System Standard's initial contact conditions as
/// quoted in `ANCHORS.md` (closing speed ≤ 0.10 m/s, lateral rate ≤ 0.04 m/s, pitch/yaw/roll
/// rates ≤ 0.2 °/s), applied here to the relative motion at the moment of capture. The
/// standard bounds each angular axis at 0.2 °/s; the default bounds the vector's magnitude at
/// √3 · 0.2 °/s ≈ 0.346 °/s, the largest magnitude the standard's per-axis box admits, so
/// that every state the standard requires a mechanism to capture is accepted.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CaptureRates {
    /// Largest |axial rate|, m/s.
    #[serde(default = "CaptureRates::idss_axial")]
    pub max_axial_rate_m_s: f64,
    /// Largest lateral rate, m/s.
    #[serde(default = "CaptureRates::idss_lateral")]
    pub max_lateral_rate_m_s: f64,
    /// Largest relative angular rate magnitude, deg/s.
    #[serde(default = "CaptureRates::idss_angular")]
    pub max_angular_rate_deg_s: f64,
}

impl CaptureRates {
    /// IDSS closing speed upper bound, m/s.
    pub const IDSS_AXIAL_M_S: f64 = 0.10;
    /// IDSS lateral rate bound, m/s.
    pub const IDSS_LATERAL_M_S: f64 = 0.04;
    /// IDSS per-axis angular rate bound, deg/s.
    pub const IDSS_ANGULAR_PER_AXIS_DEG_S: f64 = 0.2;
    fn idss_axial() -> f64 {
        Self::IDSS_AXIAL_M_S
    }
    fn idss_lateral() -> f64 {
        Self::IDSS_LATERAL_M_S
    }
    fn idss_angular() -> f64 {
        Self::IDSS_ANGULAR_PER_AXIS_DEG_S * 3f64.sqrt()
    }
}

impl Default for CaptureRates {
    fn default() -> Self {
        Self {
            max_axial_rate_m_s: Self::idss_axial(),
            max_lateral_rate_m_s: Self::idss_lateral(),
            max_angular_rate_deg_s: Self::idss_angular(),
        }
    }
}

/// Failure criteria.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MissSpec {
    /// In docking contact, not seated, and relative speed below `jam_speed_m_s` for this
    /// long: JAMMED, s.
    pub jam_time_s: f64,
    /// Relative speed below which a stuck cone counts as jammed, m/s.
    pub jam_speed_m_s: f64,
    /// After a docking contact ends, separating faster than this: REBOUND, m/s. The default,
    /// 1e-5 m/s, is a numerical floor (the f64 truth resolves 1e-9 m/s after rapier's f32
    /// contact steps), not a physical threshold: any chaser that touched the slot and moves
    /// away is a rebound, whatever the restitution of the contact that sent it (a perfectly
    /// inelastic grazing hit leaves it drifting at under 1 mm/s, a bouncy one at cm/s).
    pub rebound_speed_m_s: f64,
    /// The approach judgements (passed beside the slot, turned away outside the mouth) apply
    /// only once the gap has fallen below this, m; absent: from t = 0. For a chaser that
    /// manoeuvres around obstacles far from the target before its final approach.
    #[serde(default)]
    pub arm_gap_m: Option<f64>,
}

impl Default for MissSpec {
    fn default() -> Self {
        Self {
            jam_time_s: 5.0,
            jam_speed_m_s: 1e-3,
            rebound_speed_m_s: 1e-5,
            arm_gap_m: None,
        }
    }
}

fn one() -> u32 {
    1
}
fn ten() -> u32 {
    10
}
fn yes() -> bool {
    true
}

/// The environment the bodies move in.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub enum Environment {
    /// Earth orbit: the world frame rides on the reference orbit; every body gets the
    /// differential gravity a(r_ref + r) − a(r_ref), computed in f64.
    Orbit {
        /// The reference orbit (the target's unforced orbit).
        reference: OrbitSpec,
        /// Include Earth's J2 in the gravity model.
        #[serde(default = "yes")]
        j2: bool,
        /// Apply the gravity-gradient torque to every body.
        #[serde(default = "yes")]
        gravity_gradient: bool,
    },
    /// Force-free space with no gravity at all (for mechanism tests).
    FreeSpace,
    /// Near the Sun–Earth L2 point (Zhang et al. 2018): the world frame rides on a formation
    /// centre under Sun + Earth–Moon gravity; see [`crate::orbit::l2::L2EnvSpec`].
    SunEarthL2(crate::orbit::l2::L2EnvSpec),
    /// An air-bearing table in a lab (Xu, Wen, Wei 2019): the lab frame has z up along the
    /// table normal, the table top at z = 0; simulators float on it and move in its plane
    /// (x, y, yaw). See [`AirBearingSpec`].
    AirBearing(AirBearingSpec),
}

/// An air-bearing (granite) table. Lab frame: x, y in the table top, z along its normal
/// (up), the top at z = 0. Every body not `anchored` is a *simulator*: its centre-of-mass
/// height, roll and pitch stay as at t = 0 (the air film carries the normal component of
/// gravity, m·g·cos α_x·cos α_y), it moves in x, y and yaw under the in-plane gravity component
/// of the tilt, the air film's residual Coulomb friction and viscous drag, and whatever else
/// acts on it. A simulator whose centre of mass leaves the table top is no longer supported:
/// an `off_table` event, and it falls under the full gravity vector.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AirBearingSpec {
    /// Table top size along lab x and y, m.
    #[serde(default = "table_size")]
    pub table_size_m: [f64; 2],
    /// Lab (x, y) of the table corner with the smallest coordinates, m.
    #[serde(default)]
    pub table_corner_m: [f64; 2],
    /// Table thickness (the fixed collider below z = 0), m.
    #[serde(default = "table_thickness")]
    pub table_thickness_m: f64,
    /// Magnitude of gravity, m/s².
    #[serde(default = "standard_gravity")]
    pub gravity_m_s2: f64,
    /// Tilt of the table, deg: (α_x, α_y). Gravity in the lab frame is
    /// g·(sin α_x·cos α_y, sin α_y, −cos α_x·cos α_y): α_x alone accelerates a free puck along
    /// +x at g·sin α_x, α_y alone along +y at g·sin α_y.
    #[serde(default)]
    pub tilt_deg: [f64; 2],
    /// Residual Coulomb friction coefficient of the air film (friction force μ·N against the
    /// in-plane velocity, N the normal load; sticks when the other in-plane forces are below
    /// μ·N), dimensionless.
    #[serde(default)]
    pub coulomb_friction: f64,
    /// Viscous drag of the air film on translation, N·s/m (force −c·v).
    #[serde(default)]
    pub viscous_drag_n_s_m: f64,
    /// Viscous drag of the air film on yaw, N·m·s/rad (torque −c·ω_z).
    #[serde(default)]
    pub viscous_drag_nm_s_rad: f64,
    /// Bodies bolted to the table (obstacles, fixtures): fixed, no forces act on them.
    #[serde(default)]
    pub anchored: Vec<String>,
}

fn table_size() -> [f64; 2] {
    [2.0, 2.5]
}
fn table_thickness() -> f64 {
    0.3
}
fn standard_gravity() -> f64 {
    9.81
}

impl Default for AirBearingSpec {
    fn default() -> Self {
        Self {
            table_size_m: table_size(),
            table_corner_m: [0.0, 0.0],
            table_thickness_m: table_thickness(),
            gravity_m_s2: standard_gravity(),
            tilt_deg: [0.0, 0.0],
            coulomb_friction: 0.0,
            viscous_drag_n_s_m: 0.0,
            viscous_drag_nm_s_rad: 0.0,
            anchored: Vec::new(),
        }
    }
}

impl AirBearingSpec {
    /// Gravity in the lab frame, m/s².
    pub fn gravity_lab_m_s2(&self) -> nalgebra::Vector3<f64> {
        let (ax, ay) = (self.tilt_deg[0].to_radians(), self.tilt_deg[1].to_radians());
        nalgebra::Vector3::new(ax.sin() * ay.cos(), ay.sin(), -ax.cos() * ay.cos())
            * self.gravity_m_s2
    }
    /// Whether a lab point's (x, y) lies on the table top.
    pub fn on_table(&self, x_m: f64, y_m: f64) -> bool {
        let [cx, cy] = self.table_corner_m;
        let [w, h] = self.table_size_m;
        x_m >= cx && x_m <= cx + w && y_m >= cy && y_m <= cy + h
    }
}

/// The reference orbit's initial state.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub enum OrbitSpec {
    /// Classical elements at t = 0.
    Elements {
        /// Semi-major axis, m.
        a_m: f64,
        /// Eccentricity (0 ≤ e < 1).
        e: f64,
        /// Inclination, deg.
        i_deg: f64,
        /// Right ascension of the ascending node, deg.
        raan_deg: f64,
        /// Argument of perigee, deg.
        argp_deg: f64,
        /// True anomaly, deg.
        true_anomaly_deg: f64,
    },
    /// Earth-centred inertial state at t = 0.
    State {
        /// Position, m (ECI).
        r_eci_m: V3,
        /// Velocity, m/s (ECI).
        v_eci_m_s: V3,
    },
}

/// What a body is, for the monitor: docking contacts are between a chaser and a target.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum BodyRole {
    /// The active spacecraft.
    Chaser,
    /// The passive spacecraft (may tumble).
    Target,
    /// Anything else (a third spacecraft, debris).
    Other,
}

/// Frame in which an initial state is written.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
pub enum InitFrame {
    /// Inertial axes, origin on the reference orbit.
    #[default]
    World,
    /// Hill frame of the reference orbit at t = 0 (x radial out, y along-track, z normal).
    Hill,
}

/// An attitude as written in a scene.
#[derive(Debug, Clone, Copy, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub enum AttitudeSpec {
    /// Unit quaternion body → frame, scalar first (normalised on load; must not be zero).
    Quat {
        /// Scalar part.
        w: f64,
        /// Vector part, x.
        x: f64,
        /// Vector part, y.
        y: f64,
        /// Vector part, z.
        z: f64,
    },
    /// 3-2-1 Euler angles (yaw about z, then pitch about the new y, then roll about the new x), deg.
    EulerZyxDeg {
        /// Yaw, deg.
        yaw: f64,
        /// Pitch, deg.
        pitch: f64,
        /// Roll, deg.
        roll: f64,
    },
}

impl Default for AttitudeSpec {
    fn default() -> Self {
        AttitudeSpec::Quat {
            w: 1.0,
            x: 0.0,
            y: 0.0,
            z: 0.0,
        }
    }
}

impl AttitudeSpec {
    /// The rotation body → frame.
    pub fn to_quat(&self) -> nalgebra::UnitQuaternion<f64> {
        match *self {
            AttitudeSpec::Quat { w, x, y, z } => {
                nalgebra::UnitQuaternion::from_quaternion(nalgebra::Quaternion::new(w, x, y, z))
            }
            AttitudeSpec::EulerZyxDeg { yaw, pitch, roll } => {
                let z = nalgebra::UnitQuaternion::from_axis_angle(
                    &nalgebra::Vector3::z_axis(),
                    yaw.to_radians(),
                );
                let y = nalgebra::UnitQuaternion::from_axis_angle(
                    &nalgebra::Vector3::y_axis(),
                    pitch.to_radians(),
                );
                let x = nalgebra::UnitQuaternion::from_axis_angle(
                    &nalgebra::Vector3::x_axis(),
                    roll.to_radians(),
                );
                z * y * x
            }
        }
    }
}

/// Initial state of a body's centre of mass and attitude.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct InitialState {
    /// Frame of `pos_m`, `vel_m_s` and `attitude`.
    #[serde(default)]
    pub frame: InitFrame,
    /// Centre-of-mass position, m.
    pub pos_m: V3,
    /// Centre-of-mass velocity, m/s (relative to the frame's origin, as seen in that frame).
    #[serde(default)]
    pub vel_m_s: V3,
    /// Attitude body → frame.
    #[serde(default)]
    pub attitude: AttitudeSpec,
    /// Inertial angular velocity in body axes, deg/s.
    #[serde(default)]
    pub rate_body_deg_s: V3,
}

/// Inertia tensor about the centre of mass, in body axes, kg·m².
#[derive(Debug, Clone, Copy, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct InertiaSpec {
    /// I_xx, kg·m².
    pub xx: f64,
    /// I_yy, kg·m².
    pub yy: f64,
    /// I_zz, kg·m².
    pub zz: f64,
    /// I_xy (tensor element, i.e. minus the product of inertia), kg·m².
    #[serde(default)]
    pub xy: f64,
    /// I_xz, kg·m².
    #[serde(default)]
    pub xz: f64,
    /// I_yz, kg·m².
    #[serde(default)]
    pub yz: f64,
}

impl InertiaSpec {
    /// The symmetric tensor.
    pub fn matrix(&self) -> nalgebra::Matrix3<f64> {
        nalgebra::Matrix3::new(
            self.xx, self.xy, self.xz, self.xy, self.yy, self.yz, self.xz, self.yz, self.zz,
        )
    }
}

/// A docking port: a frame on a body.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PortSpec {
    /// Port name, unique on the body.
    pub name: String,
    /// Port origin in the body frame, m.
    pub pos_m: V3,
    /// Outward port axis in the body frame (normalised on load).
    pub axis: V3,
}

/// One spacecraft.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BodySpec {
    /// Unique name; used as the column prefix in `trajectory.csv`.
    pub name: String,
    /// Chaser, target or other.
    pub role: BodyRole,
    /// Mass, kg (left out when `mass_from_meshes`).
    #[serde(default = "unset_f64")]
    pub mass_kg: f64,
    /// Centre of mass in the body frame, m (computed when `mass_from_meshes`).
    #[serde(default)]
    pub com_m: V3,
    /// Inertia tensor about the centre of mass, body axes, kg·m² (left out when
    /// `mass_from_meshes`).
    #[serde(default = "unset_inertia")]
    pub inertia_kg_m2: InertiaSpec,
    /// Mass, centre of mass and inertia computed by the loader from the closed meshes of the
    /// parts that state a `density_kg_m3` (divergence theorem, [`crate::geometry::mesh`]);
    /// `mass_kg` and `inertia_kg_m2` are then left out.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub mass_from_meshes: bool,
    /// Initial state.
    pub initial: InitialState,
    /// Geometry: every part becomes one or more colliders.
    pub parts: Vec<PartSpec>,
    /// Docking-port frames.
    #[serde(default)]
    pub ports: Vec<PortSpec>,
    /// Coulomb friction coefficient of this body's parts (rapier combines two parts' values by
    /// their average).
    #[serde(default = "friction")]
    pub friction: f64,
    /// Restitution coefficient of this body's parts (combined by the average).
    #[serde(default)]
    pub restitution: f64,
}

fn friction() -> f64 {
    0.3
}

/// NaN: a mass not written in the scene (filled from meshes, or refused by validation).
fn unset_f64() -> f64 {
    f64::NAN
}

fn unset_inertia() -> InertiaSpec {
    InertiaSpec {
        xx: f64::NAN,
        yy: f64::NAN,
        zz: f64::NAN,
        xy: 0.0,
        xz: 0.0,
        yz: 0.0,
    }
}

/// A body axis, for directions written in a scene.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum Axis {
    /// +x
    PlusX,
    /// −x
    MinusX,
    /// +y
    PlusY,
    /// −y
    MinusY,
    /// +z
    PlusZ,
    /// −z
    MinusZ,
}

impl Axis {
    /// The unit vector.
    pub fn vector(self) -> nalgebra::Vector3<f64> {
        use nalgebra::Vector3;
        match self {
            Axis::PlusX => Vector3::x(),
            Axis::MinusX => -Vector3::x(),
            Axis::PlusY => Vector3::y(),
            Axis::MinusY => -Vector3::y(),
            Axis::PlusZ => Vector3::z(),
            Axis::MinusZ => -Vector3::z(),
        }
    }
}

/// A primitive shape, in its own frame.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub enum ShapeSpec {
    /// Rectangular box centred on its frame.
    Box {
        /// Full edge lengths along x, y, z, m.
        size_m: V3,
    },
    /// Solid cylinder centred on its frame.
    Cylinder {
        /// Radius, m.
        radius_m: f64,
        /// Full length, m.
        length_m: f64,
        /// Axis of revolution.
        axis: Axis,
    },
    /// Sphere centred on its frame.
    Sphere {
        /// Radius, m.
        radius_m: f64,
    },
    /// Prism whose cross-section (in the frame's x-y plane) is the superquadric
    /// (x²/a²)^s + (y²/b²)^s = 1, extruded along z, centred on its frame. Convex for s ≥ ½;
    /// the collider is the convex hull of `segments` boundary points on each end face.
    SuperquadricPrism {
        /// Half-width along x, a, m.
        a_m: f64,
        /// Half-width along y, b, m.
        b_m: f64,
        /// Exponent s (≥ 0.5).
        s: f64,
        /// Full height along z, m.
        height_m: f64,
        /// Boundary points per end face (≥ 8).
        #[serde(default = "prism_segments")]
        segments: u32,
    },
    /// A triangle mesh read from a file (see `docs/vehicles.md`): OBJ, STL (ASCII or binary),
    /// glTF or GLB. Distances and guarantee margins use the mesh itself (concave parts
    /// included); rapier's contact dynamics use its convex decomposition (`decomposition`).
    /// Each component of the file (glTF node with a mesh, OBJ object) becomes one collider
    /// named by the component, or by the part when there is a single component.
    Mesh {
        /// The file, relative to the scene file's folder.
        path: String,
        /// Uniform scale, file units → m.
        #[serde(default = "unit_scale")]
        scale: f64,
        /// Components to keep by name (empty: all).
        #[serde(default, skip_serializing_if = "Vec::is_empty")]
        nodes: Vec<String>,
        /// Most triangles accepted (all components together).
        #[serde(default = "max_triangles")]
        max_triangles: u32,
        /// Convex-decomposition parameters for rapier.
        #[serde(default)]
        decomposition: DecompositionSpec,
        /// Density of the solid, kg/m³: the part's components are mass sources when the body
        /// takes its mass from its meshes (`mass_from_meshes`); they must then be closed.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        density_kg_m3: Option<f64>,
        /// The file's components, read by the scene loader (never written in a scene).
        #[serde(skip)]
        loaded: Option<std::sync::Arc<crate::geometry::mesh::MeshFile>>,
    },
}

fn max_triangles() -> u32 {
    crate::geometry::mesh::DEFAULT_MAX_TRIANGLES
}

/// Parameters of the convex decomposition (parry's V-HACD) of a mesh part for rapier.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DecompositionSpec {
    /// Largest concavity left in a convex piece, as a fraction of the mesh's size (0 … 1).
    #[serde(default = "vhacd_concavity")]
    pub concavity: f64,
    /// Voxel resolution along the longest axis (16 … 512).
    #[serde(default = "vhacd_resolution")]
    pub resolution: u32,
    /// Most convex pieces per component (1 … 4096).
    #[serde(default = "vhacd_max_hulls")]
    pub max_convex_hulls: u32,
}

impl Default for DecompositionSpec {
    fn default() -> Self {
        Self {
            concavity: vhacd_concavity(),
            resolution: vhacd_resolution(),
            max_convex_hulls: vhacd_max_hulls(),
        }
    }
}

fn vhacd_concavity() -> f64 {
    0.01
}
fn vhacd_resolution() -> u32 {
    64
}
fn vhacd_max_hulls() -> u32 {
    256
}

fn prism_segments() -> u32 {
    96
}

/// What a part is, for the monitor and the docking mechanism.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum PartRole {
    /// Main structure.
    Bus,
    /// Solar panel.
    Panel,
    /// Solar-array boom.
    Boom,
    /// Antenna.
    Antenna,
    /// Docking probe cone (chaser).
    DockingCone,
    /// Docking receptacle slot (target).
    DockingSlot,
    /// Anything else.
    Other,
}

impl PartRole {
    /// Docking parts may touch each other without it counting as a collision.
    pub fn is_docking(self) -> bool {
        matches!(self, PartRole::DockingCone | PartRole::DockingSlot)
    }
}

/// A glTF model the viewer draws for a part, placed in the body frame.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ModelSpec {
    /// File under the assets directory (`assets/` of the repository, or `$RPOD_ASSETS`),
    /// `.gltf` or `.glb`, e.g. `models/hga_dish.gltf`. Its first scene is drawn, in metres.
    pub path: String,
    /// Position of the model's origin in the body frame, m.
    #[serde(default)]
    pub pos_m: V3,
    /// Orientation of the model's axes in the body frame.
    #[serde(default)]
    pub attitude: AttitudeSpec,
    /// Uniform scale applied to the model (model units → m).
    #[serde(default = "unit_scale")]
    pub scale: f64,
}

fn unit_scale() -> f64 {
    1.0
}

/// The directory glTF models are read from: `$RPOD_ASSETS` if set, else the repository's
/// `assets/`.
pub fn assets_dir() -> std::path::PathBuf {
    std::env::var_os("RPOD_ASSETS")
        .map(std::path::PathBuf::from)
        .unwrap_or_else(|| std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("assets"))
}

/// A named part of a spacecraft. Positions and rotations are in the body frame.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub enum PartSpec {
    /// The bus: one primitive shape.
    Bus {
        /// Part name, unique on the body.
        name: String,
        /// Shape.
        shape: ShapeSpec,
        /// Shape centre in the body frame, m.
        #[serde(default)]
        pos_m: V3,
        /// Shape orientation in the body frame.
        #[serde(default)]
        attitude: AttitudeSpec,
        /// The part may overlap another body's part at t = 0 without a validation error.
        #[serde(default)]
        allow_initial_overlap: bool,
        /// Drawn by the viewer as this glTF model instead of the collider shapes (the
        /// colliders, which the monitor checks, are unchanged).
        #[serde(default)]
        model: Option<ModelSpec>,
    },
    /// An antenna (or any other appendage): one primitive shape.
    Antenna {
        /// Part name.
        name: String,
        /// Shape.
        shape: ShapeSpec,
        /// Shape centre in the body frame, m.
        #[serde(default)]
        pos_m: V3,
        /// Shape orientation in the body frame.
        #[serde(default)]
        attitude: AttitudeSpec,
        /// See [`PartSpec::Bus`].
        #[serde(default)]
        allow_initial_overlap: bool,
        /// Drawn by the viewer as this glTF model instead of the collider shapes (the
        /// colliders, which the monitor checks, are unchanged).
        #[serde(default)]
        model: Option<ModelSpec>,
    },
    /// A solar-array wing: a boom from the root, then `panel_count` flat panels in a row.
    /// Colliders are named `NAME.boom` and `NAME.panel1` … `NAME.panelN`.
    SolarWing {
        /// Wing name.
        name: String,
        /// Root point on the bus, body frame, m.
        root_m: V3,
        /// Direction the wing extends in.
        direction: Axis,
        /// Axis (perpendicular to `direction`) along which the panel width lies before the cant.
        width_axis: Axis,
        /// Boom length from the root to the first panel's inner edge, m (0 = no boom).
        #[serde(default)]
        boom_length_m: f64,
        /// Boom radius, m.
        #[serde(default = "boom_radius")]
        boom_radius_m: f64,
        /// Number of panels.
        panel_count: u32,
        /// Panel length along `direction` and width along `width_axis`, m.
        panel_size_m: [f64; 2],
        /// Panel thickness, m.
        #[serde(default = "panel_thickness")]
        panel_thickness_m: f64,
        /// Gap between successive panels, m.
        #[serde(default)]
        panel_gap_m: f64,
        /// Rotation of the panels about `direction`, deg.
        #[serde(default)]
        cant_deg: f64,
        /// See [`PartSpec::Bus`].
        #[serde(default)]
        allow_initial_overlap: bool,
        /// Drawn by the viewer as this glTF model instead of the collider shapes (the
        /// colliders, which the monitor checks, are unchanged).
        #[serde(default)]
        model: Option<ModelSpec>,
    },
    /// Docking probe: a truncated cone on a port, its base on the port plane and its tip
    /// pointing out along the port axis. Collider `NAME`.
    DockingCone {
        /// Part name.
        name: String,
        /// The port it stands on.
        port: String,
        /// Base radius, m.
        base_radius_m: f64,
        /// Tip radius, m (0 < tip ≤ base).
        tip_radius_m: f64,
        /// Length along the port axis, m.
        length_m: f64,
        /// See [`PartSpec::Bus`].
        #[serde(default)]
        allow_initial_overlap: bool,
        /// Drawn by the viewer as this glTF model instead of the collider shapes (the
        /// colliders, which the monitor checks, are unchanged).
        #[serde(default)]
        model: Option<ModelSpec>,
    },
    /// Docking receptacle: a concave funnel on a port, open along the port axis, built from
    /// `segments` convex wall pieces plus a back plate. Colliders `NAME.wall1` … and `NAME.back`.
    DockingSlot {
        /// Part name.
        name: String,
        /// The port it is built around (the port origin is the bottom of the funnel).
        port: String,
        /// Inner radius at the mouth, m.
        mouth_radius_m: f64,
        /// Inner radius at the bottom, m.
        throat_radius_m: f64,
        /// Depth from the mouth to the bottom, m.
        depth_m: f64,
        /// Wall thickness, m.
        #[serde(default = "slot_wall")]
        wall_m: f64,
        /// Number of convex wall pieces around the axis (≥ 6).
        #[serde(default = "slot_segments")]
        segments: u32,
        /// See [`PartSpec::Bus`].
        #[serde(default)]
        allow_initial_overlap: bool,
        /// Drawn by the viewer as this glTF model instead of the collider shapes (the
        /// colliders, which the monitor checks, are unchanged).
        #[serde(default)]
        model: Option<ModelSpec>,
    },
}

fn boom_radius() -> f64 {
    0.03
}
fn panel_thickness() -> f64 {
    0.03
}
fn slot_wall() -> f64 {
    0.02
}
fn slot_segments() -> u32 {
    12
}

impl PartSpec {
    /// The part's name.
    pub fn name(&self) -> &str {
        match self {
            PartSpec::Bus { name, .. }
            | PartSpec::Antenna { name, .. }
            | PartSpec::SolarWing { name, .. }
            | PartSpec::DockingCone { name, .. }
            | PartSpec::DockingSlot { name, .. } => name,
        }
    }
    /// The glTF model the viewer draws for the part, if any.
    pub fn model(&self) -> Option<&ModelSpec> {
        match self {
            PartSpec::Bus { model, .. }
            | PartSpec::Antenna { model, .. }
            | PartSpec::SolarWing { model, .. }
            | PartSpec::DockingCone { model, .. }
            | PartSpec::DockingSlot { model, .. } => model.as_ref(),
        }
    }
    /// Whether the part may overlap other bodies at t = 0.
    pub fn allow_initial_overlap(&self) -> bool {
        match self {
            PartSpec::Bus {
                allow_initial_overlap,
                ..
            }
            | PartSpec::Antenna {
                allow_initial_overlap,
                ..
            }
            | PartSpec::SolarWing {
                allow_initial_overlap,
                ..
            }
            | PartSpec::DockingCone {
                allow_initial_overlap,
                ..
            }
            | PartSpec::DockingSlot {
                allow_initial_overlap,
                ..
            } => *allow_initial_overlap,
        }
    }
}

pub use crate::guarantee::GuaranteeSpec;
