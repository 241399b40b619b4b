//! The Geng 2015 law in a scene: the entry `Geng2015((...))` ([`Geng2015Spec`], its
//! [`LawSpec`](crate::control::spec::LawSpec) implementation), the paper's disturbances applied
//! by the simulation ([`Geng2015Disturbance`]) and the controller the generic host runs
//! ([`Geng2015Loop`]).

use super::*;

/// How a scene asks for this law: which bodies and ports, the law, its period, and the paper's
/// disturbances (applied by the simulation to both bodies). Every field but `body`, `target`,
/// `law`, `chaser_port` and `target_port` has the paper's value as default.
///
/// The controller's model takes the chaser mass and both inertias from the scene bodies unless
/// `model_chaser_inertia_diag_kg_m2` / `model_target_inertia_diag_kg_m2` say otherwise (the
/// ±10 % inertia cases of Tables 4–7 perturb the bodies and keep the model nominal). Port
/// positions are the scene ports' origins less the body's centre of mass. (The larger optional
/// blocks are boxed to keep [`crate::control::ControllerSpec`] small; scenes write them plainly.)
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Geng2015Spec {
    /// The body this law flies (the chaser S).
    pub body: String,
    /// The uncontrolled target T.
    pub target: String,
    /// T1, T2, M1 or M2.
    pub law: Geng2015Law,
    /// Port of `body` that is P_s (its origin is the docking point).
    pub chaser_port: String,
    /// Port of `target` that is P_t.
    pub target_port: String,
    /// Controller period, s (a whole number of steps; the command is held in between). 0.05 s
    /// reproduces the paper (module docs).
    #[serde(default = "default_period_s")]
    pub period_s: f64,
    /// Frame of ρ (default the target's Hill frame).
    #[serde(default = "default_rho_frame")]
    pub rho_frame: RhoFrame,
    /// Source of ṡ for T2/M2 (default the integral state).
    #[serde(default = "default_sdot")]
    pub sdot_estimate: SdotEstimate,
    /// Desired ρ_d in the ρ frame, m (default 0: the ports coincide).
    #[serde(default)]
    pub rho_des_m: [f64; 3],
    /// Per-axis acceleration limit a_max, m/s² (default 0.2).
    #[serde(default = "default_accel_max")]
    pub accel_max_m_s2: f64,
    /// Per-axis torque limit T_max, N·m (default 0.8).
    #[serde(default = "default_torque_max")]
    pub torque_max_nm: f64,
    /// Diagonal of the chaser inertia the controller assumes, kg·m² (default: the body's).
    #[serde(default)]
    pub model_chaser_inertia_diag_kg_m2: Option<Box<[f64; 3]>>,
    /// Diagonal of the target inertia the controller assumes, kg·m² (default: the body's).
    #[serde(default)]
    pub model_target_inertia_diag_kg_m2: Option<Box<[f64; 3]>>,
    /// Gains (default Table 2).
    #[serde(default)]
    pub gains: Option<Box<Geng2015Gains>>,
    /// The paper's disturbances on both bodies (default none).
    #[serde(default)]
    pub disturbance: Option<Box<DisturbanceSpec>>,
}

/// The disturbances of §1/§3.1 as a scene writes them: a_d on each body in its own axes (form
/// and amplitude), T_d(t) on both; ω° of T_d is the reference orbit's mean motion. The
/// gravity-gradient torque T_g is the environment's (`gravity_gradient: true`), not repeated.
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DisturbanceSpec {
    /// Form of the chaser's a_sd.
    pub chaser_form: AccelDisturbanceForm,
    /// Form of the target's a_td.
    pub target_form: AccelDisturbanceForm,
    /// k_d, 1/s (default 0.5).
    #[serde(default = "default_k_d")]
    pub k_d_per_s: f64,
    /// a_sd0, chaser body axes, m/s² (default [2.0, 4.2, 3.5]e−5).
    #[serde(default = "default_chaser_a0")]
    pub chaser_accel0_m_s2: [f64; 3],
    /// a_td0, target body axes, m/s² (default [2.5, 4.0, 3.8]e−5).
    #[serde(default = "default_target_a0")]
    pub target_accel0_m_s2: [f64; 3],
    /// Scale of T_d, N·m (default 1.5e−5).
    #[serde(default = "default_torque_scale")]
    pub torque_scale_nm: f64,
}

impl DisturbanceSpec {
    /// The law-side disturbance set, with ω° = `omega_orbit_rad_s`.
    pub fn to_disturbances(&self, omega_orbit_rad_s: f64) -> Geng2015Disturbances {
        Geng2015Disturbances {
            k_d_per_s: self.k_d_per_s,
            target_accel0_m_s2: Vector3::from(self.target_accel0_m_s2),
            chaser_accel0_m_s2: Vector3::from(self.chaser_accel0_m_s2),
            target_form: self.target_form,
            chaser_form: self.chaser_form,
            torque_scale_nm: self.torque_scale_nm,
            omega_orbit_rad_s,
        }
    }
}

fn default_period_s() -> f64 {
    0.05
}
fn default_rho_frame() -> RhoFrame {
    RhoFrame::TargetHill
}
fn default_sdot() -> SdotEstimate {
    SdotEstimate::IntegralState
}
fn default_accel_max() -> f64 {
    0.2
}
fn default_torque_max() -> f64 {
    0.8
}
fn default_k_d() -> f64 {
    0.5
}
fn default_chaser_a0() -> [f64; 3] {
    [2.0e-5, 4.2e-5, 3.5e-5]
}
fn default_target_a0() -> [f64; 3] {
    [2.5e-5, 4.0e-5, 3.8e-5]
}
fn default_torque_scale() -> f64 {
    1.5e-5
}

// ---------------------------------------------------------------------------------------------
// The law in the simulation: the scene entry `Geng2015((...))`, the controller the generic host
// runs and the paper's disturbances.
// ---------------------------------------------------------------------------------------------

/// Column names published per loop, after the `geng2015.<body>.` prefix: ρ and ρ̇ (ρ frame),
/// q_rv, ω_r (chaser axes), the port distance |ρ| — from the states after the step, i.e. at the
/// time of the trajectory row — and from the last controller call the sliding variables
/// s1..s6 and the applied command u (chaser body axes, N, N·m).
pub const COLUMNS: [&str; 25] = [
    "rho_x_m",
    "rho_y_m",
    "rho_z_m",
    "rho_dot_x_m_s",
    "rho_dot_y_m_s",
    "rho_dot_z_m_s",
    "qrv1",
    "qrv2",
    "qrv3",
    "omega_r_x_rad_s",
    "omega_r_y_rad_s",
    "omega_r_z_rad_s",
    "port_distance_m",
    "s1",
    "s2",
    "s3",
    "s4",
    "s5",
    "s6",
    "force_x_body_n",
    "force_y_body_n",
    "force_z_body_n",
    "torque_x_body_nm",
    "torque_y_body_nm",
    "torque_z_body_nm",
];

/// One controller of the scene and its held command (what the generic host runs every
/// `period_s`). The law is handed the Earth-centred f64 states of chaser and target (world
/// state plus the reference orbit's ECI state; world axes are ECI axes) and returns force and
/// torque in chaser body axes, saturated per axis; the host holds them and turns them into the
/// world frame with the chaser's attitude at the start of each step (body-fixed thrusters).
#[derive(Debug, Clone)]
pub struct Geng2015Loop {
    /// The law with its integral state (its `diagnostics()` hold the last call's e, s, u).
    pub controller: Geng2015Twisting,
    /// Chaser body index (scene order).
    pub chaser: usize,
    /// Target body index.
    pub target: usize,
    /// Held force, chaser body axes, N.
    pub force_body_n: Vector3<f64>,
    /// Held torque, chaser body axes, N·m.
    pub torque_body_nm: Vector3<f64>,
    /// Number of controller calls so far.
    pub calls: u64,
    /// Time of the last call, s.
    pub last_call_s: f64,
    prefix: String,
}

/// The paper's disturbances on both bodies: force m·R·a_d(t) (a_d in the body's own axes) and
/// torque R·T_d(t). The gravity-gradient torque T_g of the paper is the environment's (scene
/// `gravity_gradient: true`) and is not added again.
#[derive(Debug, Clone)]
pub struct Geng2015Disturbance {
    /// Chaser body index.
    pub chaser: usize,
    /// Target body index.
    pub target: usize,
    /// The disturbance set.
    pub set: Geng2015Disturbances,
}

impl crate::control::spec::Disturbance for Geng2015Disturbance {
    fn wrenches(
        &mut self,
        ctx: &crate::control::spec::DisturbanceContext,
        out: &mut Vec<crate::control::spec::BodyWrench>,
    ) {
        let dist = &self.set;
        for (idx, is_chaser) in [(self.chaser, true), (self.target, false)] {
            let a = accel_disturbance_m_s2(
                if is_chaser {
                    dist.chaser_form
                } else {
                    dist.target_form
                },
                &if is_chaser {
                    dist.chaser_accel0_m_s2
                } else {
                    dist.target_accel0_m_s2
                },
                dist.k_d_per_s,
                ctx.t_s,
            );
            let tq = torque_disturbance_nm(dist.torque_scale_nm, dist.omega_orbit_rad_s, ctx.t_s);
            let s = &ctx.bodies[idx];
            out.push(crate::control::spec::BodyWrench {
                body: idx,
                force_n: Some(s.att * (a * ctx.info[idx].mass_kg)),
                torque_nm: Some(s.att * tq),
            });
        }
    }
}

/// The observation of a loop: Earth-centred states of chaser and target at time `t_s` from
/// their world-frame truth and the reference orbit's ECI state.
pub fn observation(
    t_s: f64,
    reference: (Vector3<f64>, Vector3<f64>),
    chaser: &crate::control::interface::BodyObs,
    target: &crate::control::interface::BodyObs,
) -> Geng2015Obs {
    let eci = |s: &crate::control::interface::BodyObs| BodyStateEci {
        pos_eci_m: reference.0 + s.pos_m,
        vel_eci_m_s: reference.1 + s.vel_m_s,
        att_body_to_eci: s.att,
        rate_body_rad_s: s.rate_body_rad_s,
    };
    Geng2015Obs {
        t_s,
        chaser: eci(chaser),
        target: eci(target),
    }
}

fn diag3(d: [f64; 3]) -> Matrix3<f64> {
    Matrix3::from_diagonal(&Vector3::from(d))
}

fn positive(x: f64) -> bool {
    x.is_finite() && x > 0.0
}

impl crate::control::spec::LawSpec for Geng2015Spec {
    fn build(
        &self,
        ctx: &mut crate::control::spec::BuildContext,
    ) -> Result<crate::control::spec::Built, crate::control::spec::BuildError> {
        use crate::control::spec::{BuildError, Built, Slot};
        let spec = self;
        let scene = ctx.scene;
        let chaser = ctx.body("0.body", &spec.body)?;
        let target = ctx.body("0.target", &spec.target)?;
        let err = |field: &str, msg: String| BuildError::at(format!("0.{field}"), msg);
        if chaser == target {
            return Err(err(
                "target",
                format!("the target must differ from the chaser `{}`", spec.body),
            ));
        }
        let crate::scene::Environment::Orbit { .. } = scene.environment else {
            return Err(err(
                "body",
                "the geng2015 law needs an Orbit environment (it works on Earth-centred states)"
                    .into(),
            ));
        };
        let (bs, bt) = (&scene.bodies[chaser], &scene.bodies[target]);
        let port = |b: &crate::scene::BodySpec, field: &str, name: &str| {
            b.ports
                .iter()
                .find(|p| p.name == name)
                .map(|p| Vector3::from(p.pos_m) - Vector3::from(b.com_m))
                .ok_or_else(|| err(field, format!("body `{}` has no port `{name}`", b.name)))
        };
        let ps = port(bs, "chaser_port", &spec.chaser_port)?;
        let pt = port(bt, "target_port", &spec.target_port)?;
        let dt = scene.dt_s;
        let ratio = spec.period_s / dt;
        let period_steps = ratio.round();
        if !spec.period_s.is_finite()
            || !(1.0..=1e12).contains(&period_steps)
            || (ratio - period_steps).abs() > 1e-6
        {
            return Err(err(
                "period_s",
                format!(
                    "must be a whole number of steps (dt_s = {dt} s) and at least one, got {} s",
                    spec.period_s
                ),
            ));
        }
        if !positive(spec.accel_max_m_s2) {
            return Err(err(
                "accel_max_m_s2",
                format!(
                    "must be a positive acceleration, got {}",
                    spec.accel_max_m_s2
                ),
            ));
        }
        if !positive(spec.torque_max_nm) {
            return Err(err(
                "torque_max_nm",
                format!("must be a positive torque, got {}", spec.torque_max_nm),
            ));
        }
        for (field, v) in [
            (
                "model_chaser_inertia_diag_kg_m2",
                spec.model_chaser_inertia_diag_kg_m2.clone(),
            ),
            (
                "model_target_inertia_diag_kg_m2",
                spec.model_target_inertia_diag_kg_m2.clone(),
            ),
        ] {
            if let Some(d) = v.as_deref()
                && !d.iter().all(|x| positive(*x))
            {
                return Err(err(
                    field,
                    format!("moments must be positive kg·m², got {d:?}"),
                ));
            }
        }
        if !spec.rho_des_m.iter().all(|x| x.is_finite()) {
            return Err(err("rho_des_m", "must be finite metres".into()));
        }
        if let Some(g) = &spec.gains {
            let all = [
                &g.t1_alpha,
                &g.t1_beta,
                &g.t2_lambda,
                &g.t2_alpha,
                &g.t2_beta,
                &g.m1_m1,
                &g.m1_m2,
                &g.m1_m3,
                &g.m1_m4,
                &g.m2_lambda,
                &g.m2_k1,
                &g.m2_k2,
                &g.m2_k3,
                &g.m2_k4,
            ];
            if !all
                .iter()
                .all(|v| v.iter().all(|x| x.is_finite() && *x >= 0.0))
            {
                return Err(err("gains", "gains must be finite and non-negative".into()));
            }
        }
        if let Some(d) = &spec.disturbance {
            let ok = d.k_d_per_s.is_finite()
                && d.torque_scale_nm.is_finite()
                && d.chaser_accel0_m_s2
                    .iter()
                    .chain(&d.target_accel0_m_s2)
                    .all(|x| x.is_finite());
            if !ok {
                return Err(err("disturbance", "values must be finite".into()));
            }
        }
        let params = Geng2015Params {
            chaser_mass_kg: bs.mass_kg,
            chaser_inertia_kg_m2: spec
                .model_chaser_inertia_diag_kg_m2
                .as_deref()
                .copied()
                .map(diag3)
                .unwrap_or_else(|| bs.inertia_kg_m2.matrix()),
            target_inertia_kg_m2: spec
                .model_target_inertia_diag_kg_m2
                .as_deref()
                .copied()
                .map(diag3)
                .unwrap_or_else(|| bt.inertia_kg_m2.matrix()),
            chaser_port_body_m: ps,
            target_port_body_m: pt,
            mu_m3_s2: MU_EARTH_M3_S2,
            accel_max_m_s2: spec.accel_max_m_s2,
            torque_max_nm: spec.torque_max_nm,
            rho_frame: spec.rho_frame,
            rho_des_m: Vector3::from(spec.rho_des_m),
            sdot_estimate: spec.sdot_estimate,
            gains: spec
                .gains
                .as_deref()
                .cloned()
                .unwrap_or_else(Geng2015Gains::paper),
        };
        // ω° of T_d: the reference orbit's mean motion.
        let omega_orbit = ctx
            .env
            .reference()
            .map(|(r, v)| {
                let a = 1.0 / (2.0 / r.norm() - v.norm_squared() / MU_EARTH_M3_S2);
                (MU_EARTH_M3_S2 / a.powi(3)).sqrt()
            })
            .unwrap_or(0.0);
        let disturbances: Vec<Box<dyn crate::control::spec::Disturbance>> = spec
            .disturbance
            .as_ref()
            .map(|d| {
                Box::new(Geng2015Disturbance {
                    chaser,
                    target,
                    set: d.to_disturbances(omega_orbit),
                }) as Box<dyn crate::control::spec::Disturbance>
            })
            .into_iter()
            .collect();
        Ok(Built {
            slots: vec![Slot {
                kind: "Geng2015".into(),
                body: chaser,
                target: Some(target),
                period_steps: period_steps as u64,
                sensor: None,
                actuator: crate::actuation::ActuatorSpec::Ideal,
                ports: None,
                law: Box::new(Geng2015Loop {
                    controller: Geng2015Twisting::new(spec.law, params),
                    chaser,
                    target,
                    force_body_n: Vector3::zeros(),
                    torque_body_nm: Vector3::zeros(),
                    calls: 0,
                    last_call_s: 0.0,
                    prefix: format!("geng2015.{}", spec.body),
                }),
            }],
            disturbances,
        })
    }
}

impl crate::control::interface::Controller for Geng2015Loop {
    fn needs(&self) -> crate::control::interface::Needs {
        crate::control::interface::Needs::NONE
    }

    fn command(
        &mut self,
        obs: &crate::control::interface::Observation,
    ) -> crate::control::interface::Command {
        let reference = obs.env.reference().unwrap_or_default();
        let o = observation(
            obs.t_s,
            reference,
            &obs.bodies[self.chaser],
            &obs.bodies[self.target],
        );
        let (f, tq) = self.controller.command(&o);
        self.force_body_n = f;
        self.torque_body_nm = tq;
        self.calls += 1;
        self.last_call_s = obs.t_s;
        crate::control::interface::Command::in_frame(crate::control::interface::Frame::Body, f, tq)
    }

    fn columns(&self) -> Vec<String> {
        COLUMNS
            .iter()
            .map(|c| format!("{}.{c}", self.prefix))
            .collect()
    }

    fn diagnostics_at(&self) -> &'static [crate::control::interface::DiagnosticsAt] {
        &[crate::control::interface::DiagnosticsAt::PostStep]
    }

    fn diagnostics(
        &mut self,
        _at: crate::control::interface::DiagnosticsAt,
        obs: &crate::control::interface::Observation,
        _act: &crate::control::interface::ActuationReport,
        out: &mut [f64],
    ) {
        let reference = obs.env.reference().unwrap_or_default();
        let o = observation(
            obs.t_s,
            reference,
            &obs.bodies[self.chaser],
            &obs.bodies[self.target],
        );
        let rel = relative_state(&self.controller.params, &o);
        let d = self.controller.diagnostics();
        let q = rel.q_r.imag();
        let vals = [
            rel.rho_m.x,
            rel.rho_m.y,
            rel.rho_m.z,
            rel.rho_dot_m_s.x,
            rel.rho_dot_m_s.y,
            rel.rho_dot_m_s.z,
            q.x,
            q.y,
            q.z,
            rel.omega_r_rad_s.x,
            rel.omega_r_rad_s.y,
            rel.omega_r_rad_s.z,
            rel.rho_m.norm(),
            d.s[0],
            d.s[1],
            d.s[2],
            d.s[3],
            d.s[4],
            d.s[5],
            d.u[0],
            d.u[1],
            d.u[2],
            d.u[3],
            d.u[4],
            d.u[5],
        ];
        out.copy_from_slice(&vals);
    }
}
