//! Scene files: every bundled scene passes `rpod check`; every file of the broken-scene corpus
//! (`tests/broken_scenes/`) is refused with its own error, naming file, line:column and field,
//! and never a panic; `--set` overrides reach the scene; the CLI exits 2 on bad input and leaves
//! nothing behind.
//!
//! Reference: the expected error of each broken file, written here by hand from the edit that
//! broke it (each is `scenes/collision_course.ron` with one change).

use rpod::scene::{load_scene_file, load_scene_str};
use std::path::Path;
use std::process::Command;

#[test]
fn every_bundled_scene_passes_check() {
    let mut n = 0;
    for entry in std::fs::read_dir("scenes").unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_some_and(|e| e == "ron") {
            let loaded = load_scene_file(&path, &[]).unwrap_or_else(|e| panic!("{e}"));
            rpod::sim::Simulation::new(&loaded).unwrap_or_else(|e| panic!("{e}"));
            n += 1;
        }
    }
    assert!(n >= 2, "found only {n} scenes");
}

/// (file, line, field, words the message must contain)
const CORPUS: &[(&str, usize, &str, &str)] = &[
    ("duplicate_body", 42, "bodies.1.name", "duplicate body name"),
    ("eccentricity", 13, "environment.reference.e", "[0, 1)"),
    (
        "guarantee_unknown_body",
        62,
        "guarantees.clearance_50cm.b",
        "no body named `station`",
    ),
    (
        "inside_earth",
        12,
        "environment.reference.a_m",
        "inside the Earth",
    ),
    (
        "missing_model",
        53,
        "bodies.target.parts.antenna.model.path",
        "no model file",
    ),
    (
        "negative_mass",
        44,
        "bodies.chaser.mass_kg",
        "positive number of kilograms",
    ),
    (
        "negative_panel",
        56,
        "bodies.chaser.parts.wing_pz.panel_size_m.1",
        "positive number of metres",
    ),
    (
        "not_positive_definite",
        27,
        "bodies.target.inertia_kg_m2",
        "positive definite",
    ),
    (
        "overlap_at_start",
        53,
        "bodies.chaser.parts.bus",
        "overlaps `target/wing_py.panel2`",
    ),
    ("syntax_error", 44, "", "Expected comma"),
    (
        "triangle_inertia",
        45,
        "bodies.chaser.inertia_kg_m2",
        "triangle inequality",
    ),
    (
        "unknown_field",
        26,
        "bodies.target.colour",
        "Unexpected field named `colour`",
    ),
    (
        "unknown_variant",
        43,
        "bodies.chaser.role",
        "Unexpected variant named `Pilot`",
    ),
    (
        "wing_axes",
        55,
        "bodies.chaser.parts.wing_pz.width_axis",
        "perpendicular",
    ),
    ("wrong_type", 8, "duration_s", "Expected float"),
    ("zero_dt", 7, "dt_s", "positive number of seconds"),
];

#[test]
fn regress_broken_scene_corpus_gives_located_errors() {
    let files = std::fs::read_dir("tests/broken_scenes").unwrap().count();
    assert_eq!(
        files,
        CORPUS.len(),
        "every broken scene needs an expected error here"
    );
    for (name, line, field, words) in CORPUS {
        let path = format!("tests/broken_scenes/{name}.ron");
        let err = match load_scene_file(Path::new(&path), &[]) {
            Ok(loaded) => match rpod::sim::Simulation::new(&loaded) {
                Ok(_) => panic!("{path} was accepted"),
                Err(e) => e,
            },
            Err(e) => e,
        };
        assert_eq!(err.file, path, "{err}");
        assert_eq!(err.line, *line, "{err}");
        assert!(err.col > 0, "{err}");
        assert_eq!(err.field, *field, "{err}");
        assert!(
            err.message.contains(words),
            "{path}: `{}` lacks `{words}`",
            err.message
        );
    }
}

#[test]
fn set_overrides_replace_and_insert_fields() {
    let text = std::fs::read_to_string("scenes/collision_course.ron").unwrap();
    let l = load_scene_str(
        &text,
        "cc",
        &[
            "bodies.chaser.mass_kg=250".into(),
            "bodies.chaser.initial.vel_m_s=(-0.2, 0.0, 0.0)".into(),
            "physics_substeps=2".into(),
        ],
    )
    .unwrap();
    let chaser = l.scene.bodies.iter().find(|b| b.name == "chaser").unwrap();
    assert_eq!(chaser.mass_kg, 250.0);
    assert_eq!(chaser.initial.vel_m_s, [-0.2, 0.0, 0.0]);
    assert_eq!(l.scene.physics_substeps, 2);
    let e = load_scene_str(&text, "cc", &["bodies.chaser.mass_kg=-1".into()]).unwrap_err();
    assert_eq!(e.field, "bodies.chaser.mass_kg");
    assert!(e.line > 0);
    let e = load_scene_str(&text, "cc", &["bodies.ghost.mass_kg=1".into()]).unwrap_err();
    assert!(e.message.contains("no field `ghost`"), "{e}");
}

#[test]
fn cli_bad_scene_exits_2_and_writes_nothing() {
    let out = std::env::temp_dir().join(format!("rpod-bad-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&out);
    let r = Command::new(env!("CARGO_BIN_EXE_rpod"))
        .args(["run", "tests/broken_scenes/negative_mass.ron", "--out"])
        .arg(&out)
        .output()
        .unwrap();
    assert_eq!(r.status.code(), Some(2));
    let err = String::from_utf8_lossy(&r.stderr);
    assert!(
        err.contains("negative_mass.ron:44:22: field `bodies.chaser.mass_kg`"),
        "{err}"
    );
    assert!(!out.exists(), "a failed run left {}", out.display());
    let r = Command::new(env!("CARGO_BIN_EXE_rpod"))
        .args(["check", "tests/broken_scenes/syntax_error.ron"])
        .output()
        .unwrap();
    assert_eq!(r.status.code(), Some(2));
}
