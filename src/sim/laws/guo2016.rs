//! Simulation wiring of `control::guo2016` (to be written by the guo2016 integration).

use crate::control::guo2016::SceneSpec;
use crate::scene::{LoadedScene, SceneError};
use bevy::prelude::*;

/// Adds this law's resources and systems for one controller of the scene.
pub fn install(
    _app: &mut App,
    loaded: &LoadedScene,
    path: &str,
    spec: &SceneSpec,
) -> Result<(), SceneError> {
    super::body_index(loaded, path, "body", &spec.body)?;
    Err(loaded.error_at(
        path,
        "the guo2016 controller is not wired into the simulation yet",
    ))
}
