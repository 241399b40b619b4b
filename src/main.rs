//! `rpod`: the command line. `rpod run` (headless run of a scene), `rpod check` (validate
//! scenes), `rpod bench` (steps/s against the bare rapier and parry floor); with the `viewer`
//! feature, `rpod view` (live, in a window) and `rpod replay` (a recorded run).

use clap::{Parser, Subcommand};
use std::io::Write;
use std::path::PathBuf;

/// How much to print: 0 errors only (`-q`, or `RUST_LOG=error`/`warn`/`off`), 1 the results
/// (default), 2 also provenance and progress details (`-v`, or `RUST_LOG=info`/`debug`/`trace`).
static LEVEL: std::sync::atomic::AtomicU8 = std::sync::atomic::AtomicU8::new(1);

fn level() -> u8 {
    LEVEL.load(std::sync::atomic::Ordering::Relaxed)
}

/// println! that does not panic when stdout is closed (e.g. piped into `head`); silent with -q.
macro_rules! out {
    ($($t:tt)*) => {{
        if level() >= 1 {
            let _ = writeln!(std::io::stdout().lock(), $($t)*);
        }
    }};
}

/// Details printed with -v.
macro_rules! info {
    ($($t:tt)*) => {{
        if level() >= 2 {
            let _ = writeln!(std::io::stdout().lock(), $($t)*);
        }
    }};
}

/// A progress bar, hidden with -q (indicatif also hides it when stderr is not a terminal).
fn progress_bar(len: u64, template: &str) -> indicatif::ProgressBar {
    let bar = if level() == 0 {
        indicatif::ProgressBar::hidden()
    } else {
        indicatif::ProgressBar::new(len)
    };
    bar.set_style(indicatif::ProgressStyle::with_template(template).expect("template"));
    bar
}
use std::process::ExitCode;

#[derive(Parser)]
#[command(
    name = "rpod",
    version,
    about = "Spacecraft rendezvous, proximity operations and docking testbed"
)]
struct Cli {
    #[command(subcommand)]
    cmd: Cmd,
    /// Print nothing but errors (no results, no progress bars).
    #[arg(short, long, global = true)]
    quiet: bool,
    /// Print more: provenance (version, commit, scene hash, overrides) and details.
    #[arg(short, long, global = true)]
    verbose: bool,
}

#[derive(Subcommand)]
enum Cmd {
    /// Run a scene headless and write trajectory.csv, events.jsonl, contacts.csv and summary.json.
    Run {
        /// Scene file (RON).
        scene: PathBuf,
        /// Output directory (default: out/<scene name>).
        #[arg(long)]
        out: Option<PathBuf>,
        /// Simulated duration in seconds (default: the scene's duration_s).
        #[arg(long)]
        duration: Option<f64>,
        /// Override a scene field: `--set bodies.chaser.mass_kg=120` (repeatable).
        #[arg(long = "set", value_name = "PATH=VALUE")]
        set: Vec<String>,
        /// Also write contact_points.csv: every contact point (position, normal, depth, force)
        /// at every step, and every sub-step of the compliant docking contact.
        #[arg(long)]
        contact_points: bool,
    },
    /// Validate scene files (syntax, units, physics, geometry overlaps at t = 0).
    Check {
        /// Scene files.
        #[arg(required = true)]
        scenes: Vec<PathBuf>,
        /// Override a scene field (applies to every scene).
        #[arg(long = "set", value_name = "PATH=VALUE")]
        set: Vec<String>,
    },
    /// Draw the standard figures of a recorded run (PNG, SVG and the data as CSV).
    Plot {
        /// Run directory (trajectory.csv, contacts.csv, summary.json).
        run_dir: PathBuf,
        /// Output directory (default: RUN_DIR/plots).
        #[arg(long)]
        out: Option<PathBuf>,
    },
    /// Run a trials campaign (or `trials merge` shard outputs).
    Trials(TrialsCmd),
    /// Reproduce a paper's headline result (all papers without a name): REPORT.md, plots,
    /// claims.json under OUT/NAME.
    Reproduce {
        /// Paper (guo2016, xu2015, geng2015, xu2019, zhang2018); omit to run every paper.
        name: Option<String>,
        /// Output directory.
        #[arg(long, default_value = "out/reproduce")]
        out: PathBuf,
    },
    /// Measure steps/s of a scene against the bare rapier step and bare parry queries.
    Bench {
        /// Scene file (default scenes/examples/free_drift.ron).
        #[arg(default_value = "scenes/examples/free_drift.ron")]
        scene: PathBuf,
        /// Steps per measurement (default 20000; with --meshes, 3000 per flagship and
        /// guarantee case, the fly-bys 400).
        #[arg(long)]
        steps: Option<u64>,
        /// Instead of the scene: the swarm table for these body counts (e.g. 2,4,8,…,256).
        #[arg(long, value_delimiter = ',')]
        swarm: Vec<usize>,
        /// Instead of the scene: the cliffs (a spinning chaser, an attitude law through the
        /// latch and in contact, free_drift against bare rapier), each as a ratio to its plain
        /// case in the same run; SCENE's folder must hold docking_aligned.ron and free_drift.ron.
        #[arg(long)]
        cliffs: bool,
        /// Instead of the scene: the costs of mesh parts and of the RPOD requirement set, each as a
        /// ratio to its plain case in the same run — fly-bys of generated 100 000-triangle
        /// targets at 20 m and 1.9 m against the Box and Sphere primitives, the flagship with
        /// the example mesh vehicle against the flagship, each guarantee kind against the run
        /// without it, and the plume impingement loads against the run without them, with the
        /// bare rapier and parry floors (about 2 minutes); SCENE's
        /// folder must hold orbit_approach_latch.ron, orbit_approach_latch_truss.ron,
        /// requirements_approach.ron and orbit_approach_plume.ron. The generated meshes are
        /// written to temporary folders that are removed afterwards.
        #[arg(long)]
        meshes: bool,
    },
    /// Write an N-body swarm scene (tumbling winged spacecraft on a 20 m grid in orbit).
    Swarm {
        /// Number of spacecraft (1 … 64, the most bodies a scene may have).
        n: usize,
        /// Output file (default: print to stdout).
        #[arg(long)]
        out: Option<PathBuf>,
        /// Seed of the drift velocities, attitudes and rates.
        #[arg(long, default_value_t = 1)]
        seed: u64,
    },
    /// Run a scene live in a window (feature `viewer`).
    #[cfg(feature = "viewer")]
    View {
        /// Scene file (RON).
        scene: PathBuf,
        /// Override a scene field (repeatable).
        #[arg(long = "set", value_name = "PATH=VALUE")]
        set: Vec<String>,
        #[command(flatten)]
        win: WindowArgs,
    },
    /// Play back a run recorded by `rpod run` in a window (feature `viewer`).
    #[cfg(feature = "viewer")]
    Replay {
        /// Run directory (trajectory.csv, events.jsonl, contacts.csv, summary.json).
        run_dir: PathBuf,
        /// Scene file (default: the one summary.json names).
        #[arg(long)]
        scene: Option<PathBuf>,
        /// Start at this simulated time, s (default: the start; the end with --screenshot).
        #[arg(long)]
        at: Option<f64>,
        #[command(flatten)]
        win: WindowArgs,
    },
}

/// Window options shared by `view` and `replay`.
#[cfg(feature = "viewer")]
#[derive(clap::Args)]
struct WindowArgs {
    /// Save a PNG of the window after --frames frames, then exit.
    #[arg(long)]
    screenshot: Option<PathBuf>,
    /// Frames to render (then exit); default: run until the window is closed.
    #[arg(long)]
    frames: Option<u32>,
    /// Window width, px.
    #[arg(long, default_value_t = 1280)]
    width: u32,
    /// Window height, px.
    #[arg(long, default_value_t = 720)]
    height: u32,
    /// Playback speed, × real time (0.1 to 1000).
    #[arg(long, default_value_t = 1.0)]
    speed: f64,
    /// Start playing at once.
    #[arg(long)]
    play: bool,
    /// Hide overlays and the panel (spacecraft only).
    #[arg(long)]
    no_overlays: bool,
    /// Show only these layers at start, comma-separated: ports, lvlh, trails, closest,
    /// contacts, surfaces, panel (default: all, or none with --no-overlays).
    #[arg(long, value_delimiter = ',')]
    layers: Option<Vec<String>>,
    /// Initial camera: overview, target (orbit the target), chaser (follow the chaser), port
    /// (out of the chaser's docking port).
    #[arg(long, default_value = "overview")]
    camera: String,
    /// Render the 3-D view at this fraction of the window size, scaled up (0 < s ≤ 1; e.g.
    /// 0.5 for a software renderer).
    #[arg(long, default_value_t = 1.0)]
    render_scale: f32,
}

#[cfg(feature = "viewer")]
impl WindowArgs {
    fn options(self, start_s: Option<f64>) -> rpod::viewer::ViewerOptions {
        rpod::viewer::ViewerOptions {
            frames: self.frames.or(self.screenshot.as_ref().map(|_| 10)),
            screenshot: self.screenshot,
            size_px: (self.width.max(64), self.height.max(64)),
            overlays: !self.no_overlays,
            layers: self.layers,
            render_scale: self.render_scale,
            start_s,
            speed: self.speed,
            play: self.play,
            camera: self.camera,
        }
    }
}

#[derive(clap::Args)]
#[command(args_conflicts_with_subcommands = true)]
struct TrialsCmd {
    #[command(subcommand)]
    merge: Option<TrialsSub>,
    /// Trials file (RON).
    file: Option<PathBuf>,
    /// Worker threads (default: the machine's cores).
    #[arg(long)]
    jobs: Option<usize>,
    /// Run only shard i of n (`--shard 3/10`): trials whose index % n == i.
    #[arg(long)]
    shard: Option<String>,
    /// Output directory (default: out/trials/<campaign name>).
    #[arg(long)]
    out: Option<PathBuf>,
    /// Keep each trial's trajectory.csv, events.jsonl, contacts.csv and summary.json in
    /// OUT/runs/NNNNNN/.
    #[arg(long)]
    keep_runs: bool,
}

#[derive(Subcommand)]
enum TrialsSub {
    /// Join the outputs of shards into one trials.csv, summary.json and envelope plot.
    Merge {
        /// The trials file the shards ran.
        file: PathBuf,
        /// Shard output directories.
        #[arg(required = true)]
        shards: Vec<PathBuf>,
        /// Merged output directory.
        #[arg(long)]
        out: PathBuf,
        /// Merge even if some trials are in no shard (the summary lists them).
        #[arg(long)]
        allow_partial: bool,
    },
}

fn trials_exit(e: &rpod::trials::TrialsError) -> ExitCode {
    eprintln!("error: {e}");
    ExitCode::from(match e {
        rpod::trials::TrialsError::Refused(_) => 2,
        rpod::trials::TrialsError::FolderInUse(_) => rpod::sim::output::EXIT_FOLDER_IN_USE,
        rpod::trials::TrialsError::Io(_) => 1,
    })
}

fn trials(cmd: TrialsCmd) -> ExitCode {
    if let Some(TrialsSub::Merge {
        file,
        shards,
        out,
        allow_partial,
    }) = cmd.merge
    {
        let c = match rpod::trials::load(&file) {
            Ok(c) => c,
            Err(e) => {
                eprintln!("error: {e}");
                return ExitCode::from(2);
            }
        };
        return match rpod::trials::merge(&c, &shards, &out, allow_partial) {
            Ok(st) => {
                out!("merged {} trials into {}", st.merged, out.display());
                if !st.missing.is_empty() {
                    out!(
                        "PARTIAL: {} of {} trials are missing: {}",
                        st.missing.len(),
                        c.spec.count,
                        rpod::trials::ranges(&st.missing, 20)
                    );
                }
                ExitCode::SUCCESS
            }
            Err(e) => trials_exit(&e),
        };
    }
    let Some(file) = cmd.file else {
        eprintln!("error: name a trials file (or `rpod trials merge`)");
        return ExitCode::from(2);
    };
    let shard = match cmd.shard.as_deref().map(|s| {
        s.split_once('/')
            .and_then(|(i, n)| Some((i.parse::<usize>().ok()?, n.parse::<usize>().ok()?)))
            .filter(|(i, n)| *n > 0 && i < n)
    }) {
        None => (0, 1),
        Some(Some(s)) => s,
        Some(None) => {
            eprintln!("error: --shard takes i/n with 0 ≤ i < n, e.g. --shard 0/4");
            return ExitCode::from(2);
        }
    };
    let c = match rpod::trials::load(&file) {
        Ok(c) => c,
        Err(e) => {
            eprintln!("error: {e}");
            return ExitCode::from(2);
        }
    };
    let jobs = cmd
        .jobs
        .unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()));
    let out = cmd.out.unwrap_or_else(|| {
        PathBuf::from("out/trials").join(rpod::sim::output::safe_dir_name(&c.spec.name))
    });
    let opts = rpod::trials::RunOptions {
        jobs,
        shard,
        out: out.clone(),
        progress: level() >= 1,
        keep_runs: cmd.keep_runs,
    };
    match rpod::trials::run(&c, &opts) {
        Ok(st) => {
            out!(
                "{}: ran {} trials ({} resumed) on {jobs} jobs in {:.1} s: {:.2} trials/s, {:.0} steps/s",
                c.spec.name,
                st.ran,
                st.resumed,
                st.wall_s,
                st.ran as f64 / st.wall_s.max(1e-9),
                st.steps as f64 / st.wall_s.max(1e-9)
            );
            if let Ok(text) = rpod::report::fsio::read_regular_string(
                &out.join("summary.json"),
                64 << 20,
                "summary",
            ) && let Ok(v) = serde_json::from_str::<serde_json::Value>(&text)
            {
                let ci = &v["success_probability_95ci_wilson"];
                let what = if v["capture_probability"].is_null() {
                    "success probability"
                } else {
                    "capture probability"
                };
                out!(
                    "outcomes {}; {what} ({}) {:.3} (95 % Wilson [{:.3}, {:.3}]) over {} valid trials",
                    v["outcomes"],
                    v["success_criterion"].as_str().unwrap_or(""),
                    v["success_probability"].as_f64().unwrap_or(f64::NAN),
                    ci[0].as_f64().unwrap_or(f64::NAN),
                    ci[1].as_f64().unwrap_or(f64::NAN),
                    v["valid_trials"]
                );
                out!("success: {}", v["success_statement"].as_str().unwrap_or(""));
                if let Some(n) = v["zero_failure_runs_needed"].as_u64() {
                    out!(
                        "required probability {} at confidence {}: {n} failure-free runs needed; shown by these trials: {}",
                        v["required_probability"],
                        v["confidence"],
                        v["success_requirement_shown"]
                    );
                }
                for r in v["requirements"].as_array().into_iter().flatten() {
                    out!(
                        "requirement {} ({}): {}",
                        r["guarantee"].as_str().unwrap_or(""),
                        r["judged"].as_str().unwrap_or(""),
                        r["statement"].as_str().unwrap_or("")
                    );
                }
            }
            out!(
                "wrote {}/{{trials.csv, summary.json, capture_envelope.png, capture_envelope.svg}}",
                out.display()
            );
            ExitCode::SUCCESS
        }
        Err(e) => trials_exit(&e),
    }
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let from_env = std::env::var("RUST_LOG").ok().map(|v| {
        let v = v.to_ascii_lowercase();
        if v.contains("debug") || v.contains("trace") || v.contains("info") {
            2
        } else if v.contains("error") || v.contains("warn") || v.contains("off") {
            0
        } else {
            1
        }
    });
    let lvl = if cli.quiet {
        0
    } else if cli.verbose {
        2
    } else {
        from_env.unwrap_or(1)
    };
    LEVEL.store(lvl, std::sync::atomic::Ordering::Relaxed);
    match cli.cmd {
        Cmd::Run {
            scene,
            out,
            duration,
            set,
            contact_points,
        } => run(&scene, out, duration, &set, contact_points),
        Cmd::Check { scenes, set } => {
            let mut bad = false;
            for s in &scenes {
                match load_and_build(s, &set) {
                    Ok(sim) => out!(
                        "{}: ok ({} bodies, dt = {} s, duration = {} s)",
                        s.display(),
                        sim.scene.bodies.len(),
                        sim.scene.dt_s,
                        sim.scene.duration_s
                    ),
                    Err(e) => {
                        eprintln!("error: {e}");
                        bad = true;
                    }
                }
            }
            if bad {
                ExitCode::from(2)
            } else {
                ExitCode::SUCCESS
            }
        }
        Cmd::Reproduce { name, out } => reproduce(name, &out),
        Cmd::Plot { run_dir, out } => {
            let out = out.unwrap_or_else(|| run_dir.join("plots"));
            match rpod::report::run_plots::plot_run(&run_dir, &out) {
                Ok(files) => {
                    for f in &files {
                        info!("wrote {}", f.display());
                    }
                    out!("wrote {} files to {}", files.len(), out.display());
                    ExitCode::SUCCESS
                }
                Err(e) => {
                    eprintln!("error: {e}");
                    ExitCode::from(2)
                }
            }
        }
        Cmd::Trials(cmd) => trials(cmd),
        #[cfg(feature = "viewer")]
        Cmd::View { scene, set, win } => {
            viewer_result(rpod::viewer::view(&scene, &set, win.options(None)))
        }
        #[cfg(feature = "viewer")]
        Cmd::Replay {
            run_dir,
            scene,
            at,
            win,
        } => viewer_result(rpod::viewer::replay(
            &run_dir,
            scene.as_deref(),
            win.options(at),
        )),
        Cmd::Swarm { n, out, seed } => {
            // A swarm is a scene like any other: no larger than `rpod check` accepts.
            let max = rpod::scene::validate::MAX_BODIES;
            if !(1..=max).contains(&n) {
                eprintln!("error: the swarm size must be 1 … {max} (the scene limit), got {n}");
                return ExitCode::from(2);
            }
            let text = rpod::bench::swarm_scene(n, seed);
            match out {
                Some(p) => match std::fs::write(&p, text) {
                    Ok(()) => ExitCode::SUCCESS,
                    Err(e) => {
                        eprintln!("error: {}: {e}", p.display());
                        ExitCode::from(2)
                    }
                },
                None => {
                    out!("{text}");
                    ExitCode::SUCCESS
                }
            }
        }
        Cmd::Bench { swarm, steps, .. } if !swarm.is_empty() => {
            if let Some(n) = swarm.iter().find(|n| !(1..=4096).contains(*n)) {
                eprintln!("error: the swarm sizes must be 1 … 4096, got {n}");
                return ExitCode::from(2);
            }
            match rpod::bench::run_swarm(&swarm, steps.unwrap_or(20000)) {
                Ok(report) => {
                    out!("{report}");
                    ExitCode::SUCCESS
                }
                Err(e) => {
                    eprintln!("error: {e}");
                    ExitCode::from(2)
                }
            }
        }
        Cmd::Bench {
            scene,
            steps,
            cliffs: true,
            ..
        } => {
            let folder = scene.parent().unwrap_or(std::path::Path::new("."));
            match rpod::bench::run_cliffs(folder, steps.unwrap_or(20000)) {
                Ok(report) => {
                    out!("{report}");
                    ExitCode::SUCCESS
                }
                Err(e) => {
                    eprintln!("error: {e}");
                    ExitCode::from(2)
                }
            }
        }
        Cmd::Bench {
            scene,
            steps,
            meshes: true,
            ..
        } => {
            let folder = scene.parent().unwrap_or(std::path::Path::new("."));
            match rpod::bench::meshes::run_meshes(folder, steps.unwrap_or(3000)) {
                Ok(report) => {
                    out!("{report}");
                    ExitCode::SUCCESS
                }
                Err(e) => {
                    eprintln!("error: {e}");
                    ExitCode::from(2)
                }
            }
        }
        Cmd::Bench { scene, steps, .. } => match rpod::bench::run(&scene, steps.unwrap_or(20000)) {
            Ok(report) => {
                out!("{report}");
                ExitCode::SUCCESS
            }
            Err(e) => {
                eprintln!("error: {e}");
                ExitCode::from(2)
            }
        },
    }
}

#[cfg(feature = "viewer")]
fn viewer_result(r: Result<(), String>) -> ExitCode {
    match r {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::from(2)
        }
    }
}

fn load_and_build(
    path: &std::path::Path,
    set: &[String],
) -> Result<rpod::sim::Simulation, rpod::scene::SceneError> {
    let loaded = rpod::scene::load_scene_file(path, set)?;
    rpod::sim::Simulation::new(&loaded)
}

fn run(
    scene: &std::path::Path,
    out: Option<PathBuf>,
    duration: Option<f64>,
    set: &[String],
    contact_points: bool,
) -> ExitCode {
    let mut sim = match load_and_build(scene, set) {
        Ok(s) => s,
        Err(e) => {
            eprintln!("error: {e}");
            return ExitCode::from(2);
        }
    };
    let duration = duration.unwrap_or(sim.scene.duration_s);
    if !(duration.is_finite() && duration >= 0.0) {
        eprintln!("error: --duration must be a non-negative number of seconds, got {duration}");
        return ExitCode::from(2);
    }
    if let Err((_, m)) = rpod::scene::validate::check_steps("--duration", duration, sim.scene.dt_s)
    {
        eprintln!("error: --duration: {m}");
        return ExitCode::from(2);
    }
    let out = out.unwrap_or_else(|| default_out(&sim.scene.name));
    sim.record_contact_points(contact_points);
    if let Err(e) = sim.record_to(&out) {
        return if e.kind() == std::io::ErrorKind::WouldBlock {
            eprintln!("error: {e}");
            ExitCode::from(rpod::sim::output::EXIT_FOLDER_IN_USE)
        } else {
            eprintln!("error: cannot write to {}: {e}", out.display());
            ExitCode::from(2)
        };
    }
    let total = sim.steps_for(duration);
    info!(
        "rpod {} (commit {}); scene {} sha256 {}; --set {:?}; writing to {}",
        sim.provenance["rpod_version"].as_str().unwrap_or(""),
        sim.provenance["git_commit"].as_str().unwrap_or("unknown"),
        sim.provenance["scene_file"].as_str().unwrap_or(""),
        sim.provenance["scene_sha256"].as_str().unwrap_or(""),
        sim.provenance["set"],
        out.display()
    );
    let bar = progress_bar(
        total,
        "{spinner} [{elapsed_precise}] {bar:40} {pos}/{len} steps  sim {msg}  ETA {eta}",
    );
    let chunk = (total / 200).max(1000);
    let mut done = 0;
    while done < total && sim.guard_trip().is_none() {
        let k = chunk.min(total - done);
        sim.step(k);
        done += k;
        bar.set_position(done);
        bar.set_message(format!("{:.1} s", sim.t_s()));
    }
    bar.finish_and_clear();
    if let Some(trip) = sim.guard_trip().cloned() {
        let kept = sim
            .finish()
            .err()
            .map(|e| e.to_string())
            .unwrap_or_default();
        eprintln!("error: the run stopped: {trip}");
        if !kept.is_empty() && !kept.contains(&trip.to_string()) {
            eprintln!("error: {kept}");
        }
        eprintln!(
            "the rows up to the last good step are in {}/*.partial; no summary.json was written",
            out.display()
        );
        return ExitCode::from(rpod::sim::guard::EXIT_NUMERIC_FAILURE);
    }
    match sim.finish() {
        Ok(summary) => {
            let md = &summary["min_distance"];
            out!(
                "{}: {} steps, {:.2} s simulated in {:.2} s wall ({:.0} steps/s)",
                summary["scene"].as_str().unwrap_or(""),
                summary["steps"],
                summary["simulated_s"].as_f64().unwrap_or(0.0),
                summary["wall_s"].as_f64().unwrap_or(0.0),
                summary["steps_per_s"].as_f64().unwrap_or(0.0)
            );
            if !md.is_null() {
                out!(
                    "min distance {:.4} m between {} and {} at t = {:.2} s",
                    md["value_m"].as_f64().unwrap_or(f64::NAN),
                    md["parts"][0].as_str().unwrap_or(""),
                    md["parts"][1].as_str().unwrap_or(""),
                    md["t_s"].as_f64().unwrap_or(f64::NAN)
                );
            }
            match summary["first_collision_s"].as_f64() {
                Some(t) => {
                    let c = &summary["collisions"][0];
                    out!(
                        "COLLISION at t = {t:.2} s: {} hit {}",
                        c["a"].as_str().unwrap_or(""),
                        c["b"].as_str().unwrap_or("")
                    );
                }
                None => out!("no collision"),
            }
            for g in summary["guarantees"].as_array().into_iter().flatten() {
                out!(
                    "guarantee {}: {} (worst margin {:.4} {} at t = {:.2} s)",
                    g["name"].as_str().unwrap_or(""),
                    if g["held"].as_bool() == Some(true) {
                        "held"
                    } else {
                        "VIOLATED"
                    },
                    g["worst_margin"].as_f64().unwrap_or(f64::NAN),
                    g["unit"].as_str().unwrap_or(""),
                    g["worst_margin_t_s"].as_f64().unwrap_or(f64::NAN)
                );
            }
            let d = &summary["docking"];
            if !d.is_null() {
                let c = &d["contact"];
                out!(
                    "docking {}{} ({}); peak loads on the mechanism: axial {:.1} N, lateral {:.1} N; {}",
                    d["state"].as_str().unwrap_or(""),
                    d["t_latch_s"]
                        .as_f64()
                        .map_or(String::new(), |t| format!(", latched at t = {t:.2} s")),
                    d["reason"].as_str().unwrap_or(""),
                    c["peak_axial_load_n"].as_f64().unwrap_or(0.0),
                    c["peak_lateral_load_n"].as_f64().unwrap_or(0.0),
                    c["model"].as_str().unwrap_or("")
                );
            }
            for c in summary["controllers"].as_array().into_iter().flatten() {
                out!(
                    "controller {} on {}: {} calls, delta-v {:.4} m/s",
                    c["kind"].as_str().unwrap_or(""),
                    c["body"].as_str().unwrap_or(""),
                    c["calls"],
                    c["delta_v_m_s"].as_f64().unwrap_or(f64::NAN)
                );
            }
            out!(
                "wrote {}/{{trajectory.csv, events.jsonl, contacts.csv, summary.json{}}}",
                out.display(),
                if contact_points {
                    ", contact_points.csv"
                } else {
                    ""
                }
            );
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("error: writing outputs to {}: {e}", out.display());
            ExitCode::from(1)
        }
    }
}

/// `out/<name>`, the name made safe for a path (never outside `out/`).
fn default_out(name: &str) -> PathBuf {
    PathBuf::from("out").join(rpod::sim::output::safe_dir_name(name))
}

/// Prints one reproduced paper's folder and claims (or its error), as one block.
fn report_paper(
    bar: &indicatif::ProgressBar,
    n: &str,
    dir: &std::path::Path,
    r: Result<(), String>,
) {
    use std::fmt::Write as _;
    if let Err(e) = r {
        bar.suspend(|| {
            out!("== {n} → {}", dir.display());
            eprintln!("error: {n}: {e}");
        });
        return;
    }
    let claims =
        rpod::report::fsio::read_regular_string(&dir.join("claims.json"), 64 << 20, "claims table")
            .ok()
            .and_then(|t| serde_json::from_str::<serde_json::Value>(&t).ok());
    let mut block = format!("== {n} → {}", dir.display());
    for c in claims
        .as_ref()
        .and_then(|v| v.as_array())
        .into_iter()
        .flatten()
    {
        let _ = write!(
            block,
            "\n  [{}] {}: {}",
            if c["held"].as_bool() == Some(true) {
                "held"
            } else {
                "NOT held"
            },
            c["id"].as_str().unwrap_or(""),
            c["measured"].as_str().unwrap_or("")
        );
    }
    bar.suspend(|| out!("{block}"));
}

fn reproduce(name: Option<String>, out: &std::path::Path) -> ExitCode {
    let names: Vec<String> = match name {
        // An unknown name (a path among them) is refused before any folder is made.
        Some(n) if !rpod::reproduce::PAPERS.contains(&n.as_str()) => {
            eprintln!(
                "error: unknown paper `{}`; known: {}",
                n.escape_debug(),
                rpod::reproduce::PAPERS.join(", ")
            );
            return ExitCode::from(2);
        }
        Some(n) => vec![n],
        None => rpod::reproduce::PAPERS
            .iter()
            .map(|s| s.to_string())
            .collect(),
    };
    let mut failed = false;
    let bar = progress_bar(
        names.len() as u64,
        "{spinner} [{elapsed_precise}] {bar:20} {pos}/{len} papers  {msg}",
    );
    bar.enable_steady_tick(std::time::Duration::from_millis(200));
    // The papers are independent (each writes only its own folder, every run deterministic),
    // so they run side by side on the machine's cores, the longest first; each paper's lines
    // are printed together when it finishes.
    let workers = std::thread::available_parallelism()
        .map_or(1, |n| n.get())
        .min(names.len())
        .max(1);
    let mut order: Vec<&String> = names.iter().collect();
    order.sort_by_key(|n| {
        rpod::reproduce::TYPICAL_ORDER
            .iter()
            .position(|p| p == n)
            .unwrap_or(usize::MAX)
    });
    let next = std::sync::atomic::AtomicUsize::new(0);
    let running = std::sync::Mutex::new(Vec::<String>::new());
    let any_failed = std::sync::atomic::AtomicBool::new(false);
    std::thread::scope(|scope| {
        for _ in 0..workers {
            scope.spawn(|| {
                loop {
                    let k = next.fetch_add(1, std::sync::atomic::Ordering::SeqCst);
                    let Some(n) = order.get(k) else { break };
                    let show = |list: &Vec<String>| {
                        bar.set_message(format!("reproducing {}", list.join(", ")));
                    };
                    if let Ok(mut l) = running.lock() {
                        l.push(n.to_string());
                        show(&l);
                    }
                    let dir = out.join(n.as_str());
                    let r = rpod::reproduce::run(n, &dir);
                    if let Ok(mut l) = running.lock() {
                        l.retain(|x| x != n.as_str());
                        show(&l);
                    }
                    bar.inc(1);
                    if r.is_err() {
                        any_failed.store(true, std::sync::atomic::Ordering::SeqCst);
                    }
                    report_paper(&bar, n, &dir, r);
                }
            });
        }
    });
    failed |= any_failed.load(std::sync::atomic::Ordering::SeqCst);
    bar.finish_and_clear();
    // INDEX.md at the top of the output folder, rebuilt from the claims.json files there.
    match rpod::reproduce::write_index(out) {
        Ok(p) => out!("wrote {}", p.display()),
        Err(e) => {
            eprintln!("error: {e}");
            failed = true;
        }
    }
    if failed {
        ExitCode::from(1)
    } else {
        ExitCode::SUCCESS
    }
}
