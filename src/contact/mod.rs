//! Compliant contact (f64, Bevy-free): the force laws a docking interface is given in its scene,
//! the relation between their damping and a coefficient of restitution, and the closed forms of
//! a single impact that the tests and the documentation use ([`closed_form`]).
//!
//! # The model
//! A contact of penetration depth δ ≥ 0 (m) closing at δ̇ (m/s, positive while the bodies
//! approach) carries the normal force
//!
//! ```text
//! elastic part             F_e = k·δⁿ         n = 1 (Linear, k in N/m) or 3/2 (Hertz, k in N/m^1.5)
//! Restitution(e)           F = F_e·(1 + λ·δ̇), λ = x(e)/v₀        (Hunt–Crossley 1975, x(e) the exact
//!                                                                 root below)
//! LankaraniNikravesh(e)    F = F_e·(1 + λ·δ̇), λ = 3(1 − e²)/(4·v₀) (Lankarani and Nikravesh 1990)
//! HuntCrossley(d)          F = F_e·(1 + d·δ̇)                     (d in s/m, as Drake's dissipation)
//! Dashpot(c)               F = F_e + c·δ̇                         (Kelvin–Voigt, c in N·s/m)
//! ```
//!
//! clamped at F ≥ 0 (contacts push, never pull). v₀ is the normal approach speed when the contact
//! began (floored at [`CompliantSpec::min_impact_speed_m_s`], since λ grows without bound for a
//! contact that starts at rest). A Hunt–Crossley contact hit at v₀ leaves at e·v₀ where, with
//! x = λ·v₀, −e·x − ln(1 − e·x) = x − ln(1 + x) whatever k and n ([`closed_form`]); `Restitution`
//! solves it for x, so the restitution is the one asked for. The Lankarani–Nikravesh λ is its
//! first-order approximation in (1 − e): it gives e = 0.848 when 0.8 is asked and 0.68 for 0.5
//! (`tests/val_contact_compliance.rs` measures both).
//!
//! Friction is Coulomb's law, |F_t| ≤ μ·F_n against the sliding velocity, applied so that it
//! never reverses the slip within one integration sub-step (`crate::sim::contact_model`).
//!
//! # Defaults (a docking interface without a `contact` field)
//! Hertz with k = 2.3e9 N/m^1.5 and e = 0.8. Where they come from:
//! - k = (4/3)·E*·√R, Hertz's sphere-on-plane constant (Johnson, *Contact Mechanics*, 1985,
//!   eq. 4.23), with E* = E/(2(1 − ν²)) = 38.7 GPa for aluminium alloy 6061-T6 on itself
//!   (E = 68.9 GPa, ν = 0.33: the ASM handbook values) and R = 2 mm, our choice for the edge
//!   radius of the cone's tip ring and of the funnel's rim, the features that meet first.
//! - e = 0.8: our choice. Below the yield velocity of an aluminium-alloy contact,
//!   v_Y = (26·Y⁵/(E*⁴·ρ))^½ ≈ 0.08 m/s (Johnson 1985, §11.4, with Y = 276 MPa and
//!   ρ = 2700 kg/m³), an impact is elastic and e is close to 1; 0.8 leaves room for structural
//!   losses and stays where the Lankarani–Nikravesh λ is accurate. A real mechanism's value
//!   comes from its drop or pendulum tests: set it in the scene.

pub mod closed_form;
pub mod dock_state;
pub mod platform;

use serde::{Deserialize, Serialize};

/// The contact model of a docking interface (`docking.contact` in a scene).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub enum ContactModelSpec {
    /// rapier's rigid contact: impulses that stop the approach within one step (restitution
    /// from the bodies' `restitution`, combined by the average; 0 by default). Its peak force is
    /// impulse/dt, a property of the step, not of the mechanism.
    Rigid,
    /// Compliant contact computed by rpod from parry's contact manifolds, sub-stepped while the
    /// cone touches the slot.
    Compliant(CompliantSpec),
}

impl Default for ContactModelSpec {
    fn default() -> Self {
        ContactModelSpec::Compliant(CompliantSpec::default())
    }
}

/// A compliant contact law.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CompliantSpec {
    /// The elastic part, F_e = k·δⁿ.
    pub law: LawSpec,
    /// The dissipative part.
    pub dissipation: DissipationSpec,
    /// Integration sub-steps per period of the contact oscillation (at the stiffest the step
    /// can reach); 40 keeps the peak force within 0.5 % of the converged value.
    #[serde(default = "substeps_per_period")]
    pub substeps_per_period: u32,
    /// Floor on the impact speed v₀ in the Lankarani–Nikravesh damping λ = 3(1 − e²)/(4·v₀),
    /// m/s: a contact that starts slower is damped as if it had started at this speed.
    #[serde(default = "min_impact_speed")]
    pub min_impact_speed_m_s: f64,
}

fn substeps_per_period() -> u32 {
    40
}

fn min_impact_speed() -> f64 {
    1e-3
}

impl Default for CompliantSpec {
    fn default() -> Self {
        CompliantSpec {
            law: LawSpec::Hertz {
                stiffness_n_m1_5: DEFAULT_HERTZ_STIFFNESS_N_M1_5,
            },
            dissipation: DissipationSpec::Restitution(DEFAULT_RESTITUTION),
            substeps_per_period: substeps_per_period(),
            min_impact_speed_m_s: min_impact_speed(),
        }
    }
}

/// The default Hertz constant, N/m^1.5: (4/3)·E*·√R for aluminium 6061-T6 on itself
/// (E* = 38.7 GPa) and a 2 mm edge radius (see the module docs).
pub const DEFAULT_HERTZ_STIFFNESS_N_M1_5: f64 = 2.3e9;

/// The default coefficient of restitution (our choice; see the module docs).
pub const DEFAULT_RESTITUTION: f64 = 0.8;

/// The elastic part of a compliant contact.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub enum LawSpec {
    /// F_e = k·δ.
    Linear {
        /// k, N/m.
        stiffness_n_m: f64,
    },
    /// F_e = k·δ^{3/2} (Hertz; for a sphere of radius R on a plane k = (4/3)·E*·√R).
    Hertz {
        /// k, N/m^1.5.
        stiffness_n_m1_5: f64,
    },
}

/// The dissipative part of a compliant contact.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub enum DissipationSpec {
    /// A coefficient of restitution e ∈ [0.01, 1], through Hunt–Crossley damping with the λ
    /// that gives exactly e (the root x(e) of the exact relation, λ = x/v₀).
    Restitution(f64),
    /// A coefficient of restitution e ∈ [0.01, 1], through Hunt–Crossley damping with the
    /// Lankarani–Nikravesh λ = 3(1 − e²)/(4·v₀) (accurate only near e = 1).
    LankaraniNikravesh(f64),
    /// Hunt–Crossley with a fixed dissipation d: F = k·δⁿ·(1 + d·δ̇).
    HuntCrossley {
        /// d, s/m.
        dissipation_s_m: f64,
    },
    /// A linear dashpot in parallel with the spring: F = k·δⁿ + c·δ̇ (Kelvin–Voigt for n = 1).
    Dashpot {
        /// c, N·s/m.
        damping_n_s_m: f64,
    },
}

/// A compliant contact law, ready to evaluate.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Law {
    /// k, N/mⁿ.
    pub k: f64,
    /// n (1 or 1.5).
    pub n: f64,
    /// Dissipation.
    pub dissipation: DissipationSpec,
    /// Floor on v₀, m/s.
    pub min_impact_speed_m_s: f64,
    /// λ·v₀ of the Hunt–Crossley dissipation (0 for a dashpot or a fixed d).
    pub x: f64,
}

impl Law {
    /// From the scene's description.
    pub fn from_spec(s: &CompliantSpec) -> Self {
        let (k, n) = match s.law {
            LawSpec::Linear { stiffness_n_m } => (stiffness_n_m, 1.0),
            LawSpec::Hertz { stiffness_n_m1_5 } => (stiffness_n_m1_5, 1.5),
        };
        let x = match s.dissipation {
            DissipationSpec::Restitution(e) => hunt_crossley_x(e),
            DissipationSpec::LankaraniNikravesh(e) => 3.0 * (1.0 - e * e) / 4.0,
            _ => 0.0,
        };
        Law {
            k,
            n,
            dissipation: s.dissipation,
            min_impact_speed_m_s: s.min_impact_speed_m_s,
            x,
        }
    }

    /// The elastic force k·δⁿ, N (0 for δ ≤ 0).
    pub fn elastic_n(&self, depth_m: f64) -> f64 {
        if depth_m <= 0.0 {
            0.0
        } else if self.n == 1.0 {
            self.k * depth_m
        } else {
            self.k * depth_m * depth_m.sqrt()
        }
    }

    /// Hunt–Crossley factor λ (s/m) of a contact that began closing at `impact_speed_m_s`, or
    /// the fixed d; 0 for a dashpot.
    pub fn hunt_crossley_lambda(&self, impact_speed_m_s: f64) -> f64 {
        match self.dissipation {
            DissipationSpec::Restitution(_) | DissipationSpec::LankaraniNikravesh(_) => {
                self.x / impact_speed_m_s.max(self.min_impact_speed_m_s)
            }
            DissipationSpec::HuntCrossley { dissipation_s_m } => dissipation_s_m,
            DissipationSpec::Dashpot { .. } => 0.0,
        }
    }

    /// Normal force, N (≥ 0): depth δ (m), closing rate δ̇ (m/s, positive approaching), and the
    /// approach speed at the start of the contact (m/s).
    pub fn normal_force_n(&self, depth_m: f64, closing_m_s: f64, impact_speed_m_s: f64) -> f64 {
        if depth_m <= 0.0 {
            return 0.0;
        }
        self.normal_force_unclamped_n(depth_m, closing_m_s, impact_speed_m_s)
            .max(0.0)
    }

    /// The law's value before the clamp at 0 (negative when the damping would pull: the
    /// surfaces have separated), N; for δ > 0.
    pub fn normal_force_unclamped_n(
        &self,
        depth_m: f64,
        closing_m_s: f64,
        impact_speed_m_s: f64,
    ) -> f64 {
        let fe = self.elastic_n(depth_m);
        match self.dissipation {
            DissipationSpec::Dashpot { damping_n_s_m } => fe + damping_n_s_m * closing_m_s,
            _ => fe * (1.0 + self.hunt_crossley_lambda(impact_speed_m_s) * closing_m_s),
        }
    }

    /// The unclamped normal force with the damping taken implicitly over an impulse of
    /// duration `h` acting on effective mass `m` (kg) along the normal: the closing rate in the
    /// damping term is the one at the end of that impulse, δ̇ − F·h/m, which the force then
    /// solves for (F = F_e(1 + λδ̇)/(1 + F_e·λ·h/m), or (F_e + cδ̇)/(1 + c·h/m) for a dashpot).
    /// Unconditionally stable however stiff the damping (a contact that starts at rest has
    /// λ = x/v₀ with v₀ at its floor); it tends to [`Law::normal_force_unclamped_n`] as h → 0. N;
    /// for δ > 0.
    pub fn normal_force_implicit_n(
        &self,
        depth_m: f64,
        closing_m_s: f64,
        impact_speed_m_s: f64,
        m: f64,
        h: f64,
    ) -> f64 {
        let fe = self.elastic_n(depth_m);
        let w = if m.is_finite() && m > 0.0 { h / m } else { 0.0 };
        match self.dissipation {
            DissipationSpec::Dashpot { damping_n_s_m: c } => (fe + c * closing_m_s) / (1.0 + c * w),
            _ => {
                let l = self.hunt_crossley_lambda(impact_speed_m_s);
                fe * (1.0 + l * closing_m_s) / (1.0 + fe * l * w)
            }
        }
    }

    /// Local stiffness dF_e/dδ at depth δ, N/m.
    pub fn local_stiffness_n_m(&self, depth_m: f64) -> f64 {
        if self.n == 1.0 {
            self.k
        } else {
            self.n * self.k * depth_m.max(0.0).powf(self.n - 1.0)
        }
    }

    /// Damping coefficient dF/dδ̇ at depth δ, N·s/m.
    pub fn damping_n_s_m(&self, depth_m: f64, impact_speed_m_s: f64) -> f64 {
        match self.dissipation {
            DissipationSpec::Dashpot { damping_n_s_m } => damping_n_s_m,
            _ => self.hunt_crossley_lambda(impact_speed_m_s) * self.elastic_n(depth_m),
        }
    }

    /// A bound on the depth a contact can reach, m, with effective mass `m` (kg) closing at `v`
    /// (m/s) and pressed by a held force `f_held` (N). From the undamped energy balance
    /// k·δ^{n+1}/(n+1) = ½·m·v² + f_held·δ (damping only lowers the depth): each term alone
    /// gives δ_v = ((n+1)·½mv²/k)^{1/(n+1)} and δ_f = ((n+1)·f_held/k)^{1/n}, and the root lies
    /// below δ_v + δ_f; the sum is doubled as a margin for the step's other contacts.
    pub fn depth_bound_m(&self, m: f64, v: f64, f_held: f64) -> f64 {
        let e = 0.5 * m * v * v;
        let d_kin = ((self.n + 1.0) * e / self.k).powf(1.0 / (self.n + 1.0));
        let d_held = ((self.n + 1.0) * f_held.max(0.0) / self.k).powf(1.0 / self.n);
        2.0 * (d_kin + d_held)
    }
}

/// The x = λ·v₀ for which a Hunt–Crossley contact has the coefficient of restitution e: the
/// root in (0, 1/e) of x − ln(1 + x) = −e·x − ln(1 − e·x) (bisection to 1e-15; 0 for e ≥ 1).
pub fn hunt_crossley_x(e: f64) -> f64 {
    if e >= 1.0 {
        return 0.0;
    }
    let e = e.max(1e-6);
    // φ(x) > 0 near 0 and → −∞ as x → 1/e.
    let phi = |x: f64| x - (1.0 + x).ln() + e * x + (1.0 - e * x).ln();
    let (mut lo, mut hi) = (0.0, 1.0 / e);
    for _ in 0..300 {
        let mid = 0.5 * (lo + hi);
        if phi(mid) > 0.0 {
            lo = mid;
        } else {
            hi = mid;
        }
        if hi - lo < 1e-15 * hi.max(1.0) {
            break;
        }
    }
    0.5 * (lo + hi)
}

/// The Lankarani–Nikravesh hysteresis factor λ = 3(1 − e²)/(4·v₀), s/m (Lankarani and
/// Nikravesh, *J. Mech. Des.* 112, 1990): the Hunt–Crossley damping that dissipates the kinetic
/// energy a coefficient of restitution e removes from an impact at v₀.
pub fn lankarani_nikravesh_lambda(e: f64, v0_m_s: f64) -> f64 {
    3.0 * (1.0 - e * e) / (4.0 * v0_m_s)
}

/// Checks a compliant law's numbers; `Err(field, message)` names the offending field (relative
/// to the `Compliant(...)` value).
pub fn validate(s: &CompliantSpec) -> Result<(), (&'static str, String)> {
    let finite_pos = |v: f64| v.is_finite() && v > 0.0;
    match s.law {
        LawSpec::Linear { stiffness_n_m: k }
        | LawSpec::Hertz {
            stiffness_n_m1_5: k,
        } if !(finite_pos(k) && k <= 1e15) => {
            return Err((
                "law",
                format!("stiffness must be a positive number up to 1e15, got {k}"),
            ));
        }
        _ => {}
    }
    match s.dissipation {
        DissipationSpec::Restitution(e) | DissipationSpec::LankaraniNikravesh(e)
            if !(e.is_finite() && (0.01..=1.0).contains(&e)) =>
        {
            return Err((
                "dissipation",
                format!(
                    "a Hunt–Crossley coefficient of restitution lies in [0.01, 1] (e → 0 needs unbounded damping), got {e}"
                ),
            ));
        }
        DissipationSpec::HuntCrossley { dissipation_s_m: d }
            if !(d.is_finite() && (0.0..=1e6).contains(&d)) =>
        {
            return Err((
                "dissipation",
                format!("dissipation_s_m must lie in [0, 1e6] s/m, got {d}"),
            ));
        }
        DissipationSpec::Dashpot { damping_n_s_m: c }
            if !(c.is_finite() && (0.0..=1e12).contains(&c)) =>
        {
            return Err((
                "dissipation",
                format!("damping_n_s_m must lie in [0, 1e12] N·s/m, got {c}"),
            ));
        }
        _ => {}
    }
    if !(8..=10_000).contains(&s.substeps_per_period) {
        return Err((
            "substeps_per_period",
            format!("must lie in [8, 10000], got {}", s.substeps_per_period),
        ));
    }
    if !(s.min_impact_speed_m_s.is_finite() && s.min_impact_speed_m_s > 0.0) {
        return Err((
            "min_impact_speed_m_s",
            format!("must be a positive speed, got {}", s.min_impact_speed_m_s),
        ));
    }
    Ok(())
}

/// A one-line description of a contact model for outputs, e.g.
/// `compliant: Hertz k = 2.3e9 N/m^1.5, restitution 0.8 (Hunt–Crossley, Lankarani–Nikravesh)`.
pub fn describe(m: &ContactModelSpec) -> String {
    match m {
        ContactModelSpec::Rigid => {
            "rigid (rapier impulses; peak force = impulse/dt depends on the step)".into()
        }
        ContactModelSpec::Compliant(s) => {
            let law = match s.law {
                LawSpec::Linear { stiffness_n_m } => format!("linear k = {stiffness_n_m:e} N/m"),
                LawSpec::Hertz { stiffness_n_m1_5 } => {
                    format!("Hertz k = {stiffness_n_m1_5:e} N/m^1.5")
                }
            };
            let diss = match s.dissipation {
                DissipationSpec::Restitution(e) => format!(
                    "restitution {e} (Hunt–Crossley, exact λ = {:.6}/v₀, v₀ ≥ {} m/s)",
                    hunt_crossley_x(e),
                    s.min_impact_speed_m_s
                ),
                DissipationSpec::LankaraniNikravesh(e) => format!(
                    "restitution {e} asked (Hunt–Crossley, Lankarani–Nikravesh λ = 3(1 − e²)/(4 v₀), v₀ ≥ {} m/s)",
                    s.min_impact_speed_m_s
                ),
                DissipationSpec::HuntCrossley { dissipation_s_m } => {
                    format!("Hunt–Crossley d = {dissipation_s_m} s/m")
                }
                DissipationSpec::Dashpot { damping_n_s_m } => {
                    format!("dashpot c = {damping_n_s_m} N·s/m")
                }
            };
            format!("compliant: {law}, {diss}")
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn invariant_force_is_never_tensile() {
        let law = Law::from_spec(&CompliantSpec {
            law: LawSpec::Linear { stiffness_n_m: 1e5 },
            dissipation: DissipationSpec::Dashpot { damping_n_s_m: 1e4 },
            ..Default::default()
        });
        // Separating fast at a small depth: k·δ + c·δ̇ < 0 is clamped to 0.
        assert_eq!(law.normal_force_n(1e-4, -1.0, 1.0), 0.0);
        assert_eq!(law.normal_force_n(-1e-3, 1.0, 1.0), 0.0);
        assert!((law.normal_force_n(1e-3, 0.0, 1.0) - 100.0).abs() < 1e-9);
    }

    #[test]
    fn invariant_lankarani_nikravesh_vanishes_for_elastic_impact() {
        assert_eq!(lankarani_nikravesh_lambda(1.0, 0.1), 0.0);
        // e = 0.5 at 1 m/s: λ = 3·0.75/4 = 0.5625 s/m.
        assert!((lankarani_nikravesh_lambda(0.5, 1.0) - 0.5625).abs() < 1e-15);
    }

    /// The exact x(e) satisfies the Hunt–Crossley relation of [`closed_form`], and the
    /// Lankarani–Nikravesh x = 3(1 − e²)/4 is its limit as e → 1.
    #[test]
    fn val_hunt_crossley_x_inverts_the_exact_relation() {
        for e in [0.05, 0.2, 0.5, 0.8, 0.95, 0.999] {
            let x = hunt_crossley_x(e);
            let back = closed_form::hunt_crossley_restitution(x, 1.0);
            assert!((back - e).abs() < 1e-9, "e {e}: x {x} gives {back}");
        }
        let e = 0.999;
        let ln = 3.0 * (1.0 - e * e) / 4.0;
        assert!((hunt_crossley_x(e) / ln - 1.0).abs() < 2e-3);
    }

    #[test]
    fn invariant_validation_names_the_field() {
        let bad = CompliantSpec {
            dissipation: DissipationSpec::Restitution(1.5),
            ..Default::default()
        };
        assert_eq!(validate(&bad).unwrap_err().0, "dissipation");
        let bad = CompliantSpec {
            law: LawSpec::Hertz {
                stiffness_n_m1_5: f64::INFINITY,
            },
            ..Default::default()
        };
        assert_eq!(validate(&bad).unwrap_err().0, "law");
        assert!(validate(&CompliantSpec::default()).is_ok());
    }
}
