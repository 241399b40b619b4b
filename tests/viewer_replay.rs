//! The viewer renders for real: a recorded run of `free_drift` is replayed (and the scene is
//! run live) in a window (under
//! `xvfb-run` with Mesa's software Vulkan in CI), `--screenshot` saves a PNG, and the PNG is
//! checked pixel by pixel.
//!
//! Independent reference: the background is the image's most common colour (not a constant
//! the test assumes); where the spacecraft are is given by the viewer's camera projection of
//! each body's recorded centre of mass (written beside the PNG), and the test checks that the
//! recorded centres it projects are the ones in `trajectory.csv` at the shown time. The
//! overlays and the panel are off, so every non-background pixel is a spacecraft mesh.
#![cfg(feature = "viewer")]

use std::path::Path;
use std::process::Command;

fn record_free_drift(dir: &Path, seconds: f64) {
    let loaded = rpod::scene::load_scene_file(Path::new("scenes/free_drift.ron"), &[]).unwrap();
    let mut sim = rpod::sim::Simulation::new(&loaded).unwrap();
    sim.record_to(dir).unwrap();
    let n = sim.steps_for(seconds);
    sim.step(n);
    sim.finish().unwrap();
}

struct Png {
    w: usize,
    h: usize,
    rgba: Vec<u8>,
}

impl Png {
    fn load(p: &Path) -> Self {
        let pm = resvg::tiny_skia::Pixmap::load_png(p).expect("a PNG");
        Self {
            w: pm.width() as usize,
            h: pm.height() as usize,
            rgba: pm.data().to_vec(),
        }
    }
    fn px(&self, x: usize, y: usize) -> [u8; 3] {
        let i = 4 * (y * self.w + x);
        [self.rgba[i], self.rgba[i + 1], self.rgba[i + 2]]
    }
    fn background(&self) -> [u8; 3] {
        let mut counts = std::collections::HashMap::new();
        for y in 0..self.h {
            for x in 0..self.w {
                *counts.entry(self.px(x, y)).or_insert(0usize) += 1;
            }
        }
        counts.into_iter().max_by_key(|(_, n)| *n).unwrap().0
    }
}

fn differs(a: [u8; 3], b: [u8; 3]) -> bool {
    a.iter().zip(&b).any(|(x, y)| x.abs_diff(*y) > 12)
}

/// Runs `rpod <command...> --screenshot PNG` at 960×540 with overlays off, asserts it succeeded
/// and the image size, and returns the image and its side file (projected body centres).
fn screenshot(command: &[&std::ffi::OsStr], png: &Path) -> (Png, serde_json::Value) {
    let out = Command::new(env!("CARGO_BIN_EXE_rpod"))
        .args(command)
        .arg("--screenshot")
        .arg(png)
        .args([
            "--frames",
            "12",
            "--width",
            "960",
            "--height",
            "540",
            "--no-overlays",
        ])
        .output()
        .expect("rpod runs");
    assert!(
        out.status.success(),
        "rpod {:?} failed: {}\n{}",
        command,
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    let img = Png::load(png);
    assert_eq!((img.w, img.h), (960, 540));
    let side: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(png.with_extension("json")).unwrap())
            .unwrap();
    (img, side)
}

#[test]
fn val_viewer_replay_screenshot_shows_spacecraft() {
    assert!(
        std::env::var_os("DISPLAY").is_some() || std::env::var_os("WAYLAND_DISPLAY").is_some(),
        "no display: run this test under `xvfb-run -a` (see .ci/run)"
    );
    let dir = std::env::temp_dir().join(format!("rpod_viewer_test_{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let run = dir.join("run");
    record_free_drift(&run, 20.0);
    let png = dir.join("shot.png");
    let (img, side) = screenshot(&["replay".as_ref(), run.as_os_str()], &png);

    // Shown at the end of the recording: the projected centres are the recorded final states.
    assert!((side["t_s"].as_f64().unwrap() - 20.0).abs() < 1e-9);
    let csv = std::fs::read_to_string(run.join("trajectory.csv")).unwrap();
    let header: Vec<&str> = csv.lines().next().unwrap().split(',').collect();
    let last: Vec<&str> = csv.lines().last().unwrap().split(',').collect();
    for b in side["bodies"].as_array().unwrap() {
        let name = b["name"].as_str().unwrap();
        for (k, axis) in ["px_m", "py_m", "pz_m"].iter().enumerate() {
            let col = header
                .iter()
                .position(|h| *h == format!("{name}.{axis}"))
                .unwrap();
            let rec: f64 = last[col].parse().unwrap();
            let shown = b["centre_world_m"][k].as_f64().unwrap();
            assert!(
                (rec - shown).abs() < 1e-9,
                "{name}.{axis}: {shown} vs {rec}"
            );
        }
    }

    check_picture(&img, &side);
    let _ = std::fs::remove_dir_all(&dir);
}

/// The PNG is not blank, each body's projected centre shows the spacecraft, corners are
/// background.
fn check_picture(img: &Png, side: &serde_json::Value) {
    // Not blank: a sensible share of the picture is not background.
    let bg = img.background();
    let total = img.w * img.h;
    let fg = (0..img.h)
        .flat_map(|y| (0..img.w).map(move |x| (x, y)))
        .filter(|&(x, y)| differs(img.px(x, y), bg))
        .count();
    let share = fg as f64 / total as f64;
    assert!(
        share > 0.002 && share < 0.5,
        "non-background share {share} (background {bg:?})"
    );

    // Each spacecraft is where the camera projects its centre of mass: pixels there differ
    // from the background, within a disc of half a metre's projected size.
    let bodies = side["bodies"].as_array().unwrap();
    assert_eq!(bodies.len(), 2);
    let mut near_bodies = 0;
    for b in bodies {
        let c = b["centre_px"].as_array().expect("body in view");
        let (cx, cy) = (c[0].as_f64().unwrap(), c[1].as_f64().unwrap());
        assert!(cx > 0.0 && cx < img.w as f64 && cy > 0.0 && cy < img.h as f64);
        let r = b["half_metre_px"].as_f64().unwrap().max(2.0);
        let (mut n, mut hit) = (0, 0);
        for y in (cy - r).max(0.0) as usize..((cy + r) as usize).min(img.h - 1) {
            for x in (cx - r).max(0.0) as usize..((cx + r) as usize).min(img.w - 1) {
                if (x as f64 - cx).hypot(y as f64 - cy) <= r {
                    n += 1;
                    hit += usize::from(differs(img.px(x, y), bg));
                }
            }
        }
        assert!(
            n > 0 && hit * 2 > n,
            "body {}: {hit} of {n} pixels around ({cx:.0}, {cy:.0}) differ from the background",
            b["name"]
        );
        near_bodies += hit;
    }
    assert!(near_bodies > 0);

    // The image corners (far from both bodies) are background: the foreground is the
    // spacecraft, not noise or a cleared-to-colour failure.
    for (x, y) in [
        (2, 2),
        (img.w - 3, 2),
        (2, img.h - 3),
        (img.w - 3, img.h - 3),
    ] {
        assert!(
            !differs(img.px(x, y), bg),
            "corner ({x}, {y}) is not background"
        );
    }
}

#[test]
fn val_viewer_live_view_screenshot_shows_spacecraft() {
    assert!(
        std::env::var_os("DISPLAY").is_some() || std::env::var_os("WAYLAND_DISPLAY").is_some(),
        "no display: run this test under `xvfb-run -a` (see .ci/run)"
    );
    let dir = std::env::temp_dir().join(format!("rpod_viewer_live_{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let png = dir.join("live.png");
    let (img, side) = screenshot(&["view".as_ref(), "scenes/free_drift.ron".as_ref()], &png);
    // Paused at t = 0: the bodies drawn are where the simulation starts them.
    assert_eq!(side["t_s"].as_f64().unwrap(), 0.0);
    let loaded = rpod::scene::load_scene_file(Path::new("scenes/free_drift.ron"), &[]).unwrap();
    let sim = rpod::sim::Simulation::new(&loaded).unwrap();
    for b in side["bodies"].as_array().unwrap() {
        let s = sim.body(b["name"].as_str().unwrap()).unwrap();
        for k in 0..3 {
            assert!((b["centre_world_m"][k].as_f64().unwrap() - s.pos_m[k]).abs() < 1e-9);
        }
    }
    check_picture(&img, &side);
    let _ = std::fs::remove_dir_all(&dir);
}
