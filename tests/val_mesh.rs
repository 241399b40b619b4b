//! Mesh parts (docs/vehicles.md): judged exactly as triangle meshes, simulated as convex pieces.
//!
//! References (free space, no forces before contact, so every path is a straight line):
//! * a 12-triangle cube mesh and the `Box` primitive of the same size are the same solid: the
//!   monitor's distances at every step and the first-touch time of a ball thrown at it agree to
//!   1e-6 m and 1e-6 s (both are parry's f32 queries on the same faces);
//! * a ball of radius r at rest centred in the slot of a U-shaped prism (slot half-width w) is
//!   at w − r from the mesh — its convex hull would contain the ball (distance 0) — and rapier's
//!   decomposition must not touch it (no contact, no motion);
//! * a ball of radius r flying at speed v over a plate (half-thickness h) at height z₀ has the
//!   closest approach z₀ − h − r to the face, reached between two samples at 300 m/s; flying
//!   through it from z₀ it first touches at (z₀ − h − r)/v;
//! * a box mesh with a density gives mass ρ·abc and inertia m(b² + c²)/12 … (closed form).
//!
//! Tolerances: distances 1e-6 m (parry's f32 near 1 m); refined times the monitor's
//! `EVENT_TIME_TOL`·dt plus the touch distance (1e-4 m) over the approach speed; mass
//! properties 1e-9 relative (f64 sums of f32-exact vertices).

use rpod::scene::load_scene_str;
use rpod::sim::Simulation;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

const DT: f64 = 0.01;

fn dir(test: &str) -> PathBuf {
    let d = PathBuf::from(env!("CARGO_TARGET_TMPDIR"))
        .join("val_mesh")
        .join(test);
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// OBJ text of boxes (lo, hi, object name), outward-facing, 12 triangles each.
fn boxes_obj(boxes: &[([f64; 3], [f64; 3], &str)]) -> String {
    let mut s = String::new();
    let mut base = 1;
    for (lo, hi, name) in boxes {
        writeln!(s, "o {name}").unwrap();
        for i in 0..8 {
            let x = if i & 1 == 0 { lo[0] } else { hi[0] };
            let y = if i & 2 == 0 { lo[1] } else { hi[1] };
            let z = if i & 4 == 0 { lo[2] } else { hi[2] };
            writeln!(s, "v {x} {y} {z}").unwrap();
        }
        for q in [
            [0, 2, 3, 1],
            [4, 5, 7, 6],
            [0, 1, 5, 4],
            [2, 6, 7, 3],
            [0, 4, 6, 2],
            [1, 3, 7, 5],
        ] {
            let f = |k: usize| q[k] + base;
            writeln!(s, "f {} {} {}", f(0), f(1), f(2)).unwrap();
            writeln!(s, "f {} {} {}", f(0), f(2), f(3)).unwrap();
        }
        base += 8;
    }
    s
}

/// A closed U-shaped prism, z ∈ [−½, ½]: x ∈ [−1.5, 1.5], y ∈ [0, 2], with the slot
/// x ∈ [−0.5, 0.5], y ∈ [0.5, 2] cut out.
fn u_obj() -> String {
    // Outline, counter-clockwise seen from +z.
    let o = [
        (-1.5, 0.0), // A 0
        (1.5, 0.0),  // B 1
        (1.5, 0.5),  // C 2
        (1.5, 2.0),  // G 3
        (0.5, 2.0),  // H 4
        (0.5, 0.5),  // D 5
        (-0.5, 0.5), // E 6
        (-0.5, 2.0), // I 7
        (-1.5, 2.0), // J 8
        (-1.5, 0.5), // F 9
    ];
    let cap = [
        [0, 1, 2],
        [0, 2, 5],
        [0, 5, 6],
        [0, 6, 9],
        [5, 2, 3],
        [5, 3, 4],
        [9, 6, 7],
        [9, 7, 8],
    ];
    let mut s = String::from("o u\n");
    for z in [-0.5, 0.5] {
        for (x, y) in o {
            writeln!(s, "v {x} {y} {z}").unwrap();
        }
    }
    let n = o.len();
    for t in cap {
        // Top (z = +½, vertices n..2n) counter-clockwise; bottom reversed.
        writeln!(s, "f {} {} {}", t[0] + n + 1, t[1] + n + 1, t[2] + n + 1).unwrap();
        writeln!(s, "f {} {} {}", t[0] + 1, t[2] + 1, t[1] + 1).unwrap();
    }
    for k in 0..n {
        let (p, q) = (k, (k + 1) % n);
        let (pb, qb, qt, pt) = (p + 1, q + 1, q + n + 1, p + n + 1);
        writeln!(s, "f {pb} {qb} {qt}").unwrap();
        writeln!(s, "f {pb} {qt} {pt}").unwrap();
    }
    s
}

fn ball(name: &str, r: f64, pos: [f64; 3], vel: [f64; 3]) -> String {
    let i = 0.4 * r * r;
    format!(
        r#"(name: "{name}", role: Chaser, mass_kg: 1.0, inertia_kg_m2: (xx: {i}, yy: {i}, zz: {i}),
           initial: (pos_m: ({}, {}, {}), vel_m_s: ({}, {}, {})),
           parts: [Bus(name: "ball", shape: Sphere(radius_m: {r}))])"#,
        pos[0], pos[1], pos[2], vel[0], vel[1], vel[2]
    )
}

fn target(shape: &str) -> String {
    format!(
        r#"(name: "target", role: Target, mass_kg: 1000.0,
           inertia_kg_m2: (xx: 1000.0, yy: 1000.0, zz: 1000.0),
           initial: (pos_m: (0.0, 0.0, 0.0)),
           parts: [Bus(name: "body", shape: {shape})])"#
    )
}

fn scene_text(bodies: &[String], guarantees: &str, duration: f64) -> String {
    format!(
        r#"Scene(name: "mesh", dt_s: {DT}, duration_s: {duration}, environment: FreeSpace,
           bodies: [{}], guarantees: [{guarantees}])"#,
        bodies.join(",\n")
    )
}

fn build(d: &Path, text: &str) -> Simulation {
    let file = d.join("scene.ron");
    std::fs::write(&file, text).unwrap();
    let loaded =
        load_scene_str(text, &file.display().to_string(), &[]).unwrap_or_else(|e| panic!("{e}"));
    Simulation::new(&loaded).unwrap_or_else(|e| panic!("{e}"))
}

fn contact_start(sim: &Simulation) -> Option<(f64, f64)> {
    sim.events()
        .iter()
        .find(|e| e.kind == "contact_start")
        .map(|e| (e.t_s, e.data["t_contact_s"].as_f64().expect("t_contact_s")))
}

#[test]
fn val_mesh_cube_gives_the_box_primitive_distances_and_contact_times() {
    let d = dir("cube");
    std::fs::write(
        d.join("cube.obj"),
        boxes_obj(&[([-0.5, -0.4, -0.3], [0.5, 0.4, 0.3], "cube")]),
    )
    .unwrap();
    // A ball thrown obliquely at the cube's +x face.
    let mover = ball("ball", 0.2, [3.0, 0.1, 0.05], [-2.0, 0.03, -0.02]);
    let mut a = build(
        &d,
        &scene_text(
            &[target("Box(size_m: (1.0, 0.8, 0.6))"), mover.clone()],
            "",
            1.5,
        ),
    );
    let mut b = build(
        &d,
        &scene_text(&[target(r#"Mesh(path: "cube.obj")"#), mover], "", 1.5),
    );
    let mut worst = 0.0f64;
    for _ in 0..150 {
        a.step(1);
        b.step(1);
        if contact_start(&a).is_some() || contact_start(&b).is_some() {
            break;
        }
        let (da, db) = (
            a.monitor().pairs[0].distance_m,
            b.monitor().pairs[0].distance_m,
        );
        worst = worst.max((da - db).abs());
    }
    assert!(worst <= 1e-6, "distances differ by {worst} m");
    let (ta, tb) = (
        contact_start(&a).expect("box contact"),
        contact_start(&b).expect("mesh contact"),
    );
    assert_eq!(ta.0, tb.0, "contact reported at different steps");
    assert!((ta.1 - tb.1).abs() <= 1e-6, "touch {} vs {}", ta.1, tb.1);
    // And both at the closed form: the ball's surface within the touch distance (1e-4 m) of
    // the face x = 0.5; the search runs on certified lower bounds, which undercut by the f32
    // rounding of the relative pose (8 ulps of ~4 m, < 1e-5 m).
    let v = 2.0;
    let want = (3.0 - 0.2 - 0.5 - 1e-4) / v;
    let tol = DT / 65_536.0 + 1e-5 / v;
    assert!((tb.1 - want).abs() <= tol, "touch {} vs {want}", tb.1);
    let s = b.summary();
    let m = &s["meshes"][0];
    assert_eq!(m["part"], "target/body");
    assert_eq!(m["triangles"], 12);
    assert!(
        m["decomposition_max_deviation_m"].as_f64().unwrap() < 1e-5,
        "{m}"
    );
}

/// ASCII STL text of the triangles of an OBJ written by [`boxes_obj`] (one box).
fn stl_ascii(lo: [f64; 3], hi: [f64; 3]) -> (String, Vec<u8>) {
    let obj = boxes_obj(&[(lo, hi, "b")]);
    let v: Vec<[f32; 3]> = obj
        .lines()
        .filter_map(|l| l.strip_prefix("v "))
        .map(|l| {
            let x: Vec<f32> = l.split(' ').map(|t| t.parse().unwrap()).collect();
            [x[0], x[1], x[2]]
        })
        .collect();
    let f: Vec<[usize; 3]> = obj
        .lines()
        .filter_map(|l| l.strip_prefix("f "))
        .map(|l| {
            let x: Vec<usize> = l.split(' ').map(|t| t.parse().unwrap()).collect();
            [x[0] - 1, x[1] - 1, x[2] - 1]
        })
        .collect();
    let mut a = String::from("solid b\n");
    let mut b = vec![0u8; 80];
    b.extend_from_slice(&(f.len() as u32).to_le_bytes());
    for t in &f {
        a.push_str("facet normal 0 0 0\nouter loop\n");
        b.extend_from_slice(&[0u8; 12]);
        for i in t {
            writeln!(a, "vertex {} {} {}", v[*i][0], v[*i][1], v[*i][2]).unwrap();
            for x in v[*i] {
                b.extend_from_slice(&x.to_le_bytes());
            }
        }
        a.push_str("endloop\nendfacet\n");
        b.extend_from_slice(&[0u8; 2]);
    }
    a.push_str("endsolid b\n");
    (a, b)
}

#[test]
fn val_mesh_stl_ascii_and_binary_read_as_the_obj() {
    let d = dir("stl");
    let (lo, hi) = ([-0.5, -0.4, -0.3], [0.5, 0.4, 0.3]);
    let (ascii, binary) = stl_ascii(lo, hi);
    std::fs::write(d.join("a.stl"), ascii).unwrap();
    std::fs::write(d.join("b.stl"), binary).unwrap();
    std::fs::write(d.join("c.obj"), boxes_obj(&[(lo, hi, "c")])).unwrap();
    // The ball (r 0.2) at (1.7, 1.4, 1.3) is nearest the corner (0.5, 0.4, 0.3).
    let want = (1.2f64 * 1.2 + 1.0 + 1.0).sqrt() - 0.2;
    for f in ["a.stl", "b.stl", "c.obj"] {
        let sim = build(
            &d,
            &scene_text(
                &[
                    target(&format!(r#"Mesh(path: "{f}")"#)),
                    ball("ball", 0.2, [1.7, 1.4, 1.3], [0.0, 0.0, 0.0]),
                ],
                "",
                0.1,
            ),
        );
        let got = sim.monitor().pairs[0].distance_m;
        assert!((got - want).abs() < 1e-6, "{f}: {got} vs {want}");
    }
}

#[test]
fn val_mesh_concave_clearance_is_not_the_hull() {
    let d = dir("concave");
    std::fs::write(d.join("u.obj"), u_obj()).unwrap();
    let r = 0.3;
    let mut sim = build(
        &d,
        &scene_text(
            &[
                target(r#"Mesh(path: "u.obj", decomposition: (resolution: 64))"#),
                ball("ball", r, [0.0, 1.25, 0.0], [0.0, 0.0, 0.0]),
            ],
            r#"MinDistance(name: "slot", a: "target", b: "ball", min_m: 0.19)"#,
            0.5,
        ),
    );
    let d0 = sim.monitor().pairs[0].distance_m;
    assert!((d0 - (0.5 - r)).abs() < 1e-6, "distance in the slot {d0}");
    sim.step(50);
    assert!(
        sim.contacts().first_contact_s.is_none(),
        "the pieces fill the slot"
    );
    let s = sim.body("ball").unwrap();
    assert!(s.pos_m.norm() - 1.25 < 1e-9 && s.vel_m_s.norm() == 0.0);
    assert_eq!(sim.guarantee("slot").unwrap().verdict, "held");
    let sum = sim.summary();
    let m = &sum["meshes"][0];
    assert!(m["convex_pieces"].as_u64().unwrap() >= 3, "{m}");
    // The pieces follow the mesh to within a few voxels (3 m / 64 each), far less than the
    // 1.5 m by which the hull would stand out of the slot.
    let dev = m["decomposition_max_deviation_m"].as_f64().unwrap();
    assert!(dev < 0.25, "{m}");
}

#[test]
fn val_mesh_fast_flyby_past_a_thin_plate_between_samples() {
    let d = dir("plate");
    let h = 0.005;
    std::fs::write(
        d.join("plate.obj"),
        boxes_obj(&[([-1.0, -1.0, -h], [1.0, 1.0, h], "plate")]),
    )
    .unwrap();
    let (r, c, v) = (0.1, 0.05, 300.0);
    // Over the plate: 2 m of plate takes 6.7 ms, less than one step; the samples are at
    // x = −1.6 and x = +1.4.
    let mut sim = build(
        &d,
        &scene_text(
            &[
                target(r#"Mesh(path: "plate.obj")"#),
                ball("ball", r, [-4.6, 0.0, h + r + c], [v, 0.0, 0.0]),
            ],
            &format!(
                r#"MinDistance(name: "above", a: "target", b: "ball", min_m: {}),
                   MinDistance(name: "below", a: "target", b: "ball", min_m: {})"#,
                c + 0.002,
                c - 0.04
            ),
            0.03,
        ),
    );
    sim.step(3);
    let m = &sim.monitor().min_per_pair[0];
    assert!(
        (m.distance_m - c).abs() <= 1e-4,
        "closest approach {} m",
        m.distance_m
    );
    assert!(m.inside, "found between samples");
    assert_eq!(sim.guarantee("above").unwrap().verdict, "violated");
    // Proving 4 cm of margin over the 6.7 ms plateau at 300 m/s takes intervals of at most
    // 2·0.04/300 s (about 25 of them): the verdict is proven between the samples.
    assert_eq!(sim.guarantee("below").unwrap().verdict, "held");

    // Through the plate: first touch at (z₀ − h − r)/v, inside a step.
    let z0 = 1.4;
    let mut hit = build(
        &d,
        &scene_text(
            &[
                target(r#"Mesh(path: "plate.obj")"#),
                ball("ball", r, [0.2, 0.3, z0], [0.0, 0.0, -v]),
            ],
            "",
            0.02,
        ),
    );
    hit.step(2);
    let m = &hit.monitor().min_per_pair[0];
    assert!(m.distance_m <= 1e-3, "min distance {} m", m.distance_m);
    let (_, t) = contact_start(&hit).expect("the crossing is a contact");
    let want = (z0 - h - r - 1e-4) / v;
    assert!(
        (t - want).abs() <= DT / 65_536.0 + 1e-5 / v,
        "touch {t} vs {want}"
    );
}

#[test]
fn val_mesh_gltf_nodes_name_the_parts_and_mass_from_a_closed_mesh() {
    let d = dir("gltf");
    // Two cube meshes as glTF nodes: `truss` at the origin, `solar_array_3` at x = 3 (its
    // node translation), the buffer in an external file.
    let mut bin = Vec::new();
    let cube = [
        [-0.5f32, -0.5, -0.5],
        [0.5, -0.5, -0.5],
        [-0.5, 0.5, -0.5],
        [0.5, 0.5, -0.5],
        [-0.5, -0.5, 0.5],
        [0.5, -0.5, 0.5],
        [-0.5, 0.5, 0.5],
        [0.5, 0.5, 0.5],
    ];
    for p in cube {
        for x in p {
            bin.extend_from_slice(&x.to_le_bytes());
        }
    }
    let idx: [u16; 36] = [
        0, 2, 3, 0, 3, 1, 4, 5, 7, 4, 7, 6, 0, 1, 5, 0, 5, 4, 2, 6, 7, 2, 7, 3, 0, 4, 6, 0, 6, 2,
        1, 3, 7, 1, 7, 5,
    ];
    for i in idx {
        bin.extend_from_slice(&i.to_le_bytes());
    }
    std::fs::write(d.join("parts.bin"), &bin).unwrap();
    let gltf = r#"{"asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0, 1]}],
      "nodes": [{"name": "truss", "mesh": 0}, {"name": "solar_array_3", "mesh": 0, "translation": [3, 0, 0]}],
      "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}],
      "buffers": [{"uri": "parts.bin", "byteLength": 168}],
      "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 96},
                      {"buffer": 0, "byteOffset": 96, "byteLength": 72}],
      "accessors": [{"bufferView": 0, "componentType": 5126, "count": 8, "type": "VEC3",
                     "min": [-0.5, -0.5, -0.5], "max": [0.5, 0.5, 0.5]},
                    {"bufferView": 1, "componentType": 5123, "count": 36, "type": "SCALAR"}]}"#;
    std::fs::write(d.join("parts.gltf"), gltf).unwrap();
    let rho = 100.0;
    let tgt = format!(
        r#"(name: "target", role: Target, mass_from_meshes: true,
           initial: (pos_m: (0.0, 0.0, 0.0)),
           parts: [Bus(name: "body", shape: Mesh(path: "parts.gltf", scale: 2.0, density_kg_m3: {rho}))])"#
    );
    let sim = build(
        &d,
        &scene_text(
            &[tgt, ball("ball", 0.2, [3.0, 5.0, 0.0], [0.0, 0.0, 0.0])],
            "",
            0.1,
        ),
    );
    let mon = sim.monitor();
    let p = &mon.pairs[0];
    assert_eq!(mon.pair_names(p).0, "target/solar_array_3");
    // The scaled array cube spans x ∈ [5, 7], y ≤ 1 in the body frame, whose origin is 3 m
    // behind the centre of mass (at the world origin): the ball (r 0.2) at (3, 5) is 3.8 m
    // away.
    assert!((p.distance_m - 3.8).abs() < 1e-5, "{}", p.distance_m);
    // Mass: two 2 m cubes, centres 6 m apart on x.
    let body = &sim.scene.bodies[0];
    let m1 = rho * 8.0;
    assert!((body.mass_kg - 2.0 * m1).abs() < 1e-9 * m1);
    assert!((body.com_m[0] - 3.0).abs() < 1e-9 && body.com_m[1].abs() < 1e-12);
    let own = m1 * (4.0 + 4.0) / 12.0;
    let j = &body.inertia_kg_m2;
    assert!((j.xx - 2.0 * own).abs() < 1e-9 * own);
    assert!((j.yy - (2.0 * own + 2.0 * m1 * 9.0)).abs() < 1e-9 * own);
    assert!(j.xy.abs() < 1e-9 * own);
}

/// Loads `text` as `DIR/scene.ron` and returns the error.
fn error(d: &Path, text: &str) -> rpod::scene::SceneError {
    let file = d.join("scene.ron");
    std::fs::write(&file, text).unwrap();
    match load_scene_str(text, &file.display().to_string(), &[]) {
        Ok(l) => match Simulation::new(&l) {
            Ok(_) => panic!("accepted"),
            Err(e) => e,
        },
        Err(e) => e,
    }
}

#[test]
fn regress_bad_mesh_input_gives_located_errors() {
    let d = dir("bad");
    let field = "bodies.target.parts.body.shape.path";
    let ball = ball("ball", 0.1, [5.0, 0.0, 0.0], [0.0, 0.0, 0.0]);
    let check = |shape: &str, field: &str, words: &[&str]| {
        let e = error(&d, &scene_text(&[target(shape), ball.clone()], "", 0.1));
        assert_eq!(e.field, field, "{e}");
        assert!(e.line > 0 && e.col > 0, "{e}");
        for w in words {
            assert!(e.message.contains(w), "`{e}` lacks `{w}`");
        }
    };
    check(
        r#"Mesh(path: "none.obj")"#,
        field,
        &["none.obj", "cannot read"],
    );
    check(r#"Mesh(path: "x.ply")"#, field, &["unknown mesh extension"]);
    std::fs::create_dir_all(d.join("dir.obj")).unwrap();
    check(r#"Mesh(path: "dir.obj")"#, field, &["not a regular file"]);
    let fifo = d.join("fifo.stl");
    let ok = std::process::Command::new("mkfifo")
        .arg(&fifo)
        .status()
        .is_ok_and(|s| s.success());
    if ok {
        // Refused without opening (opening a FIFO with no writer would block).
        check(r#"Mesh(path: "fifo.stl")"#, field, &["not a regular file"]);
    }
    std::fs::write(d.join("empty.obj"), "# nothing\n").unwrap();
    check(
        r#"Mesh(path: "empty.obj")"#,
        field,
        &["empty.obj", "no triangles"],
    );
    std::fs::write(
        d.join("nan.obj"),
        "o a\nv 0 0 0\nv 1 0 0\nv nan 1 0\nf 1 2 3\n",
    )
    .unwrap();
    check(
        r#"Mesh(path: "nan.obj")"#,
        field,
        &["component \"a\"", "vertex 2", "not finite"],
    );
    std::fs::write(
        d.join("flat.obj"),
        "o a\nv 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n",
    )
    .unwrap();
    check(
        r#"Mesh(path: "flat.obj")"#,
        field,
        &["triangle 0", "degenerate"],
    );
    std::fs::write(d.join("cube.obj"), boxes_obj(&[([0.0; 3], [1.0; 3], "c")])).unwrap();
    check(
        r#"Mesh(path: "cube.obj", max_triangles: 10)"#,
        field,
        &["12 triangles", "limit of 10"],
    );
    check(
        r#"Mesh(path: "cube.obj", nodes: ["dish"])"#,
        field,
        &["no component", "\"dish\"", "\"c\""],
    );
    // Two components become two colliders named after them: a name that breaks the one name
    // rule (a comma, a quote, a space) is refused with the file and the component.
    std::fs::write(
        d.join("names.obj"),
        boxes_obj(&[
            ([0.0; 3], [1.0; 3], "ok"),
            ([2.0, 0.0, 0.0], [3.0, 1.0, 1.0], "a,b \"c"),
        ]),
    )
    .unwrap();
    check(
        r#"Mesh(path: "names.obj")"#,
        field,
        &["names.obj", "component \"a,b \\\"c\"", "a name is 1 to 64"],
    );
    std::fs::write(
        d.join("nobuf.gltf"),
        r#"{"asset": {"version": "2.0"}, "buffers": [{"uri": "gone.bin", "byteLength": 12}]}"#,
    )
    .unwrap();
    check(
        r#"Mesh(path: "nobuf.gltf")"#,
        field,
        &["buffer 0", "gone.bin", "missing"],
    );
    // An open mesh is a collision shape, not a mass source.
    std::fs::write(
        d.join("open.obj"),
        "o lid\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\n",
    )
    .unwrap();
    let tgt = r#"(name: "target", role: Target, mass_from_meshes: true,
           initial: (pos_m: (0.0, 0.0, 0.0)),
           parts: [Bus(name: "body", shape: Mesh(path: "open.obj", density_kg_m3: 10.0))])"#;
    let e = error(&d, &scene_text(&[tgt.into(), ball.clone()], "", 0.1));
    assert_eq!(
        e.field, "bodies.target.parts.body.shape.density_kg_m3",
        "{e}"
    );
    assert!(
        e.message.contains("cannot be a mass source") && e.message.contains("open.obj"),
        "{e}"
    );
}
