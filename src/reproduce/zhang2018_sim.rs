//! The closed-loop simulator of Zhang et al. (2018)'s reproduction (Bevy-free, RK4 in the
//! Sun–EMB rotating frame): a planned reconfiguration flown with or without the barrier-based
//! avoidance ([`simulate_reconfiguration`]), the collision-course plan that is the premise of
//! the avoidance test ([`collision_course_plan`]), and Fig. 2's history of eq (12) along the
//! thrust-free motion ([`boundary_value_history`]). The law itself is
//! [`crate::control::zhang2018`]; the ECS run of the same scene is `scenes/papers/zhang2018/zhang2018_pair.ron`.

use crate::control::zhang2018::{
    AvoidanceController, BoundaryValue, GameState, PlannedManeuver, PursuerRole, ThrustSegment,
    Zhang2018Params, boundary_value, closest_approach, dir, e_state, join, p_state, rel_pos_m,
    rel_vel_m_s,
};
use nalgebra::Vector2;

/// Outcome of a closed-loop reconfiguration run.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct SimResult {
    /// Minimum separation, m (refined within steps by the closed-form line).
    pub min_separation_m: f64,
    /// Time of the minimum, s.
    pub t_min_s: f64,
    /// First time the avoidance engaged, s.
    pub first_engaged_s: Option<f64>,
    /// Total time engaged, s.
    pub engaged_time_s: f64,
    /// State at the start of the step that contains the minimum.
    pub state_at_min: GameState,
    /// Final state.
    pub final_state: GameState,
}

/// Simulates both spacecraft (RK4 step `dt_s`, thrust held over each step) for `duration_s`:
/// P flies `plan_p`; E flies `plan_e`, through the [`AvoidanceController`] if `avoid`.
pub fn simulate_reconfiguration(
    params: &Zhang2018Params,
    x0: &GameState,
    plan_p: &PlannedManeuver,
    plan_e: &PlannedManeuver,
    avoid: bool,
    dt_s: f64,
    duration_s: f64,
) -> SimResult {
    let mut ctl = AvoidanceController::new(params.clone());
    let mut x = *x0;
    let mut res = SimResult {
        min_separation_m: f64::INFINITY,
        t_min_s: 0.0,
        first_engaged_s: None,
        engaged_time_s: 0.0,
        state_at_min: x,
        final_state: x,
    };
    let steps = (duration_s / dt_s).round() as usize;
    for k in 0..steps {
        let t = k as f64 * dt_s;
        let ca = closest_approach(&x);
        let tl = ca.t_ca_s.min(dt_s);
        let sep = (rel_pos_m(&x) + rel_vel_m_s(&x) * tl).norm();
        if sep < res.min_separation_m {
            res.min_separation_m = sep;
            res.t_min_s = t + tl;
            res.state_at_min = x;
        }
        let v = plan_p.dir_at(t);
        let u = if avoid {
            let c = ctl.evader_command(&x, plan_e.dir_at(t));
            if c.engaged {
                res.engaged_time_s += dt_s;
                res.first_engaged_s.get_or_insert(t);
            }
            c.dir_rad
        } else {
            plan_e.dir_at(t)
        };
        let ap = v.map_or(Vector2::zeros(), |a| dir(a) * params.alpha_p_m_s2());
        let ae = u.map_or(Vector2::zeros(), |a| dir(a) * params.alpha_e_m_s2());
        let p = params.drift.rk4_step(&p_state(&x), &ap, dt_s);
        let e = params.drift.rk4_step(&e_state(&x), &ae, dt_s);
        x = join(&p, &e);
    }
    let sep = rel_pos_m(&x).norm();
    if sep < res.min_separation_m {
        res.min_separation_m = sep;
        res.t_min_s = steps as f64 * dt_s;
        res.state_at_min = x;
    }
    res.final_state = x;
    res
}

/// A reconfiguration of P whose unprotected path runs through E (the paper gives no maneuver;
/// this is the premise of the avoidance test, built deliberately). P swaps past E: it thrusts in
/// a fixed direction θ for t_m, then in θ + π for t_m (arriving at rest, force-free, at twice
/// its crossing point). t_m solves ‖ρ0 + w0 t_m‖ = ½ (F_p/M_p) t_m² (force-free intercept of
/// coasting E), rounded to a multiple of `dt_s`; θ is then corrected by `iterations` secant
/// steps on the signed miss of the unprotected run (E coasting) in the full drift model.
/// Returns P's plan (empty if P has no thrust).
pub fn collision_course_plan(
    params: &Zhang2018Params,
    x0: &GameState,
    dt_s: f64,
    iterations: usize,
) -> PlannedManeuver {
    let rho = rel_pos_m(x0);
    let w = rel_vel_m_s(x0);
    let alpha = params.alpha_p_m_s2();
    if alpha <= 0.0 || !alpha.is_finite() {
        return PlannedManeuver::default();
    }
    let g = |t: f64| (rho + w * t).norm() - 0.5 * alpha * t * t;
    let (mut lo, mut hi) = (0.0, 1.0);
    while g(hi) > 0.0 {
        hi *= 2.0;
    }
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if g(mid) > 0.0 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let t_m = (hi / dt_s).round() * dt_s;
    let aim = rho + w * t_m;
    let plan = |theta: f64| PlannedManeuver {
        segments: vec![
            ThrustSegment {
                t_start_s: 0.0,
                t_end_s: t_m,
                dir_rad: theta,
            },
            ThrustSegment {
                t_start_s: t_m,
                t_end_s: 2.0 * t_m,
                dir_rad: theta + std::f64::consts::PI,
            },
        ],
    };
    let none = PlannedManeuver::default();
    // Signed miss: the cross product of ρ at closest approach with the relative velocity there.
    let signed_miss = |theta: f64| {
        let r = simulate_reconfiguration(params, x0, &plan(theta), &none, false, dt_s, 1.5 * t_m);
        let xs = r.state_at_min;
        let ca = closest_approach(&xs);
        let wv = rel_vel_m_s(&xs);
        let m = rel_pos_m(&xs) + wv * ca.t_ca_s.min(dt_s);
        (m[0] * wv[1] - m[1] * wv[0]) / wv.norm()
    };
    let mut th0 = aim[1].atan2(aim[0]);
    let mut th1 = th0 + 1e-6;
    let mut f0 = signed_miss(th0);
    for _ in 0..iterations {
        let f1 = signed_miss(th1);
        if f1 == f0 {
            break;
        }
        let th2 = th1 - f1 * (th1 - th0) / (f1 - f0);
        th0 = th1;
        f0 = f1;
        th1 = th2;
    }
    plan(th1)
}

/// Fig. 2 of the paper: eq (12) along the thrust-free motion of both spacecraft from `x0`
/// (RK4 step `dt_s`, `steps` steps). Returns `(t_s, value)` for `steps + 1` samples.
pub fn boundary_value_history(
    params: &Zhang2018Params,
    x0: &GameState,
    role: PursuerRole,
    dt_s: f64,
    steps: usize,
) -> Vec<(f64, BoundaryValue)> {
    let mut x = *x0;
    let mut out = Vec::with_capacity(steps + 1);
    out.push((0.0, boundary_value(params, &x, role)));
    for k in 0..steps {
        let p = params.drift.rk4_step(&p_state(&x), &Vector2::zeros(), dt_s);
        let e = params.drift.rk4_step(&e_state(&x), &Vector2::zeros(), dt_s);
        x = join(&p, &e);
        out.push(((k + 1) as f64 * dt_s, boundary_value(params, &x, role)));
    }
    out
}

#[cfg(test)]
mod tests {
    //! References: the closed form of the force-free relative line (range rate and closest
    //! approach, Fig. 2's sign change predicted 2(F/M)·d/|w|² before the closest approach,
    //! found independently by sampling the separation) and the unprotected run (the closed
    //! loop's separation against l).
    use super::*;
    use crate::control::zhang2018::{Drift, paper_initial_state_rot, rel_pos_m, rel_vel_m_s};
    use crate::orbit::l2::L2Params;

    fn l2() -> L2Params {
        L2Params::paper()
    }

    #[test]
    fn val_zhang2018_fig2_h_changes_sign() {
        // Fig. 2: eq (12) as printed (cooperative value) along the paper's scenario, both
        // spacecraft thrust-free. With Q sin(s5+a) = −ρ̇ + e·Δa0 (range rate ρ̇ = e·w) the value
        // is H = ½(−ρ̇ + e·Δa0 − 2F/M); it changes sign where the range rate crosses −2F/M,
        // i.e. (straight-line relative motion near closest approach, ρ̇ = |w|²(t − t_ca)/d)
        // 2(F/M)·d/|w|² before the closest approach. The time of closest approach is found
        // independently by sampling the separation.
        for drift in [Drift::L2(l2()), Drift::ForceFree] {
            let mut p = Zhang2018Params::paper();
            p.drift = drift;
            let x0 = paper_initial_state_rot(&l2());
            let dt = 600.0;
            let hist = boundary_value_history(&p, &x0, PursuerRole::PaperCooperative, dt, 60 * 144);
            assert!(hist[0].1.h > 0.0 && hist.last().unwrap().1.h < 0.0);
            let changes: Vec<usize> = (1..hist.len())
                .filter(|&k| hist[k - 1].1.h * hist[k].1.h <= 0.0)
                .collect();
            assert_eq!(changes.len(), 1, "sign changes at {changes:?}");
            let t_sign = hist[changes[0]].0;
            // Independent closest approach: sample the separation.
            let mut x = x0;
            let (mut best, mut t_ca, mut x_ca) = (f64::INFINITY, 0.0, x0);
            for k in 0..(60 * 144) {
                let d = rel_pos_m(&x).norm();
                if d < best {
                    (best, t_ca, x_ca) = (d, k as f64 * dt, x);
                }
                let a = p.drift.rk4_step(&p_state(&x), &Vector2::zeros(), dt);
                let b = p.drift.rk4_step(&e_state(&x), &Vector2::zeros(), dt);
                x = join(&a, &b);
            }
            let w2 = rel_vel_m_s(&x_ca).norm_squared();
            let lead = 2.0 * p.alpha_p_m_s2() * best / w2;
            eprintln!(
                "fig2 {:?}: H(0) = {:.4} , sign change at t = {:.3} d, closest approach {:.1} km at {:.3} d, predicted lead {:.0} s",
                match p.drift {
                    Drift::L2(_) => "L2",
                    Drift::ForceFree => "force-free",
                },
                hist[0].1.h,
                t_sign / 86_400.0,
                best / 1e3,
                t_ca / 86_400.0,
                lead
            );
            // Sampling resolution: one step each for the sign change and the minimum.
            assert!(
                (t_sign - (t_ca - lead)).abs() <= 2.0 * dt,
                "t_sign {t_sign} t_ca {t_ca}"
            );
        }
    }

    #[test]
    fn val_zhang2018_closed_loop_avoidance() {
        // P's planned reconfiguration runs through E (constructed, see
        // `collision_course_plan`); E coasts on its plan. Unprotected, the separation falls
        // below l; with the barrier-based avoidance it stays above l. dt = 10 s (with 1 s the
        // protected minimum moved by 0.34 km, see the report); the guarantee needs the margin
        // (1 km) to exceed the per-step change of the miss distance, ≈ t_ca·(F/M)·dt
        // ≈ 3.4e4 s · 5e-4 m/s² · 10 s ≈ 0.17 km at engagement.
        let p = Zhang2018Params::paper();
        let x0 = paper_initial_state_rot(&l2());
        let dt = 10.0;
        let plan = collision_course_plan(&p, &x0, dt, 5);
        let none = PlannedManeuver::default();
        let t_end = plan.segments[1].t_end_s;
        let off = simulate_reconfiguration(&p, &x0, &plan, &none, false, dt, t_end);
        let on = simulate_reconfiguration(&p, &x0, &plan, &none, true, dt, t_end);
        eprintln!(
            "closed loop: unprotected min sep {:.3} m at {:.0} s; protected min sep {:.1} m at {:.0} s, engaged first at {:?} s for {:.0} s",
            off.min_separation_m,
            off.t_min_s,
            on.min_separation_m,
            on.t_min_s,
            on.first_engaged_s,
            on.engaged_time_s
        );
        assert!(off.min_separation_m < p.capture_radius_m);
        assert!(on.min_separation_m > p.capture_radius_m);
        assert!(on.first_engaged_s.is_some());
        assert!(off.first_engaged_s.is_none());
    }
}
