//! The controller interface: an [`Observation`] in, a [`Command`] out, at the controller's own
//! period (zero-order hold in between). Bevy-free.
//!
//! One generic host in the Bevy layer (`sim::controllers`) runs every controller the same way —
//! a paper law, a generic law (`control::generic`), a user's Rust law or a Python callable:
//!
//! 1. **Sense** — the host builds the observation from the f64 truth of every body (and, where
//!    the controller's slot configures a [`crate::control::sensor::SensorSpec`], the
//!    *measured* state: rate, noise, latency, seed).
//! 2. **Control** — at t = 0 and every `period` after, [`Controller::command`] is called; the
//!    command it returns is held until the next call.
//! 3. **Actuate** — every step the held command is turned into the world frame with the
//!    frames of *that* step (a body-frame force turns with the body, a Hill-frame force with the
//!    orbit) and passed through the slot's actuator ([`crate::actuation::ActuatorSpec`]:
//!    ideal, per-axis saturation, or on/off thrusters with PWPF).
//!
//! # Frames (all f64)
//! - **world** — the scene's world frame (orbit: ECI axes, origin on the reference orbit;
//!   air-bearing: the lab frame; L2: the rotating frame's axes at t = 0, origin on the centre);
//! - **body** — a spacecraft's own frame (parts, ports, inertia are given in it);
//! - **hill** — the *target's* local orbital frame (x radial out, y along-track, z orbit normal),
//!   built from the target's own ECI state; without a target, the reference orbit's;
//! - **target body** — the target's body frame;
//! - **port** — a docking port's frame: origin at the port, x along its outward axis, y and z
//!   completed from the body axes ([`port_axes`]).
//!
//! Velocities relative to a rotating frame are the derivatives seen in that frame
//! (ρ̇_L = C (ρ̇ − ω × ρ)); angular velocities are inertial.

use crate::environment::EnvObs;
use crate::scene::BodyRole;
use nalgebra::{Matrix3, Rotation3, UnitQuaternion, Vector3};
use std::any::Any;

/// What does not change over a run: a body's name, role and mass properties.
#[derive(Debug, Clone)]
pub struct BodyInfo {
    /// Index in scene order.
    pub index: usize,
    /// Name.
    pub name: String,
    /// Role.
    pub role: BodyRole,
    /// Mass, kg.
    pub mass_kg: f64,
    /// Inertia about the centre of mass, body axes, kg·m².
    pub inertia_kg_m2: Matrix3<f64>,
    /// Centre of mass in the body frame, m.
    pub com_body_m: Vector3<f64>,
    /// Ports: (name, origin in the body frame (m), unit outward axis in the body frame).
    pub ports: Vec<(String, Vector3<f64>, Vector3<f64>)>,
}

impl BodyInfo {
    /// A port by name: (origin, unit axis), body frame.
    pub fn port(&self, name: &str) -> Option<(Vector3<f64>, Vector3<f64>)> {
        self.ports.iter().find(|p| p.0 == name).map(|p| (p.1, p.2))
    }
}

/// One body's state at one instant (f64 truth).
#[derive(Debug, Clone, Copy)]
pub struct BodyObs {
    /// Centre-of-mass position, world frame, m.
    pub pos_m: Vector3<f64>,
    /// Centre-of-mass velocity, world frame, m/s.
    pub vel_m_s: Vector3<f64>,
    /// Attitude, body → world.
    pub att: UnitQuaternion<f64>,
    /// Angular velocity, world frame, rad/s.
    pub omega_rad_s: Vector3<f64>,
    /// Angular velocity in body axes (att⁻¹ ω), rad/s.
    pub rate_body_rad_s: Vector3<f64>,
    /// The scene's gravity field at the centre of mass, world frame, m/s² (zero without one;
    /// in orbit the *differential* gravity about the reference orbit).
    pub gravity_m_s2: Vector3<f64>,
}

impl BodyObs {
    /// The truth of a body from its world-frame state.
    pub fn new(
        pos_m: Vector3<f64>,
        vel_m_s: Vector3<f64>,
        att: UnitQuaternion<f64>,
        omega_rad_s: Vector3<f64>,
        gravity_m_s2: Vector3<f64>,
    ) -> Self {
        Self {
            pos_m,
            vel_m_s,
            att,
            omega_rad_s,
            rate_body_rad_s: att.inverse() * omega_rad_s,
            gravity_m_s2,
        }
    }
    /// World position of a point given in the body frame (`com_body_m`: the centre of mass in
    /// the body frame).
    pub fn point_world_m(
        &self,
        com_body_m: &Vector3<f64>,
        p_body_m: &Vector3<f64>,
    ) -> Vector3<f64> {
        self.pos_m + self.att * (p_body_m - com_body_m)
    }
    /// Velocity of the material point at world position `p_world_m`, m/s.
    pub fn point_velocity_m_s(&self, p_world_m: &Vector3<f64>) -> Vector3<f64> {
        self.vel_m_s + self.omega_rad_s.cross(&(p_world_m - self.pos_m))
    }
}

/// A relative state: position and velocity of one point relative to another, in a named frame
/// (the velocity is the derivative seen in that frame).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RelState {
    /// Position, m.
    pub pos_m: Vector3<f64>,
    /// Velocity seen in the frame, m/s.
    pub vel_m_s: Vector3<f64>,
}

/// The controlled body relative to its target (centres of mass).
#[derive(Debug, Clone, Copy)]
pub struct RelativeObs {
    /// Chaser − target, world axes, inertial derivative.
    pub world: RelState,
    /// In the target's Hill frame (orbit scenes only).
    pub hill: Option<RelState>,
    /// Hill frame → world DCM (columns: Hill axes in world components), orbit scenes only.
    pub dcm_world_from_hill: Option<Matrix3<f64>>,
    /// Angular velocity of the Hill frame, world components, rad/s (orbit scenes only).
    pub hill_rate_world_rad_s: Option<Vector3<f64>>,
    /// In the target's body frame.
    pub target_body: RelState,
}

/// A docking port's pose at one instant.
#[derive(Debug, Clone, Copy)]
pub struct PortPose {
    /// Port origin, world frame, m.
    pub pos_m: Vector3<f64>,
    /// Port frame → world (x = the outward axis; see [`port_axes`]).
    pub att: UnitQuaternion<f64>,
    /// Velocity of the material point at the port origin, world frame, m/s.
    pub vel_m_s: Vector3<f64>,
}

impl PortPose {
    /// Unit outward axis, world frame.
    pub fn axis(&self) -> Vector3<f64> {
        self.att * Vector3::x()
    }
}

/// Both docking ports and the chaser port relative to the target port.
#[derive(Debug, Clone, Copy)]
pub struct PortsObs {
    /// The controlled body's port.
    pub chaser: PortPose,
    /// The target's port.
    pub target: PortPose,
    /// Chaser port origin relative to the target port, in the target port frame (x along the
    /// target port's outward axis: the approach distance), with the velocity seen in that
    /// frame, m and m/s.
    pub rel_port: RelState,
    /// Chaser port frame → target port frame.
    pub rel_att: UnitQuaternion<f64>,
    /// Angle between the chaser port axis and the reversed target port axis (0 = facing), rad.
    pub misalignment_rad: f64,
}

/// The frame a measurement is expressed in.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize, Default)]
pub enum MeasuredFrame {
    /// The body's own pose in the world frame (absolute: e.g. a lab's vision system).
    #[default]
    World,
    /// The body relative to its target, in the target's Hill frame.
    Hill,
    /// The body relative to its target, in the target's body frame.
    TargetBody,
    /// The chaser port relative to the target port, in the target port frame.
    Port,
}

/// What a sensor delivered: the latest measurement, in the frame the sensor is set to.
#[derive(Debug, Clone, Copy)]
pub struct Measurement {
    /// Exposure time, s.
    pub t_s: f64,
    /// Time it reached the controller (exposure + latency), s.
    pub delivered_s: f64,
    /// Delivered this step (the first step a controller can see it).
    pub fresh: bool,
    /// Frame of the numbers.
    pub frame: MeasuredFrame,
    /// Measured position, m (planar sensors: z is the truth, not measured).
    pub pos_m: Vector3<f64>,
    /// Measured or differenced velocity, m/s (planar: z = 0).
    pub vel_m_s: Vector3<f64>,
    /// Measured attitude, body (or port) frame → measurement frame (planar: a rotation about z
    /// by `yaw_rad`).
    pub att: UnitQuaternion<f64>,
    /// Measured or differenced angular velocity, measurement-frame axes, rad/s (planar: about
    /// z only).
    pub omega_rad_s: Vector3<f64>,
    /// Planar sensors: the measured yaw about the frame's z axis, rad.
    pub yaw_rad: Option<f64>,
}

/// The docking mechanism's state, when the scene has one.
#[derive(Debug, Clone, Copy)]
pub struct DockingObs {
    /// The state machine's state, e.g. `FREE`, `ATTRACTING`, `LATCHED`.
    pub state: &'static str,
    /// The electromagnet is on.
    pub magnet_on: bool,
    /// |chaser port − seat point|, m.
    pub gap_m: f64,
    /// Axial error (positive: not yet in), m.
    pub axial_error_m: f64,
    /// Lateral offset from the target port axis, m.
    pub lateral_m: f64,
    /// Misalignment, deg.
    pub misalignment_deg: f64,
}

/// A guarantee's margin as last evaluated (the monitor runs after the physics, so at the start
/// of a step this is the previous step's end).
#[derive(Debug, Clone)]
pub struct GuaranteeObs {
    /// Name.
    pub name: String,
    /// Unit of the margin.
    pub unit: String,
    /// Margin (≥ 0: holding).
    pub margin: f64,
}

/// Everything a controller may read at one instant. Built by the host; all f64.
#[derive(Debug, Clone, Copy)]
pub struct Observation<'a> {
    /// Simulated time, s.
    pub t_s: f64,
    /// Completed steps.
    pub step: u64,
    /// Scene step, s.
    pub dt_s: f64,
    /// The controlled body (index in scene order).
    pub body: usize,
    /// The target named in the controller's slot, if any.
    pub target: Option<usize>,
    /// Names, roles and mass properties of every body, scene order.
    pub info: &'a [BodyInfo],
    /// Every body's truth, scene order.
    pub bodies: &'a [BodyObs],
    /// The environment.
    pub env: &'a EnvObs,
    /// The controlled body relative to the target (when the slot names one).
    pub relative: Option<&'a RelativeObs>,
    /// Both docking ports (when the slot names them, or the scene's docking mechanism joins the
    /// controlled body and its target).
    pub ports: Option<&'a PortsObs>,
    /// The slot's sensor output (None without a sensor or before the first delivery).
    pub measured: Option<&'a Measurement>,
    /// The docking mechanism.
    pub docking: Option<DockingObs>,
    /// Every guarantee's margin at the end of the previous step.
    pub guarantees: &'a [GuaranteeObs],
}

impl Observation<'_> {
    /// The controlled body's truth.
    pub fn own(&self) -> &BodyObs {
        &self.bodies[self.body]
    }
    /// The controlled body's constants.
    pub fn own_info(&self) -> &BodyInfo {
        &self.info[self.body]
    }
    /// The target's truth.
    pub fn target_state(&self) -> Option<&BodyObs> {
        self.target.map(|t| &self.bodies[t])
    }
    /// Index of a body by name.
    pub fn body_index(&self, name: &str) -> Option<usize> {
        self.info.iter().position(|b| b.name == name)
    }
    /// A guarantee's last margin by name.
    pub fn guarantee_margin(&self, name: &str) -> Option<f64> {
        self.guarantees
            .iter()
            .find(|g| g.name == name)
            .map(|g| g.margin)
    }
}

/// The frame a command vector is written in. The host rotates a held command into the world
/// frame every step with that step's attitude of the frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
pub enum Frame {
    /// The world frame.
    #[default]
    World,
    /// The controlled body's frame (body-fixed thrusters).
    Body,
    /// The target's Hill frame (the reference orbit's without a target); orbit scenes only.
    Hill,
    /// The target's body frame.
    TargetBody,
}

/// A command: a force through the centre of mass and a torque, each in a stated frame, or a
/// set of thruster valves (for an actuator with thrusters).
#[derive(Debug, Clone, PartialEq)]
pub struct Command {
    /// Force through the centre of mass, N.
    pub force_n: Vector3<f64>,
    /// Frame of `force_n`.
    pub force_frame: Frame,
    /// Torque about the centre of mass, N·m.
    pub torque_nm: Vector3<f64>,
    /// Frame of `torque_nm`.
    pub torque_frame: Frame,
    /// Valve states, in the actuator's nozzle order (only for thruster actuators; then force
    /// and torque are ignored).
    pub valves: Option<Vec<bool>>,
}

impl Default for Command {
    fn default() -> Self {
        Self::zero()
    }
}

impl Command {
    /// No force, no torque (world frame).
    pub fn zero() -> Self {
        Self {
            force_n: Vector3::zeros(),
            force_frame: Frame::World,
            torque_nm: Vector3::zeros(),
            torque_frame: Frame::World,
            valves: None,
        }
    }
    /// A force and a torque in one frame.
    pub fn in_frame(frame: Frame, force_n: Vector3<f64>, torque_nm: Vector3<f64>) -> Self {
        Self {
            force_n,
            force_frame: frame,
            torque_nm,
            torque_frame: frame,
            valves: None,
        }
    }
    /// Whether every number is finite.
    pub fn is_finite(&self) -> bool {
        self.force_n
            .iter()
            .chain(self.torque_nm.iter())
            .all(|x| x.is_finite())
    }
}

/// What the actuator did with the held command this step.
#[derive(Debug, Clone, Default)]
pub struct ActuationReport {
    /// Force applied, world frame, N.
    pub force_world_n: Vector3<f64>,
    /// Torque applied, world frame, N·m.
    pub torque_world_nm: Vector3<f64>,
    /// Valve states this step (thruster actuators).
    pub valves: Option<Vec<bool>>,
    /// Each jet's mean thrust over this step, N (`Rcs` actuators; jet order).
    pub jet_thrust_n: Option<Vec<f64>>,
    /// Propellant used so far, kg (thruster actuators).
    pub propellant_used_kg: f64,
    /// Velocity increment commanded so far, ∫|F|/m dt, m/s.
    pub delta_v_m_s: f64,
    /// The actuator limited the command this step.
    pub saturated: bool,
}

/// When the host asks a controller for its diagnostic columns.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum DiagnosticsAt {
    /// Before the first step, for the t = 0 row (observation of the initial state; no command
    /// has been computed yet).
    Start,
    /// After this step's actuation (observation at the start of the step).
    Actuated,
    /// After the physics (observation at the end of the step: the time of the trajectory
    /// row written at this step).
    PostStep,
}

/// An event a controller raises (written to `events.jsonl` with the time it was raised).
#[derive(Debug, Clone)]
pub struct ControllerEvent {
    /// Kind, e.g. `xu2019_release` or `phase`.
    pub kind: String,
    /// Details (a JSON object).
    pub data: serde_json::Value,
}

/// Lets the host hand back a controller as its concrete type (tests, reports).
pub trait AsAny: Any {
    /// `self` as `&dyn Any`.
    fn as_any(&self) -> &dyn Any;
    /// `self` as `&mut dyn Any`.
    fn as_any_mut(&mut self) -> &mut dyn Any;
}

impl<T: Any> AsAny for T {
    fn as_any(&self) -> &dyn Any {
        self
    }
    fn as_any_mut(&mut self) -> &mut dyn Any {
        self
    }
}

/// What a law reads beyond every body's truth, the environment, the docking state, the
/// guarantees and its sensor: the host computes only what some law needs (a speed hint; the
/// default, [`Needs::ALL`], is always correct).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Needs {
    /// [`Observation::relative`] (the Hill and target-body relative states).
    pub relative: bool,
    /// [`Observation::ports`].
    pub ports: bool,
    /// [`BodyObs::gravity_m_s2`] (zero when not needed).
    pub gravity: bool,
}

impl Needs {
    /// Everything.
    pub const ALL: Needs = Needs {
        relative: true,
        ports: true,
        gravity: true,
    };
    /// Nothing beyond the always-present fields.
    pub const NONE: Needs = Needs {
        relative: false,
        ports: false,
        gravity: false,
    };
    /// Either's needs.
    pub fn union(self, o: Needs) -> Needs {
        Needs {
            relative: self.relative || o.relative,
            ports: self.ports || o.ports,
            gravity: self.gravity || o.gravity,
        }
    }
}

/// A control law. Only [`Controller::command`] is required.
///
/// ```
/// use rpod::control::interface::{Command, Controller, Frame, Observation};
/// use nalgebra::Vector3;
///
/// /// Hill-frame PD toward the target: F = −m (kp ρ + kd ρ̇).
/// struct MyPd { kp_per_s2: f64, kd_per_s: f64 }
///
/// impl Controller for MyPd {
///     fn command(&mut self, obs: &Observation) -> Command {
///         let Some(rel) = obs.relative.and_then(|r| r.hill) else { return Command::zero() };
///         let m = obs.own_info().mass_kg;
///         let f = -(rel.pos_m * self.kp_per_s2 + rel.vel_m_s * self.kd_per_s) * m;
///         Command::in_frame(Frame::Hill, f, Vector3::zeros())
///     }
/// }
/// ```
pub trait Controller: AsAny + Send + Sync {
    /// The command to hold until the next call (called at t = 0 and every period after).
    fn command(&mut self, obs: &Observation) -> Command;

    /// Diagnostic columns, full names with units (e.g. `my_pd.err_x_m`), fixed for the run.
    fn columns(&self) -> Vec<String> {
        Vec::new()
    }

    /// The points of a step at which [`Controller::diagnostics`] is called.
    fn diagnostics_at(&self) -> &'static [DiagnosticsAt] {
        &[DiagnosticsAt::Actuated]
    }

    /// Writes the diagnostic columns (same order as [`Controller::columns`]) at `at`. Values
    /// not written keep their previous value (NaN before the first write).
    fn diagnostics(
        &mut self,
        _at: DiagnosticsAt,
        _obs: &Observation,
        _act: &ActuationReport,
        _out: &mut [f64],
    ) {
    }

    /// Guarantees this law registers with the monitor (called once, when it is installed).
    fn guarantees(&mut self) -> Vec<Box<dyn crate::guarantee::Guarantee>> {
        Vec::new()
    }

    /// Events raised since the last call (drained after every [`Controller::command`]).
    fn take_events(&mut self) -> Vec<ControllerEvent> {
        Vec::new()
    }

    /// What the law reads (see [`Needs`]; default: everything).
    fn needs(&self) -> Needs {
        Needs::ALL
    }

    /// The tracking error of a translation law at its last call: (|position error| m,
    /// |velocity error| m/s). A sequencer's `Settled` condition reads it; `None` (the default)
    /// for laws without a reference to track.
    fn tracking_error(&self) -> Option<(f64, f64)> {
        None
    }
}

/// The axes of a port frame in its body frame: x = the outward axis `axis`; y = the body axis
/// least parallel to it, made orthogonal (ties broken in x, y, z order); z = x × y. Returns the
/// rotation port → body.
pub fn port_axes(axis: &Vector3<f64>) -> UnitQuaternion<f64> {
    let x = axis.normalize();
    let candidates = [Vector3::x(), Vector3::y(), Vector3::z()];
    let mut best = candidates[0];
    let mut best_dot = f64::INFINITY;
    for c in candidates {
        let d = x.dot(&c).abs();
        if d < best_dot - 1e-12 {
            best = c;
            best_dot = d;
        }
    }
    let y = (best - x * x.dot(&best)).normalize();
    let z = x.cross(&y);
    UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(Matrix3::from_columns(
        &[x, y, z],
    )))
}

/// The pose of a body's port at one instant.
pub fn port_pose(
    info: &BodyInfo,
    state: &BodyObs,
    origin_body_m: &Vector3<f64>,
    axis_body: &Vector3<f64>,
) -> PortPose {
    let pos = state.point_world_m(&info.com_body_m, origin_body_m);
    PortPose {
        pos_m: pos,
        att: state.att * port_axes(axis_body),
        vel_m_s: state.point_velocity_m_s(&pos),
    }
}

/// Both ports and the chaser port relative to the target port (see [`PortsObs`]).
pub fn ports_obs(chaser: PortPose, target: PortPose, target_state: &BodyObs) -> PortsObs {
    let inv = target.att.inverse();
    let d = chaser.pos_m - target.pos_m;
    // Velocity seen in the target port frame: the frame turns with the target body.
    let v = chaser.vel_m_s - target_state.point_velocity_m_s(&chaser.pos_m);
    let cos = chaser.axis().dot(&(-target.axis())).clamp(-1.0, 1.0);
    PortsObs {
        chaser,
        target,
        rel_port: RelState {
            pos_m: inv * d,
            vel_m_s: inv * v,
        },
        rel_att: inv * chaser.att,
        misalignment_rad: cos.acos(),
    }
}

/// The relative state of `chaser` with respect to `target` in every frame the observation
/// carries. `reference` is the reference orbit's ECI state in orbit scenes.
pub fn relative_obs(
    chaser: &BodyObs,
    target: &BodyObs,
    reference: Option<(Vector3<f64>, Vector3<f64>)>,
) -> RelativeObs {
    let dp = chaser.pos_m - target.pos_m;
    let dv = chaser.vel_m_s - target.vel_m_s;
    let (hill, dcm, rate) = match reference {
        Some((r, v)) => {
            let frame = crate::orbit::lvlh::LocalFrame::new(
                crate::orbit::lvlh::LocalFrameKind::Hill,
                &(r + target.pos_m),
                &(v + target.vel_m_s),
            );
            let (p, q) = frame.to_local(&dp, &dv);
            (
                Some(RelState {
                    pos_m: p,
                    vel_m_s: q,
                }),
                Some(frame.dcm_frame_from_eci.transpose()),
                Some(frame.omega_eci_rad_s),
            )
        }
        None => (None, None, None),
    };
    let inv = target.att.inverse();
    RelativeObs {
        world: RelState {
            pos_m: dp,
            vel_m_s: dv,
        },
        hill,
        dcm_world_from_hill: dcm,
        hill_rate_world_rad_s: rate,
        target_body: RelState {
            pos_m: inv * dp,
            vel_m_s: inv * (dv - target.omega_rad_s.cross(&dp)),
        },
    }
}

#[cfg(test)]
mod tests {
    //! References: orthonormal right-handed port axes; the rotating-frame derivative checked
    //! by central finite differences of the frame components along an inertial straight line.
    use super::*;

    #[test]
    fn invariant_port_axes_orthonormal() {
        for a in [
            Vector3::x(),
            -Vector3::y(),
            Vector3::new(1.0, 1.0, 0.0),
            Vector3::new(0.3, -0.2, 0.9),
        ] {
            let q = port_axes(&a);
            let m = q.to_rotation_matrix().into_inner();
            assert!((m.column(0) - a.normalize()).norm() < 1e-12);
            assert!((m.transpose() * m - Matrix3::identity()).norm() < 1e-12);
            assert!((m.determinant() - 1.0).abs() < 1e-12);
        }
    }

    #[test]
    fn val_relative_target_body_rate_by_finite_difference() {
        // Target spinning at ω about a tilted axis; chaser on an inertial straight line.
        let w = Vector3::new(0.01, -0.02, 0.03);
        let q0 = UnitQuaternion::from_euler_angles(0.1, 0.2, 0.3);
        let at = |t: f64| {
            let att = UnitQuaternion::from_scaled_axis(w * t) * q0;
            let tgt = BodyObs::new(Vector3::zeros(), Vector3::zeros(), att, w, Vector3::zeros());
            let ch = BodyObs::new(
                Vector3::new(5.0, 1.0, -2.0) + Vector3::new(0.1, 0.2, -0.05) * t,
                Vector3::new(0.1, 0.2, -0.05),
                UnitQuaternion::identity(),
                Vector3::zeros(),
                Vector3::zeros(),
            );
            relative_obs(&ch, &tgt, None)
        };
        let h = 1e-3;
        let fd = (at(1.0 + h).target_body.pos_m - at(1.0 - h).target_body.pos_m) / (2.0 * h);
        assert!((fd - at(1.0).target_body.vel_m_s).norm() < 1e-8);
    }
}
