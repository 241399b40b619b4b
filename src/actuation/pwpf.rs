//! Pulse-width pulse-frequency (PWPF) modulator: turns a continuous command into on/off
//! valve pulses. Xu, Wen, Wei (2019) §3.1 drive their cold-gas valves through PWPF, citing
//! Guglieri et al. (2014, their ref. 25) without giving its form or constants; the
//! standard form of the PWPF literature is used here.
//!
//! ```text
//!   r = F_cmd / F_max                (normalised command, dimensionless)
//!   T_m ḟ = K_m (r − U) − f          (first-order prefilter on the feedback error)
//!   U ∈ {−1, 0, +1}                  (Schmitt trigger: on when |f| ≥ U_on, off when |f| ≤ U_off)
//! ```
//!
//! **Discrete update (exact for a fixed step).** Each [`Pwpf::step`] first applies the trigger
//! to the current filter state `f_k` (giving the output `U_k` held over `[t_k, t_k + h)`),
//! then advances the filter exactly under zero-order-hold input `r_k` and output `U_k`:
//! `f_{k+1} = f_k e^{−h/T_m} + K_m (r_k − U_k)(1 − e^{−h/T_m})`. The only discretisation error
//! is that switching happens at step boundaries: every switching instant is late by less
//! than one step `h` (choose `h` ≪ the minimum pulse, e.g. 1 ms for the 14 ms of the
//! defaults).
//!
//! **Static characteristic** (constant r, steady limit cycle; `H = U_on − U_off`):
//! - dead zone `|r| < U_on/K_m` (no pulse ever),
//! - on-time  `T_on  = −T_m ln(1 − H/(U_on + K_m(1 − r)))`,
//! - off-time `T_off = −T_m ln(1 − H/(K_m r − U_off))`,
//! - duty cycle `D = T_on/(T_on + T_off)`, continuous firing for `r ≥ 1 + U_off/K_m`,
//! - minimum pulse (r just above the dead zone) `Δ_min = −T_m ln(1 − H/K_m)` ≈ 13.8 ms
//!   for the defaults.
//!
//! **Minimum on-time.** Real solenoid valves need a minimum opening; `min_on_time_s` (default
//! 0, i.e. off) holds a started pulse for at least that long. The paper gives no valve data.
//! The prefilter sees the held output, so the excess impulse of a held pulse is fed back: for
//! a small command and `min_on_time_s` ≫ Δ_min the modulator answers with alternating ±
//! pulses whose mean still tracks r. The output never reverses in one step (+1 → 0 → −1).

use serde::{Deserialize, Serialize};

/// PWPF constants. Typical values of the PWPF literature, our choice (the paper gives none):
/// K_m = 4.5, T_m = 0.2 s, U_on = 0.45, U_off = 0.15.
///
/// In a scene each field may be left out (the typical value is used).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct PwpfParams {
    /// Prefilter gain `K_m` (dimensionless).
    pub k_m: f64,
    /// Prefilter time constant `T_m` (s).
    pub t_m_s: f64,
    /// Schmitt trigger on-threshold `U_on` (dimensionless, > `u_off`).
    pub u_on: f64,
    /// Schmitt trigger off-threshold `U_off` (dimensionless, ≥ 0).
    pub u_off: f64,
    /// Valve minimum on-time (s): a started pulse lasts at least this long. 0 disables.
    pub min_on_time_s: f64,
}

impl Default for PwpfParams {
    fn default() -> Self {
        Self::typical()
    }
}

impl PwpfParams {
    /// Typical values of the PWPF literature: K_m = 4.5, T_m = 0.2 s, U_on = 0.45,
    /// U_off = 0.15, no minimum on-time.
    pub fn typical() -> Self {
        Self {
            k_m: 4.5,
            t_m_s: 0.2,
            u_on: 0.45,
            u_off: 0.15,
            min_on_time_s: 0.0,
        }
    }

    /// Checks the constants: `Err((field, message))`. K_m and T_m positive, 0 ≤ U_off < U_on <
    /// K_m (else no command could ever open the valve: the dead zone U_on/K_m would reach
    /// full scale), a finite minimum on-time ≥ 0.
    pub fn check(&self) -> Result<(), (String, String)> {
        let fin = |x: f64| x.is_finite();
        if !(fin(self.k_m) && self.k_m > 0.0) {
            return Err(("k_m".into(), format!("must be positive, got {}", self.k_m)));
        }
        if !(fin(self.t_m_s) && self.t_m_s > 0.0 && self.t_m_s <= 1e6) {
            return Err((
                "t_m_s".into(),
                format!("must be positive and at most 1e6 s, got {}", self.t_m_s),
            ));
        }
        if !(fin(self.u_off) && self.u_off >= 0.0) {
            return Err(("u_off".into(), format!("must be ≥ 0, got {}", self.u_off)));
        }
        if !(fin(self.u_on) && self.u_on > self.u_off && self.u_on < self.k_m) {
            return Err((
                "u_on".into(),
                format!(
                    "must exceed u_off ({}) and be below k_m ({}), got {}",
                    self.u_off, self.k_m, self.u_on
                ),
            ));
        }
        if !(fin(self.min_on_time_s) && (0.0..=1e6).contains(&self.min_on_time_s)) {
            return Err((
                "min_on_time_s".into(),
                format!("must be in [0, 1e6] s, got {}", self.min_on_time_s),
            ));
        }
        Ok(())
    }

    /// Dead zone of the normalised command, `U_on/K_m` (dimensionless).
    pub fn dead_zone(&self) -> f64 {
        self.u_on / self.k_m
    }

    /// Analytic minimum pulse width `−T_m ln(1 − (U_on − U_off)/K_m)` (s), ignoring
    /// `min_on_time_s`.
    pub fn min_pulse_width_s(&self) -> f64 {
        -self.t_m_s * (1.0 - (self.u_on - self.u_off) / self.k_m).ln()
    }

    /// Analytic steady on-time for a constant command `r` (s); `None` in the dead zone,
    /// `Some(inf)` when the valve stays open (`r ≥ 1 + U_off/K_m`). Uses |r| (symmetric).
    pub fn on_time_s(&self, r: f64) -> Option<f64> {
        let r = r.abs();
        if r < self.dead_zone() {
            return None;
        }
        let den = self.u_on + self.k_m * (1.0 - r);
        let x = 1.0 - (self.u_on - self.u_off) / den;
        if den <= 0.0 || x <= 0.0 {
            return Some(f64::INFINITY);
        }
        Some(-self.t_m_s * x.ln())
    }

    /// Analytic steady off-time for a constant command `r` (s); `None` in the dead zone.
    pub fn off_time_s(&self, r: f64) -> Option<f64> {
        let r = r.abs();
        if r <= self.dead_zone() {
            return None;
        }
        Some(-self.t_m_s * (1.0 - (self.u_on - self.u_off) / (self.k_m * r - self.u_off)).ln())
    }

    /// Analytic steady duty cycle `T_on/(T_on + T_off)` for a constant command (0 in the dead
    /// zone, 1 when saturated). Dimensionless, sign of r not applied.
    pub fn duty_cycle(&self, r: f64) -> f64 {
        match (self.on_time_s(r), self.off_time_s(r)) {
            (Some(on), Some(off)) if on.is_finite() => on / (on + off),
            (Some(_), _) => 1.0,
            _ => 0.0,
        }
    }
}

/// One PWPF channel: filter state and trigger output.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Pwpf {
    /// Constants.
    pub params: PwpfParams,
    /// Filter state `f` (dimensionless).
    pub f: f64,
    /// Trigger output `U` ∈ {−1, 0, +1} applied over the last step.
    pub u: i8,
    /// Time the current pulse has been on (s); 0 while off.
    pub on_elapsed_s: f64,
}

impl Pwpf {
    /// A channel at rest (f = 0, valve closed).
    pub fn new(params: PwpfParams) -> Self {
        Self {
            params,
            f: 0.0,
            u: 0,
            on_elapsed_s: 0.0,
        }
    }

    /// Reset to rest.
    pub fn reset(&mut self) {
        self.f = 0.0;
        self.u = 0;
        self.on_elapsed_s = 0.0;
    }

    /// Advance one fixed step `dt_s` (s) with normalised command `r` held over it; returns
    /// the output `U` ∈ {−1, 0, +1} to apply over `[t, t + dt_s)` (see the module doc for the
    /// order: trigger on the current state, then the exact filter update).
    pub fn step(&mut self, r: f64, dt_s: f64) -> i8 {
        self.advance(r, dt_s, true)
    }

    /// As [`Pwpf::step`] for a one-sided channel (a single jet, which can only push: r in
    /// [0, 1], the valve open or closed): the trigger never switches to −1, so a dip of the
    /// filter below −U_on (possible only when a step is not small against `T_m`) leaves the
    /// valve closed. For r ≥ 0 the static characteristic is the two-sided one's positive
    /// branch. Returns whether the valve is open over `[t, t + dt_s)`.
    pub fn step_one_sided(&mut self, r: f64, dt_s: f64) -> bool {
        self.advance(r, dt_s, false) > 0
    }

    fn advance(&mut self, r: f64, dt_s: f64, two_sided: bool) -> i8 {
        let p = &self.params;
        let hold = self.u != 0 && self.on_elapsed_s < p.min_on_time_s;
        let f = self.f;
        let next = match self.u {
            0 if f >= p.u_on => 1,
            0 if two_sided && f <= -p.u_on => -1,
            1 if f <= p.u_off && !hold => 0,
            -1 if f >= -p.u_off && !hold => 0,
            u => u,
        };
        if next != self.u {
            self.on_elapsed_s = 0.0;
        }
        self.u = next;
        let decay = (-dt_s / p.t_m_s).exp();
        self.f = f * decay + p.k_m * (r - next as f64) * (1.0 - decay);
        if next != 0 {
            self.on_elapsed_s += dt_s;
        }
        next
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Runs a constant command and returns the lengths (s) of complete on and off runs after
    /// the first pulse (transient dropped).
    fn pulse_train(p: &PwpfParams, r: f64, dt: f64, t_end: f64) -> (Vec<f64>, Vec<f64>) {
        let mut m = Pwpf::new(p.clone());
        let n = (t_end / dt).round() as usize;
        let (mut ons, mut offs) = (Vec::new(), Vec::new());
        let mut prev = 0;
        let mut run = 0usize;
        let mut started = false;
        for _ in 0..n {
            let u = m.step(r, dt);
            if u != prev {
                if started {
                    if prev != 0 {
                        ons.push(run as f64 * dt);
                    } else {
                        offs.push(run as f64 * dt);
                    }
                }
                started = true;
                run = 0;
                prev = u;
            }
            run += 1;
        }
        (ons, offs)
    }

    /// Reference: the closed-form minimum pulse width Δ_min = −T_m ln(1 − (U_on − U_off)/K_m) ≈
    /// 13.8 ms, and a simulated first pulse at r just above the dead zone. Each switching instant
    /// is quantised to the step, so a pulse width is within 2·dt of the analytic one (plus the 1e-3
    /// excess of r over the dead zone, which shortens it by ≈ 0.05 ms).
    #[test]
    fn val_pwpf_minimum_pulse_width() {
        let p = PwpfParams::typical();
        let dmin = p.min_pulse_width_s();
        assert!((dmin - (-0.2 * (1.0f64 - 0.3 / 4.5).ln())).abs() < 1e-15);
        assert!((dmin - 0.0138).abs() < 1e-4, "{dmin}");
        let dt = 1e-5;
        let r = p.dead_zone() * (1.0 + 1e-3);
        let (ons, _) = pulse_train(&p, r, dt, 6.0);
        assert!(!ons.is_empty());
        let analytic = p.on_time_s(r).unwrap();
        assert!((analytic - dmin).abs() < 1e-4);
        for on in &ons {
            assert!((on - analytic).abs() <= 2.0 * dt, "{on} vs {analytic}");
        }
        // Dead zone: no pulse at all below U_on/K_m.
        let mut m = Pwpf::new(p.clone());
        for _ in 0..200_000 {
            assert_eq!(m.step(p.dead_zone() * 0.999, 1e-4), 0);
        }
    }

    /// Reference: the analytic limit-cycle on/off times and duty cycle (module doc) at
    /// several commands, both signs.
    #[test]
    fn val_pwpf_static_characteristic() {
        let p = PwpfParams::typical();
        let dt = 1e-5;
        for r in [0.2, 0.5, 0.8, -0.5, 1.0] {
            let (ons, offs) = pulse_train(&p, r, dt, 2.0);
            let (on_a, off_a) = (p.on_time_s(r).unwrap(), p.off_time_s(r).unwrap());
            assert!(ons.len() >= 3 && offs.len() >= 3, "r={r}");
            // Switching is detected at step ends, so f overshoots a threshold by up to
            // |ḟ|·dt, which the next phase must undo at its own slope: a phase length is off
            // by at most dt·(1 + |ḟ_before|/|ḟ_after|) at its start threshold, slopes
            // |ḟ| = |target − f|/T_m with targets K_m r (off) and K_m(r − 1) (on).
            let ra = r.abs();
            let slope = |target: f64, f: f64| (target - f).abs() / p.t_m_s;
            let on_tol = dt * (2.0 + slope(p.k_m * ra, p.u_on) / slope(p.k_m * (ra - 1.0), p.u_on));
            let off_tol =
                dt * (2.0 + slope(p.k_m * (ra - 1.0), p.u_off) / slope(p.k_m * ra, p.u_off));
            for on in &ons {
                assert!((on - on_a).abs() <= on_tol, "r={r}: on {on} vs {on_a}");
            }
            for off in &offs {
                assert!(
                    (off - off_a).abs() <= off_tol,
                    "r={r}: off {off} vs {off_a}"
                );
            }
            // Sign follows r: average output over whole periods equals ±D.
            let mut m = Pwpf::new(p.clone());
            let n = (20.0 / dt) as usize;
            let mut sum = 0.0;
            for _ in 0..n {
                sum += m.step(r, dt) as f64;
            }
            let avg = sum / n as f64;
            // Over 20 s the partial first period and transient bias the mean by at most
            // (T_on + T_off + first-pulse delay)/20 s ≈ 1 %.
            assert!(
                (avg - r.signum() * p.duty_cycle(r)).abs() < 0.01,
                "r={r}: {avg}"
            );
        }
        // Saturation: r ≥ 1 + U_off/K_m keeps the valve open after the first switch-on.
        assert_eq!(p.on_time_s(1.05), Some(f64::INFINITY));
        assert_eq!(p.duty_cycle(1.05), 1.0);
        assert_eq!(p.duty_cycle(0.05), 0.0);
    }

    /// Exactness of the fixed-step filter update: between switches, one step of h equals two
    /// steps of h/2 (semigroup property of the exact exponential solution).
    #[test]
    fn invariant_pwpf_exact_discretisation() {
        let p = PwpfParams::typical();
        let mut a = Pwpf::new(p.clone());
        let mut b = Pwpf::new(p.clone());
        a.f = 0.1;
        b.f = 0.1;
        for _ in 0..10 {
            a.step(0.05, 0.02);
            b.step(0.05, 0.01);
            b.step(0.05, 0.01);
            assert_eq!(a.u, 0);
            assert!((a.f - b.f).abs() < 1e-15);
        }
        // And it equals the closed form f(t) = K_m r + (f0 − K_m r) e^{−t/T_m}.
        let t: f64 = 0.2;
        let exact = 4.5 * 0.05 + (0.1 - 4.5 * 0.05) * (-t / 0.2).exp();
        assert!((a.f - exact).abs() < 1e-14);
    }

    /// The minimum on-time holds every pulse open for at least that long.
    #[test]
    fn invariant_pwpf_min_on_time() {
        let p = PwpfParams {
            min_on_time_s: 0.05,
            ..PwpfParams::typical()
        };
        let dt = 1e-4;
        let (ons, offs) = pulse_train(&p, 0.15, dt, 10.0);
        assert!(!ons.is_empty() && !offs.is_empty());
        for on in ons {
            assert!(on >= 0.05 - 0.5 * dt, "{on}");
        }
    }
}
