//! The Guo 2016 law in a scene: the entry `Guo2016((...))` ([`Guo2016Spec`], its
//! [`LawSpec`](crate::control::spec::LawSpec) implementation), the paper's disturbance torque
//! ([`Guo2016Disturbance`]), the corridor guarantee and the controller the generic host runs
//! ([`Guo2016Instance`]).

use super::*;

fn default_boundary_layer() -> f64 {
    1e-3
}
fn default_time_constants_s() -> Box<[f64; 3]> {
    Box::new([40.0, 50.0, 60.0])
}
fn default_corridor_guarantee() -> String {
    "guo2016_corridor".to_string()
}

/// How a scene asks for this law (`controllers: [Guo2016((chaser: "chaser", target: "target",
/// …))]`). The chaser's mass and inertia are taken from its body entry in the scene (the law
/// knows its own plant), everything else is here, in SI units.
///
/// Besides the law, the scene entry asks for the paper's disturbance torque
/// `d_τ = A·cos(n t)` (chaser body axes; Section 5: `A = [0.001, 0.002, 0.003]` N·m, `n` the
/// mean motion of the reference orbit) and names the corridor guarantee registered with the
/// monitor (margin: signed distance of the chaser centre of mass to the corridor wall, m).
///
/// (The 3-vectors are boxed only to keep [`crate::control::ControllerSpec`] small; in the
/// scene they are written as plain `(x, y, z)`.)
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Guo2016Spec {
    /// The body this law flies.
    pub chaser: String,
    /// The body whose frame carries the corridor and the docking axis (+x).
    pub target: String,
    /// `k1` of eq (32), 1/s.
    pub k1_per_s: f64,
    /// `k2` of eq (32), m⁴ (0 = no corridor term).
    pub k2_m4: f64,
    /// `k3` of eq (32), dimensionless.
    pub k3: f64,
    /// `k4` of eq (33), N (force rows) / N·m (torque rows).
    pub k4_n: f64,
    /// Boundary-layer width ε of the saturation replacing `sgn S` (default 1e-3).
    #[serde(default = "default_boundary_layer")]
    pub boundary_layer: f64,
    /// Linear reaching gain `k_r`, 1/s. **Not in the paper**; default 0 (the paper's law).
    #[serde(default)]
    pub reaching_gain_per_s: f64,
    /// Corridor semi-axis `a` (eq 31), m.
    pub corridor_a_m: f64,
    /// Corridor opening `tan θ`, dimensionless.
    pub corridor_tan_theta: f64,
    /// Desired target position relative to the chaser `r_d`, chaser body axes, m.
    pub r_d_body_m: Box<[f64; 3]>,
    /// Amplitudes of `σ_d,i(t) = A_i sin(t/T_i)` (MRP, dimensionless; default 0).
    #[serde(default)]
    pub sigma_d_amplitude: Box<[f64; 3]>,
    /// Time constants `T_i` of `σ_d(t)`, s (default 40, 50, 60 s).
    #[serde(default = "default_time_constants_s")]
    pub sigma_d_time_constant_s: Box<[f64; 3]>,
    /// Amplitudes of the disturbance torque `d_τ = A cos(n t)` on the chaser, chaser body
    /// axes, N·m (default 0: none).
    #[serde(default)]
    pub disturbance_torque_amplitude_nm: Box<[f64; 3]>,
    /// Angular frequency `n` of the disturbance, rad/s. Default: the mean motion of the
    /// reference orbit (orbit scenes), 0 otherwise.
    #[serde(default)]
    pub disturbance_rate_rad_s: Option<f64>,
    /// Name of the corridor guarantee registered with the monitor (default
    /// `guo2016_corridor`).
    #[serde(default = "default_corridor_guarantee")]
    pub corridor_guarantee: String,
}

impl Guo2016Spec {
    /// The Section 5 entry for chaser `chaser` and target `target`: the paper's gains and
    /// corridor (see [`Guo2016Params::paper`] for the choices), σ_d and d_τ of Section 5.
    pub fn paper(chaser: &str, target: &str) -> Self {
        let p = Guo2016Params::paper();
        Self {
            chaser: chaser.to_string(),
            target: target.to_string(),
            k1_per_s: p.k1_per_s,
            k2_m4: p.k2_m4,
            k3: p.k3,
            k4_n: p.k4_n,
            boundary_layer: p.boundary_layer,
            reaching_gain_per_s: p.reaching_gain_per_s,
            corridor_a_m: p.corridor_a_m,
            corridor_tan_theta: p.corridor_tan_theta,
            r_d_body_m: Box::new(p.r_d_body_m.into()),
            sigma_d_amplitude: Box::new(p.sigma_d_amplitude.into()),
            sigma_d_time_constant_s: Box::new(p.sigma_d_time_constant_s.into()),
            disturbance_torque_amplitude_nm: Box::new([1e-3, 2e-3, 3e-3]),
            disturbance_rate_rad_s: None,
            corridor_guarantee: default_corridor_guarantee(),
        }
    }

    /// Checks the numbers; on error returns `(field, message)` for a located scene error.
    pub fn validate(&self) -> Result<(), (&'static str, String)> {
        let finite3 = |v: &[f64; 3]| v.iter().all(|x| x.is_finite());
        let pos = |name: &'static str, v: f64, what: &str| {
            if v.is_finite() && v > 0.0 {
                Ok(())
            } else {
                Err((name, format!("must be a positive {what}, got {v}")))
            }
        };
        let nonneg = |name: &'static str, v: f64, what: &str| {
            if v.is_finite() && v >= 0.0 {
                Ok(())
            } else {
                Err((name, format!("must be a non-negative {what}, got {v}")))
            }
        };
        pos("k1_per_s", self.k1_per_s, "rate in 1/s")?;
        nonneg("k2_m4", self.k2_m4, "number (m⁴)")?;
        pos("k3", self.k3, "number")?;
        nonneg("k4_n", self.k4_n, "force in N")?;
        pos("boundary_layer", self.boundary_layer, "width")?;
        nonneg(
            "reaching_gain_per_s",
            self.reaching_gain_per_s,
            "rate in 1/s",
        )?;
        pos("corridor_a_m", self.corridor_a_m, "length in m")?;
        pos("corridor_tan_theta", self.corridor_tan_theta, "number")?;
        if !finite3(&self.r_d_body_m) {
            return Err(("r_d_body_m", "must be finite (m)".into()));
        }
        if !finite3(&self.sigma_d_amplitude) {
            return Err(("sigma_d_amplitude", "must be finite".into()));
        }
        for &t in self.sigma_d_time_constant_s.iter() {
            pos("sigma_d_time_constant_s", t, "time in s")?;
        }
        if !finite3(&self.disturbance_torque_amplitude_nm) {
            return Err((
                "disturbance_torque_amplitude_nm",
                "must be finite (N·m)".into(),
            ));
        }
        if let Some(n) = self.disturbance_rate_rad_s {
            nonneg("disturbance_rate_rad_s", n, "rate in rad/s")?;
        }
        Ok(())
    }

    /// The law's parameters for a chaser of `mass_kg` and inertia `inertia_body_kg_m2`
    /// (body axes, about the centre of mass).
    pub fn params(&self, mass_kg: f64, inertia_body_kg_m2: Matrix3<f64>) -> Guo2016Params {
        Guo2016Params {
            k1_per_s: self.k1_per_s,
            k2_m4: self.k2_m4,
            k3: self.k3,
            k4_n: self.k4_n,
            boundary_layer: self.boundary_layer,
            reaching_gain_per_s: self.reaching_gain_per_s,
            corridor_a_m: self.corridor_a_m,
            corridor_tan_theta: self.corridor_tan_theta,
            chaser_mass_kg: mass_kg,
            chaser_inertia_body_kg_m2: inertia_body_kg_m2,
            r_d_body_m: Vector3::from(*self.r_d_body_m),
            sigma_d_amplitude: Vector3::from(*self.sigma_d_amplitude),
            sigma_d_time_constant_s: Vector3::from(*self.sigma_d_time_constant_s),
        }
    }
}

// ---------------------------------------------------------------------------------------------
// The law in the simulation: the scene entry `Guo2016((...))`, the controller the generic host
// runs, the corridor guarantee and the paper's disturbance torque.
// ---------------------------------------------------------------------------------------------

/// Diagnostics columns written per controller (prefix `guo2016.`, or `guo2016_<i>.` for the
/// i-th controller after the first): corridor function `h_m2` and `h_dot_m2_s`, `inside`
/// (1/0), `beta`, `s_norm` (|S|, mixed units as in eq 32), `r_e_m` (|r_e|), `sigma_e` (|σ_e|),
/// `omega_e_rad_s` (|ω_e|), `corridor_margin_m` (signed distance to the wall) and the command
/// in chaser body axes.
pub const COLUMNS: [&str; 15] = [
    "h_m2",
    "h_dot_m2_s",
    "inside",
    "beta",
    "s_norm",
    "r_e_m",
    "sigma_e",
    "omega_e_rad_s",
    "corridor_margin_m",
    "force_body_x_n",
    "force_body_y_n",
    "force_body_z_n",
    "torque_body_x_nm",
    "torque_body_y_nm",
    "torque_body_z_nm",
];

/// One installed controller (what the generic host runs every step).
///
/// The observation is built from the f64 truth of the chaser and the target (relative
/// position and velocity in the world frame, both attitudes, body rates in body axes) and the
/// differential gravity `g(r_c) − g(r_t)` of the scene's gravity field (with J2 when the scene
/// enables it, so the law compensates the differential J2 instead of treating it as a
/// disturbance; at 40 m it is ~1e-8 m/s²). The law returns force and torque in chaser body
/// axes, held over the step.
#[derive(Debug, Clone)]
pub struct Guo2016Instance {
    /// The law (parameters from the scene, mass and inertia from the chaser body).
    pub law: Guo2016,
    /// Chaser body index (scene order).
    pub chaser: usize,
    /// Target body index.
    pub target: usize,
    /// Disturbance torque amplitudes, chaser body axes, N·m (applied by [`Guo2016Disturbance`]).
    pub disturbance_amplitude_nm: Vector3<f64>,
    /// Disturbance angular frequency, rad/s.
    pub disturbance_rate_rad_s: f64,
    /// Last observation handed to the law.
    pub observation: Option<Guo2016Observation>,
    /// Last command (chaser body axes).
    pub command: Guo2016Command,
    /// Last diagnostics.
    pub diagnostics: Option<Guo2016Diagnostics>,
    /// Signed distance of the chaser centre of mass to the corridor wall at the last control
    /// step, m (positive inside).
    pub corridor_margin_m: f64,
    prefix: String,
    corridor_guarantee: String,
}

/// The paper's disturbance torque `d_τ = A cos(n t)` on the chaser (body axes).
#[derive(Debug, Clone)]
pub struct Guo2016Disturbance {
    /// Chaser body index.
    pub chaser: usize,
    /// Amplitudes, chaser body axes, N·m.
    pub amplitude_nm: Vector3<f64>,
    /// Angular frequency, rad/s.
    pub rate_rad_s: f64,
    /// The torque applied at the last step, chaser body axes, N·m.
    pub last_body_nm: Vector3<f64>,
}

impl crate::control::spec::Disturbance for Guo2016Disturbance {
    fn wrenches(
        &mut self,
        ctx: &crate::control::spec::DisturbanceContext,
        out: &mut Vec<crate::control::spec::BodyWrench>,
    ) {
        let d = self.amplitude_nm * (self.rate_rad_s * ctx.t_s).cos();
        self.last_body_nm = d;
        out.push(crate::control::spec::BodyWrench {
            body: self.chaser,
            force_n: None,
            torque_nm: Some(ctx.bodies[self.chaser].att * d),
        });
    }
}

/// "The chaser's centre of mass stays inside the corridor": margin = signed distance of the
/// chaser centre of mass to the cissoid wall (target body frame), m.
#[derive(Debug, Clone)]
pub struct CorridorGuarantee {
    /// Name.
    pub name: String,
    /// Chaser body index.
    pub chaser: usize,
    /// Target body index.
    pub target: usize,
    /// The corridor.
    pub corridor: Cissoid,
}

impl CorridorGuarantee {
    /// Chaser centre of mass in target body axes, m.
    pub fn r1_target_m(&self, view: &crate::guarantee::MonitorView) -> Vector3<f64> {
        let c = &view.bodies[self.chaser];
        let t = &view.bodies[self.target];
        t.att.inverse() * (c.pos_m - t.pos_m)
    }
}

impl crate::guarantee::Guarantee for CorridorGuarantee {
    fn name(&self) -> &str {
        &self.name
    }
    fn margin(&self, view: &crate::guarantee::MonitorView) -> f64 {
        self.corridor.signed_distance_m(&self.r1_target_m(view))
    }
    /// A signed Euclidean distance is 1-Lipschitz in the point, and the chaser's centre of
    /// mass in target body axes moves at most at |v_c − v_t| + Ω_t·|r_c − r_t|
    /// ([`crate::guarantee::MotionBounds::rel_speed_in_body_bound`]): the corridor is judged
    /// between samples too (to the distance's numerical precision, ~1e-9 m).
    fn rate_bound(&self, m: &dyn crate::guarantee::MotionBounds) -> Option<f64> {
        Some(m.rel_speed_in_body_bound(self.chaser, self.target))
    }
    fn reads(&self) -> crate::guarantee::Reads {
        crate::guarantee::Reads::Bodies
    }
}

use crate::control::generic::mean_motion_rad_s;

impl crate::control::spec::LawSpec for Guo2016Spec {
    /// The cissoid approach corridor in the target's body frame, vertex at its centre of mass,
    /// axis +x, out to a radius of a (it is asymptotic to x = 2a); none without a corridor.
    fn drawn(&self, scene: &crate::scene::Scene) -> Vec<crate::geometry::drawn::DrawnSurface> {
        let Some(body) = scene.bodies.iter().position(|b| b.name == self.target) else {
            return Vec::new();
        };
        if self.corridor_a_m.is_nan() || self.corridor_a_m <= 0.0 {
            return Vec::new();
        }
        let cis =
            crate::geometry::cissoid::Cissoid::new(self.corridor_a_m, self.corridor_tan_theta);
        vec![crate::geometry::drawn::DrawnSurface::RevolutionAboutBody {
            legend: format!(
                "Guo2016 corridor (cyan): cissoid a {} m, tan θ {} about {}'s +x axis",
                self.corridor_a_m, self.corridor_tan_theta, self.target
            ),
            body,
            meridian_m: crate::geometry::drawn::meridian(
                |x| cis.radius_at_m(x),
                2.0 * cis.a_m,
                cis.a_m,
                96,
            ),
            rgba: [0.3, 0.85, 1.0, 0.12],
        }]
    }
    fn build(
        &self,
        ctx: &mut crate::control::spec::BuildContext,
    ) -> Result<crate::control::spec::Built, crate::control::spec::BuildError> {
        use crate::control::spec::{BuildError, Built, Slot};
        let chaser = ctx.body("0.chaser", &self.chaser)?;
        let target = ctx.body("0.target", &self.target)?;
        if chaser == target {
            return Err(BuildError::at(
                "0.target",
                "the target must be another body than the chaser",
            ));
        }
        self.validate()
            .map_err(|(field, msg)| BuildError::at(format!("0.{field}"), msg))?;
        let body = &ctx.scene.bodies[chaser];
        let params = self.params(body.mass_kg, body.inertia_kg_m2.matrix());
        let n = match self.disturbance_rate_rad_s {
            Some(n) => n,
            None => ctx
                .env
                .reference()
                .map(|(r, v)| mean_motion_rad_s(&r, &v))
                .unwrap_or(0.0),
        };
        let k = {
            let count = ctx.shared::<usize>("Guo2016");
            *count += 1;
            *count - 1
        };
        let prefix = if k == 0 {
            "guo2016".to_string()
        } else {
            format!("guo2016_{k}")
        };
        let amplitude = Vector3::from(*self.disturbance_torque_amplitude_nm);
        Ok(Built {
            slots: vec![Slot {
                kind: "Guo2016".into(),
                body: chaser,
                target: Some(target),
                period_steps: 1,
                sensor: None,
                actuator: crate::actuation::ActuatorSpec::Ideal,
                ports: None,
                law: Box::new(Guo2016Instance {
                    law: Guo2016::new(params),
                    chaser,
                    target,
                    disturbance_amplitude_nm: amplitude,
                    disturbance_rate_rad_s: n,
                    observation: None,
                    command: Guo2016Command {
                        force_body_n: Vector3::zeros(),
                        torque_body_nm: Vector3::zeros(),
                    },
                    diagnostics: None,
                    corridor_margin_m: f64::NAN,
                    prefix,
                    corridor_guarantee: self.corridor_guarantee.clone(),
                }),
            }],
            disturbances: vec![Box::new(Guo2016Disturbance {
                chaser,
                amplitude_nm: amplitude,
                rate_rad_s: n,
                last_body_nm: Vector3::zeros(),
            })],
        })
    }
}

impl crate::control::interface::Controller for Guo2016Instance {
    fn needs(&self) -> crate::control::interface::Needs {
        crate::control::interface::Needs {
            relative: false,
            ports: false,
            gravity: true,
        }
    }

    fn command(
        &mut self,
        obs: &crate::control::interface::Observation,
    ) -> crate::control::interface::Command {
        let (sc, st) = (&obs.bodies[self.chaser], &obs.bodies[self.target]);
        let o = Guo2016Observation {
            t_s: obs.t_s,
            q_chaser_body_to_world: sc.att,
            q_target_body_to_world: st.att,
            rate_chaser_body_rad_s: sc.rate_body_rad_s,
            rate_target_body_rad_s: st.rate_body_rad_s,
            pos_rel_world_m: sc.pos_m - st.pos_m,
            vel_rel_world_m_s: sc.vel_m_s - st.vel_m_s,
            grav_diff_world_m_s2: sc.gravity_m_s2 - st.gravity_m_s2,
        };
        let (cmd, d) = self.law.control(&o);
        self.corridor_margin_m = self.law.params.corridor().signed_distance_m(&d.r1_target_m);
        self.observation = Some(o);
        self.command = cmd;
        self.diagnostics = Some(d);
        crate::control::interface::Command::in_frame(
            crate::control::interface::Frame::Body,
            cmd.force_body_n,
            cmd.torque_body_nm,
        )
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
        _obs: &crate::control::interface::Observation,
        _act: &crate::control::interface::ActuationReport,
        out: &mut [f64],
    ) {
        let Some(d) = &self.diagnostics else {
            return;
        };
        let cmd = &self.command;
        let r_e = Vector3::new(d.x[3], d.x[4], d.x[5]).norm();
        let sigma_e = Vector3::new(d.x[0], d.x[1], d.x[2]).norm();
        let values = [
            d.h_m2,
            d.h_dot_m2_s,
            if d.inside { 1.0 } else { 0.0 },
            d.beta,
            d.s.norm(),
            r_e,
            sigma_e,
            d.omega_e_body_rad_s.norm(),
            self.corridor_margin_m,
            cmd.force_body_n.x,
            cmd.force_body_n.y,
            cmd.force_body_n.z,
            cmd.torque_body_nm.x,
            cmd.torque_body_nm.y,
            cmd.torque_body_nm.z,
        ];
        out.copy_from_slice(&values);
    }

    fn guarantees(&mut self) -> Vec<Box<dyn crate::guarantee::Guarantee>> {
        vec![Box::new(CorridorGuarantee {
            name: self.corridor_guarantee.clone(),
            chaser: self.chaser,
            target: self.target,
            corridor: self.law.params.corridor(),
        })]
    }
}
