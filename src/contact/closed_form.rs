//! Closed forms of a single normal impact of a mass m arriving at speed v on a compliant
//! contact (the other side fixed, or m the reduced mass of two free bodies): the references of
//! `tests/val_contact_compliance.rs` and of the documented defaults.
//!
//! - Linear spring, F = k·δ: peak force v·√(k·m), peak depth v·√(m/k), contact duration
//!   π·√(m/k), restitution 1.
//! - Kelvin–Voigt, F = max(0, k·δ + c·δ̇), damping ratio ζ = c/(2√(k·m)) < 1: with ω = √(k/m),
//!   ω_d = ω√(1 − ζ²) and δ(t) = (v/ω_d)·e^{−ζωt}·sin(ω_d t), the force is
//!   F(t) = m·v·ω·e^{−ζωt}·sin(ω_d t + 2·asin ζ)/√(1 − ζ²); it vanishes (the bodies separate, the
//!   dashpot would pull) at ω_d·t_s = π − 2·asin ζ, where δ̇ = −v·e^{−ζωt_s}, so
//!   e = exp(−ζ(π − 2 asin ζ)/√(1 − ζ²)); the peak is at ω_d·t_p = π/2 − 3·asin ζ (ζ < ½) with
//!   F_p = m·v·ω·e^{−ζωt_p}, or at t = 0 with F_p = c·v (ζ ≥ ½). (Schwager and Pöschel,
//!   *Phys. Rev. E* 78, 2008, derive the same contact end.)
//! - Hertz, F = k·δ^{3/2}: δ_max = (5mv²/(4k))^{2/5}, F_max = k·δ_max^{3/2}, duration
//!   (2δ_max/v)·∫₀¹(1 − x^{5/2})^{−½}dx = (2δ_max/v)·(2/5)·B(2/5, ½) = 2.94328·δ_max/v
//!   (Johnson, *Contact Mechanics*, 1985, §11.2).
//! - Hunt–Crossley, F = k·δⁿ·(1 + λ·δ̇): along the trajectory m·u·du/(1 + λu) = −k·δⁿ·dδ, so
//!   u/λ − ln(1 + λu)/λ² takes the same value when the contact starts (u = v) and ends
//!   (u = −e·v): with x = λ·v, −e·x − ln(1 − e·x) = x − ln(1 + x), whatever k and n. This
//!   exact relation ([`hunt_crossley_restitution`]) is what the Lankarani–Nikravesh λ
//!   approximates to first order in (1 − e).

use std::f64::consts::PI;

/// The Hertz impact duration factor (2/5)·B(2/5, ½)·2 = 2.9432751843…, so that the duration is
/// this × δ_max / v.
pub const HERTZ_DURATION_FACTOR: f64 = 2.943_275_184_324_705;

/// What a single impact does.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Impact {
    /// Largest normal force, N.
    pub peak_force_n: f64,
    /// Largest depth, m.
    pub peak_depth_m: f64,
    /// Time in contact, s.
    pub duration_s: f64,
    /// Separation speed over approach speed.
    pub restitution: f64,
}

/// Undamped linear spring k (N/m), mass m (kg), approach speed v (m/s).
pub fn linear(m: f64, k: f64, v: f64) -> Impact {
    Impact {
        peak_force_n: v * (k * m).sqrt(),
        peak_depth_m: v * (m / k).sqrt(),
        duration_s: PI * (m / k).sqrt(),
        restitution: 1.0,
    }
}

/// Linear spring k (N/m) and dashpot c (N·s/m) in parallel, force clamped at ≥ 0; needs
/// ζ = c/(2√(km)) < 1 (`None` otherwise).
pub fn kelvin_voigt(m: f64, k: f64, c: f64, v: f64) -> Option<Impact> {
    let w = (k / m).sqrt();
    let z = c / (2.0 * (k * m).sqrt());
    if !(0.0..1.0).contains(&z) {
        return None;
    }
    let s = (1.0 - z * z).sqrt();
    let wd = w * s;
    let t_s = (PI - 2.0 * z.asin()) / wd;
    let f_p = if z < 0.5 {
        let t_p = (PI / 2.0 - 3.0 * z.asin()) / wd;
        m * v * w * (-z * w * t_p).exp()
    } else {
        c * v
    };
    let t_m = z.acos() / wd;
    Some(Impact {
        peak_force_n: f_p,
        peak_depth_m: v / wd * (-z * w * t_m).exp() * (wd * t_m).sin(),
        duration_s: t_s,
        restitution: (-z * w * t_s).exp(),
    })
}

/// Undamped Hertz contact k (N/m^1.5), mass m (kg), approach speed v (m/s).
pub fn hertz(m: f64, k: f64, v: f64) -> Impact {
    let d = (5.0 * m * v * v / (4.0 * k)).powf(0.4);
    Impact {
        peak_force_n: k * d.powf(1.5),
        peak_depth_m: d,
        duration_s: HERTZ_DURATION_FACTOR * d / v,
        restitution: 1.0,
    }
}

/// The exact coefficient of restitution of a Hunt–Crossley contact F = k·δⁿ(1 + λ·δ̇) hit at
/// speed v: the root e ∈ (0, 1] of −e·x − ln(1 − e·x) = x − ln(1 + x), x = λ·v (bisection
/// to 1e-14).
pub fn hunt_crossley_restitution(lambda_s_m: f64, v: f64) -> f64 {
    let x = lambda_s_m * v;
    if x <= 0.0 {
        return 1.0;
    }
    let rhs = x - (1.0 + x).ln();
    // g(e) = −e·x − ln(1 − e·x) grows from 0 at e = 0 to +∞ as e·x → 1.
    let g = |e: f64| -e * x - (1.0 - e * x).ln();
    let (mut lo, mut hi) = (0.0, (1.0 / x).min(1.0));
    if g(hi) <= rhs {
        return hi;
    }
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if g(mid) < rhs {
            lo = mid;
        } else {
            hi = mid;
        }
        if hi - lo < 1e-14 {
            break;
        }
    }
    0.5 * (lo + hi)
}

/// The dashpot c (N·s/m) that gives a Kelvin–Voigt contact (k, m) the restitution e ∈ (0, 1]:
/// the inverse of [`kelvin_voigt`]'s restitution, by bisection on ζ ∈ [0, 1).
pub fn kelvin_voigt_damping_for_restitution(m: f64, k: f64, e: f64) -> f64 {
    let rest = |z: f64| (-z * (PI - 2.0 * z.asin()) / (1.0 - z * z).sqrt()).exp();
    let (mut lo, mut hi) = (0.0f64, 1.0 - 1e-12);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if rest(mid) > e {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    2.0 * (0.5 * (lo + hi)) * (k * m).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The Hertz factor against a midpoint-rule quadrature of ∫₀¹(1 − x^{5/2})^{−½}dx after the
    /// substitution x = 1 − s² (which removes the end singularity).
    #[test]
    fn val_hertz_duration_factor_by_quadrature() {
        let n = 200_000;
        let mut sum = 0.0;
        for i in 0..n {
            let s = (i as f64 + 0.5) / n as f64;
            let x: f64 = 1.0 - s * s;
            sum += 2.0 * s / (1.0 - x.powf(2.5)).sqrt() / n as f64;
        }
        assert!(
            (2.0 * sum - HERTZ_DURATION_FACTOR).abs() < 1e-6,
            "{}",
            2.0 * sum
        );
    }

    /// Kelvin–Voigt closed forms against an RK4 integration of m·δ̈ = −max(0, kδ + cδ̇) at
    /// 1e-7 s steps.
    #[test]
    fn val_kelvin_voigt_against_rk4() {
        let (m, k, v): (f64, f64, f64) = (2.0, 1e5, 0.3);
        for z in [0.05, 0.3, 0.6] {
            let c = 2.0 * z * (k * m).sqrt();
            let cf = kelvin_voigt(m, k, c, v).unwrap();
            let acc = |x: f64, u: f64| -(k * x + c * u).max(0.0) / m;
            let (mut x, mut u, mut t, h) = (0.0f64, v, 0.0f64, 1e-7);
            let (mut fp, mut xp) = (0.0f64, 0.0f64);
            loop {
                let f = (k * x + c * u).max(0.0);
                fp = fp.max(f);
                xp = xp.max(x);
                if t > 0.0 && f <= 0.0 {
                    break;
                }
                let (k1x, k1u) = (u, acc(x, u));
                let (k2x, k2u) = (u + k1u * h / 2.0, acc(x + k1x * h / 2.0, u + k1u * h / 2.0));
                let (k3x, k3u) = (u + k2u * h / 2.0, acc(x + k2x * h / 2.0, u + k2u * h / 2.0));
                let (k4x, k4u) = (u + k3u * h, acc(x + k3x * h, u + k3u * h));
                x += (k1x + 2.0 * k2x + 2.0 * k3x + k4x) * h / 6.0;
                u += (k1u + 2.0 * k2u + 2.0 * k3u + k4u) * h / 6.0;
                t += h;
            }
            assert!(
                (fp - cf.peak_force_n).abs() < 1e-4 * cf.peak_force_n,
                "ζ {z}: peak {fp} vs {}",
                cf.peak_force_n
            );
            assert!(
                (xp - cf.peak_depth_m).abs() < 1e-5 * cf.peak_depth_m,
                "ζ {z}: depth"
            );
            assert!(
                (t - cf.duration_s).abs() < 2e-7 + 1e-5 * cf.duration_s,
                "ζ {z}: duration {t} vs {}",
                cf.duration_s
            );
            assert!(
                (-u / v - cf.restitution).abs() < 1e-5,
                "ζ {z}: e {} vs {}",
                -u / v,
                cf.restitution
            );
            let c_back = kelvin_voigt_damping_for_restitution(m, k, cf.restitution);
            assert!((c_back - c).abs() < 1e-6 * c);
        }
    }

    #[test]
    fn val_hunt_crossley_restitution_limits() {
        // No damping: elastic. Small x: e ≈ 1 − 2x/3 (the expansion behind Lankarani–Nikravesh:
        // x = 3(1 − e²)/4 ≈ 3(1 − e)/2).
        assert_eq!(hunt_crossley_restitution(0.0, 1.0), 1.0);
        let x = 1e-3;
        let e = hunt_crossley_restitution(x, 1.0);
        assert!((e - (1.0 - 2.0 * x / 3.0)).abs() < 1e-6, "{e}");
        // Monotone in x.
        assert!(hunt_crossley_restitution(0.5, 1.0) > hunt_crossley_restitution(1.0, 1.0));
    }
}
