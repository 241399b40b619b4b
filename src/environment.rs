//! The environment layer, Bevy-free: gravity fields acting on the bodies' centres of mass and
//! what a controller may know about the environment it flies in.
//!
//! The Bevy layer (`sim::environment`) turns a scene's `environment` into one of these models
//! ([`EnvironmentModel`]), kept in its one environment resource (`sim::Env`), and advances it;
//! the controller host hands every law an [`EnvObs`] (the one snapshot type of the environment)
//! with the same numbers. An orbit's gravity is a list of
//! [`crate::orbit::gravity::GravityTerm`]s.

use crate::orbit::gravity::GravityTerm;
use crate::orbit::l2::L2Centre;
use nalgebra::Vector3;

/// A gravity field acting on every body's centre of mass, in the world frame, at its
/// environment model's current time (the model moves it on: [`EnvironmentModel::advance`]). The
/// physics step evaluates it twice per step (velocity Verlet), so it must be a function of
/// position (and of that time) only.
pub trait GravityField: Send + Sync {
    /// Acceleration at a world position, m/s², at the field's current time.
    fn accel_m_s2(&self, pos_world_m: &Vector3<f64>) -> Vector3<f64>;
}

/// The gravity field of a `SunEarthL2` scene (Zhang et al. 2018): differential Sun + Earth–Moon
/// barycentre gravity about a thrust-free formation centre (see [`crate::orbit::l2`]). The world
/// frame is non-rotating, its axes those of the Sun–EMB rotating frame at t = 0, its origin on
/// the centre.
#[derive(Debug, Clone)]
pub struct L2Gravity(pub L2Centre);

impl GravityField for L2Gravity {
    fn accel_m_s2(&self, pos_world_m: &Vector3<f64>) -> Vector3<f64> {
        self.0.differential_accel_world_m_s2(pos_world_m)
    }
}

impl EnvironmentModel for L2Gravity {
    fn gravity(&self) -> Option<&dyn GravityField> {
        Some(self)
    }
    /// Advances one scene step (the centre steps by its own `dt_s`, the scene's step).
    fn advance(&mut self, dt_s: f64) {
        debug_assert!((dt_s - self.0.dt_s).abs() <= 1e-12 * dt_s);
        self.0.advance();
    }
    /// The centre; `states_rot` is left empty (the controller host fills its own copy).
    fn observe(&self, env: &mut EnvObs) {
        env.set_l2(&self.0);
    }
}

/// An environment model: its state (a reference orbit, a formation centre, …), the gravity
/// field it applies to every body and what a controller knows of it. A new kind of environment
/// implements this (and adds its [`EnvObs`] variant); the pipeline advances it once per step and
/// asks it for its field and for its [`EnvObs`], so neither the physics nor the controller host
/// match on the kinds.
pub trait EnvironmentModel: Send + Sync {
    /// The gravity field this environment applies to every body's centre of mass, at the
    /// model's current time, or `None` (force-free space; a table whose forces are its own
    /// systems').
    fn gravity(&self) -> Option<&dyn GravityField>;
    /// Moves the model's time (and its gravity field's) on by `dt_s`: the pipeline calls it once
    /// per step, at the head of the physics step.
    fn advance(&mut self, dt_s: f64);
    /// Writes what a controller knows of the environment now into `env`, in place.
    fn observe(&self, env: &mut EnvObs);
}

/// Force-free space: no field, an inertial world frame.
#[derive(Debug, Clone, Copy, Default)]
pub struct FreeSpace;

impl EnvironmentModel for FreeSpace {
    fn gravity(&self) -> Option<&dyn GravityField> {
        None
    }
    /// Nothing moves.
    fn advance(&mut self, _dt_s: f64) {}
    fn observe(&self, env: &mut EnvObs) {
        *env = EnvObs::FreeSpace;
    }
}

/// An air-bearing table as the controllers see it (its forces — film, friction, tilt — are the
/// table's own systems, `sim::airbearing`).
#[derive(Debug, Clone, Copy)]
pub struct Table {
    /// Gravity in the lab frame, m/s².
    pub gravity_lab_m_s2: Vector3<f64>,
}

impl EnvironmentModel for Table {
    fn gravity(&self) -> Option<&dyn GravityField> {
        None
    }
    /// The lab gravity is constant.
    fn advance(&mut self, _dt_s: f64) {}
    fn observe(&self, env: &mut EnvObs) {
        *env = EnvObs::AirBearing {
            gravity_lab_m_s2: self.gravity_lab_m_s2,
        };
    }
}

/// What a controller knows of the environment at one instant (f64): the one snapshot type. The
/// controller host keeps one, refreshed in place at the start of every step (and one after the
/// physics for post-step diagnostics); laws see it by reference (`Observation::env`,
/// `BuildContext::env`).
#[derive(Debug, Clone, Default)]
pub enum EnvObs {
    /// Force-free space, inertial world frame.
    #[default]
    FreeSpace,
    /// Earth orbit: the world frame's origin rides on the reference orbit (the target's
    /// unforced orbit), its axes parallel to the Earth-centred inertial frame.
    Orbit {
        /// Reference orbit position, ECI, m.
        r_ref_eci_m: Vector3<f64>,
        /// Reference orbit velocity, ECI, m/s.
        v_ref_eci_m_s: Vector3<f64>,
        /// The scene's gravity model: its terms, summed in this order (two-body, plus J2 if the
        /// scene's `j2` is set).
        gravity: Vec<GravityTerm>,
    },
    /// Near the Sun–Earth L2 point: the world origin is the formation centre.
    SunEarthL2 {
        /// The formation centre at the current step (frame conversions to the rotating frame).
        centre: L2Centre,
        /// Every body's planar state in the rotating frame, `centre.world_to_rot` of its world
        /// state, scene order (computed once per step by the controller host; empty where it
        /// is not).
        states_rot: Vec<crate::orbit::l2::L2State>,
    },
    /// An air-bearing table: the lab frame (x, y in the table top, z up).
    AirBearing {
        /// Gravity in the lab frame, m/s².
        gravity_lab_m_s2: Vector3<f64>,
    },
}

impl EnvObs {
    /// The reference orbit's ECI state (r, v), in orbit scenes.
    pub fn reference(&self) -> Option<(Vector3<f64>, Vector3<f64>)> {
        match self {
            EnvObs::Orbit {
                r_ref_eci_m,
                v_ref_eci_m_s,
                ..
            } => Some((*r_ref_eci_m, *v_ref_eci_m_s)),
            _ => None,
        }
    }

    /// Sets this snapshot to an orbit scene's reference state and gravity model, in place (no
    /// allocation once it holds an orbit).
    pub fn set_orbit(
        &mut self,
        r_ref_eci_m: Vector3<f64>,
        v_ref_eci_m_s: Vector3<f64>,
        gravity_terms: &[GravityTerm],
    ) {
        if let EnvObs::Orbit {
            r_ref_eci_m: r,
            v_ref_eci_m_s: v,
            gravity,
        } = self
        {
            *r = r_ref_eci_m;
            *v = v_ref_eci_m_s;
            if gravity.as_slice() != gravity_terms {
                gravity.clear();
                gravity.extend_from_slice(gravity_terms);
            }
        } else {
            *self = EnvObs::Orbit {
                r_ref_eci_m,
                v_ref_eci_m_s,
                gravity: gravity_terms.to_vec(),
            };
        }
    }

    /// Makes this snapshot a copy of `src`, reusing its allocations where the kinds match.
    pub fn assign(&mut self, src: &EnvObs) {
        match src {
            EnvObs::Orbit {
                r_ref_eci_m,
                v_ref_eci_m_s,
                gravity,
            } => self.set_orbit(*r_ref_eci_m, *v_ref_eci_m_s, gravity),
            EnvObs::SunEarthL2 { centre, states_rot } => {
                self.set_l2(centre);
                if let EnvObs::SunEarthL2 { states_rot: s, .. } = self {
                    s.extend_from_slice(states_rot);
                }
            }
            EnvObs::FreeSpace | EnvObs::AirBearing { .. } => *self = src.clone(),
        }
    }

    /// Sets this snapshot to a `SunEarthL2` scene's formation centre, in place; its
    /// `states_rot` is emptied (the host fills it).
    pub fn set_l2(&mut self, centre_now: &L2Centre) {
        if let EnvObs::SunEarthL2 { centre, states_rot } = self {
            centre.clone_from(centre_now);
            states_rot.clear();
        } else {
            *self = EnvObs::SunEarthL2 {
                centre: centre_now.clone(),
                states_rot: Vec::new(),
            };
        }
    }
}
