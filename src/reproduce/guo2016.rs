//! `rpod reproduce guo2016` (to be written by the guo2016 integration).

use std::path::Path;

/// Runs the paper's cases and writes REPORT.md, plots and claims.json into `out`.
pub fn run(_out: &Path) -> Result<(), String> {
    Err("the guo2016 reproduction is not written yet".into())
}
