//! The Bevy window: spacecraft meshes, overlays (gizmos), the read-out panel, the scrubber,
//! camera presets and keyboard/mouse controls, for a live run or a recorded one.

use super::geometry::{SceneGeom, part_look, primitive_mesh, to_transform, v3};
use super::recording::{Recording, Snapshot};
use super::timeline::{MarkerKind, SPEED_LADDER, Timeline};
use crate::scene::{BodyRole, Environment, LoadedScene};
use crate::sim::Simulation;
use bevy::app::AppExit;
use bevy::diagnostic::{DiagnosticsStore, FrameTimeDiagnosticsPlugin};
use bevy::input::mouse::{AccumulatedMouseMotion, AccumulatedMouseScroll};
use bevy::prelude::*;
use bevy::render::view::screenshot::{Screenshot, ScreenshotCaptured, save_to_disk};
use bevy::window::{PrimaryWindow, WindowResolution};
use nalgebra::Vector3;
use std::collections::BTreeMap;
use std::path::PathBuf;
use std::sync::Arc;
use std::sync::atomic::{AtomicUsize, Ordering};

/// How the viewer is started.
#[derive(Debug, Clone)]
pub struct ViewerOptions {
    /// Save a PNG of the window after `frames` frames, then exit.
    pub screenshot: Option<PathBuf>,
    /// Frames to render before the screenshot (or before exiting); `None`: run until closed.
    pub frames: Option<u32>,
    /// Window size, physical pixels.
    pub size_px: (u32, u32),
    /// Draw overlays and the panel.
    pub overlays: bool,
    /// Only these layers at start (names from [`LAYER_NAMES`]); `None`: all when `overlays`.
    pub layers: Option<Vec<String>>,
    /// Replay: start at this time, s (default: the end of the recording when taking a
    /// screenshot, else the start).
    pub start_s: Option<f64>,
    /// Initial playback speed, × real time.
    pub speed: f64,
    /// Start playing (otherwise paused).
    pub play: bool,
    /// Initial camera preset: `overview`, `target`, `chaser` or `port`.
    pub camera: String,
    /// The 3-D view is rendered at this fraction of the window's size and scaled up (the
    /// panel stays sharp): below 1 for software renderers, which pay per pixel.
    pub render_scale: f32,
}

impl Default for ViewerOptions {
    fn default() -> Self {
        Self {
            screenshot: None,
            frames: None,
            size_px: (1280, 720),
            overlays: true,
            layers: None,
            start_s: None,
            speed: 1.0,
            play: false,
            camera: "overview".into(),
            render_scale: 1.0,
        }
    }
}

/// Background colour of the 3-D view.
pub const BACKGROUND: Color = Color::srgb(0.015, 0.02, 0.045);

/// Colour of the contact-force arrows (orange).
pub const ARROW_COLOR: Color = Color::srgb(1.0, 0.45, 0.1);

/// The overlay layers, by the names `--layers` takes.
pub const LAYER_NAMES: [&str; 7] = [
    "ports", "lvlh", "trails", "closest", "contacts", "surfaces", "panel",
];

/// Reference-orbit ECI states (position m, velocity m/s), one per recorded row.
type RvTrack = Vec<(Vector3<f64>, Vector3<f64>)>;

/// A layer toggle: which flag of [`Layers`] a key flips.
type Toggle = fn(&mut Layers) -> &mut bool;

/// The recorded run being replayed.
#[derive(Resource)]
struct Replay {
    rec: Recording,
    timeline: Timeline,
    /// Reference orbit ECI state (r, v) at each recorded row (orbit scenes).
    reference: Option<RvTrack>,
}

/// The live simulation (a Bevy app of its own: not `Send`, so a non-send resource).
struct Live {
    sim: Simulation,
    /// Simulated time owed to the simulation, s.
    owed_s: f64,
    /// Simulated seconds per wall second achieved over the last frame.
    achieved: f64,
    /// Accumulated normal impulse of each active contact at the end of the last frame, N·s.
    impulses: BTreeMap<(String, String), f64>,
    /// Mean normal force of each active contact over the last frame's steps (ΔJ / Δt), N.
    force_n: BTreeMap<(String, String), f64>,
}

/// The force-arrow scale, N per m, chosen (1, 2 or 5 × 10^k) so that the peak contact force
/// is drawn at most `max_len_m` long: live, the run's peak so far (it only grows, so arrows
/// stay comparable within a run); replay, the peak of `contacts.csv`.
#[derive(Resource, Default)]
struct ContactForces {
    scale_n_per_m: Option<f64>,
    max_len_m: f64,
}

impl ContactForces {
    /// The scale for `peak_n` with arrows at most half the smallest body's radius long
    /// (clamped to 5 cm–5 m).
    fn new(geom: &SceneGeom, peak_n: f64) -> Self {
        let max_len_m = (0.5
            * geom
                .bodies
                .iter()
                .map(|b| b.radius_m)
                .fold(f64::INFINITY, f64::min))
        .clamp(0.05, 5.0);
        let mut f = Self {
            scale_n_per_m: None,
            max_len_m,
        };
        f.grow_to(peak_n);
        f
    }

    /// Sets the scale for a peak force of `peak_n` (no change for a non-positive peak).
    fn grow_to(&mut self, peak_n: f64) {
        if peak_n > 0.0 {
            self.scale_n_per_m = Some(super::geometry::arrow_scale_n_per_m(peak_n, self.max_len_m));
        }
    }
}

/// Lines drawn in front of the meshes, 3 px wide: contact points and force arrows (an arrow is
/// the force on the second part, so it starts at the contact and points into that part),
/// port frames, the LVLH triad and the Earth direction (at the reference origin, usually
/// inside the target) and the closest-points segment.
#[derive(Default, Reflect, GizmoConfigGroup)]
struct FrontGizmos;

/// A part drawn as a glTF model (on the model's root entity, a child of the body).
#[derive(Component, Clone)]
struct PartModel {
    /// `body/part`.
    part: String,
    /// Path under the assets directory.
    path: String,
    /// The file.
    gltf: Handle<bevy::gltf::Gltf>,
    /// Its nodes have been spawned.
    spawned: bool,
}

/// The glTF models: how many the scene names, those spawned (`body/part`, path, mesh
/// entities), and the first load failure.
#[derive(Resource, Default)]
struct ModelStatus {
    expected: usize,
    ready: Vec<(String, String, usize)>,
    failed: Option<String>,
}

/// The force arrows drawn this frame: (part a, part b, force N, start and end, world m).
#[derive(Resource, Default)]
struct DrawnArrows(Vec<(String, String, f64, Vec3, Vec3)>);

/// Draws a line (or an arrow) and notes it in `lines`.
fn line(
    g: &mut Gizmos<FrontGizmos>,
    lines: &mut DrawnLines,
    what: String,
    (a, b): (Vec3, Vec3),
    c: Color,
    arrow: bool,
) {
    if arrow {
        g.arrow(a, b, c);
    } else {
        g.line(a, b, c);
    }
    lines.0.push((what, c, a, b));
}

/// Other overlay lines drawn this frame, for the screenshot side file: (what, colour, start
/// and end, world m) — port axes, LVLH axes, the Earth direction, the closest-points segment.
#[derive(Resource, Default)]
struct DrawnLines(Vec<(String, Color, Vec3, Vec3)>);

/// Live play/pause and speed.
#[derive(Resource)]
struct LiveCtl {
    playing: bool,
    speed: f64,
    single_steps: u64,
}

/// What is drawn this frame.
#[derive(Resource, Default)]
struct Current {
    snap: Snapshot,
    /// Reference orbit ECI state (r, v) now, if in orbit.
    reference: Option<(Vector3<f64>, Vector3<f64>)>,
    live: bool,
    scene_name: String,
    end_s: Option<f64>,
}

/// Trails: recent centre-of-mass positions per body (live mode).
#[derive(Resource, Default)]
struct Trails(Vec<Vec<Vec3>>);

/// Layer toggles.
#[derive(Resource)]
struct Layers {
    ports: bool,
    lvlh: bool,
    trails: bool,
    closest: bool,
    contacts: bool,
    surfaces: bool,
    panel: bool,
}

impl Layers {
    /// The layers shown at start: those `opts.layers` names, else all or none (`overlays`).
    fn from_options(opts: &ViewerOptions) -> Self {
        let on = |name: &str| match &opts.layers {
            Some(list) => list.iter().any(|l| l == name),
            None => opts.overlays,
        };
        Self {
            ports: on("ports"),
            lvlh: on("lvlh"),
            trails: on("trails"),
            closest: on("closest"),
            contacts: on("contacts"),
            surfaces: on("surfaces"),
            panel: on("panel"),
        }
    }
}

/// Camera presets.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Preset {
    /// Frame every body.
    Overview,
    /// Orbit the target.
    OrbitTarget,
    /// Behind the chaser, looking at the target.
    FollowChaser,
    /// From the chaser's docking port along its axis.
    PortView,
}

/// Camera state: preset plus the mouse's yaw/pitch/zoom and pan.
#[derive(Resource)]
struct CameraRig {
    preset: Preset,
    yaw: f32,
    pitch: f32,
    zoom: f32,
    /// Camera translation added to the preset's placement (world frame), m.
    pan: Vec3,
    /// Distance from the eye to the preset's point of interest (sets the pan step), m.
    focus_dist: f32,
}

#[derive(Component)]
struct BodyMarker(usize);
#[derive(Component)]
struct PanelText;
/// A semi-transparent constraint surface (layer `surfaces`).
#[derive(Component)]
struct ConstraintSurface;
#[derive(Component)]
struct ScrubFill;
#[derive(Component)]
struct Scrubber;

/// Render pipelines still compiling (written by the render world each frame, read by the
/// screenshot logic: a picture taken before they are ready lacks whatever they draw).
#[derive(Resource, Clone)]
struct PipelinesWaiting(Arc<AtomicUsize>);

fn count_waiting_pipelines(
    cache: Option<Res<bevy::render::render_resource::PipelineCache>>,
    waiting: Res<PipelinesWaiting>,
) {
    let n = cache.map(|c| c.waiting_pipelines().count()).unwrap_or(1);
    waiting.0.store(n, Ordering::Relaxed);
}

/// Frames in a row with no pipeline compiling before the screenshot is taken.
const READY_FRAMES: u32 = 5;
/// Give up waiting for the pipelines after this many frames past `--frames`.
const MAX_READY_WAIT_FRAMES: u32 = 3000;

/// Frames counted, and the screenshot plan.
#[derive(Resource)]
struct Run {
    frame: u32,
    opts: ViewerOptions,
    shot_requested: bool,
    shot_done: bool,
    /// Screenshots retaken because the frame was still blank.
    retries: u32,
    /// Consecutive frames with no render pipeline compiling.
    ready_streak: u32,
    /// Wall time of the first counted frame (for the frame rate), s.
    t_first: Option<f64>,
    /// Simulated time shown at that frame, s.
    sim_first_s: f64,
    frames_since_first: u32,
}

/// Opens the window on a live simulation of `loaded`.
pub fn run_live(loaded: &LoadedScene, opts: ViewerOptions) -> Result<(), String> {
    check_options(&opts)?;
    let sim = Simulation::new(loaded).map_err(|e| e.to_string())?;
    let geom = SceneGeom::new(&sim.scene);
    let mut app = base_app(&opts, &sim.scene.name);
    let reference = sim.reference_state();
    let snap = live_snapshot(&sim);
    app.insert_resource(ContactForces::new(&geom, 0.0))
        .insert_resource(Table::of(&sim.scene))
        .insert_resource(Surfaces::of(&sim.scene));
    app.insert_resource(geom)
        .insert_resource(Current {
            snap,
            reference,
            live: true,
            scene_name: sim.scene.name.clone(),
            end_s: None,
        })
        .insert_resource(LiveCtl {
            playing: opts.play,
            speed: opts.speed.clamp(0.1, 1000.0),
            single_steps: 0,
        })
        .insert_non_send(Live {
            sim,
            owed_s: 0.0,
            achieved: 0.0,
            impulses: BTreeMap::new(),
            force_n: BTreeMap::new(),
        })
        .add_systems(
            Update,
            (live_controls, live_step).chain().before(apply_pose),
        );
    finish(app)
}

/// Opens the window on a recorded run (`rpod run` output) of `loaded`.
pub fn run_replay(loaded: &LoadedScene, rec: Recording, opts: ViewerOptions) -> Result<(), String> {
    check_options(&opts)?;
    let scene = &loaded.scene;
    for b in &scene.bodies {
        if !rec.body_names.contains(&b.name) {
            return Err(format!(
                "{}: trajectory.csv has no columns for body `{}` of scene `{}`",
                rec.dir.display(),
                b.name,
                scene.name
            ));
        }
    }
    // Recording columns in scene order.
    let order: Vec<usize> = scene
        .bodies
        .iter()
        .map(|b| {
            rec.body_names
                .iter()
                .position(|n| *n == b.name)
                .expect("checked")
        })
        .collect();
    let (t0, t1) = rec.span_s();
    let mut timeline = Timeline::new(t0, t1, rec.row_dt_s(), rec.markers());
    timeline.set_speed(opts.speed);
    let start = opts
        .start_s
        .unwrap_or(if opts.screenshot.is_some() { t1 } else { t0 });
    timeline.seek(start);
    timeline.playing = opts.play;
    let reference = reference_track(loaded, &rec.times_s)?;
    let geom = SceneGeom::new(scene);
    let mut app = base_app(&opts, &scene.name);
    app.insert_resource(ContactForces::new(&geom, rec.peak_contact_force_n()));
    let mut snap = rec.sample(timeline.t_s);
    snap.bodies = order.iter().map(|&i| snap.bodies[i]).collect();
    app.insert_resource(Table::of(scene))
        .insert_resource(Surfaces::of(scene));
    app.insert_resource(geom)
        .insert_resource(Current {
            snap,
            reference: None,
            live: false,
            scene_name: scene.name.clone(),
            end_s: Some(t1),
        })
        .insert_resource(ReplayOrder(order))
        .insert_resource(Replay {
            rec,
            timeline,
            reference,
        })
        .add_systems(
            Update,
            (replay_controls, replay_sample).chain().before(apply_pose),
        );
    finish(app)
}

/// Refuses an unknown camera preset or layer name before a window opens.
fn check_options(opts: &ViewerOptions) -> Result<(), String> {
    if let Some(bad) = opts
        .layers
        .iter()
        .flatten()
        .find(|l| !LAYER_NAMES.contains(&l.as_str()))
    {
        return Err(format!(
            "--layers: unknown layer `{bad}` (layers: {})",
            LAYER_NAMES.join(", ")
        ));
    }
    match opts.camera.as_str() {
        "overview" | "target" | "chaser" | "port"
            if opts.render_scale > 0.0 && opts.render_scale <= 1.0 =>
        {
            Ok(())
        }
        "overview" | "target" | "chaser" | "port" => Err(format!(
            "--render-scale must be in (0, 1], got {}",
            opts.render_scale
        )),
        other => Err(format!(
            "--camera must be overview, target, chaser or port, got `{other}`"
        )),
    }
}

/// Body order of the recording for each scene body.
#[derive(Resource)]
struct ReplayOrder(Vec<usize>);

/// The reference orbit at each row time (propagated in f64 from the scene's t = 0 state).
fn reference_track(loaded: &LoadedScene, times_s: &[f64]) -> Result<Option<RvTrack>, String> {
    if !matches!(loaded.scene.environment, Environment::Orbit { .. }) {
        return Ok(None);
    }
    let sim = Simulation::new(loaded).map_err(|e| e.to_string())?;
    let Some(mut orbit) = sim.reference_orbit() else {
        return Ok(None);
    };
    let mut out = Vec::with_capacity(times_s.len());
    let mut t = 0.0;
    for &ti in times_s {
        if ti > t {
            orbit.step(ti - t);
            t = ti;
        }
        out.push(orbit.state());
    }
    Ok(Some(out))
}

fn base_app(opts: &ViewerOptions, title: &str) -> App {
    let mut app = App::new();
    let mut resolution = WindowResolution::new(opts.size_px.0, opts.size_px.1);
    if opts.screenshot.is_some() {
        resolution = resolution.with_scale_factor_override(1.0);
    }
    app.add_plugins((
        DefaultPlugins
            .set(WindowPlugin {
                primary_window: Some(Window {
                    title: format!("rpod — {title}"),
                    resolution,
                    present_mode: bevy::window::PresentMode::AutoNoVsync,
                    ..default()
                }),
                ..default()
            })
            .set(AssetPlugin {
                file_path: crate::scene::assets_dir().to_string_lossy().into_owned(),
                ..default()
            }),
        FrameTimeDiagnosticsPlugin::default(),
    ))
    .insert_resource(ClearColor(BACKGROUND))
    .insert_resource(GlobalAmbientLight {
        color: Color::WHITE,
        brightness: 600.0,
        ..default()
    })
    .insert_gizmo_config(
        FrontGizmos,
        GizmoConfig {
            depth_bias: -1.0,
            line: GizmoLineConfig {
                width: 3.0,
                ..default()
            },
            ..default()
        },
    )
    .insert_resource(Layers::from_options(opts))
    .insert_resource(ModelStatus::default())
    .insert_resource(DrawnArrows::default())
    .insert_resource(DrawnLines::default())
    .insert_resource(CameraRig {
        preset: match opts.camera.as_str() {
            "target" => Preset::OrbitTarget,
            "chaser" => Preset::FollowChaser,
            "port" => Preset::PortView,
            _ => Preset::Overview,
        },
        yaw: 0.0,
        pitch: 0.0,
        zoom: 1.0,
        pan: Vec3::ZERO,
        focus_dist: 10.0,
    })
    .insert_resource(Trails::default())
    .insert_resource(Run {
        frame: 0,
        opts: opts.clone(),
        shot_requested: false,
        shot_done: false,
        retries: 0,
        ready_streak: 0,
        t_first: None,
        sim_first_s: 0.0,
        frames_since_first: 0,
    })
    .add_systems(Startup, setup);
    let waiting = PipelinesWaiting(Arc::new(AtomicUsize::new(usize::MAX)));
    app.insert_resource(waiting.clone());
    if let Some(render_app) = app.get_sub_app_mut(bevy::render::RenderApp) {
        render_app
            .insert_resource(waiting)
            .add_systems(bevy::render::Render, count_waiting_pipelines);
    }
    app.add_systems(
        Update,
        (
            spawn_models,
            resize_scaled_view,
            apply_pose,
            view_controls,
            camera_system,
            overlays,
            panel,
            frames_and_screenshot,
        )
            .chain(),
    );
    app
}

fn finish(mut app: App) -> Result<(), String> {
    match app.run() {
        AppExit::Success => Ok(()),
        AppExit::Error(c) => Err(format!("viewer exited with code {c}")),
    }
}

/// An air-bearing scene's table: corner (lab x, y), size (x, y) and thickness, m.
#[derive(Resource, Default)]
struct Table(Option<([f64; 2], [f64; 2], f64)>);

impl Table {
    fn of(scene: &crate::scene::Scene) -> Self {
        match &scene.environment {
            Environment::AirBearing(t) => Self(Some((
                t.table_corner_m,
                t.table_size_m,
                t.table_thickness_m,
            ))),
            _ => Self(None),
        }
    }
}

/// A constraint surface's body (if it rides on one), transform and visibility.
type SurfaceItem = (
    Option<&'static SurfaceOf>,
    &'static mut Transform,
    &'static mut Visibility,
);

/// The body a constraint surface rides on.
#[derive(Component)]
struct SurfaceOf(usize);

/// The constraint surfaces of the laws and guarantees ([`super::surfaces`]), their panel
/// legend, and the body whose centre-of-mass height the table curves are drawn at.
#[derive(Resource, Default)]
struct Surfaces {
    list: Vec<super::surfaces::Surface>,
    legend: Vec<String>,
    curve_body: Option<usize>,
}

impl Surfaces {
    fn of(scene: &crate::scene::Scene) -> Self {
        let list = super::surfaces::scene_surfaces(scene);
        let legend = list.iter().map(|s| s.legend().to_string()).collect();
        let curve_body = list.iter().find_map(|s| s.curve_body);
        Self {
            list,
            legend,
            curve_body,
        }
    }
}

/// Spawns the scene at start-up: the bodies ([`spawn_bodies`]), the constraint surfaces
/// ([`spawn_surfaces`]), the air-bearing table ([`spawn_table`]), the light and camera
/// ([`spawn_light_and_camera`]) and the panel's text, in that order.
#[allow(clippy::too_many_arguments)] // a Bevy system: one parameter per resource it reads
fn setup(
    mut commands: Commands,
    geom: Res<SceneGeom>,
    surfaces: Res<Surfaces>,
    table: Res<Table>,
    layers: Res<Layers>,
    mut meshes: ResMut<Assets<Mesh>>,
    mut materials: ResMut<Assets<StandardMaterial>>,
    asset_server: Res<AssetServer>,
    mut model_status: ResMut<ModelStatus>,
    run: Res<Run>,
    mut images: ResMut<Assets<Image>>,
) {
    spawn_bodies(
        &mut commands,
        &geom,
        &mut meshes,
        &mut materials,
        &asset_server,
        &mut model_status,
    );
    spawn_surfaces(
        &mut commands,
        &surfaces,
        &layers,
        &mut meshes,
        &mut materials,
    );
    spawn_table(&mut commands, &table, &mut meshes, &mut materials);
    spawn_light_and_camera(&mut commands, &run, &mut images);
    commands.spawn((
        Text::new(""),
        TextFont::from_font_size(13.0),
        TextColor(Color::srgb(0.9, 0.92, 0.95)),
        Node {
            position_type: PositionType::Absolute,
            top: Val::Px(6.0),
            left: Val::Px(8.0),
            ..default()
        },
        PanelText,
    ));
}

/// Spawns each body (a [`BodyMarker`] entity) with its parts as children: a part with a glTF
/// model, the model (counted in `model_status`, built later by `spawn_models`); any other
/// part, its primitive mesh.
fn spawn_bodies(
    commands: &mut Commands,
    geom: &SceneGeom,
    meshes: &mut Assets<Mesh>,
    materials: &mut Assets<StandardMaterial>,
    asset_server: &AssetServer,
    model_status: &mut ModelStatus,
) {
    for (i, b) in geom.bodies.iter().enumerate() {
        commands
            .spawn((BodyMarker(i), Transform::default(), Visibility::default()))
            .with_children(|c| {
                // Parts with a glTF model: the model (its first scene) in the body frame.
                for (part, m) in &b.models {
                    let pose = nalgebra::Isometry3::from_parts(
                        nalgebra::Translation3::from(Vector3::from(m.pos_m)),
                        m.attitude.to_quat(),
                    );
                    let mut tf = to_transform(&pose);
                    tf.scale = Vec3::splat(m.scale as f32);
                    model_status.expected += 1;
                    c.spawn((
                        tf,
                        Visibility::default(),
                        Name::new(format!("{}/{part} (model {})", b.name, m.path)),
                        PartModel {
                            part: format!("{}/{part}", b.name),
                            path: m.path.clone(),
                            gltf: asset_server.load(m.path.clone()),
                            spawned: false,
                        },
                    ));
                }
                for p in b
                    .parts
                    .iter()
                    .filter(|p| !b.models.iter().any(|(n, _)| *n == p.part))
                {
                    let (color, metallic, rough) = part_look(b.role, p.role);
                    c.spawn((
                        Mesh3d(meshes.add(primitive_mesh(&p.shape))),
                        MeshMaterial3d(materials.add(StandardMaterial {
                            base_color: color,
                            metallic,
                            perceptual_roughness: rough,
                            ..default()
                        })),
                        to_transform(&p.pose_body),
                        Name::new(p.full_name.clone()),
                    ));
                }
            });
    }
}

/// Spawns the laws' and guarantees' constraint surfaces, shown when the `surfaces` layer is on;
/// a surface about a body gets a [`SurfaceOf`] so that it follows that body.
fn spawn_surfaces(
    commands: &mut Commands,
    surfaces: &Surfaces,
    layers: &Layers,
    meshes: &mut Assets<Mesh>,
    materials: &mut Assets<StandardMaterial>,
) {
    // The laws' and guarantees' constraint surfaces (semi-transparent; a depth bias keeps a
    // surface that coincides with a collider, such as the Xu 2019 obstacle, in front of it).
    // Spheres about a body show their inner (far) side only: one layer of tint whether the
    // camera is outside or inside (a 10 m keep-out sphere fills the picture, and each blended
    // layer costs the software renderer about 30 ms at 1280×720). The table prisms, which
    // wrap colliders, and the surfaces of revolution (a corridor) are drawn two-sided.
    for s in &surfaces.list {
        use super::surfaces::Anchor;
        let [r, g, b, a] = s.rgba;
        let sphere = !s.two_sided;
        let mut e = commands.spawn((
            Mesh3d(meshes.add(s.mesh.to_mesh())),
            MeshMaterial3d(materials.add(StandardMaterial {
                base_color: Color::srgba(r, g, b, a),
                alpha_mode: AlphaMode::Blend,
                cull_mode: sphere.then_some(bevy::render::render_resource::Face::Front),
                double_sided: !sphere,
                depth_bias: 200.0,
                unlit: true,
                ..default()
            })),
            if layers.surfaces {
                Visibility::Inherited
            } else {
                Visibility::Hidden
            },
            ConstraintSurface,
        ));
        match s.anchor {
            Anchor::World(o) => {
                e.insert(Transform::from_translation(v3(&o)));
            }
            Anchor::BodyCom(i) => {
                e.insert((Transform::default(), SurfaceOf(i)));
            }
        }
    }
}

/// Spawns an air-bearing scene's table (nothing for other scenes).
fn spawn_table(
    commands: &mut Commands,
    table: &Table,
    meshes: &mut Assets<Mesh>,
    materials: &mut Assets<StandardMaterial>,
) {
    // The air-bearing table: its top at z = 0 (lab frame, z up).
    if let Some((corner, size, thick)) = table.0 {
        commands.spawn((
            Mesh3d(meshes.add(Cuboid::new(
                size[0] as f32,
                size[1] as f32,
                thick.max(0.005) as f32,
            ))),
            // Unlit: a plane under one directional light shades uniformly anyway, and the
            // table fills much of the picture (PBR per pixel is what limits llvmpipe).
            MeshMaterial3d(materials.add(StandardMaterial {
                base_color: Color::srgb(0.16, 0.17, 0.19),
                unlit: true,
                ..default()
            })),
            Transform::from_xyz(
                (corner[0] + size[0] / 2.0) as f32,
                (corner[1] + size[1] / 2.0) as f32,
                (-thick.max(0.005) / 2.0) as f32,
            ),
        ));
    }
}

/// Spawns the directional light and the 3-D camera; below a render scale of 1, also the image
/// the camera renders to, the 2-D camera and the full-window node that show it stretched, and
/// the [`ScaledView`] resource.
fn spawn_light_and_camera(commands: &mut Commands, run: &Run, images: &mut Assets<Image>) {
    commands.spawn((
        DirectionalLight {
            illuminance: 8000.0,
            shadow_maps_enabled: false,
            ..default()
        },
        Transform::from_xyz(3.0, 5.0, 8.0).looking_at(Vec3::ZERO, Vec3::Z),
    ));
    // No multisampling: the software renderer (llvmpipe) pays for every sample.
    let mut cam = commands.spawn((
        Camera3d::default(),
        bevy::render::view::Msaa::Off,
        Transform::from_xyz(0.0, -30.0, 10.0),
    ));
    // Render scale below 1: the 3-D view goes to an image of that fraction of the window,
    // which a window camera shows stretched to the full window under the panel.
    let scale = run.opts.render_scale;
    if scale < 1.0 {
        let (w, h) = scaled_px(run.opts.size_px, scale);
        let image = images.add(Image::new_target_texture(
            w,
            h,
            bevy::render::render_resource::TextureFormat::Rgba8UnormSrgb,
            None,
        ));
        cam.insert(bevy::camera::RenderTarget::Image(image.clone().into()));
        commands.spawn((
            Camera2d,
            Camera {
                order: 1,
                ..default()
            },
            bevy::render::view::Msaa::Off,
        ));
        commands.spawn((
            ImageNode::new(image.clone()),
            Node {
                position_type: PositionType::Absolute,
                width: Val::Percent(100.0),
                height: Val::Percent(100.0),
                ..default()
            },
            GlobalZIndex(-1),
        ));
        commands.insert_resource(ScaledView(image));
    }
}

/// The glTF assets a model is built from.
#[derive(bevy::ecs::system::SystemParam)]
struct GltfAssets<'w> {
    files: Res<'w, Assets<bevy::gltf::Gltf>>,
    nodes: Res<'w, Assets<bevy::gltf::GltfNode>>,
    meshes: Res<'w, Assets<bevy::gltf::GltfMesh>>,
    materials: Res<'w, Assets<bevy::gltf::GltfMaterial>>,
}

/// The render material of a glTF material (the fields the viewer's PBR pipeline uses).
fn standard_material(m: &bevy::gltf::GltfMaterial) -> StandardMaterial {
    StandardMaterial {
        base_color: m.base_color,
        base_color_texture: m.base_color_texture.clone(),
        emissive: m.emissive,
        emissive_texture: m.emissive_texture.clone(),
        perceptual_roughness: m.perceptual_roughness,
        metallic: m.metallic,
        metallic_roughness_texture: m.metallic_roughness_texture.clone(),
        reflectance: m.reflectance,
        normal_map_texture: m.normal_map_texture.clone(),
        occlusion_texture: m.occlusion_texture.clone(),
        double_sided: m.double_sided,
        cull_mode: m.cull_mode,
        unlit: m.unlit,
        alpha_mode: m.alpha_mode,
        ..default()
    }
}

/// Spawns a glTF node under `parent` (its transform, then one entity per mesh primitive, then
/// its children); returns the number of mesh entities.
fn spawn_gltf_node(
    commands: &mut Commands,
    parent: Entity,
    node: &Handle<bevy::gltf::GltfNode>,
    assets: &GltfAssets,
    materials: &mut Assets<StandardMaterial>,
) -> usize {
    let Some(n) = assets.nodes.get(node) else {
        return 0;
    };
    let e = commands
        .spawn((
            n.transform,
            Visibility::default(),
            Name::new(n.name.clone()),
            ChildOf(parent),
        ))
        .id();
    let mut count = 0;
    if let Some(mesh) = n.mesh.as_ref().and_then(|h| assets.meshes.get(h)) {
        for p in &mesh.primitives {
            let mat = p
                .material
                .as_ref()
                .and_then(|h| assets.materials.get(h))
                .map(standard_material)
                .unwrap_or_default();
            commands.spawn((
                Mesh3d(p.mesh.clone()),
                MeshMaterial3d(materials.add(mat)),
                Transform::default(),
                Name::new(p.name.clone()),
                ChildOf(e),
            ));
            count += 1;
        }
    }
    for c in &n.children {
        count += spawn_gltf_node(commands, e, c, assets, materials);
    }
    count
}

/// Builds each model once its file and everything it references have loaded: the file's root
/// nodes (those no node lists as a child), in file order, under the model's entity. Stops the
/// viewer with the loader's message when a file fails to load.
fn spawn_models(
    mut commands: Commands,
    mut models: Query<(Entity, &mut PartModel)>,
    server: Res<AssetServer>,
    assets: GltfAssets,
    mut materials: ResMut<Assets<StandardMaterial>>,
    mut status: ResMut<ModelStatus>,
    mut exit: MessageWriter<AppExit>,
) {
    for (entity, mut m) in &mut models {
        if m.spawned || status.failed.is_some() {
            continue;
        }
        if let bevy::asset::LoadState::Failed(e) = server.load_state(&m.gltf) {
            // The loader's message without the backtrace Bevy appends.
            let e = e.to_string();
            let msg = format!(
                "model {} of part {} (under {}): {}",
                m.path,
                m.part,
                crate::scene::assets_dir().display(),
                e.lines().next().unwrap_or_default()
            );
            eprintln!("error: {msg}");
            status.failed = Some(msg);
            exit.write(AppExit::error());
            return;
        }
        if !server.is_loaded_with_dependencies(&m.gltf) {
            continue;
        }
        let Some(file) = assets.files.get(&m.gltf) else {
            continue;
        };
        let children: std::collections::HashSet<_> = file
            .nodes
            .iter()
            .filter_map(|h| assets.nodes.get(h))
            .flat_map(|n| n.children.iter().map(|c| c.id()))
            .collect();
        let mut count = 0;
        for root in file.nodes.iter().filter(|h| !children.contains(&h.id())) {
            count += spawn_gltf_node(&mut commands, entity, root, &assets, &mut materials);
        }
        m.spawned = true;
        status.ready.push((m.part.clone(), m.path.clone(), count));
    }
}

/// The image the 3-D view renders to when `--render-scale` is below 1.
#[derive(Resource)]
struct ScaledView(Handle<Image>);

/// Image size for a window of `size_px` at `scale` (at least 16 px a side).
fn scaled_px(size_px: (u32, u32), scale: f32) -> (u32, u32) {
    let f = |v: u32| ((v as f32 * scale).round() as u32).max(16);
    (f(size_px.0), f(size_px.1))
}

/// Keeps the scaled view's image at the render scale of the window's current size.
fn resize_scaled_view(
    view: Option<Res<ScaledView>>,
    run: Res<Run>,
    window: Query<&Window, With<PrimaryWindow>>,
    mut images: ResMut<Assets<Image>>,
) {
    let (Some(view), Ok(w)) = (view, window.single()) else {
        return;
    };
    let (iw, ih) = scaled_px(
        (w.physical_width(), w.physical_height()),
        run.opts.render_scale,
    );
    let Some(img) = images.get(&view.0) else {
        return;
    };
    let size = img.texture_descriptor.size;
    if (size.width, size.height) != (iw, ih)
        && let Some(mut img) = images.get_mut(&view.0)
    {
        img.resize(bevy::render::render_resource::Extent3d {
            width: iw,
            height: ih,
            depth_or_array_layers: 1,
        });
    }
}

/// Scrubber bar geometry, logical pixels from the window's left/bottom.
const SCRUB_MARGIN: f32 = 16.0;
const SCRUB_BOTTOM: f32 = 12.0;
const SCRUB_HEIGHT: f32 = 14.0;

fn spawn_scrubber(commands: &mut Commands, timeline: &Timeline) {
    commands
        .spawn((
            Node {
                position_type: PositionType::Absolute,
                left: Val::Px(SCRUB_MARGIN),
                right: Val::Px(SCRUB_MARGIN),
                bottom: Val::Px(SCRUB_BOTTOM),
                height: Val::Px(SCRUB_HEIGHT),
                ..default()
            },
            BackgroundColor(Color::srgba(0.3, 0.32, 0.38, 0.8)),
            Scrubber,
        ))
        .with_children(|c| {
            c.spawn((
                Node {
                    position_type: PositionType::Absolute,
                    left: Val::Px(0.0),
                    top: Val::Px(0.0),
                    height: Val::Percent(100.0),
                    width: Val::Percent(0.0),
                    ..default()
                },
                BackgroundColor(Color::srgba(0.45, 0.6, 0.9, 0.8)),
                ScrubFill,
            ));
            for m in &timeline.markers {
                let color = marker_color(m.kind);
                let f = if timeline.end_s > timeline.start_s {
                    (m.t_s - timeline.start_s) / (timeline.end_s - timeline.start_s)
                } else {
                    0.0
                };
                c.spawn((
                    Node {
                        position_type: PositionType::Absolute,
                        left: Val::Percent((100.0 * f) as f32),
                        top: Val::Px(-4.0),
                        width: Val::Px(3.0),
                        height: Val::Px(SCRUB_HEIGHT + 8.0),
                        ..default()
                    },
                    BackgroundColor(color),
                ));
            }
        });
}

fn marker_color(k: MarkerKind) -> Color {
    match k {
        MarkerKind::Contact => Color::srgb(1.0, 0.85, 0.2),
        MarkerKind::Collision => Color::srgb(1.0, 0.2, 0.2),
        MarkerKind::Violation => Color::srgb(1.0, 0.45, 0.1),
        MarkerKind::Latch => Color::srgb(0.2, 1.0, 0.4),
        MarkerKind::Other => Color::srgb(0.7, 0.7, 0.75),
    }
}

#[allow(clippy::too_many_arguments)] // a Bevy system: one parameter per resource it reads
fn replay_controls(
    keys: Res<ButtonInput<KeyCode>>,
    mouse: Res<ButtonInput<MouseButton>>,
    window: Query<&Window, With<PrimaryWindow>>,
    time: Res<Time>,
    layers: Res<Layers>,
    mut replay: ResMut<Replay>,
    mut commands: Commands,
    scrub: Query<(), With<Scrubber>>,
) {
    let tl = &mut replay.timeline;
    if layers.panel && scrub.is_empty() {
        spawn_scrubber(&mut commands, tl);
    }
    if keys.just_pressed(KeyCode::Space) {
        tl.toggle_play();
    }
    if keys.just_pressed(KeyCode::Period) {
        tl.step(1);
    }
    if keys.just_pressed(KeyCode::Comma) {
        tl.step(-1);
    }
    if keys.just_pressed(KeyCode::Equal) || keys.just_pressed(KeyCode::NumpadAdd) {
        tl.faster();
    }
    if keys.just_pressed(KeyCode::Minus) || keys.just_pressed(KeyCode::NumpadSubtract) {
        tl.slower();
    }
    let span = tl.end_s - tl.start_s;
    if keys.just_pressed(KeyCode::ArrowRight) {
        tl.seek(tl.t_s + 0.05 * span);
    }
    if keys.just_pressed(KeyCode::ArrowLeft) {
        tl.seek(tl.t_s - 0.05 * span);
    }
    if keys.just_pressed(KeyCode::Home) {
        tl.seek(tl.start_s);
    }
    if keys.just_pressed(KeyCode::End) {
        tl.seek(tl.end_s);
    }
    if keys.just_pressed(KeyCode::BracketRight) {
        tl.next_marker();
    }
    if keys.just_pressed(KeyCode::BracketLeft) {
        tl.prev_marker();
    }
    // Click or drag on the scrubber seeks.
    if mouse.pressed(MouseButton::Left)
        && let Ok(w) = window.single()
        && let Some(c) = w.cursor_position()
    {
        let (wid, hei) = (w.width(), w.height());
        let top = hei - SCRUB_BOTTOM - SCRUB_HEIGHT - 6.0;
        if c.y >= top && c.y <= hei - SCRUB_BOTTOM + 6.0 && wid > 2.0 * SCRUB_MARGIN {
            tl.seek_fraction(f64::from((c.x - SCRUB_MARGIN) / (wid - 2.0 * SCRUB_MARGIN)));
        }
    }
    tl.advance(f64::from(time.delta_secs()));
}

fn replay_sample(replay: Res<Replay>, order: Res<ReplayOrder>, mut cur: ResMut<Current>) {
    let t = replay.timeline.t_s;
    let mut snap = replay.rec.sample(t);
    snap.bodies = order.0.iter().map(|&i| snap.bodies[i]).collect();
    cur.snap = snap;
    cur.reference = replay
        .reference
        .as_ref()
        .map(|r| r[replay.rec.row_at(t).min(r.len() - 1)]);
}

fn live_controls(keys: Res<ButtonInput<KeyCode>>, mut ctl: ResMut<LiveCtl>) {
    if keys.just_pressed(KeyCode::Space) {
        ctl.playing = !ctl.playing;
    }
    if keys.just_pressed(KeyCode::Period) {
        ctl.playing = false;
        ctl.single_steps += 1;
    }
    if keys.just_pressed(KeyCode::Equal) || keys.just_pressed(KeyCode::NumpadAdd) {
        ctl.speed = SPEED_LADDER
            .iter()
            .copied()
            .find(|&v| v > ctl.speed * (1.0 + 1e-9))
            .unwrap_or(1000.0);
    }
    if keys.just_pressed(KeyCode::Minus) || keys.just_pressed(KeyCode::NumpadSubtract) {
        ctl.speed = SPEED_LADDER
            .iter()
            .rev()
            .copied()
            .find(|&v| v < ctl.speed * (1.0 - 1e-9))
            .unwrap_or(0.1);
    }
}

/// Most fixed steps the live view runs in one frame (keeps the window responsive; at high
/// speed the simulation then runs as fast as it can, and the panel shows the rate achieved).
const MAX_STEPS_PER_FRAME: u64 = 2000;

fn live_step(
    time: Res<Time>,
    mut ctl: ResMut<LiveCtl>,
    mut live: NonSendMut<Live>,
    mut cur: ResMut<Current>,
    mut trails: ResMut<Trails>,
    mut forces: ResMut<ContactForces>,
) {
    let dt = live.sim.scene.dt_s;
    let wall = f64::from(time.delta_secs());
    let mut n = 0;
    if ctl.playing {
        live.owed_s += wall * ctl.speed;
        n = (live.owed_s / dt).floor() as u64;
        if n > MAX_STEPS_PER_FRAME {
            n = MAX_STEPS_PER_FRAME;
            live.owed_s = 0.0;
        } else {
            live.owed_s -= n as f64 * dt;
        }
    } else {
        live.owed_s = 0.0;
    }
    n += std::mem::take(&mut ctl.single_steps);
    if n > 0 {
        live.sim.step(n);
    }
    live.achieved = if wall > 0.0 {
        n as f64 * dt / wall
    } else {
        0.0
    };
    cur.snap = live_snapshot(&live.sim);
    cur.reference = live.sim.reference_state();
    if n > 0 {
        // Mean normal force of each contact over this frame's steps, from the monitor's
        // accumulated impulse (a contact that restarted within the frame counts from 0).
        let Live {
            sim,
            impulses,
            force_n,
            ..
        } = &mut *live;
        let cs = sim.contacts();
        let span_s = n as f64 * dt;
        let mut now = BTreeMap::new();
        force_n.clear();
        for (k, c) in &cs.active {
            let before = impulses.get(k).copied().unwrap_or(0.0);
            let j = if c.impulse_ns >= before {
                c.impulse_ns - before
            } else {
                c.impulse_ns
            };
            force_n.insert(k.clone(), j / span_s);
            now.insert(k.clone(), c.impulse_ns);
        }
        *impulses = now;
        let peak = cs
            .per_part
            .values()
            .map(|s| s.peak_force_n)
            .fold(0.0, f64::max);
        forces.grow_to(peak);
    }
    cur.snap.contact_force_n = live.force_n.clone();
    if n > 0 {
        let nb = cur.snap.bodies.len();
        trails.0.resize(nb, Vec::new());
        for (k, (p, _)) in cur.snap.bodies.iter().enumerate() {
            let tr = &mut trails.0[k];
            tr.push(v3(p));
            if tr.len() > 20_000 {
                tr.drain(..10_000);
            }
        }
    }
}

/// The live simulation's state as a [`Snapshot`].
fn live_snapshot(sim: &Simulation) -> Snapshot {
    let w = sim.app.world();
    let bodies = sim
        .scene
        .bodies
        .iter()
        .map(|b| {
            let s = sim.body(&b.name).expect("body of the scene");
            (s.pos_m, s.att)
        })
        .collect();
    let mon = sim.monitor();
    let best = mon
        .pairs
        .iter()
        .min_by(|a, b| a.distance_m.total_cmp(&b.distance_m));
    let diag = w.resource::<crate::sim::output::Diagnostics>();
    Snapshot {
        t_s: sim.t_s(),
        bodies,
        min_distance_m: best.map(|p| p.distance_m).unwrap_or(f64::NAN),
        closest_parts: best.map(|p| {
            let (a, b) = mon.pair_names(p);
            (a.to_string(), b.to_string())
        }),
        guarantees: sim
            .guarantees()
            .status
            .iter()
            .map(|s| (s.name.clone(), s.last_margin, s.unit.clone()))
            .collect(),
        diagnostics: diag
            .names
            .iter()
            .cloned()
            .zip(diag.values.iter().copied())
            .collect(),
        docking_state: w
            .get_resource::<crate::sim::docking::Docking>()
            .map(|d| d.state.name().to_string()),
        contacts: sim.contacts().active.keys().cloned().collect(),
        // Filled by `live_step` (forces need the impulse at the previous frame).
        contact_force_n: BTreeMap::new(),
    }
}

fn apply_pose(
    cur: Res<Current>,
    geom: Res<SceneGeom>,
    layers: Res<Layers>,
    mut q: Query<(&BodyMarker, &mut Transform), Without<ConstraintSurface>>,
    mut surfaces: Query<SurfaceItem, (With<ConstraintSurface>, Without<BodyMarker>)>,
) {
    for (m, mut tf) in &mut q {
        if let Some((p, a)) = cur.snap.bodies.get(m.0) {
            *tf = to_transform(&geom.bodies[m.0].body_pose(p, a));
        }
    }
    // Surfaces in a body frame with the vertex at the centre of mass.
    for (s, mut tf, mut vis) in &mut surfaces {
        if let Some(s) = s
            && let Some((p, a)) = cur.snap.bodies.get(s.0)
        {
            *tf = to_transform(&nalgebra::Isometry3::from_parts((*p).into(), *a));
        }
        *vis = if layers.surfaces {
            Visibility::Inherited
        } else {
            Visibility::Hidden
        };
    }
}

#[allow(clippy::too_many_arguments)] // a Bevy system: one parameter per resource it reads
fn view_controls(
    keys: Res<ButtonInput<KeyCode>>,
    mouse: Res<ButtonInput<MouseButton>>,
    motion: Res<AccumulatedMouseMotion>,
    scroll: Res<AccumulatedMouseScroll>,
    cam: Query<(&Transform, &Projection), With<Camera3d>>,
    window: Query<&Window, With<PrimaryWindow>>,
    mut rig: ResMut<CameraRig>,
    mut layers: ResMut<Layers>,
) {
    for (k, p) in [
        (KeyCode::Digit0, Preset::Overview),
        (KeyCode::Digit1, Preset::OrbitTarget),
        (KeyCode::Digit2, Preset::FollowChaser),
        (KeyCode::Digit3, Preset::PortView),
    ] {
        if keys.just_pressed(k) {
            *rig = CameraRig {
                preset: p,
                yaw: 0.0,
                pitch: 0.0,
                zoom: 1.0,
                pan: Vec3::ZERO,
                focus_dist: rig.focus_dist,
            };
        }
    }
    let shift = keys.pressed(KeyCode::ShiftLeft) || keys.pressed(KeyCode::ShiftRight);
    if mouse.pressed(MouseButton::Middle) || (shift && mouse.pressed(MouseButton::Right)) {
        // Pan: move the camera in its image plane so the point of interest follows the cursor.
        if let (Ok((tf, proj)), Ok(w)) = (cam.single(), window.single()) {
            let fov = match proj {
                Projection::Perspective(p) => p.fov,
                _ => std::f32::consts::FRAC_PI_4,
            };
            let k = super::geometry::pan_m_per_px(rig.focus_dist, fov, w.height());
            let d = motion.delta;
            rig.pan += (-d.x * tf.right().as_vec3() + d.y * tf.up().as_vec3()) * k;
        }
    } else if mouse.pressed(MouseButton::Right) || (mouse.pressed(MouseButton::Left) && shift) {
        rig.yaw -= motion.delta.x * 0.005;
        rig.pitch = (rig.pitch + motion.delta.y * 0.005).clamp(-1.5, 1.5);
    }
    if scroll.delta.y != 0.0 {
        rig.zoom = (rig.zoom * (1.0 - 0.1 * scroll.delta.y.signum())).clamp(0.02, 50.0);
    }
    let toggles: [(KeyCode, Toggle); 7] = [
        (KeyCode::KeyS, |l| &mut l.surfaces),
        (KeyCode::KeyK, |l| &mut l.contacts),
        (KeyCode::KeyP, |l| &mut l.ports),
        (KeyCode::KeyL, |l| &mut l.lvlh),
        (KeyCode::KeyT, |l| &mut l.trails),
        (KeyCode::KeyC, |l| &mut l.closest),
        (KeyCode::KeyH, |l| &mut l.panel),
    ];
    for (k, f) in toggles {
        if keys.just_pressed(k) {
            let b = f(&mut layers);
            *b = !*b;
        }
    }
}

fn body_index(geom: &SceneGeom, role: BodyRole) -> Option<usize> {
    geom.bodies.iter().position(|b| b.role == role)
}

/// Orbit-style placement: `focus`, a base direction from the focus to the eye, distance;
/// the mouse's yaw (about world z) and pitch turn the direction.
fn orbit_eye(focus: Vec3, base_dir: Vec3, dist: f32, rig: &CameraRig) -> Vec3 {
    let d = Quat::from_rotation_z(rig.yaw)
        * Quat::from_axis_angle(base_dir.cross(Vec3::Z).normalize_or(Vec3::X), rig.pitch)
        * base_dir.normalize_or(Vec3::NEG_Y);
    focus + d * dist * rig.zoom
}

fn camera_system(
    cur: Res<Current>,
    geom: Res<SceneGeom>,
    mut rig: ResMut<CameraRig>,
    mut cam: Query<&mut Transform, With<Camera3d>>,
) {
    let Ok(mut tf) = cam.single_mut() else {
        return;
    };
    let bodies = &cur.snap.bodies;
    if bodies.is_empty() {
        return;
    }
    let pos = |i: usize| v3(&bodies[i].0);
    let target = body_index(&geom, BodyRole::Target).unwrap_or(0);
    let chaser = body_index(&geom, BodyRole::Chaser).unwrap_or(bodies.len() - 1);
    let up = Vec3::Z;
    // Each preset places the camera and names its point of interest.
    let focus = match rig.preset {
        Preset::Overview => {
            let n = bodies.len() as f32;
            let centre = (0..bodies.len()).map(pos).sum::<Vec3>() / n;
            let extent = (0..bodies.len())
                .map(|i| (pos(i) - centre).length() + geom.bodies[i].radius_m as f32)
                .fold(1.0, f32::max);
            // Eye off to the side of the line joining the bodies, so both are seen apart, and
            // the screen's up chosen so that the line runs across the (wider) horizontal.
            let line = (pos(chaser) - pos(target)).normalize_or(Vec3::Y);
            let side = line.cross(up).normalize_or(Vec3::X);
            let base = (side + 0.35 * up + 0.3 * line).normalize();
            let eye = orbit_eye(centre, base, 1.9 * extent, &rig);
            let forward = (centre - eye).normalize_or(Vec3::NEG_Y);
            let mut screen_up = forward.cross(line).normalize_or(up);
            if screen_up.dot(up) < 0.0 {
                screen_up = -screen_up;
            }
            *tf = Transform::from_translation(eye).looking_at(centre, screen_up);
            centre
        }
        Preset::OrbitTarget => {
            let c = pos(target);
            let r = (geom.bodies[target].radius_m as f32).max(1.0);
            let eye = orbit_eye(c, Vec3::new(-1.0, -1.0, 0.6), 3.5 * r, &rig);
            *tf = Transform::from_translation(eye).looking_at(c, up);
            c
        }
        Preset::FollowChaser => {
            let c = pos(chaser);
            let to_target = (pos(target) - c).normalize_or(Vec3::Y);
            let r = (geom.bodies[chaser].radius_m as f32).max(1.0);
            let eye = orbit_eye(c, -to_target + 0.3 * up, 4.0 * r, &rig);
            *tf = Transform::from_translation(eye).looking_at(c + to_target * 2.0, up);
            c
        }
        Preset::PortView => {
            let b = &geom.bodies[chaser];
            let (p, a) = (&bodies[chaser].0, &bodies[chaser].1);
            let pose = b.body_pose(p, a);
            let (origin, axis) = b
                .ports
                .first()
                .map(|(_, o, ax)| (pose * nalgebra::Point3::from(*o), a * ax))
                .unwrap_or((pose.translation.vector.into(), a * Vector3::x()));
            // At the port, looking along its axis (the cone's faces point outward, so the
            // view from inside its base sees through it, out towards the target).
            let eye = v3(&origin.coords) + v3(&axis) * 0.02;
            let look = Quat::from_rotation_z(rig.yaw) * Quat::from_rotation_x(rig.pitch);
            let body_up = v3(&(a * Vector3::z()));
            *tf = Transform::from_translation(eye).looking_to(look * v3(&axis), body_up);
            pos(target)
        }
    };
    // The mouse's pan moves the camera, not its direction.
    rig.focus_dist = (focus - tf.translation).length().max(0.01);
    tf.translation += rig.pan;
}

/// Draws the overlays of the layers that are on ([`draw_surface_curves`], [`draw_ports`],
/// [`draw_lvlh`], [`draw_trails`], [`draw_contacts`], [`draw_closest`], in that order), noting
/// the force arrows and lines drawn this frame for the screenshot's sidecar.
#[allow(clippy::too_many_arguments)] // a Bevy system: one parameter per resource it reads
fn overlays(
    cur: Res<Current>,
    geom: Res<SceneGeom>,
    layers: Res<Layers>,
    replay: Option<Res<Replay>>,
    order: Option<Res<ReplayOrder>>,
    trails: Res<Trails>,
    surfaces: Res<Surfaces>,
    forces: Option<Res<ContactForces>>,
    mut arrows: ResMut<DrawnArrows>,
    mut lines: ResMut<DrawnLines>,
    mut gizmos: Gizmos,
    mut front: Gizmos<FrontGizmos>,
) {
    arrows.0.clear();
    lines.0.clear();

    if layers.surfaces {
        draw_surface_curves(&mut gizmos, &surfaces, &cur.snap);
    }
    if layers.ports {
        draw_ports(&mut front, &mut lines, &geom, &cur.snap);
    }
    if layers.lvlh
        && let Some((r, v)) = cur.reference
    {
        draw_lvlh(&mut front, &mut lines, r, v);
    }
    if layers.trails {
        draw_trails(&mut gizmos, replay.as_deref(), order.as_deref(), &trails);
    }
    if layers.contacts {
        draw_contacts(&mut front, &mut arrows, &geom, &cur.snap, forces.as_deref());
    }
    if layers.closest {
        draw_closest(&mut gizmos, &mut front, &mut lines, &geom, &cur.snap);
    }
}

/// The table curves the laws keep the chaser's centre of mass out of, at its height.
fn draw_surface_curves(gizmos: &mut Gizmos, surfaces: &Surfaces, snap: &Snapshot) {
    let bodies = &snap.bodies;
    let z = surfaces
        .curve_body
        .and_then(|i| bodies.get(i))
        .map_or(0.0, |(p, _)| p.z as f32);
    for s in &surfaces.list {
        if s.curve_lab_m.is_empty() {
            continue;
        }
        let [r, g, b, _] = s.rgba;
        let pts = s
            .curve_lab_m
            .iter()
            .chain(s.curve_lab_m.first())
            .map(|p| Vec3::new(p.x as f32, p.y as f32, z));
        gizmos.linestrip(pts, Color::srgb(r, g, b));
    }
}

/// Each docking port's axis (red arrow, 0.6 m) and its perpendicular u, v axes (green, blue;
/// 0.3 m).
fn draw_ports(
    front: &mut Gizmos<FrontGizmos>,
    lines: &mut DrawnLines,
    geom: &SceneGeom,
    snap: &Snapshot,
) {
    let bodies = &snap.bodies;
    for (i, b) in geom.bodies.iter().enumerate() {
        let Some((p, a)) = bodies.get(i) else {
            continue;
        };
        let pose = b.body_pose(p, a);
        for (name, o, ax) in &b.ports {
            let origin = v3(&(pose * nalgebra::Point3::from(*o)).coords);
            let axw = a * ax;
            let (u, v) = crate::scene::parts::perpendicular_basis(&axw);
            for (k, dir, len, c, arrow) in [
                ("axis", axw, 0.6, Color::srgb(1.0, 0.3, 0.3), true),
                ("u", u, 0.3, Color::srgb(0.3, 1.0, 0.3), false),
                ("v", v, 0.3, Color::srgb(0.3, 0.5, 1.0), false),
            ] {
                let what = format!("port {}/{name} {k}", b.name);
                let end = origin + v3(&dir) * len;
                line(front, lines, what, (origin, end), c, arrow);
            }
        }
    }
}

/// The LVLH (Hill) axes at the reference origin, from the reference orbit's ECI position `r`
/// (m) and velocity `v` (m/s), and the direction to the Earth's centre.
fn draw_lvlh(
    front: &mut Gizmos<FrontGizmos>,
    lines: &mut DrawnLines,
    r: Vector3<f64>,
    v: Vector3<f64>,
) {
    // LVLH (Hill) axes at the reference origin: x radial out, y along-track, z normal.
    let x = r.normalize();
    let z = r.cross(&v).normalize();
    let y = z.cross(&x);
    let len = 4.0;
    let o = Vec3::ZERO;
    for (name, axis, c) in [
        ("LVLH x", x, Color::srgb(1.0, 0.2, 0.2)),
        ("LVLH y", y, Color::srgb(0.2, 1.0, 0.2)),
        ("LVLH z", z, Color::srgb(0.3, 0.4, 1.0)),
    ] {
        let end = v3(&axis) * len;
        line(front, lines, name.into(), (o, end), c, true);
    }
    // Direction to the Earth's centre.
    let earth = -v3(&x) * 2.5 * len;
    line(
        front,
        lines,
        "Earth".into(),
        (o, earth),
        Color::srgb(0.2, 0.9, 1.0),
        true,
    );
}

/// The bodies' trails: replay, the recorded track up to now (at most about 3000 points each);
/// live, the trails gathered so far.
fn draw_trails(
    gizmos: &mut Gizmos,
    replay: Option<&Replay>,
    order: Option<&ReplayOrder>,
    trails: &Trails,
) {
    let colors = [Color::srgb(0.9, 0.7, 0.3), Color::srgb(0.6, 0.8, 1.0)];
    if let (Some(rp), Some(order)) = (replay, order) {
        let upto = rp.rec.row_at(rp.timeline.t_s) + 1;
        for (k, &col) in order.0.iter().enumerate() {
            let tr = rp.rec.track(col);
            let stride = (upto / 3000).max(1);
            let pts = tr[..upto.min(tr.len())].iter().step_by(stride).map(v3);
            gizmos.linestrip(pts, colors[k % 2]);
        }
    } else {
        for (k, tr) in trails.0.iter().enumerate() {
            gizmos.linestrip(tr.iter().copied(), colors[k % 2]);
        }
    }
}

/// Each contact's point and its force arrow (noted in `arrows`), or its unit normal when it
/// has no recorded force.
fn draw_contacts(
    front: &mut Gizmos<FrontGizmos>,
    arrows: &mut DrawnArrows,
    geom: &SceneGeom,
    snap: &Snapshot,
    forces: Option<&ContactForces>,
) {
    let bodies = &snap.bodies;
    // Contact points (on the first part), from the parts' geometry at the drawn poses,
    // and the force arrow (orange): the contact's normal force (live: over the last
    // frame's steps; replay: `contacts.csv`'s row interval) along the normal from the
    // first part to the second, at the panel's scale; a contact without a recorded force:
    // the unit normal (yellow, 0.3 m).
    for (a, b) in &snap.contacts {
        if let (Some(pa), Some(pb)) = (geom.find_part(a), geom.find_part(b))
            && let Some((p, n)) = geom.contact(pa, pb, bodies)
        {
            let p = v3(&p);
            let c = Color::srgb(1.0, 0.9, 0.1);
            front.sphere(Isometry3d::from_translation(p), 0.03, c);
            let force = forces.as_ref().and_then(|f| {
                let fn_ = *snap.contact_force_n.get(&(a.clone(), b.clone()))?;
                Some((fn_, fn_ / f.scale_n_per_m?)).filter(|(_, l)| *l > 0.0)
            });
            match force {
                Some((f_n, len_m)) => {
                    let end = p + v3(&n) * len_m as f32;
                    front.arrow(p, end, ARROW_COLOR);
                    arrows.0.push((a.clone(), b.clone(), f_n, p, end));
                }
                None => {
                    front.arrow(p, p + v3(&n) * 0.3, c);
                }
            }
        }
    }
}

/// The closest points of the closest pair of parts, joined by a line coloured by the smallest
/// guarantee margin ([`margin_color`]); touching, a red sphere at the first part.
fn draw_closest(
    gizmos: &mut Gizmos,
    front: &mut Gizmos<FrontGizmos>,
    lines: &mut DrawnLines,
    geom: &SceneGeom,
    snap: &Snapshot,
) {
    let bodies = &snap.bodies;
    if let Some((a, b)) = &snap.closest_parts
        && let (Some(pa), Some(pb)) = (geom.find_part(a), geom.find_part(b))
    {
        let margin = margin_m(snap);
        let color = margin_color(margin, snap.min_distance_m);
        match geom.closest_points(pa, pb, bodies) {
            Some((p1, p2)) => {
                line(
                    front,
                    lines,
                    "closest".into(),
                    (v3(&p1), v3(&p2)),
                    color,
                    false,
                );
                gizmos.sphere(Isometry3d::from_translation(v3(&p1)), 0.05, color);
                gizmos.sphere(Isometry3d::from_translation(v3(&p2)), 0.05, color);
            }
            None => {
                // Touching: mark the contact at the part of a.
                let bi = pa.0;
                let (p, q) = &bodies[bi];
                let w = geom.bodies[bi].body_pose(p, q) * geom.bodies[bi].parts[pa.1].pose_body;
                gizmos.sphere(
                    Isometry3d::from_translation(v3(&w.translation.vector)),
                    0.1,
                    Color::srgb(1.0, 0.1, 0.1),
                );
            }
        }
    }
}

/// The smallest guarantee margin in metres, or the distance when there is none, m.
fn margin_m(s: &Snapshot) -> f64 {
    s.guarantees
        .iter()
        .filter(|g| g.2 == "m" && g.1.is_finite())
        .map(|g| g.1)
        .fold(f64::NAN, f64::min)
}

/// Closest-points colour: red when a guarantee is violated (margin < 0), amber when the margin
/// is below the guarantee's own threshold (distance < 2 × threshold), green otherwise; white
/// when no metre guarantee exists.
fn margin_color(margin: f64, distance: f64) -> Color {
    if !margin.is_finite() {
        return Color::WHITE;
    }
    let threshold = distance - margin;
    if margin < 0.0 {
        Color::srgb(1.0, 0.15, 0.15)
    } else if margin < threshold {
        Color::srgb(1.0, 0.7, 0.1)
    } else {
        Color::srgb(0.2, 1.0, 0.3)
    }
}

/// Writes the read-out panel: the run's status ([`panel_status`]), the snapshot's read-outs
/// ([`panel_readouts`]), the surfaces' legend, the last events (replay, which also fills the
/// scrubber) and the camera, layers and keys ([`panel_keys`]); hides panel and scrubber when
/// the `panel` layer is off.
#[allow(clippy::too_many_arguments)]
fn panel(
    cur: Res<Current>,
    layers: Res<Layers>,
    rig: Res<CameraRig>,
    replay: Option<Res<Replay>>,
    live_ctl: Option<Res<LiveCtl>>,
    live: Option<NonSend<Live>>,
    diagnostics: Res<DiagnosticsStore>,
    mut text: Query<&mut Text, With<PanelText>>,
    mut fill: Query<&mut Node, With<ScrubFill>>,
    mut scrub_vis: Query<&mut Visibility, With<Scrubber>>,
    surfaces: Res<Surfaces>,
    forces: Option<Res<ContactForces>>,
) {
    for mut v in &mut scrub_vis {
        *v = if layers.panel {
            Visibility::Inherited
        } else {
            Visibility::Hidden
        };
    }
    let Ok(mut text) = text.single_mut() else {
        return;
    };
    if !layers.panel {
        text.0.clear();
        return;
    }
    use std::fmt::Write;
    let mut o = String::new();
    panel_status(
        &mut o,
        &cur,
        replay.as_deref(),
        live_ctl.as_deref(),
        live.as_deref(),
        &diagnostics,
    );
    panel_readouts(&mut o, &cur.snap, &layers, forces.as_deref());
    if layers.surfaces {
        for l in &surfaces.legend {
            let _ = writeln!(o, "surface: {l}");
        }
    }
    if let Some(r) = &replay {
        let past: Vec<_> = r.timeline.past_markers().collect();
        for m in past.iter().rev().take(4).rev() {
            let _ = writeln!(o, "event t = {:.2} s: {}", m.t_s, m.label);
        }
        if let Ok(mut f) = fill.single_mut() {
            f.width = Val::Percent((100.0 * r.timeline.fraction()) as f32);
        }
    }
    panel_keys(&mut o, &rig, &layers);
    text.0 = o;
}

/// The panel's first lines: live or replay, scene, time (of the end, replay), play state,
/// speed and frame rate; live, the simulation rate achieved.
fn panel_status(
    o: &mut String,
    cur: &Current,
    replay: Option<&Replay>,
    live_ctl: Option<&LiveCtl>,
    live: Option<&Live>,
    diagnostics: &DiagnosticsStore,
) {
    use std::fmt::Write;
    let s = &cur.snap;
    let fps = diagnostics
        .get(&FrameTimeDiagnosticsPlugin::FPS)
        .and_then(|d| d.smoothed())
        .unwrap_or(0.0);
    let (state, speed) = if let Some(r) = &replay {
        (r.timeline.playing, r.timeline.speed())
    } else if let Some(c) = &live_ctl {
        (c.playing, c.speed)
    } else {
        (false, 1.0)
    };
    let _ = writeln!(
        o,
        "rpod {} - {}   t = {:.2} s{}   {} {}x   {:.0} frames/s",
        if cur.live { "view (live)" } else { "replay" },
        cur.scene_name,
        s.t_s,
        cur.end_s
            .map(|e| format!(" / {e:.2} s"))
            .unwrap_or_default(),
        if state { "PLAYING" } else { "PAUSED" },
        speed,
        fps
    );
    if let Some(l) = &live {
        let _ = writeln!(o, "simulation rate achieved: {:.1}x real time", l.achieved);
    }
}

/// The snapshot's read-outs: minimum distance and closest parts, guarantee margins, docking
/// state, contacts and their normal forces, the force-arrow scale (contacts layer on) and the
/// first 12 diagnostics.
fn panel_readouts(o: &mut String, s: &Snapshot, layers: &Layers, forces: Option<&ContactForces>) {
    use std::fmt::Write;
    let _ = writeln!(
        o,
        "min distance {:.4} m   {}",
        s.min_distance_m,
        s.closest_parts
            .as_ref()
            .map(|(a, b)| format!("{a} <-> {b}"))
            .unwrap_or_default()
    );
    for (n, m, u) in &s.guarantees {
        let _ = writeln!(
            o,
            "guarantee {n}: {}  margin {m:.4} {u}",
            if *m >= 0.0 { "ok" } else { "VIOLATED" }
        );
    }
    if let Some(d) = &s.docking_state {
        let _ = writeln!(o, "docking: {d}");
    }
    for (a, b) in &s.contacts {
        match s.contact_force_n.get(&(a.clone(), b.clone())) {
            Some(f) => {
                let _ = writeln!(o, "contact: {a} <-> {b}   normal force {f:.4} N");
            }
            None => {
                let _ = writeln!(o, "contact: {a} <-> {b}");
            }
        }
    }
    if layers.contacts
        && !s.contacts.is_empty()
        && let Some(scale) = forces.as_ref().and_then(|f| f.scale_n_per_m)
    {
        let dec = (-scale.log10().floor()).max(0.0) as usize;
        let _ = writeln!(
            o,
            "force arrows (orange): normal force on the second part, {scale:.dec$} N per m of arrow"
        );
    }
    for (n, v) in s.diagnostics.iter().take(12) {
        if v.is_nan() {
            // Not computed yet (before the first step) or not applicable now.
            let _ = writeln!(o, "{n} = n/a");
        } else {
            let _ = writeln!(o, "{n} = {v:.5}");
        }
    }
}

/// The panel's last lines: the camera preset, which layers are on, and the keys.
fn panel_keys(o: &mut String, rig: &CameraRig, layers: &Layers) {
    use std::fmt::Write;
    let _ = writeln!(
        o,
        "camera: {:?}   layers: ports {} | LVLH/Earth {} | trails {} | closest {} | contacts {} | surfaces {}",
        rig.preset,
        on(layers.ports),
        on(layers.lvlh),
        on(layers.trails),
        on(layers.closest),
        on(layers.contacts),
        on(layers.surfaces)
    );
    let _ = writeln!(
        o,
        "keys: Space play/pause | . , step | + - speed | Left/Right seek | [ ] events | \
         0-3 camera | P L T C K S H layers | right-drag rotate | middle-drag pan | wheel zoom"
    );
}

fn on(b: bool) -> &'static str {
    if b { "on" } else { "off" }
}

/// Screenshots retaken at most while the first frames are still blank (10 frames apart).
const MAX_SHOT_RETRIES: u32 = 60;

/// Counts frames; prints the frame rate; takes the screenshot (with a sidecar JSON giving each
/// body's projected centre, for tests) and exits when asked.
fn frames_and_screenshot(
    mut commands: Commands,
    mut run: ResMut<Run>,
    time: Res<Time<Real>>,
    cur: Res<Current>,
    waiting: Res<PipelinesWaiting>,
    shot: ShotView,
    mut exit: MessageWriter<AppExit>,
) {
    run.frame += 1;
    if waiting.0.load(Ordering::Relaxed) == 0 {
        run.ready_streak += 1;
    } else {
        run.ready_streak = 0;
    }
    let now = time.elapsed_secs_f64();
    // Skip the first frames (pipeline compilation) for the rate.
    if run.frame == 30 {
        run.t_first = Some(now);
        run.sim_first_s = cur.snap.t_s;
    } else if run.t_first.is_some() {
        run.frames_since_first += 1;
    }
    let Some(n) = run.opts.frames else {
        return;
    };
    if run.frame < n {
        return;
    }
    if let Some(path) = run.opts.screenshot.clone() {
        // Wait (within reason) until no render pipeline is still compiling.
        let models_pending = shot.models.ready.len() < shot.models.expected;
        if !run.shot_requested
            && (run.ready_streak < READY_FRAMES || models_pending)
            && run.frame < n + MAX_READY_WAIT_FRAMES
        {
            return;
        }
        if !run.shot_requested {
            run.shot_requested = true;
            if let (Ok((cam, tf)), Ok(w)) = (shot.camera.single(), shot.window.single()) {
                let side = shot.sidecar(cam, tf, w, &cur.snap);
                let _ = std::fs::write(
                    path.with_extension("json"),
                    serde_json::to_string_pretty(&side).unwrap_or_default(),
                );
            }
            request_screenshot(&mut commands, path);
        }
        if !run.shot_done {
            return;
        }
    }
    print_rates(&run, now, &cur.snap);
    exit.write(AppExit::Success);
}

/// Asks for a screenshot of the window, saved to `path`; a frame of one colour is retaken
/// 10 frames later (at most [`MAX_SHOT_RETRIES`] times), otherwise the shot is done.
fn request_screenshot(commands: &mut Commands, path: PathBuf) {
    commands
        .spawn(Screenshot::primary_window())
        .observe(save_to_disk(path))
        .observe(|cap: On<ScreenshotCaptured>, mut run: ResMut<Run>| {
            // A frame of one colour means the render pipelines were still compiling
            // (the software renderer takes a while): take another a little later.
            let uniform = cap
                .image
                .data
                .as_deref()
                .is_none_or(|d| d.chunks_exact(4).all(|p| p == &d[..4]));
            if uniform && run.retries < MAX_SHOT_RETRIES {
                run.retries += 1;
                run.shot_requested = false;
                let next = run.frame + 10;
                run.opts.frames = Some(next);
            } else {
                run.shot_done = true;
            }
        });
}

/// Prints the frame rate and the simulated time's rate over the frames after warm-up.
fn print_rates(run: &Run, now: f64, snap: &Snapshot) {
    if let Some(t0) = run.t_first {
        let frames = run.frames_since_first;
        let dt = now - t0;
        if frames > 0 && dt > 0.0 {
            println!(
                "rendered {} frames; {frames} frames after warm-up in {dt:.2} s = {:.1} frames/s",
                run.frame,
                f64::from(frames) / dt
            );
            let sim = snap.t_s - run.sim_first_s;
            println!(
                "simulated time advanced {sim:.3} s in those {dt:.2} s = {:.2}x real time \
                 (asked {}x{})",
                sim / dt,
                run.opts.speed,
                if run.opts.play { "" } else { ", paused" }
            );
        }
    }
}

/// What the screenshot's sidecar JSON describes: the 3-D camera and the window (to project
/// world points to window pixels), the bodies, the force arrows and lines the overlays drew
/// this frame, the glTF models, the constraint surfaces, the layers and the arrow scale.
#[derive(bevy::ecs::system::SystemParam)]
struct ShotView<'w, 's> {
    camera: Query<'w, 's, (&'static Camera, &'static Transform), With<Camera3d>>,
    window: Query<'w, 's, &'static Window, With<PrimaryWindow>>,
    geom: Res<'w, SceneGeom>,
    drawn: Res<'w, DrawnArrows>,
    drawn_lines: Res<'w, DrawnLines>,
    forces: Option<Res<'w, ContactForces>>,
    models: Res<'w, ModelStatus>,
    surfaces: Res<'w, Surfaces>,
    layers: Res<'w, Layers>,
}

impl ShotView<'_, '_> {
    /// The sidecar JSON for the snapshot `snap` seen by camera `cam` at `tf` in window `w`.
    fn sidecar(
        &self,
        cam: &Camera,
        tf: &Transform,
        w: &Window,
        snap: &Snapshot,
    ) -> serde_json::Value {
        let (drawn_lines, models, layers) = (&self.drawn_lines, &self.models, &self.layers);
        let gt = GlobalTransform::from(*tf);
        // Viewport → window pixels (the scaled view's image is smaller than the window).
        let k = cam
            .logical_viewport_size()
            .map_or(1.0, |v| w.physical_width() as f32 / v.x.max(1.0));
        let project = |p: Vec3| cam.world_to_viewport(&gt, p).ok().map(|v| v * k);
        let bodies = self.bodies_json(tf, snap, &project);
        let px = |p: Vec3| project(p).map(|p| [p.x, p.y]);
        let arrows = self.arrows_json(&px);
        let shown_surfaces = self.surfaces_json(snap, &px);
        serde_json::json!({
            "layers": {
                "ports": layers.ports, "lvlh": layers.lvlh, "trails": layers.trails,
                "closest": layers.closest, "contacts": layers.contacts,
                "surfaces": layers.surfaces, "panel": layers.panel,
            },
            "surfaces": shown_surfaces,
            "width_px": w.physical_width(),
            "height_px": w.physical_height(),
            "scale_factor": w.scale_factor(),
            "t_s": snap.t_s,
            "bodies": bodies,
            "force_arrows": arrows,
            "lines": drawn_lines.0.iter().map(|(what, c, a, b)| {
                let c = c.to_srgba();
                serde_json::json!({
                    "what": what,
                    "srgb": [c.red, c.green, c.blue],
                    "start_px": px(*a),
                    "end_px": px(*b),
                })
            }).collect::<Vec<_>>(),
            "models": models.ready.iter().map(|(part, path, n)| serde_json::json!({
                "part": part, "path": path, "meshes": n,
            })).collect::<Vec<_>>(),
            "models_expected": models.expected,
            "arrow_scale_n_per_m": self.forces.as_ref().and_then(|f| f.scale_n_per_m),
        })
    }

    /// Each body's name, centre of mass (world, m) and its projection, and the projected
    /// radius of a 0.5 m sphere about it, px.
    fn bodies_json(
        &self,
        tf: &Transform,
        snap: &Snapshot,
        project: &impl Fn(Vec3) -> Option<Vec2>,
    ) -> Vec<serde_json::Value> {
        self.geom
            .bodies
            .iter()
            .zip(&snap.bodies)
            .map(|(b, (p, _))| {
                let c = v3(p);
                let px = project(c);
                // Projected radius of a 0.5 m sphere about the centre of mass.
                let right = tf.right().as_vec3();
                let r_px = px.and_then(|p0| project(c + right * 0.5).map(|p1| (p1 - p0).length()));
                serde_json::json!({
                    "name": b.name,
                    "centre_world_m": [p.x, p.y, p.z],
                    "centre_px": px.map(|p| [p.x, p.y]),
                    "half_metre_px": r_px,
                })
            })
            .collect()
    }

    /// The force arrows drawn this frame: parts, force (N), length (m) and projected ends.
    fn arrows_json(&self, px: &impl Fn(Vec3) -> Option<[f32; 2]>) -> Vec<serde_json::Value> {
        self.drawn
            .0
            .iter()
            .map(|(a, b, f, p0, p1)| {
                serde_json::json!({
                    "a": a,
                    "b": b,
                    "force_n": f,
                    "length_m": (*p1 - *p0).length(),
                    "start_px": px(*p0),
                    "end_px": px(*p1),
                })
            })
            .collect()
    }

    /// Each constraint surface's legend, colour and centroid (mean vertex), world and projected.
    fn surfaces_json(
        &self,
        snap: &Snapshot,
        px: &impl Fn(Vec3) -> Option<[f32; 2]>,
    ) -> Vec<serde_json::Value> {
        self.surfaces
            .list
            .iter()
            .zip(&self.surfaces.legend)
            .filter_map(|(sf, legend)| {
                let m = &sf.mesh.positions_m;
                let mean = m.iter().fold(Vector3::zeros(), |a, p| a + p) / m.len() as f64;
                let origin = match sf.anchor {
                    super::surfaces::Anchor::World(o) => o,
                    super::surfaces::Anchor::BodyCom(i) => snap.bodies.get(i)?.0,
                };
                let c = origin + mean;
                Some(serde_json::json!({
                    "legend": legend,
                    "rgba": sf.rgba,
                    "centroid_world_m": [c.x, c.y, c.z],
                    "centroid_px": px(v3(&c)),
                }))
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn invariant_layers_from_options() {
        let all = Layers::from_options(&ViewerOptions::default());
        assert!(all.ports && all.lvlh && all.trails && all.closest && all.contacts);
        assert!(all.surfaces && all.panel);
        let none = Layers::from_options(&ViewerOptions {
            overlays: false,
            ..default()
        });
        assert!(!(none.ports || none.lvlh || none.trails || none.closest || none.contacts));
        assert!(!(none.surfaces || none.panel));
        // `--layers` picks exactly the named ones, whatever `overlays` says.
        let some = ViewerOptions {
            overlays: false,
            layers: Some(vec!["contacts".into(), "surfaces".into()]),
            ..default()
        };
        let l = Layers::from_options(&some);
        assert!(l.contacts && l.surfaces);
        assert!(!(l.ports || l.lvlh || l.trails || l.closest || l.panel));
        assert!(check_options(&some).is_ok());
        let bad = ViewerOptions {
            layers: Some(vec!["contact".into()]),
            ..default()
        };
        let e = check_options(&bad).unwrap_err();
        assert!(
            e.contains("unknown layer `contact`") && e.contains("contacts"),
            "{e}"
        );
        let cam = ViewerOptions {
            camera: "side".into(),
            ..default()
        };
        assert!(check_options(&cam).is_err());
        for (scale, ok) in [
            (0.5, true),
            (1.0, true),
            (0.0, false),
            (1.5, false),
            (-1.0, false),
        ] {
            let o = ViewerOptions {
                render_scale: scale,
                ..default()
            };
            assert_eq!(check_options(&o).is_ok(), ok, "render scale {scale}");
        }
        assert_eq!(scaled_px((1280, 720), 0.5), (640, 360));
    }

    #[test]
    fn invariant_margin_colour() {
        // A 1 m clearance guarantee (threshold = distance − margin = 1 m): violated red, within
        // its own threshold again amber, clear green; no metre guarantee, white.
        let red = Color::srgb(1.0, 0.15, 0.15);
        let amber = Color::srgb(1.0, 0.7, 0.1);
        let green = Color::srgb(0.2, 1.0, 0.3);
        assert_eq!(margin_color(-0.2, 0.8), red);
        assert_eq!(margin_color(0.5, 1.5), amber);
        assert_eq!(margin_color(1.5, 2.5), green);
        assert_eq!(margin_color(f64::NAN, 3.0), Color::WHITE);
        assert_eq!(scaled_px((100, 20), 0.1), (16, 16));
    }
}
