//! `rpod plot RUN_DIR`: every figure is written as PNG and SVG with its data as CSV beside it,
//! and the data are right: the range in `range.csv` equals |r_chaser − r_target| computed here
//! from `trajectory.csv`'s world-frame columns, and the clearance figure carries the monitor's
//! minimum distance and every guarantee margin unchanged.
//!
//! Reference: the run's own `trajectory.csv`, read independently with the `csv` crate.

use std::process::Command;

fn rpod(args: &[&str]) {
    let r = Command::new(env!("CARGO_BIN_EXE_rpod"))
        .args(args)
        .output()
        .unwrap();
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
}

fn table(p: &std::path::Path) -> (Vec<String>, Vec<Vec<String>>) {
    let mut r = csv::Reader::from_path(p).unwrap();
    let h = r.headers().unwrap().iter().map(str::to_string).collect();
    let rows = r
        .records()
        .map(|r| r.unwrap().iter().map(str::to_string).collect())
        .collect();
    (h, rows)
}

#[test]
fn val_run_plots_carry_the_run_data() {
    let d = std::env::temp_dir().join(format!("rpod-plot-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    let run = d.join("run");
    rpod(&[
        "-q",
        "run",
        "scenes/examples/docking_aligned.ron",
        "--duration",
        "25",
        "--out",
        run.to_str().unwrap(),
    ]);
    rpod(&["-q", "plot", run.to_str().unwrap()]);
    let plots = run.join("plots");
    for f in ["relative_position", "range", "clearance", "docking"] {
        for ext in ["png", "svg", "csv"] {
            assert!(plots.join(format!("{f}.{ext}")).exists(), "{f}.{ext}");
        }
        // Tick labels use the Unicode minus, never a hyphen before a digit.
        let svg = std::fs::read_to_string(plots.join(format!("{f}.svg"))).unwrap();
        assert!(
            !svg.contains(">-0") && !svg.contains(">-1") && !svg.contains(">-2"),
            "{f}"
        );
    }
    let (th, trows) = table(&run.join("trajectory.csv"));
    let c = |n: &str| th.iter().position(|h| h == n).unwrap();
    let (rh, rrows) = table(&plots.join("range.csv"));
    assert_eq!(rh, ["t_s", "range_m", "range_rate_m_s"]);
    assert_eq!(rrows.len(), trows.len());
    for (t, r) in trows.iter().zip(&rrows) {
        let p = |b: &str, k: &str| t[c(&format!("{b}.{k}"))].parse::<f64>().unwrap();
        let d = ["px_m", "py_m", "pz_m"].map(|k| p("chaser", k) - p("target", k));
        let range = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
        let got: f64 = r[1].parse().unwrap();
        assert!(
            (got - range).abs() <= 1e-12 * range.max(1.0),
            "{got} vs {range}"
        );
    }
    let (ch, crows) = table(&plots.join("clearance.csv"));
    assert_eq!(
        ch,
        ["t_s", "min_distance_m", "guarantee.clearance_5cm.margin_m"]
    );
    for (t, r) in trows.iter().zip(&crows) {
        assert_eq!(t[c("min_distance_m")], r[1]);
        assert_eq!(t[c("guarantee.clearance_5cm.margin_m")], r[2]);
    }
    let _ = std::fs::remove_dir_all(&d);
}
