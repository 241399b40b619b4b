//! The generic laws in the simulation against closed forms and independent integrations.
//!
//! References, per test:
//! - `HillPd` (PD, ζ = 1, CW cancellation) from a radial offset at rest: the closed form of
//!   critically damped error dynamics, e(t) = e₀(1 + ωt)e^{−ωt}, on the radial axis, and zero
//!   on the others. The sampled controller (zero-order hold at T) delays the command by T/2 on
//!   average, so the trajectory departs from the continuous closed form by about
//!   (T/2)·max|ė| = (T/2)·e₀ω/e; the tests allow twice that, T·max|ė|, here and below.
//! - `HillPd` with LQR gains: the discrete closed loop x_{k+1} = (A_d − B_d K) x_k of the CW
//!   model, propagated in the test in f64 with A_d, B_d from the CW closed-form transition
//!   matrix (not from the law's matrix exponential). The simulation is nonlinear two-body
//!   motion; at 50 m from the reference the CW model's error is ~3ρ/r ≈ 2e-5 relative.
//! - `Glideslope` along V-bar: the closed-loop closed form of `tests/common` — the profile's
//!   closed form plus the critically damped responses to its two velocity steps — for the
//!   range (tolerance T·max|ė| = T·v₀ for the zero-order hold) and for the Δv the actuator
//!   applied, ∫|(2nṡ, −s̈)| dt (tolerance 2ωT of the transients' share, v₀ + v_end, for the hold,
//!   and 1e-3 relative for the nonlinear gravity the CW model leaves out at 100 m). The
//!   glideslope's analytic Δv for an ideal (impulsive-start) tracker is printed beside it; it is
//!   not a bound: a smooth tracker's start can cost less than the impulse it replaces.
//! - `Attitude` (small rest-to-rest slew about one principal axis, no gravity): the closed
//!   form of θ̈ + 2ζω θ̇ + ω²θ = 0, θ(t) = θ₀(1 + ωt)e^{−ωt} for ζ = 1; the quaternion
//!   feedback uses 2 q_v = 2 sin(θ/2) for θ, so the linear closed form holds to O(θ₀²/24)
//!   relative (2e-5 at 1°); the zero-order hold at T = 0.02 s as above: T·max|θ̇| = T·θ₀ω/e.
//! - Sequencer and registry errors: exact file:line:col and field of hand-written scenes.

mod common;

use nalgebra::{SMatrix, Vector3};
use rpod::control::generic::glideslope::{Profile, ideal_delta_v_m_s};
use rpod::orbit::constants::MU_EARTH_M3_S2;
use rpod::orbit::lvlh::{LocalFrame, LocalFrameKind};
use rpod::scene::load_scene_str;
use rpod::sim::Simulation;

const A_M: f64 = 7_000_000.0;

fn n() -> f64 {
    (MU_EARTH_M3_S2 / A_M.powi(3)).sqrt()
}

/// A circular orbit without J2 or gravity-gradient torque: the CW model's home ground.
fn orbit_scene(dt: f64, chaser_hill: [f64; 3], controller: &str) -> String {
    format!(
        r#"Scene(name: "g", dt_s: {dt}, duration_s: 100.0, record_every_steps: 1000,
        environment: Orbit(reference: Elements(a_m: {A_M}, e: 0.0, i_deg: 0.0, raan_deg: 0.0,
                           argp_deg: 0.0, true_anomaly_deg: 0.0), j2: false, gravity_gradient: false),
        bodies: [
            (name: "target", role: Target, mass_kg: 500.0, inertia_kg_m2: (xx: 100.0, yy: 100.0, zz: 100.0),
             initial: (frame: Hill, pos_m: (0.0, 0.0, 0.0)),
             parts: [Bus(name: "bus", shape: Sphere(radius_m: 0.5))]),
            (name: "chaser", role: Chaser, mass_kg: 200.0, inertia_kg_m2: (xx: 50.0, yy: 50.0, zz: 50.0),
             initial: (frame: Hill, pos_m: ({}, {}, {})),
             parts: [Bus(name: "bus", shape: Sphere(radius_m: 0.5))]),
        ],
        controllers: [{controller}],
    )"#,
        chaser_hill[0], chaser_hill[1], chaser_hill[2]
    )
}

/// The chaser relative to the target in the reference (= target) Hill frame.
fn hill_rel(sim: &Simulation) -> (Vector3<f64>, Vector3<f64>) {
    let (r, v) = sim.reference_state().unwrap();
    let c = sim.body("chaser").unwrap();
    let t = sim.body("target").unwrap();
    let f = LocalFrame::new(LocalFrameKind::Hill, &(r + t.pos_m), &(v + t.vel_m_s));
    f.to_local(&(c.pos_m - t.pos_m), &(c.vel_m_s - t.vel_m_s))
}

#[test]
fn val_hill_pd_critically_damped_closed_form() {
    let w = 0.05;
    let e0 = 2.0;
    let law = format!(
        r#"HillPd(body: "chaser", target: "target", period_s: 0.1,
           params: (hold_m: (0.0, -50.0, 0.0),
                    gains: Pd(natural_frequency_rad_s: {w}, damping_ratio: 1.0)))"#
    );
    let text = orbit_scene(0.05, [e0, -50.0, 0.0], &law);
    let loaded = load_scene_str(&text, "pd.ron", &[]).unwrap_or_else(|e| panic!("{e}"));
    let mut sim = Simulation::new(&loaded).unwrap();
    let mut worst = 0.0f64;
    let mut cross = 0.0f64;
    for k in 1..=400 {
        sim.step(10);
        let t = k as f64 * 0.5;
        let (p, _) = hill_rel(&sim);
        let want = e0 * (1.0 + w * t) * (-w * t).exp();
        worst = worst.max((p.x - want).abs());
        cross = cross.max((p.y + 50.0).abs()).max(p.z.abs());
    }
    println!(
        "HillPd: max |e − e_closed| = {worst:.3e} m, max cross-axis error {cross:.3e} m (e0 = {e0} m)"
    );
    assert!(worst < 0.01 * e0, "{worst}");
    assert!(cross < 0.005 * e0, "{cross}");
}

/// The CW state-transition matrix (closed form, Clohessy & Wiltshire 1960) and its integral.
fn cw_stm(n: f64, t: f64) -> SMatrix<f64, 6, 6> {
    let (s, c) = (n * t).sin_cos();
    let mut phi = SMatrix::<f64, 6, 6>::zeros();
    phi[(0, 0)] = 4.0 - 3.0 * c;
    phi[(0, 3)] = s / n;
    phi[(0, 4)] = 2.0 * (1.0 - c) / n;
    phi[(1, 0)] = 6.0 * (s - n * t);
    phi[(1, 1)] = 1.0;
    phi[(1, 3)] = -2.0 * (1.0 - c) / n;
    phi[(1, 4)] = (4.0 * s - 3.0 * n * t) / n;
    phi[(2, 2)] = c;
    phi[(2, 5)] = s / n;
    phi[(3, 0)] = 3.0 * n * s;
    phi[(3, 3)] = c;
    phi[(3, 4)] = 2.0 * s;
    phi[(4, 0)] = -6.0 * n * (1.0 - c);
    phi[(4, 3)] = -2.0 * s;
    phi[(4, 4)] = 4.0 * c - 3.0;
    phi[(5, 2)] = -n * s;
    phi[(5, 5)] = c;
    phi
}

#[test]
fn val_hill_lqr_against_discrete_cw_closed_loop() {
    let period = 0.5;
    let (qp, qv, r) = ([1e-2; 3], [1.0; 3], [1e4; 3]);
    let law = format!(
        r#"HillPd(body: "chaser", target: "target", period_s: {period},
           params: (hold_m: (0.0, -50.0, 0.0),
                    gains: Lqr(q_pos_per_m2: ({}, {}, {}), q_vel_s2_per_m2: ({}, {}, {}),
                               r_s4_per_m2: ({}, {}, {}))))"#,
        qp[0], qp[1], qp[2], qv[0], qv[1], qv[2], r[0], r[1], r[2]
    );
    let x0 = Vector3::new(1.5, -48.0, 0.8);
    let text = orbit_scene(0.1, [x0.x, x0.y, x0.z], &law);
    let loaded = load_scene_str(&text, "lqr.ron", &[]).unwrap_or_else(|e| panic!("{e}"));
    let mut sim = Simulation::new(&loaded).unwrap();
    let n = n();
    let k = rpod::control::generic::hill::lqr_cw_gain(n, period, &qp, &qv, &r);
    // B_d = ∫₀ᵀ Φ(s) ds B by Simpson's rule on the closed-form Φ (4th order; 1e-14 here).
    let mut bd = SMatrix::<f64, 6, 3>::zeros();
    let m = 200;
    for j in 0..=m {
        let s = period * j as f64 / m as f64;
        let wgt = if j == 0 || j == m {
            1.0
        } else if j % 2 == 1 {
            4.0
        } else {
            2.0
        };
        bd += cw_stm(n, period - s).fixed_view::<6, 3>(0, 3) * (wgt * period / (3.0 * m as f64));
    }
    let ad = cw_stm(n, period);
    let mut x = SMatrix::<f64, 6, 1>::zeros();
    x.fixed_rows_mut::<3>(0)
        .copy_from(&(x0 - Vector3::new(0.0, -50.0, 0.0)));
    let mut worst = 0.0f64;
    let e_start = x.fixed_rows::<3>(0).norm();
    for _ in 0..600 {
        x = (ad - bd * k) * x;
        sim.step(5);
        let (p, _) = hill_rel(&sim);
        let e = p - Vector3::new(0.0, -50.0, 0.0);
        worst = worst.max((e - x.fixed_rows::<3>(0)).norm());
    }
    let e_end = x.fixed_rows::<3>(0).norm();
    println!(
        "LQR: |e| {e_start:.3} m → {e_end:.3e} m in 300 s; max deviation from the discrete CW loop {worst:.3e} m"
    );
    assert!(e_end < 0.05 * e_start, "the loop converges");
    assert!(worst < 1e-3 * e_start, "{worst}");
}

#[test]
fn val_glideslope_vbar_range_and_delta_v() {
    let (tau, vmin, w, period) = (200.0, 0.05, 0.2, 0.02);
    let law = format!(
        r#"Glideslope(body: "chaser", target: "target", period_s: {period},
           params: (axis: VBarBehind, to_range_m: 10.0,
                    profile: Exponential(time_constant_s: {tau}, min_speed_m_s: {vmin}),
                    gains: Pd(natural_frequency_rad_s: {w}, damping_ratio: 1.0)))"#
    );
    let text = orbit_scene(period, [0.0, -100.0, 0.0], &law);
    let loaded = load_scene_str(&text, "gs.ron", &[]).unwrap_or_else(|e| panic!("{e}"));
    let mut sim = Simulation::new(&loaded).unwrap();
    let profile = Profile::Exponential {
        time_constant_s: tau,
        min_speed_m_s: vmin,
    };
    let d0 = 90.0;
    let cl = common::GlideslopeLoop::new(profile, d0, w);
    let t_run = cl.t_end + 60.0;
    let steps = (t_run / period).round() as u64;
    let mut worst = 0.0f64;
    for k in 1..=steps / 50 {
        sim.step(50);
        let t = k as f64 * 50.0 * period;
        let (p, _) = hill_rel(&sim);
        worst = worst.max((-p.y - (10.0 + cl.plant(t).0)).abs());
    }
    let dv = sim.controllers().slots[0].actuator.delta_v_m_s;
    let predicted = cl.delta_v(n(), t_run, 1e-3);
    let ideal = ideal_delta_v_m_s(&profile, d0, n());
    let tol_r = period * cl.v0;
    let tol_dv = 2.0 * w * period * (cl.v0 + cl.v_end) + 1e-3 * predicted;
    println!(
        "Glideslope: max |range − closed loop| {worst:.3e} m (bound {tol_r:.3e}); Δv {dv:.5} m/s vs closed loop {predicted:.5} (± {tol_dv:.5}), ideal tracker {ideal:.5} m/s"
    );
    assert!(worst < tol_r, "{worst}");
    assert!((dv - predicted).abs() < tol_dv, "{dv} vs {predicted}");
}

#[test]
fn val_attitude_small_slew_closed_form() {
    let (w, th0) = (0.5, 1f64.to_radians());
    let text = format!(
        r#"Scene(name: "att", dt_s: 0.01, duration_s: 30.0, environment: FreeSpace,
        bodies: [(name: "sc", role: Chaser, mass_kg: 100.0, inertia_kg_m2: (xx: 10.0, yy: 20.0, zz: 30.0),
                  initial: (pos_m: (0.0, 0.0, 0.0), attitude: EulerZyxDeg(yaw: 1.0, pitch: 0.0, roll: 0.0)),
                  parts: [Bus(name: "bus", shape: Sphere(radius_m: 0.5))])],
        controllers: [Attitude(body: "sc", period_s: 0.02,
                      params: (mode: Inertial(attitude: EulerZyxDeg(yaw: 0.0, pitch: 0.0, roll: 0.0)),
                               natural_frequency_rad_s: {w}, damping_ratio: 1.0))],
    )"#
    );
    let loaded = load_scene_str(&text, "att.ron", &[]).unwrap_or_else(|e| panic!("{e}"));
    let mut sim = Simulation::new(&loaded).unwrap();
    let mut worst = 0.0f64;
    for k in 1..=300 {
        sim.step(10);
        let t = k as f64 * 0.1;
        let q = sim.body("sc").unwrap().att;
        let (_, _, yaw) = q.euler_angles();
        let want = th0 * (1.0 + w * t) * (-w * t).exp();
        worst = worst.max((yaw - want).abs());
    }
    let tol = 0.02 * th0 * w / std::f64::consts::E + 2e-5 * th0;
    println!("Attitude: max |θ − θ_closed| = {worst:.3e} rad (θ0 = {th0:.4} rad, bound {tol:.3e})");
    assert!(worst < tol, "{worst}");
}

fn err_of(text: &str) -> rpod::scene::SceneError {
    let loaded = load_scene_str(text, "bad.ron", &[]).map_err(|e| e.to_string());
    match loaded {
        Err(e) => panic!("load failed early: {e}"),
        Ok(l) => match Simulation::new(&l) {
            Ok(_) => panic!("expected an error"),
            Err(e) => e,
        },
    }
}

#[test]
fn val_sequencer_and_registry_errors_are_located() {
    let seq = |phases: &str| {
        orbit_scene(
            0.1,
            [0.0, -50.0, 0.0],
            &format!(
                "Sequencer(body: \"chaser\", target: \"target\", period_s: 0.1,\n    params: (phases: [{phases}]))"
            ),
        )
    };
    let hold = r#"translation: Some(HillPd((hold_m: (0.0, -50.0, 0.0), gains: Pd(natural_frequency_rad_s: 0.05, damping_ratio: 1.0))))"#;
    // A phase with no exit that is not the last one: it could never be left.
    let t = seq(&format!("(name: \"a\", {hold}),\n (name: \"b\", {hold})"));
    let e = err_of(&t);
    assert_eq!(e.field, "controllers.0.params.phases.0.exits", "{e}");
    assert!(e.message.contains("could never be left"), "{e}");
    assert_eq!((e.line, e.col), (13, 23), "{e}");
    // An exit to a phase that does not exist.
    let t = seq(&format!(
        "(name: \"a\", {hold}, exits: [(when: InPhaseFor(1.0), to: \"zz\")]),\n (name: \"b\", {hold})"
    ));
    let e = err_of(&t);
    assert_eq!(e.field, "controllers.0.params.phases.0.exits.0.to", "{e}");
    // A phase nothing leads to.
    let t = seq(&format!(
        "(name: \"a\", {hold}, exits: [(when: InPhaseFor(1.0), to: \"c\")]),\n (name: \"b\", {hold}, exits: [(when: InPhaseFor(1.0), to: \"c\")]),\n (name: \"c\")"
    ));
    let e = err_of(&t);
    assert_eq!(e.field, "controllers.0.params.phases.1.name", "{e}");
    assert!(e.message.contains("never be entered"), "{e}");
    // An unknown law and a parameter of the wrong type: syntax-level errors with line:col.
    let t = orbit_scene(
        0.1,
        [0.0, -50.0, 0.0],
        "NoSuchLaw(body: \"chaser\", params: ())",
    );
    let e = load_scene_str(&t, "bad.ron", &[]).unwrap_err();
    assert!(e.message.contains("unknown controller `NoSuchLaw`"), "{e}");
    assert_eq!(e.line, 12, "{e}");
    let t = orbit_scene(
        0.1,
        [0.0, -50.0, 0.0],
        "HillPd(body: \"chaser\", target: \"target\",\n params: (hold_m: \"far\", gains: Pd(natural_frequency_rad_s: 0.05, damping_ratio: 1.0)))",
    );
    let e = load_scene_str(&t, "bad.ron", &[]).unwrap_err();
    assert_eq!(e.line, 13, "{e}");
    assert!(e.field.contains("hold_m"), "{e}");
    // A law naming a missing body; a bad gain.
    let t = orbit_scene(
        0.1,
        [0.0, -50.0, 0.0],
        "HillPd(body: \"nobody\", target: \"target\", params: (hold_m: (0.0, 0.0, 0.0), gains: Pd(natural_frequency_rad_s: 0.05, damping_ratio: 1.0)))",
    );
    let e = err_of(&t);
    assert_eq!(e.field, "controllers.0.body", "{e}");
    let t = orbit_scene(
        0.1,
        [0.0, -50.0, 0.0],
        "HillPd(body: \"chaser\", target: \"target\", params: (hold_m: (0.0, 0.0, 0.0), gains: Pd(natural_frequency_rad_s: -1.0, damping_ratio: 1.0)))",
    );
    let e = err_of(&t);
    assert_eq!(
        e.field, "controllers.0.params.gains.0.natural_frequency_rad_s",
        "{e}"
    );
    assert!(e.line > 0 && e.col > 0, "{e}");
}

/// A user law that commands both a force and a torque (declares `ForceAndTorque`, the default).
#[derive(Debug, Clone, serde::Deserialize)]
struct PushTwistParams {
    /// Force along world x, N.
    force_n: f64,
    /// Torque about world z, N·m.
    torque_nm: f64,
}

struct PushTwist(PushTwistParams);

impl rpod::control::registry::LawParams for PushTwistParams {
    fn build(
        &self,
        _ctx: &mut rpod::control::registry::LawContext,
    ) -> Result<Box<dyn rpod::control::interface::Controller>, rpod::control::registry::BuildError>
    {
        Ok(Box::new(PushTwist(self.clone())))
    }
}

impl rpod::control::interface::Controller for PushTwist {
    fn command(
        &mut self,
        _obs: &rpod::control::interface::Observation,
    ) -> rpod::control::interface::Command {
        rpod::control::interface::Command::in_frame(
            rpod::control::interface::Frame::World,
            Vector3::new(self.0.force_n, 0.0, 0.0),
            Vector3::new(0.0, 0.0, self.0.torque_nm),
        )
    }
}

/// A law declaring both force and torque in a Sequencer's translation slot: its force is
/// flown and its torque is not, and one `sequencer_dropped` event says so. References (free
/// space, no gravity): the momentum closed form v(t) = F t / m for the force, and conservation
/// of angular momentum (the body stays at rest in rotation: ω = 0 exactly, no torque reaches
/// it) for the dropped torque.
#[test]
fn val_sequencer_drops_the_unused_part_of_a_law_and_says_so() {
    // Registration is process-wide; a second registration of the name (another test thread
    // of this binary does not register it) would be an error, so only this test registers.
    rpod::control::registry::register_law::<PushTwistParams>("PushTwistSeqTest")
        .expect("a new name");
    let (f, m) = (2.0, 100.0);
    let text = format!(
        r#"Scene(name: "drop", dt_s: 0.01, duration_s: 10.0, environment: FreeSpace,
        bodies: [(name: "sc", role: Chaser, mass_kg: {m}, inertia_kg_m2: (xx: 10.0, yy: 20.0, zz: 30.0),
                  initial: (pos_m: (0.0, 0.0, 0.0)),
                  parts: [Bus(name: "bus", shape: Sphere(radius_m: 0.5))])],
        controllers: [Sequencer(body: "sc", period_s: 0.1,
            params: (phases: [
                (name: "a", translation: Some(PushTwistSeqTest((force_n: {f}, torque_nm: 5.0))),
                 exits: [(when: InPhaseFor(1.0), to: "b")]),
                (name: "b", translation: Some(PushTwistSeqTest((force_n: {f}, torque_nm: 5.0)))),
            ]))],
    )"#
    );
    let loaded = load_scene_str(&text, "drop.ron", &[]).unwrap_or_else(|e| panic!("{e}"));
    let mut sim = Simulation::new(&loaded).unwrap();
    sim.step(300);
    let b = sim.body("sc").unwrap();
    let t = 3.0;
    let v_want = f * t / m;
    println!(
        "dropped torque: v = {:.6} m/s (closed form {v_want:.6}), |ω| = {:e} rad/s",
        b.vel_m_s.x,
        b.omega_rad_s.norm()
    );
    // f32 rapier integrates the force: 1e-5 relative is its single-precision accumulation.
    assert!(
        (b.vel_m_s.x - v_want).abs() < 1e-5 * v_want,
        "{}",
        b.vel_m_s.x
    );
    assert_eq!(
        b.omega_rad_s.norm(),
        0.0,
        "a dropped torque must not turn the body"
    );
    let dropped: Vec<_> = sim
        .events()
        .into_iter()
        .filter(|e| e.kind == "sequencer_dropped")
        .collect();
    // One per phase and slot: phase a, then phase b.
    assert_eq!(dropped.len(), 2, "{dropped:?}");
    assert_eq!(dropped[0].data["phase"], "a");
    assert_eq!(dropped[1].data["phase"], "b");
    assert_eq!(dropped[0].data["slot"], "translation");
    assert_eq!(dropped[0].t_s, 0.0);
}
