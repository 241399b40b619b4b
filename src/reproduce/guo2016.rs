//! `rpod reproduce guo2016`: Guo, Song, Li (2016), Section 5, in the full simulation
//! (f64 truth, rapier contacts, full-geometry monitor), and a campaign beyond the paper.
//!
//! Cases (scenes `scenes/guo2016_corridor.ron` and `scenes/guo2016_no_avoidance.ron`, bundled
//! into the binary so the reproduction runs from any directory):
//! - **paper, k2 = 0.02** and **paper, k2 = 0**: the paper's gains, 100 s;
//! - **extra, not in the paper**: the same with a linear reaching term `k_r = 1/s`
//!   (`reaching_gain_per_s`), σ(0) = 0, 20 s — what the law does when its errors do converge;
//! - **campaign, beyond the paper**: [`CAMPAIGN_RUNS`] seeded start positions and velocities
//!   inside the corridor, reaching variant, k2 = 0.02, [`CAMPAIGN_DURATION_S`] each: how often
//!   the point-mass corridor held while the chaser's full geometry came within
//!   [`PANEL_CLEARANCE_M`] of a target solar-wing part (panel or boom).
//!
//! [`compute`] runs everything and returns the numbers; [`run`] also writes `REPORT.md`, the
//! plots and `claims.json`. Tests use [`run_case`] with shortened horizons.

use crate::control::ControllerSpec;
use crate::control::guo2016::SceneSpec;
use crate::geometry::cissoid::Cissoid;
use crate::scene::{AttitudeSpec, LoadedScene, PartRole, load_scene_str};
use crate::sim::laws::guo2016::Guo2016Controllers;
use crate::sim::monitor::shape_distance;
use crate::sim::{BodyState, Part, Roster, SimBody, Simulation};
use bevy_rapier3d::rapier::prelude as rp;
use nalgebra::{Isometry3, Vector3};
use std::path::Path;

/// The k2 = 0.02 scene text.
pub const CORRIDOR_SCENE: &str = include_str!("../../scenes/guo2016_corridor.ron");
/// The k2 = 0 scene text.
pub const NO_AVOIDANCE_SCENE: &str = include_str!("../../scenes/guo2016_no_avoidance.ron");
/// Horizon of the paper-gain cases, s (the paper's is in its lost figures).
pub const PAPER_DURATION_S: f64 = 100.0;
/// Horizon of the reaching-variant cases, s.
pub const REACHING_DURATION_S: f64 = 20.0;
/// Linear reaching gain of the extra cases, 1/s (not in the paper).
pub const REACHING_GAIN_PER_S: f64 = 1.0;
/// Campaign size.
pub const CAMPAIGN_RUNS: usize = 50;
/// Campaign horizon per run, s.
pub const CAMPAIGN_DURATION_S: f64 = 15.0;
/// Clearance to a target solar-wing part (panel or boom) that the campaign counts as "close", m.
pub const PANEL_CLEARANCE_M: f64 = 0.5;
/// Largest initial attitude error of a campaign start, deg.
pub const CAMPAIGN_MAX_TILT_DEG: f64 = 40.0;
/// Campaign seed.
pub const CAMPAIGN_SEED: u64 = 2016;

/// Loads one of the bundled scenes by its file name.
pub fn load_bundled(file: &str) -> Result<LoadedScene, String> {
    let text = match file {
        "scenes/guo2016_corridor.ron" => CORRIDOR_SCENE,
        "scenes/guo2016_no_avoidance.ron" => NO_AVOIDANCE_SCENE,
        other => return Err(format!("no bundled scene {other}")),
    };
    load_scene_str(text, file, &[]).map_err(|e| e.to_string())
}

/// The scene's (first) Guo2016 controller entry, for changes made before a run.
pub fn spec_mut(loaded: &mut LoadedScene) -> Option<&mut SceneSpec> {
    loaded.scene.controllers.iter_mut().find_map(|c| match c {
        ControllerSpec::Guo2016(s) => Some(s),
        _ => None,
    })
}

/// One recorded sample of a run.
#[derive(Debug, Clone, Copy)]
pub struct Sample {
    /// Time, s.
    pub t_s: f64,
    /// Attitude error σ_e (MRP).
    pub sigma_e: Vector3<f64>,
    /// Angular-velocity error ω_e, chaser body axes, rad/s.
    pub omega_e_rad_s: Vector3<f64>,
    /// Commanded torque, chaser body axes, N·m.
    pub torque_body_nm: Vector3<f64>,
    /// Commanded force, chaser body axes, N.
    pub force_body_n: Vector3<f64>,
    /// Chaser centre of mass in target body axes, m.
    pub r1_target_m: Vector3<f64>,
    /// Its rate seen in the target frame, target axes, m/s.
    pub v1_target_m_s: Vector3<f64>,
    /// |r_e|, m.
    pub r_e_m: f64,
    /// Corridor function h, m².
    pub h_m2: f64,
    /// Signed distance to the corridor wall, m.
    pub corridor_margin_m: f64,
    /// Full-geometry minimum distance chaser–target, m.
    pub min_distance_m: f64,
}

/// What one run measured.
#[derive(Debug, Clone)]
pub struct CaseRun {
    /// Label.
    pub label: String,
    /// Samples (every step for the first 2 s, then every 10 steps, and the last step).
    pub samples: Vec<Sample>,
    /// h > 0 (strictly inside) at every control step.
    pub corridor_held: bool,
    /// First control step found outside, s.
    pub first_exit_s: Option<f64>,
    /// Smallest h over the run, m².
    pub min_h_m2: f64,
    /// Smallest signed distance to the corridor wall (monitor guarantee), m.
    pub min_corridor_margin_m: f64,
    /// Final |r_e|, m.
    pub final_r_e_m: f64,
    /// Final |σ_e|.
    pub final_sigma_e: f64,
    /// Largest |F| commanded, N.
    pub max_force_n: f64,
    /// Largest |τ| commanded, N·m.
    pub max_torque_nm: f64,
    /// Smallest full-geometry distance chaser–target over the run, m.
    pub min_distance_m: f64,
    /// The parts of that closest approach (`body/part`).
    pub min_distance_parts: (String, String),
    /// When, s.
    pub min_distance_t_s: f64,
    /// Smallest distance from any chaser part to a target solar-wing part (panel or boom), m.
    pub min_wing_distance_m: f64,
    /// Which target wing part, and when (s).
    pub min_wing_part: String,
    /// When, s.
    pub min_wing_t_s: f64,
    /// First contact of any two parts, s.
    pub first_contact_s: Option<f64>,
    /// First collision (contact between non-docking parts), s.
    pub first_collision_s: Option<f64>,
    /// Wall-clock time of the run, s.
    pub wall_s: f64,
}

/// World poses and shapes of the colliders of one body.
fn body_colliders(
    sim: &mut Simulation,
    body: usize,
    filter: impl Fn(PartRole) -> bool,
) -> Vec<(String, Isometry3<f64>, rp::SharedShape)> {
    let w = sim.app.world_mut();
    let roster = w.resource::<Roster>().clone();
    let e = roster.bodies[body];
    let b = w.get::<SimBody>(e).expect("body").clone();
    let s = w.get::<BodyState>(e).expect("state").clone();
    let pose = s.body_pose(&b.com_body_m);
    roster.parts[body]
        .iter()
        .filter_map(|pe| {
            let p = w.get::<Part>(*pe).expect("part");
            filter(p.role).then(|| (p.name.clone(), pose * p.pose_body, p.shape.clone()))
        })
        .collect()
}

/// Smallest distance between any chaser part and any target solar-wing part, with the wing part.
fn wing_distance(sim: &mut Simulation, chaser: usize, target: usize) -> (f64, String) {
    let c = body_colliders(sim, chaser, |_| true);
    let t = body_colliders(sim, target, |r| {
        matches!(r, PartRole::Panel | PartRole::Boom)
    });
    let mut best = (f64::INFINITY, String::new());
    for (_, pa, sa) in &c {
        for (nb, pb, sb) in &t {
            let d = shape_distance(pa, &**sa, pb, &**sb);
            if d < best.0 {
                best = (d, nb.clone());
            }
        }
    }
    best
}

/// Runs a loaded Guo 2016 scene for `duration_s` and measures it. `wing_every_steps`: how
/// often the chaser–wing distance is computed (0 = never).
pub fn run_case(
    loaded: &LoadedScene,
    label: &str,
    duration_s: f64,
    wing_every_steps: u64,
) -> Result<CaseRun, String> {
    let mut sim = Simulation::new(loaded).map_err(|e| e.to_string())?;
    let steps = sim.steps_for(duration_s);
    let (chaser, target) = {
        let c = &sim.app.world().resource::<Guo2016Controllers>().list[0];
        (c.chaser, c.target)
    };
    let mut run = CaseRun {
        label: label.to_string(),
        samples: Vec::new(),
        corridor_held: true,
        first_exit_s: None,
        min_h_m2: f64::INFINITY,
        min_corridor_margin_m: f64::INFINITY,
        final_r_e_m: f64::NAN,
        final_sigma_e: f64::NAN,
        max_force_n: 0.0,
        max_torque_nm: 0.0,
        min_distance_m: f64::INFINITY,
        min_distance_parts: (String::new(), String::new()),
        min_distance_t_s: 0.0,
        min_wing_distance_m: f64::INFINITY,
        min_wing_part: String::new(),
        min_wing_t_s: 0.0,
        first_contact_s: None,
        first_collision_s: None,
        wall_s: 0.0,
    };
    let dt = sim.scene.dt_s;
    let dense = (2.0 / dt).round() as u64;
    let t0 = std::time::Instant::now();
    for k in 0..=steps {
        if wing_every_steps > 0 && k % wing_every_steps == 0 {
            let (d, part) = wing_distance(&mut sim, chaser, target);
            if d < run.min_wing_distance_m {
                run.min_wing_distance_m = d;
                run.min_wing_part = part;
                run.min_wing_t_s = sim.t_s();
            }
        }
        if k == steps {
            break;
        }
        sim.step(1);
        // The control step just taken ran at t = (k) dt; read what it saw and commanded.
        let w = sim.app.world();
        let c = &w.resource::<Guo2016Controllers>().list[0];
        let d = c.diagnostics.expect("the law ran");
        let t = k as f64 * dt;
        if !d.inside && run.first_exit_s.is_none() {
            run.first_exit_s = Some(t);
            run.corridor_held = false;
        }
        run.min_h_m2 = run.min_h_m2.min(d.h_m2);
        run.max_force_n = run.max_force_n.max(c.command.force_body_n.norm());
        run.max_torque_nm = run.max_torque_nm.max(c.command.torque_body_nm.norm());
        let r_e = Vector3::new(d.x[3], d.x[4], d.x[5]).norm();
        run.final_r_e_m = r_e;
        run.final_sigma_e = Vector3::new(d.x[0], d.x[1], d.x[2]).norm();
        if k < dense || k % 10 == 0 || k + 1 == steps {
            let obs = c.observation.expect("observed");
            let q_t = obs.q_target_body_to_world;
            let r1 = d.r1_target_m;
            let v1 = q_t.inverse() * obs.vel_rel_world_m_s - obs.rate_target_body_rad_s.cross(&r1);
            let mon = w.resource::<crate::sim::MonitorState>();
            run.samples.push(Sample {
                t_s: t,
                sigma_e: Vector3::new(d.x[0], d.x[1], d.x[2]),
                omega_e_rad_s: d.omega_e_body_rad_s,
                torque_body_nm: c.command.torque_body_nm,
                force_body_n: c.command.force_body_n,
                r1_target_m: r1,
                v1_target_m_s: v1,
                r_e_m: r_e,
                h_m2: d.h_m2,
                corridor_margin_m: c.corridor_margin_m,
                min_distance_m: mon.pairs.first().map_or(f64::NAN, |p| p.distance_m),
            });
        }
    }
    run.wall_s = t0.elapsed().as_secs_f64();
    let g = sim.guarantees();
    if let Some(i) = g.list.iter().position(|x| x.name() == spec_name(loaded)) {
        run.min_corridor_margin_m = g.status[i].worst_margin;
    }
    let mon = sim.monitor();
    if let (Some(m), Some(p)) = (mon.min_per_pair.first(), mon.pairs.first()) {
        run.min_distance_m = m.distance_m;
        run.min_distance_parts = (
            mon.part_name(p.a, m.part_a).to_string(),
            mon.part_name(p.b, m.part_b).to_string(),
        );
        run.min_distance_t_s = m.t_s;
    }
    let cs = sim.contacts();
    run.first_contact_s = cs.first_contact_s;
    run.first_collision_s = cs.first_collision_s;
    Ok(run)
}

fn spec_name(loaded: &LoadedScene) -> String {
    loaded
        .scene
        .controllers
        .iter()
        .find_map(|c| match c {
            ControllerSpec::Guo2016(s) => Some(s.corridor_guarantee.clone()),
            _ => None,
        })
        .unwrap_or_default()
}

/// The bundled scene with the reaching variant: `k_r` = [`REACHING_GAIN_PER_S`], σ(0) = 0
/// (chaser aligned with D0), at rest in attitude.
pub fn reaching_variant(file: &str) -> Result<LoadedScene, String> {
    let mut l = load_bundled(file)?;
    spec_mut(&mut l)
        .ok_or("no Guo2016 controller")?
        .reaching_gain_per_s = REACHING_GAIN_PER_S;
    set_chaser_aligned(&mut l);
    Ok(l)
}

/// Sets the chaser attitude to D0 (the target frame turned by π about z; the bundled
/// target starts at the identity attitude).
fn set_chaser_aligned(l: &mut LoadedScene) {
    if let Some(b) = l.scene.bodies.iter_mut().find(|b| b.name == "chaser") {
        b.initial.attitude = AttitudeSpec::Quat {
            w: 0.0,
            x: 0.0,
            y: 0.0,
            z: 1.0,
        };
    }
}

/// A deterministic 64-bit LCG (Knuth's MMIX constants), uniform in [0, 1).
#[derive(Debug, Clone)]
pub struct Lcg(pub u64);

impl Lcg {
    /// Next uniform number in [0, 1).
    pub fn uniform(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// One campaign start: position and velocity in the target frame (= world axes).
#[derive(Debug, Clone, Copy)]
pub struct CampaignStart {
    /// Chaser centre of mass, target axes, m.
    pub r0_m: Vector3<f64>,
    /// Chaser velocity, target axes, m/s.
    pub v0_m_s: Vector3<f64>,
    /// Chaser attitude relative to D0 (MRP): the initial attitude error.
    pub sigma0: Vector3<f64>,
}

/// The campaign's starts: axial coordinate x uniform in [1.6, 12] m, radial distance
/// `0.9·ρ(x)·√u` (uniform over the corridor's cross-section inside 90 % of its radius),
/// azimuth uniform, velocity uniform in direction with speed uniform in [0, 0.5] m/s, attitude
/// error about a uniformly random axis with angle uniform in [0, [`CAMPAIGN_MAX_TILT_DEG`]].
pub fn campaign_starts(corridor: &Cissoid, n: usize, seed: u64) -> Vec<CampaignStart> {
    let mut rng = Lcg(seed);
    (0..n)
        .map(|_| {
            let x = 1.6 + (12.0 - 1.6) * rng.uniform();
            let rho = 0.9 * corridor.radius_at_m(x).unwrap_or(0.0) * rng.uniform().sqrt();
            let phi = std::f64::consts::TAU * rng.uniform();
            let cz = 2.0 * rng.uniform() - 1.0;
            let az = std::f64::consts::TAU * rng.uniform();
            let sz = (1.0 - cz * cz).sqrt();
            let speed = 0.5 * rng.uniform();
            let cz2 = 2.0 * rng.uniform() - 1.0;
            let az2 = std::f64::consts::TAU * rng.uniform();
            let sz2 = (1.0 - cz2 * cz2).sqrt();
            let angle = CAMPAIGN_MAX_TILT_DEG.to_radians() * rng.uniform();
            CampaignStart {
                r0_m: Vector3::new(x, rho * phi.cos(), rho * phi.sin()),
                v0_m_s: Vector3::new(sz * az.cos(), sz * az.sin(), cz) * speed,
                // MRP of a rotation by `angle` about the unit axis: tan(angle/4)·axis.
                sigma0: Vector3::new(sz2 * az2.cos(), sz2 * az2.sin(), cz2) * (angle / 4.0).tan(),
            }
        })
        .collect()
}

/// Outcome of one campaign start.
#[derive(Debug, Clone)]
pub struct CampaignRun {
    /// The start.
    pub start: CampaignStart,
    /// `None` if the start itself was refused (chaser parts overlapping the target at t = 0),
    /// with the reason.
    pub refused: Option<String>,
    /// The run, if it ran.
    pub run: Option<CaseRun>,
}

impl CampaignRun {
    /// Outcome category: 0 corridor held and wings clear, 1 corridor held but a wing part
    /// within [`PANEL_CLEARANCE_M`], 2 corridor left, wings clear, 3 corridor left and wing
    /// close, 4 refused at t = 0 (overlap).
    pub fn category(&self) -> usize {
        match &self.run {
            None => 4,
            Some(r) => {
                let close = r.min_wing_distance_m < PANEL_CLEARANCE_M;
                match (r.corridor_held, close) {
                    (true, false) => 0,
                    (true, true) => 1,
                    (false, false) => 2,
                    (false, true) => 3,
                }
            }
        }
    }
}

/// Names of [`CampaignRun::category`].
pub const CATEGORIES: [&str; 5] = [
    "corridor held, wings clear",
    "corridor held, wing part within 0.5 m",
    "corridor left, wings clear",
    "corridor left, wing part within 0.5 m",
    "refused: overlaps the target at t = 0",
];

/// Runs the campaign (reaching variant, k2 = 0.02; the bundled target is at rest with the
/// identity attitude, so target frame = world axes).
pub fn campaign(n: usize, seed: u64, duration_s: f64) -> Result<Vec<CampaignRun>, String> {
    let base = reaching_variant("scenes/guo2016_corridor.ron")?;
    let corridor = spec_of(&base)
        .params(1.0, nalgebra::Matrix3::identity())
        .corridor();
    let mut out = Vec::new();
    for s in campaign_starts(&corridor, n, seed) {
        let mut l = base.clone();
        if let Some(b) = l.scene.bodies.iter_mut().find(|b| b.name == "chaser") {
            b.initial.pos_m = s.r0_m.into();
            b.initial.vel_m_s = s.v0_m_s.into();
            let q = crate::control::guo2016::q_d0_to_target()
                * crate::math::mrp::quat_from_mrp(&s.sigma0);
            b.initial.attitude = AttitudeSpec::Quat {
                w: q.w,
                x: q.i,
                y: q.j,
                z: q.k,
            };
        }
        match run_case(&l, "campaign", duration_s, 1) {
            Ok(r) => out.push(CampaignRun {
                start: s,
                refused: None,
                run: Some(r),
            }),
            Err(e) if e.contains("overlaps") => out.push(CampaignRun {
                start: s,
                refused: Some(e),
                run: None,
            }),
            Err(e) => return Err(e),
        }
    }
    Ok(out)
}

/// The scene's Guo2016 entry.
pub fn spec_of(l: &LoadedScene) -> SceneSpec {
    l.scene
        .controllers
        .iter()
        .find_map(|c| match c {
            ControllerSpec::Guo2016(s) => Some(s.clone()),
            _ => None,
        })
        .expect("a Guo2016 controller")
}

/// Runs the paper's cases and writes REPORT.md, plots and claims.json into `out`.
pub fn run(_out: &Path) -> Result<(), String> {
    Err("report module missing".into())
}
