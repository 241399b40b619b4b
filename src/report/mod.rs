//! Reports: PNG/SVG plots, the `REPORT.md` builder and `claims.json`.
//!
//! This is the shared output layer of `rpod reproduce NAME --out DIR` and `rpod trials` (the output
//! contract: `docs/outputs.md`, `ARCHITECTURE.md`). It is Bevy-free and has no global state besides
//! a lazily built, read-only font database.
//!
//! - [`plot`]: [`Plot`] (one set of axes: time series, XY paths with obstacle outlines and
//!   polygons, categorical outcome maps) and [`Figure`] (a grid of plots with a title), written
//!   as SVG (text as SVG `<text>`) and PNG (rasterised by `resvg` with the bundled DejaVu Sans,
//!   so no system font and no download is ever needed).
//! - [`claims`]: [`Claim`] (with its [`ClaimKind`] and threshold source) and
//!   [`write_claims_json`] — the `claims.json` contract.
//! - [`markdown`]: [`ReportBuilder`] — `REPORT.md` with paragraphs, tables, a claims table and
//!   figures, plus the figure files and `claims.json`, in one call.
//! - [`run_plots`]: `rpod plot RUN_DIR`, the standard figures of a recorded run.
//! - [`write_atomic`]: every file is written to a temporary name in its directory, flushed, and
//!   renamed, so a crash never leaves a half file that looks whole.
//!
//! Errors are `std::io::Error` whose message names the path concerned; nothing here panics on
//! bad input (non-finite data points are skipped, empty plots still draw their axes).
//!
//! Determinism: the same inputs give byte-identical SVG, PNG, JSON and Markdown (no
//! timestamps, fixed number formatting, fixed iteration order; checked by tests).

pub mod claims;
pub mod fsio;
pub mod markdown;
pub mod plot;
mod raster;
pub mod run_plots;
mod svg;
mod ticks;

pub use claims::{Claim, ClaimKind, held_word, read_claims_json, tally, write_claims_json};
pub use fsio::write_atomic;
pub use markdown::{ReportBuilder, claims_markdown, compact_table};
pub use plot::{Color, Dash, Figure, Legend, LineStyle, PALETTE, Plot};
pub use raster::svg_to_png;

/// The rpod version (`Cargo.toml`).
pub const RPOD_VERSION: &str = env!("CARGO_PKG_VERSION");

/// The git commit rpod was built from, when built from a git checkout (see `build.rs`).
pub const GIT_COMMIT: Option<&str> = option_env!("RPOD_GIT_COMMIT");

/// What built this binary: `{"rpod_version": …, "git_commit": … or null}`.
pub fn build_provenance() -> serde_json::Value {
    serde_json::json!({"rpod_version": RPOD_VERSION, "git_commit": GIT_COMMIT})
}

/// SHA-256 of bytes, lower-case hex (provenance: scene and trials file hashes).
pub fn sha256_hex(bytes: &[u8]) -> String {
    use sha2::Digest;
    let d = sha2::Sha256::digest(bytes);
    d.iter().map(|b| format!("{b:02x}")).collect()
}

/// A scratch directory unique to this test process and tag (emptied first).
#[cfg(test)]
pub(crate) fn scratch(tag: &str) -> std::path::PathBuf {
    let d = std::env::temp_dir().join(format!("rpod-report-{tag}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}
