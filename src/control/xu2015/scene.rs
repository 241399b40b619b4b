//! The Xu 2015 law in a scene: the entry `Xu2015((...))` ([`Xu2015Spec`], its
//! [`LawSpec`](crate::control::spec::LawSpec) implementation), the target manoeuvre
//! ([`Xu2015Maneuver`]), the measurement noise, the target orbital frame, the thrust-authority
//! margin and the controller the generic host runs ([`Xu2015Loop`]).

use super::*;

// ---------------------------------------------------------------------------------------------
// Scene wiring, Bevy-free part: what a scene asks for, the target maneuver, the measurement
// noise, the target orbital frame and the thrust-authority margin. The ECS systems that use
// them are in the controller further down.

/// Which of the paper's two controllers flies the chaser.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum Xu2015Law {
    /// Characteristic-model golden-section adaptive control ([`Accm`], params `accm`).
    Accm,
    /// The PD baseline ([`Pd`], params `pd`).
    Pd,
}

/// The target's maneuver force, per axis of the target orbital frame:
/// `F_t,i(t) = amplitude_n[i] · sin(omega_rad_s[i] · t + phase_rad[i])`, N, t in s from the
/// start of the run. Paper §3: amplitudes (10, 4, 8) N, ω = (0.08, 0.05, 0.1) rad/s,
/// φ = (π/6, π/4, π/2).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ManeuverSpec {
    /// Amplitudes, N (tof x, y, z).
    pub amplitude_n: [f64; 3],
    /// Angular frequencies, rad/s.
    pub omega_rad_s: [f64; 3],
    /// Phases at t = 0, rad.
    pub phase_rad: [f64; 3],
}

impl ManeuverSpec {
    /// The paper's maneuver (see the type's docs).
    pub fn paper() -> Self {
        use std::f64::consts::PI;
        Self {
            amplitude_n: [10.0, 4.0, 8.0],
            omega_rad_s: [0.08, 0.05, 0.1],
            phase_rad: [PI / 6.0, PI / 4.0, PI / 2.0],
        }
    }

    /// The force at time `t_s`, target orbital frame, N.
    pub fn force_tof_n(&self, t_s: f64) -> Vector3<f64> {
        Vector3::from_fn(|i, _| {
            self.amplitude_n[i] * (self.omega_rad_s[i] * t_s + self.phase_rad[i]).sin()
        })
    }

    /// Peak force per axis |amplitude|, N.
    pub fn peak_n(&self) -> Vector3<f64> {
        Vector3::from(self.amplitude_n).abs()
    }
}

impl Default for ManeuverSpec {
    fn default() -> Self {
        Self::paper()
    }
}

/// The relative-position measurement: sampled every `sample_period_s` of the flying law
/// (the sensor and the discrete controller share the paper's period h), with independent
/// zero-mean Gaussian noise of standard deviation `noise_sigma_m` per axis (target orbital
/// frame), drawn from a generator seeded with `seed` (same scene, same noise). Default: no
/// noise (the paper is silent on measurement noise).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SensorSpec {
    /// Noise standard deviation per axis, m (≥ 0).
    pub noise_sigma_m: f64,
    /// Seed of the noise generator.
    pub seed: u64,
}

impl Default for SensorSpec {
    fn default() -> Self {
        Self {
            noise_sigma_m: 0.0,
            seed: 1,
        }
    }
}

/// How a scene asks for this law (`controllers: [Xu2015((body: "chaser", target: "target",
/// law: Accm, ...))]`). The controlled relative position is, in the target orbital frame of
/// the reference orbit, ξ = C_tofᵀ (r_chaser − r_target) − `aim_offset_tof_m` (centres of
/// mass, world frame); see the controller below for the frame choice.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Xu2015Spec {
    /// The body this law flies (the chaser; the paper's 5 N per axis acts on it).
    pub body: String,
    /// The maneuvering target (its centre of mass is the origin of the relative position and
    /// it receives `target_maneuver`).
    pub target: String,
    /// Which controller.
    pub law: Xu2015Law,
    /// ACCM parameters (used when `law: Accm`; default [`AccmParams::paper`]; boxed to keep
    /// the scene's controller list compact).
    #[serde(default)]
    pub accm: Box<AccmParams>,
    /// PD parameters (used when `law: Pd`; default [`PdParams::paper`]).
    #[serde(default)]
    pub pd: Box<PdParams>,
    /// Measurement noise (sampled at the law's period).
    #[serde(default)]
    pub sensor: SensorSpec,
    /// The target's maneuver force, applied to the target body in the target orbital frame.
    #[serde(default)]
    pub target_maneuver: ManeuverSpec,
    /// The point, relative to the target's centre of mass in the target orbital frame, that the
    /// paper's relative-position origin is mapped to, m. Zero reproduces the paper's point-mass
    /// reading literally (the goal [−0.01, 0, 0] m would put the centres of mass 1 cm apart);
    /// a stand-off lets real spacecraft geometry end the run without overlapping.
    #[serde(default)]
    pub aim_offset_tof_m: [f64; 3],
    /// Register the per-axis thrust-authority margin with the monitor (default true).
    #[serde(default = "yes")]
    pub thrust_authority_guarantee: bool,
}

fn yes() -> bool {
    true
}

impl Xu2015Spec {
    /// Sample period of the flying law, s.
    pub fn sample_period_s(&self) -> f64 {
        match self.law {
            Xu2015Law::Accm => self.accm.sample_period_s,
            Xu2015Law::Pd => self.pd.sample_period_s,
        }
    }

    /// Per-axis thrust limit of the flying law, N.
    pub fn thrust_max_n(&self) -> f64 {
        match self.law {
            Xu2015Law::Accm => self.accm.thrust_max_n,
            Xu2015Law::Pd => self.pd.thrust_max_n,
        }
    }

    /// Field (relative to the spec) holding the flying law's sample period.
    pub fn sample_period_field(&self) -> &'static str {
        match self.law {
            Xu2015Law::Accm => "accm.sample_period_s",
            Xu2015Law::Pd => "pd.sample_period_s",
        }
    }

    /// Physical checks; on failure the field path (relative to the spec) and the message.
    pub fn validate(&self) -> Result<(), (String, String)> {
        let bad = |f: &str, m: String| Err((f.to_string(), m));
        let pos = |v: f64| v.is_finite() && v > 0.0;
        let a = &self.accm;
        let checks: [(&str, f64); 6] = [
            ("accm.sample_period_s", a.sample_period_s),
            ("accm.mass_nominal_kg", a.mass_nominal_kg),
            ("accm.thrust_max_n", a.thrust_max_n),
            ("accm.reference_duration_s", a.reference_duration_s),
            ("accm.eta_m", a.eta_m),
            ("accm.lambda2_m2", a.lambda2_m2),
        ];
        for (f, v) in checks {
            if !pos(v) {
                return bad(f, format!("must be a positive number, got {v}"));
            }
        }
        if a.shift_m.is_nan() || a.shift_m <= a.eta_m {
            return bad(
                "accm.shift_m",
                format!(
                    "the shift d must exceed η = {} m (so y = ξ + d stays away from zero), got {}",
                    a.eta_m, a.shift_m
                ),
            );
        }
        if !(a.lambda1 > 0.0 && a.lambda1 < 2.0) {
            return bad(
                "accm.lambda1",
                format!(
                    "must lie in (0, 2) for a stable gradient update, got {}",
                    a.lambda1
                ),
            );
        }
        for (f, b) in [
            ("accm.alpha1_bounds", a.alpha1_bounds),
            ("accm.alpha2_bounds", a.alpha2_bounds),
            ("accm.gamma_bounds", a.gamma_bounds),
        ] {
            if b[0].is_nan() || b[1].is_nan() || b[0] > b[1] {
                return bad(
                    f,
                    format!("must be (lower, upper) with lower ≤ upper, got {b:?}"),
                );
            }
        }
        if a.lambda_ctrl_rel.is_nan() || a.lambda_ctrl_rel < 0.0 {
            return bad(
                "accm.lambda_ctrl_rel",
                format!("must be ≥ 0, got {}", a.lambda_ctrl_rel),
            );
        }
        if a.gamma_bounds[0] + a.lambda_ctrl_rel <= 0.0 {
            return bad(
                "accm.gamma_bounds",
                "γ_min + λ must be positive (the control divides by β̂ + λ)".into(),
            );
        }
        let p = &self.pd;
        let checks: [(&str, f64); 4] = [
            ("pd.sample_period_s", p.sample_period_s),
            ("pd.mass_nominal_kg", p.mass_nominal_kg),
            ("pd.thrust_max_n", p.thrust_max_n),
            ("pd.reference_duration_s", p.reference_duration_s),
        ];
        for (f, v) in checks {
            if !pos(v) {
                return bad(f, format!("must be a positive number, got {v}"));
            }
        }
        for (f, v) in [("pd.kp_s2", p.kp_s2), ("pd.kd_s", p.kd_s)] {
            if !(v.is_finite() && v >= 0.0) {
                return bad(f, format!("must be a non-negative gain, got {v}"));
            }
        }
        if !(self.sensor.noise_sigma_m.is_finite() && self.sensor.noise_sigma_m >= 0.0) {
            return bad(
                "sensor.noise_sigma_m",
                format!(
                    "must be a non-negative standard deviation in metres, got {}",
                    self.sensor.noise_sigma_m
                ),
            );
        }
        let m = &self.target_maneuver;
        for i in 0..3 {
            if !(m.amplitude_n[i].is_finite()
                && m.omega_rad_s[i].is_finite()
                && m.phase_rad[i].is_finite())
            {
                return bad("target_maneuver", "every component must be finite".into());
            }
        }
        if self.aim_offset_tof_m.iter().any(|v| !v.is_finite()) {
            return bad("aim_offset_tof_m", "must be finite".into());
        }
        Ok(())
    }
}

/// The target orbital frame of an orbit state (paper's o-frame, see `crate::orbit::elliptic`):
/// columns are its axes in ECI, x = y × z (in-plane transverse), y = −ĥ (−orbit normal),
/// z = −r̂ (to Earth's centre). `r_eci_m`, `v_eci_m_s`: the orbit's position and velocity.
pub fn dcm_eci_from_tof_state(r_eci_m: &Vector3<f64>, v_eci_m_s: &Vector3<f64>) -> Matrix3<f64> {
    let z = -r_eci_m.normalize();
    let y = -r_eci_m.cross(v_eci_m_s).normalize();
    let x = y.cross(&z);
    Matrix3::from_columns(&[x, y, z])
}

/// Thrust-authority margin per axis at time `t_s`, m/s²: the chaser's maximum acceleration
/// `thrust_max_n / mass_chaser_kg` less the target's maneuver acceleration
/// |F_t,i(t)| / `mass_target_kg`. Negative: on that axis the chaser cannot match the target's
/// acceleration at that instant (it falls behind whatever the control law).
pub fn thrust_authority_margin_m_s2(
    thrust_max_n: f64,
    mass_chaser_kg: f64,
    maneuver: &ManeuverSpec,
    mass_target_kg: f64,
    t_s: f64,
) -> Vector3<f64> {
    let a_max = thrust_max_n / mass_chaser_kg;
    maneuver
        .force_tof_n(t_s)
        .map(|f| a_max - f.abs() / mass_target_kg)
}

pub use crate::math::rng::GaussianNoise;

// ---------------------------------------------------------------------------------------------
// The law in the simulation: the scene entry `Xu2015((...))`, the controller the generic host
// runs, the target's manoeuvre and the thrust-authority guarantees.
//
// # Frames (the choice the paper leaves open)
// The world frame is inertial with its origin on the reference orbit, which the scene makes the
// target's *unforced* orbit. The controller works in the **target orbital frame (tof) of the
// reference orbit**, built every step from the reference state (r, v) by
// [`dcm_eci_from_tof_state`]: z = −r̂, y = −ĥ, x = y × z — the paper's model (its relative
// dynamics use R, ḟ, f̈ of the target's Keplerian orbit and treat the manoeuvre as a
// disturbance). The manoeuvring target's own osculating frame differs from it by the tilt its
// manoeuvre velocity (≈ 0.6 m/s against ≈ 3.5 km/s) and its ≈ 190 m drift give the orbit:
// 2.9e−4 rad after 300 s (measured by `rpod reproduce xu2015`), i.e. 9e−4 m on the 3 m
// stand-off of the bundled scenes.
//
// # What runs each step (dt = scene `dt_s`, h = the law's `sample_period_s`, h/dt integer)
// The host calls the controller every step: ξ = Cᵀ (r_chaser − r_target) − aim_offset (f64
// truth, centres of mass); at every multiple of h a measurement ξ + N(0, σ²) is taken (seeded
// noise) and the law runs once ([`Accm::update`] / [`Pd::update`]); between samples its tof
// command is held (zero-order hold over h, as in the paper) and returned in world axes with
// this step's C. The target's manoeuvre F_t(t + dt/2) ([`Xu2015Maneuver`]) is applied at its
// mid-step value (midpoint rule: the held force then carries the step's impulse to O(dt³)).
// Over a step the tof turns by ḟ dt ≤ 1.6e−4 rad at perigee, a thrust-direction error below
// 4e−4 N.
//
// # Outputs
// Columns (prefix `xu2015.`; `xu2015_N.` for the N-th controller after the first):
// `xi_tof_{x,y,z}_m` (true ξ at the row's time), `meas_tof_{x,y,z}_m` (last measurement),
// `ref_tof_{x,y,z}_m` (reference at that sample), `thrust_tof_{x,y,z}_n` (the command held over
// the step that ends at the row's time; the t = 0 row has no measurement yet: NaN),
// `target_force_tof_{x,y,z}_n`, and for ACCM the identified `alpha1_{x,y,z}`, `alpha2_{x,y,z}`,
// `gamma_{x,y,z}` (dimensionless) and `shift_{x,y,z}_m`. The per-sample history is kept in
// [`Xu2015Loop::history`] for tests and `rpod reproduce`.
// ---------------------------------------------------------------------------------------------

/// The running controller.
#[derive(Debug, Clone)]
pub enum LawState {
    /// Adaptive characteristic-model controller.
    Accm(Box<Accm>),
    /// PD baseline.
    Pd(Box<Pd>),
}

/// What one control sample saw and did.
#[derive(Debug, Clone, Copy)]
pub struct Xu2015Sample {
    /// Sample time, s.
    pub t_s: f64,
    /// True controlled relative position ξ, tof, m.
    pub xi_tof_m: Vector3<f64>,
    /// Measured ξ (truth + noise), tof, m.
    pub meas_tof_m: Vector3<f64>,
    /// Reference ξ_r, tof, m.
    pub reference_tof_m: Vector3<f64>,
    /// Commanded (saturated, then held over h) thrust, tof, N.
    pub thrust_tof_n: Vector3<f64>,
    /// Target maneuver force at the sample time, tof, N.
    pub target_force_tof_n: Vector3<f64>,
    /// ACCM estimates after this sample (None for PD).
    pub estimates: Option<[AccmAxisEstimate; 3]>,
}

/// One xu2015 controller of the scene and its sensor.
#[derive(Debug, Clone)]
pub struct Xu2015Loop {
    /// Column prefix (`xu2015` or `xu2015_N`).
    pub prefix: String,
    /// The scene's spec.
    pub spec: Xu2015Spec,
    /// Chaser body index (scene order).
    pub chaser: usize,
    /// Target body index.
    pub target: usize,
    /// The law.
    pub law: LawState,
    /// Simulation steps per control sample (h / dt).
    pub steps_per_sample: u64,
    /// tof → world DCM at the current step.
    pub dcm_world_from_tof: Matrix3<f64>,
    /// True ξ at the current step, tof, m.
    pub xi_tof_m: Vector3<f64>,
    /// Last measurement, tof, m.
    pub meas_tof_m: Vector3<f64>,
    /// Held command, tof, N.
    pub thrust_tof_n: Vector3<f64>,
    /// One entry per control sample.
    pub history: Vec<Xu2015Sample>,
    noise: GaussianNoise,
    mass_chaser_kg: f64,
    mass_target_kg: f64,
}

/// The target's manoeuvre F_t(t + dt/2), tof of the reference orbit at the step's start.
#[derive(Debug, Clone)]
pub struct Xu2015Maneuver {
    /// Target body index.
    pub target: usize,
    /// The manoeuvre.
    pub maneuver: ManeuverSpec,
}

impl crate::control::spec::Disturbance for Xu2015Maneuver {
    fn wrenches(
        &mut self,
        ctx: &crate::control::spec::DisturbanceContext,
        out: &mut Vec<crate::control::spec::BodyWrench>,
    ) {
        let Some((r, v)) = ctx.env.reference() else {
            return;
        };
        let c = dcm_eci_from_tof_state(&r, &v);
        let f_t = self.maneuver.force_tof_n(ctx.t_s + 0.5 * ctx.dt_s);
        out.push(crate::control::spec::BodyWrench {
            body: self.target,
            force_n: Some(c * f_t),
            torque_nm: None,
        });
    }
}

/// `thrust_authority_{axis}`: F_max/m_c − |F_t,axis(t)|/m_t, m/s²: the chaser's per-axis
/// acceleration authority against the target's maneuver acceleration at that time (masses from
/// the scene). A negative margin means no control law can keep the relative position constant
/// on that axis at that instant.
#[derive(Debug, Clone)]
pub struct ThrustAuthority {
    /// Guarantee name.
    pub name: String,
    /// Axis of the tof (0 = x, 1 = y, 2 = z).
    pub axis: usize,
    /// Per-axis thrust limit, N.
    pub thrust_max_n: f64,
    /// Chaser mass, kg.
    pub mass_chaser_kg: f64,
    /// Target mass, kg.
    pub mass_target_kg: f64,
    /// The target's maneuver.
    pub maneuver: ManeuverSpec,
}

impl crate::guarantee::Guarantee for ThrustAuthority {
    fn name(&self) -> &str {
        &self.name
    }
    fn unit(&self) -> &str {
        "m_s2"
    }
    fn margin(&self, view: &crate::guarantee::MonitorView) -> f64 {
        thrust_authority_margin_m_s2(
            self.thrust_max_n,
            self.mass_chaser_kg,
            &self.maneuver,
            self.mass_target_kg,
            view.t_s,
        )[self.axis]
    }
    /// The margin a − |A sin(ωt + φ)|/m_t changes at most at |A ω|/m_t (a function of time
    /// only): judged between samples too.
    fn rate_bound(&self, _m: &dyn crate::guarantee::MotionBounds) -> Option<f64> {
        let i = self.axis;
        Some(
            (self.maneuver.amplitude_n[i] * self.maneuver.omega_rad_s[i]).abs()
                / self.mass_target_kg,
        )
    }
    fn reads(&self) -> crate::guarantee::Reads {
        crate::guarantee::Reads::Bodies
    }
}

const AXES: [&str; 3] = ["x", "y", "z"];

/// Instances of the law so far in the scene being built.
#[derive(Default)]
struct Xu2015Count(usize);

impl crate::control::spec::LawSpec for Xu2015Spec {
    fn build(
        &self,
        ctx: &mut crate::control::spec::BuildContext,
    ) -> Result<crate::control::spec::Built, crate::control::spec::BuildError> {
        use crate::control::spec::{BuildError, Built, Slot};
        let spec = self;
        // The spec sits inside the `Xu2015(( … ))` newtype: its fields are at `0.field`.
        let chaser = ctx.body("0.body", &spec.body)?;
        let target = ctx.body("0.target", &spec.target)?;
        if chaser == target {
            return Err(BuildError::at(
                "0.target",
                "the target must be another body than the chaser",
            ));
        }
        if !matches!(
            ctx.scene.environment,
            crate::scene::Environment::Orbit { .. }
        ) {
            return Err(BuildError::at_root(
                "environment",
                "the xu2015 controller needs an `Orbit` environment (it works in the reference \
                 orbit's target orbital frame)",
            ));
        }
        spec.validate()
            .map_err(|(f, m)| BuildError::at(format!("0.{f}"), m))?;
        let dt = ctx.dt_s();
        let h = spec.sample_period_s();
        let ratio = h / dt;
        let n = ratio.round();
        if !(1.0..=1e12).contains(&n) || (ratio - n).abs() > 1e-9 * ratio {
            return Err(BuildError::at(
                format!("0.{}", spec.sample_period_field()),
                format!(
                    "the sample period must be a whole multiple of the scene step dt_s = {dt} s, \
                     got {h} s"
                ),
            ));
        }
        let law = match spec.law {
            Xu2015Law::Accm => LawState::Accm(Box::new(Accm::new((*spec.accm).clone()))),
            Xu2015Law::Pd => LawState::Pd(Box::new(Pd::new((*spec.pd).clone()))),
        };
        let idx = {
            let c = ctx.shared::<Xu2015Count>("Xu2015");
            c.0 += 1;
            c.0 - 1
        };
        let prefix = if idx == 0 {
            "xu2015".to_string()
        } else {
            format!("xu2015_{idx}")
        };
        Ok(Built {
            slots: vec![Slot {
                kind: "Xu2015".into(),
                body: chaser,
                target: Some(target),
                period_steps: 1,
                sensor: None,
                actuator: crate::actuation::ActuatorSpec::Ideal,
                ports: None,
                law: Box::new(Xu2015Loop {
                    prefix,
                    spec: spec.clone(),
                    chaser,
                    target,
                    law,
                    steps_per_sample: n as u64,
                    dcm_world_from_tof: Matrix3::identity(),
                    xi_tof_m: Vector3::zeros(),
                    meas_tof_m: Vector3::zeros(),
                    thrust_tof_n: Vector3::zeros(),
                    history: Vec::new(),
                    noise: GaussianNoise::new(spec.sensor.seed),
                    mass_chaser_kg: ctx.scene.bodies[chaser].mass_kg,
                    mass_target_kg: ctx.scene.bodies[target].mass_kg,
                }),
            }],
            disturbances: vec![Box::new(Xu2015Maneuver {
                target,
                maneuver: spec.target_maneuver.clone(),
            })],
        })
    }
}

impl Xu2015Loop {
    /// Index of this controller among the scene's xu2015 controllers (from its prefix).
    fn index(&self) -> usize {
        self.prefix
            .strip_prefix("xu2015_")
            .and_then(|s| s.parse().ok())
            .unwrap_or(0)
    }

    /// ξ from the observation's truth, tof, m, and the tof → world DCM.
    fn xi(&self, obs: &crate::control::interface::Observation) -> (Matrix3<f64>, Vector3<f64>) {
        let (r, v) = obs.env.reference().unwrap_or_default();
        let c = dcm_eci_from_tof_state(&r, &v);
        let (sc, st) = (&obs.bodies[self.chaser], &obs.bodies[self.target]);
        let xi = c.transpose() * (sc.pos_m - st.pos_m) - Vector3::from(self.spec.aim_offset_tof_m);
        (c, xi)
    }
}

impl crate::control::interface::Controller for Xu2015Loop {
    fn needs(&self) -> crate::control::interface::Needs {
        crate::control::interface::Needs::NONE
    }

    fn command(
        &mut self,
        obs: &crate::control::interface::Observation,
    ) -> crate::control::interface::Command {
        let (c, xi) = self.xi(obs);
        self.dcm_world_from_tof = c;
        self.xi_tof_m = xi;
        if obs.step.is_multiple_of(self.steps_per_sample) {
            let sigma = self.spec.sensor.noise_sigma_m;
            let noise = if sigma > 0.0 {
                Vector3::from_fn(|_, _| sigma * self.noise.standard_normal())
            } else {
                Vector3::zeros()
            };
            self.meas_tof_m = xi + noise;
            let t = obs.t_s;
            let o = Xu2015Observation {
                t_s: t,
                pos_tof_m: self.meas_tof_m,
            };
            let (u, reference, estimates) = match &mut self.law {
                LawState::Accm(a) => {
                    let u = a.update(&o).force_tof_n;
                    (u, a.reference_tof_m(t), Some(a.estimates()))
                }
                LawState::Pd(p) => {
                    let u = p.update(&o).force_tof_n;
                    (u, p.reference_tof_m(t), None)
                }
            };
            self.thrust_tof_n = u;
            self.history.push(Xu2015Sample {
                t_s: t,
                xi_tof_m: xi,
                meas_tof_m: self.meas_tof_m,
                reference_tof_m: reference.unwrap_or(self.meas_tof_m),
                thrust_tof_n: u,
                target_force_tof_n: self.spec.target_maneuver.force_tof_n(t),
                estimates,
            });
        }
        crate::control::interface::Command::in_frame(
            crate::control::interface::Frame::World,
            c * self.thrust_tof_n,
            Vector3::zeros(),
        )
    }

    fn columns(&self) -> Vec<String> {
        let prefix = &self.prefix;
        let mut names: Vec<String> = Vec::new();
        for q in ["xi_tof", "meas_tof", "ref_tof"] {
            for a in AXES {
                names.push(format!("{prefix}.{q}_{a}_m"));
            }
        }
        for q in ["thrust_tof", "target_force_tof"] {
            for a in AXES {
                names.push(format!("{prefix}.{q}_{a}_n"));
            }
        }
        if self.spec.law == Xu2015Law::Accm {
            for q in ["alpha1", "alpha2", "gamma"] {
                for a in AXES {
                    names.push(format!("{prefix}.{q}_{a}"));
                }
            }
            for a in AXES {
                names.push(format!("{prefix}.shift_{a}_m"));
            }
        }
        names
    }

    fn diagnostics_at(&self) -> &'static [crate::control::interface::DiagnosticsAt] {
        use crate::control::interface::DiagnosticsAt;
        &[
            DiagnosticsAt::Start,
            DiagnosticsAt::Actuated,
            DiagnosticsAt::PostStep,
        ]
    }

    fn diagnostics(
        &mut self,
        at: crate::control::interface::DiagnosticsAt,
        obs: &crate::control::interface::Observation,
        _act: &crate::control::interface::ActuationReport,
        out: &mut [f64],
    ) {
        use crate::control::interface::DiagnosticsAt;
        match at {
            // The t = 0 row is written before the first step: the true ξ, zero thrust, the
            // maneuver at t = 0 and the initial estimates (no measurement or reference exists
            // yet: NaN).
            DiagnosticsAt::Start => {
                let (_, xi0) = self.xi(obs);
                let mut vals: Vec<f64> = xi0.iter().copied().collect();
                vals.extend([f64::NAN; 6]);
                vals.extend([0.0; 3]);
                vals.extend(self.spec.target_maneuver.force_tof_n(0.0).iter());
                if self.spec.law == Xu2015Law::Accm {
                    for j in 0..3 {
                        vals.extend([self.spec.accm.theta0[j]; 3]);
                    }
                    vals.extend([0.0; 3]);
                }
                out.copy_from_slice(&vals);
            }
            DiagnosticsAt::Actuated => {
                let f_t = self
                    .spec
                    .target_maneuver
                    .force_tof_n(obs.t_s + 0.5 * obs.dt_s);
                let reference = self
                    .history
                    .last()
                    .map_or(self.xi_tof_m, |s| s.reference_tof_m);
                for (k, v) in [
                    self.xi_tof_m,
                    self.meas_tof_m,
                    reference,
                    self.thrust_tof_n,
                    f_t,
                ]
                .iter()
                .enumerate()
                {
                    out[3 * k..3 * k + 3].copy_from_slice(v.as_slice());
                }
                if let LawState::Accm(a) = &self.law {
                    let e = a.estimates();
                    for j in 0..3 {
                        out[15 + j] = e[j].alpha1;
                        out[18 + j] = e[j].alpha2;
                        out[21 + j] = e[j].gamma;
                        out[24 + j] = e[j].shift_m;
                    }
                }
            }
            // The ξ columns at the end of the step (the row's time), after the physics.
            DiagnosticsAt::PostStep => {
                let (_, xi) = self.xi(obs);
                out[..3].copy_from_slice(xi.as_slice());
            }
        }
    }

    fn guarantees(&mut self) -> Vec<Box<dyn crate::guarantee::Guarantee>> {
        if !self.spec.thrust_authority_guarantee {
            return Vec::new();
        }
        let idx = self.index();
        let maneuver = self.spec.target_maneuver.clone();
        let thrust_max_n = self.spec.thrust_max_n();
        AXES.iter()
            .enumerate()
            .map(|(axis, a)| {
                let name = if idx == 0 {
                    format!("thrust_authority_{a}")
                } else {
                    format!("thrust_authority_{idx}_{a}")
                };
                Box::new(ThrustAuthority {
                    name,
                    axis,
                    thrust_max_n,
                    mass_chaser_kg: self.mass_chaser_kg,
                    mass_target_kg: self.mass_target_kg,
                    maneuver: maneuver.clone(),
                }) as Box<dyn crate::guarantee::Guarantee>
            })
            .collect()
    }
}
