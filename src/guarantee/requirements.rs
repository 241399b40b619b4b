//! The RPOD requirement set, as registered guarantee kinds: `KeepOutEllipsoid`,
//! `ClosingSpeedGate`, `PassiveSafety` and `LineOfSight`. Each kind's physics, its margin
//! (with unit) and how it is judged between samples are in its doc comment; the closed-form
//! tests are in `tests/val_requirements.rs`.

use super::registry::{GuaranteeContext, GuaranteeParams};
use super::{Guarantee, MonitorView, MotionBounds, Reads};
use crate::control::registry::BuildError;
use crate::orbit::gravity::{GravityTerm, earth_gravity};
use crate::scene::validate::MAX_POSITION_M;
use crate::scene::{Environment, OrbitSpec, Scene};
use nalgebra::{Matrix3, SMatrix, SVector, Vector3};
use serde::Deserialize;

/// The frame a requirement's zone is fixed in.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
pub enum ZoneFrame {
    /// The reference orbit's Hill frame (x radial out, y along-track, z orbit normal), origin
    /// at `around`'s centre of mass (orbit scenes only).
    Hill,
    /// `around`'s body axes, origin at its centre of mass.
    TargetBody,
}

fn finite_positive(field: &str, v: f64, unit: &str) -> Result<(), BuildError> {
    if !(v.is_finite() && v > 0.0 && v <= MAX_POSITION_M) {
        return Err(BuildError::at(
            field,
            format!("must be a positive number of {unit} up to {MAX_POSITION_M:e}, got {v}"),
        ));
    }
    Ok(())
}

/// The orbit scene's Hill frame is needed: a located error otherwise.
fn needs_orbit(scene: &Scene, field: &str) -> Result<(), BuildError> {
    if !matches!(scene.environment, Environment::Orbit { .. }) {
        return Err(BuildError::at(
            field,
            "`Hill` needs an orbit scene (`environment: Orbit(...)`): use `TargetBody`",
        ));
    }
    Ok(())
}

/// Scaled ellipsoid margin of a point p (zone frame) for semi-axes a: (s − 1)·a_min with
/// s = |diag(1/a) p|, m. It is ≥ 0 exactly outside the ellipsoid, never exceeds the Euclidean
/// clearance outside it (s is (1/a_min)-Lipschitz and 1 on the surface), and is 1-Lipschitz in p.
pub fn ellipsoid_margin(p: &Vector3<f64>, semi_axes_m: &Vector3<f64>) -> f64 {
    let s = p.component_div(semi_axes_m).norm();
    (s - 1.0) * semi_axes_m.min()
}

fn check_semi_axes(a: &[f64; 3]) -> Result<(), BuildError> {
    for (k, v) in a.iter().enumerate() {
        finite_positive(&format!("semi_axes_m.{k}"), *v, "metres")?;
    }
    Ok(())
}

/// `KeepOutEllipsoid(name, body, around, semi_axes_m, frame)`: the centre of mass of `body`
/// stays outside the ellipsoid with semi-axes `semi_axes_m` (x, y, z of `frame`) centred on
/// `around`'s centre of mass — an RPOD keep-out zone or approach ellipsoid, in the Hill frame
/// or the target's body frame. The point checked is the centre of mass (not the full geometry:
/// size the ellipsoid for the chaser's extent).
///
/// Margin (m): (s − 1)·a_min with s = |diag(1/a) p|, p the relative position in the frame —
/// ≥ 0 exactly outside, and never more than the Euclidean clearance to the surface
/// ([`ellipsoid_margin`]). Judged on every step interval: the margin is 1-Lipschitz in p and
/// |ṗ| ≤ |v_body − v_around| + ω_F·|r_body − r_around|, with ω_F the frame's rate bound (the
/// Hill frame's, [`crate::orbit::lvlh::hill_rate_bound_rad_s`]; the target's angular speed for
/// `TargetBody`).
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct KeepOutEllipsoidParams {
    /// Guarantee name.
    pub name: String,
    /// The body whose centre of mass is checked.
    pub body: String,
    /// The body at the ellipsoid's centre.
    pub around: String,
    /// Semi-axes along the frame's x, y, z, m.
    pub semi_axes_m: [f64; 3],
    /// The ellipsoid's frame.
    pub frame: ZoneFrame,
}

impl GuaranteeParams for KeepOutEllipsoidParams {
    fn name(&self) -> &str {
        &self.name
    }
    fn bodies(&self) -> Vec<(&'static str, &str)> {
        vec![("body", &self.body), ("around", &self.around)]
    }
    fn check(&self, scene: &Scene) -> Result<(), BuildError> {
        check_semi_axes(&self.semi_axes_m)?;
        if self.frame == ZoneFrame::Hill {
            needs_orbit(scene, "frame")?;
        }
        Ok(())
    }
    fn build(&self, ctx: &GuaranteeContext) -> Result<Box<dyn Guarantee>, BuildError> {
        Ok(Box::new(KeepOutEllipsoid {
            name: self.name.clone(),
            body: ctx.body("body", &self.body)?,
            around: ctx.body("around", &self.around)?,
            semi_axes_m: Vector3::from(self.semi_axes_m),
            frame: self.frame,
        }))
    }
}

/// [`KeepOutEllipsoidParams`] as the monitor checks it.
#[derive(Debug, Clone)]
pub struct KeepOutEllipsoid {
    /// Name.
    pub name: String,
    /// Checked body.
    pub body: usize,
    /// Centre body.
    pub around: usize,
    /// Semi-axes, m.
    pub semi_axes_m: Vector3<f64>,
    /// Frame.
    pub frame: ZoneFrame,
}

/// World → zone-frame rotation at the view's time (`None`: Hill without a reference).
fn zone_rotation(frame: ZoneFrame, v: &MonitorView, around: usize) -> Option<Matrix3<f64>> {
    match frame {
        ZoneFrame::Hill => v.reference.map(|r| r.hill().dcm_frame_from_eci),
        ZoneFrame::TargetBody => Some(
            v.bodies[around]
                .att
                .inverse()
                .to_rotation_matrix()
                .into_inner(),
        ),
    }
}

fn frame_rate_bound(frame: ZoneFrame, m: &dyn MotionBounds, around: usize) -> Option<f64> {
    match frame {
        ZoneFrame::Hill => m.hill_rate_bound_rad_s(),
        ZoneFrame::TargetBody => Some(m.omega_bound(around)),
    }
}

impl Guarantee for KeepOutEllipsoid {
    fn name(&self) -> &str {
        &self.name
    }
    fn margin(&self, v: &MonitorView) -> f64 {
        let Some(c) = zone_rotation(self.frame, v, self.around) else {
            return f64::NEG_INFINITY;
        };
        let r = v.bodies[self.body].pos_m - v.bodies[self.around].pos_m;
        ellipsoid_margin(&(c * r), &self.semi_axes_m)
    }
    /// |ṁ| ≤ |ṗ| ≤ |v_body − v_around| + ω_F·|r_body − r_around|.
    fn rate_bound(&self, m: &dyn MotionBounds) -> Option<f64> {
        let w = frame_rate_bound(self.frame, m, self.around)?;
        Some(
            m.rel_speed_bound(self.body, self.around)
                + w * m.separation_bound(self.body, self.around),
        )
    }
    fn reads(&self) -> Reads {
        Reads::Bodies
    }
}

/// `ClosingSpeedGate(name, body, around, gates: [(within_m, max_m_s), …], ports)`: the closing
/// speed along the line of sight, −d|r|/dt = −r·ṙ/|r| (r from `around`'s point to `body`'s:
/// the centres of mass, or the two ports of `ports: Some(("body_port", "around_port"))`), is at
/// most the tightest limit among the gates whose range applies (|r| ≤ within_m). Gates are
/// listed outermost first (within_m strictly decreasing).
///
/// Margin (m/s): limit − closing speed; beyond the outermost gate the limit is
/// [`MAX_SPEED_M_S`](crate::scene::validate::MAX_SPEED_M_S) (no gate applies; the margin stays
/// finite, as every output must).
/// Judged at the samples only ("samples only" in the outputs): the closing speed changes with
/// the relative acceleration (thrust included), which the monitor's motion bounds do not
/// bound, and the limit steps at each gate's range.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ClosingSpeedGateParams {
    /// Guarantee name.
    pub name: String,
    /// The approaching body.
    pub body: String,
    /// The body approached.
    pub around: String,
    /// (within_m, max_m_s), outermost first.
    pub gates: Vec<(f64, f64)>,
    /// Ports (on `body`, on `around`) whose origins define the line of sight (default: the
    /// centres of mass).
    #[serde(default)]
    pub ports: Option<(String, String)>,
}

/// A port's origin relative to its body's centre of mass, body frame, m.
fn port_offset(scene: &Scene, body: usize, port: &str) -> Option<Vector3<f64>> {
    let b = &scene.bodies[body];
    crate::scene::parts::port_frame(b, port).map(|(p, _)| p - Vector3::from(b.com_m))
}

impl GuaranteeParams for ClosingSpeedGateParams {
    fn name(&self) -> &str {
        &self.name
    }
    fn bodies(&self) -> Vec<(&'static str, &str)> {
        vec![("body", &self.body), ("around", &self.around)]
    }
    fn check(&self, scene: &Scene) -> Result<(), BuildError> {
        if self.gates.is_empty() || self.gates.len() > 64 {
            return Err(BuildError::at(
                "gates",
                "give 1 to 64 gates (within_m, max_m_s)",
            ));
        }
        for (k, (within, max)) in self.gates.iter().enumerate() {
            finite_positive(&format!("gates.{k}.0"), *within, "metres")?;
            if !(max.is_finite() && *max >= 0.0) {
                return Err(BuildError::at(
                    format!("gates.{k}.1"),
                    format!("must be a closing speed ≥ 0 m/s, got {max}"),
                ));
            }
            if k > 0 && *within >= self.gates[k - 1].0 {
                return Err(BuildError::at(
                    format!("gates.{k}.0"),
                    format!(
                        "gates go outermost first: within_m must be below the previous gate's {} m, got {within}",
                        self.gates[k - 1].0
                    ),
                ));
            }
        }
        if let Some((p, q)) = &self.ports {
            for (field, body, port) in [("ports.0", &self.body, p), ("ports.1", &self.around, q)] {
                let i = scene.bodies.iter().position(|b| &b.name == body);
                if i.and_then(|i| port_offset(scene, i, port)).is_none() {
                    return Err(BuildError::at(
                        field,
                        format!("body `{body}` has no port `{port}`"),
                    ));
                }
            }
        }
        Ok(())
    }
    fn build(&self, ctx: &GuaranteeContext) -> Result<Box<dyn Guarantee>, BuildError> {
        let body = ctx.body("body", &self.body)?;
        let around = ctx.body("around", &self.around)?;
        let (off_body, off_around) = match &self.ports {
            Some((p, q)) => (
                port_offset(ctx.scene, body, p)
                    .ok_or_else(|| BuildError::at("ports.0", "no such port"))?,
                port_offset(ctx.scene, around, q)
                    .ok_or_else(|| BuildError::at("ports.1", "no such port"))?,
            ),
            None => (Vector3::zeros(), Vector3::zeros()),
        };
        Ok(Box::new(ClosingSpeedGate {
            name: self.name.clone(),
            body,
            around,
            gates: self.gates.clone(),
            off_body,
            off_around,
        }))
    }
}

/// [`ClosingSpeedGateParams`] as the monitor checks it.
#[derive(Debug, Clone)]
pub struct ClosingSpeedGate {
    /// Name.
    pub name: String,
    /// Approaching body.
    pub body: usize,
    /// Approached body.
    pub around: usize,
    /// (within_m, max_m_s), outermost first.
    pub gates: Vec<(f64, f64)>,
    /// Point on `body` relative to its centre of mass, body frame, m.
    pub off_body: Vector3<f64>,
    /// Point on `around`, m.
    pub off_around: Vector3<f64>,
}

impl ClosingSpeedGate {
    /// The tightest limit whose gate applies at range `r_m`, m/s (`None` beyond every gate).
    pub fn limit_m_s(&self, r_m: f64) -> Option<f64> {
        self.gates
            .iter()
            .filter(|(w, _)| r_m <= *w)
            .map(|(_, m)| *m)
            .reduce(f64::min)
    }
}

/// World position and velocity of a point fixed on a body (offset from the centre of mass,
/// body frame).
fn point_state(b: &super::BodyView, off: &Vector3<f64>) -> (Vector3<f64>, Vector3<f64>) {
    let arm = b.att * off;
    (b.pos_m + arm, b.vel_m_s + b.omega_rad_s.cross(&arm))
}

impl Guarantee for ClosingSpeedGate {
    fn name(&self) -> &str {
        &self.name
    }
    fn unit(&self) -> &str {
        "m_s"
    }
    fn margin(&self, v: &MonitorView) -> f64 {
        let (pb, vb) = point_state(&v.bodies[self.body], &self.off_body);
        let (pa, va) = point_state(&v.bodies[self.around], &self.off_around);
        let (r, rd) = (pb - pa, vb - va);
        let range = r.norm();
        // Beyond the outermost gate no gate applies: the limit is the scene's limit on any
        // speed (the guard stops a run past it), so the margin stays finite and ≥ 0 there.
        let limit = self
            .limit_m_s(range)
            .unwrap_or(crate::scene::validate::MAX_SPEED_M_S);
        // At zero range the direction is undefined: the closing speed is at most |ṙ|.
        let closing = if range > 0.0 {
            -r.dot(&rd) / range
        } else {
            rd.norm()
        };
        limit - closing
    }
    fn reads(&self) -> Reads {
        Reads::Bodies
    }
}

/// `PassiveSafety(name, body, around, radius_m | semi_axes_m, horizon_s, grid_s,
/// active_from_range_m)`: if the
/// thrusters failed now, the thrust-free drift of both bodies from their current states would
/// keep `body`'s centre of mass outside the keep-out zone about `around`'s — a sphere of
/// `radius_m`, or an ellipsoid of `semi_axes_m` in the Hill frame — for `horizon_s`.
///
/// Physics. The drift is the Clohessy–Wiltshire closed form ([`crate::orbit::cw::cw_stm`]),
/// exact for the linearised relative motion about a circular two-body reference: the relative
/// Hill state x₀ of `body` from `around` drifts as x(τ) = Φ(τ)x₀ (both bodies obey the same
/// linear equations about the reference). It is evaluated on the grid τ_k = k·H/K, K =
/// ⌈H/grid_s⌉. Between grid points the drift moves at most at V = |(3n|x₀| + |ẋ₀| + 2|ẏ₀|,
/// 12n|x₀| + 2|ẋ₀| + 7|ẏ₀|, n|z₀| + |ż₀|)| (a bound of the CW velocity rows of Φ over all τ), so
/// on [τ_k, τ_k+1] the zone margin (1-Lipschitz in the position) is ≥ (m_k + m_k+1 − V·Δτ)/2.
/// The CW model's error against the exact two-body drift is bounded for each body about the
/// reference by [`crate::orbit::cw::cw_error_bound_from_cw_max`] (B_body + B_around).
///
/// Margin (m): min over the grid intervals of (m_k + m_k+1 − VΔτ)/2, less B_body + B_around —
/// a certified lower bound of the drift's closest approach to the zone over the horizon (the
/// sphere: |ρ| − radius; the ellipsoid: [`ellipsoid_margin`]). −∞ if the linearisation error
/// cannot be bounded (separation or horizon too large).
///
/// Any other orbit scene (an elliptic or state-vector reference, J2 on): the drift is
/// *propagated* under the scene's own gravity model ([`propagate_drift`]): the reference and
/// both bodies' world-frame states with the differential gravity the simulation itself applies
/// ([`crate::orbit::gravity::differential_accel`], two-body plus J2 if on), no linearisation,
/// by the 8th-order method with the reference orbit's sub-step rule, twice (m and 2m sub-steps
/// per grid interval). Margin: the same grid lower bound with the speed bound of each interval
/// from its end speeds and a bound on the differential gravity inside it, less the step-doubling
/// difference (an error *estimate*: the 2m-step solution's error is about 1/255 of it for an
/// 8th-order method) — see [`propagate_drift`]. The ellipsoid's axes are `around`'s own Hill
/// frame at each grid time (the reference's, to the angle |ρ_around|/r, in the CW model).
///
/// Reuse (a propagated drift about a sphere, evaluated every step — the default): a drift is
/// propagated [`REUSE_WINDOW_FRACTION`] of the horizon further and kept ([`DriftTrack`]). At a
/// later step, τ after it, the kept drift's state at τ (one 8th-order stretch from the grid
/// point before τ, with its step-doubling estimate) is compared with the bodies' current
/// absolute states: for each body, with position and velocity deviations δr, δv (plus the
/// step-doubling differences of the kept run and 16ε rounding per sub-step), the drift from the
/// current state stays within Δ = δr·cosh(√G s) + δv·sinh(√G s)/√G of the kept one over the
/// s ≤ H + Δτ ahead (Grönwall for ÿ = g(x + y) − g(x), |∇g| ≤ G =
/// [`gravity_gradient_bound`] at [`REUSE_MAX_DEVIATION_M`] below the kept drift's lowest
/// radius; valid while Δ ≤ that distance). The sphere margin being 1-Lipschitz in the relative
/// position, the current drift's margin is at least the kept drift's margin over the grid
/// intervals covering [τ, τ + H] less Δ_body + Δ_around: that certified value is reported while
/// Δ ≤ [`REUSE_SLACK_FRACTION`] of the kept window's margin (and the window is positive and
/// fits); otherwise the drift is propagated afresh. A reused margin is therefore a lower bound
/// of a fresh evaluation's, at most 25 % below the kept drift's over the same window, never
/// negative (a violation is always found
/// by a fresh evaluation), and the verdict at each step is the fresh evaluation's. An ellipsoid
/// (whose axes follow `around`'s own Hill frame) or an `eval_period_s` is not reused.
///
/// Judged at the samples only: thrust changes the state, and so the drift, between samples.
/// Every step by default; with `eval_period_s: Some(P)` the drift is evaluated every P seconds
/// of simulated time over a horizon of `horizon_s + P`, and the margin of the last evaluation
/// is reported at the steps between. That value is exact at those steps *for a coasting body*
/// (a drift from a later point of the same coast is the same trajectory, inside the longer
/// horizon); a burn between evaluations is judged at the next evaluation, at most P later.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PassiveSafetyParams {
    /// Guarantee name.
    pub name: String,
    /// The drifting body (chaser).
    pub body: String,
    /// The body at the zone's centre (target).
    pub around: String,
    /// Keep-out sphere radius, m (give this or `semi_axes_m`).
    #[serde(default)]
    pub radius_m: Option<f64>,
    /// Keep-out ellipsoid semi-axes in the Hill frame, m.
    #[serde(default)]
    pub semi_axes_m: Option<[f64; 3]>,
    /// Drift horizon, s.
    pub horizon_s: f64,
    /// Grid spacing of the drift evaluation, s (at most; the grid divides the horizon evenly).
    pub grid_s: f64,
    /// The requirement applies only while `body`'s centre of mass is at least this far from
    /// `around`'s, m (default: always): hold points and the approach to them, not a final
    /// approach that is not passively safe by design. The margin is then max(drift margin,
    /// r − range): ≥ 0 exactly when the range is below r or the drift is safe (positive below
    /// r, continuous across it, as `ApproachCone`'s outside its band).
    #[serde(default)]
    pub active_from_range_m: Option<f64>,
    /// Evaluate the drift every this many seconds of simulated time (default: every step),
    /// over `horizon_s` plus this period; the steps between report the last evaluation.
    #[serde(default)]
    pub eval_period_s: Option<f64>,
}

/// Most grid points of a passive-safety drift.
pub const MAX_DRIFT_GRID_POINTS: f64 = 100_000.0;

/// How a scene's drift is propagated: the CW closed form for a circular two-body reference
/// (mean motion rad/s, orbit radius m), else the scene's own gravity model (its list of terms:
/// two-body, plus J2 if the scene's `j2` is set), or why the scene cannot have one.
fn drift_model_of(scene: &Scene) -> Result<ModelKind, String> {
    match &scene.environment {
        Environment::Orbit {
            reference: OrbitSpec::Elements { a_m, e, .. },
            j2: false,
            ..
        } if *e == 0.0 => Ok(ModelKind::Cw {
            n_rad_s: (crate::orbit::constants::MU_EARTH_M3_S2 / a_m.powi(3)).sqrt(),
            r0_m: *a_m,
        }),
        // The scene's `j2` flag becomes the gravity model's list of terms here, as in the
        // simulation's environment.
        Environment::Orbit { j2, .. } => Ok(ModelKind::Propagated {
            gravity: earth_gravity(*j2),
        }),
        _ => Err("PassiveSafety needs an orbit scene (`environment: Orbit(...)`)".into()),
    }
}

/// Most sub-steps one propagated-drift evaluation may integrate (its horizon over the reference
/// orbit's sub-step rule; each evaluation runs them three times, 12 stages each): 20 000 is 35
/// LEO orbits, about 0.1 s of computation per evaluation.
pub const MAX_PROPAGATED_SUBSTEPS: f64 = 20_000.0;

/// The reference orbit's sub-step rule of a scene ([`crate::orbit::integrate::ReferenceOrbit`]:
/// 1° of true anomaly at perigee), s; `None` outside orbit scenes or for an orbit that is not
/// elliptic (validated elsewhere).
fn reference_substep_s(scene: &Scene) -> Option<f64> {
    use crate::orbit::constants::MU_EARTH_M3_S2;
    let (a, e) = match &scene.environment {
        Environment::Orbit {
            reference: OrbitSpec::Elements { a_m, e, .. },
            ..
        } => (*a_m, *e),
        Environment::Orbit {
            reference: OrbitSpec::State { r_eci_m, v_eci_m_s },
            ..
        } => {
            let el = crate::orbit::kepler::ClassicalElements::from_state(
                &Vector3::from(*r_eci_m),
                &Vector3::from(*v_eci_m_s),
                MU_EARTH_M3_S2,
            );
            (el.a_m, el.e)
        }
        _ => return None,
    };
    let rp = a * (1.0 - e);
    let fdot = (MU_EARTH_M3_S2 * (1.0 + e) / (rp * rp * rp)).sqrt();
    let h = crate::orbit::integrate::MAX_SUBSTEP_ANOMALY_RAD / fdot;
    (h.is_finite() && h > 0.0).then_some(h)
}

/// Which drift model a scene gives (see [`drift_model_of`]).
#[derive(Debug, Clone, Copy)]
enum ModelKind {
    Cw { n_rad_s: f64, r0_m: f64 },
    Propagated { gravity: &'static [GravityTerm] },
}

impl GuaranteeParams for PassiveSafetyParams {
    fn name(&self) -> &str {
        &self.name
    }
    fn bodies(&self) -> Vec<(&'static str, &str)> {
        vec![("body", &self.body), ("around", &self.around)]
    }
    fn check(&self, scene: &Scene) -> Result<(), BuildError> {
        match (self.radius_m, &self.semi_axes_m) {
            (Some(r), None) => finite_positive("radius_m", r, "metres")?,
            (None, Some(a)) => check_semi_axes(a)?,
            _ => {
                return Err(BuildError::at(
                    "radius_m",
                    "give exactly one of `radius_m: Some(…)` and `semi_axes_m: Some((…))`",
                ));
            }
        }
        finite_positive("horizon_s", self.horizon_s, "seconds")?;
        finite_positive("grid_s", self.grid_s, "seconds")?;
        if let Some(r) = self.active_from_range_m {
            finite_positive("active_from_range_m", r, "metres")?;
        }
        if let Some(p) = self.eval_period_s {
            finite_positive("eval_period_s", p, "seconds")?;
            if p > self.horizon_s {
                return Err(BuildError::at(
                    "eval_period_s",
                    format!(
                        "must be at most horizon_s ({} s), got {p} s",
                        self.horizon_s
                    ),
                ));
            }
        }
        if self.grid_s > self.horizon_s || self.horizon_s / self.grid_s > MAX_DRIFT_GRID_POINTS {
            return Err(BuildError::at(
                "grid_s",
                format!(
                    "must be at most horizon_s ({:?} s) and give at most {MAX_DRIFT_GRID_POINTS} grid points, got {:?} s",
                    self.horizon_s, self.grid_s
                ),
            ));
        }
        if let ModelKind::Propagated { .. } =
            drift_model_of(scene).map_err(|m| BuildError::at_root("environment", m))?
            && self.grid_s > MAX_PROPAGATED_GRID_S
        {
            return Err(BuildError::at(
                "grid_s",
                format!(
                    "the propagated drift (elliptic or J2 reference) bounds the differential gravity inside each grid interval only for intervals up to {MAX_PROPAGATED_GRID_S} s, got {} s",
                    self.grid_s
                ),
            ));
        }
        if let ModelKind::Propagated { .. } =
            drift_model_of(scene).map_err(|m| BuildError::at_root("environment", m))?
            && let Some(h_max) = reference_substep_s(scene)
        {
            // Every evaluation integrates the whole horizon (three runs' worth): bounded, so
            // that no horizon makes a step take minutes.
            let horizon = self.horizon_s + self.eval_period_s.unwrap_or(0.0);
            let k = (horizon / self.grid_s).ceil().max(1.0);
            let sub = k * (horizon / k / h_max).ceil().max(1.0);
            if sub > MAX_PROPAGATED_SUBSTEPS {
                return Err(BuildError::at(
                    "horizon_s",
                    format!(
                        "the propagated drift (elliptic or J2 reference) would integrate {sub} sub-steps of at most {h_max:.1} s at every evaluation; at most {MAX_PROPAGATED_SUBSTEPS} (about {:.0} s of horizon here): shorten horizon_s",
                        MAX_PROPAGATED_SUBSTEPS * h_max
                    ),
                ));
            }
        }
        Ok(())
    }
    fn build(&self, ctx: &GuaranteeContext) -> Result<Box<dyn Guarantee>, BuildError> {
        let kind = drift_model_of(ctx.scene).map_err(|m| BuildError::at_root("environment", m))?;
        // The evaluated horizon covers every step until the next evaluation.
        let horizon = self.horizon_s + self.eval_period_s.unwrap_or(0.0);
        let k = (horizon / self.grid_s).ceil().max(1.0) as usize;
        let dtau = horizon / k as f64;
        let model = match kind {
            ModelKind::Cw { n_rad_s, r0_m } => DriftModel::Cw {
                n_rad_s,
                r0_m,
                stm: (0..=k)
                    .map(|i| crate::orbit::cw::cw_stm(n_rad_s, i as f64 * dtau))
                    .collect(),
            },
            ModelKind::Propagated { gravity } => DriftModel::Propagated {
                gravity,
                intervals: k,
            },
        };
        // A propagated drift about a sphere, evaluated every step, is kept and reused: it is
        // propagated REUSE_WINDOW_FRACTION further, within the sub-step budget.
        let reuse_intervals = match (kind, self.radius_m, self.eval_period_s) {
            (ModelKind::Propagated { .. }, Some(_), None) => {
                let extra = (k as f64 * REUSE_WINDOW_FRACTION).ceil() as usize;
                let fits = reference_substep_s(ctx.scene).is_some_and(|h_max| {
                    (k + extra) as f64 * (dtau / h_max).ceil().max(1.0) <= MAX_PROPAGATED_SUBSTEPS
                });
                if fits { extra } else { 0 }
            }
            _ => 0,
        };
        Ok(Box::new(PassiveSafety {
            name: self.name.clone(),
            body: ctx.body("body", &self.body)?,
            around: ctx.body("around", &self.around)?,
            zone: match (self.radius_m, self.semi_axes_m) {
                (Some(r), _) => Zone::Sphere(r),
                (None, Some(a)) => Zone::Ellipsoid(Vector3::from(a)),
                (None, None) => return Err(BuildError::at("radius_m", "missing")),
            },
            horizon_s: horizon,
            active_from_range_m: self.active_from_range_m,
            dtau_s: dtau,
            model,
            eval_period_s: self.eval_period_s,
            last_eval: std::sync::Mutex::new(None),
            reuse_intervals,
            track: std::sync::Mutex::new(None),
            counts: std::sync::Mutex::new((0, 0)),
        }))
    }
}

/// A keep-out zone about a centre.
#[derive(Debug, Clone, Copy)]
pub enum Zone {
    /// Sphere of this radius, m.
    Sphere(f64),
    /// Ellipsoid with these semi-axes (Hill x, y, z), m.
    Ellipsoid(Vector3<f64>),
}

impl Zone {
    /// The zone margin of a point (1-Lipschitz), m.
    pub fn margin(&self, p: &Vector3<f64>) -> f64 {
        match self {
            Zone::Sphere(r) => p.norm() - r,
            Zone::Ellipsoid(a) => ellipsoid_margin(p, a),
        }
    }
}

/// How a [`PassiveSafety`] drift is propagated.
#[derive(Debug, Clone)]
pub enum DriftModel {
    /// The Clohessy–Wiltshire closed form (circular two-body reference).
    Cw {
        /// Mean motion of the reference, rad/s.
        n_rad_s: f64,
        /// Orbit radius of the reference, m.
        r0_m: f64,
        /// Φ(τ_k), k = 0 … K.
        stm: Vec<SMatrix<f64, 6, 6>>,
    },
    /// The scene's own gravity, propagated ([`propagate_drift`]).
    Propagated {
        /// The scene's gravity model, its terms summed in this order.
        gravity: &'static [GravityTerm],
        /// Grid intervals K over the evaluated horizon.
        intervals: usize,
    },
}

/// [`PassiveSafetyParams`] as the monitor checks it.
#[derive(Debug)]
pub struct PassiveSafety {
    /// Name.
    pub name: String,
    /// Drifting body.
    pub body: usize,
    /// Centre body.
    pub around: usize,
    /// Keep-out zone.
    pub zone: Zone,
    /// Evaluated horizon, s (the requirement's, plus the evaluation period if any).
    pub horizon_s: f64,
    /// Applies only at centre-of-mass ranges from this up, m.
    pub active_from_range_m: Option<f64>,
    /// Grid spacing, s.
    pub dtau_s: f64,
    /// The drift's propagation.
    pub model: DriftModel,
    /// Evaluation period, s (`None`: every step).
    pub eval_period_s: Option<f64>,
    /// (time s, drift margin m) of the last evaluation, with an evaluation period.
    last_eval: std::sync::Mutex<Option<(f64, f64)>>,
    /// Extra grid intervals a propagated drift is kept for reuse (0: no reuse), see
    /// [`PassiveSafetyParams`].
    pub reuse_intervals: usize,
    /// (time s, drift) of the last propagated evaluation kept for reuse.
    track: std::sync::Mutex<Option<(f64, DriftTrack)>>,
    /// (fresh propagations, reused steps) so far.
    pub counts: std::sync::Mutex<(u64, u64)>,
}

/// What [`PassiveSafety::drift`] finds.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DriftFinding {
    /// Certified lower bound of the zone margin over the horizon, m (the guarantee's margin).
    pub margin_m: f64,
    /// Smallest zone margin at the grid points (CW), m.
    pub grid_min_m: f64,
    /// Bound on the drift's speed, m/s.
    pub speed_bound_m_s: f64,
    /// CW error bound (both bodies), m.
    pub cw_error_m: f64,
}

/// The CW drift's speed bound V for an initial Hill state (see [`PassiveSafetyParams`]).
pub fn cw_drift_speed_bound(x0: &SVector<f64, 6>, n: f64) -> f64 {
    let (x, z, xd, yd, zd) = (
        x0[0].abs(),
        x0[2].abs(),
        x0[3].abs(),
        x0[4].abs(),
        x0[5].abs(),
    );
    Vector3::new(
        3.0 * n * x + xd + 2.0 * yd,
        12.0 * n * x + 2.0 * xd + 7.0 * yd,
        n * z + zd,
    )
    .norm()
}

impl PassiveSafety {
    /// The CW drift of the relative Hill state `rel` (body from around) with the two bodies'
    /// own Hill states `own` (about the reference), for the linearisation error bound. For a
    /// propagated model this is not defined and gives a margin of −∞ (use
    /// [`propagate_drift`]).
    pub fn drift(&self, rel: &SVector<f64, 6>, own: [&SVector<f64, 6>; 2]) -> DriftFinding {
        let DriftModel::Cw { n_rad_s, r0_m, stm } = &self.model else {
            return DriftFinding {
                margin_m: f64::NEG_INFINITY,
                grid_min_m: f64::NEG_INFINITY,
                speed_bound_m_s: f64::INFINITY,
                cw_error_m: f64::INFINITY,
            };
        };
        let n = *n_rad_s;
        let v = cw_drift_speed_bound(rel, n);
        let mut prev: Option<f64> = None;
        let mut grid_min = f64::INFINITY;
        let mut lower = f64::INFINITY;
        for phi in stm {
            let x = phi * rel;
            let m = self.zone.margin(&Vector3::new(x[0], x[1], x[2]));
            grid_min = grid_min.min(m);
            lower = lower.min(m);
            if let Some(p) = prev {
                lower = lower.min(0.5 * (p + m - v * self.dtau_s));
            }
            prev = Some(m);
        }
        // Each body's CW error about the reference, from its own drift's largest separation.
        let mut err = 0.0;
        for x0 in own {
            let vb = cw_drift_speed_bound(x0, n);
            let rho_max = stm
                .iter()
                .map(|phi| {
                    let x = phi * x0;
                    Vector3::new(x[0], x[1], x[2]).norm()
                })
                .fold(0.0, f64::max)
                + 0.5 * vb * self.dtau_s;
            match crate::orbit::cw::cw_error_bound_from_cw_max(rho_max, *r0_m, n, self.horizon_s) {
                Some((_, b)) => err += b,
                None => err = f64::INFINITY,
            }
        }
        DriftFinding {
            margin_m: lower - err,
            grid_min_m: grid_min,
            speed_bound_m_s: v,
            cw_error_m: err,
        }
    }

    /// The drift margin of the current view (without `active_from_range_m`), m.
    fn drift_margin(&self, v: &MonitorView, reference: &super::ReferenceView) -> f64 {
        match &self.model {
            DriftModel::Cw { .. } => {
                let hill = reference.hill();
                let state = |i: usize| {
                    let (p, d) = hill.to_local(&v.bodies[i].pos_m, &v.bodies[i].vel_m_s);
                    SVector::<f64, 6>::from_column_slice(&[p.x, p.y, p.z, d.x, d.y, d.z])
                };
                let (xb, xa) = (state(self.body), state(self.around));
                self.drift(&(xb - xa), [&xb, &xa]).margin_m
            }
            DriftModel::Propagated { gravity, intervals } => {
                let (b, a) = (&v.bodies[self.body], &v.bodies[self.around]);
                let setup = DriftSetup {
                    zone: self.zone,
                    gravity,
                    horizon_s: self.horizon_s,
                    intervals: *intervals,
                };
                let mut counts = self
                    .counts
                    .lock()
                    .unwrap_or_else(std::sync::PoisonError::into_inner);
                if self.reuse_intervals == 0 {
                    counts.0 += 1;
                    return propagate_drift(
                        &setup,
                        reference,
                        (&b.pos_m, &b.vel_m_s),
                        (&a.pos_m, &a.vel_m_s),
                    )
                    .margin_m;
                }
                let mut kept = self
                    .track
                    .lock()
                    .unwrap_or_else(std::sync::PoisonError::into_inner);
                if let Some((t0, track)) = kept.as_ref() {
                    let abs = |x: &super::BodyView| {
                        (
                            reference.pos_eci_m + x.pos_m,
                            reference.vel_eci_m_s + x.vel_m_s,
                        )
                    };
                    let (bb, aa) = (abs(b), abs(a));
                    if let Some((m, dev)) =
                        track.reuse(v.t_s - t0, self.horizon_s, (&bb.0, &bb.1), (&aa.0, &aa.1))
                        && dev <= REUSE_SLACK_FRACTION * (m + dev)
                    {
                        counts.1 += 1;
                        return m;
                    }
                }
                counts.0 += 1;
                let track = propagate_drift_track(
                    &setup,
                    reference,
                    (&b.pos_m, &b.vel_m_s),
                    (&a.pos_m, &a.vel_m_s),
                    self.reuse_intervals,
                );
                let m = track.window(0, *intervals).margin_m;
                *kept = Some((v.t_s, track));
                m
            }
        }
    }
}

/// Longest grid interval of a propagated drift, s. [`propagate_drift`]'s interval bound needs
/// G·Δτ² ≤ 1 (G the differential gravity's gradient bound, ≈ 2n² ≈ 2.6e-6 s⁻² in LEO): at
/// 90 s, G·Δτ² ≈ 0.02 in LEO and ≤ 1 for any body above 1.1 Earth radii... as long as it is
/// above ~60 km of altitude; where it does not hold the margin is −∞.
pub const MAX_PROPAGATED_GRID_S: f64 = 90.0;

/// What [`propagate_drift`] propagates.
#[derive(Debug, Clone, Copy)]
pub struct DriftSetup {
    /// Keep-out zone about `around`, axes of `around`'s own Hill frame at each grid time.
    pub zone: Zone,
    /// The gravity model, its terms summed in this order (the scene's `Orbit(j2: …)` gives
    /// [`crate::orbit::gravity::TWO_BODY`] or [`crate::orbit::gravity::TWO_BODY_J2`]).
    pub gravity: &'static [GravityTerm],
    /// Horizon, s.
    pub horizon_s: f64,
    /// Grid intervals K (grid spacing Δτ = horizon / K).
    pub intervals: usize,
}

/// Frobenius-norm bound on the Jacobian of the J2 acceleration, in units of
/// (3/2)·J2·μ·R_E²/r⁵: the largest value over all directions is √96 ≈ 9.798 (on the poles;
/// checked over 10⁵ random directions by finite differences in this module's tests).
pub const J2_GRADIENT_FACTOR: f64 = 9.8;

/// Upper bound on |g| anywhere above the Earth's surface (μ/R_E² = 9.798 m/s², J2 adds < 0.4 %),
/// m/s².
const G_SURFACE_BOUND_M_S2: f64 = 10.0;

/// Bound on the gradient of one term of the Earth's gravity at radius ≥ `r_m`, s⁻²: the point
/// mass, 2μ/r³ (its spectral norm); J2, [`J2_GRADIENT_FACTOR`]·(3/2)J2μR_E²/r⁵.
fn term_gradient_bound(term: GravityTerm, r_m: f64) -> f64 {
    use crate::orbit::constants::{J2_EARTH, MU_EARTH_M3_S2, R_EARTH_M};
    match term {
        GravityTerm::TwoBody => 2.0 * MU_EARTH_M3_S2 / r_m.powi(3),
        GravityTerm::J2 => {
            J2_GRADIENT_FACTOR * 1.5 * J2_EARTH * MU_EARTH_M3_S2 * R_EARTH_M * R_EARTH_M
                / r_m.powi(5)
        }
    }
}

/// Bound on the gradient of the Earth gravity model `gravity` (its terms) at radius ≥ `r_m`,
/// s⁻²: the sum of its terms' bounds, in order (2μ/r³ for the point mass, the spectral norm of
/// its gradient, plus [`J2_GRADIENT_FACTOR`]·(3/2)J2μR_E²/r⁵ for J2); zero for an empty model.
pub fn gravity_gradient_bound(r_m: f64, gravity: &[GravityTerm]) -> f64 {
    let mut terms = gravity.iter().map(|t| term_gradient_bound(*t, r_m));
    let first = terms.next().unwrap_or(0.0);
    terms.fold(first, |sum, b| sum + b)
}

/// The thrust-free drift of `body` (world-frame position and velocity) from `around`, under the
/// scene's own gravity: `around`'s orbit (ECI) and `body`'s state relative to it propagated
/// together, the relative one under the differential gravity the simulation applies
/// ([`crate::orbit::gravity::differential_accel`], cancellation-free), by the 8th-order method in m
/// sub-steps per grid interval (m from the reference orbit's sub-step rule,
/// [`crate::orbit::integrate::MAX_SUBSTEP_ANOMALY_RAD`]) and again in 2m.
///
/// At grid point k the relative position p_k (2m run), velocity v_k and zone margin m_k are
/// known. On [τ_k, τ_k+1] the relative acceleration is the difference of gravity at the two
/// bodies, |a| ≤ G·|p| with G = [`gravity_gradient_bound`] at the lowest radius the segment
/// between them can reach in the interval (r ≥ min(r_k, r_k+1) − (|V| + 10 m/s²·Δτ)·Δτ/2 − |p|,
/// V the larger absolute speed at the ends), and |p| ≤ (|p_k| + |v_k|Δτ)(1 + GΔτ²) while
/// GΔτ² ≤ 1 (Grönwall, cosh x ≤ 1 + x² for x ≤ 1); so |v| ≤ (|v_k| + |v_k+1| + A·Δτ)/2 on
/// average over the interval, A = G·max|p|, and the zone margin (1-Lipschitz) is at least
/// (m_k + m_k+1 − Δτ·(|v_k| + |v_k+1| + AΔτ)/2)/2 there. The margin is the smallest of these
/// less the largest step-doubling difference of p over the grid (an error estimate: ≈ 255× the
/// 2m run's own error for an 8th-order method) and a rounding allowance of 16ε·max|p| per
/// sub-step. −∞ where the interval bound does not hold (GΔτ² > 1, or a body at the Earth's
/// surface).
pub fn propagate_drift(
    setup: &DriftSetup,
    reference: &super::ReferenceView,
    body: (&Vector3<f64>, &Vector3<f64>),
    around: (&Vector3<f64>, &Vector3<f64>),
) -> DriftFinding {
    let k = setup.intervals.max(1);
    propagate_drift_track(setup, reference, body, around, 0).window(0, k)
}

/// The finding when nothing can be certified.
const BAD_FINDING: DriftFinding = DriftFinding {
    margin_m: f64::NEG_INFINITY,
    grid_min_m: f64::NEG_INFINITY,
    speed_bound_m_s: f64::INFINITY,
    cw_error_m: f64::INFINITY,
};

/// Time derivative of a drift state [R_a, V_a, p, v] (ECI axes: `around`'s absolute state,
/// `body`'s relative one) under the scene's gravity.
fn drift_rhs(y: &SVector<f64, 12>, gravity: &[GravityTerm]) -> SVector<f64, 12> {
    use crate::orbit::gravity::{accel_earth, differential_accel};
    let r = Vector3::new(y[0], y[1], y[2]);
    let p = Vector3::new(y[6], y[7], y[8]);
    let mut d = SVector::<f64, 12>::zeros();
    d.fixed_rows_mut::<3>(0).copy_from(&y.fixed_rows::<3>(3));
    d.fixed_rows_mut::<3>(3)
        .copy_from(&accel_earth(&r, gravity));
    d.fixed_rows_mut::<3>(6).copy_from(&y.fixed_rows::<3>(9));
    d.fixed_rows_mut::<3>(9)
        .copy_from(&differential_accel(&r, &p, gravity));
    d
}

/// A propagated drift ([`propagate_drift`]) kept so that the margin of any window of
/// `horizon` within it can be read, and a later state compared with it.
#[derive(Debug, Clone)]
pub struct DriftTrack {
    /// Grid spacing, s.
    pub dtau_s: f64,
    /// Sub-steps per grid interval of the finer run.
    sub_fine: usize,
    /// The reference orbit's sub-step rule, s.
    h_max_s: f64,
    /// The gravity model, its terms summed in this order.
    gravity: &'static [GravityTerm],
    /// Finer-run states [R_a, V_a, p, v] at the grid points (ECI axes), m and m/s.
    states: Vec<SVector<f64, 12>>,
    /// Zone margin at each grid point, m.
    grid_m: Vec<f64>,
    /// Lower bound of the zone margin on each interval (−∞ where it cannot be bounded), m.
    lows: Vec<f64>,
    /// Step-doubling difference of p at each grid point, m.
    diff_p: Vec<f64>,
    /// |p| at each grid point, m.
    p_norm: Vec<f64>,
    /// |v| at each grid point, m/s.
    v_norm: Vec<f64>,
    /// Largest step-doubling difference of either body's absolute position (|ΔR_a| + |Δp|), m,
    /// and velocity, m/s, over the grid.
    err_abs: (f64, f64),
    /// Lowest radius either body reaches on any interval (the bound of each interval), m.
    r_min_m: f64,
}

impl DriftTrack {
    /// Number of grid intervals.
    pub fn intervals(&self) -> usize {
        self.lows.len()
    }

    /// The certified margin over the grid intervals `i0 .. i1` (see [`propagate_drift`]): the
    /// smallest grid value and interval bound there, less the largest step-doubling difference
    /// at those grid points and the rounding allowance of the sub-steps integrated up to `i1`.
    pub fn window(&self, i0: usize, i1: usize) -> DriftFinding {
        let i1 = i1.min(self.intervals());
        if i0 >= i1 {
            return BAD_FINDING;
        }
        let pts = i0..=i1;
        let fold_max = |v: &[f64]| v[pts.clone()].iter().copied().fold(0.0, f64::max);
        let grid_min = self.grid_m[pts.clone()]
            .iter()
            .copied()
            .fold(f64::INFINITY, f64::min);
        let lower = self.lows[i0..i1].iter().copied().fold(grid_min, f64::min);
        let rounding = 16.0 * f64::EPSILON * fold_max(&self.p_norm) * (self.sub_fine * i1) as f64;
        let err = fold_max(&self.diff_p) + rounding;
        if !(lower.is_finite() && err.is_finite()) {
            return BAD_FINDING;
        }
        DriftFinding {
            margin_m: lower - err,
            grid_min_m: grid_min,
            speed_bound_m_s: fold_max(&self.v_norm),
            cw_error_m: err,
        }
    }

    /// The margin of the drift that starts `tau_s` after this track's start, over `horizon_s`,
    /// from the bodies' current absolute ECI states (`body`, `around`: position m, velocity
    /// m/s), if this track can certify it (see [`PassiveSafetyParams`], reuse): `Some((margin,
    /// deviation bound))` with margin = the track's window margin − the deviation bound.
    pub fn reuse(
        &self,
        tau_s: f64,
        horizon_s: f64,
        body: (&Vector3<f64>, &Vector3<f64>),
        around: (&Vector3<f64>, &Vector3<f64>),
    ) -> Option<(f64, f64)> {
        use crate::orbit::constants::R_EARTH_M;
        use crate::orbit::integrate::rk8_step;
        let dt = self.dtau_s;
        if !(tau_s >= 0.0 && tau_s.is_finite()) {
            return None;
        }
        let i0 = (tau_s / dt).floor() as usize;
        let i1 = ((tau_s + horizon_s) / dt - 1e-9).ceil().max(0.0) as usize;
        if i1 > self.intervals() || i0 >= i1 {
            return None;
        }
        let window = self.window(i0, i1).margin_m;
        if !(window.is_finite() && window > 0.0) {
            return None;
        }
        // The old drift at τ: from grid point i0, in n and 2n sub-steps (their difference is
        // the estimate of this last stretch's error, as for the grid).
        let sigma = tau_s - i0 as f64 * dt;
        let y0 = self.states[i0];
        let (y, step_err) = if sigma > 0.0 {
            let n = (sigma / self.h_max_s).ceil().max(1.0) as usize;
            let mut f = |_t: f64, y: &SVector<f64, 12>| drift_rhs(y, self.gravity);
            let mut run = |sub: usize| {
                let h = sigma / sub as f64;
                let mut y = y0;
                for j in 0..sub {
                    y = rk8_step(&mut f, j as f64 * h, &y, h);
                }
                y
            };
            let (c, fy) = (run(n), run(2 * n));
            let d = c - fy;
            let dp = d.fixed_rows::<3>(0).norm() + d.fixed_rows::<3>(6).norm();
            let dv = d.fixed_rows::<3>(3).norm() + d.fixed_rows::<3>(9).norm();
            (fy, (dp, dv))
        } else {
            (y0, (0.0, 0.0))
        };
        let r_a = Vector3::new(y[0], y[1], y[2]);
        let v_a = Vector3::new(y[3], y[4], y[5]);
        let p = Vector3::new(y[6], y[7], y[8]);
        let v = Vector3::new(y[9], y[10], y[11]);
        // Rounding of the absolute states over the sub-steps integrated (16ε per sub-step, as
        // for p).
        let substeps = (self.sub_fine * (i0 + 1)) as f64 * 2.0;
        let eps_p = self.err_abs.0 + step_err.0 + 16.0 * f64::EPSILON * r_a.norm() * substeps;
        let eps_v = self.err_abs.1 + step_err.1 + 16.0 * f64::EPSILON * v_a.norm() * substeps;
        let da_p = (around.0 - r_a).norm() + eps_p;
        let da_v = (around.1 - v_a).norm() + eps_v;
        let db_p = ((body.0 - around.0) - p + (around.0 - r_a)).norm() + eps_p;
        let db_v = ((body.1 - around.1) - v + (around.1 - v_a)).norm() + eps_v;
        let r_lo = self.r_min_m - REUSE_MAX_DEVIATION_M;
        if r_lo.is_nan() || r_lo <= R_EARTH_M {
            return None;
        }
        let g = gravity_gradient_bound(r_lo, self.gravity).sqrt();
        let s = i1 as f64 * dt - tau_s;
        let (ch, sh) = ((g * s).cosh(), (g * s).sinh() / g);
        let dev_a = da_p * ch + da_v * sh;
        let dev_b = db_p * ch + db_v * sh;
        if !(dev_a <= REUSE_MAX_DEVIATION_M && dev_b <= REUSE_MAX_DEVIATION_M) {
            return None;
        }
        let dev = dev_a + dev_b;
        Some((window - dev, dev))
    }
}

/// Largest deviation of either body from a kept drift under which [`DriftTrack::reuse`]
/// certifies a margin (the gravity-gradient bound is taken 1 km below the drift's lowest
/// radius), m.
pub const REUSE_MAX_DEVIATION_M: f64 = 1000.0;

/// A kept drift is reused while its deviation bound is at most this fraction of the window
/// margin (so a reused margin is at least 75 % of the kept drift's over the same window). It
/// sets how conservative a reused margin may be, never a verdict (a reused margin is > 0); on
/// the flagship's first 120 s, 0.25 needs 363 fresh propagations in 12 000 steps, 0.1 needs 818.
pub const REUSE_SLACK_FRACTION: f64 = 0.25;

/// Extra grid intervals a reusable drift is propagated beyond the horizon, as a fraction of the
/// horizon's intervals (it can then be reused for up to that fraction of the horizon).
pub const REUSE_WINDOW_FRACTION: f64 = 0.1;

/// [`propagate_drift`] over `setup.intervals + extra` grid intervals, kept ([`DriftTrack`]).
pub fn propagate_drift_track(
    setup: &DriftSetup,
    reference: &super::ReferenceView,
    body: (&Vector3<f64>, &Vector3<f64>),
    around: (&Vector3<f64>, &Vector3<f64>),
    extra: usize,
) -> DriftTrack {
    use crate::orbit::constants::R_EARTH_M;
    use crate::orbit::integrate::{ReferenceOrbit, rk8_step};
    type S = SVector<f64, 12>;
    let gravity = setup.gravity;
    let k0 = setup.intervals.max(1);
    let dtau = setup.horizon_s / k0 as f64;
    let k = k0 + extra;
    let h_max = ReferenceOrbit::from_state(reference.pos_eci_m, reference.vel_eci_m_s, gravity)
        .max_substep_s();
    let mut track = DriftTrack {
        dtau_s: dtau,
        sub_fine: 2,
        h_max_s: h_max,
        gravity,
        states: Vec::new(),
        grid_m: vec![f64::NEG_INFINITY; k + 1],
        lows: vec![f64::NEG_INFINITY; k],
        diff_p: vec![f64::INFINITY; k + 1],
        p_norm: vec![0.0; k + 1],
        v_norm: vec![f64::INFINITY; k + 1],
        err_abs: (f64::INFINITY, f64::INFINITY),
        r_min_m: f64::NEG_INFINITY,
    };
    if !(h_max.is_finite() && h_max > 0.0 && dtau.is_finite() && dtau > 0.0) {
        return track;
    }
    let m = (dtau / h_max).ceil().max(1.0) as usize;
    track.sub_fine = 2 * m;
    // [R_a, V_a]: `around`'s ECI state; [p, v]: `body` from `around` (ECI axes).
    let mut y0 = S::zeros();
    for (off, v) in [
        (0, reference.pos_eci_m + around.0),
        (3, reference.vel_eci_m_s + around.1),
        (6, body.0 - around.0),
        (9, body.1 - around.1),
    ] {
        y0.fixed_rows_mut::<3>(off).copy_from(&v);
    }
    let mut f = |_t: f64, y: &S| -> S { drift_rhs(y, gravity) };
    // Grid states of both runs.
    let mut run = |sub: usize| -> Vec<S> {
        let h = dtau / sub as f64;
        let mut y = y0;
        let mut out = Vec::with_capacity(k + 1);
        out.push(y);
        for i in 0..k {
            for j in 0..sub {
                y = rk8_step(&mut f, (i * sub + j) as f64 * h, &y, h);
            }
            out.push(y);
        }
        out
    };
    let coarse = run(m);
    let fine = run(2 * m);
    let rel = |y: &S| {
        (
            Vector3::new(y[6], y[7], y[8]),
            Vector3::new(y[9], y[10], y[11]),
        )
    };
    // (zone margin, relative position, relative velocity, lowest radius, fastest speed).
    struct Grid {
        m: f64,
        p: Vector3<f64>,
        v: Vector3<f64>,
        r_lo: f64,
        v_hi: f64,
    }
    let mut prev: Option<Grid> = None;
    let (mut err_abs_p, mut err_abs_v): (f64, f64) = (0.0, 0.0);
    let mut r_min = f64::INFINITY;
    for (i, (yc, yf)) in coarse.iter().zip(&fine).enumerate() {
        let (p, v) = rel(yf);
        let d = yc - yf;
        track.diff_p[i] = d.fixed_rows::<3>(6).norm();
        err_abs_p = err_abs_p.max(d.fixed_rows::<3>(0).norm() + d.fixed_rows::<3>(6).norm());
        err_abs_v = err_abs_v.max(d.fixed_rows::<3>(3).norm() + d.fixed_rows::<3>(9).norm());
        track.p_norm[i] = p.norm();
        track.v_norm[i] = v.norm();
        let (r_a, v_a) = (
            Vector3::new(yf[0], yf[1], yf[2]),
            Vector3::new(yf[3], yf[4], yf[5]),
        );
        let hill = super::ReferenceView {
            pos_eci_m: r_a,
            vel_eci_m_s: v_a,
        }
        .hill();
        let (p_hill, _) = hill.to_local(&p, &Vector3::zeros());
        let mk = setup.zone.margin(&p_hill);
        track.grid_m[i] = mk;
        // Lowest radius of either body and fastest absolute speed at this grid point.
        let r_lo = r_a.norm().min((r_a + p).norm());
        let v_hi = v_a.norm().max((v_a + v).norm());
        if let Some(Grid {
            m: m0,
            p: p0,
            v: v0,
            r_lo: r0,
            v_hi: vh0,
        }) = prev
        {
            let p_seg0 = (p0.norm() + v0.norm() * dtau).max(p.norm() + v.norm() * dtau);
            let r_seg =
                r0.min(r_lo) - (vh0.max(v_hi) + G_SURFACE_BOUND_M_S2 * dtau) * dtau * 0.5 - p_seg0;
            if !r_seg.is_nan() && r_seg > R_EARTH_M {
                let g = gravity_gradient_bound(r_seg, gravity);
                if g * dtau * dtau <= 1.0 {
                    let p_seg = p_seg0 * (1.0 + g * dtau * dtau);
                    let a = g * p_seg;
                    let travel = dtau * 0.5 * (v0.norm() + v.norm() + a * dtau);
                    track.lows[i - 1] = 0.5 * (m0 + mk - travel);
                    r_min = r_min.min(r_seg);
                }
            }
            if track.lows[i - 1] == f64::NEG_INFINITY {
                r_min = f64::NEG_INFINITY;
            }
        }
        prev = Some(Grid {
            m: mk,
            p,
            v,
            r_lo,
            v_hi,
        });
    }
    track.err_abs = (err_abs_p, err_abs_v);
    track.r_min_m = r_min;
    track.states = fine;
    track
}

impl Guarantee for PassiveSafety {
    fn name(&self) -> &str {
        &self.name
    }
    fn margin(&self, v: &MonitorView) -> f64 {
        let Some(reference) = v.reference else {
            return f64::NEG_INFINITY;
        };
        let range = (v.bodies[self.body].pos_m - v.bodies[self.around].pos_m).norm();
        let below = self.active_from_range_m.map(|r| r - range);
        // Held where the range is below r, or where the drift is safe: the margin is the
        // larger of the two (continuous, ≥ 0 exactly when the requirement holds).
        if let Some(b) = below
            && b > 0.0
        {
            return b;
        }
        let drift = match self.eval_period_s {
            None => self.drift_margin(v, &reference),
            Some(period) => {
                let mut last = self
                    .last_eval
                    .lock()
                    .unwrap_or_else(std::sync::PoisonError::into_inner);
                match *last {
                    Some((t0, m)) if v.t_s >= t0 && v.t_s < t0 + period => m,
                    _ => {
                        let m = self.drift_margin(v, &reference);
                        *last = Some((v.t_s, m));
                        m
                    }
                }
            }
        };
        match below {
            Some(b) => drift.max(b),
            None => drift,
        }
    }
    fn reads(&self) -> Reads {
        Reads::Bodies
    }
}

/// The line-of-sight requirement: it needs the full geometry (parry's ray casts and distances),
/// so it exists only with the `sim` feature (the Bevy + rapier layer).
#[cfg(feature = "sim")]
mod line_of_sight {
    use super::*;
    use nalgebra::{Isometry3, Translation3, UnitQuaternion};

    /// `LineOfSight(name, sensor_body, position_m, boresight, half_fov_deg, range_m, target,
    /// port, standoff_m, clearance_m)`: a sensor fixed on `sensor_body` (at `position_m`, body
    /// frame, looking along `boresight`) keeps the point `standoff_m` out along the outward axis of
    /// `target`'s port `port` inside its field of view (half-angle `half_fov_deg`) and range
    /// (`range_m`), and the segment between them clear of every part of every body by
    /// `clearance_m` — the sensor's own body and the target's arrays included.
    ///
    /// Margin (m): the smallest of (range_m − d), d·sin(α − θ) (the point's distance to the
    /// edge of the field of view, clamped to ±d beyond ±90°) and the signed distance from the
    /// segment to the nearest part less `clearance_m` (parry's distance between the segment and
    /// each collider, its penetration depth when they overlap), with d the segment's length, θ
    /// the angle off the boresight, α the half field of view. Judged on every step interval:
    /// with u_S, u_T the speed bounds of the two end points (centre-of-mass speed + Ω·lever arm)
    /// and w = max over bodies of (speed + Ω·extent), the three terms change at most at
    /// u_S + u_T, 2(u_S + u_T) + Ω_S·d_max and max(u_S, u_T) + w.
    #[derive(Debug, Clone, Deserialize)]
    #[serde(deny_unknown_fields)]
    pub struct LineOfSightParams {
        /// Guarantee name.
        pub name: String,
        /// The body carrying the sensor.
        pub sensor_body: String,
        /// Sensor position, sensor body frame (from the body origin, as parts), m.
        pub position_m: [f64; 3],
        /// Boresight, sensor body frame (any length > 0).
        pub boresight: [f64; 3],
        /// Half field of view, deg (0 < α < 90).
        pub half_fov_deg: f64,
        /// Sensor range, m.
        pub range_m: f64,
        /// The body carrying the point to keep in view.
        pub target: String,
        /// Its port.
        pub port: String,
        /// The point's distance out along the port's outward axis, m (it must lie outside every
        /// part of the target).
        pub standoff_m: f64,
        /// Required clearance of the segment from every part, m (default 0).
        #[serde(default)]
        pub clearance_m: f64,
    }

    impl GuaranteeParams for LineOfSightParams {
        fn name(&self) -> &str {
            &self.name
        }
        fn bodies(&self) -> Vec<(&'static str, &str)> {
            vec![("sensor_body", &self.sensor_body), ("target", &self.target)]
        }
        fn check(&self, scene: &Scene) -> Result<(), BuildError> {
            for (k, v) in self.position_m.iter().enumerate() {
                if !(v.is_finite() && v.abs() <= crate::scene::validate::MAX_BODY_OFFSET_M) {
                    return Err(BuildError::at(
                        format!("position_m.{k}"),
                        "must be a finite offset within the body's limits",
                    ));
                }
            }
            let b = Vector3::from(self.boresight);
            if !(b.iter().all(|x| x.is_finite()) && b.norm() > 1e-9) {
                return Err(BuildError::at(
                    "boresight",
                    "must be a finite, non-zero direction",
                ));
            }
            let a = self.half_fov_deg;
            if !(a.is_finite() && a > 0.0 && a < 90.0) {
                return Err(BuildError::at(
                    "half_fov_deg",
                    format!("must be an angle in (0, 90) deg, got {a}"),
                ));
            }
            finite_positive("range_m", self.range_m, "metres")?;
            if !(self.standoff_m.is_finite() && self.standoff_m >= 0.0 && self.standoff_m <= 1e3) {
                return Err(BuildError::at(
                    "standoff_m",
                    format!("must be from 0 to 1000 m, got {}", self.standoff_m),
                ));
            }
            if !(self.clearance_m.is_finite() && self.clearance_m >= 0.0 && self.clearance_m <= 1e3)
            {
                return Err(BuildError::at(
                    "clearance_m",
                    format!("must be from 0 to 1000 m, got {}", self.clearance_m),
                ));
            }
            let t = scene.bodies.iter().find(|x| x.name == self.target);
            if t.and_then(|t| crate::scene::parts::port_frame(t, &self.port))
                .is_none()
            {
                return Err(BuildError::at(
                    "port",
                    format!("body `{}` has no port `{}`", self.target, self.port),
                ));
            }
            Ok(())
        }
        fn build(&self, ctx: &GuaranteeContext) -> Result<Box<dyn Guarantee>, BuildError> {
            let s = ctx.body("sensor_body", &self.sensor_body)?;
            let t = ctx.body("target", &self.target)?;
            let (port_m, axis) = crate::scene::parts::port_frame(&ctx.scene.bodies[t], &self.port)
                .ok_or_else(|| BuildError::at("port", "no such port"))?;
            let point_m = port_m + axis.normalize() * self.standoff_m;
            let com = |i: usize| Vector3::from(ctx.scene.bodies[i].com_m);
            let mut parts = Vec::new();
            for (i, cols) in ctx.parts.iter().enumerate() {
                for c in cols {
                    let Some(shape) = crate::sim::build::primitive_shape(&c.shape) else {
                        continue;
                    };
                    parts.push(LosPart {
                        body: i,
                        name: c.name.clone(),
                        // Part pose relative to the body's centre of mass (body axes).
                        pose_com: Isometry3::from_parts(
                            Translation3::from(-com(i)),
                            UnitQuaternion::identity(),
                        ) * c.pose_body,
                        shape,
                    });
                }
            }
            // The end points must be outside every part (else the segment is blocked from the start
            // whatever happens): a located error.
            let inside = |body: usize, p: &Vector3<f64>| -> Option<String> {
                parts.iter().filter(|q| q.body == body).find_map(|q| {
                    let local = q.pose_com.inverse_transform_point(&(p - com(body)).into());
                    let l32 = bevy_rapier3d::rapier::math::Vector::new(
                        local.x as f32,
                        local.y as f32,
                        local.z as f32,
                    );
                    q.shape.contains_local_point(l32).then(|| q.name.clone())
                })
            };
            let sensor_m = Vector3::from(self.position_m);
            if let Some(p) = inside(s, &sensor_m) {
                return Err(BuildError::at(
                    "position_m",
                    format!("the sensor is inside part `{p}` of `{}`", self.sensor_body),
                ));
            }
            if let Some(p) = inside(t, &point_m) {
                return Err(BuildError::at(
                    "standoff_m",
                    format!(
                        "the point {} m out of port `{}` is inside part `{p}` of `{}`: give a larger standoff_m",
                        self.standoff_m, self.port, self.target
                    ),
                ));
            }
            Ok(Box::new(LineOfSight {
                name: self.name.clone(),
                sensor_body: s,
                sensor_off: sensor_m - com(s),
                boresight: Vector3::from(self.boresight).normalize(),
                half_fov_rad: self.half_fov_deg.to_radians(),
                range_m: self.range_m,
                target: t,
                point_off: point_m - com(t),
                clearance_m: self.clearance_m,
                parts,
            }))
        }
    }

    /// One collider as [`LineOfSight`] sees it.
    #[derive(Clone)]
    pub struct LosPart {
        /// Body index.
        pub body: usize,
        /// Collider name.
        pub name: String,
        /// Pose relative to the body's centre of mass, body axes.
        pub pose_com: Isometry3<f64>,
        /// Shape.
        pub shape: bevy_rapier3d::rapier::prelude::SharedShape,
    }

    /// [`LineOfSightParams`] as the monitor checks it.
    #[derive(Clone)]
    pub struct LineOfSight {
        /// Name.
        pub name: String,
        /// Sensor body.
        pub sensor_body: usize,
        /// Sensor position from the sensor body's centre of mass, body frame, m.
        pub sensor_off: Vector3<f64>,
        /// Unit boresight, body frame.
        pub boresight: Vector3<f64>,
        /// Half field of view, rad.
        pub half_fov_rad: f64,
        /// Range, m.
        pub range_m: f64,
        /// Target body.
        pub target: usize,
        /// Target point from the target's centre of mass, body frame, m.
        pub point_off: Vector3<f64>,
        /// Required clearance, m.
        pub clearance_m: f64,
        /// Every collider of every body.
        pub parts: Vec<LosPart>,
    }

    impl LineOfSight {
        /// (range term, field-of-view term, obstruction term and the closest part), m.
        pub fn terms(&self, v: &MonitorView) -> (f64, f64, f64, Option<&str>) {
            let sb = &v.bodies[self.sensor_body];
            let s = sb.pos_m + sb.att * self.sensor_off;
            let tb = &v.bodies[self.target];
            let p = tb.pos_m + tb.att * self.point_off;
            let los = p - s;
            let d = los.norm();
            let range = self.range_m - d;
            let bore = sb.att * self.boresight;
            let fov = if d > 0.0 {
                let theta = (bore.dot(&los) / d).clamp(-1.0, 1.0).acos();
                let phi = self.half_fov_rad - theta;
                if phi.abs() <= std::f64::consts::FRAC_PI_2 {
                    d * phi.sin()
                } else {
                    d * phi.signum()
                }
            } else {
                0.0
            };
            // The segment in a frame at the sensor point with world axes.
            let seg = bevy_rapier3d::parry::shape::Segment::new(
                bevy_rapier3d::rapier::math::Vector::ZERO,
                bevy_rapier3d::rapier::math::Vector::new(los.x as f32, los.y as f32, los.z as f32),
            );
            let seg_pose = Isometry3::from_parts(Translation3::from(s), UnitQuaternion::identity());
            let mut obs = f64::INFINITY;
            let mut closest = None;
            for q in &self.parts {
                let b = &v.bodies[q.body];
                let pose = Isometry3::from_parts(Translation3::from(b.pos_m), b.att) * q.pose_com;
                let dist = segment_clearance(&seg_pose, &los, &seg, &pose, &*q.shape);
                if dist < obs {
                    obs = dist;
                    closest = Some(q.name.as_str());
                }
            }
            (range, fov, obs - self.clearance_m, closest)
        }
    }

    /// Signed clearance of the segment from the origin of `pose_a` along `los` (world axes) to
    /// the shape `b` at `pose_b`, m: parry's distance when a ray cast along the segment (solid
    /// shape, so a start inside counts) does not hit the shape and GJK finds them apart; else
    /// minus the
    /// penetration depth (parry's EPA), or minus the f32 resolution of the relative pose where the
    /// overlap is too thin for EPA — a blocked line is never reported clear.
    fn segment_clearance(
        pose_a: &Isometry3<f64>,
        los: &Vector3<f64>,
        seg: &dyn bevy_rapier3d::rapier::prelude::Shape,
        pose_b: &Isometry3<f64>,
        b: &dyn bevy_rapier3d::rapier::prelude::Shape,
    ) -> f64 {
        use bevy_rapier3d::parry::query::Ray;
        use bevy_rapier3d::rapier::math::{Pose, Vector};
        let rel64 = pose_a.inv_mul(pose_b);
        let rel = crate::sim::conv::pose(&rel64);
        let ray = Ray::new(
            Vector::ZERO,
            Vector::new(los.x as f32, los.y as f32, los.z as f32),
        );
        let resolution = crate::sim::monitor::F32_REL_TOL * (1.0 + rel64.translation.vector.norm());
        if b.cast_ray(&rel, &ray, 1.0, true).is_none() {
            let d = crate::sim::monitor::shape_distance(pose_a, seg, pose_b, b);
            // Not hit, but touching to GJK's precision: counted as blocked (conservative).
            return if d > 0.0 { d } else { -resolution };
        }
        match bevy_rapier3d::parry::query::contact(&Pose::IDENTITY, seg, &rel, b, 0.0) {
            Ok(Some(c)) if (c.dist as f64) < -resolution => c.dist as f64,
            _ => -resolution,
        }
    }

    impl Guarantee for LineOfSight {
        fn name(&self) -> &str {
            &self.name
        }
        fn margin(&self, v: &MonitorView) -> f64 {
            let (a, b, c, _) = self.terms(v);
            a.min(b).min(c)
        }
        /// See [`LineOfSightParams`].
        fn rate_bound(&self, m: &dyn MotionBounds) -> Option<f64> {
            let (s, t) = (self.sensor_body, self.target);
            let u_s = m.speed_bound(s) + m.omega_bound(s) * self.sensor_off.norm();
            let u_t = m.speed_bound(t) + m.omega_bound(t) * self.point_off.norm();
            let d_max = m.separation_bound(s, t) + self.sensor_off.norm() + self.point_off.norm();
            let n = self.parts.iter().map(|q| q.body + 1).max().unwrap_or(0);
            let w = (0..n)
                .map(|i| m.speed_bound(i) + m.omega_bound(i) * m.extent_m(i))
                .fold(0.0, f64::max);
            let range = u_s + u_t;
            let fov = 2.0 * (u_s + u_t) + m.omega_bound(s) * d_max;
            let obs = u_s.max(u_t) + w;
            Some(range.max(fov).max(obs))
        }
        fn reads(&self) -> Reads {
            Reads::Bodies
        }
        /// parry's distances are f32 (≈ 1e-6 relative): refine to 10 µm.
        fn tolerance(&self) -> f64 {
            1e-5
        }
    }
}
#[cfg(feature = "sim")]
pub use line_of_sight::*;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::orbit::constants::{J2_EARTH, MU_EARTH_M3_S2, R_EARTH_M};

    /// [`J2_GRADIENT_FACTOR`]: the Frobenius norm of the J2 acceleration's Jacobian (central
    /// differences, relative step 1e-6) over 10⁵ directions of a fixed-seed generator never
    /// exceeds the factor times (3/2)J2μR_E²/r⁵ (reference: the largest value, √96 ≈ 9.798,
    /// on the poles).
    #[test]
    fn j2_gradient_factor_bounds_the_jacobian() {
        let r: f64 = 7.0e6;
        let scale = 1.5 * J2_EARTH * MU_EARTH_M3_S2 * R_EARTH_M * R_EARTH_M / r.powi(5);
        let mut rng = crate::math::rng::GaussianNoise::new(20261205);
        let mut worst: f64 = 0.0;
        for _ in 0..100_000 {
            let u = Vector3::new(
                rng.standard_normal(),
                rng.standard_normal(),
                rng.standard_normal(),
            )
            .normalize()
                * r;
            let h = 1e-6 * r;
            let mut frob2 = 0.0;
            for j in 0..3 {
                let mut e = Vector3::zeros();
                e[j] = h;
                let d = (crate::orbit::gravity::accel_j2(&(u + e))
                    - crate::orbit::gravity::accel_j2(&(u - e)))
                    / (2.0 * h);
                frob2 += d.norm_squared();
            }
            worst = worst.max(frob2.sqrt() / scale);
        }
        println!("largest |∇a_J2|_F / ((3/2)J2μR²/r⁵) = {worst}");
        assert!(worst <= J2_GRADIENT_FACTOR, "{worst}");
        assert!(worst > 9.7, "{worst}: the sample missed the poles");
    }
}
