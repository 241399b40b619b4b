//! `REPORT.md` builder: title, headings, paragraphs, tables, a claims table and figures,
//! written together with the figure files and `claims.json` by [`ReportBuilder::write`].

use std::fmt::Write as _;
use std::io;
use std::path::{Path, PathBuf};

use super::claims::{Claim, ClaimKind, tally, validate_claims, write_claims_json};
use super::fsio::{with_path, write_atomic};
use super::plot::Figure;

/// File name of the report inside the output directory.
pub const REPORT_FILE: &str = "REPORT.md";
/// File name of the claims inside the output directory.
pub const CLAIMS_FILE: &str = "claims.json";

#[derive(Debug, Clone)]
enum Block {
    Heading(String),
    Subheading(String),
    Findings,
    Raw(String),
    Paragraph(String),
    Table {
        headers: Vec<String>,
        rows: Vec<Vec<String>>,
    },
    Claims,
    Image {
        alt: String,
        rel_path: String,
    },
    Code(String),
}

/// Builds a `REPORT.md` and the files it links to.
///
/// Blocks appear in the order they are added. [`Self::figure`] stores a [`Figure`] that
/// [`Self::write`] renders to `DIR/<stem>.png` (and `DIR/<stem>.svg` with [`Self::with_svg`]);
/// [`Self::claims`] inserts the claims table and makes [`Self::write`] also write
/// `DIR/claims.json`. Output is byte-identical for identical input.
#[derive(Debug, Clone)]
pub struct ReportBuilder {
    title: String,
    blocks: Vec<Block>,
    figures: Vec<(String, Figure)>,
    claims: Option<Vec<Claim>>,
    findings: Option<Vec<String>>,
    svg: bool,
}

/// Escapes a table cell: `|` and newlines would break the row.
fn cell(s: &str) -> String {
    s.replace('|', "\\|")
        .replace("\r\n", "<br>")
        .replace('\n', "<br>")
}

fn invalid(msg: String) -> io::Error {
    io::Error::new(io::ErrorKind::InvalidInput, msg)
}

/// Checks that `p` is a relative path inside the report directory (no `..`, not absolute,
/// forward slashes only), as Markdown viewers resolve links against the report's directory.
fn check_rel_path(p: &str) -> io::Result<()> {
    let bad = p.is_empty()
        || p.starts_with('/')
        || p.contains('\\')
        || p.contains(':')
        || p.split('/').any(|c| c == ".." || c.is_empty());
    if bad {
        return Err(invalid(format!(
            "image path {p:?} must be relative to the report directory (no '..', '/' separators)"
        )));
    }
    Ok(())
}

impl ReportBuilder {
    /// A report whose first line is `# title`.
    pub fn new(title: impl Into<String>) -> Self {
        Self {
            title: title.into(),
            blocks: Vec::new(),
            figures: Vec::new(),
            claims: None,
            findings: None,
            svg: false,
        }
    }

    /// Also write each figure as SVG next to its PNG (default: PNG only).
    pub fn with_svg(&mut self, svg: bool) -> &mut Self {
        self.svg = svg;
        self
    }

    /// A second-level heading (`## text`).
    pub fn heading(&mut self, text: impl Into<String>) -> &mut Self {
        self.blocks.push(Block::Heading(text.into()));
        self
    }

    /// A third-level heading (`### text`).
    pub fn subheading(&mut self, text: impl Into<String>) -> &mut Self {
        self.blocks.push(Block::Subheading(text.into()));
        self
    }

    /// A paragraph of Markdown text (inserted as given).
    pub fn paragraph(&mut self, text: impl Into<String>) -> &mut Self {
        self.blocks.push(Block::Paragraph(text.into()));
        self
    }

    /// Markdown inserted exactly as given (not trimmed, no newline added) after the blank
    /// line that separates blocks; `raw("")` ends a report with a blank line.
    pub fn raw(&mut self, text: impl Into<String>) -> &mut Self {
        self.blocks.push(Block::Raw(text.into()));
        self
    }

    /// A fenced code block (e.g. a scene excerpt or a command line).
    pub fn code(&mut self, text: impl Into<String>) -> &mut Self {
        self.blocks.push(Block::Code(text.into()));
        self
    }

    /// A Markdown table. Every row must have as many cells as `headers` (checked by
    /// [`Self::write`] / [`Self::to_markdown`]); `|` and newlines in cells are escaped.
    pub fn table<S: AsRef<str>>(&mut self, headers: &[S], rows: &[Vec<String>]) -> &mut Self {
        self.blocks.push(Block::Table {
            headers: headers.iter().map(|h| h.as_ref().to_owned()).collect(),
            rows: rows.to_vec(),
        });
        self
    }

    /// The claims tables of [`claims_markdown`] (the paper's claims, then those beyond the
    /// paper); [`Self::write`] also writes them to `claims.json`. Calling it again replaces
    /// the claims.
    pub fn claims(&mut self, claims: &[Claim]) -> &mut Self {
        if self.claims.is_none() {
            self.blocks.push(Block::Claims);
        }
        self.claims = Some(claims.to_vec());
        self
    }

    /// Appends one claim to the claims table, placing the table here if [`Self::claims`] has
    /// not placed it yet. A report that computes its claims section by section places the
    /// table first (`claims(&[])`) and adds each claim where it is measured.
    pub fn claim(&mut self, claim: Claim) -> &mut Self {
        if self.claims.is_none() {
            self.blocks.push(Block::Claims);
        }
        self.claims.get_or_insert_with(Vec::new).push(claim);
        self
    }

    /// The claim with this id, to amend (e.g. a sensitivity measured in a later section).
    pub fn claim_mut(&mut self, id: &str) -> Option<&mut Claim> {
        self.claims.as_mut()?.iter_mut().find(|c| c.id == id)
    }

    /// Places the findings list here: one `- finding` line per [`Self::finding`], in the
    /// order they are added, wherever in the report they are measured.
    pub fn findings(&mut self) -> &mut Self {
        if self.findings.is_none() {
            self.blocks.push(Block::Findings);
            self.findings = Some(Vec::new());
        }
        self
    }

    /// Appends one finding (Markdown) to the findings list, placing the list here if
    /// [`Self::findings`] has not placed it yet.
    pub fn finding(&mut self, text: impl Into<String>) -> &mut Self {
        self.findings();
        self.findings.get_or_insert_with(Vec::new).push(text.into());
        self
    }

    /// An image link to a file the caller has written; `rel_path` is relative to the report
    /// directory (e.g. `"trajectory.png"`).
    pub fn image(&mut self, alt: impl Into<String>, rel_path: impl Into<String>) -> &mut Self {
        self.blocks.push(Block::Image {
            alt: alt.into(),
            rel_path: rel_path.into(),
        });
        self
    }

    /// A figure rendered by [`Self::write`] to `<stem>.png` (and `<stem>.svg`) in the report
    /// directory, linked here with `alt` as its text.
    pub fn figure(
        &mut self,
        stem: impl Into<String>,
        alt: impl Into<String>,
        figure: Figure,
    ) -> &mut Self {
        let stem = stem.into();
        self.blocks.push(Block::Image {
            alt: alt.into(),
            rel_path: format!("{stem}.png"),
        });
        self.figures.push((stem, figure));
        self
    }

    /// The claims given to [`Self::claims`], if any.
    pub fn claims_list(&self) -> Option<&[Claim]> {
        self.claims.as_deref()
    }

    /// The Markdown text of the report. Errors (`InvalidInput`) on a table row whose length
    /// differs from its header, an image path outside the report directory, or bad claim ids.
    pub fn to_markdown(&self) -> io::Result<String> {
        let mut md = String::new();
        let _ = writeln!(md, "# {}", self.title);
        for (bi, b) in self.blocks.iter().enumerate() {
            md.push('\n');
            match b {
                Block::Heading(t) => {
                    let _ = writeln!(md, "## {t}");
                }
                Block::Subheading(t) => {
                    let _ = writeln!(md, "### {t}");
                }
                Block::Paragraph(t) => {
                    let _ = writeln!(md, "{}", t.trim_end());
                }
                Block::Raw(t) => md.push_str(t),
                Block::Findings => {
                    for f in self.findings.as_deref().unwrap_or(&[]) {
                        let _ = writeln!(md, "- {f}");
                    }
                }
                Block::Code(t) => {
                    let _ = writeln!(md, "```\n{}\n```", t.trim_end());
                }
                Block::Table { headers, rows } => {
                    for (ri, r) in rows.iter().enumerate() {
                        if r.len() != headers.len() {
                            return Err(invalid(format!(
                                "report block {bi}: table row {ri} has {} cells, header has {}",
                                r.len(),
                                headers.len()
                            )));
                        }
                    }
                    write_table(&mut md, headers, rows);
                }
                Block::Claims => {
                    md.push_str(&claims_markdown(self.claims.as_deref().unwrap_or(&[]))?);
                }
                Block::Image { alt, rel_path } => {
                    check_rel_path(rel_path)?;
                    let alt = alt.replace(['[', ']'], "");
                    let _ = writeln!(md, "![{alt}]({rel_path})");
                }
            }
        }
        Ok(md)
    }

    /// Creates `dir` (and parents) if needed and writes, each atomically: the figures
    /// (`<stem>.png`, and `<stem>.svg` if enabled), `claims.json` (if [`Self::claims`] was
    /// called) and last `REPORT.md`, so a `REPORT.md` exists only if everything it links to was
    /// written. Returns the path of `REPORT.md`.
    pub fn write(&self, dir: &Path) -> io::Result<PathBuf> {
        let md = self.to_markdown()?;
        std::fs::create_dir_all(dir).map_err(|e| with_path(dir, "create directory", e))?;
        let mut stems = std::collections::BTreeSet::new();
        for (stem, fig) in &self.figures {
            if !stems.insert(stem.as_str()) {
                return Err(invalid(format!("figure file {stem:?} added twice")));
            }
            fig.write_png(&dir.join(format!("{stem}.png")))?;
            if self.svg {
                fig.write_svg(&dir.join(format!("{stem}.svg")))?;
            }
        }
        if let Some(claims) = &self.claims {
            write_claims_json(&dir.join(CLAIMS_FILE), claims)?;
        }
        let path = dir.join(REPORT_FILE);
        write_atomic(&path, md.as_bytes())?;
        Ok(path)
    }
}

/// Markdown of a claims list: a "K of N claims held" line with the count per kind, then one
/// table per kind that has claims — "Claims of the paper", then "Beyond the paper" — with the
/// columns `id | claim | paper | threshold (source) | measured | held | sensitivity`; held as
/// "✔ held" or "✘ NOT held", a missing paper value or sensitivity as "—". Errors
/// (`InvalidInput`) on claims that [`validate_claims`] refuses.
pub fn claims_markdown(claims: &[Claim]) -> io::Result<String> {
    validate_claims(claims)?;
    let t = tally(claims);
    let held = t[0].0 + t[1].0;
    let mut md = String::new();
    let _ = writeln!(
        md,
        "{held} of {} claims held: {} of {} claims of the paper, {} of {} beyond the paper.",
        claims.len(),
        t[0].0,
        t[0].1,
        t[1].0,
        t[1].1
    );
    let headers: Vec<String> = [
        "id",
        "claim",
        "paper",
        "threshold (source)",
        "measured",
        "held",
        "sensitivity (the other plausible choice)",
    ]
    .iter()
    .map(|s| s.to_string())
    .collect();
    for (k, kind) in ClaimKind::ALL.iter().enumerate() {
        let rows: Vec<Vec<String>> = claims
            .iter()
            .filter(|c| c.kind == *kind)
            .map(|c| {
                vec![
                    format!("`{}`", c.id),
                    c.claim.clone(),
                    c.paper.clone().unwrap_or_else(|| "—".into()),
                    c.threshold_source.clone(),
                    c.measured.clone(),
                    if c.held { "✔ held" } else { "✘ NOT held" }.into(),
                    c.sensitivity.clone().unwrap_or_else(|| "—".into()),
                ]
            })
            .collect();
        if rows.is_empty() {
            continue;
        }
        let title = match kind {
            ClaimKind::Paper => "Claims of the paper",
            ClaimKind::BeyondThePaper => "Beyond the paper",
        };
        let _ = writeln!(md, "\n### {title} ({} of {} held)\n", t[k].0, t[k].1);
        write_table(&mut md, &headers, &rows);
    }
    Ok(md)
}

/// A Markdown table with compact rules (`|---|`) whose header and cells are Markdown as given
/// (the caller escapes `|`), one line per row, ending with a newline; for
/// [`ReportBuilder::paragraph`] where a report's tables keep that layout.
pub fn compact_table<S: AsRef<str>>(headers: &[S], rows: &[Vec<String>]) -> String {
    let mut md = String::new();
    let h: Vec<&str> = headers.iter().map(|h| h.as_ref()).collect();
    let _ = writeln!(md, "| {} |", h.join(" | "));
    let _ = writeln!(md, "|{}", "---|".repeat(h.len()));
    for r in rows {
        let _ = writeln!(md, "| {} |", r.join(" | "));
    }
    md
}

fn write_table(md: &mut String, headers: &[String], rows: &[Vec<String>]) {
    let line = |cells: &mut dyn Iterator<Item = String>| {
        let v: Vec<String> = cells.collect();
        format!("| {} |\n", v.join(" | "))
    };
    md.push_str(&line(&mut headers.iter().map(|h| cell(h))));
    md.push_str(&line(&mut headers.iter().map(|_| "---".to_owned())));
    for r in rows {
        md.push_str(&line(&mut r.iter().map(|c| cell(c))));
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::report::plot::Plot;
    use crate::report::{read_claims_json, scratch};

    fn report() -> ReportBuilder {
        let claims = vec![
            Claim::new(
                "t-cap",
                ClaimKind::Paper,
                "Capture within 100 s.",
                Some("86 s"),
                "paper: Fig. 4",
                "91.3 s",
                true,
            ),
            Claim::new(
                "d-min",
                ClaimKind::BeyondThePaper,
                "Distance stays above 0.5 m.",
                None,
                "ours: half a panel",
                "0.41 m",
                false,
            )
            .with_sensitivity("0.4 m: held"),
        ];
        let fig = Figure::new("x(t)").plot(
            Plot::new("")
                .x_label("t [s]")
                .y_label("x [m]")
                .line("x", (0..50).map(|i| (f64::from(i), f64::from(i).sin()))),
        );
        let mut r = ReportBuilder::new("guo2016 — reproduction");
        r.paragraph("Scene `guo2016_capture.ron`, dt = 0.01 s.")
            .heading("Results")
            .table(
                &["case", "t_capture [s]"],
                &[
                    vec!["nominal".into(), "91.3".into()],
                    vec!["a|b".into(), "7".into()],
                ],
            )
            .claims(&claims)
            .figure("x_t", "x over time", fig);
        r
    }

    /// Reference: CommonMark/GFM table syntax, written out by hand.
    #[test]
    fn invariant_report_md_contains_tables_claims_and_relative_links() {
        let d = scratch("md");
        let path = report().write(&d).unwrap();
        let md = std::fs::read_to_string(&path).unwrap();
        assert!(md.starts_with("# guo2016 — reproduction\n"));
        assert!(md.contains("| case | t_capture [s] |\n| --- | --- |\n| nominal | 91.3 |\n"));
        assert!(md.contains("| a\\|b | 7 |\n"), "pipe escaped");
        assert!(
            md.contains("1 of 2 claims held: 1 of 1 claims of the paper, 0 of 1 beyond the paper.")
        );
        let (pa, be) = (
            md.find("### Claims of the paper (1 of 1 held)").unwrap(),
            md.find("### Beyond the paper (0 of 1 held)").unwrap(),
        );
        let (ti, di) = (md.find("`t-cap`").unwrap(), md.find("`d-min`").unwrap());
        assert!(pa < ti && ti < be && be < di, "kinds in separate tables");
        assert!(md.contains(
            "| `t-cap` | Capture within 100 s. | 86 s | paper: Fig. 4 | 91.3 s | ✔ held | — |\n"
        ));
        assert!(md.contains(
            "| `d-min` | Distance stays above 0.5 m. | — | ours: half a panel | 0.41 m | ✘ NOT held | 0.4 m: held |\n"
        ));
        assert!(md.contains("![x over time](x_t.png)\n"));
        assert!(d.join("x_t.png").is_file());
        assert!(!d.join("x_t.svg").exists());
        assert_eq!(read_claims_json(&d.join(CLAIMS_FILE)).unwrap().len(), 2);
    }

    #[test]
    fn invariant_report_write_is_byte_identical_for_identical_input() {
        let (a, b) = (scratch("md-a"), scratch("md-b"));
        report().with_svg(true).write(&a).unwrap();
        report().with_svg(true).write(&b).unwrap();
        for f in ["REPORT.md", "claims.json", "x_t.png", "x_t.svg"] {
            assert_eq!(
                std::fs::read(a.join(f)).unwrap(),
                std::fs::read(b.join(f)).unwrap(),
                "{f}"
            );
        }
    }

    #[test]
    fn regress_ragged_table_and_escaping_image_path_are_errors_not_panics() {
        let d = scratch("md-bad");
        let mut r = ReportBuilder::new("t");
        r.table(&["a", "b"], &[vec!["1".into()]]);
        let e = r.write(&d).unwrap_err();
        assert!(e.to_string().contains("row 0 has 1 cells"), "{e}");
        assert!(!d.join(REPORT_FILE).exists());
        let mut r = ReportBuilder::new("t");
        r.image("up", "../x.png");
        assert!(r.to_markdown().is_err());
        let mut r = ReportBuilder::new("t");
        r.image("abs", "/tmp/x.png");
        assert!(r.to_markdown().is_err());
    }

    /// Reference: the Markdown written out by hand. Claims and findings placed early and
    /// filled by later sections appear where they were placed, in the order added.
    #[test]
    fn invariant_claims_and_findings_filled_later_render_where_placed() {
        let mut r = ReportBuilder::new("t");
        r.heading("Claims")
            .claims(&[])
            .heading("Findings")
            .findings();
        r.subheading("S").paragraph(compact_table(
            &["a", "b\\|c"],
            &[vec!["1".into(), "2".into()]],
        ));
        r.finding("first").claim(Claim::new(
            "x",
            ClaimKind::Paper,
            "c",
            None,
            "ours: s",
            "m",
            true,
        ));
        r.finding("second").raw("");
        if let Some(c) = r.claim_mut("x") {
            c.measured = "m2".into();
        }
        let md = r.to_markdown().unwrap();
        let claims = claims_markdown(r.claims_list().unwrap()).unwrap();
        assert!(
            claims.contains("| `x` | c | — | ours: s | m2 | ✔ held | — |\n"),
            "{claims}"
        );
        assert_eq!(
            md,
            format!(
                "# t\n\n## Claims\n\n{claims}\n## Findings\n\n- first\n- second\n\n### S\n\n\
                 | a | b\\|c |\n|---|---|\n| 1 | 2 |\n\n"
            )
        );
    }
}
