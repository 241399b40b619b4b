//! Docking loads converge with the step (compliant cone–slot contact).
//!
//! - `docking_aligned`'s peak contact force at dt = 2, 1 and 0.5 ms agrees within 10 % (the
//!   issue's criterion; rigid contact spreads over 2.3× there), and agrees within 2 % with the
//!   peak of an independent 1-D f64 integration of the same law, face on face (RK4 at 1 µs,
//!   written here): it is the mechanism's load, not the step's.
//! - The capture envelope (`scenes/trials/capture_envelope.ron`, 35 trials) gives the same
//!   outcome in every trial at dt = 10, 5 and 2 ms (seven representative trials in CI, the
//!   whole grid as an ignored test).

use rpod::contact::{ContactModelSpec, Law};
use rpod::scene::load_scene_file;
use rpod::sim::Simulation;
use rpod::sim::docking::Docking;

/// Peak axial load (N) of docking_aligned at `dt` s, and what it latched.
fn aligned_peak(dt: f64, rigid: bool) -> (f64, f64, bool) {
    let mut set = vec![format!("dt_s={dt}")];
    if rigid {
        set.push("docking.contact=Rigid".into());
    }
    let loaded = load_scene_file("scenes/examples/docking_aligned.ron".as_ref(), &set).unwrap();
    let mut s = Simulation::new(&loaded).unwrap();
    s.step(s.steps_for(26.0));
    let d = s.app.world().resource::<Docking>();
    (
        d.loads.peak_axial_load_n,
        d.loads.impulse_ns,
        d.t_latch_s.is_some(),
    )
}

/// Peak contact force of the aligned impact from a 1-D integration: the reduced system
/// (k_m = 1/300 + 1/800 per newton) arriving on the back plate at the speed the magnet gives it
/// (RK4 at 1 µs from the start), the law F = k·δ^{3/2}(1 + λ·δ̇) face on face, the magnet on.
fn reference_peak() -> f64 {
    let loaded = load_scene_file("scenes/examples/docking_aligned.ron".as_ref(), &[]).unwrap();
    let spec = loaded.scene.docking.clone().unwrap();
    let ContactModelSpec::Compliant(c) = &spec.contact else {
        panic!("compliant")
    };
    let law = Law::from_spec(c);
    let m = &spec.magnet;
    let km = 1.0 / 300.0 + 1.0 / 800.0;
    let (mut x, mut v, h) = (0.5f64, -0.02f64, 1e-6);
    let (mut on, mut v0, mut peak) = (false, f64::NAN, 0.0f64);
    let acc = |x: f64, v: f64, on: bool, v0: f64| {
        let mag = if on {
            (m.f0_n / (1.0 + x.abs() / m.g0_m).powi(2)).min(m.max_force_n)
        } else {
            0.0
        };
        let f = if x < 0.0 {
            law.normal_force_n(-x, -v, v0)
        } else {
            0.0
        };
        (km * (f - mag), f)
    };
    for _ in 0..30_000_000u64 {
        if !on && x.abs() < m.activation_distance_m {
            on = true;
        }
        if x < 0.0 && v0.is_nan() {
            v0 = -v;
        }
        if !v0.is_nan() && x >= 0.0 && v > 0.0 {
            break;
        }
        let (k1v, f) = acc(x, v, on, v0);
        peak = peak.max(f);
        let k1x = v;
        let (k2v, _) = acc(x + k1x * h / 2.0, v + k1v * h / 2.0, on, v0);
        let k2x = v + k1v * h / 2.0;
        let (k3v, _) = acc(x + k2x * h / 2.0, v + k2v * h / 2.0, on, v0);
        let k3x = v + k2v * h / 2.0;
        let (k4v, _) = acc(x + k3x * h, v + k3v * h, on, v0);
        let k4x = v + k3v * h;
        x += (k1x + 2.0 * k2x + 2.0 * k3x + k4x) * h / 6.0;
        v += (k1v + 2.0 * k2v + 2.0 * k3v + k4v) * h / 6.0;
    }
    peak
}

#[test]
fn val_docking_peak_force_converges_with_dt() {
    let reference = reference_peak();
    let mut peaks = Vec::new();
    for dt in [0.002, 0.001, 0.0005] {
        let (p, j, latched) = aligned_peak(dt, false);
        let (pr, jr, _) = aligned_peak(dt, true);
        println!(
            "dt {dt} s: compliant peak {p:.1} N (impulse {j:.3} N·s, latched {latched}); rigid peak {pr:.1} N (impulse {jr:.3} N·s)"
        );
        assert!(latched, "dt {dt}: no latch");
        peaks.push(p);
    }
    let (lo, hi) = peaks
        .iter()
        .fold((f64::INFINITY, 0.0f64), |(l, h), p| (l.min(*p), h.max(*p)));
    println!(
        "compliant spread {:.3} %, 1-D reference {reference:.1} N",
        (hi / lo - 1.0) * 100.0
    );
    assert!(
        hi / lo - 1.0 < 0.10,
        "peaks {peaks:?} spread over {}",
        hi / lo
    );
    for p in &peaks {
        assert!(
            (p / reference - 1.0).abs() < 0.02,
            "peak {p} N vs the 1-D reference {reference} N"
        );
    }
}

/// The envelope's outcomes at three steps for the trials `which` (all when `None`). A trial whose
/// run ends with the cone still in the funnel would be judged on a transient state; the bundled
/// mechanism resolves every trial within the 50 s (checked: no CONTACT, SOFT_CAPTURE or
/// ATTRACTING at the end).
fn envelope_outcomes_at_three_dts(which: Option<&[usize]>) {
    let dir = std::env::temp_dir().join(format!(
        "rpod_envelope_dt_{}_{}",
        std::process::id(),
        which.map_or(0, |w| w.len())
    ));
    std::fs::create_dir_all(&dir).unwrap();
    let base = std::fs::read_to_string("scenes/examples/docking_aligned.ron").unwrap();
    let trials = std::fs::read_to_string("scenes/trials/capture_envelope.ron").unwrap();
    let all: Vec<usize> = (0..rpod::trials::load("scenes/trials/capture_envelope.ron".as_ref())
        .unwrap()
        .spec
        .count)
        .collect();
    let which = which.unwrap_or(&all);
    let mut outcomes: Vec<Vec<String>> = Vec::new();
    for dt in [0.01, 0.005, 0.002] {
        assert!(base.contains("dt_s: 0.01,"));
        let scene = dir.join(format!("aligned_{dt}.ron"));
        std::fs::write(&scene, base.replace("dt_s: 0.01,", &format!("dt_s: {dt},"))).unwrap();
        let tf = dir.join(format!("envelope_{dt}.ron"));
        assert!(trials.contains("scene: \"../examples/docking_aligned.ron\""));
        std::fs::write(
            &tf,
            trials.replace(
                "scene: \"../examples/docking_aligned.ron\"",
                &format!("scene: \"aligned_{dt}.ron\""),
            ),
        )
        .unwrap();
        let c = rpod::trials::load(&tf).unwrap();
        let next = std::sync::atomic::AtomicUsize::new(0);
        let results = std::sync::Mutex::new(vec![String::new(); which.len()]);
        std::thread::scope(|s| {
            for _ in 0..2 {
                s.spawn(|| {
                    loop {
                        let i = next.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                        if i >= which.len() {
                            break;
                        }
                        let r = rpod::trials::run_trial(&c, which[i], None);
                        results.lock().unwrap()[i] = r.outcome;
                    }
                });
            }
        });
        let r = results.into_inner().unwrap();
        println!("dt {dt} s: {r:?}");
        for (i, o) in r.iter().enumerate() {
            assert!(
                !matches!(
                    o.as_str(),
                    "CONTACT" | "SOFT_CAPTURE" | "ATTRACTING" | "INVALID" | "NUMERIC_FAILURE"
                ),
                "dt {dt}: trial {} ends unresolved ({o})",
                which[i]
            );
        }
        outcomes.push(r);
    }
    let _ = std::fs::remove_dir_all(&dir);
    for i in 0..outcomes[0].len() {
        assert!(
            outcomes.iter().all(|o| o[i] == outcomes[0][i]),
            "trial {}: {:?}",
            which[i],
            outcomes.iter().map(|o| &o[i]).collect::<Vec<_>>()
        );
    }
}

/// Seven of the 35 trials (every row and every column of the 7 × 5 grid at least once, both
/// captured and missed outcomes), so the test's cost stays inside CI's budget: the whole grid at
/// the three steps takes about 12 minutes on the two-core CI machine. The whole grid is
/// `val_capture_envelope_all_trials_do_not_change_with_dt` (run with `--ignored`).
#[test]
fn val_capture_envelope_outcomes_do_not_change_with_dt() {
    envelope_outcomes_at_three_dts(Some(&[0, 6, 12, 18, 24, 25, 32]));
}

/// The whole envelope (35 trials) at the three steps; about 12 minutes on two cores, so not in
/// CI (`cargo test --release --test val_docking_convergence -- --ignored`). Last run: all 35
/// outcomes the same at dt = 10, 5 and 2 ms.
#[test]
#[ignore = "about 12 minutes; the CI test runs seven representative trials"]
fn val_capture_envelope_all_trials_do_not_change_with_dt() {
    envelope_outcomes_at_three_dts(None);
}
