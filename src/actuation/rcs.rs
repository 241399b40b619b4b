//! Three-dimensional reaction-control jets (`Rcs` actuator): a layout of jets (position,
//! thrust direction, maximum thrust, minimum impulse bit, plume cone), the allocation of a
//! commanded body-frame force and torque to non-negative jet thrusts, and the per-jet
//! accounting (on-time, impulse, firings, propellant). Bevy-free, f64.
//!
//! **Allocation.** With B the 6 × n matrix whose column j is jet j's wrench per newton,
//! (d_j, r_j × d_j) (r_j from the centre of mass, body frame), the thrusts solve
//!
//! ```text
//!   minimise ½‖B u − w‖²  subject to  0 ≤ u_j ≤ F_max,j
//! ```
//!
//! by cyclic coordinate descent (each jet in turn set to its exact one-dimensional minimiser,
//! clamped to its bounds) until the Karush–Kuhn–Tucker conditions hold to
//! [`KKT_REL_TOL`] of ‖w‖ or [`MAX_SWEEPS`] sweeps. The problem is convex, so this is the
//! least-error allocation: exact (residual 0) wherever w is reachable, the least-squares
//! wrench otherwise; the result is *saturated* when the residual is non-zero. Descent starts
//! from zero thrusts, so no jet fires that the command does not need.
//!
//! **Minimum impulse bit.** Within a step of length dt a jet fires at full thrust for
//! t_on = u·dt/F_max; an impulse I = u·dt below the jet's minimum impulse bit I_min is not
//! available: it is rounded to I_min when I ≥ I_min/2, else to 0 (the applied wrench is the
//! rounded one).
//!
//! **PWPF (optional).** With `pwpf: Some(…)` on the actuator, each jet's allocated thrust u_j is
//! not applied as a mean thrust: its normalised command r_j = u_j/F_max,j drives the jet's own
//! one-sided pulse-width pulse-frequency modulator ([`super::pwpf`]), whose output opens the
//! valve at full thrust for whole steps. The minimum impulse bit is then honoured by the valve's
//! minimum on-time, max(`min_on_time_s`, I_min/F_max) (every pulse delivers at least I_min),
//! not by the per-step rounding above. The steady average thrust for a constant demand is
//! F_max·D(r), D the modulator's duty cycle ([`super::pwpf::PwpfParams::duty_cycle`]).
//!
//! **Firing pulses.** A pulse is a run of consecutive steps in which the jet delivers an
//! impulse; it is counted in `firings` when it starts and reported (optionally, as a
//! `jet_pulse` event) when it ends, with its steps, impulse and on-time.
//!
//! **Propellant.** Σ I_j / (I_sp g₀).

use nalgebra::{Vector3, Vector6};
use serde::{Deserialize, Serialize};

/// KKT tolerance of the allocation, relative to ‖w‖ (and to 1 N when w = 0).
pub const KKT_REL_TOL: f64 = 1e-12;
/// Most coordinate-descent sweeps per allocation.
pub const MAX_SWEEPS: usize = 20_000;

/// A jet's plume: a cone from the nozzle along the exhaust (−thrust direction).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PlumeSpec {
    /// Half-angle of the cone, deg (0 < α < 90).
    pub half_angle_deg: f64,
    /// Length of the cone along the exhaust, m.
    pub length_m: f64,
}

/// One jet, as written in a scene.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct JetSpec {
    /// Name, unique in the layout.
    pub name: String,
    /// Nozzle position relative to the centre of mass, body frame, m.
    pub pos_m: [f64; 3],
    /// Thrust direction (the force on the vehicle; normalised on load), body frame.
    pub direction: [f64; 3],
    /// Maximum thrust, N (> 0).
    pub max_thrust_n: f64,
    /// Minimum impulse bit, N·s (0: none).
    #[serde(default)]
    pub min_impulse_bit_ns: f64,
    /// Plume cone (for plume keep-off checks).
    #[serde(default)]
    pub plume: Option<PlumeSpec>,
}

impl JetSpec {
    /// Unit thrust direction.
    pub fn dir(&self) -> Vector3<f64> {
        Vector3::from(self.direction).normalize()
    }
    /// Wrench per newton of thrust: (force, torque about the centre of mass), body frame.
    pub fn column(&self) -> Vector6<f64> {
        let d = self.dir();
        let t = Vector3::from(self.pos_m).cross(&d);
        Vector6::new(d.x, d.y, d.z, t.x, t.y, t.z)
    }
}

/// Checks a jet layout: `Err((field relative to the layout, message))`.
pub fn validate_jets(jets: &[JetSpec], isp_s: f64) -> Result<(), (String, String)> {
    if jets.is_empty() || jets.len() > 256 {
        return Err(("jets".into(), "from 1 to 256 jets".into()));
    }
    if !(isp_s.is_finite() && isp_s > 0.0 && isp_s < 1e5) {
        return Err((
            "isp_s".into(),
            format!("must be positive and below 1e5 s, got {isp_s}"),
        ));
    }
    for (k, j) in jets.iter().enumerate() {
        let at = |f: &str| format!("jets.{k}.{f}");
        if j.name.is_empty() || jets[..k].iter().any(|o| o.name == j.name) {
            return Err((
                at("name"),
                format!("`{}`: empty or duplicate jet name", j.name),
            ));
        }
        if !j.pos_m.iter().all(|x| x.is_finite() && x.abs() <= 1e3) {
            return Err((at("pos_m"), "must be finite, within 1 km".into()));
        }
        let n = Vector3::from(j.direction).norm();
        if !(n.is_finite() && n > 1e-9) {
            return Err((at("direction"), "must be a non-zero direction".into()));
        }
        if !(j.max_thrust_n.is_finite() && j.max_thrust_n > 0.0 && j.max_thrust_n <= 1e6) {
            return Err((
                at("max_thrust_n"),
                format!("must be positive and at most 1e6 N, got {}", j.max_thrust_n),
            ));
        }
        if !(j.min_impulse_bit_ns.is_finite() && j.min_impulse_bit_ns >= 0.0) {
            return Err((at("min_impulse_bit_ns"), "must be finite and ≥ 0".into()));
        }
        if let Some(p) = j.plume
            && !(p.half_angle_deg > 0.0
                && p.half_angle_deg < 90.0
                && p.length_m.is_finite()
                && p.length_m > 0.0
                && p.length_m <= 1e4)
        {
            return Err((
                at("plume"),
                "half_angle_deg must be in (0, 90) and length_m in (0, 1e4]".into(),
            ));
        }
    }
    Ok(())
}

/// The thrusts allocated to a wrench.
#[derive(Debug, Clone, PartialEq)]
pub struct Allocation {
    /// Thrust per jet, N, in [0, F_max].
    pub thrust_n: Vec<f64>,
    /// The wrench they give, body frame: (force N, torque N·m).
    pub achieved: Vector6<f64>,
    /// ‖B u − w‖ (N and N·m mixed, as the least-squares problem weighs them).
    pub residual: f64,
    /// The command could not be met exactly (residual above the tolerance).
    pub saturated: bool,
}

/// Allocates the body-frame wrench `w` = (force, torque about the centre of mass) to the jets
/// (see the module docs).
pub fn allocate(jets: &[JetSpec], w: &Vector6<f64>) -> Allocation {
    let cols: Vec<Vector6<f64>> = jets.iter().map(JetSpec::column).collect();
    let n = jets.len();
    let mut u = vec![0.0; n];
    let mut r = *w; // w − B u
    let tol = KKT_REL_TOL * w.norm().max(1.0);
    for _ in 0..MAX_SWEEPS {
        let mut worst: f64 = 0.0;
        for j in 0..n {
            let c = &cols[j];
            let cc = c.norm_squared();
            if cc == 0.0 {
                continue;
            }
            let g = c.dot(&r); // −∂/∂u_j of ½‖r‖²
            // KKT violation of jet j before its update (the projected gradient).
            let v = if u[j] <= 0.0 {
                g.max(0.0)
            } else if u[j] >= jets[j].max_thrust_n {
                (-g).max(0.0)
            } else {
                g.abs()
            };
            let new = (u[j] + g / cc).clamp(0.0, jets[j].max_thrust_n);
            let du = new - u[j];
            if du != 0.0 {
                r -= c * du;
                u[j] = new;
            }
            worst = worst.max(v);
        }
        if worst <= tol {
            break;
        }
    }
    let achieved = w - r;
    let residual = r.norm();
    Allocation {
        thrust_n: u,
        achieved,
        residual,
        saturated: residual > 1e-9 * w.norm().max(1.0),
    }
}

/// The thrusts actually delivered over a step of `dt_s` after the minimum impulse bits (see
/// the module docs), N.
pub fn apply_minimum_impulse(jets: &[JetSpec], thrust_n: &[f64], dt_s: f64) -> Vec<f64> {
    jets.iter()
        .zip(thrust_n)
        .map(|(j, u)| {
            let impulse = u * dt_s;
            let bit = j.min_impulse_bit_ns;
            if impulse <= 0.0 || impulse >= bit {
                *u
            } else if impulse >= bit / 2.0 {
                (bit / dt_s).min(j.max_thrust_n)
            } else {
                0.0
            }
        })
        .collect()
}

/// The wrench of given thrusts, body frame.
pub fn wrench(jets: &[JetSpec], thrust_n: &[f64]) -> Vector6<f64> {
    jets.iter()
        .zip(thrust_n)
        .map(|(j, u)| j.column() * *u)
        .sum()
}

/// Per-jet running totals.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct JetTotals {
    /// Jet name.
    pub name: String,
    /// Time at full thrust, Σ I/F_max, s.
    pub on_time_s: f64,
    /// Impulse delivered, N·s.
    pub impulse_ns: f64,
    /// Steps in which the jet fired after a step in which it did not.
    pub firings: u64,
    /// Propellant used, kg.
    pub propellant_kg: f64,
    /// Fired in the last step.
    #[serde(skip)]
    pub firing: bool,
    /// The pulse under way (while `firing`): steps, impulse N·s and on-time s so far.
    #[serde(skip)]
    pub pulse: (u64, f64, f64),
    /// Firing events raised for this jet (`jet_pulse`, at most [`MAX_PULSE_EVENTS_PER_JET`]).
    #[serde(skip)]
    pub pulse_events: u64,
}

/// Most `jet_pulse` events one jet raises in a run; later pulses are counted in the summary's
/// totals only (one `jet_pulse_events_capped` event says so).
pub const MAX_PULSE_EVENTS_PER_JET: u64 = 1000;

/// Most `jet_pulse` events all the jets of a run raise together (a tenth of the run's limit of
/// 10⁶ events, `sim::guard`), so that a chattering layout can never stop a run.
pub const MAX_PULSE_EVENTS_PER_RUN: u64 = 100_000;

/// One firing pulse of a jet that has ended: the consecutive steps in which it delivered an
/// impulse.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct JetPulse {
    /// Jet index in the layout.
    pub jet: usize,
    /// Steps the pulse lasted (its duration is `steps·dt`).
    pub steps: u64,
    /// Impulse delivered, N·s.
    pub impulse_ns: f64,
    /// Time at full thrust, Σ I/F_max, s (the duration for on/off valves).
    pub on_time_s: f64,
}

/// Plume cone of a jet in the body frame: apex (the nozzle), unit axis (the exhaust
/// direction, −thrust), half-angle (rad) and length (m).
pub fn plume_cone(j: &JetSpec) -> Option<(Vector3<f64>, Vector3<f64>, f64, f64)> {
    let p = j.plume?;
    Some((
        Vector3::from(j.pos_m),
        -j.dir(),
        p.half_angle_deg.to_radians(),
        p.length_m,
    ))
}

#[cfg(test)]
mod tests {
    //! Reference: a layout solved by hand. Four jets in the body x–y plane at (±1, 0, 0) and
    //! (0, ±1, 0) thrusting along ±y / ∓x, plus two along ±x through the centre of mass:
    //! a pure force F_x is met by the x jet alone (u = F_x), a pure torque τ_z by the two jets
    //! whose moments are +z, each τ_z/2 (r = 1 m); a command outside the cone of reachable
    //! wrenches (a −z force, no jet pushes along −z) is the least-squares projection, reported
    //! saturated; beyond F_max the jet saturates at F_max.
    use super::*;

    fn jet(name: &str, pos: [f64; 3], dir: [f64; 3], fmax: f64) -> JetSpec {
        JetSpec {
            name: name.into(),
            pos_m: pos,
            direction: dir,
            max_thrust_n: fmax,
            min_impulse_bit_ns: 0.0,
            plume: None,
        }
    }

    fn layout() -> Vec<JetSpec> {
        vec![
            jet("px", [-1.0, 0.0, 0.0], [1.0, 0.0, 0.0], 10.0),
            jet("mx", [1.0, 0.0, 0.0], [-1.0, 0.0, 0.0], 10.0),
            // Moments about z: r × d.
            jet("a", [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], 2.0), // +z
            jet("b", [-1.0, 0.0, 0.0], [0.0, -1.0, 0.0], 2.0), // +z
            jet("c", [1.0, 0.0, 0.0], [0.0, -1.0, 0.0], 2.0), // −z
            jet("d", [-1.0, 0.0, 0.0], [0.0, 1.0, 0.0], 2.0), // −z
            jet("up", [0.0, 0.0, -1.0], [0.0, 0.0, 1.0], 1.0),
        ]
    }

    #[test]
    fn val_rcs_allocation_matches_the_hand_solution() {
        let l = layout();
        let a = allocate(&l, &Vector6::new(3.0, 0.0, 0.0, 0.0, 0.0, 0.0));
        let want = [3.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0];
        for (u, w) in a.thrust_n.iter().zip(want) {
            assert!((u - w).abs() < 1e-9, "{:?}", a.thrust_n);
        }
        assert!(!a.saturated);
        // τ_z = 1.5 N·m: jets a and b, 0.75 N each (any split of a + b = 1.5 with c = d = 0
        // and a = b for zero net y force).
        let a = allocate(&l, &Vector6::new(0.0, 0.0, 0.0, 0.0, 0.0, 1.5));
        assert!((a.thrust_n[2] - 0.75).abs() < 1e-9 && (a.thrust_n[3] - 0.75).abs() < 1e-9);
        assert!(a.thrust_n[4].abs() < 1e-9 && a.thrust_n[5].abs() < 1e-9);
        assert!(a.residual < 1e-9 && !a.saturated);
        // −z force: unreachable, least squares gives nothing, residual 2 N, saturated.
        let a = allocate(&l, &Vector6::new(0.0, 0.0, -2.0, 0.0, 0.0, 0.0));
        assert!(a.thrust_n.iter().all(|u| u.abs() < 1e-12));
        assert!((a.residual - 2.0).abs() < 1e-12 && a.saturated);
        // 15 N along x: px at its 10 N limit, 5 N short.
        let a = allocate(&l, &Vector6::new(15.0, 0.0, 0.0, 0.0, 0.0, 0.0));
        assert!((a.thrust_n[0] - 10.0).abs() < 1e-12 && (a.residual - 5.0).abs() < 1e-9);
        assert!(a.saturated);
        // The jet "up" at (0, 0, −1) pushing +z has no moment (r ∥ d): 0.4 N up, exactly.
        let a = allocate(&l, &Vector6::new(0.0, 0.0, 0.4, 0.0, 0.0, 0.0));
        assert!((a.thrust_n[6] - 0.4).abs() < 1e-9 && !a.saturated);
    }

    #[test]
    fn val_rcs_minimum_impulse_bit_rounds() {
        let mut l = layout();
        l[0].min_impulse_bit_ns = 0.1;
        let dt = 0.01;
        // 4 N for 10 ms = 0.04 N·s < 0.05: off; 6 N → 0.06 N·s ≥ 0.05: one bit, 10 N.
        assert_eq!(
            apply_minimum_impulse(&l, &[4.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0], dt)[0],
            0.0
        );
        assert_eq!(
            apply_minimum_impulse(&l, &[6.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0], dt)[0],
            10.0
        );
        assert_eq!(
            apply_minimum_impulse(&l, &[10.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0], dt)[0],
            10.0
        );
    }
}
