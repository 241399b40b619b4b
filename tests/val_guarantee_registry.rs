//! The open guarantee registry (docs/guarantees.md): a kind registered from outside the crate is read
//! from a scene, checked with located errors and judged on the step intervals like a built-in
//! one; every kind refuses a guarantee between a body and itself. Errors are located on the
//! entry's line (line 8 of the test scene: two three-line bodies precede the list).
//!
//! Reference (closed form, free space, straight-line motion, so the f64 path is exact): a ball
//! leaving another along a line at speed v from range r₀ leaves a radio range R at
//! t = (R − r₀)/v. Tolerance: the monitor refines a first violation to a time interval
//! `t_tol_s` (< 1e-6 s here) containing the crossing; 1e-9 s covers the f64 rounding of t.

use rpod::control::registry::BuildError;
use rpod::guarantee::registry::{GuaranteeContext, registered};
use rpod::guarantee::{
    Guarantee, GuaranteeParams, MonitorView, MotionBounds, Reads, register_guarantee,
};
use rpod::scene::{Scene, load_scene_str};
use rpod::sim::Simulation;
use serde::Deserialize;

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
struct WithinParams {
    name: String,
    body: String,
    around: String,
    max_range_m: f64,
}

impl GuaranteeParams for WithinParams {
    fn name(&self) -> &str {
        &self.name
    }
    fn bodies(&self) -> Vec<(&'static str, &str)> {
        vec![("body", &self.body), ("around", &self.around)]
    }
    fn check(&self, _scene: &Scene) -> Result<(), BuildError> {
        if self.max_range_m.is_nan() || self.max_range_m <= 0.0 {
            return Err(BuildError::at("max_range_m", "must be positive"));
        }
        Ok(())
    }
    fn build(&self, ctx: &GuaranteeContext) -> Result<Box<dyn Guarantee>, BuildError> {
        Ok(Box::new(Within {
            name: self.name.clone(),
            body: ctx.body("body", &self.body)?,
            around: ctx.body("around", &self.around)?,
            max_range_m: self.max_range_m,
        }))
    }
}

struct Within {
    name: String,
    body: usize,
    around: usize,
    max_range_m: f64,
}

impl Guarantee for Within {
    fn name(&self) -> &str {
        &self.name
    }
    fn margin(&self, v: &MonitorView) -> f64 {
        self.max_range_m - (v.bodies[self.body].pos_m - v.bodies[self.around].pos_m).norm()
    }
    fn rate_bound(&self, m: &dyn MotionBounds) -> Option<f64> {
        Some(m.rel_speed_bound(self.body, self.around))
    }
    fn reads(&self) -> Reads {
        Reads::Bodies
    }
}

fn register() {
    // Tests in one binary share the process-wide registry: the first registers.
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| register_guarantee::<WithinParams>("Within").expect("new name"));
}

fn ball(name: &str, x: f64, vx: f64) -> String {
    format!(
        r#"(name: "{name}", role: Other, mass_kg: 1.0, inertia_kg_m2: (xx: 0.004, yy: 0.004, zz: 0.004),
           initial: (pos_m: ({x}, 0.0, 0.0), vel_m_s: ({vx}, 0.0, 0.0)),
           parts: [Bus(name: "ball", shape: Sphere(radius_m: 0.1))])"#
    )
}

fn text(guarantees: &str) -> String {
    format!(
        "Scene(name: \"registry\", dt_s: 0.01, duration_s: 1.0, environment: FreeSpace,\n\
         bodies: [{}, {}],\n\
         guarantees: [\n{guarantees}\n])",
        ball("a", 0.0, 0.0),
        ball("b", 1.0, 2.0)
    )
}

#[test]
fn registered_kind_is_judged_on_intervals_like_a_builtin() {
    register();
    assert!(registered().iter().any(|k| k == "Within"));
    let (r0, v, range) = (1.0, 2.0, 1.5051);
    let loaded = load_scene_str(
        &text(r#"Within(name: "radio", body: "b", around: "a", max_range_m: 1.5051)"#),
        "registry",
        &[],
    )
    .unwrap_or_else(|e| panic!("{e}"));
    let mut sim = Simulation::new(&loaded).unwrap_or_else(|e| panic!("{e}"));
    sim.step(100);
    let s = sim.summary();
    let g = &s["guarantees"][0];
    println!("{g}");
    assert_eq!(g["judged"], "interval");
    assert_eq!(g["verdict"], "violated");
    let want = (range - r0) / v;
    let t = g["first_violation_s"].as_f64().unwrap();
    let tol = g["first_violation_tol_s"].as_f64().unwrap();
    assert!(
        t <= want + 1e-9 && want <= t + tol + 1e-9 && tol < 1e-6,
        "{t} +{tol} vs {want}"
    );
    assert_eq!(g["first_violation_found"], "interval");
}

fn error(guarantees: &str) -> rpod::scene::SceneError {
    register();
    let t = text(guarantees);
    match load_scene_str(&t, "registry", &[]) {
        Err(e) => e,
        Ok(l) => match Simulation::new(&l) {
            Err(e) => e,
            Ok(_) => panic!("accepted: {guarantees}"),
        },
    }
}

#[test]
fn unknown_kind_is_a_located_error_listing_the_registered_kinds() {
    let e = error(r#"NoSuchThing(name: "x", body: "b", around: "a")"#);
    println!("{e}");
    assert_eq!(e.line, 8, "{e}");
    assert!(
        e.message.contains("unknown guarantee kind `NoSuchThing`"),
        "{e}"
    );
    assert!(
        e.message.contains("KeepOutSphere") && e.message.contains("MinDistance"),
        "{e}"
    );
}

#[test]
fn bad_params_are_located_errors() {
    let e = error(r#"Within(name: "radio", body: "b", around: "a", max_range_m: -1.0)"#);
    assert_eq!(
        (e.line, e.field.as_str()),
        (8, "guarantees.radio.max_range_m"),
        "{e}"
    );
    let e = error(r#"Within(name: "radio", body: "b", around: "a", max_range: 1.0)"#);
    assert_eq!(e.line, 8, "{e}");
    assert!(e.message.contains("max_range"), "{e}");
    let e = error(r#"KeepOutSphere(name: "k", body: "b", around: "nobody", radius_m: 1.0)"#);
    assert_eq!(
        (e.line, e.field.as_str()),
        (8, "guarantees.k.around"),
        "{e}"
    );
    assert!(e.message.contains("no body named `nobody`"), "{e}");
}

#[test]
fn a_guarantee_between_a_body_and_itself_is_refused_for_every_kind() {
    for (entry, field) in [
        (
            r#"Within(name: "g", body: "a", around: "a", max_range_m: 1.0)"#,
            "around",
        ),
        (
            r#"KeepOutSphere(name: "g", body: "a", around: "a", radius_m: 1.0)"#,
            "around",
        ),
        (r#"MinDistance(name: "g", a: "b", b: "b", min_m: 1.0)"#, "b"),
    ] {
        let e = error(entry);
        assert_eq!(e.field, format!("guarantees.g.{field}"), "{e}");
        assert!(e.message.contains("must name a different body"), "{e}");
        assert_eq!(e.line, 8, "{e}");
    }
}

#[test]
fn a_kind_name_is_registered_once() {
    register();
    let e = register_guarantee::<WithinParams>("Within").unwrap_err();
    assert!(e.0.contains("already registered"), "{e}");
    let e = register_guarantee::<WithinParams>("KeepOutSphere").unwrap_err();
    assert!(e.0.contains("already registered"), "{e}");
    let e = register_guarantee::<WithinParams>("not a name").unwrap_err();
    assert!(e.0.contains("RON identifier"), "{e}");
}
