//! Guo, Song, Li (2016) in the full simulation (scenes `guo2016_corridor.ron`,
//! `guo2016_no_avoidance.ron`), each claim of the paper's Section 5 (and beyond it) asserted as
//! it turns out.
//!
//! Independent references: the closed-form cissoid `h(r) = x³tan²θ/(2a − x) − y² − z²` and the
//! MRP of the scene's quaternion written out by hand (initial state); the mean motion
//! `√(μ/a³)` of the scene's elements (disturbance torque); the sliding-surface algebra
//! `S = k1 x + β ẋ` with the reaching bound `|ΔS_tr| ≤ β k4‖B2‖/m · T` (plus the d_τ coupling
//! through ω̇ × r_b), which predicts where the chaser stops with the paper's gains; the relative
//! size `k2/h_min²` of the barrier term, which bounds the k2 = 0.02 vs k2 = 0 difference; the
//! straight-line sliding motion `ẋ = −k1 x/β` whose midpoint lies outside the corridor
//! (closed-form h); the monitor's full-geometry minimum as a lower bound of the separately
//! computed chaser–wing distances in the campaign; in continuous time (Bevy-free plant), the
//! 100 Hz exit time of the ECS and, at the continuous-time exit, the rate ḣ = ∇h·(ω × r1) of
//! a rigid rotation of the line of sight with the desired frame (closed-form ∇h).

use nalgebra::Vector3;
use rpod::control::guo2016::Guo2016Instance;
use rpod::control::guo2016::Guo2016Params;
use rpod::orbit::constants::MU_EARTH_M3_S2;
use rpod::reproduce::guo2016 as rep;
use rpod::scene::load_scene_str;
use rpod::sim::Simulation;

fn h_closed_form(r: &Vector3<f64>, a: f64, tan_theta: f64) -> f64 {
    r.x.powi(3) * tan_theta * tan_theta / (2.0 * a - r.x) - r.y * r.y - r.z * r.z
}

fn sim_of(file: &str) -> Simulation {
    let l = rep::load_bundled(file).unwrap_or_else(|e| panic!("{e}"));
    Simulation::new(&l).unwrap_or_else(|e| panic!("{e}"))
}

#[test]
fn val_guo2016_section5_initial_state() {
    let mut sim = sim_of("scenes/papers/guo2016/guo2016_corridor.ron");
    sim.step(1);
    let c = sim.law::<Guo2016Instance>(0).unwrap().clone();
    let d = c.diagnostics.unwrap();
    // r1(0) = r0 of the paper, target frame (target at rest at the origin, identity attitude).
    let r0 = Vector3::new(14.9, 17.1, 37.7);
    assert!((d.r1_target_m - r0).norm() < 1e-12, "{}", d.r1_target_m);
    let h0 = h_closed_form(&r0, 25.0, 5.0);
    assert!((d.h_m2 - h0).abs() < 1e-9 * h0, "{} vs {h0}", d.h_m2);
    assert!(d.inside && h0 > 0.0);
    // σ_e(0) = σ(0) ⊖ σ_d(0) with σ_d(0) = 0: the scene's quaternion is D0 ⊗ q(σ0),
    // σ0 = [0.05, −0.05, 0.05].
    let se = Vector3::new(d.x[0], d.x[1], d.x[2]);
    assert!(
        (se - Vector3::new(0.05, -0.05, 0.05)).norm() < 1e-12,
        "{se}"
    );
    // r_e(0) = r_b − r_d, |r_b| = |r0| (line of sight).
    let r_b = Vector3::new(d.x[3], d.x[4], d.x[5]) + Vector3::new(2.0, 0.0, 0.0);
    assert!((r_b.norm() - r0.norm()).abs() < 1e-12);
    // Disturbance torque at t = 0: A cos(0) = [1, 2, 3]·1e-3 N·m, and n = √(μ/a³).
    let dist = sim
        .controllers()
        .disturbance::<rpod::control::guo2016::Guo2016Disturbance>(0)
        .unwrap()
        .last_body_nm;
    assert!((dist - Vector3::new(1e-3, 2e-3, 3e-3)).norm() < 1e-15);
    let n = (MU_EARTH_M3_S2 / 7.178e6f64.powi(3)).sqrt();
    assert!(((c.disturbance_rate_rad_s - n) / n).abs() < 1e-9);
    // Law parameters: the paper's gains, mass and inertia from the chaser body.
    let p = Guo2016Params::paper();
    let q = &c.law.params;
    assert_eq!(
        (q.k1_per_s, q.k2_m4, q.k3, q.k4_n),
        (p.k1_per_s, p.k2_m4, p.k3, p.k4_n)
    );
    assert_eq!(q.chaser_mass_kg, 100.0);
    assert_eq!(q.chaser_inertia_body_kg_m2, p.chaser_inertia_body_kg_m2);
}

/// Runs a scene for `steps`, returning per step (chaser position world, r_e, ṙ_e, S, h).
struct Trace {
    pos: Vec<Vector3<f64>>,
    x0: [f64; 6],
    s0: Vector3<f64>,
    r_e_end: f64,
    sigma_e_end: f64,
    x_dot_end: f64,
    max_x_dot_tr: f64,
    max_r_e: f64,
    min_h: f64,
    all_inside: bool,
}

fn trace(sim: &mut Simulation, steps: u64) -> Trace {
    let mut t = Trace {
        pos: Vec::new(),
        x0: [0.0; 6],
        s0: Vector3::zeros(),
        r_e_end: 0.0,
        sigma_e_end: 0.0,
        x_dot_end: 0.0,
        max_x_dot_tr: 0.0,
        max_r_e: 0.0,
        min_h: f64::INFINITY,
        all_inside: true,
    };
    for k in 0..steps {
        sim.step(1);
        let d = sim.law::<Guo2016Instance>(0).unwrap().diagnostics.unwrap();
        if k == 0 {
            t.x0.copy_from_slice(d.x.as_slice());
            t.s0 = Vector3::new(d.s[3], d.s[4], d.s[5]);
        }
        let r_e = Vector3::new(d.x[3], d.x[4], d.x[5]).norm();
        t.r_e_end = r_e;
        t.max_r_e = t.max_r_e.max(r_e);
        t.sigma_e_end = Vector3::new(d.x[0], d.x[1], d.x[2]).norm();
        let xd_tr = Vector3::new(d.x_dot[3], d.x_dot[4], d.x_dot[5]).norm();
        t.x_dot_end = xd_tr;
        t.max_x_dot_tr = t.max_x_dot_tr.max(xd_tr);
        t.min_h = t.min_h.min(d.h_m2);
        t.all_inside &= d.inside;
        t.pos.push(sim.body("chaser").unwrap().pos_m);
    }
    t
}

#[test]
fn val_guo2016_paper_gains_corridor_holds_errors_do_not_converge() {
    // k2 = 0.02, the paper's gains, the full 100 s.
    let p = Guo2016Params::paper();
    let horizon = rep::PAPER_DURATION_S;
    let mut sim = sim_of("scenes/papers/guo2016/guo2016_corridor.ron");
    let steps = sim.steps_for(horizon);
    let t = trace(&mut sim, steps);
    // Claim "corridor holds": h > 0 at every control step, and the monitor's guarantee
    // (signed distance to the wall) held at every step.
    assert!(t.all_inside && t.min_h > 0.0);
    let g = sim.guarantees();
    let i = g
        .list
        .iter()
        .position(|x| x.name() == "guo2016_corridor")
        .unwrap();
    assert!(g.status[i].held && g.status[i].worst_margin > 0.0);
    // Claim "errors converge (|r_e| < 1 cm, |σ_e| < 1e-4)": NOT held. Prediction: S_tr moves by
    // at most the reaching bound 4 k4/m·T plus the d_τ coupling m|r_b||J⁻¹d_τ|/m·T, so the
    // chaser settles at |x_tr| ≥ (|S_tr(0)| − √3·ΔS)/k1 − |ẋ_tr(T)|/k1.
    let reach = 4.0 * p.k4_n / p.chaser_mass_kg * horizon;
    let j_inv = p.chaser_inertia_body_kg_m2.try_inverse().unwrap();
    let coupling = (j_inv * Vector3::new(1e-3, 2e-3, 3e-3)).norm() * 45.0 * horizon;
    let r_e_min =
        (t.s0.norm() - 3f64.sqrt() * (reach + coupling)) / p.k1_per_s - t.x_dot_end / p.k1_per_s;
    eprintln!(
        "k2=0.02: |S_tr(0)| {:.3} m/s, final |r_e| {:.4} m (bound ≥ {r_e_min:.4}), |σ_e| {:.4e}, min h {:.2} m²",
        t.s0.norm(),
        t.r_e_end,
        t.sigma_e_end,
        t.min_h
    );
    assert!(r_e_min > 40.0 && t.r_e_end > r_e_min);
    assert!(t.r_e_end > 0.01 && t.sigma_e_end > 1e-4);
    // Claim "no collision": no contact at all; the closest approach stays tens of metres.
    assert!(sim.contacts().first_contact_s.is_none());
    assert!(sim.monitor().min_per_pair[0].distance_m > 30.0);
}

#[test]
fn val_guo2016_k2_zero_does_not_leave_corridor() {
    // The paper's comparison run (k2 = 0) against k2 = 0.02, 100 s each. The barrier changes
    // β = k2/h² + k3 by the relative amount δ = k2/h_min²; a relative change δ of the ẋ
    // coefficient moves the state by at most δ·(max|r_e| + max|ṙ_e|·T).
    let mut a = sim_of("scenes/papers/guo2016/guo2016_corridor.ron");
    let mut b = sim_of("scenes/papers/guo2016/guo2016_no_avoidance.ron");
    let steps = a.steps_for(rep::PAPER_DURATION_S);
    let ta = trace(&mut a, steps);
    let tb = trace(&mut b, steps);
    let diff = ta
        .pos
        .iter()
        .zip(&tb.pos)
        .map(|(p, q)| (p - q).norm())
        .fold(0.0, f64::max);
    let delta = 0.02 / (ta.min_h * ta.min_h);
    let bound = delta * (ta.max_r_e + ta.max_x_dot_tr * rep::PAPER_DURATION_S);
    eprintln!(
        "max |Δr| k2=0.02 vs 0: {diff:.3e} m (bound {bound:.3e} m); min h (k2=0) {:.2}",
        tb.min_h
    );
    assert!(diff <= bound, "{diff} > {bound}");
    // Claim "with k2 = 0 the chaser leaves the corridor": NOT held.
    assert!(tb.all_inside && tb.min_h > 0.0);
    let g = b.guarantees();
    let i = g
        .list
        .iter()
        .position(|x| x.name() == "guo2016_corridor")
        .unwrap();
    assert!(g.status[i].held);
    assert!(b.contacts().first_contact_s.is_none());
}

#[test]
fn val_guo2016_reaching_variant_sampled_at_100hz_leaves_corridor() {
    // Not the paper's law: k_r = 1/s, σ(0) = 0, 20 s, the law sampled at the scenes' 100 Hz.
    // The straight line r1(0) → [2, 0, 0] m has its midpoint outside (closed form), but that
    // alone does not make the chaser leave: on S = 0, βẋ = −k1x and β = k2/h² + k3 → ∞ at the
    // wall, so in continuous time the body-frame motion stops there (see
    // `val_guo2016_continuous_time_barrier`). What this test asserts is a property of the
    // sampled law: with the command held for 10 ms the chaser crosses the sub-millimetre
    // layer where k2/h² acts, with k2 = 0.02 as with k2 = 0; the errors converge below the
    // issue's thresholds.
    let mid = (Vector3::new(14.9, 17.1, 37.7) + Vector3::new(2.0, 0.0, 0.0)) * 0.5;
    assert!(h_closed_form(&mid, 25.0, 5.0) < 0.0);
    for file in [
        "scenes/papers/guo2016/guo2016_corridor.ron",
        "scenes/papers/guo2016/guo2016_no_avoidance.ron",
    ] {
        let l = rep::reaching_variant(file).unwrap();
        assert_eq!(l.scene.dt_s, 0.01, "the law runs every step");
        let r = rep::run_case(&l, "reaching", rep::REACHING_DURATION_S, 0).unwrap();
        eprintln!(
            "{file} k_r=1, 100 Hz: exit {:?} s, min h {:.2} m², final |r_e| {:.2e} m, |σ_e| {:.2e}, min dist {:.3} m ({:?}), contact {:?}",
            r.first_exit_s,
            r.min_h_m2,
            r.final_r_e_m,
            r.final_sigma_e,
            r.min_distance_m,
            r.min_distance_parts,
            r.first_contact_s
        );
        assert!(r.final_r_e_m < 0.01 && r.final_sigma_e < 1e-4);
        assert!(!r.corridor_held && r.min_h_m2 < 0.0 && r.min_corridor_margin_m < 0.0);
        // At r_e = 0 the closest parts are the cone tip and the slot mouth: axially 0.3 m apart
        // (cone tip 0.7 m ahead of the chaser centre, slot mouth 1.0 m ahead of the target
        // centre, centres 2 m apart), and in the meridian plane the tip edge (ρ = 0.03 m) is
        // √(0.3² + 0.12²) = 0.3231 m from the mouth rim (ρ = 0.15 m); the facetted hulls move
        // that by millimetres. The approach is a straight line that stops there: no contact.
        assert!(r.first_contact_s.is_none());
        assert!(
            r.min_distance_parts.1 == "chaser/cone"
                && r.min_distance_parts.0.starts_with("target/slot")
        );
        assert!(r.min_distance_m > 0.3 && r.min_distance_m < 0.3231 + 5e-3);
    }
}

/// ∇h of the closed-form cissoid by central differences (step 1e-6 m).
fn grad_h(r: &Vector3<f64>) -> Vector3<f64> {
    Vector3::from_fn(|i, _| {
        let (mut a, mut b) = (*r, *r);
        a[i] += 1e-6;
        b[i] -= 1e-6;
        (h_closed_form(&a, 25.0, 5.0) - h_closed_form(&b, 25.0, 5.0)) / 2e-6
    })
}

#[test]
fn val_guo2016_continuous_time_barrier() {
    // The reaching variant in continuous time (Bevy-free plant of `reproduce::guo2016_ct`,
    // adaptive Rosenbrock steps, event on h = 0), against two independent readings:
    // 1. Desired attitude held fixed (σ_d ≡ 0): the law alone. The same plant sampled at
    //    100 Hz leaves the corridor at the sample where the ECS leaves it (0.51 s); in
    //    continuous time h stays > 0 through the wall encounter — the exit is the sampling.
    // 2. The paper's σ_d(t): the continuous-time run ends at the event h = 0. At that point
    //    the chaser's body-frame velocity has vanished (|ṙ_e| < 1e-6 m/s) and the rate at
    //    which h falls is the one a rigid rotation of the body-fixed line of sight with the
    //    desired frame's angular velocity gives: ḣ = ∇h·(ω × r1), ω = q_D0·q(σ_d)·G(σ_d)⁻¹σ̇_d
    //    (closed-form ∇h). That is a property of the law with a moving attitude reference.
    use rpod::control::guo2016::q_d0_to_target;
    use rpod::math::mrp::{mrp_g_inv, quat_from_mrp};
    use rpod::reproduce::guo2016_ct::{CtSetup, run_continuous, run_sampled};
    let mut fixed = rep::reaching_variant("scenes/papers/guo2016/guo2016_corridor.ron").unwrap();
    *rep::spec_mut(&mut fixed).unwrap().sigma_d_amplitude = [0.0; 3];
    let sf = CtSetup::from_scene(&fixed).unwrap();
    let z = run_sampled(&sf, "100 Hz", 0.01, 0.6, 0.01);
    let c = run_continuous(&sf, "continuous", 1.5, 0.01);
    eprintln!(
        "σ_d ≡ 0: 100 Hz exit at sample {:?} s; continuous: end {:?}, min h {:.3e} m², peak |F| {:.3e} N, {} steps",
        z.first_exit_at_sample_s, c.end, c.min_h_m2, c.peak_force_n, c.stats.accepted
    );
    let t_exit = z.first_exit_at_sample_s.expect("the sampled law leaves");
    assert!((t_exit - 0.51).abs() < 0.015, "{t_exit}");
    assert!(c.first_outside_s.is_none() && c.min_h_m2 > 0.0);
    assert_eq!(c.end, rpod::math::ode::OdeEnd::Reached);
    // It did meet the wall: h came within 1e-2 m² of it (vs 642 m² at the start), at a
    // finite force.
    assert!(c.min_h_m2 < 1e-2, "{}", c.min_h_m2);
    assert!(c.peak_force_n.is_finite() && c.peak_force_n < 1e8);

    let paper = rep::reaching_variant("scenes/papers/guo2016/guo2016_corridor.ron").unwrap();
    let sp = CtSetup::from_scene(&paper).unwrap();
    let r = run_continuous(&sp, "continuous", 0.6, 0.001);
    let last = *r.samples.last().unwrap();
    let (sd, sd_dot, _) = sp.params.sigma_d(r.t_end_s);
    let w = q_d0_to_target() * quat_from_mrp(&sd) * (mrp_g_inv(&sd) * sd_dot);
    let h_dot_pred = grad_h(&last.r1_m).dot(&w.cross(&last.r1_m));
    eprintln!(
        "paper σ_d: end {:?} at {:.5} s, h {:.3e} m², |ṙ_e| {:.2e} m/s, ḣ {:.4} m²/s (rigid rotation: {:.4}), |r_e| {:.3} m, peak |F| {:.3e} N",
        r.end,
        r.t_end_s,
        last.h_m2,
        last.r_e_dot_m_s,
        last.h_dot_m2_s,
        h_dot_pred,
        last.r_e_m,
        r.peak_force_n
    );
    assert!(matches!(r.end, rpod::math::ode::OdeEnd::Event { .. }));
    assert!(last.h_m2 > 0.0 && last.h_m2 < 1e-9);
    assert!(last.r_e_dot_m_s < 1e-6);
    assert!(h_dot_pred < 0.0 && ((last.h_dot_m2_s - h_dot_pred) / h_dot_pred).abs() < 0.01);
    assert!(r.peak_force_n.is_finite() && r.peak_force_n < 1e8);
}

#[test]
fn val_guo2016_reproduce_report_and_campaign() {
    // Everything `rpod reproduce guo2016` computes, written to a temporary directory: the
    // claims.json it writes says what the other tests of this file assert (4 of 9 held).
    let results = rep::compute().unwrap();
    let dir = std::env::temp_dir().join(format!("rpod-val-guo2016-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let claims = rep::write(&dir, &results, 0.0).unwrap();
    let text = std::fs::read_to_string(dir.join("claims.json")).unwrap();
    let json: serde_json::Value = serde_json::from_str(&text).unwrap();
    let held: Vec<(String, bool)> = json
        .as_array()
        .unwrap()
        .iter()
        .map(|c| {
            (
                c["id"].as_str().unwrap().to_string(),
                c["held"].as_bool().unwrap(),
            )
        })
        .collect();
    let want = [
        ("guo2016-corridor-held", true),
        ("guo2016-errors-converge", false),
        ("guo2016-no-collision", true),
        ("guo2016-k2-0-leaves-corridor", false),
        ("guo2016-k2-changes-path", false),
        ("guo2016-reaching-converges", true),
        ("guo2016-reaching-corridor-held-continuous", false),
        ("guo2016-reaching-corridor-held-100hz", false),
        ("guo2016-campaign-corridor-keeps-wings-clear", true),
    ];
    for c in json.as_array().unwrap() {
        let kind = c["kind"].as_str().unwrap();
        assert!(kind == "paper" || kind == "beyond the paper", "{c}");
        let src = c["threshold_source"].as_str().unwrap();
        assert!(
            src.starts_with("paper: ") || src.starts_with("ours: "),
            "{c}"
        );
        // The reaching term is ours: every claim about it is beyond the paper.
        if c["id"].as_str().unwrap().contains("reaching") {
            assert_eq!(kind, "beyond the paper");
        }
    }
    assert_eq!(held.len(), want.len());
    for ((id, h), (wid, wh)) in held.iter().zip(want) {
        assert_eq!((id.as_str(), *h), (wid, wh));
    }
    assert_eq!(claims.len(), want.len());
    for f in [
        "REPORT.md",
        "path_corridor.png",
        "attitude_error.png",
        "rate_error.png",
        "torque.png",
        "position.png",
        "velocity.png",
        "force.png",
        "campaign.png",
        "continuous_vs_sampled.png",
    ] {
        let m = std::fs::metadata(dir.join(f)).unwrap();
        assert!(m.len() > 1000, "{f}");
    }
    let _ = std::fs::remove_dir_all(&dir);

    // The campaign (50 seeded starts, 15 s each) and a 6-start campaign with the same seed,
    // whose starts are the first 6 of the big one: identical numbers (determinism).
    // Every start lies inside the corridor (closed-form h); the law's own inside flag agrees
    // with the monitor's guarantee; the chaser–wing distance is never below the monitor's
    // full-geometry minimum (a lower bound over all part pairs).
    let big = rep::campaign(
        rep::CAMPAIGN_RUNS,
        rep::CAMPAIGN_SEED,
        rep::CAMPAIGN_DURATION_S,
    )
    .unwrap();
    let small = rep::campaign(6, rep::CAMPAIGN_SEED, rep::CAMPAIGN_DURATION_S).unwrap();
    assert_eq!(big.len(), rep::CAMPAIGN_RUNS);
    for (x, y) in big.iter().zip(&small) {
        assert_eq!(x.category(), y.category());
        if let (Some(r), Some(s)) = (&x.run, &y.run) {
            assert_eq!(
                r.min_wing_distance_m.to_bits(),
                s.min_wing_distance_m.to_bits()
            );
            assert_eq!(r.final_r_e_m.to_bits(), s.final_r_e_m.to_bits());
        }
    }
    for x in &big {
        assert!(h_closed_form(&x.start.r0_m, 25.0, 5.0) > 0.0);
        if let Some(r) = &x.run {
            assert_eq!(r.corridor_held, r.min_corridor_margin_m > 0.0);
            assert!(r.min_wing_distance_m >= r.min_distance_m - 1e-6);
        }
    }
    // Claim (beyond the paper): whenever the point-mass corridor held, no chaser part came
    // within 0.5 m of a target wing part — held in this campaign.
    let n = rep::campaign_counts(&big);
    eprintln!("campaign outcome counts {n:?} ({:?})", rep::CATEGORIES);
    assert_eq!(n[1], 0);
    // Finding: runs leave the corridor although their straight line r0 → r_d lies inside it
    // (the body-frame sliding motion curves while the attitude error decays).
    let corridor = rpod::geometry::cissoid::Cissoid::new(25.0, 5.0);
    let left_with_line_inside = big
        .iter()
        .filter(|x| x.run.as_ref().is_some_and(|r| !r.corridor_held))
        .filter(|x| rep::straight_line_inside(&corridor, &x.start.r0_m))
        .count();
    assert!(left_with_line_inside > 0);
}

#[test]
fn regress_guo2016_bad_controller_entry_is_a_located_error() {
    let bad = rep::CORRIDOR_SCENE.replace("k1_per_s: 9.0", "k1_per_s: -9.0");
    let l = load_scene_str(&bad, "bad.ron", &[]).unwrap();
    let e = Simulation::new(&l).err().expect("refused");
    // The error names the field and points into the controllers block of the text.
    let controllers_line = bad
        .lines()
        .position(|l| l.contains("controllers:"))
        .unwrap()
        + 1;
    eprintln!("{e}");
    assert!(
        e.field.ends_with("k1_per_s") && e.line >= controllers_line,
        "{e}"
    );
    let bad = rep::CORRIDOR_SCENE.replace("chaser: \"chaser\",", "chaser: \"nobody\",");
    let l = load_scene_str(&bad, "bad.ron", &[]).unwrap();
    let e = Simulation::new(&l).err().expect("refused");
    assert!(
        e.field.contains("chaser") && e.message.contains("nobody"),
        "{e}"
    );
}

#[test]
fn val_guo2016_command_reaches_the_chaser_in_world_axes() {
    // Reference: one step integrated by hand. The law's force F_b (chaser axes) must change the
    // chaser velocity by q₀·F_b/m·dt (world axes) up to the differential gravity over the step
    // (≤ 3n²|r|·dt ≈ 1.3e-6 m/s at 41 m); its torque plus d_τ must change the (initially zero)
    // rate by q₀·J⁻¹(τ + d_τ)·dt up to three terms second order in ω̇·dt, each bounded by
    // ‖J‖‖J⁻¹‖|ω̇dt|²·dt: the gyroscopic term, the torque held in world axes while the body
    // turns, and q₁ vs q₀ in the conversion to world axes.
    let mut sim = sim_of("scenes/papers/guo2016/guo2016_corridor.ron");
    let s0 = sim.body("chaser").unwrap();
    sim.step(1);
    let s1 = sim.body("chaser").unwrap();
    let c = sim.law::<Guo2016Instance>(0).unwrap().clone();
    let dt = 0.01;
    let p = &c.law.params;
    let dv = s1.vel_m_s - s0.vel_m_s;
    let want = s0.att * c.command.force_body_n / p.chaser_mass_kg * dt;
    let n = c.disturbance_rate_rad_s;
    let grav_bound = 3.0 * n * n * s0.pos_m.norm() * dt;
    eprintln!(
        "Δv {dv} want {want} (|F| {:.3} N)",
        c.command.force_body_n.norm()
    );
    assert!(want.norm() > 100.0 * grav_bound);
    assert!((dv - want).norm() < grav_bound, "{}", (dv - want).norm());
    let j_inv = p.chaser_inertia_body_kg_m2.try_inverse().unwrap();
    let dist = sim
        .controllers()
        .disturbance::<rpod::control::guo2016::Guo2016Disturbance>(0)
        .unwrap()
        .last_body_nm;
    let wdot = j_inv * (c.command.torque_body_nm + dist);
    let want_w = s0.att * wdot * dt;
    let err = (s1.omega_rad_s - want_w).norm();
    let gyro =
        (p.chaser_inertia_body_kg_m2.norm() * (wdot * dt).norm_squared()) * j_inv.norm() * dt;
    eprintln!(
        "ω₁ {} want {want_w}: err {err:.3e} (gyroscopic bound {gyro:.3e})",
        s1.omega_rad_s
    );
    assert!(err <= 3.0 * gyro + 1e-12 * want_w.norm(), "{err}");
}
