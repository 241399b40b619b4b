//! `rpod reproduce xu2019`: Xu, Wen, Wei (2019), Fig. 13 on the air-bearing lab twin.
//!
//! Two cases, each a bundled scene run through the whole pipeline (table, vision, actuators,
//! monitor, docking mechanism):
//! - **simulation** (`scenes/papers/xu2019/xu2019_simulation.ron`): ideal continuous force and torque, ideal
//!   sensor, I_z = 0.05 kg·m²;
//! - **experiment** (`scenes/papers/xu2019/xu2019_experiment.ron`): eight 0.05 N on/off nozzles through PWPF,
//!   25 Hz vision with noise and one frame of latency, differenced velocity, true
//!   I_z = 0.055 kg·m² (the paper says its measured 0.05 is slightly low).
//!
//! Variants of both cases (same scenes, one change each):
//! - **law kept active** (`release_on_magnet: false`): the paper does not say the law stops
//!   at the magnet; the scenes' default switches it off there;
//! - **ghost obstacle**: the obstacle body removed from the scene, the law keeping its
//!   obstacle parameters — the approach without the contacts the prism causes;
//! - **experiment, I_z as tuned** (0.05 kg·m²): separates the inertia effect from the
//!   nozzles in the attitude comparison.
//!
//! Writes `REPORT.md`, `path.png`, `states.png`, `distances.png`, `valves.png`, `claims.json`
//! and each case's `trajectory.csv`, `events.jsonl`, `summary.json` under `OUT/<case>/`.

use crate::control::xu2019::Xu2019Instance;
use crate::control::xu2019::{Xu2019Params, Xu2019Potential};
use crate::geometry::superquadric::RadialForm;
use crate::report::ClaimKind::{BeyondThePaper, Paper};
use crate::report::{Claim, Color, Dash, Figure, LineStyle, Plot, ReportBuilder, held_word};
use crate::scene::load_scene_str;
use crate::sim::Simulation;
use crate::sim::docking::{DockState, Docking};
use nalgebra::{Vector2, Vector3};
use std::path::Path;

/// The simulation case scene.
pub const SIMULATION_SCENE: &str = include_str!("../../scenes/papers/xu2019/xu2019_simulation.ron");
/// The experiment case scene.
pub const EXPERIMENT_SCENE: &str = include_str!("../../scenes/papers/xu2019/xu2019_experiment.ron");

/// Goal tolerance of the claims: position, m.
pub const GOAL_POS_TOL_M: f64 = 0.01;
/// Goal tolerance of the claims: attitude, deg. Ours: the paper shows the attitude converging
/// (Fig. 13d) without a tolerance; 2° is a round value below the mechanism's 3° latch
/// tolerance. [`LATCH_ANGLE_TOL_DEG`] is the sensitivity.
pub const GOAL_ANGLE_TOL_DEG: f64 = 2.0;
/// The scenes' latch angle tolerance, deg: the other plausible goal tolerance.
pub const LATCH_ANGLE_TOL_DEG: f64 = 3.0;
/// Override that keeps the law commanding after the magnet switches on.
pub const LAW_KEPT_ACTIVE: &str = "controllers.0.0.release_on_magnet=false";
/// Override that gives the experiment's chaser the I_z the law was tuned with.
pub const EXPERIMENT_TUNED_IZ: &str = "bodies.chaser.inertia_kg_m2.zz=0.05";
/// Sampling period of the recorded series, s.
pub const SAMPLE_S: f64 = 0.1;

/// One case's recorded run.
#[derive(Debug, Clone, Default)]
pub struct CaseRun {
    /// Case name.
    pub name: String,
    /// Sample times, s.
    pub t_s: Vec<f64>,
    /// Chaser centre of mass x, lab frame, m.
    pub x_m: Vec<f64>,
    /// Chaser centre of mass y, m.
    pub y_m: Vec<f64>,
    /// Chaser yaw θ, deg (unwrapped).
    pub theta_deg: Vec<f64>,
    /// Chaser velocity (ẋ, ẏ) m/s and yaw rate rad/s.
    pub vel: Vec<[f64; 3]>,
    /// Radial distance to the obstacle, eq (8) form, m.
    pub radial_obstacle_eq8_m: Vec<f64>,
    /// Radial distance to the obstacle, exact ray intersection, m.
    pub radial_obstacle_exact_m: Vec<f64>,
    /// Radial distance to the heart keep-out, m.
    pub radial_heart_m: Vec<f64>,
    /// Full-geometry distance chaser ↔ obstacle prism, m.
    pub geometry_obstacle_m: Vec<f64>,
    /// Mean number of open nozzles over each sample window.
    pub open_nozzles: Vec<f64>,
    /// Gas used, kg.
    pub gas_kg: Vec<f64>,
    /// Valve openings per nozzle (NOZZLE_NAMES order) over the run.
    pub valve_openings: [u64; 8],
    /// Valve-open time per nozzle, s.
    pub valve_open_s: [f64; 8],
    /// When the docking magnet switched on (the law hands over), s.
    pub magnet_on_s: Option<f64>,
    /// Final docking state and reason.
    pub dock_state: String,
    /// Why.
    pub dock_reason: String,
    /// Latch time, s.
    pub t_latch_s: Option<f64>,
    /// Final position error, m.
    pub final_pos_err_m: f64,
    /// Final attitude error, deg.
    pub final_angle_err_deg: f64,
    /// First time within the goal tolerances, s.
    pub first_at_goal_s: Option<f64>,
    /// Smallest full-geometry distance chaser ↔ obstacle, m, its parts and time.
    pub min_geometry_obstacle: (f64, String, f64),
    /// Collision events of the chaser with the obstacle: (t s, part, part).
    pub obstacle_collisions: Vec<(f64, String, String)>,
    /// Every collision (any pair), count.
    pub collisions: usize,
    /// `off_table` events: (t s, body).
    pub off_table: Vec<(f64, String)>,
    /// Steps run and wall time, s.
    pub steps: u64,
    /// Wall-clock time of the run, s.
    pub wall_s: f64,
}

impl CaseRun {
    /// Index of the last sample before the magnet switched on (the free approach).
    pub fn approach_end(&self) -> usize {
        match self.magnet_on_s {
            Some(t) => self.t_s.iter().rposition(|s| *s <= t).unwrap_or(0),
            None => self.t_s.len() - 1,
        }
    }
    /// Minimum of a series over the whole run.
    pub fn min(v: &[f64]) -> f64 {
        v.iter().copied().fold(f64::INFINITY, f64::min)
    }
    /// Time at which a series first covers `frac` of its change from the start to `goal`, s.
    pub fn time_to_fraction(&self, v: &[f64], goal: f64, frac: f64) -> Option<f64> {
        let e0 = v[0] - goal;
        v.iter()
            .zip(&self.t_s)
            .find(|(x, _)| ((*x - goal) / e0) <= 1.0 - frac)
            .map(|(_, t)| *t)
    }
}

/// Both cases.
#[derive(Debug, Clone)]
pub struct Results {
    /// The simulation case.
    pub simulation: CaseRun,
    /// The experiment case.
    pub experiment: CaseRun,
    /// A diagnostic when the simulation case did not latch: the case restarted at each of
    /// [`RESTART_S`] from its own recorded state (fresh world, law and sensor state).
    pub restarts: Vec<(f64, CaseRun)>,
    /// The simulation case with the law kept active after the magnet ([`LAW_KEPT_ACTIVE`]).
    pub simulation_active: CaseRun,
    /// The experiment case with the law kept active after the magnet.
    pub experiment_active: CaseRun,
    /// The simulation case with a ghost obstacle ([`ghost_obstacle`]).
    pub simulation_ghost: CaseRun,
    /// The experiment case with a ghost obstacle.
    pub experiment_ghost: CaseRun,
    /// The experiment case with the chaser's true I_z = 0.05 kg·m² ([`EXPERIMENT_TUNED_IZ`]).
    pub experiment_tuned_iz: CaseRun,
}

impl Results {
    /// The (case, law kept active, ghost obstacle) runs of both cases, simulation first.
    pub fn variants(&self) -> [(&CaseRun, &CaseRun, &CaseRun); 2] {
        [
            (
                &self.simulation,
                &self.simulation_active,
                &self.simulation_ghost,
            ),
            (
                &self.experiment,
                &self.experiment_active,
                &self.experiment_ghost,
            ),
        ]
    }
}

/// Restart times of the diagnostic runs, s (after the obstacle episode, before the magnet).
pub const RESTART_S: [f64; 2] = [10.0, 40.0];

/// Overrides that start a case's chaser from sample `i` of a run.
fn restart_overrides(run: &CaseRun, i: usize) -> Vec<String> {
    let v = run.vel[i];
    vec![
        format!(
            "bodies.chaser.initial.pos_m=({:e}, {:e}, 0.16)",
            run.x_m[i], run.y_m[i]
        ),
        format!(
            "bodies.chaser.initial.attitude=EulerZyxDeg(yaw: {:e}, pitch: 0.0, roll: 0.0)",
            run.theta_deg[i]
        ),
        format!(
            "bodies.chaser.initial.vel_m_s=({:e}, {:e}, 0.0)",
            v[0], v[1]
        ),
        format!(
            "bodies.chaser.initial.rate_body_deg_s=(0.0, 0.0, {:e})",
            v[2].to_degrees()
        ),
    ]
}

/// Runs one case from its scene text for `duration_s` (None: the scene's), recording to
/// `out` if given.
pub fn run_case(
    name: &str,
    text: &str,
    file: &str,
    duration_s: Option<f64>,
    out: Option<&Path>,
) -> Result<CaseRun, String> {
    run_case_with(name, text, file, &[], duration_s, out)
}

/// [`run_case`] with `--set` style overrides.
pub fn run_case_with(
    name: &str,
    text: &str,
    file: &str,
    overrides: &[String],
    duration_s: Option<f64>,
    out: Option<&Path>,
) -> Result<CaseRun, String> {
    let loaded = load_scene_str(text, file, overrides).map_err(|e| e.to_string())?;
    run_loaded(name, &loaded, duration_s, out)
}

/// The loaded scene with its obstacle made a ghost: the `obstacle` body (and its anchoring)
/// removed, the law unchanged (it keeps its own obstacle parameters, `Xu2019Params`).
pub fn ghost_obstacle(loaded: &crate::scene::LoadedScene) -> crate::scene::LoadedScene {
    let mut l = loaded.clone();
    l.scene.bodies.retain(|b| b.name != "obstacle");
    if let crate::scene::Environment::AirBearing(ab) = &mut l.scene.environment {
        ab.anchored.retain(|n| n != "obstacle");
    }
    l
}

/// [`run_case`] on a loaded (possibly modified) scene.
pub fn run_loaded(
    name: &str,
    loaded: &crate::scene::LoadedScene,
    duration_s: Option<f64>,
    out: Option<&Path>,
) -> Result<CaseRun, String> {
    let mut sim = Simulation::new(loaded).map_err(|e| e.to_string())?;
    let obstacle = loaded
        .scene
        .bodies
        .iter()
        .position(|b| b.name == "obstacle");
    if let Some(dir) = out {
        sim.record_to(dir)
            .map_err(|e| format!("cannot write {}: {e}", dir.display()))?;
    }
    let duration = duration_s.unwrap_or(sim.scene.duration_s);
    let dt = sim.scene.dt_s;
    let per_sample = (SAMPLE_S / dt).round().max(1.0) as u64;
    let n_samples = sim.steps_for(duration) / per_sample;
    let law = Xu2019Potential::new(Xu2019Params::paper());
    let goal = Vector3::new(
        law.params.goal_pos_lab_m[0],
        law.params.goal_pos_lab_m[1],
        law.params.goal_theta_rad,
    );
    let mut run = CaseRun {
        name: name.into(),
        ..Default::default()
    };
    let mut last_theta: Option<f64> = None;
    let mut open_acc = 0.0;
    let mut sample = |sim: &Simulation, run: &mut CaseRun, open_mean: f64| {
        push_sample(
            run,
            sim,
            (&law.params, obstacle),
            &mut last_theta,
            open_mean,
        );
    };
    sample(&sim, &mut run, 0.0);
    for _ in 0..n_samples {
        open_acc = 0.0;
        for _ in 0..per_sample {
            sim.step(1);
            let ctl = sim.law::<Xu2019Instance>(0).expect("an Xu2019 controller");
            open_acc += ctl.valves.iter().filter(|v| **v).count() as f64;
            if run.magnet_on_s.is_none() {
                let d = sim.app.world().resource::<Docking>();
                if d.magnet_on {
                    run.magnet_on_s = Some(sim.t_s());
                }
            }
        }
        sample(&sim, &mut run, open_acc / per_sample as f64);
    }
    let _ = open_acc;
    read_final_state(&mut run, &sim, &law, goal);
    read_contacts(&mut run, &sim, obstacle);
    run.steps = sim.steps();
    run.wall_s = sim.wall_s;
    if out.is_some() {
        sim.finish()
            .map_err(|e| format!("cannot finish the outputs of {name}: {e}"))?;
    }
    Ok(run)
}

/// One sample of the chaser's state, distances, valves and gas into `run`; θ is unwrapped
/// against the previous sample's (`last_theta`).
fn push_sample(
    run: &mut CaseRun,
    sim: &Simulation,
    (params, obstacle): (&Xu2019Params, Option<usize>),
    last_theta: &mut Option<f64>,
    open_mean: f64,
) {
    let c = sim.body("chaser").expect("chaser");
    let p = c.pos_m.xy();
    let th = c.yaw_rad();
    let th = match *last_theta {
        None => th,
        Some(prev) => {
            prev + (th - prev + std::f64::consts::PI).rem_euclid(2.0 * std::f64::consts::PI)
                - std::f64::consts::PI
        }
    };
    *last_theta = Some(th);
    run.t_s.push(sim.t_s());
    run.x_m.push(p.x);
    run.y_m.push(p.y);
    run.theta_deg.push(th.to_degrees());
    run.vel.push([c.vel_m_s.x, c.vel_m_s.y, c.omega_rad_s.z]);
    run.radial_obstacle_eq8_m
        .push(params.obstacle.radial_distance_m(p, RadialForm::PaperEq8));
    run.radial_obstacle_exact_m
        .push(params.obstacle.radial_distance_m(p, RadialForm::Exact));
    run.radial_heart_m.push(params.heart.radial_distance_m(p));
    let mon = sim.monitor();
    let d = mon
        .pairs
        .iter()
        .find(|q| q.a == 0 && Some(q.b) == obstacle)
        .map_or(f64::NAN, |q| q.distance_m);
    run.geometry_obstacle_m.push(d);
    run.open_nozzles.push(open_mean);
    let ctl = sim.law::<Xu2019Instance>(0).expect("an Xu2019 controller");
    run.gas_kg.push(ctl.gas_used_kg);
}

/// The actuator, docking and goal outcome at the end of the run.
fn read_final_state(
    run: &mut CaseRun,
    sim: &Simulation,
    law: &Xu2019Potential,
    goal: Vector3<f64>,
) {
    let act = &sim
        .controllers()
        .slot_of::<Xu2019Instance>(0)
        .expect("an Xu2019 controller")
        .actuator;
    run.valve_openings = act.valve_openings;
    run.valve_open_s = act.valve_open_s;
    let d = sim.app.world().resource::<Docking>().clone();
    run.dock_state = d.state.name().to_string();
    run.dock_reason = d.reason.clone();
    run.t_latch_s = d.t_latch_s;
    let c = sim.body("chaser").expect("chaser");
    let e = law.pose_error(Vector3::new(c.pos_m.x, c.pos_m.y, c.yaw_rad()));
    run.final_pos_err_m = e.xy().norm();
    run.final_angle_err_deg = e.z.abs().to_degrees();
    run.first_at_goal_s = run
        .t_s
        .iter()
        .zip(run.x_m.iter().zip(&run.y_m).zip(&run.theta_deg))
        .find(|(_, ((x, y), th))| {
            (Vector2::new(**x, **y) - goal.xy()).norm() < GOAL_POS_TOL_M
                && (th.to_radians() - goal.z).abs().to_degrees() < GOAL_ANGLE_TOL_DEG
        })
        .map(|(t, _)| *t);
}

/// The closest approach to the obstacle, the collisions and the off-table events.
fn read_contacts(run: &mut CaseRun, sim: &Simulation, obstacle: Option<usize>) {
    let mon = sim.monitor();
    run.min_geometry_obstacle = (f64::NAN, "no obstacle body".into(), f64::NAN);
    if let Some(b) = obstacle
        && let Some(i) = mon.pairs.iter().position(|q| q.a == 0 && q.b == b)
    {
        let m = &mon.min_per_pair[i];
        run.min_geometry_obstacle = (
            m.distance_m,
            format!(
                "{} | {}",
                mon.part_name(0, m.part_a),
                mon.part_name(b, m.part_b)
            ),
            m.t_s,
        );
    }
    let cs = sim.contacts();
    run.collisions = cs.collisions.len();
    run.obstacle_collisions = cs
        .collisions
        .iter()
        .filter(|(_, a, b)| {
            (a.starts_with("chaser/") && b.starts_with("obstacle/"))
                || (b.starts_with("chaser/") && a.starts_with("obstacle/"))
        })
        .cloned()
        .collect();
    run.off_table = sim
        .events()
        .iter()
        .filter(|e| e.kind == "off_table")
        .map(|e| {
            (
                e.t_s,
                e.data
                    .get("body")
                    .and_then(|b| b.as_str())
                    .unwrap_or("")
                    .to_string(),
            )
        })
        .collect();
}

/// Runs both cases (their scenes' durations), recording under `out/<case>/` if given.
pub fn compute(out: Option<&Path>) -> Result<Results, String> {
    let simulation = run_case(
        "simulation",
        SIMULATION_SCENE,
        "scenes/papers/xu2019/xu2019_simulation.ron",
        None,
        out.map(|o| o.join("simulation")).as_deref(),
    )?;
    let experiment = run_case(
        "experiment",
        EXPERIMENT_SCENE,
        "scenes/papers/xu2019/xu2019_experiment.ron",
        None,
        out.map(|o| o.join("experiment")).as_deref(),
    )?;
    let mut restarts = Vec::new();
    if simulation.dock_state != DockState::Latched.name() {
        for t0 in RESTART_S {
            let i = simulation
                .t_s
                .iter()
                .position(|t| (t - t0).abs() < 1e-6)
                .ok_or("restart sample missing")?;
            let loaded = load_scene_str(SIMULATION_SCENE, "x", &[]).map_err(|e| e.to_string())?;
            let mut r = run_case_with(
                "simulation-restart",
                SIMULATION_SCENE,
                "scenes/papers/xu2019/xu2019_simulation.ron",
                &restart_overrides(&simulation, i),
                Some(loaded.scene.duration_s - t0),
                None,
            )?;
            r.t_s.iter_mut().for_each(|t| *t += t0);
            r.magnet_on_s = r.magnet_on_s.map(|t| t + t0);
            r.t_latch_s = r.t_latch_s.map(|t| t + t0);
            restarts.push((t0, r));
        }
    }
    let case = |name: &str, text: &str, file: &str, ov: &[String]| {
        run_case_with(name, text, file, ov, None, None)
    };
    let ghost = |name: &str, text: &str, file: &str| {
        let loaded = load_scene_str(text, file, &[]).map_err(|e| e.to_string())?;
        run_loaded(name, &ghost_obstacle(&loaded), None, None)
    };
    let (sf, ef) = (
        "scenes/papers/xu2019/xu2019_simulation.ron",
        "scenes/papers/xu2019/xu2019_experiment.ron",
    );
    let active = [LAW_KEPT_ACTIVE.to_string()];
    Ok(Results {
        simulation,
        experiment,
        restarts,
        simulation_active: case("simulation, law kept active", SIMULATION_SCENE, sf, &active)?,
        experiment_active: case("experiment, law kept active", EXPERIMENT_SCENE, ef, &active)?,
        simulation_ghost: ghost("simulation, ghost obstacle", SIMULATION_SCENE, sf)?,
        experiment_ghost: ghost("experiment, ghost obstacle", EXPERIMENT_SCENE, ef)?,
        experiment_tuned_iz: case(
            "experiment, I_z = 0.05",
            EXPERIMENT_SCENE,
            ef,
            &[EXPERIMENT_TUNED_IZ.to_string()],
        )?,
    })
}

fn fmt_opt(t: Option<f64>) -> String {
    t.map_or("never".into(), |t| format!("{t:.1} s"))
}

/// Settling times (50 % and 90 % of the change) of x, y, θ over the free approach, s.
pub fn settling(run: &CaseRun) -> [[Option<f64>; 2]; 3] {
    let p = Xu2019Params::paper();
    let n = run.approach_end() + 1;
    let clip = |v: &Vec<f64>| v[..n].to_vec();
    let goals = [
        p.goal_pos_lab_m[0],
        p.goal_pos_lab_m[1],
        p.goal_theta_rad.to_degrees(),
    ];
    let series = [clip(&run.x_m), clip(&run.y_m), clip(&run.theta_deg)];
    let mut out = [[None; 2]; 3];
    for k in 0..3 {
        for (j, f) in [0.5, 0.9].iter().enumerate() {
            out[k][j] = run.time_to_fraction(&series[k], goals[k], *f);
        }
    }
    out
}

/// Whether a run latched and ended within `angle_tol_deg` and [`GOAL_POS_TOL_M`] of the goal.
fn at_goal_and_latched(run: &CaseRun, angle_tol_deg: f64) -> bool {
    run.dock_state == DockState::Latched.name()
        && run.final_pos_err_m < GOAL_POS_TOL_M
        && run.final_angle_err_deg < angle_tol_deg
}

fn goal_text(run: &CaseRun) -> String {
    format!(
        "final |Δp| {:.4} m, |Δθ| {:.2}°; first within 1 cm & 2° at {}; docking {} ({}); latch {}",
        run.final_pos_err_m,
        run.final_angle_err_deg,
        fmt_opt(run.first_at_goal_s),
        run.dock_state,
        run.dock_reason,
        fmt_opt(run.t_latch_s)
    )
}

/// Largest distance between two runs' centre-of-mass paths at their common samples with
/// t < `before_s` and with t ≥ `before_s`, m.
pub fn path_deviation_m(a: &CaseRun, b: &CaseRun, before_s: f64) -> (f64, f64) {
    let mut d = (0.0f64, 0.0f64);
    for k in 0..a.t_s.len().min(b.t_s.len()) {
        let e = (a.x_m[k] - b.x_m[k]).hypot(a.y_m[k] - b.y_m[k]);
        if a.t_s[k] < before_s {
            d.0 = d.0.max(e);
        } else {
            d.1 = d.1.max(e);
        }
    }
    d
}

/// θ settling lag of run `a` behind run `b` at 50 % (`j` = 0) or 90 % (`j` = 1) of the
/// change, as "+x.x s" (or "n/a").
fn lag_s(a: &CaseRun, b: &CaseRun, j: usize) -> String {
    match (settling(a)[2][j], settling(b)[2][j]) {
        (Some(x), Some(y)) => format!("{:+.1} s", x - y),
        _ => "n/a".into(),
    }
}

/// Threshold source of the goal claims.
const TOL_SRC: &str = "ours: 1 cm and 2° — the paper shows x, y, θ converging (Fig. 13b–d) without \
                   a tolerance; 2° is a round value below the mechanism's 3° latch tolerance";

/// The claims, measured on `r`: goal and latch per variant, radial distances, obstacle
/// contacts, the ghost obstacle, the experiment's lag.
pub fn claims(r: &Results) -> Vec<Claim> {
    let mut v = Vec::new();
    goal_claims(r, &mut v);
    radial_claims(r, &mut v);
    obstacle_claims(r, &mut v);
    ghost_claims(r, &mut v);
    lag_claims(r, &mut v);
    v
}

/// Every variant reaches the goal and latches.
fn goal_claims(r: &Results, v: &mut Vec<Claim>) {
    let tol_src = TOL_SRC;
    for (run, active, _) in r.variants() {
        let held = at_goal_and_latched(run, GOAL_ANGLE_TOL_DEG);
        v.push(
            Claim::new(
                format!("{}-reaches-goal-and-latches", run.name),
                Paper,
                format!(
                    "The {} case reaches the goal (0.25 m, 1.4 m, 90°) within 1 cm and 2° and the chaser latches to the target simulator (law switched off when the magnet switches on, the scenes' default).",
                    run.name
                ),
                Some("Fig. 13b–d: both reach (0.25 m, 1.4 m, 90°); the docking mechanism locks"),
                tol_src,
                goal_text(run),
                held,
            )
            .with_sensitivity(format!(
                "with the latch's own {LATCH_ANGLE_TOL_DEG}° tolerance: {}; with the law kept active after the magnet (the paper does not say it stops): {} (|Δθ| {:.2}°)",
                held_word(at_goal_and_latched(run, LATCH_ANGLE_TOL_DEG)),
                held_word(at_goal_and_latched(active, GOAL_ANGLE_TOL_DEG)),
                active.final_angle_err_deg
            )),
        );
        v.push(
            Claim::new(
                format!("{}-law-kept-active-reaches-goal-and-latches", run.name),
                Paper,
                format!(
                    "The {} case with the law kept active after the magnet switches on (`release_on_magnet: false`) reaches the goal within 1 cm and 2° and latches.",
                    run.name
                ),
                Some("Fig. 13b–d: both reach (0.25 m, 1.4 m, 90°); the docking mechanism locks"),
                tol_src,
                goal_text(active),
                at_goal_and_latched(active, GOAL_ANGLE_TOL_DEG),
            )
            .with_sensitivity(format!(
                "law switched off at the magnet (scenes' default): {} (|Δθ| {:.2}°)",
                held_word(held),
                run.final_angle_err_deg
            )),
        );
    }
}

/// The radial distances to the obstacle and the heart stay positive.
fn radial_claims(r: &Results, v: &mut Vec<Claim>) {
    for run in [&r.simulation, &r.experiment] {
        let n = run.approach_end() + 1;
        let m8 = CaseRun::min(&run.radial_obstacle_eq8_m[..n]);
        let me = CaseRun::min(&run.radial_obstacle_exact_m[..n]);
        let mh = CaseRun::min(&run.radial_heart_m[..n]);
        let mh_all = CaseRun::min(&run.radial_heart_m);
        let mo_all = CaseRun::min(&run.radial_obstacle_exact_m);
        v.push(Claim::new(
            format!("{}-radial-distances-positive", run.name),
            Paper,
            format!(
                "In the {} case the chaser centre of mass keeps positive radial distances to the obstacle and to the heart keep-out throughout the controlled approach (until the law hands over to the docking magnet).",
                run.name
            ),
            Some("Fig. 13a: both radial Euclidean distances > 0 throughout, no collision"),
            "paper: Fig. 13a, radial distance > 0",
            format!(
                "until the hand-over at {}: min obstacle radial {m8:.4} m (eq 8) / {me:.4} m (exact), min heart radial {mh:.4} m; over the whole run (approach, capture and after): obstacle {mo_all:.4} m, heart {mh_all:.4} m (sampled every {SAMPLE_S} s)",
                fmt_opt(run.magnet_on_s)
            ),
            m8 > 0.0 && me > 0.0 && mh > 0.0,
        ));
    }
}

/// No contact with the obstacle.
fn obstacle_claims(r: &Results, v: &mut Vec<Claim>) {
    for run in [&r.simulation, &r.experiment] {
        let (d, parts, t) = &run.min_geometry_obstacle;
        let first = run.obstacle_collisions.first();
        v.push(Claim::new(
            format!("{}-no-obstacle-collision", run.name),
            BeyondThePaper,
            format!(
                "In the {} case the chaser's full geometry (body and docking cone) never touches the obstacle prism.",
                run.name
            ),
            Some("no collision during the whole rendezvous (judged on the centre of mass only)"),
            "ours: any contact between a chaser part and the prism (the paper judges the centre of mass only)",
            match first {
                None => format!("min full-geometry distance {d:.4} m ({parts}) at {t:.2} s; no collision"),
                Some((tc, a, b)) => format!(
                    "{} collision(s); first at {tc:.2} s between {a} and {b}; min full-geometry distance {d:.4} m ({parts}) at {t:.2} s",
                    run.obstacle_collisions.len()
                ),
            },
            first.is_none() && *d > 0.0,
        ));
    }
}

/// With a ghost obstacle (no prism body) the goal is reached and latched.
fn ghost_claims(r: &Results, v: &mut Vec<Claim>) {
    let tol_src = TOL_SRC;
    for (run, _, ghost) in r.variants() {
        let t_hit = run
            .obstacle_collisions
            .first()
            .map_or(f64::INFINITY, |c| c.0);
        let (before, after) = path_deviation_m(run, ghost, t_hit);
        v.push(Claim::new(
            format!("{}-ghost-obstacle-reaches-goal-and-latches", run.name),
            BeyondThePaper,
            format!(
                "With the obstacle not physical (body removed, the law keeping its obstacle parameters) the {} case reaches the goal within 1 cm and 2° and latches: what the approach does without the contacts.",
                run.name
            ),
            None,
            tol_src,
            format!(
                "{}; path identical to the real run until its first obstacle contact at {} (largest difference {before:.1e} m), up to {after:.3} m apart afterwards",
                goal_text(ghost),
                fmt_opt(run.obstacle_collisions.first().map(|c| c.0))
            ),
            at_goal_and_latched(ghost, GOAL_ANGLE_TOL_DEG),
        ));
    }
}

/// The experiment lags the simulation in x and y, and (the paper says) leads in θ.
fn lag_claims(r: &Results, v: &mut Vec<Claim>) {
    let ss = settling(&r.simulation);
    let se = settling(&r.experiment);
    let si = settling(&r.experiment_tuned_iz);
    let diff = |a: &[[Option<f64>; 2]; 3], b: &[[Option<f64>; 2]; 3], k: usize, j: usize| match (
        a[k][j], b[k][j],
    ) {
        (Some(x), Some(y)) => Some(x - y),
        _ => None,
    };
    let lag = |k: usize, j: usize| diff(&se, &ss, k, j);
    let f = |x: Option<f64>| x.map_or("n/a".into(), |x| format!("{x:+.1} s"));
    let held = lag(0, 0).is_some_and(|l| l > 0.0) && lag(1, 0).is_some_and(|l| l > 0.0);
    let held90 = lag(0, 1).is_some_and(|l| l > 0.0) && lag(1, 1).is_some_and(|l| l > 0.0);
    v.push(
        Claim::new(
            "experiment-lags-in-x-and-y",
            Paper,
            "The experiment (0.05 N nozzles through PWPF) lags the simulation in x and y.",
            Some(
                "x and y displacements of the experiment lag the simulation (thrust capped at 0.05 N)",
            ),
            "ours: 'lags' read as a later time to 50 % of the change from start to goal, in x and in y (the paper gives no measure)",
            format!(
                "time to 50 % of the change, experiment − simulation: x {}, y {}; to 90 %: x {}, y {}",
                f(lag(0, 0)),
                f(lag(1, 0)),
                f(lag(0, 1)),
                f(lag(1, 1))
            ),
            held,
        )
        .with_sensitivity(format!(
            "at 90 % of the change: {}",
            held_word(held90)
        )),
    );
    v.push(
        Claim::new(
            "experiment-attitude-leads",
            Paper,
            "The experiment's attitude slightly leads the simulation's.",
            Some("attitude slightly ahead, attributed to a measured I_z slightly below the true one"),
            "ours: 'leads' read as an earlier time to 50 % of the change in θ (the paper gives no measure)",
            format!(
                "time to 50 % of the change in θ, experiment − simulation: {}; to 90 %: {}. The paper's own explanation predicts the opposite: a true I_z above the measured one turns the chaser more slowly under the same torque (the law does not use I_z). With the experiment's I_z set to the tuned 0.05 kg·m²: {} / {} (the lag is the nozzles and the vision, not the inertia)",
                f(lag(2, 0)),
                f(lag(2, 1)),
                f(diff(&si, &ss, 2, 0)),
                f(diff(&si, &ss, 2, 1)),
            ),
            lag(2, 0).is_some_and(|l| l < 0.0),
        )
        .with_sensitivity(format!(
            "at 90 % of the change: {}",
            held_word(lag(2, 1).is_some_and(|l| l < 0.0))
        )),
    );
}

fn pts(t: &[f64], v: &[f64]) -> Vec<(f64, f64)> {
    t.iter().zip(v).map(|(a, b)| (*a, *b)).collect()
}

/// A run's samples up to the chaser leaving the table (afterwards it falls).
fn on_table(run: &CaseRun) -> CaseRun {
    let Some((t_off, _)) = run.off_table.iter().find(|(_, b)| b == "chaser") else {
        return run.clone();
    };
    let n = run.t_s.iter().take_while(|t| *t <= t_off).count();
    let mut r = run.clone();
    for v in [
        &mut r.t_s,
        &mut r.x_m,
        &mut r.y_m,
        &mut r.theta_deg,
        &mut r.radial_obstacle_eq8_m,
        &mut r.radial_obstacle_exact_m,
        &mut r.radial_heart_m,
        &mut r.geometry_obstacle_m,
        &mut r.open_nozzles,
        &mut r.gas_kg,
    ] {
        v.truncate(n);
    }
    r
}

/// Runs both cases and writes the report into `out`.
pub fn run(out: &Path) -> Result<(), String> {
    let r = compute(Some(out))?;
    let claims = claims(&r);
    write_report(out, &r, &claims)?;
    for c in &claims {
        println!(
            "[{}] {}: {}",
            if c.held { "held" } else { "NOT HELD" },
            c.id,
            c.measured
        );
    }
    for (t0, rs) in &r.restarts {
        println!(
            "diagnostic: simulation restarted at {t0} s from its own state: docking {} ({}), latch {}",
            rs.dock_state,
            rs.dock_reason,
            fmt_opt(rs.t_latch_s)
        );
    }
    println!("wrote {}", out.join("REPORT.md").display());
    Ok(())
}

/// Fig. 13 (path): both cases, the ghost-obstacle run and the last restart in the table plane.
fn path_plot(r: &Results, s: &CaseRun, e: &CaseRun) -> Plot {
    let p = Xu2019Params::paper();
    let dashed = LineStyle::dashed();
    // Path in the plane.
    let obstacle: Vec<(f64, f64)> = p
        .obstacle
        .outline_lab_m(240)
        .iter()
        .map(|q| (q.x, q.y))
        .collect();
    let heart: Vec<(f64, f64)> = p
        .heart
        .outline_lab_m(240)
        .iter()
        .map(|q| (q.x, q.y))
        .collect();
    let target_body: Vec<(f64, f64)> = (0..=72)
        .map(|k| {
            let a = k as f64 * std::f64::consts::TAU / 72.0;
            (-0.01 + 0.1 * a.cos(), 1.4 + 0.1 * a.sin())
        })
        .collect();
    let mut path = Plot::new("Chaser centre-of-mass path, lab frame (table top)")
        .x_label("x (m)")
        .y_label("y (m)")
        .equal_aspect()
        .x_range(-0.3, 1.7)
        .y_range(-0.25, 2.25)
        .outline(
            "obstacle (superquadric a = 0.1 m, b = 0.2 m, s = 4)",
            obstacle,
        )
        .polygon_styled(
            "heart keep-out (R2 = 0.2 m)",
            heart,
            crate::report::plot::PolygonStyle {
                fill: None,
                stroke: Some(Color::RED),
                width_px: 1.5,
                dash: Dash::Dashed,
                closed: true,
            },
        )
        .outline("target simulator body (r = 0.1 m)", target_body)
        .line("simulation (ideal force)", pts(&s.x_m, &s.y_m))
        .line("experiment (PWPF nozzles)", pts(&e.x_m, &e.y_m))
        .scatter(
            "start (0.809, 0.224) m / goal (0.25, 1.4) m",
            [(0.809, 0.224), (p.goal_pos_lab_m[0], p.goal_pos_lab_m[1])],
        );
    path = path.line_styled(
        "simulation, ghost obstacle (no prism body)",
        pts(
            &on_table(&r.simulation_ghost).x_m,
            &on_table(&r.simulation_ghost).y_m,
        ),
        dashed,
    );
    if let Some((t0, rs)) = r.restarts.last() {
        path = path.line_styled(
            format!("simulation restarted at {t0} s (diagnostic)"),
            pts(&rs.x_m, &rs.y_m),
            LineStyle::dotted(),
        );
    }
    path
}

/// x(t), y(t), θ(t) of both cases.
fn states_figure(s: &CaseRun, e: &CaseRun) -> Figure {
    let p = Xu2019Params::paper();
    Figure::new(
        "Chaser state vs time (lab frame; axes clipped to the approach, the rebound leaves them)",
    )
    .cols(1)
    .plot(
        Plot::new("x(t)")
            .x_label("t (s)")
            .y_label("x (m)")
            .y_range(0.0, 1.0)
            .line("simulation", pts(&s.t_s, &s.x_m))
            .line("experiment", pts(&e.t_s, &e.x_m))
            .hline(p.goal_pos_lab_m[0], "goal 0.25 m"),
    )
    .plot(
        Plot::new("y(t)")
            .x_label("t (s)")
            .y_label("y (m)")
            .y_range(0.0, 1.8)
            .line("simulation", pts(&s.t_s, &s.y_m))
            .line("experiment", pts(&e.t_s, &e.y_m))
            .hline(p.goal_pos_lab_m[1], "goal 1.4 m"),
    )
    .plot(
        Plot::new("θ(t)")
            .x_label("t (s)")
            .y_label("θ (deg)")
            .y_range(-20.0, 140.0)
            .line("simulation", pts(&s.t_s, &s.theta_deg))
            .line("experiment", pts(&e.t_s, &e.theta_deg))
            .hline(90.0, "goal 90°"),
    )
}

/// Radial distances (both forms) and the full-geometry distance to the obstacle.
fn distances_figure(s: &CaseRun, e: &CaseRun) -> Figure {
    let dashed = LineStyle::dashed();
    Figure::new("Distances of the chaser to the constraints")
        .cols(2)
        .plot(
            Plot::new("Radial distance to the obstacle (centre of mass)")
                .x_label("t (s)")
                .y_label("radial distance (m)")
                .y_range(-0.1, 1.2)
                .line("simulation, eq (8)", pts(&s.t_s, &s.radial_obstacle_eq8_m))
                .line("experiment, eq (8)", pts(&e.t_s, &e.radial_obstacle_eq8_m))
                .line_styled(
                    "simulation, exact",
                    pts(&s.t_s, &s.radial_obstacle_exact_m),
                    dashed,
                )
                .line_styled(
                    "experiment, exact",
                    pts(&e.t_s, &e.radial_obstacle_exact_m),
                    dashed,
                )
                .hline(0.0, "boundary"),
        )
        .plot(
            Plot::new("Radial distance to the heart keep-out (centre of mass)")
                .x_label("t (s)")
                .y_label("radial distance (m)")
                .y_range(-0.1, 1.4)
                .line("simulation", pts(&s.t_s, &s.radial_heart_m))
                .line("experiment", pts(&e.t_s, &e.radial_heart_m))
                .hline(0.0, "boundary"),
        )
        .plot(
            Plot::new("Full geometry: chaser (body + cone) ↔ obstacle prism")
                .x_label("t (s)")
                .y_label("distance (m)")
                .y_range(-0.05, 1.0)
                .line("simulation", pts(&s.t_s, &s.geometry_obstacle_m))
                .line("experiment", pts(&e.t_s, &e.geometry_obstacle_m))
                .hline(0.0, "contact"),
        )
}

/// Valve activity and gas used by the experiment.
fn valves_figure(e: &CaseRun) -> Figure {
    let gas_g: Vec<f64> = e.gas_kg.iter().map(|g| g * 1e3).collect();
    Figure::new("Experiment: cold-gas valves")
        .cols(2)
        .plot(
            Plot::new("Open nozzles (mean over each 0.1 s)")
                .x_label("t (s)")
                .y_label("open nozzles (count)")
                .line("experiment", pts(&e.t_s, &e.open_nozzles)),
        )
        .plot(
            Plot::new("CO₂ used")
                .x_label("t (s)")
                .y_label("gas used (g)")
                .line("experiment", pts(&e.t_s, &gas_g)),
        )
}

fn write_report(out: &Path, r: &Results, claims: &[Claim]) -> Result<(), String> {
    let (s, e) = (&on_table(&r.simulation), &on_table(&r.experiment));
    let mut rep = ReportBuilder::new(
        "Xu, Wen, Wei (2019): air-bearing rendezvous and docking with a superquadric obstacle and a heart-shaped target",
    );
    rep.paragraph(
        "J. Dynamics and Control 17(1), 2019, DOI 10.6052/1672-6553-2019-052. Fig. 13 reproduced on \
         the lab twin: a granite air-bearing table (2 m × 2.5 m), two 9 kg simulators, the \
         potential-function law of eqs (12)–(16) with Table 2's gains, as published (eq (8) \
         radial distance, printed gradient), from (0.809 m, 0.224 m, 7°) to (0.25 m, 1.4 m, 90°), \
         ending with the electromagnetic cone/slot capture. Frame: the lab frame of the table \
         (x, y in the table top, z up, top at z = 0); θ is the chaser's yaw about z from x.",
    );
    rep.paragraph(
        "Cases. *simulation*: the commanded force and torque applied exactly (continuous, \
         unlimited), ideal sensor (pose and velocity every 5 ms step), I_z = 0.05 kg·m². \
         *experiment*: the eight 0.05 N nozzles of Fig. 10 (a pair gives 0.009 N·m) on/off \
         through one PWPF modulator per channel (K_m 4.5, T_m 0.2 s, U_on 0.45, U_off 0.15), 5 % \
         thrust noise, vision pose every 0.04 s with 0.5 mm / 0.2° noise and 0.04 s latency, \
         velocity differenced from successive poses and low-passed (0.1 s), and a true \
         I_z = 0.055 kg·m² (10 % above the measured value the law's gains were tuned with; the \
         law itself does not use I_z). Both: when the cone is 3 cm from its seat the \
         electromagnet switches on and the law stops commanding (the mechanism does the rest) — \
         our choice: the paper does not say the law stops, so every goal claim is also judged \
         with the law kept active (`release_on_magnet: false`).",
    );
    rep.claims(claims);
    rep.heading("Figures");
    rep.figure(
        "path",
        "Path in the plane with the obstacle, the heart keep-out and the target body",
        Figure::new("Fig. 13 (path)").plot(path_plot(r, s, e)),
    );
    rep.figure(
        "states",
        "x(t), y(t), θ(t) of both cases",
        states_figure(s, e),
    );
    rep.figure(
        "distances",
        "Radial distances (both forms) and the full-geometry distance to the obstacle",
        distances_figure(s, e),
    );
    rep.figure(
        "valves",
        "Valve activity and gas used (experiment)",
        valves_figure(e),
    );
    numbers_section(&mut rep, s, e);
    variants_section(&mut rep, r);
    choices_section(&mut rep);
    restarts_section(&mut rep, r);
    rep.write(out)
        .map_err(|e| format!("cannot write the report in {}: {e}", out.display()))?;
    Ok(())
}

/// The numbers of both cases: settling, capture, distances, collisions, gas, steps.
fn numbers_section(rep: &mut ReportBuilder, s: &CaseRun, e: &CaseRun) {
    rep.heading("Numbers");
    let mut rows = settling_rows(s, e);
    rows.extend(outcome_rows(s, e));
    rep.table(&["quantity", "simulation", "experiment"], &rows);
}

/// Rows of the numbers table: settling times, magnet, docking.
fn settling_rows(s: &CaseRun, e: &CaseRun) -> Vec<Vec<String>> {
    let ssim = settling(s);
    let sexp = settling(e);
    let f = |x: Option<f64>| x.map_or("n/a".into(), |x| format!("{x:.1}"));
    vec![
        vec![
            "x: 50 % / 90 % of the change (s)".into(),
            format!("{} / {}", f(ssim[0][0]), f(ssim[0][1])),
            format!("{} / {}", f(sexp[0][0]), f(sexp[0][1])),
        ],
        vec![
            "y: 50 % / 90 % of the change (s)".into(),
            format!("{} / {}", f(ssim[1][0]), f(ssim[1][1])),
            format!("{} / {}", f(sexp[1][0]), f(sexp[1][1])),
        ],
        vec![
            "θ: 50 % / 90 % of the change (s)".into(),
            format!("{} / {}", f(ssim[2][0]), f(ssim[2][1])),
            format!("{} / {}", f(sexp[2][0]), f(sexp[2][1])),
        ],
        vec![
            "magnet on (law hands over) (s)".into(),
            fmt_opt(s.magnet_on_s),
            fmt_opt(e.magnet_on_s),
        ],
        vec![
            "docking".into(),
            format!("{}: {}", s.dock_state, s.dock_reason),
            format!("{}: {}", e.dock_state, e.dock_reason),
        ],
    ]
}

/// Rows of the numbers table: distances, collisions, table, gas, valves, steps.
fn outcome_rows(s: &CaseRun, e: &CaseRun) -> Vec<Vec<String>> {
    vec![
        vec![
            "min radial distance over the whole run, obstacle eq (8) / exact (m)".into(),
            format!(
                "{:.4} / {:.4}",
                CaseRun::min(&s.radial_obstacle_eq8_m),
                CaseRun::min(&s.radial_obstacle_exact_m)
            ),
            format!(
                "{:.4} / {:.4}",
                CaseRun::min(&e.radial_obstacle_eq8_m),
                CaseRun::min(&e.radial_obstacle_exact_m)
            ),
        ],
        vec![
            "min full-geometry distance to the obstacle, whole run (m)".into(),
            format!(
                "{:.4} ({}, {:.2} s)",
                s.min_geometry_obstacle.0, s.min_geometry_obstacle.1, s.min_geometry_obstacle.2
            ),
            format!(
                "{:.4} ({}, {:.2} s)",
                e.min_geometry_obstacle.0, e.min_geometry_obstacle.1, e.min_geometry_obstacle.2
            ),
        ],
        vec![
            "collisions (all pairs)".into(),
            s.collisions.to_string(),
            e.collisions.to_string(),
        ],
        vec![
            "off the table".into(),
            format!("{:?}", s.off_table),
            format!("{:?}", e.off_table),
        ],
        vec![
            "gas used (g)".into(),
            "—".into(),
            format!("{:.2}", e.gas_kg.last().copied().unwrap_or(0.0) * 1e3),
        ],
        vec![
            "valve openings per nozzle (1-1 … 4-2)".into(),
            "—".into(),
            format!("{:?}", e.valve_openings),
        ],
        vec![
            "steps / wall time".into(),
            format!("{} / {:.1} s", s.steps, s.wall_s),
            format!("{} / {:.1} s", e.steps, e.wall_s),
        ],
    ]
}

/// The variants: law kept active, ghost obstacle, tuned inertia.
fn variants_section(rep: &mut ReportBuilder, r: &Results) {
    rep.heading("Variants: law kept active, ghost obstacle, tuned inertia");
    let variant_row = |label: &str, run: &CaseRun| {
        vec![
            label.to_string(),
            format!(
                "{:.4} m / {:.2}°",
                run.final_pos_err_m, run.final_angle_err_deg
            ),
            format!("{}: {}", run.dock_state, run.dock_reason),
            fmt_opt(run.t_latch_s),
            run.obstacle_collisions.len().to_string(),
            run.collisions.to_string(),
        ]
    };
    rep.table(
        &[
            "run",
            "final |Δp| / |Δθ|",
            "docking",
            "latch",
            "obstacle collisions",
            "collisions (all pairs)",
        ],
        &[
            variant_row("simulation (law off at the magnet)", &r.simulation),
            variant_row("simulation, law kept active", &r.simulation_active),
            variant_row("simulation, ghost obstacle", &r.simulation_ghost),
            variant_row("experiment (law off at the magnet)", &r.experiment),
            variant_row("experiment, law kept active", &r.experiment_active),
            variant_row("experiment, ghost obstacle", &r.experiment_ghost),
            variant_row(
                "experiment, I_z = 0.05 kg·m² (tuned value)",
                &r.experiment_tuned_iz,
            ),
        ],
    );
    variants_paragraph(rep, r);
}

/// What the variants show: the latch angle, the contacts' effect on the path, the inertia.
fn variants_paragraph(rep: &mut ReportBuilder, r: &Results) {
    let dev = |a: &CaseRun, b: &CaseRun| {
        let t = a.obstacle_collisions.first().map_or(f64::INFINITY, |c| c.0);
        path_deviation_m(a, b, t)
    };
    let (ds, de) = (
        dev(&r.simulation, &r.simulation_ghost),
        dev(&r.experiment, &r.experiment_ghost),
    );
    rep.paragraph(format!(
        "**Law kept active.** With the law switched off at the magnet, contact and the \
         magnet's pull turn the chaser after the hand-over and it latches at the angle it \
         has then ({:.2}° simulation, {:.2}° experiment); with the law kept active the \
         attitude loop keeps acting while seated and it latches at {:.2}° / {:.2}°. The 2° \
         goal verdict of the simulation case depends on that choice, which the paper does not \
         make.\n\n\
         **Ghost obstacle.** Without the prism body (the law still avoids the superquadric it \
         knows) the path is the real run's until the first obstacle contact (largest \
         difference {:.1e} m simulation, {:.1e} m experiment), then up to {:.3} m / {:.3} m \
         apart: that is what the contacts changed. The ghost runs end {} / {}, latched at {} / {} \
         against {} / {} with the prism.\n\n\
         **Attitude and inertia.** The paper attributes its attitude lead to a measured I_z \
         slightly *below* the true one. A larger true inertia makes the same torque turn the \
         chaser more slowly, so that explanation predicts a lag, not a lead. The experiment \
         case (true I_z = 0.055 kg·m²) lags by {} / {} (50 % / 90 % of the change in θ); with \
         its I_z set to the tuned 0.05 kg·m² it lags by {} / {}: on the twin the attitude \
         timing is set by the nozzles and the vision, not by the inertia error (claim \
         `experiment-attitude-leads`).",
        r.simulation.final_angle_err_deg,
        r.experiment.final_angle_err_deg,
        r.simulation_active.final_angle_err_deg,
        r.experiment_active.final_angle_err_deg,
        ds.0,
        de.0,
        ds.1,
        de.1,
        r.simulation_ghost.dock_state,
        r.experiment_ghost.dock_state,
        fmt_opt(r.simulation_ghost.t_latch_s),
        fmt_opt(r.experiment_ghost.t_latch_s),
        fmt_opt(r.simulation.t_latch_s),
        fmt_opt(r.experiment.t_latch_s),
        lag_s(&r.experiment, &r.simulation, 0),
        lag_s(&r.experiment, &r.simulation, 1),
        lag_s(&r.experiment_tuned_iz, &r.simulation, 0),
        lag_s(&r.experiment_tuned_iz, &r.simulation, 1),
    ));
}

/// Choices where the paper is silent, and how to read the result.
fn choices_section(rep: &mut ReportBuilder) {
    rep.heading("Choices where the paper is silent");
    rep.paragraph(
        "Geometry: both simulators are cylinders of radius 0.1 m (the nozzle lever arm 0.09 m \
         that gives the 0.009 N·m couple), 0.3 m tall; the cone (base 3 cm, tip 0.8 cm, 5 cm long) \
         stands on the chaser's +y face, which points along lab −x at θ = 90°; the slot (mouth \
         4 cm, throat 1.2 cm, 4 cm deep) is on the target's +x face. The target sits so that the \
         seated chaser centre of mass is exactly the goal: its centre is at (−0.01, 1.4) m, \
         inside the heart keep-out, and it is held still (anchored: the paper treats the target \
         as stationary). The table spans x ∈ [−0.3, 1.7] m, y ∈ [−0.25, 2.25] m. The obstacle is \
         a 0.3 m prism with the superquadric cross-section, bolted to the table. Magnet: \
         F = min(0.2 N / (1 + gap/1 cm)², 0.2 N), on at 3 cm. Air film: no residual friction or \
         drag, no tilt (the paper reports none). Measurement noise, latency and the velocity \
         filter are assumptions (the paper gives the 25 Hz rate only).",
    );
    rep.heading("Reading the result");
    rep.paragraph(
        "The law only sees the centre of mass; the monitor sees the bodies. The radial distances of \
         Fig. 13a stay positive, but at the closest approach the chaser's cone — already turned \
         towards −x by the attitude loop — reaches the obstacle prism: a collision in full \
         geometry the centre-of-mass picture cannot show (see the claims and the distance \
         figure). Every collision is a real rapier contact: it deflects the chaser. The docking \
         row says what the mechanism did; where the capture fails, the events in \
         `<case>/events.jsonl` give the sequence (magnet on, contact, rebound or miss, and why).",
    );
}

/// Diagnostic (only when the simulation case was restarted): the restarts' outcomes.
fn restarts_section(rep: &mut ReportBuilder, r: &Results) {
    if !r.restarts.is_empty() {
        rep.heading("Diagnostic: the capture is sensitive to the last millimetres");
        let rows: Vec<Vec<String>> = r
            .restarts
            .iter()
            .map(|(t0, rs)| {
                vec![
                    format!("{t0} s"),
                    fmt_opt(rs.magnet_on_s),
                    format!("{}: {}", rs.dock_state, rs.dock_reason),
                    fmt_opt(rs.t_latch_s),
                ]
            })
            .collect();
        rep.paragraph(format!(
            "The simulation case did not latch ({}: {}). The same case restarted from its own \
             recorded f64 state (fresh rapier world, law and sensor) arrives at the slot on the \
             same path (the full run's magnet switched on at {}; compare the restarts' times \
             below), yet the outcome differs:",
            r.simulation.dock_state,
            r.simulation.dock_reason,
            fmt_opt(r.simulation.magnet_on_s),
        ));
        rep.table(&["restart at", "magnet on", "docking", "latch"], &rows);
        rep.paragraph(
            "The per-case `events.jsonl` gives the sequence (magnet on, contacts with their peak \
             forces, rebound or miss, and why).",
        );
    }
}
