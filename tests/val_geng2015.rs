//! Geng, Chen, Liang (2015) in the full testbed (Bevy pipeline, f64 truth, rapier contacts).
//!
//! References, per test:
//! - initial states: Table 1 elements converted to ECI by the closed-form Kepler map of
//!   `orbit::kepler` (the scenes were generated independently, outside the crate);
//! - wiring: an independent f64 inertial integration written here (point-mass gravity on each
//!   body in ECI, Euler's equations, quaternion kinematics, RK4 at the scene's 10 ms step) with
//!   its own controller instance at the 50 ms period and the paper's disturbances; the
//!   simulated port-to-port state must follow it;
//! - claims: the paper's Table 3 statements (M1 vs T1, M2 vs T2, M1 vs M2, chattering), the
//!   ±10 % inertia robustness, contact only between docking parts (the monitor's exact
//!   full-geometry distances and rapier contacts), and eq (10) against the observed convergence.
//!   Thresholds are the claims' own (5×, "better", same order of magnitude = factor 10).
//!
//! Runtime (release): the representative runs (the four laws under the linear and the periodic
//! disturbance, paper model; one full-geometry run; four inertia runs) are made once and shared
//! (≈ 3 s); the end-to-end `reproduce` test runs all 32 scenes and the truth-step variants
//! (≈ 10 s).

use nalgebra::{Matrix3, Quaternion, UnitQuaternion, Vector3};
use rpod::control::geng2015::{
    BodyStateEci, Geng2015Disturbances, Geng2015Law, Geng2015Obs, Geng2015Twisting,
    gravity_gradient_torque_nm, relative_state,
};
use rpod::control::geng2015::{Geng2015Loop, observation};
use rpod::orbit::constants::MU_EARTH_M3_S2;
use rpod::orbit::kepler::ClassicalElements;
use rpod::reproduce::geng2015::{
    CaseResult, INERTIA_WINDOW, accuracy, eq10_bound_s, observed_convergence_s,
    paper_model_overrides, run_case, scene_file, window,
};
use rpod::scene::{load_scene_file, load_scene_str};
use rpod::sim::Simulation;
use std::sync::OnceLock;

fn eci(a_deg: [f64; 3]) -> (Vector3<f64>, Vector3<f64>) {
    ClassicalElements {
        a_m: 7170.0e3,
        e: 0.05,
        i_rad: a_deg[0].to_radians(),
        raan_rad: a_deg[1].to_radians(),
        argp_rad: 10f64.to_radians(),
        true_anomaly_rad: a_deg[2].to_radians(),
    }
    .to_state(MU_EARTH_M3_S2)
}

fn hill_dcm(r: &Vector3<f64>, v: &Vector3<f64>) -> Matrix3<f64> {
    let x = r.normalize();
    let z = r.cross(v).normalize();
    let y = z.cross(&x);
    Matrix3::from_columns(&[x, y, z])
}

#[test]
fn val_geng2015_table1_initial_states() {
    // Every Table 3 scene starts both bodies on their own Table 1 orbits, aligned with their
    // own orbital frames, the target tumbling at [−3, 2, 3] °/s relative to its orbital frame.
    let (rt, vt) = eci([15.0002, 30.0001, 20.0002]);
    let (rs, vs) = eci([15.0, 30.0, 20.0]);
    for law in ["t1", "t2", "m1", "m2"] {
        for form in ["linear", "cosine", "sine", "periodic"] {
            let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
                .join(format!("scenes/papers/geng2015/geng2015_{law}_{form}.ron"));
            let loaded = load_scene_file(&path, &[]).unwrap();
            let sim = Simulation::new(&loaded).unwrap();
            let (r0, v0) = sim.reference_state().unwrap();
            assert!((r0 - rt).norm() < 1e-6 && (v0 - vt).norm() < 1e-9);
            let s = sim.body("chaser").unwrap();
            let t = sim.body("target").unwrap();
            // Scene values are printed to 1e-10 m: position to 1e-6 m, velocity to 1e-8 m/s.
            assert!((r0 + s.pos_m - rs).norm() < 1e-6, "{law} {form}");
            assert!((v0 + s.vel_m_s - vs).norm() < 1e-8, "{law} {form}");
            assert!(t.pos_m.norm() < 1e-9 && t.vel_m_s.norm() < 1e-9);
            let cs = hill_dcm(&rs, &vs);
            let ct = hill_dcm(&rt, &vt);
            let att_s = s.att.to_rotation_matrix().into_inner();
            assert!((att_s - cs).abs().max() < 1e-9);
            assert!((t.att.to_rotation_matrix().into_inner() - ct).abs().max() < 1e-9);
            // Rates: inertial = relative + orbital (h/r² about the orbit normal).
            let nt = rt.cross(&vt).norm() / rt.norm_squared();
            let ns = rs.cross(&vs).norm() / rs.norm_squared();
            let wt_body = t.att.inverse() * t.omega_rad_s;
            let expect_t = Vector3::new(-3.0, 2.0, 3.0).map(f64::to_radians) + Vector3::z() * nt;
            assert!((wt_body - expect_t).norm() < 1e-11);
            let ws_body = s.att.inverse() * s.omega_rad_s;
            assert!((ws_body - Vector3::z() * ns).norm() < 1e-11);
            // The ports start 36.6 m apart.
            let rel = relative_state(
                &sim.law::<Geng2015Loop>(0).unwrap().controller.params,
                &observation(0.0, (r0, v0), &(&s).into(), &(&t).into()),
            );
            assert!(
                (rel.rho_m.norm() - 36.55).abs() < 0.1,
                "{}",
                rel.rho_m.norm()
            );
        }
    }
}

type S13 = nalgebra::SVector<f64, 13>;

fn pack(b: &BodyStateEci) -> S13 {
    let q = b.att_body_to_eci.quaternion();
    let mut y = S13::zeros();
    y.fixed_rows_mut::<3>(0).copy_from(&b.pos_eci_m);
    y.fixed_rows_mut::<3>(3).copy_from(&b.vel_eci_m_s);
    y[6] = q.w;
    y[7] = q.i;
    y[8] = q.j;
    y[9] = q.k;
    y.fixed_rows_mut::<3>(10).copy_from(&b.rate_body_rad_s);
    y
}

fn unpack(y: &S13) -> BodyStateEci {
    BodyStateEci {
        pos_eci_m: y.fixed_rows::<3>(0).into(),
        vel_eci_m_s: y.fixed_rows::<3>(3).into(),
        att_body_to_eci: UnitQuaternion::from_quaternion(Quaternion::new(y[6], y[7], y[8], y[9])),
        rate_body_rad_s: y.fixed_rows::<3>(10).into(),
    }
}

/// RK4 step of one rigid body under point-mass gravity plus a force and torque held constant in
/// ECI over the step (as the testbed holds its wrench over a step).
fn rk4(
    y: &S13,
    h: f64,
    m: f64,
    j: &Matrix3<f64>,
    f_eci: Vector3<f64>,
    tq_eci: Vector3<f64>,
) -> S13 {
    let j_inv = j.try_inverse().unwrap();
    let d = |y: &S13| {
        let r: Vector3<f64> = y.fixed_rows::<3>(0).into();
        let v: Vector3<f64> = y.fixed_rows::<3>(3).into();
        let q = Quaternion::new(y[6], y[7], y[8], y[9]);
        let w: Vector3<f64> = y.fixed_rows::<3>(10).into();
        let acc = -MU_EARTH_M3_S2 / r.norm().powi(3) * r + f_eci / m;
        let tq_b = UnitQuaternion::from_quaternion(q).inverse() * tq_eci;
        let wd = j_inv * (tq_b - w.cross(&(j * w)));
        let qd = q * Quaternion::from_imag(w) * 0.5;
        let mut o = S13::zeros();
        o.fixed_rows_mut::<3>(0).copy_from(&v);
        o.fixed_rows_mut::<3>(3).copy_from(&acc);
        o[6] = qd.w;
        o[7] = qd.i;
        o[8] = qd.j;
        o[9] = qd.k;
        o.fixed_rows_mut::<3>(10).copy_from(&wd);
        o
    };
    let k1 = d(y);
    let k2 = d(&(y + k1 * (h / 2.0)));
    let k3 = d(&(y + k2 * (h / 2.0)));
    let k4 = d(&(y + k3 * h));
    let mut n = y + (k1 + k2 * 2.0 + k3 * 2.0 + k4) * (h / 6.0);
    let qn = n.fixed_rows::<4>(6).norm();
    n.fixed_rows_mut::<4>(6).scale_mut(1.0 / qn);
    n
}

#[test]
fn val_geng2015_wiring_matches_independent_integration() {
    // M1, linear disturbance, first 20 s (the saturated approach and the attitude capture):
    // the testbed's port-to-port state against the in-test inertial integration. A wrong frame
    // or sign in the command (body → world), the disturbances or the ECI observation would
    // show at the metre / degree level; integrator differences (velocity Verlet on differential
    // gravity vs RK4 on full gravity) are ~1e-9 m per step.
    let path = scene_file(Geng2015Law::M1, "linear", None);
    let loaded = load_scene_file(&path, &[]).unwrap();
    let mut sim = Simulation::new(&loaded).unwrap();
    let (r0, v0) = sim.reference_state().unwrap();
    let mut obs = observation(
        0.0,
        (r0, v0),
        &(&sim.body("chaser").unwrap()).into(),
        &(&sim.body("target").unwrap()).into(),
    );
    let params = sim
        .law::<Geng2015Loop>(0)
        .unwrap()
        .controller
        .params
        .clone();
    let n = (MU_EARTH_M3_S2 / 7170.0e3f64.powi(3)).sqrt();
    let dist = Geng2015Disturbances::paper_linear(n);
    let mut ctrl = Geng2015Twisting::new(Geng2015Law::M1, params.clone());
    let (ms, mt) = (240.0, 320.0);
    let (js, jt) = (params.chaser_inertia_kg_m2, params.target_inertia_kg_m2);
    let h = 0.01;
    let (mut ys, mut yt) = (pack(&obs.chaser), pack(&obs.target));
    let (mut f_b, mut tq_b) = (Vector3::zeros(), Vector3::zeros());
    let mut worst = (0.0f64, 0.0f64);
    for k in 0..2000u64 {
        let t = k as f64 * h;
        obs = Geng2015Obs {
            t_s: t,
            chaser: unpack(&ys),
            target: unpack(&yt),
        };
        if k % 5 == 0 {
            (f_b, tq_b) = ctrl.command(&obs);
        }
        let (cs, ct) = (obs.chaser, obs.target);
        let a_s = rpod::control::geng2015::accel_disturbance_m_s2(
            dist.chaser_form,
            &dist.chaser_accel0_m_s2,
            dist.k_d_per_s,
            t,
        );
        let a_t = rpod::control::geng2015::accel_disturbance_m_s2(
            dist.target_form,
            &dist.target_accel0_m_s2,
            dist.k_d_per_s,
            t,
        );
        let td = rpod::control::geng2015::torque_disturbance_nm(dist.torque_scale_nm, n, t);
        let tg_s =
            gravity_gradient_torque_nm(MU_EARTH_M3_S2, &cs.pos_eci_m, &cs.att_body_to_eci, &js);
        let tg_t =
            gravity_gradient_torque_nm(MU_EARTH_M3_S2, &ct.pos_eci_m, &ct.att_body_to_eci, &jt);
        let (qs, qt) = (cs.att_body_to_eci, ct.att_body_to_eci);
        ys = rk4(
            &ys,
            h,
            ms,
            &js,
            qs * (f_b + a_s * ms),
            qs * (tq_b + td + tg_s),
        );
        yt = rk4(&yt, h, mt, &jt, qt * (a_t * mt), qt * (td + tg_t));
        sim.step(1);
        let reference = sim.reference_state().unwrap();
        let sim_obs = observation(
            sim.t_s(),
            reference,
            &(&sim.body("chaser").unwrap()).into(),
            &(&sim.body("target").unwrap()).into(),
        );
        let ref_obs = Geng2015Obs {
            t_s: sim.t_s(),
            chaser: unpack(&ys),
            target: unpack(&yt),
        };
        let a = relative_state(&params, &sim_obs);
        let b = relative_state(&params, &ref_obs);
        worst.0 = worst.0.max((a.rho_m - b.rho_m).norm());
        worst.1 = worst.1.max((a.q_r.inverse() * b.q_r).angle().to_degrees());
    }
    let start = 36.55;
    println!(
        "worst |Δρ| {:.3e} m, worst Δangle {:.3e} deg",
        worst.0, worst.1
    );
    // The ports closed from 36.6 m; the two runs agree to better than 1 mm and 1e-3 deg.
    let end = relative_state(
        &params,
        &observation(
            sim.t_s(),
            sim.reference_state().unwrap(),
            &(&sim.body("chaser").unwrap()).into(),
            &(&sim.body("target").unwrap()).into(),
        ),
    );
    assert!(end.rho_m.norm() < start - 5.0, "the chaser closed in");
    assert!(worst.0 < 1e-3, "ρ differs by {} m", worst.0);
    assert!(worst.1 < 1e-3, "attitude differs by {} deg", worst.1);
}

#[test]
fn invariant_geng2015_scene_errors_are_located() {
    // Bad controller input gives a located SceneError, never a panic.
    let path = scene_file(Geng2015Law::M1, "linear", None);
    let text = std::fs::read_to_string(&path).unwrap();
    for (from, to, field) in [
        ("period_s: 0.05", "period_s: 0.033", "period_s"),
        (
            "chaser_port: \"dock\"",
            "chaser_port: \"nope\"",
            "chaser_port",
        ),
        ("target: \"target\",\n", "target: \"chaser\",\n", "target"),
    ] {
        let bad = text.replacen(from, to, 1);
        assert_ne!(bad, text, "{from}");
        let loaded = load_scene_str(&bad, "bad.ron", &[]).unwrap();
        let Err(e) = Simulation::new(&loaded) else {
            panic!("{field}: accepted");
        };
        assert!(e.line > 0, "{field}: not located: {e}");
        assert!(e.to_string().contains(field), "{e}");
    }
}

// ---------------------------------------------------------------------------------------------
// Claims (Table 3, §3.3, geometry, eq 10) on representative runs, made once and shared.
// ---------------------------------------------------------------------------------------------

use Geng2015Law::{M1, M2, T1, T2};

/// Paper-model runs (5 cm spheres instead of the geometry) of the four laws under the linear
/// and the periodic disturbance, each to the end of its accuracy window.
fn paper_runs() -> &'static Vec<((Geng2015Law, bool), CaseResult)> {
    static RUNS: OnceLock<Vec<((Geng2015Law, bool), CaseResult)>> = OnceLock::new();
    RUNS.get_or_init(|| {
        let pm = paper_model_overrides();
        let mut v = vec![];
        for linear in [true, false] {
            for law in [T1, M1, T2, M2] {
                let form = if linear { "linear" } else { "periodic" };
                let r = run_case(&scene_file(law, form, None), &pm, None, window(law)).unwrap();
                v.push(((law, linear), r));
            }
        }
        v
    })
}

fn run(law: Geng2015Law, linear: bool) -> &'static CaseResult {
    &paper_runs()
        .iter()
        .find(|((l, lin), _)| *l == law && *lin == linear)
        .unwrap()
        .1
}

#[test]
fn val_geng2015_m1_vs_t1_position() {
    // Claim: M1 position accuracy ≥ 5× better than T1 on every axis (paper ≈ 10×). Also the
    // rotation columns of T1 and M1 against the paper's Table 3 (the rotation loop does not see
    // a_d, so both cases share them): within 35 % (measured 0–31 %).
    let paper_rot_t1 = [1.041e-3, 0.480e-3, 0.458e-3, 3.029e-2, 1.328e-2, 1.329e-2];
    let paper_rot_m1 = [3.621e-5, 4.892e-5, 3.537e-5, 6.829e-4, 13.720e-4, 9.098e-4];
    for linear in [true, false] {
        let (t1, m1) = (run(T1, linear), run(M1, linear));
        for i in 0..3 {
            let r = t1.accuracy[i] / m1.accuracy[i];
            println!("linear={linear} T1/M1 ρ[{i}] = {r:.1}");
            assert!(r >= 5.0, "T1/M1 position ratio {r} on axis {i}");
        }
        for i in 0..6 {
            for (acc, paper) in [
                (t1.accuracy[6 + i], paper_rot_t1[i]),
                (m1.accuracy[6 + i], paper_rot_m1[i]),
            ] {
                assert!(
                    (acc / paper - 1.0).abs() < 0.35,
                    "rot[{i}] {acc} vs paper {paper}"
                );
            }
        }
    }
}

#[test]
fn val_geng2015_chaser_body_frame_series() {
    // The paper's translational figures are in the chaser body frame F_bs. The series in F_bs
    // against two independent readings of the recorded Hill series: a rotation keeps the
    // length (|ρ_bs| = |ρ_Hill| at every sample), and the rate seen in F_bs is the time
    // derivative of ρ_bs's components (central differences over the 50 ms samples; the
    // truncation ρ⃛·dt²/6 with |ρ⃛| ≲ ω_t³|ρ| + … is below 1e-4 of |ρ̇| here).
    for law in [T2, M2] {
        let r = run(law, true);
        let s = &r.series;
        for k in 0..s.t.len() {
            let (h, b) = (s.trans[k], s.trans_bs[k]);
            let (nh, nb) = (h.fixed_rows::<3>(0).norm(), b.fixed_rows::<3>(0).norm());
            assert!((nh - nb).abs() <= 1e-12 * nh.max(1e-9), "{law:?} k {k}");
        }
        let mut worst: f64 = 0.0;
        let mut scale: f64 = 0.0;
        for k in 1..s.t.len() - 1 {
            let dt = s.t[k + 1] - s.t[k - 1];
            let fd =
                (s.trans_bs[k + 1].fixed_rows::<3>(0) - s.trans_bs[k - 1].fixed_rows::<3>(0)) / dt;
            worst = worst.max((fd - s.trans_bs[k].fixed_rows::<3>(3)).norm());
            scale = scale.max(s.trans_bs[k].fixed_rows::<3>(3).norm());
        }
        println!(
            "{law:?}: rate in F_bs vs central difference: worst {worst:.3e} m/s (peak {scale:.3e})"
        );
        assert!(worst < 2e-3 * scale, "{worst} vs {scale}");
    }
}

#[test]
fn val_geng2015_m2_vs_t2() {
    // Claim "M2 better than T2 in every column", read in F_bs (the paper's frame): M2 wins
    // every position and velocity column with the linear a_d and 11 of 12 with the periodic
    // one, where the normal position ties (T2/M2 = 0.98): claims.json records held = false.
    // In the target Hill frame (the sensitivity) it fails on x and z position (ratio ≈ 1.0
    // with the linear a_d, 0.44–0.49 with the periodic one). Every rotation channel: M2 wins.
    for linear in [true, false] {
        let (t2, m2) = (run(T2, linear), run(M2, linear));
        let r: Vec<f64> = (0..6)
            .map(|i| t2.accuracy_bs[i] / m2.accuracy_bs[i])
            .collect();
        let rh: Vec<f64> = (0..6).map(|i| t2.accuracy[i] / m2.accuracy[i]).collect();
        println!("linear={linear} T2/M2 [ρ; V] F_bs {r:.2?}, Hill {rh:.2?}");
        for i in 9..12 {
            assert!(m2.accuracy[i] < t2.accuracy[i], "ω_r[{}]", i - 9);
        }
        if linear {
            assert!(r.iter().all(|x| *x > 1.0), "{r:?}");
        } else {
            assert!(r.iter().filter(|x| **x > 1.0).count() == 5, "{r:?}");
            assert!(r[2] < 1.0 && r[2] > 0.9, "{r:?}");
            // Hill reading: T2 beats M2 on radial and normal position.
            assert!(rh[0] < 1.0 && rh[2] < 1.0, "{rh:?}");
        }
    }
}

#[test]
fn val_geng2015_m1_vs_m2() {
    // Claim (Table 3, §2.3): M1 better than M2 on position, M2 better than M1 on velocity,
    // every axis, both cases.
    for linear in [true, false] {
        let (m1, m2) = (run(M1, linear), run(M2, linear));
        for i in 0..3 {
            assert!(m1.accuracy[i] < m2.accuracy[i], "position {i}");
            assert!(m2.accuracy[3 + i] < m1.accuracy[3 + i], "velocity {i}");
        }
    }
}

#[test]
fn val_geng2015_chattering() {
    // Claim: M "far superior" in eliminating chattering (the 5× threshold is ours). Total
    // variation of the applied command per second over the accuracy window: M1 ≥ 5× below T1
    // on every channel; M2 ≥ 5× below T2 on the torques but only 1.2–4.5× on the forces
    // (claims.json: held = false for "every channel"); below T2 on every channel (the
    // sensitivity reading "any reduction": held).
    for linear in [true, false] {
        let (t1, m1, t2, m2) = (
            run(T1, linear),
            run(M1, linear),
            run(T2, linear),
            run(M2, linear),
        );
        for i in 0..6 {
            assert!(m1.tv_per_s[i] * 5.0 <= t1.tv_per_s[i], "TV M1 vs T1 [{i}]");
            assert!(m2.tv_per_s[i] < t2.tv_per_s[i], "TV M2 vs T2 [{i}]");
            if i >= 3 {
                assert!(m2.tv_per_s[i] * 5.0 <= t2.tv_per_s[i], "TV M2 vs T2 [{i}]");
            }
        }
        // Sign changes are not a claim: at the 50 ms control period a channel changes sign at
        // most 20 times per second (the closed-form cap of `invariant_geng2015_metrics_closed_form`).
        for r in [t1, m1, t2, m2] {
            assert!(r.sign_changes_per_s.iter().all(|x| *x <= 20.0 + 1e-9));
        }
    }
}

#[test]
fn val_geng2015_inertia_order_of_magnitude() {
    // Claim (§3.3, Tables 4–7): with J_s, J_t perturbed by ±10 % (model nominal) the M1/M2
    // accuracies over 70–100 s keep their order of magnitude: within a factor 10 of the
    // nominal run's accuracy over the same window, every column (measured 0.34–5.8).
    let pm = paper_model_overrides();
    for law in [M1, M2] {
        let nominal = run(law, true);
        for tag in ["jsp10_jtp10", "jsm10_jtm10"] {
            let r = run_case(
                &scene_file(law, "linear", Some(tag)),
                &pm,
                None,
                INERTIA_WINDOW,
            )
            .unwrap();
            for i in 0..12 {
                let x: Vec<f64> = nominal
                    .series
                    .trans
                    .iter()
                    .chain(&nominal.series.rot)
                    .map(|v| v[i % 6])
                    .collect();
                let n = nominal.series.t.len();
                let x = if i < 6 { &x[..n] } else { &x[n..] };
                let nom = accuracy(&nominal.series.t, x, INERTIA_WINDOW.0, INERTIA_WINDOW.1);
                let q = r.accuracy[i] / nom;
                assert!(q > 0.1 && q < 10.0, "{law:?} {tag} column {i}: ratio {q}");
            }
        }
    }
}

#[test]
fn val_geng2015_full_geometry_collides_before_the_ports_meet() {
    // Claim "the ports meet with contact only between docking parts": refuted. Flying the
    // scene's full geometry (buses, wings, cone, slot), M1 approaches from 36.6 m along the
    // Hill frame while the target tumbles at 4.7 °/s, and the buses touch at 28.5 s with the
    // ports still 1.1 m apart (a collision: neither part is a docking part). The paper-model run
    // of the same scene docks to < 1 mm with the spheres never touching.
    let full = run_case(&scene_file(M1, "linear", None), &[], None, window(M1)).unwrap();
    assert!(!full.collisions.is_empty());
    let (t_c, a, b) = &full.collisions[0];
    assert!(
        !a.contains("cone") && !a.contains("slot") && !b.contains("cone") && !b.contains("slot")
    );
    let (d, _, _, t_d) = full.closest.clone().unwrap();
    assert!(
        d <= 1e-3 && *t_c <= t_d + 0.02,
        "closest {d} at {t_d}, collision at {t_c}"
    );
    let before: f64 = full
        .series
        .t
        .iter()
        .zip(&full.series.port_distance_m)
        .filter(|(t, _)| **t < *t_c)
        .map(|(_, d)| *d)
        .fold(f64::INFINITY, f64::min);
    assert!(before > 0.5, "ports {before} m apart at first contact");
    for linear in [true, false] {
        for law in [T1, M1, T2, M2] {
            let r = run(law, linear);
            assert!(r.collisions.is_empty() && r.first_contact_s.is_none());
            assert!(*r.series.port_distance_m.last().unwrap() < 1e-3, "{law:?}");
            // Spheres of 5 cm: the centres stay > 0.1 m apart (monitor's exact distance).
            assert!(r.min_clearance_non_docking_m > 0.0);
            assert!(r.closest.as_ref().unwrap().0 > 0.0);
        }
    }
}

#[test]
fn val_geng2015_seated_pair_touches_only_docking_parts() {
    // Geometry: seated (ports coincident, q_r = 1) the chaser's bus face, where the
    // cone stands, must clear the slot rim axially. Cone 0.20 m long on the bus face at
    // x = −0.55 m; slot 0.18 m deep from P_t = 0.50 m: the face is 0.20 − 0.18 = 0.02 m
    // outside the rim plane. Placed 1 cm short of seated (so the cone tip does not rest on the
    // back plate), the smallest clearance between parts that are not both docking parts is the
    // bus face to the rim, 0.02 + 0.01 = 0.03 m (closed form; facets move it by < 1 mm).
    let loaded = load_scene_file(
        &scene_file(M2, "linear", None),
        &[
            "bodies.chaser.initial.pos_m=(1.26, 0.0, 0.0)".into(),
            "bodies.chaser.initial.vel_m_s=(0.0, 0.0, 0.0)".into(),
            "bodies.chaser.initial.attitude=Quat(w: 1.0, x: 0.0, y: 0.0, z: 0.0)".into(),
            "bodies.chaser.initial.rate_body_deg_s=(0.0, 0.0, 0.0)".into(),
            "bodies.target.initial.rate_body_deg_s=(0.0, 0.0, 0.0)".into(),
        ],
    )
    .unwrap();
    let mut sim = Simulation::new(&loaded).unwrap();
    sim.step(1);
    let mon = sim.monitor();
    let clear = mon
        .min_clearance_per_pair
        .iter()
        .copied()
        .fold(f64::INFINITY, f64::min);
    println!("seated − 1 cm: smallest non-docking clearance {clear:.4} m");
    assert!((clear - 0.03).abs() < 1e-3, "{clear}");
    assert!(sim.contacts().collisions.is_empty());
}

#[test]
fn val_geng2015_eq10_bound_vs_observed() {
    // Eq (10) per channel (premises: α − β − D > 0, β > D; D from the disturbance bounds),
    // against the observed convergence time (last exit of |s_i| from 10× its window accuracy).
    // M1 translation with the linear a_d: premises fail (D grows with t), consistent with the
    // twisting-condition finding of the law's tests. Where the bound exists it holds, but it is
    // 3–10 orders of magnitude above the observed 15–50 s: uninformative.
    for linear in [true, false] {
        for law in [M1, M2] {
            let r = run(law, linear);
            for i in 0..6 {
                let s: Vec<f64> = r.series.s.iter().map(|v| v[i]).collect();
                let band = 10.0 * accuracy(&r.series.t[..s.len()], &s, r.window_s.0, r.window_s.1);
                let obs = observed_convergence_s(&r.series, i, band);
                assert!(
                    obs > 1.0 && obs < r.window_s.0,
                    "{law:?} ch{i} converged at {obs}"
                );
                match eq10_bound_s(r, i) {
                    Some(b) => assert!(b >= obs * 100.0, "{law:?} ch{i}: {b} vs {obs}"),
                    None => assert!(law == M1 && linear && i < 3, "{law:?} ch{i} premises"),
                }
            }
        }
    }
}

#[test]
fn regress_geng2015_deterministic() {
    // Same scene, same outputs: two 10 s runs give bit-identical series.
    let pm = paper_model_overrides();
    let a = run_case(
        &scene_file(T2, "periodic", None),
        &pm,
        Some(10.0),
        (5.0, 10.0),
    )
    .unwrap();
    let b = run_case(
        &scene_file(T2, "periodic", None),
        &pm,
        Some(10.0),
        (5.0, 10.0),
    )
    .unwrap();
    assert_eq!(a.series.trans, b.series.trans);
    assert_eq!(a.series.u, b.series.u);
}

#[test]
fn invariant_geng2015_metrics_closed_form() {
    // The report's metrics on series with closed-form answers: |mean| + 3σ of a constant c is
    // |c|; of a ±a square wave (mean 0, σ = a) it is 3a; a command alternating ±1 every 50 ms
    // changes sign 20 times per second with total variation 40 per second.
    let t: Vec<f64> = (0..=200).map(|k| k as f64 * 0.05).collect();
    let c = vec![-2.5; t.len()];
    assert!((accuracy(&t, &c, 0.0, 10.0) - 2.5).abs() < 1e-12);
    let sq: Vec<f64> = (0..t.len())
        .map(|k| if k % 2 == 0 { 0.3 } else { -0.3 })
        .collect();
    // 201 samples: mean 0.3/201, σ ≈ 0.3.
    let a = accuracy(&t[..200], &sq[..200], 0.0, 10.0);
    assert!((a - 0.9).abs() < 1e-9, "{a}");
    let u: Vec<nalgebra::Vector6<f64>> = sq
        .iter()
        .map(|x| nalgebra::Vector6::repeat(x / 0.3))
        .collect();
    let (sc, tv) = rpod::reproduce::geng2015::chattering(&t, &u, 0.0, 10.0);
    for i in 0..6 {
        assert!((sc[i] - 20.0).abs() < 1e-9 && (tv[i] - 40.0).abs() < 1e-9);
    }
}

#[test]
fn val_geng2015_inertia_scenes() {
    // The 16 ±10 % inertia scenes: the bodies carry J·(1 ± 0.1) (paper J_s, J_t), the
    // controller's model keeps the nominal J_s, J_t; everything else equals the nominal scene.
    let js = Vector3::new(45.6, 47.3, 46.9);
    let jt = Vector3::new(67.6, 57.6, 57.6);
    for law in [M1, M2] {
        for form in ["linear", "periodic"] {
            for (tag, ks, kt) in [
                ("jsp10_jtp10", 1.1, 1.1),
                ("jsp10_jtm10", 1.1, 0.9),
                ("jsm10_jtp10", 0.9, 1.1),
                ("jsm10_jtm10", 0.9, 0.9),
            ] {
                let loaded = load_scene_file(&scene_file(law, form, Some(tag)), &[]).unwrap();
                let sim = Simulation::new(&loaded).unwrap();
                let b = &loaded.scene.bodies;
                let (tb, cb) = (&b[0], &b[1]);
                assert_eq!((tb.name.as_str(), cb.name.as_str()), ("target", "chaser"));
                let d = |m: Matrix3<f64>| Vector3::new(m[(0, 0)], m[(1, 1)], m[(2, 2)]);
                assert!(
                    (d(cb.inertia_kg_m2.matrix()) - js * ks).norm() < 1e-9,
                    "{tag}"
                );
                assert!(
                    (d(tb.inertia_kg_m2.matrix()) - jt * kt).norm() < 1e-9,
                    "{tag}"
                );
                let p = &sim.law::<Geng2015Loop>(0).unwrap().controller.params;
                assert_eq!(d(p.chaser_inertia_kg_m2), js);
                assert_eq!(d(p.target_inertia_kg_m2), jt);
                let nominal = load_scene_file(&scene_file(law, form, None), &[]).unwrap();
                let n0 = &nominal.scene.bodies[1].initial;
                assert_eq!(cb.initial.pos_m, n0.pos_m);
                assert_eq!(cb.initial.vel_m_s, n0.vel_m_s);
            }
        }
    }
}

#[test]
fn val_geng2015_reproduce_report_and_claims() {
    // `rpod reproduce geng2015` end to end (all 32 scenes plus the 50 ms truth-step runs,
    // ≈ 10 s in release): REPORT.md, the figures and claims.json exist; claims.json follows the
    // contract (array of {id, claim, kind, paper, threshold_source, measured, held,
    // sensitivity}) and its verdicts agree with what
    // the tests above measure on the representative runs.
    let dir = std::env::temp_dir().join(format!("rpod_geng2015_{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    rpod::reproduce::run("geng2015", &dir).unwrap();
    let report = std::fs::read_to_string(dir.join("REPORT.md")).unwrap();
    assert!(report.contains("## Table 3") && report.contains("Tables 4–7"));
    for law in ["t1", "m1", "t2", "m2"] {
        assert!(dir.join(format!("geng2015_{law}_linear.png")).exists());
        assert!(
            dir.join(format!("geng2015_{law}_linear_full_geometry.png"))
                .exists()
        );
    }
    let claims: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("claims.json")).unwrap()).unwrap();
    let arr = claims.as_array().unwrap();
    let held = |id: &str| {
        let c = arr
            .iter()
            .find(|c| c["id"] == id)
            .unwrap_or_else(|| panic!("{id}"));
        for k in ["claim", "paper", "measured"] {
            assert!(c.get(k).is_some(), "{id}.{k}");
        }
        c["held"].as_bool().unwrap()
    };
    assert!(held("m1_vs_t1_position"));
    assert!(!held("m2_vs_t2"));
    assert!(held("m1_m2_position_velocity"));
    assert!(held("t1_m1_match_table3"));
    assert!(!held("t2_m2_match_table3"));
    assert!(!held("chattering_total_variation"));
    assert!(held("inertia_robustness"));
    assert!(!held("ports_meet_no_collision"));
    assert!(held("eq10_bound"));
    assert_eq!(arr.len(), 9);
    for c in arr {
        let src = c["threshold_source"].as_str().unwrap();
        assert!(
            src.starts_with("paper: ") || src.starts_with("ours: "),
            "{c}"
        );
    }
    let kind = |id: &str| arr.iter().find(|c| c["id"] == id).unwrap()["kind"].clone();
    assert_eq!(kind("ports_meet_no_collision"), "beyond the paper");
    assert_eq!(kind("m2_vs_t2"), "paper");
    assert!(report.contains("How far the testbed's Table 3 is from the printed one"));
    assert!(report.contains("at most 20"));
    let _ = std::fs::remove_dir_all(&dir);
}
