//! A recorded run (`trajectory.csv`, `events.jsonl`, `contacts.csv`, `summary.json`, as written
//! by `rpod run`) read back for replay, and sampled at any time between rows: positions
//! linearly, attitudes by slerp, other columns from the row at or before the time, contact
//! forces from the row interval that contains the time.

use nalgebra::{Quaternion, UnitQuaternion, Vector3};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// A part pair (`body/part`, `body/part`), in the monitor's order.
pub type PartPair = (String, String);

/// `contacts.csv` rows grouped by time: (row time s, [(pair, mean normal force N)]).
type ContactRows = Vec<(f64, Vec<(PartPair, f64)>)>;

use super::timeline::Marker;

/// The state of everything the viewer draws at one instant (from a recording or a live run).
#[derive(Debug, Clone, Default)]
pub struct Snapshot {
    /// Simulated time, s.
    pub t_s: f64,
    /// Per body (scene order): centre-of-mass position (world, m) and attitude body → world.
    pub bodies: Vec<(Vector3<f64>, UnitQuaternion<f64>)>,
    /// Minimum full-geometry distance between the bodies, m.
    pub min_distance_m: f64,
    /// The parts that are closest (`body/part`, `body/part`).
    pub closest_parts: Option<(String, String)>,
    /// Guarantees: name, margin and its unit.
    pub guarantees: Vec<(String, f64, String)>,
    /// Other columns (controller and mechanism diagnostics): name, value.
    pub diagnostics: Vec<(String, f64)>,
    /// Docking state name, if the scene has a mechanism.
    pub docking_state: Option<String>,
    /// Part pairs in contact (`body/part`, `body/part`).
    pub contacts: Vec<PartPair>,
    /// Mean normal contact force per part pair over the recorded interval (replay: the
    /// `contacts.csv` row interval containing `t_s`; live: the last frame's steps), N.
    pub contact_force_n: BTreeMap<PartPair, f64>,
}

/// Column indices of one body's state in `trajectory.csv`.
#[derive(Debug, Clone)]
struct BodyCols {
    pos: [usize; 3],
    quat_wxyz: [usize; 4],
}

/// A recorded run in memory.
#[derive(Debug, Clone)]
pub struct Recording {
    /// The run directory.
    pub dir: PathBuf,
    /// Scene file named by `summary.json` (`scene_file`).
    pub scene_file: Option<String>,
    /// `summary.json`.
    pub summary: serde_json::Value,
    /// Body names, in the order of [`Snapshot::bodies`].
    pub body_names: Vec<String>,
    /// Row times, s.
    pub times_s: Vec<f64>,
    /// Numeric cells per row (NaN where not a number).
    rows: Vec<Vec<f64>>,
    /// `closest_parts` per row.
    closest: Vec<String>,
    cols: Vec<BodyCols>,
    min_col: Option<usize>,
    /// (column, name, unit) of each guarantee margin.
    guarantee_cols: Vec<(usize, String, String)>,
    /// (column, name) of the other numeric columns.
    diag_cols: Vec<(usize, String)>,
    /// Events (`events.jsonl`), in file order.
    pub events: Vec<serde_json::Value>,
    /// `contacts.csv` rows grouped by time: (row time s, [(pair, mean normal force N)]), in
    /// time order (empty for a run recorded before `contacts.csv` existed).
    contact_rows: ContactRows,
}

fn read(path: &Path) -> Result<String, String> {
    crate::report::fsio::read_regular_string(
        path,
        crate::report::fsio::MAX_OUTPUT_READ_BYTES,
        "run file",
    )
    .map_err(|e| e.to_string())
}

impl Recording {
    /// Reads a run directory. `body_names` are the scene's bodies in scene order; each must have
    /// its 13 state columns in `trajectory.csv`.
    pub fn load(dir: &Path) -> Result<Self, String> {
        let summary: serde_json::Value = serde_json::from_str(&read(&dir.join("summary.json"))?)
            .map_err(|e| format!("{}: {e}", dir.join("summary.json").display()))?;
        let text = read(&dir.join("trajectory.csv"))?;
        let events_text = read(&dir.join("events.jsonl")).unwrap_or_default();
        let mut rec = Self::parse(&text, &events_text)?;
        let contacts = dir.join("contacts.csv");
        if contacts.exists() {
            rec.contact_rows = parse_contacts(&read(&contacts)?)?;
        }
        rec.dir = dir.to_path_buf();
        rec.scene_file = summary
            .get("scene_file")
            .and_then(|v| v.as_str())
            .map(str::to_string);
        rec.summary = summary;
        Ok(rec)
    }

    /// Parses the CSV and JSONL text (the bodies are found from the `NAME.px_m` columns).
    pub fn parse(csv: &str, events_jsonl: &str) -> Result<Self, String> {
        let mut lines = csv.lines();
        let header: Vec<&str> = lines
            .next()
            .ok_or("trajectory.csv is empty")?
            .split(',')
            .collect();
        let col = |n: &str| header.iter().position(|h| *h == n);
        if col("t_s") != Some(0) {
            return Err("trajectory.csv: the first column must be t_s".into());
        }
        let mut body_names = Vec::new();
        let mut cols = Vec::new();
        for h in &header {
            if let Some(name) = h.strip_suffix(".px_m") {
                let c = |s: &str| {
                    col(&format!("{name}.{s}"))
                        .ok_or_else(|| format!("trajectory.csv: no column {name}.{s}"))
                };
                cols.push(BodyCols {
                    pos: [c("px_m")?, c("py_m")?, c("pz_m")?],
                    quat_wxyz: [c("qw")?, c("qx")?, c("qy")?, c("qz")?],
                });
                body_names.push(name.to_string());
            }
        }
        let state_prefixes: Vec<String> = body_names.iter().map(|n| format!("{n}.")).collect();
        let closest_col = col("closest_parts");
        let mut guarantee_cols = Vec::new();
        let mut diag_cols = Vec::new();
        for (i, h) in header.iter().enumerate() {
            if let Some(rest) = h.strip_prefix("guarantee.") {
                if let Some((name, unit)) = rest.rsplit_once(".margin_") {
                    guarantee_cols.push((i, name.to_string(), unit.to_string()));
                }
            } else if i > 0
                && Some(i) != closest_col
                && *h != "min_distance_m"
                && !state_prefixes.iter().any(|p| h.starts_with(p.as_str()))
            {
                diag_cols.push((i, h.to_string()));
            }
        }
        let mut times_s = Vec::new();
        let mut rows = Vec::new();
        let mut closest = Vec::new();
        for (k, line) in lines.enumerate() {
            if line.is_empty() {
                continue;
            }
            let cells: Vec<&str> = line.split(',').collect();
            if cells.len() != header.len() {
                return Err(format!(
                    "trajectory.csv line {}: {} cells, header has {}",
                    k + 2,
                    cells.len(),
                    header.len()
                ));
            }
            let nums: Vec<f64> = cells
                .iter()
                .map(|c| c.parse::<f64>().unwrap_or(f64::NAN))
                .collect();
            if !nums[0].is_finite() || times_s.last().is_some_and(|&t| nums[0] < t) {
                return Err(format!(
                    "trajectory.csv line {}: bad or decreasing t_s",
                    k + 2
                ));
            }
            times_s.push(nums[0]);
            closest.push(
                closest_col
                    .map(|c| cells[c].to_string())
                    .unwrap_or_default(),
            );
            rows.push(nums);
        }
        if rows.is_empty() {
            return Err("trajectory.csv has no rows".into());
        }
        let events = events_jsonl
            .lines()
            .filter(|l| !l.trim().is_empty())
            .map(|l| serde_json::from_str(l).map_err(|e| format!("events.jsonl: {e}")))
            .collect::<Result<Vec<serde_json::Value>, String>>()?;
        Ok(Self {
            dir: PathBuf::new(),
            scene_file: None,
            summary: serde_json::Value::Null,
            body_names,
            times_s,
            rows,
            closest,
            min_col: col("min_distance_m"),
            cols,
            guarantee_cols,
            diag_cols,
            events,
            contact_rows: Vec::new(),
        })
    }

    /// Attaches `contacts.csv` text (as [`Recording::load`] does from the run directory).
    pub fn with_contacts(mut self, contacts_csv: &str) -> Result<Self, String> {
        self.contact_rows = parse_contacts(contacts_csv)?;
        Ok(self)
    }

    /// The largest mean normal contact force in `contacts.csv`, N (0 without contacts).
    pub fn peak_contact_force_n(&self) -> f64 {
        self.contact_rows
            .iter()
            .flat_map(|(_, g)| g.iter().map(|(_, f)| *f))
            .fold(0.0, f64::max)
    }

    /// Contact forces at `t` (clamped): those of the `contacts.csv` row that closes the
    /// trajectory row interval (t_prev, t_row] containing `t`.
    fn contact_forces_at(&self, t: f64) -> BTreeMap<PartPair, f64> {
        let r = self.times_s.partition_point(|&x| x < t);
        let Some(&t_row) = self.times_s.get(r) else {
            return BTreeMap::new();
        };
        match self
            .contact_rows
            .binary_search_by(|(tc, _)| tc.total_cmp(&t_row))
        {
            Ok(k) => self.contact_rows[k].1.iter().cloned().collect(),
            Err(_) => BTreeMap::new(),
        }
    }

    /// First and last recorded times, s.
    pub fn span_s(&self) -> (f64, f64) {
        (self.times_s[0], *self.times_s.last().expect("non-empty"))
    }

    /// Median interval between rows, s.
    pub fn row_dt_s(&self) -> f64 {
        let mut d: Vec<f64> = self.times_s.windows(2).map(|w| w[1] - w[0]).collect();
        if d.is_empty() {
            return 0.1;
        }
        d.sort_by(f64::total_cmp);
        d[d.len() / 2]
    }

    /// The event markers for the timeline.
    pub fn markers(&self) -> Vec<Marker> {
        self.events.iter().filter_map(Marker::from_event).collect()
    }

    /// Body positions (centre of mass, world, m) at every row, per body.
    pub fn track(&self, body: usize) -> Vec<Vector3<f64>> {
        self.rows.iter().map(|r| self.pos(r, body)).collect()
    }

    fn pos(&self, r: &[f64], body: usize) -> Vector3<f64> {
        let c = &self.cols[body].pos;
        Vector3::new(r[c[0]], r[c[1]], r[c[2]])
    }

    fn att(&self, r: &[f64], body: usize) -> UnitQuaternion<f64> {
        let c = &self.cols[body].quat_wxyz;
        UnitQuaternion::from_quaternion(Quaternion::new(r[c[0]], r[c[1]], r[c[2]], r[c[3]]))
    }

    /// Index of the last row at or before `t_s` (0 before the start).
    pub fn row_at(&self, t_s: f64) -> usize {
        self.times_s
            .partition_point(|&t| t <= t_s)
            .saturating_sub(1)
    }

    /// Everything at time `t_s` (clamped to the recording).
    pub fn sample(&self, t_s: f64) -> Snapshot {
        let (t0, t1) = self.span_s();
        let t = if t_s.is_finite() {
            t_s.clamp(t0, t1)
        } else {
            t0
        };
        let i = self.row_at(t);
        let j = (i + 1).min(self.rows.len() - 1);
        let (a, b) = (&self.rows[i], &self.rows[j]);
        let span = self.times_s[j] - self.times_s[i];
        let s = if span > 0.0 {
            ((t - self.times_s[i]) / span).clamp(0.0, 1.0)
        } else {
            0.0
        };
        let bodies = (0..self.cols.len())
            .map(|k| {
                let p = self.pos(a, k).lerp(&self.pos(b, k), s);
                let qa = self.att(a, k);
                let qb = self.att(b, k);
                let q = qa.try_slerp(&qb, s, 1e-12).unwrap_or(qa);
                (p, q)
            })
            .collect();
        let closest_parts = self.closest[i]
            .split_once('|')
            .map(|(x, y)| (x.to_string(), y.to_string()));
        let docking_state = self
            .events
            .iter()
            .filter(|e| e["kind"] == "docking_state")
            .take_while(|e| e["t_s"].as_f64().unwrap_or(f64::INFINITY) <= t + 1e-9)
            .last()
            .and_then(|e| e["to"].as_str().map(str::to_string))
            .or_else(|| {
                self.diag_cols
                    .iter()
                    .any(|(_, n)| n == "dock.state")
                    .then(|| "FREE".to_string())
            });
        // Contacts open at t: every contact_start not yet closed by its contact_end.
        let mut contacts: Vec<(String, String)> = Vec::new();
        for e in &self.events {
            if e["t_s"].as_f64().unwrap_or(f64::INFINITY) > t + 1e-9 {
                break;
            }
            let pair = || {
                (
                    e["a"].as_str().unwrap_or("").to_string(),
                    e["b"].as_str().unwrap_or("").to_string(),
                )
            };
            match e["kind"].as_str() {
                Some("contact_start") => {
                    let p = pair();
                    if !contacts.contains(&p) {
                        contacts.push(p);
                    }
                }
                Some("contact_end") => {
                    let p = pair();
                    contacts.retain(|c| *c != p);
                }
                _ => {}
            }
        }
        Snapshot {
            t_s: t,
            contacts,
            bodies,
            min_distance_m: self.min_col.map(|c| a[c]).unwrap_or(f64::NAN),
            closest_parts,
            guarantees: self
                .guarantee_cols
                .iter()
                .map(|(c, n, u)| (n.clone(), a[*c], u.clone()))
                .collect(),
            diagnostics: self
                .diag_cols
                .iter()
                .map(|(c, n)| (n.clone(), a[*c]))
                .collect(),
            docking_state,
            contact_force_n: self.contact_forces_at(t),
        }
    }
}

/// Parses `contacts.csv` (`t_s`, `a`, `b`, `force_n` and the other columns) into rows grouped
/// by time.
fn parse_contacts(text: &str) -> Result<ContactRows, String> {
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap_or("").split(',').collect();
    let col = |n: &str| {
        header
            .iter()
            .position(|h| *h == n)
            .ok_or_else(|| format!("contacts.csv: no column {n}"))
    };
    let (ct, ca, cb, cf) = (col("t_s")?, col("a")?, col("b")?, col("force_n")?);
    let mut out: ContactRows = Vec::new();
    for (k, line) in lines.enumerate() {
        if line.is_empty() {
            continue;
        }
        let cells: Vec<&str> = line.split(',').collect();
        let bad = || format!("contacts.csv line {}: {line}", k + 2);
        if cells.len() != header.len() {
            return Err(bad());
        }
        let t: f64 = cells[ct].parse().map_err(|_| bad())?;
        let f: f64 = cells[cf].parse().map_err(|_| bad())?;
        let pair = (cells[ca].to_string(), cells[cb].to_string());
        match out.last_mut() {
            Some((tl, g)) if *tl == t => g.push((pair, f)),
            Some((tl, _)) if *tl > t => return Err(format!("{}: decreasing t_s", bad())),
            _ => out.push((t, vec![(pair, f)])),
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    const CSV: &str = "t_s,a.px_m,a.py_m,a.pz_m,a.vx_m_s,a.vy_m_s,a.vz_m_s,a.qw,a.qx,a.qy,a.qz,a.wx_rad_s,a.wy_rad_s,a.wz_rad_s,min_distance_m,closest_parts,guarantee.g1.margin_m,dock.gap_m\n\
0,0,0,0,1,0,0,1,0,0,0,0,0,1,5,a/bus|b/cone,4,0.5\n\
1,1,0,0,1,0,0,0.7071067811865476,0,0,0.7071067811865476,0,0,1,3,a/wing.panel1|b/cone,2,0.25\n";

    #[test]
    fn invariant_recording_sample_interpolates() {
        let ev = r#"{"t_s":0.5,"kind":"docking_state","from":"FREE","to":"ATTRACTING"}"#;
        let r = Recording::parse(CSV, ev).unwrap();
        assert_eq!(r.body_names, vec!["a"]);
        assert_eq!(r.span_s(), (0.0, 1.0));
        assert_eq!(r.row_dt_s(), 1.0);
        let s = r.sample(0.25);
        assert!((s.bodies[0].0.x - 0.25).abs() < 1e-12);
        // Slerp from identity to 90° about z: a quarter of the way is 22.5°.
        let (axis, angle) = s.bodies[0].1.axis_angle().unwrap();
        assert!((angle - std::f64::consts::FRAC_PI_8).abs() < 1e-12);
        assert!((axis.z - 1.0).abs() < 1e-12);
        assert_eq!(s.min_distance_m, 5.0);
        assert_eq!(s.closest_parts, Some(("a/bus".into(), "b/cone".into())));
        assert_eq!(s.guarantees, vec![("g1".to_string(), 4.0, "m".to_string())]);
        assert_eq!(s.diagnostics, vec![("dock.gap_m".to_string(), 0.5)]);
        assert_eq!(s.docking_state, None);
        let s = r.sample(0.75);
        assert_eq!(s.docking_state.as_deref(), Some("ATTRACTING"));
        assert!(s.contacts.is_empty());
        // Clamped past the end: the last row.
        let s = r.sample(9.0);
        assert_eq!(s.t_s, 1.0);
        assert!((s.bodies[0].0.x - 1.0).abs() < 1e-12);
        assert_eq!(s.min_distance_m, 3.0);
    }

    #[test]
    fn invariant_recording_open_contacts() {
        let ev = [
            r#"{"t_s":0.2,"kind":"contact_start","a":"a/bus","b":"b/cone"}"#,
            r#"{"t_s":0.3,"kind":"contact_start","a":"a/wing.panel1","b":"b/cone"}"#,
            r#"{"t_s":0.6,"kind":"contact_end","a":"a/bus","b":"b/cone"}"#,
        ]
        .join("\n");
        let r = Recording::parse(CSV, &ev).unwrap();
        assert!(r.sample(0.1).contacts.is_empty());
        assert_eq!(r.sample(0.25).contacts.len(), 1);
        assert_eq!(r.sample(0.5).contacts.len(), 2);
        assert_eq!(
            r.sample(0.7).contacts,
            vec![("a/wing.panel1".to_string(), "b/cone".to_string())]
        );
    }

    #[test]
    fn invariant_recording_contact_forces_by_row_interval() {
        // Rows at 0 and 1 s; contacts.csv gives the mean force over (0, 1] s.
        let contacts = "t_s,a,b,docking,force_n,impulse_ns,jx_b_ns,jy_b_ns,jz_b_ns,in_contact\n\
1,a/bus,b/cone,false,20,20,20,0,0,true\n\
1,a/wing.panel1,b/cone,false,2.5,2.5,0,2.5,0,false\n";
        let r = Recording::parse(CSV, "")
            .unwrap()
            .with_contacts(contacts)
            .unwrap();
        assert_eq!(r.peak_contact_force_n(), 20.0);
        // At the first row no interval has closed yet.
        assert!(r.sample(0.0).contact_force_n.is_empty());
        for t in [0.01, 0.5, 1.0, 7.0] {
            let f = r.sample(t).contact_force_n;
            assert_eq!(f.len(), 2, "t = {t}");
            assert_eq!(f[&("a/bus".to_string(), "b/cone".to_string())], 20.0);
        }
        let bad = "t_s,a,b,docking,force_n,impulse_ns,jx_b_ns,jy_b_ns,jz_b_ns,in_contact\n\
1,a/bus,b/cone,false,x,1,1,0,0,true\n";
        assert!(
            Recording::parse(CSV, "")
                .unwrap()
                .with_contacts(bad)
                .unwrap_err()
                .contains("line 2")
        );
    }

    #[test]
    fn regress_recording_rejects_bad_tables() {
        assert!(Recording::parse("", "").is_err());
        assert!(Recording::parse("x,y\n1,2\n", "").is_err());
        let short = "t_s,a.px_m\n0\n";
        assert!(Recording::parse(short, "").is_err());
        let no_q = "t_s,a.px_m,a.py_m,a.pz_m\n0,0,0,0\n";
        assert!(Recording::parse(no_q, "").unwrap_err().contains("a.qw"));
        let back = CSV.replace("\n1,1,", "\n-1,1,");
        assert!(Recording::parse(&back, "").is_err());
    }
}
