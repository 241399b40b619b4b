//! The viewer renders for real: a recorded run of `free_drift` is replayed (and the scene is
//! run live) in a window (under
//! `xvfb-run` with Mesa's software Vulkan in CI), `--screenshot` saves a PNG, and the PNG is
//! checked pixel by pixel.
//!
//! Independent reference: the background is the image's most common colour (not a constant
//! the test assumes); where the spacecraft are is given by the viewer's camera projection of
//! each body's recorded centre of mass (written beside the PNG), and the test checks that the
//! recorded centres it projects are the ones in `trajectory.csv` at the shown time. The
//! overlays and the panel are off, so every non-background pixel is a spacecraft mesh. The
//! antenna is drawn from its glTF model: the instance has as many meshes as the file's first
//! scene has mesh primitives, counted here from the file.
//!
//! Force arrows: a recorded `collision_course` run replayed at its contact with only the
//! contacts layer on, seen from behind the chaser. The arrow drawn carries the force `contacts.csv` gives for the row
//! interval of that time (read here from the file), its length is that force over the printed
//! scale, and the pixels along its projection are the arrow's orange; with the overlays off the
//! same pixels are not. A model file that is not glTF stops the viewer with an error naming it.
//! Port frames, LVLH axes, the Earth direction and the closest-points segment: live at t = 0
//! (`free_drift` for the axes and the segment, `docking_aligned` for the port frames), overview
//! camera, with those layers on; along each line's projection (its ends from the side file) at
//! least 90 % of the sampled points have the line's hue (the lines are drawn in front of the
//! meshes), and without overlays at least 40 points in 100 fewer do.
//! With `--render-scale 0.5` (the 3-D view drawn at half size and stretched to the window),
//! the spacecraft are still where the camera projects their initial centres.
//!
//! Constraint surfaces: `xu2019_simulation` live at t = 0 with only the surfaces layer on, and
//! with the overlays off. The surfaces are semi-transparent over whatever is behind them, so
//! around each table prism's projected centroid almost every pixel changes, and it moves
//! toward the surface's colour: the obstacle (magenta) raises red and blue against green, the
//! keep-out (orange) raises red and green against blue. The alpha blend makes the sign of that
//! shift certain whatever is behind: Δ(r − g) = α(c_r − c_g) − α(u_r − u_g) > 0 when the
//! surface's own r − g exceeds the underlying pixel's.
#![cfg(feature = "viewer")]

use std::path::Path;
use std::process::Command;

fn record_free_drift(dir: &Path, seconds: f64) {
    record("scenes/examples/free_drift.ron", dir, seconds);
}

fn record(scene: &str, dir: &Path, seconds: f64) {
    let loaded = rpod::scene::load_scene_file(Path::new(scene), &[]).unwrap();
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
    screenshot_with(command, png, &["--no-overlays"])
}

/// As [`screenshot`], with `layers` (e.g. `--layers contacts`) instead of `--no-overlays`.
fn screenshot_with(
    command: &[&std::ffi::OsStr],
    png: &Path,
    layers: &[&str],
) -> (Png, serde_json::Value) {
    let out = Command::new(env!("CARGO_BIN_EXE_rpod"))
        .args(command)
        .arg("--screenshot")
        .arg(png)
        .args(["--frames", "12", "--width", "960", "--height", "540"])
        .args(layers)
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

/// Asserts a display is there (CI runs these under `xvfb-run`) and returns a fresh, empty
/// temporary directory named after `tag` and this process.
fn display_and_dir(tag: &str) -> std::path::PathBuf {
    assert!(
        std::env::var_os("DISPLAY").is_some() || std::env::var_os("WAYLAND_DISPLAY").is_some(),
        "no display: run this test under `xvfb-run -a` (see .ci/run)"
    );
    let dir = std::env::temp_dir().join(format!("{tag}_{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

#[test]
fn val_viewer_replay_screenshot_shows_spacecraft() {
    let dir = display_and_dir("rpod_viewer_test");
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
    check_models(&side);
    let _ = std::fs::remove_dir_all(&dir);
}

/// Mesh primitives in the first scene of a glTF file (nodes followed recursively).
fn gltf_primitives(path: &str) -> u64 {
    let g: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap();
    fn count(g: &serde_json::Value, node: usize) -> u64 {
        let n = &g["nodes"][node];
        let own = n["mesh"].as_u64().map_or(0, |m| {
            g["meshes"][m as usize]["primitives"]
                .as_array()
                .unwrap()
                .len() as u64
        });
        own + n["children"].as_array().map_or(0, |c| {
            c.iter()
                .map(|k| count(g, k.as_u64().unwrap() as usize))
                .sum()
        })
    }
    let scene = g["scene"].as_u64().unwrap_or(0) as usize;
    g["scenes"][scene]["nodes"]
        .as_array()
        .unwrap()
        .iter()
        .map(|k| count(&g, k.as_u64().unwrap() as usize))
        .sum()
}

/// `free_drift`'s antenna is drawn as its glTF dish: one instance, every mesh of the file.
fn check_models(side: &serde_json::Value) {
    assert_eq!(side["models_expected"].as_u64(), Some(1), "{side}");
    let models = side["models"].as_array().unwrap();
    assert_eq!(models.len(), 1, "the model was not spawned: {side}");
    assert_eq!(models[0]["part"], "target/antenna");
    assert_eq!(models[0]["path"], "models/hga_dish.gltf");
    let want = gltf_primitives("assets/models/hga_dish.gltf");
    assert!(want >= 2);
    assert_eq!(models[0]["meshes"].as_u64(), Some(want));
}

/// The force arrows' orange (sRGB 1.0, 0.45, 0.1) after the renderer's tone mapping: red well
/// above green, green above blue.
fn orange(p: [u8; 3]) -> bool {
    let [r, g, b] = p.map(i32::from);
    r > 150 && r - g > 50 && g - b > 25
}

/// Share of `n` points spread from `from` to `to` of the way along the projected segment a → b
/// with a pixel within one pixel that satisfies `hit`.
fn share_along(
    img: &Png,
    (a, b): ([f64; 2], [f64; 2]),
    (from, to, n): (f64, f64, usize),
    hit: impl Fn([u8; 3]) -> bool,
) -> f64 {
    let hits = (0..n)
        .filter(|k| {
            let s = from + (to - from) * *k as f64 / (n - 1) as f64;
            let (x, y) = (a[0] + s * (b[0] - a[0]), a[1] + s * (b[1] - a[1]));
            (-1..=1).any(|dy| {
                (-1..=1).any(|dx| {
                    let (px, py) = (x as i64 + dx, y as i64 + dy);
                    px >= 0
                        && py >= 0
                        && (px as usize) < img.w
                        && (py as usize) < img.h
                        && hit(img.px(px as usize, py as usize))
                })
            })
        })
        .count();
    hits as f64 / n as f64
}

/// Share of 40 points from 25 % to 90 % of the arrow (away from the contact sphere and the
/// head) with an orange pixel within one pixel.
fn orange_share(img: &Png, a: [f64; 2], b: [f64; 2]) -> f64 {
    share_along(img, (a, b), (0.25, 0.9, 40), orange)
}

#[test]
fn val_viewer_replay_draws_contact_force_arrows() {
    let dir = display_and_dir("rpod_viewer_arrows");
    let run = dir.join("run");
    record("scenes/examples/collision_course.ron", &run, 40.0);
    // The first contact (from events.jsonl) and the contacts.csv row that closes the recorded
    // interval it falls in (the contact lasts 0.02 s, well inside one 0.1 s row interval).
    let events = std::fs::read_to_string(run.join("events.jsonl")).unwrap();
    let start: serde_json::Value = events
        .lines()
        .map(|l| serde_json::from_str::<serde_json::Value>(l).unwrap())
        .find(|e| e["kind"] == "contact_start")
        .expect("a contact");
    let t = start["t_s"].as_f64().unwrap();
    let (a, b) = (
        start["a"].as_str().unwrap().to_string(),
        start["b"].as_str().unwrap().to_string(),
    );
    let contacts = std::fs::read_to_string(run.join("contacts.csv")).unwrap();
    let force = contacts
        .lines()
        .skip(1)
        .map(|l| l.split(',').map(str::to_string).collect::<Vec<_>>())
        .filter(|f| f[1] == a && f[2] == b)
        .map(|f| (f[0].parse::<f64>().unwrap(), f[4].parse::<f64>().unwrap()))
        .find(|(t_row, _)| *t_row >= t)
        .expect("the contact's row in contacts.csv")
        .1;
    assert!(force > 0.0);
    let at = t.to_string();
    let png = dir.join("arrows.png");
    let cmd = [
        "replay".as_ref(),
        run.as_os_str(),
        "--at".as_ref(),
        at.as_ref(),
    ];
    // Seen from behind the chaser (the overview is too far out for a 0.4 m arrow).
    let (img, side) = screenshot_with(&cmd, &png, &["--layers", "contacts", "--camera", "chaser"]);
    assert_eq!(side["t_s"].as_f64(), Some(t));
    let arrows = side["force_arrows"].as_array().unwrap();
    assert_eq!(arrows.len(), 1, "{side}");
    let arrow = &arrows[0];
    assert_eq!(
        (arrow["a"].as_str(), arrow["b"].as_str()),
        (Some(&*a), Some(&*b))
    );
    let shown = arrow["force_n"].as_f64().unwrap();
    assert!(
        (shown - force).abs() <= 1e-12 * force,
        "{shown} N vs {force} N"
    );
    let scale = side["arrow_scale_n_per_m"].as_f64().unwrap();
    let len = arrow["length_m"].as_f64().unwrap();
    assert!(
        (len - force / scale).abs() < 1e-4 * len,
        "arrow {len} m, force {force} N at {scale} N/m"
    );
    let p0: Vec<f64> = arrow["start_px"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_f64().unwrap())
        .collect();
    let p1: Vec<f64> = arrow["end_px"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_f64().unwrap())
        .collect();
    let (p0, p1) = ([p0[0], p0[1]], [p1[0], p1[1]]);
    let px_len = (p1[0] - p0[0]).hypot(p1[1] - p0[1]);
    assert!(px_len > 15.0, "the arrow is {px_len} px long");
    let on = orange_share(&img, p0, p1);
    println!(
        "arrow {a} → {b}: {force} N at t = {t} s, {len} m ({px_len:.0} px), {:.0} % orange",
        100.0 * on
    );
    assert!(on > 0.8, "only {:.0} % of the arrow is orange", 100.0 * on);
    // Control: the same picture without overlays has no arrow there.
    let (plain, side0) = screenshot_with(
        &cmd,
        &dir.join("plain.png"),
        &["--no-overlays", "--camera", "chaser"],
    );
    assert!(side0["force_arrows"].as_array().unwrap().is_empty());
    let off = orange_share(&plain, p0, p1);
    assert!(off < 0.2, "{:.0} % orange without overlays", 100.0 * off);
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
    let dir = display_and_dir("rpod_viewer_live");
    let loaded =
        rpod::scene::load_scene_file(Path::new("scenes/examples/free_drift.ron"), &[]).unwrap();
    let sim = rpod::sim::Simulation::new(&loaded).unwrap();
    // Full size, and the 3-D view drawn at half size and stretched to the window.
    for (png, extra) in [
        ("live.png", &["--no-overlays"][..]),
        ("half.png", &["--no-overlays", "--render-scale", "0.5"][..]),
    ] {
        let cmd = ["view".as_ref(), "scenes/examples/free_drift.ron".as_ref()];
        let (img, side) = screenshot_with(&cmd, &dir.join(png), extra);
        // Paused at t = 0: the bodies drawn are where the simulation starts them.
        assert_eq!(side["t_s"].as_f64().unwrap(), 0.0);
        for b in side["bodies"].as_array().unwrap() {
            let s = sim.body(b["name"].as_str().unwrap()).unwrap();
            for k in 0..3 {
                assert!((b["centre_world_m"][k].as_f64().unwrap() - s.pos_m[k]).abs() < 1e-9);
            }
        }
        check_picture(&img, &side);
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// Mean colour shift (on − off) in a disc of `r` px about `c`, and the share of pixels changed.
fn shift(on: &Png, off: &Png, c: [f64; 2], r: f64) -> ([f64; 3], f64) {
    let (mut sum, mut n, mut changed) = ([0.0; 3], 0usize, 0usize);
    for y in (c[1] - r).max(0.0) as usize..((c[1] + r) as usize).min(on.h - 1) {
        for x in (c[0] - r).max(0.0) as usize..((c[0] + r) as usize).min(on.w - 1) {
            if (x as f64 - c[0]).hypot(y as f64 - c[1]) > r {
                continue;
            }
            let (a, b) = (on.px(x, y), off.px(x, y));
            for k in 0..3 {
                sum[k] += f64::from(a[k]) - f64::from(b[k]);
            }
            n += 1;
            changed += usize::from(a != b);
        }
    }
    assert!(n > 0);
    (sum.map(|v| v / n as f64), changed as f64 / n as f64)
}

#[test]
fn val_viewer_draws_constraint_surfaces() {
    let dir = display_and_dir("rpod_viewer_surfaces");
    let cmd = [
        "view".as_ref(),
        "scenes/papers/xu2019/xu2019_simulation.ron".as_ref(),
    ];
    let (on, side) = screenshot_with(&cmd, &dir.join("on.png"), &["--layers", "surfaces"]);
    let (off, _) = screenshot(&cmd, &dir.join("off.png"));
    assert_eq!(side["layers"]["surfaces"], true);
    assert_eq!(side["layers"]["contacts"], false);
    let surfaces = side["surfaces"].as_array().unwrap();
    assert_eq!(surfaces.len(), 2, "{side}");
    for sf in surfaces {
        let legend = sf["legend"].as_str().unwrap();
        let c = sf["centroid_px"].as_array().expect("centroid in view");
        let c = [c[0].as_f64().unwrap(), c[1].as_f64().unwrap()];
        assert!(c[0] > 0.0 && c[0] < on.w as f64 && c[1] > 0.0 && c[1] < on.h as f64);
        let ([dr, dg, db], changed) = shift(&on, &off, c, 6.0);
        println!(
            "{legend}: Δrgb ({dr:.1}, {dg:.1}, {db:.1}), {:.0} % changed",
            100.0 * changed
        );
        assert!(
            changed > 0.9,
            "{legend}: only {:.0} % changed",
            100.0 * changed
        );
        if legend.starts_with("Xu2019 obstacle") {
            assert!(
                dr - dg > 0.0 && db - dg > 0.0,
                "{legend}: not toward magenta"
            );
        } else {
            assert!(legend.starts_with("Xu2019 keep-out"), "{legend}");
            assert!(
                dr - db > 0.0 && dg - db > 0.0,
                "{legend}: not toward orange"
            );
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// A model file that is there but is not glTF: the viewer stops with an error naming the file
/// and the part (the scene check only sees that the file exists).
#[test]
fn regress_viewer_bad_model_file_is_a_clear_error() {
    let dir = display_and_dir("rpod_viewer_bad_model");
    std::fs::create_dir_all(dir.join("models")).unwrap();
    std::fs::write(dir.join("models/hga_dish.gltf"), "this is not glTF\n").unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_rpod"))
        .args(["view", "scenes/examples/free_drift.ron", "--frames", "600"])
        .args(["--width", "320", "--height", "180", "--no-overlays"])
        .env("RPOD_ASSETS", &dir)
        .output()
        .expect("rpod runs");
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "a broken model was accepted");
    assert!(
        err.contains("model models/hga_dish.gltf of part target/antenna"),
        "stderr: {err}"
    );
    assert!(!err.contains("panicked"), "stderr: {err}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// Hue (deg), saturation and value of an sRGB colour (components 0–1).
fn hsv(c: [f64; 3]) -> (f64, f64, f64) {
    let max = c.iter().cloned().fold(0.0, f64::max);
    let min = c.iter().cloned().fold(1.0, f64::min);
    let d = max - min;
    let h = if d == 0.0 {
        0.0
    } else if max == c[0] {
        60.0 * (((c[1] - c[2]) / d).rem_euclid(6.0))
    } else if max == c[1] {
        60.0 * ((c[2] - c[0]) / d + 2.0)
    } else {
        60.0 * ((c[0] - c[1]) / d + 4.0)
    };
    (h, if max > 0.0 { d / max } else { 0.0 }, max)
}

/// Share of 30 points from 40 % to 95 % of a projected line with a pixel within one pixel of
/// the line's hue (±25°, saturated and bright enough to be a line, not shading).
fn hue_share(img: &Png, a: [f64; 2], b: [f64; 2], srgb: [f64; 3]) -> f64 {
    let (h0, _, _) = hsv(srgb);
    share_along(img, (a, b), (0.4, 0.95, 30), |p| {
        let (h, sat, val) = hsv(p.map(|v| f64::from(v) / 255.0));
        let dh = (h - h0).abs();
        dh.min(360.0 - dh) < 25.0 && sat > 0.45 && val > 0.35
    })
}

/// Renders `scene` live at t = 0 from `camera` with `layers` and without overlays, checks
/// every line of the side file that is on screen and at least 20 px long, and returns the
/// kinds of line checked (`port`, `LVLH`, `Earth`, `closest`).
fn check_lines(dir: &Path, scene: &str, camera: &str, layers: &str) -> Vec<String> {
    let cmd = ["view".as_ref(), scene.as_ref()];
    let (on, side) = screenshot_with(
        &cmd,
        &dir.join("on.png"),
        &["--layers", layers, "--camera", camera],
    );
    let (off, _) = screenshot_with(
        &cmd,
        &dir.join("off.png"),
        &["--no-overlays", "--camera", camera],
    );
    let mut seen = Vec::new();
    for l in side["lines"].as_array().unwrap() {
        let what = l["what"].as_str().unwrap();
        let (Some(a), Some(b)) = (l["start_px"].as_array(), l["end_px"].as_array()) else {
            continue; // behind the camera
        };
        let a = [a[0].as_f64().unwrap(), a[1].as_f64().unwrap()];
        let b = [b[0].as_f64().unwrap(), b[1].as_f64().unwrap()];
        let inside = |p: [f64; 2]| p[0] >= 0.0 && p[1] >= 0.0 && p[0] < 960.0 && p[1] < 540.0;
        let px_len = (b[0] - a[0]).hypot(b[1] - a[1]);
        if !(inside(a) && inside(b)) || px_len < 20.0 {
            continue; // off screen or end-on: nothing to sample
        }
        let c: Vec<f64> = l["srgb"]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_f64().unwrap())
            .collect();
        let c = [c[0], c[1], c[2]];
        let (s_on, s_off) = (hue_share(&on, a, b, c), hue_share(&off, a, b, c));
        println!(
            "{scene} {what}: {px_len:.0} px, {:.0} % of its hue drawn, {:.0} % without overlays",
            100.0 * s_on,
            100.0 * s_off
        );
        // These lines are drawn in front of the meshes (the LVLH y axis of free_drift runs
        // inside the +y wing): nearly every sample shows the line, other lines aside.
        assert!(
            s_on >= 0.9 && s_on - s_off >= 0.4,
            "{scene} {what}: {s_on} on, {s_off} off"
        );
        seen.push(what.split(' ').next().unwrap().to_string());
    }
    seen
}

#[test]
fn val_viewer_draws_frames_axes_and_closest_segment() {
    let dir = display_and_dir("rpod_viewer_lines");
    // Far out: the LVLH axes, the Earth direction and the 40 m closest-points segment.
    let seen = check_lines(
        &dir,
        "scenes/examples/free_drift.ron",
        "overview",
        "lvlh,closest",
    );
    for k in ["LVLH", "Earth", "closest"] {
        assert!(seen.iter().any(|s| s == k), "no {k} line checked");
    }
    // Close up: the two docking-port frames.
    let seen = check_lines(
        &dir,
        "scenes/examples/docking_aligned.ron",
        "overview",
        "ports",
    );
    assert!(seen.iter().filter(|s| *s == "port").count() >= 2);
    let _ = std::fs::remove_dir_all(&dir);
}
