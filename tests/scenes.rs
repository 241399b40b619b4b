//! Scene files: every bundled scene passes `rpod check`; every file of the broken-scene corpus
//! (`tests/broken_scenes/`) is refused with its own error, naming file, line:column and field,
//! and never a panic; `--set` overrides reach the scene; the CLI exits 2 on bad input and leaves
//! nothing behind.
//!
//! Reference: the expected error of each broken file, written here by hand from the edit that
//! broke it (each is `scenes/examples/collision_course.ron` with one change).

use rpod::scene::{load_scene_file, load_scene_str};
use std::path::Path;
use std::process::Command;

#[test]
fn every_bundled_scene_passes_check() {
    let mut n = 0;
    // The examples under scenes/examples/, the papers' scenes under scenes/papers/PAPER/ (the
    // trials files in scenes/trials/ are campaigns, checked by their own tests).
    let mut paths: Vec<std::path::PathBuf> = Vec::new();
    let mut dirs = vec![std::path::PathBuf::from("scenes")];
    while let Some(d) = dirs.pop() {
        for entry in std::fs::read_dir(&d).unwrap() {
            let p = entry.unwrap().path();
            if p.is_dir() && p.file_name().is_some_and(|n| n != "trials") {
                dirs.push(p);
            } else {
                paths.push(p);
            }
        }
    }
    paths.sort();
    assert!(
        paths
            .iter()
            .any(|p| p.starts_with("scenes/papers/geng2015")),
        "the papers' folders are walked"
    );
    for path in paths {
        if path.extension().is_some_and(|e| e == "ron") {
            let loaded = load_scene_file(&path, &[]).unwrap_or_else(|e| panic!("{e}"));
            rpod::sim::Simulation::new(&loaded).unwrap_or_else(|e| panic!("{e}"));
            n += 1;
        }
    }
    assert!(n >= 2, "found only {n} scenes");
}

/// (file, line, field, words the message must contain)
///
/// The corpus covers, besides single wrong values: panics once hit (a tiny inertia, a file
/// ending inside a string or after a backslash, an unclosed `#![`), stack overflows (deep
/// nesting), allocation aborts and hangs (panel, slot and prism segment counts, body and part
/// counts, substeps, steps), finite values that overflow downstream (inertia, mass, speed,
/// magnet force, table gravity, a tiny box), names that would break CSV columns or `--set`
/// paths, duplicate names, docking that cannot dock, non-UTF-8 bytes, degenerate reference
/// orbits and far-away bodies (once reported as overlaps).
const CORPUS: &[(&str, usize, &str, &str)] = &[
    (
        "law_guarantee_name_comma",
        73,
        "controllers.0",
        "guarantee name: a name is 1 to 64 characters",
    ),
    (
        "law_guarantee_name_taken",
        73,
        "controllers.0",
        "a guarantee named `clearance_20cm` already exists",
    ),
    (
        "min_impact_speed_1e300",
        65,
        "docking.contact.min_impact_speed_m_s",
        "the largest value of a speed",
    ),
    (
        "hold_velocity_1e9",
        101,
        "controllers.1.params.phases.hold100.translation.0.hold_vel_m_s",
        "the largest value of a speed",
    ),
    (
        "gain_1e200",
        102,
        "controllers.1.params.phases.hold100.translation.0.gains.damping_ratio",
        "the largest number a scene may hold",
    ),
    (
        "unknown_field_contact_law",
        65,
        "docking.contact.law.exponent",
        "unknown field `exponent`",
    ),
    (
        "unknown_field_law_params",
        102,
        "controllers.1.params.phases.hold100.translation.0.0.gains.integral_gain",
        "integral_gain",
    ),
    (
        "sensor_period_tiny",
        72,
        "controllers.0.0.vision.period_s",
        "cannot expose faster than the scene step",
    ),
    ("deep_brackets", 62, "", "nested deeper than 64 levels"),
    ("deep_parens", 45, "", "nested deeper than 64 levels"),
    (
        "docking_no_cone",
        58,
        "docking.chaser_port",
        "carries no DockingCone",
    ),
    (
        "docking_no_slot",
        58,
        "docking.target_port",
        "carries no DockingSlot",
    ),
    ("docking_role_other", 58, "docking.target", "has role Other"),
    (
        "docking_roles_swapped",
        58,
        "docking.chaser",
        "has role Target",
    ),
    ("dt_huge", 8, "dt_s", "at most 100 s, got 1e12"),
    (
        "stepping_max_step_huge",
        11,
        "stepping.max_step_s",
        "to 86400 s, got 1e6",
    ),
    (
        "stepping_tol_nan",
        11,
        "stepping.tol_m",
        "not a finite number",
    ),
    (
        "stepping_unknown_field",
        11,
        "stepping.tol",
        "Unexpected field named `tol`",
    ),
    ("dt_tiny", 8, "dt_s", "got 1e-300"),
    ("duplicate_body", 42, "bodies.1.name", "duplicate body name"),
    (
        "duplicate_guarantee",
        64,
        "guarantees.1.name",
        "duplicate guarantee name `clearance_50cm`",
    ),
    ("eccentricity", 13, "environment.reference.e", "[0, 1)"),
    ("eof_after_backslash", 56, "", "Expected end of string"),
    ("eof_in_string", 56, "", "Expected end of string"),
    (
        "far_away_body",
        50,
        "bodies.chaser.initial.pos_m",
        "the largest value of a length",
    ),
    (
        "guarantee_unknown_body",
        62,
        "guarantees.clearance_50cm.b",
        "no body named `station`",
    ),
    (
        "huge_inertia",
        46,
        "bodies.chaser.inertia_kg_m2.xx",
        "the largest number a scene may hold",
    ),
    (
        "inside_earth",
        12,
        "environment.reference.a_m",
        "inside the Earth",
    ),
    (
        // scenes/examples/soft_capture.ron with a 0.60 m compression stroke on 0.395 m legs.
        "soft_capture_leg_unreachable",
        83,
        "docking.mechanism.platform.leg 0",
        "the leg cannot reach the ring",
    ),
    (
        "magnet_1e308",
        61,
        "docking.magnet.f0_n",
        "the largest value of a force",
    ),
    (
        "mass_1e308",
        45,
        "bodies.chaser.mass_kg",
        "the largest number a scene may hold",
    ),
    (
        "missing_model",
        53,
        "bodies.target.parts.antenna.model.path",
        "no model file",
    ),
    ("name_comma", 43, "bodies.1.name", "A-Z a-z 0-9 _ -"),
    (
        "name_newline",
        56,
        "bodies.chaser.parts.1.name",
        "A-Z a-z 0-9 _ -",
    ),
    ("name_quote", 63, "guarantees.0.name", "A-Z a-z 0-9 _ -"),
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
    ("non_utf8", 45, "", "byte 0xFF is not valid UTF-8"),
    (
        "not_positive_definite",
        27,
        "bodies.target.inertia_kg_m2",
        "positive definite",
    ),
    (
        "orbit_hyperbolic",
        12,
        "environment.reference.v_eci_m_s",
        "not a bound orbit",
    ),
    (
        "orbit_radial",
        12,
        "environment.reference.v_eci_m_s",
        "degenerate orbit",
    ),
    (
        "overlap_at_start",
        53,
        "bodies.chaser.parts.bus",
        "overlaps `target/wing_py.panel2`",
    ),
    (
        "panel_count_huge",
        57,
        "bodies.chaser.parts.wing_pz.panel_count",
        "from 1 to 64, got 4000000000",
    ),
    (
        "plume_unknown_part",
        24,
        "guarantees.arrays.parts.1",
        "`solar_array_*` matches no part of `target`",
    ),
    (
        "port_name_space",
        53,
        "bodies.chaser.ports.0.name",
        "A-Z a-z 0-9 _ -",
    ),
    (
        "prism_segments_huge",
        54,
        "bodies.chaser.parts.bus.shape.segments",
        "from 8 to 1024",
    ),
    (
        "sequencer_any_empty",
        78,
        "controllers.0.params.phases.0.exits.0.when",
        "`Any([])` combines no condition: it can never hold",
    ),
    (
        "sequencer_law_wrong_slot",
        81,
        "controllers.1.params.phases.0.translation",
        "`Attitude` commands a torque only",
    ),
    (
        "sequencer_range_negative",
        78,
        "controllers.0.params.phases.0.exits.0.when.0.1",
        "`RangeBelow(-1)` can never hold",
    ),
    (
        "sequencer_states_empty",
        80,
        "controllers.0.params.phases.1.exits.0.when",
        "`DockingState([])` names no state",
    ),
    (
        "scene_name_newline",
        7,
        "name",
        "without control characters",
    ),
    (
        "size_tiny",
        54,
        "bodies.chaser.parts.bus.shape.size_m.0",
        "from 1e-6 to 10000 m, got 1e-300",
    ),
    (
        "slot_segments_huge",
        32,
        "bodies.target.parts.slot.segments",
        "from 6 to 256",
    ),
    (
        "speed_1e308",
        51,
        "bodies.chaser.initial.vel_m_s",
        "the largest value of a speed",
    ),
    (
        "substeps_max",
        9,
        "physics_substeps",
        "from 1 to 1000, got 4294967295",
    ),
    ("syntax_error", 44, "", "Expected comma"),
    (
        "table_gravity_1e308",
        24,
        "environment.gravity_m_s2",
        "the largest value of an acceleration",
    ),
    (
        "tiny_inertia",
        46,
        "bodies.chaser.inertia_kg_m2",
        "below the limit of 1e-12 kg·m²",
    ),
    ("too_many_bodies", 23, "bodies", "at most 64 bodies, got 67"),
    (
        "too_many_parts",
        53,
        "bodies.chaser.parts",
        "at most 256 parts on a body, got 258",
    ),
    ("too_many_steps", 9, "duration_s", "1e14 steps"),
    (
        "triangle_inertia",
        45,
        "bodies.chaser.inertia_kg_m2",
        "triangle inequality",
    ),
    ("unclosed_attribute", 5, "", "Expected comma"),
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
    let text = std::fs::read_to_string("scenes/examples/collision_course.ron").unwrap();
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

#[test]
fn regress_set_value_with_newlines_is_located_in_its_own_text() {
    let path = "tests/broken_scenes/negative_mass.ron";
    let text = std::fs::read_to_string(path).unwrap();
    // An error inside a multi-line value points into the `--set` argument, line and column.
    let e = load_scene_str(&text, path, &["bodies.chaser.mass_kg=\n  -5.0".into()]).unwrap_err();
    assert_eq!(e.field, "bodies.chaser.mass_kg", "{e}");
    assert!(
        e.file.contains("(--set bodies.chaser.mass_kg=\\n  -5.0)"),
        "{e}"
    );
    assert_eq!((e.line, e.col), (2, 3), "{e}");
    // An override with newlines earlier in the file does not shift the lines of errors after
    // it: the chaser's negative mass stays at line 44 of the file.
    let e =
        load_scene_str(&text, path, &["bodies.target.mass_kg=\n\n\n800.0\n".into()]).unwrap_err();
    assert_eq!((e.file.as_str(), e.line, e.col), (path, 44, 22), "{e}");
    // A syntax error inside the value is located in the value too.
    let e = load_scene_str(
        &text,
        path,
        &["bodies.chaser.com_m=(1.0,\n 2.0 3.0)".into()],
    )
    .unwrap_err();
    assert!(e.file.contains("--set"), "{e}");
    assert_eq!(e.line, 2, "{e}");
}

#[test]
fn regress_set_cannot_inject_scene_text() {
    let text = std::fs::read_to_string("scenes/examples/collision_course.ron").unwrap();
    for (set, words) in [
        (
            "bodies.chaser.mass_kg=1.0, friction: 9.0",
            "expected one value",
        ),
        (
            "bodies.chaser.mass_kg=300.0 // the rest of the line",
            "comment",
        ),
        ("bodies.chaser.mass_kg=300.0 /* x */", "comment"),
        ("bodies.chaser.friction: 1.0, restitution=0.5", "no field"),
        (
            "bodies.chaser.initial.pos_m=((((((((((((((((((((((((((((((((((((((((((((((((((((((((((((((((((1.0)))))))))))))))))))))))))))))))))))))))))))))))))))))))))))))))))))",
            "nest deeper",
        ),
    ] {
        let e = load_scene_str(&text, "cc", &[set.into()]).unwrap_err();
        assert!(e.message.contains(words), "{set}: {e}");
        assert!(e.file.contains("--set"), "{set}: {e}");
    }
}

/// A minimal body line for the count-limit scenes.
fn tiny_body(k: usize) -> String {
    format!(
        "(name:\"b{k}\",role:Other,mass_kg:1.0,inertia_kg_m2:(xx:1.0,yy:1.0,zz:1.0),initial:(pos_m:({k}.0,0.0,0.0)),parts:[Bus(name:\"p\",shape:Sphere(radius_m:0.1))]),\n"
    )
}

#[test]
fn regress_check_on_a_hundred_thousand_bodies_or_parts_is_a_located_error() {
    let head =
        "Scene(name: \"many\", dt_s: 0.01, duration_s: 1.0, environment: FreeSpace,\nbodies: [\n";
    let bodies: String = (0..100_000).map(tiny_body).collect();
    let text = format!("{head}{bodies}],\n)");
    let e = load_scene_str(&text, "many", &[]).unwrap_err();
    assert_eq!((e.line, e.field.as_str()), (2, "bodies"), "{e}");
    assert!(e.message.contains("at most 64 bodies, got 100000"), "{e}");
    let parts: String = (0..100_000)
        .map(|k| format!("Bus(name:\"p{k}\",shape:Sphere(radius_m:0.1)),\n"))
        .collect();
    let text = format!(
        "{head}(name:\"b\",role:Other,mass_kg:1.0,inertia_kg_m2:(xx:1.0,yy:1.0,zz:1.0),initial:(pos_m:(0.0,0.0,0.0)),parts:[\n{parts}]),\n],\n)"
    );
    let e = load_scene_str(&text, "many", &[]).unwrap_err();
    assert_eq!(e.field, "bodies.b.parts", "{e}");
    assert!(
        e.message
            .contains("at most 256 parts on a body, got 100000"),
        "{e}"
    );
}

#[test]
fn regress_scene_and_files_beyond_the_size_limit_are_refused() {
    let d = std::env::temp_dir().join(format!("rpod-big-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    let f = d.join("big.ron");
    let mut text = std::fs::read_to_string("scenes/examples/collision_course.ron").unwrap();
    text.push_str(&"// padding\n".repeat(2 << 20));
    std::fs::write(&f, text).unwrap();
    let e = load_scene_file(&f, &[]).unwrap_err();
    assert!(e.message.contains("larger than 16 MiB"), "{e}");
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn regress_default_output_folder_is_a_safe_name_under_out() {
    let d = std::env::temp_dir().join(format!("rpod-outname-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(d.join("work")).unwrap();
    let scene = std::fs::canonicalize("scenes/examples/collision_course.ron").unwrap();
    for (name, dir) in [
        ("../../escaped", "_.._escaped"),
        ("/tmp/absolute", "_tmp_absolute"),
        ("..", "unnamed"),
        ("a b\\c", "a_b_c"),
    ] {
        let r = Command::new(env!("CARGO_BIN_EXE_rpod"))
            .current_dir(d.join("work"))
            .arg("run")
            .arg(&scene)
            .args(["--duration", "0.05", "--set"])
            .arg(format!("name={name:?}"))
            .output()
            .unwrap();
        assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
        let out = d.join("work/out").join(dir);
        assert!(
            out.join("summary.json").exists(),
            "{name}: no {}",
            out.display()
        );
    }
    // Nothing was written beside `work/` or at the absolute path.
    let top: Vec<_> = std::fs::read_dir(&d)
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert_eq!(top, vec![std::ffi::OsString::from("work")]);
    assert!(!Path::new("/tmp/absolute/summary.json").exists());
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn regress_symlinked_model_files_and_folders_are_refused() {
    let d = std::env::temp_dir().join(format!("rpod-assets-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    let real = std::fs::canonicalize("assets/models").unwrap();
    // A link to a file, then a link to the folder.
    std::fs::create_dir_all(d.join("file/models")).unwrap();
    std::os::unix::fs::symlink(
        real.join("hga_dish.gltf"),
        d.join("file/models/hga_dish.gltf"),
    )
    .unwrap();
    std::fs::create_dir_all(d.join("folder")).unwrap();
    std::os::unix::fs::symlink(&real, d.join("folder/models")).unwrap();
    for (assets, link) in [("file", "models/hga_dish.gltf"), ("folder", "models")] {
        let r = Command::new(env!("CARGO_BIN_EXE_rpod"))
            .env("RPOD_ASSETS", d.join(assets))
            .args(["check", "scenes/examples/free_drift.ron"])
            .output()
            .unwrap();
        assert_eq!(r.status.code(), Some(2));
        let err = String::from_utf8_lossy(&r.stderr);
        assert!(
            err.contains("field `bodies.target.parts.antenna.model.path`")
                && err.contains("is a symbolic link")
                && err.contains(&d.join(assets).join(link).display().to_string()),
            "{err}"
        );
    }
    // The real folder is accepted.
    let r = Command::new(env!("CARGO_BIN_EXE_rpod"))
        .env("RPOD_ASSETS", real.parent().unwrap())
        .args(["check", "scenes/examples/free_drift.ron"])
        .output()
        .unwrap();
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    let _ = std::fs::remove_dir_all(&d);
}

/// A generic sensor faster than the scene step (found by the long fuzz run as 10³⁰⁶ exposures a
/// step) is a located error through `--set` too.
#[test]
fn regress_sensor_faster_than_the_step_is_refused() {
    let e = load_scene_file(
        Path::new("scenes/examples/orbit_approach_latch.ron"),
        &["controllers.0.sensor=Some((period_s: 1e-308))".to_string()],
    )
    .and_then(|l| rpod::sim::Simulation::new(&l).map(|_| ()))
    .expect_err("refused");
    assert_eq!(e.field, "controllers.0.sensor.period_s", "{e}");
    assert!(e.message.contains("1e-308 s"), "{e}");
}
