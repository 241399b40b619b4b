//! `rpod reproduce geng2015` (to be written by the geng2015 integration).

use std::path::Path;

/// Runs the paper's cases and writes REPORT.md, plots and claims.json into `out`.
pub fn run(_out: &Path) -> Result<(), String> {
    Err("the geng2015 reproduction is not written yet".into())
}
