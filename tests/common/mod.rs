//! Closed forms shared by the integration tests (each test file that uses them names them in
//! its own `//!` header).

use rpod::control::generic::glideslope::Profile;

/// The closed-loop motion of a glideslope flown by a critically damped PD (ω, ζ = 1) with
/// exact CW cancellation and reference feed-forward, along V-bar, from rest at range
/// r_f + d₀: the range error e = s − s_ref obeys ë + 2ωė + ω²e = 0 between the reference's two
/// velocity steps (its start, −d₀/τ or −v, and its arrival, +v_min), so
/// e(t) = v₀ t e^{−ωt} − v_end (t − t_end) e^{−ω(t − t_end)} (the second term after t_end).
pub struct GlideslopeLoop {
    /// The profile.
    pub profile: Profile,
    /// d₀, m.
    pub d0: f64,
    /// ω, rad/s.
    pub omega: f64,
    /// The reference's initial speed, m/s.
    pub v0: f64,
    /// The reference's arrival time, s.
    pub t_end: f64,
    /// The reference's speed just before arrival, m/s.
    pub v_end: f64,
}

impl GlideslopeLoop {
    /// The loop for a profile from d₀.
    pub fn new(profile: Profile, d0: f64, omega: f64) -> Self {
        let v0 = -profile.at(d0, 0.0).1;
        // Arrival: the first time the profile reaches d = 0 (found by bisection on the closed form).
        let (mut lo, mut hi) = (0.0, 1e7);
        for _ in 0..200 {
            let mid = 0.5 * (lo + hi);
            if profile.at(d0, mid).0 > 0.0 {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        let v_end = -profile.at(d0, lo).1;
        Self {
            profile,
            d0,
            omega,
            v0,
            t_end: hi,
            v_end,
        }
    }

    /// (e, ė, ë) at t.
    pub fn error(&self, t: f64) -> (f64, f64, f64) {
        let w = self.omega;
        let f = |v: f64, t: f64| {
            if t <= 0.0 {
                return (0.0, 0.0, 0.0);
            }
            let x = (-w * t).exp();
            (v * t * x, v * (1.0 - w * t) * x, v * w * (w * t - 2.0) * x)
        };
        let a = f(self.v0, t);
        let b = f(-self.v_end, t - self.t_end);
        (a.0 + b.0, a.1 + b.1, a.2 + b.2)
    }

    /// (range − r_f, range rate, range acceleration) of the plant at t.
    pub fn plant(&self, t: f64) -> (f64, f64, f64) {
        let (d, dd, ddd) = self.profile.at(self.d0, t);
        let (e, ed, edd) = self.error(t);
        (d + e, dd + ed, ddd + edd)
    }

    /// ∫₀ᵀ |a| dt with a = (2n ṡ, −s̈, 0) (V-bar: the CW command that keeps x = 0), by the
    /// midpoint rule at `h` s.
    pub fn delta_v(&self, n: f64, t_s: f64, h: f64) -> f64 {
        let mut dv = 0.0;
        let mut t = 0.0;
        while t < t_s {
            let (_, sd, sdd) = self.plant(t + 0.5 * h);
            dv += ((2.0 * n * sd).powi(2) + sdd * sdd).sqrt() * h;
            t += h;
        }
        // The reference's steps are smooth in the plant: no impulses left to add.
        dv
    }
}
