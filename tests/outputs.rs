//! The output folder: one writer at a time (a second `rpod run` into a folder in use is
//! refused with exit 4 and the holder's pid), nothing stale (a run killed with SIGKILL leaves
//! only `.partial` files, never an earlier run's complete files beside them; the lock dies
//! with the process), files created new (a planted symlink is not followed), and no NaN or
//! infinity in any output of a bundled scene (undefined controller and mechanism columns are
//! empty cells).
//!
//! Links and special files planted where rpod writes or reads are refused with exit 2 and the
//! outside file untouched (`.rpod.lock`, `runs/`, `plots/`, a FIFO as scene, a run file linked
//! to `/dev/zero`); `rpod reproduce` with a path as the paper's name makes no folder.
//!
//! Reference: the output contract in docs/outputs.md; the file lists are read back
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

/// `rpod run scenes/examples/free_drift.ron --duration 1 --out OUT`, waited for.
fn free_drift_1s(out: impl AsRef<std::ffi::OsStr>) -> std::process::Output {
    rpod()
        .args([
            "run",
            "scenes/examples/free_drift.ron",
            "--duration",
            "1",
            "--out",
        ])
        .arg(out)
        .output()
        .unwrap()
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
    let r = free_drift_1s(out);
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    assert!(d.join("summary.json").exists());
    // A long run into the same folder; while it runs, a second writer is refused.
    let mut long = rpod()
        .args([
            "run",
            "scenes/examples/free_drift.ron",
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
    let r = free_drift_1s(out);
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
    let r = free_drift_1s(out);
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
    let r = free_drift_1s(&d);
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    assert_eq!(std::fs::read_to_string(&victim).unwrap(), "precious\n");
    assert!(!d.join("summary.json").is_symlink());
    let _ = std::fs::remove_dir_all(&d);
    let _ = std::fs::remove_file(&victim);
}

#[test]
fn regress_links_planted_at_the_lock_runs_and_plots_are_refused() {
    let d = tmp("links2");
    std::fs::create_dir_all(&d).unwrap();
    let victim = d.with_extension("victim2");
    std::fs::write(&victim, "precious\n").unwrap();
    std::os::unix::fs::symlink(&victim, d.join(".rpod.lock")).unwrap();
    let r = free_drift_1s(&d);
    assert!(!r.status.success());
    let err = String::from_utf8_lossy(&r.stderr);
    assert!(err.contains("symbolic link"), "{err}");
    assert_eq!(std::fs::read_to_string(&victim).unwrap(), "precious\n");
    // A run, then RUN/plots as a link to a folder outside: `rpod plot` refuses it.
    std::fs::remove_file(d.join(".rpod.lock")).unwrap();
    let r = free_drift_1s(&d);
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    let outside = d.with_extension("outside");
    std::fs::create_dir_all(&outside).unwrap();
    std::os::unix::fs::symlink(&outside, d.join("plots")).unwrap();
    let r = rpod().arg("plot").arg(&d).output().unwrap();
    assert_eq!(
        r.status.code(),
        Some(2),
        "{}",
        String::from_utf8_lossy(&r.stderr)
    );
    assert!(std::fs::read_dir(&outside).unwrap().next().is_none());
    // contacts.csv replaced by a link to /dev/zero: refused, not read.
    std::fs::remove_file(d.join("plots")).unwrap();
    std::fs::remove_file(d.join("trajectory.csv")).unwrap();
    std::os::unix::fs::symlink("/dev/zero", d.join("trajectory.csv")).unwrap();
    let r = rpod().arg("plot").arg(&d).output().unwrap();
    assert_eq!(r.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&r.stderr).contains("not a regular file"));
    for p in [&d, &outside] {
        let _ = std::fs::remove_dir_all(p);
    }
    let _ = std::fs::remove_file(&victim);
}

#[test]
fn regress_fifo_scene_and_path_as_paper_name_are_refused_without_waiting() {
    let d = tmp("fifo");
    std::fs::create_dir_all(&d).unwrap();
    let fifo = d.join("scene.ron");
    assert!(
        Command::new("mkfifo")
            .arg(&fifo)
            .status()
            .unwrap()
            .success()
    );
    for cmd in ["check", "run"] {
        let mut c = rpod();
        c.arg(cmd).arg(&fifo);
        if cmd == "run" {
            c.arg("--out").arg(d.join("out"));
        }
        // Nobody ever opens the FIFO for writing: a reader that waited would never return.
        let r = c.stdin(Stdio::null()).output().unwrap();
        assert_eq!(r.status.code(), Some(2), "rpod {cmd}");
        assert!(
            String::from_utf8_lossy(&r.stderr).contains("not a regular file"),
            "{}",
            String::from_utf8_lossy(&r.stderr)
        );
    }
    let target = d.join("made_by_reproduce");
    let r = rpod()
        .args(["reproduce"])
        .arg(&target)
        .arg("--out")
        .arg(d.join("rep"))
        .output()
        .unwrap();
    assert_eq!(r.status.code(), Some(2));
    assert!(!target.exists() && !d.join("rep").join(&target).exists());
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn invariant_no_nan_or_infinity_in_any_output() {
    for scene in [
        "examples/docking_aligned",
        "papers/xu2019/xu2019_simulation",
        "papers/zhang2018/zhang2018_pair",
        "papers/geng2015/geng2015_m1_linear",
    ] {
        let d = tmp(&scene.replace('/', "_"));
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

/// A run in progress shows its events so far: after `collision_course`'s guarantee is violated
/// (21.17 s) the temporary `events.jsonl.partial` already holds that event, although the run
/// has not ended (it used to stay in the write buffer until the end, so a stopped run looked as
/// if nothing had happened). Reference: the event the same run reports in memory.
#[test]
fn regress_events_reach_the_partial_file_while_the_run_goes_on() {
    let dir = tmp("events-live");
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let mut sim =
        rpod::sim::Simulation::from_file("scenes/examples/collision_course.ron", &[]).unwrap();
    sim.record_to(&dir).unwrap();
    sim.run_for(30.0);
    let want: Vec<String> = sim.events().iter().map(|e| e.kind.clone()).collect();
    assert!(
        want.iter().any(|k| k == "guarantee_violated"),
        "the scene's violation happens by 30 s: {want:?}"
    );
    let text = std::fs::read_to_string(dir.join("events.jsonl.partial")).unwrap();
    let got: Vec<String> = text
        .lines()
        .map(|l| serde_json::from_str::<serde_json::Value>(l).unwrap()["kind"].to_string())
        .map(|k| k.trim_matches('"').to_string())
        .collect();
    assert_eq!(got, want, "every event so far is on disk");
    let _ = std::fs::remove_dir_all(&dir);
}
