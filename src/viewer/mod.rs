//! Feature `viewer`: the scene in a window — `rpod view SCENE` (live) and `rpod replay RUN_DIR`
//! (a run recorded by `rpod run`).
//!
//! - [`timeline`]: play/pause, speed 0.1×–1000×, seeking, event markers (plain Rust, tested
//!   without a window);
//! - [`recording`]: `trajectory.csv` / `events.jsonl` / `summary.json` read back and sampled at
//!   any time (positions interpolated linearly, attitudes by slerp);
//! - [`geometry`]: render meshes and parry shapes from the same part expansion as the colliders
//!   ([`crate::scene::parts::expand_body`]);
//! - [`app`]: the Bevy app — meshes, overlays (docking-port frames, the reference orbit's LVLH
//!   axes and the direction to the Earth, trails, the monitor's closest-points segment coloured
//!   by margin), the read-out panel, the scrubber with event markers, camera presets, and
//!   `--screenshot FILE --frames N` for tests;
//! - [`surfaces`]: the laws' and guarantees' constraint surfaces (Xu 2019 superquadric and
//!   heart prisms, Zhang 2018 capture spheres, keep-out spheres) as f64 meshes.

pub mod app;
pub mod geometry;
pub mod recording;
pub mod surfaces;
pub mod timeline;

pub use app::{ViewerOptions, run_live, run_replay};

use std::path::{Path, PathBuf};

/// The scene file a run directory names (`summary.json`'s `scene_file`), resolved as given, or
/// else relative to the run directory and its parents.
pub fn scene_of_run(rec: &recording::Recording) -> Result<PathBuf, String> {
    let name = rec.scene_file.as_deref().ok_or_else(|| {
        format!(
            "{}: summary.json names no scene_file; pass --scene",
            rec.dir.display()
        )
    })?;
    let p = PathBuf::from(name);
    if p.exists() {
        return Ok(p);
    }
    let mut dir: Option<&Path> = Some(rec.dir.as_path());
    while let Some(d) = dir {
        let c = d.join(name);
        if c.exists() {
            return Ok(c);
        }
        dir = d.parent();
    }
    Err(format!(
        "scene file `{name}` named by {} not found; pass --scene",
        rec.dir.join("summary.json").display()
    ))
}

/// `rpod replay`: loads the run in `dir` and its scene (or `scene`), and opens the window.
pub fn replay(dir: &Path, scene: Option<&Path>, opts: ViewerOptions) -> Result<(), String> {
    let rec = recording::Recording::load(dir)?;
    let scene_path = match scene {
        Some(s) => s.to_path_buf(),
        None => scene_of_run(&rec)?,
    };
    let loaded = crate::scene::load_scene_file(&scene_path, &[]).map_err(|e| e.to_string())?;
    run_replay(&loaded, rec, opts)
}

/// `rpod view`: loads the scene and runs it live in the window.
pub fn view(scene: &Path, set: &[String], opts: ViewerOptions) -> Result<(), String> {
    let loaded = crate::scene::load_scene_file(scene, set).map_err(|e| e.to_string())?;
    run_live(&loaded, opts)
}
