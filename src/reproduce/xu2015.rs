//! `rpod reproduce xu2015`: Xu & Hu (2015) §3 in the ECS — ACCM against PD, chaser 90/100/110 kg,
//! the target maneuvering on its e = 0.7 orbit (scenes `scenes/xu2015_*.ron`, embedded here).
//!
//! Cases: the six scenes as written (real geometry, 3 m stand-off of the aim point behind the
//! target); and, for 110 kg, the same control problem with the aim point also displaced 10 m
//! toward Earth (`aim_offset_tof_m = (−3, 0, 10)`, the chaser's start moved with it) so the
//! saturated oscillation cannot bring the bodies into contact: that is the point-mass run the
//! paper's model describes. Terminal accuracy = |ξ − goal| over the last 100 s (t ≥ 200 s),
//! sampled at the control period h = 0.1 s.

use crate::control::xu2015::{
    Accm, AccmParams, ManeuverSpec, Pd, PdParams, Xu2015Law, Xu2015Observation,
    dcm_eci_from_tof_state,
};
use crate::control::xu2015::{Xu2015Loop, Xu2015Sample};
use crate::orbit::elliptic::{EllipticOrbit, RelStateTof, rk4_step_relative};
use crate::report::{Claim, Dash, Figure, LineStyle, Plot, write_atomic, write_claims_json};
use crate::scene::{SceneError, load_scene_str};
use crate::sim::Simulation;
use nalgebra::Vector3;
use std::path::Path;

/// The bundled scenes: (file name, text).
pub const SCENES: [(&str, &str); 6] = [
    (
        "xu2015_accm.ron",
        include_str!("../../scenes/xu2015_accm.ron"),
    ),
    ("xu2015_pd.ron", include_str!("../../scenes/xu2015_pd.ron")),
    (
        "xu2015_accm_m90.ron",
        include_str!("../../scenes/xu2015_accm_m90.ron"),
    ),
    (
        "xu2015_pd_m90.ron",
        include_str!("../../scenes/xu2015_pd_m90.ron"),
    ),
    (
        "xu2015_accm_m110.ron",
        include_str!("../../scenes/xu2015_accm_m110.ron"),
    ),
    (
        "xu2015_pd_m110.ron",
        include_str!("../../scenes/xu2015_pd_m110.ron"),
    ),
];

/// Overrides that move the aim point 10 m toward Earth (tof +z) and the chaser's start with it
/// (Hill radial = −tof z), so the bodies cannot touch (see module docs).
pub const POINT_MASS_OVERRIDES: [&str; 2] = [
    "controllers.0.0.aim_offset_tof_m=(-3.0, 0.0, 10.0)",
    "bodies.chaser.initial.pos_m=(-15.0, -23.0, 0.0)",
];

/// Start of the terminal window, s (the last 100 s of the 300 s run).
pub const TERMINAL_FROM_S: f64 = 200.0;

/// The text of a bundled scene.
pub fn scene_text(file: &str) -> Option<&'static str> {
    SCENES.iter().find(|(f, _)| *f == file).map(|(_, t)| *t)
}

/// One run's record and measures.
#[derive(Debug, Clone)]
pub struct CaseRun {
    /// Scene file (and overrides) it came from.
    pub label: String,
    /// Law flown.
    pub law: Xu2015Law,
    /// Chaser mass, kg.
    pub mass_chaser_kg: f64,
    /// Goal ξ, tof, m.
    pub goal_tof_m: Vector3<f64>,
    /// Per control sample.
    pub samples: Vec<Xu2015Sample>,
    /// Full-geometry chaser–target distance at each control sample, m.
    pub distance_m: Vec<f64>,
    /// The run summary (`summary.json` content).
    pub summary: serde_json::Value,
    /// Angle between the reference orbit's tof and the actual target's osculating tof at the
    /// end of the run, rad.
    pub frame_tilt_end_rad: f64,
    /// Distance of the target from the reference orbit (the world origin) at the end, m.
    pub target_drift_end_m: f64,
}

impl CaseRun {
    /// Samples of the terminal window (t ≥ [`TERMINAL_FROM_S`]).
    pub fn terminal(&self) -> impl Iterator<Item = &Xu2015Sample> {
        self.samples
            .iter()
            .filter(|s| s.t_s >= TERMINAL_FROM_S - 1e-9)
    }

    /// RMS of |ξ − goal| over the terminal window, m.
    pub fn terminal_rms_m(&self) -> f64 {
        let (s, n) = self.terminal().fold((0.0, 0usize), |(s, n), x| {
            (s + (x.xi_tof_m - self.goal_tof_m).norm_squared(), n + 1)
        });
        (s / n.max(1) as f64).sqrt()
    }

    /// Max of |ξ − goal| over the terminal window, m.
    pub fn terminal_max_m(&self) -> f64 {
        self.terminal()
            .map(|x| (x.xi_tof_m - self.goal_tof_m).norm())
            .fold(0.0, f64::max)
    }

    /// Per-axis max |ξ_i − goal_i| over the terminal window, m.
    pub fn terminal_max_axis_m(&self) -> Vector3<f64> {
        self.terminal().fold(Vector3::zeros(), |m, x| {
            m.zip_map(&(x.xi_tof_m - self.goal_tof_m), |a: f64, b: f64| {
                a.max(b.abs())
            })
        })
    }

    /// RMS of |u| over the whole run, N.
    pub fn rms_thrust_n(&self) -> f64 {
        let s: f64 = self
            .samples
            .iter()
            .map(|x| x.thrust_tof_n.norm_squared())
            .sum();
        (s / self.samples.len().max(1) as f64).sqrt()
    }

    /// Per-axis max |u_i| over the run, N.
    pub fn max_thrust_axis_n(&self) -> Vector3<f64> {
        self.samples.iter().fold(Vector3::zeros(), |m, x| {
            m.zip_map(&x.thrust_tof_n, |a: f64, b: f64| a.max(b.abs()))
        })
    }

    /// Fraction of terminal-window samples with the x thrust at its limit.
    pub fn terminal_saturation_x(&self, thrust_max_n: f64) -> f64 {
        let (k, n) = self.terminal().fold((0usize, 0usize), |(k, n), x| {
            (
                k + usize::from(x.thrust_tof_n.x.abs() >= thrust_max_n * (1.0 - 1e-12)),
                n + 1,
            )
        });
        k as f64 / n.max(1) as f64
    }

    /// First collision time, s, if any.
    pub fn first_collision_s(&self) -> Option<f64> {
        self.summary["first_collision_s"].as_f64()
    }

    /// Status of the guarantee `name` from the summary.
    pub fn guarantee(&self, name: &str) -> Option<&serde_json::Value> {
        self.summary["guarantees"]
            .as_array()?
            .iter()
            .find(|g| g["name"] == name)
    }
}

/// Runs a bundled scene (with `overrides`, `path=value` as `rpod run --set`) for its duration;
/// writes its outputs into `record_dir` if given.
pub fn run_case(
    file: &str,
    overrides: &[&str],
    record_dir: Option<&Path>,
) -> Result<CaseRun, String> {
    let text = scene_text(file).ok_or_else(|| format!("no bundled scene {file}"))?;
    let ov: Vec<String> = overrides.iter().map(|s| s.to_string()).collect();
    let loaded = load_scene_str(text, &format!("scenes/{file}"), &ov)
        .map_err(|e: SceneError| e.to_string())?;
    run_loaded(&loaded, record_dir)
}

/// Runs a loaded scene holding one xu2015 controller for its duration.
pub fn run_loaded(
    loaded: &crate::scene::LoadedScene,
    record_dir: Option<&Path>,
) -> Result<CaseRun, String> {
    let mut sim = Simulation::new(loaded).map_err(|e| e.to_string())?;
    if let Some(d) = record_dir {
        sim.record_to(d)
            .map_err(|e| format!("cannot record to {}: {e}", d.display()))?;
    }
    let n = sim.steps_for(loaded.scene.duration_s);
    let (per, target_name) = {
        let l = sim.law::<Xu2015Loop>(0).ok_or("no xu2015 controller")?;
        (l.steps_per_sample, l.spec.target.clone())
    };
    let mut distance_m = Vec::new();
    let mut done = 0;
    while done < n {
        if done % per == 0 {
            distance_m.push(
                sim.monitor()
                    .pairs
                    .first()
                    .map_or(f64::NAN, |p| p.distance_m),
            );
        }
        sim.step(1);
        done += 1;
    }
    let lp = sim
        .law::<Xu2015Loop>(0)
        .ok_or("no xu2015 controller")?
        .clone();
    let (r_ref, v_ref) = sim.reference_state().ok_or("the scene has no orbit")?;
    let tgt = sim.body(&target_name).ok_or("no target body")?;
    let c_ref = dcm_eci_from_tof_state(&r_ref, &v_ref);
    let c_act = dcm_eci_from_tof_state(&(r_ref + tgt.pos_m), &(v_ref + tgt.vel_m_s));
    let rel = c_ref.transpose() * c_act;
    let frame_tilt_end_rad = ((rel.trace() - 1.0) / 2.0).clamp(-1.0, 1.0).acos();
    let summary = match record_dir {
        Some(_) => sim.finish().map_err(|e| e.to_string())?,
        None => sim.summary(),
    };
    let goal = match lp.spec.law {
        Xu2015Law::Accm => lp.spec.accm.goal_tof_m,
        Xu2015Law::Pd => lp.spec.pd.goal_tof_m,
    };
    Ok(CaseRun {
        label: loaded.file.clone(),
        law: lp.spec.law,
        mass_chaser_kg: loaded.scene.bodies[lp.chaser].mass_kg,
        goal_tof_m: Vector3::from(goal),
        samples: lp.history,
        distance_m,
        summary,
        frame_tilt_end_rad,
        target_drift_end_m: tgt.pos_m.norm(),
    })
}

/// Terminal RMS and max of |ξ − goal| (last 100 s), m, of the paper's relative model in the
/// tof (`orbit::elliptic`, RK4 at h = 0.1 s, thrust held in the rotating frame, maneuver
/// continuous) flown by a fresh controller from ξ0 = [−20, 0, 5] m at rest: the f64 reference
/// the ECS run is compared with (the colleague's numbers of `control::xu2015`).
pub fn relative_model_terminal(law: Xu2015Law, mass_chaser_kg: f64) -> (f64, f64) {
    let mut accm = Accm::new(AccmParams::paper());
    let mut pd = Pd::new(PdParams::paper());
    let orbit = EllipticOrbit::xu2015();
    let man = ManeuverSpec::paper();
    let (h, n, m_t) = (0.1, 3000usize, 200.0);
    let goal = Vector3::new(-0.01, 0.0, 0.0);
    let mut x = RelStateTof::new(-20.0, 0.0, 5.0, 0.0, 0.0, 0.0);
    let (mut se2, mut cnt, mut mx) = (0.0, 0usize, 0.0f64);
    for k in 0..n {
        let t = k as f64 * h;
        let p = Vector3::new(x[0], x[1], x[2]);
        if t >= TERMINAL_FROM_S - 1e-9 {
            let e = (p - goal).norm();
            se2 += e * e;
            mx = mx.max(e);
            cnt += 1;
        }
        let obs = Xu2015Observation {
            t_s: t,
            pos_tof_m: p,
        };
        let u = match law {
            Xu2015Law::Accm => accm.update(&obs).force_tof_n,
            Xu2015Law::Pd => pd.update(&obs).force_tof_n,
        };
        x = rk4_step_relative(&x, t, h, &orbit, |ts| {
            u / mass_chaser_kg - man.force_tof_n(ts) / m_t
        });
    }
    ((se2 / cnt as f64).sqrt(), mx)
}

/// Bound on the acceleration difference between the ECS plant and the f64 relative model,
/// m/s²: thrust (≤ 5√3 N) and maneuver held in the inertial frame over a step of `dt_s` while
/// the model holds them in the tof, which turns by ḟ dt (mean direction error ḟ dt / 2), plus
/// the mid-step sampling of the maneuver (|F̈| dt² / 24 / m_t).
pub fn model_difference_bound_m_s2(dt_s: f64, mass_chaser_kg: f64) -> f64 {
    let orbit = EllipticOrbit::xu2015();
    let f_dot_max = (0..=300)
        .map(|k| orbit.f_dot_rad_s(orbit.true_anomaly_at(k as f64)))
        .fold(0.0, f64::max);
    let man = ManeuverSpec::paper();
    let a_thrust = 5.0 * 3f64.sqrt() / mass_chaser_kg;
    let a_man = man.peak_n().norm() / 200.0;
    let fddot = (0..3)
        .map(|i| man.amplitude_n[i] * man.omega_rad_s[i].powi(2))
        .fold(0.0, f64::max)
        / 200.0;
    (a_thrust + a_man) * f_dot_max * dt_s / 2.0 + fddot * dt_s * dt_s / 24.0
}

/// Velocity the chaser unavoidably loses on x over one half-period of the maneuver when its
/// authority `a_max` is below the peak `a_peak` (m/s²): ∫ max(0, a_peak |sin θ| − a_max) dθ/ω.
pub fn velocity_deficit_per_peak_m_s(a_peak: f64, a_max: f64, omega_rad_s: f64) -> f64 {
    let n = 100_000;
    let d = std::f64::consts::PI / n as f64;
    (0..n)
        .map(|j| (a_peak * ((j as f64 + 0.5) * d).sin() - a_max).max(0.0) * d / omega_rad_s)
        .sum()
}

fn claim(id: &str, text: &str, paper: Option<&str>, measured: String, held: bool) -> Claim {
    Claim::new(id, text, paper, measured, held)
}

/// Every case of the reproduction.
#[derive(Debug, Clone)]
pub struct AllRuns {
    /// ACCM and PD at 100 kg (scenes as written).
    pub nominal: [CaseRun; 2],
    /// ACCM and PD at 90 kg.
    pub m90: [CaseRun; 2],
    /// ACCM and PD at 110 kg, real geometry on the target's line (collide).
    pub m110_geometry: [CaseRun; 2],
    /// ACCM and PD at 110 kg, point-mass variant ([`POINT_MASS_OVERRIDES`]).
    pub m110_point_mass: [CaseRun; 2],
}

/// Runs every case; with `record` the trajectories go to `record/<case>/`.
pub fn run_all(record: Option<&Path>) -> Result<AllRuns, String> {
    let dir = |name: &str| record.map(|r| r.join(name));
    let case = |file: &str, ov: &[&str], name: &str| run_case(file, ov, dir(name).as_deref());
    Ok(AllRuns {
        nominal: [
            case("xu2015_accm.ron", &[], "accm_100kg")?,
            case("xu2015_pd.ron", &[], "pd_100kg")?,
        ],
        m90: [
            case("xu2015_accm_m90.ron", &[], "accm_90kg")?,
            case("xu2015_pd_m90.ron", &[], "pd_90kg")?,
        ],
        m110_geometry: [
            case("xu2015_accm_m110.ron", &[], "accm_110kg")?,
            case("xu2015_pd_m110.ron", &[], "pd_110kg")?,
        ],
        m110_point_mass: [
            case(
                "xu2015_accm_m110.ron",
                &POINT_MASS_OVERRIDES,
                "accm_110kg_point_mass",
            )?,
            case(
                "xu2015_pd_m110.ron",
                &POINT_MASS_OVERRIDES,
                "pd_110kg_point_mass",
            )?,
        ],
    })
}

fn e(v: f64) -> String {
    format!("{v:.3e}")
}

/// Worst margin of a guarantee, or NaN.
fn worst(run: &CaseRun, name: &str) -> f64 {
    run.guarantee(name)
        .and_then(|g| g["worst_margin"].as_f64())
        .unwrap_or(f64::NAN)
}

/// The claims of the paper, measured on `r`.
pub fn claims(r: &AllRuns) -> Vec<Claim> {
    let mut out = Vec::new();
    for (pair, m) in [(&r.nominal, 100), (&r.m90, 90)] {
        let (a, p) = (&pair[0], &pair[1]);
        let dthr = (a.rms_thrust_n() - p.rms_thrust_n()).abs() / p.rms_thrust_n();
        out.push(claim(
            &format!("accm-beats-pd-{m}kg"),
            &format!(
                "With a {m} kg chaser, ACCM's terminal accuracy (RMS |ξ − goal| over the last \
                 100 s) is better than PD's at comparable control force (RMS thrust within 1 %)."
            ),
            Some("Fig. 2: ACCM clearly better than PD; higher rendezvous accuracy at comparable control force"),
            format!(
                "ACCM {} m RMS (max {} m), PD {} m RMS (max {} m): {:.0}× better; RMS thrust {:.3} N vs {:.3} N ({:.2} %)",
                e(a.terminal_rms_m()),
                e(a.terminal_max_m()),
                e(p.terminal_rms_m()),
                e(p.terminal_max_m()),
                p.terminal_rms_m() / a.terminal_rms_m(),
                a.rms_thrust_n(),
                p.rms_thrust_n(),
                100.0 * dthr
            ),
            a.terminal_rms_m() < p.terminal_rms_m() && dthr < 0.01,
        ));
    }
    let axis_ok = [&r.nominal, &r.m90].iter().all(|pr| {
        let (a, p) = (pr[0].terminal_max_axis_m(), pr[1].terminal_max_axis_m());
        (0..3).all(|i| a[i] < p[i])
    });
    let ax = |c: &CaseRun| {
        let v = c.terminal_max_axis_m();
        format!("({}, {}, {})", e(v.x), e(v.y), e(v.z))
    };
    out.push(claim(
        "accm-beats-pd-per-axis",
        "On every axis of the target orbital frame ACCM's terminal error is smaller than PD's (90 and 100 kg).",
        Some("Fig. 3: accuracy on each axis better than PD"),
        format!(
            "max |ξ_i − goal_i| over the last 100 s (x, y, z) m — 100 kg: ACCM {} PD {}; 90 kg: ACCM {} PD {}",
            ax(&r.nominal[0]),
            ax(&r.nominal[1]),
            ax(&r.m90[0]),
            ax(&r.m90[1])
        ),
        axis_ok,
    ));
    let all: Vec<&CaseRun> = [&r.nominal, &r.m90, &r.m110_geometry, &r.m110_point_mass]
        .iter()
        .flat_map(|p| p.iter())
        .collect();
    let umax = all
        .iter()
        .map(|c| c.max_thrust_axis_n().amax())
        .fold(0.0, f64::max);
    out.push(claim(
        "thrust-within-5n",
        "The chaser's thrust never exceeds 5 N on any axis of the target orbital frame, in any case.",
        Some("Fig. 4: the ACCM thrust satisfies the 5 N limit"),
        format!(
            "max |u_i| over all {} runs (ACCM and PD, 90/100/110 kg, 110 kg also point-mass) = {umax:.6} N; the limit is reached in {} of them",
            all.len(),
            all.iter()
                .filter(|c| c.max_thrust_axis_n().amax() >= 5.0 * (1.0 - 1e-12))
                .count()
        ),
        umax <= 5.0 + 1e-12,
    ));
    let auth = |c: &CaseRun| {
        [
            worst(c, "thrust_authority_x"),
            worst(c, "thrust_authority_y"),
            worst(c, "thrust_authority_z"),
        ]
    };
    let (a90, a100, a110) = (
        auth(&r.m90[0]),
        auth(&r.nominal[0]),
        auth(&r.m110_point_mass[0]),
    );
    out.push(claim(
        "authority-90-100kg",
        "At 90 and 100 kg the chaser's 5 N per axis covers the target's maneuver acceleration on every axis (thrust-authority margin ≥ 0 throughout).",
        Some("chaser 100 kg with ±10 % mass variation, thrust ≤ 5 N (scenario)"),
        format!(
            "worst margins (x, y, z) m/s²: 90 kg ({:.3e}, {:.3e}, {:.3e}); 100 kg ({:.3e}, {:.3e}, {:.3e}) — x at 100 kg is exactly the boundary 5/100 = 10/200",
            a90[0], a90[1], a90[2], a100[0], a100[1], a100[2]
        ),
        a90.iter().chain(a100.iter()).all(|m| *m >= -1e-9),
    ));
    let (pa, pp) = (&r.m110_point_mass[0], &r.m110_point_mass[1]);
    out.push(claim(
        "m110-keeps-accuracy",
        "With +10 % chaser mass (110 kg) ACCM still reaches and holds the goal (terminal error of the order of the nominal case).",
        Some("±10 % chaser mass variation is part of the simulated scenario (no per-case result given)"),
        format!(
            "x authority 5/110 = 0.04545 < 10/200 = 0.05 m/s² (worst margin {:.3e} m/s²): ACCM terminal RMS {:.2} m, max {:.1} m on x, x saturated {:.1} % of the last 100 s (PD {:.2} m RMS, {:.1} %); y, z still at {} / {} m",
            a110[0],
            pa.terminal_rms_m(),
            pa.terminal_max_axis_m().x,
            100.0 * pa.terminal_saturation_x(5.0),
            pp.terminal_rms_m(),
            100.0 * pp.terminal_saturation_x(5.0),
            e(pa.terminal_max_axis_m().y),
            e(pa.terminal_max_axis_m().z)
        ),
        pa.terminal_rms_m() < 10.0 * r.nominal[0].terminal_rms_m(),
    ));
    let (ga, gp) = (&r.m110_geometry[0], &r.m110_geometry[1]);
    let col = |c: &CaseRun| {
        c.summary["collisions"]
            .get(0)
            .map(|x| {
                format!(
                    "{} vs {} at {:.1} s",
                    x["a"].as_str().unwrap_or("?"),
                    x["b"].as_str().unwrap_or("?"),
                    x["t_s"].as_f64().unwrap_or(f64::NAN)
                )
            })
            .unwrap_or_else(|| "none".into())
    };
    out.push(claim(
        "m110-real-geometry-clear",
        "With both spacecraft's real geometry on the paper's approach line (aim point 3 m behind the target), the +10 % mass runs stay clear of the target.",
        None,
        format!(
            "first collision — ACCM: {}; PD: {} (the unmatched x maneuver carries the chaser more than the 2.0 m bus-to-bus gap forward)",
            col(ga),
            col(gp)
        ),
        ga.first_collision_s().is_none() && gp.first_collision_s().is_none(),
    ));
    out
}

/// Runs the paper's cases and writes REPORT.md, plots and claims.json into `out`.
pub fn run(out: &Path) -> Result<(), String> {
    let runs = run_all(Some(&out.join("cases")))?;
    let cl = claims(&runs);
    write_claims_json(&out.join("claims.json"), &cl).map_err(|e| e.to_string())?;
    let figures = write_figures(out, &runs)?;
    let md = report_markdown(&runs, &cl, &figures);
    write_atomic(&out.join("REPORT.md"), md.as_bytes()).map_err(|e| e.to_string())?;
    Ok(())
}

/// REPORT.md text.
fn report_markdown(r: &AllRuns, cl: &[Claim], figures: &[(String, String)]) -> String {
    let mut s = String::new();
    s.push_str("# Xu & Hu (2015): ACCM vs PD, rendezvous with a maneuvering target on an e = 0.7 orbit\n\n");
    let held = cl.iter().filter(|c| c.held).count();
    s.push_str(&format!("{held} of {} claims held.\n\n", cl.len()));
    s.push_str("| id | claim | paper | measured | held |\n|---|---|---|---|---|\n");
    let esc = |t: &str| t.replace('|', "\\|");
    for c in cl {
        s.push_str(&format!(
            "| {} | {} | {} | {} | {} |\n",
            c.id,
            esc(&c.claim),
            esc(c.paper.as_deref().unwrap_or("—")),
            esc(&c.measured),
            if c.held { "✔ held" } else { "✘ NOT held" }
        ));
    }
    s.push_str(&method_text());
    s.push_str("\n## Cases\n\n");
    s.push_str("| case | chaser kg | terminal RMS m | terminal max m | max per axis (x, y, z) m | RMS thrust N | x saturated (last 100 s) | first collision s | min distance m |\n|---|---|---|---|---|---|---|---|---|\n");
    let rows: [(&str, &CaseRun); 8] = [
        ("ACCM", &r.nominal[0]),
        ("PD", &r.nominal[1]),
        ("ACCM", &r.m90[0]),
        ("PD", &r.m90[1]),
        ("ACCM, point-mass", &r.m110_point_mass[0]),
        ("PD, point-mass", &r.m110_point_mass[1]),
        ("ACCM, real geometry", &r.m110_geometry[0]),
        ("PD, real geometry", &r.m110_geometry[1]),
    ];
    for (name, c) in rows {
        let ax = c.terminal_max_axis_m();
        s.push_str(&format!(
            "| {name} | {} | {} | {} | ({}, {}, {}) | {:.3} | {:.1} % | {} | {} |\n",
            c.mass_chaser_kg,
            e(c.terminal_rms_m()),
            e(c.terminal_max_m()),
            e(ax.x),
            e(ax.y),
            e(ax.z),
            c.rms_thrust_n(),
            100.0 * c.terminal_saturation_x(5.0),
            c.first_collision_s()
                .map_or("none".into(), |t| format!("{t:.1}")),
            c.summary["min_distance"]["value_m"]
                .as_f64()
                .map_or("?".into(), |d| format!("{d:.3}"))
        ));
    }
    s.push_str("\n## Figures\n");
    for (file, caption) in figures {
        let alt = file.trim_end_matches(".png");
        s.push_str(&format!("\n{caption}\n\n![{alt}]({file})\n"));
    }
    s.push_str(&comparison_text(r));
    s
}

fn method_text() -> String {
    "\n## Set-up and choices\n\n\
- **Scenario** (paper §3): target orbit perigee altitude 200 km, e = 0.7, f0 = −150°, i = 30°, \
Ω = 60°, ω = 0, two-body gravity (no J2: the paper's model is Keplerian); target 200 kg with \
F_t = [10 sin(0.08t+π/6), 4 sin(0.05t+π/4), 8 sin(0.1t+π/2)] N in the target orbital frame; \
chaser 100 kg (90, 110 kg cases), ≤ 5 N per axis; only relative position measured, every \
h = 0.1 s, no noise (configurable: `sensor: (noise_sigma_m, seed)`); ξ0 = [−20, 0, 5] m, goal \
[−0.01, 0, 0] m, 300 s. Controllers and every reconstructed choice: `src/control/xu2015.rs`.\n\
- **Frames.** World: inertial axes, origin on the reference orbit = the target's unforced orbit. \
The controller, the maneuver and the thrust limit live in the target orbital frame (tof: x in-plane \
transverse, y = −orbit normal, z to Earth's centre) **of the reference orbit**, rebuilt each step \
from its (r, v): that is the paper's model (relative dynamics built on the target's Keplerian orbit, \
the maneuver a disturbance). The origin of ξ is the actual (maneuvering) target's centre of mass. \
The maneuvering target's own osculating tof is tilted from it by the angle given below.\n\
- **Aim point.** The paper's goal would put the centres of mass 1 cm apart; with real geometry \
(target: 1.2 × 1.0 × 1.0 m bus, two 2-panel wings, antenna; chaser: 0.8 m bus, two 2-panel wings) \
ξ is measured from a point 3 m behind the target's centre of mass in the tof (`aim_offset_tof_m`), \
so the chaser ends with a 2.0 m bus-to-bus gap. The gravity-gradient difference this offset makes \
is ≈ 3μ/R³ · 3 m ≈ 1.5e−7 m/s². The 110 kg point-mass variant moves the aim point 10 m toward \
Earth as well, so the bodies cannot touch and the run is the paper's point-mass problem.\n\
- **Step.** dt = 0.1 s = h: in the inertial world frame the physics is differential gravity \
(gradient ≈ 1.7e−8 s⁻², velocity Verlet), the held thrust (exact) and the maneuver (period ≥ 63 s, \
applied at its mid-step value). A run is 3000 steps. `tests/val_xu2015.rs` checks that \
dt = 0.02 s gives the same terminal RMS within the plant-difference bound below.\n\
- **Attitude.** Nobody controls it (the paper has none): both bodies start aligned with the tof and \
turning with it at ḟ0 = 8.28e−5 rad/s; gravity-gradient torque acts.\n\
- **Thrust-authority guarantee** (`thrust_authority_{x,y,z}`, m/s²): 5 N / m_c − |F_t,i(t)| / 200 kg, \
checked every step by the monitor; negative = no law can hold the relative position on that axis.\n"
        .to_string()
}

fn comparison_text(r: &AllRuns) -> String {
    let orbit = EllipticOrbit::xu2015();
    let f_dot_max = (0..=300)
        .map(|k| orbit.f_dot_rad_s(orbit.true_anomaly_at(k as f64)))
        .fold(0.0, f64::max);
    let da = model_difference_bound_m_s2(0.1, 90.0);
    let mut s = format!(
        "\n## ECS run vs the f64 relative model\n\n\
The law's author measured the closed loop on the paper's relative model in the tof (RK4 at \
0.1 s, thrust held in the rotating frame). The ECS plant differs from it only by: thrust and \
maneuver held fixed in the inertial frame over a step while the tof turns by ḟ dt (≤ {:.1e} rad \
here), the mid-step sampling of the maneuver, and the exact differential gravity on the \
target's drift from its unforced orbit — together ≤ {da:.1e} m/s², {:.1e} of the 0.05 m/s² \
maneuver that sets the terminal error.\n\n\
| case | ECS terminal RMS m | f64 model RMS m | relative difference | ECS max m | f64 max m |\n|---|---|---|---|---|---|\n",
        f_dot_max * 0.1,
        da / 0.05
    );
    let cases: [(&str, &CaseRun); 6] = [
        ("ACCM 100 kg", &r.nominal[0]),
        ("PD 100 kg", &r.nominal[1]),
        ("ACCM 90 kg", &r.m90[0]),
        ("PD 90 kg", &r.m90[1]),
        ("ACCM 110 kg (point-mass)", &r.m110_point_mass[0]),
        ("PD 110 kg (point-mass)", &r.m110_point_mass[1]),
    ];
    let mut rel = Vec::new();
    for (name, c) in cases {
        let (rms, mx) = relative_model_terminal(c.law, c.mass_chaser_kg);
        rel.push((c.terminal_rms_m() - rms) / rms);
        s.push_str(&format!(
            "| {name} | {} | {} | {:.2e} | {} | {} |\n",
            e(c.terminal_rms_m()),
            e(rms),
            rel[rel.len() - 1],
            e(c.terminal_max_m()),
            e(mx)
        ));
    }
    let nominal_rel = rel[..4].iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let c = &r.nominal[0];
    s.push_str(&format!(
        "\nAt 90 and 100 kg the ECS and the model agree to {nominal_rel:.1e} (relative), \
below the plant-difference fraction {:.1e}: the author's f64 numbers hold in the ECS. At \
110 kg PD agrees to {:.1e}; ACCM's saturated limit cycle (bang-bang on x, identification fed \
by saturated data) amplifies the small plant differences: {:.1e}. \
At the end of the run the target has drifted {:.1} m from its unforced orbit and its osculating \
tof is tilted {:.2e} rad from the reference tof the controller uses ({:.1e} m on the 3.01 m \
stand-off: where the aim point sits, not an error of the law; {:.1e} m on the paper's literal \
1 cm goal).\n",
        da / 0.05,
        rel[5].abs(),
        rel[4].abs(),
        c.target_drift_end_m,
        c.frame_tilt_end_rad,
        c.frame_tilt_end_rad * 3.01,
        c.frame_tilt_end_rad * 0.01
    ));
    let a_max = 5.0 / 110.0;
    let dv = velocity_deficit_per_peak_m_s(0.05, a_max, 0.08);
    s.push_str(&format!(
        "\n## +10 % chaser mass\n\n\
At 110 kg the x authority is 5/110 = {a_max:.5} m/s² against the maneuver's peak 10/200 = 0.05 m/s² \
(worst registered margin {:.3e} m/s²). Near each x peak the chaser loses at least {dv:.4} m/s \
of relative velocity whatever the law; both controllers (same high nominal gain) answer with a \
saturated oscillation on x of up to {:.1} m (ACCM) / {:.1} m (PD), saturated for {:.1} % / {:.1} % \
of the last 100 s, while y and z keep their nominal accuracy. With the real geometry on the \
approach line the excursion exceeds the 2 m gap: the monitor reports the collision (parts and time \
in the claims table), after which the run is a contact problem the paper does not model.\n",
        worst(&r.m110_point_mass[0], "thrust_authority_x"),
        r.m110_point_mass[0].terminal_max_axis_m().x,
        r.m110_point_mass[1].terminal_max_axis_m().x,
        100.0 * r.m110_point_mass[0].terminal_saturation_x(5.0),
        100.0 * r.m110_point_mass[1].terminal_saturation_x(5.0),
    ));
    s.push_str(&noise_text());
    s.push_str(
        "\n## Reproduce\n\n```sh\nrpod reproduce xu2015 --out out/reproduce\n\
rpod run scenes/xu2015_accm.ron   # or xu2015_pd, xu2015_{accm,pd}_m90, xu2015_{accm,pd}_m110\n\
cargo test --release --test val_xu2015\n```\n\
Each case's `trajectory.csv`, `events.jsonl` and `summary.json` are in `cases/<case>/`.\n",
    );
    s
}

/// Beyond the paper: the nominal case with Gaussian measurement noise (seed 1).
fn noise_text() -> String {
    let mut s = String::from(
        "\n## Beyond the paper: measurement noise\n\n\
The paper is silent on sensor noise. Both controllers act on position differences over \
h = 0.1 s with a high gain (PD k_d = 6.18 s⁻¹), so noise reaches the thrust as ≈ m k_d σ√2 / h. \
Chaser 100 kg, `sensor: (noise_sigma_m: σ, seed: 1)`:\n\n\
| σ m | ACCM terminal RMS m | PD terminal RMS m | ACCM / PD | RMS thrust ACCM / PD N |\n|---|---|---|---|---|\n",
    );
    let mut ratios = Vec::new();
    for sigma in [0.0, 1e-4, 1e-3, 1e-2] {
        let ov = format!("controllers.0.0.sensor=(noise_sigma_m: {sigma}, seed: 1)");
        let run = |f: &str| run_case(f, &[ov.as_str()], None);
        match (run("xu2015_accm.ron"), run("xu2015_pd.ron")) {
            (Ok(a), Ok(p)) => {
                let ratio = a.terminal_rms_m() / p.terminal_rms_m();
                ratios.push((sigma, ratio));
                s.push_str(&format!(
                    "| {sigma:e} | {} | {} | {ratio:.3} | {:.2} / {:.2} |\n",
                    e(a.terminal_rms_m()),
                    e(p.terminal_rms_m()),
                    a.rms_thrust_n(),
                    p.rms_thrust_n()
                ))
            }
            (Err(x), _) | (_, Err(x)) => s.push_str(&format!("| {sigma:e} | error: {x} | | | |\n")),
        }
    }
    let first_lost = ratios.iter().find(|(_, r)| *r >= 1.0);
    s.push_str(&match first_lost {
        Some((sigma, _)) => format!(
            "\nACCM's accuracy advantage over PD is a noise-free result here: from σ = {sigma:e} m \
on, PD is at least as accurate (the thrust of both loops is then mostly noise).\n"
        ),
        None => "\nACCM stays more accurate than PD at every noise level tried.\n".to_string(),
    });
    s
}

/// Series (t, value) of one quantity of a run's samples.
fn series<'a>(
    c: &'a CaseRun,
    from_s: f64,
    f: impl Fn(&Xu2015Sample) -> f64 + 'a,
) -> impl Iterator<Item = (f64, f64)> + 'a {
    c.samples
        .iter()
        .filter(move |s| s.t_s >= from_s - 1e-9)
        .map(move |s| (s.t_s, f(s)))
}

fn dashed() -> LineStyle {
    LineStyle {
        dash: Dash::Dashed,
        ..LineStyle::default()
    }
}

/// Writes the figures into `out`; returns (file, caption) in report order.
pub fn write_figures(out: &Path, r: &AllRuns) -> Result<Vec<(String, String)>, String> {
    let (a, p) = (&r.nominal[0], &r.nominal[1]);
    let goal = a.goal_tof_m;
    let mut figs: Vec<(String, String, Figure)> = Vec::new();
    let err = move |s: &Xu2015Sample| (s.xi_tof_m - goal).norm();
    // Fig. 2: relative distance, with zooms on the last 100 s.
    let fig = Figure::new("Relative distance |ξ| (target orbital frame), chaser 100 kg")
        .cols(2)
        .plot(
            Plot::new("|ξ| over the run")
                .x_label("t [s]")
                .y_label("|ξ| [m]")
                .log_y()
                .line("ACCM", series(a, 0.0, |s| s.xi_tof_m.norm()))
                .line_styled("PD", series(p, 0.0, |s| s.xi_tof_m.norm()), dashed()),
        )
        .plot(
            Plot::new("terminal error |ξ − goal| over the run")
                .x_label("t [s]")
                .y_label("|ξ − goal| [m]")
                .log_y()
                .line("ACCM", series(a, 0.0, err))
                .line_styled("PD", series(p, 0.0, err), dashed()),
        )
        .plot(
            Plot::new("ACCM, last 100 s")
                .x_label("t [s]")
                .y_label("|ξ − goal| [µm]")
                .line("ACCM", series(a, TERMINAL_FROM_S, move |s| 1e6 * err(s))),
        )
        .plot(
            Plot::new("PD, last 100 s")
                .x_label("t [s]")
                .y_label("|ξ − goal| [mm]")
                .line_styled(
                    "PD",
                    series(p, TERMINAL_FROM_S, move |s| 1e3 * err(s)),
                    dashed(),
                ),
        );
    figs.push((
        "relative_distance".into(),
        "Relative distance (paper Fig. 2) with the last 100 s of each controller".into(),
        fig,
    ));
    // Fig. 3: relative position per axis, full run and last 100 s.
    let mut fig =
        Figure::new("Relative position ξ per axis (target orbital frame), chaser 100 kg").cols(2);
    for (i, ax) in ["x", "y", "z"].iter().enumerate() {
        // y stays within millimetres of zero: plot it in mm.
        let (k, unit) = if i == 1 { (1e3, "mm") } else { (1.0, "m") };
        fig.push(
            Plot::new(format!("ξ_{ax}"))
                .x_label("t [s]")
                .y_label(format!("ξ_{ax} [{unit}]"))
                .line("ACCM", series(a, 0.0, move |s| k * s.xi_tof_m[i]))
                .line_styled("PD", series(p, 0.0, move |s| k * s.xi_tof_m[i]), dashed())
                .line_styled(
                    "reference",
                    series(a, 0.0, move |s| k * s.reference_tof_m[i]),
                    LineStyle {
                        dash: Dash::Dotted,
                        ..LineStyle::default()
                    },
                ),
        );
        fig.push(
            Plot::new(format!("ξ_{ax} − goal_{ax}, last 100 s"))
                .x_label("t [s]")
                .y_label(format!("ξ_{ax} − goal_{ax} [mm]"))
                .line(
                    "ACCM",
                    series(a, TERMINAL_FROM_S, move |s| 1e3 * (s.xi_tof_m[i] - goal[i])),
                )
                .line_styled(
                    "PD",
                    series(p, TERMINAL_FROM_S, move |s| 1e3 * (s.xi_tof_m[i] - goal[i])),
                    dashed(),
                ),
        );
    }
    figs.push((
        "relative_position".into(),
        "Relative position per axis (paper Fig. 3); right: error to the goal over the last 100 s"
            .into(),
        fig,
    ));
    // Fig. 4: thrust.
    let mut fig = Figure::new("Chaser thrust u (target orbital frame), chaser 100 kg, limit ±5 N");
    for (i, ax) in ["x", "y", "z"].iter().enumerate() {
        fig.push(
            Plot::new(format!("u_{ax}"))
                .x_label("t [s]")
                .y_label(format!("u_{ax} [N]"))
                .line("ACCM", series(a, 0.0, move |s| s.thrust_tof_n[i]))
                .line_styled("PD", series(p, 0.0, move |s| s.thrust_tof_n[i]), dashed())
                .hline(5.0, "+5 N")
                .hline(-5.0, "−5 N"),
        );
    }
    figs.push((
        "thrust".into(),
        "Control thrust (paper Fig. 4), ACCM and PD".into(),
        fig,
    ));
    // Identified parameters.
    let mut fig = Figure::new("ACCM identified characteristic parameters, chaser 100 kg");
    let est = |k: usize, i: usize| {
        series(a, 0.0, move |s| {
            s.estimates.map_or(f64::NAN, |e| match k {
                0 => e[i].alpha1,
                1 => e[i].alpha2,
                _ => e[i].gamma,
            })
        })
    };
    for (k, name) in ["α̂1", "α̂2", "γ̂ = β̂/β0"].iter().enumerate() {
        let mut pl = Plot::new(name.to_string())
            .x_label("t [s]")
            .y_label(format!("{name} [-]"));
        for (i, ax) in ["x", "y", "z"].iter().enumerate() {
            pl = pl.line(format!("axis {ax}"), est(k, i));
        }
        fig.push(pl);
    }
    figs.push((
        "parameters".into(),
        "Identified parameters α̂1, α̂2, γ̂ per axis (projection box α1 ∈ [1.5, 2.02], α2 ∈ [−1.02, −0.5], γ ∈ [0.85, 1.15])".into(),
        fig,
    ));
    // Mass cases.
    let cases: [(&str, &CaseRun); 6] = [
        ("ACCM 90 kg", &r.m90[0]),
        ("ACCM 100 kg", &r.nominal[0]),
        ("ACCM 110 kg (point-mass)", &r.m110_point_mass[0]),
        ("PD 90 kg", &r.m90[1]),
        ("PD 100 kg", &r.nominal[1]),
        ("PD 110 kg (point-mass)", &r.m110_point_mass[1]),
    ];
    let mut pl = Plot::new("terminal error |ξ − goal|")
        .x_label("t [s]")
        .y_label("|ξ − goal| [m]")
        .log_y();
    for (name, c) in cases {
        let st = if name.starts_with("PD") {
            dashed()
        } else {
            LineStyle::default()
        };
        pl = pl.line_styled(name, series(c, 0.0, err), st);
    }
    let pm = &r.m110_point_mass[0];
    let need: Vec<(f64, f64)> =
        series(pm, 0.0, |s| s.target_force_tof_n.x / 200.0 * 110.0).collect();
    let fig = Figure::new("Chaser mass 90 / 100 / 110 kg")
        .plot(pl)
        .plot(
            Plot::new("110 kg, x axis: thrust vs the force needed to follow the target")
                .x_label("t [s]")
                .y_label("force [N]")
                .line("ACCM u_x", series(pm, 0.0, |s| s.thrust_tof_n.x))
                .line_styled("m_c F_t,x / m_t (needed)", need, dashed())
                .hline(5.0, "+5 N")
                .hline(-5.0, "−5 N"),
        )
        .plot(
            Plot::new("full-geometry chaser–target distance")
                .x_label("t [s]")
                .y_label("distance [m]")
                .line(
                    "100 kg ACCM",
                    a.distance_m
                        .iter()
                        .enumerate()
                        .map(|(k, d)| (k as f64 * 0.1, *d)),
                )
                .line(
                    "110 kg ACCM (real geometry)",
                    r.m110_geometry[0]
                        .distance_m
                        .iter()
                        .enumerate()
                        .map(|(k, d)| (k as f64 * 0.1, *d)),
                )
                .line_styled(
                    "110 kg PD (real geometry)",
                    r.m110_geometry[1]
                        .distance_m
                        .iter()
                        .enumerate()
                        .map(|(k, d)| (k as f64 * 0.1, *d)),
                    dashed(),
                ),
        );
    figs.push((
        "mass_cases".into(),
        "Mass cases: terminal error, the x thrust at 110 kg against the force needed to follow the target's maneuver, and the monitor's full-geometry distance".into(),
        fig,
    ));
    let mut list = Vec::new();
    for (stem, caption, fig) in figs {
        let file = format!("{stem}.png");
        fig.write_png(&out.join(&file))
            .map_err(|e| format!("cannot write {file}: {e}"))?;
        list.push((file, caption));
    }
    Ok(list)
}
