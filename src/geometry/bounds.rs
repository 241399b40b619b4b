//! Sound bounds of a function of time over an interval, from its values at sample points and a
//! bound on its rate of change (Bevy-free, f64).
//!
//! The monitor judges distances and guarantee margins on whole step intervals, not only at the
//! step times. Everything here rests on one fact: if |f′(t)| ≤ L on [a, b], then for every t
//! in [a, b], f(t) ≥ max(f(a) − L·(t − a), f(b) − L·(b − t)), hence
//!
//! ```text
//! min over [a, b] of f ≥ (f(a) + f(b) − L·(b − a)) / 2.
//! ```
//!
//! Values may come with an error bar: a [`Bracket`] carries the value an evaluation found
//! (achieved: f really is that small there, to the evaluation's precision) and a certified
//! lower bound (f is at least that large there). Exact parry distances are brackets — GJK stops
//! at a relative tolerance and parry works in f32.
//!
//! * [`minimize`]: branch and bound on the interval, bisecting the sub-interval with the lowest
//!   bound until every sub-interval's bound clears a caller's threshold (which may depend on
//!   the best value found so far) — the minimum to a tolerance, or a proof that it stays above
//!   a level.
//! * [`first_below`]: the earliest time f drops below a level, bracketed to a time tolerance,
//!   or a proof it never does on the interval.
//! * [`advance_to`]: conservative advancement — the earliest time f can reach a target, by
//!   steps (f(t) − target)/L that never overshoot the first crossing.
//!
//! A rate bound that is too small makes the bounds unsound; callers derive theirs from the
//! motion (see `sim::motion`), with the argument written where they do.

/// A function value with a certified lower bound: `lower ≤ f(t) ≲ value`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Bracket {
    /// The value found (f is this small at the point, to the evaluation's precision).
    pub value: f64,
    /// A certified lower bound of f at the point.
    pub lower: f64,
}

impl Bracket {
    /// An exact value (lower bound equal to the value).
    pub fn exact(v: f64) -> Self {
        Self { value: v, lower: v }
    }

    /// value − lower: how far below the value the certified bound may sit.
    pub fn width(&self) -> f64 {
        self.value - self.lower
    }
}

/// The finest tolerance a search between the end brackets `a` and `b` can be asked to prove:
/// twice the wider one's width. Every sub-interval's bound sits below its samples' values by
/// their widths, so a threshold closer to the values than that could never be cleared and the
/// search would spend its whole budget (the closest approach, `sim::monitor::tracked`; a
/// guarantee's worst margin, `sim::StepJudge::finding`).
pub fn provable_tolerance(a: &Bracket, b: &Bracket) -> f64 {
    2.0 * a.width().max(b.width())
}

/// The interval lower bound from the ends' lower bounds and the rate bound, over a width `h`:
/// (f(a) + f(b) − L·h)/2, never above either end.
pub fn interval_lower_bound(fa: f64, fb: f64, rate: f64, h: f64) -> f64 {
    ((fa + fb - rate * h) * 0.5).min(fa).min(fb)
}

/// The result of [`minimize`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MinSearch {
    /// Smallest value found (at an end or at an evaluated interior point).
    pub value: f64,
    /// Where, as an offset from the interval start, s.
    pub t: f64,
    /// Certified lower bound of f over the whole interval.
    pub lower: f64,
    /// Interior evaluations made.
    pub evals: u32,
    /// The evaluation budget ran out before every sub-interval cleared the threshold.
    pub exhausted: bool,
}

#[derive(Clone, Copy)]
struct Piece {
    a: f64,
    fa: usize,
    b: f64,
    fb: usize,
    lb: f64,
}

/// Branch and bound for the minimum of f over [0, h].
///
/// `fa`, `fb` are f at 0 and h; `rate` bounds |f′|. `threshold(best)` says how low the bound
/// of a sub-interval may be left, given the best value found so far: the search stops when
/// every remaining sub-interval's bound is at or above it (so the minimum is within
/// `best − threshold(best)` of `best`, or above the threshold), when `max_evals` interior
/// evaluations have been made, or when sub-intervals are narrower than `min_width` (then their
/// bound stands as is). `f(t)` evaluates at an interior offset.
#[allow(clippy::too_many_arguments)] // the interval, its ends, the bound, and the stop rules
pub fn minimize(
    h: f64,
    fa: Bracket,
    fb: Bracket,
    rate: f64,
    threshold: impl Fn(f64) -> f64,
    max_evals: u32,
    min_width: f64,
    f: impl FnMut(f64) -> Bracket,
) -> MinSearch {
    minimize_by(
        h,
        fa,
        fb,
        |x: &Bracket| x.value,
        |x: &Bracket, y: &Bracket, w: f64| interval_lower_bound(x.lower, y.lower, rate, w),
        threshold,
        max_evals,
        min_width,
        f,
    )
}

/// [`minimize`] over samples that carry more than one bracket: `value(s)` is f at a sample
/// (the value found), and `bound(s_a, s_b, w)` a certified lower bound of f over a
/// sub-interval of width `w` whose ends are sampled by `s_a` and `s_b`. With
/// f = min over pieces k of f_k and |f_k′| ≤ L_k, min over k of
/// (lower_k(a) + lower_k(b) − L_k·w)/2 is such a bound — a piece whose own bound clears the
/// threshold then never forces a bisection. Same search, same stop rules; with Bracket samples
/// and [`interval_lower_bound`] it is [`minimize`].
#[allow(clippy::too_many_arguments)] // the interval, its ends, the bound, and the stop rules
pub fn minimize_by<S>(
    h: f64,
    fa: S,
    fb: S,
    value_of: impl Fn(&S) -> f64,
    bound: impl Fn(&S, &S, f64) -> f64,
    threshold: impl Fn(f64) -> f64,
    max_evals: u32,
    min_width: f64,
    mut f: impl FnMut(f64) -> S,
) -> MinSearch {
    let (va, vb) = (value_of(&fa), value_of(&fb));
    let (mut value, mut t) = if vb < va { (vb, h) } else { (va, 0.0) };
    let lb0 = bound(&fa, &fb, h);
    // Every sample, once; pieces refer to them by index.
    let mut samples = vec![fa, fb];
    let mut pieces = vec![Piece {
        a: 0.0,
        fa: 0,
        b: h,
        fb: 1,
        lb: lb0,
    }];
    let mut evals = 0;
    let mut settled_lb = f64::INFINITY;
    // The piece with the lowest bound (few pieces: a linear scan beats a heap).
    while let Some((k, p)) = pieces
        .iter()
        .copied()
        .enumerate()
        .min_by(|x, y| x.1.lb.total_cmp(&y.1.lb))
    {
        let thr = threshold(value);
        if p.lb >= thr {
            break;
        }
        if evals >= max_evals {
            let lower = p.lb.min(settled_lb);
            return MinSearch {
                value,
                t,
                lower,
                evals,
                exhausted: true,
            };
        }
        pieces.swap_remove(k);
        if p.b - p.a <= min_width {
            settled_lb = settled_lb.min(p.lb);
            continue;
        }
        let m = 0.5 * (p.a + p.b);
        let fm = f(m);
        evals += 1;
        let vm = value_of(&fm);
        if vm < value {
            value = vm;
            t = m;
        }
        let im = samples.len();
        samples.push(fm);
        for (a, ia, b, ib) in [(p.a, p.fa, m, im), (m, im, p.b, p.fb)] {
            pieces.push(Piece {
                a,
                fa: ia,
                b,
                fb: ib,
                lb: bound(&samples[ia], &samples[ib], b - a),
            });
        }
    }
    let lower = pieces
        .iter()
        .map(|p| p.lb)
        .fold(settled_lb, f64::min)
        .min(value);
    MinSearch {
        value,
        t,
        lower,
        evals,
        exhausted: false,
    }
}

/// The result of [`first_below`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Crossing {
    /// f ≥ level on the whole interval (proven).
    Never,
    /// f ≥ level on [0, `t_lo`] (proven) and f(`t_hi`) < level (found). `t_hi − t_lo` is the
    /// time tolerance, or more where f stays within the evaluations' precision of the level
    /// just before the crossing.
    At {
        /// Last time f is proven at or above the level, s (offset).
        t_lo: f64,
        /// First time f was found below it, s (offset).
        t_hi: f64,
    },
    /// Neither proven nor found: f comes within the evaluations' precision of the level near
    /// `t_lo` without an evaluation below it (or the budget ran out there).
    Unresolved {
        /// Start of the first sub-interval that could not be cleared, s (offset).
        t_lo: f64,
    },
}

/// The earliest time in [0, h] at which f < `level`, to `t_tol`.
///
/// Depth-first, left half first, over sub-intervals; a sub-interval whose bound is at or above
/// the level is cleared. `fa`, `fb` are f at 0 and h; `rate` bounds |f′|.
#[allow(clippy::too_many_arguments)] // the interval, its ends, the bound, and the stop rules
pub fn first_below(
    h: f64,
    fa: Bracket,
    fb: Bracket,
    rate: f64,
    level: f64,
    t_tol: f64,
    max_evals: u32,
    mut f: impl FnMut(f64) -> Bracket,
) -> Crossing {
    if fa.value < level {
        return Crossing::At {
            t_lo: 0.0,
            t_hi: 0.0,
        };
    }
    // Stack of pieces, rightmost at the bottom. `pending`: start of the first piece (at the
    // time tolerance) that could be neither cleared nor shown below the level — the crossing
    // is at or after it; the bracket returned starts there.
    let mut stack = vec![(0.0, fa, h, fb)];
    let mut evals = 0;
    let mut pending: Option<f64> = None;
    while let Some((a, fa, b, fb)) = stack.pop() {
        if interval_lower_bound(fa.lower, fb.lower, rate, b - a) >= level {
            continue;
        }
        if b - a <= t_tol {
            if fb.value < level {
                return Crossing::At {
                    t_lo: pending.unwrap_or(a),
                    t_hi: b,
                };
            }
            pending.get_or_insert(a);
            continue;
        }
        if evals >= max_evals {
            return Crossing::Unresolved {
                t_lo: pending.unwrap_or(a),
            };
        }
        let m = 0.5 * (a + b);
        let fm = f(m);
        evals += 1;
        stack.push((m, fm, b, fb));
        stack.push((a, fa, m, fm));
    }
    match pending {
        Some(t_lo) => Crossing::Unresolved { t_lo },
        None => Crossing::Never,
    }
}

/// Conservative advancement: the earliest offset t in [0, h] at which f can be at or below
/// `target`, stepping t ← t + (lower(t) − target)/rate, which never passes the first time f
/// reaches the target. Returns `None` when the steps leave the interval (proven: f > target
/// on [0, h]), else the offset reached and f there: its value is within `tol` of the target
/// (or below it), or its lower bound no longer allows a step (the evaluation's precision), or
/// `max_iter` steps were made (the offset is still before any crossing).
pub fn advance_to(
    h: f64,
    f0: Bracket,
    rate: f64,
    target: f64,
    tol: f64,
    max_iter: u32,
    mut f: impl FnMut(f64) -> Bracket,
) -> Option<(f64, Bracket)> {
    let (mut t, mut ft) = (0.0, f0);
    for _ in 0..max_iter {
        if ft.value <= target + tol || ft.lower <= target || rate <= 0.0 {
            break;
        }
        let step = (ft.lower - target) / rate;
        if t + step > h {
            return None;
        }
        t += step;
        ft = f(t);
    }
    if rate <= 0.0 && ft.lower > target {
        return None;
    }
    Some((t, ft))
}

#[cfg(test)]
mod tests {
    //! Checked against closed forms: the distance |t − t*|·v + d_min of a straight fly-by at
    //! speed v (a V-shaped function with slope exactly v), and sin t.
    use super::*;

    /// f(t) = 1 + 0.2·|t − 0.5| on [0, 1] (minimum 1 at t = 0.5, rate 0.2), every sample
    /// bracketed 1e-3 wide: a threshold 1e-4 under the minimum (inside
    /// [`provable_tolerance`], 2e-3) is never cleared and the search spends its whole budget; a
    /// threshold the provable tolerance under it is cleared within a few evaluations.
    #[test]
    fn a_tolerance_finer_than_the_brackets_is_never_proved() {
        let f = |t: f64| Bracket {
            value: 1.0 + 0.2 * (t - 0.5).abs(),
            lower: 1.0 + 0.2 * (t - 0.5).abs() - 1e-3,
        };
        let (fa, fb) = (f(0.0), f(1.0));
        let tol = provable_tolerance(&fa, &fb);
        assert!((tol - 2e-3).abs() < 1e-12);
        let fine = minimize(1.0, fa, fb, 0.2, |v| v - 1e-4, 256, 1e-12, f);
        assert!(fine.exhausted && fine.evals == 256, "{fine:?}");
        let provable = minimize(1.0, fa, fb, 0.2, |v| v - tol, 256, 1e-12, f);
        assert!(!provable.exhausted && provable.evals < 16, "{provable:?}");
        assert!(provable.lower <= 1.0 && provable.value >= 1.0);
    }

    fn vee(t: f64) -> Bracket {
        Bracket::exact((t - 0.37).abs() * 2.0 + 0.5)
    }

    #[test]
    fn minimize_finds_an_interior_minimum() {
        let r = minimize(
            1.0,
            vee(0.0),
            vee(1.0),
            2.0,
            |best| best - 1e-9,
            200,
            1e-12,
            vee,
        );
        assert!((r.value - 0.5).abs() < 2e-9, "{r:?}");
        assert!(r.lower <= 0.5 && r.lower > 0.5 - 2e-9, "{r:?}");
        assert!(!r.exhausted);
    }

    #[test]
    fn minimize_stops_at_once_when_the_bound_clears() {
        // f between 10 and 11 with rate 1 on a width of 0.1: bound 10.45 > threshold 5.
        let r = minimize(
            0.1,
            Bracket::exact(10.0),
            Bracket::exact(11.0),
            1.0,
            |_| 5.0,
            10,
            1e-12,
            |_| panic!("no evaluation needed"),
        );
        assert_eq!(r.evals, 0);
        assert!(r.lower >= 5.0);
    }

    #[test]
    fn minimize_by_lets_a_far_fast_piece_clear_on_its_own_bound() {
        // f = min(f₁, f₂): f₁ = 10 + 50·sin(40t) (far, |f₁′| ≤ 2000), f₂ = 1 + 0.1·t (near,
        // |f₂′| ≤ 0.1) on [0, 0.01]. With one rate (2000) the bound (2·1 − 20)/2 forces
        // bisection; with per-piece rates f₂'s (1 + 1.001 − 0.001)/2 = 1 clears 1 − 1e-3 and
        // f₁'s (10 + 10.1 − 20)/2 > 1 does too: no evaluation. The true minimum, 1 at t = 0,
        // is inside [lower, value].
        let f = |t: f64| [10.0 + 50.0 * (40.0 * t).sin(), 1.0 + 0.1 * t];
        let rates = [2000.0, 0.1];
        let thr = |b: f64| b - 1e-3;
        let r = minimize_by(
            0.01,
            f(0.0),
            f(0.01),
            |s: &[f64; 2]| s[0].min(s[1]),
            |a: &[f64; 2], b: &[f64; 2], w: f64| {
                (0..2)
                    .map(|k| interval_lower_bound(a[k], b[k], rates[k], w))
                    .fold(f64::INFINITY, f64::min)
            },
            thr,
            100,
            1e-12,
            f,
        );
        assert_eq!(r.evals, 0, "{r:?}");
        assert!(r.lower <= 1.0 && r.value == 1.0, "{r:?}");
        let one = minimize(
            0.01,
            Bracket::exact(1.0),
            Bracket::exact(1.001),
            2000.0,
            thr,
            100,
            1e-12,
            |t| Bracket::exact(f(t)[0].min(f(t)[1])),
        );
        assert!(one.evals > 0, "{one:?}");
    }

    #[test]
    fn first_below_brackets_the_crossing() {
        // sin t drops below −0.5 first at 7π/6.
        let want = 7.0 * std::f64::consts::PI / 6.0;
        let f = |t: f64| Bracket::exact(t.sin());
        let c = first_below(4.0, f(0.0), f(4.0), 1.0, -0.5, 1e-9, 200, f);
        match c {
            Crossing::At { t_lo, t_hi } => {
                assert!(t_lo <= want && want <= t_hi && t_hi - t_lo <= 1e-9, "{c:?}");
            }
            _ => panic!("{c:?}"),
        }
        assert_eq!(
            first_below(4.0, f(0.0), f(4.0), 1.0, -1.5, 1e-9, 200, f),
            Crossing::Never
        );
    }

    #[test]
    fn advance_never_passes_the_first_contact() {
        // Head-on at 100 m/s from 0.4 m: contact at 0.004 s.
        let f = |t: f64| Bracket::exact(0.4 - 100.0 * t);
        let (t, ft) = advance_to(0.01, f(0.0), 100.0, 0.0, 1e-6, 50, f).expect("hits");
        assert!(t <= 0.004 && ft.value <= 1e-6, "{t} {ft:?}");
        // Receding: no contact.
        let g = |t: f64| Bracket::exact(0.4 + 10.0 * t);
        assert!(advance_to(0.01, g(0.0), 100.0, 0.0, 1e-6, 50, g).is_none());
    }
}
