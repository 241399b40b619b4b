//! The output contract: `trajectory.csv`, `events.jsonl`, `summary.json`, `contacts.csv`
//! (per recorded row, each part pair's mean normal contact force since the previous row) and,
//! on request (`rpod run --contact-points`), `contact_points.csv` (every contact point at every
//! step, and every sub-step of the compliant docking contact: the full-rate contact force
//! history; tens of MB for a run that stays in contact for tens of seconds).
//!
//! All are written under a temporary name (`NAME.partial`) and renamed when the run
//! finishes, `summary.json` last, so a crash never leaves a file that looks whole: a folder
//! without `summary.json` holds no complete run. Numbers are printed in Rust's shortest
//! round-trip form, so the same run gives byte-identical files. A controller or mechanism
//! column that is undefined at a row (NaN) is an empty cell; no output holds a NaN (the
//! finiteness guard, [`super::guard`], stops a run before anything non-finite is written).
//!
//! # The output folder
//! - One writer at a time: a run holds an exclusive lock on `DIR/.rpod.lock` (an OS file lock,
//!   released by the kernel when the process ends, even by `kill -9`) for as long as it
//!   writes; a second `rpod run` or `rpod trials` into the same folder is refused
//!   ([`EXIT_FOLDER_IN_USE`]) with the holder's process id.
//! - Nothing stale: once it holds the lock, a run deletes every file an earlier run wrote
//!   there ([`RUN_FILES`], complete or `.partial`) before it writes its own, so a run killed at
//!   any point leaves only `.partial` files, never an older run's complete files beside them.
//!   Other files in the folder are left alone. Files are created new (a symlink planted under
//!   one of these names is removed, not followed).
//! - The default folder is `out/<name>` with the scene name made safe ([`safe_dir_name`]): a
//!   name never leads outside `out/`.

use super::monitor::{ContactState, CumulativeImpulse};
use super::{BodyState, Clock, EventLog, Guarantees, MonitorState, Roster, SimBody};
use bevy::prelude::*;
use std::collections::BTreeMap;
use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

/// Extra per-step columns published by controllers and mechanisms (name with unit suffix).
#[derive(Resource, Debug, Default, Clone)]
pub struct Diagnostics {
    /// Column names, e.g. `ctrl.h` or `dock.gap_m`.
    pub names: Vec<String>,
    /// Current values, same order.
    pub values: Vec<f64>,
    /// Index of each name in `names` (registration stays linear in the number of columns:
    /// a scene with tens of thousands of controllers is checked in seconds, not hours).
    index: std::collections::HashMap<String, usize>,
}

impl Diagnostics {
    /// Registers a column and returns its index (registering twice returns the same index).
    pub fn column(&mut self, name: &str) -> usize {
        if let Some(&i) = self.index.get(name) {
            return i;
        }
        self.index.insert(name.to_string(), self.names.len());
        self.names.push(name.to_string());
        self.values.push(f64::NAN);
        self.names.len() - 1
    }

    /// Whether a column of this name is registered.
    pub fn contains(&self, name: &str) -> bool {
        self.index.contains_key(name)
    }
}

/// Exit code of a command refused because another rpod process writes into its output folder.
pub const EXIT_FOLDER_IN_USE: u8 = 4;

/// The files a run writes into its folder (each also as `NAME.partial` while it runs): deleted
/// when a new run starts there.
pub const RUN_FILES: [&str; 5] = FILES;

/// An exclusive lock on an output folder (`DIR/.rpod.lock`), held until dropped.
#[derive(Debug)]
pub struct FolderLock {
    _file: File,
    /// The folder.
    pub dir: PathBuf,
}

impl FolderLock {
    /// Creates `dir` if needed and locks it. A folder another process holds gives an error of
    /// kind [`std::io::ErrorKind::WouldBlock`] whose message names the holder.
    pub fn acquire(dir: &Path) -> std::io::Result<Self> {
        use std::io::{Read, Seek};
        std::fs::create_dir_all(dir)?;
        let path = dir.join(".rpod.lock");
        // A link planted at `.rpod.lock` is refused, not followed (truncating its target).
        let mut file = crate::report::fsio::open_write_nofollow(
            &path,
            std::fs::OpenOptions::new()
                .read(true)
                .create(true)
                .truncate(false),
        )?;
        match file.try_lock() {
            Ok(()) => {}
            Err(std::fs::TryLockError::WouldBlock) => {
                let mut holder = String::new();
                let _ = file.read_to_string(&mut holder);
                return Err(std::io::Error::new(
                    std::io::ErrorKind::WouldBlock,
                    format!(
                        "{} is in use by another rpod process ({}); wait for it to finish or \
                         choose another --out",
                        dir.display(),
                        holder.trim().chars().take(200).collect::<String>()
                    ),
                ));
            }
            Err(std::fs::TryLockError::Error(e)) => return Err(e),
        }
        file.set_len(0)?;
        file.seek(std::io::SeekFrom::Start(0))?;
        writeln!(file, "pid {}", std::process::id())?;
        file.flush()?;
        Ok(Self {
            _file: file,
            dir: dir.to_path_buf(),
        })
    }

    /// Deletes `names` and their `.partial` files from the folder (a symlink is removed, not
    /// followed).
    pub fn clear(&self, names: &[&str]) -> std::io::Result<()> {
        for n in names {
            for p in [self.dir.join(n), partial(&self.dir, n)] {
                match std::fs::remove_file(&p) {
                    Ok(()) => {}
                    Err(e) if e.kind() == std::io::ErrorKind::NotFound => {}
                    Err(e) => {
                        return Err(std::io::Error::new(
                            e.kind(),
                            format!("cannot remove the earlier run's {}: {e}", p.display()),
                        ));
                    }
                }
            }
        }
        Ok(())
    }
}

/// A file name made from a scene or campaign name: ASCII letters, digits, `_`, `-` and `.`
/// kept, anything else (`/`, `\`, spaces, control characters, non-ASCII) replaced by `_`,
/// leading dots removed (no `..`, no hidden folder), at most 64 characters; `unnamed` if
/// nothing is left. Used for the default output folders `out/<name>`.
pub fn safe_dir_name(name: &str) -> String {
    let s: String = name
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || matches!(c, '_' | '-' | '.') {
                c
            } else {
                '_'
            }
        })
        .collect();
    let s: String = s.trim_start_matches('.').chars().take(64).collect();
    if s.is_empty() { "unnamed".into() } else { s }
}

/// Creates a new file: fails if something (a file, a planted symlink) is already there.
fn create_new(path: &Path) -> std::io::Result<File> {
    crate::report::fsio::create_new_nofollow(path)
        .map_err(|e| std::io::Error::new(e.kind(), format!("{}: {e}", path.display())))
}

/// Open output files of a run.
pub struct OutputFiles {
    /// Output directory.
    pub dir: PathBuf,
    traj: BufWriter<File>,
    events: BufWriter<File>,
    contacts: BufWriter<File>,
    points: Option<BufWriter<File>>,
    lock: Option<FolderLock>,
}

/// The output files, in the order they are renamed into place.
const FILES: [&str; 5] = [
    "trajectory.csv",
    "events.jsonl",
    "contacts.csv",
    "contact_points.csv",
    "summary.json",
];

/// Header of `contact_points.csv`.
pub const CONTACT_POINTS_HEADER: &str = "t_s,a,b,model,px_m,py_m,pz_m,nx_b,ny_b,nz_b,depth_m,normal_force_n,normal_impulse_ns,fx_b_n,fy_b_n,fz_b_n";

/// Header of `contacts.csv`.
pub const CONTACTS_HEADER: &str =
    "t_s,a,b,docking,force_n,impulse_ns,jx_b_ns,jy_b_ns,jz_b_ns,in_contact";

/// The recorder resource.
#[derive(Resource)]
pub struct Recorder {
    /// Write a row every this many steps.
    pub every: u32,
    /// Files, when recording to disk.
    pub files: Option<OutputFiles>,
    /// Events already written.
    pub events_written: usize,
    /// Rows written.
    pub rows: u64,
    /// Step of the last row written.
    pub last_row_step: Option<u64>,
    /// First I/O error, if any (reported when the run finishes).
    pub error: Option<String>,
    /// All events of the run (kept for tests and the summary).
    pub history: Vec<super::Event>,
    /// Write a row at the next record call whatever the step.
    pub force_row: bool,
    /// Time of the last row written, s.
    pub last_row_t_s: Option<f64>,
    /// Each part pair's cumulative contact impulse at the last row written.
    pub contact_impulse_at_row: BTreeMap<(String, String), CumulativeImpulse>,
    /// Body pairs with a `distance.A.B_m` column (see [`pair_columns`]).
    pub pair_columns: Vec<(usize, usize)>,
    /// Write `contact_points.csv` (set before recording starts).
    pub contact_points: bool,
}

const STATE_COLS: [&str; 13] = [
    "px_m", "py_m", "pz_m", "vx_m_s", "vy_m_s", "vz_m_s", "qw", "qx", "qy", "qz", "wx_rad_s",
    "wy_rad_s", "wz_rad_s",
];

fn partial(dir: &Path, name: &str) -> PathBuf {
    dir.join(format!("{name}.partial"))
}

impl OutputFiles {
    /// Locks the directory (creating it), deletes an earlier run's files there and creates
    /// the temporary files (`contact_points.csv` if `points`; see the module docs).
    pub fn create(dir: &Path, points: bool) -> std::io::Result<Self> {
        let lock = FolderLock::acquire(dir)?;
        lock.clear(&RUN_FILES)?;
        Self::create_locked(dir, Some(lock), points)
    }

    /// Creates the temporary files in a folder the caller has locked and cleared (a trial of
    /// `rpod trials --keep-runs` writes into a folder of the campaign's locked output).
    pub fn create_locked(
        dir: &Path,
        lock: Option<FolderLock>,
        points: bool,
    ) -> std::io::Result<Self> {
        std::fs::create_dir_all(dir)?;
        for n in RUN_FILES {
            let _ = std::fs::remove_file(partial(dir, n));
        }
        let mut contacts = BufWriter::new(create_new(&partial(dir, "contacts.csv"))?);
        writeln!(contacts, "{CONTACTS_HEADER}")?;
        let points = if points {
            let mut w = BufWriter::new(create_new(&partial(dir, "contact_points.csv"))?);
            writeln!(w, "{CONTACT_POINTS_HEADER}")?;
            Some(w)
        } else {
            None
        };
        Ok(Self {
            dir: dir.to_path_buf(),
            traj: BufWriter::new(create_new(&partial(dir, "trajectory.csv"))?),
            events: BufWriter::new(create_new(&partial(dir, "events.jsonl"))?),
            contacts,
            points,
            lock,
        })
    }

    /// Flushes the temporary files and leaves them as `.partial` (a run the guard stopped:
    /// the rows up to the last good step, and no summary).
    pub fn keep_partial(mut self) -> std::io::Result<()> {
        self.traj.flush()?;
        self.events.flush()?;
        self.contacts.flush()?;
        if let Some(p) = self.points.as_mut() {
            p.flush()?;
        }
        Ok(())
    }

    /// Flushes, writes the summary and renames the files into place.
    pub fn finish(mut self, summary: &serde_json::Value) -> std::io::Result<()> {
        self.traj.flush()?;
        self.events.flush()?;
        self.contacts.flush()?;
        if let Some(p) = self.points.as_mut() {
            p.flush()?;
        }
        let points = self.points.is_some();
        drop(self.traj);
        drop(self.events);
        drop(self.contacts);
        drop(self.points);
        let s = serde_json::to_string_pretty(summary).map_err(std::io::Error::other)?;
        let mut f = create_new(&partial(&self.dir, "summary.json"))?;
        f.write_all((s + "\n").as_bytes())?;
        f.sync_all()?;
        drop(f);
        for n in FILES {
            if n != "contact_points.csv" || points {
                std::fs::rename(partial(&self.dir, n), self.dir.join(n))?;
            }
        }
        drop(self.lock);
        Ok(())
    }

    /// Removes the temporary files (after a failure).
    pub fn abandon(self) {
        let dir = self.dir.clone();
        drop(self);
        for n in FILES {
            let _ = std::fs::remove_file(partial(&dir, n));
        }
    }
}

/// Columns of the reference orbit's ECI state (orbit scenes), after every other column.
const REF_COLS: [&str; 6] = ["rx_m", "ry_m", "rz_m", "vx_m_s", "vy_m_s", "vz_m_s"];

/// Columns of a body's state in the reference orbit's rotating Hill frame (orbit scenes).
const HILL_COLS: [&str; 6] = [
    "hill_x_m",
    "hill_y_m",
    "hill_z_m",
    "hill_vx_m_s",
    "hill_vy_m_s",
    "hill_vz_m_s",
];

/// The body pairs that get a `distance.A.B_m` column: every pair when the monitor tracks every
/// pair and there are more than two bodies; with a horizon (many bodies), only the pairs a
/// guarantee names — the others go to `pairs.csv` while they are within the horizon.
pub fn pair_columns(n: usize, all_pairs: bool, named: &[(usize, usize)]) -> Vec<(usize, usize)> {
    if all_pairs {
        if n > 2 {
            (0..n)
                .flat_map(|i| (i + 1..n).map(move |j| (i, j)))
                .collect()
        } else {
            Vec::new()
        }
    } else {
        named.to_vec()
    }
}

/// The CSV header for the current roster, pair columns, guarantees and diagnostics. `orbit`:
/// the scene is in orbit (then the reference orbit's ECI state `ref.*` and each body's
/// Hill-frame state `NAME.hill_*` end the row).
pub fn header(
    roster: &Roster,
    pairs: &[(usize, usize)],
    g: &Guarantees,
    diag: &Diagnostics,
    orbit: bool,
) -> String {
    let mut cols = vec!["t_s".to_string()];
    for name in &roster.names {
        for c in STATE_COLS {
            cols.push(format!("{name}.{c}"));
        }
    }
    cols.push("min_distance_m".into());
    cols.push("closest_parts".into());
    for (i, j) in pairs {
        cols.push(format!(
            "distance.{}.{}_m",
            roster.names[*i], roster.names[*j]
        ));
    }
    for s in &g.status {
        cols.push(format!("guarantee.{}.margin_{}", s.name, s.unit));
    }
    cols.extend(diag.names.iter().cloned());
    if orbit {
        cols.extend(REF_COLS.iter().map(|c| format!("ref.{c}")));
        for name in &roster.names {
            cols.extend(HILL_COLS.iter().map(|c| format!("{name}.{c}")));
        }
    }
    cols.join(",")
}

/// The reference orbit's ECI state and every body's state relative to it in its rotating
/// Hill frame (x radial out, y along-track, z orbit normal; velocity seen in the rotating
/// frame, ρ̇_H = C (ρ̇ − ω × ρ) with ω = r × v / |r|²), for the row.
fn orbit_values(orbit: &super::OrbitEnv, states: &[(&SimBody, &BodyState)]) -> Vec<f64> {
    use crate::orbit::lvlh::{LocalFrame, LocalFrameKind};
    let (r, v) = orbit.reference.state();
    let f = LocalFrame::new(LocalFrameKind::Hill, &r, &v);
    let mut out = Vec::with_capacity(6 + 6 * states.len());
    out.extend(r.iter().chain(v.iter()));
    for (_, s) in states {
        let (p, q) = f.to_local(&s.pos_m, &s.vel_m_s);
        out.extend(p.iter().chain(q.iter()));
    }
    out
}

/// Writes one row to `w`.
/// An f64 written exactly as Rust's `Display` writes it (the shortest digits that read back to
/// the same value, in plain decimal notation: `2070`, `0.0000008779485369814211`, `-0`, `NaN`,
/// `inf`), from ryu's shortest digits: both give the shortest round-trip digits, the closest to
/// the value where several are shortest, and differ only where two are equally close (ryu then
/// takes the even one, `Display` rounds up: 1690060720831323.25). Such a tie needs the value's
/// exact decimal expansion to be at most 18 digits long; those values (integers, and m·2⁻ˢ with
/// m·5ˢ < 10¹⁸) go to `Display` itself. The unit test compares the two on two million values.
/// A third of `Display`'s cost in a trajectory row.
pub struct Plain(pub f64);

/// The exact decimal expansion of finite `v` has at most 18 significant digits.
fn short_expansion(v: f64) -> bool {
    let bits = v.to_bits();
    let exp_bits = ((bits >> 52) & 0x7ff) as i32;
    let frac = bits & ((1u64 << 52) - 1);
    let (mut m, mut e) = if exp_bits == 0 {
        (frac, -1074)
    } else {
        (frac | (1u64 << 52), exp_bits - 1075)
    };
    if m == 0 {
        return true;
    }
    let tz = m.trailing_zeros();
    m >>= tz;
    e += tz as i32;
    if e >= 0 {
        return true; // an integer
    }
    let s = -e;
    if s > 27 {
        return false; // 5^28 > 10^18
    }
    u128::from(m) * 5u128.pow(s as u32) < 1_000_000_000_000_000_000u128
}

impl std::fmt::Display for Plain {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let v = self.0;
        if !v.is_finite() || short_expansion(v) {
            return write!(f, "{v}");
        }
        if v.is_sign_negative() {
            f.write_str("-")?;
        }
        let mut buf = ryu::Buffer::new();
        let s = buf.format_finite(v.abs());
        // ryu writes `I.F` or `I.Fe±X` / `Ie±X`: the digits I F and the decimal point's place.
        let (mant, exp) = match s.split_once('e') {
            Some((m, e)) => (m, e.parse::<i32>().unwrap_or(0)),
            None => (s, 0),
        };
        let (int, frac) = mant.split_once('.').unwrap_or((mant, ""));
        let mut digits = [0u8; 40];
        let mut n = 0;
        for c in int.bytes().chain(frac.bytes()) {
            if n < digits.len() {
                digits[n] = c;
                n += 1;
            }
        }
        let mut point = int.len() as i32 + exp;
        let mut start = 0;
        while start + 1 < n && digits[start] == b'0' {
            start += 1;
            point -= 1;
        }
        while n > start + 1 && digits[n - 1] == b'0' {
            n -= 1;
        }
        let d = &digits[start..n];
        if d == b"0" {
            return f.write_str("0");
        }
        fn text(b: &[u8]) -> &str {
            std::str::from_utf8(b).unwrap_or("")
        }
        let len = d.len() as i32;
        if point <= 0 {
            f.write_str("0.")?;
            for _ in 0..-point {
                f.write_str("0")?;
            }
            f.write_str(text(d))
        } else if point >= len {
            f.write_str(text(d))?;
            for _ in 0..point - len {
                f.write_str("0")?;
            }
            Ok(())
        } else {
            let p = point as usize;
            f.write_str(text(&d[..p]))?;
            f.write_str(".")?;
            f.write_str(text(&d[p..]))
        }
    }
}

#[allow(clippy::too_many_arguments)]
fn write_row(
    w: &mut impl Write,
    t_s: f64,
    states: &[(&SimBody, &BodyState)],
    pair_cols: &[(usize, usize)],
    mon: &MonitorState,
    g: &Guarantees,
    diag: &Diagnostics,
    orbit: Option<&super::OrbitEnv>,
) -> std::io::Result<()> {
    write!(w, "{}", Plain(t_s))?;
    for (_, s) in states {
        let q = s.att.quaternion();
        for v in [
            s.pos_m.x,
            s.pos_m.y,
            s.pos_m.z,
            s.vel_m_s.x,
            s.vel_m_s.y,
            s.vel_m_s.z,
            q.w,
            q.i,
            q.j,
            q.k,
            s.omega_rad_s.x,
            s.omega_rad_s.y,
            s.omega_rad_s.z,
        ] {
            write!(w, ",{}", Plain(v))?;
        }
    }
    match &mon.closest {
        Some(p) => {
            let (a, b) = mon.pair_names(p);
            write!(w, ",{},{a}|{b}", Plain(p.distance_m))?
        }
        None => write!(w, ",,")?,
    }
    for ij in pair_cols {
        match mon.pair_index.get(ij) {
            Some(k) => write!(w, ",{}", Plain(mon.pairs[*k].distance_m))?,
            None => write!(w, ",")?,
        }
    }
    for s in &g.status {
        write!(w, ",{}", Plain(s.last_margin))?;
    }
    for v in &diag.values {
        if v.is_nan() {
            write!(w, ",")?;
        } else {
            write!(w, ",{}", Plain(*v))?;
        }
    }
    if let Some(o) = orbit {
        for v in orbit_values(o, states) {
            write!(w, ",{}", Plain(v))?;
        }
    }
    writeln!(w)
}

/// Writes one `contacts.csv` line per part pair whose cumulative impulse grew since the last
/// row or that is in contact now: the mean normal force over the interval (ΔJ / Δt, N), the
/// impulse magnitude ΔJ (N·s), the impulse vector on the second part (world frame, N·s), and
/// whether the pair touches at `t_s`. The differences telescope: summed over a run they give
/// each pair's totals.
fn write_contacts(
    w: &mut impl Write,
    t_s: f64,
    since_s: f64,
    cs: &ContactState,
    at_row: &BTreeMap<(String, String), CumulativeImpulse>,
) -> std::io::Result<()> {
    let span_s = t_s - since_s;
    if span_s <= 0.0 {
        return Ok(());
    }
    let zero = CumulativeImpulse::default();
    for (k, cum) in &cs.cumulative_impulse_ns {
        let before = at_row.get(k).unwrap_or(&zero);
        let in_contact = cs.active.contains_key(k);
        let dj = cum.magnitude_ns - before.magnitude_ns;
        let jb = cum.on_b_ns - before.on_b_ns;
        if dj > 0.0 || in_contact {
            writeln!(
                w,
                "{t_s},{},{},{},{},{dj},{},{},{},{in_contact}",
                k.0,
                k.1,
                cum.docking,
                dj / span_s,
                jb.x,
                jb.y,
                jb.z
            )?;
        }
    }
    Ok(())
}

/// Writes one `contact_points.csv` line per contact point of the last step.
fn write_points(w: &mut impl Write, cs: &ContactState) -> std::io::Result<()> {
    for p in &cs.points {
        let (x, n, f) = (&p.point_m, &p.normal_on_b, &p.force_on_b_n);
        writeln!(
            w,
            "{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{}",
            p.t_s,
            p.a,
            p.b,
            if p.compliant { "compliant" } else { "rigid" },
            x.x,
            x.y,
            x.z,
            n.x,
            n.y,
            n.z,
            p.depth_m,
            p.normal_force_n,
            p.normal_impulse_ns,
            f.x,
            f.y,
            f.z
        )?;
    }
    Ok(())
}

/// Writes the current state as a row (and pending events) now, whatever the step.
pub fn record_now(world: &mut World) {
    use bevy::ecs::system::RunSystemOnce;
    world.resource_mut::<Recorder>().force_row = true;
    world
        .run_system_once(record)
        .expect("the record system's resources exist");
}

/// Writes the step's pending events to `events.jsonl` and keeps them in the history. Events are
/// few: each step's reach the (still temporary) file at once, so a run that is stopped or still
/// running shows what has happened so far (a whole run's 1.7 KiB of events used to sit in the
/// 8 KiB write buffer until the end, and a stopped run looked as if nothing had happened).
fn write_events(rec: &mut Recorder, log: &mut EventLog) {
    if log.pending.is_empty() {
        return;
    }
    let pending: Vec<super::Event> = std::mem::take(&mut log.pending);
    if let Some(files) = rec.files.as_mut() {
        for e in &pending {
            let line = serde_json::to_string(e).expect("event serialises");
            if let Err(err) = writeln!(files.events, "{line}") {
                rec.error.get_or_insert(err.to_string());
            }
        }
        if let Err(err) = files.events.flush() {
            rec.error.get_or_insert(err.to_string());
        }
    }
    rec.history.extend(pending);
}

#[allow(clippy::too_many_arguments)]
fn write_step(
    rec: &mut Recorder,
    step: u64,
    t: f64,
    states: &[(&SimBody, &BodyState)],
    mon: &MonitorState,
    g: &Guarantees,
    diag: &Diagnostics,
    log: &mut EventLog,
    cs: &ContactState,
    orbit: Option<&super::OrbitEnv>,
) {
    write_events(rec, log);
    rec.events_written = rec.history.len();
    if rec.last_row_step == Some(step) {
        return;
    }
    if let Some(files) = rec.files.as_mut()
        && let Err(err) = write_row(
            &mut files.traj,
            t,
            states,
            &rec.pair_columns,
            mon,
            g,
            diag,
            orbit,
        )
    {
        rec.error.get_or_insert(err.to_string());
    }
    if let (Some(files), Some(since)) = (rec.files.as_mut(), rec.last_row_t_s)
        && let Err(err) = write_contacts(
            &mut files.contacts,
            t,
            since,
            cs,
            &rec.contact_impulse_at_row,
        )
    {
        rec.error.get_or_insert(err.to_string());
    }
    rec.contact_impulse_at_row.clear();
    rec.contact_impulse_at_row.extend(
        cs.cumulative_impulse_ns
            .iter()
            .map(|(k, c)| (k.clone(), c.clone())),
    );
    rec.last_row_t_s = Some(t);
    rec.rows += 1;
    rec.last_row_step = Some(step);
}

/// Run condition of [`record`]: a row is due (or forced), contact points are written at full
/// rate, or events are pending — everything `record` does; on the other steps it would do
/// nothing, and not running it saves its resource fetches.
pub fn record_wanted(clock: Res<Clock>, rec: Res<Recorder>, log: Res<EventLog>) -> bool {
    clock.step.is_multiple_of(u64::from(rec.every))
        || rec.force_row
        || rec.files.as_ref().is_some_and(|f| f.points.is_some())
        || !log.pending.is_empty()
}

/// Record system: a row every `every` steps, events as they happen.
#[allow(clippy::too_many_arguments)] // a Bevy system: one parameter per resource it reads
pub fn record(
    clock: Res<Clock>,
    roster: Res<Roster>,
    bodies: Query<(&SimBody, &BodyState)>,
    mon: Res<MonitorState>,
    g: Res<Guarantees>,
    diag: Res<Diagnostics>,
    mut log: ResMut<EventLog>,
    mut rec: ResMut<Recorder>,
    cs: Res<ContactState>,
    env: Res<super::Env>,
) {
    let rec = &mut *rec;
    let due = clock.step.is_multiple_of(u64::from(rec.every)) || rec.force_row;
    // Contact points at full rate; a forced row (start, end of run) repeats no step.
    if !rec.force_row
        && let Some(points) = rec.files.as_mut().and_then(|f| f.points.as_mut())
        && let Err(err) = write_points(points, &cs)
    {
        rec.error.get_or_insert(err.to_string());
    }
    rec.force_row = false;
    if !due {
        write_events(rec, &mut log);
        return;
    }
    let states: Vec<(&SimBody, &BodyState)> = roster
        .bodies
        .iter()
        .map(|e| bodies.get(*e).expect("roster body"))
        .collect();
    write_step(
        rec,
        clock.step,
        clock.t_s(),
        &states,
        &mon,
        &g,
        &diag,
        &mut log,
        &cs,
        env.orbit(),
    );
}

/// Writes the header line (called once, when recording starts).
pub fn write_header(world: &mut World) {
    let cols = pair_columns(
        world.resource::<Roster>().names.len(),
        world.resource::<super::broadphase::BroadPhase>().all_pairs,
        &world.resource::<super::NamedPairs>().0,
    );
    let h = header(
        world.resource::<Roster>(),
        &cols,
        world.resource::<Guarantees>(),
        world.resource::<Diagnostics>(),
        world.resource::<super::Env>().orbit().is_some(),
    );
    let mut rec = world.resource_mut::<Recorder>();
    rec.pair_columns = cols;
    if let Some(files) = rec.files.as_mut()
        && let Err(e) = writeln!(files.traj, "{h}")
    {
        rec.error.get_or_insert(e.to_string());
    }
}

#[cfg(test)]
mod plain_tests {
    //! Reference: Rust's own `Display` for f64.
    use super::Plain;

    #[test]
    fn plain_writes_what_display_writes() {
        let mut x: u64 = 0x9E37_79B9_7F4A_7C15;
        let check = |v: f64| {
            assert_eq!(format!("{}", Plain(v)), format!("{v}"), "{v:e}");
        };
        for v in [
            0.0,
            -0.0,
            1.0,
            -1.0,
            0.1,
            2070.0,
            1e20,
            1e21,
            1e-7,
            123456789012345680.0,
            f64::MAX,
            f64::MIN_POSITIVE,
            5e-324,
            f64::NAN,
            f64::INFINITY,
            f64::NEG_INFINITY,
            0.0000008779485369814211,
            1_690_060_720_831_323.2,
        ] {
            check(v);
        }
        for k in 0..2_000_000u64 {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            // Every bit pattern, values of the size a trajectory holds, and large values with
            // few fraction bits (where ties between two shortest strings happen).
            let v = match k % 4 {
                0 => f64::from_bits(x),
                1 => (x >> 11) as f64 / (1u64 << 53) as f64 * 2e4 - 1e4,
                2 => (x >> 11) as f64 * 0.25 - 1e15,
                _ => (x >> 11) as f64 / (1u64 << (x % 40)) as f64,
            };
            check(v);
        }
    }
}
