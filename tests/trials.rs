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
    let scene = std::fs::canonicalize("scenes/examples/docking_aligned.ron").unwrap();
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

fn trials_fails(args: &[&str]) -> (i32, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_rpod"))
        .arg("trials")
        .args(args)
        .output()
        .unwrap();
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stderr).to_string(),
    )
}

/// Damaged `trials.csv` files are refused on resume with the line and the reason; only an
/// unterminated last line (a crash while writing it) is dropped and rerun.
#[test]
fn regress_damaged_trials_csv_is_refused_on_resume() {
    let d = tmp("damaged");
    let f = campaign(&d);
    let f = f.to_str().unwrap();
    let good = d.join("good");
    trials(&[f, "--out", good.to_str().unwrap()]);
    let reference = read(&good.join("trials.csv"));
    let lines: Vec<&str> = reference.lines().collect();
    let cut = &lines[3][..lines[3].len() / 2];
    let garbage = format!("{}\n{}\nhello, world\n", lines[0], lines[1]);
    let swapped = lines[2].replacen(",0.05,", ",0.04,", 1);
    assert_ne!(swapped, lines[2]);
    let cases: Vec<(&str, String, &str)> = vec![
        (
            "cut row ending in a newline",
            format!("{}\n{}\n{cut}\n", lines[0], lines[1]),
            ":3: ",
        ),
        (
            "duplicated row",
            format!("{}\n{}\n{}\n{}\n", lines[0], lines[1], lines[2], lines[2]),
            "appears twice",
        ),
        ("garbage line", garbage, ":3: "),
        (
            "index out of range",
            format!("{}\n{}\n", lines[0], lines[1].replacen("0,", "99,", 1)),
            "index 99 is out of range",
        ),
        (
            "values that are not trial k's",
            format!("{}\n{swapped}\n", lines[0]),
            "the campaign gives it",
        ),
        (
            "another campaign's row",
            format!(
                "{}\n{}\n",
                lines[0],
                lines[1].replace(&lines[1][lines[1].len() - 16..], "0123456789abcdef")
            ),
            "belongs to campaign",
        ),
    ];
    for (what, text, words) in cases {
        let dir = d.join(what.replace(' ', "_"));
        std::fs::create_dir_all(&dir).unwrap();
        std::fs::write(dir.join("trials.csv"), &text).unwrap();
        let (code, err) = trials_fails(&[f, "--out", dir.to_str().unwrap()]);
        assert_eq!(code, 2, "{what}: {err}");
        assert!(err.contains(words), "{what}: {err}");
        // Nothing was changed.
        assert_eq!(read(&dir.join("trials.csv")), text, "{what}");
    }
    // A shard's rows resumed under another --shard are not this shard's.
    let s0 = d.join("s0");
    trials(&[f, "--shard", "0/2", "--out", s0.to_str().unwrap()]);
    let (code, err) = trials_fails(&[f, "--shard", "1/2", "--out", s0.to_str().unwrap()]);
    assert_eq!(code, 2);
    assert!(err.contains("is not in shard 1/2"), "{err}");
    let _ = std::fs::remove_dir_all(&d);
}

/// Merge refuses shards of another seed or base scene, an index in two shards and missing
/// indices; `--allow-partial` merges what there is and says what is missing.
#[test]
fn regress_merge_refuses_mismatched_missing_and_duplicated_shards() {
    let d = tmp("merge");
    let f = campaign(&d);
    let fs = f.to_str().unwrap();
    let (s0, s1) = (d.join("s0"), d.join("s1"));
    trials(&[fs, "--shard", "0/2", "--out", s0.to_str().unwrap()]);
    trials(&[fs, "--shard", "1/2", "--out", s1.to_str().unwrap()]);
    let merged = d.join("merged");
    let m = merged.to_str().unwrap();
    // A missing shard.
    let (code, err) = trials_fails(&["merge", fs, s0.to_str().unwrap(), "--out", m]);
    assert_eq!(code, 2);
    assert!(
        err.contains("3 of 6 trials are in no shard: 1, 3, 5"),
        "{err}"
    );
    assert!(!merged.join("trials.csv").exists());
    // The same shard twice.
    let (code, err) = trials_fails(&[
        "merge",
        fs,
        s0.to_str().unwrap(),
        s0.to_str().unwrap(),
        "--out",
        m,
    ]);
    assert_eq!(code, 2);
    assert!(err.contains("trial 0 is in two shards"), "{err}");
    // --allow-partial merges what there is and says what is missing.
    let out = trials(&[
        "merge",
        fs,
        s0.to_str().unwrap(),
        "--allow-partial",
        "--out",
        m,
    ]);
    let so = String::from_utf8_lossy(&out.stdout);
    assert!(
        so.contains("PARTIAL: 3 of 6 trials are missing: 1, 3, 5"),
        "{so}"
    );
    let s: serde_json::Value = serde_json::from_str(&read(&merged.join("summary.json"))).unwrap();
    assert_eq!(s["complete"], false);
    assert_eq!(s["missing_indices"], "1, 3, 5");
    assert_eq!(s["trials"], 3);
    // Another seed: the trials file differs, so the campaign does.
    let other = d.join("other.ron");
    std::fs::write(&other, read(&f).replace("seed: 7", "seed: 8")).unwrap();
    let (code, err) = trials_fails(&[
        "merge",
        other.to_str().unwrap(),
        s0.to_str().unwrap(),
        s1.to_str().unwrap(),
        "--out",
        d.join("m2").to_str().unwrap(),
    ]);
    assert_eq!(code, 2);
    assert!(err.contains("the trials file, the seed differ"), "{err}");
    // Resuming into a folder of another campaign is refused too.
    let (code, err) = trials_fails(&[other.to_str().unwrap(), "--out", s0.to_str().unwrap()]);
    assert_eq!(code, 2);
    assert!(err.contains("holds campaign"), "{err}");
    // Every row carries the campaign id; summary.json the full fingerprint.
    let s: serde_json::Value = serde_json::from_str(&read(&s0.join("summary.json"))).unwrap();
    let id = s["fingerprint"]["campaign_id"]
        .as_str()
        .unwrap()
        .to_string();
    assert_eq!(s["fingerprint"]["seed"], 7);
    assert_eq!(
        s["fingerprint"]["trials_sha256"],
        rpod::report::sha256_hex(read(&f).as_bytes())
    );
    for l in read(&s0.join("trials.csv")).lines().skip(1) {
        assert!(l.ends_with(&format!(",{id}")), "{l}");
    }
    let _ = std::fs::remove_dir_all(&d);
}

/// A trial whose *drawn* values make an invalid scene is `INVALID` (its own outcome, not a
/// failed run, not in the probability's denominator), with the scene error as its reason,
/// quoted as CSV needs; which trials those are follows from the drawn values in `trials.csv`
/// (a mass ≤ 0 kg is invalid). A *grid* value that makes an invalid scene is a located error
/// at load, wherever it stands in the list (the check does not depend on the values' order).
#[test]
fn regress_invalid_trials_are_their_own_outcome() {
    let d = tmp("invalid");
    let scene = std::fs::canonicalize("scenes/examples/docking_aligned.ron").unwrap();
    let f = d.join("inv.ron");
    std::fs::write(
        &f,
        format!(
            r#"Trials(name: "inv", scene: "{}", duration_s: 5.0, count: 6,
    parameters: [Uniform(path: "bodies.chaser.mass_kg", min: -300.0, max: 500.0)],
    success: NoCollision)"#,
            scene.display()
        ),
    )
    .unwrap();
    let out = d.join("out");
    trials(&[f.to_str().unwrap(), "--out", out.to_str().unwrap()]);
    let text = read(&out.join("trials.csv"));
    let mut rdr = csv::Reader::from_reader(text.as_bytes());
    let h = rdr.headers().unwrap().clone();
    let col = |n: &str| h.iter().position(|c| c == n).unwrap();
    let rows: Vec<csv::StringRecord> = rdr.records().map(|r| r.unwrap()).collect();
    assert_eq!(rows.len(), 6);
    let mut invalid = 0;
    for r in &rows {
        let m: f64 = r[col("bodies.chaser.mass_kg")].parse().unwrap();
        if m <= 0.0 {
            invalid += 1;
            assert_eq!(&r[col("outcome")], "INVALID", "{r:?}");
            assert_eq!(&r[col("success")], "false");
            assert!(
                r[col("reason")]
                    .contains("field `bodies.chaser.mass_kg`: must be a positive number"),
                "{r:?}"
            );
        } else {
            assert_ne!(&r[col("outcome")], "INVALID", "{r:?}");
        }
    }
    // The seed's draws give both kinds (else the test would assert nothing of one of them).
    assert!(invalid > 0 && invalid < 6, "{invalid}");
    let s: serde_json::Value = serde_json::from_str(&read(&out.join("summary.json"))).unwrap();
    assert_eq!(s["invalid"], invalid);
    assert_eq!(s["valid_trials"], 6 - invalid);
    assert_eq!(s["successes"], 6 - invalid);
    assert_eq!(s["success_probability"], 1.0);
    // NoCollision is not about docking: no capture probability.
    assert!(s.get("capture_probability").is_none(), "{s}");
    // An invalid grid value: refused at load, located at the value, in any position.
    for (values, j) in [("[300.0, -1.0, 250.0]", 1), ("[-1.0, 300.0, 250.0]", 0)] {
        let g = d.join("grid.ron");
        std::fs::write(
            &g,
            format!(
                r#"Trials(name: "inv", scene: "{}", duration_s: 5.0, count: 3,
    parameters: [Grid(path: "bodies.chaser.mass_kg", values: {values})],
    success: NoCollision)"#,
                scene.display()
            ),
        )
        .unwrap();
        let e = rpod::trials::load(&g).err().expect("refused");
        assert_eq!(e.field, format!("parameters.0.values.{j}"), "{e}");
        assert_eq!(e.line, 2, "{e}");
        assert!(
            e.message.contains("grid value -1.0 makes an invalid scene"),
            "{e}"
        );
        assert!(e.message.contains("must be a positive number"), "{e}");
    }
    let _ = std::fs::remove_dir_all(&d);
}

/// Success beyond docking: `All([GuaranteeHeld(..), MinClearance(..)])` is judged per trial
/// from the guarantee's status and the clearance — checked here against the trial's own
/// `trials.csv` columns (worst margin, first violation, clearance); the summary names the
/// criterion and gives no capture probability; `--keep-runs` keeps each trial's outputs with
/// their provenance.
#[test]
fn val_success_criteria_match_the_recorded_columns() {
    let d = tmp("criteria");
    let scene = std::fs::canonicalize("scenes/examples/docking_aligned.ron").unwrap();
    let f = d.join("c.ron");
    let text = format!(
        r#"Trials(name: "criteria", scene: "{}", duration_s: 30.0, count: 4,
    parameters: [Grid(path: "bodies.chaser.initial.pos_m.1", values: [0.0, 0.05, 0.4, 0.9])],
    success: All([GuaranteeHeld("clearance_5cm"), MinClearance(0.01)]),
    confidence: 0.9, required_probability: 0.9973)"#,
        scene.display()
    );
    std::fs::write(&f, &text).unwrap();
    let out = d.join("out");
    trials(&[
        f.to_str().unwrap(),
        "--keep-runs",
        "--out",
        out.to_str().unwrap(),
    ]);
    let csv_text = read(&out.join("trials.csv"));
    let mut rdr = csv::Reader::from_reader(csv_text.as_bytes());
    let h = rdr.headers().unwrap().clone();
    let col = |n: &str| {
        h.iter()
            .position(|c| c == n)
            .unwrap_or_else(|| panic!("{n}: {h:?}"))
    };
    let (mut successes, mut held) = (0, 0);
    for r in rdr.records().map(|r| r.unwrap()) {
        let worst: f64 = r[col("guarantee.clearance_5cm.worst_margin_m")]
            .parse()
            .unwrap();
        let first = &r[col("guarantee.clearance_5cm.first_violation_s")];
        let clearance: f64 = r[col("min_clearance_non_docking_m")].parse().unwrap();
        // Held ⇔ never violated ⇔ worst margin ≥ 0; the verdict says the same.
        assert_eq!(first.is_empty(), worst >= 0.0, "{r:?}");
        let verdict = &r[col("guarantee.clearance_5cm.verdict")];
        assert_eq!(verdict == "held", first.is_empty(), "{r:?}");
        held += usize::from(verdict == "held");
        let expect = first.is_empty() && clearance >= 0.01;
        assert_eq!(
            &r[col("success")],
            if expect { "true" } else { "false" },
            "{r:?}"
        );
        successes += usize::from(expect);
        let k = &r[col("index")];
        let kept = out.join(format!("runs/{:06}", k.parse::<usize>().unwrap()));
        let s: serde_json::Value = serde_json::from_str(&read(&kept.join("summary.json"))).unwrap();
        assert_eq!(s["provenance"]["rpod_version"], env!("CARGO_PKG_VERSION"));
        assert!(
            s["provenance"]["set"][0]
                .as_str()
                .unwrap()
                .starts_with("bodies.chaser.initial.pos_m.1=")
        );
        assert!(kept.join("trajectory.csv").exists());
    }
    let s: serde_json::Value = serde_json::from_str(&read(&out.join("summary.json"))).unwrap();
    assert_eq!(
        s["success_criterion"],
        "GuaranteeHeld(clearance_5cm) and MinClearance(0.01 m)"
    );
    assert_eq!(s["successes"], successes);
    assert!(s.get("capture_probability").is_none(), "{s}");
    // The programme's statements: the one-sided Clopper–Pearson lower bound at 90 % (closed
    // form with no failure, (1 − c)^(1/n); 0 with no success), the zero-failure run count
    // ⌈ln(0.1)/ln(0.9973)⌉ = 852, and per requirement the held count from the verdicts.
    let lb = s["success_probability_lower_bound"].as_f64().unwrap();
    match successes {
        0 => assert_eq!(lb, 0.0),
        4 => assert!((lb - 0.1f64.powf(0.25)).abs() < 1e-15),
        _ => assert!(lb > 0.0 && lb < successes as f64 / 4.0, "{lb}"),
    }
    assert!(
        s["success_statement"]
            .as_str()
            .unwrap()
            .starts_with("met with probability ≥ ")
    );
    assert_eq!(s["zero_failure_runs_needed"], 852);
    assert_eq!(s["success_requirement_shown"], false);
    let req = &s["requirements"][0];
    assert_eq!(req["guarantee"], "clearance_5cm");
    assert_eq!(req["held"], held);
    assert_eq!(req["trials"], 4);
    assert_eq!(s["provenance"]["rpod_version"], env!("CARGO_PKG_VERSION"));
    // An unknown guarantee is a located error.
    std::fs::write(
        &f,
        text.replace(
            "GuaranteeHeld(\"clearance_5cm\")",
            "GuaranteeHeld(\"nope\")",
        ),
    )
    .unwrap();
    let e = rpod::trials::load(&f).err().expect("refused");
    assert_eq!((e.line, e.field.as_str()), (3, "success.0.0"), "{e}");
    assert!(e.message.contains("no guarantee `nope`"), "{e}");
    // A docking state that does not exist, and no state at all: criteria that could never be
    // met are located errors (not a campaign of 0 % success).
    for (criterion, words) in [
        ("StateIn([\"LATCHD\"])", "unknown docking state \"LATCHD\""),
        ("StateIn([])", "names no state"),
    ] {
        std::fs::write(
            &f,
            text.replace("GuaranteeHeld(\"clearance_5cm\")", criterion),
        )
        .unwrap();
        let e = rpod::trials::load(&f).err().expect("refused");
        assert_eq!((e.line, e.field.as_str()), (3, "success.0.0"), "{e}");
        assert!(e.message.contains(words), "{e}");
    }
    // A docking criterion over a scene without a docking mechanism.
    let free = std::fs::canonicalize("scenes/examples/free_drift.ron").unwrap();
    for criterion in ["Latched", "Docked"] {
        std::fs::write(
            &f,
            text.replace(&scene.display().to_string(), &free.display().to_string())
                .replace(
                    "GuaranteeHeld(\"clearance_5cm\"), MinClearance(0.01)",
                    criterion,
                ),
        )
        .unwrap();
        let e = rpod::trials::load(&f).err().expect("refused");
        assert_eq!(e.field, "success.0.0", "{criterion}: {e}");
        assert!(
            e.message.contains("needs the base scene's `docking`"),
            "{criterion}: {e}"
        );
    }
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn regress_trials_file_limits_and_nesting_are_located() {
    let d = tmp("limits");
    for (body, line, field, words) in [
        ("count: 100000000,", 3, "count", "from 1 to 1000000"),
        (
            "count: 2, parameters: [Grid(path: \"a\", values: [1.0]), Grid(path: \"a\", values: [2.0])],",
            3,
            "parameters.1.path",
            "varied twice",
        ),
        (
            &format!("count: 2, parameters: [{}]", "[".repeat(10_000)),
            3,
            "",
            "nested deeper than 64",
        ),
        (
            "count: 2, parameters: [Grid(path: \"a, b\", values: [1.0])],",
            3,
            "parameters.0.path",
            "a scene field path",
        ),
    ] {
        let f = d.join("t.ron");
        let params = if body.contains("parameters") {
            ""
        } else {
            "parameters: [Grid(path: \"a\", values: [1.0])],"
        };
        std::fs::write(
            &f,
            format!("Trials(\n  name: \"x\", scene: \"s.ron\",\n  {body} {params}\n  success: Latched,\n)"),
        )
        .unwrap();
        let e = rpod::trials::load(&f).err().expect("refused");
        assert_eq!((e.line, e.field.as_str()), (line, field), "{e}");
        assert!(e.message.contains(words), "{e}");
    }
    let _ = std::fs::remove_dir_all(&d);
}

/// The envelope plot coloured by a numeric column, with small multiples over a third
/// parameter: the SVG's legend holds the five bins of the column's recorded range (read back
/// from `trials.csv`), one panel title per value of the third (grid) parameter; an unknown
/// column is a located error.
#[test]
fn regress_envelope_plot_colours_by_a_column_and_draws_small_multiples() {
    let d = tmp("envelope");
    let scene = std::fs::canonicalize("scenes/examples/docking_aligned.ron").unwrap();
    let text = format!(
        r#"Trials(
    name: "multiples",
    scene: "{}",
    duration_s: 2.0,
    seed: 3,
    count: 8,
    parameters: [
        Grid(path: "bodies.chaser.initial.pos_m.1", values: [0.0, 0.05]),
        Grid(path: "bodies.chaser.initial.pos_m.2", values: [0.0, 0.05]),
        Grid(path: "bodies.chaser.initial.vel_m_s.0", values: [-0.03, -0.02]),
    ],
    success: Latched,
    plot: (color_by: "min_clearance_non_docking_m"),
)"#,
        scene.display()
    );
    let f = d.join("multiples.ron");
    std::fs::write(&f, &text).unwrap();
    let out = d.join("out");
    trials(&[f.to_str().unwrap(), "--out", out.to_str().unwrap()]);
    let svg = read(&out.join("capture_envelope.svg"));
    assert!(out.join("capture_envelope.png").is_file());
    // Panels: one per value of the third parameter.
    for v in ["\u{2212}0.03", "\u{2212}0.02"] {
        assert!(
            svg.contains(&format!("bodies.chaser.initial.vel_m_s.0 = {v}")),
            "panel {v} missing"
        );
    }
    // Legend: five bins from the smallest to the largest recorded clearance.
    let csv = read(&out.join("trials.csv"));
    let mut lines = csv.lines();
    let head: Vec<&str> = lines.next().unwrap().split(',').collect();
    let col = head
        .iter()
        .position(|h| *h == "min_clearance_non_docking_m")
        .unwrap();
    let vals: Vec<f64> = lines
        .map(|l| l.split(',').nth(col).unwrap().parse().unwrap())
        .collect();
    assert_eq!(vals.len(), 8);
    let (lo, hi) = vals
        .iter()
        .fold((f64::INFINITY, 0.0f64), |(l, h), v| (l.min(*v), h.max(*v)));
    assert!(hi > lo, "{vals:?}");
    // The legend once, beside the last panel: five bins `COLUMN a to b`.
    let bins = svg.matches(" to ").count();
    assert_eq!(bins, 5, "{bins} bin labels");
    let _ = std::fs::remove_dir_all(&out);
    std::fs::write(
        &f,
        text.replace("min_clearance_non_docking_m\"", "clearance\""),
    )
    .unwrap();
    let e = rpod::trials::load(&f).err().expect("refused");
    assert_eq!(e.field, "plot.color_by", "{e}");
    assert!(
        e.line > 0 && e.message.contains("no trials.csv column"),
        "{e}"
    );
    let _ = std::fs::remove_dir_all(&d);
}

/// The requirements campaign's per-requirement output, on 2 short trials of
/// `scenes/examples/requirements_approach.ron` (60 s: the hold 100 m out, where the passive-safety,
/// line-of-sight and closing-speed requirements are active): every guarantee of the scene has
/// its verdict column; each row's verdict is the one the trial's own `summary.json` gives
/// (`--keep-runs`); `summary.json`'s per-requirement counts are the column's counts and its
/// lower bound is the Clopper–Pearson one (with no failure the closed form (1 − c)^(1/n)).
#[test]
fn val_requirements_campaign_reports_each_requirement() {
    let d = tmp("requirements");
    let scene = std::fs::canonicalize("scenes/examples/requirements_approach.ron").unwrap();
    let f = d.join("r.ron");
    // The bundled campaign's dispersions, shortened.
    let bundled = read(Path::new("scenes/trials/requirements_campaign.ron"));
    let text = bundled
        .replace(
            "\"../examples/requirements_approach.ron\"",
            &format!("{:?}", scene.display().to_string()),
        )
        .replace("duration_s: 2300.0", "duration_s: 60.0")
        .replace("count: 20", "count: 2");
    assert_ne!(text, bundled);
    std::fs::write(&f, &text).unwrap();
    let out = d.join("out");
    trials(&[
        f.to_str().unwrap(),
        "--keep-runs",
        "--out",
        out.to_str().unwrap(),
    ]);
    let csv_text = read(&out.join("trials.csv"));
    let mut rdr = csv::Reader::from_reader(csv_text.as_bytes());
    let h = rdr.headers().unwrap().clone();
    let col = |n: &str| {
        h.iter()
            .position(|c| c == n)
            .unwrap_or_else(|| panic!("{n}: {h:?}"))
    };
    let names = [
        "kos_30m_corridor_20deg",
        "closing_speed_gates",
        "passive_safety_2p5m",
        "docking_target_in_view",
    ];
    let rows: Vec<csv::StringRecord> = rdr.records().map(|r| r.unwrap()).collect();
    assert_eq!(rows.len(), 2);
    let s: serde_json::Value = serde_json::from_str(&read(&out.join("summary.json"))).unwrap();
    for (i, name) in names.iter().enumerate() {
        let mut held = 0;
        for r in &rows {
            let verdict = &r[col(&format!("guarantee.{name}.verdict"))];
            let k: usize = r[col("index")].parse().unwrap();
            let run: serde_json::Value =
                serde_json::from_str(&read(&out.join(format!("runs/{k:06}/summary.json"))))
                    .unwrap();
            let g = run["guarantees"]
                .as_array()
                .unwrap()
                .iter()
                .find(|g| g["name"] == *name)
                .unwrap_or_else(|| panic!("{name} in {run}"));
            assert_eq!(g["verdict"], *verdict, "trial {k} {name}");
            held += usize::from(verdict == "held");
        }
        let req = &s["requirements"][i];
        assert_eq!(req["guarantee"], *name);
        // The cone and the line of sight have rate bounds (judged on intervals); the gate and
        // passive safety are judged at the samples.
        let want = if i == 0 || i == 3 {
            "interval"
        } else {
            "samples only"
        };
        assert_eq!(req["judged"], want, "{req}");
        assert_eq!(req["held"], held, "{req}");
        assert_eq!(req["trials"], 2);
        let lb = req["probability_lower_bound"].as_f64().unwrap();
        match held {
            0 => assert_eq!(lb, 0.0),
            2 => assert!((lb - 0.1f64.sqrt()).abs() < 1e-15, "{lb}"),
            _ => assert!(lb > 0.0 && lb < 0.5, "{lb}"),
        }
    }
    assert_eq!(s["zero_failure_runs_needed"], 852);
}
