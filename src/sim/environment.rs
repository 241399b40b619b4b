//! The environment layer of the Bevy app: a scene's `environment` becomes its gravity field
//! ([`super::Gravity`]) and the resources the Environment stage and the controllers read.
//!
//! - `Orbit`: [`OrbitEnv`] (the f64 reference orbit and its gravity model, a list of terms:
//!   two-body, plus J2 if the scene's `j2` is set) and its differential gravity.
//! - `SunEarthL2`: [`crate::environment::L2Gravity`] about the formation centre, and
//!   [`L2Frame`], a copy of the centre advanced on the same steps (bit-identical) for frame
//!   conversions (controllers, reports), brought to the current step in the Sense stage.
//! - `FreeSpace`: nothing. `AirBearing`: the lab gravity the controllers see (the table itself
//!   is [`super::airbearing`]).
//!
//! Each is a [`EnvironmentModel`]: the plugin takes its gravity field from it and keeps
//! [`EnvNow`], the [`EnvObs`] the controllers read, current after each of the model's updates.

use super::{Clock, Gravity, OrbitEnv, SimStep, Stage};
use crate::environment::{EnvObs, EnvironmentModel, GravityField, L2Gravity};
use crate::orbit::constants::MU_EARTH_M3_S2;
use crate::orbit::l2::L2Centre;
use crate::scene::{Environment, OrbitSpec};
use bevy::prelude::*;
use nalgebra::Vector3;

/// The formation centre of a `SunEarthL2` scene as the controllers see it (advanced on the
/// same steps as the gravity field's copy, in the Sense stage).
#[derive(Resource, Debug, Clone)]
pub struct L2Frame(pub L2Centre);

impl EnvironmentModel for L2Frame {
    fn gravity_field(&self) -> Option<Box<dyn GravityField>> {
        Some(Box::new(L2Gravity(self.0.clone())))
    }
    /// The centre; `states_rot` is left empty (the controller host fills its own copy).
    fn observe(&self, env: &mut EnvObs) {
        env.set_l2(&self.0);
    }
}

impl EnvironmentModel for OrbitEnv {
    fn gravity_field(&self) -> Option<Box<dyn GravityField>> {
        Some(Box::new(self.clone()))
    }
    fn observe(&self, env: &mut EnvObs) {
        let (r, v) = self.reference.state();
        env.set_orbit(r, v, self.reference.gravity());
    }
}

/// The environment as the controllers see it now: the model's [`EnvObs`], brought up to date
/// after each of the model's own updates (orbit: after the reference orbit is advanced in
/// [`Stage::Physics`]; L2: after [`sync_l2_frame`] in [`EnvironmentSense`]; constant otherwise).
#[derive(Resource, Debug, Clone, Default)]
pub struct EnvNow(pub EnvObs);

/// The environment's Sense-stage systems (the L2 frame brought to this step, then
/// [`EnvNow`]); the controllers sense after it. Empty outside `SunEarthL2` scenes.
#[derive(SystemSet, Debug, Clone, PartialEq, Eq, Hash)]
pub struct EnvironmentSense;

/// Writes the model `E`'s current [`EnvObs`] into [`EnvNow`].
fn publish<E: Resource + EnvironmentModel>(model: Res<E>, mut now: ResMut<EnvNow>) {
    model.observe(&mut now.0);
}

/// Sense: brings the [`L2Frame`] to the current step.
pub fn sync_l2_frame(clock: Res<Clock>, mut frame: ResMut<L2Frame>) {
    while frame.0.steps < clock.step {
        frame.0.advance();
    }
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

/// The scene's environment: owns its gravity field ([`Gravity`], from the model's
/// [`EnvironmentModel::gravity_field`]), [`EnvNow`] (what the controllers read) and the model's
/// resources — `Orbit`: [`OrbitEnv`] and `publish` of it in [`Stage::Physics`] after the
/// reference orbit is advanced; `SunEarthL2`: [`L2Frame`], and `sync_l2_frame` then `publish` in
/// [`EnvironmentSense`] (in [`Stage::Sense`]; the controllers' `host_sense` runs after it);
/// `FreeSpace` and `AirBearing`: [`EnvNow`] only (the table is
/// [`super::airbearing::AirBearingPlugin`]). The gravity itself is applied by the pipeline's
/// `environment_gravity` in [`super::Order::Gravity`]. Add it after [`super::PipelinePlugin`].
pub struct EnvironmentPlugin {
    /// Orbit scenes: the reference orbit and its gravity.
    orbit: Option<OrbitEnv>,
    /// `SunEarthL2` scenes: the formation centre at t = 0.
    l2: Option<L2Centre>,
    /// Air-bearing scenes: the table as the controllers see it.
    table: Option<crate::environment::Table>,
    /// The reference orbit's ECI state at t = 0 (orbit scenes).
    reference: Option<(Vector3<f64>, Vector3<f64>)>,
}

/// Inserts a model's gravity field (if any) and its [`EnvNow`].
fn install_model(app: &mut App, model: &dyn EnvironmentModel) {
    if let Some(field) = model.gravity_field() {
        app.insert_resource(Gravity(field));
    }
    let mut now = EnvObs::default();
    model.observe(&mut now);
    app.insert_resource(EnvNow(now));
}

impl EnvironmentPlugin {
    /// The plugin of a scene's `environment`, stepped at `dt_s`.
    pub fn new(environment: &Environment, dt_s: f64) -> Self {
        let mut plugin = Self {
            orbit: None,
            l2: None,
            table: None,
            reference: None,
        };
        match environment {
            Environment::Orbit {
                reference,
                j2,
                gravity_gradient,
            } => {
                let (r, v) = reference_state(reference);
                // The scene's `j2` flag becomes the gravity model's list of terms here, once.
                plugin.orbit = Some(OrbitEnv {
                    reference: crate::orbit::integrate::ReferenceOrbit::from_state(
                        r,
                        v,
                        crate::orbit::gravity::earth_gravity(*j2),
                    ),
                    gravity_gradient: *gravity_gradient,
                });
                plugin.reference = Some((r, v));
            }
            Environment::FreeSpace => {}
            Environment::AirBearing(spec) => {
                plugin.table = Some(crate::environment::Table {
                    gravity_lab_m_s2: spec.gravity_lab_m_s2(),
                });
            }
            Environment::SunEarthL2(spec) => plugin.l2 = Some(L2Centre::new(spec, dt_s)),
        }
        plugin
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
        if let Some(env) = &self.orbit {
            install_model(app, env);
            app.insert_resource(env.clone());
            app.add_systems(
                SimStep,
                publish::<OrbitEnv>
                    .in_set(Stage::Physics)
                    .after(super::advance_orbit),
            );
        } else if let Some(centre) = &self.l2 {
            let frame = L2Frame(centre.clone());
            install_model(app, &frame);
            app.insert_resource(frame);
            app.add_systems(
                SimStep,
                (sync_l2_frame, publish::<L2Frame>)
                    .chain()
                    .in_set(EnvironmentSense),
            );
        } else if let Some(table) = &self.table {
            install_model(app, table);
        } else {
            install_model(app, &crate::environment::FreeSpace);
        }
    }
}
