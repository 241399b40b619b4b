//! Simulation wiring of `control::xu2015` (to be written by the xu2015 integration).

use crate::control::xu2015::SceneSpec;
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
        "the xu2015 controller is not wired into the simulation yet",
    ))
}
