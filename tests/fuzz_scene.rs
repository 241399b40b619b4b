//! A fuzz harness for the scene loader, `--set` overrides and the simulation build, on stable
//! Rust (no cargo-fuzz, which needs nightly): seeded mutations of every bundled scene and of
//! the broken-scene corpus, and random `--set` assignments. Every input must give `Ok` or a
//! `SceneError` — never a panic, an abort or a hang — and an error with a line has a column.
//! Scenes that load are built into a simulation and stepped 20 steps (the finiteness guard
//! may stop them; nothing may panic).
//!
//! The CI run is short (`RPOD_FUZZ_ITERS`, default 2000 inputs per target: about a second); a
//! longer run, documented in the README:
//!
//! ```sh
//! RPOD_FUZZ_ITERS=200000 RPOD_FUZZ_SEED=$RANDOM cargo test --release --test fuzz_scene -- --nocapture
//! ```
//!
//! An input that panics is written to `target/fuzz-crash-SEED-N.ron` (with its `--set`
//! arguments in a comment) and the test fails naming that file.
//!
//! Reference: the loader's contract (a located error or a scene); the mutations are ours:
//! byte deletions, insertions of RON tokens and extreme numbers, duplications, truncations,
//! deep nesting, and numbers swapped for extremes.

use rpod::scene::load_scene_str;
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::PathBuf;

/// SplitMix64.
struct Rng(u64);
impl Rng {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }
    fn pick<'a, T>(&mut self, v: &'a [T]) -> &'a T {
        &v[self.below(v.len())]
    }
}

const TOKENS: &[&str] = &[
    "(",
    ")",
    "[",
    "]",
    "{",
    "}",
    ",",
    ":",
    "\"",
    "\\",
    "'",
    "#![",
    "#![enable(implicit_some)]",
    "/*",
    "*/",
    "//",
    "\n",
    " ",
    "Some(",
    "None",
    "true",
    "1e308",
    "-1e308",
    "1e-320",
    "-0.0",
    "NaN",
    "inf",
    "4294967295",
    "18446744073709551616",
    "0",
    "-1",
    "r#\"",
    "\"#",
    "é",
    "\u{0}",
    "name: \"x\",",
    "bodies: [],",
    "Box(size_m: (1.0, 1.0, 1.0))",
    "Target",
    "Chaser",
];

const EXTREMES: &[&str] = &[
    "1e308",
    "-1e308",
    "1e-308",
    "0.0",
    "-0.0",
    "1e12",
    "4294967295",
    "1e-200",
    "NaN",
    "inf",
];

fn mutate(rng: &mut Rng, text: &str) -> String {
    let mut s = text.to_string();
    for _ in 0..1 + rng.below(4) {
        let n = s.len();
        let mut at = rng.below(n + 1);
        while !s.is_char_boundary(at) {
            at -= 1;
        }
        match rng.below(7) {
            0 => {
                let mut end = (at + 1 + rng.below(64)).min(n);
                while !s.is_char_boundary(end) {
                    end -= 1;
                }
                s.replace_range(at..end, "");
            }
            1 | 2 => {
                let tok: &&str = rng.pick(TOKENS);
                s.insert_str(at, tok)
            }
            3 => s.truncate(at),
            4 => {
                let mut end = (at + rng.below(200)).min(n);
                while !s.is_char_boundary(end) {
                    end -= 1;
                }
                let dup = s[at..end].to_string();
                s.insert_str(end, &dup);
            }
            5 => {
                let depth = 1 + rng.below(200);
                let open = if rng.below(2) == 0 { "(" } else { "[" };
                s.insert_str(at, &open.repeat(depth));
            }
            _ => {
                // Replace the next number after `at` by an extreme.
                if let Some(k) = s[at..].find(|c: char| c.is_ascii_digit()) {
                    let a = at + k;
                    let e = s[a..]
                        .find(|c: char| !(c.is_ascii_digit() || c == '.' || c == 'e' || c == '-'))
                        .map_or(s.len(), |k| a + k);
                    let x: &&str = rng.pick(EXTREMES);
                    s.replace_range(a..e, x);
                }
            }
        }
    }
    s
}

const PATHS: &[&str] = &[
    "name",
    "dt_s",
    "duration_s",
    "physics_substeps",
    "bodies.chaser.mass_kg",
    "bodies.0.initial.pos_m",
    "bodies.chaser.initial.pos_m.1",
    "bodies[1].parts.0.shape",
    "bodies.target.parts.wing_py.panel_count",
    "bodies.chaser.inertia_kg_m2.xx",
    "environment.reference.e",
    "guarantees.0.name",
    "docking.magnet.f0_n",
    "bodies.chaser.nonexistent",
    "a.b[3].c]",
    "",
];

const VALUES: &[&str] = &[
    "1.0",
    "-1",
    "1e308",
    "(1.0, 2.0, 3.0)",
    "(1.0,\n 2.0,\n 3.0)",
    "\"a,b\\n\"",
    "\"",
    "((((",
    "1.0 // c",
    "1.0, x: 2",
    "Sphere(radius_m: 1e-300)",
    "[]",
    "\n",
    "4294967295",
    "NaN",
    "Some(1.0)",
];

fn scenes() -> Vec<(String, String)> {
    let mut v = Vec::new();
    for dir in [
        "scenes/examples",
        "scenes/papers/geng2015",
        "scenes/papers/guo2016",
        "scenes/papers/xu2015",
        "scenes/papers/xu2019",
        "scenes/papers/zhang2018",
        "tests/broken_scenes",
    ] {
        let mut paths: Vec<PathBuf> = std::fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().path())
            .filter(|p| p.extension().is_some_and(|e| e == "ron"))
            .collect();
        paths.sort();
        for p in paths {
            if let Ok(t) = std::fs::read_to_string(&p)
                && t.len() < 200_000
            {
                v.push((p.display().to_string(), t));
            }
        }
    }
    v
}

fn iters() -> usize {
    std::env::var("RPOD_FUZZ_ITERS")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(2000)
}

fn seed() -> u64 {
    std::env::var("RPOD_FUZZ_SEED")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(17)
}

/// Loads, builds and steps one input; `Err` with a description on a broken contract.
fn exercise(text: &str, sets: &[String]) -> Result<(), String> {
    let r = catch_unwind(AssertUnwindSafe(|| {
        match load_scene_str(text, "fuzz.ron", sets) {
            Ok(loaded) => {
                if let Ok(mut sim) = rpod::sim::Simulation::new(&loaded) {
                    sim.step(20);
                }
                Ok(())
            }
            Err(e) if e.line > 0 && e.col == 0 => {
                Err(format!("error with a line but no column: {e}"))
            }
            Err(_) => Ok(()),
        }
    }));
    match r {
        Ok(r) => r,
        Err(p) => Err(format!(
            "panic: {}",
            p.downcast_ref::<String>()
                .cloned()
                .or_else(|| p.downcast_ref::<&str>().map(|s| s.to_string()))
                .unwrap_or_default()
        )),
    }
}

/// An input slower than this (load, build and 20 steps) counts as a hang, s.
const SLOW_S: f64 = 10.0;

fn timed(text: &str, sets: &[String]) -> Result<(), String> {
    // With RPOD_FUZZ_TRACE set, the input under test is written first, so an input that never
    // returns (a hang) is left in target/fuzz-current.ron when the run is stopped.
    if std::env::var_os("RPOD_FUZZ_TRACE").is_some() {
        let f = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("target/fuzz-current.ron");
        let _ = std::fs::create_dir_all(f.parent().unwrap());
        let _ = std::fs::write(&f, format!("// --set {sets:?}\n{text}"));
    }
    let t0 = std::time::Instant::now();
    let r = exercise(text, sets);
    let dt = t0.elapsed().as_secs_f64();
    if r.is_ok() && dt > SLOW_S {
        return Err(format!("took {dt:.1} s (more than {SLOW_S} s: a hang)"));
    }
    r
}

fn report(seed: u64, i: usize, text: &str, sets: &[String], why: &str) -> String {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("target");
    let _ = std::fs::create_dir_all(&dir);
    let f = dir.join(format!("fuzz-crash-{seed}-{i}.ron"));
    let _ = std::fs::write(&f, format!("// --set {sets:?}\n{text}"));
    format!("{why}\ninput saved to {}", f.display())
}

#[test]
fn invariant_fuzzed_scenes_never_panic() {
    let corpus = scenes();
    let seed = seed();
    let mut rng = Rng(seed);
    for i in 0..iters() {
        let (_, base) = rng.pick(&corpus);
        let text = mutate(&mut rng, base);
        if let Err(why) = timed(&text, &[]) {
            panic!("{}", report(seed, i, &text, &[], &why));
        }
    }
}

#[test]
fn invariant_fuzzed_set_overrides_never_panic() {
    let corpus = scenes();
    let seed = seed() ^ 0x5e7;
    let mut rng = Rng(seed);
    for i in 0..iters() {
        let (_, base) = rng.pick(&corpus[..corpus.len().min(60)]);
        let sets: Vec<String> = (0..1 + rng.below(3))
            .map(|_| {
                let p = (*rng.pick(PATHS)).to_string();
                let v = if rng.below(3) == 0 {
                    let v0 = rng_value(&mut rng);
                    mutate(&mut rng, v0)
                } else {
                    rng_value(&mut rng).to_string()
                };
                format!("{p}={v}")
            })
            .collect();
        if let Err(why) = timed(base, &sets) {
            panic!("{}", report(seed, i, base, &sets, &why));
        }
    }
}

fn rng_value(rng: &mut Rng) -> &'static str {
    VALUES[rng.below(VALUES.len())]
}
