//! Determinism: two runs of `scenes/examples/free_drift.ron` write byte-identical `trajectory.csv`,
//! `events.jsonl` and `contacts.csv`, and `summary.json` is identical except for the wall-clock fields.
//!
//! Reference: the first run. To see a difference, `diff` the two directories this test prints.

use std::process::Command;

fn run(dir: &std::path::Path) {
    let _ = std::fs::remove_dir_all(dir);
    let r = Command::new(env!("CARGO_BIN_EXE_rpod"))
        .args(["run", "scenes/examples/free_drift.ron", "--out"])
        .arg(dir)
        .output()
        .unwrap();
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
}

#[test]
fn regress_free_drift_outputs_are_byte_identical() {
    let base = std::env::temp_dir().join(format!("rpod-det-{}", std::process::id()));
    let (a, b) = (base.join("a"), base.join("b"));
    run(&a);
    run(&b);
    for f in ["trajectory.csv", "events.jsonl", "contacts.csv"] {
        let x = std::fs::read(a.join(f)).unwrap();
        let y = std::fs::read(b.join(f)).unwrap();
        assert!(
            x == y,
            "{f} differs between {} and {}",
            a.display(),
            b.display()
        );
    }
    let strip = |p: &std::path::Path| {
        let mut v: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(p.join("summary.json")).unwrap())
                .unwrap();
        v["wall_s"] = serde_json::Value::Null;
        v["steps_per_s"] = serde_json::Value::Null;
        v
    };
    assert_eq!(strip(&a), strip(&b));
    // The run is the full 600 s: 60 000 steps, a row every 10 from step 0 → 6 001 rows + header.
    let rows = std::fs::read_to_string(a.join("trajectory.csv"))
        .unwrap()
        .lines()
        .count();
    assert_eq!(rows, 6002);
    let _ = std::fs::remove_dir_all(&base);
}
