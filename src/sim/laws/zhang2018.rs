//! Simulation wiring of `control::zhang2018` (to be written by the zhang2018 integration).

use crate::control::zhang2018::SceneSpec;
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
        "the zhang2018 controller is not wired into the simulation yet",
    ))
}
