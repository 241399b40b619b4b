//! From a scene to a running [`Simulation`].

use super::monitor::{ColliderRef, ContactState};
use super::output::{Diagnostics, OutputFiles, Recorder};
use super::{
    BodyState, Clock, Env, EventLog, Guarantees, MonitorState, Part, Physics, Roster, SimBody,
    StepBudget, Wrench, conv,
};
use crate::scene::parts::{PartCollider, Primitive, expand_body};
use crate::scene::{BodySpec, Environment, InitFrame, LoadedScene, Scene, SceneError};
use bevy::prelude::*;
use bevy_rapier3d::rapier::prelude as rp;
use nalgebra::{Matrix3, Rotation3, UnitQuaternion, Vector3};
use std::path::Path;

/// Steps run per `App::update` when advancing a long way.
pub const STEPS_PER_UPDATE: u64 = 1000;

/// A scene turned into a Bevy app, ready to step.
pub struct Simulation {
    /// The Bevy app (world, schedules).
    pub app: App,
    /// The scene it was built from.
    pub scene: Scene,
    /// Scene file name, for the summary.
    pub scene_file: String,
    /// Wall-clock seconds spent stepping.
    pub wall_s: f64,
    /// What produced this run (rpod version, git commit, scene hash, `--set` overrides), for
    /// `summary.json`.
    pub provenance: serde_json::Value,
    /// Mesh parts: judged exactly, simulated as convex pieces (empty without meshes).
    pub meshes: Vec<MeshPartReport>,
}

/// The rapier/parry shape of a part primitive (f32, in the part frame); `None` for a hull
/// parry cannot build. The viewer uses the same shapes as the colliders.
pub(crate) fn primitive_shape(p: &Primitive) -> Option<rp::SharedShape> {
    Some(match p {
        Primitive::Cuboid { half_m } => {
            rp::SharedShape::cuboid(half_m.x as f32, half_m.y as f32, half_m.z as f32)
        }
        Primitive::Cylinder {
            radius_m,
            half_length_m,
        } => rp::SharedShape::cylinder(*half_length_m as f32, *radius_m as f32),
        Primitive::Ball { radius_m } => rp::SharedShape::ball(*radius_m as f32),
        Primitive::ConvexHull { points_m } => {
            let pts: Vec<_> = points_m.iter().map(|p| conv::v(&p.coords)).collect();
            rp::SharedShape::convex_hull(&pts)?
        }
        Primitive::Mesh { mesh, .. } => super::mesh::judged_shape(mesh)?,
    })
}

/// Whether rapier's continuous collision pass could ever clamp a motion in `w`.
///
/// In rapier 0.35 every fast dynamic body is swept (`CCDSolver::solve_continuous`), and a
/// sweep considers only the targets its tier allows (`ccd::sweeps::tier_allows`): a body
/// without `ccd_enabled` sweeps against fixed targets (a fixed body's colliders, or a collider
/// with no parent) and a body with it (a bullet) against every body but another bullet. So
/// when there is no fixed target and the dynamic bodies are all bullets or all not, no sweep
/// has a target: no motion is clamped and no event is sent, and the pass changes nothing but
/// its cost. `true` (conservatively) also for any kinematic body.
pub(crate) fn ccd_has_targets(w: &rp::PhysicsWorld) -> bool {
    if w.colliders.iter().any(|(_, c)| c.parent().is_none())
        || w.bodies.iter().any(|(_, b)| !b.is_dynamic())
    {
        return true;
    }
    let bullets = w.bodies.iter().filter(|(_, b)| b.is_ccd_enabled()).count();
    bullets > 0 && bullets < w.bodies.len()
}

/// A mesh part as built: its name, triangles, convex pieces and the decomposition's measured
/// deviation from the mesh (`summary.json`'s `meshes`).
#[derive(Debug, Clone, serde::Serialize)]
pub struct MeshPartReport {
    /// `body/collider`.
    pub part: String,
    /// Triangles of the judged mesh.
    pub triangles: usize,
    /// Convex pieces rapier simulates.
    pub convex_pieces: usize,
    /// Largest deviation measured between the pieces and the mesh, m ([`super::mesh`]).
    pub decomposition_max_deviation_m: f64,
}

/// Initial world-frame state of a body (centre of mass), given the reference orbit state.
fn initial_state(b: &BodySpec, reference: Option<(Vector3<f64>, Vector3<f64>)>) -> BodyState {
    let i = &b.initial;
    let pos = Vector3::from(i.pos_m);
    let vel = Vector3::from(i.vel_m_s);
    let att_in_frame = i.attitude.to_quat();
    let omega_body = Vector3::from(i.rate_body_deg_s).map(f64::to_radians);
    let (pos_w, vel_w, att_w) = match (i.frame, reference) {
        (InitFrame::Hill, Some((r, v))) => {
            // Hill axes in the world (ECI-parallel) frame: x radial, y along-track, z normal.
            let x = r.normalize();
            let z = r.cross(&v).normalize();
            let y = z.cross(&x);
            let c = Matrix3::from_columns(&[x, y, z]);
            let omega_frame = r.cross(&v) / r.norm_squared();
            let pos_w = c * pos;
            let vel_w = c * vel + omega_frame.cross(&pos_w);
            let rot = UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(c));
            (pos_w, vel_w, rot * att_in_frame)
        }
        _ => (pos, vel, att_in_frame),
    };
    BodyState {
        pos_m: pos_w,
        vel_m_s: vel_w,
        att: att_w,
        omega_rad_s: att_w * omega_body,
    }
}

/// Principal moments and the rotation body → principal frame (right-handed), f64.
fn principal(j: &Matrix3<f64>) -> (Vector3<f64>, UnitQuaternion<f64>) {
    let e = j.symmetric_eigen();
    let mut vecs = e.eigenvectors;
    let mut vals = e.eigenvalues;
    if vecs.determinant() < 0.0 {
        vecs.swap_columns(1, 2);
        vals.swap_rows(1, 2);
    }
    let rot = UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(vecs));
    (vals, rot)
}

/// The rapier world of a scene: no gravity (the environment applies it), no speed cap, the
/// scene's step over its substeps, contact recycling off.
fn physics_world(scene: &Scene) -> rp::PhysicsWorld {
    let dt = scene.dt_s;
    let mut pw = rp::PhysicsWorld::new();
    pw.gravity = rp::Vector::ZERO;
    // No speed cap: debris and fly-bys move at km/s (rapier's default clamps at 400 m/s).
    pw.integration_parameters.normalized_max_linear_velocity = f32::MAX;
    pw.integration_parameters.dt = (dt / f64::from(scene.physics_substeps)) as f32;
    // rapier 0.35 "recycles" a contact pair whose relative pose moved less than 5 cm (2 cm
    // without contact points) since its last full narrow-phase update: it keeps the old
    // contact points, normal and lever arms and only advances their separations along the
    // frozen normal. A speculative contact made 2 cm above the slot's rim (its normal along
    // the rim edge) then stops the cone when it crosses the mouth plane, millimetres clear of
    // the real wall (trial 17 of `scenes/trials/capture_envelope.ron`). Every pair is
    // recomputed every step instead: `tests/val_contact_normals.rs`.
    pw.integration_parameters.contact_recycling = false;
    pw
}

/// Spawns a scene's bodies, in scene order: each body's rapier body and colliders, its entity
/// ([`SimBody`], [`BodyState`], [`Wrench`]) and one [`Part`] entity per collider.
struct BodyBuilder<'a> {
    /// The scene (errors are located in its text).
    loaded: &'a LoadedScene,
    /// The app the entities are spawned in.
    app: &'a mut App,
    /// The rapier world the bodies and colliders are inserted in.
    pw: &'a mut rp::PhysicsWorld,
    /// The reference orbit's ECI state at t = 0 (orbit scenes: Hill-frame initial states).
    reference: Option<(Vector3<f64>, Vector3<f64>)>,
    /// Body and part entities so far.
    roster: Roster,
    /// Collider → body and part, so far.
    contacts: ContactState,
    /// Each body's colliders so far, scene order.
    all_parts: Vec<Vec<PartCollider>>,
    /// Mesh parts so far.
    meshes: Vec<MeshPartReport>,
}

impl BodyBuilder<'_> {
    /// Spawns body `index` (its colliders with it).
    fn body(&mut self, index: usize, b: &BodySpec) -> Result<(), SceneError> {
        let loaded = self.loaded;
        if matches!(b.initial.frame, InitFrame::Hill) && self.reference.is_none() {
            return Err(loaded.error_at(
                &format!("bodies.{}.initial.frame", b.name),
                "frame `Hill` needs an `Orbit` environment",
            ));
        }
        let state = initial_state(b, self.reference);
        let com = Vector3::from(b.com_m);
        let j = b.inertia_kg_m2.matrix();
        let (moments, frame) = principal(&j);
        let mprops = rp::MassProperties::with_principal_inertia_frame(
            conv::v(&com),
            b.mass_kg as f32,
            conv::v(&moments),
            conv::q(&frame),
        );
        let Some(inertia_inv) = j.try_inverse().filter(|m| m.iter().all(|v| v.is_finite())) else {
            return Err(loaded.error_at(
                &format!("bodies.{}.inertia_kg_m2", b.name),
                "the inertia tensor cannot be inverted in f64",
            ));
        };
        let colliders = expand_body(b);
        let has_docking = colliders.iter().any(|c| c.role.is_docking());
        let has_mesh = colliders
            .iter()
            .any(|c| matches!(c.shape, Primitive::Mesh { .. }));
        let rb = rp::RigidBodyBuilder::dynamic()
            .pose(conv::pose(&state.body_pose(&com)))
            .linvel(conv::v(&state.vel_m_s))
            .angvel(conv::v(&state.omega_rad_s))
            .can_sleep(false)
            .gyroscopic_forces_enabled(true)
            .ccd_enabled(has_docking || has_mesh)
            .additional_mass_properties(mprops)
            .build();
        let handle = self.pw.insert_body(rb);
        let body_entity = self
            .app
            .world_mut()
            .spawn((
                SimBody {
                    index,
                    name: b.name.clone(),
                    role: b.role,
                    handle,
                    mass_kg: b.mass_kg,
                    inertia_kg_m2: j,
                    com_body_m: com,
                    inertia_inv,
                },
                state,
                Wrench::default(),
            ))
            .id();
        let mut part_entities = Vec::new();
        for (part_index, pc) in colliders.iter().enumerate() {
            part_entities.push(self.part(b, (index, body_entity, handle), part_index, pc)?);
        }
        self.roster.bodies.push(body_entity);
        self.roster.parts.push(part_entities);
        self.roster.names.push(b.name.clone());
        self.all_parts.push(colliders);
        Ok(())
    }

    /// Spawns collider `part_index` of body `b` (its index, entity and rapier handle): the
    /// rapier collider (a mesh's convex pieces), its [`ColliderRef`] and its [`Part`] entity.
    fn part(
        &mut self,
        b: &BodySpec,
        (index, body_entity, handle): (usize, Entity, rp::RigidBodyHandle),
        part_index: usize,
        pc: &PartCollider,
    ) -> Result<Entity, SceneError> {
        let loaded = self.loaded;
        let Some(shape) = primitive_shape(&pc.shape) else {
            return Err(loaded.error_at(
                &format!("bodies.{}.parts.{}", b.name, pc.part),
                format!("collider `{}` has a degenerate convex hull", pc.name),
            ));
        };
        // Judged as the mesh; simulated as its convex pieces.
        let simulated = match &pc.shape {
            Primitive::Mesh {
                mesh,
                decomposition,
            } => {
                let Some(s) = super::mesh::simulated_shape(mesh, decomposition) else {
                    return Err(loaded.error_at(
                        &format!("bodies.{}.parts.{}.shape.decomposition", b.name, pc.part),
                        format!(
                            "collider `{}`: the convex decomposition gave no piece",
                            pc.name
                        ),
                    ));
                };
                let d = super::mesh::decomposition(mesh, decomposition);
                self.meshes.push(MeshPartReport {
                    part: format!("{}/{}", b.name, pc.name),
                    triangles: mesh.triangles.len(),
                    convex_pieces: d.hulls.len(),
                    decomposition_max_deviation_m: d.max_deviation_m,
                });
                s
            }
            _ => shape.clone(),
        };
        let col = rp::ColliderBuilder::new(simulated)
            .position(conv::pose(&pc.pose_body))
            .density(0.0)
            .friction(b.friction as f32)
            .restitution(b.restitution as f32)
            .build();
        let ch = self.pw.insert_collider(col, Some(handle));
        self.contacts.colliders.insert(
            ch,
            ColliderRef {
                body: index,
                part: part_index,
                full_name: format!("{}/{}", b.name, pc.name),
                docking: pc.role.is_docking(),
            },
        );
        Ok(self
            .app
            .world_mut()
            .spawn(Part {
                body: body_entity,
                body_index: index,
                part: pc.part.clone(),
                name: pc.name.clone(),
                role: pc.role,
                collider: ch,
                shape,
                pose_body: pc.pose_body,
                bound_radius_m: pc.shape.bounding_radius_m(),
            })
            .id())
    }
}

/// A scene's bodies as spawned.
struct SpawnedBodies {
    /// Body and part entities, scene order.
    roster: Roster,
    /// Collider → body and part; the per-body contact state sized.
    contacts: ContactState,
    /// Each body's colliders, scene order.
    all_parts: Vec<Vec<PartCollider>>,
    /// Mesh parts.
    meshes: Vec<MeshPartReport>,
}

/// Spawns every body of the scene, in scene order ([`BodyBuilder`]).
fn spawn_bodies(
    app: &mut App,
    pw: &mut rp::PhysicsWorld,
    loaded: &LoadedScene,
    reference: Option<(Vector3<f64>, Vector3<f64>)>,
) -> Result<SpawnedBodies, SceneError> {
    let mut builder = BodyBuilder {
        loaded,
        app,
        pw,
        reference,
        roster: Roster::default(),
        contacts: ContactState::default(),
        all_parts: Vec::new(),
        meshes: Vec::new(),
    };
    for (index, b) in loaded.scene.bodies.iter().enumerate() {
        builder.body(index, b)?;
    }
    let n = loaded.scene.bodies.len();
    let mut contacts = builder.contacts;
    contacts.touching = vec![false; n];
    contacts.body_impulse = vec![Vector3::zeros(); n];
    contacts.body_angular_impulse = vec![Vector3::zeros(); n];
    Ok(SpawnedBodies {
        roster: builder.roster,
        contacts,
        all_parts: builder.all_parts,
        meshes: builder.meshes,
    })
}

/// Parts of different bodies must not overlap at t = 0 unless marked: the overlaps the scene
/// allows ([`super::overlap::check_initial`]), or the located error.
fn check_initial_overlaps(
    app: &App,
    loaded: &LoadedScene,
    bodies: &SpawnedBodies,
) -> Result<Vec<super::overlap::SuppressedPair>, SceneError> {
    let probes: Vec<Vec<super::overlap::Probe>> = bodies
        .roster
        .bodies
        .iter()
        .zip(&bodies.all_parts)
        .zip(&bodies.roster.parts)
        .enumerate()
        .map(|(i, ((be, cols), pes))| {
            let s = app.world().get::<BodyState>(*be).expect("state");
            let body_pose = s.body_pose(&Vector3::from(loaded.scene.bodies[i].com_m));
            cols.iter()
                .zip(pes)
                .map(|(c, pe)| {
                    let part = app.world().get::<Part>(*pe).expect("part");
                    super::overlap::Probe {
                        collider: c,
                        pose: body_pose * c.pose_body,
                        shape: part.shape.clone(),
                        handle: part.collider,
                        entity: *pe,
                    }
                })
                .collect()
        })
        .collect();
    super::overlap::check_initial(loaded, &probes)
}

/// The scene's `guarantees`, built (errors located under `guarantees.NAME`).
fn scene_guarantees(
    loaded: &LoadedScene,
    all_parts: &[Vec<PartCollider>],
) -> Result<Guarantees, SceneError> {
    let scene = &loaded.scene;
    let mut guarantees = Guarantees::default();
    let gctx = crate::guarantee::registry::GuaranteeContext {
        scene,
        parts: all_parts,
    };
    for g in &scene.guarantees {
        let p = format!("guarantees.{}", g.name());
        let built = g.build(&gctx).map_err(|e| {
            let e = e.within(&p);
            loaded.error_at(&e.field, e.message)
        })?;
        guarantees.register(built);
    }
    Ok(guarantees)
}

/// Inserts the core's resources: the rapier world, the clock, the roster and contact state,
/// the guarantees, the monitor's and the recorder's state (and the multi-rate planner if the
/// scene asks for it).
fn insert_core_resources(
    app: &mut App,
    pw: rp::PhysicsWorld,
    scene: &Scene,
    roster: Roster,
    contacts: ContactState,
    guarantees: Guarantees,
    all_parts: &[Vec<PartCollider>],
) {
    let dt = scene.dt_s;
    app.insert_resource(Physics {
        world: pw,
        substeps: scene.physics_substeps,
    })
    .insert_resource(Clock::new(dt))
    .insert_resource(StepBudget(0))
    .insert_resource(super::multirate::SpanCap::default())
    .insert_resource(roster)
    .insert_resource(contacts)
    .insert_resource(guarantees)
    .insert_resource(MonitorState {
        part_names: all_parts
            .iter()
            .zip(&scene.bodies)
            .map(|(ps, b)| {
                ps.iter()
                    .map(|p| format!("{}/{}", b.name, p.name))
                    .collect()
            })
            .collect(),
        part_docking: all_parts
            .iter()
            .map(|ps| ps.iter().map(|p| p.role.is_docking()).collect())
            .collect(),
        min_lower_m: f64::INFINITY,
        ..Default::default()
    })
    .insert_resource(EventLog::default())
    .insert_resource(Diagnostics::default())
    .insert_resource(Recorder {
        every: scene.record_every_steps,
        files: None,
        events_written: 0,
        rows: 0,
        last_row_step: None,
        error: None,
        history: Vec::new(),
        force_row: false,
        last_row_t_s: None,
        contact_impulse_at_row: Default::default(),
        pair_columns: Vec::new(),
        contact_points: false,
    });
    if let Some(m) = super::multirate::MultiRate::from_scene(&scene.stepping, dt) {
        app.insert_resource(m);
    }
}

/// Adds one plugin per feature, in this order (each doc comment names the sets it runs in):
/// the pipeline, the guard, the environment, then where the scene has them the multi-rate
/// planner's system, the t = 0 overlaps, the docking mechanism and its compliant contact, the
/// air-bearing table, the controllers and the plume loads; then finishes the app.
fn add_feature_plugins(
    app: &mut App,
    loaded: &LoadedScene,
    environment: super::environment::EnvironmentPlugin,
    suppressed: Vec<super::overlap::SuppressedPair>,
    has_meshes: bool,
) -> Result<(), SceneError> {
    app.add_plugins((
        super::PipelinePlugin,
        super::guard::GuardPlugin,
        environment,
    ));
    if app
        .world()
        .contains_resource::<super::multirate::MultiRate>()
    {
        // The planner is in the schedule only with its resource (a fixed-step scene plans
        // nothing and pays nothing for it).
        app.add_systems(
            super::SimStep,
            super::multirate::plan_step.in_set(super::Order::Plan),
        );
    }
    if let Some(p) = super::overlap::OverlapPlugin::new(loaded, suppressed)? {
        app.add_plugins(p);
    }
    if let Some(p) = super::docking::DockingPlugin::new(app.world(), loaded)? {
        app.add_plugins(p);
    }
    super::contact_model::install(app, loaded)?;
    if let Some(p) = super::airbearing::AirBearingPlugin::new(app.world(), loaded)? {
        app.add_plugins(p);
    }
    // rapier's continuous pass (CCD) sweeps every fast dynamic body (the `ccd_enabled`
    // flag only widens what it sweeps against); in a scene with a mesh body where no sweep
    // can have a target ([`ccd_has_targets`]) it is pure cost — the convex pieces' mass
    // properties recomputed every sweep — and cannot change a result: switch it off there.
    if has_meshes {
        let mut phys = app.world_mut().resource_mut::<super::Physics>();
        if !ccd_has_targets(&phys.world) {
            phys.world.integration_parameters.max_ccd_substeps = 0;
        }
    }
    super::controllers::install(app, loaded)?;
    super::plume::install_loads(app);
    app.finish();
    app.cleanup();
    Ok(())
}

/// Inserts the monitor's geometry, the step motion at rest, the broad phase, the pairs
/// guarantees name and the rapier hand-over's bookkeeping.
fn install_monitor(w: &mut World, scene: &Scene) {
    let dt = scene.dt_s;
    let geo = super::monitor::MonitorGeometry::from_world(w);
    let n = geo.extent_m.len();
    let states: Vec<BodyState> = w
        .resource::<Roster>()
        .bodies
        .clone()
        .iter()
        .map(|e| w.get::<BodyState>(*e).expect("state").clone())
        .collect();
    let motion = super::motion::StepMotion {
        t0_s: 0.0,
        dt_s: dt,
        paths: states
            .iter()
            .map(|s| super::motion::BodyPath::at_rest(s, dt))
            .collect(),
        extent_m: geo.extent_m.clone(),
        ..Default::default()
    };
    // The physics stage engages rapier for pairs whose collider boxes may come within
    // RAPIER_ENGAGE_M: boxes reach √3 of a part's bounding radius, so pairs up to
    // that much beyond the extents must be seen by the broad phase.
    let physics_reach = super::RAPIER_ENGAGE_M
        + 2.0
            * geo
                .aabb_extent_m
                .iter()
                .zip(&geo.extent_m)
                .map(|(a, e)| a - e)
                .fold(0.0, f64::max);
    let mut bp = super::broadphase::BroadPhase::new(n, scene.monitor.horizon_for(n), physics_reach);
    bp.update(&motion);
    let mut named: Vec<(usize, usize)> = w
        .resource::<Guarantees>()
        .list
        .iter()
        .flat_map(|g| match g.reads() {
            crate::guarantee::Reads::Pairs(l) => l,
            _ => Vec::new(),
        })
        .map(|(a, b)| (a.min(b), a.max(b)))
        .filter(|(a, b)| a != b)
        .collect();
    named.sort_unstable();
    named.dedup();
    w.insert_resource(geo);
    w.insert_resource(super::motion::StepMotion {
        paths: Vec::new(),
        ready: false,
        ..motion
    });
    w.insert_resource(bp);
    w.insert_resource(super::NamedPairs(named));
    w.insert_resource(super::RapierSync {
        every_step: scene.monitor.rapier_every_step,
        ..Default::default()
    });
}

/// The monitor's view of t = 0: distances, then the guarantees' first sample.
fn monitor_t0(w: &mut World) {
    use bevy::ecs::system::RunSystemOnce;
    w.run_system_once(super::monitor::distances)
        .expect("monitor resources exist");
    w.run_system_once(super::check_guarantees)
        .expect("monitor resources exist");
}

impl Simulation {
    /// Builds the app. Geometry checks that need the shapes (overlaps at t = 0) are reported
    /// against the scene text, like every other scene error.
    ///
    /// In order: the rapier world, the environment (its reference orbit places Hill-frame
    /// initial states), the bodies, the t = 0 overlap check, the guarantees, the core's
    /// resources, the feature plugins, the monitor's state and its view of t = 0.
    pub fn new(loaded: &LoadedScene) -> Result<Self, SceneError> {
        let scene = loaded.scene.clone();
        let mut app = App::new();
        let mut pw = physics_world(&scene);
        let environment =
            super::environment::EnvironmentPlugin::new(&scene.environment, scene.dt_s);
        let bodies = spawn_bodies(&mut app, &mut pw, loaded, environment.reference())?;
        let suppressed = check_initial_overlaps(&app, loaded, &bodies)?;
        let guarantees = scene_guarantees(loaded, &bodies.all_parts)?;
        let SpawnedBodies {
            roster,
            contacts,
            all_parts,
            meshes,
        } = bodies;
        insert_core_resources(
            &mut app, pw, &scene, roster, contacts, guarantees, &all_parts,
        );
        add_feature_plugins(
            &mut app,
            loaded,
            environment,
            suppressed,
            !meshes.is_empty(),
        )?;
        install_monitor(app.world_mut(), &scene);
        monitor_t0(app.world_mut());
        Ok(Self {
            app,
            scene,
            scene_file: loaded.file.clone(),
            wall_s: 0.0,
            provenance: loaded.provenance(),
            meshes,
        })
    }

    /// Starts recording into `dir` (temporary names until [`Simulation::finish`]); writes the
    /// header and the t = 0 row.
    pub fn record_to(&mut self, dir: &Path) -> std::io::Result<()> {
        let points = self.app.world().resource::<Recorder>().contact_points;
        let files = OutputFiles::create(dir, points)?;
        self.app.world_mut().resource_mut::<Recorder>().files = Some(files);
        super::output::write_header(self.app.world_mut());
        super::output::record_now(self.app.world_mut());
        Ok(())
    }

    /// Also write `contact_points.csv` (every contact point at every step and compliant
    /// sub-step); call before [`Simulation::record_to`].
    pub fn record_contact_points(&mut self, on: bool) {
        self.app
            .world_mut()
            .resource_mut::<Recorder>()
            .contact_points = on;
    }

    /// Advances exactly `n` fixed steps.
    pub fn step(&mut self, n: u64) {
        let t0 = std::time::Instant::now();
        let mut left = n;
        while left > 0 && self.guard_trip().is_none() {
            let k = left.min(STEPS_PER_UPDATE);
            self.app.world_mut().resource_mut::<StepBudget>().0 = k;
            self.app.update();
            left -= k;
        }
        self.wall_s += t0.elapsed().as_secs_f64();
    }

    /// Runs one pipeline step of at most `max` fixed steps and returns how many it advanced:
    /// one with `stepping: Fixed`, possibly several with `MultiRate` ([`super::multirate`]); 0
    /// when `max` is 0 or the finiteness guard has stopped the run. For callers that must look
    /// at the run after every pipeline step (the Python binding, where a Python law or guarantee
    /// may have raised); the same steps as [`Simulation::step`] (the `SimStep` schedule, which
    /// is all an update runs).
    pub fn step_pipeline(&mut self, max: u64) -> u64 {
        if max == 0 || self.guard_trip().is_some() {
            return 0;
        }
        let t0 = std::time::Instant::now();
        let before = self.steps();
        let world = self.app.world_mut();
        world.resource_mut::<super::multirate::SpanCap>().0 = max;
        world.run_schedule(super::SimStep);
        self.wall_s += t0.elapsed().as_secs_f64();
        self.steps() - before
    }

    /// Steps needed to cover `duration_s` (rounded to the nearest step).
    pub fn steps_for(&self, duration_s: f64) -> u64 {
        (duration_s / self.scene.dt_s).round().max(0.0) as u64
    }

    /// What stopped the run, if the finiteness guard did (see [`super::guard`]).
    pub fn guard_trip(&self) -> Option<&super::guard::GuardTrip> {
        self.app
            .world()
            .get_resource::<super::guard::Guard>()
            .and_then(|g| g.trip())
    }

    /// Simulated time, s.
    pub fn t_s(&self) -> f64 {
        self.app.world().resource::<Clock>().t_s()
    }

    /// Completed steps.
    pub fn steps(&self) -> u64 {
        self.app.world().resource::<Clock>().step
    }

    /// The f64 state of a body by name.
    pub fn body(&self, name: &str) -> Option<BodyState> {
        let roster = self.app.world().resource::<Roster>();
        let i = roster.names.iter().position(|n| n == name)?;
        self.app.world().get::<BodyState>(roster.bodies[i]).cloned()
    }

    /// The reference orbit's ECI state (r, v), if the scene is in orbit.
    pub fn reference_state(&self) -> Option<(Vector3<f64>, Vector3<f64>)> {
        self.app
            .world()
            .resource::<Env>()
            .orbit()
            .map(|e| e.reference.state())
    }

    /// A copy of the reference orbit (orbit scenes): its current state and its gravity model,
    /// to propagate it further outside the app (the viewer's track of the reference).
    pub fn reference_orbit(&self) -> Option<crate::orbit::integrate::ReferenceOrbit> {
        self.app
            .world()
            .resource::<Env>()
            .orbit()
            .map(|e| e.reference.clone())
    }

    /// Loads, validates and builds a scene file (`overrides`: `--set`-style `path=value`).
    pub fn from_file(path: impl AsRef<Path>, overrides: &[String]) -> Result<Self, SceneError> {
        let loaded = crate::scene::load_scene_file(path.as_ref(), overrides)?;
        Self::new(&loaded)
    }

    /// Advances the simulation by `duration_s` of simulated time (rounded to whole steps).
    pub fn run_for(&mut self, duration_s: f64) {
        let n = self.steps_for(duration_s);
        self.step(n);
    }

    /// A guarantee's running status by name (held, worst margin and when, first violation).
    pub fn guarantee(&self, name: &str) -> Option<&crate::guarantee::GuaranteeStatus> {
        self.guarantees().status.iter().find(|s| s.name == name)
    }

    /// The docking mechanism's state (`FREE`, …, `LATCHED`), if the scene has one.
    pub fn docking_state(&self) -> Option<&'static str> {
        self.app
            .world()
            .get_resource::<super::docking::Docking>()
            .map(|d| d.state.name())
    }

    /// Commands the docking mechanism to release (acted on at the next step: RELEASED and the
    /// separation springs if latched, else a `docking_release_ignored` event). `false` when the
    /// scene has no docking mechanism.
    pub fn release_docking(&mut self, source: &str) -> bool {
        match self
            .app
            .world_mut()
            .get_resource_mut::<super::docking::DockingCommands>()
        {
            Some(mut c) => {
                c.release.push(source.to_string());
                true
            }
            None => false,
        }
    }

    /// The smallest clearance so far between parts that are not both docking parts, over every
    /// body pair, m (0 when they touched).
    pub fn min_clearance_non_docking_m(&self) -> f64 {
        self.monitor()
            .min_clearance_per_pair
            .iter()
            .copied()
            .fold(f64::INFINITY, f64::min)
    }

    /// The current value of a `trajectory.csv` diagnostics column (a controller's, a
    /// mechanism's or a navigation filter's, e.g. `nav.chaser.sigma_x_m`), None if there is no
    /// such column.
    pub fn diagnostic(&self, name: &str) -> Option<f64> {
        let d = self.app.world().resource::<super::output::Diagnostics>();
        d.names.iter().position(|n| n == name).map(|i| d.values[i])
    }

    /// The controller host: every controller's slot (law, held command, sensor, actuator) and
    /// the scenario's disturbances.
    pub fn controllers(&self) -> &super::controllers::ControllerHost {
        self.app
            .world()
            .resource::<super::controllers::ControllerHost>()
    }

    /// The `k`-th controller (0-based, installation order) whose law is a `T`, e.g.
    /// `sim.law::<rpod::control::guo2016::Guo2016Instance>(0)`.
    pub fn law<T: 'static>(&self, k: usize) -> Option<&T> {
        self.controllers().law::<T>(k)
    }

    /// Hosts one more controller (a user's law, a Python callable) on the built simulation.
    /// Call it before [`Simulation::record_to`] (the header names its columns). Returns the
    /// slot's index.
    pub fn add_controller(
        &mut self,
        slot: crate::control::registry::Slot,
    ) -> Result<usize, String> {
        if self.app.world().resource::<Recorder>().files.is_some() {
            return Err("controllers must be added before recording starts".into());
        }
        super::controllers::host_slot(self.app.world_mut(), slot)
    }

    /// Adds a guarantee (a user's Rust guarantee, a Python callable) to the built simulation,
    /// judged like a scene's: its margin is sampled now (t = 0) and then every step, on the
    /// whole interval when it gives a rate bound, at the samples only otherwise. Call it before
    /// the first step and before [`Simulation::record_to`] (the header names its column).
    /// Returns its index in [`Simulation::guarantees`].
    pub fn add_guarantee(
        &mut self,
        g: Box<dyn crate::guarantee::Guarantee>,
    ) -> Result<usize, String> {
        if self.app.world().resource::<Recorder>().files.is_some() || self.steps() > 0 {
            return Err(
                "guarantees must be added before the first step and before recording starts".into(),
            );
        }
        self.guarantees().admissible(g.as_ref())?;
        let w = self.app.world_mut();
        let n = w.resource::<Roster>().names.len();
        // The pairs it reads are tracked from now on (and measured again at t = 0).
        if let crate::guarantee::Reads::Pairs(l) = g.reads() {
            let mut np = w.resource_mut::<super::NamedPairs>();
            let before = np.0.len();
            for (a, b) in l {
                if a >= n || b >= n || a == b {
                    return Err(format!(
                        "guarantee `{}` reads the pair ({a}, {b}), not two different bodies of the {n}",
                        g.name()
                    ));
                }
                np.0.push((a.min(b), a.max(b)));
            }
            np.0.sort_unstable();
            np.0.dedup();
            if np.0.len() != before {
                use bevy::ecs::system::RunSystemOnce;
                w.run_system_once(super::monitor::distances)
                    .map_err(|e| e.to_string())?;
            }
        }
        let t = w.resource::<Clock>().t_s();
        let m = {
            let mon = w.resource::<MonitorState>();
            let jets = super::jets_view(w.get_resource::<super::controllers::ControllerHost>());
            let view = crate::guarantee::MonitorView {
                t_s: t,
                bodies: &mon.bodies,
                pairs: &mon.pairs,
                reference: w.resource::<Env>().orbit().map(|o| {
                    let (p, v) = o.reference.state();
                    crate::guarantee::ReferenceView {
                        pos_eci_m: p,
                        vel_eci_m_s: v,
                    }
                }),
                jets: &jets,
            };
            g.margin_bracket(&view)
        };
        let mut gs = w.resource_mut::<Guarantees>();
        let k = gs.list.len();
        gs.last
            .resize(k, crate::geometry::bounds::Bracket::exact(f64::INFINITY));
        gs.register(g);
        gs.status[k].update(t, m.value);
        gs.last.push(m);
        Ok(k)
    }

    /// Adds a disturbance (forces and torques on any body, added in the Actuate stage after the
    /// controllers' commands, e.g. forces applied from Python). It writes no columns, so it may
    /// be added at any time; it acts from the next step.
    pub fn add_disturbance(&mut self, d: Box<dyn crate::control::registry::Disturbance>) {
        let world = self.app.world_mut();
        world
            .resource_mut::<super::controllers::ControllerHost>()
            .disturbances
            .push(d);
        // It fails only while the schedule runs, and a `&mut Simulation` is not stepping.
        let _ = super::controllers::schedule_host_systems(world);
    }

    /// The monitor's results.
    pub fn monitor(&self) -> &MonitorState {
        self.app.world().resource::<MonitorState>()
    }

    /// Contacts so far.
    pub fn contacts(&self) -> &ContactState {
        self.app.world().resource::<ContactState>()
    }

    /// Guarantees and their status.
    pub fn guarantees(&self) -> &Guarantees {
        self.app.world().resource::<Guarantees>()
    }

    /// Every event raised so far (written or not).
    pub fn events(&self) -> Vec<super::Event> {
        let w = self.app.world();
        let mut v = w.resource::<Recorder>().history.clone();
        v.extend(w.resource::<EventLog>().pending.iter().cloned());
        v
    }

    /// The run summary (the content of `summary.json`).
    pub fn summary(&self) -> serde_json::Value {
        let mut v = self.with_meshes(self.summary_core());
        if let (Some(p), Some(o)) = (
            self.app
                .world()
                .get_resource::<super::plume::PlumeLoadState>(),
            v.as_object_mut(),
        ) {
            o.insert("plume_loads".into(), p.summary());
        }
        // Only a multi-rate run says how it stepped: a fixed-step summary stays as it was.
        if let (Some(m), Some(o)) = (
            self.app
                .world()
                .get_resource::<super::multirate::MultiRate>(),
            v.as_object_mut(),
        ) {
            o.insert("stepping".into(), m.summary(self.scene.dt_s));
        }
        v
    }

    fn summary_core(&self) -> serde_json::Value {
        let w = self.app.world();
        let mon = w.resource::<MonitorState>();
        let cs = w.resource::<ContactState>();
        let g = w.resource::<Guarantees>();
        let roster = w.resource::<Roster>();
        let rec = w.resource::<Recorder>();
        let bp = w.resource::<super::broadphase::BroadPhase>();
        let sync = w.resource::<super::RapierSync>();
        let motion = w.resource::<super::motion::StepMotion>();
        let steps = self.steps();
        let overall = mon.overall.as_ref().map(|m| {
            let (a, b) = mon.overall_pair;
            serde_json::json!({"value_m": m.distance_m,
                "parts": [mon.part_name(a, m.part_a), mon.part_name(b, m.part_b)],
                "t_s": m.t_s, "found": if m.inside { "interval" } else { "sample" },
                "tolerance_m": m.tolerance_m})
        });
        let pairs: Vec<_> = mon
            .min_per_pair
            .iter()
            .zip(&mon.pairs)
            .map(|(m, p)| {
                serde_json::json!({"a": roster.names[p.a], "b": roster.names[p.b],
                    "min_distance_m": m.distance_m,
                    "parts": [mon.part_name(p.a, m.part_a), mon.part_name(p.b, m.part_b)],
                    "t_s": m.t_s, "found": if m.inside { "interval" } else { "sample" }})
            })
            .collect();
        let finals: serde_json::Map<String, serde_json::Value> = roster
            .bodies
            .iter()
            .zip(&roster.names)
            .map(|(e, n)| {
                let s = w.get::<BodyState>(*e).expect("state");
                let q = s.att.quaternion();
                (
                    n.clone(),
                    serde_json::json!({
                        "pos_m": [s.pos_m.x, s.pos_m.y, s.pos_m.z],
                        "vel_m_s": [s.vel_m_s.x, s.vel_m_s.y, s.vel_m_s.z],
                        "att_wxyz": [q.w, q.i, q.j, q.k],
                        "omega_rad_s": [s.omega_rad_s.x, s.omega_rad_s.y, s.omega_rad_s.z],
                    }),
                )
            })
            .collect();
        let collisions: Vec<_> = cs
            .collisions
            .iter()
            .map(|(t, a, b)| serde_json::json!({"t_s": t, "a": a, "b": b}))
            .collect();
        serde_json::json!({
            "scene": self.scene.name,
            "scene_file": self.scene_file,
            "provenance": self.provenance,
            "frame": match self.scene.environment {
                Environment::Orbit { .. } => "world: Earth-inertial axes, origin on the reference orbit (the target's unforced orbit); positions are centres of mass",
                Environment::FreeSpace => "world: inertial, no gravity; positions are centres of mass",
                Environment::AirBearing(_) => "world: the lab frame of the air-bearing table (x, y in the table top, z up, top at z = 0); positions are centres of mass",
                _ => "world: non-rotating, origin on the environment's reference trajectory (see the scene's environment); positions are centres of mass",
            },
            "dt_s": self.scene.dt_s,
            "steps": steps,
            "simulated_s": self.t_s(),
            "wall_s": self.wall_s,
            "steps_per_s": if self.wall_s > 0.0 { steps as f64 / self.wall_s } else { 0.0 },
            "rows": rec.rows,
            "events": rec.history.len(),
            "min_distance": overall,
            "pairs": pairs,
            "min_clearance_non_docking_m": mon.min_clearance_per_pair.iter().copied().fold(f64::INFINITY, f64::min),
            "first_contact_s": cs.first_contact_s,
            "first_touch_s": cs.first_touch_s,
            "first_collision_s": cs.first_collision_s,
            "collisions": collisions,
            "contact_per_part": cs.per_part,
            "guarantees": g.status,
            "final_states": finals,
            "monitor": {
                "exact_queries": mon.exact_queries,
                "pruned_pairs": mon.pruned_pairs,
                "interval_evaluations": mon.interval_evals,
                "guarantee_interval_queries": g.interval_queries,
                "horizon_m": if bp.all_pairs { None } else { Some(bp.horizon_m) },
                "tracked_pairs": mon.pairs.len(),
                "broad_phase_refreshes": bp.refreshes,
                "rapier_steps": sync.rapier_steps,
                "rapier_skipped_steps": sync.skipped_steps,
                "split_steps": sync.split_steps,
                "swept_test_queries": sync.swept_queries,
                "rotation_under_resolved_steps": motion.under_resolved_steps,
                "min_distance_tolerance": "max(1e-6 m, 0.1 % of the distance), or the closest pair's own bracket width where wider (twice it between samples): min_distance.tolerance_m",
                "event_time_tolerance_s": self.scene.dt_s * super::EVENT_TIME_TOL,
            },
            "docking": w.get_resource::<super::docking::Docking>().map(super::docking::summary),
            "controllers": w.resource::<super::controllers::ControllerHost>().summary(),
        })
    }

    /// The run summary with the mesh parts (`meshes`), when the scene has any.
    fn with_meshes(&self, mut v: serde_json::Value) -> serde_json::Value {
        if !self.meshes.is_empty()
            && let Some(o) = v.as_object_mut()
        {
            o.insert(
                "meshes".into(),
                serde_json::to_value(&self.meshes).unwrap_or_default(),
            );
        }
        v
    }

    /// Writes the last row, the summary, and renames the files into place.
    pub fn finish(mut self) -> std::io::Result<serde_json::Value> {
        if let Some(trip) = self.guard_trip().cloned() {
            // Nothing of the bad step is recorded; the rows so far stay as `.partial` files.
            if let Some(files) = self.app.world_mut().resource_mut::<Recorder>().files.take() {
                files.keep_partial()?;
            }
            return Err(std::io::Error::other(trip.to_string()));
        }
        super::output::record_now(self.app.world_mut());
        let summary = self.summary();
        let mut rec = self.app.world_mut().resource_mut::<Recorder>();
        let err = rec.error.take();
        if let Some(files) = rec.files.take() {
            if let Some(e) = err {
                files.abandon();
                return Err(std::io::Error::other(e));
            }
            files.finish(&summary)?;
        }
        Ok(summary)
    }
}

#[cfg(test)]
mod tests {
    //! [`ccd_has_targets`] against rapier itself: a thin plate (1 cm) flying at 200 m/s (2 m
    //! per 10 ms step: a tunnelling speed, so it is CCD-active) through another plate 1.2 m
    //! ahead, stepped with the continuous pass on (`max_ccd_substeps` 1) and off (0).
    //! Reference: where `ccd_has_targets` says no sweep has a target (both plates bullets, or
    //! neither), the two runs' poses are bit-identical; with the second plate fixed (a target
    //! of every fast body) the pass clamps the motion and the poses differ, so the comparison
    //! can see a difference.
    use super::*;

    /// The plates' x positions (f32 bits) after each of `steps` rapier steps; `bullet` per
    /// plate, the second one `fixed` or dynamic.
    fn run(
        bullet: [bool; 2],
        fixed: bool,
        ccd: bool,
        steps: usize,
    ) -> (rp::PhysicsWorld, Vec<[u32; 2]>) {
        let mut w = rp::PhysicsWorld::new();
        w.gravity = rp::Vector::ZERO;
        w.integration_parameters.normalized_max_linear_velocity = f32::MAX;
        w.integration_parameters.dt = 0.01;
        w.integration_parameters.max_ccd_substeps = usize::from(ccd);
        let mut hs = Vec::new();
        for (k, b) in bullet.iter().enumerate() {
            let rb = if k == 0 {
                rp::RigidBodyBuilder::dynamic()
                    .translation(rp::Vector::new(-0.6, 0.0, 0.0))
                    .linvel(rp::Vector::new(200.0, 0.0, 0.0))
            } else if fixed {
                rp::RigidBodyBuilder::fixed().translation(rp::Vector::new(0.6, 0.0, 0.0))
            } else {
                rp::RigidBodyBuilder::dynamic().translation(rp::Vector::new(0.6, 0.0, 0.0))
            };
            let h = w.insert_body(rb.ccd_enabled(*b).build());
            w.insert_collider(
                rp::ColliderBuilder::cuboid(0.005, 1.0, 1.0).build(),
                Some(h),
            );
            hs.push(h);
        }
        let mut out = Vec::new();
        for _ in 0..steps {
            w.step();
            out.push([
                w.bodies[hs[0]].translation().x.to_bits(),
                w.bodies[hs[1]].translation().x.to_bits(),
            ]);
        }
        (w, out)
    }

    #[test]
    fn invariant_ccd_off_changes_nothing_where_no_sweep_has_a_target() {
        for bullet in [[true, true], [false, false]] {
            let (w, on) = run(bullet, false, true, 4);
            assert!(!ccd_has_targets(&w), "{bullet:?}");
            let (_, off) = run(bullet, false, false, 4);
            assert_eq!(on, off, "{bullet:?}");
        }
        let (w, on) = run([false, false], true, true, 4);
        assert!(ccd_has_targets(&w));
        let (_, off) = run([false, false], true, false, 4);
        assert_ne!(on, off, "a fast body is swept against a fixed one");
    }
}
