//! `claims.json`: one JSON object per claim a reproduction checks.
//!
//! Contract (design notes, "Outputs"): a JSON array; each object has exactly the keys
//! `id` (short slug), `claim` (one sentence), `paper` (the paper's value or statement, or
//! `null`), `measured` (what this run measured, with units) and `held` (`true`/`false`).
//! A claim the testbed refutes stays in the file with `held: false` and the numbers.

use std::io;
use std::path::Path;

use serde::{Deserialize, Serialize};

use super::fsio::{with_path, write_atomic};

/// One claim of a paper and what this run measured for it.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Claim {
    /// Short slug, unique within a file: lowercase ASCII letters, digits, `-`, `_`, `.`
    /// (e.g. `guo2016-capture-time`).
    pub id: String,
    /// The claim in one sentence.
    pub claim: String,
    /// The paper's value or statement (with units), or `None` (JSON `null`) when the paper
    /// gives none.
    pub paper: Option<String>,
    /// What this run measured, with units.
    pub measured: String,
    /// Whether the claim held in this run.
    pub held: bool,
}

impl Claim {
    /// Builds a claim; `paper` is `None` when the paper states no value.
    pub fn new(
        id: impl Into<String>,
        claim: impl Into<String>,
        paper: Option<&str>,
        measured: impl Into<String>,
        held: bool,
    ) -> Self {
        Self {
            id: id.into(),
            claim: claim.into(),
            paper: paper.map(str::to_owned),
            measured: measured.into(),
            held,
        }
    }
}

/// Checks that every id is a non-empty slug (`[a-z0-9._-]+`) and that ids are unique.
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
    }
    Ok(())
}

/// Serialises `claims` as the `claims.json` text: a pretty-printed JSON array in the given
/// order, keys in the order `id, claim, paper, measured, held`, ending with a newline.
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
                "The chaser captures the target within 100 s.",
                Some("86 s"),
                "91.3 s",
                true,
            ),
            Claim::new(
                "no-collision",
                "The minimum distance stays above 0.5 m.",
                None,
                "min distance 0.41 m at t = 52.0 s",
                false,
            ),
        ]
    }

    /// Reference: the contract in the design notes — exactly five keys, `paper` may be null,
    /// `held` a JSON boolean; and serde round trip gives back the same values.
    #[test]
    fn invariant_claims_json_has_exactly_the_five_keys_and_round_trips() {
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
            assert_eq!(keys, ["claim", "held", "id", "measured", "paper"]);
            assert!(obj["held"].is_boolean());
        }
        assert!(arr[1]["paper"].is_null());
        assert_eq!(arr[0]["paper"], "86 s");
        assert_eq!(read_claims_json(&p).unwrap(), claims);
        // Key order in the file follows the contract.
        let i: Vec<usize> = [
            "\"id\"",
            "\"claim\"",
            "\"paper\"",
            "\"measured\"",
            "\"held\"",
        ]
        .iter()
        .map(|k| text.find(k).unwrap())
        .collect();
        assert!(i.windows(2).all(|w| w[0] < w[1]), "{i:?}");
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
            r#"[{"id":"a","claim":"c","paper":null,"measured":"m","held":true,"x":1}]"#,
        )
        .unwrap();
        assert!(read_claims_json(&p).is_err());
    }
}
