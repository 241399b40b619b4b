//! Simulation wiring of [`crate::control::geng2015`] (Geng, Chen, Liang 2015: twisting and
//! modified twisting on the coupled docking-port dynamics).
//!
//! Per controller of the scene, one [`Geng2015Loop`] in the [`Geng2015Runtime`] resource:
//! - **Control** (`Stage::Control`): every `period_s` (a whole number of steps, the first call at
//!   t = 0) the law is handed the Earth-centred f64 states of chaser and target (world state plus
//!   the reference orbit's ECI state from [`OrbitEnv`]; world axes are ECI axes) and returns
//!   force and torque in chaser body axes, saturated per axis; the command is held until the
//!   next call.
//! - **Actuate** (`Stage::Actuate`): the held body-frame command is turned into the world frame
//!   with the chaser's attitude at the start of each step (body-fixed thrusters) and added to
//!   its [`Wrench`]; the paper's disturbances are added to both bodies: force m·R·a_d(t)
//!   (a_d in the body's own axes) and torque R·T_d(t). The gravity-gradient torque T_g of the
//!   paper is the environment's (scene `gravity_gradient: true`) and is not added again.
//! - Diagnostics columns `geng2015.<body>.*` (`Stage::Monitor`, from the states after the step,
//!   i.e. at the time of the trajectory row): ρ and ρ̇ (ρ frame), q_rv, ω_r (chaser axes), the
//!   port distance |ρ|; and from the last controller call the sliding variables s1..s6 and the
//!   applied command u (chaser body axes, N, N·m).
//!
//! Scene errors (missing bodies or ports, no orbit, a period that is not a whole number of
//! steps, bad limits) point at the controller's fields.

use crate::control::geng2015::{
    Geng2015Controller, Geng2015Disturbances, Geng2015Gains, Geng2015Obs, Geng2015Params,
    SceneSpec, relative_state,
};
use crate::orbit::constants::MU_EARTH_M3_S2;
use crate::scene::{Environment, LoadedScene, SceneError};
use crate::sim::output::Diagnostics;
use crate::sim::{BodyState, Clock, OrbitEnv, Roster, SimBody, SimStep, Stage, Wrench};
use bevy::prelude::*;
use nalgebra::{Matrix3, Vector3};

/// Column names published per loop, after the `geng2015.<body>.` prefix.
pub const COLUMNS: [&str; 25] = [
    "rho_x_m",
    "rho_y_m",
    "rho_z_m",
    "rho_dot_x_m_s",
    "rho_dot_y_m_s",
    "rho_dot_z_m_s",
    "qrv1",
    "qrv2",
    "qrv3",
    "omega_r_x_rad_s",
    "omega_r_y_rad_s",
    "omega_r_z_rad_s",
    "port_distance_m",
    "s1",
    "s2",
    "s3",
    "s4",
    "s5",
    "s6",
    "force_x_body_n",
    "force_y_body_n",
    "force_z_body_n",
    "torque_x_body_nm",
    "torque_y_body_nm",
    "torque_z_body_nm",
];

/// One controller of the scene and its held command.
pub struct Geng2015Loop {
    /// The law with its integral state (its `diagnostics()` hold the last call's e, s, u).
    pub controller: Geng2015Controller,
    /// Chaser body index (scene order).
    pub chaser: usize,
    /// Target body index.
    pub target: usize,
    /// Controller period in steps.
    pub period_steps: u64,
    /// Held force, chaser body axes, N.
    pub force_body_n: Vector3<f64>,
    /// Held torque, chaser body axes, N·m.
    pub torque_body_nm: Vector3<f64>,
    /// The paper's disturbances, if the scene asks for them.
    pub disturbances: Option<Geng2015Disturbances>,
    /// Number of controller calls so far.
    pub calls: u64,
    /// Time of the last call, s.
    pub last_call_s: f64,
    cols: [usize; 25],
}

/// Every Geng 2015 loop of the scene.
#[derive(Resource, Default)]
pub struct Geng2015Runtime {
    /// Loops in scene order.
    pub loops: Vec<Geng2015Loop>,
}

fn diag3(d: [f64; 3]) -> Matrix3<f64> {
    Matrix3::from_diagonal(&Vector3::from(d))
}

fn positive(x: f64) -> bool {
    x.is_finite() && x > 0.0
}

/// Adds this law's resources and systems for one controller of the scene.
pub fn install(
    app: &mut App,
    loaded: &LoadedScene,
    path: &str,
    spec: &SceneSpec,
) -> Result<(), SceneError> {
    let scene = &loaded.scene;
    let chaser = super::body_index(loaded, path, "body", &spec.body)?;
    let target = super::body_index(loaded, path, "target", &spec.target)?;
    let err = |field: &str, msg: String| loaded.error_at(&format!("{path}.{field}"), msg);
    if chaser == target {
        return Err(err(
            "target",
            format!("the target must differ from the chaser `{}`", spec.body),
        ));
    }
    let Environment::Orbit { .. } = scene.environment else {
        return Err(err(
            "body",
            "the geng2015 law needs an Orbit environment (it works on Earth-centred states)".into(),
        ));
    };
    let (bs, bt) = (&scene.bodies[chaser], &scene.bodies[target]);
    let port = |b: &crate::scene::BodySpec, field: &str, name: &str| {
        b.ports
            .iter()
            .find(|p| p.name == name)
            .map(|p| Vector3::from(p.pos_m) - Vector3::from(b.com_m))
            .ok_or_else(|| err(field, format!("body `{}` has no port `{name}`", b.name)))
    };
    let ps = port(bs, "chaser_port", &spec.chaser_port)?;
    let pt = port(bt, "target_port", &spec.target_port)?;
    let dt = scene.dt_s;
    let ratio = spec.period_s / dt;
    let period_steps = ratio.round();
    if !spec.period_s.is_finite() || period_steps < 1.0 || (ratio - period_steps).abs() > 1e-6 {
        return Err(err(
            "period_s",
            format!(
                "must be a whole number of steps (dt_s = {dt} s) and at least one, got {} s",
                spec.period_s
            ),
        ));
    }
    if !positive(spec.accel_max_m_s2) {
        return Err(err(
            "accel_max_m_s2",
            format!(
                "must be a positive acceleration, got {}",
                spec.accel_max_m_s2
            ),
        ));
    }
    if !positive(spec.torque_max_nm) {
        return Err(err(
            "torque_max_nm",
            format!("must be a positive torque, got {}", spec.torque_max_nm),
        ));
    }
    for (field, v) in [
        (
            "model_chaser_inertia_diag_kg_m2",
            spec.model_chaser_inertia_diag_kg_m2.clone(),
        ),
        (
            "model_target_inertia_diag_kg_m2",
            spec.model_target_inertia_diag_kg_m2.clone(),
        ),
    ] {
        if let Some(d) = v.as_deref()
            && !d.iter().all(|x| positive(*x))
        {
            return Err(err(
                field,
                format!("moments must be positive kg·m², got {d:?}"),
            ));
        }
    }
    if !spec.rho_des_m.iter().all(|x| x.is_finite()) {
        return Err(err("rho_des_m", "must be finite metres".into()));
    }
    if let Some(g) = &spec.gains {
        let all = [
            &g.t1_alpha,
            &g.t1_beta,
            &g.t2_lambda,
            &g.t2_alpha,
            &g.t2_beta,
            &g.m1_m1,
            &g.m1_m2,
            &g.m1_m3,
            &g.m1_m4,
            &g.m2_lambda,
            &g.m2_k1,
            &g.m2_k2,
            &g.m2_k3,
            &g.m2_k4,
        ];
        if !all
            .iter()
            .all(|v| v.iter().all(|x| x.is_finite() && *x >= 0.0))
        {
            return Err(err("gains", "gains must be finite and non-negative".into()));
        }
    }
    if let Some(d) = &spec.disturbance {
        let ok = d.k_d_per_s.is_finite()
            && d.torque_scale_nm.is_finite()
            && d.chaser_accel0_m_s2
                .iter()
                .chain(&d.target_accel0_m_s2)
                .all(|x| x.is_finite());
        if !ok {
            return Err(err("disturbance", "values must be finite".into()));
        }
    }
    let params = Geng2015Params {
        chaser_mass_kg: bs.mass_kg,
        chaser_inertia_kg_m2: spec
            .model_chaser_inertia_diag_kg_m2
            .as_deref()
            .copied()
            .map(diag3)
            .unwrap_or_else(|| bs.inertia_kg_m2.matrix()),
        target_inertia_kg_m2: spec
            .model_target_inertia_diag_kg_m2
            .as_deref()
            .copied()
            .map(diag3)
            .unwrap_or_else(|| bt.inertia_kg_m2.matrix()),
        chaser_port_body_m: ps,
        target_port_body_m: pt,
        mu_m3_s2: MU_EARTH_M3_S2,
        accel_max_m_s2: spec.accel_max_m_s2,
        torque_max_nm: spec.torque_max_nm,
        rho_frame: spec.rho_frame,
        rho_des_m: Vector3::from(spec.rho_des_m),
        sdot_estimate: spec.sdot_estimate,
        gains: spec
            .gains
            .as_deref()
            .cloned()
            .unwrap_or_else(Geng2015Gains::paper),
    };
    // ω° of T_d: the reference orbit's mean motion.
    let omega_orbit = app
        .world()
        .get_resource::<OrbitEnv>()
        .map(|e| {
            let (r, v) = e.reference.state();
            let a = 1.0 / (2.0 / r.norm() - v.norm_squared() / MU_EARTH_M3_S2);
            (MU_EARTH_M3_S2 / a.powi(3)).sqrt()
        })
        .unwrap_or(0.0);
    let prefix = format!("geng2015.{}", spec.body);
    let cols = {
        let mut d = app.world_mut().resource_mut::<Diagnostics>();
        COLUMNS.map(|c| d.column(&format!("{prefix}.{c}")))
    };
    let lp = Geng2015Loop {
        controller: Geng2015Controller::new(spec.law, params),
        chaser,
        target,
        period_steps: period_steps as u64,
        force_body_n: Vector3::zeros(),
        torque_body_nm: Vector3::zeros(),
        disturbances: spec
            .disturbance
            .as_ref()
            .map(|d| d.to_disturbances(omega_orbit)),
        calls: 0,
        last_call_s: 0.0,
        cols,
    };
    if app.world().get_resource::<Geng2015Runtime>().is_none() {
        app.insert_resource(Geng2015Runtime::default());
        app.add_systems(SimStep, control.in_set(Stage::Control));
        app.add_systems(SimStep, actuate.in_set(Stage::Actuate));
        app.add_systems(SimStep, publish.in_set(Stage::Monitor));
    }
    app.world_mut()
        .resource_mut::<Geng2015Runtime>()
        .loops
        .push(lp);
    Ok(())
}

/// The observation of a loop: Earth-centred states of chaser and target at time `t_s`.
pub fn observation(
    t_s: f64,
    reference: (Vector3<f64>, Vector3<f64>),
    chaser: &BodyState,
    target: &BodyState,
) -> Geng2015Obs {
    let eci = |s: &BodyState| crate::control::geng2015::BodyStateEci {
        pos_eci_m: reference.0 + s.pos_m,
        vel_eci_m_s: reference.1 + s.vel_m_s,
        att_body_to_eci: s.att,
        rate_body_rad_s: s.att.inverse() * s.omega_rad_s,
    };
    Geng2015Obs {
        t_s,
        chaser: eci(chaser),
        target: eci(target),
    }
}

/// Control stage: call each law on its period and hold the command.
fn control(
    clock: Res<Clock>,
    orbit: Res<OrbitEnv>,
    roster: Res<Roster>,
    states: Query<&BodyState>,
    mut rt: ResMut<Geng2015Runtime>,
) {
    let t = clock.t_s();
    let reference = orbit.reference.state();
    for lp in &mut rt.loops {
        let (Ok(sc), Ok(st)) = (
            states.get(roster.bodies[lp.chaser]),
            states.get(roster.bodies[lp.target]),
        ) else {
            continue;
        };
        let obs = observation(t, reference, sc, st);
        if clock.step.is_multiple_of(lp.period_steps) {
            let (f, tq) = lp.controller.command(&obs);
            lp.force_body_n = f;
            lp.torque_body_nm = tq;
            lp.calls += 1;
            lp.last_call_s = t;
        }
    }
}

/// Monitor stage: diagnostics from the states after the step (the time of the trajectory row);
/// s and u are those of the last controller call.
fn publish(
    clock: Res<Clock>,
    orbit: Res<OrbitEnv>,
    roster: Res<Roster>,
    states: Query<&BodyState>,
    rt: Res<Geng2015Runtime>,
    mut diag: ResMut<Diagnostics>,
) {
    let t = clock.t_s();
    let reference = orbit.reference.state();
    for lp in &rt.loops {
        let (Ok(sc), Ok(st)) = (
            states.get(roster.bodies[lp.chaser]),
            states.get(roster.bodies[lp.target]),
        ) else {
            continue;
        };
        let obs = observation(t, reference, sc, st);
        let rel = relative_state(&lp.controller.params, &obs);
        let d = lp.controller.diagnostics();
        let q = rel.q_r.imag();
        let vals = [
            rel.rho_m.x,
            rel.rho_m.y,
            rel.rho_m.z,
            rel.rho_dot_m_s.x,
            rel.rho_dot_m_s.y,
            rel.rho_dot_m_s.z,
            q.x,
            q.y,
            q.z,
            rel.omega_r_rad_s.x,
            rel.omega_r_rad_s.y,
            rel.omega_r_rad_s.z,
            rel.rho_m.norm(),
            d.s[0],
            d.s[1],
            d.s[2],
            d.s[3],
            d.s[4],
            d.s[5],
            d.u[0],
            d.u[1],
            d.u[2],
            d.u[3],
            d.u[4],
            d.u[5],
        ];
        for (c, v) in lp.cols.iter().zip(vals) {
            diag.values[*c] = v;
        }
    }
}

/// Actuate stage: held command (body → world) on the chaser; disturbances on both bodies.
fn actuate(
    clock: Res<Clock>,
    roster: Res<Roster>,
    rt: Res<Geng2015Runtime>,
    mut q: Query<(&SimBody, &BodyState, &mut Wrench)>,
) {
    let t = clock.t_s();
    for lp in &rt.loops {
        if let Ok((_, s, mut w)) = q.get_mut(roster.bodies[lp.chaser]) {
            w.force_n += s.att * lp.force_body_n;
            w.torque_nm += s.att * lp.torque_body_nm;
        }
        let Some(dist) = &lp.disturbances else {
            continue;
        };
        for (idx, is_chaser) in [(lp.chaser, true), (lp.target, false)] {
            if let Ok((b, s, mut w)) = q.get_mut(roster.bodies[idx]) {
                let a = crate::control::geng2015::accel_disturbance_m_s2(
                    if is_chaser {
                        dist.chaser_form
                    } else {
                        dist.target_form
                    },
                    &if is_chaser {
                        dist.chaser_accel0_m_s2
                    } else {
                        dist.target_accel0_m_s2
                    },
                    dist.k_d_per_s,
                    t,
                );
                let tq = crate::control::geng2015::torque_disturbance_nm(
                    dist.torque_scale_nm,
                    dist.omega_orbit_rad_s,
                    t,
                );
                w.force_n += s.att * (a * b.mass_kg);
                w.torque_nm += s.att * tq;
            }
        }
    }
}
