//! The Bevy wiring of each paper's control law: one file per law. `install` adds the law's
//! resources and systems (Sense/Control/Actuate stages of `SimStep`) for every controller the
//! scene lists.

use crate::control::ControllerSpec;
use crate::scene::{LoadedScene, SceneError};
use bevy::prelude::*;

pub mod geng2015;
pub mod guo2016;
pub mod xu2015;
pub mod xu2019;
pub mod zhang2018;

/// Installs the scene's controllers. Called after the pipeline exists, before t = 0 is
/// monitored. Errors (e.g. a controller naming a missing body) point into the scene.
pub fn install(app: &mut App, loaded: &LoadedScene) -> Result<(), SceneError> {
    for (i, spec) in loaded.scene.controllers.iter().enumerate() {
        let path = format!("controllers.{i}");
        match spec {
            ControllerSpec::Guo2016(s) => guo2016::install(app, loaded, &path, s)?,
            ControllerSpec::Geng2015(s) => geng2015::install(app, loaded, &path, s)?,
            ControllerSpec::Xu2015(s) => xu2015::install(app, loaded, &path, s)?,
            ControllerSpec::Zhang2018(s) => zhang2018::install(app, loaded, &path, s)?,
            ControllerSpec::Xu2019(s) => xu2019::install(app, loaded, &path, s)?,
        }
    }
    Ok(())
}

/// Index of a body by name, or a located scene error at `path.field`.
pub fn body_index(
    loaded: &LoadedScene,
    path: &str,
    field: &str,
    name: &str,
) -> Result<usize, SceneError> {
    loaded
        .scene
        .bodies
        .iter()
        .position(|b| b.name == name)
        .ok_or_else(|| {
            loaded.error_at(
                &format!("{path}.{field}"),
                format!("no body named `{name}`"),
            )
        })
}
