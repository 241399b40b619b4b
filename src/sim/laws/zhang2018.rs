//! Simulation wiring of [`crate::control::zhang2018`] (Zhang, He, Lü, Wang 2018): the Sun–Earth
//! L2 environment with a floating origin, fixed-magnitude thrust per spacecraft, the
//! barrier-based avoidance law, and the capture-distance guarantee.
//!
//! # Environment (`Environment::SunEarthL2`)
//! [`install_environment`] inserts the gravity field [`L2Gravity`]: the world frame is
//! non-rotating, its axes are the Sun–EMB rotating frame's at t = 0, and its origin rides on the
//! formation centre, a thrust-free point propagated in f64 (RK4 in the rotating frame, the
//! circular restricted three-body problem of [`crate::orbit::l2`]). Every body receives the
//! differential gravity a(r_c + ρ) − a(r_c) of the Sun and the EMB, so world positions are the
//! formation's own size. The [`L2Frame`] resource holds a copy of the centre, advanced on the
//! same steps (bit-identical), for the controllers' frame conversions.
//!
//! # Precision at L2 scales
//! The core keeps an f64 state per body (truth) and only writes poses into rapier, whose f32
//! positions resolve ulp(1000 km) = 0.0625 m (ulp(735 km), the pair scene's ±half separation,
//! is also 0.0625 m): immaterial to a capture radius of 5 km, and rapier's f32 is used only for
//! contact detection between bodies that are kilometres apart. The monitor forms relative poses
//! in f64. The rotating-frame states the law needs are formed as centre (f64, ~1.5·10¹¹ m, ulp
//! 3·10⁻⁵ m) plus the relative state rotated by −n t, so relative positions keep ~10⁻⁵ m.
//! The full-geometry monitor (a 2 m bus with 5 m panels per spacecraft) measures distances of
//! kilometres here: correct but of no consequence at a 5 km capture radius; the guarantee that
//! matters is [`CaptureDistance`] on centre-of-mass separation.
//!
//! # Control (`Zhang2018(...)` in `controllers`)
//! Every step (Control stage) each controlled spacecraft converts every body's world state into
//! the paper's rotating frame `rot`, evaluates its plan and, if `avoid`, one
//! [`AvoidanceController`] per other body (that body as the pursuer P, itself as the evader E):
//! when one or more are engaged, the one with the smallest barrier function (miss − l) gives
//! the direction u* of eq (8). The Actuate stage adds F·(direction rotated to the world axes)
//! to the body's `Wrench::force_n` (held constant over the step). Columns per controlled body:
//! `zhang2018.NAME.barrier_m` (smallest miss − l over the other bodies),
//! `zhang2018.NAME.engaged` (0/1), `zhang2018.NAME.thrust_dir_rot_deg` (NaN when off),
//! `zhang2018.NAME.h_eq12_m_s2` (eq (12) as printed, the cooperative value, against the nearest
//! body; mixed m/s + m/s² units read with the paper's implicit 1 s time scale).

use crate::control::zhang2018::{
    AvoidanceController, Drift, GameState, PlannedManeuver, PursuerRole, SceneSpec,
    Zhang2018Params, boundary_value, closest_approach,
};
use crate::guarantee::{Guarantee, MonitorView};
use crate::orbit::l2::{L2Centre, L2EnvSpec, L2State};
use crate::scene::{Environment, LoadedScene, SceneError};
use crate::sim::output::Diagnostics;
use crate::sim::{
    BodyState, Clock, Gravity, GravityField, Guarantees, Roster, SimBody, SimStep, Stage, Wrench,
};
use bevy::prelude::*;
use nalgebra::Vector3;

/// The gravity field of a `SunEarthL2` scene: differential Sun + EMB gravity about the
/// formation centre (see the module doc).
pub struct L2Gravity(pub L2Centre);

impl GravityField for L2Gravity {
    fn accel_m_s2(&self, pos_world_m: &Vector3<f64>) -> Vector3<f64> {
        self.0.differential_accel_world_m_s2(pos_world_m)
    }
    /// Advances one scene step (the centre steps by its own `dt_s`, the scene's step).
    fn advance(&mut self, dt_s: f64) {
        debug_assert!((dt_s - self.0.dt_s).abs() <= 1e-12 * dt_s);
        self.0.advance();
    }
}

/// The formation centre seen by the controllers (a copy of the gravity field's, advanced on
/// the same steps in the Sense stage).
#[derive(Resource, Debug, Clone)]
pub struct L2Frame(pub L2Centre);

/// Inserts the gravity field and the [`L2Frame`] of a `SunEarthL2` scene. Returns the
/// reference-orbit state used for Hill-frame initial states: none here (initial states are
/// written in the world frame).
pub fn install_environment(
    app: &mut App,
    spec: &L2EnvSpec,
    dt_s: f64,
) -> Option<(Vector3<f64>, Vector3<f64>)> {
    let centre = L2Centre::new(spec, dt_s);
    app.insert_resource(Gravity(Box::new(L2Gravity(centre.clone()))));
    app.insert_resource(L2Frame(centre));
    None
}

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

impl Guarantee for CaptureDistance {
    fn name(&self) -> &str {
        &self.name
    }
    fn margin(&self, v: &MonitorView) -> f64 {
        (v.bodies[self.a].pos_m - v.bodies[self.b].pos_m).norm() - self.capture_radius_m
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
    /// Diagnostics columns: barrier, engaged, direction, H of eq (12).
    pub cols: [usize; 4],
}

/// Every zhang2018 controller of the scene.
#[derive(Resource, Debug, Clone, Default)]
pub struct Zhang2018Laws {
    /// Controlled spacecraft, in scene order of the controllers.
    pub laws: Vec<LawState>,
    /// Capture radius of the registered guarantees, m.
    pub capture_radius_m: f64,
}

/// Adds this law's resources and systems for one controller of the scene.
pub fn install(
    app: &mut App,
    loaded: &LoadedScene,
    path: &str,
    spec: &SceneSpec,
) -> Result<(), SceneError> {
    // The spec is the newtype content of `Zhang2018((...))`: its fields are under `path.0`.
    let field = |f: &str| format!("{path}.0.{f}");
    let body = super::body_index(loaded, &format!("{path}.0"), "body", &spec.body)?;
    spec.validate()
        .map_err(|(f, m)| loaded.error_at(&field(&f), m))?;
    let Environment::SunEarthL2(env) = &loaded.scene.environment else {
        return Err(loaded.error_at(
            path,
            "the zhang2018 controller needs `environment: SunEarthL2(...)`",
        ));
    };
    let bodies = &loaded.scene.bodies;
    let first = app.world().get_resource::<Zhang2018Laws>().is_none();
    if first {
        let mut g = app.world_mut().resource_mut::<Guarantees>();
        for a in 0..bodies.len() {
            for b in a + 1..bodies.len() {
                g.register(Box::new(CaptureDistance {
                    name: format!("capture.{}.{}", bodies[a].name, bodies[b].name),
                    a,
                    b,
                    capture_radius_m: spec.capture_radius_m,
                }));
            }
        }
        app.insert_resource(Zhang2018Laws {
            laws: Vec::new(),
            capture_radius_m: spec.capture_radius_m,
        });
        app.add_systems(SimStep, sync_frame.in_set(Stage::Sense));
        app.add_systems(SimStep, control.in_set(Stage::Control));
        app.add_systems(SimStep, actuate.in_set(Stage::Actuate));
    }
    let world = app.world_mut();
    let laws = world.resource::<Zhang2018Laws>();
    if laws.capture_radius_m != spec.capture_radius_m {
        return Err(loaded.error_at(
            &field("capture_radius_m"),
            format!(
                "all zhang2018 controllers of a scene share one capture radius ({} m here)",
                laws.capture_radius_m
            ),
        ));
    }
    if laws.laws.iter().any(|l| l.body == body) {
        return Err(loaded.error_at(
            &field("body"),
            format!("body `{}` already has a zhang2018 controller", spec.body),
        ));
    }
    let mass = bodies[body].mass_kg;
    let params = Zhang2018Params {
        mass_p_kg: mass,
        mass_e_kg: mass,
        thrust_p_n: spec.thrust_n,
        thrust_e_n: spec.thrust_n,
        capture_radius_m: spec.capture_radius_m,
        avoidance_margin_m: spec.avoidance_margin_m,
        drift: Drift::L2(env.model.clone()),
    };
    let threats = (0..bodies.len())
        .filter(|&j| j != body)
        .map(|j| (j, AvoidanceController::new(params.clone())))
        .collect();
    let name = &spec.body;
    let mut diag = world.resource_mut::<Diagnostics>();
    let cols = [
        diag.column(&format!("zhang2018.{name}.barrier_m")),
        diag.column(&format!("zhang2018.{name}.engaged")),
        diag.column(&format!("zhang2018.{name}.thrust_dir_rot_deg")),
        diag.column(&format!("zhang2018.{name}.h_eq12_m_s2")),
    ];
    world.resource_mut::<Zhang2018Laws>().laws.push(LawState {
        body,
        thrust_n: spec.thrust_n,
        plan: spec.planned_maneuver(),
        avoid: spec.avoid,
        threats,
        params,
        dir_rot_rad: None,
        cols,
    });
    Ok(())
}

/// Sense: brings the controllers' copy of the formation centre to the current step.
fn sync_frame(clock: Res<Clock>, mut frame: ResMut<L2Frame>) {
    while frame.0.steps < clock.step {
        frame.0.advance();
    }
}

/// Game state with P = body `p`, E = body `e` (rotating frame `rot`).
fn game_state(states: &[L2State], p: usize, e: usize) -> GameState {
    let mut x = GameState::zeros();
    x.fixed_rows_mut::<4>(0).copy_from(&states[p]);
    x.fixed_rows_mut::<4>(4).copy_from(&states[e]);
    x
}

/// Control: plan or evasive direction for every controlled spacecraft.
fn control(
    clock: Res<Clock>,
    frame: Res<L2Frame>,
    roster: Res<Roster>,
    bodies: Query<&BodyState>,
    mut laws: ResMut<Zhang2018Laws>,
    mut diag: ResMut<Diagnostics>,
) {
    let t = clock.t_s();
    let states: Vec<L2State> = roster
        .bodies
        .iter()
        .map(|e| {
            let s = bodies.get(*e).expect("roster body");
            frame.0.world_to_rot(&s.pos_m, &s.vel_m_s)
        })
        .collect();
    for law in &mut laws.laws {
        let planned = law.plan.dir_at(t);
        let mut barrier = f64::INFINITY;
        let mut chosen: Option<(f64, Option<f64>)> = None;
        let mut nearest: Option<(f64, usize)> = None;
        for (j, ctl) in &mut law.threats {
            let x = game_state(&states, *j, law.body);
            let sep = crate::control::zhang2018::rel_pos_m(&x).norm();
            if nearest.is_none_or(|(d, _)| sep < d) {
                nearest = Some((sep, *j));
            }
            let b = closest_approach(&x).miss_m - law.params.capture_radius_m;
            barrier = barrier.min(b);
            if law.avoid {
                let c = ctl.evader_command(&x, planned);
                if c.engaged && chosen.is_none_or(|(bb, _)| c.barrier_m < bb) {
                    chosen = Some((c.barrier_m, c.dir_rad));
                }
            }
        }
        law.dir_rot_rad = match chosen {
            Some((_, d)) => d,
            None => planned,
        };
        let h = nearest.map_or(f64::NAN, |(_, j)| {
            boundary_value(
                &law.params,
                &game_state(&states, j, law.body),
                PursuerRole::PaperCooperative,
            )
            .h
        });
        let [cb, ce, cd, ch] = law.cols;
        diag.values[cb] = barrier;
        diag.values[ce] = if chosen.is_some() { 1.0 } else { 0.0 };
        diag.values[cd] = law.dir_rot_rad.map_or(f64::NAN, f64::to_degrees);
        diag.values[ch] = h;
    }
}

/// Actuate: the fixed-magnitude thrust along the commanded direction, in the world frame.
fn actuate(
    frame: Res<L2Frame>,
    roster: Res<Roster>,
    laws: Res<Zhang2018Laws>,
    mut q: Query<(&SimBody, &mut Wrench)>,
) {
    for law in &laws.laws {
        if let Some(d) = law.dir_rot_rad
            && let Ok((_, mut w)) = q.get_mut(roster.bodies[law.body])
        {
            w.force_n += frame.0.rot_dir_to_world(d) * law.thrust_n;
        }
    }
}
