//! The docking mechanism: electromagnetic capture, soft capture, latch (a rapier fixed joint,
//! or a compliant spring–damper, with a finite break force) that engages only within the
//! capture rate limits, release with separation springs, and the state machine FREE →
//! ATTRACTING → CONTACT → SOFT_CAPTURE → LATCHED → RELEASED, with REBOUND, JAMMED and MISSED.
//! The soft-capture mechanism (`docking.mechanism: SoftCapture`) replaces the seat and latch by
//! capture latches, the attenuation platform's legs, retraction and hooks: … → SOFT_CAPTURED →
//! RETRACTED → HARD_DOCKED (→ RELEASED). Every change is an event; `docs/mechanisms.md`
//! describes the issue-28 additions.
//!
//! Geometry and the magnet law are documented on [`crate::scene::DockingSpec`] and
//! [`crate::scene::MagnetSpec`]. Contact is real: the cone and the slot's wall pieces are rapier
//! colliders, and the monitor says which parts touch.

use super::contact_model::{CompliantContact, ImpactRecord, LatchSpring, SeparationSpring};
use super::monitor::ContactState;
use super::output::Diagnostics;
use super::{BodyState, Clock, EventLog, Physics, SimBody, SimStep, Wrench, conv};
use crate::scene::{DockingSpec, LatchJoint, LoadedScene, SceneError};
use bevy::prelude::*;
use bevy_rapier3d::rapier::prelude as rp;
use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};
use serde::Serialize;

/// How long a docking contact counts as ongoing after the last touching step, s.
pub const CONTACT_HOLD_S: f64 = 0.1;

/// A port in its body frame: (origin, unit outward axis).
pub type PortFrame = (Vector3<f64>, Vector3<f64>);

/// Impacts kept in the summary (the count is always given).
pub const MAX_IMPACTS_LISTED: usize = 100;

/// Loads on the mechanism from the first docking contact to the latch (the latched pair's
/// internal forces are joint loads, reported apart). The contact force on the chaser's docking
/// parts F is split along the target port axis a_t: axial |F·a_t|, lateral |F − (F·a_t)·a_t|.
#[derive(Debug, Clone, Default, Serialize)]
pub struct DockingLoads {
    /// Which contact model ran ([`crate::contact::describe`]).
    pub model: String,
    /// Largest axial load, N.
    pub peak_axial_load_n: f64,
    /// When, s.
    pub peak_axial_t_s: Option<f64>,
    /// Largest lateral load, N.
    pub peak_lateral_load_n: f64,
    /// When, s.
    pub peak_lateral_t_s: Option<f64>,
    /// Largest contact force magnitude, N.
    pub peak_force_n: f64,
    /// Time in docking contact, s (compliant: sub-steps with a penetrating pair; rigid: steps
    /// with a touching pair × dt).
    pub contact_duration_s: f64,
    /// Sum over steps of the magnitude of the contact impulse on the chaser, N·s.
    pub impulse_ns: f64,
    /// Net contact impulse on the chaser, world frame, N·s.
    pub net_impulse_on_chaser_ns: [f64; 3],
    /// Impacts (compliant model: first touch to separation of one part pair), the first
    /// [`MAX_IMPACTS_LISTED`].
    pub impacts: Vec<ImpactRecord>,
    /// Impacts in all.
    pub impact_count: u64,
    /// Peak force of the latch joint on the chaser, N. The joint is rigid (a rapier fixed
    /// joint): a latch that closes on a cone still moving stops it within one step, so this
    /// peak is that impulse over dt and depends on the step; the impulse does not.
    pub peak_joint_force_n: f64,
    /// Peak moment of the latch joint on the chaser about its port, N·m (same caveat).
    pub peak_joint_torque_nm: f64,
    /// The joint's impulse on the chaser in the first step after the latch (what it took to
    /// stop the relative motion the latch caught), N·s.
    pub latch_impulse_ns: Option<f64>,
    /// The compliant model's sub-stepping (absent for rigid contact).
    pub substepping: Option<super::contact_model::SubstepStats>,
}

impl DockingLoads {
    /// Adds one sample of the contact force on the chaser `f` (N, world) held for `h` s.
    fn sample(&mut self, t: f64, f: &Vector3<f64>, axis: &Vector3<f64>) {
        let ax = f.dot(axis);
        let lat = (f - axis * ax).norm();
        if ax.abs() > self.peak_axial_load_n {
            self.peak_axial_load_n = ax.abs();
            self.peak_axial_t_s = Some(t);
        }
        if lat > self.peak_lateral_load_n {
            self.peak_lateral_load_n = lat;
            self.peak_lateral_t_s = Some(t);
        }
        self.peak_force_n = self.peak_force_n.max(f.norm());
    }
}

/// Loads of a compliant latch at the interface (the chaser port origin), from the f64
/// spring–damper force evaluated at every sub-step.
#[derive(Debug, Clone, Default, Serialize)]
pub struct InterfaceLoads {
    /// Largest force on the chaser at its port, N.
    pub peak_force_n: f64,
    /// When (end of the step that held it), s.
    pub peak_force_t_s: Option<f64>,
    /// Largest moment on the chaser about its port, N·m.
    pub peak_moment_nm: f64,
    /// When, s.
    pub peak_moment_t_s: Option<f64>,
    /// Force on the chaser at its port at the end of the last latched step, world, N.
    pub last_force_n: [f64; 3],
    /// Moment on the chaser about its port then, world, N·m.
    pub last_moment_nm: [f64; 3],
}

pub use crate::contact::dock_state::DockState;

/// Results of a soft-capture mechanism (`summary.json` → `docking.soft_capture`). Leg loads
/// are the largest over every sub-step; the interface load is the platform's and the hooks'
/// load on the chaser at (force) and about (moment) its port origin, world frame; each time is
/// the end of the step that held the peak, s.
#[derive(Debug, Clone, Default, Serialize)]
pub struct SoftCaptureResults {
    /// Event `SOFT_CAPTURED`, s.
    pub t_soft_captured_s: Option<f64>,
    /// The retraction began (end of the attenuation), s.
    pub t_retraction_start_s: Option<f64>,
    /// Event `RETRACTED`, s.
    pub t_retracted_s: Option<f64>,
    /// Event `HARD_DOCKED`, s.
    pub t_hard_docked_s: Option<f64>,
    /// Largest |leg stroke|, m.
    pub peak_leg_stroke_m: f64,
    /// When, s.
    pub peak_leg_stroke_t_s: Option<f64>,
    /// Largest |leg force|, N.
    pub peak_leg_force_n: f64,
    /// When, s.
    pub peak_leg_force_t_s: Option<f64>,
    /// Largest interface force on the chaser at its port, N.
    pub peak_interface_force_n: f64,
    /// When, s.
    pub peak_interface_force_t_s: Option<f64>,
    /// Largest interface moment on the chaser about its port, N·m.
    pub peak_interface_moment_nm: f64,
    /// When, s.
    pub peak_interface_moment_t_s: Option<f64>,
    /// Retraction at the end of the run, m.
    pub retraction_m: f64,
    /// The capture latches were tried in the present visit of the capture zone (one try per
    /// visit: a refused ring bounces off, as a real capture latch does not engage later in
    /// the same contact).
    #[serde(skip)]
    pub attempted: bool,
    /// Trajectory columns: per leg (stroke, force), ring pose in P (x, y, z m, rotation
    /// vector x, y, z deg), interface force (x, y, z N) and moment (x, y, z N·m), retraction.
    #[serde(skip)]
    pub cols: Vec<usize>,
}

/// Commands to the mechanism, acted on at the start of the next mechanism step: the Sequencer
/// (a phase with `release_docking`) and [`crate::sim::Simulation::release_docking`] push here.
#[derive(Resource, Debug, Clone, Default)]
pub struct DockingCommands {
    /// Release commands not yet acted on, each with where it came from.
    pub release: Vec<String>,
}

/// What let go of the chaser (`the capture latches let go`, `the latch broke`), when and by how
/// much the `what` force (`interface`, `joint`) exceeded the break force, for [`Docking::let_go`].
fn let_go_text(who: &str, what: &str, t_s: f64, force_n: f64, break_force_n: f64) -> String {
    format!(
        "{who} at {t_s:.3} s: {what} force {force_n:.1} N, {:.1} N above the break force {break_force_n:.1} N",
        force_n - break_force_n
    )
}

/// Port geometry at one instant (world frame).
#[derive(Debug, Clone, Default, Serialize)]
pub struct PortGeometry {
    /// |p_c − p_seat|, m.
    pub gap_m: f64,
    /// (p_c − p_t)·a_t − seat depth, m (positive: not yet in).
    pub axial_error_m: f64,
    /// Offset of p_c from the target port axis, m.
    pub lateral_m: f64,
    /// Angle between a_c and −a_t, deg.
    pub misalignment_deg: f64,
    /// Rate of the axial error (negative: closing), m/s.
    pub axial_rate_m_s: f64,
    /// Relative speed of the chaser port point w.r.t. the target's material point there, m/s.
    pub rel_speed_m_s: f64,
    /// Part of that relative velocity perpendicular to the target port axis, m/s.
    pub lateral_rate_m_s: f64,
    /// Magnitude of the relative angular velocity |ω_c − ω_t|, deg/s.
    pub angular_rate_deg_s: f64,
}

/// Which capture rate limit, if any, the relative motion `g` exceeds: the first of axial,
/// lateral, angular (in that order) whose value is strictly above its limit, as an event
/// payload (`rate`, `value`, `limit`) and a sentence naming the rate. A rate equal to its limit
/// is accepted.
pub fn capture_rate_violation(
    limits: &crate::scene::CaptureRates,
    g: &PortGeometry,
) -> Option<(serde_json::Value, String)> {
    [
        (
            "axial_rate_m_s",
            g.axial_rate_m_s.abs(),
            limits.max_axial_rate_m_s,
            "m/s",
        ),
        (
            "lateral_rate_m_s",
            g.lateral_rate_m_s,
            limits.max_lateral_rate_m_s,
            "m/s",
        ),
        (
            "angular_rate_deg_s",
            g.angular_rate_deg_s,
            limits.max_angular_rate_deg_s,
            "deg/s",
        ),
    ]
    .into_iter()
    // A NaN rate is refused too.
    .find(|(_, v, lim, _)| v.is_nan() || v > lim)
    .map(|(name, v, lim, unit)| {
        (
            serde_json::json!({"rate": name, "value": v, "limit": lim}),
            format!("latch refused: relative {name} {v:.6} {unit} > limit {lim:.6} {unit}"),
        )
    })
}

/// The mechanism's state and results.
#[derive(Resource, Debug, Clone)]
pub struct Docking {
    /// The scene's specification.
    pub spec: DockingSpec,
    /// Chaser and target entities.
    pub bodies: (Entity, Entity),
    /// Ports in their body frames: (origin, unit axis).
    pub ports: (PortFrame, PortFrame),
    /// Current state.
    pub state: DockState,
    /// Why the current state was entered.
    pub reason: String,
    /// Magnet on.
    pub magnet_on: bool,
    /// Magnet force this step, N.
    pub magnet_force_n: f64,
    /// Latest geometry.
    pub geometry: PortGeometry,
    /// When the cone last seated, s.
    pub seated_since: Option<f64>,
    /// In docking contact, not seated, slow, since, s.
    pub jam_since: Option<f64>,
    /// Latch time, s.
    pub t_latch_s: Option<f64>,
    /// First docking contact, s.
    pub t_first_contact_s: Option<f64>,
    /// Largest misalignment while in contact, deg.
    pub max_misalignment_deg: f64,
    /// The latch joint.
    pub joint: Option<rp::ImpulseJointHandle>,
    /// Peak latch-joint force, N.
    pub peak_joint_force_n: f64,
    /// Loads on the mechanism.
    pub loads: DockingLoads,
    /// Last step with a docking contact, s.
    pub last_docking_contact_s: Option<f64>,
    /// The approach judgements apply (the gap has fallen below `miss.arm_gap_m`, or no such
    /// threshold).
    pub armed: bool,
    /// The chaser port's axial error at the previous step, m (positive: in front of the seat).
    pub prev_axial_error_m: Option<f64>,
    /// The rate the latch is refusing on now (`None`: not refusing); a refusal is an event when
    /// it starts or the rate named changes.
    pub refusing: Option<String>,
    /// Latch refusals (events `capture_refused`) in the run.
    pub refusals: u64,
    /// Relative rates when the latch engaged: axial, lateral (m/s), angular (deg/s).
    pub latch_rates: Option<[f64; 3]>,
    /// A compliant latch's interface loads (absent for a rigid latch).
    pub interface: Option<InterfaceLoads>,
    /// The release time, s.
    pub t_release_s: Option<f64>,
    /// Relative velocity of the chaser port w.r.t. the target when the separation springs
    /// reached the end of their stroke (world, m/s), and when, s.
    pub separation_end: Option<([f64; 3], f64)>,
    /// A soft-capture mechanism's results (absent for the cone and slot).
    pub soft: Option<SoftCaptureResults>,
    /// What let go of the chaser, when and why, if the latch broke or the capture latches let
    /// go (`the capture latches let go at 2.310 s: interface force 5523.1 N, 523.1 N above the
    /// break force 5000.0 N`): a later MISSED or REBOUND names it as its cause's start.
    pub let_go: Option<String>,
    /// Diagnostics column indices: gap, axial, lateral, misalignment, magnet, state, joint force,
    /// joint torque.
    cols: [usize; 8],
}

/// The platform frame P of a port in its body frame: origin the port origin, +z the port axis,
/// the rotation the shortest one from body +z onto the axis (half a turn about x when the axis
/// is −z).
pub fn port_platform_frame(port: &PortFrame) -> Isometry3<f64> {
    let rot = UnitQuaternion::rotation_between(&Vector3::z(), &port.1).unwrap_or_else(|| {
        UnitQuaternion::from_axis_angle(&Vector3::x_axis(), std::f64::consts::PI)
    });
    Isometry3::from_parts(Translation3::from(port.0), rot)
}

/// World port origin and unit axis of a body.
fn port_world(s: &BodyState, com: &Vector3<f64>, port: &PortFrame) -> (Vector3<f64>, Vector3<f64>) {
    let pose = s.body_pose(com);
    (pose.transform_point(&port.0.into()).coords, s.att * port.1)
}

/// Velocity of the material point at world position `p` of a body.
fn point_velocity(s: &BodyState, p: &Vector3<f64>) -> Vector3<f64> {
    s.vel_m_s + s.omega_rad_s.cross(&(p - s.pos_m))
}

/// Port geometry of the chaser relative to the target.
pub fn geometry(
    spec: &DockingSpec,
    chaser: (&BodyState, &SimBody),
    target: (&BodyState, &SimBody),
    ports: &(PortFrame, PortFrame),
) -> (PortGeometry, Vector3<f64>, Vector3<f64>) {
    let (pc, ac) = port_world(chaser.0, &chaser.1.com_body_m, &ports.0);
    let (pt, at) = port_world(target.0, &target.1.com_body_m, &ports.1);
    let d = pc - pt;
    let axial = d.dot(&at);
    let lateral = (d - at * axial).norm();
    let seat = pt + at * spec.seat_depth_m;
    let v_rel = point_velocity(chaser.0, &pc) - point_velocity(target.0, &pc);
    // Rate of the axial error: d/dt[(p_c − p_t)·a_t] = (v_c(p_c) − v_t(p_t))·a_t
    // + (p_c − p_t)·(ω_t × a_t), which reduces to v_rel·a_t with v_rel taken at p_c.
    let axial_rate = v_rel.dot(&at);
    let w_rel = chaser.0.omega_rad_s - target.0.omega_rad_s;
    let g = PortGeometry {
        gap_m: (pc - seat).norm(),
        axial_error_m: axial - spec.seat_depth_m,
        lateral_m: lateral,
        misalignment_deg: ac.dot(&(-at)).clamp(-1.0, 1.0).acos().to_degrees(),
        axial_rate_m_s: axial_rate,
        rel_speed_m_s: v_rel.norm(),
        lateral_rate_m_s: (v_rel - at * axial_rate).norm(),
        angular_rate_deg_s: w_rel.norm().to_degrees(),
    };
    (g, pc, at)
}

/// The docking mechanism of a scene with `docking: Some(..)`: owns the [`Docking`] and
/// [`DockingCommands`] resources, the `dock.*` output columns (registered when it is added, in
/// the order the trajectory shows them) and two systems: `docking_actuate` in
/// [`super::Order::MechanismForces`] (Actuate: a latch that starts closed, release commands,
/// the magnet) and `docking_monitor` in [`super::Order::Mechanism`] (Monitor: capture, latch,
/// loads and state changes from the step's contacts). Add it after [`super::PipelinePlugin`]
/// and before the controllers (their observations read the docking state).
#[derive(Debug, Clone)]
pub struct DockingPlugin {
    /// The mechanism at t = 0, its column indices still unset.
    docking: Docking,
    /// Legs of a soft-capture platform (their columns), `None` for a cone-and-slot mechanism.
    soft_legs: Option<usize>,
}

impl DockingPlugin {
    /// The mechanism of the scene's `docking` (`None` without one), checked against the built
    /// bodies (`world` holds the [`super::Roster`] and the bodies' states at t = 0): located
    /// errors for an unknown body or platform, or a chaser that `start_latched` but is not
    /// seated.
    pub fn new(world: &World, loaded: &LoadedScene) -> Result<Option<Self>, SceneError> {
        let Some(docking) = new_docking(world, loaded)? else {
            return Ok(None);
        };
        let soft_legs = docking.soft.as_ref().map(|s| s.cols.len());
        Ok(Some(Self { docking, soft_legs }))
    }
}

impl Plugin for DockingPlugin {
    fn build(&self, app: &mut App) {
        let mut docking = self.docking.clone();
        let mut diag = app.world_mut().resource_mut::<Diagnostics>();
        docking.cols = [
            diag.column("dock.gap_m"),
            diag.column("dock.axial_error_m"),
            diag.column("dock.lateral_m"),
            diag.column("dock.misalignment_deg"),
            diag.column("dock.magnet_n"),
            diag.column("dock.state"),
            diag.column("dock.joint_force_n"),
            diag.column("dock.joint_torque_nm"),
        ];
        if let (Some(n), Some(soft)) = (self.soft_legs, docking.soft.as_mut()) {
            let mut c = Vec::with_capacity(2 * n + 13);
            for i in 0..n {
                c.push(diag.column(&format!("dock.leg{i}_stroke_m")));
                c.push(diag.column(&format!("dock.leg{i}_force_n")));
            }
            for name in SOFT_CAPTURE_COLUMNS {
                c.push(diag.column(name));
            }
            soft.cols = c;
        }
        app.init_resource::<DockingCommands>();
        app.insert_resource(docking);
        app.add_systems(
            SimStep,
            docking_actuate.in_set(super::Order::MechanismForces),
        );
        app.add_systems(SimStep, docking_monitor.in_set(super::Order::Mechanism));
    }
}

/// A soft-capture platform's columns after its legs' (ring pose, interface loads, retraction).
const SOFT_CAPTURE_COLUMNS: [&str; 13] = [
    "dock.ring_x_m",
    "dock.ring_y_m",
    "dock.ring_z_m",
    "dock.ring_rot_x_deg",
    "dock.ring_rot_y_deg",
    "dock.ring_rot_z_deg",
    "dock.iface_fx_n",
    "dock.iface_fy_n",
    "dock.iface_fz_n",
    "dock.iface_mx_nm",
    "dock.iface_my_nm",
    "dock.iface_mz_nm",
    "dock.retraction_m",
];

/// The mechanism's state at t = 0 (column indices unset; `soft.cols` holds one placeholder per
/// leg).
fn new_docking(world: &World, loaded: &LoadedScene) -> Result<Option<Docking>, SceneError> {
    let Some(spec) = loaded.scene.docking.clone() else {
        return Ok(None);
    };
    let roster = world.resource::<super::Roster>().clone();
    let find = |name: &str, field: &str| {
        roster.names.iter().position(|n| n == name).ok_or_else(|| {
            loaded.error_at(&format!("docking.{field}"), format!("no body `{name}`"))
        })
    };
    let ci = find(&spec.chaser, "chaser")?;
    let ti = find(&spec.target, "target")?;
    let port = |bi: usize, name: &str| {
        crate::scene::parts::port_frame(&loaded.scene.bodies[bi], name).expect("validated port")
    };
    let ports = (port(ci, &spec.chaser_port), port(ti, &spec.target_port));
    let soft = match &spec.mechanism {
        crate::scene::Mechanism::SoftCapture(sc) => {
            let n = crate::contact::platform::Platform::new(&sc.platform)
                .map_err(|e| {
                    loaded.error_at(
                        &format!("docking.mechanism.platform.{}", e.field),
                        e.why.clone(),
                    )
                })?
                .legs
                .len();
            Some(SoftCaptureResults {
                cols: vec![0; n],
                ..Default::default()
            })
        }
        crate::scene::Mechanism::ConeSlot => None,
    };
    let magnet_on = spec.magnet.on_at_start;
    let spec_contact = spec.contact.clone();
    let start_latched = spec.start_latched;
    if start_latched {
        let state = |e: Entity| {
            (
                world.get::<BodyState>(e).cloned(),
                world.get::<SimBody>(e).cloned(),
            )
        };
        let (e_c, e_t) = (roster.bodies[ci], roster.bodies[ti]);
        if let ((Some(cs), Some(cb)), (Some(ts), Some(tb))) = (state(e_c), state(e_t)) {
            let (g, _, _) = geometry(&spec, (&cs, &cb), (&ts, &tb), &ports);
            let l = &spec.latch;
            if !(g.axial_error_m.abs() <= l.axial_tolerance_m
                && g.lateral_m <= l.lateral_tolerance_m
                && g.misalignment_deg <= l.angle_tolerance_deg)
            {
                return Err(loaded.error_at(
                    "docking.start_latched",
                    format!(
                        "the chaser is not seated at t = 0 (axial error {:.4} m, lateral {:.4} m, misalignment {:.2}°; tolerances {} m, {} m, {}°): place its port on the seat",
                        g.axial_error_m,
                        g.lateral_m,
                        g.misalignment_deg,
                        l.axial_tolerance_m,
                        l.lateral_tolerance_m,
                        l.angle_tolerance_deg
                    ),
                ));
            }
        }
    }
    Ok(Some(Docking {
        spec,
        bodies: (roster.bodies[ci], roster.bodies[ti]),
        ports,
        state: if start_latched {
            // The latch closes at the first mechanism step ([`docking_actuate`]).
            DockState::Latched
        } else if magnet_on {
            DockState::Attracting
        } else {
            DockState::Free
        },
        reason: String::new(),
        magnet_on,
        magnet_force_n: 0.0,
        geometry: PortGeometry::default(),
        seated_since: None,
        jam_since: None,
        t_latch_s: None,
        t_first_contact_s: None,
        max_misalignment_deg: 0.0,
        joint: None,
        peak_joint_force_n: 0.0,
        loads: DockingLoads {
            model: crate::contact::describe(&spec_contact),
            ..Default::default()
        },
        last_docking_contact_s: None,
        armed: false,
        prev_axial_error_m: None,
        refusing: None,
        refusals: 0,
        latch_rates: None,
        interface: None,
        t_release_s: None,
        separation_end: None,
        let_go: None,
        soft,
        cols: [0; 8],
    }))
}

/// Actuate: the magnet's force on the chaser port and its reaction on the target.
/// Actuate: a latch that starts closed, release commands, and the magnet's force on the chaser
/// port and its reaction on the target.
#[allow(clippy::too_many_arguments)] // a Bevy system: one parameter per resource it uses
fn docking_actuate(
    mut dock: ResMut<Docking>,
    mut q: Query<(&SimBody, &BodyState, &mut Wrench)>,
    clock: Res<Clock>,
    mut phys: ResMut<Physics>,
    mut compliant: Option<ResMut<CompliantContact>>,
    mut cmds: ResMut<DockingCommands>,
    mut log: ResMut<EventLog>,
) {
    let (ce, te) = dock.bodies;
    let t = clock.t_s();
    let [(cb, cs, _), (tb, ts, _)] = q.get_many([ce, te]).expect("docking bodies");
    if dock.state == DockState::Latched && dock.t_latch_s.is_none() {
        // `start_latched`: close the latch where the scene placed the chaser.
        engage_latch(
            &mut dock,
            (cs, cb),
            (ts, tb),
            &mut phys,
            compliant.as_deref_mut(),
        );
        dock.t_latch_s = Some(t);
        dock.reason = "started latched (docking.start_latched)".into();
    }
    for source in std::mem::take(&mut cmds.release) {
        if !dock.state.docked() {
            log.push(
                t,
                "docking_release_ignored",
                serde_json::json!({"state": dock.state.name(), "source": source,
                    "reason": format!("release commanded while {}: not docked", dock.state.name())}),
            );
            continue;
        }
        if let Some(h) = dock.joint.take() {
            phys.world.impulse_joints.remove(h, true);
        }
        let (pc, _) = port_world(cs, &cb.com_body_m, &dock.ports.0);
        let (pt, at) = port_world(ts, &tb.com_body_m, &dock.ports.1);
        if let Some(c) = compliant.as_deref_mut() {
            c.link.latch = None;
            // A soft-capture mechanism opens everything: hooks, capture latches (the ring
            // returns to the chaser's platform).
            c.link.platform = None;
            c.link.chaser_is_b = c.indices.1 == cb.index;
            c.link.separation = dock.spec.separation.as_ref().map(|sp| SeparationSpring {
                stroke_m: sp.stroke_m,
                force_n: sp.force_n,
                preload_n: sp.preload_n,
                x0_m: (pc - pt).dot(&at),
                ports_body_m: (dock.ports.0.0, dock.ports.1.0, dock.ports.1.1),
            });
            c.enabled = true;
        }
        let reason = format!(
            "released ({source}){}",
            if dock.spec.separation.is_some() {
                "; separation springs pushing"
            } else {
                ""
            }
        );
        log.push(
            t,
            "docking_state",
            serde_json::json!({"from": dock.state.name(), "to": "RELEASED", "reason": reason}),
        );
        dock.state = DockState::Released;
        dock.reason = reason;
        dock.t_release_s = Some(t);
        dock.magnet_on = false;
    }
    let (g, pc, at) = geometry(&dock.spec, (cs, cb), (ts, tb), &dock.ports);
    let m = dock.spec.magnet.clone();
    if !dock.magnet_on && m.activation_distance_m > 0.0 && g.gap_m < m.activation_distance_m {
        dock.magnet_on = true;
    }
    let on = dock.magnet_on && !dock.state.docked() && dock.state != DockState::Released;
    let f = if on {
        (m.f0_n / (1.0 + g.gap_m / m.g0_m).powi(2)).min(m.max_force_n)
    } else {
        0.0
    };
    dock.magnet_force_n = f;
    dock.geometry = g;
    if f > 0.0 {
        let force = -at * f; // into the slot
        let [(cb, cs, mut cw), (_, ts, mut tw)] = q.get_many_mut([ce, te]).expect("docking bodies");
        let _ = cb;
        cw.force_n += force;
        cw.torque_nm += (pc - cs.pos_m).cross(&force);
        tw.force_n -= force;
        tw.torque_nm += (pc - ts.pos_m).cross(&(-force));
    }
}

/// Monitor: the state machine, the latch joint and its break force. One step, in order: the
/// loads on the mechanism up to the latch ([`record_approach_loads`]), what the step saw of the
/// approach ([`observe`]), the state machine ([`decide`]), the state change and its event
/// ([`commit_change`]), and the `dock.*` columns ([`write_columns`]).
#[allow(clippy::too_many_arguments)] // a Bevy system: one parameter per resource it uses
fn docking_monitor(
    mut dock: ResMut<Docking>,
    clock: Res<Clock>,
    contacts: Res<ContactState>,
    mut phys: ResMut<Physics>,
    q: Query<(&SimBody, &BodyState)>,
    mut log: ResMut<EventLog>,
    mut diag: ResMut<Diagnostics>,
    mut compliant: Option<ResMut<CompliantContact>>,
) {
    let dock = &mut *dock;
    let (ce, te) = dock.bodies;
    let [(cb, cs), (tb, ts)] = q.get_many([ce, te]).expect("docking bodies");
    let (g, _, at) = geometry(&dock.spec, (cs, cb), (ts, tb), &dock.ports);
    let spec = dock.spec.clone();
    let s = MonitorStep {
        t: clock.t_s(),
        dt: clock.h_s(),
        chaser: (cs, cb),
        target: (ts, tb),
        g: &g,
        at,
        spec: &spec,
    };
    if !dock.state.docked() {
        record_approach_loads(
            &s,
            &mut dock.loads,
            compliant.as_deref_mut(),
            &contacts,
            &mut log,
        );
    }
    let seen = observe(dock, &s, &contacts);
    let (joint_now, change) = decide(
        dock,
        &s,
        &seen,
        &mut phys,
        &contacts,
        compliant.as_deref_mut(),
        &mut log,
    );
    commit_change(dock, s.t, change, &mut log);
    write_columns(dock, &s, joint_now, compliant.as_deref(), &mut diag);
    dock.geometry = g;
}

/// What every phase of one [`docking_monitor`] step reads: the time, the pair and their port
/// geometry at the end of the step.
struct MonitorStep<'a> {
    /// End of the step, s.
    t: f64,
    /// The step, s.
    dt: f64,
    /// The chaser's state and body.
    chaser: (&'a BodyState, &'a SimBody),
    /// The target's state and body.
    target: (&'a BodyState, &'a SimBody),
    /// Port geometry at the end of the step (world frame).
    g: &'a PortGeometry,
    /// The target port's unit axis, world frame.
    at: Vector3<f64>,
    /// The scene's specification (a copy of [`Docking::spec`]).
    spec: &'a DockingSpec,
}

/// What one step saw of the approach, for the state machine ([`observe`]).
struct Seen {
    /// In docking contact: a docking part pair touches now, or touched within
    /// [`CONTACT_HOLD_S`].
    docking_contact: bool,
    /// The approach judgements apply ([`Docking::armed`]).
    armed: bool,
    /// The chaser port is within the latch's axial, lateral and angle tolerances of the seat.
    seated: bool,
    /// The chaser port was in front of the seat plane (axial error ≥ 0 m) at the previous step.
    crossed_from_front: bool,
    /// A pair of the two vehicles' parts other than the docking parts touching (`"A and B"`),
    /// the first found.
    collision: Option<String>,
}

/// A state change: the state entered and why.
type Change = (DockState, String);

/// The soft-capture mechanism's specification, `None` for the cone and slot.
fn soft_spec(spec: &DockingSpec) -> Option<&crate::scene::SoftCaptureSpec> {
    match &spec.mechanism {
        crate::scene::Mechanism::SoftCapture(sc) => Some(sc),
        crate::scene::Mechanism::ConeSlot => None,
    }
}

/// Loads on the mechanism up to the latch: the compliant model's sub-step history (its impacts
/// become `impact` events), or the rigid contacts' impulse / dt.
fn record_approach_loads(
    s: &MonitorStep,
    loads: &mut DockingLoads,
    mut compliant: Option<&mut CompliantContact>,
    contacts: &ContactState,
    log: &mut EventLog,
) {
    let (t, dt, at) = (s.t, s.dt, &s.at);
    let chaser = s.chaser.1.index;
    let mut j_step = Vector3::zeros();
    match compliant
        .as_deref_mut()
        .filter(|c| c.enabled || !c.step.is_empty())
    {
        Some(c) => {
            let sign = if c.indices.1 == chaser { 1.0 } else { -1.0 };
            let mut tt = t - dt;
            for (h, f) in &c.b_force_history {
                tt += h;
                loads.sample(tt, &(f * sign), at);
            }
            loads.contact_duration_s += c.step_contact_s;
            for st in &c.step {
                j_step += st.impulse_on_b_ns * sign;
            }
            for imp in c.impacts.drain(..) {
                log.push(
                    imp.t_end_s,
                    "impact",
                    serde_json::to_value(&imp).unwrap_or_default(),
                );
                loads.impact_count += 1;
                if loads.impacts.len() < MAX_IMPACTS_LISTED {
                    loads.impacts.push(imp);
                }
            }
        }
        None => {
            let mut any = false;
            for sp in contacts.step_pairs.iter().filter(|p| p.docking) {
                if sp.bodies.1 == chaser {
                    j_step += sp.impulse_on_b_ns;
                } else if sp.bodies.0 == chaser {
                    j_step -= sp.impulse_on_b_ns;
                } else {
                    continue;
                }
                any = true;
            }
            if any {
                loads.contact_duration_s += dt;
                loads.sample(t, &(j_step / dt), at);
            }
        }
    }
    loads.impulse_ns += j_step.norm();
    loads.substepping = compliant.as_deref().map(|c| c.stats);
    for (n, v) in loads.net_impulse_on_chaser_ns.iter_mut().zip(j_step.iter()) {
        *n += v;
    }
}

/// The touching pairs between the chaser's and the target's parts (names `BODY/part`): whether
/// a docking pair touches, and the first other pair (`"A and B"`), a collision.
fn scan_contacts(contacts: &ContactState, chaser: &str, target: &str) -> (bool, Option<String>) {
    let prefix = (format!("{chaser}/"), format!("{target}/"));
    let between = |a: &str, b: &str| {
        (a.starts_with(&prefix.0) && b.starts_with(&prefix.1))
            || (a.starts_with(&prefix.1) && b.starts_with(&prefix.0))
    };
    let mut touching_now = false;
    let mut collision: Option<String> = None;
    for ((a, b), c) in &contacts.active {
        if between(a, b) {
            if c.docking {
                touching_now = true;
            } else if collision.is_none() {
                collision = Some(format!("{a} and {b}"));
            }
        }
    }
    (touching_now, collision)
}

/// What the step saw of the approach, with its bookkeeping: the last docking contact, arming,
/// the first contact and the largest misalignment in contact, the previous axial error, and a
/// soft-capture visit of the capture zone ending when the chaser leaves the seat tolerances.
fn observe(dock: &mut Docking, s: &MonitorStep, contacts: &ContactState) -> Seen {
    let (t, g, spec) = (s.t, s.g, s.spec);
    let (touching_now, collision) = scan_contacts(contacts, &s.chaser.1.name, &s.target.1.name);
    // A cone sliding in a funnel touches and leaves the walls from step to step; contact counts
    // as ongoing until it has been absent for CONTACT_HOLD_S.
    if touching_now {
        dock.last_docking_contact_s = Some(t);
    }
    let docking_contact = dock
        .last_docking_contact_s
        .is_some_and(|tc| t - tc <= CONTACT_HOLD_S + 1e-9);
    if !dock.armed && spec.miss.arm_gap_m.is_none_or(|d| g.gap_m <= d) {
        dock.armed = true;
    }
    let seated = g.axial_error_m.abs() <= spec.latch.axial_tolerance_m
        && g.lateral_m <= spec.latch.lateral_tolerance_m
        && g.misalignment_deg <= spec.latch.angle_tolerance_deg;
    if docking_contact {
        dock.t_first_contact_s.get_or_insert(t);
        dock.max_misalignment_deg = dock.max_misalignment_deg.max(g.misalignment_deg);
    }
    // "Passed beside" is a crossing of the seat plane from the front this step, not a chaser that
    // is (or starts) behind the target's port plane while it manoeuvres.
    let crossed_from_front = dock.prev_axial_error_m.is_some_and(|p| p >= 0.0);
    dock.prev_axial_error_m = Some(g.axial_error_m);
    if !seated && let Some(r) = dock.soft.as_mut() {
        r.attempted = false;
    }
    Seen {
        docking_contact,
        armed: dock.armed,
        seated,
        crossed_from_front,
        collision,
    }
}

/// The state machine, one function per family of states: the change this step makes (`None`:
/// none) and the load on the chaser of what holds it (`dock.joint_force_n`, N, and
/// `dock.joint_torque_nm`, N·m; zero unless a latch or the capture latches hold it).
fn decide(
    dock: &mut Docking,
    s: &MonitorStep,
    seen: &Seen,
    phys: &mut Physics,
    contacts: &ContactState,
    compliant: Option<&mut CompliantContact>,
    log: &mut EventLog,
) -> ((f64, f64), Option<Change>) {
    use DockState::*;
    let unloaded = (0.0, 0.0);
    match dock.state {
        Missed => (unloaded, None),
        SoftCaptured | Retracted | HardDocked => soft_captured_step(dock, s, compliant, log),
        Released => {
            separation_step(dock, s, compliant.as_deref(), log);
            (unloaded, None)
        }
        Latched if dock.interface.is_some() => compliant_latch_step(dock, s, compliant),
        Latched => rigid_latch_step(dock, s, phys, contacts, compliant),
        _ => (unloaded, approach_step(dock, s, seen, phys, compliant, log)),
    }
}

/// Enters the state `change` names if it differs from the present one: a MISSED or REBOUND
/// after the mechanism let go of the chaser says so, a docked state forgets the let-go, and the
/// change is a `docking_state` event.
fn commit_change(dock: &mut Docking, t: f64, change: Option<Change>, log: &mut EventLog) {
    let old = dock.state;
    let Some((new, mut reason)) = change.filter(|(new, _)| *new != old) else {
        return;
    };
    if matches!(new, DockState::Missed | DockState::Rebound)
        && let Some(why) = dock.let_go.as_deref()
        && !reason.contains(why)
    {
        // The cause began when the mechanism let go of the chaser: say so.
        reason = format!("{reason}, after {why}");
    }
    if new.docked() {
        // Held again: a later let-go is a new one.
        dock.let_go = None;
    }
    dock.refusing = None;
    dock.state = new;
    dock.reason = reason.clone();
    log.push(
        t,
        "docking_state",
        serde_json::json!({"from": old.name(), "to": new.name(), "reason": reason}),
    );
}

/// SOFT_CAPTURED, RETRACTED, HARD_DOCKED: the platform's and the interface's peaks, then the
/// capture latches letting go above the break force, the end of the attenuation (the
/// retraction starts), the end of the retraction, or the hooks closing once the interface is
/// aligned. Returns the interface load on the chaser this step (N, N·m) and the change.
fn soft_captured_step(
    dock: &mut Docking,
    s: &MonitorStep,
    compliant: Option<&mut CompliantContact>,
    log: &mut EventLog,
) -> ((f64, f64), Option<Change>) {
    use DockState::*;
    let (t, g, spec) = (s.t, s.g, s.spec);
    let old = dock.state;
    let sc = soft_spec(spec).expect("soft-capture states need the mechanism");
    let ports = dock.ports;
    let (ls, ps) = compliant
        .as_deref()
        .map(|c| (c.link_step, c.platform_step.clone()))
        .unwrap_or_default();
    let joint_now = (ls.peak_force_n, ls.peak_moment_nm);
    let r = dock.soft.as_mut().expect("soft-capture results");
    record_soft_peaks(r, t, &ls, &ps);
    let retraction = compliant
        .as_deref()
        .and_then(|c| c.link.platform.as_ref())
        .map_or(0.0, |p| p.retraction_m);
    r.retraction_m = retraction;
    let t_cap = r.t_soft_captured_s.unwrap_or(t);
    let change = if old != HardDocked && ls.peak_force_n > spec.latch.break_force_n {
        Some(capture_latches_let_go(
            &mut dock.let_go,
            s,
            sc,
            (ls.peak_force_n, &ps),
            compliant,
        ))
    } else if old == SoftCaptured
        && r.t_retraction_start_s.is_none()
        && t - t_cap >= sc.attenuation_s - 1e-9
    {
        // Attenuation over: the platform retracts from the next step on.
        r.t_retraction_start_s = Some(t);
        set_retraction_rate(compliant, sc.retraction_speed_m_s);
        log.push(
            t,
            "retraction_start",
            serde_json::json!({"speed_m_s": sc.retraction_speed_m_s,
                "stroke_m": sc.retracted_stroke_m}),
        );
        None
    } else if old == SoftCaptured
        && r.t_retraction_start_s.is_some()
        && retraction >= sc.retracted_stroke_m
    {
        r.t_retracted_s = Some(t);
        set_retraction_rate(compliant, 0.0);
        let reason = format!(
            "retracted {:.4} m at {} m/s",
            retraction, sc.retraction_speed_m_s
        );
        Some((Retracted, reason))
    } else if old == Retracted
        && g.lateral_m <= sc.hook_lateral_tolerance_m
        && g.misalignment_deg <= sc.hook_angle_tolerance_deg
    {
        r.t_hard_docked_s = Some(t);
        if let Some(c) = compliant {
            close_hooks(s, sc, &ports, c);
        }
        let reason = format!(
            "hooks closed: lateral {:.4} m, misalignment {:.3}° (axial {:.4} m)",
            g.lateral_m, g.misalignment_deg, g.axial_error_m
        );
        Some((HardDocked, reason))
    } else {
        None
    };
    (joint_now, change)
}

/// Sets the platform's retraction rate (m/s), if the compliant model has a platform carrying
/// the chaser.
fn set_retraction_rate(compliant: Option<&mut CompliantContact>, rate_m_s: f64) {
    if let Some(p) = compliant.and_then(|c| c.link.platform.as_mut()) {
        p.retraction_rate_m_s = rate_m_s;
    }
}

/// The structural hooks close: a stiff compliant joint (`sc.hooks`) holding the chaser where it
/// is relative to the target.
fn close_hooks(
    s: &MonitorStep,
    sc: &crate::scene::SoftCaptureSpec,
    ports: &(PortFrame, PortFrame),
    c: &mut CompliantContact,
) {
    let ((cs, cb), (ts, tb)) = (s.chaser, s.target);
    let pt: Isometry3<f64> = ts.body_pose(&tb.com_body_m);
    let pc: Isometry3<f64> = cs.body_pose(&cb.com_body_m);
    c.link.latch = Some(LatchSpring {
        spec: sc.hooks.clone(),
        port_c_body_m: ports.0.0,
        caught: pt.inv_mul(&pc),
    });
}

/// A soft-capture platform's peaks (leg stroke and force, interface force and moment) updated
/// with this step's, each with its time `t` (s).
fn record_soft_peaks(
    r: &mut SoftCaptureResults,
    t: f64,
    ls: &super::contact_model::LinkStep,
    ps: &super::contact_model::PlatformStep,
) {
    let peak = |v: f64, p: &mut f64, pt: &mut Option<f64>| {
        if v > *p {
            *p = v;
            *pt = Some(t);
        }
    };
    peak(
        ps.peak_leg_stroke_m,
        &mut r.peak_leg_stroke_m,
        &mut r.peak_leg_stroke_t_s,
    );
    peak(
        ps.peak_leg_force_n,
        &mut r.peak_leg_force_n,
        &mut r.peak_leg_force_t_s,
    );
    peak(
        ls.peak_force_n,
        &mut r.peak_interface_force_n,
        &mut r.peak_interface_force_t_s,
    );
    peak(
        ls.peak_moment_nm,
        &mut r.peak_interface_moment_nm,
        &mut r.peak_interface_moment_t_s,
    );
}

/// The capture latches let go (the interface force `force_n`, N, of the step `ps` above the
/// break force): the ring returns to the chaser's platform, `let_go` says what let go, and the
/// change to FREE names the legs past a stroke limit.
fn capture_latches_let_go(
    let_go: &mut Option<String>,
    s: &MonitorStep,
    sc: &crate::scene::SoftCaptureSpec,
    (force_n, ps): (f64, &super::contact_model::PlatformStep),
    compliant: Option<&mut CompliantContact>,
) -> Change {
    let break_force_n = s.spec.latch.break_force_n;
    if let Some(c) = compliant {
        c.link.platform = None;
        c.enabled = true;
    }
    let legs = legs_past_limits(ps, &sc.platform);
    let reason = format!(
        "capture latches let go: interface force {:.1} N > break force {:.1} N{legs}",
        force_n, break_force_n
    );
    *let_go = Some(format!(
        "{}{legs}",
        let_go_text(
            "the capture latches let go",
            "interface",
            s.t,
            force_n,
            break_force_n,
        )
    ));
    (DockState::Free, reason)
}

/// The legs past a stroke limit at the end of the step `ps` (on their stops, which is what
/// drives the interface force up), leg I as in `dock.legI_stroke_m`: ` (leg 2 at 61.0 mm, past
/// its 60.0 mm extension limit; …)`, or an empty string.
fn legs_past_limits(
    ps: &super::contact_model::PlatformStep,
    platform: &crate::contact::platform::PlatformSpec,
) -> String {
    let (lo, hi) = (platform.stroke_min_m, platform.stroke_max_m);
    let past: Vec<String> = ps
        .end
        .as_ref()
        .map(|e| {
            e.legs
                .iter()
                .enumerate()
                .filter_map(|(i, l)| {
                    let s_mm = l.stroke_m * 1e3;
                    if l.stroke_m > hi {
                        Some(format!(
                            "leg {i} at {s_mm:.1} mm, past its {:.1} mm extension limit",
                            hi * 1e3
                        ))
                    } else if l.stroke_m < lo {
                        Some(format!(
                            "leg {i} at {s_mm:.1} mm, past its {:.1} mm compression limit",
                            lo * 1e3
                        ))
                    } else {
                        None
                    }
                })
                .collect()
        })
        .unwrap_or_default();
    if past.is_empty() {
        String::new()
    } else {
        format!(" ({})", past.join("; "))
    }
}

/// RELEASED: when the separation springs reach the end of their stroke, the chaser port's
/// velocity relative to the target's material point there is kept and is a
/// `separation_complete` event.
fn separation_step(
    dock: &mut Docking,
    s: &MonitorStep,
    compliant: Option<&CompliantContact>,
    log: &mut EventLog,
) {
    let ((cs, cb), (ts, _)) = (s.chaser, s.target);
    let t = s.t;
    if let Some(c) = compliant
        && c.link_step.separation_ended
    {
        let (pc, _) = port_world(cs, &cb.com_body_m, &dock.ports.0);
        let v = point_velocity(cs, &pc) - point_velocity(ts, &pc);
        dock.separation_end = Some((v.into(), t));
        log.push(
            t,
            "separation_complete",
            serde_json::json!({"relative_velocity_m_s": [v.x, v.y, v.z],
                "axial_rate_m_s": v.dot(&s.at)}),
        );
    }
}

/// LATCHED with a compliant latch: the interface loads and their peaks, and the latch breaking
/// above the break force. Returns the interface load on the chaser this step (N, N·m) and the
/// change.
fn compliant_latch_step(
    dock: &mut Docking,
    s: &MonitorStep,
    compliant: Option<&mut CompliantContact>,
) -> ((f64, f64), Option<Change>) {
    let (t, spec) = (s.t, s.spec);
    let ls = compliant
        .as_deref()
        .map(|c| c.link_step)
        .unwrap_or_default();
    let joint_now = (ls.peak_force_n, ls.peak_moment_nm);
    let il = dock.interface.get_or_insert_with(Default::default);
    if ls.peak_force_n > il.peak_force_n {
        il.peak_force_n = ls.peak_force_n;
        il.peak_force_t_s = Some(t);
    }
    if ls.peak_moment_nm > il.peak_moment_nm {
        il.peak_moment_nm = ls.peak_moment_nm;
        il.peak_moment_t_s = Some(t);
    }
    il.last_force_n = ls.force_end_n.into();
    il.last_moment_nm = ls.moment_end_nm.into();
    dock.peak_joint_force_n = dock.peak_joint_force_n.max(ls.peak_force_n);
    dock.loads.peak_joint_force_n = dock.peak_joint_force_n;
    dock.loads.peak_joint_torque_nm = dock.loads.peak_joint_torque_nm.max(ls.peak_moment_nm);
    let mut change = None;
    if ls.peak_force_n > spec.latch.break_force_n {
        if let Some(c) = compliant {
            c.link.latch = None;
            c.enabled = true;
        }
        let reason = format!(
            "latch broke: joint force {:.1} N > break force {:.1} N",
            ls.peak_force_n, spec.latch.break_force_n
        );
        change = Some((DockState::Free, reason));
        dock.let_go = Some(let_go_text(
            "the latch broke",
            "joint",
            t,
            ls.peak_force_n,
            spec.latch.break_force_n,
        ));
    }
    (joint_now, change)
}

/// LATCHED with a rigid latch (a rapier fixed joint): the joint's load on the chaser and its
/// peaks, the impulse of the first latched step, and the joint breaking above the break force.
/// Returns the joint's load on the chaser this step (N, N·m) and the change.
fn rigid_latch_step(
    dock: &mut Docking,
    s: &MonitorStep,
    phys: &mut Physics,
    contacts: &ContactState,
    compliant: Option<&mut CompliantContact>,
) -> ((f64, f64), Option<Change>) {
    let (t, dt, spec) = (s.t, s.dt, s.spec);
    let (cs, cb) = s.chaser;
    let mut joint_now = (0.0, 0.0);
    let mut change = None;
    if let Some(h) = dock.joint
        && let Some(j) = phys.world.impulse_joints.get(h)
    {
        // The joint's load on the chaser: its momentum change less the applied forces
        // (exact for the step rapier took, whatever its solver passes wrote back),
        // when no contact shares it; the moment about the chaser's port. Otherwise
        // rapier's last-pass joint impulses.
        let ci = cb.index;
        let shared = contacts
            .step_pairs
            .iter()
            .any(|p| p.bodies.0 == ci || p.bodies.1 == ci);
        let (f, tq) = match (
            contacts.body_impulse.get(ci),
            contacts.body_angular_impulse.get(ci),
        ) {
            (Some(jl), Some(ja)) if !shared => {
                let (pc, _) = port_world(cs, &cb.com_body_m, &dock.ports.0);
                let m_port = ja - (pc - cs.pos_m).cross(jl);
                (jl.norm() / dt, m_port.norm() / dt)
            }
            _ => (
                Vector3::new(j.impulses[0], j.impulses[1], j.impulses[2])
                    .map(f64::from)
                    .norm()
                    / dt,
                Vector3::new(j.impulses[3], j.impulses[4], j.impulses[5])
                    .map(f64::from)
                    .norm()
                    / dt,
            ),
        };
        if dock.loads.latch_impulse_ns.is_none() {
            dock.loads.latch_impulse_ns = Some(f * dt);
        }
        joint_now = (f, tq);
        dock.peak_joint_force_n = dock.peak_joint_force_n.max(f);
        dock.loads.peak_joint_force_n = dock.peak_joint_force_n;
        dock.loads.peak_joint_torque_nm = dock.loads.peak_joint_torque_nm.max(tq);
        if f > spec.latch.break_force_n {
            phys.world.impulse_joints.remove(h, true);
            dock.joint = None;
            if let Some(c) = compliant {
                c.enabled = true;
            }
            let reason = format!(
                "latch broke: joint force {f:.1} N > break force {:.1} N",
                spec.latch.break_force_n
            );
            change = Some((DockState::Free, reason));
            dock.let_go = Some(let_go_text(
                "the latch broke",
                "joint",
                t,
                f,
                spec.latch.break_force_n,
            ));
        }
    }
    (joint_now, change)
}

/// The approach (FREE, ATTRACTING, CONTACT, SOFT_CAPTURE, JAMMED, REBOUND), the first that
/// applies of: a miss ([`missed`]); the capture latches' one try per visit of the capture zone
/// (soft capture, [`try_capture_latches`]); the seat, the dwell and the latch (cone and slot,
/// [`seat_and_latch`]); contact and jamming ([`in_contact`]); or no contact
/// ([`out_of_contact`]).
fn approach_step(
    dock: &mut Docking,
    s: &MonitorStep,
    seen: &Seen,
    phys: &mut Physics,
    compliant: Option<&mut CompliantContact>,
    log: &mut EventLog,
) -> Option<Change> {
    let old = dock.state;
    let soft = soft_spec(s.spec);
    if let Some(miss) = missed(dock, s, seen) {
        Some(miss)
    } else if let Some(sc) = soft
        && seen.seated
        && !dock.soft.as_ref().is_some_and(|r| r.attempted)
    {
        try_capture_latches(dock, s, sc, compliant, log)
    } else if soft.is_none()
        && seen.seated
        && (seen.docking_contact || old == DockState::SoftCapture)
    {
        seat_and_latch(dock, s, phys, compliant, log)
    } else if seen.docking_contact {
        in_contact(dock, s)
    } else {
        out_of_contact(dock, s)
    }
}

/// A miss on the approach: another part collided, the chaser port passed beside the slot (it
/// crossed the seat plane from the front outside the mouth), or the approach turned away
/// outside the mouth before any contact.
fn missed(dock: &Docking, s: &MonitorStep, seen: &Seen) -> Option<Change> {
    use DockState::*;
    let (g, spec) = (s.g, s.spec);
    let old = dock.state;
    let reason = if let Some(pair) = &seen.collision {
        match dock.let_go.as_deref() {
            Some(why) => format!("collision between {pair} after {why}"),
            None => format!("collision between {pair} before the latch engaged"),
        }
    } else if seen.armed
        && g.axial_error_m < 0.0
        && seen.crossed_from_front
        && g.lateral_m > spec.mouth_radius_m
    {
        format!(
            "the chaser port passed beside the slot: lateral offset {:.3} m > mouth radius {:.3} m",
            g.lateral_m, spec.mouth_radius_m
        )
    } else if seen.armed
        && !seen.docking_contact
        && matches!(old, Free | Attracting)
        && g.axial_rate_m_s > spec.miss.rebound_speed_m_s
        && g.lateral_m > spec.mouth_radius_m
    {
        format!(
            "the approach turned away outside the mouth: lateral offset {:.3} m > {:.3} m, separating at {:.3e} m/s",
            g.lateral_m, spec.mouth_radius_m, g.axial_rate_m_s
        )
    } else {
        return None;
    };
    Some((Missed, reason))
}

/// Soft capture, seated, the capture latches not yet tried in this visit of the capture zone:
/// they try once, and engage (SOFT_CAPTURED, [`engage_platform`]) unless a capture rate limit
/// refuses them (a `capture_refused` event).
fn try_capture_latches(
    dock: &mut Docking,
    s: &MonitorStep,
    sc: &crate::scene::SoftCaptureSpec,
    compliant: Option<&mut CompliantContact>,
    log: &mut EventLog,
) -> Option<Change> {
    let (t, g, spec) = (s.t, s.g, s.spec);
    // The capture latches get one try per visit of the capture zone.
    if let Some(r) = dock.soft.as_mut() {
        r.attempted = true;
    }
    if let Some((payload, why)) = capture_rate_violation(&spec.latch.capture_rates, g) {
        dock.refusals += 1;
        let mut payload = payload;
        payload["reason"] = why.replace("latch refused", "capture refused").into();
        log.push(t, "capture_refused", payload);
        dock.reason = why.replace("latch refused", "capture refused");
        None
    } else {
        dock.latch_rates = Some([
            g.axial_rate_m_s.abs(),
            g.lateral_rate_m_s,
            g.angular_rate_deg_s,
        ]);
        let reason = format!(
            "capture latches engaged: axial {:.4} m, lateral {:.4} m, misalignment {:.2}°, closing at {:.4} m/s",
            g.axial_error_m, g.lateral_m, g.misalignment_deg, -g.axial_rate_m_s
        );
        if let Some(c) = compliant {
            engage_platform(dock, sc, s.chaser, s.target, c);
        }
        if let Some(r) = dock.soft.as_mut() {
            r.t_soft_captured_s = Some(t);
        }
        Some((DockState::SoftCaptured, reason))
    }
}

/// Cone and slot, seated: entering SOFT_CAPTURE, then after the dwell the latch closes
/// (LATCHED, [`engage_latch`]) unless a capture rate limit refuses it (a `capture_refused`
/// event when a refusal starts or the rate it names changes).
fn seat_and_latch(
    dock: &mut Docking,
    s: &MonitorStep,
    phys: &mut Physics,
    compliant: Option<&mut CompliantContact>,
    log: &mut EventLog,
) -> Option<Change> {
    let (t, g, spec) = (s.t, s.g, s.spec);
    if dock.state != DockState::SoftCapture {
        dock.seated_since = Some(t);
        let reason = format!(
            "seated: axial {:.4} m, lateral {:.4} m, misalignment {:.2}°",
            g.axial_error_m, g.lateral_m, g.misalignment_deg
        );
        Some((DockState::SoftCapture, reason))
    } else if t - dock.seated_since.unwrap_or(t) >= spec.latch.dwell_s - 1e-9
        && let Some((payload, why)) = capture_rate_violation(&spec.latch.capture_rates, g)
    {
        let rate = payload["rate"].as_str().unwrap_or_default().to_string();
        if dock.refusing.as_deref() != Some(rate.as_str()) {
            dock.refusals += 1;
            let mut payload = payload;
            payload["reason"] = why.clone().into();
            log.push(t, "capture_refused", payload);
            dock.refusing = Some(rate);
        }
        dock.reason = why;
        None
    } else if t - dock.seated_since.unwrap_or(t) >= spec.latch.dwell_s - 1e-9 {
        dock.refusing = None;
        dock.latch_rates = Some([
            g.axial_rate_m_s.abs(),
            g.lateral_rate_m_s,
            g.angular_rate_deg_s,
        ]);
        let reason = format!(
            "latched after {:.2} s seated (axial {:.4} m, lateral {:.4} m, misalignment {:.2}°)",
            spec.latch.dwell_s, g.axial_error_m, g.lateral_m, g.misalignment_deg
        );
        engage_latch(dock, s.chaser, s.target, phys, compliant);
        dock.t_latch_s = Some(t);
        Some((DockState::Latched, reason))
    } else {
        None
    }
}

/// In docking contact, not seated: CONTACT, and JAMMED after `miss.jam_time_s` slower than
/// `miss.jam_speed_m_s` (back to CONTACT when it moves again).
fn in_contact(dock: &mut Docking, s: &MonitorStep) -> Option<Change> {
    use DockState::*;
    let (t, g, spec) = (s.t, s.g, s.spec);
    let old = dock.state;
    let mut change = None;
    if old != Contact && old != Jammed {
        change = Some((Contact, "cone touches the slot".into()));
        dock.jam_since = None;
    }
    if g.rel_speed_m_s < spec.miss.jam_speed_m_s {
        let since = *dock.jam_since.get_or_insert(t);
        if old != Jammed && t - since >= spec.miss.jam_time_s {
            let reason = format!(
                "in contact, not seated, relative speed < {} m/s for {} s (axial {:.4} m, lateral {:.4} m, misalignment {:.2}°)",
                spec.miss.jam_speed_m_s,
                spec.miss.jam_time_s,
                g.axial_error_m,
                g.lateral_m,
                g.misalignment_deg
            );
            change = Some((Jammed, reason));
        }
    } else {
        dock.jam_since = None;
        if old == Jammed {
            change = Some((Contact, "moving again".into()));
        }
    }
    change
}

/// No docking contact: a contact that ended (REBOUND if the cone left separating faster than
/// `miss.rebound_speed_m_s`), a deflection after an earlier touch (REBOUND), or the magnet
/// switching on (ATTRACTING).
fn out_of_contact(dock: &Docking, s: &MonitorStep) -> Option<Change> {
    use DockState::*;
    let (g, spec) = (s.g, s.spec);
    let old = dock.state;
    if matches!(old, Contact | SoftCapture | Jammed) {
        if g.axial_rate_m_s > spec.miss.rebound_speed_m_s {
            let reason = format!(
                "the cone left the slot separating at {:.3e} m/s",
                g.axial_rate_m_s
            );
            Some((Rebound, reason))
        } else {
            let new = if dock.magnet_on { Attracting } else { Free };
            Some((new, "contact ended".into()))
        }
    } else if matches!(old, Free | Attracting)
        && dock.t_first_contact_s.is_some()
        && g.axial_rate_m_s > spec.miss.rebound_speed_m_s
    {
        let reason = format!(
            "deflected: after touching the slot the cone moves away at {:.3e} m/s",
            g.axial_rate_m_s
        );
        Some((Rebound, reason))
    } else if old == Free && dock.magnet_on {
        Some((Attracting, format!("magnet on at gap {:.3} m", g.gap_m)))
    } else {
        None
    }
}

/// The `dock.*` columns: the port geometry, the magnet force, the state (after this step's
/// change) and the load `joint_now` (N, N·m) of what holds the chaser; then a soft-capture
/// platform's ([`write_soft_columns`]).
fn write_columns(
    dock: &Docking,
    s: &MonitorStep,
    joint_now: (f64, f64),
    compliant: Option<&CompliantContact>,
    diag: &mut Diagnostics,
) {
    let g = s.g;
    let values = [
        g.gap_m,
        g.axial_error_m,
        g.lateral_m,
        g.misalignment_deg,
        dock.magnet_force_n,
        dock.state.code(),
        joint_now.0,
        joint_now.1,
    ];
    for (c, v) in dock.cols.iter().zip(values) {
        diag.values[*c] = v;
    }
    if let (Some(r), Some(sc)) = (dock.soft.as_ref(), soft_spec(s.spec)) {
        write_soft_columns(r, sc, compliant, diag);
    }
}

/// A soft-capture platform's columns: per leg (stroke, force), the ring pose in P, the
/// interface force and moment and the retraction. The platform while it carries the chaser;
/// otherwise the ring at rest on its stops at the neutral pose and no load.
fn write_soft_columns(
    r: &SoftCaptureResults,
    sc: &crate::scene::SoftCaptureSpec,
    compliant: Option<&CompliantContact>,
    diag: &mut Diagnostics,
) {
    let live = compliant.filter(|c| c.link.platform.is_some());
    let ps = live.map(|c| c.platform_step.clone()).unwrap_or_default();
    let n = (r.cols.len() - 13) / 2;
    for i in 0..n {
        let leg = ps.end.as_ref().and_then(|l| l.legs.get(i));
        diag.values[r.cols[2 * i]] = leg.map_or(0.0, |l| l.stroke_m);
        diag.values[r.cols[2 * i + 1]] = leg.map_or(0.0, |l| l.force_n);
    }
    let ring = ps
        .ring_in_base
        .unwrap_or_else(|| Isometry3::translation(0.0, 0.0, sc.platform.height_m));
    let rot = ring.rotation.scaled_axis().map(f64::to_degrees);
    let (f, m) = live.map_or((Vector3::zeros(), Vector3::zeros()), |c| {
        (c.link_step.force_end_n, c.link_step.moment_end_nm)
    });
    let retraction = live
        .and_then(|c| c.link.platform.as_ref())
        .map_or(0.0, |p| p.retraction_m);
    let rest = [
        ring.translation.vector.x,
        ring.translation.vector.y,
        ring.translation.vector.z,
        rot.x,
        rot.y,
        rot.z,
        f.x,
        f.y,
        f.z,
        m.x,
        m.y,
        m.z,
        retraction,
    ];
    for (c, v) in r.cols[2 * n..].iter().zip(rest) {
        diag.values[*c] = v;
    }
}

/// The capture latches engage: the chaser's ring, at the platform's neutral pose, is pressed
/// flat on the target's ring (turned by the smallest rotation that puts its axis on −a_t and
/// moved across onto the target port axis, keeping its axial position and its roll) and held
/// there, fixed in the target's body frame; from then the legs carry the chaser and take up the
/// misalignment the rings met with. The cone–slot contact stops (the ring holds the chaser).
fn engage_platform(
    dock: &Docking,
    sc: &crate::scene::SoftCaptureSpec,
    (cs, cb): (&BodyState, &SimBody),
    (ts, tb): (&BodyState, &SimBody),
    c: &mut CompliantContact,
) {
    let platform =
        crate::contact::platform::Platform::new(&sc.platform).expect("validated platform");
    let port_c_body = port_platform_frame(&dock.ports.0);
    let p_world = cs.body_pose(&cb.com_body_m) * port_c_body;
    let ring_now = p_world * Translation3::new(0.0, 0.0, sc.platform.height_m);
    let target = ts.body_pose(&tb.com_body_m);
    let (pt, at) = port_world(ts, &tb.com_body_m, &dock.ports.1);
    let z_ring = ring_now.rotation * Vector3::z();
    let turn =
        UnitQuaternion::rotation_between(&z_ring, &(-at)).unwrap_or_else(UnitQuaternion::identity);
    let c_ring = ring_now.translation.vector;
    let c_nominal = pt + at * (c_ring - pt).dot(&at);
    let ring_world = Isometry3::from_parts(Translation3::from(c_nominal), turn * ring_now.rotation);
    c.link.chaser_is_b = c.indices.1 == cb.index;
    c.link.platform = Some(super::contact_model::PlatformLink {
        platform,
        port_c_body,
        ring_in_target: target.inv_mul(&ring_world),
        retraction_m: 0.0,
        retraction_rate_m_s: 0.0,
        retraction_max_m: sc.retracted_stroke_m,
    });
    disable_contact(c);
}

/// Closes the latch where the chaser is: a rapier fixed joint, or the compliant latch's spring.
/// The latched pair is one structure: no more docking contact (the joint carries the loads,
/// reported as joint loads).
fn engage_latch(
    dock: &mut Docking,
    (cs, cb): (&BodyState, &SimBody),
    (ts, tb): (&BodyState, &SimBody),
    phys: &mut Physics,
    compliant: Option<&mut CompliantContact>,
) {
    match (&dock.spec.latch.joint, compliant) {
        (LatchJoint::Compliant(j), Some(c)) => {
            let pt: Isometry3<f64> = ts.body_pose(&tb.com_body_m);
            let pc: Isometry3<f64> = cs.body_pose(&cb.com_body_m);
            c.link.chaser_is_b = c.indices.1 == cb.index;
            c.link.latch = Some(LatchSpring {
                spec: j.clone(),
                port_c_body_m: dock.ports.0.0,
                caught: pt.inv_mul(&pc),
            });
            dock.interface = Some(InterfaceLoads::default());
            disable_contact(c);
        }
        (_, c) => {
            let joint = latch_joint(cs, cb, ts, tb);
            let h = phys.world.insert_impulse_joint(tb.handle, cb.handle, joint);
            dock.joint = Some(h);
            if let Some(c) = c {
                disable_contact(c);
            }
        }
    }
}

fn disable_contact(c: &mut CompliantContact) {
    c.enabled = false;
    for p in &mut c.pairs {
        p.in_contact = false;
    }
}

/// A fixed joint holding the chaser where it is relative to the target: frame 1 is the target's
/// body frame, frame 2 the same frame expressed in the chaser's body frame.
fn latch_joint(cs: &BodyState, cb: &SimBody, ts: &BodyState, tb: &SimBody) -> rp::FixedJoint {
    let pt: Isometry3<f64> = ts.body_pose(&tb.com_body_m);
    let pc: Isometry3<f64> = cs.body_pose(&cb.com_body_m);
    let frame1 = Isometry3::from_parts(Translation3::identity(), UnitQuaternion::identity());
    let frame2 = pc.inv_mul(&pt);
    let mut j = rp::FixedJointBuilder::new()
        .local_frame1(conv::pose(&frame1))
        .local_frame2(conv::pose(&frame2))
        .build();
    // Contacts between the latched bodies would be internal forces of one structure.
    j.data.set_contacts_enabled(false);
    j
}

/// The docking section of `summary.json`.
pub fn summary(dock: &Docking) -> serde_json::Value {
    let mut v = serde_json::json!({
        "state": dock.state.name(),
        "reason": dock.reason,
        "first_docking_contact_s": dock.t_first_contact_s,
        "t_latch_s": dock.t_latch_s,
        "max_misalignment_in_contact_deg": dock.max_misalignment_deg,
        "peak_latch_force_n": dock.peak_joint_force_n,
        "capture_rate_limits": dock.spec.latch.capture_rates,
        "capture_rates_at_latch": dock.latch_rates.map(|[a, l, w]| serde_json::json!({
            "axial_rate_m_s": a, "lateral_rate_m_s": l, "angular_rate_deg_s": w,
        })),
        "capture_refusals": dock.refusals,
        "final_geometry": dock.geometry,
        "contact": dock.loads,
    });
    if let Some(r) = &dock.soft {
        v["soft_capture"] = serde_json::to_value(r).unwrap_or_default();
    }
    // A compliant latch's loads at the interface (a rigid latch's are `peak_latch_force_n`
    // and `contact.peak_joint_*`).
    if let Some(il) = &dock.interface {
        v["interface_loads"] = serde_json::to_value(il).unwrap_or_default();
    }
    if let Some(tr) = dock.t_release_s {
        v["t_release_s"] = tr.into();
        v["separation_end"] = dock
            .separation_end
            .map(|(vel, te)| serde_json::json!({"t_s": te, "relative_velocity_m_s": vel}))
            .unwrap_or_default();
    }
    v
}

#[cfg(test)]
mod tests {
    //! The state list against itself: the codes are 0, 1, … in the order of
    //! [`DockState::ALL`] (the `dock.state` column and the plot labels rely on it), names are
    //! unique and are the serde names, and the code and name lookups invert `code` and `name`.
    use super::*;

    #[test]
    fn every_state_has_a_distinct_code_and_name_in_order() {
        for (i, s) in DockState::ALL.iter().enumerate() {
            assert_eq!(s.code(), i as f64, "{s:?}");
            assert_eq!(DockState::from_code(s.code()), Some(*s));
            assert_eq!(DockState::from_name(s.name()), Some(*s));
            assert_eq!(
                serde_json::to_value(s).expect("a unit variant serialises"),
                serde_json::json!(s.name())
            );
        }
        let mut names: Vec<&str> = DockState::ALL.iter().map(|s| s.name()).collect();
        names.sort_unstable();
        names.dedup();
        assert_eq!(names.len(), DockState::ALL.len());
        assert_eq!(DockState::from_code(DockState::ALL.len() as f64), None);
        assert_eq!(DockState::from_code(0.5), None);
        assert_eq!(DockState::from_name("LATCHD"), None);
    }

    #[test]
    fn docked_end_state_per_mechanism() {
        assert_eq!(
            DockState::docked_end_state(&crate::scene::Mechanism::ConeSlot),
            DockState::Latched
        );
        let sc = crate::scene::load_scene_file(
            std::path::Path::new(concat!(
                env!("CARGO_MANIFEST_DIR"),
                "/scenes/examples/soft_capture.ron"
            )),
            &[],
        )
        .expect("the bundled soft-capture scene loads");
        let m = &sc
            .scene
            .docking
            .as_ref()
            .expect("a docking mechanism")
            .mechanism;
        assert_eq!(DockState::docked_end_state(m), DockState::HardDocked);
        assert!(DockState::HardDocked.docked() && DockState::Latched.docked());
    }
}
