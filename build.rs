//! Records the git commit rpod is built from, when it is built from a git checkout, as the
//! compile-time variable `RPOD_GIT_COMMIT` (provenance in `summary.json`). Built from a tarball
//! without `.git`, or without git installed, the variable is simply not set.

use std::process::Command;

fn git(args: &[&str]) -> Option<String> {
    let out = Command::new("git").args(args).output().ok()?;
    out.status
        .success()
        .then(|| String::from_utf8_lossy(&out.stdout).trim().to_string())
        .filter(|s| !s.is_empty())
}

fn main() {
    println!("cargo:rerun-if-changed=build.rs");
    if std::path::Path::new(".git").exists()
        && let Some(commit) = git(&["rev-parse", "HEAD"])
    {
        println!("cargo:rustc-env=RPOD_GIT_COMMIT={commit}");
        // Rebuild when HEAD moves: the HEAD file, the branch it names, packed refs.
        for p in [
            git(&["rev-parse", "--git-path", "HEAD"]),
            git(&["rev-parse", "--symbolic-full-name", "HEAD"])
                .and_then(|r| git(&["rev-parse", "--git-path", &r])),
            git(&["rev-parse", "--git-path", "packed-refs"]),
        ]
        .into_iter()
        .flatten()
        {
            println!("cargo:rerun-if-changed={p}");
        }
    }
}
