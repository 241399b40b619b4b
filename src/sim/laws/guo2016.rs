//! Simulation wiring of [`crate::control::guo2016`] (Guo, Song, Li 2016).
//!
//! Per step, for every `Guo2016` controller of the scene:
//! - **Control** ([`guo2016_control`]): the observation is built from the f64 [`BodyState`] of
//!   the chaser and the target (relative position and velocity in the world frame, both
//!   attitudes, body rates converted to body axes) and the differential gravity
//!   `g(r_c) − g(r_t)` from the scene's [`Gravity`] field (with J2 when the scene enables it, so
//!   the law compensates the differential J2 instead of treating it as a disturbance; at 40 m
//!   it is ~1e-8 m/s²). The law returns force and torque in chaser body axes; the command,
//!   the diagnostics and the corridor distance are kept in [`Guo2016Controllers`] and written to
//!   the `guo2016.*` diagnostics columns (see [`COLUMNS`]).
//! - **Actuate** ([`guo2016_actuate`]): the command is turned into the world frame with the
//!   chaser attitude and added to the chaser's [`Wrench`] (held over the step).
//! - **Environment** ([`guo2016_disturbance`]): the paper's disturbance torque
//!   `d_τ = A cos(n t)` (chaser body axes) is added to the chaser's torque.
//!
//! The corridor guarantee ([`CorridorGuarantee`]) is registered with the monitor: its margin is
//! the signed distance (m) of the chaser centre of mass to the cissoid wall, in the target body
//! frame — positive inside. It concerns the centre-of-mass point only; the monitor's
//! full-geometry distances say what the parts did.

use crate::control::guo2016::{
    Guo2016, Guo2016Command, Guo2016Diagnostics, Guo2016Observation, SceneSpec,
};
use crate::geometry::cissoid::Cissoid;
use crate::guarantee::{Guarantee, MonitorView};
use crate::orbit::constants::MU_EARTH_M3_S2;
use crate::scene::{LoadedScene, SceneError};
use crate::sim::output::Diagnostics;
use crate::sim::{BodyState, Clock, Gravity, Guarantees, OrbitEnv, Roster, SimStep, Stage, Wrench};
use bevy::prelude::*;
use nalgebra::Vector3;

/// Diagnostics columns written per controller (prefix `guo2016.`, or `guo2016_<i>.` for the
/// i-th controller after the first): corridor function `h_m2` and `h_dot_m2_s`, `inside`
/// (1/0), `beta`, `s_norm` (|S|, mixed units as in eq 32), `r_e_m` (|r_e|), `sigma_e` (|σ_e|),
/// `omega_e_rad_s` (|ω_e|), `corridor_margin_m` (signed distance to the wall), the command in
/// chaser body axes, and the disturbance torque applied.
pub const COLUMNS: [&str; 15] = [
    "h_m2",
    "h_dot_m2_s",
    "inside",
    "beta",
    "s_norm",
    "r_e_m",
    "sigma_e",
    "omega_e_rad_s",
    "corridor_margin_m",
    "force_body_x_n",
    "force_body_y_n",
    "force_body_z_n",
    "torque_body_x_nm",
    "torque_body_y_nm",
    "torque_body_z_nm",
];

/// One installed controller.
#[derive(Debug, Clone)]
pub struct Guo2016Instance {
    /// The law (parameters from the scene, mass and inertia from the chaser body).
    pub law: Guo2016,
    /// Chaser body index (scene order).
    pub chaser: usize,
    /// Target body index.
    pub target: usize,
    /// Disturbance torque amplitudes, chaser body axes, N·m.
    pub disturbance_amplitude_nm: Vector3<f64>,
    /// Disturbance angular frequency, rad/s.
    pub disturbance_rate_rad_s: f64,
    /// Last observation handed to the law.
    pub observation: Option<Guo2016Observation>,
    /// Last command (chaser body axes).
    pub command: Guo2016Command,
    /// Last diagnostics.
    pub diagnostics: Option<Guo2016Diagnostics>,
    /// Disturbance torque applied at the last step, chaser body axes, N·m.
    pub disturbance_body_nm: Vector3<f64>,
    /// Signed distance of the chaser centre of mass to the corridor wall at the last control
    /// step, m (positive inside).
    pub corridor_margin_m: f64,
    /// Index of the first diagnostics column (the others follow in [`COLUMNS`] order).
    pub first_column: usize,
}

/// Every `Guo2016` controller of the scene, in scene order.
#[derive(Resource, Debug, Clone, Default)]
pub struct Guo2016Controllers {
    /// The controllers.
    pub list: Vec<Guo2016Instance>,
}

/// "The chaser's centre of mass stays inside the corridor": margin = signed distance of the
/// chaser centre of mass to the cissoid wall (target body frame), m.
#[derive(Debug, Clone)]
pub struct CorridorGuarantee {
    /// Name.
    pub name: String,
    /// Chaser body index.
    pub chaser: usize,
    /// Target body index.
    pub target: usize,
    /// The corridor.
    pub corridor: Cissoid,
}

impl CorridorGuarantee {
    /// Chaser centre of mass in target body axes, m.
    pub fn r1_target_m(&self, view: &MonitorView) -> Vector3<f64> {
        let c = &view.bodies[self.chaser];
        let t = &view.bodies[self.target];
        t.att.inverse() * (c.pos_m - t.pos_m)
    }
}

impl Guarantee for CorridorGuarantee {
    fn name(&self) -> &str {
        &self.name
    }
    fn margin(&self, view: &MonitorView) -> f64 {
        self.corridor.signed_distance_m(&self.r1_target_m(view))
    }
}

/// Mean motion of the osculating two-body orbit through `(r, v)`, rad/s (0 if not bound).
fn mean_motion_rad_s(r: &Vector3<f64>, v: &Vector3<f64>) -> f64 {
    let inv_a = 2.0 / r.norm() - v.norm_squared() / MU_EARTH_M3_S2;
    if inv_a > 0.0 {
        (MU_EARTH_M3_S2 * inv_a * inv_a * inv_a).sqrt()
    } else {
        0.0
    }
}

/// Adds this law's resources and systems for one controller of the scene.
pub fn install(
    app: &mut App,
    loaded: &LoadedScene,
    path: &str,
    spec: &SceneSpec,
) -> Result<(), SceneError> {
    let chaser = super::body_index(loaded, path, "chaser", &spec.chaser)?;
    let target = super::body_index(loaded, path, "target", &spec.target)?;
    if chaser == target {
        return Err(loaded.error_at(
            &format!("{path}.target"),
            "the target must be another body than the chaser",
        ));
    }
    spec.validate()
        .map_err(|(field, msg)| loaded.error_at(&format!("{path}.{field}"), msg))?;
    let body = &loaded.scene.bodies[chaser];
    let params = spec.params(body.mass_kg, body.inertia_kg_m2.matrix());
    let corridor = params.corridor();
    let n = match spec.disturbance_rate_rad_s {
        Some(n) => n,
        None => app
            .world()
            .get_resource::<OrbitEnv>()
            .map(|e| {
                let (r, v) = e.reference.state();
                mean_motion_rad_s(&r, &v)
            })
            .unwrap_or(0.0),
    };

    let world = app.world_mut();
    let first_install = !world.contains_resource::<Guo2016Controllers>();
    if first_install {
        world.insert_resource(Guo2016Controllers::default());
    }
    let k = world.resource::<Guo2016Controllers>().list.len();
    let prefix = if k == 0 {
        "guo2016".to_string()
    } else {
        format!("guo2016_{k}")
    };
    let first_column = {
        let mut diag = world.resource_mut::<Diagnostics>();
        let cols: Vec<usize> = COLUMNS
            .iter()
            .map(|c| diag.column(&format!("{prefix}.{c}")))
            .collect();
        cols[0]
    };
    world
        .resource_mut::<Guarantees>()
        .register(Box::new(CorridorGuarantee {
            name: spec.corridor_guarantee.clone(),
            chaser,
            target,
            corridor,
        }));
    world
        .resource_mut::<Guo2016Controllers>()
        .list
        .push(Guo2016Instance {
            law: Guo2016::new(params),
            chaser,
            target,
            disturbance_amplitude_nm: Vector3::from(*spec.disturbance_torque_amplitude_nm),
            disturbance_rate_rad_s: n,
            observation: None,
            command: Guo2016Command {
                force_body_n: Vector3::zeros(),
                torque_body_nm: Vector3::zeros(),
            },
            diagnostics: None,
            disturbance_body_nm: Vector3::zeros(),
            corridor_margin_m: f64::NAN,
            first_column,
        });
    if first_install {
        app.add_systems(
            SimStep,
            (
                guo2016_control.in_set(Stage::Control),
                guo2016_actuate.in_set(Stage::Actuate),
                guo2016_disturbance.in_set(Stage::Environment),
            ),
        );
    }
    Ok(())
}

/// Control stage: observation → law → stored command and diagnostics columns.
pub fn guo2016_control(
    clock: Res<Clock>,
    roster: Res<Roster>,
    gravity: Option<Res<Gravity>>,
    bodies: Query<&BodyState>,
    mut ctrls: ResMut<Guo2016Controllers>,
    mut diag: ResMut<Diagnostics>,
) {
    let t = clock.t_s();
    for c in ctrls.list.iter_mut() {
        let (Ok(sc), Ok(st)) = (
            bodies.get(roster.bodies[c.chaser]),
            bodies.get(roster.bodies[c.target]),
        ) else {
            continue;
        };
        let grav = gravity.as_ref().map_or_else(Vector3::zeros, |g| {
            g.0.accel_m_s2(&sc.pos_m) - g.0.accel_m_s2(&st.pos_m)
        });
        let obs = Guo2016Observation {
            t_s: t,
            q_chaser_body_to_world: sc.att,
            q_target_body_to_world: st.att,
            rate_chaser_body_rad_s: sc.att.inverse() * sc.omega_rad_s,
            rate_target_body_rad_s: st.att.inverse() * st.omega_rad_s,
            pos_rel_world_m: sc.pos_m - st.pos_m,
            vel_rel_world_m_s: sc.vel_m_s - st.vel_m_s,
            grav_diff_world_m_s2: grav,
        };
        let (cmd, d) = c.law.control(&obs);
        let margin = c.law.params.corridor().signed_distance_m(&d.r1_target_m);
        let r_e = Vector3::new(d.x[3], d.x[4], d.x[5]).norm();
        let sigma_e = Vector3::new(d.x[0], d.x[1], d.x[2]).norm();
        let values = [
            d.h_m2,
            d.h_dot_m2_s,
            if d.inside { 1.0 } else { 0.0 },
            d.beta,
            d.s.norm(),
            r_e,
            sigma_e,
            d.omega_e_body_rad_s.norm(),
            margin,
            cmd.force_body_n.x,
            cmd.force_body_n.y,
            cmd.force_body_n.z,
            cmd.torque_body_nm.x,
            cmd.torque_body_nm.y,
            cmd.torque_body_nm.z,
        ];
        for (k, v) in values.iter().enumerate() {
            diag.values[c.first_column + k] = *v;
        }
        c.observation = Some(obs);
        c.command = cmd;
        c.diagnostics = Some(d);
        c.corridor_margin_m = margin;
    }
}

/// Actuate stage: the command (chaser body axes) into the chaser's world-frame wrench.
pub fn guo2016_actuate(
    roster: Res<Roster>,
    ctrls: Res<Guo2016Controllers>,
    mut q: Query<(&BodyState, &mut Wrench)>,
) {
    for c in &ctrls.list {
        if let Ok((s, mut w)) = q.get_mut(roster.bodies[c.chaser]) {
            w.force_n += s.att * c.command.force_body_n;
            w.torque_nm += s.att * c.command.torque_body_nm;
        }
    }
}

/// Environment stage: the paper's disturbance torque `A cos(n t)` (chaser body axes).
pub fn guo2016_disturbance(
    clock: Res<Clock>,
    roster: Res<Roster>,
    mut ctrls: ResMut<Guo2016Controllers>,
    mut q: Query<(&BodyState, &mut Wrench)>,
) {
    let t = clock.t_s();
    for c in ctrls.list.iter_mut() {
        let d = c.disturbance_amplitude_nm * (c.disturbance_rate_rad_s * t).cos();
        c.disturbance_body_nm = d;
        if let Ok((s, mut w)) = q.get_mut(roster.bodies[c.chaser]) {
            w.torque_nm += s.att * d;
        }
    }
}
