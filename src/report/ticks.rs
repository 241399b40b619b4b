//! Axis ticks: "nice" linear steps (1, 2, 2.5, 5 × 10^k) and decade ticks for log axes, with
//! fixed, deterministic label formatting.

/// One tick: position in data units (for log axes, the data value, not its logarithm), and
/// its label (empty for unlabelled minor ticks).
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Tick {
    pub value: f64,
    pub label: String,
    pub major: bool,
}

/// The nice step (1, 2, 2.5 or 5 × 10^k) closest above `raw`.
pub(crate) fn nice_step(raw: f64) -> f64 {
    if !(raw.is_finite() && raw > 0.0) {
        return 1.0;
    }
    let mag = 10f64.powf(raw.log10().floor());
    let m = raw / mag;
    let nice = if m <= 1.0 {
        1.0
    } else if m <= 2.0 {
        2.0
    } else if m <= 2.5 {
        2.5
    } else if m <= 5.0 {
        5.0
    } else {
        10.0
    };
    nice * mag
}

/// Formats `v` for a tick grid of spacing `step`: enough decimals to tell ticks apart, plain
/// notation for 1e-3 ≤ |v| < 1e5, otherwise `1.5e−4` style; every minus sign is the Unicode
/// minus U+2212 (typographic, the width of a plus), as in every rpod figure.
pub(crate) fn format_tick(v: f64, step: f64) -> String {
    format_tick_ascii(v, step).replace('-', "\u{2212}")
}

fn format_tick_ascii(v: f64, step: f64) -> String {
    let v = if v.abs() < step * 1e-6 { 0.0 } else { v };
    let big = v.abs().max(step);
    if big >= 1e5 || step < 1e-3 {
        if v == 0.0 {
            return "0".to_owned();
        }
        // Mantissa digits: enough to resolve `step` relative to v's magnitude.
        let e = v.abs().log10().floor();
        let digits = ((e - step.log10().floor()).max(0.0) as usize).min(6);
        let s = format!("{v:.digits$e}");
        return s;
    }
    // The fewest decimals that write the step exactly (0.25 → 2, 25 → 0, 0.1 → 1).
    let decimals = (0..=12)
        .find(|&d| {
            let s = step * 10f64.powi(d);
            (s - s.round()).abs() <= 1e-6 * s.max(1.0)
        })
        .unwrap_or(12) as usize;
    format!("{v:.decimals$}")
}

/// Linear ticks inside [lo, hi] (inclusive with a small tolerance), about `target` of them and
/// never fewer than three: a nice step rounded up from span/target can leave a single tick (just
/// "0") on a short axis, which gives the reader no scale, so the step shrinks until three fit.
pub(crate) fn linear_ticks(lo: f64, hi: f64, target: usize) -> Vec<Tick> {
    let mut target = target.max(2);
    loop {
        let ticks = linear_ticks_once(lo, hi, target);
        if ticks.is_empty() || ticks.len() >= 3 || target >= 12 {
            return ticks;
        }
        target += 1;
    }
}

fn linear_ticks_once(lo: f64, hi: f64, target: usize) -> Vec<Tick> {
    let span = hi - lo;
    if !(span.is_finite() && span > 0.0) {
        return Vec::new();
    }
    let step = nice_step(span / target as f64);
    let first = (lo / step - 1e-9).ceil() as i64;
    let last = (hi / step + 1e-9).floor() as i64;
    (first..=last)
        .map(|k| {
            let v = k as f64 * step;
            Tick {
                value: v,
                label: format_tick(v, step),
                major: true,
            }
        })
        .collect()
}

fn superscript(n: i32) -> String {
    const SUP: [char; 10] = ['⁰', '¹', '²', '³', '⁴', '⁵', '⁶', '⁷', '⁸', '⁹'];
    let mut s = String::new();
    if n < 0 {
        s.push('⁻');
    }
    for d in n.unsigned_abs().to_string().bytes() {
        s.push(SUP[usize::from(d - b'0')]);
    }
    s
}

/// Ticks for a log10 axis over [lo, hi] (both > 0): decades labelled `10ⁿ`, minor ticks at
/// 2..9 × 10ⁿ when the axis spans ≤ 6 decades; when fewer than two decades lie inside, the
/// 2× and 5× ticks are labelled too.
pub(crate) fn log_ticks(lo: f64, hi: f64) -> Vec<Tick> {
    if !(lo > 0.0 && hi > lo && hi.is_finite()) {
        return Vec::new();
    }
    let (a, b) = (lo.log10(), hi.log10());
    let (k0, k1) = ((a - 1e-9).floor() as i32, (b + 1e-9).ceil() as i32);
    let decades = b - a;
    let every = ((decades / 8.0).ceil() as i32).max(1);
    let inside = |v: f64| v.log10() >= a - 1e-9 && v.log10() <= b + 1e-9;
    let majors_inside = (k0..=k1).filter(|&k| inside(10f64.powi(k))).count();
    let mut out = Vec::new();
    for k in k0..=k1 {
        let base = 10f64.powi(k);
        if inside(base) && k.rem_euclid(every) == 0 {
            out.push(Tick {
                value: base,
                label: format!("10{}", superscript(k)),
                major: true,
            });
        }
        if decades <= 6.0 {
            for m in 2..=9 {
                let v = f64::from(m) * base;
                if inside(v) {
                    let label = if majors_inside < 2 && (m == 2 || m == 5) {
                        format_tick(v, base)
                    } else {
                        String::new()
                    };
                    out.push(Tick {
                        value: v,
                        major: !label.is_empty(),
                        label,
                    });
                }
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Reference: the 1-2-2.5-5 sequence by hand.
    #[test]
    fn invariant_nice_steps_and_labels() {
        assert_eq!(nice_step(0.13), 0.2);
        assert_eq!(nice_step(2.2), 2.5);
        assert_eq!(nice_step(3.0), 5.0);
        assert_eq!(nice_step(700.0), 1000.0);
        let t: Vec<String> = linear_ticks(-0.05, 1.05, 5)
            .into_iter()
            .map(|t| t.label)
            .collect();
        // span 1.1 / 5 = 0.22 → step 0.25, which needs two decimals.
        assert_eq!(t, ["0.00", "0.25", "0.50", "0.75", "1.00"]);
        let t: Vec<String> = linear_ticks(0.0, 100.0, 4)
            .into_iter()
            .map(|t| t.label)
            .collect();
        assert_eq!(t, ["0", "25", "50", "75", "100"]);
        // span 34 / 3 = 11.3 → step 20 leaves only "0" inside ±17; the step shrinks to 10.
        let t: Vec<String> = linear_ticks(-17.0, 17.0, 3)
            .into_iter()
            .map(|t| t.label)
            .collect();
        assert_eq!(t, ["\u{2212}10", "0", "10"]);
        assert_eq!(format_tick(2.5e-5, 5e-6), "2.5e\u{2212}5");
        assert_eq!(format_tick(-1e-12, 0.1), "0.0");
        assert_eq!(format_tick(7.0e6, 1e6), "7e6");
    }

    #[test]
    fn invariant_log_ticks_label_decades() {
        let t = log_ticks(1e-4, 1e2);
        let labels: Vec<&str> = t
            .iter()
            .filter(|t| t.major)
            .map(|t| t.label.as_str())
            .collect();
        assert_eq!(
            labels,
            ["10⁻⁴", "10⁻³", "10⁻²", "10⁻¹", "10⁰", "10¹", "10²"]
        );
        assert!(
            t.iter()
                .all(|t| t.value >= 1e-4 * (1.0 - 1e-9) && t.value <= 1e2 * (1.0 + 1e-9))
        );
        // Less than a decade: 2× and 5× labelled.
        let t = log_ticks(1.5, 9.0);
        let labels: Vec<&str> = t
            .iter()
            .filter(|t| t.major)
            .map(|t| t.label.as_str())
            .collect();
        assert_eq!(labels, ["2", "5"]);
    }
}
