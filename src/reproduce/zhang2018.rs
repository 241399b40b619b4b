//! `rpod reproduce zhang2018` (to be written by the zhang2018 integration).

use std::path::Path;

/// Runs the paper's cases and writes REPORT.md, plots and claims.json into `out`.
pub fn run(_out: &Path) -> Result<(), String> {
    Err("the zhang2018 reproduction is not written yet".into())
}
