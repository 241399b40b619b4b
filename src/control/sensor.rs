//! A relative-navigation sensor any controller can use: a pose every `period_s`, seeded
//! Gaussian noise, a delivery latency, and a velocity that is either measured exactly or
//! differenced from successive delivered poses (optionally low-pass filtered). Bevy-free.
//!
//! It generalises the vision system of Xu, Wen, Wei (2019) (`control::xu2019::VisionSpec`,
//! which now builds one of these with `planar: true`): a planar sensor measures (x, y, yaw) in
//! the frame's x–y plane, a 3-D one the full position and attitude.
//!
//! # Model
//! - Exposures at t = k·`period_s` (k = 0, 1, …). At an exposure the truth of the chosen
//!   quantity ([`crate::control::interface::MeasuredFrame`]) is taken at the current step (the
//!   sensor is stepped once per simulation step: a period shorter than the step repeats the
//!   step's state) and noise is added: position N(0, σ_p²) per axis; attitude a rotation by
//!   N(0, σ_θ²) per axis (planar: the yaw only).
//! - The sample reaches the controller `latency_s` after its exposure (at the first step at
//!   or after that time).
//! - Velocity `Ideal`: the truth at exposure. `Differenced`: the backward difference of the
//!   last two delivered samples (for the attitude, the rotation between them as a rotation
//!   vector over the interval), then a first-order low-pass with time constant
//!   `velocity_filter_s` (0: none), updated once per delivered sample with gain
//!   α = T/(τ + T). The first delivered sample has zero velocity.
//! - Noise draws, in order per exposure: planar (x, y, yaw); 3-D (x, y, z, then the three
//!   attitude components). A seed gives the same numbers on every run.

use crate::control::interface::{MeasuredFrame, Measurement};
use crate::control::navfilter::NavFilterSpec;
use crate::math::rng::GaussianNoise;
use nalgebra::{UnitQuaternion, Vector2, Vector3};
use serde::{Deserialize, Serialize};
use std::collections::VecDeque;

/// Where a sensor's velocity comes from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
pub enum VelocitySource {
    /// Backward difference of successive (noisy, delayed) pose measurements, optionally
    /// low-pass filtered (`velocity_filter_s`).
    #[default]
    Differenced,
    /// The sensor also measures the velocity exactly (an ideal sensor).
    Ideal,
}

/// A sensor, as written in a scene (`sensor: Some((period_s: 0.1, …))` in a controller).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SensorSpec {
    /// What is measured, in which frame (default: the controlled body's own world pose).
    #[serde(default)]
    pub frame: MeasuredFrame,
    /// Measurement period, s.
    pub period_s: f64,
    /// Delay from exposure to the controller, s.
    #[serde(default)]
    pub latency_s: f64,
    /// Standard deviation of the position noise per axis, m.
    #[serde(default)]
    pub position_noise_m: f64,
    /// Standard deviation of the attitude noise per axis, deg.
    #[serde(default)]
    pub angle_noise_deg: f64,
    /// Where the velocity comes from.
    #[serde(default)]
    pub velocity: VelocitySource,
    /// Time constant of a first-order low-pass filter on the differenced velocity, s (0: none).
    #[serde(default)]
    pub velocity_filter_s: f64,
    /// Seed of the noise.
    #[serde(default)]
    pub seed: u64,
    /// Measure only (x, y, yaw) in the frame's x–y plane (air-bearing tables).
    #[serde(default)]
    pub planar: bool,
    /// A navigation filter the measurements feed; the law then flies on its estimate instead
    /// of the raw measurement ([`crate::control::navfilter`]; needs `frame: Hill`, a 3-D
    /// sensor with position noise, and the `Differenced` velocity without its low-pass).
    #[serde(default)]
    pub filter: Option<NavFilterSpec>,
}

/// Largest accepted sensor period, latency or filter constant, s (about 31.7 years): beyond,
/// sample times stop being representable to a step.
pub const MAX_SENSOR_TIME_S: f64 = 1e9;

impl SensorSpec {
    /// Checks the numbers: `Err((field, message))` with the field relative to the spec.
    pub fn validate(&self) -> Result<(), (String, String)> {
        let bad = |f: &str, m: String| Err((f.to_string(), m));
        if !(self.period_s.is_finite() && self.period_s > 0.0 && self.period_s <= MAX_SENSOR_TIME_S)
        {
            return bad(
                "period_s",
                format!(
                    "must be a positive number of seconds up to {MAX_SENSOR_TIME_S:e}, got {}",
                    self.period_s
                ),
            );
        }
        for (f, v) in [
            ("latency_s", self.latency_s),
            ("velocity_filter_s", self.velocity_filter_s),
        ] {
            if !(v.is_finite() && (0.0..=MAX_SENSOR_TIME_S).contains(&v)) {
                return bad(
                    f,
                    format!("must be zero or a positive number of seconds, got {v}"),
                );
            }
        }
        for (f, v) in [
            ("position_noise_m", self.position_noise_m),
            ("angle_noise_deg", self.angle_noise_deg),
        ] {
            if !(v.is_finite() && (0.0..1e6).contains(&v)) {
                return bad(
                    f,
                    format!("must be a standard deviation ≥ 0 (below 1e6), got {v}"),
                );
            }
        }
        if let Some(f) = &self.filter {
            f.validate()
                .map_err(|(g, m)| (format!("filter.0.{g}"), m))?;
            let why = if self.frame != MeasuredFrame::Hill {
                Some(
                    "the filter runs on the CW or Yamanaka–Ankersen relative model in the target's Hill frame: give the sensor `frame: Hill`",
                )
            } else if self.planar {
                Some("the filter estimates the 3-D relative state: a planar sensor cannot feed it")
            } else if self.position_noise_m <= 0.0 {
                Some("the filter weighs measurements by their noise: give `position_noise_m` > 0")
            } else if self.velocity != VelocitySource::Differenced || self.velocity_filter_s > 0.0 {
                Some(
                    "with a filter the velocity is the filter's estimate: leave `velocity` Differenced and `velocity_filter_s` 0 (they would be ignored)",
                )
            } else {
                None
            };
            if let Some(m) = why {
                return bad("filter", m.to_string());
            }
        }
        Ok(())
    }

    /// The period against the scene step: a sensor exposes at most once per step (the truth
    /// exists at the steps), so `period_s` ≥ `dt_s` (a period of 1e−308 s would otherwise ask
    /// for 10³⁰⁶ exposures in one step).
    pub fn check_period(&self, dt_s: f64) -> Result<(), (String, String)> {
        if self.period_s < dt_s * (1.0 - 1e-9) {
            return Err((
                "period_s".to_string(),
                format!(
                    "a sensor cannot expose faster than the scene step dt_s = {dt_s} s, got {:?} s",
                    self.period_s
                ),
            ));
        }
        Ok(())
    }
}

/// The truth a sensor measures at one step, in its frame.
#[derive(Debug, Clone, Copy)]
pub struct SensorTruth {
    /// Position, m.
    pub pos_m: Vector3<f64>,
    /// Velocity seen in the frame, m/s.
    pub vel_m_s: Vector3<f64>,
    /// Attitude, measured body (or port) frame → sensor frame.
    pub att: UnitQuaternion<f64>,
    /// Angular velocity, sensor-frame axes, rad/s.
    pub omega_rad_s: Vector3<f64>,
}

/// One exposure on its way to the controller.
#[derive(Debug, Clone, Copy)]
pub struct SensorSample {
    /// Exposure time, s.
    pub t_s: f64,
    /// Delivery time, s.
    pub deliver_s: f64,
    /// Noisy position, m.
    pub pos_m: Vector3<f64>,
    /// Noisy attitude.
    pub att: UnitQuaternion<f64>,
    /// Planar: noisy yaw, rad, wrapped to (−π, π].
    pub yaw_rad: f64,
    /// True velocity at exposure (used with `VelocitySource::Ideal`), m/s.
    pub vel_m_s: Vector3<f64>,
    /// True angular velocity at exposure (with `VelocitySource::Ideal`), rad/s.
    pub omega_rad_s: Vector3<f64>,
}

/// A running sensor.
#[derive(Debug, Clone)]
pub struct Sensor {
    /// The scene's request.
    pub spec: SensorSpec,
    /// Exposures taken, not yet delivered.
    pub in_flight: VecDeque<SensorSample>,
    /// Index of the next exposure (at `k · period_s`).
    pub next_exposure: u64,
    /// Last delivered sample.
    pub last: Option<SensorSample>,
    /// Velocity estimate: planar (ẋ, ẏ, ψ̇); 3-D the linear part.
    pub vel_est: Vector3<f64>,
    /// 3-D: angular velocity estimate, rad/s.
    pub omega_est: Vector3<f64>,
    /// The latest delivered measurement.
    pub measurement: Option<Measurement>,
    noise: GaussianNoise,
}

/// Wraps an angle to (−π, π]: [`crate::orbit::kepler::wrap_pi`] (which wraps to [−π, π)) with
/// −π sent to π.
pub fn wrap_pi(a: f64) -> f64 {
    let w = crate::orbit::kepler::wrap_pi(a);
    if w == -std::f64::consts::PI {
        std::f64::consts::PI
    } else {
        w
    }
}

/// Yaw of an attitude about the frame's z axis: the angle of the body x axis from frame x, rad.
pub fn yaw_of(att: &UnitQuaternion<f64>) -> f64 {
    let x = att * Vector3::x();
    x.y.atan2(x.x)
}

impl Sensor {
    /// A sensor at t = 0 (its first exposure is at t = 0).
    pub fn new(spec: SensorSpec) -> Self {
        let noise = GaussianNoise::new(spec.seed);
        Self {
            spec,
            in_flight: VecDeque::new(),
            next_exposure: 0,
            last: None,
            vel_est: Vector3::zeros(),
            omega_est: Vector3::zeros(),
            measurement: None,
            noise,
        }
    }

    /// Steps the sensor at time `t_s` (scene step `dt_s`) with the truth of this step; returns
    /// the latest delivered measurement (its `fresh` flag says whether it arrived now).
    pub fn step(&mut self, t_s: f64, dt_s: f64, truth: &SensorTruth) -> Option<Measurement> {
        let eps = 1e-9 * dt_s;
        let v = self.spec.clone();
        if let Some(m) = self.measurement.as_mut() {
            m.fresh = false;
        }
        while self.next_exposure as f64 * v.period_s <= t_s + eps {
            let te = self.next_exposure as f64 * v.period_s;
            self.next_exposure += 1;
            let sample = if v.planar {
                let nx = self.noise.standard_normal() * v.position_noise_m;
                let ny = self.noise.standard_normal() * v.position_noise_m;
                let nt = self.noise.standard_normal() * v.angle_noise_deg.to_radians();
                let xy = truth.pos_m.xy() + Vector2::new(nx, ny);
                let yaw = wrap_pi(yaw_of(&truth.att) + nt);
                SensorSample {
                    t_s: te,
                    deliver_s: te + v.latency_s,
                    pos_m: Vector3::new(xy.x, xy.y, truth.pos_m.z),
                    att: UnitQuaternion::from_axis_angle(&Vector3::z_axis(), yaw),
                    yaw_rad: yaw,
                    vel_m_s: Vector3::new(truth.vel_m_s.x, truth.vel_m_s.y, 0.0),
                    omega_rad_s: Vector3::new(0.0, 0.0, truth.omega_rad_s.z),
                }
            } else {
                let sp = v.position_noise_m;
                let sa = v.angle_noise_deg.to_radians();
                let n = &mut self.noise;
                let dp = Vector3::new(
                    n.standard_normal(),
                    n.standard_normal(),
                    n.standard_normal(),
                ) * sp;
                let da = Vector3::new(
                    n.standard_normal(),
                    n.standard_normal(),
                    n.standard_normal(),
                ) * sa;
                let att = UnitQuaternion::from_scaled_axis(da) * truth.att;
                SensorSample {
                    t_s: te,
                    deliver_s: te + v.latency_s,
                    pos_m: truth.pos_m + dp,
                    att,
                    yaw_rad: yaw_of(&att),
                    vel_m_s: truth.vel_m_s,
                    omega_rad_s: truth.omega_rad_s,
                }
            };
            self.in_flight.push_back(sample);
        }
        while self
            .in_flight
            .front()
            .is_some_and(|m| m.deliver_s <= t_s + eps)
        {
            let m = self.in_flight.pop_front().expect("front exists");
            let (vel, omega) = match v.velocity {
                VelocitySource::Ideal => (m.vel_m_s, m.omega_rad_s),
                VelocitySource::Differenced => self.difference(&m),
            };
            self.last = Some(m);
            self.measurement = Some(Measurement {
                t_s: m.t_s,
                delivered_s: t_s,
                fresh: true,
                frame: v.frame,
                pos_m: m.pos_m,
                vel_m_s: vel,
                att: m.att,
                omega_rad_s: omega,
                yaw_rad: v.planar.then_some(m.yaw_rad),
            });
        }
        self.measurement
    }

    /// The differenced (and filtered) velocity after delivering `m`.
    fn difference(&mut self, m: &SensorSample) -> (Vector3<f64>, Vector3<f64>) {
        let v = &self.spec;
        let alpha = if v.velocity_filter_s > 0.0 {
            Some(v.period_s / (v.velocity_filter_s + v.period_s))
        } else {
            None
        };
        if v.planar {
            let raw = match &self.last {
                None => Vector3::zeros(),
                Some(p) => {
                    let h = m.t_s - p.t_s;
                    let d = m.pos_m.xy() - p.pos_m.xy();
                    Vector3::new(d.x / h, d.y / h, wrap_pi(m.yaw_rad - p.yaw_rad) / h)
                }
            };
            match (&self.last, alpha) {
                (Some(_), Some(a)) => self.vel_est += (raw - self.vel_est) * a,
                _ => self.vel_est = raw,
            }
            (
                Vector3::new(self.vel_est.x, self.vel_est.y, 0.0),
                Vector3::new(0.0, 0.0, self.vel_est.z),
            )
        } else {
            let (raw_v, raw_w) = match &self.last {
                None => (Vector3::zeros(), Vector3::zeros()),
                Some(p) => {
                    let h = m.t_s - p.t_s;
                    // Rotation from the previous attitude to this one, in sensor-frame axes.
                    let dq = m.att * p.att.inverse();
                    ((m.pos_m - p.pos_m) / h, dq.scaled_axis() / h)
                }
            };
            match (&self.last, alpha) {
                (Some(_), Some(a)) => {
                    self.vel_est += (raw_v - self.vel_est) * a;
                    self.omega_est += (raw_w - self.omega_est) * a;
                }
                _ => {
                    self.vel_est = raw_v;
                    self.omega_est = raw_w;
                }
            }
            (self.vel_est, self.omega_est)
        }
    }
}

#[cfg(test)]
mod tests {
    //! References: exact arithmetic of the model (exposure and delivery times; the difference
    //! of two noiseless samples of a uniform motion equals its velocity); the noise moments of
    //! the standard normal law.
    use super::*;

    /// `wrap_pi` (through the orbit module's) equals, bit for bit, the inline formula it
    /// replaced, `(a + π).rem_euclid(2π) − π` with −π sent to π, on the boundaries, their
    /// neighbours and a sweep, and lands in (−π, π].
    #[test]
    fn wrap_pi_is_the_former_formula_bit_for_bit() {
        use std::f64::consts::PI;
        let former = |a: f64| {
            let w = (a + PI).rem_euclid(2.0 * PI) - PI;
            if w == -PI { PI } else { w }
        };
        let mut xs = vec![
            0.0,
            -0.0,
            PI,
            -PI,
            3.0 * PI,
            -3.0 * PI,
            1e-300,
            -1e-300,
            1e6,
            -1e6,
        ];
        for b in [PI, -PI, 3.0 * PI, -3.0 * PI] {
            xs.extend([b.next_up(), b.next_down()]);
        }
        xs.extend((-2000..=2000).map(|k| k as f64 * 0.0137));
        for a in xs {
            let w = wrap_pi(a);
            assert_eq!(w.to_bits(), former(a).to_bits(), "a = {a:e}");
            assert!(w > -PI && w <= PI, "a = {a:e}: {w}");
        }
    }

    fn truth(t: f64) -> SensorTruth {
        SensorTruth {
            pos_m: Vector3::new(1.0 + 0.1 * t, -2.0 + 0.05 * t, 0.3 - 0.02 * t),
            vel_m_s: Vector3::new(0.1, 0.05, -0.02),
            att: UnitQuaternion::from_scaled_axis(Vector3::new(0.0, 0.0, 0.2 * t)),
            omega_rad_s: Vector3::new(0.0, 0.0, 0.2),
        }
    }

    fn spec(planar: bool) -> SensorSpec {
        SensorSpec {
            frame: MeasuredFrame::World,
            period_s: 0.1,
            latency_s: 0.05,
            position_noise_m: 0.0,
            angle_noise_deg: 0.0,
            velocity: VelocitySource::Differenced,
            velocity_filter_s: 0.0,
            seed: 1,
            planar,
            filter: None,
        }
    }

    /// Noiseless uniform motion: after two deliveries the differenced velocity is exact, and
    /// each measurement is the truth at its exposure, delivered `latency_s` later.
    #[test]
    fn val_sensor_latency_and_differencing() {
        for planar in [true, false] {
            let mut s = Sensor::new(spec(planar));
            let dt = 0.01;
            let mut seen = Vec::new();
            for k in 0..40u64 {
                let t = k as f64 * dt;
                if let Some(m) = s.step(t, dt, &truth(t))
                    && m.fresh
                {
                    seen.push((t, m));
                }
            }
            assert_eq!(
                seen.len(),
                4,
                "exposures 0, 0.1, 0.2, 0.3 delivered by 0.39 s"
            );
            for (t, m) in &seen {
                assert!((t - m.t_s - 0.05).abs() < 1e-9, "latency");
                assert!((m.pos_m - truth(m.t_s).pos_m).norm() < 1e-12);
            }
            let m = seen[3].1;
            let want = truth(0.0).vel_m_s;
            let got = if planar {
                Vector3::new(m.vel_m_s.x, m.vel_m_s.y, want.z)
            } else {
                m.vel_m_s
            };
            assert!((got - want).norm() < 1e-9, "{got} vs {want}");
            assert!((m.omega_rad_s.z - 0.2).abs() < 1e-9);
        }
    }

    /// Noise of σ = 1 cm: sample mean and standard deviation of 4000 position errors.
    #[test]
    fn val_sensor_noise_moments() {
        let mut sp = spec(false);
        sp.position_noise_m = 0.01;
        sp.latency_s = 0.0;
        sp.period_s = 0.01;
        let mut s = Sensor::new(sp);
        let mut errs = Vec::new();
        for k in 0..4000u64 {
            let t = k as f64 * 0.01;
            let m = s.step(t, 0.01, &truth(t)).expect("delivered at once");
            errs.push(m.pos_m.x - truth(t).pos_m.x);
        }
        let n = errs.len() as f64;
        let mean = errs.iter().sum::<f64>() / n;
        let sd = (errs.iter().map(|e| (e - mean).powi(2)).sum::<f64>() / (n - 1.0)).sqrt();
        // 4 standard errors: 4·σ/√n for the mean, 4·σ/√(2n) for the deviation.
        assert!(mean.abs() < 4.0 * 0.01 / n.sqrt(), "mean {mean}");
        assert!((sd - 0.01).abs() < 4.0 * 0.01 / (2.0 * n).sqrt(), "sd {sd}");
    }
}
