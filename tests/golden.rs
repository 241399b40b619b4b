//! Golden hashes: the outputs of a canonical set of scenes, pinned by SHA-256, so that no change
//! anywhere in the code moves a number by accident.
//!
//! Each case runs `rpod run SCENE` (a few with `--duration`, to keep the test short, or
//! `--contact-points`) and hashes `trajectory.csv`, `events.jsonl`, `contacts.csv` (and
//! `contact_points.csv` where written) byte for byte, and `summary.json` without the fields that
//! are not results: `wall_s`, `steps_per_s` and the build's `provenance.git_commit` /
//! `provenance.rpod_version` (the scene's SHA-256 and the `--set` list stay: they are inputs).
//!
//! Reference: the hashes minted from the outputs of the commit that last re-minted them, in
//! `tests/golden/<case>.sha256`. They hold for this build platform (x86_64 Linux, glibc's libm):
//! another libm may round `sin`/`exp` differently in the last bit.
//!
//! When a change of results is *intended*, re-mint and commit the new hashes in a commit of their
//! own that says why:
//!
//! ```sh
//! RPOD_GOLDEN_MINT=1 cargo test --release --test golden
//! git add tests/golden && git commit -m "golden: re-mint (why the numbers changed)"
//! ```
//!
//! When it is not intended, the failing case keeps its outputs in the folder it prints: `diff`
//! them against a run of the previous commit to see what moved.

use sha2::{Digest, Sha256};
use std::path::{Path, PathBuf};
use std::process::Command;

/// The output files hashed byte for byte (`summary.json` is normalised first).
const FILES: [&str; 4] = [
    "trajectory.csv",
    "events.jsonl",
    "contacts.csv",
    "contact_points.csv",
];

fn hex(bytes: &[u8]) -> String {
    bytes.iter().map(|b| format!("{b:02x}")).collect()
}

/// `summary.json` without the fields that depend on the machine, the clock or the build.
fn normalised_summary(dir: &Path) -> Vec<u8> {
    let text = std::fs::read_to_string(dir.join("summary.json")).expect("summary.json");
    let mut v: serde_json::Value = serde_json::from_str(&text).expect("summary.json is JSON");
    let obj = v.as_object_mut().expect("summary.json is an object");
    obj.remove("wall_s");
    obj.remove("steps_per_s");
    if let Some(p) = obj.get_mut("provenance").and_then(|p| p.as_object_mut()) {
        p.remove("git_commit");
        p.remove("rpod_version");
    }
    serde_json::to_vec_pretty(&v).expect("serialise")
}

/// `file  sha256` lines of a run's outputs, in a fixed order.
fn hashes(dir: &Path) -> String {
    let mut out = String::new();
    for f in FILES {
        let p = dir.join(f);
        if p.exists() {
            let bytes = std::fs::read(&p).expect("read output");
            out += &format!("{f}  {}\n", hex(&Sha256::digest(&bytes)));
        }
    }
    let s = normalised_summary(dir);
    out += &format!("summary.json  {}\n", hex(&Sha256::digest(&s)));
    out
}

fn golden_file(case: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/golden")
        .join(format!("{case}.sha256"))
}

/// Runs `scene` with `args` and compares (or, with `RPOD_GOLDEN_MINT=1`, writes) its hashes.
fn check(case: &str, scene: &str, args: &[&str]) {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join("golden")
        .join(case);
    let _ = std::fs::remove_dir_all(&dir);
    let r = Command::new(env!("CARGO_BIN_EXE_rpod"))
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .args(["run", scene, "-q", "--out"])
        .arg(&dir)
        .args(args)
        .output()
        .expect("run rpod");
    assert!(
        r.status.success(),
        "{case}: rpod run {scene} failed: {}",
        String::from_utf8_lossy(&r.stderr)
    );
    let got = hashes(&dir);
    let path = golden_file(case);
    if std::env::var_os("RPOD_GOLDEN_MINT").is_some() {
        std::fs::create_dir_all(path.parent().expect("parent")).expect("mkdir tests/golden");
        let header = format!(
            "# rpod run {scene} {} — SHA-256 of the outputs (tests/golden.rs says how to re-mint)\n",
            args.join(" ")
        );
        std::fs::write(&path, header + &got).expect("write golden file");
        return;
    }
    let want = std::fs::read_to_string(&path).unwrap_or_else(|_| {
        panic!(
            "{case}: no golden file {}; mint it with RPOD_GOLDEN_MINT=1 cargo test --release --test golden",
            path.display()
        )
    });
    let want: String = want
        .lines()
        .filter(|l| !l.starts_with('#'))
        .map(|l| format!("{l}\n"))
        .collect();
    if got != want {
        let differing: Vec<&str> = got
            .lines()
            .zip(want.lines())
            .filter(|(a, b)| a != b)
            .map(|(a, _)| a.split_whitespace().next().unwrap_or(""))
            .collect();
        panic!(
            "{case}: the outputs of `rpod run {scene} {}` changed ({}; {} files now, {} pinned).\n\
             The run's outputs are kept in {}.\n\
             If the change of results is intended, re-mint in a commit of its own that says why:\n  \
             RPOD_GOLDEN_MINT=1 cargo test --release --test golden\n\
             got:\n{got}pinned:\n{want}",
            args.join(" "),
            differing.join(", "),
            got.lines().count(),
            want.lines().count(),
            dir.display(),
        );
    }
}

#[test]
fn golden_free_drift() {
    check("free_drift", "scenes/examples/free_drift.ron", &[]);
}

#[test]
fn golden_collision_course() {
    check(
        "collision_course",
        "scenes/examples/collision_course.ron",
        &[],
    );
}

#[test]
fn golden_docking_aligned() {
    check(
        "docking_aligned",
        "scenes/examples/docking_aligned.ron",
        &[],
    );
}

#[test]
fn golden_docking_offset_contact_points() {
    check(
        "docking_offset",
        "scenes/examples/docking_offset.ron",
        &["--contact-points"],
    );
}

#[test]
fn golden_docking_miss() {
    check("docking_miss", "scenes/examples/docking_miss.ron", &[]);
}

#[test]
fn golden_orbit_approach_latch() {
    check(
        "orbit_approach_latch",
        "scenes/examples/orbit_approach_latch.ron",
        &[],
    );
}

#[test]
fn golden_guo2016_corridor() {
    check(
        "guo2016_corridor",
        "scenes/papers/guo2016/guo2016_corridor.ron",
        &[],
    );
}

#[test]
fn golden_xu2015_accm() {
    check("xu2015_accm", "scenes/papers/xu2015/xu2015_accm.ron", &[]);
}

#[test]
fn golden_xu2015_pd() {
    check("xu2015_pd", "scenes/papers/xu2015/xu2015_pd.ron", &[]);
}

#[test]
fn golden_xu2019_simulation_20s() {
    check(
        "xu2019_simulation_20s",
        "scenes/papers/xu2019/xu2019_simulation.ron",
        &["--duration", "20"],
    );
}

#[test]
fn golden_xu2019_experiment_20s() {
    check(
        "xu2019_experiment_20s",
        "scenes/papers/xu2019/xu2019_experiment.ron",
        &["--duration", "20"],
    );
}

#[test]
fn golden_zhang2018_pair() {
    check(
        "zhang2018_pair",
        "scenes/papers/zhang2018/zhang2018_pair.ron",
        &[],
    );
}

#[test]
fn golden_zhang2018_reconfiguration() {
    check(
        "zhang2018_reconfiguration",
        "scenes/papers/zhang2018/zhang2018_reconfiguration.ron",
        &[],
    );
}

#[test]
fn golden_geng2015_m1_linear_10s() {
    check(
        "geng2015_m1_linear_10s",
        "scenes/papers/geng2015/geng2015_m1_linear.ron",
        &["--duration", "10"],
    );
}

#[test]
fn golden_geng2015_t1_linear_10s() {
    check(
        "geng2015_t1_linear_10s",
        "scenes/papers/geng2015/geng2015_t1_linear.ron",
        &["--duration", "10"],
    );
}

#[test]
fn golden_with_set_override() {
    // A `--set` path through the scene, so the override machinery is pinned too.
    check(
        "collision_course_set",
        "scenes/examples/collision_course.ron",
        &["--set", "bodies.chaser.initial.vel_m_s=(-0.2, 0.0, 0.0)"],
    );
}
