//! An orthographic picture of every body's full geometry, drawn on the CPU (no GPU, no window,
//! no rendering crate): each collider of [`crate::scene::parts::expand_body`] — the shapes the
//! contacts and the monitor use — becomes triangles, projected along the view direction and
//! filled with a depth buffer, flat-shaded by the angle between the face and the view.
//!
//! It is a picture for a person or a video (Gymnasium's `render_mode="rgb_array"`), not a
//! measurement: the pixel size is `span_m / width`, cylinders and balls are drawn as
//! 24-sided prisms and 12 × 24 facet spheres, and parts thinner than a pixel may vanish.

use super::Simulation;
use crate::scene::parts::{PartCollider, Primitive, expand_body};
use crate::scene::{BodyRole, PartRole};
use bevy_rapier3d::parry;
use nalgebra::{Isometry3, Point3, Vector3};

/// Largest picture side, pixels (a count has a limit: 4096² RGB is 48 MiB).
pub const MAX_SIDE_PX: usize = 4096;

/// Facets around a cylinder, and rings × facets of a ball.
const ROUND_SEGMENTS: usize = 24;
const BALL_RINGS: usize = 12;

/// Background (deep space), sRGB.
pub const BACKGROUND_RGB: [u8; 3] = [8, 10, 22];

/// Where the picture is taken from.
#[derive(Debug, Clone, Copy)]
pub struct View {
    /// Direction the camera looks along, world frame (any length but zero).
    pub look_dir: Vector3<f64>,
    /// The world direction shown upward (projected square to `look_dir`).
    pub up: Vector3<f64>,
    /// World point at the picture's centre, m; `None`: the middle of every part, as seen.
    pub centre_m: Option<Vector3<f64>>,
    /// Width of the picture in the world, m; `None`: every body fits, with a 5 % border.
    pub span_m: Option<f64>,
}

/// Base colour of a part, sRGB 0–1: the viewer's palette (the target's bus gold foil, the
/// chaser's silver, panels blue, booms grey, the cone orange, the slot green).
pub fn part_rgb(body: BodyRole, role: PartRole) -> [f64; 3] {
    match role {
        PartRole::Bus => match body {
            BodyRole::Target => [0.85, 0.65, 0.2],
            BodyRole::Chaser => [0.8, 0.82, 0.86],
            BodyRole::Other => [0.6, 0.5, 0.45],
        },
        PartRole::Panel => [0.12, 0.2, 0.6],
        PartRole::Boom => [0.55, 0.55, 0.55],
        PartRole::Antenna => [0.95, 0.95, 0.92],
        PartRole::DockingCone => [0.9, 0.3, 0.15],
        PartRole::DockingSlot => [0.2, 0.75, 0.35],
        PartRole::Other => [0.7, 0.7, 0.7],
    }
}

/// Triangles of a primitive in its own frame, m.
pub fn primitive_triangles(p: &Primitive) -> Vec<[Point3<f64>; 3]> {
    let mut out = Vec::new();
    match p {
        Primitive::Cuboid { half_m } => {
            let c = |i: usize| {
                Point3::new(
                    if i & 1 == 0 { -half_m.x } else { half_m.x },
                    if i & 2 == 0 { -half_m.y } else { half_m.y },
                    if i & 4 == 0 { -half_m.z } else { half_m.z },
                )
            };
            for [a, b, cc, d] in [
                [0, 1, 3, 2],
                [4, 5, 7, 6],
                [0, 1, 5, 4],
                [2, 3, 7, 6],
                [0, 2, 6, 4],
                [1, 3, 7, 5],
            ] {
                out.push([c(a), c(b), c(cc)]);
                out.push([c(a), c(cc), c(d)]);
            }
        }
        Primitive::Cylinder {
            radius_m,
            half_length_m,
        } => {
            let ring = |k: usize, y: f64| {
                let phi = std::f64::consts::TAU * k as f64 / ROUND_SEGMENTS as f64;
                Point3::new(radius_m * phi.cos(), y, radius_m * phi.sin())
            };
            let (lo, hi) = (-half_length_m, *half_length_m);
            for k in 0..ROUND_SEGMENTS {
                let (a0, a1) = (ring(k, lo), ring(k + 1, lo));
                let (b0, b1) = (ring(k, hi), ring(k + 1, hi));
                out.push([a0, a1, b1]);
                out.push([a0, b1, b0]);
                out.push([Point3::new(0.0, lo, 0.0), a0, a1]);
                out.push([Point3::new(0.0, hi, 0.0), b0, b1]);
            }
        }
        Primitive::Ball { radius_m } => {
            let at = |i: usize, k: usize| {
                let theta = std::f64::consts::PI * i as f64 / BALL_RINGS as f64;
                let phi = std::f64::consts::TAU * k as f64 / ROUND_SEGMENTS as f64;
                Point3::new(
                    radius_m * theta.sin() * phi.cos(),
                    radius_m * theta.cos(),
                    radius_m * theta.sin() * phi.sin(),
                )
            };
            for i in 0..BALL_RINGS {
                for k in 0..ROUND_SEGMENTS {
                    out.push([at(i, k), at(i + 1, k), at(i + 1, k + 1)]);
                    out.push([at(i, k), at(i + 1, k + 1), at(i, k + 1)]);
                }
            }
        }
        Primitive::ConvexHull { points_m } => {
            let pts: Vec<_> = points_m.iter().map(|p| super::conv::v(&p.coords)).collect();
            if let Ok((v, tris)) = parry::transformation::try_convex_hull(&pts) {
                let p = |i: u32| {
                    v.get(i as usize)
                        .map(|q| Point3::new(f64::from(q.x), f64::from(q.y), f64::from(q.z)))
                };
                for [a, b, c] in tris {
                    if let (Some(a), Some(b), Some(c)) = (p(a), p(b), p(c)) {
                        out.push([a, b, c]);
                    }
                }
            }
        }
        Primitive::Mesh { mesh, .. } => {
            out.extend((0..mesh.triangles.len()).map(|k| mesh.corners(k)))
        }
    }
    out
}

/// One body's geometry for pictures: triangles in the body frame with their colours.
struct BodyMesh {
    name: String,
    com_body_m: Vector3<f64>,
    triangles: Vec<([Point3<f64>; 3], [f64; 3])>,
}

/// A camera: look direction f, right r, up u (world), the picture's centre (r, u coordinates)
/// and width, m, and the body poses.
struct Frame {
    f: Vector3<f64>,
    r: Vector3<f64>,
    u: Vector3<f64>,
    cr: f64,
    cu: f64,
    span: f64,
    poses: Vec<Isometry3<f64>>,
}

/// The triangles of every body of a scene, built once (see [`Snapshot::render`]).
pub struct Snapshot {
    bodies: Vec<BodyMesh>,
}

impl Snapshot {
    /// Expands every body of the simulation's scene into coloured triangles.
    pub fn new(sim: &Simulation) -> Self {
        let bodies = sim
            .scene
            .bodies
            .iter()
            .map(|b| {
                let parts: Vec<PartCollider> = expand_body(b);
                let mut triangles = Vec::new();
                for pc in &parts {
                    let rgb = part_rgb(b.role, pc.role);
                    for t in primitive_triangles(&pc.shape) {
                        triangles.push((t.map(|p| pc.pose_body * p), rgb));
                    }
                }
                BodyMesh {
                    name: b.name.clone(),
                    com_body_m: Vector3::from(b.com_m),
                    triangles,
                }
            })
            .collect();
        Self { bodies }
    }

    /// The camera axes, the picture's centre and width, and the body poses now.
    fn frame(
        &self,
        sim: &Simulation,
        width: usize,
        height: usize,
        view: &View,
    ) -> Result<Frame, String> {
        if !(1..=MAX_SIDE_PX).contains(&width) || !(1..=MAX_SIDE_PX).contains(&height) {
            return Err(format!(
                "width and height: 1 to {MAX_SIDE_PX} pixels, got {width} × {height}"
            ));
        }
        let f = view
            .look_dir
            .try_normalize(1e-12)
            .filter(|v| v.iter().all(|c| c.is_finite()))
            .ok_or("look_dir: a finite non-zero vector")?;
        let r = f
            .cross(&view.up)
            .try_normalize(1e-9)
            .filter(|v| v.iter().all(|c| c.is_finite()))
            .ok_or("up: a finite vector not parallel to look_dir")?;
        let u = r.cross(&f);
        // Body poses now (body frame → world).
        let poses: Vec<Isometry3<f64>> = self
            .bodies
            .iter()
            .map(|b| {
                sim.body(&b.name)
                    .map(|s| s.body_pose(&b.com_body_m))
                    .unwrap_or_else(Isometry3::identity)
            })
            .collect();
        // The picture-plane box of every vertex now.
        let (mut lo_r, mut hi_r, mut lo_u, mut hi_u) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
        for (b, pose) in self.bodies.iter().zip(&poses) {
            for (tri, _) in &b.triangles {
                for p in tri {
                    let w = (pose * p).coords;
                    let (x, y) = (w.dot(&r), w.dot(&u));
                    lo_r = lo_r.min(x);
                    hi_r = hi_r.max(x);
                    lo_u = lo_u.min(y);
                    hi_u = hi_u.max(y);
                }
            }
        }
        let empty = lo_r > hi_r;
        let aspect = height as f64 / width as f64;
        let (cr, cu) = match view.centre_m {
            Some(c) => {
                if !c.iter().all(|x| x.is_finite()) {
                    return Err("centre_m: finite numbers".into());
                }
                (c.dot(&r), c.dot(&u))
            }
            None if empty => (0.0, 0.0),
            None => (0.5 * (lo_r + hi_r), 0.5 * (lo_u + hi_u)),
        };
        let span = match view.span_m {
            Some(s) if s.is_finite() && s > 0.0 && s < 1e15 => s,
            Some(s) => return Err(format!("span_m: a positive finite width, got {s}")),
            None if empty => 1.0,
            None => {
                let need_r = (hi_r - cr).abs().max((cr - lo_r).abs());
                let need_u = (hi_u - cu).abs().max((cu - lo_u).abs());
                (2.0 * need_r).max(2.0 * need_u / aspect).max(1e-6) * 1.05
            }
        };
        Ok(Frame {
            f,
            r,
            u,
            cr,
            cu,
            span,
            poses,
        })
    }

    /// The view `render` would use with `view`: the world point at the picture's centre (on
    /// the plane through the world origin square to the view) and the width, m.
    pub fn fit(
        &self,
        sim: &Simulation,
        width: usize,
        height: usize,
        view: &View,
    ) -> Result<(Vector3<f64>, f64), String> {
        let fr = self.frame(sim, width, height, view)?;
        Ok((fr.r * fr.cr + fr.u * fr.cu, fr.span))
    }

    /// The picture now, `height` rows of `width` RGB pixels (row-major, top row first).
    /// Errors: a side of 0 or above [`MAX_SIDE_PX`], a view direction or up vector that is
    /// zero, non-finite or parallel, a span that is not a positive finite number.
    pub fn render(
        &self,
        sim: &Simulation,
        width: usize,
        height: usize,
        view: &View,
    ) -> Result<Vec<u8>, String> {
        let Frame {
            f,
            r,
            u,
            cr,
            cu,
            span,
            poses,
        } = self.frame(sim, width, height, view)?;
        let px = width as f64 / span;
        let mut rgb = vec![0u8; width * height * 3];
        for c in rgb.chunks_exact_mut(3) {
            c.copy_from_slice(&BACKGROUND_RGB);
        }
        let mut depth = vec![f64::INFINITY; width * height];
        // Light from over the camera's left shoulder.
        let light = (f - 0.4 * r + 0.5 * u).normalize();
        for (b, pose) in self.bodies.iter().zip(&poses) {
            for (tri, base) in &b.triangles {
                let w = tri.map(|p| (pose * p).coords);
                let n = (w[1] - w[0]).cross(&(w[2] - w[0]));
                let Some(n) = n.try_normalize(1e-18) else {
                    continue;
                };
                let shade = 0.3 + 0.7 * n.dot(&light).abs();
                let colour = base.map(|c| (c * shade * 255.0).round().clamp(0.0, 255.0) as u8);
                // Picture coordinates: x to the right, y down, in pixels; depth along f.
                let s = w.map(|p| {
                    (
                        (p.dot(&r) - cr) * px + 0.5 * width as f64,
                        0.5 * height as f64 - (p.dot(&u) - cu) * px,
                        p.dot(&f),
                    )
                });
                fill_triangle(&s, width, height, &mut depth, &mut rgb, colour);
            }
        }
        Ok(rgb)
    }
}

/// Fills a projected triangle (x, y in pixels, depth) where it is nearer than the depth buffer
/// (pixel centres inside or on an edge).
fn fill_triangle(
    s: &[(f64, f64, f64); 3],
    width: usize,
    height: usize,
    depth: &mut [f64],
    rgb: &mut [u8],
    colour: [u8; 3],
) {
    if s.iter()
        .any(|p| !(p.0.is_finite() && p.1.is_finite() && p.2.is_finite()))
    {
        return;
    }
    let area = (s[1].0 - s[0].0) * (s[2].1 - s[0].1) - (s[2].0 - s[0].0) * (s[1].1 - s[0].1);
    if area.abs() < 1e-12 {
        return;
    }
    let x0 = s
        .iter()
        .map(|p| p.0)
        .fold(f64::MAX, f64::min)
        .floor()
        .max(0.0);
    let x1 = s
        .iter()
        .map(|p| p.0)
        .fold(f64::MIN, f64::max)
        .ceil()
        .min(width as f64);
    let y0 = s
        .iter()
        .map(|p| p.1)
        .fold(f64::MAX, f64::min)
        .floor()
        .max(0.0);
    let y1 = s
        .iter()
        .map(|p| p.1)
        .fold(f64::MIN, f64::max)
        .ceil()
        .min(height as f64);
    if x0 >= x1 || y0 >= y1 {
        return;
    }
    for y in (y0 as usize)..(y1 as usize) {
        let py = y as f64 + 0.5;
        for x in (x0 as usize)..(x1 as usize) {
            let pxc = x as f64 + 0.5;
            let edge = |a: &(f64, f64, f64), b: &(f64, f64, f64)| {
                (b.0 - a.0) * (py - a.1) - (pxc - a.0) * (b.1 - a.1)
            };
            let w0 = edge(&s[1], &s[2]) / area;
            let w1 = edge(&s[2], &s[0]) / area;
            let w2 = edge(&s[0], &s[1]) / area;
            if w0 < 0.0 || w1 < 0.0 || w2 < 0.0 {
                continue;
            }
            let z = w0 * s[0].2 + w1 * s[1].2 + w2 * s[2].2;
            let k = y * width + x;
            if z < depth[k] {
                depth[k] = z;
                rgb[3 * k..3 * k + 3].copy_from_slice(&colour);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The triangles of a box cover its six faces: their areas add up to 2(ab + bc + ca), and
    /// every vertex lies on the box.
    #[test]
    fn val_snapshot_cuboid_triangles_cover_its_faces() {
        let half = Vector3::new(0.5, 0.75, 1.0);
        let t = primitive_triangles(&Primitive::Cuboid { half_m: half });
        let area: f64 = t
            .iter()
            .map(|[a, b, c]| 0.5 * (b - a).cross(&(c - a)).norm())
            .sum();
        let (a, b, c) = (2.0 * half.x, 2.0 * half.y, 2.0 * half.z);
        assert!(
            (area - 2.0 * (a * b + b * c + c * a)).abs() < 1e-12,
            "{area}"
        );
        for p in t.iter().flatten() {
            assert!(
                (p.x.abs() - half.x).abs() < 1e-15
                    || (p.y.abs() - half.y).abs() < 1e-15
                    || (p.z.abs() - half.z).abs() < 1e-15
            );
        }
    }
}
