//! Characteristic-model golden-section adaptive control (ACCM) and its PD baseline, after
//! Xu & Hu (2015), "Control for relative position of spacecraft rendezvous with a
//! non-cooperative maneuver target", Aerospace Control and Application 41(6):13–18,
//! eqs. (9)–(27).
//!
//! The paper's equations were lost in extraction; every formula below is a
//! reconstruction from the characteristic-model literature (Wu, Hu, Xie 2007;
//! Meng & Wu 2009) and is marked **\[derived\]** where it is a choice, not a quotation.
//!
//! # Plant and model (per axis, decoupled, paper eqs. (9)–(11))
//! Each axis of the target-orbital-frame (tof) relative position ξ obeys
//! ξ̈ = a ξ + b u + g + δ with b = 1/m_c, g the coupling to the other axes and δ the target
//! maneuver and disturbances. Euler discretisation with sample period h gives
//! `ξ(k+1) = α1 ξ(k) + α2 ξ(k−1) + β u(k) + q(k)`, α1 = 2 + h²a, α2 = −1, β = h²b,
//! q = h²(g + δ).
//!
//! # Modified compression (paper eqs. (12)–(18)) \[derived\]
//! Ω = {|ξ| ≤ η}. Outside Ω, q is absorbed into the characteristic parameters
//! (α1' = α1 + q/ξ). Inside Ω that would blow up, so the characteristic variable is
//! shifted away from zero, ζ = ξ + d with d > η, and q is absorbed into the parameters of the
//! ζ-model. Both cases are written y = ξ + D(Ω, ξ) with the shift/dead-zone function
//! `D(Ω, ξ) = 0` outside Ω and `d` inside (paper eq. (24)), giving the unified model
//! `y(k+1) = α1 y(k) + α2 y(k−1) + β u(k)` (eq. (18)).
//! **One shift per step**: at sample k the shift s_k = D(Ω, ξ(k)) is applied to *every*
//! sample used in that step's regression and control law (y(k), y(k−1), y(k−2), y_r(k−1),
//! y_r(k), y_r(k+1)); shifting each sample by its own D would inject a jump of d into the
//! regression when ξ crosses ∂Ω.
//!
//! # Identification (normalised gradient with projection) \[derived\]
//! θ = [α1, α2, γ], β = γ β0, β0 = h²/m_nominal (scaling β by β0 makes the third regressor
//! O(h²u/m) comparable in the update; raw β ≈ 1e−4 s²/kg would never move):
//! `θ̂(k) = Π{θ̂(k−1) + λ1 φ ε / (λ2 + φᵀφ)}`, φ = [y(k−1), y(k−2), β0 u(k−1)],
//! ε = y(k) − φᵀ θ̂(k−1), 0 < λ1 < 2, λ2 > 0, Π = clip to a box. u(k−1) is the *applied*
//! (saturated) force, so saturation never corrupts the regression.
//!
//! # Control (paper eqs. (19)–(23))
//! u = sat(u1 + u2), with the maintaining-tracking law
//! `u1 = [y_r(k+1) − α̂1 y_r(k) − α̂2 y_r(k−1)] / (β̂ + λ)` and the golden-section law
//! `u2 = −[l1 α̂1 e(k) + l2 α̂2 e(k−1)] / (β̂ + λ)`, e = y − y_r, l1 = 0.382, l2 = 0.618.
//! On the nominal model (α = [2, −1], β̂ = β, λ = 0) the error obeys
//! e(k+1) = 1.236 e(k) − 0.382 e(k−1): a double pole at z = 0.618.
//! The reference y_r = ξ_r + s_k, ξ_r a quintic from the first measured position to the goal
//! (zero velocity and acceleration at both ends) over `reference_duration_s`, then held
//! [derived: regulating straight to the goal saturates and limit-cycles].
//!
//! # PD baseline \[derived\]
//! u = sat(m_nominal [ξ̈_r − k_p e − k_d ė]), e = ξ − ξ_r, ė = (e(k) − e(k−1))/h (backward
//! difference of the measured position minus that of the reference). Gains: the paper gives
//! none. We use `k_p = (l1·2 − l2)/h² = 0.146/h²`, `k_d = l2/h = 0.618/h`: with these the PD
//! *is* the golden-section loop frozen at the nominal parameters (α = [2, −1], γ = 1, λ = 0)
//! without compression, so both controllers command the same force for the same tracking
//! error ("comparable thrust", as the paper's comparison requires) and any accuracy gap is
//! what the adaptive compression buys. At h = 0.1 s: k_p = 14.6 s⁻², k_d = 6.18 s⁻¹
//! (ω_n = 3.8 rad/s, ζ = 0.81; far above the 0.05–0.1 rad/s maneuver).
//!
//! # What the P1 closed loop shows (test `val_xu2015_p1_accm_vs_pd`, h = 0.1 s, no noise)
//! |ξ − goal| over the last 100 s, RMS / max:
//! - m_c = 90 kg: ACCM 5.7e−5 / 8.1e−5 m, PD 3.0e−3 / 4.0e−3 m, RMS thrust 4.34 N both.
//! - m_c = 100 kg: ACCM 6.4e−5 / 9.0e−5 m, PD 3.3e−3 / 4.4e−3 m, RMS thrust 4.92 / 4.93 N.
//! - m_c = 110 kg: x authority 5/110 = 0.0455 m/s² < maneuver peak 10/200 = 0.05 m/s²
//!   (unavoidable Δv deficit ≈ 0.03 m/s per peak); both controllers fall into a saturated
//!   oscillation on x (max error 38 m, x saturated ≥ 99.9 % of the last 100 s).
//!
//! The ACCM gain comes from the compression: α̂1 + α̂2 − 1 tracks q/y, so u1 cancels the
//! maneuver; γ̂ barely moves in closed loop (its regressor β0 u ≈ 5e−4 m against
//! y ≥ 0.5 m), so mass errors are absorbed by the α̂'s, not identified. Sensitivity to the
//! \[derived\] λ at 100 kg (RMS): λ = 0 → 5.5e−5 m, 0.01 → 6.4e−5 m, 0.1 → 3.4e−4 m. A
//! conventional PD (ω_n = 1 rad/s, ζ = 1) gives 4.9e−2 m.
//!
//! # Sampling
//! Both controllers are discrete with period h: the first call latches t0 and the start
//! position; a call with `t_s < t0 + k h` (next sample not reached) returns the held command
//! (zero-order hold), so the caller may step faster than h. Calls must not be spaced by more
//! than h (the model assumes exactly h between samples).
//!
//! # In the simulation
//! [`SceneSpec`] (bottom of this file) is how a scene flies either law; the ECS wiring
//! (the controller at the end of this file) measures ξ in the reference orbit's target orbital frame,
//! applies the target's maneuver and registers the thrust-authority margins. The bundled
//! scenes `scenes/xu2015_*.ron` reproduce the numbers above to a few 1e−6 (relative) at 90
//! and 100 kg (`tests/val_xu2015.rs`, `rpod reproduce xu2015`).

use nalgebra::{Matrix3, Vector3};
use serde::{Deserialize, Serialize};

/// Golden-section coefficient l1 = (3 − √5)/2 ≈ 0.382 (paper, eq. (21)).
pub const L1_GOLDEN: f64 = 0.382;
/// Golden-section coefficient l2 = (√5 − 1)/2 ≈ 0.618 (paper, eq. (21)).
pub const L2_GOLDEN: f64 = 0.618;

/// What the controller sees at one call: time and measured relative position of the chaser
/// with respect to the target, in the target orbital frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Xu2015Observation {
    /// Simulation time, s.
    pub t_s: f64,
    /// Measured relative position (chaser − target), target orbital frame, m.
    pub pos_tof_m: Vector3<f64>,
}

/// What the controller commands: chaser thrust force in the target orbital frame, each axis
/// saturated at the thrust limit.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Xu2015Command {
    /// Thrust force, target orbital frame, N (|component| ≤ thrust_max_n).
    pub force_tof_n: Vector3<f64>,
}

/// Quintic rest-to-rest reference from `start` to `goal` over `duration_s`, then held.
/// Returns (position m, velocity m/s, acceleration m/s²) at `tau_s` after its start.
pub fn quintic_reference(
    start_m: f64,
    goal_m: f64,
    duration_s: f64,
    tau_s: f64,
) -> (f64, f64, f64) {
    let d = goal_m - start_m;
    if tau_s <= 0.0 {
        return (start_m, 0.0, 0.0);
    }
    if tau_s >= duration_s {
        return (goal_m, 0.0, 0.0);
    }
    let s = tau_s / duration_s;
    let (s2, s3) = (s * s, s * s * s);
    let p = 10.0 * s3 - 15.0 * s3 * s + 6.0 * s3 * s2;
    let v = (30.0 * s2 - 60.0 * s3 + 30.0 * s2 * s2) / duration_s;
    let a = (60.0 * s - 180.0 * s2 + 120.0 * s3) / (duration_s * duration_s);
    (start_m + d * p, d * v, d * a)
}

/// Parameters of the ACCM controller (per-axis identical), SI units.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct AccmParams {
    /// Sample period h, s [derived: paper silent; 0.1 s (10 Hz), for which
    /// β0 = h²/m = 1e−4 s²/kg].
    pub sample_period_s: f64,
    /// Nominal chaser mass used in β0 = h²/m_nominal, kg (paper: 100 kg).
    pub mass_nominal_kg: f64,
    /// Per-axis thrust limit, N (paper: 5 N).
    pub thrust_max_n: f64,
    /// Goal relative position, target orbital frame, m (paper: [−0.01, 0, 0]).
    pub goal_tof_m: [f64; 3],
    /// Duration of the quintic reference from the first measurement to the goal, s
    /// [derived: 150 s, half of t_f = 300 s, peak reference acceleration 5e−3 m/s² for 20 m].
    pub reference_duration_s: f64,
    /// Half-width η of the region Ω = {|ξ| ≤ η}, m [derived: 0.5 m].
    pub eta_m: f64,
    /// Shift d applied inside Ω, m (d > η) [derived: 1.0 m, so |y| ≥ d − η = 0.5 m always].
    pub shift_m: f64,
    /// Identification gain λ1, 0 < λ1 < 2 [derived: 0.5, halves the one-step prediction
    /// error per sample, fast enough for a maneuver of period ≥ 63 s sampled at 10 Hz].
    pub lambda1: f64,
    /// Identification regulariser λ2 > 0, m² [derived: 0.01 m², ≪ φᵀφ ≥ 2(d − η)² = 0.5 m²].
    pub lambda2_m2: f64,
    /// Projection box for α1 [derived: [1.5, 2.02] about α1 = 2 + h²a ≈ 2].
    pub alpha1_bounds: [f64; 2],
    /// Projection box for α2 [derived: [−1.02, −0.5] about α2 = −1].
    pub alpha2_bounds: [f64; 2],
    /// Projection box for γ = β/β0 [derived: [0.85, 1.15], covers ±10 % mass].
    pub gamma_bounds: [f64; 2],
    /// Initial estimate [α1, α2, γ] (the nominal double integrator: [2, −1, 1]).
    pub theta0: [f64; 3],
    /// Golden-section coefficient l1 (0.382).
    pub l1: f64,
    /// Golden-section coefficient l2 (0.618).
    pub l2: f64,
    /// λ of the control denominator (β̂ + λ), as a fraction of β0 [derived: 0.01; its role
    /// of keeping the denominator off zero is already ensured by γ ≥ 0.85, and a λ/β
    /// fraction of the disturbance is left uncancelled, so it is kept small].
    pub lambda_ctrl_rel: f64,
}

impl AccmParams {
    /// Values of the P1 scenario (paper where it gives them, documented choices elsewhere).
    pub fn paper() -> Self {
        Self {
            sample_period_s: 0.1,
            mass_nominal_kg: 100.0,
            thrust_max_n: 5.0,
            goal_tof_m: [-0.01, 0.0, 0.0],
            reference_duration_s: 150.0,
            eta_m: 0.5,
            shift_m: 1.0,
            lambda1: 0.5,
            lambda2_m2: 0.01,
            alpha1_bounds: [1.5, 2.02],
            alpha2_bounds: [-1.02, -0.5],
            gamma_bounds: [0.85, 1.15],
            theta0: [2.0, -1.0, 1.0],
            l1: L1_GOLDEN,
            l2: L2_GOLDEN,
            lambda_ctrl_rel: 0.01,
        }
    }

    /// β0 = h²/m_nominal, s²/kg (= m/N per sample²).
    pub fn beta0(&self) -> f64 {
        self.sample_period_s * self.sample_period_s / self.mass_nominal_kg
    }
}

impl Default for AccmParams {
    fn default() -> Self {
        Self::paper()
    }
}

/// Normalised-gradient identifier with projection for θ = [α1, α2, γ] (see module docs).
#[derive(Debug, Clone, PartialEq)]
pub struct Identifier {
    /// Current estimate [α̂1, α̂2, γ̂].
    pub theta: Vector3<f64>,
    /// Gain λ1 (0 < λ1 < 2).
    pub lambda1: f64,
    /// Regulariser λ2 (units of φᵀφ, m²).
    pub lambda2: f64,
    /// Lower corner of the projection box.
    pub lower: Vector3<f64>,
    /// Upper corner of the projection box.
    pub upper: Vector3<f64>,
}

impl Identifier {
    /// Identifier with the gains, box and initial estimate of `p`.
    pub fn new(p: &AccmParams) -> Self {
        Self {
            theta: Vector3::from(p.theta0),
            lambda1: p.lambda1,
            lambda2: p.lambda2_m2,
            lower: Vector3::new(p.alpha1_bounds[0], p.alpha2_bounds[0], p.gamma_bounds[0]),
            upper: Vector3::new(p.alpha1_bounds[1], p.alpha2_bounds[1], p.gamma_bounds[1]),
        }
    }

    /// One update with regressor φ = [y(k−1), y(k−2), β0 u(k−1)] and new output y(k);
    /// returns the a-priori prediction error ε = y(k) − φᵀθ̂(k−1).
    pub fn update(&mut self, phi: &Vector3<f64>, y: f64) -> f64 {
        let eps = y - phi.dot(&self.theta);
        let step = phi * (self.lambda1 * eps / (self.lambda2 + phi.norm_squared()));
        self.theta =
            (self.theta + step).zip_zip_map(&self.lower, &self.upper, |t, lo, hi| t.clamp(lo, hi));
        eps
    }
}

/// What one ACCM axis currently believes, for logging.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct AccmAxisEstimate {
    /// α̂1 (dimensionless).
    pub alpha1: f64,
    /// α̂2 (dimensionless).
    pub alpha2: f64,
    /// γ̂ = β̂/β0 (dimensionless).
    pub gamma: f64,
    /// β̂ = γ̂ β0, m/N (per sample: metres of Δ²ξ per newton held over h).
    pub beta_m_per_n: f64,
    /// Shift D(Ω, ξ) used at the last sample, m (0 outside Ω, d inside).
    pub shift_m: f64,
    /// Last a-priori prediction error ε, m.
    pub eps_m: f64,
}

/// Per-axis state: the last two measurements, reference samples and the applied force.
#[derive(Debug, Clone)]
struct AxisHistory {
    /// ξ(k−1), ξ(k−2), m.
    xi: [f64; 2],
    /// Applied (saturated) u(k−1), N.
    u_prev: f64,
}

#[derive(Debug, Clone)]
struct AccmAxis {
    id: Identifier,
    hist: Option<AxisHistory>,
    samples: u64,
    shift_m: f64,
    eps_m: f64,
}

/// Sample-clock and reference bookkeeping shared by ACCM and PD.
#[derive(Debug, Clone)]
struct Clock {
    t0_s: Option<f64>,
    start_tof_m: Vector3<f64>,
    k_next: u64,
    held: Vector3<f64>,
}

impl Clock {
    fn new() -> Self {
        Self {
            t0_s: None,
            start_tof_m: Vector3::zeros(),
            k_next: 0,
            held: Vector3::zeros(),
        }
    }

    /// Returns Some(k) if `obs` is at or past sample k, else None (hold).
    fn tick(&mut self, obs: &Xu2015Observation, h: f64) -> Option<u64> {
        let t0 = *self.t0_s.get_or_insert_with(|| {
            self.start_tof_m = obs.pos_tof_m;
            obs.t_s
        });
        let t_next = t0 + self.k_next as f64 * h;
        if obs.t_s + 1e-9 * h < t_next {
            return None;
        }
        let k = self.k_next;
        self.k_next += 1;
        Some(k)
    }
}

/// The ACCM controller of Xu & Hu (2015): three decoupled characteristic-model axes, each
/// with its own identifier and golden-section law (see module docs).
#[derive(Debug, Clone)]
pub struct Accm {
    /// Parameters (read-only after construction).
    pub params: AccmParams,
    axes: [AccmAxis; 3],
    clock: Clock,
}

impl Accm {
    /// A controller in its initial state; the first `update` latches t0 and the start.
    pub fn new(params: AccmParams) -> Self {
        let axis = AccmAxis {
            id: Identifier::new(&params),
            hist: None,
            samples: 0,
            shift_m: 0.0,
            eps_m: 0.0,
        };
        Self {
            params,
            axes: [axis.clone(), axis.clone(), axis],
            clock: Clock::new(),
        }
    }

    /// Reference position ξ_r (tof, m) at time `t_s`, or None before the first update.
    pub fn reference_tof_m(&self, t_s: f64) -> Option<Vector3<f64>> {
        let t0 = self.clock.t0_s?;
        let p = &self.params;
        Some(Vector3::from_fn(|i, _| {
            quintic_reference(
                self.clock.start_tof_m[i],
                p.goal_tof_m[i],
                p.reference_duration_s,
                t_s - t0,
            )
            .0
        }))
    }

    /// Identified characteristic parameters of the x, y, z axes (for logging).
    pub fn estimates(&self) -> [AccmAxisEstimate; 3] {
        let b0 = self.params.beta0();
        std::array::from_fn(|i| {
            let a = &self.axes[i];
            AccmAxisEstimate {
                alpha1: a.id.theta[0],
                alpha2: a.id.theta[1],
                gamma: a.id.theta[2],
                beta_m_per_n: a.id.theta[2] * b0,
                shift_m: a.shift_m,
                eps_m: a.eps_m,
            }
        })
    }

    /// One control call: runs a sample if one is due, otherwise returns the held command.
    pub fn update(&mut self, obs: &Xu2015Observation) -> Xu2015Command {
        let h = self.params.sample_period_s;
        if let Some(k) = self.clock.tick(obs, h) {
            let tau = k as f64 * h;
            for i in 0..3 {
                let (start, goal) = (self.clock.start_tof_m[i], self.params.goal_tof_m[i]);
                let tr = self.params.reference_duration_s;
                let r = |t: f64| quintic_reference(start, goal, tr, t).0;
                let (rm1, r0, rp1) = (r(tau - h), r(tau), r(tau + h));
                self.clock.held[i] = accm_axis_step(
                    &self.params,
                    &mut self.axes[i],
                    obs.pos_tof_m[i],
                    rm1,
                    r0,
                    rp1,
                );
            }
        }
        Xu2015Command {
            force_tof_n: self.clock.held,
        }
    }
}

/// One sample of one ACCM axis: shift, identification, control; returns the applied force.
fn accm_axis_step(
    p: &AccmParams,
    ax: &mut AccmAxis,
    xi_k: f64,
    xi_r_km1: f64,
    xi_r_k: f64,
    xi_r_kp1: f64,
) -> f64 {
    let b0 = p.beta0();
    // Shift/dead-zone function D(Ω, ξ(k)), one shift for the whole step.
    let s = if xi_k.abs() <= p.eta_m {
        p.shift_m
    } else {
        0.0
    };
    ax.shift_m = s;
    // History: before the first sample the chaser is assumed at rest at ξ(0) (and the
    // reference at its start), with no force applied.
    let hist = ax.hist.clone().unwrap_or(AxisHistory {
        xi: [xi_k, xi_k],
        u_prev: 0.0,
    });
    // Identification needs two past samples.
    if ax.samples >= 2 {
        let phi = Vector3::new(hist.xi[0] + s, hist.xi[1] + s, b0 * hist.u_prev);
        ax.eps_m = ax.id.update(&phi, xi_k + s);
    }
    let th = ax.id.theta;
    let (a1, a2) = (th[0], th[1]);
    let den = th[2] * b0 + p.lambda_ctrl_rel * b0;
    let (y_k, y_km1) = (xi_k + s, hist.xi[0] + s);
    let (yr_km1, yr_k, yr_kp1) = (xi_r_km1 + s, xi_r_k + s, xi_r_kp1 + s);
    let e_k = y_k - yr_k;
    let e_km1 = y_km1 - yr_km1;
    let u1 = (yr_kp1 - a1 * yr_k - a2 * yr_km1) / den;
    let u2 = -(p.l1 * a1 * e_k + p.l2 * a2 * e_km1) / den;
    let u = (u1 + u2).clamp(-p.thrust_max_n, p.thrust_max_n);
    ax.hist = Some(AxisHistory {
        xi: [xi_k, hist.xi[0]],
        u_prev: u,
    });
    ax.samples += 1;
    u
}

/// Parameters of the PD baseline, SI units.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct PdParams {
    /// Sample period h, s (same as ACCM).
    pub sample_period_s: f64,
    /// Nominal chaser mass m in u = m[ξ̈_r − k_p e − k_d ė], kg.
    pub mass_nominal_kg: f64,
    /// Proportional gain k_p, 1/s².
    pub kp_s2: f64,
    /// Derivative gain k_d, 1/s.
    pub kd_s: f64,
    /// Per-axis thrust limit, N.
    pub thrust_max_n: f64,
    /// Goal relative position, target orbital frame, m.
    pub goal_tof_m: [f64; 3],
    /// Duration of the quintic reference, s (same as ACCM).
    pub reference_duration_s: f64,
}

impl PdParams {
    /// Paper scenario values; gains are the golden-section loop's nominal equivalent
    /// k_p = (2 l1 − l2)/h², k_d = l2/h (module docs: "comparable thrust").
    pub fn paper() -> Self {
        let h: f64 = 0.1;
        Self {
            sample_period_s: h,
            mass_nominal_kg: 100.0,
            kp_s2: (2.0 * L1_GOLDEN - L2_GOLDEN) / (h * h),
            kd_s: L2_GOLDEN / h,
            thrust_max_n: 5.0,
            goal_tof_m: [-0.01, 0.0, 0.0],
            reference_duration_s: 150.0,
        }
    }
}

impl Default for PdParams {
    fn default() -> Self {
        Self::paper()
    }
}

/// The PD baseline: u = sat(m[ξ̈_r − k_p e − k_d ė]) per axis, ė by backward difference.
#[derive(Debug, Clone)]
pub struct Pd {
    /// Parameters.
    pub params: PdParams,
    clock: Clock,
    e_prev: Option<Vector3<f64>>,
}

impl Pd {
    /// A controller in its initial state; the first `update` latches t0 and the start.
    pub fn new(params: PdParams) -> Self {
        Self {
            params,
            clock: Clock::new(),
            e_prev: None,
        }
    }

    /// Reference position ξ_r (tof, m) at time `t_s`, or None before the first update.
    pub fn reference_tof_m(&self, t_s: f64) -> Option<Vector3<f64>> {
        let t0 = self.clock.t0_s?;
        let p = &self.params;
        Some(Vector3::from_fn(|i, _| {
            quintic_reference(
                self.clock.start_tof_m[i],
                p.goal_tof_m[i],
                p.reference_duration_s,
                t_s - t0,
            )
            .0
        }))
    }

    /// One control call: runs a sample if one is due, otherwise returns the held command.
    pub fn update(&mut self, obs: &Xu2015Observation) -> Xu2015Command {
        let p = &self.params;
        let h = p.sample_period_s;
        if let Some(k) = self.clock.tick(obs, h) {
            let tau = k as f64 * h;
            let mut e = Vector3::zeros();
            let mut acc_r = Vector3::zeros();
            for i in 0..3 {
                let (xr, _, ar) = quintic_reference(
                    self.clock.start_tof_m[i],
                    p.goal_tof_m[i],
                    p.reference_duration_s,
                    tau,
                );
                e[i] = obs.pos_tof_m[i] - xr;
                acc_r[i] = ar;
            }
            let e_dot = (e - self.e_prev.unwrap_or(e)) / h;
            self.e_prev = Some(e);
            let u = (acc_r - e * p.kp_s2 - e_dot * p.kd_s) * p.mass_nominal_kg;
            self.clock.held = u.map(|c| c.clamp(-p.thrust_max_n, p.thrust_max_n));
        }
        Xu2015Command {
            force_tof_n: self.clock.held,
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Scene wiring, Bevy-free part: what a scene asks for, the target maneuver, the measurement
// noise, the target orbital frame and the thrust-authority margin. The ECS systems that use
// them are in the controller at the end of this file.

/// Which of the paper's two controllers flies the chaser.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum Xu2015Law {
    /// Characteristic-model golden-section adaptive control ([`Accm`], params `accm`).
    Accm,
    /// The PD baseline ([`Pd`], params `pd`).
    Pd,
}

/// The target's maneuver force, per axis of the target orbital frame:
/// `F_t,i(t) = amplitude_n[i] · sin(omega_rad_s[i] · t + phase_rad[i])`, N, t in s from the
/// start of the run. Paper §3: amplitudes (10, 4, 8) N, ω = (0.08, 0.05, 0.1) rad/s,
/// φ = (π/6, π/4, π/2).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ManeuverSpec {
    /// Amplitudes, N (tof x, y, z).
    pub amplitude_n: [f64; 3],
    /// Angular frequencies, rad/s.
    pub omega_rad_s: [f64; 3],
    /// Phases at t = 0, rad.
    pub phase_rad: [f64; 3],
}

impl ManeuverSpec {
    /// The paper's maneuver (see the type's docs).
    pub fn paper() -> Self {
        use std::f64::consts::PI;
        Self {
            amplitude_n: [10.0, 4.0, 8.0],
            omega_rad_s: [0.08, 0.05, 0.1],
            phase_rad: [PI / 6.0, PI / 4.0, PI / 2.0],
        }
    }

    /// The force at time `t_s`, target orbital frame, N.
    pub fn force_tof_n(&self, t_s: f64) -> Vector3<f64> {
        Vector3::from_fn(|i, _| {
            self.amplitude_n[i] * (self.omega_rad_s[i] * t_s + self.phase_rad[i]).sin()
        })
    }

    /// Peak force per axis |amplitude|, N.
    pub fn peak_n(&self) -> Vector3<f64> {
        Vector3::from(self.amplitude_n).abs()
    }
}

impl Default for ManeuverSpec {
    fn default() -> Self {
        Self::paper()
    }
}

/// The relative-position measurement: sampled every `sample_period_s` of the flying law
/// (the sensor and the discrete controller share the paper's period h), with independent
/// zero-mean Gaussian noise of standard deviation `noise_sigma_m` per axis (target orbital
/// frame), drawn from a generator seeded with `seed` (same scene, same noise). Default: no
/// noise (the paper is silent on measurement noise).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SensorSpec {
    /// Noise standard deviation per axis, m (≥ 0).
    pub noise_sigma_m: f64,
    /// Seed of the noise generator.
    pub seed: u64,
}

impl Default for SensorSpec {
    fn default() -> Self {
        Self {
            noise_sigma_m: 0.0,
            seed: 1,
        }
    }
}

/// How a scene asks for this law (`controllers: [Xu2015((body: "chaser", target: "target",
/// law: Accm, ...))]`). The controlled relative position is, in the target orbital frame of
/// the reference orbit, ξ = C_tofᵀ (r_chaser − r_target) − `aim_offset_tof_m` (centres of
/// mass, world frame); see the controller at the end of this file for the frame choice.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SceneSpec {
    /// The body this law flies (the chaser; the paper's 5 N per axis acts on it).
    pub body: String,
    /// The maneuvering target (its centre of mass is the origin of the relative position and
    /// it receives `target_maneuver`).
    pub target: String,
    /// Which controller.
    pub law: Xu2015Law,
    /// ACCM parameters (used when `law: Accm`; default [`AccmParams::paper`]; boxed to keep
    /// the scene's controller list compact).
    #[serde(default)]
    pub accm: Box<AccmParams>,
    /// PD parameters (used when `law: Pd`; default [`PdParams::paper`]).
    #[serde(default)]
    pub pd: Box<PdParams>,
    /// Measurement noise (sampled at the law's period).
    #[serde(default)]
    pub sensor: SensorSpec,
    /// The target's maneuver force, applied to the target body in the target orbital frame.
    #[serde(default)]
    pub target_maneuver: ManeuverSpec,
    /// The point, relative to the target's centre of mass in the target orbital frame, that the
    /// paper's relative-position origin is mapped to, m. Zero reproduces the paper's point-mass
    /// reading literally (the goal [−0.01, 0, 0] m would put the centres of mass 1 cm apart);
    /// a stand-off lets real spacecraft geometry end the run without overlapping.
    #[serde(default)]
    pub aim_offset_tof_m: [f64; 3],
    /// Register the per-axis thrust-authority margin with the monitor (default true).
    #[serde(default = "yes")]
    pub thrust_authority_guarantee: bool,
}

fn yes() -> bool {
    true
}

impl SceneSpec {
    /// Sample period of the flying law, s.
    pub fn sample_period_s(&self) -> f64 {
        match self.law {
            Xu2015Law::Accm => self.accm.sample_period_s,
            Xu2015Law::Pd => self.pd.sample_period_s,
        }
    }

    /// Per-axis thrust limit of the flying law, N.
    pub fn thrust_max_n(&self) -> f64 {
        match self.law {
            Xu2015Law::Accm => self.accm.thrust_max_n,
            Xu2015Law::Pd => self.pd.thrust_max_n,
        }
    }

    /// Field (relative to the spec) holding the flying law's sample period.
    pub fn sample_period_field(&self) -> &'static str {
        match self.law {
            Xu2015Law::Accm => "accm.sample_period_s",
            Xu2015Law::Pd => "pd.sample_period_s",
        }
    }

    /// Physical checks; on failure the field path (relative to the spec) and the message.
    pub fn validate(&self) -> Result<(), (String, String)> {
        let bad = |f: &str, m: String| Err((f.to_string(), m));
        let pos = |v: f64| v.is_finite() && v > 0.0;
        let a = &self.accm;
        let checks: [(&str, f64); 6] = [
            ("accm.sample_period_s", a.sample_period_s),
            ("accm.mass_nominal_kg", a.mass_nominal_kg),
            ("accm.thrust_max_n", a.thrust_max_n),
            ("accm.reference_duration_s", a.reference_duration_s),
            ("accm.eta_m", a.eta_m),
            ("accm.lambda2_m2", a.lambda2_m2),
        ];
        for (f, v) in checks {
            if !pos(v) {
                return bad(f, format!("must be a positive number, got {v}"));
            }
        }
        if a.shift_m.is_nan() || a.shift_m <= a.eta_m {
            return bad(
                "accm.shift_m",
                format!(
                    "the shift d must exceed η = {} m (so y = ξ + d stays away from zero), got {}",
                    a.eta_m, a.shift_m
                ),
            );
        }
        if !(a.lambda1 > 0.0 && a.lambda1 < 2.0) {
            return bad(
                "accm.lambda1",
                format!(
                    "must lie in (0, 2) for a stable gradient update, got {}",
                    a.lambda1
                ),
            );
        }
        for (f, b) in [
            ("accm.alpha1_bounds", a.alpha1_bounds),
            ("accm.alpha2_bounds", a.alpha2_bounds),
            ("accm.gamma_bounds", a.gamma_bounds),
        ] {
            if b[0].is_nan() || b[1].is_nan() || b[0] > b[1] {
                return bad(
                    f,
                    format!("must be (lower, upper) with lower ≤ upper, got {b:?}"),
                );
            }
        }
        if a.lambda_ctrl_rel.is_nan() || a.lambda_ctrl_rel < 0.0 {
            return bad(
                "accm.lambda_ctrl_rel",
                format!("must be ≥ 0, got {}", a.lambda_ctrl_rel),
            );
        }
        if a.gamma_bounds[0] + a.lambda_ctrl_rel <= 0.0 {
            return bad(
                "accm.gamma_bounds",
                "γ_min + λ must be positive (the control divides by β̂ + λ)".into(),
            );
        }
        let p = &self.pd;
        let checks: [(&str, f64); 4] = [
            ("pd.sample_period_s", p.sample_period_s),
            ("pd.mass_nominal_kg", p.mass_nominal_kg),
            ("pd.thrust_max_n", p.thrust_max_n),
            ("pd.reference_duration_s", p.reference_duration_s),
        ];
        for (f, v) in checks {
            if !pos(v) {
                return bad(f, format!("must be a positive number, got {v}"));
            }
        }
        for (f, v) in [("pd.kp_s2", p.kp_s2), ("pd.kd_s", p.kd_s)] {
            if !(v.is_finite() && v >= 0.0) {
                return bad(f, format!("must be a non-negative gain, got {v}"));
            }
        }
        if !(self.sensor.noise_sigma_m.is_finite() && self.sensor.noise_sigma_m >= 0.0) {
            return bad(
                "sensor.noise_sigma_m",
                format!(
                    "must be a non-negative standard deviation in metres, got {}",
                    self.sensor.noise_sigma_m
                ),
            );
        }
        let m = &self.target_maneuver;
        for i in 0..3 {
            if !(m.amplitude_n[i].is_finite()
                && m.omega_rad_s[i].is_finite()
                && m.phase_rad[i].is_finite())
            {
                return bad("target_maneuver", "every component must be finite".into());
            }
        }
        if self.aim_offset_tof_m.iter().any(|v| !v.is_finite()) {
            return bad("aim_offset_tof_m", "must be finite".into());
        }
        Ok(())
    }
}

/// The target orbital frame of an orbit state (paper's o-frame, see `crate::orbit::elliptic`):
/// columns are its axes in ECI, x = y × z (in-plane transverse), y = −ĥ (−orbit normal),
/// z = −r̂ (to Earth's centre). `r_eci_m`, `v_eci_m_s`: the orbit's position and velocity.
pub fn dcm_eci_from_tof_state(r_eci_m: &Vector3<f64>, v_eci_m_s: &Vector3<f64>) -> Matrix3<f64> {
    let z = -r_eci_m.normalize();
    let y = -r_eci_m.cross(v_eci_m_s).normalize();
    let x = y.cross(&z);
    Matrix3::from_columns(&[x, y, z])
}

/// Thrust-authority margin per axis at time `t_s`, m/s²: the chaser's maximum acceleration
/// `thrust_max_n / mass_chaser_kg` less the target's maneuver acceleration
/// |F_t,i(t)| / `mass_target_kg`. Negative: on that axis the chaser cannot match the target's
/// acceleration at that instant (it falls behind whatever the control law).
pub fn thrust_authority_margin_m_s2(
    thrust_max_n: f64,
    mass_chaser_kg: f64,
    maneuver: &ManeuverSpec,
    mass_target_kg: f64,
    t_s: f64,
) -> Vector3<f64> {
    let a_max = thrust_max_n / mass_chaser_kg;
    maneuver
        .force_tof_n(t_s)
        .map(|f| a_max - f.abs() / mass_target_kg)
}

pub use crate::math::rng::GaussianNoise;

#[cfg(test)]
mod scene_tests {
    //! References: the Keplerian frame of `crate::orbit::elliptic` (built from elements, not
    //! from r × v), the moments of the standard normal law, and the paper's numbers.
    use super::*;
    use crate::orbit::elliptic::EllipticOrbit;

    /// The tof built from (r, v) equals `EllipticOrbit::dcm_eci_from_tof(f)` built from the
    /// elements, along the P1 orbit (orthonormal, right-handed, same axes to round-off).
    #[test]
    fn val_xu2015_tof_from_state_matches_elements() {
        let o = EllipticOrbit::xu2015();
        for k in 0..50 {
            let f = o.true_anomaly_at(k as f64 * 300.0);
            let (r, v) = o.eci_state(f);
            let a = dcm_eci_from_tof_state(&r, &v);
            let b = o.dcm_eci_from_tof(f);
            assert!((a - b).amax() < 1e-12, "f = {f}: {}", (a - b).amax());
            assert!((a.transpose() * a - Matrix3::identity()).amax() < 1e-14);
            assert!((a.determinant() - 1.0).abs() < 1e-14);
        }
    }

    /// Paper numbers: peak maneuver accelerations (10, 4, 8)/200 m/s²; the 5 N chaser has a
    /// positive margin on every axis at 90 and 100 kg and a negative one on x only at 110 kg
    /// (5/110 − 10/200 = −4.5e−3 m/s²), reached where |sin| = 1.
    #[test]
    fn val_xu2015_thrust_authority_margins() {
        let m = ManeuverSpec::paper();
        let worst = |mc: f64| {
            (0..=30_000).fold(Vector3::repeat(f64::INFINITY), |acc, k| {
                let g = thrust_authority_margin_m_s2(5.0, mc, &m, 200.0, k as f64 * 0.01);
                acc.zip_map(&g, f64::min)
            })
        };
        for mc in [90.0, 100.0] {
            assert!(worst(mc).min() > 0.0, "{mc} kg: {:?}", worst(mc));
        }
        let w = worst(110.0);
        let exact = 5.0 / 110.0 - 10.0 / 200.0;
        assert!(w.x < 0.0 && (w.x - exact).abs() < 1e-8, "x {}", w.x);
        assert!(w.y > 0.0 && w.z > 0.0);
    }

    /// Gaussian noise: same seed, same sequence; sample mean and variance within 5 standard
    /// errors of 0 and 1 (SE of the mean 1/√n, of the variance √(2/n)).
    #[test]
    fn invariant_gaussian_noise_moments_and_determinism() {
        let n = 200_000;
        let mut g = GaussianNoise::new(7);
        let xs: Vec<f64> = (0..n).map(|_| g.standard_normal()).collect();
        let mut g2 = GaussianNoise::new(7);
        assert!(xs.iter().take(100).all(|x| *x == g2.standard_normal()));
        let mean = xs.iter().sum::<f64>() / n as f64;
        let var = xs.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1) as f64;
        let nf = n as f64;
        assert!(mean.abs() < 5.0 / nf.sqrt(), "mean {mean}");
        assert!((var - 1.0).abs() < 5.0 * (2.0 / nf).sqrt(), "var {var}");
    }

    /// A scene spec with only the required fields takes the paper's values; validation
    /// rejects a shift inside Ω and negative noise with the field named.
    #[test]
    fn regress_scene_spec_defaults_and_validation() {
        let s: SceneSpec =
            ron::from_str(r#"(body: "chaser", target: "target", law: Accm)"#).expect("parses");
        assert_eq!(s.accm.sample_period_s, 0.1);
        assert_eq!(s.pd.kp_s2, PdParams::paper().kp_s2);
        assert_eq!(s.target_maneuver, ManeuverSpec::paper());
        assert!(s.validate().is_ok());
        let mut b = s.clone();
        b.accm.shift_m = 0.4;
        assert_eq!(b.validate().unwrap_err().0, "accm.shift_m");
        let mut b = s.clone();
        b.sensor.noise_sigma_m = -1.0;
        assert_eq!(b.validate().unwrap_err().0, "sensor.noise_sigma_m");
        let p: Result<SceneSpec, _> =
            ron::from_str(r#"(body: "c", target: "t", law: Accm, accm: (eta: 1.0))"#);
        assert!(p.is_err(), "unknown field accepted");
    }
}

#[cfg(test)]
mod tests {
    //! References: linear error dynamics of the normalised-gradient identifier, the closed
    //! form of the golden-section error recursion, and a closed-loop f64 simulation of the
    //! paper's scenario on the relative dynamics of [`crate::orbit::elliptic`].
    use super::*;
    use crate::orbit::elliptic::{EllipticOrbit, RelStateTof, rk4_step_relative};
    use nalgebra::Matrix3;

    /// Deterministic multi-sine excitation, N.
    fn excitation_n(k: usize) -> f64 {
        let k = k as f64;
        3000.0 * (0.7 * k).sin() + 2000.0 * (2.3 * k + 1.0).sin() + 1500.0 * (0.23 * k).sin()
    }

    /// Identification on a known, stable second-order plant
    /// y(k+1) = α1 y(k) + α2 y(k−1) + γ β0 u(k) (noise-free, truth strictly inside the box).
    /// Reference: on steps where the projection is inactive the parameter error obeys the
    /// linear recursion θ̃(k) = (I − λ1 φ̄φ̄ᵀ) θ̃(k−1), φ̄ = φ/√(λ2 + φᵀφ); so from the last
    /// step j where the projection acted, ‖θ̃(N)‖ ≤ ‖Π_{k>j} (I − λ1 φ̄φ̄ᵀ)‖₂ ‖θ̃(j)‖ — a
    /// tolerance computed from the excitation alone. Also the Lyapunov property: ‖θ̃‖ never
    /// increases (0 < λ1 < 2 and the truth is in the convex box, so Π is non-expansive).
    #[test]
    fn val_xu2015_identification_known_plant() {
        let p = AccmParams::paper();
        let b0 = p.beta0();
        let truth = Vector3::new(1.7, -0.75, 1.08);
        let mut id = Identifier::new(&p);
        let n = 2000;
        let mut y = vec![0.0f64, 0.0];
        let mut u = Vec::new();
        for k in 0..n + 2 {
            u.push(excitation_n(k));
            let yk = y[k + 1];
            let ykm1 = y[k];
            y.push(truth[0] * yk + truth[1] * ykm1 + truth[2] * b0 * u[k]);
        }
        // y[j+1] is the plant output at sample j (y[0] = y(−1) = 0).
        let mut prod = Matrix3::<f64>::identity();
        let mut err_prev = (id.theta - truth).norm();
        let mut err_at_last_clip = err_prev;
        let mut last_clip = None;
        for k in 2..n + 2 {
            let phi = Vector3::new(y[k], y[k - 1], b0 * u[k - 1]);
            id.update(&phi, y[k + 1]);
            let err = (id.theta - truth).norm();
            assert!(err <= err_prev * (1.0 + 1e-12) + 1e-15, "‖θ̃‖ grew at k={k}");
            err_prev = err;
            let clipped = (0..3).any(|i| id.theta[i] == id.lower[i] || id.theta[i] == id.upper[i]);
            if clipped {
                prod = Matrix3::identity();
                err_at_last_clip = err;
                last_clip = Some(k);
            } else {
                let pb = phi / (p.lambda2_m2 + phi.norm_squared()).sqrt();
                prod = (Matrix3::identity() - pb * pb.transpose() * p.lambda1) * prod;
            }
        }
        assert!(
            last_clip.is_none_or(|k| k < 100),
            "projection still active late: {last_clip:?}"
        );
        let contraction = prod.singular_values().max();
        let tol = contraction * err_at_last_clip + 1e-12;
        assert!(
            contraction < 1e-6,
            "excitation not persistent: {contraction}"
        );
        for i in 0..3 {
            assert!(
                (id.theta[i] - truth[i]).abs() <= tol,
                "θ[{i}] = {} vs {} (tol {tol})",
                id.theta[i],
                truth[i]
            );
        }
    }

    /// Nominal characteristic model ξ(k+1) = 2ξ(k) − ξ(k−1) + β0 u(k) under ACCM (identifier
    /// starting at the truth, thrust unlimited so the loop is linear). Reference: with
    /// ρ = β/(β + λ) the tracking error obeys exactly
    /// e(k+1) = (2 − 2ρ l1) e(k) − (1 − ρ l2) e(k−1) − (1 − ρ) Δ²ξ_r(k+1),
    /// stable iff both roots of z² − (2 − 2ρ l1) z + (1 − ρ l2) lie in the unit disc (for
    /// λ = 0, a double root at 0.618). The closed loop must follow that recursion through
    /// the whole quintic, including the entry into Ω (shift d), and end on the goal.
    #[test]
    fn val_xu2015_golden_section_nominal_closed_loop() {
        for lambda_rel in [0.0, AccmParams::paper().lambda_ctrl_rel] {
            let mut p = AccmParams::paper();
            p.lambda_ctrl_rel = lambda_rel;
            p.thrust_max_n = 1e12;
            let h = p.sample_period_s;
            let b0 = p.beta0();
            let rho = 1.0 / (1.0 + lambda_rel);
            let (a, b) = (2.0 - 2.0 * rho * p.l1, -(1.0 - rho * p.l2));
            // Roots of z² − a z − b: spectral radius < 1.
            let disc = a * a + 4.0 * b;
            let radius = if disc >= 0.0 {
                ((a.abs() + disc.sqrt()) / 2.0).abs()
            } else {
                (-b).sqrt()
            };
            assert!(radius < 1.0, "closed-loop spectral radius {radius}");
            if lambda_rel == 0.0 {
                // Double root at z = 0.618: a = 2·0.618, b = −0.618² (to the 3-digit l1, l2).
                assert!((a - 1.236).abs() < 1e-12 && (b + 0.382).abs() < 1e-12);
                assert!((radius - 0.618).abs() < 0.01, "radius {radius}");
            }
            let mut c = Accm::new(p.clone());
            // Plant starts displaced from rest: ξ(0) = [−20, 0.3, 5], velocity 1e−3 m/s.
            let x0 = Vector3::new(-20.0, 0.3, 5.0);
            let mut xi_prev = x0 - Vector3::repeat(1e-3 * h);
            let mut xi = x0;
            let n = 3000;
            let mut e_hist: Vec<Vector3<f64>> = Vec::new();
            let mut xr_hist: Vec<Vector3<f64>> = Vec::new();
            for k in 0..=n {
                let t = k as f64 * h;
                let u = c
                    .update(&Xu2015Observation {
                        t_s: t,
                        pos_tof_m: xi,
                    })
                    .force_tof_n;
                let xr = c.reference_tof_m(t).unwrap();
                e_hist.push(xi - xr);
                xr_hist.push(xr);
                let next = xi * 2.0 - xi_prev + u * b0;
                xi_prev = xi;
                xi = next;
            }
            xr_hist.push(c.reference_tof_m((n + 1) as f64 * h).unwrap());
            // Independent recursion from e(1), e(2) onward (k = 0 uses the at-rest history).
            let mut ec = [e_hist[1], e_hist[2]];
            let mut max_dev: f64 = 0.0;
            for k in 2..n {
                let d2 = xr_hist[k + 1] - xr_hist[k] * 2.0 + xr_hist[k - 1];
                let e_next = ec[1] * a + ec[0] * b - d2 * (1.0 - rho);
                ec = [ec[1], e_next];
                max_dev = max_dev.max((e_next - e_hist[k + 1]).amax());
            }
            // Round-off: ulp(20 m) per step through a loop of DC gain 1/(1 − a − b).
            let tol = 100.0 * 20.0 * f64::EPSILON / (1.0 - a - b);
            assert!(
                max_dev < tol,
                "λ={lambda_rel}: deviation {max_dev} m > {tol} m"
            );
            // Tracks: the initial 1e−4 m offset has decayed, the goal is reached.
            let goal = Vector3::from(p.goal_tof_m);
            assert!(
                (xi - goal).amax() < 1e-9,
                "final error {}",
                (xi - goal).amax()
            );
            // The x axis entered Ω: the last step used the shift d.
            assert_eq!(c.estimates()[0].shift_m, p.shift_m);
        }
    }

    /// With identification frozen (λ1 = 0), λ = 0 and no saturation, ACCM *is* the PD
    /// baseline with `PdParams::paper()` gains, except for the feedforward: ACCM uses the
    /// central second difference of the reference, PD its analytic acceleration. Reference:
    /// the commands differ by exactly m_nom |Δ²ξ_r/h² − ξ̈_r| (evaluated independently here).
    #[test]
    fn invariant_pd_is_frozen_golden_section() {
        let mut ap = AccmParams::paper();
        ap.lambda1 = 0.0;
        ap.lambda_ctrl_rel = 0.0;
        ap.thrust_max_n = 1e12;
        let mut pp = PdParams::paper();
        pp.thrust_max_n = 1e12;
        let (h, m, tr) = (
            ap.sample_period_s,
            ap.mass_nominal_kg,
            ap.reference_duration_s,
        );
        let (mut a, mut p) = (Accm::new(ap.clone()), Pd::new(pp));
        let start = Vector3::new(-20.0, 0.0, 5.0);
        let goal = Vector3::from(ap.goal_tof_m);
        for k in 0..2000 {
            let t = k as f64 * h;
            // Arbitrary measured path near the reference.
            let pos = start + Vector3::new((0.3 * t).sin(), (0.7 * t).cos() - 1.0, 0.1 * t) * 0.01;
            let obs = Xu2015Observation {
                t_s: t,
                pos_tof_m: pos,
            };
            let du = a.update(&obs).force_tof_n - p.update(&obs).force_tof_n;
            for i in 0..3 {
                let r = |tt: f64| quintic_reference(start[i], goal[i], tr, tt);
                let d2 = (r(t + h).0 - 2.0 * r(t).0 + r(t - h).0) / (h * h);
                let expect = m * (d2 - r(t).2);
                assert!(
                    (du[i] - expect).abs() < 1e-6 * (1.0 + expect.abs()),
                    "k={k} i={i}"
                );
            }
        }
    }

    /// Zero-order hold: calling every 0.01 s returns the command computed at the last
    /// multiple of h, identical to a controller called only at the samples.
    #[test]
    fn invariant_accm_zero_order_hold() {
        let p = AccmParams::paper();
        let (mut fast, mut slow) = (Accm::new(p.clone()), Accm::new(p.clone()));
        let pos = |t: f64| Vector3::new(-20.0 + 0.01 * t, 0.1 * (0.2 * t).sin(), 5.0 - 0.02 * t);
        let mut held = Vector3::zeros();
        for j in 0..=1000 {
            let t = j as f64 * 0.01;
            let u = fast
                .update(&Xu2015Observation {
                    t_s: t,
                    pos_tof_m: pos(t),
                })
                .force_tof_n;
            if j % 10 == 0 {
                held = slow
                    .update(&Xu2015Observation {
                        t_s: t,
                        pos_tof_m: pos(t),
                    })
                    .force_tof_n;
            }
            assert_eq!(u, held, "t = {t}");
        }
    }

    /// Outcome of one closed-loop P1 run.
    #[derive(Debug)]
    struct RunStats {
        rms_err_m: f64,
        max_err_m: f64,
        max_err_axis_m: Vector3<f64>,
        max_thrust_n: Vector3<f64>,
        rms_thrust_n: f64,
        sat_frac_x_last100: f64,
    }

    /// Target maneuver of the paper, tof, N.
    fn target_force_n(t: f64) -> Vector3<f64> {
        use std::f64::consts::PI;
        Vector3::new(
            10.0 * (0.08 * t + PI / 6.0).sin(),
            4.0 * (0.05 * t + PI / 4.0).sin(),
            8.0 * (0.1 * t + PI / 2.0).sin(),
        )
    }

    /// The paper's scenario on the relative dynamics of [`crate::orbit::elliptic`] (RK4 at the
    /// sample period, thrust held), chaser at rest relative to the target frame at t = 0.
    fn run_p1(
        mass_chaser_kg: f64,
        mut ctrl: impl FnMut(&Xu2015Observation) -> Vector3<f64>,
    ) -> RunStats {
        let orbit = EllipticOrbit::xu2015();
        let (m_t, h, tf): (f64, f64, f64) = (200.0, 0.1, 300.0);
        let goal = Vector3::new(-0.01, 0.0, 0.0);
        let n = (tf / h).round() as usize;
        let mut x = RelStateTof::new(-20.0, 0.0, 5.0, 0.0, 0.0, 0.0);
        let (mut se2, mut cnt, mut maxe) = (0.0, 0usize, 0.0f64);
        let mut maxe_ax = Vector3::zeros();
        let mut maxu = Vector3::<f64>::zeros();
        let (mut su2, mut sat) = (0.0, 0usize);
        for k in 0..=n {
            let t = k as f64 * h;
            let pos = Vector3::new(x[0], x[1], x[2]);
            if t >= tf - 100.0 - 1e-9 {
                let e = pos - goal;
                se2 += e.norm_squared();
                maxe = maxe.max(e.norm());
                maxe_ax = maxe_ax.zip_map(&e, |m: f64, v: f64| m.max(v.abs()));
                cnt += 1;
            }
            if k == n {
                break;
            }
            let u = ctrl(&Xu2015Observation {
                t_s: t,
                pos_tof_m: pos,
            });
            maxu = maxu.zip_map(&u, |m: f64, v: f64| m.max(v.abs()));
            su2 += u.norm_squared();
            if t >= tf - 100.0 - 1e-9 && u.x.abs() >= 5.0 - 1e-12 {
                sat += 1;
            }
            x = rk4_step_relative(&x, t, h, &orbit, |ts| {
                u / mass_chaser_kg - target_force_n(ts) / m_t
            });
        }
        RunStats {
            rms_err_m: (se2 / cnt as f64).sqrt(),
            max_err_m: maxe,
            max_err_axis_m: maxe_ax,
            max_thrust_n: maxu,
            rms_thrust_n: (su2 / n as f64).sqrt(),
            sat_frac_x_last100: sat as f64 / 1000.0,
        }
    }

    /// The P1 closed loop (paper §3): ACCM vs PD, chaser 90/100/110 kg, t_f = 300 s,
    /// h = 0.1 s, chaser initially at rest in the tof, no measurement noise (paper silent).
    /// Accuracy = |ξ − goal| over the last 100 s (reference already at the goal).
    /// Independent reference for PD: with the reference constant, the quasi-static error of
    /// m_nom[−k_p e − k_d ė]/m_c = F_t/m_t is e_i = (F_t,i/m_t)·m_c/(m_nom k_p); the dynamic
    /// correction |1 + iω k_d/k_p − ω²/k_p| − 1 ≤ 1e−3 at ω ≤ 0.1 rad/s, so the per-axis PD
    /// peak must match F_max,i m_c/(m_t m_nom k_p) within 5 % (margin for the short x-axis
    /// saturation at 100 kg and the 0.1 s sampling of the peak).
    /// Findings asserted as measured (see the printed table; do not re-tune to pass):
    /// - 90 and 100 kg: ACCM is more than 10× more accurate than PD (measured ≈ 50×) at the
    ///   same RMS thrust (within 2 %, measured within 0.1 %).
    /// - 110 kg: x authority 5/110 = 0.0455 m/s² < maneuver peak 10/200 = 0.05 m/s². The
    ///   unavoidable velocity deficit per maneuver peak is only ≈ 0.03 m/s, yet both
    ///   controllers (same high nominal gain) fall into a saturated oscillation on x of tens
    ///   of metres and are saturated ≥ 90 % of the last 100 s.
    #[test]
    fn val_xu2015_p1_accm_vs_pd() {
        let pdp = PdParams::paper();
        let f_max = Vector3::new(10.0, 4.0, 8.0);
        let m_t = 200.0;
        let mut table = Vec::new();
        for m_c in [90.0, 100.0, 110.0] {
            let mut accm = Accm::new(AccmParams::paper());
            let sa = run_p1(m_c, |o| accm.update(o).force_tof_n);
            let est = accm.estimates();
            let mut pd = Pd::new(pdp.clone());
            let sp = run_p1(m_c, |o| pd.update(o).force_tof_n);
            println!("m_c = {m_c} kg\n  ACCM {sa:?}\n  PD   {sp:?}\n  ACCM estimates {est:?}");
            table.push((m_c, sa, sp));
        }
        // Thrust limit always respected.
        for (_, sa, sp) in &table {
            assert!(sa.max_thrust_n.amax() <= 5.0 && sp.max_thrust_n.amax() <= 5.0);
        }
        for (m_c, sa, sp) in &table[..2] {
            let pred = f_max * (*m_c / (m_t * pdp.mass_nominal_kg * pdp.kp_s2));
            for i in 0..3 {
                let r = sp.max_err_axis_m[i] / pred[i];
                assert!((r - 1.0).abs() < 0.05, "PD axis {i} at {m_c} kg: {r}");
            }
            assert!(sa.rms_err_m * 10.0 < sp.rms_err_m, "{m_c} kg rms");
            assert!(sa.max_err_m * 10.0 < sp.max_err_m, "{m_c} kg max");
            assert!((sa.rms_thrust_n - sp.rms_thrust_n).abs() < 0.02 * sp.rms_thrust_n);
        }
        // Thrust authority on x at +10 % mass: 5/110 vs 10/200 m/s².
        let (auth, need) = (5.0 / 110.0, 10.0 / m_t);
        // Unavoidable velocity deficit over one maneuver peak: ∫ max(0, need|sin| − auth) dt
        // with θ = 0.08 t (midpoint quadrature over a half period).
        let nq = 100_000;
        let dtheta = std::f64::consts::PI / nq as f64;
        let dv_deficit: f64 = (0..nq)
            .map(|j| (need * ((j as f64 + 0.5) * dtheta).sin() - auth).max(0.0) * dtheta / 0.08)
            .sum();
        println!(
            "110 kg: x authority {auth:.5} m/s² < maneuver peak {need:.5} m/s²; \
             unavoidable Δv deficit per peak {dv_deficit:.4} m/s"
        );
        assert!(auth < need);
        let (_, sa, sp) = &table[2];
        for s in [sa, sp] {
            assert!(
                s.sat_frac_x_last100 >= 0.9,
                "x saturation fraction {}",
                s.sat_frac_x_last100
            );
            assert!(s.max_err_axis_m.x > 1.0, "x error {}", s.max_err_axis_m.x);
        }
    }
}

// ---------------------------------------------------------------------------------------------
// The law in the simulation: the scene entry `Xu2015((...))`, the controller the generic host
// runs, the target's manoeuvre and the thrust-authority guarantees.
//
// # Frames (the choice the paper leaves open)
// The world frame is inertial with its origin on the reference orbit, which the scene makes the
// target's *unforced* orbit. The controller works in the **target orbital frame (tof) of the
// reference orbit**, built every step from the reference state (r, v) by
// [`dcm_eci_from_tof_state`]: z = −r̂, y = −ĥ, x = y × z — the paper's model (its relative
// dynamics use R, ḟ, f̈ of the target's Keplerian orbit and treat the manoeuvre as a
// disturbance). The manoeuvring target's own osculating frame differs from it by the tilt its
// manoeuvre velocity (≈ 0.6 m/s against ≈ 3.5 km/s) and its ≈ 190 m drift give the orbit:
// 2.9e−4 rad after 300 s (measured by `rpod reproduce xu2015`), i.e. 9e−4 m on the 3 m
// stand-off of the bundled scenes.
//
// # What runs each step (dt = scene `dt_s`, h = the law's `sample_period_s`, h/dt integer)
// The host calls the controller every step: ξ = Cᵀ (r_chaser − r_target) − aim_offset (f64
// truth, centres of mass); at every multiple of h a measurement ξ + N(0, σ²) is taken (seeded
// noise) and the law runs once ([`Accm::update`] / [`Pd::update`]); between samples its tof
// command is held (zero-order hold over h, as in the paper) and returned in world axes with
// this step's C. The target's manoeuvre F_t(t + dt/2) ([`Xu2015Maneuver`]) is applied at its
// mid-step value (midpoint rule: the held force then carries the step's impulse to O(dt³)).
// Over a step the tof turns by ḟ dt ≤ 1.6e−4 rad at perigee, a thrust-direction error below
// 4e−4 N.
//
// # Outputs
// Columns (prefix `xu2015.`; `xu2015_N.` for the N-th controller after the first):
// `xi_tof_{x,y,z}_m` (true ξ at the row's time), `meas_tof_{x,y,z}_m` (last measurement),
// `ref_tof_{x,y,z}_m` (reference at that sample), `thrust_tof_{x,y,z}_n` (the command held over
// the step that ends at the row's time; the t = 0 row has no measurement yet: NaN),
// `target_force_tof_{x,y,z}_n`, and for ACCM the identified `alpha1_{x,y,z}`, `alpha2_{x,y,z}`,
// `gamma_{x,y,z}` (dimensionless) and `shift_{x,y,z}_m`. The per-sample history is kept in
// [`Xu2015Loop::history`] for tests and `rpod reproduce`.
// ---------------------------------------------------------------------------------------------

/// The running controller.
#[derive(Debug, Clone)]
pub enum LawState {
    /// Adaptive characteristic-model controller.
    Accm(Box<Accm>),
    /// PD baseline.
    Pd(Box<Pd>),
}

/// What one control sample saw and did.
#[derive(Debug, Clone, Copy)]
pub struct Xu2015Sample {
    /// Sample time, s.
    pub t_s: f64,
    /// True controlled relative position ξ, tof, m.
    pub xi_tof_m: Vector3<f64>,
    /// Measured ξ (truth + noise), tof, m.
    pub meas_tof_m: Vector3<f64>,
    /// Reference ξ_r, tof, m.
    pub reference_tof_m: Vector3<f64>,
    /// Commanded (saturated, then held over h) thrust, tof, N.
    pub thrust_tof_n: Vector3<f64>,
    /// Target maneuver force at the sample time, tof, N.
    pub target_force_tof_n: Vector3<f64>,
    /// ACCM estimates after this sample (None for PD).
    pub estimates: Option<[AccmAxisEstimate; 3]>,
}

/// One xu2015 controller of the scene and its sensor.
#[derive(Debug, Clone)]
pub struct Xu2015Loop {
    /// Column prefix (`xu2015` or `xu2015_N`).
    pub prefix: String,
    /// The scene's spec.
    pub spec: SceneSpec,
    /// Chaser body index (scene order).
    pub chaser: usize,
    /// Target body index.
    pub target: usize,
    /// The law.
    pub law: LawState,
    /// Simulation steps per control sample (h / dt).
    pub steps_per_sample: u64,
    /// tof → world DCM at the current step.
    pub dcm_world_from_tof: Matrix3<f64>,
    /// True ξ at the current step, tof, m.
    pub xi_tof_m: Vector3<f64>,
    /// Last measurement, tof, m.
    pub meas_tof_m: Vector3<f64>,
    /// Held command, tof, N.
    pub thrust_tof_n: Vector3<f64>,
    /// One entry per control sample.
    pub history: Vec<Xu2015Sample>,
    noise: GaussianNoise,
    mass_chaser_kg: f64,
    mass_target_kg: f64,
}

/// The target's manoeuvre F_t(t + dt/2), tof of the reference orbit at the step's start.
#[derive(Debug, Clone)]
pub struct Xu2015Maneuver {
    /// Target body index.
    pub target: usize,
    /// The manoeuvre.
    pub maneuver: ManeuverSpec,
}

impl crate::control::spec::Disturbance for Xu2015Maneuver {
    fn wrenches(
        &mut self,
        ctx: &crate::control::spec::DisturbanceContext,
        out: &mut Vec<crate::control::spec::BodyWrench>,
    ) {
        let Some((r, v)) = ctx.env.reference() else {
            return;
        };
        let c = dcm_eci_from_tof_state(&r, &v);
        let f_t = self.maneuver.force_tof_n(ctx.t_s + 0.5 * ctx.dt_s);
        out.push(crate::control::spec::BodyWrench {
            body: self.target,
            force_n: Some(c * f_t),
            torque_nm: None,
        });
    }
}

/// `thrust_authority_{axis}`: F_max/m_c − |F_t,axis(t)|/m_t, m/s²: the chaser's per-axis
/// acceleration authority against the target's maneuver acceleration at that time (masses from
/// the scene). A negative margin means no control law can keep the relative position constant
/// on that axis at that instant.
#[derive(Debug, Clone)]
pub struct ThrustAuthority {
    /// Guarantee name.
    pub name: String,
    /// Axis of the tof (0 = x, 1 = y, 2 = z).
    pub axis: usize,
    /// Per-axis thrust limit, N.
    pub thrust_max_n: f64,
    /// Chaser mass, kg.
    pub mass_chaser_kg: f64,
    /// Target mass, kg.
    pub mass_target_kg: f64,
    /// The target's maneuver.
    pub maneuver: ManeuverSpec,
}

impl crate::guarantee::Guarantee for ThrustAuthority {
    fn name(&self) -> &str {
        &self.name
    }
    fn unit(&self) -> &str {
        "m_s2"
    }
    fn margin(&self, view: &crate::guarantee::MonitorView) -> f64 {
        thrust_authority_margin_m_s2(
            self.thrust_max_n,
            self.mass_chaser_kg,
            &self.maneuver,
            self.mass_target_kg,
            view.t_s,
        )[self.axis]
    }
    /// The margin a − |A sin(ωt + φ)|/m_t changes at most at |A ω|/m_t (a function of time
    /// only): judged between samples too.
    fn rate_bound(&self, _m: &dyn crate::guarantee::MotionBounds) -> Option<f64> {
        let i = self.axis;
        Some(
            (self.maneuver.amplitude_n[i] * self.maneuver.omega_rad_s[i]).abs()
                / self.mass_target_kg,
        )
    }
    fn reads(&self) -> crate::guarantee::Reads {
        crate::guarantee::Reads::Bodies
    }
}

const AXES: [&str; 3] = ["x", "y", "z"];

/// Instances of the law so far in the scene being built.
#[derive(Default)]
struct Xu2015Count(usize);

impl crate::control::spec::LawSpec for SceneSpec {
    fn build(
        &self,
        ctx: &mut crate::control::spec::BuildContext,
    ) -> Result<crate::control::spec::Built, crate::control::spec::BuildError> {
        use crate::control::spec::{BuildError, Built, Slot};
        let spec = self;
        // The spec sits inside the `Xu2015(( … ))` newtype: its fields are at `0.field`.
        let chaser = ctx.body("0.body", &spec.body)?;
        let target = ctx.body("0.target", &spec.target)?;
        if chaser == target {
            return Err(BuildError::at(
                "0.target",
                "the target must be another body than the chaser",
            ));
        }
        if !matches!(
            ctx.scene.environment,
            crate::scene::Environment::Orbit { .. }
        ) {
            return Err(BuildError::at_root(
                "environment",
                "the xu2015 controller needs an `Orbit` environment (it works in the reference \
                 orbit's target orbital frame)",
            ));
        }
        spec.validate()
            .map_err(|(f, m)| BuildError::at(format!("0.{f}"), m))?;
        let dt = ctx.dt_s();
        let h = spec.sample_period_s();
        let ratio = h / dt;
        let n = ratio.round();
        if !(1.0..=1e12).contains(&n) || (ratio - n).abs() > 1e-9 * ratio {
            return Err(BuildError::at(
                format!("0.{}", spec.sample_period_field()),
                format!(
                    "the sample period must be a whole multiple of the scene step dt_s = {dt} s, \
                     got {h} s"
                ),
            ));
        }
        let law = match spec.law {
            Xu2015Law::Accm => LawState::Accm(Box::new(Accm::new((*spec.accm).clone()))),
            Xu2015Law::Pd => LawState::Pd(Box::new(Pd::new((*spec.pd).clone()))),
        };
        let idx = {
            let c = ctx.shared::<Xu2015Count>("Xu2015");
            c.0 += 1;
            c.0 - 1
        };
        let prefix = if idx == 0 {
            "xu2015".to_string()
        } else {
            format!("xu2015_{idx}")
        };
        Ok(Built {
            slots: vec![Slot {
                kind: "Xu2015".into(),
                body: chaser,
                target: Some(target),
                period_steps: 1,
                sensor: None,
                actuator: crate::actuation::ActuatorSpec::Ideal,
                ports: None,
                law: Box::new(Xu2015Loop {
                    prefix,
                    spec: spec.clone(),
                    chaser,
                    target,
                    law,
                    steps_per_sample: n as u64,
                    dcm_world_from_tof: Matrix3::identity(),
                    xi_tof_m: Vector3::zeros(),
                    meas_tof_m: Vector3::zeros(),
                    thrust_tof_n: Vector3::zeros(),
                    history: Vec::new(),
                    noise: GaussianNoise::new(spec.sensor.seed),
                    mass_chaser_kg: ctx.scene.bodies[chaser].mass_kg,
                    mass_target_kg: ctx.scene.bodies[target].mass_kg,
                }),
            }],
            disturbances: vec![Box::new(Xu2015Maneuver {
                target,
                maneuver: spec.target_maneuver.clone(),
            })],
        })
    }
}

impl Xu2015Loop {
    /// Index of this controller among the scene's xu2015 controllers (from its prefix).
    fn index(&self) -> usize {
        self.prefix
            .strip_prefix("xu2015_")
            .and_then(|s| s.parse().ok())
            .unwrap_or(0)
    }

    /// ξ from the observation's truth, tof, m, and the tof → world DCM.
    fn xi(&self, obs: &crate::control::interface::Observation) -> (Matrix3<f64>, Vector3<f64>) {
        let (r, v) = obs.env.reference().unwrap_or_default();
        let c = dcm_eci_from_tof_state(&r, &v);
        let (sc, st) = (&obs.bodies[self.chaser], &obs.bodies[self.target]);
        let xi = c.transpose() * (sc.pos_m - st.pos_m) - Vector3::from(self.spec.aim_offset_tof_m);
        (c, xi)
    }
}

impl crate::control::interface::Controller for Xu2015Loop {
    fn needs(&self) -> crate::control::interface::Needs {
        crate::control::interface::Needs::NONE
    }

    fn command(
        &mut self,
        obs: &crate::control::interface::Observation,
    ) -> crate::control::interface::Command {
        let (c, xi) = self.xi(obs);
        self.dcm_world_from_tof = c;
        self.xi_tof_m = xi;
        if obs.step.is_multiple_of(self.steps_per_sample) {
            let sigma = self.spec.sensor.noise_sigma_m;
            let noise = if sigma > 0.0 {
                Vector3::from_fn(|_, _| sigma * self.noise.standard_normal())
            } else {
                Vector3::zeros()
            };
            self.meas_tof_m = xi + noise;
            let t = obs.t_s;
            let o = Xu2015Observation {
                t_s: t,
                pos_tof_m: self.meas_tof_m,
            };
            let (u, reference, estimates) = match &mut self.law {
                LawState::Accm(a) => {
                    let u = a.update(&o).force_tof_n;
                    (u, a.reference_tof_m(t), Some(a.estimates()))
                }
                LawState::Pd(p) => {
                    let u = p.update(&o).force_tof_n;
                    (u, p.reference_tof_m(t), None)
                }
            };
            self.thrust_tof_n = u;
            self.history.push(Xu2015Sample {
                t_s: t,
                xi_tof_m: xi,
                meas_tof_m: self.meas_tof_m,
                reference_tof_m: reference.unwrap_or(self.meas_tof_m),
                thrust_tof_n: u,
                target_force_tof_n: self.spec.target_maneuver.force_tof_n(t),
                estimates,
            });
        }
        crate::control::interface::Command::in_frame(
            crate::control::interface::Frame::World,
            c * self.thrust_tof_n,
            Vector3::zeros(),
        )
    }

    fn columns(&self) -> Vec<String> {
        let prefix = &self.prefix;
        let mut names: Vec<String> = Vec::new();
        for q in ["xi_tof", "meas_tof", "ref_tof"] {
            for a in AXES {
                names.push(format!("{prefix}.{q}_{a}_m"));
            }
        }
        for q in ["thrust_tof", "target_force_tof"] {
            for a in AXES {
                names.push(format!("{prefix}.{q}_{a}_n"));
            }
        }
        if self.spec.law == Xu2015Law::Accm {
            for q in ["alpha1", "alpha2", "gamma"] {
                for a in AXES {
                    names.push(format!("{prefix}.{q}_{a}"));
                }
            }
            for a in AXES {
                names.push(format!("{prefix}.shift_{a}_m"));
            }
        }
        names
    }

    fn diagnostics_at(&self) -> &'static [crate::control::interface::DiagnosticsAt] {
        use crate::control::interface::DiagnosticsAt;
        &[
            DiagnosticsAt::Start,
            DiagnosticsAt::Actuated,
            DiagnosticsAt::PostStep,
        ]
    }

    fn diagnostics(
        &mut self,
        at: crate::control::interface::DiagnosticsAt,
        obs: &crate::control::interface::Observation,
        _act: &crate::control::interface::ActuationReport,
        out: &mut [f64],
    ) {
        use crate::control::interface::DiagnosticsAt;
        match at {
            // The t = 0 row is written before the first step: the true ξ, zero thrust, the
            // maneuver at t = 0 and the initial estimates (no measurement or reference exists
            // yet: NaN).
            DiagnosticsAt::Start => {
                let (_, xi0) = self.xi(obs);
                let mut vals: Vec<f64> = xi0.iter().copied().collect();
                vals.extend([f64::NAN; 6]);
                vals.extend([0.0; 3]);
                vals.extend(self.spec.target_maneuver.force_tof_n(0.0).iter());
                if self.spec.law == Xu2015Law::Accm {
                    for j in 0..3 {
                        vals.extend([self.spec.accm.theta0[j]; 3]);
                    }
                    vals.extend([0.0; 3]);
                }
                out.copy_from_slice(&vals);
            }
            DiagnosticsAt::Actuated => {
                let f_t = self
                    .spec
                    .target_maneuver
                    .force_tof_n(obs.t_s + 0.5 * obs.dt_s);
                let reference = self
                    .history
                    .last()
                    .map_or(self.xi_tof_m, |s| s.reference_tof_m);
                for (k, v) in [
                    self.xi_tof_m,
                    self.meas_tof_m,
                    reference,
                    self.thrust_tof_n,
                    f_t,
                ]
                .iter()
                .enumerate()
                {
                    out[3 * k..3 * k + 3].copy_from_slice(v.as_slice());
                }
                if let LawState::Accm(a) = &self.law {
                    let e = a.estimates();
                    for j in 0..3 {
                        out[15 + j] = e[j].alpha1;
                        out[18 + j] = e[j].alpha2;
                        out[21 + j] = e[j].gamma;
                        out[24 + j] = e[j].shift_m;
                    }
                }
            }
            // The ξ columns at the end of the step (the row's time), after the physics.
            DiagnosticsAt::PostStep => {
                let (_, xi) = self.xi(obs);
                out[..3].copy_from_slice(xi.as_slice());
            }
        }
    }

    fn guarantees(&mut self) -> Vec<Box<dyn crate::guarantee::Guarantee>> {
        if !self.spec.thrust_authority_guarantee {
            return Vec::new();
        }
        let idx = self.index();
        let maneuver = self.spec.target_maneuver.clone();
        let thrust_max_n = self.spec.thrust_max_n();
        AXES.iter()
            .enumerate()
            .map(|(axis, a)| {
                let name = if idx == 0 {
                    format!("thrust_authority_{a}")
                } else {
                    format!("thrust_authority_{idx}_{a}")
                };
                Box::new(ThrustAuthority {
                    name,
                    axis,
                    thrust_max_n,
                    mass_chaser_kg: self.mass_chaser_kg,
                    mass_target_kg: self.mass_target_kg,
                    maneuver: maneuver.clone(),
                }) as Box<dyn crate::guarantee::Guarantee>
            })
            .collect()
    }
}
