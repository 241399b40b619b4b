//! `Sequencer`: a mission as phases. Each phase names the laws it flies — a translation law
//! (its force) and an attitude law (its torque), written by their parameters — and its exits:
//! conditions on the range, the time, a guarantee's margin, the docking state or the
//! translation law's tracking error, each naming the next phase. Every switch is a `phase`
//! event; the `PHASE.phase` column holds the active phase's index.
//!
//! ```ron
//! Sequencer(body: "chaser", target: "target", period_s: 0.1, actuator: Saturated(...),
//!   params: (phases: [
//!     (name: "hold100",
//!      translation: Some(HillPd((hold_m: (0.0, -100.0, 0.0), point: Port, gains: Pd(...)))),
//!      attitude: Some(Attitude((mode: AlignPort, natural_frequency_rad_s: 0.2, damping_ratio: 1.0))),
//!      exits: [(when: All([InPhaseFor(60.0), Settled(pos_m: 0.5, vel_m_s: 0.01)]), to: "approach")]),
//!     (name: "approach", translation: Some(Glideslope((...))), attitude: …,
//!      exits: [(when: PortRangeBelow(10.05), to: "hold10")]),
//!     …
//!     (name: "capture", translation: None, attitude: …, exits: []),   // the last phase
//!   ]))
//! ```
//!
//! The sub-laws share the entry's body, target, ports, period, sensor and actuator; each is
//! called only while its phase is active (its columns, prefixed `SEQ.PHASE.`, are NaN
//! otherwise), and is built fresh at the start (a glideslope's profile starts when its phase
//! first runs). Exits are checked, in order, at every call before the laws run; the first that
//! holds switches (one switch per call).
//!
//! # Checked when the scene loads (located errors)
//! Phase names unique and non-empty; every exit names an existing phase; only the last phase
//! may have no exits (any other could never be left); every phase but the first is the target
//! of some exit (else it could never be entered); numbers finite; no condition that can never
//! hold or always holds where a choice was meant (`Any([])`, `All([])`, `DockingState([])`, a
//! range ≤ 0 m below or < 0 m above, a negative time (a time beyond the scene's duration is
//! allowed: a run may be shortened with `--set duration_s=…`),
//! `Settled` with a bound ≤ 0); `MarginBelow` names a
//! guarantee of the scene; `DockingState` names states of a scene with a docking mechanism.

use crate::control::interface::{
    ActuationReport, Command, Controller, ControllerEvent, DiagnosticsAt, Observation,
};
use crate::control::spec::{BuildError, Commands, LawContext, LawParams, LawParamsSpec};
use nalgebra::Vector3;
use serde::{Deserialize, Serialize};

/// When a phase is left.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub enum Condition {
    /// Centre-of-mass range to the target below, m.
    RangeBelow(f64),
    /// Centre-of-mass range to the target above, m.
    RangeAbove(f64),
    /// Range from the body's port to the target's port below, m.
    PortRangeBelow(f64),
    /// Time spent in the phase at least, s.
    InPhaseFor(f64),
    /// Simulated time at least, s.
    TimeAbove(f64),
    /// A guarantee's margin (end of the previous step) below a value, in the guarantee's unit.
    MarginBelow(String, f64),
    /// The docking mechanism in one of these states (`FREE`, `ATTRACTING`, `CONTACT`,
    /// `SOFT_CAPTURE`, `LATCHED`, `REBOUND`, `JAMMED`, `MISSED`, `RELEASED`, and the soft-capture
    /// mechanism's `SOFT_CAPTURED`, `RETRACTED`, `HARD_DOCKED`).
    DockingState(Vec<String>),
    /// The phase's translation law tracks its reference within these errors.
    Settled {
        /// |position error| below, m.
        pos_m: f64,
        /// |velocity error| below, m/s.
        vel_m_s: f64,
    },
    /// Every condition.
    All(Vec<Condition>),
    /// Any condition.
    Any(Vec<Condition>),
}

/// The docking states a `DockingState` condition may name: every state of both mechanisms
/// ([`crate::contact::dock_state::DockState::NAMES`], so the list cannot miss one).
pub const DOCK_STATES: &[&str] = crate::contact::dock_state::DockState::NAMES;

/// One exit of a phase.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Exit {
    /// The condition.
    pub when: Condition,
    /// The next phase's name.
    pub to: String,
}

/// One phase.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Phase {
    /// Name (unique).
    pub name: String,
    /// The law that gives the force.
    #[serde(default)]
    pub translation: Option<LawParamsSpec>,
    /// The law that gives the torque.
    #[serde(default)]
    pub attitude: Option<LawParamsSpec>,
    /// Exits, checked in order.
    #[serde(default)]
    pub exits: Vec<Exit>,
    /// On entering this phase, command the docking mechanism to release (open the latch; the
    /// separation springs push the vehicles apart). A `docking_release` event; the mechanism
    /// acts on it in the same step, or raises `docking_release_ignored` when not docked.
    #[serde(default)]
    pub release_docking: bool,
}

/// Parameters of `Sequencer`.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SequencerParams {
    /// The phases; the first is active at t = 0.
    pub phases: Vec<Phase>,
}

/// The kind of the event a phase with `release_docking` raises on entry; the docking
/// mechanism acts on it.
pub const DOCKING_RELEASE_EVENT: &str = "docking_release";

/// Most phases a sequencer may have.
pub const MAX_PHASES: usize = 256;

fn check_condition(
    c: &Condition,
    field: &str,
    ctx: &LawContext,
    depth: usize,
) -> Result<(), BuildError> {
    let num = |v: f64, what: &str| {
        if v.is_finite() {
            Ok(())
        } else {
            Err(BuildError::at(
                field,
                format!("{what} must be finite, got {v}"),
            ))
        }
    };
    if depth > 16 {
        return Err(BuildError::at(field, "conditions nest more than 16 deep"));
    }
    // A condition that can never hold (or always holds where a choice was meant) is a scene
    // error: the phase would never be left, or the condition says nothing.
    let never = |why: String| -> Result<(), BuildError> { Err(BuildError::at(field, why)) };
    match c {
        Condition::RangeBelow(v) | Condition::RangeAbove(v) => {
            num(*v, "the range (m)")?;
            if ctx.target.is_none() {
                return Err(BuildError::at_root(
                    format!("controllers.{}.target", ctx.build.index),
                    "range conditions need the entry's `target`",
                ));
            }
            match c {
                Condition::RangeBelow(_) if *v <= 0.0 => {
                    return never(format!(
                        "a range is ≥ 0 m, so `RangeBelow({v})` can never hold"
                    ));
                }
                Condition::RangeAbove(_) if *v < 0.0 => {
                    return never(format!(
                        "a range is ≥ 0 m, so `RangeAbove({v})` always holds (use `InPhaseFor(0.0)` to leave at once)"
                    ));
                }
                _ => {}
            }
        }
        Condition::PortRangeBelow(v) => {
            num(*v, "the range (m)")?;
            if ctx.ports.is_none() {
                return Err(BuildError::at(
                    field,
                    "`PortRangeBelow` needs the entry's ports (or a docking mechanism between the two bodies)",
                ));
            }
            if *v <= 0.0 {
                return never(format!(
                    "a range is ≥ 0 m, so `PortRangeBelow({v})` can never hold"
                ));
            }
        }
        Condition::InPhaseFor(v) | Condition::TimeAbove(v) => {
            num(*v, "the time (s)")?;
            if *v < 0.0 {
                return never(format!(
                    "a time is ≥ 0 s, so a negative time ({v} s) always holds (use `InPhaseFor(0.0)` to leave at once)"
                ));
            }
        }
        Condition::MarginBelow(name, v) => {
            num(*v, "the margin")?;
            if !ctx.build.scene.guarantees.iter().any(|g| g.name() == name) {
                return Err(BuildError::at(
                    field,
                    format!("no guarantee named `{name}` in the scene's `guarantees`"),
                ));
            }
        }
        Condition::DockingState(states) => {
            if ctx.build.scene.docking.is_none() {
                return Err(BuildError::at(
                    field,
                    "`DockingState` needs the scene's `docking` mechanism",
                ));
            }
            if states.is_empty() {
                return never("`DockingState([])` names no state: it can never hold".into());
            }
            if let Some(s) = states.iter().find(|s| !DOCK_STATES.contains(&s.as_str())) {
                return Err(BuildError::at(
                    field,
                    format!(
                        "unknown docking state `{s}`; one of {}",
                        DOCK_STATES.join(", ")
                    ),
                ));
            }
        }
        Condition::Settled { pos_m, vel_m_s } => {
            num(*pos_m, "pos_m")?;
            num(*vel_m_s, "vel_m_s")?;
            if *pos_m <= 0.0 || *vel_m_s <= 0.0 {
                return never(format!(
                    "an error's norm is ≥ 0, so `Settled` below pos_m = {pos_m} m, vel_m_s = {vel_m_s} m/s can never hold: both must be > 0"
                ));
            }
        }
        Condition::All(v) | Condition::Any(v) => {
            if v.is_empty() {
                return never(if matches!(c, Condition::Any(_)) {
                    "`Any([])` combines no condition: it can never hold".into()
                } else {
                    "`All([])` combines no condition: it always holds (use `InPhaseFor(0.0)` to leave at once)".into()
                });
            }
            for (i, c) in v.iter().enumerate() {
                check_condition(c, &format!("{field}.0.{i}"), ctx, depth + 1)?;
            }
        }
    }
    Ok(())
}

impl LawParams for SequencerParams {
    fn build(&self, ctx: &mut LawContext) -> Result<Box<dyn Controller>, BuildError> {
        if self.phases.is_empty() {
            return Err(BuildError::at("phases", "needs at least one phase"));
        }
        if self.phases.len() > MAX_PHASES {
            return Err(BuildError::at(
                "phases",
                format!("at most {MAX_PHASES} phases, got {}", self.phases.len()),
            ));
        }
        let names: Vec<&str> = self.phases.iter().map(|p| p.name.as_str()).collect();
        let mut entered = vec![false; self.phases.len()];
        entered[0] = true;
        for (i, p) in self.phases.iter().enumerate() {
            let f = format!("phases.{i}");
            // The one name rule of every scene name (phase names become column names and
            // event fields).
            if let Some(problem) = crate::scene::validate::name_problem(&p.name) {
                return Err(BuildError::at(format!("{f}.name"), problem));
            }
            if names[..i].contains(&p.name.as_str()) {
                return Err(BuildError::at(
                    format!("{f}.name"),
                    format!("two phases are named `{}`", p.name),
                ));
            }
            if p.release_docking && ctx.build.scene.docking.is_none() {
                return Err(BuildError::at(
                    format!("{f}.release_docking"),
                    "the scene has no `docking` mechanism to release",
                ));
            }
            if p.release_docking && i == 0 {
                return Err(BuildError::at(
                    format!("{f}.release_docking"),
                    "the first phase is never entered by an exit: release from a later phase",
                ));
            }
            if p.exits.is_empty() && i + 1 != self.phases.len() {
                return Err(BuildError::at(
                    format!("{f}.exits"),
                    format!(
                        "phase `{}` has no exits and is not the last phase: it could never be left",
                        p.name
                    ),
                ));
            }
            for (k, e) in p.exits.iter().enumerate() {
                let ef = format!("{f}.exits.{k}");
                let Some(j) = names.iter().position(|n| *n == e.to) else {
                    return Err(BuildError::at(
                        format!("{ef}.to"),
                        format!("no phase named `{}`", e.to),
                    ));
                };
                if j == i {
                    return Err(BuildError::at(
                        format!("{ef}.to"),
                        "an exit must lead to another phase",
                    ));
                }
                entered[j] = true;
                check_condition(&e.when, &format!("{ef}.when"), ctx, 0)?;
                if matches!(e.when, Condition::Settled { .. }) && p.translation.is_none() {
                    return Err(BuildError::at(
                        format!("{ef}.when"),
                        "`Settled` needs the phase's translation law: it could never hold",
                    ));
                }
            }
        }
        if let Some(i) = entered.iter().position(|e| !e) {
            return Err(BuildError::at(
                format!("phases.{i}.name"),
                format!(
                    "no exit leads to phase `{}`: it could never be entered",
                    self.phases[i].name
                ),
            ));
        }
        let prefix = super::unique_prefix(ctx, "seq");
        let mut phases = Vec::with_capacity(self.phases.len());
        for (i, p) in self.phases.iter().enumerate() {
            for (spec, field, refused, carries) in [
                (
                    &p.translation,
                    "translation",
                    Commands::Torque,
                    "a torque only",
                ),
                (&p.attitude, "attitude", Commands::Force, "a force only"),
            ] {
                if let Some(s) = spec.as_ref().filter(|s| s.params.commands() == refused) {
                    return Err(BuildError::at(
                        format!("phases.{i}.{field}"),
                        format!(
                            "`{}` commands {carries}: as the phase's `{field}` law nothing of its \
                             command would be used (translation laws give the force, attitude laws \
                             the torque)",
                            s.kind
                        ),
                    ));
                }
            }
            let build = |ctx: &mut LawContext, spec: &Option<LawParamsSpec>, field: &str| {
                spec.as_ref()
                    .map(|s| {
                        s.params
                            .build(ctx)
                            .map_err(|e| e.within(&format!("phases.{i}.{field}.0")))
                            .map(|law| (s.kind.clone(), law))
                    })
                    .transpose()
            };
            let translation = build(ctx, &p.translation, "translation")?;
            // The entry's sensor feeds the translation laws (relative state); the attitude
            // laws fly on the truth of the attitude.
            let sensor = ctx.sensor.take();
            let attitude = build(ctx, &p.attitude, "attitude");
            ctx.sensor = sensor;
            let attitude = attitude?;
            phases.push(RunningPhase {
                name: p.name.clone(),
                translation,
                attitude,
                exits: p.exits.clone(),
                release_docking: p.release_docking,
                cols: (0, 0, 0),
                dropped: (false, false),
            });
        }
        // Column layout: [phase index] then each phase's translation and attitude columns.
        let mut at = 1;
        for ph in &mut phases {
            let nt = ph.translation.as_ref().map_or(0, |l| l.1.columns().len());
            let na = ph.attitude.as_ref().map_or(0, |l| l.1.columns().len());
            ph.cols = (at, nt, na);
            at += nt + na;
        }
        Ok(Box::new(Sequencer {
            prefix,
            phases,
            active: 0,
            entered_s: None,
            width: at,
            events: Vec::new(),
            switches: Vec::new(),
        }))
    }
}

struct RunningPhase {
    name: String,
    translation: Option<(String, Box<dyn Controller>)>,
    attitude: Option<(String, Box<dyn Controller>)>,
    exits: Vec<Exit>,
    release_docking: bool,
    /// (first column, translation columns, attitude columns).
    cols: (usize, usize, usize),
    /// Whether the translation (.0) / attitude (.1) law's unused part was reported dropped.
    dropped: (bool, bool),
}

/// The running `Sequencer`.
pub struct Sequencer {
    prefix: String,
    phases: Vec<RunningPhase>,
    active: usize,
    entered_s: Option<f64>,
    width: usize,
    events: Vec<ControllerEvent>,
    /// Every switch: (time s, from, to, reason).
    pub switches: Vec<(f64, String, String, String)>,
}

impl std::fmt::Debug for Sequencer {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Sequencer")
            .field("prefix", &self.prefix)
            .field("active", &self.active_name())
            .field("switches", &self.switches)
            .finish_non_exhaustive()
    }
}

impl Sequencer {
    /// The active phase's name.
    pub fn active_name(&self) -> &str {
        &self.phases[self.active].name
    }

    fn holds(&self, c: &Condition, obs: &Observation, in_phase_s: f64) -> bool {
        let range = || obs.relative.map(|r| r.world.pos_m.norm());
        match c {
            Condition::RangeBelow(v) => range().is_some_and(|r| r < *v),
            Condition::RangeAbove(v) => range().is_some_and(|r| r > *v),
            Condition::PortRangeBelow(v) => obs
                .ports
                .is_some_and(|p| (p.chaser.pos_m - p.target.pos_m).norm() < *v),
            Condition::InPhaseFor(v) => in_phase_s >= *v,
            Condition::TimeAbove(v) => obs.t_s >= *v,
            Condition::MarginBelow(name, v) => obs.guarantee_margin(name).is_some_and(|m| m < *v),
            Condition::DockingState(states) => obs
                .docking
                .is_some_and(|d| states.iter().any(|s| s == d.state)),
            Condition::Settled { pos_m, vel_m_s } => self.phases[self.active]
                .translation
                .as_ref()
                .and_then(|l| l.1.tracking_error())
                .is_some_and(|(p, v)| p < *pos_m && v < *vel_m_s),
            Condition::All(v) => v.iter().all(|c| self.holds(c, obs, in_phase_s)),
            Condition::Any(v) => v.iter().any(|c| self.holds(c, obs, in_phase_s)),
        }
    }
}

impl Controller for Sequencer {
    fn command(&mut self, obs: &Observation) -> Command {
        let t0 = *self.entered_s.get_or_insert(obs.t_s);
        let in_phase = obs.t_s - t0;
        let exits = self.phases[self.active].exits.clone();
        if let Some(e) = exits.iter().find(|e| self.holds(&e.when, obs, in_phase)) {
            let from = self.phases[self.active].name.clone();
            let to = self
                .phases
                .iter()
                .position(|p| p.name == e.to)
                .expect("checked when built");
            self.active = to;
            self.entered_s = Some(obs.t_s);
            // The condition as written, at most 256 characters (a condition may be large).
            let mut reason = format!("{:?}", e.when);
            if reason.chars().count() > 256 {
                reason = reason.chars().take(255).chain(['…']).collect();
            }
            self.events.push(ControllerEvent {
                kind: "phase".into(),
                data: serde_json::json!({"sequencer": self.prefix, "from": from,
                    "to": e.to, "reason": reason, "in_phase_s": in_phase}),
            });
            self.switches.push((obs.t_s, from, e.to.clone(), reason));
            if self.phases[to].release_docking {
                self.events.push(ControllerEvent {
                    kind: DOCKING_RELEASE_EVENT.into(),
                    data: serde_json::json!({"sequencer": self.prefix, "phase": e.to}),
                });
            }
        }
        let ph = &mut self.phases[self.active];
        let mut cmd = Command::zero();
        let mut dropped = Vec::new();
        if let Some((kind, law)) = ph.translation.as_mut() {
            let c = law.command(obs);
            cmd.force_n = c.force_n;
            cmd.force_frame = c.force_frame;
            if !ph.dropped.0 && (c.torque_nm != Vector3::zeros() || c.valves.is_some()) {
                ph.dropped.0 = true;
                dropped.push(("translation", kind.clone(), "torque_nm and valves"));
            }
        }
        if let Some((kind, law)) = ph.attitude.as_mut() {
            let c = law.command(obs);
            cmd.torque_nm = c.torque_nm;
            cmd.torque_frame = c.torque_frame;
            if !ph.dropped.1 && (c.force_n != Vector3::zeros() || c.valves.is_some()) {
                ph.dropped.1 = true;
                dropped.push(("attitude", kind.clone(), "force_n and valves"));
            }
        }
        for (slot, law, what) in dropped {
            self.events.push(ControllerEvent {
                kind: "sequencer_dropped".into(),
                data: serde_json::json!({"sequencer": self.prefix, "phase": ph.name,
                    "slot": slot, "law": law, "dropped": what,
                    "why": "a phase's translation law gives only the force, its attitude law only the torque"}),
            });
        }
        cmd
    }

    fn columns(&self) -> Vec<String> {
        let mut v = vec![format!("{}.phase", self.prefix)];
        for ph in &self.phases {
            for l in [&ph.translation, &ph.attitude].into_iter().flatten() {
                v.extend(
                    l.1.columns()
                        .into_iter()
                        .map(|c| format!("{}.{}.{c}", self.prefix, ph.name)),
                );
            }
        }
        debug_assert_eq!(v.len(), self.width);
        v
    }

    fn diagnostics_at(&self) -> &'static [DiagnosticsAt] {
        &[DiagnosticsAt::Actuated, DiagnosticsAt::PostStep]
    }

    fn diagnostics(
        &mut self,
        at: DiagnosticsAt,
        obs: &Observation,
        act: &ActuationReport,
        out: &mut [f64],
    ) {
        out[0] = self.active as f64;
        for (k, ph) in self.phases.iter_mut().enumerate() {
            let (first, nt, na) = ph.cols;
            let active = k == self.active;
            for (law, off, n) in [
                (&mut ph.translation, first, nt),
                (&mut ph.attitude, first + nt, na),
            ] {
                let slice = &mut out[off..off + n];
                match law {
                    Some((_, l)) if active => {
                        if l.diagnostics_at().contains(&at) {
                            l.diagnostics(at, obs, act, slice);
                        }
                    }
                    _ => slice.fill(f64::NAN),
                }
            }
        }
    }

    fn guarantees(&mut self) -> Vec<Box<dyn crate::guarantee::Guarantee>> {
        let mut g = Vec::new();
        for ph in &mut self.phases {
            for l in [&mut ph.translation, &mut ph.attitude]
                .into_iter()
                .flatten()
            {
                g.extend(l.1.guarantees());
            }
        }
        g
    }

    fn take_events(&mut self) -> Vec<ControllerEvent> {
        let mut e = std::mem::take(&mut self.events);
        for ph in &mut self.phases {
            for l in [&mut ph.translation, &mut ph.attitude]
                .into_iter()
                .flatten()
            {
                e.extend(l.1.take_events());
            }
        }
        e
    }

    fn needs(&self) -> crate::control::interface::Needs {
        // Range conditions read the relative state, port ranges the ports.
        let mut n = crate::control::interface::Needs {
            relative: true,
            ports: true,
            gravity: false,
        };
        for ph in &self.phases {
            for l in [&ph.translation, &ph.attitude].into_iter().flatten() {
                n = n.union(l.1.needs());
            }
        }
        n
    }

    fn tracking_error(&self) -> Option<(f64, f64)> {
        self.phases[self.active]
            .translation
            .as_ref()
            .and_then(|l| l.1.tracking_error())
    }
}
