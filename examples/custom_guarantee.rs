//! A user's own kind of guarantee, written outside rpod, registered under a name and checked
//! on `scenes/examples/free_drift.ron` next to the scene's own guarantees:
//!
//! ```sh
//! cargo run --release --example custom_guarantee -- --out out/custom_guarantee
//! ```
//!
//! `CommsRange(name, body, around, max_range_m)`: the centres of mass of two bodies stay
//! within a radio's range (margin = max_range_m − |r_body − r_around|, m). The distance between
//! the centres of mass changes at most at the bodies' relative speed, so the guarantee gives
//! that as its rate bound and the monitor judges it on every step interval, between samples
//! included ([`Guarantee::rate_bound`]). A kind gets rpod's checks for free: the bodies it
//! names must exist and differ, and its own checks ([`GuaranteeParams::check`]) are located
//! scene errors (`file:line:col: field guarantees.NAME.max_range_m: …`).

use rpod::control::registry::BuildError;
use rpod::guarantee::registry::GuaranteeContext;
use rpod::guarantee::{
    Guarantee, GuaranteeParams, MonitorView, MotionBounds, Reads, register_guarantee,
};
use rpod::scene::Scene;
use rpod::sim::Simulation;
use serde::Deserialize;

/// The scene entry: `CommsRange(name: "radio", body: "chaser", around: "target", max_range_m: 45.0)`.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
struct CommsRangeParams {
    name: String,
    body: String,
    around: String,
    /// Radio range, m.
    max_range_m: f64,
}

impl GuaranteeParams for CommsRangeParams {
    fn name(&self) -> &str {
        &self.name
    }
    fn bodies(&self) -> Vec<(&'static str, &str)> {
        vec![("body", &self.body), ("around", &self.around)]
    }
    fn check(&self, _scene: &Scene) -> Result<(), BuildError> {
        if !(self.max_range_m.is_finite() && self.max_range_m > 0.0) {
            return Err(BuildError::at(
                "max_range_m",
                format!(
                    "must be a positive number of metres, got {}",
                    self.max_range_m
                ),
            ));
        }
        Ok(())
    }
    fn build(&self, ctx: &GuaranteeContext) -> Result<Box<dyn Guarantee>, BuildError> {
        Ok(Box::new(CommsRange {
            name: self.name.clone(),
            body: ctx.body("body", &self.body)?,
            around: ctx.body("around", &self.around)?,
            max_range_m: self.max_range_m,
        }))
    }
    /// The viewer draws the radio's range as a sphere about `around` (`rpod view`).
    fn drawn(&self, scene: &Scene) -> Vec<rpod::geometry::drawn::DrawnSurface> {
        let Some(body) = scene.bodies.iter().position(|b| b.name == self.around) else {
            return Vec::new();
        };
        vec![rpod::geometry::drawn::DrawnSurface::SphereAboutBody {
            legend: format!(
                "radio range {} (green): {} m about {}",
                self.name, self.max_range_m, self.around
            ),
            body,
            radius_m: self.max_range_m,
            rgba: [0.3, 1.0, 0.4, 0.08],
        }]
    }
}

/// The running guarantee.
struct CommsRange {
    name: String,
    body: usize,
    around: usize,
    max_range_m: f64,
}

impl Guarantee for CommsRange {
    fn name(&self) -> &str {
        &self.name
    }
    fn margin(&self, v: &MonitorView) -> f64 {
        self.max_range_m - (v.bodies[self.body].pos_m - v.bodies[self.around].pos_m).norm()
    }
    /// |d|r|/dt| ≤ |v_body − v_around|.
    fn rate_bound(&self, m: &dyn MotionBounds) -> Option<f64> {
        Some(m.rel_speed_bound(self.body, self.around))
    }
    fn reads(&self) -> Reads {
        Reads::Bodies
    }
}

fn main() {
    let mut out = std::path::PathBuf::from("out/custom_guarantee");
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        if a == "--out" {
            out = args.next().expect("--out DIR").into();
        }
    }
    register_guarantee::<CommsRangeParams>("CommsRange").expect("a new name");
    // The scene's two guarantees, and a 45 m radio range (the chaser drifts from 41 m to 34 m).
    let overrides = [r#"guarantees=[
        MinDistance(name: "clearance_1m", a: "chaser", b: "target", min_m: 1.0),
        KeepOutSphere(name: "keep_out_10m", body: "chaser", around: "target", radius_m: 10.0),
        CommsRange(name: "radio_45m", body: "chaser", around: "target", max_range_m: 45.0),
    ]"#
    .to_string()];
    let mut sim = Simulation::from_file("scenes/examples/free_drift.ron", &overrides)
        .unwrap_or_else(|e| {
            eprintln!("error: {e}");
            std::process::exit(2)
        });
    sim.record_to(&out).expect("output folder");
    sim.run_for(sim.scene.duration_s);
    for g in &sim.guarantees().status {
        println!(
            "{:>14}: {} ({}), worst margin {:.3} {} at t = {:.2} s",
            g.name, g.verdict, g.judged, g.worst_margin, g.unit, g.worst_margin_t_s
        );
    }
    sim.finish().expect("outputs written");
    println!("wrote {}", out.display());
}
