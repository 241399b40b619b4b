//! The environment layer of the Bevy app: a scene's `environment` becomes [`Env`], the one
//! resource through which every system reads the environment — its model ([`EnvModel`], an
//! [`EnvironmentModel`]: the state, the gravity field on every body) and [`Env::now`], the
//! [`EnvObs`] the controllers read.
//!
//! - `Orbit`: [`OrbitEnv`] (the f64 reference orbit and its gravity model, a list of terms:
//!   two-body, plus J2 if the scene's `j2` is set) and its differential gravity.
//! - `SunEarthL2`: [`L2Gravity`], the formation centre and its differential gravity; the
//!   controllers' frame conversions use the same centre.
//! - `FreeSpace`: nothing. `AirBearing`: the lab gravity the controllers see (the table itself
//!   is [`super::airbearing`]).

use super::{SimStep, Stage};
use crate::environment::{EnvObs, EnvironmentModel, FreeSpace, GravityField, L2Gravity, Table};
use crate::orbit::constants::MU_EARTH_M3_S2;
use crate::orbit::l2::L2Centre;
use crate::scene::{Environment, OrbitSpec};
use bevy::prelude::*;
use nalgebra::Vector3;

/// The orbital environment: the reference orbit (f64, with its gravity model: the list of
/// terms every body's differential gravity also sums) and the torque toggle.
#[derive(Debug, Clone)]
pub struct OrbitEnv {
    /// Reference orbit (the world frame's origin), ECI, and the gravity model's terms
    /// ([`crate::orbit::integrate::ReferenceOrbit::gravity`]).
    pub reference: crate::orbit::integrate::ReferenceOrbit,
    /// Apply gravity-gradient torques.
    pub gravity_gradient: bool,
}

impl GravityField for OrbitEnv {
    fn accel_m_s2(&self, pos_world_m: &Vector3<f64>) -> Vector3<f64> {
        crate::orbit::gravity::differential_accel(
            &self.reference.state().0,
            pos_world_m,
            self.reference.gravity(),
        )
    }
}

impl EnvironmentModel for OrbitEnv {
    fn gravity(&self) -> Option<&dyn GravityField> {
        Some(self)
    }
    /// Propagates the reference orbit by `dt_s`.
    fn advance(&mut self, dt_s: f64) {
        self.reference.step(dt_s);
    }
    fn observe(&self, env: &mut EnvObs) {
        let (r, v) = self.reference.state();
        env.set_orbit(r, v, self.reference.gravity());
    }
}

/// The kinds of environment a scene names, each an [`EnvironmentModel`].
#[derive(Debug, Clone)]
pub enum EnvModel {
    /// Force-free space.
    FreeSpace(FreeSpace),
    /// Earth orbit: the reference orbit and its differential gravity.
    Orbit(OrbitEnv),
    /// Near the Sun–Earth L2 point: the formation centre and its differential gravity.
    SunEarthL2(L2Gravity),
    /// An air-bearing table as the controllers see it.
    AirBearing(Table),
}

impl EnvModel {
    /// The model, to ask for its gravity field and its [`EnvObs`].
    pub fn model(&self) -> &dyn EnvironmentModel {
        match self {
            EnvModel::FreeSpace(m) => m,
            EnvModel::Orbit(m) => m,
            EnvModel::SunEarthL2(m) => m,
            EnvModel::AirBearing(m) => m,
        }
    }

    /// The model, to advance it.
    fn model_mut(&mut self) -> &mut dyn EnvironmentModel {
        match self {
            EnvModel::FreeSpace(m) => m,
            EnvModel::Orbit(m) => m,
            EnvModel::SunEarthL2(m) => m,
            EnvModel::AirBearing(m) => m,
        }
    }
}

/// The scene's environment: the one resource through which every system reads it (inserted by
/// [`EnvironmentPlugin`], present in every [`super::Simulation`]).
///
/// Its [`Env::model`] is advanced once per pipeline step, by the step's length h, at the head
/// of the physics step (the velocity Verlet update evaluates the gravity at the bodies' end
/// positions): before [`Stage::Physics`] it holds the state at the step's start t, from there
/// on the state at t + h. [`Env::now`] is the model's [`EnvObs`], published after each of the
/// model's updates the controllers are meant to see: orbit scenes right after the physics step
/// (in [`Stage::Physics`]); `SunEarthL2` scenes at the head of each step (in
/// [`EnvironmentSense`], so a law's post-step diagnostics see the centre the step started
/// from); constant otherwise.
///
/// Readers: the pipeline's `environment_gravity` (gravity, gravity-gradient torque),
/// `physics_step` (gravity at the step's end), `check_guarantees` (the reference orbit),
/// [`super::multirate::plan_step`], [`super::output::record`] (the reference orbit's columns),
/// the controller host ([`Env::now`], the gravity at the bodies) and [`super::Simulation`]'s
/// accessors.
#[derive(Resource, Debug, Clone)]
pub struct Env {
    /// The model: its state now and its gravity field.
    pub model: EnvModel,
    /// What the controllers read (see above for when it is brought up to date).
    pub now: EnvObs,
}

impl Env {
    /// The environment of a model, its [`Env::now`] observed from it.
    pub fn new(model: EnvModel) -> Self {
        let mut now = EnvObs::default();
        model.model().observe(&mut now);
        Self { model, now }
    }

    /// The gravity field on every body's centre of mass now, if any.
    pub fn gravity(&self) -> Option<&dyn GravityField> {
        self.model.model().gravity()
    }

    /// The gravity field's acceleration at a world position now, m/s² (zero without a field).
    pub fn accel_m_s2(&self, pos_world_m: &Vector3<f64>) -> Vector3<f64> {
        self.gravity()
            .map_or_else(Vector3::zeros, |g| g.accel_m_s2(pos_world_m))
    }

    /// Moves the model on by `dt_s` (the physics step's head; [`Env::now`] is not touched).
    pub fn advance(&mut self, dt_s: f64) {
        self.model.model_mut().advance(dt_s);
    }

    /// Brings [`Env::now`] up to date with the model.
    pub fn publish(&mut self) {
        self.model.model().observe(&mut self.now);
    }

    /// The orbital environment, in orbit scenes.
    pub fn orbit(&self) -> Option<&OrbitEnv> {
        match &self.model {
            EnvModel::Orbit(o) => Some(o),
            _ => None,
        }
    }

    /// The formation centre now, in `SunEarthL2` scenes.
    pub fn l2_centre(&self) -> Option<&L2Centre> {
        match &self.model {
            EnvModel::SunEarthL2(l2) => Some(&l2.0),
            _ => None,
        }
    }
}

/// The environment's Sense-stage systems (`SunEarthL2` scenes: [`Env::now`] published for this
/// step); the controllers sense after it. Empty in other scenes.
#[derive(SystemSet, Debug, Clone, PartialEq, Eq, Hash)]
pub struct EnvironmentSense;

/// Brings [`Env::now`] up to date with the model.
fn publish(mut env: ResMut<Env>) {
    env.publish();
}

/// The reference orbit's ECI state at t = 0 of an orbit spec.
pub fn reference_state(reference: &OrbitSpec) -> (Vector3<f64>, Vector3<f64>) {
    match reference {
        OrbitSpec::Elements {
            a_m,
            e,
            i_deg,
            raan_deg,
            argp_deg,
            true_anomaly_deg,
        } => crate::orbit::kepler::ClassicalElements {
            a_m: *a_m,
            e: *e,
            i_rad: i_deg.to_radians(),
            raan_rad: raan_deg.to_radians(),
            argp_rad: argp_deg.to_radians(),
            true_anomaly_rad: true_anomaly_deg.to_radians(),
        }
        .to_state(MU_EARTH_M3_S2),
        OrbitSpec::State { r_eci_m, v_eci_m_s } => {
            (Vector3::from(*r_eci_m), Vector3::from(*v_eci_m_s))
        }
    }
}

/// The scene's environment: owns [`Env`] and the system that publishes [`Env::now`]: orbit
/// scenes in [`Stage::Physics`] after the physics step (which advances the model);
/// `SunEarthL2` scenes in [`EnvironmentSense`] (in [`Stage::Sense`]; the controllers'
/// `host_sense` runs after it); none in `FreeSpace` and `AirBearing` scenes (the table is
/// [`super::airbearing::AirBearingPlugin`]). The gravity itself is applied by the pipeline's
/// `environment_gravity` in [`super::Order::Gravity`]. Add it after [`super::PipelinePlugin`].
pub struct EnvironmentPlugin {
    /// The model at t = 0.
    model: EnvModel,
    /// The reference orbit's ECI state at t = 0 (orbit scenes).
    reference: Option<(Vector3<f64>, Vector3<f64>)>,
}

impl EnvironmentPlugin {
    /// The plugin of a scene's `environment`, stepped at `dt_s`.
    pub fn new(environment: &Environment, dt_s: f64) -> Self {
        let mut reference = None;
        let model = match environment {
            Environment::Orbit {
                reference: spec,
                j2,
                gravity_gradient,
            } => {
                let (r, v) = reference_state(spec);
                reference = Some((r, v));
                // The scene's `j2` flag becomes the gravity model's list of terms here, once.
                EnvModel::Orbit(OrbitEnv {
                    reference: crate::orbit::integrate::ReferenceOrbit::from_state(
                        r,
                        v,
                        crate::orbit::gravity::earth_gravity(*j2),
                    ),
                    gravity_gradient: *gravity_gradient,
                })
            }
            Environment::FreeSpace => EnvModel::FreeSpace(FreeSpace),
            Environment::AirBearing(spec) => EnvModel::AirBearing(Table {
                gravity_lab_m_s2: spec.gravity_lab_m_s2(),
            }),
            Environment::SunEarthL2(spec) => {
                EnvModel::SunEarthL2(L2Gravity(L2Centre::new(spec, dt_s)))
            }
        };
        Self { model, reference }
    }

    /// The reference orbit's ECI state (position m, velocity m/s) at t = 0, in orbit scenes
    /// (Hill-frame initial states are written relative to it).
    pub fn reference(&self) -> Option<(Vector3<f64>, Vector3<f64>)> {
        self.reference
    }
}

impl Plugin for EnvironmentPlugin {
    fn build(&self, app: &mut App) {
        app.configure_sets(SimStep, EnvironmentSense.in_set(Stage::Sense));
        app.insert_resource(Env::new(self.model.clone()));
        match &self.model {
            EnvModel::Orbit(_) => {
                app.add_systems(
                    SimStep,
                    publish.in_set(Stage::Physics).after(super::physics_step),
                );
            }
            EnvModel::SunEarthL2(_) => {
                app.add_systems(SimStep, publish.in_set(EnvironmentSense));
            }
            EnvModel::FreeSpace(_) | EnvModel::AirBearing(_) => {}
        }
    }
}
