//! The safety monitor's full-geometry distances against analytic distances, and the
//! `collision_course` scene's contact against a straight-line prediction and momentum
//! conservation.
//!
//! References: closed-form box/box distances (face–face, rotated corner–face, edge–edge);
//! box/panel from the panel layout written in the scene; cone/slot clearances from the
//! meridional-plane geometry (cone and slot built with the same number of facets and aligned,
//! so the closest features are facet mid-lines and the distance is a 2-D segment distance);
//! linear momentum of the two bodies across the impact (differential gravity over the contact
//! is below 1e-5 N·s); for `contacts.csv`, the chaser's momentum change read from the recorded
//! `trajectory.csv` velocities; for the interval searches in contact, that a distance is never
//! negative (once a pair has touched, its closest approach is 0 and nothing is left to prove).

use nalgebra::Vector2;
use rpod::scene::load_scene_str;
use rpod::sim::Simulation;

/// Monitor distance for a two-body free-space scene.
fn distance(
    target_parts: &str,
    chaser: &str,
    chaser_parts: &str,
    ports: &str,
) -> (f64, String, String) {
    let text = format!(
        r#"Scene(name: "d", dt_s: 0.01, duration_s: 1.0, environment: FreeSpace, bodies: [
        (name: "target", role: Target, mass_kg: 800.0, inertia_kg_m2: (xx: 620.0, yy: 910.0, zz: 1080.0),
         initial: (pos_m: (0.0, 0.0, 0.0)), parts: [{target_parts}],
         ports: [(name: "dock", pos_m: (0.8, 0.0, 0.0), axis: (1.0, 0.0, 0.0))]),
        (name: "chaser", role: Chaser, mass_kg: 300.0, inertia_kg_m2: (xx: 110.0, yy: 140.0, zz: 160.0),
         initial: {chaser}, parts: [{chaser_parts}], ports: [{ports}]),
    ])"#
    );
    let loaded = load_scene_str(&text, "monitor", &[]).unwrap_or_else(|e| panic!("{e}"));
    let sim = Simulation::new(&loaded).unwrap_or_else(|e| panic!("{e}"));
    let mon = sim.monitor();
    let p = &mon.pairs[0];
    let (a, b) = mon.pair_names(p);
    (p.distance_m, a.to_string(), b.to_string())
}

const TOL: f64 = 1e-5;
const BIG_BOX: &str = r#"Bus(name: "bus", shape: Box(size_m: (2.0, 2.0, 2.0)))"#;
const UNIT_BOX: &str = r#"Bus(name: "bus", shape: Box(size_m: (1.0, 1.0, 1.0)))"#;

#[test]
fn val_monitor_box_box() {
    // Face to face: 3.7 − 1 − 0.5.
    let (d, ..) = distance(BIG_BOX, "(pos_m: (3.7, 0.3, -0.2))", UNIT_BOX, "");
    assert!((d - 2.2).abs() < TOL, "face-face {d}");
    // Chaser turned 45° about z: its vertical edge reaches 0.5·√2 towards the target.
    let (d, ..) = distance(
        BIG_BOX,
        "(pos_m: (3.7, 0.3, -0.2), attitude: EulerZyxDeg(yaw: 45.0, pitch: 0.0, roll: 0.0))",
        UNIT_BOX,
        "",
    );
    let want = 3.7 - 1.0 - 0.5 * 2f64.sqrt();
    assert!((d - want).abs() < TOL, "corner-face {d} vs {want}");
    // Diagonal offset: edge to edge, √(1.5² + 1.5²).
    let (d, ..) = distance(BIG_BOX, "(pos_m: (3.0, 3.0, 0.0))", UNIT_BOX, "");
    let want = (2.0 * 1.5f64 * 1.5).sqrt();
    assert!((d - want).abs() < TOL, "edge-edge {d} vs {want}");
}

#[test]
fn val_monitor_box_panel_names_the_panel() {
    // Wing along +y: boom 0.75–1.25 m, panels of 1.2 m with 0.05 m gaps:
    // panel1 1.25–2.45, panel2 2.50–3.70, panel3 3.75–4.95; panel thickness 0.03, normal x.
    let target = r#"Bus(name: "bus", shape: Box(size_m: (1.6, 1.5, 1.5))),
        SolarWing(name: "wing", root_m: (0.0, 0.75, 0.0), direction: PlusY, width_axis: PlusZ,
                  boom_length_m: 0.5, panel_count: 3, panel_size_m: (1.2, 1.0), panel_gap_m: 0.05)"#;
    // Chaser cube (y 2.6–3.6) in front of panel2: 2.0 − 0.5 − 0.015.
    let (d, a, b) = distance(target, "(pos_m: (2.0, 3.1, 0.0))", UNIT_BOX, "");
    assert!((d - 1.485).abs() < TOL, "box-panel {d}");
    assert_eq!(a, "target/wing.panel2");
    assert_eq!(b, "chaser/bus");
    // Cant the wing 30° about y: the panel's half-width 0.5 m now reaches 0.5·sin 30° in x.
    let canted = target.replace("panel_gap_m: 0.05)", "panel_gap_m: 0.05, cant_deg: 30.0)");
    let (d, a, _) = distance(&canted, "(pos_m: (2.0, 3.1, 0.0))", UNIT_BOX, "");
    let want = 2.0 - 0.5 - (0.5 * 30f64.to_radians().sin() + 0.015 * 30f64.to_radians().cos());
    assert!((d - want).abs() < TOL, "canted box-panel {d} vs {want}");
    assert_eq!(a, "target/wing.panel2");
}

/// Distance between 2-D segments.
fn seg_seg(a0: Vector2<f64>, a1: Vector2<f64>, b0: Vector2<f64>, b1: Vector2<f64>) -> f64 {
    let pt_seg = |p: Vector2<f64>, s0: Vector2<f64>, s1: Vector2<f64>| {
        let d = s1 - s0;
        let t = ((p - s0).dot(&d) / d.norm_squared()).clamp(0.0, 1.0);
        (p - (s0 + d * t)).norm()
    };
    // Non-intersecting segments: the minimum is at an endpoint.
    pt_seg(a0, b0, b1)
        .min(pt_seg(a1, b0, b1))
        .min(pt_seg(b0, a0, a1))
        .min(pt_seg(b1, a0, a1))
}

#[test]
fn val_monitor_cone_in_slot_clearances() {
    // Slot on the target port (x = 0.8, axis +x): throat 0.04 m at the bottom, mouth 0.15 m
    // at 0.20 m depth, 32 facets (same as the cone's hull) so facets align.
    let slot = r#"Bus(name: "bus", shape: Box(size_m: (1.6, 1.5, 1.5))),
        DockingSlot(name: "slot", port: "dock", mouth_radius_m: 0.15, throat_radius_m: 0.04, depth_m: 0.2, segments: 32)"#;
    let cone = r#"Bus(name: "bus", shape: Box(size_m: (1.0, 1.0, 1.0))),
        DockingCone(name: "cone", port: "dock", base_radius_m: 0.12, tip_radius_m: 0.03, length_m: 0.25)"#;
    let port = r#"(name: "dock", pos_m: (0.5, 0.0, 0.0), axis: (1.0, 0.0, 0.0))"#;
    let c = (std::f64::consts::PI / 32.0).cos(); // cone facet mid-line radius factor
    for s_tip in [0.005, 0.05, 0.12] {
        // Chaser turned 180° about z: its port faces −x; tip at x = 0.8 + s_tip.
        let x = 0.8 + s_tip + 0.25 + 0.5;
        let init = format!(
            "(pos_m: ({x}, 0.0, 0.0), attitude: EulerZyxDeg(yaw: 180.0, pitch: 0.0, roll: 0.0))"
        );
        let (d, a, b) = distance(slot, &init, cone, port);
        // Meridional plane: (axial distance from the slot bottom, radius).
        let cone_line = (
            Vector2::new(s_tip, 0.03 * c),
            Vector2::new(s_tip + 0.25, 0.12 * c),
        );
        let wall = (Vector2::new(0.0, 0.04), Vector2::new(0.2, 0.15));
        let lateral = seg_seg(cone_line.0, cone_line.1, wall.0, wall.1);
        let want = lateral.min(s_tip); // s_tip: tip face to the back plate
        println!(
            "tip {s_tip} m above the bottom: monitor {d:.7} m, analytic {want:.7} m ({a} | {b})"
        );
        assert!(
            (d - want).abs() < TOL,
            "cone/slot at s_tip = {s_tip}: {d} vs {want}"
        );
        assert_eq!(b, "chaser/cone");
        if want == s_tip {
            // The tip faces the funnel bottom: the back plate and the bus face are coplanar there.
            assert!(
                a == "target/slot.back" || a == "target/bus",
                "closest target part {a}"
            );
        } else {
            assert!(a.starts_with("target/slot.wall"), "closest target part {a}");
        }
    }
}

#[test]
fn val_collision_course_names_the_panel_and_time() {
    let loaded =
        rpod::scene::load_scene_file("scenes/examples/collision_course.ron".as_ref(), &[]).unwrap();
    let mut sim = Simulation::new(&loaded).unwrap();
    // Straight-line prediction from the initial world states: the chaser cube (half 0.3 m) and
    // the panel (half-thickness 0.015 m) share the target's x axis as normal.
    let t0 = sim.body("target").unwrap();
    let c0 = sim.body("chaser").unwrap();
    let n = t0.att * nalgebra::Vector3::x();
    let gap = (c0.pos_m - t0.pos_m).dot(&n) - 0.3 - 0.015;
    let closing = -(c0.vel_m_s - t0.vel_m_s).dot(&n);
    let t_pred = gap / closing;
    sim.step(sim.steps_for(t_pred - 0.2));
    let v_before = sim.body("chaser").unwrap().vel_m_s;
    sim.step(sim.steps_for(0.6));
    let v_after = sim.body("chaser").unwrap().vel_m_s;
    sim.step(sim.steps_for(60.0 - sim.t_s()));
    let cs = sim.contacts();
    let t_hit = cs.first_collision_s.expect("a collision");
    let (_, a, b) = &cs.collisions[0];
    assert_eq!(a, "target/wing_py.panel2");
    assert_eq!(b, "chaser/bus");
    // Differential gravity (≤ 3n²ρ ≈ 1.4e-5 m/s² at ρ ≈ 4.3 m) and the gravity-gradient turn of
    // the target move the contact by ≤ 6.5 mm over 27 s, i.e. 0.065 s at 0.1 m/s, plus one step.
    assert!(
        (t_hit - t_pred).abs() < 0.075,
        "contact at {t_hit} s, predicted {t_pred} s"
    );
    assert_eq!(cs.collisions.len(), 1, "{:?}", cs.collisions);
    // The recorded impulse is the momentum the chaser exchanged across the contact window;
    // differential gravity over the 0.6 s window adds ≤ 300·1.4e-5·0.6 ≈ 3e-3 N·s.
    let exchanged = (v_after - v_before).norm() * 300.0;
    let net = nalgebra::Vector3::from(cs.per_part["chaser/bus"].net_impulse_ns);
    let reaction = nalgebra::Vector3::from(cs.per_part["target/wing_py.panel2"].net_impulse_ns);
    assert!(
        (net + reaction).norm() < 1e-4 * net.norm(),
        "action {net:?} vs reaction {reaction:?}"
    );
    let impulse = net.norm();
    println!(
        "contact at {t_hit} s (predicted {t_pred:.3} s), impulse {impulse} N·s, m·Δv {exchanged} N·s"
    );
    assert!(exchanged > 1.0, "the impact exchanged only {exchanged} N·s");
    assert!(
        (impulse - exchanged).abs() < 3e-3 + 1e-4 * exchanged,
        "impulse {impulse} vs m·Δv {exchanged}"
    );
}

/// `contacts.csv` of a recorded `collision_course` run: the per-row impulse vectors on the
/// chaser's bus add up to the momentum the chaser exchanged (m·Δv between the recorded rows
/// that bracket the contact, read from `trajectory.csv`); the impulse magnitudes add up to at
/// least that (they sum per-step magnitudes) and to the `contact_end` event's impulse; each
/// row's force is its impulse over the row interval; and the pair is listed in contact only
/// between its `contact_start` and `contact_end` events.
#[test]
fn val_contacts_csv_impulses_add_up_to_the_momentum_exchanged() {
    let dir = std::env::temp_dir().join(format!("rpod_contacts_csv_{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let loaded =
        rpod::scene::load_scene_file("scenes/examples/collision_course.ron".as_ref(), &[]).unwrap();
    let mut sim = Simulation::new(&loaded).unwrap();
    sim.record_to(&dir).unwrap();
    sim.step(sim.steps_for(40.0));
    sim.finish().unwrap();

    let traj = std::fs::read_to_string(dir.join("trajectory.csv")).unwrap();
    let header: Vec<&str> = traj.lines().next().unwrap().split(',').collect();
    let col = |n: &str| header.iter().position(|h| *h == n).unwrap();
    let (ct, cvx, cvy, cvz) = (
        col("t_s"),
        col("chaser.vx_m_s"),
        col("chaser.vy_m_s"),
        col("chaser.vz_m_s"),
    );
    let rows: Vec<Vec<f64>> = traj
        .lines()
        .skip(1)
        .map(|l| {
            l.split(',')
                .map(|c| c.parse::<f64>().unwrap_or(f64::NAN))
                .collect()
        })
        .collect();
    let contacts = std::fs::read_to_string(dir.join("contacts.csv")).unwrap();
    let mut lines = contacts.lines();
    assert_eq!(
        lines.next().unwrap(),
        "t_s,a,b,docking,force_n,impulse_ns,jx_b_ns,jy_b_ns,jz_b_ns,in_contact"
    );
    let mut total = 0.0;
    let mut total_vec = nalgebra::Vector3::zeros();
    let (mut first, mut last) = (f64::INFINITY, 0.0f64);
    let mut in_contact_rows = Vec::new();
    for l in lines {
        let f: Vec<&str> = l.split(',').collect();
        assert_eq!(f.len(), 10, "{l}");
        assert_eq!(
            (f[1], f[2], f[3]),
            ("target/wing_py.panel2", "chaser/bus", "false")
        );
        let t: f64 = f[0].parse().unwrap();
        let force: f64 = f[4].parse().unwrap();
        let dj: f64 = f[5].parse().unwrap();
        // The row interval is the recording's: 10 steps of 0.01 s.
        let k = rows
            .iter()
            .position(|r| r[ct] == t)
            .expect("a trajectory row at t");
        let span = t - rows[k - 1][ct];
        assert!((force * span - dj).abs() <= 1e-12 * dj.max(1.0), "{l}");
        assert!(dj >= 0.0);
        total += dj;
        let jb = nalgebra::Vector3::new(
            f[6].parse::<f64>().unwrap(),
            f[7].parse::<f64>().unwrap(),
            f[8].parse::<f64>().unwrap(),
        );
        assert!(jb.norm() <= dj * (1.0 + 1e-12), "{l}");
        total_vec += jb;
        first = first.min(t);
        last = last.max(t);
        if f[9] == "true" {
            in_contact_rows.push(t);
        }
    }
    assert!(total > 0.0, "no contact impulse recorded");
    // Rows bracketing the contact: the row before the first contact row, and the last one.
    let i0 = rows.iter().position(|r| r[ct] == first).unwrap() - 1;
    let i1 = rows.iter().position(|r| r[ct] == last).unwrap();
    let v = |r: &Vec<f64>| nalgebra::Vector3::new(r[cvx], r[cvy], r[cvz]);
    let exchanged = 300.0 * (v(&rows[i1]) - v(&rows[i0]));
    let window = rows[i1][ct] - rows[i0][ct];
    println!(
        "contacts.csv: Σ|ΔJ| {total} N·s, Σ ΔJ_b {total_vec:?} N·s over {first}–{last} s; \
         m·Δv {exchanged:?} N·s over {window} s"
    );
    // Differential gravity over the window: ≤ 300 kg · 1.4e-5 m/s² · window.
    let gravity = 300.0 * 1.4e-5 * window;
    assert!(exchanged.norm() > 1.0);
    assert!(
        (total_vec - exchanged).norm() < gravity + 1e-4 * exchanged.norm(),
        "Σ ΔJ_b {total_vec:?} N·s vs m·Δv {exchanged:?} N·s"
    );
    assert!(total >= total_vec.norm() * (1.0 - 1e-12));
    // In contact exactly between the events.
    let events = std::fs::read_to_string(dir.join("events.jsonl")).unwrap();
    let ev: Vec<serde_json::Value> = events
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    let start = ev.iter().find(|e| e["kind"] == "contact_start").unwrap()["t_s"]
        .as_f64()
        .unwrap();
    let end = ev.iter().find(|e| e["kind"] == "contact_end").unwrap()["t_s"]
        .as_f64()
        .unwrap();
    let end_impulse = ev.iter().find(|e| e["kind"] == "contact_end").unwrap()["impulse_ns"]
        .as_f64()
        .unwrap();
    assert!((total - end_impulse).abs() <= 1e-12 * end_impulse);
    for t in in_contact_rows {
        assert!(
            t >= start && t < end,
            "in contact at {t} s, contact {start}–{end} s"
        );
    }
    // The last impulse came the step before `contact_end`; its row is the next one.
    assert!(first >= start && last + 0.01 + 1e-9 >= end && last < end + 0.1 + 1e-9);
    let _ = std::fs::remove_dir_all(&dir);
}

/// Once the cone has touched the slot (closest approach 0, `clearance_5cm` at its floor
/// −0.05 m), neither the monitor's closest-approach search nor the guarantee's interval search
/// may bisect again, however the chaser turns: here an `AlignPort` attitude law turns it in the
/// slot (the latch is refused at 24.4 s, the cone rebounds and reseats). Before the floor
/// (main at 22b466a) this window cost 14 439 monitor and 11 052 guarantee interval
/// evaluations, all proving that a distance is not below zero.
#[test]
fn val_monitor_no_interval_search_after_touching() {
    let law = "controllers=[Attitude(body: \"chaser\", target: \"target\", period_s: 0.1, \
        actuator: Saturated(max_force_n: (0.0, 0.0, 0.0), max_torque_nm: (1.0, 1.0, 1.0)), \
        params: (mode: AlignPort, natural_frequency_rad_s: 0.3, damping_ratio: 0.9))]";
    let loaded = rpod::scene::load_scene_file(
        std::path::Path::new(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/scenes/examples/docking_aligned.ron"
        )),
        &[law.to_string(), "duration_s=30.0".to_string()],
    )
    .unwrap_or_else(|e| panic!("{e}"));
    let mut sim = Simulation::new(&loaded).unwrap_or_else(|e| panic!("{e}"));
    sim.step(2430); // 24.3 s: first touch at 24.2 s
    let counts = |s: &serde_json::Value| {
        (
            s["monitor"]["interval_evaluations"]
                .as_u64()
                .unwrap_or(u64::MAX),
            s["guarantees"][0]["interval_evaluations"]
                .as_u64()
                .unwrap_or(u64::MAX),
            s["guarantees"][0]["worst_margin"]
                .as_f64()
                .unwrap_or(f64::NAN),
        )
    };
    let before = counts(&sim.summary());
    assert_eq!(before.2, -0.05, "the cone touched: margin at its floor");
    sim.step(570);
    let after = counts(&sim.summary());
    assert!(sim.t_s() > 29.99);
    assert_eq!(after.0, before.0, "monitor searched after touching");
    assert_eq!(after.1, before.1, "guarantee searched at its floor");
}
