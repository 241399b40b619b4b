//! The Zhang 2018 law in a scene: the entry `Zhang2018((...))` ([`Zhang2018Spec`], its
//! [`LawSpec`](crate::control::spec::LawSpec) implementation), the capture-distance guarantee
//! ([`CaptureDistance`]) and the controller the generic host runs ([`LawState`]).

use super::*;

/// One segment of a planned maneuver as written in a scene: thrust on from `t_start_s` to
/// `t_end_s` in the direction `dir_deg` (angle from +X of the rotating frame `rot`, towards +Y).
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PlanSegmentSpec {
    /// Start time, s.
    pub t_start_s: f64,
    /// End time (exclusive), s.
    pub t_end_s: f64,
    /// Thrust direction in `rot`, deg.
    pub dir_deg: f64,
}

/// How a scene asks for this law: one entry per spacecraft that flies a planned maneuver with a
/// thrust of fixed magnitude and, if `avoid`, switches to the barrier-based evasive direction
/// ([`AvoidanceController`]) against every other body of the scene. Needs the `SunEarthL2`
/// environment. The first zhang2018 controller of a scene registers the capture guarantee
/// `capture.A.B` (centre-of-mass separation ≥ l, margin in m) for every body pair.
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Zhang2018Spec {
    /// The body this law flies.
    pub body: String,
    /// Thrust magnitude F, N (fixed; the paper gives none, [`Zhang2018Params::paper`] uses 1 N).
    pub thrust_n: f64,
    /// Planned maneuver (thrust off outside the segments); directions in `rot`.
    #[serde(default)]
    pub plan: Vec<PlanSegmentSpec>,
    /// Fly the avoidance law (the body is an evader against every other body).
    #[serde(default)]
    pub avoid: bool,
    /// Capture (critical) distance l, m.
    pub capture_radius_m: f64,
    /// Avoidance margin: the law engages when the barrier function (miss − l) falls below it, m.
    #[serde(default = "default_margin_m")]
    pub avoidance_margin_m: f64,
}

fn default_margin_m() -> f64 {
    1000.0
}

impl Zhang2018Spec {
    /// The plan as a [`PlannedManeuver`] (directions in rad).
    pub fn planned_maneuver(&self) -> PlannedManeuver {
        PlannedManeuver {
            segments: self
                .plan
                .iter()
                .map(|s| ThrustSegment {
                    t_start_s: s.t_start_s,
                    t_end_s: s.t_end_s,
                    dir_rad: s.dir_deg.to_radians(),
                })
                .collect(),
        }
    }

    /// Checks the numbers; on failure returns `(field, message)` (field relative to the spec).
    pub fn validate(&self) -> Result<(), (String, String)> {
        let pos = |f: &str, v: f64, unit: &str| {
            if v.is_finite() && v > 0.0 {
                Ok(())
            } else {
                Err((
                    f.to_string(),
                    format!("must be a positive number of {unit}, got {v}"),
                ))
            }
        };
        pos("thrust_n", self.thrust_n, "newtons")?;
        pos("capture_radius_m", self.capture_radius_m, "metres")?;
        if !(self.avoidance_margin_m.is_finite() && self.avoidance_margin_m >= 0.0) {
            return Err((
                "avoidance_margin_m".into(),
                format!("must be ≥ 0 m, got {}", self.avoidance_margin_m),
            ));
        }
        let mut last_end = f64::NEG_INFINITY;
        for (k, seg) in self.plan.iter().enumerate() {
            let ok = seg.t_start_s.is_finite()
                && seg.t_end_s.is_finite()
                && seg.dir_deg.is_finite()
                && seg.t_start_s >= 0.0
                && seg.t_end_s > seg.t_start_s;
            if !ok {
                return Err((
                    format!("plan.{k}"),
                    "a segment needs finite numbers with 0 ≤ t_start_s < t_end_s".into(),
                ));
            }
            if seg.t_start_s < last_end {
                return Err((
                    format!("plan.{k}.t_start_s"),
                    "segments must be in time order and must not overlap".into(),
                ));
            }
            last_end = seg.t_end_s;
        }
        Ok(())
    }
}

// ---------------------------------------------------------------------------------------------
// The law in the simulation (environment `SunEarthL2`, see `crate::sim::environment`): the
// scene entry `Zhang2018((...))`, the controller the generic host runs and the capture-distance
// guarantee.
//
// Every step each controlled spacecraft converts every body's world state into the paper's
// rotating frame `rot` (through the formation centre the host's observation carries),
// evaluates its plan and, if `avoid`, one [`AvoidanceController`] per other body (that body as
// the pursuer P, itself as the evader E): when one or more are engaged, the one with the
// smallest barrier function (miss − l) gives the direction u* of eq (8). The command is
// F·(the direction rotated to the world axes), held over the step. Columns per controlled
// body: `zhang2018.NAME.barrier_m` (smallest miss − l over the other bodies),
// `zhang2018.NAME.engaged` (0/1), `zhang2018.NAME.thrust_dir_rot_deg` (NaN when off),
// `zhang2018.NAME.h_eq12_m_s2` (eq (12) as printed, the cooperative value, against the nearest
// body; mixed m/s + m/s² units read with the paper's implicit 1 s time scale).
//
// Precision at L2 scales: the core keeps an f64 state per body and only writes poses into
// rapier, whose f32 positions resolve ulp(1000 km) = 0.0625 m, immaterial to a capture radius
// of 5 km; the monitor forms relative poses in f64. The rotating-frame states the law needs
// are formed as centre (f64, ~1.5·10¹¹ m, ulp 3·10⁻⁵ m) plus the relative state rotated by
// −n t, so relative positions keep ~10⁻⁵ m. The guarantee that matters here is
// [`CaptureDistance`] on centre-of-mass separation.
// ---------------------------------------------------------------------------------------------

/// Capture-distance guarantee: centre-of-mass separation of two bodies ≥ l
/// (margin = |r_a − r_b| − l, m).
#[derive(Debug, Clone)]
pub struct CaptureDistance {
    /// Name (`capture.A.B`).
    pub name: String,
    /// First body index.
    pub a: usize,
    /// Second body index.
    pub b: usize,
    /// Capture distance l, m.
    pub capture_radius_m: f64,
}

impl crate::guarantee::Guarantee for CaptureDistance {
    fn name(&self) -> &str {
        &self.name
    }
    fn margin(&self, v: &crate::guarantee::MonitorView) -> f64 {
        (v.bodies[self.a].pos_m - v.bodies[self.b].pos_m).norm() - self.capture_radius_m
    }
    /// |r_a − r_b| changes at most at |v_a − v_b| (judged between samples too).
    fn rate_bound(&self, m: &dyn crate::guarantee::MotionBounds) -> Option<f64> {
        Some(m.rel_speed_bound(self.a, self.b))
    }
    fn reads(&self) -> crate::guarantee::Reads {
        crate::guarantee::Reads::Bodies
    }
}

/// One controlled spacecraft.
#[derive(Debug, Clone)]
pub struct LawState {
    /// Body index (scene order).
    pub body: usize,
    /// Thrust magnitude, N.
    pub thrust_n: f64,
    /// Planned maneuver (directions in `rot`).
    pub plan: PlannedManeuver,
    /// Avoidance on.
    pub avoid: bool,
    /// One avoidance controller per other body (index, controller).
    pub threats: Vec<(usize, AvoidanceController)>,
    /// Game parameters (this body as E; P's thrust taken equal to E's: the equal-F/M game).
    pub params: Zhang2018Params,
    /// This step's thrust direction in `rot` (None: off), rad.
    pub dir_rot_rad: Option<f64>,
    /// Diagnostics of the last call: barrier, engaged, direction (deg), H of eq (12).
    pub last: [f64; 4],
    /// The capture guarantees of every body pair (registered by the scene's first
    /// zhang2018 controller).
    capture: Vec<CaptureDistance>,
    name: String,
}

/// What the scene's zhang2018 entries share while they are built.
#[derive(Default)]
struct Zhang2018Shared {
    capture_radius_m: Option<f64>,
    bodies: Vec<usize>,
}

fn game_state(states: &[L2State], p: usize, e: usize) -> GameState {
    let mut x = GameState::zeros();
    x.fixed_rows_mut::<4>(0).copy_from(&states[p]);
    x.fixed_rows_mut::<4>(4).copy_from(&states[e]);
    x
}

impl crate::control::spec::LawSpec for Zhang2018Spec {
    /// The capture sphere of radius l about every body's centre of mass (the law's capture
    /// guarantee is |r_a − r_b| ≥ l for every pair).
    fn drawn(&self, scene: &crate::scene::Scene) -> Vec<crate::geometry::drawn::DrawnSurface> {
        scene
            .bodies
            .iter()
            .enumerate()
            .map(
                |(i, b)| crate::geometry::drawn::DrawnSurface::SphereAboutBody {
                    legend: format!(
                        "Zhang2018 capture sphere (red): l = {} m about {}",
                        self.capture_radius_m, b.name
                    ),
                    body: i,
                    radius_m: self.capture_radius_m,
                    rgba: [1.0, 0.2, 0.2, 0.12],
                },
            )
            .collect()
    }
    fn build(
        &self,
        ctx: &mut crate::control::spec::BuildContext,
    ) -> Result<crate::control::spec::Built, crate::control::spec::BuildError> {
        use crate::control::spec::{BuildError, Built, Slot};
        let spec = self;
        // The spec is the newtype content of `Zhang2018((...))`: its fields are under `0.`.
        let body = ctx.body("0.body", &spec.body)?;
        spec.validate()
            .map_err(|(f, m)| BuildError::at(format!("0.{f}"), m))?;
        let crate::scene::Environment::SunEarthL2(env) = &ctx.scene.environment else {
            return Err(BuildError::at(
                "",
                "the zhang2018 controller needs `environment: SunEarthL2(...)`",
            ));
        };
        let model = env.model.clone();
        let names: Vec<String> = ctx.info.iter().map(|b| b.name.clone()).collect();
        let n_bodies = names.len();
        let shared = ctx.shared::<Zhang2018Shared>("Zhang2018");
        let first = shared.capture_radius_m.is_none();
        if let Some(l) = shared.capture_radius_m
            && l != spec.capture_radius_m
        {
            return Err(BuildError::at(
                "0.capture_radius_m",
                format!(
                    "all zhang2018 controllers of a scene share one capture radius ({l} m here)"
                ),
            ));
        }
        if shared.bodies.contains(&body) {
            return Err(BuildError::at(
                "0.body",
                format!("body `{}` already has a zhang2018 controller", spec.body),
            ));
        }
        shared.capture_radius_m = Some(spec.capture_radius_m);
        shared.bodies.push(body);
        let mut capture = Vec::new();
        if first {
            for a in 0..n_bodies {
                for b in a + 1..n_bodies {
                    capture.push(CaptureDistance {
                        name: format!("capture.{}.{}", names[a], names[b]),
                        a,
                        b,
                        capture_radius_m: spec.capture_radius_m,
                    });
                }
            }
        }
        let mass = ctx.info[body].mass_kg;
        let params = Zhang2018Params {
            mass_p_kg: mass,
            mass_e_kg: mass,
            thrust_p_n: spec.thrust_n,
            thrust_e_n: spec.thrust_n,
            capture_radius_m: spec.capture_radius_m,
            avoidance_margin_m: spec.avoidance_margin_m,
            drift: Drift::L2(model),
        };
        let threats = (0..n_bodies)
            .filter(|&j| j != body)
            .map(|j| (j, AvoidanceController::new(params.clone())))
            .collect();
        Ok(Built {
            slots: vec![Slot {
                kind: "Zhang2018".into(),
                body,
                target: None,
                period_steps: 1,
                sensor: None,
                actuator: crate::actuation::ActuatorSpec::Ideal,
                ports: None,
                law: Box::new(LawState {
                    body,
                    thrust_n: spec.thrust_n,
                    plan: spec.planned_maneuver(),
                    avoid: spec.avoid,
                    threats,
                    params,
                    dir_rot_rad: None,
                    last: [f64::NAN; 4],
                    capture,
                    name: spec.body.clone(),
                }),
            }],
            disturbances: Vec::new(),
        })
    }
}

impl crate::control::interface::Controller for LawState {
    fn needs(&self) -> crate::control::interface::Needs {
        crate::control::interface::Needs::NONE
    }

    fn command(
        &mut self,
        obs: &crate::control::interface::Observation,
    ) -> crate::control::interface::Command {
        use crate::control::interface::{Command, Frame};
        let crate::environment::EnvObs::SunEarthL2 { centre, states_rot } = obs.env else {
            return Command::zero();
        };
        let t = obs.t_s;
        let computed: Vec<L2State>;
        let states: &[L2State] = if states_rot.len() == obs.bodies.len() {
            states_rot
        } else {
            computed = obs
                .bodies
                .iter()
                .map(|s| centre.world_to_rot(&s.pos_m, &s.vel_m_s))
                .collect();
            &computed
        };
        let planned = self.plan.dir_at(t);
        let mut barrier = f64::INFINITY;
        let mut chosen: Option<(f64, Option<f64>)> = None;
        let mut nearest: Option<(f64, usize)> = None;
        for (j, ctl) in &mut self.threats {
            let x = game_state(states, *j, self.body);
            let sep = rel_pos_m(&x).norm();
            if nearest.is_none_or(|(d, _)| sep < d) {
                nearest = Some((sep, *j));
            }
            let b = closest_approach(&x).miss_m - self.params.capture_radius_m;
            barrier = barrier.min(b);
            if self.avoid {
                let c = ctl.evader_command(&x, planned);
                if c.engaged && chosen.is_none_or(|(bb, _)| c.barrier_m < bb) {
                    chosen = Some((c.barrier_m, c.dir_rad));
                }
            }
        }
        self.dir_rot_rad = match chosen {
            Some((_, d)) => d,
            None => planned,
        };
        let h = nearest.map_or(f64::NAN, |(_, j)| {
            boundary_value(
                &self.params,
                &game_state(states, j, self.body),
                PursuerRole::PaperCooperative,
            )
            .h
        });
        self.last = [
            barrier,
            if chosen.is_some() { 1.0 } else { 0.0 },
            self.dir_rot_rad.map_or(f64::NAN, f64::to_degrees),
            h,
        ];
        match self.dir_rot_rad {
            Some(d) => Command::in_frame(
                Frame::World,
                centre.rot_dir_to_world(d) * self.thrust_n,
                nalgebra::Vector3::zeros(),
            ),
            None => Command::zero(),
        }
    }

    fn columns(&self) -> Vec<String> {
        let name = &self.name;
        vec![
            format!("zhang2018.{name}.barrier_m"),
            format!("zhang2018.{name}.engaged"),
            format!("zhang2018.{name}.thrust_dir_rot_deg"),
            format!("zhang2018.{name}.h_eq12_m_s2"),
        ]
    }

    fn diagnostics(
        &mut self,
        _at: crate::control::interface::DiagnosticsAt,
        _obs: &crate::control::interface::Observation,
        _act: &crate::control::interface::ActuationReport,
        out: &mut [f64],
    ) {
        out.copy_from_slice(&self.last);
    }

    fn guarantees(&mut self) -> Vec<Box<dyn crate::guarantee::Guarantee>> {
        std::mem::take(&mut self.capture)
            .into_iter()
            .map(|g| Box::new(g) as Box<dyn crate::guarantee::Guarantee>)
            .collect()
    }
}
