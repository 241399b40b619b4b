//! `claims.json`: one JSON object per claim a reproduction checks.
//!
//! Contract (the `claims.json` of every `rpod reproduce` report, `docs/papers.md`): a JSON
//! array; each object has exactly the keys, in this order,
//! - `id` (short slug),
//! - `claim` (one sentence),
//! - `kind`: `"paper"` (a claim the paper makes) or `"beyond the paper"` (a question the
//!   testbed asks that the paper does not: full geometry, an added term, a campaign),
//! - `paper` (the paper's value or statement, or `null`),
//! - `threshold_source`: where the number the verdict is judged against comes from —
//!   `"paper: <where>"` or `"ours: <why this value>"`,
//! - `measured` (what this run measured, with units),
//! - `held` (`true`/`false`),
//! - `sensitivity`: the verdict under the other plausible choice where the paper leaves one
//!   open (a reading, a tolerance, a frame), or `null` where no such choice matters.
//!
//! A claim the testbed refutes stays in the file with `held: false` and the numbers.

use std::io;
use std::path::Path;

use serde::{Deserialize, Serialize};

use super::fsio::{with_path, write_atomic};

/// Whether a claim is the paper's or a question beyond it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
pub enum ClaimKind {
    /// A claim the paper makes (its figures, tables or text), checked as stated.
    #[serde(rename = "paper")]
    Paper,
    /// A question the paper does not ask (full geometry, an added term, a campaign, a
    /// feasibility bound).
    #[serde(rename = "beyond the paper")]
    BeyondThePaper,
}

impl ClaimKind {
    /// Both kinds, in report order.
    pub const ALL: [ClaimKind; 2] = [ClaimKind::Paper, ClaimKind::BeyondThePaper];

    /// The JSON spelling (`"paper"`, `"beyond the paper"`).
    pub fn as_str(self) -> &'static str {
        match self {
            ClaimKind::Paper => "paper",
            ClaimKind::BeyondThePaper => "beyond the paper",
        }
    }
}

/// One claim of a paper and what this run measured for it.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Claim {
    /// Short slug, unique within a file: lowercase ASCII letters, digits, `-`, `_`, `.`
    /// (e.g. `guo2016-capture-time`).
    pub id: String,
    /// The claim in one sentence.
    pub claim: String,
    /// The paper's claim or a question beyond it.
    pub kind: ClaimKind,
    /// The paper's value or statement (with units), or `None` (JSON `null`) when the paper
    /// gives none.
    pub paper: Option<String>,
    /// Where the threshold of the verdict comes from: `"paper: <where>"` or
    /// `"ours: <why this value>"` (checked by [`validate_claims`]).
    pub threshold_source: String,
    /// What this run measured, with units.
    pub measured: String,
    /// Whether the claim held in this run.
    pub held: bool,
    /// The verdict under the other plausible choice the paper leaves open, with its numbers,
    /// or `None` where the verdict depends on no such choice.
    pub sensitivity: Option<String>,
}

impl Claim {
    /// Builds a claim; `paper` is `None` when the paper states no value;
    /// `threshold_source` starts with `paper: ` or `ours: `.
    pub fn new(
        id: impl Into<String>,
        kind: ClaimKind,
        claim: impl Into<String>,
        paper: Option<&str>,
        threshold_source: impl Into<String>,
        measured: impl Into<String>,
        held: bool,
    ) -> Self {
        Self {
            id: id.into(),
            claim: claim.into(),
            kind,
            paper: paper.map(str::to_owned),
            threshold_source: threshold_source.into(),
            measured: measured.into(),
            held,
            sensitivity: None,
        }
    }

    /// The same claim with the verdict under the other plausible choice (see
    /// [`Claim::sensitivity`]).
    pub fn with_sensitivity(mut self, text: impl Into<String>) -> Self {
        self.sensitivity = Some(text.into());
        self
    }
}

/// "held" or "NOT held": a verdict inside a claim's measured or sensitivity text.
pub fn held_word(held: bool) -> &'static str {
    if held { "held" } else { "NOT held" }
}

/// Claims held and in all, per kind, in [`ClaimKind::ALL`] order: `[(held, total); 2]`.
pub fn tally(claims: &[Claim]) -> [(usize, usize); 2] {
    let mut t = [(0, 0); 2];
    for c in claims {
        let i = usize::from(c.kind == ClaimKind::BeyondThePaper);
        t[i].1 += 1;
        t[i].0 += usize::from(c.held);
    }
    t
}

/// Checks that every id is a non-empty slug (`[a-z0-9._-]+`), that ids are unique and that
/// every `threshold_source` starts with `paper: ` or `ours: ` and says something after it.
/// Errors are `InvalidInput` and name the offending id.
pub fn validate_claims(claims: &[Claim]) -> io::Result<()> {
    let mut seen = std::collections::BTreeSet::new();
    for c in claims {
        let slug_ok = !c.id.is_empty()
            && c.id.bytes().all(|b| {
                b.is_ascii_lowercase() || b.is_ascii_digit() || matches!(b, b'-' | b'_' | b'.')
            });
        if !slug_ok {
            return Err(io::Error::new(
                io::ErrorKind::InvalidInput,
                format!("claim id {:?} is not a slug of [a-z0-9._-]", c.id),
            ));
        }
        if !seen.insert(c.id.as_str()) {
            return Err(io::Error::new(
                io::ErrorKind::InvalidInput,
                format!("claim id {:?} appears twice", c.id),
            ));
        }
        let src_ok = ["paper: ", "ours: "].iter().any(|p| {
            c.threshold_source
                .strip_prefix(p)
                .is_some_and(|rest| !rest.trim().is_empty())
        });
        if !src_ok {
            return Err(io::Error::new(
                io::ErrorKind::InvalidInput,
                format!(
                    "claim {:?}: threshold_source {:?} must start with \"paper: \" or \"ours: \" and say where or why",
                    c.id, c.threshold_source
                ),
            ));
        }
    }
    Ok(())
}

/// Serialises `claims` as the `claims.json` text: a pretty-printed JSON array in the given
/// order, keys in the order of the module docs, ending with a newline.
pub fn claims_to_json(claims: &[Claim]) -> String {
    // Serialising plain strings and bools cannot fail.
    let mut s = serde_json::to_string_pretty(claims).unwrap_or_else(|_| "[]".to_owned());
    s.push('\n');
    s
}

/// Validates `claims` ([`validate_claims`]) and writes them to `path` atomically.
pub fn write_claims_json(path: &Path, claims: &[Claim]) -> io::Result<()> {
    validate_claims(claims).map_err(|e| with_path(path, "claims for", e))?;
    write_atomic(path, claims_to_json(claims).as_bytes())
}

/// Reads a `claims.json` written by [`write_claims_json`] (unknown or missing keys are errors).
pub fn read_claims_json(path: &Path) -> io::Result<Vec<Claim>> {
    let text = std::fs::read_to_string(path).map_err(|e| with_path(path, "read", e))?;
    serde_json::from_str(&text).map_err(|e| {
        io::Error::new(
            io::ErrorKind::InvalidData,
            format!("parse {}: {e}", path.display()),
        )
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::report::scratch;

    fn sample() -> Vec<Claim> {
        vec![
            Claim::new(
                "capture-time",
                ClaimKind::Paper,
                "The chaser captures the target within 100 s.",
                Some("86 s"),
                "paper: Fig. 4",
                "91.3 s",
                true,
            ),
            Claim::new(
                "no-collision",
                ClaimKind::BeyondThePaper,
                "The minimum distance stays above 0.5 m.",
                None,
                "ours: half the panel span",
                "min distance 0.41 m at t = 52.0 s",
                false,
            )
            .with_sensitivity("with 0.4 m: held"),
        ]
    }

    /// Reference: the contract in the module docs — exactly eight keys in their order,
    /// `paper` and `sensitivity` may be null, `kind` one of two strings, `held` a JSON boolean;
    /// and serde round trip gives back the same values.
    #[test]
    fn invariant_claims_json_has_exactly_the_eight_keys_and_round_trips() {
        let d = scratch("claims");
        let p = d.join("claims.json");
        let claims = sample();
        write_claims_json(&p, &claims).unwrap();
        let text = std::fs::read_to_string(&p).unwrap();
        let v: serde_json::Value = serde_json::from_str(&text).unwrap();
        let arr = v.as_array().expect("top level is an array");
        assert_eq!(arr.len(), 2);
        for obj in arr {
            let obj = obj.as_object().unwrap();
            let mut keys: Vec<&str> = obj.keys().map(String::as_str).collect();
            keys.sort_unstable();
            assert_eq!(
                keys,
                [
                    "claim",
                    "held",
                    "id",
                    "kind",
                    "measured",
                    "paper",
                    "sensitivity",
                    "threshold_source"
                ]
            );
            assert!(obj["held"].is_boolean());
        }
        assert!(arr[1]["paper"].is_null());
        assert!(arr[0]["sensitivity"].is_null());
        assert_eq!(arr[0]["paper"], "86 s");
        assert_eq!(arr[0]["kind"], "paper");
        assert_eq!(arr[1]["kind"], "beyond the paper");
        assert_eq!(arr[1]["sensitivity"], "with 0.4 m: held");
        assert_eq!(read_claims_json(&p).unwrap(), claims);
        // Key order in the file follows the contract.
        let i: Vec<usize> = [
            "\"id\"",
            "\"claim\"",
            "\"kind\"",
            "\"paper\"",
            "\"threshold_source\"",
            "\"measured\"",
            "\"held\"",
            "\"sensitivity\"",
        ]
        .iter()
        .map(|k| text.find(k).unwrap())
        .collect();
        assert!(i.windows(2).all(|w| w[0] < w[1]), "{i:?}");
        assert_eq!(tally(&claims), [(1, 1), (0, 1)]);
    }

    #[test]
    fn regress_threshold_source_must_say_paper_or_ours() {
        let d = scratch("claims-src");
        let p = d.join("claims.json");
        for bad in ["", "paper:", "ours:   ", "Paper: Fig. 2", "we chose 5"] {
            let mut c = sample();
            c[0].threshold_source = bad.into();
            let e = write_claims_json(&p, &c).unwrap_err();
            assert!(e.to_string().contains("threshold_source"), "{bad:?}: {e}");
            assert!(!p.exists());
        }
        // An unknown kind is rejected on reading.
        std::fs::write(
            &p,
            r#"[{"id":"a","claim":"c","kind":"ours","paper":null,"threshold_source":"ours: x","measured":"m","held":true,"sensitivity":null}]"#,
        )
        .unwrap();
        assert!(read_claims_json(&p).is_err());
    }

    #[test]
    fn regress_bad_or_duplicate_ids_are_rejected_and_nothing_is_written() {
        let d = scratch("claims-bad");
        let p = d.join("claims.json");
        let mut c = sample();
        c[1].id = "capture-time".into();
        let e = write_claims_json(&p, &c).unwrap_err();
        assert!(e.to_string().contains("twice"), "{e}");
        c[1].id = "Has Space".into();
        assert!(write_claims_json(&p, &c).is_err());
        assert!(!p.exists());
        // Unknown keys are rejected on reading.
        std::fs::write(
            &p,
            r#"[{"id":"a","claim":"c","kind":"paper","paper":null,"threshold_source":"ours: x","measured":"m","held":true,"sensitivity":null,"x":1}]"#,
        )
        .unwrap();
        assert!(read_claims_json(&p).is_err());
    }
}
