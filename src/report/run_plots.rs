//! `rpod plot RUN_DIR`: the standard figures of a recorded run, from its `trajectory.csv`,
//! `contacts.csv` and `summary.json`, as PNG and SVG with the data behind each figure as CSV
//! beside it (so a user can restyle it without reading the run's files).
//!
//! Figures (each `NAME.png`, `NAME.svg`, `NAME.csv` in the output folder):
//! - `relative_position` — the chaser's centre of mass relative to the target's, in the
//!   target's body frame (x–y and x–z, equal aspect); with Hill-frame columns in the run
//!   (`NAME.hill_x_m …`) also in the reference orbit's Hill frame;
//! - `range` — range |r| and range rate ṙ = r·v/|r| over time;
//! - `clearance` — the monitor's minimum full-geometry distance and every guarantee's margin
//!   over time, with the zero line;
//! - `docking` — the docking state code (`dock.state`) and the summed contact force of each
//!   recorded row (from `contacts.csv`), when the run has a mechanism or contacts;
//! - `commands` — every controller column that is a force (`…force…_n`, `…_fx_n`) or a torque
//!   (`…torque…_nm`).
//!
//! The chaser and target are the bodies of those roles in the scene `summary.json` names
//! (loaded with the run's `--set` overrides); failing that, bodies named `chaser` and `target`,
//! else the first two bodies. Curves that can overlap are told apart by dashes as well as
//! colour; tick labels use the Unicode minus; units are in brackets after every axis name.

use super::{Dash, Figure, LineStyle, Plot};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// Opens a run's output file for reading: a regular file only (a link to `/dev/zero` or a FIFO
/// planted in a run folder is refused, not read), at most
/// [`super::fsio::MAX_OUTPUT_READ_BYTES`] read.
fn open_run_file(path: &Path) -> std::io::Result<std::io::Take<std::fs::File>> {
    use std::io::Read;
    Ok(super::fsio::open_regular(path, "run file")?.take(super::fsio::MAX_OUTPUT_READ_BYTES))
}

/// Columns of a CSV file, by header name (empty cells and text are NaN).
struct Table {
    names: Vec<String>,
    cols: Vec<Vec<f64>>,
}

impl Table {
    fn read(path: &Path) -> Result<Self, String> {
        let mut rdr = csv::Reader::from_reader(open_run_file(path).map_err(|e| e.to_string())?);
        let names: Vec<String> = rdr
            .headers()
            .map_err(|e| format!("{}: {e}", path.display()))?
            .iter()
            .map(str::to_string)
            .collect();
        let mut cols = vec![Vec::new(); names.len()];
        for r in rdr.records() {
            let r = r.map_err(|e| format!("{}: {e}", path.display()))?;
            for (c, v) in cols.iter_mut().zip(r.iter()) {
                c.push(v.parse().unwrap_or(f64::NAN));
            }
        }
        Ok(Self { names, cols })
    }
    fn col(&self, name: &str) -> Option<&[f64]> {
        self.names
            .iter()
            .position(|n| n == name)
            .map(|i| self.cols[i].as_slice())
    }
    fn text_col(path: &Path, name: &str) -> Vec<String> {
        let Ok(file) = open_run_file(path) else {
            return Vec::new();
        };
        let mut rdr = csv::Reader::from_reader(file);
        let Some(i) = rdr
            .headers()
            .ok()
            .and_then(|h| h.iter().position(|c| c == name))
        else {
            return Vec::new();
        };
        rdr.records()
            .filter_map(|r| r.ok().map(|r| r.get(i).unwrap_or("").to_string()))
            .collect()
    }
}

/// Line styles told apart by dash as well as colour: solid, dashed, dotted in turn.
fn style(k: usize) -> LineStyle {
    LineStyle {
        dash: [Dash::Solid, Dash::Dashed, Dash::Dotted][k % 3],
        ..LineStyle::default()
    }
}

/// Writes `name.png`, `name.svg` and `name.csv` (columns `header`, rows of `data`).
fn write(
    out: &Path,
    name: &str,
    fig: &Figure,
    header: &[String],
    data: &[Vec<f64>],
    written: &mut Vec<PathBuf>,
) -> Result<(), String> {
    let png = out.join(format!("{name}.png"));
    let svg = out.join(format!("{name}.svg"));
    fig.write_png(&png).map_err(|e| e.to_string())?;
    fig.write_svg(&svg).map_err(|e| e.to_string())?;
    let mut w = csv::WriterBuilder::new()
        .terminator(csv::Terminator::Any(b'\n'))
        .from_writer(Vec::new());
    w.write_record(header).map_err(|e| e.to_string())?;
    let n = data.first().map_or(0, Vec::len);
    for i in 0..n {
        w.write_record(data.iter().map(|c| {
            let v = c.get(i).copied().unwrap_or(f64::NAN);
            if v.is_finite() {
                format!("{v}")
            } else {
                String::new()
            }
        }))
        .map_err(|e| e.to_string())?;
    }
    let bytes = w.into_inner().map_err(|e| e.to_string())?;
    let csv_path = out.join(format!("{name}.csv"));
    super::write_atomic(&csv_path, &bytes).map_err(|e| e.to_string())?;
    written.extend([png, svg, csv_path]);
    Ok(())
}

/// (chaser, target) names for a run.
fn roles(dir: &Path, bodies: &[String]) -> (String, String) {
    let summary: Option<serde_json::Value> =
        super::fsio::read_regular_string(&dir.join("summary.json"), 64 << 20, "run summary")
            .ok()
            .and_then(|t| serde_json::from_str(&t).ok());
    if let Some(s) = &summary
        && let Some(file) = s["scene_file"].as_str()
    {
        let set: Vec<String> = s["provenance"]["set"]
            .as_array()
            .map(|a| {
                a.iter()
                    .filter_map(|v| v.as_str().map(str::to_string))
                    .collect()
            })
            .unwrap_or_default();
        if let Ok(l) = crate::scene::load_scene_file(Path::new(file), &set) {
            let find = |r: crate::scene::BodyRole| {
                l.scene
                    .bodies
                    .iter()
                    .find(|b| b.role == r)
                    .map(|b| b.name.clone())
            };
            if let (Some(c), Some(t)) = (
                find(crate::scene::BodyRole::Chaser),
                find(crate::scene::BodyRole::Target),
            ) {
                return (c, t);
            }
        }
    }
    let has = |n: &str| bodies.iter().any(|b| b == n);
    if has("chaser") && has("target") {
        return ("chaser".into(), "target".into());
    }
    (
        bodies.first().cloned().unwrap_or_default(),
        bodies.get(1).cloned().unwrap_or_default(),
    )
}
/// What the figure writers of [`plot_run`] share: the trajectory, its time column (s), the
/// run's label and the output folder.
struct Ctx<'a> {
    traj: &'a Table,
    t: Vec<f64>,
    run: String,
    out: &'a Path,
}

/// Draws the standard figures of the run in `dir` into `out` (created); returns the files.
pub fn plot_run(dir: &Path, out: &Path) -> Result<Vec<PathBuf>, String> {
    let traj = Table::read(&dir.join("trajectory.csv"))?;
    if std::fs::symlink_metadata(out).is_ok_and(|m| m.file_type().is_symlink()) {
        return Err(format!(
            "{} is a symbolic link: rpod writes plots only into a real folder; remove the link \
             or choose another --out",
            out.display()
        ));
    }
    std::fs::create_dir_all(out).map_err(|e| format!("{}: {e}", out.display()))?;
    let t = traj
        .col("t_s")
        .ok_or("trajectory.csv has no t_s column")?
        .to_vec();
    let bodies: Vec<String> = traj
        .names
        .iter()
        .filter_map(|n| n.strip_suffix(".px_m").map(str::to_string))
        .collect();
    let cx = Ctx {
        traj: &traj,
        t,
        run: dir.display().to_string(),
        out,
    };
    let mut written = Vec::new();
    if bodies.len() >= 2 {
        relative_figures(&cx, roles(dir, &bodies), &mut written)?;
    }
    clearance_figure(&cx, &mut written)?;
    docking_figure(&cx, dir, &mut written)?;
    commands_figure(&cx, &bodies, &mut written)?;
    Ok(written)
}

/// The chaser's position relative to the target in the target's body axes, range and range
/// rate, per sample: `cp` the chaser's [p m; v m/s] columns, `tp` the target's and its
/// attitude quaternion (w, x, y, z).
fn relative_state(
    t: &[f64],
    cp: &[Vec<f64>],
    tp: &[Vec<f64>],
) -> (Vec<Vec<f64>>, Vec<f64>, Vec<f64>) {
    let n = t.len();
    let mut body: Vec<Vec<f64>> = (0..3).map(|_| Vec::with_capacity(n)).collect();
    let (mut range, mut rate) = (Vec::with_capacity(n), Vec::with_capacity(n));
    for i in 0..n {
        let r = nalgebra::Vector3::new(
            cp[0][i] - tp[0][i],
            cp[1][i] - tp[1][i],
            cp[2][i] - tp[2][i],
        );
        let v = nalgebra::Vector3::new(
            cp[3][i] - tp[3][i],
            cp[4][i] - tp[4][i],
            cp[5][i] - tp[5][i],
        );
        let q = nalgebra::UnitQuaternion::from_quaternion(nalgebra::Quaternion::new(
            tp[6][i], tp[7][i], tp[8][i], tp[9][i],
        ));
        let rb = q.inverse() * r;
        for k in 0..3 {
            body[k].push(rb[k]);
        }
        range.push(r.norm());
        rate.push(if r.norm() > 0.0 {
            r.dot(&v) / r.norm()
        } else {
            f64::NAN
        });
    }
    (body, range, rate)
}

/// Relative state in the target's body frame (and the Hill frame when recorded), range and
/// range rate, when both bodies' states are recorded.
fn relative_figures(
    cx: &Ctx,
    (ch, tg): (String, String),
    written: &mut Vec<PathBuf>,
) -> Result<(), String> {
    let (traj, t, out) = (cx.traj, &cx.t, cx.out);
    let get = |b: &str, c: &str| traj.col(&format!("{b}.{c}")).map(<[f64]>::to_vec);
    let (Some(cp), Some(tp)) = (
        ["px_m", "py_m", "pz_m", "vx_m_s", "vy_m_s", "vz_m_s"]
            .iter()
            .map(|c| get(&ch, c))
            .collect::<Option<Vec<_>>>(),
        [
            "px_m", "py_m", "pz_m", "vx_m_s", "vy_m_s", "vz_m_s", "qw", "qx", "qy", "qz",
        ]
        .iter()
        .map(|c| get(&tg, c))
        .collect::<Option<Vec<_>>>(),
    ) else {
        return Ok(());
    };
    let (body, range, rate) = relative_state(t, &cp, &tp);
    relative_position_figure(cx, (&ch, &tg), &body, written)?;
    let run = &cx.run;
    let fig = Figure::new(format!("{run}: range and range rate, {ch} to {tg}"))
        .cols(1)
        .plot(
            Plot::new("range (centres of mass)")
                .x_label("t [s]")
                .y_label("range [m]")
                .line("|r|", t.iter().copied().zip(range.iter().copied())),
        )
        .plot(
            Plot::new("range rate")
                .x_label("t [s]")
                .y_label("range rate [m/s]")
                .hline(0.0, "0")
                .line("ṙ = r·v/|r|", t.iter().copied().zip(rate.iter().copied())),
        );
    write(
        out,
        "range",
        &fig,
        &["t_s", "range_m", "range_rate_m_s"].map(String::from),
        &[t.clone(), range, rate],
        written,
    )?;
    Ok(())
}

/// The chaser's path in the target's body frame, and in the Hill frame when recorded.
fn relative_position_figure(
    cx: &Ctx,
    (ch, tg): (&str, &str),
    body: &[Vec<f64>],
    written: &mut Vec<PathBuf>,
) -> Result<(), String> {
    let (traj, t, run, out) = (cx.traj, &cx.t, &cx.run, cx.out);
    let get = |b: &str, c: &str| traj.col(&format!("{b}.{c}")).map(<[f64]>::to_vec);
    let xy = |a: usize, b: usize| body[a].iter().copied().zip(body[b].iter().copied());
    let mut fig = Figure::new(format!("{run}: {ch} relative to {tg}"))
        .cols(2)
        .plot(
            Plot::new(format!("{tg} body frame, x–y"))
                .x_label("x [m]")
                .y_label("y [m]")
                .equal_aspect()
                .line(format!("{ch} centre of mass"), xy(0, 1))
                .scatter("start", xy(0, 1).take(1)),
        )
        .plot(
            Plot::new(format!("{tg} body frame, x–z"))
                .x_label("x [m]")
                .y_label("z [m]")
                .equal_aspect()
                .line(format!("{ch} centre of mass"), xy(0, 2))
                .scatter("start", xy(0, 2).take(1)),
        );
    let mut header: Vec<String> = ["t_s", "x_body_m", "y_body_m", "z_body_m"]
        .map(String::from)
        .to_vec();
    let mut data = vec![t.clone(), body[0].clone(), body[1].clone(), body[2].clone()];
    let hill: Option<Vec<Vec<f64>>> = ["hill_x_m", "hill_y_m", "hill_z_m"]
        .iter()
        .map(|c| Some((get(ch, c)?, get(tg, c)?)))
        .map(|p| p.map(|(a, b)| a.iter().zip(&b).map(|(x, y)| x - y).collect()))
        .collect();
    if let Some(h) = hill {
        let hp = |a: usize, b: usize| h[a].iter().copied().zip(h[b].iter().copied());
        fig.push(
            Plot::new("Hill frame, y (along-track) – x (radial)")
                .x_label("y along-track [m]")
                .y_label("x radial [m]")
                .equal_aspect()
                .line(format!("{ch} − {tg}"), hp(1, 0)),
        );
        fig.push(
            Plot::new("Hill frame, y (along-track) – z (normal)")
                .x_label("y along-track [m]")
                .y_label("z normal [m]")
                .equal_aspect()
                .line(format!("{ch} − {tg}"), hp(1, 2)),
        );
        header.extend(["x_hill_m", "y_hill_m", "z_hill_m"].map(String::from));
        data.extend(h);
    }
    write(out, "relative_position", &fig, &header, &data, written)?;
    Ok(())
}

/// Minimum distance and guarantee margins.
fn clearance_figure(cx: &Ctx, written: &mut Vec<PathBuf>) -> Result<(), String> {
    let (traj, t, run, out) = (cx.traj, &cx.t, &cx.run, cx.out);
    let mut p = Plot::new("minimum distance and guarantee margins")
        .x_label("t [s]")
        .y_label("distance, margin [m]")
        .hline(0.0, "0");
    let mut header = vec!["t_s".to_string()];
    let mut data = vec![t.clone()];
    let mut k = 0;
    for (i, n) in traj.names.iter().enumerate() {
        let label = if n == "min_distance_m" {
            Some("minimum distance (full geometry)".to_string())
        } else {
            n.strip_prefix("guarantee.")
                .map(|g| format!("margin of {g}"))
        };
        if let Some(label) = label {
            let pts = t.iter().copied().zip(traj.cols[i].iter().copied());
            p = p.line_styled(label, pts, style(k));
            k += 1;
            header.push(n.clone());
            data.push(traj.cols[i].clone());
        }
    }
    if k > 0 {
        let fig = Figure::new(format!("{run}: clearance")).cols(1).plot(p);
        write(out, "clearance", &fig, &header, &data, written)?;
    }
    Ok(())
}

/// Docking state and contact forces.
fn docking_figure(cx: &Ctx, dir: &Path, written: &mut Vec<PathBuf>) -> Result<(), String> {
    let (traj, t, run, out) = (cx.traj, &cx.t, &cx.run, cx.out);
    let contacts = dir.join("contacts.csv");
    let mut force_by_t: BTreeMap<u64, f64> = BTreeMap::new();
    if contacts.exists() {
        let ts = Table::text_col(&contacts, "t_s");
        let fs = Table::text_col(&contacts, "force_n");
        for (a, b) in ts.iter().zip(&fs) {
            if let (Ok(a), Ok(b)) = (a.parse::<f64>(), b.parse::<f64>()) {
                *force_by_t.entry(a.to_bits()).or_default() += b;
            }
        }
    }
    let state = traj.col("dock.state");
    if state.is_some() || !force_by_t.is_empty() {
        let force: Vec<f64> = t
            .iter()
            .map(|x| force_by_t.get(&x.to_bits()).copied().unwrap_or(0.0))
            .collect();
        let mut fig = Figure::new(format!("{run}: docking and contact")).cols(1);
        if let Some(s) = state {
            fig.push(
                Plot::new(state_legend(s))
                    .x_label("t [s]")
                    .y_label("state code")
                    .line("dock.state", t.iter().copied().zip(s.iter().copied())),
            );
        }
        fig.push(
            Plot::new("contact force (all part pairs, mean over each recorded row)")
                .x_label("t [s]")
                .y_label("force [N]")
                .line("Σ force_n", t.iter().copied().zip(force.iter().copied())),
        );
        let mut header = vec!["t_s".to_string(), "contact_force_n".to_string()];
        let mut data = vec![t.clone(), force];
        if let Some(s) = state {
            header.push("dock.state".into());
            data.push(s.to_vec());
        }
        write(out, "docking", &fig, &header, &data, written)?;
    }
    Ok(())
}

/// Commanded forces and torques: the recorded columns that are not body states.
fn commands_figure(cx: &Ctx, bodies: &[String], written: &mut Vec<PathBuf>) -> Result<(), String> {
    let (traj, t, run, out) = (cx.traj, &cx.t, &cx.run, cx.out);
    let is_state = |n: &str| bodies.iter().any(|b| n.starts_with(&format!("{b}.")));
    let mut forces = Plot::new("forces").x_label("t [s]").y_label("force [N]");
    let mut torques = Plot::new("torques")
        .x_label("t [s]")
        .y_label("torque [N·m]");
    let (mut nf, mut nt) = (0, 0);
    let mut header = vec!["t_s".to_string()];
    let mut data = vec![t.clone()];
    for (i, n) in traj.names.iter().enumerate() {
        if is_state(n) || n.starts_with("dock.") || traj.cols[i].iter().all(|v| !v.is_finite()) {
            continue;
        }
        let pts = t.iter().copied().zip(traj.cols[i].iter().copied());
        if n.ends_with("_n") && (n.contains("force") || n.contains("_f")) {
            forces = forces.line_styled(n.clone(), pts, style(nf));
            nf += 1;
        } else if n.contains("torque") && n.ends_with("_nm") {
            torques = torques.line_styled(n.clone(), pts, style(nt));
            nt += 1;
        } else {
            continue;
        }
        header.push(n.clone());
        data.push(traj.cols[i].clone());
    }
    if nf + nt > 0 {
        let mut fig = Figure::new(format!("{run}: controller forces and torques")).cols(1);
        if nf > 0 {
            fig.push(forces);
        }
        if nt > 0 {
            fig.push(torques);
        }
        write(out, "commands", &fig, &header, &data, written)?;
    }
    Ok(())
}

/// The docking-state plot's title: every state code the run's `dock.state` column holds, with
/// its name from [`crate::contact::dock_state::DockState`] (the one definition of the codes), in code
/// order, e.g. `docking state (0 FREE, 2 CONTACT, 9 SOFT_CAPTURED)`. A code that is no state
/// (a file from another version) is shown with `?`; non-finite values are skipped.
pub fn state_legend(codes: &[f64]) -> String {
    use crate::contact::dock_state::DockState;
    let mut seen: Vec<f64> = codes.iter().copied().filter(|c| c.is_finite()).collect();
    seen.sort_by(f64::total_cmp);
    seen.dedup();
    let labels: Vec<String> = seen
        .iter()
        .map(|&c| match DockState::from_code(c) {
            Some(s) => format!("{c} {}", s.name()),
            None => format!("{c} ?"),
        })
        .collect();
    if labels.is_empty() {
        "docking state".into()
    } else {
        format!("docking state ({})", labels.join(", "))
    }
}

#[cfg(test)]
mod tests {
    //! The docking-state legend against the state list itself ([`DockState::ALL`], where the
    //! codes are defined): every state code gets its own name.
    use super::state_legend;
    use crate::contact::dock_state::DockState;

    #[test]
    fn every_state_code_has_a_label() {
        for s in DockState::ALL {
            assert_eq!(
                state_legend(&[s.code()]),
                format!("docking state ({} {})", s.code(), s.name())
            );
        }
        let all: Vec<f64> = DockState::ALL.iter().rev().map(|s| s.code()).collect();
        let legend = state_legend(&all);
        for s in DockState::ALL {
            assert!(
                legend.contains(&format!("{} {}", s.code(), s.name())),
                "{legend}"
            );
        }
        assert!(!legend.contains('?'), "{legend}");
    }

    #[test]
    fn a_soft_capture_run_is_labelled_in_code_order() {
        let codes = [0.0, 0.0, 2.0, 9.0, 9.0, 10.0, 11.0, f64::NAN];
        assert_eq!(
            state_legend(&codes),
            "docking state (0 FREE, 2 CONTACT, 9 SOFT_CAPTURED, 10 RETRACTED, 11 HARD_DOCKED)"
        );
        assert_eq!(
            state_legend(&[4.0, 99.0]),
            "docking state (4 LATCHED, 99 ?)"
        );
        assert_eq!(state_legend(&[f64::NAN]), "docking state");
    }
}
