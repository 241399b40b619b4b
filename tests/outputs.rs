//! The output folder: one writer at a time (a second `rpod run` into a folder in use is
//! refused with exit 4 and the holder's pid), nothing stale (a run killed with SIGKILL leaves
//! only `.partial` files, never an earlier run's complete files beside them; the lock dies
//! with the process), files created new (a planted symlink is not followed), and no NaN or
//! infinity in any output of a bundled scene (undefined controller and mechanism columns are
//! empty cells).
//!
//! Reference: the output contract in the README ("Outputs"); the file lists are read back
//! from the folder itself.

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("rpod-outputs-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    d
}

fn rpod() -> Command {
    Command::new(env!("CARGO_BIN_EXE_rpod"))
}

fn names(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().to_string())
        .collect();
    v.sort();
    v
}

fn wait_for(p: &Path) {
    let t0 = Instant::now();
    while !p.exists() {
        assert!(
            t0.elapsed() < Duration::from_secs(60),
            "{} never appeared",
            p.display()
        );
        std::thread::sleep(Duration::from_millis(20));
    }
}

#[test]
fn regress_second_writer_refused_and_kill_9_leaves_nothing_that_looks_whole() {
    let d = tmp("lock");
    let out = d.to_str().unwrap();
    // A complete run first.
    let r = rpod()
        .args([
            "run",
            "scenes/free_drift.ron",
            "--duration",
            "1",
            "--out",
            out,
        ])
        .output()
        .unwrap();
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    assert!(d.join("summary.json").exists());
    // A long run into the same folder; while it runs, a second writer is refused.
    let mut long = rpod()
        .args([
            "run",
            "scenes/free_drift.ron",
            "--duration",
            "100000",
            "--out",
            out,
        ])
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    wait_for(&d.join("trajectory.csv.partial"));
    // The earlier run's complete files are gone before the new run writes.
    for f in [
        "trajectory.csv",
        "events.jsonl",
        "contacts.csv",
        "summary.json",
    ] {
        assert!(!d.join(f).exists(), "stale {f} beside a running run");
    }
    let r = rpod()
        .args([
            "run",
            "scenes/free_drift.ron",
            "--duration",
            "1",
            "--out",
            out,
        ])
        .output()
        .unwrap();
    assert_eq!(r.status.code(), Some(4));
    let err = String::from_utf8_lossy(&r.stderr);
    assert!(
        err.contains("is in use by another rpod process")
            && err.contains(&format!("pid {}", long.id())),
        "{err}"
    );
    let r = rpod()
        .args(["trials", "scenes/trials/capture_envelope.ron", "--out", out])
        .output()
        .unwrap();
    assert_eq!(
        r.status.code(),
        Some(4),
        "{}",
        String::from_utf8_lossy(&r.stderr)
    );
    // kill -9: only partial files (and the lock file) remain.
    long.kill().unwrap();
    long.wait().unwrap();
    assert_eq!(
        names(&d),
        [
            ".rpod.lock",
            "contacts.csv.partial",
            "events.jsonl.partial",
            "trajectory.csv.partial"
        ]
    );
    // The kernel released the lock with the process: a new run proceeds, and clears the
    // partial files of the killed one.
    let r = rpod()
        .args([
            "run",
            "scenes/free_drift.ron",
            "--duration",
            "1",
            "--out",
            out,
        ])
        .output()
        .unwrap();
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    assert_eq!(
        names(&d),
        [
            ".rpod.lock",
            "contacts.csv",
            "events.jsonl",
            "summary.json",
            "trajectory.csv"
        ]
    );
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn regress_planted_symlink_in_the_output_folder_is_not_followed() {
    let d = tmp("symlink");
    std::fs::create_dir_all(&d).unwrap();
    let victim = d.with_extension("victim");
    std::fs::write(&victim, "precious\n").unwrap();
    for n in ["trajectory.csv.partial", "summary.json"] {
        std::os::unix::fs::symlink(&victim, d.join(n)).unwrap();
    }
    let r = rpod()
        .args(["run", "scenes/free_drift.ron", "--duration", "1", "--out"])
        .arg(&d)
        .output()
        .unwrap();
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    assert_eq!(std::fs::read_to_string(&victim).unwrap(), "precious\n");
    assert!(!d.join("summary.json").is_symlink());
    let _ = std::fs::remove_dir_all(&d);
    let _ = std::fs::remove_file(&victim);
}

#[test]
fn invariant_no_nan_or_infinity_in_any_output() {
    for scene in [
        "docking_aligned",
        "xu2019_simulation",
        "zhang2018_pair",
        "geng2015_m1_linear",
    ] {
        let d = tmp(scene);
        let r = rpod()
            .args([
                "run",
                &format!("scenes/{scene}.ron"),
                "--duration",
                "2",
                "--out",
            ])
            .arg(&d)
            .output()
            .unwrap();
        assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
        for f in [
            "trajectory.csv",
            "events.jsonl",
            "contacts.csv",
            "summary.json",
        ] {
            let text = std::fs::read_to_string(d.join(f)).unwrap();
            for (i, line) in text.lines().enumerate() {
                for cell in line.split([',', ' ', ':', '[', ']']) {
                    let c = cell.trim_matches(['"', '{', '}']).to_ascii_lowercase();
                    assert!(
                        !matches!(c.as_str(), "nan" | "inf" | "-inf" | "infinity"),
                        "{scene}/{f}:{}: {line}",
                        i + 1
                    );
                }
            }
        }
        let _ = std::fs::remove_dir_all(&d);
    }
}
