//! Adaptive-step integration of stiff ODEs with a terminal event: the linearly implicit
//! Rosenbrock (W-)method of order 2 with a 3rd-order error estimate of Shampine & Reichelt,
//! "The MATLAB ODE Suite", SIAM J. Sci. Comput. 18(1), 1997, §3.1 (MATLAB's `ode23s`).
//!
//! One step from (t, y) with step h, `d = 1/(2 + √2)`, `e32 = 6 + √2`, `J ≈ ∂f/∂y`,
//! `T ≈ ∂f/∂t`, `W = I − h d J`:
//! ```text
//! F0 = f(t, y)
//! k1 = W⁻¹ (F0 + h d T)
//! F1 = f(t + h/2, y + h k1/2)
//! k2 = W⁻¹ (F1 − k1) + k1
//! y1 = y + h k2                                  (2nd order, L-stable)
//! F2 = f(t + h, y1)
//! k3 = W⁻¹ [F2 − e32 (k2 − F1) − 2 (k1 − F0) + h d T]
//! err = h (k1 − 2 k2 + k3) / 6                   (local error estimate)
//! ```
//! It is a W-method: its order does not depend on the accuracy of `J`, only its stability
//! does, so a finite-difference Jacobian (forward differences, one evaluation of `f` per
//! component, increments chosen by the system) is enough. L-stability lets the step follow the
//! slow dynamics while a fast mode (a stiff eigenvalue of `J`) is damped.
//!
//! Error control: a step is accepted when `max_i |err_i| / (atol_i + rtol·max(|y_i|, |y1_i|))`
//! ≤ 1; the next step is `h · clamp(0.8·norm^(−1/3), 0.2, 5)` (no growth right after a
//! rejection).
//!
//! Terminal event: the system's [`OdeSystem::event`] g(t, y) must stay > 0. An accepted step
//! whose end has g ≤ 0 is rejected and retried with half the step, from the same point, until
//! the step is below `event_time_tol_s`: the crossing is then located to within that time (the
//! integration never accepts a state beyond the event; between the last accepted point and
//! the crossing at most `event_time_tol_s` passes). The method has no dense output: what
//! happens between accepted points is what the local error bound allows.

use nalgebra::{SMatrix, SVector};

/// A system x' = f(t, x) for [`integrate_rosenbrock23`].
pub trait OdeSystem<const N: usize> {
    /// f(t, y).
    fn rhs(&mut self, t: f64, y: &SVector<f64, N>) -> SVector<f64, N>;

    /// Forward-difference increment of component `i` for the Jacobian at (t, y). Default:
    /// `√ε · max(|y_i|, 1)`. A system whose right-hand side changes form nearby (a boundary
    /// at a small distance) gives a smaller one.
    fn fd_increment(&self, _t: f64, y: &SVector<f64, N>, i: usize) -> f64 {
        f64::EPSILON.sqrt() * y[i].abs().max(1.0)
    }

    /// The terminal event function: the integration stops where it reaches ≤ 0.
    /// Default: never.
    fn event(&self, _t: f64, _y: &SVector<f64, N>) -> f64 {
        f64::INFINITY
    }

    /// Called after every accepted step with the new state; may project it (e.g. renormalise
    /// a quaternion) and record it. Default: nothing.
    fn accepted(&mut self, _t: f64, _y: &mut SVector<f64, N>) {}
}

/// Tolerances and limits of [`integrate_rosenbrock23`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OdeOptions<const N: usize> {
    /// Relative tolerance.
    pub rtol: f64,
    /// Absolute tolerance per component (units of the component).
    pub atol: SVector<f64, N>,
    /// First step, s.
    pub h0_s: f64,
    /// Largest step, s.
    pub h_max_s: f64,
    /// Smallest step; a step that would be smaller ends the run with
    /// [`OdeEnd::StepTooSmall`], s.
    pub h_min_s: f64,
    /// Time to which a terminal event is located, s.
    pub event_time_tol_s: f64,
    /// Largest number of attempted steps; more end the run with [`OdeEnd::MaxSteps`].
    pub max_steps: usize,
}

/// Why an integration ended.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum OdeEnd {
    /// The final time was reached.
    Reached,
    /// The event function reached ≤ 0 between the returned (last accepted) time and that
    /// time plus [`OdeOptions::event_time_tol_s`]; `g_s` is its value at the end of the
    /// rejected step.
    Event {
        /// Event function at the end of the last (rejected) step.
        g: f64,
    },
    /// The error control asked for a step below [`OdeOptions::h_min_s`] (step asked, s).
    StepTooSmall {
        /// The step the error control asked for, s.
        h_s: f64,
    },
    /// [`OdeOptions::max_steps`] steps were attempted.
    MaxSteps,
    /// The right-hand side returned a non-finite value.
    NonFinite,
}

/// Counters of one integration.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct OdeStats {
    /// Accepted steps.
    pub accepted: usize,
    /// Steps rejected by the error control.
    pub rejected_error: usize,
    /// Steps rejected because they crossed the event.
    pub rejected_event: usize,
    /// Evaluations of the right-hand side (Jacobians included).
    pub rhs_evals: usize,
    /// Smallest accepted step, s.
    pub h_min_used_s: f64,
    /// Largest accepted step, s.
    pub h_max_used_s: f64,
}

/// Result of [`integrate_rosenbrock23`]: last accepted time and state, why it ended, counters.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OdeResult<const N: usize> {
    /// Time of the last accepted state, s.
    pub t_s: f64,
    /// The last accepted state.
    pub y: SVector<f64, N>,
    /// Why the integration ended.
    pub end: OdeEnd,
    /// Counters.
    pub stats: OdeStats,
}

/// W⁻¹ by LU with partial pivoting (nalgebra's, on a dynamic copy), or `None` if singular.
fn invert<const N: usize>(w: &SMatrix<f64, N, N>) -> Option<SMatrix<f64, N, N>> {
    let d = nalgebra::DMatrix::from_column_slice(N, N, w.as_slice());
    let inv = d.lu().try_inverse()?;
    Some(SMatrix::<f64, N, N>::from_column_slice(inv.as_slice()))
}

/// Integrates `sys` from (`t0_s`, `y0`) to `t1_s` (> t0) with the Rosenbrock 2(3) W-method
/// of the module docs, stopping early at a terminal event, a step below the minimum, a
/// non-finite right-hand side or the step limit.
pub fn integrate_rosenbrock23<const N: usize, S: OdeSystem<N>>(
    sys: &mut S,
    t0_s: f64,
    y0: &SVector<f64, N>,
    t1_s: f64,
    opt: &OdeOptions<N>,
) -> OdeResult<N> {
    let d = 1.0 / (2.0 + std::f64::consts::SQRT_2);
    let e32 = 6.0 + std::f64::consts::SQRT_2;
    let mut t = t0_s;
    let mut y = *y0;
    let mut h = opt.h0_s.min(opt.h_max_s).max(opt.h_min_s);
    let mut st = OdeStats {
        h_min_used_s: f64::INFINITY,
        ..Default::default()
    };
    let mut attempts = 0usize;
    let mut just_rejected = false;
    let finite = |v: &SVector<f64, N>| v.iter().all(|x| x.is_finite());
    let end = loop {
        if t >= t1_s {
            break OdeEnd::Reached;
        }
        if attempts >= opt.max_steps {
            break OdeEnd::MaxSteps;
        }
        let last = t + h >= t1_s;
        let h_step = if last { t1_s - t } else { h };
        // f, its Jacobian (forward differences) and ∂f/∂t at (t, y).
        let f0 = sys.rhs(t, &y);
        st.rhs_evals += 1;
        if !finite(&f0) {
            break OdeEnd::NonFinite;
        }
        let mut jac = SMatrix::<f64, N, N>::zeros();
        for i in 0..N {
            let di = sys.fd_increment(t, &y, i);
            let mut yp = y;
            yp[i] += di;
            let fi = sys.rhs(t, &yp);
            st.rhs_evals += 1;
            jac.set_column(i, &((fi - f0) / di));
        }
        let dt_fd = f64::EPSILON.sqrt() * t.abs().max(h_step).max(1e-3);
        let ft = sys.rhs(t + dt_fd, &y);
        st.rhs_evals += 1;
        let tdot = (ft - f0) / dt_fd;
        // Retry loop at this (t, y) with the same J.
        let mut hs = h_step;
        let outcome = loop {
            attempts += 1;
            let w = SMatrix::<f64, N, N>::identity() - jac * (hs * d);
            let Some(lu) = invert(&w) else {
                break Err(OdeEnd::NonFinite);
            };
            let k1 = lu * (f0 + tdot * (hs * d));
            let f1 = sys.rhs(t + 0.5 * hs, &(y + k1 * (0.5 * hs)));
            let k2 = lu * (f1 - k1) + k1;
            let y1 = y + k2 * hs;
            let f2 = sys.rhs(t + hs, &y1);
            st.rhs_evals += 2;
            let k3 = lu * (f2 - (k2 - f1) * e32 - (k1 - f0) * 2.0 + tdot * (hs * d));
            let err = (k1 - k2 * 2.0 + k3) * (hs / 6.0);
            if !finite(&y1) || !finite(&err) {
                // Treat as a failed step: shrink.
                st.rejected_error += 1;
                hs *= 0.2;
                just_rejected = true;
                if hs < opt.h_min_s {
                    break Err(OdeEnd::StepTooSmall { h_s: hs });
                }
                if attempts >= opt.max_steps {
                    break Err(OdeEnd::MaxSteps);
                }
                continue;
            }
            let mut norm: f64 = 0.0;
            for i in 0..N {
                let sc = opt.atol[i] + opt.rtol * y[i].abs().max(y1[i].abs());
                norm = norm.max(err[i].abs() / sc);
            }
            if norm > 1.0 {
                st.rejected_error += 1;
                hs *= (0.8 * norm.powf(-1.0 / 3.0)).clamp(0.2, 0.9);
                just_rejected = true;
                if hs < opt.h_min_s {
                    break Err(OdeEnd::StepTooSmall { h_s: hs });
                }
                if attempts >= opt.max_steps {
                    break Err(OdeEnd::MaxSteps);
                }
                continue;
            }
            let g = sys.event(t + hs, &y1);
            if g <= 0.0 {
                if hs <= opt.event_time_tol_s {
                    break Err(OdeEnd::Event { g });
                }
                st.rejected_event += 1;
                hs *= 0.5;
                just_rejected = true;
                if attempts >= opt.max_steps {
                    break Err(OdeEnd::MaxSteps);
                }
                continue;
            }
            break Ok((hs, y1, norm));
        };
        match outcome {
            Err(e) => break e,
            Ok((hs, y1, norm)) => {
                t = if last && hs == h_step { t1_s } else { t + hs };
                y = y1;
                sys.accepted(t, &mut y);
                st.accepted += 1;
                st.h_min_used_s = st.h_min_used_s.min(hs);
                st.h_max_used_s = st.h_max_used_s.max(hs);
                let grow = if just_rejected {
                    1.0
                } else {
                    (0.8 * norm.max(1e-10).powf(-1.0 / 3.0)).clamp(0.2, 5.0)
                };
                just_rejected = false;
                h = (hs * grow).clamp(opt.h_min_s, opt.h_max_s);
            }
        }
    };
    OdeResult {
        t_s: t,
        y,
        end,
        stats: st,
    }
}

#[cfg(test)]
mod tests {
    //! References: closed-form solutions (a forced linear ODE, a stiff linear ODE whose smooth
    //! solution is cos t, free fall) and the order of the method by step halving.
    use super::*;
    use nalgebra::{Vector1, Vector2};

    struct Forced;
    impl OdeSystem<1> for Forced {
        fn rhs(&mut self, t: f64, y: &Vector1<f64>) -> Vector1<f64> {
            Vector1::new(-y[0] + t.sin())
        }
    }

    fn opts<const N: usize>(rtol: f64, atol: f64) -> OdeOptions<N> {
        OdeOptions {
            rtol,
            atol: SVector::repeat(atol),
            h0_s: 1e-3,
            h_max_s: 1.0,
            h_min_s: 1e-14,
            event_time_tol_s: 1e-10,
            max_steps: 1_000_000,
        }
    }

    /// y' = −y + sin t, y(0) = 1: y = 1.5 e^{−t} + (sin t − cos t)/2. The controller bounds
    /// the local error per step; the global error after 10 s is the sum over the steps, a few
    /// hundred times the tolerance here (asserted: < 500·rtol, and shrinking with rtol).
    #[test]
    fn val_ode_rosenbrock23_forced_linear_closed_form() {
        let exact = |t: f64| 1.5 * (-t).exp() + 0.5 * (t.sin() - t.cos());
        for (rtol, tol) in [(1e-6, 5e-4), (1e-9, 5e-7)] {
            let r = integrate_rosenbrock23(
                &mut Forced,
                0.0,
                &Vector1::new(1.0),
                10.0,
                &opts(rtol, rtol),
            );
            assert_eq!(r.end, OdeEnd::Reached);
            assert_eq!(r.t_s, 10.0);
            let e = (r.y[0] - exact(10.0)).abs();
            assert!(e < tol, "rtol {rtol}: error {e:.2e}");
        }
    }

    /// Fixed-step order check on the same problem: halving h divides the error by ≈ 4.
    #[test]
    fn invariant_ode_rosenbrock23_is_second_order() {
        let exact = 1.5 * (-2.0f64).exp() + 0.5 * (2.0f64.sin() - 2.0f64.cos());
        let err = |h: f64| {
            let mut o = opts::<1>(1e30, 1e30); // accept every step
            o.h0_s = h;
            o.h_max_s = h;
            o.h_min_s = h;
            let r = integrate_rosenbrock23(&mut Forced, 0.0, &Vector1::new(1.0), 2.0, &o);
            (r.y[0] - exact).abs()
        };
        let (a, b) = (err(0.02), err(0.01));
        let order = (a / b).log2();
        assert!((order - 2.0).abs() < 0.15, "observed order {order:.3}");
    }

    /// Stiff: y' = −λ(y − cos t) − sin t, y(0) = 1 has the solution cos t for every λ; with
    /// λ = 1e8 an explicit method needs ≳ λ·T/2 = 5e8 steps for stability alone, the L-stable
    /// method follows cos t with steps set by accuracy.
    struct Stiff;
    impl OdeSystem<1> for Stiff {
        fn rhs(&mut self, t: f64, y: &Vector1<f64>) -> Vector1<f64> {
            Vector1::new(-1e8 * (y[0] - t.cos()) - t.sin())
        }
    }

    #[test]
    fn val_ode_rosenbrock23_stiff_follows_slow_solution() {
        let r =
            integrate_rosenbrock23(&mut Stiff, 0.0, &Vector1::new(1.0), 10.0, &opts(1e-6, 1e-6));
        assert_eq!(r.end, OdeEnd::Reached);
        assert!((r.y[0] - 10f64.cos()).abs() < 1e-4, "{}", r.y[0]);
        assert!(r.stats.accepted < 5000, "{:?}", r.stats);
    }

    /// Free fall from 10 m: the event y = 0 at t = √(2·10/g), located to the event tolerance;
    /// the last accepted state is above the ground.
    struct Fall {
        last_t: f64,
    }
    impl OdeSystem<2> for Fall {
        fn rhs(&mut self, _t: f64, y: &Vector2<f64>) -> Vector2<f64> {
            Vector2::new(y[1], -9.81)
        }
        fn event(&self, _t: f64, y: &Vector2<f64>) -> f64 {
            y[0]
        }
        fn accepted(&mut self, t: f64, _y: &mut Vector2<f64>) {
            self.last_t = t;
        }
    }

    #[test]
    fn val_ode_rosenbrock23_event_located() {
        let mut s = Fall { last_t: 0.0 };
        let r = integrate_rosenbrock23(
            &mut s,
            0.0,
            &Vector2::new(10.0, 0.0),
            5.0,
            &opts(1e-10, 1e-12),
        );
        let t_hit = (2.0 * 10.0 / 9.81f64).sqrt();
        assert!(matches!(r.end, OdeEnd::Event { .. }), "{:?}", r.end);
        assert!(
            r.y[0] > 0.0 && r.t_s <= t_hit && t_hit - r.t_s < 1e-9,
            "{} vs {t_hit}",
            r.t_s
        );
        assert_eq!(s.last_t, r.t_s);
        assert!(r.stats.rejected_event > 0);
    }

    /// A right-hand side that blows up ends the run, it does not hang or panic.
    struct Blow;
    impl OdeSystem<1> for Blow {
        fn rhs(&mut self, _t: f64, y: &Vector1<f64>) -> Vector1<f64> {
            Vector1::new(y[0] * y[0])
        }
    }

    #[test]
    fn regress_ode_rosenbrock23_blow_up_ends_cleanly() {
        // y' = y², y(0) = 1: y = 1/(1 − t), infinite at t = 1.
        let mut o = opts::<1>(1e-8, 1e-8);
        o.h_min_s = 1e-12;
        o.max_steps = 100_000;
        let r = integrate_rosenbrock23(&mut Blow, 0.0, &Vector1::new(1.0), 2.0, &o);
        assert!(r.t_s < 1.0 && r.y[0].is_finite(), "{r:?}");
        assert!(!matches!(r.end, OdeEnd::Reached));
    }
}
