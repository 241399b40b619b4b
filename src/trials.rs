//! Scripted trials: `rpod trials FILE [--jobs N] [--shard i/N] [--out DIR]` and
//! `rpod trials merge --out DIR SHARD_DIR...`.
//!
//! A trials file (RON) names a base scene, the parameters to vary (grid sweeps and seeded random
//! distributions over any scene field, by `--set` path), the count and the success criterion.
//! Trial `k`'s parameters depend only on `k` and the seed: grid parameters enumerate their
//! cells in order (the first parameter varies slowest) and cycle when `count` exceeds the grid;
//! random parameters are drawn from a SplitMix64 stream seeded with (seed, k, parameter index).
//! Each trial is an independent headless simulation; trials run on `--jobs` threads, and rows
//! are appended to `trials.csv` in index order as soon as all lower indices are done, so an
//! interrupted campaign resumes where it stopped, and the file is the same for any `--jobs` and
//! for merged shards.

use crate::scene::{SceneError, load_scene_file};
use crate::sim::Simulation;
use crate::sim::docking::Docking;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::mpsc;

/// A trials file: `Trials(name: …, scene: …, …)`.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields, rename = "Trials")]
pub struct TrialsSpec {
    /// Campaign name.
    pub name: String,
    /// Base scene, relative to the trials file's directory.
    pub scene: String,
    /// Simulated duration of each trial, s (default: the scene's).
    #[serde(default)]
    pub duration_s: Option<f64>,
    /// Seed of the random parameters.
    #[serde(default)]
    pub seed: u64,
    /// Number of trials.
    pub count: usize,
    /// Parameters to vary.
    pub parameters: Vec<Parameter>,
    /// What counts as a success.
    pub success: Success,
}

/// One varied scene field.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub enum Parameter {
    /// A grid sweep over listed values.
    Grid {
        /// Scene field path (as for `--set`).
        path: String,
        /// Axis label with unit for plots (default: the path).
        #[serde(default)]
        label: Option<String>,
        /// Values, in the field's unit.
        values: Vec<f64>,
    },
    /// Uniform on [min, max).
    Uniform {
        /// Scene field path.
        path: String,
        /// Axis label with unit for plots (default: the path).
        #[serde(default)]
        label: Option<String>,
        /// Lower bound.
        min: f64,
        /// Upper bound.
        max: f64,
    },
    /// Normal (Box–Muller).
    Normal {
        /// Scene field path.
        path: String,
        /// Axis label with unit for plots (default: the path).
        #[serde(default)]
        label: Option<String>,
        /// Mean.
        mean: f64,
        /// Standard deviation.
        sd: f64,
    },
}

impl Parameter {
    /// The plot label.
    pub fn label(&self) -> &str {
        match self {
            Parameter::Grid { label, path, .. }
            | Parameter::Uniform { label, path, .. }
            | Parameter::Normal { label, path, .. } => label.as_deref().unwrap_or(path),
        }
    }
    /// The field path.
    pub fn path(&self) -> &str {
        match self {
            Parameter::Grid { path, .. }
            | Parameter::Uniform { path, .. }
            | Parameter::Normal { path, .. } => path,
        }
    }
}

/// Success criterion.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub enum Success {
    /// The docking mechanism latched (and is still latched at the end).
    Latched,
    /// The final docking state is one of these (`"LATCHED"`, `"SOFT_CAPTURE"`, …).
    StateIn(Vec<String>),
    /// No collision (a contact between non-docking parts).
    NoCollision,
}

/// SplitMix64: a small, well-mixed generator; one stream per (seed, trial, parameter).
fn splitmix(mut x: u64) -> u64 {
    x = x.wrapping_add(0x9E37_79B9_7F4A_7C15);
    let mut z = x;
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

fn uniform01(seed: u64, trial: usize, param: usize, draw: u64) -> f64 {
    let h = splitmix(splitmix(splitmix(seed) ^ trial as u64) ^ ((param as u64) << 32 | draw));
    (h >> 11) as f64 / (1u64 << 53) as f64
}

impl TrialsSpec {
    /// The parameter values of trial `k`, in parameter order.
    pub fn values(&self, k: usize) -> Vec<f64> {
        let grids: Vec<usize> = self
            .parameters
            .iter()
            .filter_map(|p| match p {
                Parameter::Grid { values, .. } => Some(values.len()),
                _ => None,
            })
            .collect();
        let cells: usize = grids.iter().product::<usize>().max(1);
        let mut cell = k % cells;
        // Mixed radix, first grid parameter slowest.
        let mut digits = vec![0; grids.len()];
        for (d, n) in digits.iter_mut().zip(&grids).rev() {
            *d = cell % n;
            cell /= n;
        }
        let mut g = 0;
        self.parameters
            .iter()
            .enumerate()
            .map(|(i, p)| match p {
                Parameter::Grid { values, .. } => {
                    let v = values[digits[g]];
                    g += 1;
                    v
                }
                Parameter::Uniform { min, max, .. } => {
                    min + (max - min) * uniform01(self.seed, k, i, 0)
                }
                Parameter::Normal { mean, sd, .. } => {
                    let u1 = uniform01(self.seed, k, i, 0).max(f64::MIN_POSITIVE);
                    let u2 = uniform01(self.seed, k, i, 1);
                    mean + sd * (-2.0 * u1.ln()).sqrt() * (2.0 * std::f64::consts::PI * u2).cos()
                }
            })
            .collect()
    }

    fn validate(&self, file: &str, text: &str) -> Result<(), SceneError> {
        let err = |path: &str, msg: String| {
            let (line, col) = crate::scene::load::locate(text, path)
                .map(|(s, _)| crate::scene::load::line_col(text, s))
                .unwrap_or((0, 0));
            SceneError {
                file: file.to_string(),
                line,
                col,
                field: path.to_string(),
                message: msg,
            }
        };
        if self.count == 0 {
            return Err(err("count", "must be at least 1".into()));
        }
        if self.parameters.is_empty() {
            return Err(err("parameters", "name at least one parameter".into()));
        }
        if let Some(d) = self.duration_s
            && !(d.is_finite() && d > 0.0)
        {
            return Err(err(
                "duration_s",
                format!("must be a positive number of seconds, got {d}"),
            ));
        }
        for (i, p) in self.parameters.iter().enumerate() {
            let at = format!("parameters.{i}");
            match p {
                Parameter::Grid { values, .. } if values.is_empty() => {
                    return Err(err(&format!("{at}.values"), "a grid needs values".into()));
                }
                Parameter::Uniform { min, max, .. }
                    if !(min.is_finite() && max.is_finite() && min <= max) =>
                {
                    return Err(err(
                        &format!("{at}.max"),
                        format!("need min ≤ max, got [{min}, {max}]"),
                    ));
                }
                Parameter::Normal { sd, .. } if !(sd.is_finite() && *sd >= 0.0) => {
                    return Err(err(&format!("{at}.sd"), format!("must be ≥ 0, got {sd}")));
                }
                _ => {}
            }
        }
        Ok(())
    }
}

/// A loaded campaign: the spec and the base scene's path.
pub struct Campaign {
    /// The trials file.
    pub spec: TrialsSpec,
    /// The base scene file.
    pub scene_path: PathBuf,
}

/// Reads and checks a trials file; the base scene and every parameter path are checked by
/// building trial 0.
pub fn load(path: &Path) -> Result<Campaign, SceneError> {
    let file = path.display().to_string();
    let text = std::fs::read_to_string(path).map_err(|e| SceneError {
        file: file.clone(),
        line: 0,
        col: 0,
        field: String::new(),
        message: format!("cannot read the trials file: {e}"),
    })?;
    let spec: TrialsSpec = crate::scene::load::parse_ron(&text, &file)?;
    spec.validate(&file, &text)?;
    let scene_path = path.parent().unwrap_or(Path::new(".")).join(&spec.scene);
    if !scene_path.exists() {
        let (line, col) = crate::scene::load::locate(&text, "scene")
            .map(|(s, _)| crate::scene::load::line_col(&text, s))
            .unwrap_or((0, 0));
        return Err(SceneError {
            file,
            line,
            col,
            field: "scene".into(),
            message: format!("no scene file at {}", scene_path.display()),
        });
    }
    let c = Campaign { spec, scene_path };
    // Trial 0 must build: catches bad paths and values now rather than in every worker.
    build(&c, 0)?;
    Ok(c)
}

fn overrides(c: &Campaign, k: usize) -> Vec<String> {
    c.spec
        .parameters
        .iter()
        .zip(c.spec.values(k))
        .map(|(p, v)| format!("{}={v:?}", p.path()))
        .collect()
}

fn build(c: &Campaign, k: usize) -> Result<Simulation, SceneError> {
    let loaded = load_scene_file(&c.scene_path, &overrides(c, k))?;
    Simulation::new(&loaded)
}

/// One trial's result.
#[derive(Debug, Clone)]
pub struct TrialResult {
    /// Trial index.
    pub index: usize,
    /// Parameter values.
    pub values: Vec<f64>,
    /// Final docking state (or `NO_DOCKING`, or `ERROR`).
    pub outcome: String,
    /// Success per the criterion.
    pub success: bool,
    /// Time to latch, s.
    pub t_latch_s: Option<f64>,
    /// Peak contact force on any part, N.
    pub peak_contact_force_n: f64,
    /// Peak axial and lateral loads on the docking mechanism up to the latch, N (the summary's
    /// `docking.contact`).
    pub peak_loads_n: (f64, f64),
    /// Largest misalignment in contact, deg.
    pub max_misalignment_deg: f64,
    /// Smallest clearance between parts that are not both docking parts, m.
    pub min_clearance_m: f64,
    /// First collision, s.
    pub first_collision_s: Option<f64>,
    /// Steps simulated.
    pub steps: u64,
    /// Why (the docking state's reason).
    pub reason: String,
}

/// Runs trial `k`.
pub fn run_trial(c: &Campaign, k: usize) -> TrialResult {
    let values = c.spec.values(k);
    let mut sim = match build(c, k) {
        Ok(s) => s,
        Err(e) => {
            return TrialResult {
                index: k,
                values,
                outcome: "ERROR".into(),
                success: false,
                t_latch_s: None,
                peak_contact_force_n: 0.0,
                peak_loads_n: (0.0, 0.0),
                max_misalignment_deg: 0.0,
                min_clearance_m: f64::NAN,
                first_collision_s: None,
                steps: 0,
                reason: e.to_string(),
            };
        }
    };
    let duration = c.spec.duration_s.unwrap_or(sim.scene.duration_s);
    sim.step(sim.steps_for(duration));
    let dock = sim.app.world().get_resource::<Docking>().cloned();
    let cs = sim.contacts();
    let outcome = dock
        .as_ref()
        .map_or("NO_DOCKING".to_string(), |d| d.state.name().to_string());
    let success = match &c.spec.success {
        Success::Latched => outcome == "LATCHED",
        Success::StateIn(v) => v.contains(&outcome),
        Success::NoCollision => cs.first_collision_s.is_none(),
    };
    TrialResult {
        index: k,
        values,
        outcome,
        success,
        t_latch_s: dock.as_ref().and_then(|d| d.t_latch_s),
        peak_contact_force_n: cs
            .per_part
            .values()
            .map(|p| p.peak_force_n)
            .fold(0.0, f64::max),
        peak_loads_n: dock.as_ref().map_or((0.0, 0.0), |d| {
            (d.loads.peak_axial_load_n, d.loads.peak_lateral_load_n)
        }),
        max_misalignment_deg: dock.as_ref().map_or(0.0, |d| d.max_misalignment_deg),
        min_clearance_m: sim
            .monitor()
            .min_clearance_per_pair
            .iter()
            .copied()
            .fold(f64::INFINITY, f64::min),
        first_collision_s: cs.first_collision_s,
        steps: sim.steps(),
        reason: dock.map_or(String::new(), |d| d.reason),
    }
}

fn opt(v: Option<f64>) -> String {
    v.map_or(String::new(), |x| format!("{x}"))
}

/// The CSV header for a campaign.
pub fn header(spec: &TrialsSpec) -> String {
    let mut cols = vec!["index".to_string()];
    cols.extend(spec.parameters.iter().map(|p| p.path().to_string()));
    cols.extend(
        [
            "outcome",
            "success",
            "t_latch_s",
            "peak_contact_force_n",
            "peak_axial_load_n",
            "peak_lateral_load_n",
            "max_misalignment_deg",
            "min_clearance_non_docking_m",
            "first_collision_s",
            "steps",
            "reason",
        ]
        .map(String::from),
    );
    cols.join(",")
}

/// One CSV row.
pub fn row(r: &TrialResult) -> String {
    let mut cells = vec![r.index.to_string()];
    cells.extend(r.values.iter().map(|v| format!("{v}")));
    cells.push(r.outcome.clone());
    cells.push(r.success.to_string());
    cells.push(opt(r.t_latch_s));
    cells.push(format!("{}", r.peak_contact_force_n));
    cells.push(format!("{}", r.peak_loads_n.0));
    cells.push(format!("{}", r.peak_loads_n.1));
    cells.push(format!("{}", r.max_misalignment_deg));
    cells.push(format!("{}", r.min_clearance_m));
    cells.push(opt(r.first_collision_s));
    cells.push(r.steps.to_string());
    cells.push(format!("\"{}\"", r.reason.replace('"', "'")));
    cells.join(",")
}

/// Options of a run.
#[derive(Debug, Clone)]
pub struct RunOptions {
    /// Worker threads.
    pub jobs: usize,
    /// This shard `(i, n)`: trials with index % n == i.
    pub shard: (usize, usize),
    /// Output directory.
    pub out: PathBuf,
    /// Show a progress bar.
    pub progress: bool,
}

/// What a run did.
#[derive(Debug, Clone)]
pub struct RunStats {
    /// Trials run now (not resumed).
    pub ran: usize,
    /// Trials found already done.
    pub resumed: usize,
    /// Wall time, s.
    pub wall_s: f64,
    /// Steps simulated now.
    pub steps: u64,
}

/// Indices already in an existing `trials.csv` (for resuming), checking the header.
fn done_indices(path: &Path, header: &str) -> Result<Vec<usize>, String> {
    let Ok(text) = std::fs::read_to_string(path) else {
        return Ok(Vec::new());
    };
    // Only complete (newline-terminated) rows count: a crash may leave half a row.
    let mut lines = text
        .split_inclusive('\n')
        .filter(|l| l.ends_with('\n'))
        .map(|l| l.trim_end_matches('\n'));
    match lines.next() {
        Some(h) if h == header => {}
        Some(_) => {
            return Err(format!(
                "{} belongs to a different campaign (its header differs); use another --out",
                path.display()
            ));
        }
        None => return Ok(Vec::new()),
    }
    Ok(lines
        .filter_map(|l| l.split(',').next()?.parse().ok())
        .collect())
}

/// Runs (or resumes) a campaign's shard into `opts.out`.
pub fn run(c: &Campaign, opts: &RunOptions) -> Result<RunStats, String> {
    std::fs::create_dir_all(&opts.out).map_err(|e| format!("{}: {e}", opts.out.display()))?;
    let csv = opts.out.join("trials.csv");
    let header = header(&c.spec);
    let done = done_indices(&csv, &header)?;
    let (si, sn) = opts.shard;
    let todo: Vec<usize> = (0..c.spec.count)
        .filter(|k| k % sn == si && !done.contains(k))
        .collect();
    // A partial last line from a crash is dropped by rewriting the file's complete lines.
    let mut file = if done.is_empty() {
        let mut f = std::fs::File::create(&csv).map_err(|e| format!("{}: {e}", csv.display()))?;
        writeln!(f, "{header}").map_err(|e| e.to_string())?;
        f
    } else {
        let text = std::fs::read_to_string(&csv).map_err(|e| e.to_string())?;
        let complete: String = text
            .split_inclusive('\n')
            .filter(|l| l.ends_with('\n'))
            .collect();
        std::fs::write(&csv, complete).map_err(|e| e.to_string())?;
        std::fs::OpenOptions::new()
            .append(true)
            .open(&csv)
            .map_err(|e| format!("{}: {e}", csv.display()))?
    };
    let bar = if opts.progress {
        indicatif::ProgressBar::new(todo.len() as u64)
    } else {
        indicatif::ProgressBar::hidden()
    };
    bar.set_style(
        indicatif::ProgressStyle::with_template(
            "{spinner} [{elapsed_precise}] {bar:40} {pos}/{len} trials  {per_sec}  ETA {eta}",
        )
        .expect("template"),
    );
    let t0 = std::time::Instant::now();
    let next = AtomicUsize::new(0);
    let (tx, rx) = mpsc::channel::<TrialResult>();
    let mut steps = 0u64;
    let jobs = opts.jobs.max(1).min(todo.len().max(1));
    std::thread::scope(|s| -> Result<(), String> {
        for _ in 0..jobs {
            let tx = tx.clone();
            let (todo, next) = (&todo, &next);
            s.spawn(move || {
                loop {
                    let i = next.fetch_add(1, Ordering::Relaxed);
                    let Some(&k) = todo.get(i) else { break };
                    if tx.send(run_trial(c, k)).is_err() {
                        break;
                    }
                }
            });
        }
        drop(tx);
        // Write in index order: hold results until every lower index of this shard is in.
        let mut pending: BTreeMap<usize, TrialResult> = BTreeMap::new();
        let mut cursor = 0;
        for r in rx {
            steps += r.steps;
            pending.insert(r.index, r);
            while cursor < todo.len() {
                let Some(r) = pending.remove(&todo[cursor]) else {
                    break;
                };
                writeln!(file, "{}", row(&r)).map_err(|e| e.to_string())?;
                file.flush().map_err(|e| e.to_string())?;
                cursor += 1;
                bar.inc(1);
            }
        }
        Ok(())
    })?;
    bar.finish_and_clear();
    let wall_s = t0.elapsed().as_secs_f64();
    write_summary(&opts.out, c)?;
    Ok(RunStats {
        ran: todo.len(),
        resumed: done.len(),
        wall_s,
        steps,
    })
}

/// Wilson score interval for `s` successes in `n` trials at z = 1.959964 (95 %).
pub fn wilson(s: usize, n: usize) -> (f64, f64, f64) {
    if n == 0 {
        return (f64::NAN, 0.0, 1.0);
    }
    let z = 1.959_963_984_540_054;
    let (s, n) = (s as f64, n as f64);
    let p = s / n;
    let denom = 1.0 + z * z / n;
    let centre = (p + z * z / (2.0 * n)) / denom;
    let half = z / denom * (p * (1.0 - p) / n + z * z / (4.0 * n * n)).sqrt();
    (p, (centre - half).max(0.0), (centre + half).min(1.0))
}

/// One row read back from `trials.csv`: (index, values, outcome, success, the line itself).
type Row = (usize, Vec<f64>, String, bool, String);

/// Reads `trials.csv`: its header and rows.
fn read_rows(path: &Path) -> Result<(String, Vec<Row>), String> {
    let text = std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))?;
    let mut lines = text.lines();
    let header = lines.next().unwrap_or("").to_string();
    let nparams = header.split(',').position(|h| h == "outcome").unwrap_or(1) - 1;
    let mut rows = Vec::new();
    for l in lines {
        let cells: Vec<&str> = l.splitn(nparams + 4, ',').collect();
        if cells.len() < nparams + 3 {
            continue;
        }
        let Ok(k) = cells[0].parse() else { continue };
        let values = cells[1..=nparams]
            .iter()
            .map(|c| c.parse().unwrap_or(f64::NAN))
            .collect();
        rows.push((
            k,
            values,
            cells[nparams + 1].to_string(),
            cells[nparams + 2] == "true",
            l.to_string(),
        ));
    }
    Ok((header, rows))
}

/// Writes `summary.json` and the capture-envelope plot from `dir/trials.csv`.
pub fn write_summary(dir: &Path, c: &Campaign) -> Result<(), String> {
    let (_, rows) = read_rows(&dir.join("trials.csv"))?;
    let mut counts: BTreeMap<String, usize> = BTreeMap::new();
    for r in &rows {
        *counts.entry(r.2.clone()).or_default() += 1;
    }
    let s = rows.iter().filter(|r| r.3).count();
    let (p, lo, hi) = wilson(s, rows.len());
    let summary = serde_json::json!({
        "campaign": c.spec.name,
        "scene": c.scene_path.display().to_string(),
        "trials": rows.len(),
        "planned": c.spec.count,
        "success_criterion": format!("{:?}", c.spec.success),
        "successes": s,
        "outcomes": counts,
        "capture_probability": p,
        "capture_probability_95ci_wilson": [lo, hi],
        "parameters": c.spec.parameters.iter().map(|p| p.path()).collect::<Vec<_>>(),
    });
    crate::report::write_atomic(
        &dir.join("summary.json"),
        (serde_json::to_string_pretty(&summary).map_err(|e| e.to_string())? + "\n").as_bytes(),
    )
    .map_err(|e| e.to_string())?;
    envelope_plot(dir, c, &rows)
}

/// Outcome over the two leading parameters (`capture_envelope.png` and `.svg`); with a
/// single parameter the vertical axis is the trial index.
fn envelope_plot(dir: &Path, c: &Campaign, rows: &[Row]) -> Result<(), String> {
    let paths: Vec<&str> = c.spec.parameters.iter().map(|p| p.label()).collect();
    let mut cats: Vec<String> = rows.iter().map(|r| r.2.clone()).collect();
    cats.sort();
    cats.dedup();
    let points: Vec<(f64, f64, usize)> = rows
        .iter()
        .map(|r| {
            let y = if paths.len() > 1 { r.1[1] } else { r.0 as f64 };
            let k = cats.iter().position(|c| *c == r.2).expect("category");
            (r.1[0], y, k)
        })
        .collect();
    let plot =
        crate::report::Plot::new(format!("{}: outcome of {} trials", c.spec.name, rows.len()))
            .x_label(paths[0])
            .y_label(if paths.len() > 1 {
                paths[1]
            } else {
                "trial index"
            })
            .outcomes(points, &cats);
    plot.write_png(&dir.join("capture_envelope.png"))
        .and_then(|_| plot.write_svg(&dir.join("capture_envelope.svg")))
        .map_err(|e| e.to_string())
}

/// Joins shard outputs into one `trials.csv` (rows in index order), `summary.json` and plot.
pub fn merge(c: &Campaign, shards: &[PathBuf], out: &Path) -> Result<usize, String> {
    let header = header(&c.spec);
    let mut all: BTreeMap<usize, String> = BTreeMap::new();
    for d in shards {
        let (h, rows) = read_rows(&d.join("trials.csv"))?;
        if h != header {
            return Err(format!("{} is from a different campaign", d.display()));
        }
        for r in rows {
            all.insert(r.0, r.4);
        }
    }
    std::fs::create_dir_all(out).map_err(|e| e.to_string())?;
    let mut text = header + "\n";
    for l in all.values() {
        text.push_str(l);
        text.push('\n');
    }
    crate::report::write_atomic(&out.join("trials.csv"), text.as_bytes())
        .map_err(|e| e.to_string())?;
    write_summary(out, c)?;
    Ok(all.len())
}
