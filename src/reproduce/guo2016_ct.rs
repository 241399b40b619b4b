//! The Guo 2016 law in continuous time, and sampled, in a Bevy-free f64 plant: what the law
//! itself does, separated from what a fixed control period does to it.
//!
//! Plant (state of 19 components, SI): target orbit `[r_t; v_t]` (ECI, two-body + J2 as the
//! scene asks), relative motion `[r; v] = [r_c − r_t; v_c − v_t]` (inertial axes), chaser
//! attitude `q` (body → inertial, scalar first) and body rate `ω` (body axes). Forces: gravity
//! on both spacecraft, the law's force `q·F_b/m`; torques: the law's `τ` plus the paper's
//! `d_τ = A cos(n t)` (body axes), Euler's equations with the chaser inertia. The target is at
//! rest in attitude (the bundled scenes' target: identity attitude, zero rate; [`CtSetup`]
//! refuses any other). The law sees the exact state — the same observation the ECS builds
//! (the law as `control::guo2016` hosts it), differential gravity with J2.
//!
//! - **Continuous time** ([`run_continuous`]): the law is evaluated at every right-hand-side
//!   evaluation; the closed loop is integrated by the linearly implicit Rosenbrock method of
//!   [`crate::math::ode`] (adaptive step, L-stable: near the wall the sliding variable's
//!   dynamics become stiff, with a rate ∝ k2/h²), with the terminal event h(r1) = 0 (or r1
//!   leaving 0 < x < 2a). The Jacobian's position increments are kept below 1/1000 of the
//!   distance to the wall, so a finite difference never straddles it.
//! - **Sampled** ([`run_sampled`]): the law evaluated every `period_s` on the exact state and
//!   its command held (zero-order hold, as the ECS does at 100 Hz), the plant integrated
//!   between samples by the same method; the corridor is judged at the samples (as the ECS
//!   judges it) and, separately, at every accepted integration point in between.

use crate::control::guo2016::{Guo2016, Guo2016Command, Guo2016Observation, Guo2016Params};
use crate::math::ode::{OdeEnd, OdeOptions, OdeStats, OdeSystem, integrate_rosenbrock23};
use crate::orbit::constants::MU_EARTH_M3_S2;
use crate::orbit::gravity::{accel_earth, earth_gravity};
use crate::scene::LoadedScene;
use crate::sim::Simulation;
use nalgebra::{Quaternion, SVector, UnitQuaternion, Vector3};

/// Plant state: `[r_t (3), v_t (3), r (3), v (3), q (w, x, y, z), ω_body (3)]`.
pub type PlantState = SVector<f64, 19>;

/// Everything the plant needs, taken from a loaded Guo 2016 scene.
#[derive(Debug, Clone)]
pub struct CtSetup {
    /// The law's parameters (mass and inertia from the chaser body).
    pub params: Guo2016Params,
    /// Disturbance torque amplitude `A`, chaser body axes, N·m.
    pub dtau_amplitude_nm: Vector3<f64>,
    /// Disturbance angular frequency `n`, rad/s.
    pub dtau_rate_rad_s: f64,
    /// J2 on both spacecraft.
    pub j2: bool,
    /// Initial state.
    pub y0: PlantState,
}

impl CtSetup {
    /// Reads the initial states from the scene's own simulation at t = 0 (so both start from
    /// the same numbers) and the law's parameters from its Guo2016 entry.
    pub fn from_scene(loaded: &LoadedScene) -> Result<Self, String> {
        let spec = super::guo2016::spec_of(loaded);
        let sim = Simulation::new(loaded).map_err(|e| e.to_string())?;
        let body = |name: &str| sim.body(name).ok_or(format!("no body {name}"));
        let (c, t) = (body(&spec.chaser)?, body(&spec.target)?);
        if t.omega_rad_s.norm() != 0.0 || t.att.angle() != 0.0 {
            return Err("the continuous-time plant needs a target at rest in attitude".into());
        }
        let (r_ref, v_ref) = sim.reference_state().ok_or("the scene has no orbit")?;
        let cb = loaded
            .scene
            .bodies
            .iter()
            .find(|b| b.name == spec.chaser)
            .ok_or("no chaser body")?;
        let params = spec.params(cb.mass_kg, cb.inertia_kg_m2.matrix());
        let r_t = r_ref + t.pos_m;
        let v_t = v_ref + t.vel_m_s;
        // Mean motion of the reference orbit (vis-viva), the ECS's default disturbance rate.
        let a = 1.0 / (2.0 / r_ref.norm() - v_ref.norm_squared() / MU_EARTH_M3_S2);
        let n = spec
            .disturbance_rate_rad_s
            .unwrap_or((MU_EARTH_M3_S2 / (a * a * a)).sqrt());
        let j2 = matches!(
            &loaded.scene.environment,
            crate::scene::Environment::Orbit { j2: true, .. }
        );
        let w_body = c.att.inverse() * c.omega_rad_s;
        let q = c.att.into_inner();
        let mut y0 = PlantState::zeros();
        let parts = [r_t, v_t, c.pos_m - t.pos_m, c.vel_m_s - t.vel_m_s];
        for (k, v) in parts.iter().enumerate() {
            y0.fixed_rows_mut::<3>(3 * k).copy_from(v);
        }
        y0[12] = q.w;
        y0[13] = q.i;
        y0[14] = q.j;
        y0[15] = q.k;
        y0.fixed_rows_mut::<3>(16).copy_from(&w_body);
        Ok(Self {
            params,
            dtau_amplitude_nm: Vector3::from(*spec.disturbance_torque_amplitude_nm),
            dtau_rate_rad_s: n,
            j2,
            y0,
        })
    }
}

fn v3(y: &PlantState, i: usize) -> Vector3<f64> {
    Vector3::new(y[i], y[i + 1], y[i + 2])
}

fn quat(y: &PlantState) -> UnitQuaternion<f64> {
    UnitQuaternion::from_quaternion(Quaternion::new(y[12], y[13], y[14], y[15]))
}

/// The observation the ECS would build from this state (target at rest, identity attitude).
pub fn observation(y: &PlantState, t_s: f64, j2: bool) -> Guo2016Observation {
    let (r_t, r) = (v3(y, 0), v3(y, 6));
    Guo2016Observation {
        t_s,
        q_chaser_body_to_world: quat(y),
        q_target_body_to_world: UnitQuaternion::identity(),
        rate_chaser_body_rad_s: v3(y, 16),
        rate_target_body_rad_s: Vector3::zeros(),
        pos_rel_world_m: r,
        vel_rel_world_m_s: v3(y, 9),
        grav_diff_world_m_s2: accel_earth(&(r_t + r), earth_gravity(j2))
            - accel_earth(&r_t, earth_gravity(j2)),
    }
}

/// One recorded point of a plant run.
#[derive(Debug, Clone, Copy)]
pub struct CtSample {
    /// Time, s.
    pub t_s: f64,
    /// Corridor function h(r1), m².
    pub h_m2: f64,
    /// Signed distance of the chaser centre of mass to the corridor wall (+ inside), m.
    pub wall_distance_m: f64,
    /// |r_e|, m.
    pub r_e_m: f64,
    /// |σ_e|.
    pub sigma_e: f64,
    /// |F| the law commands at this state (continuous) or holds (sampled), N.
    pub force_n: f64,
    /// β = k2/h² + k3.
    pub beta: f64,
    /// |S| of the translation rows, m/s.
    pub s_tr_m_s: f64,
    /// ḣ, m²/s.
    pub h_dot_m2_s: f64,
    /// |ṙ_e|, m/s.
    pub r_e_dot_m_s: f64,
    /// Chaser centre of mass in target axes, m.
    pub r1_m: Vector3<f64>,
}

/// The closed loop as an [`OdeSystem`].
struct Loop<'a> {
    s: &'a CtSetup,
    law: Guo2016,
    /// `Some(command)`: held (sampled law); `None`: the law at every evaluation.
    held: Option<Guo2016Command>,
    /// Judge the event (continuous time) or only record (sampled).
    event: bool,
    samples: Vec<CtSample>,
    /// Record at most one sample per this much time (the last accepted point is kept too), s.
    record_dt_s: f64,
    last_record_s: f64,
    /// First accepted point outside the corridor, s.
    first_outside_s: Option<f64>,
    min_h_m2: f64,
    min_wall_m: f64,
    peak_force_n: f64,
    peak_torque_nm: f64,
}

impl Loop<'_> {
    fn command(&self, t: f64, y: &PlantState) -> Guo2016Command {
        match self.held {
            Some(c) => c,
            None => self.law.control(&observation(y, t, self.s.j2)).0,
        }
    }
}

impl OdeSystem<19> for Loop<'_> {
    fn rhs(&mut self, t: f64, y: &PlantState) -> PlantState {
        let s = self.s;
        let u = self.command(t, y);
        let (r_t, r) = (v3(y, 0), v3(y, 6));
        let q = quat(y);
        let w = v3(y, 16);
        let p = &s.params;
        let a_t = accel_earth(&r_t, earth_gravity(s.j2));
        let a_c =
            accel_earth(&(r_t + r), earth_gravity(s.j2)) + q * u.force_body_n / p.chaser_mass_kg;
        let j = p.chaser_inertia_body_kg_m2;
        let dtau = s.dtau_amplitude_nm * (s.dtau_rate_rad_s * t).cos();
        let wdot = j.try_inverse().unwrap_or_else(nalgebra::Matrix3::zeros)
            * (u.torque_body_nm + dtau - w.cross(&(j * w)));
        let qq = Quaternion::new(y[12], y[13], y[14], y[15]);
        let qd = qq * Quaternion::new(0.0, w.x, w.y, w.z) * 0.5;
        let mut d = PlantState::zeros();
        d.fixed_rows_mut::<3>(0).copy_from(&v3(y, 3));
        d.fixed_rows_mut::<3>(3).copy_from(&a_t);
        d.fixed_rows_mut::<3>(6).copy_from(&v3(y, 9));
        d.fixed_rows_mut::<3>(9).copy_from(&(a_c - a_t));
        d[12] = qd.w;
        d[13] = qd.i;
        d[14] = qd.j;
        d[15] = qd.k;
        d.fixed_rows_mut::<3>(16).copy_from(&wdot);
        d
    }

    fn fd_increment(&self, _t: f64, y: &PlantState, i: usize) -> f64 {
        let base = f64::EPSILON.sqrt() * y[i].abs().max(1.0);
        if (6..9).contains(&i) {
            // Keep the perturbed position on the same side of the wall, by a wide margin.
            let wall = self.s.params.corridor().signed_distance_m(&v3(y, 6)).abs();
            base.min(1e-3 * wall).max(1e-300)
        } else {
            base
        }
    }

    fn event(&self, _t: f64, y: &PlantState) -> f64 {
        if !self.event {
            return f64::INFINITY;
        }
        let c = self.s.params.corridor();
        let r1 = v3(y, 6);
        if c.inside(&r1) { c.h(&r1) } else { -1.0 }
    }

    fn accepted(&mut self, t: f64, y: &mut PlantState) {
        let n = (y[12] * y[12] + y[13] * y[13] + y[14] * y[14] + y[15] * y[15]).sqrt();
        for k in 12..16 {
            y[k] /= n;
        }
        let (cmd, d) = match self.held {
            Some(c) => (c, self.law.control(&observation(y, t, self.s.j2)).1),
            None => self.law.control(&observation(y, t, self.s.j2)),
        };
        let c = self.s.params.corridor();
        let r1 = v3(y, 6);
        let wall = c.signed_distance_m(&r1);
        if !c.inside(&r1) && self.first_outside_s.is_none() {
            self.first_outside_s = Some(t);
        }
        self.min_h_m2 = self.min_h_m2.min(d.h_m2);
        self.min_wall_m = self.min_wall_m.min(wall);
        let f = cmd.force_body_n.norm();
        self.peak_force_n = self.peak_force_n.max(f);
        self.peak_torque_nm = self.peak_torque_nm.max(cmd.torque_body_nm.norm());
        if t - self.last_record_s >= self.record_dt_s || self.samples.is_empty() {
            self.last_record_s = t;
            self.samples.push(CtSample {
                t_s: t,
                h_m2: d.h_m2,
                wall_distance_m: wall,
                r_e_m: Vector3::new(d.x[3], d.x[4], d.x[5]).norm(),
                sigma_e: Vector3::new(d.x[0], d.x[1], d.x[2]).norm(),
                force_n: f,
                beta: d.beta,
                s_tr_m_s: Vector3::new(d.s[3], d.s[4], d.s[5]).norm(),
                h_dot_m2_s: d.h_dot_m2_s,
                r_e_dot_m_s: Vector3::new(d.x_dot[3], d.x_dot[4], d.x_dot[5]).norm(),
                r1_m: r1,
            });
        }
    }
}

/// What one plant run measured.
#[derive(Debug, Clone)]
pub struct CtRun {
    /// Label.
    pub label: String,
    /// Control period, s (`None`: continuous time).
    pub period_s: Option<f64>,
    /// Recorded points (accepted integration points, thinned to ≥ `record_dt_s` apart) and
    /// the final point.
    pub samples: Vec<CtSample>,
    /// Time reached, s.
    pub t_end_s: f64,
    /// Why the run ended (continuous time: `Event` = the chaser reached the wall; sampled
    /// runs always run to the end).
    pub end: OdeEnd,
    /// Sampled law: first sample at which the law found itself outside (`inside` false), s.
    pub first_exit_at_sample_s: Option<f64>,
    /// First accepted integration point outside the corridor, s (continuous time: the event).
    pub first_outside_s: Option<f64>,
    /// Smallest h at the accepted points, m².
    pub min_h_m2: f64,
    /// Smallest signed wall distance at the accepted points, m.
    pub min_wall_m: f64,
    /// Largest |F| at the accepted points (continuous: the law at those states; sampled: the
    /// held commands), N.
    pub peak_force_n: f64,
    /// Largest |τ|, N·m.
    pub peak_torque_nm: f64,
    /// Final |r_e|, m.
    pub final_r_e_m: f64,
    /// Final |σ_e|.
    pub final_sigma_e: f64,
    /// Final h, m².
    pub final_h_m2: f64,
    /// Integrator counters (summed over the sample intervals of a sampled run).
    pub stats: OdeStats,
}

/// Tolerances: rtol 1e-9; atol 0.1 mm / 1e-7 m/s on the target orbit, 1e-10 m and m/s on the
/// relative motion, 1e-12 on the quaternion and the rate. Smallest step 1e-13 s.
fn options(h0_s: f64, h_max_s: f64) -> OdeOptions<19> {
    let mut atol = PlantState::repeat(1e-12);
    for i in 0..3 {
        atol[i] = 1e-4;
        atol[3 + i] = 1e-7;
        atol[6 + i] = 1e-10;
        atol[9 + i] = 1e-10;
    }
    OdeOptions {
        rtol: 1e-9,
        atol,
        h0_s,
        h_max_s,
        h_min_s: 1e-13,
        event_time_tol_s: 1e-9,
        max_steps: 2_000_000,
    }
}

fn new_loop(s: &CtSetup, held: Option<Guo2016Command>, event: bool, record_dt_s: f64) -> Loop<'_> {
    Loop {
        s,
        law: Guo2016::new(s.params.clone()),
        held,
        event,
        samples: Vec::new(),
        record_dt_s,
        last_record_s: f64::NEG_INFINITY,
        first_outside_s: None,
        min_h_m2: f64::INFINITY,
        min_wall_m: f64::INFINITY,
        peak_force_n: 0.0,
        peak_torque_nm: 0.0,
    }
}

fn finish(label: &str, period_s: Option<f64>, mut lp: Loop<'_>, t: f64, y: &PlantState) -> CtRun {
    // Always keep the last accepted point.
    if lp.samples.last().is_some_and(|s| s.t_s < t) {
        lp.last_record_s = f64::NEG_INFINITY;
        let mut y1 = *y;
        lp.accepted(t, &mut y1);
    }
    let d = lp.law.control(&observation(y, t, lp.s.j2)).1;
    CtRun {
        label: label.to_string(),
        period_s,
        samples: lp.samples,
        t_end_s: t,
        end: OdeEnd::Reached,
        first_exit_at_sample_s: None,
        first_outside_s: lp.first_outside_s,
        min_h_m2: lp.min_h_m2,
        min_wall_m: lp.min_wall_m,
        peak_force_n: lp.peak_force_n,
        peak_torque_nm: lp.peak_torque_nm,
        final_r_e_m: Vector3::new(d.x[3], d.x[4], d.x[5]).norm(),
        final_sigma_e: Vector3::new(d.x[0], d.x[1], d.x[2]).norm(),
        final_h_m2: d.h_m2,
        stats: OdeStats::default(),
    }
}

/// The law in continuous time from the setup's initial state for `duration_s`, recording a
/// point at least every `record_dt_s`.
pub fn run_continuous(s: &CtSetup, label: &str, duration_s: f64, record_dt_s: f64) -> CtRun {
    let mut lp = new_loop(s, None, true, record_dt_s);
    let mut y0 = s.y0;
    lp.accepted(0.0, &mut y0);
    let res = integrate_rosenbrock23(&mut lp, 0.0, &y0, duration_s, &options(1e-4, 0.5));
    let mut run = finish(label, None, lp, res.t_s, &res.y);
    run.end = res.end;
    run.stats = res.stats;
    if matches!(res.end, OdeEnd::Event { .. }) {
        run.first_outside_s = Some(res.t_s);
    }
    run
}

/// The law sampled every `period_s` (zero-order hold) from the setup's initial state for
/// `duration_s`.
pub fn run_sampled(
    s: &CtSetup,
    label: &str,
    period_s: f64,
    duration_s: f64,
    record_dt_s: f64,
) -> CtRun {
    let law = Guo2016::new(s.params.clone());
    let mut y = s.y0;
    let n = (duration_s / period_s).round() as usize;
    let mut lp = new_loop(s, None, false, record_dt_s);
    let mut first_exit_at_sample = None;
    let mut stats = OdeStats {
        h_min_used_s: f64::INFINITY,
        ..Default::default()
    };
    let mut t = 0.0;
    for k in 0..n {
        t = k as f64 * period_s;
        let (cmd, d) = law.control(&observation(&y, t, s.j2));
        if !d.inside && first_exit_at_sample.is_none() {
            first_exit_at_sample = Some(t);
        }
        lp.held = Some(cmd);
        if k == 0 {
            lp.accepted(0.0, &mut y);
        }
        let res =
            integrate_rosenbrock23(&mut lp, t, &y, t + period_s, &options(period_s, period_s));
        stats.accepted += res.stats.accepted;
        stats.rejected_error += res.stats.rejected_error;
        stats.rhs_evals += res.stats.rhs_evals;
        stats.h_min_used_s = stats.h_min_used_s.min(res.stats.h_min_used_s);
        stats.h_max_used_s = stats.h_max_used_s.max(res.stats.h_max_used_s);
        y = res.y;
        t = res.t_s;
        if res.end != OdeEnd::Reached {
            let mut run = finish(label, Some(period_s), lp, t, &y);
            run.end = res.end;
            run.first_exit_at_sample_s = first_exit_at_sample;
            run.stats = stats;
            return run;
        }
    }
    lp.held = None;
    let mut run = finish(label, Some(period_s), lp, t, &y);
    run.first_exit_at_sample_s = first_exit_at_sample;
    run.stats = stats;
    run
}
