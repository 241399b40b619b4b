//! The Xu 2019 law in a scene: the entry `Xu2019((...))` ([`Xu2019Spec`], its
//! [`LawSpec`](crate::control::spec::LawSpec) implementation), the vision system and actuation
//! choices, the radial-distance guarantees and the controller the generic host runs
//! ([`Xu2019Instance`]).

use super::*;

/// Where the vision velocity comes from (the generic sensor's choice).
pub use crate::control::sensor::VelocitySource;

/// The vision system: a pose (x, y, θ) of the chaser every `period_s`, with noise and latency.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct VisionSpec {
    /// Measurement period, s. Paper: 0.04 s (25 Hz).
    #[serde(default = "vision_period")]
    pub period_s: f64,
    /// Delay from exposure to the controller, s (image processing, radio link).
    #[serde(default)]
    pub latency_s: f64,
    /// Standard deviation of the position noise per axis, m.
    #[serde(default)]
    pub position_noise_m: f64,
    /// Standard deviation of the attitude noise, deg.
    #[serde(default)]
    pub angle_noise_deg: f64,
    /// Where the velocity comes from.
    #[serde(default)]
    pub velocity: VelocitySource,
    /// Time constant of a first-order low-pass filter on the differenced velocity, s
    /// (0: none).
    #[serde(default)]
    pub velocity_filter_s: f64,
    /// Seed of the noise.
    #[serde(default)]
    pub seed: u64,
}

fn vision_period() -> f64 {
    0.04
}

impl Default for VisionSpec {
    fn default() -> Self {
        Self {
            period_s: vision_period(),
            latency_s: 0.0,
            position_noise_m: 0.0,
            angle_noise_deg: 0.0,
            velocity: VelocitySource::Differenced,
            velocity_filter_s: 0.0,
            seed: 0,
        }
    }
}

/// How the command becomes a force on the simulator.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub enum ActuationSpec {
    /// The commanded (Fx, Fy, T) applied exactly, continuous and unlimited (the paper's
    /// numerical simulation).
    Ideal,
    /// The eight cold-gas nozzles of Fig. 10, on/off, through one PWPF modulator per channel
    /// (body x, body y, torque), stepped every simulation step.
    Thrusters {
        /// Nozzle thrust, lever arm, specific impulse and the PWPF constants
        /// (default: [`crate::actuation::thrusters::ThrusterParams::paper`]).
        #[serde(default)]
        params: crate::actuation::thrusters::ThrusterParams,
        /// Relative thrust noise: each open nozzle gives F·(1 + σ·N(0, 1)) per step
        /// (dimensionless standard deviation σ; 0: none).
        #[serde(default)]
        thrust_noise: f64,
        /// Seed of the thrust noise.
        #[serde(default)]
        seed: u64,
    },
}

/// How a scene asks for the Xu, Wen, Wei (2019) law (`controllers: [Xu2019((...))]`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Xu2019Spec {
    /// The chaser simulator.
    pub chaser: String,
    /// Published or exact variant.
    #[serde(default)]
    pub form: LawForm,
    /// Goal position in the lab frame, m (default Table 1: (0.25, 1.4)).
    #[serde(default)]
    pub goal_pos_m: Option<[f64; 2]>,
    /// Goal attitude, deg (default Table 1: 90°).
    #[serde(default)]
    pub goal_theta_deg: Option<f64>,
    /// The vision system.
    #[serde(default)]
    pub vision: VisionSpec,
    /// The actuators.
    pub actuation: ActuationSpec,
    /// Stop commanding (zero force and torque, valves closed) once the docking electromagnet
    /// is on: the final centimetres are left to the magnet and the cone/slot guidance.
    #[serde(default)]
    pub release_on_magnet: bool,
}

impl Xu2019Spec {
    /// The law's constants for this scene.
    pub fn params(&self) -> Xu2019Params {
        let mut p = match self.form {
            LawForm::Paper => Xu2019Params::paper(),
            LawForm::Exact => Xu2019Params::exact(),
        };
        if let Some(g) = self.goal_pos_m {
            p.goal_pos_lab_m = g;
        }
        if let Some(t) = self.goal_theta_deg {
            p.goal_theta_rad = t.to_radians();
        }
        p
    }

    /// Checks the numbers; `Err((field, message))` with the field relative to the spec.
    pub fn validate(&self) -> Result<(), (String, String)> {
        let v = &self.vision;
        let bad = |f: &str, m: String| Err((f.to_string(), m));
        if !(v.period_s.is_finite() && v.period_s > 0.0) {
            return bad(
                "vision.period_s",
                format!("must be a positive number of seconds, got {}", v.period_s),
            );
        }
        for (f, x) in [
            ("vision.latency_s", v.latency_s),
            ("vision.position_noise_m", v.position_noise_m),
            ("vision.angle_noise_deg", v.angle_noise_deg),
            ("vision.velocity_filter_s", v.velocity_filter_s),
        ] {
            if !(x.is_finite() && x >= 0.0) {
                return bad(f, format!("must be finite and non-negative, got {x}"));
            }
        }
        if let ActuationSpec::Thrusters {
            params,
            thrust_noise,
            ..
        } = &self.actuation
        {
            for (f, x) in [
                (
                    "actuation.params.thrust_per_nozzle_n",
                    params.thrust_per_nozzle_n,
                ),
                ("actuation.params.lever_arm_m", params.lever_arm_m),
                ("actuation.params.isp_s", params.isp_s),
                ("actuation.params.pwpf.k_m", params.pwpf.k_m),
                ("actuation.params.pwpf.t_m_s", params.pwpf.t_m_s),
            ] {
                if !(x.is_finite() && x > 0.0) {
                    return bad(f, format!("must be positive, got {x}"));
                }
            }
            let p = &params.pwpf;
            if !(p.u_off >= 0.0 && p.u_off < p.u_on && p.min_on_time_s >= 0.0) {
                return bad(
                    "actuation.params.pwpf",
                    format!(
                        "needs 0 ≤ u_off < u_on and min_on_time_s ≥ 0, got u_on {}, u_off {}, min_on_time_s {}",
                        p.u_on, p.u_off, p.min_on_time_s
                    ),
                );
            }
            if !(thrust_noise.is_finite() && *thrust_noise >= 0.0) {
                return bad(
                    "actuation.thrust_noise",
                    format!("must be finite and non-negative, got {thrust_noise}"),
                );
            }
        }
        Ok(())
    }
}

// ---------------------------------------------------------------------------------------------
// The law in the simulation (air-bearing table, `crate::sim::airbearing`): the scene entry
// `Xu2019((...))`, the controller the generic host runs and its guarantees.
//
// Per step:
// - **Sense**: the slot's sensor is the generic [`crate::control::sensor::Sensor`] built from
//   `vision` (planar, lab frame): at t = k·`period_s` the chaser's true pose (x, y, θ = yaw
//   about lab z) plus seeded Gaussian noise, delivered `latency_s` later; the velocity is the
//   backward difference of successive delivered poses (first-order low-pass with
//   `velocity_filter_s`), or, with `velocity: Ideal`, measured exactly. The controller never
//   reads the truth otherwise.
// - **Control**: when a measurement is delivered, eq (16) is evaluated and the command held
//   until the next one (zero before the first). With `release_on_magnet`, zero once the
//   docking magnet is on (an `xu2019_release` event).
// - **Actuate**: `Ideal` applies the lab-frame command; `Thrusters` is the host's
//   `PlanarThrusters` actuator: three PWPF channels stepped every simulation step with the
//   body-frame command (rotated by the *measured* θ, as the on-board computer does), the valves
//   of Fig. 10, the body-fixed nozzle forces (each F·(1 + σ·N(0,1)) with thrust noise) rotated
//   by the *true* attitude. Gas used = Σ F_i·dt / (I_sp·g₀).
//
// Two guarantees: `xu2019_obstacle_radial` (exact radial distance of the chaser centre of mass
// to the superquadric, m) and `xu2019_heart_radial` (radial distance to the heart keep-out, m)
// — positive means outside. Diagnostics columns (prefix `xu2019.`): see [`COLUMNS`].
// ---------------------------------------------------------------------------------------------

/// Diagnostics columns (prefix `xu2019.`): the delivered measurement, the command (lab frame),
/// the radial distances of the true centre of mass (the law's obstacle form, the exact one,
/// the heart), the wrench applied (lab frame), the valve states (bit i = nozzle i in
/// [`crate::actuation::thrusters::NOZZLE_NAMES`] order), the open nozzle count, the gas used,
/// the potential and the true yaw.
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

/// One installed controller.
#[derive(Debug, Clone)]
pub struct Xu2019Instance {
    /// The law.
    pub law: Xu2019Potential,
    /// The scene's request.
    pub spec: Xu2019Spec,
    /// Chaser body index.
    pub chaser: usize,
    /// Last observation the law used.
    pub observation: Option<Xu2019Observation>,
    /// Held command.
    pub command: Xu2019Command,
    /// Valve states at the last step (from the actuator).
    pub valves: [bool; 8],
    /// Gas used so far, kg (from the actuator).
    pub gas_used_kg: f64,
    /// Wrench applied at the last step, lab frame: (Fx N, Fy N, T N·m).
    pub applied: Vector3<f64>,
    /// When the law handed over to the docking magnet, s.
    pub released_s: Option<f64>,
    prefix: String,
    events: Vec<crate::control::interface::ControllerEvent>,
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

impl crate::guarantee::Guarantee for ObstacleRadialGuarantee {
    fn name(&self) -> &str {
        &self.name
    }
    fn margin(&self, view: &crate::guarantee::MonitorView) -> f64 {
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

impl crate::guarantee::Guarantee for HeartRadialGuarantee {
    fn name(&self) -> &str {
        &self.name
    }
    fn margin(&self, view: &crate::guarantee::MonitorView) -> f64 {
        self.shape
            .radial_distance_m(view.bodies[self.body].pos_m.xy())
    }
}

/// Instances of the law so far in the scene being built.
#[derive(Default)]
struct Xu2019Count(usize);

impl VisionSpec {
    /// The generic sensor this vision system is: planar, lab frame.
    pub fn sensor(&self) -> crate::control::sensor::SensorSpec {
        crate::control::sensor::SensorSpec {
            frame: crate::control::interface::MeasuredFrame::World,
            period_s: self.period_s,
            latency_s: self.latency_s,
            position_noise_m: self.position_noise_m,
            angle_noise_deg: self.angle_noise_deg,
            velocity: self.velocity,
            velocity_filter_s: self.velocity_filter_s,
            seed: self.seed,
            planar: true,
            filter: None,
        }
    }
}

impl crate::control::spec::LawSpec for Xu2019Spec {
    /// On an air-bearing table: the superquadric obstacle and the heart-shaped keep-out the law
    /// keeps the chaser's centre of mass out of (its own [`Xu2019Params`]), as prisms over the
    /// table up to twice the chaser's initial centre-of-mass height (its plane mid-way).
    fn drawn(&self, scene: &crate::scene::Scene) -> Vec<crate::geometry::drawn::DrawnSurface> {
        use crate::geometry::drawn::{DrawnSurface, OUTLINE_POINTS};
        if !matches!(scene.environment, crate::scene::Environment::AirBearing(_)) {
            return Vec::new();
        }
        let params = self.params();
        let chaser = scene.bodies.iter().position(|b| b.name == self.chaser);
        let top_m = chaser
            .map(|i| 2.0 * scene.bodies[i].initial.pos_m[2])
            .filter(|z| *z > 0.0)
            .unwrap_or(0.3);
        let sq = params.obstacle;
        let h = params.heart;
        vec![
            DrawnSurface::TablePrism {
                legend: format!(
                    "Xu2019 obstacle (magenta): superquadric a {} m, b {} m, s {}, centre ({}, {}) m (lab)",
                    sq.a_m, sq.b_m, sq.s, sq.centre_lab_m[0], sq.centre_lab_m[1]
                ),
                outline_lab_m: sq.outline_lab_m(OUTLINE_POINTS),
                centre_lab_m: sq.centre(),
                top_m,
                curve_body: chaser,
                rgba: [1.0, 0.3, 0.75, 0.22],
            },
            DrawnSurface::TablePrism {
                legend: format!(
                    "Xu2019 keep-out (orange): heart R1 {} m, R2 {} m, R3 {} m, notch ({}, {}) m (lab)",
                    h.r1_m, h.r2_m, h.r3_m, h.centre_lab_m[0], h.centre_lab_m[1]
                ),
                outline_lab_m: h.outline_lab_m(OUTLINE_POINTS),
                centre_lab_m: h.centre(),
                top_m,
                curve_body: chaser,
                rgba: [1.0, 0.55, 0.15, 0.2],
            },
        ]
    }
    fn build(
        &self,
        ctx: &mut crate::control::spec::BuildContext,
    ) -> Result<crate::control::spec::Built, crate::control::spec::BuildError> {
        use crate::control::spec::{BuildError, Built, Slot};
        let chaser = ctx.body("0.chaser", &self.chaser)?;
        self.validate()
            .map_err(|(field, msg)| BuildError::at(format!("0.{field}"), msg))?;
        self.vision
            .sensor()
            .check_period(ctx.scene.dt_s)
            .map_err(|(field, msg)| BuildError::at(format!("0.vision.{field}"), msg))?;
        if !matches!(
            ctx.scene.environment,
            crate::scene::Environment::AirBearing(_)
        ) {
            return Err(BuildError::at_root(
                "environment",
                "the Xu2019 law flies a simulator on an air-bearing table: use `AirBearing((...))`",
            ));
        }
        let k = {
            let c = ctx.shared::<Xu2019Count>("Xu2019");
            c.0 += 1;
            c.0 - 1
        };
        let prefix = if k == 0 {
            "xu2019".to_string()
        } else {
            format!("xu2019_{k}")
        };
        let actuator = match &self.actuation {
            ActuationSpec::Ideal => crate::actuation::ActuatorSpec::Ideal,
            ActuationSpec::Thrusters {
                params,
                thrust_noise,
                seed,
            } => crate::actuation::ActuatorSpec::PlanarThrusters {
                params: params.clone(),
                thrust_noise: *thrust_noise,
                seed: *seed,
            },
        };
        Ok(Built {
            slots: vec![Slot {
                kind: "Xu2019".into(),
                body: chaser,
                target: None,
                period_steps: 1,
                sensor: Some(self.vision.sensor()),
                actuator,
                ports: None,
                law: Box::new(Xu2019Instance {
                    law: Xu2019Potential::new(self.params()),
                    spec: self.clone(),
                    chaser,
                    observation: None,
                    command: Xu2019Command {
                        force_lab_n: Vector2::zeros(),
                        torque_nm: 0.0,
                        force_body_n: Vector2::zeros(),
                    },
                    valves: [false; 8],
                    gas_used_kg: 0.0,
                    applied: Vector3::zeros(),
                    released_s: None,
                    prefix,
                    events: Vec::new(),
                }),
            }],
            disturbances: Vec::new(),
        })
    }
}

impl crate::control::interface::Controller for Xu2019Instance {
    fn needs(&self) -> crate::control::interface::Needs {
        crate::control::interface::Needs::NONE
    }

    fn command(
        &mut self,
        obs: &crate::control::interface::Observation,
    ) -> crate::control::interface::Command {
        use crate::control::interface::{Command, ControllerEvent, Frame};
        if let Some(m) = obs.measured.filter(|m| m.fresh) {
            let o = Xu2019Observation {
                t_s: m.t_s,
                pos_lab_m: m.pos_m.xy(),
                theta_rad: m.yaw_rad.unwrap_or(0.0),
                vel_lab_m_s: m.vel_m_s.xy(),
                omega_rad_s: m.omega_rad_s.z,
            };
            let cmd = self.law.command(&o);
            if cmd.force_lab_n.iter().all(|x| x.is_finite()) && cmd.torque_nm.is_finite() {
                self.command = cmd;
            }
            self.observation = Some(o);
        }
        let magnet_on = obs.docking.is_some_and(|d| d.magnet_on);
        if self.spec.release_on_magnet && magnet_on {
            if self.released_s.is_none() {
                self.released_s = Some(obs.t_s);
                self.events.push(ControllerEvent {
                    kind: "xu2019_release".into(),
                    data: serde_json::json!({"reason": "docking magnet on: thrusters off"}),
                });
            }
            self.command = Xu2019Command {
                force_lab_n: Vector2::zeros(),
                torque_nm: 0.0,
                force_body_n: Vector2::zeros(),
            };
        }
        let c = &self.command;
        match self.spec.actuation {
            ActuationSpec::Ideal => Command::in_frame(
                Frame::World,
                Vector3::new(c.force_lab_n.x, c.force_lab_n.y, 0.0),
                Vector3::new(0.0, 0.0, c.torque_nm),
            ),
            ActuationSpec::Thrusters { .. } => Command::in_frame(
                Frame::Body,
                Vector3::new(c.force_body_n.x, c.force_body_n.y, 0.0),
                Vector3::new(0.0, 0.0, c.torque_nm),
            ),
        }
    }

    fn columns(&self) -> Vec<String> {
        COLUMNS
            .iter()
            .map(|c| format!("{}.{c}", self.prefix))
            .collect()
    }

    fn diagnostics(
        &mut self,
        _at: crate::control::interface::DiagnosticsAt,
        obs: &crate::control::interface::Observation,
        act: &crate::control::interface::ActuationReport,
        out: &mut [f64],
    ) {
        if let Some(v) = &act.valves {
            for (k, b) in self.valves.iter_mut().enumerate() {
                *b = v.get(k).copied().unwrap_or(false);
            }
        }
        self.gas_used_kg = act.propellant_used_kg;
        self.applied = Vector3::new(
            act.force_world_n.x,
            act.force_world_n.y,
            act.torque_world_nm.z,
        );
        if let Some(o) = &self.observation {
            out[0] = o.pos_lab_m.x;
            out[1] = o.pos_lab_m.y;
            out[2] = o.theta_rad.to_degrees();
        }
        out[3] = self.command.force_lab_n.x;
        out[4] = self.command.force_lab_n.y;
        out[5] = self.command.torque_nm;
        let own = obs.own();
        let pos = own.pos_m.xy();
        let yaw = crate::control::sensor::yaw_of(&own.att);
        let (ro, rh) = self.law.radial_distances_m(pos);
        out[6] = ro;
        out[7] = self
            .law
            .params
            .obstacle
            .radial_distance_m(pos, RadialForm::Exact);
        out[8] = rh;
        out[9] = self.applied.x;
        out[10] = self.applied.y;
        out[11] = self.applied.z;
        out[12] = self
            .valves
            .iter()
            .enumerate()
            .map(|(k, v)| if *v { (1u32 << k) as f64 } else { 0.0 })
            .sum();
        out[13] = self.valves.iter().filter(|v| **v).count() as f64;
        out[14] = self.gas_used_kg;
        out[15] = self.law.potential(Vector3::new(pos.x, pos.y, yaw));
        out[16] = yaw.to_degrees();
    }

    fn guarantees(&mut self) -> Vec<Box<dyn crate::guarantee::Guarantee>> {
        let p = &self.law.params;
        vec![
            Box::new(ObstacleRadialGuarantee {
                name: format!("{}_obstacle_radial", self.prefix),
                body: self.chaser,
                shape: p.obstacle.clone(),
            }),
            Box::new(HeartRadialGuarantee {
                name: format!("{}_heart_radial", self.prefix),
                body: self.chaser,
                shape: p.heart.clone(),
            }),
        ]
    }

    fn take_events(&mut self) -> Vec<crate::control::interface::ControllerEvent> {
        std::mem::take(&mut self.events)
    }
}
