//! Distribution functions for the statistics rpod states: the regularized incomplete beta and
//! gamma functions, their quantiles, the one-sided Clopper–Pearson lower bound of a success
//! probability and the zero-failure number of runs.
//!
//! # Methods
//! - ln Γ: Lanczos (g = 7, 9 coefficients; relative error below 1e-15 for x > 0).
//! - I_x(a, b) (regularized incomplete beta): the continued fraction of Numerical Recipes
//!   (§6.4, modified Lentz), on the side x < (a+1)/(a+b+2) where it converges fast, the symmetry
//!   I_x(a, b) = 1 − I_{1−x}(b, a) otherwise.
//! - P(a, x) (regularized lower incomplete gamma): its series for x < a + 1, the continued
//!   fraction of Q = 1 − P otherwise (Numerical Recipes §6.2).
//! - Quantiles: bisection on the monotone distribution function to 1e-14 of the bracket (no
//!   starting guess that could miss a root).

/// ln Γ(x) for x > 0 (Lanczos, g = 7).
pub fn ln_gamma(x: f64) -> f64 {
    const G: f64 = 7.0;
    const C: [f64; 9] = [
        0.999_999_999_999_809_9,
        676.520_368_121_885_1,
        -1_259.139_216_722_402_8,
        771.323_428_777_653_1,
        -176.615_029_162_140_6,
        12.507_343_278_686_905,
        -0.138_571_095_265_720_12,
        9.984_369_578_019_572e-6,
        1.505_632_735_149_311_6e-7,
    ];
    if x < 0.5 {
        // Reflection: Γ(x)Γ(1−x) = π / sin(πx).
        let s = (std::f64::consts::PI * x).sin().abs();
        return std::f64::consts::PI.ln() - s.ln() - ln_gamma(1.0 - x);
    }
    let x = x - 1.0;
    let mut a = C[0];
    let t = x + G + 0.5;
    for (i, c) in C.iter().enumerate().skip(1) {
        a += c / (x + i as f64);
    }
    0.5 * (2.0 * std::f64::consts::PI).ln() + (x + 0.5) * t.ln() - t + a.ln()
}

/// Continued fraction of the incomplete beta (modified Lentz).
fn beta_cf(a: f64, b: f64, x: f64) -> f64 {
    const TINY: f64 = 1e-300;
    let (qab, qap, qam) = (a + b, a + 1.0, a - 1.0);
    let mut c = 1.0;
    let mut d = 1.0 - qab * x / qap;
    if d.abs() < TINY {
        d = TINY;
    }
    d = 1.0 / d;
    let mut h = d;
    for m in 1..10_000 {
        let m = m as f64;
        let m2 = 2.0 * m;
        let aa = m * (b - m) * x / ((qam + m2) * (a + m2));
        d = 1.0 + aa * d;
        if d.abs() < TINY {
            d = TINY;
        }
        c = 1.0 + aa / c;
        if c.abs() < TINY {
            c = TINY;
        }
        d = 1.0 / d;
        h *= d * c;
        let aa = -(a + m) * (qab + m) * x / ((a + m2) * (qap + m2));
        d = 1.0 + aa * d;
        if d.abs() < TINY {
            d = TINY;
        }
        c = 1.0 + aa / c;
        if c.abs() < TINY {
            c = TINY;
        }
        d = 1.0 / d;
        let del = d * c;
        h *= del;
        if (del - 1.0).abs() < 1e-16 {
            break;
        }
    }
    h
}

/// The regularized incomplete beta function I_x(a, b) (a, b > 0, x in [0, 1]): the
/// distribution function of the Beta(a, b) law.
pub fn beta_cdf(x: f64, a: f64, b: f64) -> f64 {
    if x <= 0.0 {
        return 0.0;
    }
    if x >= 1.0 {
        return 1.0;
    }
    let ln_front = ln_gamma(a + b) - ln_gamma(a) - ln_gamma(b) + a * x.ln() + b * (1.0 - x).ln();
    let front = ln_front.exp();
    if x < (a + 1.0) / (a + b + 2.0) {
        front * beta_cf(a, b, x) / a
    } else {
        1.0 - front * beta_cf(b, a, 1.0 - x) / b
    }
}

/// Bisection for the root of an increasing `f − target` on [lo, hi].
fn bisect(f: impl Fn(f64) -> f64, target: f64, mut lo: f64, mut hi: f64) -> f64 {
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if f(mid) < target {
            lo = mid;
        } else {
            hi = mid;
        }
        if hi - lo <= 1e-14 * hi.abs().max(1e-300) {
            break;
        }
    }
    0.5 * (lo + hi)
}

/// The q-quantile of Beta(a, b): the x with I_x(a, b) = q.
pub fn beta_quantile(q: f64, a: f64, b: f64) -> f64 {
    if q <= 0.0 {
        return 0.0;
    }
    if q >= 1.0 {
        return 1.0;
    }
    bisect(|x| beta_cdf(x, a, b), q, 0.0, 1.0)
}

/// The regularized lower incomplete gamma function P(a, x) (a > 0, x ≥ 0).
pub fn gamma_p(a: f64, x: f64) -> f64 {
    if x <= 0.0 {
        return 0.0;
    }
    let ln_front = -x + a * x.ln() - ln_gamma(a);
    if x < a + 1.0 {
        let (mut ap, mut sum) = (a, 1.0 / a);
        let mut del = sum;
        for _ in 0..100_000 {
            ap += 1.0;
            del *= x / ap;
            sum += del;
            if del.abs() < sum.abs() * 1e-16 {
                break;
            }
        }
        sum * ln_front.exp()
    } else {
        const TINY: f64 = 1e-300;
        let mut b = x + 1.0 - a;
        let mut c = 1.0 / TINY;
        let mut d = 1.0 / b;
        let mut h = d;
        for i in 1..100_000 {
            let an = -(i as f64) * (i as f64 - a);
            b += 2.0;
            d = an * d + b;
            if d.abs() < TINY {
                d = TINY;
            }
            c = b + an / c;
            if c.abs() < TINY {
                c = TINY;
            }
            d = 1.0 / d;
            let del = d * c;
            h *= del;
            if (del - 1.0).abs() < 1e-16 {
                break;
            }
        }
        1.0 - ln_front.exp() * h
    }
}

/// The distribution function of the chi-square law with `k` degrees of freedom at `x`.
pub fn chi2_cdf(x: f64, k: f64) -> f64 {
    gamma_p(0.5 * k, 0.5 * x)
}

/// The q-quantile of the chi-square law with `k` degrees of freedom.
pub fn chi2_quantile(q: f64, k: f64) -> f64 {
    if q <= 0.0 {
        return 0.0;
    }
    // The quantile lies below k + 40·√(2k) + 100 for every q < 1 − 1e-15.
    let hi = k + 40.0 * (2.0 * k).sqrt() + 100.0;
    bisect(|x| chi2_cdf(x, k), q.min(1.0 - 1e-15), 0.0, hi)
}

/// The one-sided exact (Clopper–Pearson) lower confidence bound of a success probability after
/// `successes` of `n` independent trials, at confidence `c` (in (0, 1)): the largest p such that
/// P(X ≥ successes | p) ≤ 1 − c, i.e. the (1 − c)-quantile of Beta(s, n − s + 1); 0 with no
/// success. With no failure (s = n) it is (1 − c)^(1/n) in closed form.
pub fn clopper_pearson_lower(successes: usize, n: usize, c: f64) -> f64 {
    if n == 0 || successes == 0 {
        return 0.0;
    }
    let s = successes.min(n);
    if s == n {
        return (1.0 - c).powf(1.0 / n as f64);
    }
    beta_quantile(1.0 - c, s as f64, (n - s + 1) as f64)
}

/// The number of failure-free runs that show a success probability of at least `p` at
/// confidence `c`: the smallest n with p^n ≤ 1 − c, n = ⌈ln(1 − c) / ln p⌉ (None unless p and c
/// are in (0, 1)).
pub fn zero_failure_runs(p: f64, c: f64) -> Option<u64> {
    if !(p > 0.0 && p < 1.0 && c > 0.0 && c < 1.0) {
        return None;
    }
    let n = ((1.0 - c).ln() / p.ln()).ceil();
    // Rounding of the quotient: step to the smallest n that truly satisfies p^n ≤ 1 − c.
    let mut n = n.max(1.0) as u64;
    while n > 1 && p.powf((n - 1) as f64) <= 1.0 - c {
        n -= 1;
    }
    while p.powf(n as f64) > 1.0 - c {
        n += 1;
    }
    Some(n)
}

#[cfg(test)]
mod tests {
    //! References: tabulated values (Γ at integers and ½; chi-square quantiles from Abramowitz &
    //! Stegun table 26.8 / NIST e-handbook 1.3.6.7.4, 3 decimals; binomial lower bounds from the
    //! closed forms of the beta law with integer parameters: I_x(s, 1) = x^s, and
    //! I_x(1, b) = 1 − (1 − x)^b), and the zero-failure closed form.
    use super::*;

    #[test]
    fn ln_gamma_at_known_points() {
        for (x, g) in [(1.0, 1.0), (2.0, 1.0), (5.0, 24.0), (10.0, 362_880.0)] {
            assert!((ln_gamma(x) - f64::ln(g)).abs() < 1e-13, "{x}");
        }
        assert!((ln_gamma(0.5) - std::f64::consts::PI.sqrt().ln()).abs() < 1e-13);
    }

    /// Beta(s, 1) has I_x = x^s; Beta(1, b) has I_x = 1 − (1 − x)^b: their quantiles in closed
    /// form, to 1e-12.
    #[test]
    fn beta_quantile_closed_forms() {
        for s in [1.0, 3.0, 20.0, 852.0] {
            for q in [0.05, 0.1, 0.5] {
                let x: f64 = beta_quantile(q, s, 1.0);
                assert!((x - q.powf(1.0 / s)).abs() < 1e-12, "s {s} q {q}: {x}");
            }
        }
        for b in [2.0, 7.0, 100.0] {
            let x = beta_quantile(0.1, 1.0, b);
            assert!(
                (x - (1.0 - 0.9f64.powf(1.0 / b))).abs() < 1e-12,
                "b {b}: {x}"
            );
        }
    }

    /// Clopper–Pearson lower bounds against published values: 0 failures in n → (1 − c)^(1/n);
    /// 1 failure in 20 at 95 %: 0.7839 (the 0.05-quantile of Beta(19, 2), tabulated e.g. in the
    /// exact binomial tables; cross-checked here by its closed form I_x(19, 2) = 20x¹⁹ − 19x²⁰).
    #[test]
    fn clopper_pearson_lower_bounds() {
        assert!((clopper_pearson_lower(852, 852, 0.9) - 0.1f64.powf(1.0 / 852.0)).abs() < 1e-15);
        let x = clopper_pearson_lower(19, 20, 0.95);
        let cdf = 20.0 * x.powi(19) - 19.0 * x.powi(20);
        assert!((cdf - 0.05).abs() < 1e-12, "I_x(19,2) at the bound: {cdf}");
        assert!((x - 0.7839).abs() < 5e-5, "{x}");
        assert_eq!(clopper_pearson_lower(0, 10, 0.9), 0.0);
        // The bound never exceeds the observed proportion, and grows with confidence falling.
        assert!(clopper_pearson_lower(90, 100, 0.95) < clopper_pearson_lower(90, 100, 0.5));
        assert!(clopper_pearson_lower(90, 100, 0.5) < 0.9);
    }

    /// n = ⌈ln(1 − c)/ln p⌉: 0.9973 at 90 % → 852; 0.99 at 95 % → 299; 0.9 at 90 % → 22.
    #[test]
    fn zero_failure_run_counts() {
        assert_eq!(zero_failure_runs(0.9973, 0.90), Some(852));
        assert_eq!(zero_failure_runs(0.99, 0.95), Some(299));
        assert_eq!(zero_failure_runs(0.9, 0.9), Some(22));
        assert_eq!(zero_failure_runs(1.0, 0.9), None);
        // Consistency: n failure-free runs give a lower bound ≥ p, n − 1 do not.
        for (p, c) in [(0.9973, 0.9), (0.99, 0.95), (0.95, 0.99)] {
            let n = zero_failure_runs(p, c).expect("valid") as usize;
            assert!(clopper_pearson_lower(n, n, c) >= p);
            assert!(clopper_pearson_lower(n - 1, n - 1, c) < p);
        }
    }

    /// Chi-square quantiles against the table (3 decimals).
    #[test]
    fn chi2_quantiles_tabulated() {
        for (q, k, want) in [
            (0.975, 6.0, 14.449),
            (0.025, 6.0, 1.237),
            (0.995, 3.0, 12.838),
            (0.005, 3.0, 0.072),
            (0.95, 100.0, 124.342),
            (0.05, 100.0, 77.929),
        ] {
            let x = chi2_quantile(q, k);
            assert!((x - want).abs() < 1.5e-3, "q {q} k {k}: {x} vs {want}");
        }
    }
}
