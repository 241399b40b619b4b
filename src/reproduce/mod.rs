//! `rpod reproduce NAME --out DIR`: each paper's headline result, one file per paper. Every run
//! writes `DIR/NAME/REPORT.md`, its PNG plots and `DIR/NAME/claims.json` (a JSON array of
//! `{id, claim, paper, measured, held}`); a claim the testbed refutes stays with `held: false`.

use std::path::Path;

pub mod geng2015;
pub mod guo2016;
pub mod xu2015;
pub mod xu2019;
pub mod zhang2018;

/// The papers `rpod reproduce` knows, in the order it runs them.
pub const PAPERS: &[&str] = &["guo2016", "xu2015", "geng2015", "xu2019", "zhang2018"];

/// Runs one paper's reproduction into `out` (the paper's own directory).
pub fn run(name: &str, out: &Path) -> Result<(), String> {
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
