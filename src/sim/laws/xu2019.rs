//! Simulation wiring of [`crate::control::xu2019`] (Xu, Wen, Wei 2019) on the air-bearing
//! table ([`crate::sim::airbearing`]).
//!
//! Per step, for every `Xu2019` controller of the scene:
//! - **Sense** ([`xu2019_sense`]): at t = k·`period_s` the vision system takes the chaser's
//!   true pose (x, y, θ = yaw about lab z), adds seeded Gaussian noise, and delivers it
//!   `latency_s` later. The velocity is the backward difference of successive delivered poses
//!   (first-order low-pass with `velocity_filter_s`), or, with `velocity: Ideal`, measured
//!   exactly. The controller never reads the truth otherwise.
//! - **Control** ([`xu2019_control`]): when a measurement is delivered, eq (16) is evaluated
//!   and the command held until the next one (zero before the first).
//! - **Actuate** ([`xu2019_actuate`]): `Ideal` adds the lab-frame command to the chaser's
//!   wrench; `Thrusters` steps the three PWPF channels every simulation step with the body-frame
//!   command (rotated by the *measured* θ, as the on-board computer does), opens the valves
//!   of Fig. 10, and applies the body-fixed nozzle forces (each F·(1 + σ·N(0,1)) with thrust
//!   noise) rotated by the *true* attitude. Gas used = Σ F_i·dt / (I_sp·g₀).
//!
//! Two guarantees are registered: `xu2019_obstacle_radial` (exact radial distance of the chaser
//! centre of mass to the superquadric, m) and `xu2019_heart_radial` (radial distance to the
//! heart keep-out, m) — positive means outside. The monitor's full-geometry distances (chaser
//! vs the obstacle prism and the target simulator) say what the real bodies did.
//!
//! Diagnostics columns (prefix `xu2019.`): see [`COLUMNS`].

use crate::actuation::thrusters::{G0_M_S2, ThrusterParams, ThrusterPwpf};
use crate::control::xu2015::GaussianNoise;
use crate::control::xu2019::{
    ActuationSpec, SceneSpec, VelocitySource, Xu2019Command, Xu2019Controller, Xu2019Observation,
};
use crate::geometry::heart::HeartParams;
use crate::geometry::superquadric::{RadialForm, SuperquadricParams};
use crate::guarantee::{Guarantee, MonitorView};
use crate::scene::{LoadedScene, SceneError};
use crate::sim::output::Diagnostics;
use crate::sim::{BodyState, Clock, Guarantees, Roster, SimStep, Stage, Wrench};
use bevy::prelude::*;
use nalgebra::{Vector2, Vector3};
use std::collections::VecDeque;

/// Diagnostics columns (prefix `xu2019.`): the delivered measurement, the command (lab frame),
/// the radial distances of the true centre of mass (the law's obstacle form, the exact one,
/// the heart), the wrench applied (lab frame), the valve states (bit i = nozzle i in
/// [`crate::actuation::thrusters::NOZZLE_NAMES`] order), the open nozzle count and the gas used.
pub const COLUMNS: [&str; 17] = [
    "meas_x_m",
    "meas_y_m",
    "meas_theta_deg",
    "cmd_fx_n",
    "cmd_fy_n",
    "cmd_torque_nm",
    "radial_obstacle_m",
    "radial_obstacle_exact_m",
    "radial_heart_m",
    "applied_fx_n",
    "applied_fy_n",
    "applied_torque_nm",
    "valves",
    "open_nozzles",
    "gas_used_kg",
    "potential_j",
    "theta_deg",
];

/// One pose measurement.
#[derive(Debug, Clone, Copy)]
pub struct VisionSample {
    /// Exposure time, s.
    pub t_s: f64,
    /// Delivery time, s.
    pub deliver_s: f64,
    /// Measured position, lab frame, m.
    pub pos_m: Vector2<f64>,
    /// Measured attitude, rad.
    pub theta_rad: f64,
    /// True velocity at exposure (used only with `VelocitySource::Ideal`), m/s.
    pub vel_m_s: Vector2<f64>,
    /// True yaw rate at exposure (only with `VelocitySource::Ideal`), rad/s.
    pub omega_rad_s: f64,
}

/// One installed controller.
#[derive(Debug, Clone)]
pub struct Xu2019Instance {
    /// The law.
    pub law: Xu2019Controller,
    /// The scene's request.
    pub spec: SceneSpec,
    /// Chaser body index.
    pub chaser: usize,
    /// Measurements taken, not yet delivered.
    pub in_flight: VecDeque<VisionSample>,
    /// Index of the next exposure (at `k · period_s`).
    pub next_exposure: u64,
    /// Last delivered measurement.
    pub last: Option<VisionSample>,
    /// Filtered velocity estimate (ẋ, ẏ, θ̇).
    pub vel_est: Vector3<f64>,
    /// An observation delivered this step, not yet used.
    pub fresh: Option<Xu2019Observation>,
    /// Last observation the law used.
    pub observation: Option<Xu2019Observation>,
    /// Held command.
    pub command: Xu2019Command,
    /// PWPF channels (thrusters only).
    pub pwpf: Option<ThrusterPwpf>,
    /// Valve states this step.
    pub valves: [bool; 8],
    /// Cumulative valve-open time per nozzle, s.
    pub valve_open_s: [f64; 8],
    /// Valve openings (off → on transitions) per nozzle.
    pub valve_openings: [u64; 8],
    /// Gas used so far, kg.
    pub gas_used_kg: f64,
    /// Wrench applied this step, lab frame: (Fx N, Fy N, T N·m).
    pub applied: Vector3<f64>,
    /// Vision noise generator.
    pub vision_noise: GaussianNoise,
    /// Thrust noise generator.
    pub thrust_noise: GaussianNoise,
    /// When the law handed over to the docking magnet, s.
    pub released_s: Option<f64>,
    /// First diagnostics column.
    pub first_column: usize,
}

/// Every `Xu2019` controller of the scene.
#[derive(Resource, Debug, Clone, Default)]
pub struct Xu2019Controllers {
    /// The controllers, scene order.
    pub list: Vec<Xu2019Instance>,
}

/// Radial distance of a body's centre of mass to the superquadric (exact ray intersection),
/// m; positive outside.
#[derive(Debug, Clone)]
pub struct ObstacleRadialGuarantee {
    /// Name.
    pub name: String,
    /// Body index.
    pub body: usize,
    /// The obstacle.
    pub shape: SuperquadricParams,
}

impl Guarantee for ObstacleRadialGuarantee {
    fn name(&self) -> &str {
        &self.name
    }
    fn margin(&self, view: &MonitorView) -> f64 {
        let p = view.bodies[self.body].pos_m.xy();
        self.shape.radial_distance_m(p, RadialForm::Exact)
    }
}

/// Radial distance of a body's centre of mass to the heart keep-out (eq 11, corrected), m;
/// positive outside.
#[derive(Debug, Clone)]
pub struct HeartRadialGuarantee {
    /// Name.
    pub name: String,
    /// Body index.
    pub body: usize,
    /// The keep-out.
    pub shape: HeartParams,
}

impl Guarantee for HeartRadialGuarantee {
    fn name(&self) -> &str {
        &self.name
    }
    fn margin(&self, view: &MonitorView) -> f64 {
        self.shape
            .radial_distance_m(view.bodies[self.body].pos_m.xy())
    }
}

/// Yaw θ of a body about lab z (angle of its body x axis from lab x), rad.
pub fn yaw_rad(s: &BodyState) -> f64 {
    let x = s.att * Vector3::x();
    x.y.atan2(x.x)
}

fn wrap_pi(a: f64) -> f64 {
    let w =
        (a + std::f64::consts::PI).rem_euclid(2.0 * std::f64::consts::PI) - std::f64::consts::PI;
    if w == -std::f64::consts::PI {
        std::f64::consts::PI
    } else {
        w
    }
}

/// Adds this law's resources and systems for one controller of the scene.
pub fn install(
    app: &mut App,
    loaded: &LoadedScene,
    path: &str,
    spec: &SceneSpec,
) -> Result<(), SceneError> {
    let chaser = super::body_index(loaded, path, "chaser", &spec.chaser)?;
    spec.validate()
        .map_err(|(field, msg)| loaded.error_at(&format!("{path}.{field}"), msg))?;
    if !matches!(
        loaded.scene.environment,
        crate::scene::Environment::AirBearing(_)
    ) {
        return Err(loaded.error_at(
            "environment",
            "the Xu2019 law flies a simulator on an air-bearing table: use `AirBearing((...))`",
        ));
    }
    let params = spec.params();
    let world = app.world_mut();
    let first_install = !world.contains_resource::<Xu2019Controllers>();
    if first_install {
        world.insert_resource(Xu2019Controllers::default());
    }
    let k = world.resource::<Xu2019Controllers>().list.len();
    let prefix = if k == 0 {
        "xu2019".to_string()
    } else {
        format!("xu2019_{k}")
    };
    let first_column = {
        let mut diag = world.resource_mut::<Diagnostics>();
        let cols: Vec<usize> = COLUMNS
            .iter()
            .map(|c| diag.column(&format!("{prefix}.{c}")))
            .collect();
        cols[0]
    };
    {
        let mut g = world.resource_mut::<Guarantees>();
        g.register(Box::new(ObstacleRadialGuarantee {
            name: format!("{prefix}_obstacle_radial"),
            body: chaser,
            shape: params.obstacle.clone(),
        }));
        g.register(Box::new(HeartRadialGuarantee {
            name: format!("{prefix}_heart_radial"),
            body: chaser,
            shape: params.heart.clone(),
        }));
    }
    let (pwpf, seed_t) = match &spec.actuation {
        ActuationSpec::Ideal => (None, 0),
        ActuationSpec::Thrusters { params, seed, .. } => (Some(ThrusterPwpf::new(params)), *seed),
    };
    world
        .resource_mut::<Xu2019Controllers>()
        .list
        .push(Xu2019Instance {
            law: Xu2019Controller::new(params),
            spec: spec.clone(),
            chaser,
            in_flight: VecDeque::new(),
            next_exposure: 0,
            last: None,
            vel_est: Vector3::zeros(),
            fresh: None,
            observation: None,
            command: Xu2019Command {
                force_lab_n: Vector2::zeros(),
                torque_nm: 0.0,
                force_body_n: Vector2::zeros(),
            },
            pwpf,
            valves: [false; 8],
            valve_open_s: [0.0; 8],
            valve_openings: [0; 8],
            gas_used_kg: 0.0,
            applied: Vector3::zeros(),
            vision_noise: GaussianNoise::new(spec.vision.seed),
            thrust_noise: GaussianNoise::new(seed_t ^ 0x5851_F42D_4C95_7F2D),
            released_s: None,
            first_column,
        });
    if first_install {
        app.add_systems(
            SimStep,
            (
                xu2019_sense.in_set(Stage::Sense),
                xu2019_control.in_set(Stage::Control),
                xu2019_actuate.in_set(Stage::Actuate),
            ),
        );
    }
    Ok(())
}

/// Sense stage: exposures at k·period, noise, latency, velocity estimate.
pub fn xu2019_sense(
    clock: Res<Clock>,
    roster: Res<Roster>,
    bodies: Query<&BodyState>,
    mut ctrls: ResMut<Xu2019Controllers>,
) {
    let t = clock.t_s();
    let eps = 1e-9 * clock.dt_s;
    for c in ctrls.list.iter_mut() {
        let Ok(s) = bodies.get(roster.bodies[c.chaser]) else {
            continue;
        };
        let v = c.spec.vision.clone();
        while c.next_exposure as f64 * v.period_s <= t + eps {
            let te = c.next_exposure as f64 * v.period_s;
            c.next_exposure += 1;
            let nx = c.vision_noise.standard_normal() * v.position_noise_m;
            let ny = c.vision_noise.standard_normal() * v.position_noise_m;
            let nt = c.vision_noise.standard_normal() * v.angle_noise_deg.to_radians();
            c.in_flight.push_back(VisionSample {
                t_s: te,
                deliver_s: te + v.latency_s,
                pos_m: s.pos_m.xy() + Vector2::new(nx, ny),
                theta_rad: wrap_pi(yaw_rad(s) + nt),
                vel_m_s: s.vel_m_s.xy(),
                omega_rad_s: s.omega_rad_s.z,
            });
        }
        while c.in_flight.front().is_some_and(|m| m.deliver_s <= t + eps) {
            let m = c.in_flight.pop_front().expect("front exists");
            let (vel, omega) = match v.velocity {
                VelocitySource::Ideal => (m.vel_m_s, m.omega_rad_s),
                VelocitySource::Differenced => {
                    let raw = match &c.last {
                        None => Vector3::zeros(),
                        Some(p) => {
                            let h = m.t_s - p.t_s;
                            let d = m.pos_m - p.pos_m;
                            Vector3::new(d.x / h, d.y / h, wrap_pi(m.theta_rad - p.theta_rad) / h)
                        }
                    };
                    if c.last.is_none() || v.velocity_filter_s <= 0.0 {
                        c.vel_est = raw;
                    } else {
                        let a = v.period_s / (v.velocity_filter_s + v.period_s);
                        c.vel_est += (raw - c.vel_est) * a;
                    }
                    (c.vel_est.xy(), c.vel_est.z)
                }
            };
            c.last = Some(m);
            c.fresh = Some(Xu2019Observation {
                t_s: m.t_s,
                pos_lab_m: m.pos_m,
                theta_rad: m.theta_rad,
                vel_lab_m_s: vel,
                omega_rad_s: omega,
            });
        }
    }
}

/// Control stage: eq (16) on a freshly delivered observation; the command is held otherwise.
/// With `release_on_magnet`, the command is zero once the docking magnet is on.
pub fn xu2019_control(
    clock: Res<Clock>,
    dock: Option<Res<crate::sim::docking::Docking>>,
    mut ctrls: ResMut<Xu2019Controllers>,
    mut diag: ResMut<Diagnostics>,
    mut log: ResMut<crate::sim::EventLog>,
) {
    let magnet_on = dock.as_ref().is_some_and(|d| d.magnet_on);
    for c in ctrls.list.iter_mut() {
        if let Some(obs) = c.fresh.take() {
            let cmd = c.law.command(&obs);
            if cmd.force_lab_n.iter().all(|x| x.is_finite()) && cmd.torque_nm.is_finite() {
                c.command = cmd;
            }
            c.observation = Some(obs);
        }
        if c.spec.release_on_magnet && magnet_on {
            if c.released_s.is_none() {
                c.released_s = Some(clock.t_s());
                log.push(
                    clock.t_s(),
                    "xu2019_release",
                    serde_json::json!({"reason": "docking magnet on: thrusters off"}),
                );
            }
            c.command = Xu2019Command {
                force_lab_n: Vector2::zeros(),
                torque_nm: 0.0,
                force_body_n: Vector2::zeros(),
            };
        }
        if let Some(o) = &c.observation {
            let i = c.first_column;
            diag.values[i] = o.pos_lab_m.x;
            diag.values[i + 1] = o.pos_lab_m.y;
            diag.values[i + 2] = o.theta_rad.to_degrees();
        }
        let i = c.first_column;
        diag.values[i + 3] = c.command.force_lab_n.x;
        diag.values[i + 4] = c.command.force_lab_n.y;
        diag.values[i + 5] = c.command.torque_nm;
    }
}

/// The nozzle forces of the open valves with thrust noise: body-frame force (N) and torque
/// about z (N·m), and the gas mass flow, kg/s.
fn noisy_wrench(
    p: &ThrusterParams,
    valves: &[bool; 8],
    sigma: f64,
    noise: &mut GaussianNoise,
) -> (Vector2<f64>, f64, f64) {
    let mut force = Vector2::zeros();
    let mut torque = 0.0;
    let mut flow = 0.0;
    for (n, open) in p.nozzles().iter().zip(valves) {
        if *open {
            let f = p.thrust_per_nozzle_n
                * if sigma > 0.0 {
                    (1.0 + sigma * noise.standard_normal()).max(0.0)
                } else {
                    1.0
                };
            let fi = n.dir_body * f;
            force += fi;
            torque += n.pos_body_m.x * fi.y - n.pos_body_m.y * fi.x;
            flow += f / (p.isp_s * G0_M_S2);
        }
    }
    (force, torque, flow)
}

/// Actuate stage: the held command through the actuators into the chaser's wrench.
pub fn xu2019_actuate(
    clock: Res<Clock>,
    roster: Res<Roster>,
    mut ctrls: ResMut<Xu2019Controllers>,
    mut q: Query<(&BodyState, &mut Wrench)>,
    mut diag: ResMut<Diagnostics>,
) {
    let dt = clock.dt_s;
    for c in ctrls.list.iter_mut() {
        let Ok((s, mut w)) = q.get_mut(roster.bodies[c.chaser]) else {
            continue;
        };
        let i = c.first_column;
        match &c.spec.actuation {
            ActuationSpec::Ideal => {
                c.applied = Vector3::new(
                    c.command.force_lab_n.x,
                    c.command.force_lab_n.y,
                    c.command.torque_nm,
                );
            }
            ActuationSpec::Thrusters {
                params,
                thrust_noise,
                ..
            } => {
                let pw = c.pwpf.as_mut().expect("thrusters have PWPF");
                let valves = pw.step(params, c.command.force_body_n, c.command.torque_nm, dt);
                for (k, open) in valves.iter().enumerate() {
                    if *open {
                        c.valve_open_s[k] += dt;
                        if !c.valves[k] {
                            c.valve_openings[k] += 1;
                        }
                    }
                }
                c.valves = valves;
                let (fb, tq, flow) =
                    noisy_wrench(params, &valves, *thrust_noise, &mut c.thrust_noise);
                c.gas_used_kg += flow * dt;
                let f_lab = s.att * Vector3::new(fb.x, fb.y, 0.0);
                c.applied = Vector3::new(f_lab.x, f_lab.y, tq);
            }
        }
        w.force_n.x += c.applied.x;
        w.force_n.y += c.applied.y;
        w.torque_nm.z += c.applied.z;
        let pos = s.pos_m.xy();
        let (ro, rh) = c.law.radial_distances_m(pos);
        diag.values[i + 6] = ro;
        diag.values[i + 7] = c
            .law
            .params
            .obstacle
            .radial_distance_m(pos, RadialForm::Exact);
        diag.values[i + 8] = rh;
        diag.values[i + 9] = c.applied.x;
        diag.values[i + 10] = c.applied.y;
        diag.values[i + 11] = c.applied.z;
        diag.values[i + 12] = c
            .valves
            .iter()
            .enumerate()
            .map(|(k, v)| if *v { (1u32 << k) as f64 } else { 0.0 })
            .sum();
        diag.values[i + 13] = c.valves.iter().filter(|v| **v).count() as f64;
        diag.values[i + 14] = c.gas_used_kg;
        diag.values[i + 15] = c.law.potential(Vector3::new(pos.x, pos.y, yaw_rad(s)));
        diag.values[i + 16] = yaw_rad(s).to_degrees();
    }
}
