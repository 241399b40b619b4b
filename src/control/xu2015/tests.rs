//! References: linear error dynamics of the normalised-gradient identifier, the closed
//! form of the golden-section error recursion, and a closed-loop f64 simulation of the
//! paper's scenario on the relative dynamics of [`crate::orbit::elliptic`].
use super::*;
use crate::orbit::elliptic::{EllipticOrbit, RelStateTof, rk4_step_relative};
use nalgebra::Matrix3;

/// Deterministic multi-sine excitation, N.
fn excitation_n(k: usize) -> f64 {
    let k = k as f64;
    3000.0 * (0.7 * k).sin() + 2000.0 * (2.3 * k + 1.0).sin() + 1500.0 * (0.23 * k).sin()
}

/// Identification on a known, stable second-order plant
/// y(k+1) = α1 y(k) + α2 y(k−1) + γ β0 u(k) (noise-free, truth strictly inside the box).
/// Reference: on steps where the projection is inactive the parameter error obeys the
/// linear recursion θ̃(k) = (I − λ1 φ̄φ̄ᵀ) θ̃(k−1), φ̄ = φ/√(λ2 + φᵀφ); so from the last
/// step j where the projection acted, ‖θ̃(N)‖ ≤ ‖Π_{k>j} (I − λ1 φ̄φ̄ᵀ)‖₂ ‖θ̃(j)‖ — a
/// tolerance computed from the excitation alone. Also the Lyapunov property: ‖θ̃‖ never
/// increases (0 < λ1 < 2 and the truth is in the convex box, so Π is non-expansive).
#[test]
fn val_xu2015_identification_known_plant() {
    let p = AccmParams::paper();
    let b0 = p.beta0();
    let truth = Vector3::new(1.7, -0.75, 1.08);
    let mut id = Identifier::new(&p);
    let n = 2000;
    let mut y = vec![0.0f64, 0.0];
    let mut u = Vec::new();
    for k in 0..n + 2 {
        u.push(excitation_n(k));
        let yk = y[k + 1];
        let ykm1 = y[k];
        y.push(truth[0] * yk + truth[1] * ykm1 + truth[2] * b0 * u[k]);
    }
    // y[j+1] is the plant output at sample j (y[0] = y(−1) = 0).
    let mut prod = Matrix3::<f64>::identity();
    let mut err_prev = (id.theta - truth).norm();
    let mut err_at_last_clip = err_prev;
    let mut last_clip = None;
    for k in 2..n + 2 {
        let phi = Vector3::new(y[k], y[k - 1], b0 * u[k - 1]);
        id.update(&phi, y[k + 1]);
        let err = (id.theta - truth).norm();
        assert!(err <= err_prev * (1.0 + 1e-12) + 1e-15, "‖θ̃‖ grew at k={k}");
        err_prev = err;
        let clipped = (0..3).any(|i| id.theta[i] == id.lower[i] || id.theta[i] == id.upper[i]);
        if clipped {
            prod = Matrix3::identity();
            err_at_last_clip = err;
            last_clip = Some(k);
        } else {
            let pb = phi / (p.lambda2_m2 + phi.norm_squared()).sqrt();
            prod = (Matrix3::identity() - pb * pb.transpose() * p.lambda1) * prod;
        }
    }
    assert!(
        last_clip.is_none_or(|k| k < 100),
        "projection still active late: {last_clip:?}"
    );
    let contraction = prod.singular_values().max();
    let tol = contraction * err_at_last_clip + 1e-12;
    assert!(
        contraction < 1e-6,
        "excitation not persistent: {contraction}"
    );
    for i in 0..3 {
        assert!(
            (id.theta[i] - truth[i]).abs() <= tol,
            "θ[{i}] = {} vs {} (tol {tol})",
            id.theta[i],
            truth[i]
        );
    }
}

/// Nominal characteristic model ξ(k+1) = 2ξ(k) − ξ(k−1) + β0 u(k) under ACCM (identifier
/// starting at the truth, thrust unlimited so the loop is linear). Reference: with
/// ρ = β/(β + λ) the tracking error obeys exactly
/// e(k+1) = (2 − 2ρ l1) e(k) − (1 − ρ l2) e(k−1) − (1 − ρ) Δ²ξ_r(k+1),
/// stable iff both roots of z² − (2 − 2ρ l1) z + (1 − ρ l2) lie in the unit disc (for
/// λ = 0, a double root at 0.618). The closed loop must follow that recursion through
/// the whole quintic, including the entry into Ω (shift d), and end on the goal.
#[test]
fn val_xu2015_golden_section_nominal_closed_loop() {
    for lambda_rel in [0.0, AccmParams::paper().lambda_ctrl_rel] {
        let mut p = AccmParams::paper();
        p.lambda_ctrl_rel = lambda_rel;
        p.thrust_max_n = 1e12;
        let h = p.sample_period_s;
        let b0 = p.beta0();
        let rho = 1.0 / (1.0 + lambda_rel);
        let (a, b) = (2.0 - 2.0 * rho * p.l1, -(1.0 - rho * p.l2));
        // Roots of z² − a z − b: spectral radius < 1.
        let disc = a * a + 4.0 * b;
        let radius = if disc >= 0.0 {
            ((a.abs() + disc.sqrt()) / 2.0).abs()
        } else {
            (-b).sqrt()
        };
        assert!(radius < 1.0, "closed-loop spectral radius {radius}");
        if lambda_rel == 0.0 {
            // Double root at z = 0.618: a = 2·0.618, b = −0.618² (to the 3-digit l1, l2).
            assert!((a - 1.236).abs() < 1e-12 && (b + 0.382).abs() < 1e-12);
            assert!((radius - 0.618).abs() < 0.01, "radius {radius}");
        }
        let mut c = Accm::new(p.clone());
        // Plant starts displaced from rest: ξ(0) = [−20, 0.3, 5], velocity 1e−3 m/s.
        let x0 = Vector3::new(-20.0, 0.3, 5.0);
        let mut xi_prev = x0 - Vector3::repeat(1e-3 * h);
        let mut xi = x0;
        let n = 3000;
        let mut e_hist: Vec<Vector3<f64>> = Vec::new();
        let mut xr_hist: Vec<Vector3<f64>> = Vec::new();
        for k in 0..=n {
            let t = k as f64 * h;
            let u = c
                .update(&Xu2015Observation {
                    t_s: t,
                    pos_tof_m: xi,
                })
                .force_tof_n;
            let xr = c.reference_tof_m(t).unwrap();
            e_hist.push(xi - xr);
            xr_hist.push(xr);
            let next = xi * 2.0 - xi_prev + u * b0;
            xi_prev = xi;
            xi = next;
        }
        xr_hist.push(c.reference_tof_m((n + 1) as f64 * h).unwrap());
        // Independent recursion from e(1), e(2) onward (k = 0 uses the at-rest history).
        let mut ec = [e_hist[1], e_hist[2]];
        let mut max_dev: f64 = 0.0;
        for k in 2..n {
            let d2 = xr_hist[k + 1] - xr_hist[k] * 2.0 + xr_hist[k - 1];
            let e_next = ec[1] * a + ec[0] * b - d2 * (1.0 - rho);
            ec = [ec[1], e_next];
            max_dev = max_dev.max((e_next - e_hist[k + 1]).amax());
        }
        // Round-off: ulp(20 m) per step through a loop of DC gain 1/(1 − a − b).
        let tol = 100.0 * 20.0 * f64::EPSILON / (1.0 - a - b);
        assert!(
            max_dev < tol,
            "λ={lambda_rel}: deviation {max_dev} m > {tol} m"
        );
        // Tracks: the initial 1e−4 m offset has decayed, the goal is reached.
        let goal = Vector3::from(p.goal_tof_m);
        assert!(
            (xi - goal).amax() < 1e-9,
            "final error {}",
            (xi - goal).amax()
        );
        // The x axis entered Ω: the last step used the shift d.
        assert_eq!(c.estimates()[0].shift_m, p.shift_m);
    }
}

/// With identification frozen (λ1 = 0), λ = 0 and no saturation, ACCM *is* the PD
/// baseline with `PdParams::paper()` gains, except for the feedforward: ACCM uses the
/// central second difference of the reference, PD its analytic acceleration. Reference:
/// the commands differ by exactly m_nom |Δ²ξ_r/h² − ξ̈_r| (evaluated independently here).
#[test]
fn invariant_pd_is_frozen_golden_section() {
    let mut ap = AccmParams::paper();
    ap.lambda1 = 0.0;
    ap.lambda_ctrl_rel = 0.0;
    ap.thrust_max_n = 1e12;
    let mut pp = PdParams::paper();
    pp.thrust_max_n = 1e12;
    let (h, m, tr) = (
        ap.sample_period_s,
        ap.mass_nominal_kg,
        ap.reference_duration_s,
    );
    let (mut a, mut p) = (Accm::new(ap.clone()), Pd::new(pp));
    let start = Vector3::new(-20.0, 0.0, 5.0);
    let goal = Vector3::from(ap.goal_tof_m);
    for k in 0..2000 {
        let t = k as f64 * h;
        // Arbitrary measured path near the reference.
        let pos = start + Vector3::new((0.3 * t).sin(), (0.7 * t).cos() - 1.0, 0.1 * t) * 0.01;
        let obs = Xu2015Observation {
            t_s: t,
            pos_tof_m: pos,
        };
        let du = a.update(&obs).force_tof_n - p.update(&obs).force_tof_n;
        for i in 0..3 {
            let r = |tt: f64| quintic_reference(start[i], goal[i], tr, tt);
            let d2 = (r(t + h).0 - 2.0 * r(t).0 + r(t - h).0) / (h * h);
            let expect = m * (d2 - r(t).2);
            assert!(
                (du[i] - expect).abs() < 1e-6 * (1.0 + expect.abs()),
                "k={k} i={i}"
            );
        }
    }
}

/// Zero-order hold: calling every 0.01 s returns the command computed at the last
/// multiple of h, identical to a controller called only at the samples.
#[test]
fn invariant_accm_zero_order_hold() {
    let p = AccmParams::paper();
    let (mut fast, mut slow) = (Accm::new(p.clone()), Accm::new(p.clone()));
    let pos = |t: f64| Vector3::new(-20.0 + 0.01 * t, 0.1 * (0.2 * t).sin(), 5.0 - 0.02 * t);
    let mut held = Vector3::zeros();
    for j in 0..=1000 {
        let t = j as f64 * 0.01;
        let u = fast
            .update(&Xu2015Observation {
                t_s: t,
                pos_tof_m: pos(t),
            })
            .force_tof_n;
        if j % 10 == 0 {
            held = slow
                .update(&Xu2015Observation {
                    t_s: t,
                    pos_tof_m: pos(t),
                })
                .force_tof_n;
        }
        assert_eq!(u, held, "t = {t}");
    }
}

/// Outcome of one closed-loop P1 run.
#[derive(Debug)]
struct RunStats {
    rms_err_m: f64,
    max_err_m: f64,
    max_err_axis_m: Vector3<f64>,
    max_thrust_n: Vector3<f64>,
    rms_thrust_n: f64,
    sat_frac_x_last100: f64,
}

/// Target maneuver of the paper, tof, N.
fn target_force_n(t: f64) -> Vector3<f64> {
    use std::f64::consts::PI;
    Vector3::new(
        10.0 * (0.08 * t + PI / 6.0).sin(),
        4.0 * (0.05 * t + PI / 4.0).sin(),
        8.0 * (0.1 * t + PI / 2.0).sin(),
    )
}

/// The paper's scenario on the relative dynamics of [`crate::orbit::elliptic`] (RK4 at the
/// sample period, thrust held), chaser at rest relative to the target frame at t = 0.
fn run_p1(
    mass_chaser_kg: f64,
    mut ctrl: impl FnMut(&Xu2015Observation) -> Vector3<f64>,
) -> RunStats {
    let orbit = EllipticOrbit::xu2015();
    let (m_t, h, tf): (f64, f64, f64) = (200.0, 0.1, 300.0);
    let goal = Vector3::new(-0.01, 0.0, 0.0);
    let n = (tf / h).round() as usize;
    let mut x = RelStateTof::new(-20.0, 0.0, 5.0, 0.0, 0.0, 0.0);
    let (mut se2, mut cnt, mut maxe) = (0.0, 0usize, 0.0f64);
    let mut maxe_ax = Vector3::zeros();
    let mut maxu = Vector3::<f64>::zeros();
    let (mut su2, mut sat) = (0.0, 0usize);
    for k in 0..=n {
        let t = k as f64 * h;
        let pos = Vector3::new(x[0], x[1], x[2]);
        if t >= tf - 100.0 - 1e-9 {
            let e = pos - goal;
            se2 += e.norm_squared();
            maxe = maxe.max(e.norm());
            maxe_ax = maxe_ax.zip_map(&e, |m: f64, v: f64| m.max(v.abs()));
            cnt += 1;
        }
        if k == n {
            break;
        }
        let u = ctrl(&Xu2015Observation {
            t_s: t,
            pos_tof_m: pos,
        });
        maxu = maxu.zip_map(&u, |m: f64, v: f64| m.max(v.abs()));
        su2 += u.norm_squared();
        if t >= tf - 100.0 - 1e-9 && u.x.abs() >= 5.0 - 1e-12 {
            sat += 1;
        }
        x = rk4_step_relative(&x, t, h, &orbit, |ts| {
            u / mass_chaser_kg - target_force_n(ts) / m_t
        });
    }
    RunStats {
        rms_err_m: (se2 / cnt as f64).sqrt(),
        max_err_m: maxe,
        max_err_axis_m: maxe_ax,
        max_thrust_n: maxu,
        rms_thrust_n: (su2 / n as f64).sqrt(),
        sat_frac_x_last100: sat as f64 / 1000.0,
    }
}

/// The P1 closed loop (paper §3): ACCM vs PD, chaser 90/100/110 kg, t_f = 300 s,
/// h = 0.1 s, chaser initially at rest in the tof, no measurement noise (paper silent).
/// Accuracy = |ξ − goal| over the last 100 s (reference already at the goal).
/// Independent reference for PD: with the reference constant, the quasi-static error of
/// m_nom[−k_p e − k_d ė]/m_c = F_t/m_t is e_i = (F_t,i/m_t)·m_c/(m_nom k_p); the dynamic
/// correction |1 + iω k_d/k_p − ω²/k_p| − 1 ≤ 1e−3 at ω ≤ 0.1 rad/s, so the per-axis PD
/// peak must match F_max,i m_c/(m_t m_nom k_p) within 5 % (margin for the short x-axis
/// saturation at 100 kg and the 0.1 s sampling of the peak).
/// Findings asserted as measured (see the printed table; do not re-tune to pass):
/// - 90 and 100 kg: ACCM is more than 10× more accurate than PD (measured ≈ 50×) at the
///   same RMS thrust (within 2 %, measured within 0.1 %).
/// - 110 kg: x authority 5/110 = 0.0455 m/s² < maneuver peak 10/200 = 0.05 m/s². The
///   unavoidable velocity deficit per maneuver peak is only ≈ 0.03 m/s, yet both
///   controllers (same high nominal gain) fall into a saturated oscillation on x of tens
///   of metres and are saturated ≥ 90 % of the last 100 s.
#[test]
fn val_xu2015_p1_accm_vs_pd() {
    let pdp = PdParams::paper();
    let f_max = Vector3::new(10.0, 4.0, 8.0);
    let m_t = 200.0;
    let mut table = Vec::new();
    for m_c in [90.0, 100.0, 110.0] {
        let mut accm = Accm::new(AccmParams::paper());
        let sa = run_p1(m_c, |o| accm.update(o).force_tof_n);
        let est = accm.estimates();
        let mut pd = Pd::new(pdp.clone());
        let sp = run_p1(m_c, |o| pd.update(o).force_tof_n);
        println!("m_c = {m_c} kg\n  ACCM {sa:?}\n  PD   {sp:?}\n  ACCM estimates {est:?}");
        table.push((m_c, sa, sp));
    }
    // Thrust limit always respected.
    for (_, sa, sp) in &table {
        assert!(sa.max_thrust_n.amax() <= 5.0 && sp.max_thrust_n.amax() <= 5.0);
    }
    for (m_c, sa, sp) in &table[..2] {
        let pred = f_max * (*m_c / (m_t * pdp.mass_nominal_kg * pdp.kp_s2));
        for i in 0..3 {
            let r = sp.max_err_axis_m[i] / pred[i];
            assert!((r - 1.0).abs() < 0.05, "PD axis {i} at {m_c} kg: {r}");
        }
        assert!(sa.rms_err_m * 10.0 < sp.rms_err_m, "{m_c} kg rms");
        assert!(sa.max_err_m * 10.0 < sp.max_err_m, "{m_c} kg max");
        assert!((sa.rms_thrust_n - sp.rms_thrust_n).abs() < 0.02 * sp.rms_thrust_n);
    }
    // Thrust authority on x at +10 % mass: 5/110 vs 10/200 m/s².
    let (auth, need) = (5.0 / 110.0, 10.0 / m_t);
    // Unavoidable velocity deficit over one maneuver peak: ∫ max(0, need|sin| − auth) dt
    // with θ = 0.08 t (midpoint quadrature over a half period).
    let nq = 100_000;
    let dtheta = std::f64::consts::PI / nq as f64;
    let dv_deficit: f64 = (0..nq)
        .map(|j| (need * ((j as f64 + 0.5) * dtheta).sin() - auth).max(0.0) * dtheta / 0.08)
        .sum();
    println!(
        "110 kg: x authority {auth:.5} m/s² < maneuver peak {need:.5} m/s²; \
             unavoidable Δv deficit per peak {dv_deficit:.4} m/s"
    );
    assert!(auth < need);
    let (_, sa, sp) = &table[2];
    for s in [sa, sp] {
        assert!(
            s.sat_frac_x_last100 >= 0.9,
            "x saturation fraction {}",
            s.sat_frac_x_last100
        );
        assert!(s.max_err_axis_m.x > 1.0, "x error {}", s.max_err_axis_m.x);
    }
}

mod scene_tests {
    //! References: the Keplerian frame of `crate::orbit::elliptic` (built from elements, not
    //! from r × v), the moments of the standard normal law, and the paper's numbers.
    use super::*;
    use crate::orbit::elliptic::EllipticOrbit;

    /// The tof built from (r, v) equals `EllipticOrbit::dcm_eci_from_tof(f)` built from the
    /// elements, along the P1 orbit (orthonormal, right-handed, same axes to round-off).
    #[test]
    fn val_xu2015_tof_from_state_matches_elements() {
        let o = EllipticOrbit::xu2015();
        for k in 0..50 {
            let f = o.true_anomaly_at(k as f64 * 300.0);
            let (r, v) = o.eci_state(f);
            let a = dcm_eci_from_tof_state(&r, &v);
            let b = o.dcm_eci_from_tof(f);
            assert!((a - b).amax() < 1e-12, "f = {f}: {}", (a - b).amax());
            assert!((a.transpose() * a - Matrix3::identity()).amax() < 1e-14);
            assert!((a.determinant() - 1.0).abs() < 1e-14);
        }
    }

    /// Paper numbers: peak maneuver accelerations (10, 4, 8)/200 m/s²; the 5 N chaser has a
    /// positive margin on every axis at 90 and 100 kg and a negative one on x only at 110 kg
    /// (5/110 − 10/200 = −4.5e−3 m/s²), reached where |sin| = 1.
    #[test]
    fn val_xu2015_thrust_authority_margins() {
        let m = ManeuverSpec::paper();
        let worst = |mc: f64| {
            (0..=30_000).fold(Vector3::repeat(f64::INFINITY), |acc, k| {
                let g = thrust_authority_margin_m_s2(5.0, mc, &m, 200.0, k as f64 * 0.01);
                acc.zip_map(&g, f64::min)
            })
        };
        for mc in [90.0, 100.0] {
            assert!(worst(mc).min() > 0.0, "{mc} kg: {:?}", worst(mc));
        }
        let w = worst(110.0);
        let exact = 5.0 / 110.0 - 10.0 / 200.0;
        assert!(w.x < 0.0 && (w.x - exact).abs() < 1e-8, "x {}", w.x);
        assert!(w.y > 0.0 && w.z > 0.0);
    }

    /// Gaussian noise: same seed, same sequence; sample mean and variance within 5 standard
    /// errors of 0 and 1 (SE of the mean 1/√n, of the variance √(2/n)).
    #[test]
    fn invariant_gaussian_noise_moments_and_determinism() {
        let n = 200_000;
        let mut g = GaussianNoise::new(7);
        let xs: Vec<f64> = (0..n).map(|_| g.standard_normal()).collect();
        let mut g2 = GaussianNoise::new(7);
        assert!(xs.iter().take(100).all(|x| *x == g2.standard_normal()));
        let mean = xs.iter().sum::<f64>() / n as f64;
        let var = xs.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1) as f64;
        let nf = n as f64;
        assert!(mean.abs() < 5.0 / nf.sqrt(), "mean {mean}");
        assert!((var - 1.0).abs() < 5.0 * (2.0 / nf).sqrt(), "var {var}");
    }

    /// A scene spec with only the required fields takes the paper's values; validation
    /// rejects a shift inside Ω and negative noise with the field named.
    #[test]
    fn regress_scene_spec_defaults_and_validation() {
        let s: Xu2015Spec =
            ron::from_str(r#"(body: "chaser", target: "target", law: Accm)"#).expect("parses");
        assert_eq!(s.accm.sample_period_s, 0.1);
        assert_eq!(s.pd.kp_s2, PdParams::paper().kp_s2);
        assert_eq!(s.target_maneuver, ManeuverSpec::paper());
        assert!(s.validate().is_ok());
        let mut b = s.clone();
        b.accm.shift_m = 0.4;
        assert_eq!(b.validate().unwrap_err().0, "accm.shift_m");
        let mut b = s.clone();
        b.sensor.noise_sigma_m = -1.0;
        assert_eq!(b.validate().unwrap_err().0, "sensor.noise_sigma_m");
        let p: Result<Xu2015Spec, _> =
            ron::from_str(r#"(body: "c", target: "t", law: Accm, accm: (eta: 1.0))"#);
        assert!(p.is_err(), "unknown field accepted");
    }
}
