//! `rpod._rpod`: the Python extension of rpod (PyO3). The Python package `rpod` re-exports it
//! (see `python/rpod/__init__.py` and the type stubs `python/rpod/_rpod.pyi`).
//!
//! - [`PySimulation`] wraps [`rpod::sim::Simulation`]: a scene file with `--set`-style
//!   overrides, stepping, states (world and Hill frames), forces applied from Python, the
//!   monitor, events, the summary and the standard output files.
//! - A Python callable added with `add_controller` becomes a `PyLaw`, a
//!   [`rpod::control::Controller`] hosted by the same generic host as every Rust law: it is
//!   called at its own period inside the fixed-step pipeline (Sense → Control → Actuate), its
//!   command held in between and passed through the slot's actuator.
//! - Nothing crashes the interpreter: scene errors raise `SceneError` (file, line, column,
//!   field, message); an exception in a Python law is re-raised from `step`; a non-finite
//!   command or state raises `NumericError` naming the body, the quantity and the time; a Rust
//!   panic raises `SimulationError`.

use nalgebra::{Matrix3, UnitQuaternion, Vector3};
use numpy::{PyArray1, PyArray2, PyArray3, PyReadonlyArray1};
use pyo3::exceptions::{PyKeyError, PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyDict, PyFloat, PyInt, PyList, PyString};
use rpod::actuation::ActuatorSpec;
use rpod::control::interface::{
    BodyObs, Command, Controller, DiagnosticsAt, Frame, Measurement, Needs, Observation, PortPose,
    RelState, port_pose, ports_obs,
};
use rpod::control::registry::{BodyWrench, Disturbance, DisturbanceContext, Slot};
use rpod::control::sensor::SensorSpec;
use std::cell::RefCell;
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::rc::Rc;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex};
use std::thread::ThreadId;

// Defined in Python (`rpod/_errors.py`, shown as `rpod.SceneError`, …), so that they pickle by
// name with their attributes: an error raised in a worker process (multiprocessing, Gymnasium's
// AsyncVectorEnv) reaches the parent.
pyo3::import_exception!(rpod._errors, SceneError);
pyo3::import_exception!(rpod._errors, NumericError);
pyo3::import_exception!(rpod._errors, SimulationError);

/// Most steps one call may ask for (a count has a limit: 10¹² steps is 300 years at 10 ms).
const MAX_STEPS: u64 = 1_000_000_000_000;

fn scene_error(py: Python<'_>, e: &rpod::scene::SceneError) -> PyErr {
    let err = SceneError::new_err(e.to_string());
    let v = err.value(py);
    let _ = v.setattr("file", e.file.clone());
    let _ = v.setattr("line", e.line);
    let _ = v.setattr("column", e.col);
    let _ = v.setattr("field", e.field.clone());
    let _ = v.setattr("message", e.message.clone());
    err
}

fn panic_message(p: &(dyn std::any::Any + Send)) -> String {
    if let Some(s) = p.downcast_ref::<&str>() {
        s.to_string()
    } else if let Some(s) = p.downcast_ref::<String>() {
        s.clone()
    } else {
        "a panic without a message".into()
    }
}

/// Runs `f`, turning a Rust panic into `SimulationError`.
fn guarded<T>(what: &str, f: impl FnOnce() -> T) -> PyResult<T> {
    std::panic::catch_unwind(std::panic::AssertUnwindSafe(f)).map_err(|p| {
        SimulationError::new_err(format!(
            "{what}: internal failure in rpod ({}); the simulation cannot go on",
            panic_message(&*p)
        ))
    })
}

fn vec3<'py>(py: Python<'py>, v: &Vector3<f64>) -> Bound<'py, PyArray1<f64>> {
    PyArray1::from_slice(py, &[v.x, v.y, v.z])
}

fn quat<'py>(py: Python<'py>, q: &UnitQuaternion<f64>) -> Bound<'py, PyArray1<f64>> {
    PyArray1::from_slice(py, &[q.w, q.i, q.j, q.k])
}

fn mat3<'py>(py: Python<'py>, m: &Matrix3<f64>) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let rows: Vec<Vec<f64>> = (0..3)
        .map(|i| (0..3).map(|j| m[(i, j)]).collect())
        .collect();
    PyArray2::from_vec2(py, &rows).map_err(|e| PyValueError::new_err(e.to_string()))
}

fn body_dict<'py>(py: Python<'py>, b: &BodyObs) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("pos_m", vec3(py, &b.pos_m))?;
    d.set_item("vel_m_s", vec3(py, &b.vel_m_s))?;
    d.set_item("quat_wxyz", quat(py, &b.att))?;
    d.set_item("omega_rad_s", vec3(py, &b.omega_rad_s))?;
    d.set_item("rate_body_rad_s", vec3(py, &b.rate_body_rad_s))?;
    d.set_item("gravity_m_s2", vec3(py, &b.gravity_m_s2))?;
    Ok(d)
}

fn rel_dict<'py>(py: Python<'py>, r: &RelState) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("pos_m", vec3(py, &r.pos_m))?;
    d.set_item("vel_m_s", vec3(py, &r.vel_m_s))?;
    Ok(d)
}

fn port_dict<'py>(py: Python<'py>, p: &PortPose) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("pos_m", vec3(py, &p.pos_m))?;
    d.set_item("vel_m_s", vec3(py, &p.vel_m_s))?;
    d.set_item("quat_wxyz", quat(py, &p.att))?;
    d.set_item("axis", vec3(py, &p.axis()))?;
    Ok(d)
}

fn ports_dict<'py>(
    py: Python<'py>,
    p: &rpod::control::interface::PortsObs,
) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("chaser", port_dict(py, &p.chaser)?)?;
    d.set_item("target", port_dict(py, &p.target)?)?;
    d.set_item("rel_pos_m", vec3(py, &p.rel_port.pos_m))?;
    d.set_item("rel_vel_m_s", vec3(py, &p.rel_port.vel_m_s))?;
    d.set_item("rel_quat_wxyz", quat(py, &p.rel_att))?;
    d.set_item("misalignment_rad", p.misalignment_rad)?;
    Ok(d)
}

fn measured_dict<'py>(py: Python<'py>, m: &Measurement) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("t_s", m.t_s)?;
    d.set_item("delivered_s", m.delivered_s)?;
    d.set_item("fresh", m.fresh)?;
    d.set_item("frame", format!("{:?}", m.frame))?;
    d.set_item("pos_m", vec3(py, &m.pos_m))?;
    d.set_item("vel_m_s", vec3(py, &m.vel_m_s))?;
    d.set_item("quat_wxyz", quat(py, &m.att))?;
    d.set_item("omega_rad_s", vec3(py, &m.omega_rad_s))?;
    d.set_item("yaw_rad", m.yaw_rad)?;
    Ok(d)
}

/// The observation of the `Controller` interface as a dict of numpy arrays (see the stubs).
fn observation_dict<'py>(py: Python<'py>, obs: &Observation) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("t_s", obs.t_s)?;
    d.set_item("step", obs.step)?;
    d.set_item("dt_s", obs.dt_s)?;
    let own = obs.own_info();
    d.set_item("body", own.name.as_str())?;
    d.set_item("target", obs.target.map(|t| obs.info[t].name.as_str()))?;
    d.set_item("mass_kg", own.mass_kg)?;
    d.set_item("inertia_kg_m2", mat3(py, &own.inertia_kg_m2)?)?;
    d.set_item("own", body_dict(py, obs.own())?)?;
    match obs.target_state() {
        Some(t) => d.set_item("target_state", body_dict(py, t)?)?,
        None => d.set_item("target_state", py.None())?,
    }
    let bodies = PyDict::new(py);
    for (i, b) in obs.bodies.iter().enumerate() {
        bodies.set_item(obs.info[i].name.as_str(), body_dict(py, b)?)?;
    }
    d.set_item("bodies", bodies)?;
    match obs.relative {
        Some(r) => {
            let rd = PyDict::new(py);
            rd.set_item("world", rel_dict(py, &r.world)?)?;
            match &r.hill {
                Some(h) => rd.set_item("hill", rel_dict(py, h)?)?,
                None => rd.set_item("hill", py.None())?,
            }
            rd.set_item("target_body", rel_dict(py, &r.target_body)?)?;
            match &r.dcm_world_from_hill {
                Some(c) => rd.set_item("dcm_world_from_hill", mat3(py, c)?)?,
                None => rd.set_item("dcm_world_from_hill", py.None())?,
            }
            match &r.hill_rate_world_rad_s {
                Some(w) => rd.set_item("hill_rate_world_rad_s", vec3(py, w))?,
                None => rd.set_item("hill_rate_world_rad_s", py.None())?,
            }
            rd.set_item(
                "mean_motion_rad_s",
                rpod::control::generic::target_mean_motion(obs),
            )?;
            d.set_item("relative", rd)?;
        }
        None => d.set_item("relative", py.None())?,
    }
    match obs.ports {
        Some(p) => d.set_item("ports", ports_dict(py, p)?)?,
        None => d.set_item("ports", py.None())?,
    }
    match obs.measured {
        Some(m) => d.set_item("measured", measured_dict(py, m)?)?,
        None => d.set_item("measured", py.None())?,
    }
    match &obs.docking {
        Some(k) => {
            let dd = PyDict::new(py);
            dd.set_item("state", k.state)?;
            dd.set_item("magnet_on", k.magnet_on)?;
            dd.set_item("gap_m", k.gap_m)?;
            dd.set_item("axial_error_m", k.axial_error_m)?;
            dd.set_item("lateral_m", k.lateral_m)?;
            dd.set_item("misalignment_deg", k.misalignment_deg)?;
            d.set_item("docking", dd)?;
        }
        None => d.set_item("docking", py.None())?,
    }
    let g = PyDict::new(py);
    for o in obs.guarantees {
        g.set_item(o.name.as_str(), o.margin)?;
    }
    d.set_item("guarantees", g)?;
    Ok(d)
}

fn parse_frame(s: &str) -> Option<Frame> {
    match s {
        "world" => Some(Frame::World),
        "body" => Some(Frame::Body),
        "hill" => Some(Frame::Hill),
        "target_body" => Some(Frame::TargetBody),
        _ => None,
    }
}

fn frame_arg(v: &Bound<'_, PyAny>, key: &str) -> PyResult<Frame> {
    let s: String = v
        .extract()
        .map_err(|_| PyTypeError::new_err(format!("`{key}` must be a string")))?;
    parse_frame(&s).ok_or_else(|| {
        PyValueError::new_err(format!(
            "`{key}`: unknown frame {s:?} (world, body, hill or target_body)"
        ))
    })
}

/// A 3-vector from a sequence or a numpy array.
fn extract_vec3(v: &Bound<'_, PyAny>, what: &str) -> PyResult<Vector3<f64>> {
    if let Ok(a) = v.extract::<PyReadonlyArray1<'_, f64>>() {
        let s = a
            .as_slice()
            .map_err(|e| PyValueError::new_err(e.to_string()))?;
        if s.len() == 3 {
            return Ok(Vector3::new(s[0], s[1], s[2]));
        }
        return Err(PyValueError::new_err(format!(
            "`{what}` must have 3 components, got {}",
            s.len()
        )));
    }
    let items: Vec<f64> = v.extract().map_err(|_| {
        PyTypeError::new_err(format!(
            "`{what}` must be 3 numbers (a list, a tuple or a numpy array)"
        ))
    })?;
    if items.len() != 3 {
        return Err(PyValueError::new_err(format!(
            "`{what}` must have 3 components, got {}",
            items.len()
        )));
    }
    Ok(Vector3::new(items[0], items[1], items[2]))
}

/// Where a Python law's failure waits for `step` to raise it.
type ErrorSlot = Arc<Mutex<Option<PyErr>>>;

/// A Python callable as a guarantee: `func(view) -> margin` (a float in `unit`), judged on
/// the step intervals when `rate_bound` (|d margin/dt| ≤ rate_bound, in unit/s, the caller's
/// claim) is given, at the samples only otherwise. A raising callable or a non-finite margin
/// stops the run with an exception naming the guarantee; its margin then counts as −∞
/// (violated), so it is never reported held.
struct PyGuarantee {
    func: Py<PyAny>,
    name: String,
    unit: String,
    rate_bound: Option<f64>,
    body_names: Vec<String>,
    error: ErrorSlot,
    failed: std::sync::atomic::AtomicBool,
}

/// What a Python guarantee sees: `t_s`, `bodies` (per body, world frame, the keys of a law
/// observation's `bodies` entries: `pos_m`, `vel_m_s`, `quat_wxyz`, `omega_rad_s`,
/// `rate_body_rad_s`) and `distances_m` (`"a/b"`: full-geometry distance of each tracked pair).
fn monitor_view_dict<'py>(
    py: Python<'py>,
    names: &[String],
    v: &rpod::guarantee::MonitorView,
) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("t_s", v.t_s)?;
    let bodies = PyDict::new(py);
    for (n, b) in names.iter().zip(v.bodies) {
        let bd = PyDict::new(py);
        bd.set_item("pos_m", vec3(py, &b.pos_m))?;
        bd.set_item("vel_m_s", vec3(py, &b.vel_m_s))?;
        bd.set_item("quat_wxyz", quat(py, &b.att))?;
        bd.set_item("omega_rad_s", vec3(py, &b.omega_rad_s))?;
        bd.set_item(
            "rate_body_rad_s",
            vec3(py, &b.att.inverse_transform_vector(&b.omega_rad_s)),
        )?;
        bodies.set_item(n.as_str(), bd)?;
    }
    d.set_item("bodies", bodies)?;
    let dist = PyDict::new(py);
    for p in v.pairs {
        if let (Some(a), Some(b)) = (names.get(p.a), names.get(p.b)) {
            dist.set_item(format!("{a}/{b}"), p.distance_m)?;
        }
    }
    d.set_item("distances_m", dist)?;
    Ok(d)
}

impl PyGuarantee {
    fn call(&self, py: Python<'_>, v: &rpod::guarantee::MonitorView) -> PyResult<f64> {
        let o = monitor_view_dict(py, &self.body_names, v)?;
        let r = self.func.bind(py).call1((o,)).map_err(|e| {
            let err = SimulationError::new_err(format!(
                "guarantee `{}` raised {} at t = {} s",
                self.name, e, v.t_s
            ));
            err.set_cause(py, Some(e));
            err
        })?;
        let m: f64 = r.extract().map_err(|_| {
            PyTypeError::new_err(format!(
                "guarantee `{}` must return its margin as a float, got {}",
                self.name,
                r.get_type().name().map_or("?".into(), |n| n.to_string())
            ))
        })?;
        if !m.is_finite() {
            return Err(NumericError::new_err(format!(
                "guarantee `{}` returned a non-finite margin {m} at t = {} s",
                self.name, v.t_s
            )));
        }
        Ok(m)
    }
}

impl rpod::guarantee::Guarantee for PyGuarantee {
    fn name(&self) -> &str {
        &self.name
    }
    fn unit(&self) -> &str {
        &self.unit
    }
    fn margin(&self, v: &rpod::guarantee::MonitorView) -> f64 {
        if self.failed.load(Ordering::Relaxed) {
            return f64::NEG_INFINITY;
        }
        Python::attach(|py| match self.call(py, v) {
            Ok(m) => m,
            Err(e) => {
                self.failed.store(true, Ordering::Relaxed);
                if let Ok(mut slot) = self.error.lock()
                    && slot.is_none()
                {
                    *slot = Some(e);
                }
                f64::NEG_INFINITY
            }
        })
    }
    fn rate_bound(&self, _m: &dyn rpod::guarantee::MotionBounds) -> Option<f64> {
        self.rate_bound
    }
    fn reads(&self) -> rpod::guarantee::Reads {
        rpod::guarantee::Reads::Everything
    }
}

/// A Python callable as a control law.
struct PyLaw {
    func: Py<PyAny>,
    body: String,
    columns: Vec<String>,
    diag: Vec<f64>,
    error: ErrorSlot,
    failed: bool,
}

impl PyLaw {
    fn call(&mut self, py: Python<'_>, obs: &Observation) -> PyResult<Command> {
        let o = observation_dict(py, obs)?;
        let r = self.func.bind(py).call1((o,))?;
        self.parse(&r, obs.t_s)
    }

    fn parse(&mut self, r: &Bound<'_, PyAny>, t_s: f64) -> PyResult<Command> {
        if r.is_none() {
            return Ok(Command::zero());
        }
        let d = r.cast::<PyDict>().map_err(|_| {
            PyTypeError::new_err(format!(
                "the controller of `{}` must return a dict (force_n, torque_nm, frame, …) or None, got {}",
                self.body,
                r.get_type().name().map_or("?".into(), |n| n.to_string())
            ))
        })?;
        let mut c = Command::zero();
        let mut frame: Option<Frame> = None;
        for (k, v) in d.iter() {
            let key: String = k
                .extract()
                .map_err(|_| PyTypeError::new_err("command keys must be strings"))?;
            match key.as_str() {
                "force_n" => c.force_n = extract_vec3(&v, "force_n")?,
                "torque_nm" => c.torque_nm = extract_vec3(&v, "torque_nm")?,
                "frame" => frame = Some(frame_arg(&v, "frame")?),
                "force_frame" => c.force_frame = frame_arg(&v, "force_frame")?,
                "torque_frame" => c.torque_frame = frame_arg(&v, "torque_frame")?,
                "valves" => {
                    let valves: Vec<bool> = v
                        .extract()
                        .map_err(|_| PyTypeError::new_err("`valves` must be a list of booleans"))?;
                    if valves.len() > 4096 {
                        return Err(PyValueError::new_err("`valves`: at most 4096"));
                    }
                    c.valves = Some(valves);
                }
                "diagnostics" => {
                    let dd = v.cast::<PyDict>().map_err(|_| {
                        PyTypeError::new_err("`diagnostics` must be a dict {column: number}")
                    })?;
                    for (name, val) in dd.iter() {
                        let name: String = name.extract()?;
                        let i = self.columns.iter().position(|c| *c == name).ok_or_else(|| {
                            PyKeyError::new_err(format!(
                                "diagnostic column {name:?} was not declared in add_controller(columns=…)"
                            ))
                        })?;
                        let x: f64 = val.extract().map_err(|_| {
                            PyTypeError::new_err(format!("diagnostic {name:?} must be a number"))
                        })?;
                        self.diag[i] = x;
                    }
                }
                other => {
                    return Err(PyKeyError::new_err(format!(
                        "unknown command key {other:?} (force_n, torque_nm, frame, force_frame, torque_frame, valves, diagnostics)"
                    )));
                }
            }
        }
        if let Some(f) = frame {
            c.force_frame = f;
            c.torque_frame = f;
        }
        for (q, v) in [("force_n", &c.force_n), ("torque_nm", &c.torque_nm)] {
            for (i, x) in v.iter().enumerate() {
                if !x.is_finite() || x.abs() > 1e15 {
                    return Err(NumericError::new_err(format!(
                        "the controller of body `{}` returned {q}[{i}] = {x} at t = {t_s} s (a command must be finite and below 1e15)",
                        self.body
                    )));
                }
            }
        }
        Ok(c)
    }
}

impl Controller for PyLaw {
    fn command(&mut self, obs: &Observation) -> Command {
        if self.failed {
            return Command::zero();
        }
        Python::attach(|py| match self.call(py, obs) {
            Ok(c) => c,
            Err(e) => {
                self.failed = true;
                if let Ok(mut slot) = self.error.lock()
                    && slot.is_none()
                {
                    *slot = Some(e);
                }
                Command::zero()
            }
        })
    }

    fn columns(&self) -> Vec<String> {
        self.columns.clone()
    }

    fn diagnostics(
        &mut self,
        _at: DiagnosticsAt,
        _obs: &Observation,
        _act: &rpod::control::interface::ActuationReport,
        out: &mut [f64],
    ) {
        out.copy_from_slice(&self.diag);
    }

    fn needs(&self) -> Needs {
        Needs::ALL
    }
}

/// A force or torque applied from Python, held over the next step.
#[derive(Clone, Copy)]
struct Applied {
    body: usize,
    force_n: Option<Vector3<f64>>,
    torque_nm: Option<Vector3<f64>>,
    body_frame: bool,
}

/// The forces `Simulation.apply` queued, as a disturbance (added in the Actuate stage).
struct ApplyQueue {
    queue: Arc<Mutex<Vec<Applied>>>,
}

impl Disturbance for ApplyQueue {
    fn wrenches(&mut self, ctx: &DisturbanceContext, out: &mut Vec<BodyWrench>) {
        let Ok(mut q) = self.queue.lock() else {
            return;
        };
        for a in q.drain(..) {
            let att = ctx.bodies[a.body].att;
            let turn = |v: Vector3<f64>| if a.body_frame { att * v } else { v };
            out.push(BodyWrench {
                body: a.body,
                force_n: a.force_n.map(turn),
                torque_nm: a.torque_nm.map(turn),
            });
        }
    }
}

/// A simulation held by the thread that created it.
type SimCell = Rc<RefCell<rpod::sim::Simulation>>;

thread_local! {
    /// The simulations this thread created, by id. A Bevy app is not `Send`: a simulation is
    /// built, stepped and dropped on its own thread, and a handle used from another thread finds
    /// nothing here (a `SimulationError`). One still held when its Python object is collected on
    /// another thread is dropped with this thread's locals, on its own thread.
    static SIMS: RefCell<HashMap<u64, SimCell>> = RefCell::new(HashMap::new());
}

static NEXT_SIM: AtomicU64 = AtomicU64::new(0);

/// Staging folders in use, with the process that made them: removed by `Drop`, by `finish`, and
/// at interpreter exit for any simulation still alive then (`atexit`). A forked child inherits
/// the list but removes only its own folders.
static STAGING_DIRS: Mutex<Vec<(u32, PathBuf)>> = Mutex::new(Vec::new());

fn staging_register(dir: &Path) {
    if let Ok(mut v) = STAGING_DIRS.lock() {
        v.push((std::process::id(), dir.to_path_buf()));
    }
}

/// Removes a staging folder and forgets it.
fn staging_remove(dir: &Path) {
    if let Ok(mut v) = STAGING_DIRS.lock() {
        v.retain(|(_, d)| d != dir);
    }
    let _ = std::fs::remove_dir_all(dir);
}

/// Removes this process's staging folders still in use (registered with `atexit` by the
/// module; a run recorded into its own `out_dir` is not touched).
#[pyfunction]
fn _remove_staging_folders() {
    let pid = std::process::id();
    let mine: Vec<PathBuf> = match STAGING_DIRS.lock() {
        Ok(mut v) => {
            let (mine, rest): (Vec<_>, Vec<_>) = v.drain(..).partition(|(p, _)| *p == pid);
            *v = rest;
            mine.into_iter().map(|(_, d)| d).collect()
        }
        Err(_) => Vec::new(),
    };
    for d in mine {
        let _ = std::fs::remove_dir_all(d);
    }
}

/// A simulation of one scene (see the module `rpod` docs). The handle may be passed between
/// threads, but only the thread that created it may use it: any other raises
/// `SimulationError` (checked here rather than by PyO3's `unsendable`, which panics).
#[pyclass(name = "Simulation", module = "rpod")]
pub struct PySimulation {
    /// Key of the simulation in its thread's `SIMS`.
    id: u64,
    /// The thread that created it.
    owner: ThreadId,
    /// Its name, for the message.
    owner_name: String,
    scene_file: String,
    /// Where rows are being written (the constructor's `out_dir`, or a private staging folder).
    recording: Option<PathBuf>,
    staging: bool,
    record: bool,
    /// The constructor's `out_dir` (recording starts there at the first step).
    out_dir: Option<PathBuf>,
    errors: ErrorSlot,
    /// Python laws and guarantees (the run then steps one step at a time).
    python_laws: usize,
    /// A step was taken.
    started: bool,
    /// `finish()` took the simulation.
    finished: bool,
    /// Why the run stopped (a law's exception, a non-finite number): no further step, and no
    /// summary written as if the run were whole.
    stopped: Option<String>,
    /// The scene's triangles for `render` (built at the first picture).
    snapshot: Option<rpod::sim::snapshot::Snapshot>,
    applied: Option<Arc<Mutex<Vec<Applied>>>>,
}

fn finished_error() -> PyErr {
    SimulationError::new_err("this simulation has finished (finish() was called)")
}

impl Drop for PySimulation {
    fn drop(&mut self) {
        // On its own thread the simulation goes now (its files closed before its staging folder
        // is removed); elsewhere it stays in its thread's locals until that thread ends.
        if std::thread::current().id() == self.owner {
            let sim = SIMS
                .try_with(|m| m.try_borrow_mut().ok().and_then(|mut m| m.remove(&self.id)))
                .ok()
                .flatten();
            drop(sim);
        }
        if self.staging
            && let Some(dir) = self.recording.take()
        {
            staging_remove(&dir);
        }
    }
}

impl PySimulation {
    /// The simulation, on its own thread.
    fn cell(&self) -> PyResult<SimCell> {
        if std::thread::current().id() != self.owner {
            let here = Python::attach(python_thread_name);
            return Err(SimulationError::new_err(format!(
                "this Simulation belongs to thread {:?}, which created it; it was used from thread {:?}. A simulation (a Bevy app) cannot move between threads: create one in each thread that steps it",
                self.owner_name, here
            )));
        }
        if self.finished {
            return Err(finished_error());
        }
        SIMS.try_with(|m| m.try_borrow().ok().and_then(|m| m.get(&self.id).cloned()))
            .ok()
            .flatten()
            .ok_or_else(finished_error)
    }
    /// Runs `f` on the simulation (its own thread only).
    fn with<T>(&self, f: impl FnOnce(&rpod::sim::Simulation) -> PyResult<T>) -> PyResult<T> {
        let cell = self.cell()?;
        let sim = cell.try_borrow().map_err(|_| busy_error())?;
        f(&sim)
    }
    /// Runs `f` on the simulation, mutably (its own thread only).
    fn with_mut<T>(
        &self,
        f: impl FnOnce(&mut rpod::sim::Simulation) -> PyResult<T>,
    ) -> PyResult<T> {
        let cell = self.cell()?;
        let mut sim = cell.try_borrow_mut().map_err(|_| busy_error())?;
        f(&mut sim)
    }
    fn body_index(&self, name: &str) -> PyResult<usize> {
        self.with(|sim| body_index_in(sim, name))
    }
    /// `add_controller`'s ports (body's port, target's port): `ports` when given, else the
    /// docking mechanism's, when it joins `body` and its `target` (as a scene's controller
    /// entry).
    fn controller_ports(
        &self,
        ports: Option<(String, String)>,
        body: &str,
        target: Option<&str>,
    ) -> PyResult<Option<(String, String)>> {
        // Default ports: the docking mechanism's, when it joins this body and its target (as a
        // scene's controller entry).
        Ok(match (ports, target) {
            (Some(p), _) => Some(p),
            (None, Some(t)) => self.with(|sim| {
                Ok(sim
                    .app
                    .world()
                    .get_resource::<rpod::sim::docking::Docking>()
                    .and_then(|k| {
                        let s = &k.spec;
                        if s.chaser == body && s.target == t {
                            Some((s.chaser_port.clone(), s.target_port.clone()))
                        } else if s.target == body && s.chaser == t {
                            Some((s.target_port.clone(), s.chaser_port.clone()))
                        } else {
                            None
                        }
                    }))
            })?,
            (None, None) => None,
        })
    }
    fn start_recording(&mut self) -> PyResult<()> {
        if self.recording.is_some() || !self.record {
            return Ok(());
        }
        if let Some(d) = self.out_dir.clone() {
            return self.begin(&d);
        }
        let dir = std::env::temp_dir().join(format!(
            "rpod-python-{}-{}",
            std::process::id(),
            STAGING.fetch_add(1, std::sync::atomic::Ordering::Relaxed)
        ));
        staging_register(&dir);
        self.staging = true;
        let begun = self.begin(&dir);
        if begun.is_err() {
            self.staging = false;
            staging_remove(&dir);
        }
        begun
    }
    fn begin(&mut self, dir: &Path) -> PyResult<()> {
        self.with_mut(|sim| {
            guarded("recording", || sim.record_to(dir))?.map_err(|e| {
                pyo3::exceptions::PyOSError::new_err(format!("cannot write {}: {e}", dir.display()))
            })
        })?;
        self.recording = Some(dir.to_path_buf());
        Ok(())
    }
    /// Steps `n`, one at a time while Python laws run (so a law's exception stops the run at
    /// the step it was raised), checking for Ctrl-C every 10 000 steps.
    fn advance(&mut self, py: Python<'_>, n: u64) -> PyResult<()> {
        if n > MAX_STEPS {
            return Err(PyValueError::new_err(format!(
                "at most {MAX_STEPS} steps per call, got {n}"
            )));
        }
        // Refused from another thread before anything starts (recording included).
        let cell = self.cell()?;
        if let Some(why) = &self.stopped {
            return Err(SimulationError::new_err(format!(
                "the run stopped: {why}; it cannot go on (make a new Simulation)"
            )));
        }
        self.start_recording()?;
        self.started = true;
        // With Python code in the loop, one pipeline step at a time (one fixed step, or a long
        // step with `stepping: MultiRate`), so that a raise stops the run at its step.
        let chunk = if self.python_laws > 0 { 0 } else { 10_000 };
        let errors = self.errors.clone();
        let mut left = n;
        while left > 0 {
            let k = {
                let mut sim = cell.try_borrow_mut().map_err(|_| busy_error())?;
                let sim = &mut *sim;
                let t_before = sim.t_s();
                let stepped = guarded("step", || {
                    if chunk == 0 {
                        sim.step_pipeline(left)
                    } else {
                        let k = left.min(chunk);
                        sim.step(k);
                        k
                    }
                });
                let k = match stepped {
                    Ok(k) => k,
                    Err(e) => {
                        self.stopped = Some(format!("at t = {t_before} s, {e}"));
                        return Err(e);
                    }
                };
                // A pipeline step that advanced nothing: the finiteness guard stopped the run
                // (reported just below); never loop on it.
                left -= k.min(left);
                if k == 0 {
                    left = 0;
                }
                if let Some(e) = errors.lock().ok().and_then(|mut s| s.take()) {
                    let what: String = e.to_string().chars().take(500).collect();
                    self.stopped = Some(format!(
                        "at t = {} s, Python code (a law or a guarantee) raised {what}",
                        sim.t_s()
                    ));
                    return Err(e);
                }
                if let Some(trip) = sim.guard_trip() {
                    self.stopped = Some(trip.to_string());
                    return Err(NumericError::new_err(trip.to_string()));
                }
                k
            };
            if (n - left) % 10_000 < k {
                py.check_signals()?;
            }
        }
        Ok(())
    }
}

/// The Python name of the calling thread (`threading.current_thread().name`).
fn python_thread_name(py: Python<'_>) -> String {
    py.import("threading")
        .and_then(|t| t.call_method0("current_thread"))
        .and_then(|t| t.getattr("name"))
        .and_then(|n| n.extract::<String>())
        .unwrap_or_else(|_| "unknown".into())
}

fn busy_error() -> PyErr {
    SimulationError::new_err(
        "this simulation is in use (called from inside one of its own laws or callbacks)",
    )
}

fn body_index_in(sim: &rpod::sim::Simulation, name: &str) -> PyResult<usize> {
    sim.controllers()
        .info
        .iter()
        .position(|b| b.name == name)
        .ok_or_else(|| {
            PyKeyError::new_err(format!(
                "no body named {name:?} in the scene (bodies: {})",
                sim.controllers()
                    .info
                    .iter()
                    .map(|b| b.name.as_str())
                    .collect::<Vec<_>>()
                    .join(", ")
            ))
        })
}

static STAGING: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);

fn override_value(v: &Bound<'_, PyAny>, key: &str) -> PyResult<String> {
    if v.is_instance_of::<PyBool>() {
        return Ok(if v.extract::<bool>()? {
            "true"
        } else {
            "false"
        }
        .into());
    }
    if v.is_instance_of::<PyString>() {
        return v.extract();
    }
    if v.is_instance_of::<PyInt>() || v.is_instance_of::<PyFloat>() {
        return v.repr()?.extract::<String>();
    }
    Err(PyTypeError::new_err(format!(
        "set[{key:?}]: a value must be a str (a RON value), a number or a bool"
    )))
}

/// `add_controller`'s period as a number of scene steps of `dt` s: `period_s` must be a whole
/// number of them, 1 to 10^12 (to 1e-9 relative).
fn controller_period_steps(period_s: f64, dt: f64) -> PyResult<f64> {
    let ratio = period_s / dt;
    let n = ratio.round();
    if !period_s.is_finite() || !(1.0..=1e12).contains(&n) || (ratio - n).abs() > 1e-9 * ratio {
        return Err(PyValueError::new_err(format!(
            "add_controller: period_s must be a whole number (≥ 1) of scene steps dt_s = {dt} s, got {period_s:?} s"
        )));
    }
    Ok(n)
}

/// `add_controller`'s `actuator` (RON, as in a scene; None: ideal), parsed and validated.
fn controller_actuator(actuator: Option<&str>) -> PyResult<ActuatorSpec> {
    let actuator: ActuatorSpec = match actuator {
        None => ActuatorSpec::Ideal,
        Some(s) => ron::from_str(s)
            .map_err(|e| PyValueError::new_err(format!("add_controller: actuator: {e}")))?,
    };
    actuator
        .validate()
        .map_err(|(f, m)| PyValueError::new_err(format!("add_controller: actuator.{f}: {m}")))?;
    Ok(actuator)
}

/// `add_controller`'s `sensor` (RON, as in a scene; None: none), parsed and validated, its
/// period against the scene step `dt` s.
fn controller_sensor(sensor: Option<&str>, dt: f64) -> PyResult<Option<SensorSpec>> {
    Ok(match sensor {
        None => None,
        Some(s) => {
            let spec: SensorSpec = ron::from_str(s)
                .map_err(|e| PyValueError::new_err(format!("add_controller: sensor: {e}")))?;
            spec.validate()
                .and_then(|_| spec.check_period(dt))
                .map_err(|(f, m)| {
                    PyValueError::new_err(format!("add_controller: sensor.{f}: {m}"))
                })?;
            Some(spec)
        }
    })
}

/// `add_controller`'s diagnostic `columns` (None: none): at most 1000, each 1 to 128 of
/// A-Z a-z 0-9 _ - .
fn controller_columns(columns: Option<Vec<String>>) -> PyResult<Vec<String>> {
    let columns = columns.unwrap_or_default();
    if columns.len() > 1000 {
        return Err(PyValueError::new_err(
            "add_controller: at most 1000 columns",
        ));
    }
    for c in &columns {
        if c.is_empty()
            || c.len() > 128
            || !c
                .chars()
                .all(|ch| ch.is_ascii_alphanumeric() || "_-.".contains(ch))
        {
            return Err(PyValueError::new_err(format!(
                "add_controller: column {c:?}: 1 to 128 of A-Z a-z 0-9 _ - ."
            )));
        }
    }
    Ok(columns)
}

#[pymethods]
impl PySimulation {
    /// Loads, validates and builds `scene` (a path) with `set` overrides (`{"dt_s": 0.005,
    /// "bodies.chaser.mass_kg": 250}`, as `rpod run --set`). With `out_dir` rows are written
    /// from the first step (and the t = 0 row); otherwise into a private folder until
    /// `finish(out_dir)`.
    /// `record=False` writes nothing (`finish` then only returns the summary).
    #[new]
    #[pyo3(signature = (scene, set=None, out_dir=None, record=true))]
    fn new(
        py: Python<'_>,
        scene: PathBuf,
        set: Option<Bound<'_, PyDict>>,
        out_dir: Option<PathBuf>,
        record: bool,
    ) -> PyResult<Self> {
        let mut overrides = Vec::new();
        if let Some(s) = set {
            if s.len() > 10_000 {
                return Err(PyValueError::new_err("set: at most 10000 overrides"));
            }
            for (k, v) in s.iter() {
                let key: String = k
                    .extract()
                    .map_err(|_| PyTypeError::new_err("set: keys must be str paths"))?;
                overrides.push(format!("{key}={}", override_value(&v, &key)?));
            }
        }
        let built = guarded("loading the scene", || {
            rpod::sim::Simulation::from_file(&scene, &overrides)
        })?;
        let sim = built.map_err(|e| scene_error(py, &e))?;
        let id = NEXT_SIM.fetch_add(1, Ordering::Relaxed);
        SIMS.try_with(|m| {
            m.try_borrow_mut()
                .map(|mut m| m.insert(id, Rc::new(RefCell::new(sim))))
                .is_ok()
        })
        .ok()
        .filter(|ok| *ok)
        .ok_or_else(|| SimulationError::new_err("this thread is shutting down"))?;
        let mut s = PySimulation {
            id,
            owner: std::thread::current().id(),
            owner_name: python_thread_name(py),
            finished: false,
            stopped: None,
            snapshot: None,
            scene_file: scene.display().to_string(),
            recording: None,
            staging: false,
            record,
            errors: Arc::new(Mutex::new(None)),
            python_laws: 0,
            started: false,
            applied: None,
            out_dir: out_dir.clone(),
        };
        if out_dir.is_some() {
            s.record = true;
        }
        Ok(s)
    }

    /// Simulated time, s.
    #[getter]
    fn t_s(&self) -> PyResult<f64> {
        self.with(|s| Ok(s.t_s()))
    }

    /// Completed steps.
    #[getter]
    fn steps(&self) -> PyResult<u64> {
        self.with(|s| Ok(s.steps()))
    }

    /// The scene's fixed step, s.
    #[getter]
    fn dt_s(&self) -> PyResult<f64> {
        self.with(|s| Ok(s.scene.dt_s))
    }

    /// The scene's duration, s.
    #[getter]
    fn duration_s(&self) -> PyResult<f64> {
        self.with(|s| Ok(s.scene.duration_s))
    }

    /// The scene's name.
    #[getter]
    fn name(&self) -> PyResult<String> {
        self.with(|s| Ok(s.scene.name.clone()))
    }

    /// The scene file.
    #[getter]
    fn scene_file(&self) -> String {
        self.scene_file.clone()
    }

    /// Body names, scene order.
    #[getter]
    fn body_names(&self) -> PyResult<Vec<String>> {
        self.with(|s| {
            Ok(s.controllers()
                .info
                .iter()
                .map(|b| b.name.clone())
                .collect())
        })
    }

    /// A body's constant parameters: `mass_kg`, `inertia_kg_m2` (3×3 about the centre of
    /// mass, body axes), `com_body_m` (centre of mass in the body frame), `bounding_radius_m`
    /// (a sphere about the centre of mass holding every part), `role` and `ports`
    /// ({name: {`pos_body_m`, `axis_body`}}: origin and unit outward axis, body frame).
    fn body_info<'py>(&self, py: Python<'py>, name: &str) -> PyResult<Bound<'py, PyDict>> {
        let b = self.body_index(name)?;
        let cell = self.cell()?;
        let sim = cell.try_borrow().map_err(|_| busy_error())?;
        let info = &sim.controllers().info[b];
        let d = PyDict::new(py);
        d.set_item("name", info.name.as_str())?;
        d.set_item("role", format!("{:?}", info.role))?;
        d.set_item("mass_kg", info.mass_kg)?;
        d.set_item("inertia_kg_m2", mat3(py, &info.inertia_kg_m2)?)?;
        d.set_item("com_body_m", vec3(py, &info.com_body_m))?;
        // Radius of a sphere about the centre of mass holding every part (the colliders).
        let radius = sim
            .scene
            .bodies
            .get(b)
            .map(|spec| {
                rpod::scene::parts::expand_body(spec)
                    .iter()
                    .map(|pc| {
                        (pc.pose_body.translation.vector - info.com_body_m).norm()
                            + pc.shape.bounding_radius_m()
                    })
                    .fold(0.0, f64::max)
            })
            .unwrap_or(0.0);
        d.set_item("bounding_radius_m", radius)?;
        let ports = PyDict::new(py);
        for (n, o, a) in &info.ports {
            let p = PyDict::new(py);
            p.set_item("pos_body_m", vec3(py, o))?;
            p.set_item("axis_body", vec3(py, a))?;
            ports.set_item(n.as_str(), p)?;
        }
        d.set_item("ports", ports)?;
        Ok(d)
    }

    /// A body's state, world frame: `pos_m`, `vel_m_s` (centre of mass), `quat_wxyz` (body →
    /// world), `omega_rad_s` (world components).
    fn state<'py>(&self, py: Python<'py>, name: &str) -> PyResult<Bound<'py, PyDict>> {
        self.body_index(name)?;
        let s = self.with(|s| {
            s.body(name).ok_or_else(|| {
                SimulationError::new_err(format!("body {name:?} has no state (internal)"))
            })
        })?;
        let d = PyDict::new(py);
        d.set_item("pos_m", vec3(py, &s.pos_m))?;
        d.set_item("vel_m_s", vec3(py, &s.vel_m_s))?;
        d.set_item("quat_wxyz", quat(py, &s.att))?;
        d.set_item("omega_rad_s", vec3(py, &s.omega_rad_s))?;
        Ok(d)
    }

    /// A body's state relative to the reference orbit in its rotating Hill frame (x radial out,
    /// y along-track, z orbit normal): `[x, y, z, vx, vy, vz]` in m and m/s (the velocity seen
    /// in the rotating frame), as the trajectory's `NAME.hill_*` columns. Orbit scenes only.
    fn hill_state<'py>(&self, py: Python<'py>, name: &str) -> PyResult<Bound<'py, PyArray1<f64>>> {
        self.body_index(name)?;
        let cell = self.cell()?;
        let sim = cell.try_borrow().map_err(|_| busy_error())?;
        let (r, v) = sim.reference_state().ok_or_else(|| {
            PyValueError::new_err("hill_state: the scene is not in orbit (no reference orbit)")
        })?;
        let s = sim.body(name).ok_or_else(|| {
            SimulationError::new_err(format!("body {name:?} has no state (internal)"))
        })?;
        let f = rpod::orbit::lvlh::LocalFrame::new(rpod::orbit::lvlh::LocalFrameKind::Hill, &r, &v);
        let (p, q) = f.to_local(&s.pos_m, &s.vel_m_s);
        Ok(PyArray1::from_slice(py, &[p.x, p.y, p.z, q.x, q.y, q.z]))
    }

    /// The chaser port relative to the target port now (the observation's `ports` entry):
    /// `rel_pos_m` and `rel_vel_m_s` in the target port frame (x along the target port's
    /// outward axis), `rel_quat_wxyz` (chaser port frame → target port frame),
    /// `misalignment_rad`, and both ports' world poses.
    #[pyo3(signature = (chaser, chaser_port, target, target_port))]
    fn port_relative<'py>(
        &self,
        py: Python<'py>,
        chaser: &str,
        chaser_port: &str,
        target: &str,
        target_port: &str,
    ) -> PyResult<Bound<'py, PyDict>> {
        let (a, b) = (self.body_index(chaser)?, self.body_index(target)?);
        let cell = self.cell()?;
        let sim = cell.try_borrow().map_err(|_| busy_error())?;
        let info = &sim.controllers().info;
        let pa = info[a].port(chaser_port).ok_or_else(|| {
            PyKeyError::new_err(format!("body {chaser:?} has no port {chaser_port:?}"))
        })?;
        let pb = info[b].port(target_port).ok_or_else(|| {
            PyKeyError::new_err(format!("body {target:?} has no port {target_port:?}"))
        })?;
        let sa = BodyObs::from(&sim.body(chaser).expect("a body's state"));
        let sb = BodyObs::from(&sim.body(target).expect("a body's state"));
        let p = ports_obs(
            port_pose(&info[a], &sa, &pa.0, &pa.1),
            port_pose(&info[b], &sb, &pb.0, &pb.1),
            &sb,
        );
        let d = ports_dict(py, &p)?;
        d.set_item("chaser_omega_rad_s", vec3(py, &sa.omega_rad_s))?;
        d.set_item("target_omega_rad_s", vec3(py, &sb.omega_rad_s))?;
        Ok(d)
    }

    /// Applies a force through the body's centre of mass and/or a torque over the next step
    /// only (added to whatever the scene's laws command), in the world or the body frame.
    #[pyo3(signature = (name, force_n=None, torque_nm=None, frame="world"))]
    fn apply(
        &mut self,
        name: &str,
        force_n: Option<Bound<'_, PyAny>>,
        torque_nm: Option<Bound<'_, PyAny>>,
        frame: &str,
    ) -> PyResult<()> {
        let body = self.body_index(name)?;
        let body_frame = match frame {
            "world" => false,
            "body" => true,
            f => {
                return Err(PyValueError::new_err(format!(
                    "apply: frame {f:?} (world or body)"
                )));
            }
        };
        let check = |v: Option<Bound<'_, PyAny>>, q: &str| -> PyResult<Option<Vector3<f64>>> {
            let Some(v) = v else { return Ok(None) };
            let x = extract_vec3(&v, q)?;
            if x.iter().any(|c| !c.is_finite() || c.abs() > 1e15) {
                return Err(NumericError::new_err(format!(
                    "apply({name:?}): {q} = {x:?} must be finite and below 1e15"
                )));
            }
            Ok(Some(x))
        };
        let a = Applied {
            body,
            force_n: check(force_n, "force_n")?,
            torque_nm: check(torque_nm, "torque_nm")?,
            body_frame,
        };
        if self.applied.is_none() {
            let q = Arc::new(Mutex::new(Vec::new()));
            self.with_mut(|sim| {
                sim.add_disturbance(Box::new(ApplyQueue { queue: q.clone() }));
                Ok(())
            })?;
            self.applied = Some(q);
        }
        if let Some(q) = &self.applied
            && let Ok(mut q) = q.lock()
        {
            q.push(a);
        }
        Ok(())
    }

    /// Hosts a Python callable as a control law on `body`: `fn(obs) -> command`, called at t = 0
    /// and every `period_s` (a whole number of steps), its command held in between. `obs` is a
    /// dict of numpy arrays (see the stubs); the command is a dict with `force_n`, `torque_nm`
    /// (3 numbers each), `frame` (`world`, `body`, `hill` or `target_body`; or `force_frame`,
    /// `torque_frame`), `valves` (thruster actuators) and `diagnostics` ({column: value} for
    /// the declared `columns`), or None for no command. `actuator` and `sensor` are RON as in a
    /// scene (`"Saturated(max_force_n: (5.0, 5.0, 5.0), max_torque_nm: (0.0, 0.0, 0.0))"`);
    /// `ports` = (body's port, target's port). Returns the slot's index. Call before the first
    /// step (the trajectory's header names the law's columns).
    #[pyo3(signature = (func, body, period_s, target=None, actuator=None, sensor=None, ports=None, columns=None))]
    #[allow(clippy::too_many_arguments)]
    fn add_controller(
        &mut self,
        func: Bound<'_, PyAny>,
        body: &str,
        period_s: f64,
        target: Option<&str>,
        actuator: Option<&str>,
        sensor: Option<&str>,
        ports: Option<(String, String)>,
        columns: Option<Vec<String>>,
    ) -> PyResult<usize> {
        // Refused from another thread (or after finish) before anything else.
        self.cell()?;
        if !func.is_callable() {
            return Err(PyTypeError::new_err(
                "add_controller: `func` must be callable (obs -> command dict)",
            ));
        }
        if self.recording.is_some() || self.started {
            return Err(SimulationError::new_err(
                "add_controller: controllers must be added before the first step (the trajectory's header names their columns)",
            ));
        }
        let b = self.body_index(body)?;
        let t = target.map(|t| self.body_index(t)).transpose()?;
        let dt = self.with(|s| Ok(s.scene.dt_s))?;
        let n = controller_period_steps(period_s, dt)?;
        let actuator = controller_actuator(actuator)?;
        let sensor = controller_sensor(sensor, dt)?;
        let ports = self.controller_ports(ports, body, target)?;
        let columns = controller_columns(columns)?;
        let law = PyLaw {
            func: func.unbind(),
            body: body.to_string(),
            diag: vec![f64::NAN; columns.len()],
            columns,
            error: self.errors.clone(),
            failed: false,
        };
        let slot = Slot {
            kind: "python".into(),
            body: b,
            target: t,
            period_steps: n as u64,
            sensor,
            actuator,
            ports,
            law: Box::new(law),
        };
        let k = self.with_mut(|sim| {
            sim.add_controller(slot)
                .map_err(|e| PyValueError::new_err(format!("add_controller: {e}")))
        })?;
        self.python_laws += 1;
        Ok(k)
    }

    /// Adds a guarantee written in Python: `func(view) -> margin` (a float in `unit`; ≥ 0
    /// held, < 0 violated), `view` = {`t_s`, `bodies`: per body `pos_m`, `vel_m_s`,
    /// `quat_wxyz`, `omega_rad_s`, `rate_body_rad_s` (world frame), `distances_m`: `"a/b"` →
    /// full-geometry distance of each tracked pair}. With `rate_bound` (your bound on
    /// |d margin/dt|, unit/s) it is judged on every step interval (the monitor evaluates it
    /// between samples); without, at the samples only, and the outputs say "samples only".
    /// It appears in `monitor()`, the trajectory's columns and the summary like a scene's.
    /// A raising callable or a non-finite margin stops the run with an exception naming the
    /// guarantee. Call before the first step. Returns its index among the guarantees.
    #[pyo3(signature = (func, name, unit, rate_bound=None))]
    fn add_guarantee(
        &mut self,
        py: Python<'_>,
        func: Bound<'_, PyAny>,
        name: &str,
        unit: &str,
        rate_bound: Option<f64>,
    ) -> PyResult<usize> {
        self.cell()?;
        if !func.is_callable() {
            return Err(PyTypeError::new_err(format!(
                "add_guarantee `{name}`: `func` must be callable (view -> margin)"
            )));
        }
        if self.recording.is_some() || self.started {
            return Err(SimulationError::new_err(format!(
                "add_guarantee `{name}`: guarantees must be added before the first step (the trajectory's header names their columns)"
            )));
        }
        if let Some(r) = rate_bound
            && !(r.is_finite() && r >= 0.0)
        {
            return Err(PyValueError::new_err(format!(
                "add_guarantee `{name}`: rate_bound must be a finite number ≥ 0 ({unit}/s), got {r}"
            )));
        }
        let body_names = self.with(|sim| {
            Ok(sim
                .controllers()
                .info
                .iter()
                .map(|b| b.name.clone())
                .collect())
        })?;
        let g = PyGuarantee {
            func: func.unbind(),
            name: name.to_string(),
            unit: unit.to_string(),
            rate_bound,
            body_names,
            error: self.errors.clone(),
            failed: std::sync::atomic::AtomicBool::new(false),
        };
        let k = self.with_mut(|sim| {
            sim.add_guarantee(Box::new(g))
                .map_err(|e| PyValueError::new_err(format!("add_guarantee `{name}`: {e}")))
        })?;
        self.python_laws += 1;
        // The t = 0 sample was just taken: its failure is raised now.
        if let Some(e) = self.errors.lock().ok().and_then(|mut s| s.take()) {
            self.stopped = Some(format!("at t = 0 s, guarantee `{name}` failed"));
            let _ = py;
            return Err(e);
        }
        Ok(k)
    }

    /// Advances `n` fixed steps.
    #[pyo3(signature = (n=1))]
    fn step(&mut self, py: Python<'_>, n: u64) -> PyResult<()> {
        self.advance(py, n)
    }

    /// Advances to the first step at or after `t_s` (nothing if already there).
    fn run_until(&mut self, py: Python<'_>, t_s: f64) -> PyResult<()> {
        if !t_s.is_finite() {
            return Err(PyValueError::new_err(format!(
                "run_until: t_s must be finite, got {t_s}"
            )));
        }
        let (now, n) = self.with(|sim| {
            let now = sim.t_s();
            Ok((now, sim.steps_for((t_s - now).max(0.0))))
        })?;
        if t_s <= now {
            return Ok(());
        }
        self.advance(py, n)
    }

    /// A picture of every body's full geometry now (the colliders the contacts and the monitor
    /// use), orthographic, as a `(height, width, 3)` `uint8` RGB array: the camera looks along
    /// `look_dir` (world frame) with `up` upward, centred on `centre_m` (default: the middle of
    /// the parts) over `span_m` metres of width (default: every part fits). Flat-shaded by
    /// the angle of each face to the view; a picture, not a measurement.
    /// With `fit_only=True` nothing is drawn: the view it would use, `{"centre_m", "span_m"}`
    /// (pass them back to keep a framing fixed while the bodies move).
    #[pyo3(signature = (width=480, height=360, look_dir=None, up=None, centre_m=None, span_m=None, fit_only=false))]
    #[allow(clippy::too_many_arguments)]
    fn render<'py>(
        &mut self,
        py: Python<'py>,
        width: usize,
        height: usize,
        look_dir: Option<Bound<'_, PyAny>>,
        up: Option<Bound<'_, PyAny>>,
        centre_m: Option<Bound<'_, PyAny>>,
        span_m: Option<f64>,
        fit_only: bool,
    ) -> PyResult<Bound<'py, PyAny>> {
        let look_dir = match look_dir {
            Some(v) => extract_vec3(&v, "look_dir")?,
            None => Vector3::new(0.0, 1.0, 0.0),
        };
        let up = match up {
            Some(v) => extract_vec3(&v, "up")?,
            None => Vector3::new(0.0, 0.0, 1.0),
        };
        let centre_m = centre_m.map(|v| extract_vec3(&v, "centre_m")).transpose()?;
        let view = rpod::sim::snapshot::View {
            look_dir,
            up,
            centre_m,
            span_m,
        };
        let cell = self.cell()?;
        let sim = cell.try_borrow().map_err(|_| busy_error())?;
        let snap = self
            .snapshot
            .get_or_insert_with(|| rpod::sim::snapshot::Snapshot::new(&sim));
        if fit_only {
            let (c, span) = snap
                .fit(&sim, width, height, &view)
                .map_err(|e| PyValueError::new_err(format!("render: {e}")))?;
            let d = PyDict::new(py);
            d.set_item("centre_m", vec3(py, &c))?;
            d.set_item("span_m", span)?;
            return Ok(d.into_any());
        }
        let rgb = snap
            .render(&sim, width, height, &view)
            .map_err(|e| PyValueError::new_err(format!("render: {e}")))?;
        numpy::ndarray::Array3::from_shape_vec((height, width, 3), rgb)
            .map(|a| PyArray3::from_owned_array(py, a).into_any())
            .map_err(|e| SimulationError::new_err(format!("render: {e}")))
    }

    /// The monitor now: `min_distance_m` and `closest_parts` (the closest part pair at the
    /// last step), `min_distance_run_m` (over the run), each guarantee (`margin`, `held`,
    /// `verdict`, `worst_margin`, …, in its unit), the docking state and the contacts in
    /// progress.
    fn monitor<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let cell = self.cell()?;
        let sim = cell.try_borrow().map_err(|_| busy_error())?;
        let m = sim.monitor();
        let d = PyDict::new(py);
        let name = |b: usize, p: usize| {
            m.part_names
                .get(b)
                .and_then(|v| v.get(p))
                .cloned()
                .unwrap_or_default()
        };
        match &m.closest {
            Some(c) => {
                d.set_item("min_distance_m", c.distance_m)?;
                d.set_item("closest_parts", (name(c.a, c.part_a), name(c.b, c.part_b)))?;
            }
            None => {
                d.set_item("min_distance_m", py.None())?;
                d.set_item("closest_parts", py.None())?;
            }
        }
        d.set_item(
            "min_distance_run_m",
            m.overall.as_ref().map(|o| o.distance_m),
        )?;
        d.set_item(
            "min_clearance_non_docking_m",
            sim.min_clearance_non_docking_m(),
        )?;
        let gs = PyList::empty(py);
        for g in &sim.guarantees().status {
            let gd = PyDict::new(py);
            gd.set_item("name", g.name.as_str())?;
            gd.set_item("unit", g.unit.as_str())?;
            gd.set_item("margin", g.last_margin)?;
            gd.set_item("held", g.held)?;
            gd.set_item("verdict", g.verdict)?;
            gd.set_item("judged", g.judged)?;
            gd.set_item("worst_margin", g.worst_margin)?;
            gd.set_item("worst_margin_t_s", g.worst_margin_t_s)?;
            gd.set_item("first_violation_s", g.first_violation_s)?;
            gs.append(gd)?;
        }
        d.set_item("guarantees", gs)?;
        d.set_item("docking_state", sim.docking_state())?;
        d.set_item("first_contact_s", sim.contacts().first_contact_s)?;
        d.set_item("first_collision_s", sim.contacts().first_collision_s)?;
        let cs = PyList::empty(py);
        for ((a, b), c) in &sim.contacts().active {
            let cd = PyDict::new(py);
            cd.set_item("a", a.as_str())?;
            cd.set_item("b", b.as_str())?;
            cd.set_item("docking", c.docking)?;
            cd.set_item("start_s", c.start_s)?;
            cd.set_item("peak_force_n", c.peak_force_n)?;
            cd.set_item("impulse_ns", c.impulse_ns)?;
            cs.append(cd)?;
        }
        d.set_item("contacts", cs)?;
        Ok(d)
    }

    /// Commands the docking mechanism to release, acted on at the next step: when latched,
    /// the latch opens (state `RELEASED`, a `docking_state` event) and the separation springs
    /// push the vehicles apart; otherwise a `docking_release_ignored` event. ValueError when
    /// the scene has no docking mechanism.
    fn release_docking(&self) -> PyResult<()> {
        self.with_mut(|sim| {
            if sim.release_docking("python") {
                Ok(())
            } else {
                Err(PyValueError::new_err(
                    "release_docking: the scene has no docking mechanism",
                ))
            }
        })
    }

    /// The scene's docking mechanism, or None: `chaser`, `chaser_port`, `target`,
    /// `target_port`, `seat_depth_m` (chaser port above the target port when seated, m),
    /// `mouth_radius_m`, `state`, `reason`, `t_latch_s`, `docked_state` (the state a successful
    /// docking ends in with the scene's mechanism: `LATCHED`, or `HARD_DOCKED` for
    /// `SoftCapture`), `spec` (the scene's whole `docking`
    /// entry as a dict: `magnet` (`f0_n`, `g0_m`, `max_force_n`, `activation_distance_m`, …),
    /// `latch` (`axial_tolerance_m`, `lateral_tolerance_m`, `angle_tolerance_deg`, `dwell_s`,
    /// `break_force_n`), `miss`, `contact`) and `contact_model` (its description).
    fn docking<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyDict>>> {
        let cell = self.cell()?;
        let sim = cell.try_borrow().map_err(|_| busy_error())?;
        let Some(k) = sim
            .app
            .world()
            .get_resource::<rpod::sim::docking::Docking>()
        else {
            return Ok(None);
        };
        let d = PyDict::new(py);
        d.set_item("chaser", k.spec.chaser.as_str())?;
        d.set_item("chaser_port", k.spec.chaser_port.as_str())?;
        d.set_item("target", k.spec.target.as_str())?;
        d.set_item("target_port", k.spec.target_port.as_str())?;
        d.set_item("seat_depth_m", k.spec.seat_depth_m)?;
        d.set_item("state", k.state.name())?;
        d.set_item("reason", k.reason.as_str())?;
        d.set_item("t_latch_s", k.t_latch_s)?;
        d.set_item(
            "docked_state",
            rpod::sim::docking::DockState::docked_end_state(&k.spec.mechanism).name(),
        )?;
        d.set_item("mouth_radius_m", k.spec.mouth_radius_m)?;
        let spec =
            serde_json::to_string(&k.spec).map_err(|e| SimulationError::new_err(e.to_string()))?;
        d.set_item("spec", json_loads(py, &spec)?)?;
        d.set_item("contact_model", rpod::contact::describe(&k.spec.contact))?;
        Ok(Some(d))
    }

    /// Every event so far, as dicts (`t_s`, `kind`, details), as in `events.jsonl`.
    fn events<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let ev = self.with(|s| Ok(s.events()))?;
        let s = serde_json::to_string(&ev).map_err(|e| SimulationError::new_err(e.to_string()))?;
        json_loads(py, &s)
    }

    /// The run summary so far (what `summary.json` would hold now), as a dict.
    fn summary<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let s = self.with(|s| Ok(s.summary()))?;
        json_loads(py, &s.to_string())
    }

    /// Ends the run: writes `trajectory.csv`, `events.jsonl`, `contacts.csv` and
    /// `summary.json` into `out_dir` (or the constructor's `out_dir`) and returns the summary.
    /// Without a folder (and `record=False`) nothing is written. The simulation cannot step
    /// after this.
    #[pyo3(signature = (out_dir=None))]
    fn finish<'py>(
        &mut self,
        py: Python<'py>,
        out_dir: Option<PathBuf>,
    ) -> PyResult<Bound<'py, PyAny>> {
        // Refused from another thread, or a second time, before anything is written.
        let cell = self.cell()?;
        if Rc::strong_count(&cell) > 2 {
            return Err(busy_error());
        }
        drop(cell);
        if let Some(why) = &self.stopped {
            // Rows written so far stay in the constructor's out_dir as `NAME.partial` (no
            // summary.json: the output contract's mark of a whole run), the simulation is
            // dropped (its files closed, the folder's lock released); a staging folder goes.
            let sim = SIMS
                .try_with(|m| m.try_borrow_mut().ok().and_then(|mut m| m.remove(&self.id)))
                .ok()
                .flatten();
            drop(sim);
            self.finished = true;
            if self.staging
                && let Some(dir) = self.recording.take()
            {
                staging_remove(&dir);
            }
            return Err(SimulationError::new_err(format!(
                "finish: the run stopped ({why}); no summary is written as if it were whole"
            )));
        }
        if self.record {
            self.start_recording()?;
        }
        if let (Some(rec), Some(out)) = (&self.recording, &out_dir)
            && !self.staging
            && rec != out
        {
            return Err(PyValueError::new_err(format!(
                "finish: this run records into {} (the constructor's out_dir); call finish() without a folder",
                rec.display()
            )));
        }
        if let Some(out) = &out_dir
            && out.exists()
            && !out.is_dir()
        {
            return Err(pyo3::exceptions::PyOSError::new_err(format!(
                "finish: {} exists and is not a folder (nothing was written; the run can still be finished elsewhere)",
                out.display()
            )));
        }
        let cell = SIMS
            .try_with(|m| m.try_borrow_mut().ok().and_then(|mut m| m.remove(&self.id)))
            .ok()
            .flatten()
            .ok_or_else(finished_error)?;
        self.finished = true;
        let sim = Rc::try_unwrap(cell).map_err(|_| busy_error())?.into_inner();
        let summary = guarded("finish", move || sim.finish())?.map_err(|e| {
            pyo3::exceptions::PyOSError::new_err(format!("writing the outputs: {e}"))
        })?;
        if self.staging
            && let Some(rec) = self.recording.take()
        {
            let moved = match &out_dir {
                Some(out) => move_outputs(&rec, out),
                None => Ok(()),
            };
            staging_remove(&rec);
            moved.map_err(|e| {
                pyo3::exceptions::PyOSError::new_err(format!(
                    "writing the outputs into {}: {e}",
                    out_dir
                        .as_ref()
                        .map_or(String::new(), |o| o.display().to_string())
                ))
            })?;
        }
        json_loads(py, &summary.to_string())
    }

    fn __repr__(&self) -> String {
        if std::thread::current().id() != self.owner {
            return format!(
                "rpod.Simulation({:?}, owned by thread {:?})",
                self.scene_file, self.owner_name
            );
        }
        match self.with(|s| Ok((s.t_s(), s.steps()))) {
            Ok((t, n)) => format!("rpod.Simulation({:?}, t_s={t}, steps={n})", self.scene_file),
            Err(_) if self.finished => format!("rpod.Simulation({:?}, finished)", self.scene_file),
            Err(_) => format!("rpod.Simulation({:?}, in use)", self.scene_file),
        }
    }
}

/// Moves a finished run's files from the staging folder into `out` under the output contract
/// (the folder locked, an earlier run's files removed, files created new).
fn move_outputs(from: &Path, out: &Path) -> std::io::Result<()> {
    use rpod::sim::output::{FolderLock, RUN_FILES};
    let lock = FolderLock::acquire(out)?;
    lock.clear(&RUN_FILES)?;
    // summary.json last, as the output contract says: a folder without it holds no whole run.
    for n in RUN_FILES.iter().filter(|n| **n != "summary.json") {
        copy_new(&from.join(n), &out.join(n))?;
    }
    copy_new(&from.join("summary.json"), &out.join("summary.json"))?;
    drop(lock);
    Ok(())
}

fn copy_new(from: &Path, to: &Path) -> std::io::Result<()> {
    if !from.exists() {
        return Ok(());
    }
    let mut src = std::fs::File::open(from)?;
    let mut dst = std::fs::OpenOptions::new()
        .write(true)
        .create_new(true)
        .open(to)?;
    std::io::copy(&mut src, &mut dst)?;
    dst.sync_all()
}

fn json_loads<'py>(py: Python<'py>, s: &str) -> PyResult<Bound<'py, PyAny>> {
    py.import("json")?.call_method1("loads", (s,))
}

/// The extension module.
#[pymodule]
fn _rpod(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PySimulation>()?;
    m.add_function(wrap_pyfunction!(_remove_staging_folders, m)?)?;
    // Staging folders of simulations still alive at exit are removed then.
    m.py()
        .import("atexit")?
        .call_method1("register", (m.getattr("_remove_staging_folders")?,))?;
    m.add("SceneError", m.py().get_type::<SceneError>())?;
    m.add("NumericError", m.py().get_type::<NumericError>())?;
    m.add("SimulationError", m.py().get_type::<SimulationError>())?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
