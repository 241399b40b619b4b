//! `Rcs` jets through PWPF, and their firing events (docs/vehicles.md).
//!
//! References:
//! - **Duty cycle.** A constant demand r = u/F_max on a jet through its pulse-width
//!   pulse-frequency modulator settles into a limit cycle whose on- and off-times are the
//!   closed forms T_on = −T_m ln(1 − H/(U_on + K_m(1 − r))), T_off = −T_m ln(1 − H/(K_m r −
//!   U_off)) (H = U_on − U_off; `actuation::pwpf`), so the jet's average thrust is F_max·D(r),
//!   D = T_on/(T_on + T_off); below the dead zone U_on/K_m it never fires. Tolerances: a
//!   switching instant is found at a step boundary, so each phase is off by at most
//!   dt·(2 + |ḟ before|/|ḟ after|) (the slopes of the filter at the threshold, as in
//!   `pwpf::tests`); over a 20 s window the partial first period and the start-up bias the
//!   average by at most 1 % of full scale (as `thrusters::tests::val_thruster_pwpf_average_force`).
//! - **Minimum impulse bit.** With PWPF each pulse is held open for at least I_min/F_max, so
//!   every pulse delivers at least I_min (rounding of the summed on-time only, 1e-12).
//! - **Momentum.** In free space the body's velocity change is the jets' total impulse over its
//!   mass (the jets push through the centre of mass); each pulse event's impulse is F_max times
//!   its duration (valves at full thrust), and the events' impulses plus the pulse still open
//!   at the end add up to the summary's per-jet impulse.
//! - **Event caps.** A jet chattering every step raises exactly `MAX_PULSE_EVENTS_PER_JET`
//!   pulse events and one `jet_pulse_events_capped`; a layout chattering together stops at
//!   `MAX_PULSE_EVENTS_PER_RUN` for the run, and the run completes; the summary still counts
//!   every pulse and the impulse is (number of on-steps)·F·dt.

use nalgebra::{UnitQuaternion, Vector3};
use rpod::actuation::actuator::{Actuator, ActuatorSpec, CommandFrames};
use rpod::actuation::pwpf::PwpfParams;
use rpod::actuation::rcs::{JetSpec, MAX_PULSE_EVENTS_PER_JET, MAX_PULSE_EVENTS_PER_RUN};
use rpod::control::interface::{Command, Controller, Frame, Observation};
use rpod::control::registry::{BuildError, LawContext, LawParams, register_law};
use rpod::scene::load_scene_str;
use rpod::sim::Simulation;
use serde::Deserialize;

/// A test law: a constant force in body axes.
#[derive(Debug, Clone, Deserialize)]
struct BodyForceParams {
    force_n: [f64; 3],
}

impl LawParams for BodyForceParams {
    fn build(&self, _ctx: &mut LawContext) -> Result<Box<dyn Controller>, BuildError> {
        Ok(Box::new(BodyForce(Vector3::from(self.force_n))))
    }
}

struct BodyForce(Vector3<f64>);

impl Controller for BodyForce {
    fn command(&mut self, _obs: &Observation) -> Command {
        Command::in_frame(Frame::Body, self.0, Vector3::zeros())
    }
}

/// A test law: every valve of its `Rcs` open on one call, closed on the next.
#[derive(Debug, Clone, Deserialize)]
struct ToggleParams {
    jets: usize,
}

impl LawParams for ToggleParams {
    fn build(&self, _ctx: &mut LawContext) -> Result<Box<dyn Controller>, BuildError> {
        Ok(Box::new(Toggle(self.jets, false)))
    }
}

struct Toggle(usize, bool);

impl Controller for Toggle {
    fn command(&mut self, _obs: &Observation) -> Command {
        self.1 = !self.1;
        let mut c = Command::zero();
        c.valves = Some(vec![self.1; self.0]);
        c
    }
}

fn register() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| {
        register_law::<BodyForceParams>("TestBodyForce").expect("a new name");
        register_law::<ToggleParams>("TestToggle").expect("a new name");
    });
}

fn jet(name: &str, x: f64, dir: f64, fmax: f64, bit: f64) -> JetSpec {
    JetSpec {
        name: name.into(),
        pos_m: [x, 0.0, 0.0],
        direction: [dir, 0.0, 0.0],
        max_thrust_n: fmax,
        min_impulse_bit_ns: bit,
        plume: None,
    }
}

/// Two opposed jets on the body x axis (no moment), through PWPF.
fn actuator(fmax: f64, bit: f64, pwpf: PwpfParams) -> Actuator {
    Actuator::new(ActuatorSpec::Rcs {
        jets: vec![
            jet("px", -0.5, 1.0, fmax, bit),
            jet("mx", 0.5, -1.0, fmax, 0.0),
        ],
        isp_s: 220.0,
        plume_loads: false,
        pwpf: Some(pwpf),
        firing_events: true,
    })
}

fn frames() -> CommandFrames {
    CommandFrames {
        body: UnitQuaternion::identity(),
        hill: None,
        target_body: None,
    }
}

/// Steps the actuator with a constant body force along x: the thrust of jet `px` per step.
fn thrusts(a: &mut Actuator, force_n: f64, dt: f64, n: usize) -> Vec<f64> {
    let cmd = Command::in_frame(
        Frame::Body,
        Vector3::new(force_n, 0.0, 0.0),
        Vector3::zeros(),
    );
    (0..n)
        .map(|_| {
            let r = a.step(&cmd, &frames(), 100.0, dt).expect("body frame");
            let t = r.jet_thrust_n.expect("jet thrusts");
            assert_eq!(t[1], 0.0, "the opposed jet never fires");
            t[0]
        })
        .collect()
}

/// Complete on and off runs (s) from the first pulse on (the first pulse starts at U_on as
/// every later one does, so it is already the steady pulse).
fn runs(t: &[f64], dt: f64) -> (Vec<f64>, Vec<f64>) {
    let (mut ons, mut offs) = (Vec::new(), Vec::new());
    let start = t.iter().position(|u| *u > 0.0).expect("fires");
    let mut k = start;
    while k < t.len() {
        let on = t[k] > 0.0;
        let len = t[k..].iter().take_while(|u| (**u > 0.0) == on).count();
        if k + len < t.len() {
            if on { &mut ons } else { &mut offs }.push(len as f64 * dt);
        }
        k += len;
    }
    (ons, offs)
}

#[test]
fn val_rcs_pwpf_average_thrust_is_the_duty_cycle() {
    let p = PwpfParams::typical();
    let (fmax, dt, n) = (10.0, 1e-4, 200_000);
    for r in [0.3, 0.5, 0.8] {
        let mut a = actuator(fmax, 0.0, p.clone());
        let t = thrusts(&mut a, r * fmax, dt, n);
        assert!(t.iter().all(|u| *u == 0.0 || *u == fmax), "on/off valves");
        let avg = t.iter().sum::<f64>() / n as f64;
        assert!(
            (avg - fmax * p.duty_cycle(r)).abs() < 0.01 * fmax,
            "r = {r}: {avg} vs {}",
            fmax * p.duty_cycle(r)
        );
        let slope = |target: f64, f: f64| (target - f).abs() / p.t_m_s;
        let on_tol = dt * (2.0 + slope(p.k_m * r, p.u_on) / slope(p.k_m * (r - 1.0), p.u_on));
        let off_tol = dt * (2.0 + slope(p.k_m * (r - 1.0), p.u_off) / slope(p.k_m * r, p.u_off));
        let (ons, offs) = runs(&t, dt);
        assert!(ons.len() > 100 && offs.len() > 100, "r = {r}");
        let (on_a, off_a) = (p.on_time_s(r).unwrap(), p.off_time_s(r).unwrap());
        for on in &ons {
            assert!((on - on_a).abs() <= on_tol, "r = {r}: on {on} vs {on_a}");
        }
        for off in &offs {
            assert!(
                (off - off_a).abs() <= off_tol,
                "r = {r}: off {off} vs {off_a}"
            );
        }
        // Accounting: impulse, on-time, firings and propellant of jet px.
        let j = &a.jets[0];
        let impulse = t.iter().sum::<f64>() * dt;
        assert!((j.impulse_ns - impulse).abs() < 1e-9 * impulse);
        assert!((j.on_time_s - impulse / fmax).abs() < 1e-9 * impulse);
        // `ons` holds every complete pulse from the first; one more if the last is open.
        assert_eq!(j.firings as usize, ons.len() + usize::from(t[n - 1] > 0.0));
        assert!((a.propellant_used_kg - impulse / (220.0 * 9.80665)).abs() < 1e-12 * impulse);
    }
    // Dead zone: r just below U_on/K_m never opens the valve.
    let mut a = actuator(fmax, 0.0, p.clone());
    let t = thrusts(&mut a, 0.999 * p.dead_zone() * fmax, dt, n);
    assert!(t.iter().all(|u| *u == 0.0));
}

#[test]
fn val_rcs_pwpf_pulses_honour_the_minimum_impulse_bit() {
    // I_min = 0.5 N·s at 10 N: 50 ms, longer than the modulator's own minimum pulse (13.8 ms).
    let p = PwpfParams::typical();
    let (fmax, bit, dt) = (10.0, 0.5, 1e-4);
    let mut a = actuator(fmax, bit, p.clone());
    let t = thrusts(&mut a, 0.15 * fmax, dt, 100_000);
    let (ons, _) = runs(&t, dt);
    assert!(ons.len() > 5);
    for on in ons {
        assert!(
            on * fmax >= bit * (1.0 - 1e-12),
            "pulse of {} N·s",
            on * fmax
        );
    }
    // Without the bit the same demand gives shorter pulses (the modulator's own, ≈ 15 ms).
    let mut a = actuator(fmax, 0.0, p.clone());
    let t = thrusts(&mut a, 0.15 * fmax, dt, 100_000);
    let (ons, _) = runs(&t, dt);
    let on_a = p.on_time_s(0.15).unwrap();
    assert!(on_a < 0.02 && ons.iter().all(|on| (on - on_a).abs() < 5.0 * dt));
}

fn scene(dt: f64, duration: f64, law: &str, jets: &str, rcs_options: &str) -> String {
    format!(
        r#"Scene(name: "rcs_pwpf", dt_s: {dt:?}, duration_s: {duration:?}, environment: FreeSpace,
        bodies: [(name: "sc", role: Chaser, mass_kg: 100.0, inertia_kg_m2: (xx: 10.0, yy: 20.0, zz: 30.0),
                  initial: (pos_m: (0.0, 0.0, 0.0)),
                  parts: [Bus(name: "bus", shape: Sphere(radius_m: 0.5))])],
        controllers: [{law}(body: "sc", period_s: {dt:?},
                      actuator: Rcs(jets: [{jets}]{rcs_options}),
                      params: {params})],
    )"#,
        params = if law == "TestToggle" {
            format!("(jets: {})", jets.matches("name:").count())
        } else {
            "(force_n: (5.0, 0.0, 0.0))".to_string()
        }
    )
}

const PAIR: &str = r#"(name: "px", pos_m: (-0.5, 0.0, 0.0), direction: (1.0, 0.0, 0.0), max_thrust_n: 10.0),
                      (name: "mx", pos_m: (0.5, 0.0, 0.0), direction: (-1.0, 0.0, 0.0), max_thrust_n: 10.0)"#;

fn run(text: &str, steps: u64) -> Simulation {
    register();
    let l = load_scene_str(text, "rcs_pwpf.ron", &[]).unwrap_or_else(|e| panic!("{e}"));
    let mut sim = Simulation::new(&l).unwrap_or_else(|e| panic!("{e}"));
    sim.step(steps);
    sim
}

#[test]
fn val_rcs_pwpf_pulse_events_in_a_run() {
    let p = PwpfParams::typical();
    let (dt, steps) = (1e-3, 10_000);
    let sim = run(
        &scene(
            dt,
            20.0,
            "TestBodyForce",
            PAIR,
            ", pwpf: Some(()), firing_events: true",
        ),
        steps,
    );
    let a = &sim.controllers().slots[0].actuator;
    let px = &a.jets[0];
    assert_eq!(a.jets[1].impulse_ns, 0.0, "mx never fires");
    // Momentum: Δv = impulse / m (rapier's f32 velocity, relative 1e-5).
    let v = sim.body("sc").unwrap().vel_m_s;
    assert!(
        (v.x - px.impulse_ns / 100.0).abs() < 1e-5 * v.x,
        "{} vs {}",
        v.x,
        px.impulse_ns / 100.0
    );
    let events: Vec<_> = sim
        .events()
        .into_iter()
        .filter(|e| e.kind == "jet_pulse")
        .collect();
    assert!(events.iter().all(|e| e.data["jet"] == "px"));
    assert_eq!(
        events.len() as u64 + u64::from(px.firing),
        px.firings,
        "one event per ended pulse"
    );
    let r = 0.5;
    let slope = |target: f64, f: f64| (target - f).abs() / p.t_m_s;
    let on_tol = dt * (2.0 + slope(p.k_m * r, p.u_on) / slope(p.k_m * (r - 1.0), p.u_on));
    let on_a = p.on_time_s(r).unwrap();
    let mut sum = 0.0;
    for (k, e) in events.iter().enumerate() {
        let f = |key: &str| e.data[key].as_f64().expect(key);
        let (start, dur, imp) = (f("start_s"), f("duration_s"), f("impulse_ns"));
        assert!(
            (start + dur - e.t_s).abs() < 1e-9,
            "ends at the event's time"
        );
        assert!((imp - 10.0 * dur).abs() < 1e-9 && (f("on_time_s") - dur).abs() < 1e-9);
        if k > 0 {
            assert!((dur - on_a).abs() <= on_tol, "pulse {k}: {dur} vs {on_a}");
        }
        sum += imp;
    }
    let open = if px.firing { px.pulse.1 } else { 0.0 };
    assert!((sum + open - px.impulse_ns).abs() < 1e-9 * px.impulse_ns);
    assert_eq!(
        sim.summary()["controllers"][0]["jets"][0]["firings"],
        px.firings
    );
}

#[test]
fn regress_rcs_chattering_jets_do_not_flood_the_events() {
    // One jet toggling every step for 2400 steps: 1200 pulses of one step each.
    let jet =
        r#"(name: "j0", pos_m: (0.0, 0.0, 0.0), direction: (1.0, 0.0, 0.0), max_thrust_n: 1.0)"#;
    let sim = run(
        &scene(0.01, 100.0, "TestToggle", jet, ", firing_events: true"),
        2400,
    );
    let ev = sim.events();
    let pulses: Vec<_> = ev.iter().filter(|e| e.kind == "jet_pulse").collect();
    let capped: Vec<_> = ev
        .iter()
        .filter(|e| e.kind == "jet_pulse_events_capped")
        .collect();
    assert_eq!(pulses.len() as u64, MAX_PULSE_EVENTS_PER_JET);
    assert_eq!(capped.len(), 1);
    assert_eq!(capped[0].data["scope"], "jet");
    for e in &pulses {
        assert!((e.data["impulse_ns"].as_f64().unwrap() - 0.01).abs() < 1e-15);
    }
    let j = &sim.controllers().slots[0].actuator.jets[0];
    assert_eq!(j.firings, 1200);
    assert!((j.impulse_ns - 1200.0 * 0.01).abs() < 1e-9);
    let v = sim.body("sc").unwrap().vel_m_s.x;
    assert!((v - j.impulse_ns / 100.0).abs() < 1e-5 * v, "{v}");

    // 120 jets toggling together: the run's cap (100 000) is reached before any jet's.
    let mut jets = String::new();
    for k in 0..120 {
        jets.push_str(&format!(
            "(name: \"j{k}\", pos_m: (0.0, 0.0, 0.0), direction: ({}, 0.0, 0.0), max_thrust_n: 1.0),",
            if k % 2 == 0 { 1.0 } else { -1.0 }
        ));
    }
    let sim = run(
        &scene(0.01, 100.0, "TestToggle", &jets, ", firing_events: true"),
        2000,
    );
    let ev = sim.events();
    let n = ev.iter().filter(|e| e.kind == "jet_pulse").count() as u64;
    let capped: Vec<_> = ev
        .iter()
        .filter(|e| e.kind == "jet_pulse_events_capped")
        .collect();
    assert_eq!(n, MAX_PULSE_EVENTS_PER_RUN);
    assert_eq!(capped.len(), 1);
    assert_eq!(capped[0].data["scope"], "run");
    let a = &sim.controllers().slots[0].actuator;
    assert!(a.jets.iter().all(|j| j.firings == 1000));
    // Opposed jets in pairs: no net force.
    assert!(sim.body("sc").unwrap().vel_m_s.norm() < 1e-12);
}

#[test]
fn regress_rcs_pwpf_bad_constants_are_located_errors() {
    register();
    for (opt, field) in [
        ("pwpf: Some((u_on: 5.0))", "pwpf.u_on"),
        ("pwpf: Some((t_m_s: -0.2))", "pwpf.t_m_s"),
        ("pwpf: Some((u_off: 0.5, u_on: 0.45))", "pwpf.u_on"),
    ] {
        let text = scene(0.01, 1.0, "TestBodyForce", PAIR, &format!(", {opt}"));
        let e = match load_scene_str(&text, "rcs_pwpf.ron", &[]) {
            Err(e) => e,
            Ok(l) => match Simulation::new(&l) {
                Err(e) => e,
                Ok(_) => panic!("accepted {opt}"),
            },
        };
        assert!(e.field.ends_with(field), "{opt}: {e}");
        assert!(e.line > 0, "{e}");
    }
}
