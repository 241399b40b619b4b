//! The environment layer of the Bevy app: a scene's `environment` becomes its gravity field
//! ([`super::Gravity`]) and the resources the Environment stage and the controllers read.
//!
//! - `Orbit`: [`OrbitEnv`] (the f64 reference orbit and its gravity model, a list of terms:
//!   two-body, plus J2 if the scene's `j2` is set) and its differential gravity.
//! - `SunEarthL2`: [`crate::environment::L2Gravity`] about the formation centre, and
//!   [`L2Frame`], a copy of the centre advanced on the same steps (bit-identical) for frame
//!   conversions (controllers, reports), brought to the current step in the Sense stage.
//! - `FreeSpace`: nothing. `AirBearing`: see [`super::airbearing`].

use super::{Clock, Gravity, OrbitEnv, SimStep, Stage};
use crate::environment::L2Gravity;
use crate::orbit::constants::MU_EARTH_M3_S2;
use crate::orbit::l2::L2Centre;
use crate::scene::{Environment, OrbitSpec};
use bevy::prelude::*;
use nalgebra::Vector3;

/// The formation centre of a `SunEarthL2` scene as the controllers see it (advanced on the
/// same steps as the gravity field's copy, in the Sense stage).
#[derive(Resource, Debug, Clone)]
pub struct L2Frame(pub L2Centre);

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

/// The scene's environment: owns its gravity field ([`Gravity`]) and the resources the
/// Environment stage and the controllers read — `Orbit`: [`OrbitEnv`]; `SunEarthL2`:
/// [`L2Frame`] and the system `sync_l2_frame` in [`Stage::Sense`] (the controllers' `host_sense`
/// runs after it); `FreeSpace` and `AirBearing`: nothing (the table is
/// [`super::airbearing::AirBearingPlugin`]). The gravity itself is applied by the pipeline's
/// `environment_gravity` in [`super::Order::Gravity`] and the reference orbit advanced in
/// [`Stage::Physics`]. Add it after [`super::PipelinePlugin`].
pub struct EnvironmentPlugin {
    /// Orbit scenes: the reference orbit and its gravity.
    orbit: Option<OrbitEnv>,
    /// `SunEarthL2` scenes: the formation centre at t = 0.
    l2: Option<L2Centre>,
    /// The reference orbit's ECI state at t = 0 (orbit scenes).
    reference: Option<(Vector3<f64>, Vector3<f64>)>,
}

impl EnvironmentPlugin {
    /// The plugin of a scene's `environment`, stepped at `dt_s`.
    pub fn new(environment: &Environment, dt_s: f64) -> Self {
        let mut plugin = Self {
            orbit: None,
            l2: None,
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
            Environment::FreeSpace | Environment::AirBearing(_) => {}
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
        if let Some(env) = &self.orbit {
            app.insert_resource(Gravity(Box::new(env.clone())));
            app.insert_resource(env.clone());
        }
        if let Some(centre) = &self.l2 {
            app.insert_resource(Gravity(Box::new(L2Gravity(centre.clone()))));
            app.insert_resource(L2Frame(centre.clone()));
            app.add_systems(SimStep, sync_l2_frame.in_set(Stage::Sense));
        }
    }
}
