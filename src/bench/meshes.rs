//! `rpod bench --meshes`: the costs of mesh parts, plumes and requirements, each a ratio to its plain case
//! measured in the same run, with the floors (a bare rapier step of the same world, one bare
//! parry distance query per tracked pair) measured in the same run too:
//!
//! 1. a fly-by of a 100 000-triangle target 20 m away against the same fly-by past the `Box`
//!    primitive of the same size (goal ≤ 3×);
//! 2. the same with 1.9 m of clearance (goal ≤ 10×; rapier stays asleep above 1 m, so this is
//!    the monitor's cost);
//! 3. the flagship flown against the example mesh vehicle (`orbit_approach_latch_truss.ron`)
//!    against the flagship (`orbit_approach_latch.ron`), over the same windows of steps with the
//!    chaser held 100 m, 10 m and 1 m out (goal ≤ 2×);
//! 4. the cost per step of each guarantee kind, as the ratio of a run with it alone to the same
//!    run with no guarantee.
//! 5. the cost per step of the plume impingement loads on
//!    `orbit_approach_plume.ron` held 10 m out, as the ratio of the run with them to the same
//!    run with `plume_loads: false`.
//!
//! The 100 000-triangle target ([`tessellated_box`]) is generated here at run time and written
//! as an OBJ file into a fresh temporary folder that is removed afterwards; nothing else is
//! written.

use super::{Measure, measure, measure_within, window_rate};
use crate::scene::{LoadedScene, SceneError, load_scene_file, load_scene_str};
use crate::sim::Simulation;
use nalgebra::Vector3;
use std::collections::HashMap;
use std::fmt::Write;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Size of the fly-by target, m (x, y, z): a spacecraft bus.
pub const TARGET_SIZE_M: [f64; 3] = [2.0, 2.0, 1.5];

/// Cells per axis of the tessellated target: 2 cm squares, 4·(nx·ny + ny·nz + nz·nx) =
/// 100 000 triangles.
pub const TARGET_CELLS: [usize; 3] = [100, 100, 75];

/// The fly-by chaser: a 1 m cube at a fixed attitude (no face parallel to the target's, so the
/// closest feature is a corner), yaw, pitch, roll in degrees.
pub const CHASER_ATTITUDE_DEG: [f64; 3] = [30.0, 20.0, 10.0];

/// Fly-by speed along x, m/s.
pub const FLYBY_SPEED_M_S: f64 = 0.5;

/// A box of `size_m` (centred on the origin) whose faces are cut into `cells` squares per axis,
/// two triangles each: vertices (m, welded: the lattice points of the surface, so the mesh is
/// closed) and triangles counter-clockwise seen from outside. 4·(nx·ny + ny·nz + nz·nx)
/// triangles.
pub fn tessellated_box(size_m: [f64; 3], cells: [usize; 3]) -> (Vec<[f64; 3]>, Vec<[u32; 3]>) {
    let mut index: HashMap<[usize; 3], u32> = HashMap::new();
    let mut vertices: Vec<[f64; 3]> = Vec::new();
    let mut triangles = Vec::new();
    let mut vertex = |c: [usize; 3], vertices: &mut Vec<[f64; 3]>| -> u32 {
        *index.entry(c).or_insert_with(|| {
            vertices.push(std::array::from_fn(|i| {
                -size_m[i] / 2.0 + size_m[i] * c[i] as f64 / cells[i] as f64
            }));
            (vertices.len() - 1) as u32
        })
    };
    for a in 0..3 {
        // (u, v) with u × v = +a.
        let (u, v) = ((a + 1) % 3, (a + 2) % 3);
        for side in [0, cells[a]] {
            for p in 0..cells[u] {
                for q in 0..cells[v] {
                    let corner = |dp: usize, dq: usize| {
                        let mut c = [0; 3];
                        c[a] = side;
                        c[u] = p + dp;
                        c[v] = q + dq;
                        c
                    };
                    let [c00, c10, c11, c01] =
                        [corner(0, 0), corner(1, 0), corner(1, 1), corner(0, 1)]
                            .map(|c| vertex(c, &mut vertices));
                    if side == 0 {
                        triangles.push([c00, c11, c10]);
                        triangles.push([c00, c01, c11]);
                    } else {
                        triangles.push([c00, c10, c11]);
                        triangles.push([c00, c11, c01]);
                    }
                }
            }
        }
    }
    (vertices, triangles)
}

/// A sphere of radius `radius_m` as a latitude–longitude mesh: `bands` bands of latitude
/// (even, so the equator is a ring) and `segments` meridians (a multiple of 4, so the ±x and ±y
/// extremes are vertices), a single vertex at each pole: 2·segments·(bands − 1) triangles,
/// counter-clockwise seen from outside, vertices on the sphere (it is inscribed in the `Sphere`
/// primitive, within radius·(1 − cos(π/bands)) of it) and its bounding box the primitive's.
pub fn uv_sphere(radius_m: f64, bands: usize, segments: usize) -> (Vec<[f64; 3]>, Vec<[u32; 3]>) {
    use std::f64::consts::PI;
    let mut v = vec![[0.0, 0.0, radius_m]];
    for k in 1..bands {
        let th = PI * k as f64 / bands as f64;
        for j in 0..segments {
            let ph = 2.0 * PI * j as f64 / segments as f64;
            // Exact zeros and ones at the quarter turns (the bounding box is the primitive's).
            let (s, c) = match (4 * j) % segments {
                0 => match 4 * j / segments {
                    0 => (0.0, 1.0),
                    1 => (1.0, 0.0),
                    2 => (0.0, -1.0),
                    _ => (-1.0, 0.0),
                },
                _ => ph.sin_cos(),
            };
            let (st, ct) = if 2 * k == bands {
                (1.0, 0.0)
            } else {
                th.sin_cos()
            };
            v.push([radius_m * st * c, radius_m * st * s, radius_m * ct]);
        }
    }
    v.push([0.0, 0.0, -radius_m]);
    let south = (v.len() - 1) as u32;
    let ring = |k: usize, j: usize| (1 + (k - 1) * segments + j % segments) as u32;
    let mut t = Vec::new();
    for j in 0..segments {
        t.push([0, ring(1, j), ring(1, j + 1)]);
        for k in 1..bands - 1 {
            let (a, b, c, d) = (
                ring(k, j),
                ring(k + 1, j),
                ring(k + 1, j + 1),
                ring(k, j + 1),
            );
            t.push([a, b, c]);
            t.push([a, c, d]);
        }
        t.push([south, ring(bands - 1, j + 1), ring(bands - 1, j)]);
    }
    (v, t)
}

/// Radius of the spherical fly-by target, m.
pub const SPHERE_RADIUS_M: f64 = 1.0;

/// Latitude bands and meridians of the spherical target: 2·400·125 = 100 000 triangles.
pub const SPHERE_BANDS_SEGMENTS: [usize; 2] = [126, 400];

/// The mesh as OBJ text (one object, `target`).
pub fn obj_text(vertices: &[[f64; 3]], triangles: &[[u32; 3]]) -> String {
    let mut s = String::with_capacity(40 * (vertices.len() + triangles.len()));
    s.push_str("# rpod bench --meshes: tessellated box\no target\n");
    for v in vertices {
        let _ = writeln!(s, "v {} {} {}", v[0], v[1], v[2]);
    }
    for t in triangles {
        let _ = writeln!(s, "f {} {} {}", t[0] + 1, t[1] + 1, t[2] + 1);
    }
    s
}

/// The fly-by chaser's lowest corner (along −y) relative to its centre, m, world axes, at
/// [`CHASER_ATTITUDE_DEG`].
pub fn chaser_lowest_corner_m() -> Vector3<f64> {
    let [yaw, pitch, roll] = CHASER_ATTITUDE_DEG;
    let q = crate::scene::AttitudeSpec::EulerZyxDeg { yaw, pitch, roll }.to_quat();
    (0..8)
        .map(|i| {
            q * Vector3::new(
                if i & 1 == 0 { -0.5 } else { 0.5 },
                if i & 2 == 0 { -0.5 } else { 0.5 },
                if i & 4 == 0 { -0.5 } else { 0.5 },
            )
        })
        .min_by(|a, b| a.y.total_cmp(&b.y))
        .unwrap_or_default()
}

/// A fly-by target: its shape as a primitive and as a 100 000-triangle mesh, and the height of
/// its top (+y) above its centre, m.
#[derive(Debug, Clone, Copy)]
pub enum FlybyTarget {
    /// A 2 × 2 × 1.5 m box ([`tessellated_box`]).
    Box,
    /// A 1 m sphere ([`uv_sphere`]).
    Sphere,
}

impl FlybyTarget {
    /// Its primitive, as RON.
    pub fn primitive(self) -> String {
        match self {
            FlybyTarget::Box => {
                let [x, y, z] = TARGET_SIZE_M;
                format!("Box(size_m: ({x:?}, {y:?}, {z:?}))")
            }
            FlybyTarget::Sphere => format!("Sphere(radius_m: {SPHERE_RADIUS_M:?})"),
        }
    }
    /// Its mesh: vertices (m) and triangles.
    pub fn mesh(self) -> (Vec<[f64; 3]>, Vec<[u32; 3]>) {
        match self {
            FlybyTarget::Box => tessellated_box(TARGET_SIZE_M, TARGET_CELLS),
            FlybyTarget::Sphere => {
                let [bands, segments] = SPHERE_BANDS_SEGMENTS;
                uv_sphere(SPHERE_RADIUS_M, bands, segments)
            }
        }
    }
    /// Height of its +y extreme above its centre, m.
    pub fn top_y_m(self) -> f64 {
        match self {
            FlybyTarget::Box => TARGET_SIZE_M[1] / 2.0,
            FlybyTarget::Sphere => SPHERE_RADIUS_M,
        }
    }
    fn label(self) -> &'static str {
        match self {
            FlybyTarget::Box => "2 × 2 × 1.5 m box",
            FlybyTarget::Sphere => "1 m sphere",
        }
    }
}

/// The fly-by scene: the target (`target_shape`, a part shape as RON, its top `top_y_m` above
/// its centre) at rest at the origin, and the chaser's 1 m cube flying along +x at
/// [`FLYBY_SPEED_M_S`] from `start_x_m`, its lowest corner passing over the target's centre
/// line (z = 0) `clearance_m` above the target's top — the closest approach, when the corner
/// is over the top. Free space, two bodies (the monitor tracks the pair exactly every step),
/// no law, no guarantee.
pub fn flyby_scene(
    name: &str,
    target_shape: &str,
    top_y_m: f64,
    clearance_m: f64,
    start_x_m: f64,
) -> String {
    let [yaw, pitch, roll] = CHASER_ATTITUDE_DEG;
    let c = chaser_lowest_corner_m();
    let (y, z) = (top_y_m + clearance_m - c.y, -c.z);
    format!(
        r#"Scene(name: "{name}", dt_s: 0.01, duration_s: 1000.0, environment: FreeSpace,
    bodies: [
      (name: "target", role: Target, mass_kg: 800.0, inertia_kg_m2: (xx: 620.0, yy: 910.0, zz: 1080.0),
       initial: (pos_m: (0.0, 0.0, 0.0)),
       parts: [Bus(name: "body", shape: {target_shape})]),
      (name: "chaser", role: Chaser, mass_kg: 300.0, inertia_kg_m2: (xx: 110.0, yy: 140.0, zz: 160.0),
       initial: (pos_m: ({start_x_m:?}, {y:?}, {z:?}), vel_m_s: ({FLYBY_SPEED_M_S:?}, 0.0, 0.0),
                 attitude: EulerZyxDeg(yaw: {yaw:?}, pitch: {pitch:?}, roll: {roll:?})),
       parts: [Bus(name: "bus", shape: Box(size_m: (1.0, 1.0, 1.0)))]),
    ],
)
"#
    )
}

/// A fresh folder under the system's temporary directory, removed (with what it holds) when
/// dropped. Created with `create_dir`, so an existing path (or a link planted there) is an
/// error, never reused.
struct TempDir(PathBuf);

impl TempDir {
    fn new() -> std::io::Result<Self> {
        let nanos = std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .map_or(0, |d| d.as_nanos());
        let p =
            std::env::temp_dir().join(format!("rpod-bench-meshes-{}-{nanos}", std::process::id()));
        std::fs::create_dir(&p)?;
        Ok(Self(p))
    }
}

impl Drop for TempDir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

fn io_error(what: &str, e: std::io::Error) -> SceneError {
    SceneError {
        file: what.to_string(),
        line: 0,
        col: 0,
        field: String::new(),
        message: e.to_string(),
    }
}

/// Wall time a mesh case may take, s: its steps are cut to fit (and its plain case gets the
/// same steps), so that the whole `--meshes` run stays within about three minutes on a busy
/// two-core machine.
pub const CASE_BUDGET_S: f64 = 10.0;

/// A line on stderr saying which case is done (the report itself goes to stdout at the end).
fn progress(what: &str) {
    eprintln!("bench --meshes: {what}");
}

/// Steps that fit in `budget_s` at the pipeline's cost per step, timed over a few steps of a
/// fresh run of `loaded` (at least 20, at most `steps`).
fn steps_within(loaded: &LoadedScene, steps: u64, budget_s: f64) -> Result<u64, SceneError> {
    let mut sim = Simulation::new(loaded)?;
    sim.step(2);
    let t0 = Instant::now();
    let mut n = 0;
    while n < 50 && (n < 3 || t0.elapsed().as_secs_f64() < 0.5) {
        sim.step(1);
        n += 1;
    }
    let per_step_s = t0.elapsed().as_secs_f64() / n as f64;
    progress(&format!(
        "{}: {:.3} ms/step over {n} steps",
        loaded.scene.name,
        per_step_s * 1e3
    ));
    Ok(((budget_s / per_step_s) as u64).clamp(20, steps))
}

/// Wall seconds of the fastest of `repeats` runs of `steps` steps after `skip` untimed ones
/// (the least disturbed by the machine's other work).
fn best_window_s(
    loaded: &LoadedScene,
    skip: u64,
    steps: u64,
    repeats: usize,
) -> Result<f64, SceneError> {
    let mut best = f64::INFINITY;
    for _ in 0..repeats {
        let (rate, _) = window_rate(loaded, skip, steps)?;
        best = best.min(steps as f64 / rate);
    }
    Ok(best)
}

/// Steps of a fly-by window: the corner from 1 m before the target's top to 1 m past it at
/// [`FLYBY_SPEED_M_S`] (cut to [`CASE_BUDGET_S`] for a slow mesh).
pub const FLYBY_STEPS: u64 = 400;

/// Runs of each fly-by case, mesh and primitive alternately, the fastest of each kept: one run
/// is a few milliseconds of wall time, which another process on the machine can double.
/// Fewer when the case's wall time passes [`CASE_BUDGET_S`].
pub const FLYBY_REPEATS: usize = 5;

/// One fly-by target at one clearance: the mesh measured over the window (or the part of it
/// that fits in [`CASE_BUDGET_S`]), then the primitive over the same steps, each the fastest
/// of [`FLYBY_REPEATS`] runs, as two table rows.
fn flyby_rows(
    r: &mut String,
    dir: &Path,
    target: FlybyTarget,
    clearance_m: f64,
    goal: f64,
) -> Result<(), SceneError> {
    let scene_file = dir.join("flyby.ron").display().to_string();
    let mesh_shape = r#"Mesh(path: "target_100k.obj")"#;
    // Two untimed steps, then the window: the corner passes over the top mid-window.
    let warm_up = 2;
    let dt = 0.01;
    let start_x_m = -chaser_lowest_corner_m().x
        - FLYBY_SPEED_M_S * dt * (warm_up as f64 + FLYBY_STEPS as f64 / 2.0);
    let load = |shape: &str| {
        load_scene_str(
            &flyby_scene("flyby", shape, target.top_y_m(), clearance_m, start_x_m),
            &scene_file,
            &[],
        )
    };
    let t0 = Instant::now();
    let (mesh_scene, prim_scene) = (load(mesh_shape)?, load(&target.primitive())?);
    let mut m = measure_within(&mesh_scene, warm_up, FLYBY_STEPS, CASE_BUDGET_S)?;
    let mut p = measure_within(&prim_scene, warm_up, m.steps, f64::INFINITY)?;
    let mut runs = 1;
    while runs < FLYBY_REPEATS && t0.elapsed().as_secs_f64() < CASE_BUDGET_S {
        let m2 = measure_within(&mesh_scene, warm_up, m.steps, f64::INFINITY)?;
        if m2.pipeline_s < m.pipeline_s {
            m = m2;
        }
        let p2 = measure_within(&prim_scene, warm_up, m.steps, f64::INFINITY)?;
        if p2.pipeline_s < p.pipeline_s {
            p = p2;
        }
        runs += 1;
    }
    progress(&format!(
        "fly-by {} at {clearance_m} m: {} steps, fastest of {runs} runs ({:.0} s)",
        target.label(),
        m.steps,
        t0.elapsed().as_secs_f64()
    ));
    let per = |x: &Measure, s: f64| s / x.steps as f64 * 1e6;
    for (label, x, is_mesh) in [
        (format!("{} primitive", target.label()), &p, false),
        (
            format!("{} mesh, 100 000 triangles", target.label()),
            &m,
            true,
        ),
    ] {
        let ratio = if is_mesh {
            let q = m.pipeline_s / p.pipeline_s;
            format!(
                "**{q:.2}** (goal ≤ {goal}: {})",
                if q <= goal { "met" } else { "NOT met" }
            )
        } else {
            "1".to_string()
        };
        let _ = writeln!(
            r,
            "| {clearance_m} m | {label} | {} | {:.1} | {:.2} | {:.2} | {:.1} | {ratio} |",
            x.steps,
            per(x, x.pipeline_s),
            per(x, x.rapier_s),
            per(x, x.parry_s),
            x.exact_per_step,
        );
    }
    Ok(())
}

/// The `--set` overrides that hold the flagship's chaser with its port `range_m` out on the
/// target port's axis: it starts there at rest in the Hill frame and the first phase
/// (`hold100`) holds it there (its exit needs 60 s in the phase: beyond every window).
fn held_at(range_m: f64) -> Vec<String> {
    // Port 0.82 m ahead of the target's centre on Hill −y; the chaser's port 0.5 m ahead of
    // its centre of mass.
    vec![
        format!(
            "bodies.chaser.initial.pos_m=(0.0, {:?}, 0.0)",
            -(range_m + 0.82 + 0.5)
        ),
        format!(
            "controllers.1.params.phases.hold100.translation=Some(HillPd((hold_m: (0.0, {:?}, 0.0), \
             point: Port, gains: Pd(natural_frequency_rad_s: 0.05, damping_ratio: 1.0))))",
            -range_m
        ),
    ]
}

/// The guarantee kinds measured, each as the scene entry written alone in the base scene:
/// (kind, entry, base: requirements (true) or plume (false)).
fn guarantee_cases() -> Vec<(&'static str, &'static str, bool)> {
    vec![
        (
            "MinDistance",
            r#"MinDistance(name: "g", a: "chaser", b: "target", min_m: 1.0)"#,
            true,
        ),
        (
            "KeepOutSphere",
            r#"KeepOutSphere(name: "g", body: "chaser", around: "target", radius_m: 5.0)"#,
            true,
        ),
        (
            "ApproachCone",
            r#"ApproachCone(name: "g", body: "chaser", around: "target", port: "dock", half_angle_deg: 20.0, from_range_m: 30.0, to_range_m: 4.0)"#,
            true,
        ),
        (
            "KeepOutEllipsoid",
            r#"KeepOutEllipsoid(name: "g", body: "chaser", around: "target", semi_axes_m: (5.0, 8.0, 5.0), frame: Hill)"#,
            true,
        ),
        (
            "ClosingSpeedGate",
            r#"ClosingSpeedGate(name: "g", body: "chaser", around: "target", gates: [(150.0, 0.30), (30.0, 0.10), (12.0, 0.08)], ports: Some(("dock", "dock")))"#,
            true,
        ),
        (
            "PassiveSafety",
            r#"PassiveSafety(name: "g", body: "chaser", around: "target", radius_m: Some(2.5), horizon_s: 3000.0, grid_s: 5.0)"#,
            true,
        ),
        (
            "LineOfSight",
            r#"LineOfSight(name: "g", sensor_body: "chaser", position_m: (0.52, 0.0, -0.4), boresight: (1.0, 0.0, 0.0), half_fov_deg: 15.0, range_m: 150.0, target: "target", port: "marker", standoff_m: 0.02, clearance_m: 0.0)"#,
            true,
        ),
        (
            "PlumeKeepOff",
            r#"PlumeKeepOff(name: "g", body: "chaser", around: "target", parts: ["wing_*.panel*"])"#,
            false,
        ),
    ]
}

/// Runs the five measurements and returns the report (Markdown tables). `scenes` is the folder
/// holding `orbit_approach_latch.ron`, `orbit_approach_latch_truss.ron`,
/// `requirements_approach.ron` and `orbit_approach_plume.ron`; `steps` the most steps per case
/// (a mesh case is cut to [`CASE_BUDGET_S`] of wall time).
pub fn run_meshes(scenes: &Path, steps: u64) -> Result<String, SceneError> {
    let steps = steps.max(100);
    let mut r = String::new();

    // 1–2. Fly-bys.
    let _ = writeln!(
        r,
        "Fly-bys: a 1 m cube chaser (yaw/pitch/roll {CHASER_ATTITUDE_DEG:?}°, no rotation) along +x \
         at {FLYBY_SPEED_M_S} m/s, its lowest corner passing the stated clearance above the \
         target's top (+y); the target a primitive or a mesh of it generated here (100 000 \
         triangles: the box {TARGET_CELLS:?} cells of 2 cm per axis, welded and closed; the \
         sphere {} latitude bands × {} meridians). Each pair over the same steps after 2 untimed \
         ones: {FLYBY_STEPS} steps, the corner from 1 m before the top to 1 m past it, or the \
         first part of them when the mesh's took more than {CASE_BUDGET_S} s of wall time; the \
         fastest of {FLYBY_REPEATS} runs each, mesh and primitive alternately (fewer when a \
         case passes that time). µs per step; the floors on the same world in the same run \
         (bare parry: one distance query per step between the closest parts).\n",
        SPHERE_BANDS_SEGMENTS[0], SPHERE_BANDS_SEGMENTS[1]
    );
    let _ = writeln!(
        r,
        "| clearance | target | steps | pipeline µs/step | bare rapier µs/step | bare parry µs/step | exact queries/step | pipeline ratio to the primitive |"
    );
    let _ = writeln!(r, "|---|---|---|---|---|---|---|---|");
    for target in [FlybyTarget::Sphere, FlybyTarget::Box] {
        let dir = TempDir::new().map_err(|e| io_error("temporary folder", e))?;
        let (v, t) = target.mesh();
        std::fs::write(dir.0.join("target_100k.obj"), obj_text(&v, &t))
            .map_err(|e| io_error("temporary mesh", e))?;
        for (clearance_m, goal) in [(20.0, 3.0), (1.9, 10.0)] {
            flyby_rows(&mut r, &dir.0, target, clearance_m, goal)?;
        }
    }

    // 3. The flagship with the example mesh vehicle.
    let _ = writeln!(
        r,
        "\nThe flagship against the example mesh vehicle (`orbit_approach_latch_truss.ron`, \
         32 048 triangles) and against its box-and-wings target (`orbit_approach_latch.ron`): the \
         chaser held with its port at the stated range on the port axis (`--set` of its initial \
         position and of the `hold100` phase's hold point, the same in both), the same steps \
         after 100 untimed ones, the faster of two runs each.\n"
    );
    let _ = writeln!(
        r,
        "| chaser port range | steps | flagship µs/step | mesh vehicle µs/step | ratio | goal |"
    );
    let _ = writeln!(r, "|---|---|---|---|---|---|");
    for range_m in [100.0, 10.0, 1.0] {
        let sets = held_at(range_m);
        let plain = load_scene_file(&scenes.join("orbit_approach_latch.ron"), &sets)?;
        let truss = load_scene_file(&scenes.join("orbit_approach_latch_truss.ron"), &sets)?;
        let n = steps_within(&truss, steps, CASE_BUDGET_S / 4.0)?;
        let p = best_window_s(&plain, 100, n, 2)?;
        let m = best_window_s(&truss, 100, n, 2)?;
        let ratio = m / p;
        progress(&format!("flagship at {range_m} m: {n} steps"));
        let us = |s: f64| s / n as f64 * 1e6;
        let _ = writeln!(
            r,
            "| {range_m} m | {n} | {:.1} | {:.1} | **{ratio:.2}** | ≤ 2 ({}) |",
            us(p),
            us(m),
            if ratio <= 2.0 { "met" } else { "NOT met" }
        );
    }

    // 4. Per guarantee kind.
    let _ = writeln!(
        r,
        "\nGuarantees: each kind alone against the same run with none (`guarantees=[]`), the \
         chaser held 10 m out as above; base `requirements_approach.ron` (circular orbit, no J2, \
         noisy sensor and Kalman filter), except `PlumeKeepOff` on `orbit_approach_plume.ron` \
         (16 plumed 4 N jets) with `plume_loads: false` (the loads are not the guarantee's \
         cost). The same steps after 100 untimed ones for a kind and its base, the faster of \
         two runs each; the floors on the requirements world.\n"
    );
    let sets_with = |entry: &str, plume: bool| {
        let mut s = held_at(10.0);
        s.push(format!("guarantees=[{entry}]"));
        if plume {
            s.push("controllers.1.actuator.plume_loads=false".into());
        }
        s
    };
    let req = scenes.join("requirements_approach.ron");
    let plume = scenes.join("orbit_approach_plume.ron");
    let base_req = load_scene_file(&req, &sets_with("", false))?;
    let base_plume = load_scene_file(&plume, &sets_with("", true))?;
    let _ = writeln!(
        r,
        "| guarantee | base | steps | base µs/step | with it µs/step | added µs/step | ratio to the run without it |"
    );
    let _ = writeln!(r, "|---|---|---|---|---|---|---|");
    for (kind, entry, on_req) in guarantee_cases() {
        let (file, base, name) = if on_req {
            (&req, &base_req, "requirements_approach")
        } else {
            (&plume, &base_plume, "orbit_approach_plume")
        };
        let l = load_scene_file(file, &sets_with(entry, !on_req))?;
        let n = steps_within(&l, steps, CASE_BUDGET_S / 8.0)?;
        let b = best_window_s(base, 100, n, 2)?;
        let x = best_window_s(&l, 100, n, 2)?;
        progress(&format!("{kind}: {n} steps"));
        let us = |s: f64| s / n as f64 * 1e6;
        let _ = writeln!(
            r,
            "| {kind} | {name} | {n} | {:.1} | {:.1} | {:+.1} | **{:.2}** |",
            us(b),
            us(x),
            us(x) - us(b),
            x / b
        );
    }
    // 5. The plume impingement loads.
    let _ = writeln!(
        r,
        "\nPlume impingement loads: `orbit_approach_plume.ron` held 10 m out as above with no \
         guarantee, the loads on (the default) against `plume_loads: false` (the base of \
         `PlumeKeepOff` above); the forward jets exhaust at the target's bus, slot and arrays \
         whenever the hold brakes. The same steps after 100 untimed ones, the faster of two runs \
         each.\n"
    );
    let _ = writeln!(
        r,
        "| base | steps | loads off µs/step | loads on µs/step | added µs/step | ratio to the run without them |"
    );
    let _ = writeln!(r, "|---|---|---|---|---|---|");
    let mut sets = held_at(10.0);
    sets.push("guarantees=[]".into());
    let loads_on = load_scene_file(&plume, &sets)?;
    let n = steps_within(&loads_on, steps, CASE_BUDGET_S / 8.0)?;
    let b = best_window_s(&base_plume, 100, n, 2)?;
    let x = best_window_s(&loads_on, 100, n, 2)?;
    progress(&format!("plume loads: {n} steps"));
    let us = |s: f64| s / n as f64 * 1e6;
    let _ = writeln!(
        r,
        "| orbit_approach_plume | {n} | {:.1} | {:.1} | {:+.1} | **{:.2}** |",
        us(b),
        us(x),
        us(x) - us(b),
        x / b
    );
    let floor = measure(&base_req, steps)?;
    let per = |s: f64| s / floor.steps as f64 * 1e6;
    let _ = writeln!(
        r,
        "\nFloors on the requirements world ({} steps): pipeline without guarantees {:.1} µs/step, \
         bare rapier step {:.2} µs/step, bare parry distance {:.2} µs/step ({} query/step, the \
         closest part pair).",
        floor.steps,
        per(floor.pipeline_s),
        per(floor.rapier_s),
        per(floor.parry_s),
        floor.parry_queries
    );
    Ok(r)
}

#[cfg(test)]
mod tests {
    //! Reference: the tessellated box is the `Box` primitive's surface — its vertices span
    //! exactly the primitive's bounding box, every vertex lies on a face, its triangle count is
    //! 4·(nx·ny + ny·nz + nz·nx) = 100 000, it is closed and consistently oriented
    //! (`geometry::mesh::check_closed`), and its volume from the divergence theorem is the
    //! box's (2 × 2 × 1.5 = 6 m³). The fly-by's closest approach is the stated clearance: the
    //! cube's lowest corner (the support along −y of the rotated cube) passes that far above
    //! the +y face — checked against an independent computation of the corners' heights.
    use super::*;
    use crate::geometry::mesh::{MeshComponent, check_closed, mass_properties};
    use nalgebra::Point3;

    #[test]
    fn invariant_bench_tessellated_box_is_the_primitive() {
        let (v, t) = tessellated_box(TARGET_SIZE_M, TARGET_CELLS);
        assert_eq!(t.len(), 100_000);
        // Euler: V − E + F = 2 with E = 3F/2 for a closed triangle mesh.
        assert_eq!(v.len(), 2 + t.len() / 2);
        for i in 0..3 {
            let lo = v.iter().map(|p| p[i]).fold(f64::MAX, f64::min);
            let hi = v.iter().map(|p| p[i]).fold(f64::MIN, f64::max);
            assert_eq!((lo, hi), (-TARGET_SIZE_M[i] / 2.0, TARGET_SIZE_M[i] / 2.0));
        }
        for p in &v {
            assert!(
                (0..3).any(|i| (p[i].abs() - TARGET_SIZE_M[i] / 2.0).abs() < 1e-12),
                "{p:?} is not on a face"
            );
        }
        let c = MeshComponent {
            decomposition: Default::default(),
            name: "target".into(),
            offset_m: Vector3::zeros(),
            vertices_m: v.iter().map(|p| Point3::from(*p)).collect(),
            triangles: t,
        };
        check_closed(&c).expect("closed and consistently oriented");
        let vol = TARGET_SIZE_M.iter().product::<f64>();
        let mp = mass_properties(&c, 1.0);
        assert!((mp.mass_kg - vol).abs() < 1e-9 * vol, "{}", mp.mass_kg);
    }

    #[test]
    fn invariant_bench_obj_round_trips_through_the_loader() {
        // A coarse box (3 × 2 × 1 cells) written and read back: the loader's triangle count
        // and bounding box.
        let (v, t) = tessellated_box([2.0, 1.0, 0.5], [3, 2, 1]);
        let dir = TempDir::new().expect("temp dir");
        let path = dir.0.join("b.obj");
        std::fs::write(&path, obj_text(&v, &t)).expect("write");
        let m = crate::geometry::mesh::load_mesh_file(&path, 1.0, &[], 1000).expect("loads");
        assert_eq!(m.components.len(), 1);
        let c = &m.components[0];
        assert_eq!(c.triangles.len(), 4 * (6 + 2 + 3));
        for (i, half) in [1.0, 0.5, 0.25].into_iter().enumerate() {
            let hi = c
                .vertices_m
                .iter()
                .map(|p| p[i] + c.offset_m[i])
                .fold(f64::MIN, f64::max);
            assert!((hi - half).abs() < 1e-12, "{hi}");
        }
        let p = dir.0.clone();
        drop(dir);
        assert!(!p.exists(), "the temporary folder is removed");
    }

    #[test]
    fn invariant_bench_uv_sphere_is_the_primitive() {
        let [bands, segments] = SPHERE_BANDS_SEGMENTS;
        let (v, t) = uv_sphere(SPHERE_RADIUS_M, bands, segments);
        assert_eq!(t.len(), 100_000);
        assert_eq!(v.len(), 2 + t.len() / 2);
        for p in &v {
            let r = Vector3::from(*p).norm();
            assert!((r - SPHERE_RADIUS_M).abs() < 1e-12, "{r}");
        }
        for i in 0..3 {
            let lo = v.iter().map(|p| p[i]).fold(f64::MAX, f64::min);
            let hi = v.iter().map(|p| p[i]).fold(f64::MIN, f64::max);
            assert_eq!((lo, hi), (-SPHERE_RADIUS_M, SPHERE_RADIUS_M));
        }
        let c = MeshComponent {
            decomposition: Default::default(),
            name: "target".into(),
            offset_m: Vector3::zeros(),
            vertices_m: v.iter().map(|p| Point3::from(*p)).collect(),
            triangles: t,
        };
        check_closed(&c).expect("closed and consistently oriented");
        // The inscribed polyhedron's volume is below the ball's, by at most the shell between
        // the ball and the sphere of radius R·cos(π/bands) (every face is at least that far
        // from the centre... for these thin bands, within 2·(1 − cos(π/bands)) relative).
        let ball = 4.0 / 3.0 * std::f64::consts::PI * SPHERE_RADIUS_M.powi(3);
        let vol = mass_properties(&c, 1.0).mass_kg;
        let shell = 3.0 * (1.0 - (std::f64::consts::PI / bands as f64).cos());
        assert!(vol < ball && vol > ball * (1.0 - shell), "{vol} vs {ball}");
    }

    #[test]
    fn val_bench_flyby_clearance_is_the_lowest_corner_height() {
        // Independent: the rotation matrix from the three elementary rotations, the corners'
        // y, the lowest one.
        let [yaw, pitch, roll] = CHASER_ATTITUDE_DEG.map(f64::to_radians);
        let rz = nalgebra::Rotation3::from_axis_angle(&Vector3::z_axis(), yaw);
        let ry = nalgebra::Rotation3::from_axis_angle(&Vector3::y_axis(), pitch);
        let rx = nalgebra::Rotation3::from_axis_angle(&Vector3::x_axis(), roll);
        let m = rz * ry * rx;
        let mut lowest = f64::MAX;
        for i in 0..8 {
            let c = Vector3::new(
                if i & 1 == 0 { -0.5 } else { 0.5 },
                if i & 2 == 0 { -0.5 } else { 0.5 },
                if i & 4 == 0 { -0.5 } else { 0.5 },
            );
            lowest = lowest.min((m * c).y);
        }
        assert!((chaser_lowest_corner_m().y - lowest).abs() < 1e-12);
        // And in a run, for both primitives: the closest approach is the clearance (the corner
        // passes over the top at 4 s).
        for target in [FlybyTarget::Box, FlybyTarget::Sphere] {
            let x0 = -chaser_lowest_corner_m().x - 4.0 * FLYBY_SPEED_M_S;
            let text = flyby_scene("t", &target.primitive(), target.top_y_m(), 1.9, x0);
            let l = load_scene_str(&text, "flyby.ron", &[]).expect("loads");
            let mut sim = crate::sim::Simulation::new(&l).expect("builds");
            sim.step(800);
            let d = sim.summary()["pairs"][0]["min_distance_m"]
                .as_f64()
                .expect("distance");
            // The monitor's closest-approach tolerance: 0.1 % of the distance
            // (`monitor::min_distance_tolerance_m`), above f32 GJK's 1e-5 m at this scale.
            assert!((d - 1.9).abs() <= 1.9e-3, "{target:?}: {d}");
        }
    }
}
