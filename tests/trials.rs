//! `rpod trials`: results independent of `--jobs` and of sharding (merged shards equal one
//! run, byte for byte), resuming after an interruption gives the same file, a malformed trials
//! file is refused with file, line and field, and the capture probability's Wilson interval
//! matches its closed form.
//!
//! References: the single-job run's `trials.csv`; the Wilson score interval's closed forms
//! (0 of n: [0, z²/(n + z²)]; n of n: [n/(n + z²), 1]).

use std::path::{Path, PathBuf};
use std::process::Command;

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("rpod-trials-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// A small campaign: 3 lateral offsets (two latch, one misses) × 2 random closing speeds.
fn campaign(dir: &Path) -> PathBuf {
    let scene = std::fs::canonicalize("scenes/docking_aligned.ron").unwrap();
    let text = format!(
        r#"Trials(
    name: "small",
    scene: "{}",
    duration_s: 30.0,
    seed: 7,
    count: 6,
    parameters: [
        Grid(path: "bodies.chaser.initial.pos_m.1", values: [0.0, 0.05, 0.4]),
        Uniform(path: "bodies.chaser.initial.vel_m_s.0", min: -0.03, max: -0.02),
    ],
    success: Latched,
)"#,
        scene.display()
    );
    let f = dir.join("small.ron");
    std::fs::write(&f, text).unwrap();
    f
}

fn trials(args: &[&str]) -> std::process::Output {
    let out = Command::new(env!("CARGO_BIN_EXE_rpod"))
        .arg("trials")
        .args(args)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    out
}

fn read(p: &Path) -> String {
    std::fs::read_to_string(p).unwrap()
}

#[test]
fn regress_trials_csv_independent_of_jobs_shards_and_resume() {
    let d = tmp("jobs");
    let f = campaign(&d);
    let f = f.to_str().unwrap();
    let one = d.join("one");
    let two = d.join("two");
    trials(&[f, "--jobs", "1", "--out", one.to_str().unwrap()]);
    trials(&[f, "--jobs", "2", "--out", two.to_str().unwrap()]);
    let reference = read(&one.join("trials.csv"));
    assert_eq!(reference.lines().count(), 7, "{reference}");
    assert_eq!(
        reference,
        read(&two.join("trials.csv")),
        "--jobs 2 differs from --jobs 1"
    );
    // Outcomes: the 0.4 m offset misses, the aligned ones latch.
    for line in reference.lines().skip(1) {
        let cells: Vec<&str> = line.split(',').collect();
        let y: f64 = cells[1].parse().unwrap();
        let outcome = cells[3];
        if y > 0.3 {
            assert_eq!(outcome, "MISSED", "{line}");
        } else {
            assert_eq!(outcome, "LATCHED", "{line}");
        }
    }
    // Shards 0/2 and 1/2, merged, equal the single run.
    let s0 = d.join("s0");
    let s1 = d.join("s1");
    trials(&[f, "--shard", "0/2", "--out", s0.to_str().unwrap()]);
    trials(&[f, "--shard", "1/2", "--out", s1.to_str().unwrap()]);
    let merged = d.join("merged");
    trials(&[
        "merge",
        f,
        s0.to_str().unwrap(),
        s1.to_str().unwrap(),
        "--out",
        merged.to_str().unwrap(),
    ]);
    assert_eq!(
        reference,
        read(&merged.join("trials.csv")),
        "merged shards differ"
    );
    // Interrupted after two rows and half a third: resuming completes the same file.
    let resumed = d.join("resumed");
    std::fs::create_dir_all(&resumed).unwrap();
    let mut partial: String = reference
        .lines()
        .take(3)
        .map(|l| format!("{l}\n"))
        .collect();
    partial.push_str("2,0.05,-0.02");
    std::fs::write(resumed.join("trials.csv"), partial).unwrap();
    let out = trials(&[f, "--out", resumed.to_str().unwrap()]);
    assert!(String::from_utf8_lossy(&out.stdout).contains("(2 resumed)"));
    assert_eq!(
        reference,
        read(&resumed.join("trials.csv")),
        "resumed file differs"
    );
    // Summary and plots.
    let s: serde_json::Value = serde_json::from_str(&read(&one.join("summary.json"))).unwrap();
    assert_eq!(s["trials"], 6);
    assert_eq!(s["successes"], 4);
    assert!(one.join("capture_envelope.png").exists() && one.join("capture_envelope.svg").exists());
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn regress_malformed_trials_file_gets_a_located_error() {
    let d = tmp("bad");
    let f = d.join("bad.ron");
    std::fs::write(
        &f,
        "Trials(\n  name: \"x\",\n  scene: \"nowhere.ron\",\n  count: 3,\n  parameters: [Grid(path: \"a\", valuez: [1.0])],\n  success: Latched,\n)",
    )
    .unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_rpod"))
        .args(["trials", f.to_str().unwrap()])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("bad.ron:5:"), "{err}");
    assert!(err.contains("valuez"), "{err}");
    let e = rpod::trials::load(&f).err().unwrap();
    assert_eq!(e.line, 5);
    assert_eq!(e.field, "parameters.0.valuez");
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn val_wilson_interval_closed_forms() {
    let z2 = 1.959_963_984_540_054f64.powi(2);
    let (p, lo, hi) = rpod::trials::wilson(0, 10);
    assert_eq!(p, 0.0);
    assert!(lo.abs() < 1e-15 && (hi - z2 / (10.0 + z2)).abs() < 1e-12);
    let (_, lo, hi) = rpod::trials::wilson(10, 10);
    assert!((lo - 10.0 / (10.0 + z2)).abs() < 1e-12 && (hi - 1.0).abs() < 1e-15);
    // Symmetry: s of n mirrors n − s of n.
    let (_, a, b) = rpod::trials::wilson(3, 17);
    let (_, c, d) = rpod::trials::wilson(14, 17);
    assert!((a - (1.0 - d)).abs() < 1e-12 && (b - (1.0 - c)).abs() < 1e-12);
}
