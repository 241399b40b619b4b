//! `rpod reproduce NAME --out DIR`: each paper's headline result, one file per paper. Every run
//! writes `DIR/NAME/REPORT.md`, its PNG plots and `DIR/NAME/claims.json` (a JSON array of
//! `{id, claim, kind, paper, threshold_source, measured, held, sensitivity}`, see
//! [`crate::report::claims`]); a claim the testbed refutes stays with `held: false`.
//! [`write_index`] then writes `DIR/INDEX.md`: one row per paper, claims held per kind, a
//! link to each report.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use crate::report::{ClaimKind, read_claims_json, tally, write_atomic};

pub mod geng2015;
pub mod guo2016;
pub mod guo2016_ct;
pub mod xu2015;
pub mod xu2019;
pub mod zhang2018;
pub mod zhang2018_sim;

/// The papers `rpod reproduce` knows, in the order it runs them.
pub const PAPERS: &[&str] = &["guo2016", "xu2015", "geng2015", "xu2019", "zhang2018"];

/// The papers from the longest reproduction to the shortest (measured 2026-12-06: xu2019
/// 176 s, guo2016 135 s, geng2015 90 s, xu2015 51 s, zhang2018 5 s on a loaded 2-core
/// machine): `rpod reproduce` starts them in this order on its worker threads, so the long
/// ones do not end up last.
pub const TYPICAL_ORDER: &[&str] = &["xu2019", "guo2016", "geng2015", "xu2015", "zhang2018"];

/// Short citation of each paper of [`PAPERS`], same order.
pub const CITATIONS: &[&str] = &[
    "Guo, Song, Li (2016): coupled sliding-mode control, elliptic-cissoid corridor",
    "Xu, Hu (2015): characteristic-model golden-section adaptive control vs PD",
    "Geng, Chen, Liang (2015): twisting and modified twisting on the docking ports",
    "Xu, Wen, Wei (2019): artificial potential on the air-bearing table",
    "Zhang, He, Lü, Wang (2018): differential-game barrier near Sun–Earth L2",
];

/// File name of the index at the top of the output folder.
pub const INDEX_FILE: &str = "INDEX.md";

/// Runs one paper's reproduction into `out` (the paper's own directory).
pub fn run(name: &str, out: &Path) -> Result<(), String> {
    if !PAPERS.contains(&name) {
        return Err(format!(
            "unknown paper `{}`; known: {}",
            name.escape_debug(),
            PAPERS.join(", ")
        ));
    }
    std::fs::create_dir_all(out).map_err(|e| format!("cannot create {}: {e}", out.display()))?;
    match name {
        "guo2016" => guo2016::run(out),
        "xu2015" => xu2015::run(out),
        "geng2015" => geng2015::run(out),
        "xu2019" => xu2019::run(out),
        "zhang2018" => zhang2018::run(out),
        other => Err(format!(
            "unknown paper `{other}`; known: {}",
            PAPERS.join(", ")
        )),
    }
}

/// The text of `DIR/INDEX.md` for the papers' `claims.json` found under `dir`: one row per
/// paper of [`PAPERS`] with the claims held per kind ("K of N"), the number of claims whose
/// verdict depends on a choice the paper leaves open, and a relative link to its report; a
/// paper without a readable `DIR/NAME/claims.json` gets a row saying so.
pub fn index_markdown(dir: &Path) -> String {
    let mut md = String::from(
        "# rpod reproductions\n\n\
         One row per paper: how many of the paper's own claims held in this build, how many of \
         the questions beyond the paper (full geometry, added terms, campaigns, feasibility \
         bounds), and how many verdicts depend on a choice the paper leaves open (each report \
         shows the verdict under the other choice). Every threshold's source (the paper, or \
         us and why) is in each report's claims tables and in `claims.json`.\n\n\
         | paper | claims of the paper held | beyond the paper held | verdicts with a sensitivity | report |\n\
         |---|---|---|---|---|\n",
    );
    for (name, cite) in PAPERS.iter().zip(CITATIONS) {
        let report = format!("{name}/REPORT.md");
        match read_claims_json(&dir.join(name).join("claims.json")) {
            Ok(claims) => {
                let t = tally(&claims);
                let sens = claims.iter().filter(|c| c.sensitivity.is_some()).count();
                let _ = writeln!(
                    md,
                    "| {cite} | {} of {} | {} of {} | {sens} | [{report}]({report}) |",
                    t[0].0, t[0].1, t[1].0, t[1].1
                );
            }
            Err(_) => {
                let _ = writeln!(md, "| {cite} | not run | not run | — | — |");
            }
        }
    }
    let _ = writeln!(
        md,
        "\nKinds: `{}` = a claim the paper makes, checked as stated; `{}` = a question the \
         testbed asks that the paper does not.",
        ClaimKind::Paper.as_str(),
        ClaimKind::BeyondThePaper.as_str()
    );
    md
}

/// Writes `dir/INDEX.md` ([`index_markdown`]) atomically; returns its path.
pub fn write_index(dir: &Path) -> Result<PathBuf, String> {
    let path = dir.join(INDEX_FILE);
    write_atomic(&path, index_markdown(dir).as_bytes())
        .map_err(|e| format!("cannot write {}: {e}", path.display()))?;
    Ok(path)
}

#[cfg(test)]
mod tests {
    //! INDEX.md against claims written by hand: counts per kind, links, missing papers.
    use super::*;
    use crate::report::{Claim, ClaimKind, write_claims_json};

    #[test]
    fn val_index_counts_claims_per_kind_and_links_reports() {
        let d = std::env::temp_dir().join(format!("rpod-index-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(d.join("guo2016")).unwrap();
        let c = |id: &str, kind, held| Claim::new(id, kind, "c", None, "ours: x", "m", held);
        write_claims_json(
            &d.join("guo2016").join("claims.json"),
            &[
                c("a", ClaimKind::Paper, true),
                c("b", ClaimKind::Paper, false),
                c("c", ClaimKind::BeyondThePaper, true).with_sensitivity("s"),
            ],
        )
        .unwrap();
        let path = write_index(&d).unwrap();
        let md = std::fs::read_to_string(path).unwrap();
        assert!(md.contains(
            "| Guo, Song, Li (2016): coupled sliding-mode control, elliptic-cissoid corridor | 1 of 2 | 1 of 1 | 1 | [guo2016/REPORT.md](guo2016/REPORT.md) |"
        ), "{md}");
        for name in &PAPERS[1..] {
            let cite = CITATIONS[PAPERS.iter().position(|p| p == name).unwrap()];
            assert!(
                md.contains(&format!("| {cite} | not run | not run | — | — |")),
                "{name}"
            );
        }
        let _ = std::fs::remove_dir_all(&d);
    }

    #[test]
    fn invariant_typical_order_is_every_paper_once() {
        let mut a: Vec<_> = PAPERS.to_vec();
        let mut b: Vec<_> = TYPICAL_ORDER.to_vec();
        a.sort_unstable();
        b.sort_unstable();
        assert_eq!(a, b);
    }
}
