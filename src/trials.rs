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
    /// The envelope plot (`capture_envelope.png`): `plot: (color_by: "peak_axial_load_n")`.
    #[serde(default)]
    pub plot: EnvelopePlot,
    /// One-sided confidence of the summary's probability statements ("met with probability ≥
    /// p at confidence c"), in (0, 1) (default 0.9).
    #[serde(default = "default_confidence")]
    pub confidence: f64,
    /// The probability a programme requires of the success criterion and of each guarantee,
    /// in (0, 1), e.g. 0.9973: the summary then gives the failure-free runs needed to show it
    /// at `confidence` and whether these trials show it.
    #[serde(default)]
    pub required_probability: Option<f64>,
}

fn default_confidence() -> f64 {
    0.9
}

/// How the envelope plot is drawn.
#[derive(Debug, Clone, Serialize, Deserialize, Default, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct EnvelopePlot {
    /// The `trials.csv` column that colours the cells (default `outcome`): `success`, or a
    /// numeric column (`t_latch_s`, `peak_axial_load_n`, `guarantee.NAME.worst_margin_m`, …),
    /// drawn in five equal bins between its smallest and largest value (empty cells: `n/a`).
    #[serde(default)]
    pub color_by: Option<String>,
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
    /// The label as written, if any.
    pub fn label_override(&self) -> Option<&str> {
        match self {
            Parameter::Grid { label, .. }
            | Parameter::Uniform { label, .. }
            | Parameter::Normal { label, .. } => label.as_deref(),
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

/// Success criterion: what a trial must show to count as a success. Combine with `All`, `Any`
/// and `Not`, e.g. `All([GuaranteeHeld("keep_out_10m"), MinClearance(0.5)])`.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub enum Success {
    /// The docking mechanism latched (and is still latched at the end): LATCHED, the cone and
    /// slot's end state only (refused over a SoftCapture base scene, which never latches).
    Latched,
    /// The docking mechanism is docked at the end, in its mechanism's successful end state:
    /// LATCHED (cone and slot) or HARD_DOCKED (soft capture, hooks closed).
    Docked,
    /// The final docking state is one of these (`"LATCHED"`, `"SOFT_CAPTURE"`, …).
    StateIn(Vec<String>),
    /// No collision (a contact between non-docking parts).
    NoCollision,
    /// The named guarantee of the scene held over the whole run.
    GuaranteeHeld(String),
    /// The smallest clearance between parts that are not both docking parts stayed at least
    /// this, m (full geometry, every body pair).
    MinClearance(f64),
    /// Every criterion.
    All(Vec<Success>),
    /// At least one criterion.
    Any(Vec<Success>),
    /// Not the criterion.
    Not(Box<Success>),
}

/// What a finished trial shows, for judging it.
struct Judged<'a> {
    outcome: &'a str,
    collided: bool,
    min_clearance_m: f64,
    held: &'a dyn Fn(&str) -> Option<bool>,
}

impl Success {
    /// The criterion in words, for summaries: `Latched`, `GuaranteeHeld(keep_out) and
    /// MinClearance(0.5 m)`.
    pub fn describe(&self) -> String {
        let join = |v: &[Success], w: &str| {
            v.iter()
                .map(|c| match c {
                    Success::All(_) | Success::Any(_) => format!("({})", c.describe()),
                    _ => c.describe(),
                })
                .collect::<Vec<_>>()
                .join(w)
        };
        match self {
            Success::Latched => "Latched".into(),
            Success::Docked => "Docked".into(),
            Success::StateIn(v) => format!("StateIn({})", v.join(", ")),
            Success::NoCollision => "NoCollision".into(),
            Success::GuaranteeHeld(n) => format!("GuaranteeHeld({n})"),
            Success::MinClearance(m) => format!("MinClearance({m} m)"),
            Success::All(v) => join(v, " and "),
            Success::Any(v) => join(v, " or "),
            Success::Not(c) => format!("not {}", c.describe()),
        }
    }

    /// Whether the criterion is about docking only (then its probability is a capture
    /// probability).
    pub fn is_docking(&self) -> bool {
        match self {
            Success::Latched | Success::Docked | Success::StateIn(_) => true,
            Success::All(v) | Success::Any(v) => !v.is_empty() && v.iter().all(Success::is_docking),
            Success::Not(_)
            | Success::NoCollision
            | Success::GuaranteeHeld(_)
            | Success::MinClearance(_) => false,
        }
    }

    fn judge(&self, j: &Judged) -> bool {
        match self {
            Success::Latched => j.outcome == "LATCHED",
            Success::Docked => {
                use crate::sim::docking::DockState;
                DockState::from_name(j.outcome)
                    .is_some_and(|s| matches!(s, DockState::Latched | DockState::HardDocked))
            }
            Success::StateIn(v) => v.iter().any(|s| s == j.outcome),
            Success::NoCollision => !j.collided,
            Success::GuaranteeHeld(n) => (j.held)(n) == Some(true),
            Success::MinClearance(m) => j.min_clearance_m >= *m,
            Success::All(v) => v.iter().all(|c| c.judge(j)),
            Success::Any(v) => v.iter().any(|c| c.judge(j)),
            Success::Not(c) => !c.judge(j),
        }
    }

    /// Checks names and values against the base scene's guarantees; `(path, message)`.
    fn check(
        &self,
        path: &str,
        guarantees: &[(String, String)],
        dock_end: Option<crate::sim::docking::DockState>,
    ) -> Result<(), (String, String)> {
        use crate::control::generic::sequencer::DOCK_STATES;
        use crate::sim::docking::DockState;
        match self {
            Success::Latched | Success::Docked | Success::StateIn(_) if dock_end.is_none() => Err((
                path.to_string(),
                "a docking criterion needs the base scene's `docking` mechanism: it could never be met"
                    .into(),
            )),
            Success::Latched if dock_end == Some(DockState::HardDocked) => Err((
                path.to_string(),
                "`Latched` means LATCHED, which the base scene's SoftCapture mechanism never reaches: \
                 use `Docked` (LATCHED or HARD_DOCKED) or `StateIn([\"HARD_DOCKED\"])`"
                    .into(),
            )),
            Success::StateIn(v) if v.is_empty() => Err((
                path.to_string(),
                "`StateIn([])` names no state: it could never be met".into(),
            )),
            Success::StateIn(v) if v.iter().any(|s| !DOCK_STATES.contains(&s.as_str())) => {
                let bad = v
                    .iter()
                    .find(|s| !DOCK_STATES.contains(&s.as_str()))
                    .map(String::as_str)
                    .unwrap_or_default();
                Err((
                    path.to_string(),
                    format!(
                        "unknown docking state {bad:?}; one of {}",
                        DOCK_STATES.join(", ")
                    ),
                ))
            }
            Success::GuaranteeHeld(n) if !guarantees.iter().any(|(g, _)| g == n) => Err((
                path.to_string(),
                format!(
                    "the base scene has no guarantee `{n}` (it has: {})",
                    guarantees
                        .iter()
                        .map(|g| g.0.as_str())
                        .collect::<Vec<_>>()
                        .join(", ")
                ),
            )),
            Success::MinClearance(m) if !(m.is_finite() && *m >= 0.0) => Err((
                path.to_string(),
                format!("a clearance is a finite number of metres ≥ 0, got {m}"),
            )),
            Success::All(v) | Success::Any(v) => {
                if v.is_empty() {
                    return Err((path.to_string(), "combine at least one criterion".into()));
                }
                v.iter()
                    .enumerate()
                    .try_for_each(|(i, c)| {
                        c.check(&format!("{path}.0.{i}"), guarantees, dock_end)
                    })
            }
            Success::Not(c) => c.check(&format!("{path}.0"), guarantees, dock_end),
            _ => Ok(()),
        }
    }
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

    /// One value per parameter that stands for it when the campaign is checked: a grid's first
    /// value, a uniform draw's midpoint, a normal draw's mean (independent of seed and order).
    pub fn representative(&self) -> Vec<f64> {
        self.parameters
            .iter()
            .map(|p| match p {
                Parameter::Grid { values, .. } => values.first().copied().unwrap_or(0.0),
                Parameter::Uniform { min, max, .. } => 0.5 * (min + max),
                Parameter::Normal { mean, .. } => *mean,
            })
            .collect()
    }

    fn validate(&self, file: &str, text: &str) -> Result<(), SceneError> {
        let err = |path: &str, msg: String| located(text, file, path, path, msg);
        if self.name.trim().is_empty()
            || self.name.chars().count() > 128
            || self.name.chars().any(char::is_control)
        {
            return Err(err(
                "name",
                "a campaign name is 1 to 128 characters without control characters".into(),
            ));
        }
        if self.count == 0 || self.count > MAX_TRIALS {
            return Err(err(
                "count",
                format!("must be from 1 to {MAX_TRIALS}, got {}", self.count),
            ));
        }
        if self.parameters.is_empty() {
            return Err(err("parameters", "name at least one parameter".into()));
        }
        if !(self.confidence > 0.0 && self.confidence < 1.0) {
            return Err(err(
                "confidence",
                format!(
                    "a one-sided confidence is a number in (0, 1), e.g. 0.9, got {}",
                    self.confidence
                ),
            ));
        }
        if let Some(p) = self.required_probability
            && !(p > 0.0 && p < 1.0)
        {
            return Err(err(
                "required_probability",
                format!("a required probability is a number in (0, 1), e.g. 0.9973, got {p}"),
            ));
        }
        if self.parameters.len() > MAX_PARAMETERS {
            return Err(err(
                "parameters",
                format!(
                    "at most {MAX_PARAMETERS} parameters, got {}",
                    self.parameters.len()
                ),
            ));
        }
        if let Some(d) = self.duration_s
            && !(d.is_finite() && d > 0.0)
        {
            return Err(err(
                "duration_s",
                format!("must be a positive number of seconds, got {d}"),
            ));
        }
        let mut cells: usize = 1;
        for (i, p) in self.parameters.iter().enumerate() {
            self.validate_parameter(i, p, &mut cells, &err)?;
        }
        Ok(())
    }

    /// Checks parameter `i` (`p`) of [`Self::validate`]: its path (not varied before; letters,
    /// digits, _ - . [ ], at most 256), its label (at most 200 characters, no control
    /// characters) and its values: a grid's 1 to [`MAX_GRID_VALUES`] finite values (their count
    /// multiplied into `cells`, the grids' cells together, at most [`MAX_GRID_CELLS`]), a
    /// uniform's finite min ≤ max, a normal's finite mean and sd ≥ 0. `err` locates an error.
    fn validate_parameter(
        &self,
        i: usize,
        p: &Parameter,
        cells: &mut usize,
        err: &impl Fn(&str, String) -> SceneError,
    ) -> Result<(), SceneError> {
        let at = format!("parameters.{i}");
        if self.parameters[..i].iter().any(|o| o.path() == p.path()) {
            return Err(err(
                &format!("{at}.path"),
                format!("`{}` is varied twice", p.path()),
            ));
        }
        let path_ok = !p.path().is_empty()
            && p.path().len() <= 256
            && p.path()
                .chars()
                .all(|c| c.is_ascii_alphanumeric() || matches!(c, '_' | '-' | '.' | '[' | ']'));
        if !path_ok {
            return Err(err(
                &format!("{at}.path"),
                format!(
                    "a scene field path (letters, digits, _ - . [ ], at most 256), got {:?}",
                    p.path()
                ),
            ));
        }
        if let Some(l) = p.label_override()
            && (l.chars().count() > 200 || l.chars().any(char::is_control))
        {
            return Err(err(
                &format!("{at}.label"),
                "a label is at most 200 characters without control characters".into(),
            ));
        }
        match p {
            Parameter::Grid { values, .. } => {
                if values.is_empty() || values.len() > MAX_GRID_VALUES {
                    return Err(err(
                        &format!("{at}.values"),
                        format!(
                            "a grid needs 1 to {MAX_GRID_VALUES} values, got {}",
                            values.len()
                        ),
                    ));
                }
                if let Some(k) = values.iter().position(|v| !v.is_finite()) {
                    return Err(err(
                        &format!("{at}.values.{k}"),
                        "grid values must be finite".into(),
                    ));
                }
                *cells = cells.saturating_mul(values.len());
                if *cells > MAX_GRID_CELLS {
                    return Err(err(
                        &format!("{at}.values"),
                        format!("the grids have more than {MAX_GRID_CELLS} cells together"),
                    ));
                }
            }
            Parameter::Uniform { min, max, .. }
                if !(min.is_finite()
                    && max.is_finite()
                    && min <= max
                    && (max - min).is_finite()) =>
            {
                return Err(err(
                    &format!("{at}.max"),
                    format!("need finite min ≤ max, got [{min}, {max}]"),
                ));
            }
            Parameter::Normal { mean, sd, .. }
                if !(mean.is_finite()
                    && sd.is_finite()
                    && *sd >= 0.0
                    && (mean.abs() + 40.0 * sd).is_finite()) =>
            {
                return Err(err(
                    &format!("{at}.sd"),
                    format!("need a finite mean and a finite sd ≥ 0, got mean {mean}, sd {sd}"),
                ));
            }
            _ => {}
        }
        Ok(())
    }
}

/// Most trials in a campaign.
pub const MAX_TRIALS: usize = 1_000_000;
/// Most varied parameters.
pub const MAX_PARAMETERS: usize = 64;
/// Most values of one grid parameter.
pub const MAX_GRID_VALUES: usize = 100_000;
/// Most cells of all grid parameters together.
pub const MAX_GRID_CELLS: usize = 10_000_000;

/// Outcome of a trial whose sampled parameters make an invalid scene (its reason is the
/// scene error): not a run, so not counted in the success probability.
pub const OUTCOME_INVALID: &str = "INVALID";
/// Outcome of a trial the finiteness guard stopped (its reason names the body, quantity and
/// time): a run that did not succeed, counted as a failure.
pub const OUTCOME_NUMERIC_FAILURE: &str = "NUMERIC_FAILURE";
/// Outcome of a trial of a scene without a docking mechanism.
pub const OUTCOME_NO_DOCKING: &str = "NO_DOCKING";

/// What identifies a campaign: every shard and every `trials.csv` row carries its id, and
/// resuming or merging refuses rows of another campaign.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Fingerprint {
    /// SHA-256 of the base scene file, hex.
    pub scene_sha256: String,
    /// SHA-256 of the trials file, hex.
    pub trials_sha256: String,
    /// The random parameters' seed.
    pub seed: u64,
    /// The rpod version that ran it.
    pub rpod_version: String,
    /// The first 16 hex digits of the SHA-256 of the four above: the `campaign_id` column.
    pub campaign_id: String,
}

impl Fingerprint {
    fn new(scene: &[u8], trials: &[u8], seed: u64) -> Self {
        let scene_sha256 = crate::report::sha256_hex(scene);
        let trials_sha256 = crate::report::sha256_hex(trials);
        let rpod_version = env!("CARGO_PKG_VERSION").to_string();
        let id = crate::report::sha256_hex(
            format!("rpod-trials-v1\n{rpod_version}\n{scene_sha256}\n{trials_sha256}\n{seed}\n")
                .as_bytes(),
        );
        Self {
            scene_sha256,
            trials_sha256,
            seed,
            rpod_version,
            campaign_id: id[..16].to_string(),
        }
    }

    /// What differs from `other`, in words (empty when nothing does).
    pub fn differences(&self, other: &Fingerprint) -> Vec<&'static str> {
        let mut d = Vec::new();
        if self.scene_sha256 != other.scene_sha256 {
            d.push("the base scene file");
        }
        if self.trials_sha256 != other.trials_sha256 {
            d.push("the trials file");
        }
        if self.seed != other.seed {
            d.push("the seed");
        }
        if self.rpod_version != other.rpod_version {
            d.push("the rpod version");
        }
        d
    }
}

/// A loaded campaign: the spec, the base scene's path and the campaign's fingerprint.
pub struct Campaign {
    /// The trials file.
    pub spec: TrialsSpec,
    /// The base scene file.
    pub scene_path: PathBuf,
    /// The fingerprint.
    pub fingerprint: Fingerprint,
    /// The base scene's guarantees (name, unit), in scene order: three `trials.csv` columns
    /// each.
    pub guarantees: Vec<(String, String)>,
    /// How each guarantee is judged (`interval` or `samples only`), same order.
    pub guarantee_judged: Vec<String>,
    /// The base scene's docking mechanism is a soft capture: `trials.csv` gains
    /// [`SOFT_CAPTURE_COLS`].
    pub soft_capture: bool,
}

/// A located error in a trials file: the line and column of `path` in `text` (0, 0 when it
/// cannot be found), the field `field`.
fn located(
    text: &str,
    file: &str,
    path: &str,
    field: impl Into<String>,
    message: impl Into<String>,
) -> SceneError {
    let (line, col) = crate::scene::load::locate(text, path)
        .map(|(s, _)| crate::scene::load::line_col(text, s))
        .unwrap_or((0, 0));
    SceneError {
        file: file.to_string(),
        line,
        col,
        field: field.into(),
        message: message.into(),
    }
}

/// Reads and checks a trials file; the base scene and every parameter path are checked by
/// building the representative trial ([`TrialsSpec::representative`]) and every grid value.
pub fn load(path: &Path) -> Result<Campaign, SceneError> {
    let file = path.display().to_string();
    let text = crate::scene::load::read_text(path, "trials file")?;
    let spec: TrialsSpec = crate::scene::load::parse_ron(&text, &file)?;
    spec.validate(&file, &text)?;
    let scene_path = path.parent().unwrap_or(Path::new(".")).join(&spec.scene);
    let scene_bytes = crate::report::fsio::read_regular(
        &scene_path,
        crate::scene::load::MAX_FILE_BYTES as u64,
        "scene",
    )
    .ok();
    let Some(scene_bytes) = scene_bytes else {
        return Err(located(
            &text,
            &file,
            "scene",
            "scene",
            format!("no scene file at {}", scene_path.display()),
        ));
    };
    let fingerprint = Fingerprint::new(&scene_bytes, text.as_bytes(), spec.seed);
    let mut c = Campaign {
        spec,
        scene_path,
        fingerprint,
        guarantees: Vec::new(),
        guarantee_judged: Vec::new(),
        soft_capture: false,
    };
    let repr = check_grid_values(&c, &text, &file)?;
    let loaded = load_scene_file(&c.scene_path, &overrides_of(&c.spec, &repr))?;
    if let Some(d) = c.spec.duration_s {
        crate::scene::validate::check_steps("duration_s", d, loaded.scene.dt_s)
            .map_err(|(_, m)| located(&text, &file, "duration_s", "duration_s", m))?;
    }
    c.soft_capture = loaded
        .scene
        .docking
        .as_ref()
        .is_some_and(|d| matches!(d.mechanism, crate::scene::Mechanism::SoftCapture(_)));
    let sim = Simulation::new(&loaded)?;
    c.guarantees = sim
        .guarantees()
        .status
        .iter()
        .map(|g| (g.name.clone(), g.unit.clone()))
        .collect();
    // How each guarantee is judged is decided by the monitor on its first step (interval
    // with a rate bound, samples only without): one step of trial 0 tells.
    let mut sim = sim;
    sim.step(1);
    c.guarantee_judged = sim
        .guarantees()
        .status
        .iter()
        .map(|g| g.judged.to_string())
        .collect();
    check_color_by(&c, &text, &file)?;
    let dock_end = loaded
        .scene
        .docking
        .as_ref()
        .map(|d| crate::sim::docking::DockState::docked_end_state(&d.mechanism));
    if let Err((p, m)) = c.spec.success.check("success", &c.guarantees, dock_end) {
        return Err(located(&text, &file, &p, p.clone(), m));
    }
    Ok(c)
}

/// [`load`]'s check of every grid value: each (with the other parameters at their
/// representative values) must make a valid scene, else an error located at it in the trials
/// file (`text`, named `file`). Returns the representative values.
fn check_grid_values(c: &Campaign, text: &str, file: &str) -> Result<Vec<f64>, SceneError> {
    // Checked now rather than in every worker, the same way whatever the order of the grid
    // values or the seed: every grid value (each with the other parameters at their
    // representative values: a grid's first value, a draw's centre) must make a valid scene —
    // a grid value is the user's explicit choice, an invalid one a mistake; a random draw
    // that makes an invalid scene is that trial's `INVALID` outcome. The representative
    // trial must build (paths, references).
    let repr = c.spec.representative();
    for (i, p) in c.spec.parameters.iter().enumerate() {
        let Parameter::Grid { values, .. } = p else {
            continue;
        };
        for (j, v) in values.iter().enumerate() {
            let mut vals = repr.clone();
            vals[i] = *v;
            if let Err(e) = load_scene_file(&c.scene_path, &overrides_of(&c.spec, &vals)) {
                let at = format!("parameters.{i}.values.{j}");
                return Err(located(
                    text,
                    file,
                    &at,
                    at.clone(),
                    format!("grid value {v:?} makes an invalid scene: {e}"),
                ));
            }
        }
    }
    Ok(repr)
}

/// [`load`]'s check of `plot.color_by`: a `trials.csv` column other than `index`, `reason`
/// and `campaign_id`, else an error located at it in the trials file (`text`, named `file`).
fn check_color_by(c: &Campaign, text: &str, file: &str) -> Result<(), SceneError> {
    if let Some(col) = &c.spec.plot.color_by {
        let cols = header(c);
        let allowed: Vec<&String> = cols
            .iter()
            .filter(|h| !matches!(h.as_str(), "index" | "reason" | "campaign_id"))
            .collect();
        if !allowed.contains(&col) {
            return Err(located(
                text,
                file,
                "plot.color_by",
                "plot.color_by",
                format!(
                    "no trials.csv column {col:?} to colour by; one of: {}",
                    allowed
                        .iter()
                        .map(|s| s.as_str())
                        .collect::<Vec<_>>()
                        .join(", ")
                ),
            ));
        }
    }
    Ok(())
}

fn overrides(c: &Campaign, k: usize) -> Vec<String> {
    overrides_of(&c.spec, &c.spec.values(k))
}

/// The `--set` overrides that give the parameters these values.
fn overrides_of(spec: &TrialsSpec, values: &[f64]) -> Vec<String> {
    spec.parameters
        .iter()
        .zip(values)
        .map(|(p, &v)| {
            // A whole number is written without a fraction, so that it also sets an integer
            // field (a sensor's `seed`); RON reads it into a float field all the same.
            if v.fract() == 0.0 && v.abs() < 9.0e15 {
                format!("{}={}", p.path(), v as i64)
            } else {
                format!("{}={v:?}", p.path())
            }
        })
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
    /// Final docking state, or `NO_DOCKING`, `INVALID`, `NUMERIC_FAILURE`.
    pub outcome: String,
    /// Success per the criterion.
    pub success: bool,
    /// Time to latch, s.
    pub t_latch_s: Option<f64>,
    /// Peak contact force on any part, N.
    pub peak_contact_force_n: Option<f64>,
    /// Peak axial and lateral loads on the docking mechanism up to the latch, N (the summary's
    /// `docking.contact`; none without a docking mechanism).
    pub peak_loads_n: Option<(f64, f64)>,
    /// Largest misalignment in contact, deg.
    pub max_misalignment_deg: Option<f64>,
    /// Smallest clearance between parts that are not both docking parts, m.
    pub min_clearance_m: Option<f64>,
    /// First collision, s.
    pub first_collision_s: Option<f64>,
    /// Per guarantee of the campaign (same order): worst margin (in its unit), first
    /// violation time, s, and the verdict (`held`, `violated`, `unresolved`).
    pub guarantees: Vec<(Option<f64>, Option<f64>, Option<&'static str>)>,
    /// A soft-capture campaign's [`SOFT_CAPTURE_COLS`] (`None` for other campaigns).
    pub soft: Option<[Option<f64>; 6]>,
    /// Steps simulated.
    pub steps: u64,
    /// Why (the docking state's reason, the scene error, the guard's trip).
    pub reason: String,
}

impl TrialResult {
    fn not_run(
        c: &Campaign,
        k: usize,
        values: Vec<f64>,
        outcome: &str,
        reason: String,
        steps: u64,
    ) -> Self {
        TrialResult {
            index: k,
            values,
            outcome: outcome.into(),
            success: false,
            t_latch_s: None,
            peak_contact_force_n: None,
            peak_loads_n: None,
            max_misalignment_deg: None,
            min_clearance_m: None,
            first_collision_s: None,
            guarantees: vec![(None, None, None); c.guarantees.len()],
            soft: c.soft_capture.then_some([None; 6]),
            steps,
            reason,
        }
    }
}

/// Runs trial `k`; with `keep` its standard outputs (`trajectory.csv`, `events.jsonl`,
/// `contacts.csv`, `summary.json`) are written into that folder.
pub fn run_trial(c: &Campaign, k: usize, keep: Option<&Path>) -> TrialResult {
    let values = c.spec.values(k);
    let mut sim = match build(c, k) {
        Ok(s) => s,
        Err(e) => {
            return TrialResult::not_run(c, k, values, OUTCOME_INVALID, e.to_string(), 0);
        }
    };
    if let Some(dir) = keep
        && let Err(e) = crate::report::fsio::ensure_own_dir(dir).and_then(|()| sim.record_to(dir))
    {
        let reason = format!("cannot write {}: {e}", dir.display());
        return TrialResult::not_run(c, k, values, "IO_ERROR", reason, 0);
    }
    let duration = c.spec.duration_s.unwrap_or(sim.scene.duration_s);
    sim.step(sim.steps_for(duration));
    if let Some(trip) = sim.guard_trip().cloned() {
        let steps = sim.steps();
        let _ = sim.finish();
        return TrialResult::not_run(
            c,
            k,
            values,
            OUTCOME_NUMERIC_FAILURE,
            trip.to_string(),
            steps,
        );
    }
    let dock = sim.app.world().get_resource::<Docking>().cloned();
    let cs = sim.contacts();
    let outcome = dock.as_ref().map_or(OUTCOME_NO_DOCKING.to_string(), |d| {
        d.state.name().to_string()
    });
    let min_clearance = sim
        .monitor()
        .min_clearance_per_pair
        .iter()
        .copied()
        .fold(f64::INFINITY, f64::min);
    let status = &sim.guarantees().status;
    let held = |n: &str| status.iter().find(|g| g.name == n).map(|g| g.held);
    let success = c.spec.success.judge(&Judged {
        outcome: &outcome,
        collided: cs.first_collision_s.is_some(),
        min_clearance_m: min_clearance,
        held: &held,
    });
    let guarantees = c
        .guarantees
        .iter()
        .map(|(n, _)| {
            status
                .iter()
                .find(|g| &g.name == n)
                .map_or((None, None, None), |g| {
                    (
                        g.worst_margin.is_finite().then_some(g.worst_margin),
                        g.first_violation_s,
                        Some(g.verdict),
                    )
                })
        })
        .collect();
    let r = TrialResult {
        index: k,
        values,
        outcome,
        success,
        t_latch_s: dock.as_ref().and_then(|d| d.t_latch_s),
        peak_contact_force_n: Some(
            cs.per_part
                .values()
                .map(|p| p.peak_force_n)
                .fold(0.0, f64::max),
        ),
        peak_loads_n: dock
            .as_ref()
            .map(|d| (d.loads.peak_axial_load_n, d.loads.peak_lateral_load_n)),
        max_misalignment_deg: dock.as_ref().map(|d| d.max_misalignment_deg),
        min_clearance_m: min_clearance.is_finite().then_some(min_clearance),
        first_collision_s: cs.first_collision_s,
        guarantees,
        soft: c.soft_capture.then(|| {
            let r = dock
                .as_ref()
                .and_then(|d| d.soft.clone())
                .unwrap_or_default();
            [
                r.peak_leg_stroke_t_s.map(|_| r.peak_leg_stroke_m),
                r.peak_leg_force_t_s.map(|_| r.peak_leg_force_n),
                r.peak_interface_force_t_s.map(|_| r.peak_interface_force_n),
                r.peak_interface_moment_t_s
                    .map(|_| r.peak_interface_moment_nm),
                r.t_soft_captured_s,
                r.t_hard_docked_s,
            ]
        }),
        steps: sim.steps(),
        reason: dock.map_or(String::new(), |d| d.reason),
    };
    if keep.is_some() {
        let _ = sim.finish();
    }
    r
}

fn opt(v: Option<f64>) -> String {
    v.map_or(String::new(), |x| format!("{x}"))
}

/// The fixed result columns after the parameters.
const RESULT_COLS: [&str; 9] = [
    "outcome",
    "success",
    "t_latch_s",
    "peak_contact_force_n",
    "peak_axial_load_n",
    "peak_lateral_load_n",
    "max_misalignment_deg",
    "min_clearance_non_docking_m",
    "first_collision_s",
];

/// The result columns a soft-capture campaign adds after `RESULT_COLS` (empty: never
/// captured): peak |leg stroke| (m), peak |leg force| (N), peak interface force (N) and moment
/// (N·m) on the chaser at its port, the capture and hard-dock times (s).
pub const SOFT_CAPTURE_COLS: [&str; 6] = [
    "peak_leg_stroke_m",
    "peak_leg_force_n",
    "peak_interface_force_n",
    "peak_interface_moment_nm",
    "t_soft_captured_s",
    "t_hard_docked_s",
];

/// The CSV header cells for a campaign: `index`, one column per parameter path, the results,
/// per guarantee `guarantee.NAME.worst_margin_UNIT`, `guarantee.NAME.first_violation_s`
/// (empty: never violated) and `guarantee.NAME.verdict` (`held`, `violated`, `unresolved`;
/// empty when the trial did not run), `steps`, `reason`, `campaign_id`.
pub fn header(c: &Campaign) -> Vec<String> {
    let mut cols = vec!["index".to_string()];
    cols.extend(c.spec.parameters.iter().map(|p| p.path().to_string()));
    cols.extend(RESULT_COLS.map(String::from));
    if c.soft_capture {
        cols.extend(SOFT_CAPTURE_COLS.map(String::from));
    }
    for (n, u) in &c.guarantees {
        cols.push(format!("guarantee.{n}.worst_margin_{u}"));
        cols.push(format!("guarantee.{n}.first_violation_s"));
        cols.push(format!("guarantee.{n}.verdict"));
    }
    cols.extend(["steps", "reason", "campaign_id"].map(String::from));
    cols
}

/// One CSV row's cells. Free text (the reason) is kept on one line: control characters become
/// spaces, so every row is one line of the file; the CSV writer quotes commas and quotes.
pub fn row(r: &TrialResult, campaign_id: &str) -> Vec<String> {
    let mut cells = vec![r.index.to_string()];
    cells.extend(r.values.iter().map(|v| format!("{v}")));
    cells.push(r.outcome.clone());
    cells.push(r.success.to_string());
    cells.push(opt(r.t_latch_s));
    cells.push(opt(r.peak_contact_force_n));
    cells.push(opt(r.peak_loads_n.map(|l| l.0)));
    cells.push(opt(r.peak_loads_n.map(|l| l.1)));
    cells.push(opt(r.max_misalignment_deg));
    cells.push(opt(r.min_clearance_m));
    cells.push(opt(r.first_collision_s));
    for v in r.soft.iter().flatten() {
        cells.push(opt(*v));
    }
    for (w, f, v) in &r.guarantees {
        cells.push(opt(*w));
        cells.push(opt(*f));
        cells.push(v.unwrap_or("").to_string());
    }
    cells.push(r.steps.to_string());
    cells.push(
        r.reason
            .chars()
            .map(|c| if c.is_control() { ' ' } else { c })
            .collect(),
    );
    cells.push(campaign_id.to_string());
    cells
}

/// One CSV line (with its newline) from cells, quoted as RFC 4180 says.
fn csv_line(cells: &[String]) -> String {
    let mut w = csv::WriterBuilder::new()
        .terminator(csv::Terminator::Any(b'\n'))
        .from_writer(Vec::new());
    w.write_record(cells).expect("writing to memory");
    String::from_utf8(w.into_inner().expect("writing to memory")).expect("cells are UTF-8")
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
    /// Keep each trial's standard outputs in `OUT/runs/NNNNNN/`.
    pub keep_runs: bool,
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

/// Why a command on trials failed: bad files (exit 2), the output folder in use (exit 4),
/// or I/O (exit 1).
#[derive(Debug)]
pub enum TrialsError {
    /// A `trials.csv` or shard that cannot be used (another campaign, damaged rows, missing
    /// or duplicated indices): the message says which file, line and why.
    Refused(String),
    /// Another rpod process writes into the output folder.
    FolderInUse(String),
    /// Reading or writing failed.
    Io(String),
}

impl std::fmt::Display for TrialsError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            TrialsError::Refused(m) | TrialsError::FolderInUse(m) | TrialsError::Io(m) => {
                write!(f, "{m}")
            }
        }
    }
}

fn io_err(e: impl std::fmt::Display) -> TrialsError {
    TrialsError::Io(e.to_string())
}

fn lock(dir: &Path) -> Result<crate::sim::output::FolderLock, TrialsError> {
    crate::sim::output::FolderLock::acquire(dir).map_err(|e| {
        if e.kind() == std::io::ErrorKind::WouldBlock {
            TrialsError::FolderInUse(e.to_string())
        } else {
            TrialsError::Io(format!("{}: {e}", dir.display()))
        }
    })
}

/// A row read back from a `trials.csv` and checked: index, values, outcome, success, cells.
#[derive(Debug, Clone)]
pub struct Row {
    /// Trial index.
    pub index: usize,
    /// Parameter values.
    pub values: Vec<f64>,
    /// Outcome.
    pub outcome: String,
    /// Success.
    pub success: bool,
    /// All cells, as written.
    pub cells: Vec<String>,
}

/// Reads and checks every row of a `trials.csv` against the campaign: the header; per row, the
/// cell count, an index below `count` (and in `shard` when given) seen once, the parameter
/// values trial k must have (recomputed from k and the seed), an outcome, a boolean success,
/// numbers where numbers belong, and this campaign's id. An unterminated last line (a crash
/// while writing it) is dropped when `drop_torn_tail` (a resume reruns that trial); any other
/// damage is refused with the file, line and reason. Returns the rows and the length of the
/// file's accepted prefix, bytes.
pub fn read_checked(
    path: &Path,
    c: &Campaign,
    shard: Option<(usize, usize)>,
    drop_torn_tail: bool,
) -> Result<(Vec<Row>, usize), TrialsError> {
    let text = crate::report::fsio::read_regular_string(
        path,
        crate::report::fsio::MAX_OUTPUT_READ_BYTES,
        "trials table",
    )
    .map_err(|e| TrialsError::Refused(format!("{e}; cannot read it as text")))?;
    let at = |line: usize, why: String| {
        TrialsError::Refused(format!(
            "{}:{line}: {why}; this file cannot be resumed or merged as it is (fix or remove \
             the line, or use another --out)",
            path.display()
        ))
    };
    let mut accepted = text.len();
    let mut body = text.as_str();
    if !text.is_empty() && !text.ends_with('\n') {
        let cut = text.rfind('\n').map_or(0, |i| i + 1);
        if !drop_torn_tail {
            return Err(at(
                text[..cut].matches('\n').count() + 1,
                "the last line is cut (no newline at its end)".into(),
            ));
        }
        accepted = cut;
        body = &text[..cut];
    }
    let header = header(c);
    let mut rows = Vec::new();
    let mut seen = std::collections::HashSet::new();
    for (n, line) in body.lines().enumerate() {
        let lineno = n + 1;
        let cells = csv_cells(line).map_err(|why| at(lineno, why))?;
        if n == 0 {
            if cells != header {
                return Err(TrialsError::Refused(format!(
                    "{}: its header differs from this campaign's (another trials file, or an \
                     older rpod); use another --out",
                    path.display()
                )));
            }
            continue;
        }
        let row = check_row(c, &header, shard, &mut seen, cells).map_err(|why| at(lineno, why))?;
        rows.push(row);
    }
    Ok((rows, accepted))
}

/// The cells of one line of a `trials.csv`, or why it is not a CSV row.
fn csv_cells(line: &str) -> Result<Vec<String>, String> {
    match csv::ReaderBuilder::new()
        .has_headers(false)
        .from_reader(line.as_bytes())
        .records()
        .next()
    {
        Some(Ok(r)) => Ok(r.iter().map(str::to_string).collect()),
        Some(Err(e)) => Err(format!("not a CSV row ({e})")),
        None => Err("an empty line".into()),
    }
}

/// Checks one data row of a `trials.csv` (its `cells`, under `header`) as [`read_checked`]
/// describes, noting its index in `seen`; returns the row, or why it is refused.
fn check_row(
    c: &Campaign,
    header: &[String],
    shard: Option<(usize, usize)>,
    seen: &mut std::collections::HashSet<usize>,
    cells: Vec<String>,
) -> Result<Row, String> {
    let np = c.spec.parameters.len();
    if cells.len() != header.len() {
        return Err(format!(
            "{} cells, the header has {}",
            cells.len(),
            header.len()
        ));
    }
    let id = cells.last().map(String::as_str).unwrap_or("");
    if id != c.fingerprint.campaign_id {
        return Err(format!(
            "the row belongs to campaign {id:?}, not to this one ({}): the base scene, \
             the trials file, the seed or the rpod version differ",
            c.fingerprint.campaign_id
        ));
    }
    let k: usize = cells[0]
        .parse()
        .map_err(|_| format!("index {:?} is not a number", cells[0]))?;
    if k >= c.spec.count {
        return Err(format!(
            "index {k} is out of range (count {})",
            c.spec.count
        ));
    }
    if let Some((i, m)) = shard
        && k % m != i
    {
        return Err(format!("trial {k} is not in shard {i}/{m}"));
    }
    if !seen.insert(k) {
        return Err(format!("trial {k} appears twice"));
    }
    let expect = c.spec.values(k);
    for (j, v) in expect.iter().enumerate() {
        if cells[1 + j] != format!("{v}") {
            return Err(format!(
                "trial {k}'s `{}` is {:?}, the campaign gives it {v}",
                header[1 + j],
                cells[1 + j]
            ));
        }
    }
    let outcome = cells[np + 1].clone();
    if outcome.is_empty() || !outcome.bytes().all(|b| b.is_ascii_uppercase() || b == b'_') {
        return Err(format!("outcome {outcome:?} is not an outcome"));
    }
    let success = match cells[np + 2].as_str() {
        "true" => true,
        "false" => false,
        other => {
            return Err(format!("success {other:?} is not true or false"));
        }
    };
    check_result_cells(header, &cells, np)?;
    Ok(Row {
        index: k,
        values: expect,
        outcome,
        success,
        cells,
    })
}

/// Checks a row's numeric result columns (empty = none), its verdicts and `steps` (the
/// columns after the `np` parameters, the outcome and the success, up to the last two);
/// returns why a cell is refused.
fn check_result_cells(header: &[String], cells: &[String], np: usize) -> Result<(), String> {
    // The numeric result columns (empty = none) and `steps`.
    for j in np + 3..header.len() - 2 {
        let cell = &cells[j];
        let ok = if header[j] == "steps" {
            cell.parse::<u64>().is_ok()
        } else if header[j].ends_with(".verdict") {
            matches!(cell.as_str(), "" | "held" | "violated" | "unresolved")
        } else {
            cell.is_empty() || cell.parse::<f64>().is_ok_and(f64::is_finite)
        };
        if !ok {
            return Err(format!(
                "`{}` is {cell:?}, not {}",
                header[j],
                if header[j].ends_with(".verdict") {
                    "a verdict (held, violated, unresolved or empty)"
                } else {
                    "a number"
                }
            ));
        }
    }
    Ok(())
}

/// Writes the campaign's fingerprint as `campaign.json` in `dir`.
fn write_campaign_json(dir: &Path, c: &Campaign) -> Result<(), TrialsError> {
    let v = serde_json::json!({
        "campaign": c.spec.name,
        "fingerprint": c.fingerprint,
    });
    crate::report::write_atomic(
        &dir.join("campaign.json"),
        (serde_json::to_string_pretty(&v).map_err(io_err)? + "\n").as_bytes(),
    )
    .map_err(io_err)
}

/// Refuses a folder whose `campaign.json` names another campaign, saying what differs.
fn check_campaign_json(dir: &Path, c: &Campaign) -> Result<(), TrialsError> {
    let path = dir.join("campaign.json");
    if std::fs::symlink_metadata(&path).is_err() {
        return Ok(());
    }
    let text = crate::report::fsio::read_regular_string(&path, 16 << 20, "campaign record")
        .map_err(|e| TrialsError::Refused(e.to_string()))?;
    let other: Option<Fingerprint> = serde_json::from_str::<serde_json::Value>(&text)
        .ok()
        .and_then(|v| serde_json::from_value(v["fingerprint"].clone()).ok());
    match other {
        Some(f) if f == c.fingerprint => Ok(()),
        Some(f) => Err(TrialsError::Refused(format!(
            "{} holds campaign {} ({} differ from this campaign {}); use another --out",
            dir.display(),
            f.campaign_id,
            c.fingerprint.differences(&f).join(", "),
            c.fingerprint.campaign_id
        ))),
        None => Err(TrialsError::Refused(format!(
            "{}/campaign.json cannot be read; use another --out",
            dir.display()
        ))),
    }
}

/// Runs (or resumes) a campaign's shard into `opts.out`.
pub fn run(c: &Campaign, opts: &RunOptions) -> Result<RunStats, TrialsError> {
    let _lock = lock(&opts.out)?;
    check_campaign_json(&opts.out, c)?;
    let csv_path = opts.out.join("trials.csv");
    let (si, sn) = opts.shard;
    let done: Vec<usize> = if csv_path.exists() {
        let (rows, accepted) = read_checked(&csv_path, c, Some((si, sn)), true)?;
        // A torn last line from a crash is dropped: that trial runs again.
        let f =
            crate::report::fsio::open_write_nofollow(&csv_path, &mut std::fs::OpenOptions::new())
                .map_err(io_err)?;
        f.set_len(accepted as u64).map_err(io_err)?;
        if accepted == 0 {
            drop(f);
            std::fs::remove_file(&csv_path).map_err(io_err)?;
        }
        rows.iter().map(|r| r.index).collect()
    } else {
        Vec::new()
    };
    write_campaign_json(&opts.out, c)?;
    let done_set: std::collections::HashSet<usize> = done.iter().copied().collect();
    let todo: Vec<usize> = (0..c.spec.count)
        .filter(|k| k % sn == si && !done_set.contains(k))
        .collect();
    let mut file = if csv_path.exists() {
        crate::report::fsio::open_write_nofollow(
            &csv_path,
            std::fs::OpenOptions::new().append(true),
        )
        .map_err(|e| TrialsError::Io(e.to_string()))?
    } else {
        let mut f = crate::report::fsio::create_new_nofollow(&csv_path)
            .map_err(|e| TrialsError::Io(format!("{}: {e}", csv_path.display())))?;
        f.write_all(csv_line(&header(c)).as_bytes())
            .map_err(io_err)?;
        f
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
    let id = c.fingerprint.campaign_id.clone();
    let runs_dir = opts.out.join("runs");
    let keep_runs = opts.keep_runs;
    if keep_runs {
        // A link planted at OUT/runs would send every trial's files outside the output folder.
        crate::report::fsio::ensure_own_dir(&runs_dir).map_err(io_err)?;
    }
    std::thread::scope(|s| -> Result<(), TrialsError> {
        for _ in 0..jobs {
            let tx = tx.clone();
            let runs_dir = &runs_dir;
            let (todo, next) = (&todo, &next);
            s.spawn(move || {
                loop {
                    let i = next.fetch_add(1, Ordering::Relaxed);
                    let Some(&k) = todo.get(i) else { break };
                    let keep = keep_runs.then(|| runs_dir.join(format!("{k:06}")));
                    if tx.send(run_trial(c, k, keep.as_deref())).is_err() {
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
                file.write_all(csv_line(&row(&r, &id)).as_bytes())
                    .map_err(io_err)?;
                file.flush().map_err(io_err)?;
                cursor += 1;
                bar.inc(1);
            }
        }
        Ok(())
    })?;
    bar.finish_and_clear();
    let wall_s = t0.elapsed().as_secs_f64();
    let (rows, _) = read_checked(&csv_path, c, Some((si, sn)), false)?;
    write_summary(&opts.out, c, &rows, &[])?;
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

/// "Met with probability ≥ p at confidence c" for `s` successes in `n` trials: the observed
/// proportion, the one-sided exact (Clopper–Pearson) lower bound p at confidence `conf`
/// ([`crate::math::stats::clopper_pearson_lower`]), the sentence, and with a `required`
/// probability whether the bound reaches it.
pub fn probability_statement(
    s: usize,
    n: usize,
    conf: f64,
    required: Option<f64>,
) -> serde_json::Value {
    let lb = crate::math::stats::clopper_pearson_lower(s, n, conf);
    // Rounded down, so the sentence never claims more than the bound.
    let shown = (lb * 1e4).floor() / 1e4;
    let mut j = serde_json::json!({
        "successes": s,
        "trials": n,
        "probability": if n > 0 { serde_json::json!(s as f64 / n as f64) } else { serde_json::Value::Null },
        "probability_lower_bound": lb,
        "confidence": conf,
        "statement": format!(
            "met with probability ≥ {shown:.4} at confidence {conf} ({s} of {n} trials; one-sided Clopper–Pearson)"
        ),
    });
    if let Some(p) = required {
        j["required_probability"] = serde_json::json!(p);
        j["requirement_shown"] = serde_json::json!(n > 0 && lb >= p);
    }
    j
}

/// Index ranges `a-b` (or `a`) of a sorted list, comma-separated, at most `max` ranges shown.
pub fn ranges(idx: &[usize], max: usize) -> String {
    let mut out: Vec<String> = Vec::new();
    let mut i = 0;
    while i < idx.len() {
        let mut j = i;
        while j + 1 < idx.len() && idx[j + 1] == idx[j] + 1 {
            j += 1;
        }
        out.push(if i == j {
            idx[i].to_string()
        } else {
            format!("{}-{}", idx[i], idx[j])
        });
        i = j + 1;
    }
    let n = out.len();
    if n > max {
        out.truncate(max);
        out.push(format!("… ({} more ranges)", n - max));
    }
    out.join(", ")
}

/// Writes `summary.json` and the capture-envelope plot for the checked rows of `dir/trials.csv`
/// (`missing`: indices a partial merge lacks).
pub fn write_summary(
    dir: &Path,
    c: &Campaign,
    rows: &[Row],
    missing: &[usize],
) -> Result<(), TrialsError> {
    let mut counts: BTreeMap<String, usize> = BTreeMap::new();
    for r in rows {
        *counts.entry(r.outcome.clone()).or_default() += 1;
    }
    let invalid = counts.get(OUTCOME_INVALID).copied().unwrap_or(0);
    let valid: Vec<&Row> = rows
        .iter()
        .filter(|r| r.outcome != OUTCOME_INVALID)
        .collect();
    let s = valid.iter().filter(|r| r.success).count();
    let (p, lo, hi) = wilson(s, valid.len());
    let p_json = if valid.is_empty() {
        serde_json::Value::Null
    } else {
        serde_json::json!(p)
    };
    let mut summary = serde_json::json!({
        "campaign": c.spec.name,
        "scene": c.scene_path.display().to_string(),
        "fingerprint": c.fingerprint,
        "trials": rows.len(),
        "planned": c.spec.count,
        "complete": missing.is_empty() && rows.len() == c.spec.count,
        "missing_indices": ranges(missing, 50),
        "invalid": invalid,
        "valid_trials": valid.len(),
        "numeric_failures": counts.get(OUTCOME_NUMERIC_FAILURE).copied().unwrap_or(0),
        "success_criterion": c.spec.success.describe(),
        "successes": s,
        "outcomes": counts,
        "success_probability": p_json,
        "success_probability_95ci_wilson": [lo, hi],
        "probability_over": "valid trials (INVALID trials, whose sampled parameters made an invalid scene, are not runs; NUMERIC_FAILURE counts as a failure)",
        "parameters": c.spec.parameters.iter().map(|p| p.path()).collect::<Vec<_>>(),
        "provenance": crate::report::build_provenance(),
    });
    let conf = c.spec.confidence;
    let req = c.spec.required_probability;
    summary["confidence"] = serde_json::json!(conf);
    let st = probability_statement(s, valid.len(), conf, req);
    summary["success_probability_lower_bound"] = st["probability_lower_bound"].clone();
    summary["success_statement"] = st["statement"].clone();
    if let Some(p) = req {
        summary["required_probability"] = serde_json::json!(p);
        summary["zero_failure_runs_needed"] =
            serde_json::json!(crate::math::stats::zero_failure_runs(p, conf));
        summary["success_requirement_shown"] = st["requirement_shown"].clone();
    }
    let header = header(c);
    let requirements: Vec<serde_json::Value> = c
        .guarantees
        .iter()
        .enumerate()
        .map(|(i, (name, unit))| {
            let col = header
                .iter()
                .position(|h| *h == format!("guarantee.{name}.verdict"));
            let verdicts: Vec<&str> = valid
                .iter()
                .map(|r| col.and_then(|j| r.cells.get(j)).map_or("", String::as_str))
                .collect();
            let count = |v: &str| verdicts.iter().filter(|x| **x == v).count();
            let held = count("held");
            let mut j = probability_statement(held, valid.len(), conf, req);
            j["guarantee"] = serde_json::json!(name);
            j["unit"] = serde_json::json!(unit);
            j["judged"] = serde_json::json!(c.guarantee_judged.get(i));
            j["held"] = serde_json::json!(held);
            j["violated"] = serde_json::json!(count("violated"));
            j["unresolved"] = serde_json::json!(count("unresolved"));
            j["no_verdict"] = serde_json::json!(count(""));
            j
        })
        .collect();
    summary["requirements"] = serde_json::json!(requirements);
    summary["requirements_counting"] = serde_json::json!(
        "per guarantee over the valid trials: a success is a `held` verdict; `violated`, \
         `unresolved` (not proven to hold) and a trial without a verdict (NUMERIC_FAILURE) \
         count against it"
    );
    if c.spec.success.is_docking() {
        summary["capture_probability"] = p_json;
        summary["capture_probability_95ci_wilson"] = serde_json::json!([lo, hi]);
    }
    crate::report::write_atomic(
        &dir.join("summary.json"),
        (serde_json::to_string_pretty(&summary).map_err(io_err)? + "\n").as_bytes(),
    )
    .map_err(io_err)?;
    envelope_plot(dir, c, rows).map_err(TrialsError::Io)
}

/// Colours of the five bins of a numeric `color_by` column, low to high (viridis), and of
/// empty cells.
const BIN_COLORS: [crate::report::Color; 5] = [
    crate::report::Color::rgb(0x44, 0x01, 0x54),
    crate::report::Color::rgb(0x3b, 0x52, 0x8b),
    crate::report::Color::rgb(0x21, 0x91, 0x8c),
    crate::report::Color::rgb(0x5e, 0xc9, 0x62),
    crate::report::Color::rgb(0xfd, 0xe7, 0x25),
];
const NA_COLOR: crate::report::Color = crate::report::Color::rgb(0x99, 0x99, 0x99);

/// A number with 3 significant digits and the Unicode minus sign, for legends and titles.
fn fmt_sig(x: f64) -> String {
    let s = if x == 0.0 || (1e-3..1e6).contains(&x.abs()) {
        let d = (2 - x.abs().log10().floor() as i32).clamp(0, 6) as usize;
        let t = format!("{x:.d$}");
        if t.contains('.') {
            t.trim_end_matches('0').trim_end_matches('.').to_string()
        } else {
            t
        }
    } else {
        format!("{x:.2e}")
    };
    s.replace('-', "\u{2212}")
}

/// Each row's category and the categories (name, colour) for the envelope plot.
fn envelope_categories(
    c: &Campaign,
    rows: &[Row],
) -> (Vec<usize>, Vec<(String, crate::report::Color)>) {
    use crate::report::PALETTE;
    let col = c.spec.plot.color_by.as_deref().unwrap_or("outcome");
    let at = header(c).iter().position(|h| h == col);
    let cell = |r: &Row| at.and_then(|i| r.cells.get(i)).cloned().unwrap_or_default();
    let nums: Vec<Option<f64>> = rows
        .iter()
        .map(|r| cell(r).parse::<f64>().ok().filter(|x| x.is_finite()))
        .collect();
    let numeric = !matches!(col, "outcome" | "success") && nums.iter().any(|x| x.is_some());
    if !numeric {
        let mut cats: Vec<String> = rows.iter().map(cell).collect();
        cats.sort();
        cats.dedup();
        let ks = rows
            .iter()
            .map(|r| cats.iter().position(|c| *c == cell(r)).unwrap_or(0))
            .collect();
        let cats = cats
            .into_iter()
            .enumerate()
            .map(|(i, s)| {
                let name = if s.is_empty() { "n/a".to_string() } else { s };
                (name, PALETTE[i % PALETTE.len()])
            })
            .collect();
        return (ks, cats);
    }
    let (lo, hi) = nums
        .iter()
        .flatten()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), x| {
            (l.min(*x), h.max(*x))
        });
    let n = if hi > lo { BIN_COLORS.len() } else { 1 };
    let w = (hi - lo) / n as f64;
    let fmt = fmt_sig;
    let mut cats: Vec<(String, crate::report::Color)> = (0..n)
        .map(|b| {
            let (a, z) = (
                lo + w * b as f64,
                if b + 1 == n {
                    hi
                } else {
                    lo + w * (b + 1) as f64
                },
            );
            let name = if n == 1 {
                format!("{col} = {}", fmt(lo))
            } else {
                format!("{col} {} to {}", fmt(a), fmt(z))
            };
            (
                name,
                BIN_COLORS[b * (BIN_COLORS.len() - 1) / (n.max(2) - 1)],
            )
        })
        .collect();
    let na = cats.len();
    let mut any_na = false;
    let ks = nums
        .iter()
        .map(|x| match x {
            Some(x) if n > 1 => (((x - lo) / w) as usize).min(n - 1),
            Some(_) => 0,
            None => {
                any_na = true;
                na
            }
        })
        .collect();
    if any_na {
        cats.push(("n/a".into(), NA_COLOR));
    }
    (ks, cats)
}

/// The envelope plot (`capture_envelope.png` and `.svg`): cells coloured by the outcome (or
/// `plot.color_by`) over the two leading parameters; with one parameter the vertical axis is
/// the trial index; with more than two, small multiples: one panel per value of the third
/// parameter (a grid of at most six values), or per third of its range (the fourth and later
/// parameters vary within each panel), the legend once, beside the last panel.
fn envelope_plot(dir: &Path, c: &Campaign, rows: &[Row]) -> Result<(), String> {
    use crate::report::Legend;
    let params = &c.spec.parameters;
    let labels: Vec<&str> = params.iter().map(|p| p.label()).collect();
    let (ks, cats) = envelope_categories(c, rows);
    let what = c.spec.plot.color_by.as_deref().unwrap_or("outcome");
    // The legend (on one panel) counts the trials of every panel.
    let totals: Vec<usize> = (0..cats.len())
        .map(|k| ks.iter().filter(|x| **x == k).count())
        .collect();
    let panel = |title: String, sel: &dyn Fn(&Row) -> bool, legend: bool| {
        let points: Vec<(f64, f64, usize)> = rows
            .iter()
            .zip(&ks)
            .filter(|(r, _)| sel(r))
            .map(|(r, k)| {
                let y = if params.len() > 1 {
                    r.values[1]
                } else {
                    r.index as f64
                };
                (r.values[0], y, *k)
            })
            .collect();
        crate::report::Plot::new(title)
            .x_label(labels[0])
            .y_label(if params.len() > 1 {
                labels[1]
            } else {
                "trial index"
            })
            .outcomes_colored(points, &cats)
            .outcome_counts(totals.clone())
            .legend(if legend { Legend::Best } else { Legend::Off })
    };
    let title = format!("{}: {what} of {} trials", c.spec.name, rows.len());
    let fig = if params.len() <= 2 {
        panel(title, &|_| true, true).into_figure()
    } else {
        let fmt = fmt_sig;
        let third: Vec<f64> = rows.iter().map(|r| r.values[2]).collect();
        let mut fig = crate::report::Figure::new(format!(
            "{title}, by {}{}",
            labels[2],
            if params.len() > 3 {
                " (later parameters vary within each panel)"
            } else {
                ""
            }
        ));
        let mut n_panels = 0;
        match &params[2] {
            Parameter::Grid { values, .. } if values.len() <= 6 => {
                for (i, v) in values.iter().enumerate() {
                    let v = *v;
                    fig.push(panel(
                        format!("{} = {}", labels[2], fmt(v)),
                        &|r| r.values[2] == v,
                        i + 1 == values.len(),
                    ));
                    n_panels += 1;
                }
            }
            _ => {
                let (lo, hi) = third
                    .iter()
                    .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), x| {
                        (l.min(*x), h.max(*x))
                    });
                let w = (hi - lo) / 3.0;
                for b in 0..3 {
                    let a = lo + w * b as f64;
                    let z = if b == 2 { hi } else { a + w };
                    let last = b == 2;
                    fig.push(panel(
                        format!("{} {} to {}", labels[2], fmt(a), fmt(z)),
                        &|r| r.values[2] >= a && (r.values[2] < z || (last && r.values[2] <= z)),
                        last,
                    ));
                    n_panels += 1;
                }
            }
        }
        fig.cols(n_panels.min(3))
    };
    fig.write_png(&dir.join("capture_envelope.png"))
        .and_then(|_| fig.write_svg(&dir.join("capture_envelope.svg")))
        .map_err(|e| e.to_string())
}

/// What a merge did.
#[derive(Debug, Clone)]
pub struct MergeStats {
    /// Trials merged.
    pub merged: usize,
    /// Indices missing (only with `allow_partial`).
    pub missing: Vec<usize>,
}

/// Joins shard outputs into one `trials.csv` (rows in index order), `summary.json` and plot.
/// Every shard row is checked ([`read_checked`]: this campaign's id, values, cells); a shard
/// of another campaign, an index in two shards, or (unless `allow_partial`) an index in none
/// is refused, naming the shard or the indices.
pub fn merge(
    c: &Campaign,
    shards: &[PathBuf],
    out: &Path,
    allow_partial: bool,
) -> Result<MergeStats, TrialsError> {
    let mut all: BTreeMap<usize, (Row, usize)> = BTreeMap::new();
    for (si, d) in shards.iter().enumerate() {
        check_campaign_json(d, c)?;
        let (rows, _) = read_checked(&d.join("trials.csv"), c, None, false)?;
        for r in rows {
            if let Some((_, other)) = all.get(&r.index) {
                return Err(TrialsError::Refused(format!(
                    "trial {} is in two shards, {} and {}",
                    r.index,
                    shards[*other].display(),
                    d.display()
                )));
            }
            all.insert(r.index, (r, si));
        }
    }
    let missing: Vec<usize> = (0..c.spec.count).filter(|k| !all.contains_key(k)).collect();
    if !missing.is_empty() && !allow_partial {
        return Err(TrialsError::Refused(format!(
            "{} of {} trials are in no shard: {} (a shard is missing or unfinished; rerun it, \
             or merge with --allow-partial)",
            missing.len(),
            c.spec.count,
            ranges(&missing, 20)
        )));
    }
    let _lock = lock(out)?;
    let mut text = csv_line(&header(c));
    for (r, _) in all.values() {
        text.push_str(&csv_line(&r.cells));
    }
    crate::report::write_atomic(&out.join("trials.csv"), text.as_bytes()).map_err(io_err)?;
    write_campaign_json(out, c)?;
    let rows: Vec<Row> = all.into_values().map(|(r, _)| r).collect();
    write_summary(out, c, &rows, &missing)?;
    Ok(MergeStats {
        merged: rows.len(),
        missing,
    })
}
