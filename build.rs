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
        // Rebuild when HEAD moves: the HEAD file, the branch it names, packed refs. Only paths
        // that exist are declared: cargo treats a declared path that is missing as changed, so
        // a checkout without `packed-refs` (or with its branch packed) would rebuild rpod on
        // every `cargo build`. A branch ref that is packed is watched through its folder, where
        // the next commit writes it loose again.
        let branch = git(&["rev-parse", "--symbolic-full-name", "HEAD"])
            .and_then(|r| git(&["rev-parse", "--git-path", &r]))
            .map(std::path::PathBuf::from)
            .and_then(|p| {
                if p.exists() {
                    Some(p)
                } else {
                    p.parent().filter(|d| d.exists()).map(|d| d.to_path_buf())
                }
            });
        let watched = [
            git(&["rev-parse", "--git-path", "HEAD"]).map(std::path::PathBuf::from),
            branch,
            git(&["rev-parse", "--git-path", "packed-refs"]).map(std::path::PathBuf::from),
        ];
        for p in watched.into_iter().flatten().filter(|p| p.exists()) {
            println!("cargo:rerun-if-changed={}", p.display());
        }
    }
}
