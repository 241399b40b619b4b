//! Plume impingement load: the force and moment a firing jet's exhaust puts on the parts it
//! strikes. Bevy-free, f64; the ray casts against the parts' shapes are the caller's
//! ([`impingement`] takes them as a closure; `sim::plume::plume_loads` casts them with parry).
//!
//! **Model.** The exhaust of a jet of thrust F carries the momentum flux F. Inside the plume
//! cone (half-angle α, apex at the nozzle, axis the exhaust direction) it is spread uniformly
//! over solid angle and falls off with the square of the distance r from the nozzle:
//!
//! ```text
//!   p(r, θ) = F / (Ω r²)   for θ ≤ α   (0 outside, and beyond the plume's length L),
//!   Ω = 2π (1 − cos α)     (the cone's solid angle),
//! ```
//!
//! so the flux through any sphere about the nozzle (r ≤ L) is ∫ p r² dΩ = F. A surface absorbs
//! the momentum that reaches it (full accommodation: the gas leaves with no momentum), so a
//! surface element dA at distance r, its normal at angle β to the flow, receives the force
//! p·cos β·dA along the flow — F·dΩ/Ω along the ray, dΩ the solid angle it subtends. A part
//! in the shadow of another (along the ray) receives nothing. This is the simplest model with
//! the stated fall-off; real plumes are not uniform (a cos^n θ profile) and reflect part of
//! their momentum.
//!
//! **Discretisation.** The cone is cut into `rings` × `sectors` cells of equal solid angle
//! (rings equally spaced in cos θ, sectors in φ), each carried by the ray through its centre
//! (the midpoint in cos θ and φ) with the flux F/(rings·sectors). A cell cut by a part's edge
//! is counted whole or not at all: the force is exact to the flux of the cells the edges cross
//! (`tests/val_plume.rs` bounds that against the closed form of a flat plate).

use nalgebra::Vector3;

/// Default rings of the ray grid.
pub const DEFAULT_RINGS: usize = 24;
/// Default sectors of the ray grid.
pub const DEFAULT_SECTORS: usize = 48;

/// One ray of the grid: its unit direction in the cone's frame (axis +z) and its share of
/// the jet's momentum flux.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PlumeRay {
    /// Unit direction, cone frame (axis +z).
    pub dir: Vector3<f64>,
    /// Share of the flux (1/(rings·sectors)).
    pub share: f64,
}

/// The equal-solid-angle ray grid of a cone of half-angle `half_angle_rad` (see the module
/// docs). `rings` and `sectors` are at least 1.
pub fn cone_rays(half_angle_rad: f64, rings: usize, sectors: usize) -> Vec<PlumeRay> {
    let (rings, sectors) = (rings.max(1), sectors.max(1));
    let share = 1.0 / (rings * sectors) as f64;
    let c_min = half_angle_rad.cos();
    let mut out = Vec::with_capacity(rings * sectors);
    for i in 0..rings {
        let c = 1.0 - (1.0 - c_min) * (i as f64 + 0.5) / rings as f64;
        let s = (1.0 - c * c).max(0.0).sqrt();
        for j in 0..sectors {
            let phi = std::f64::consts::TAU * (j as f64 + 0.5) / sectors as f64;
            out.push(PlumeRay {
                dir: Vector3::new(s * phi.cos(), s * phi.sin(), c),
                share,
            });
        }
    }
    out
}

/// The load on one struck part.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PartLoad {
    /// The part (the index the caller's ray cast returns).
    pub part: usize,
    /// Force, in the frame of `apex` and `axis`, N.
    pub force_n: Vector3<f64>,
    /// Moment about the reference point, same frame, N·m.
    pub moment_nm: Vector3<f64>,
}

/// The load of one jet's plume on the parts it strikes: thrust `thrust_n`, nozzle `apex`,
/// unit exhaust `axis` (any frame), plume length `length_m`; `cast(k, origin, dir, max_m)`
/// returns the first part ray `k` of `rays` (from `origin` along unit `dir`, the ray's
/// direction in the frame of `axis`) strikes within `max_m` (distance m, part index); it is
/// called once per ray, in order. Moments are about `about`. Parts in index order, each once.
#[allow(clippy::too_many_arguments)] // the jet, its cone, the grid and the ray cast
pub fn impingement(
    thrust_n: f64,
    apex: &Vector3<f64>,
    axis: &Vector3<f64>,
    rays: &[PlumeRay],
    length_m: f64,
    about: &Vector3<f64>,
    mut cast: impl FnMut(usize, &Vector3<f64>, &Vector3<f64>, f64) -> Option<(f64, usize)>,
) -> Vec<PartLoad> {
    let z = axis.normalize();
    let (x, y) = crate::scene::parts::perpendicular_basis(&z);
    let mut out: Vec<PartLoad> = Vec::new();
    for (k, r) in rays.iter().enumerate() {
        let d = x * r.dir.x + y * r.dir.y + z * r.dir.z;
        let Some((toi, part)) = cast(k, apex, &d, length_m) else {
            continue;
        };
        let f = d * (thrust_n * r.share);
        let m = (apex + d * toi - about).cross(&f);
        match out.iter_mut().find(|l| l.part == part) {
            Some(l) => {
                l.force_n += f;
                l.moment_nm += m;
            }
            None => out.push(PartLoad {
                part,
                force_n: f,
                moment_nm: m,
            }),
        }
    }
    out.sort_by_key(|l| l.part);
    out
}

#[cfg(test)]
mod tests {
    //! Reference: the flux through the whole cone is F, and a plate covering the cone's
    //! section normal to its axis takes the axial force F·⟨cos θ⟩ = F(1 + cos α)/2 (cos θ is
    //! uniform on [cos α, 1] over equal solid angles; the midpoint rule is exact for it).
    use super::*;

    #[test]
    fn val_plume_load_full_cover_plate_takes_the_mean_cosine() {
        let a = 20f64.to_radians();
        let rays = cone_rays(a, 24, 48);
        let total: f64 = rays.iter().map(|r| r.share).sum();
        assert!((total - 1.0).abs() < 1e-12);
        // A plane z = 2 m wider than the cone: every ray strikes it.
        let loads = impingement(
            10.0,
            &Vector3::zeros(),
            &Vector3::z(),
            &rays,
            5.0,
            &Vector3::new(0.0, 0.0, 2.0),
            |_, o, d, max| {
                let t = (2.0 - o.z) / d.z;
                (t > 0.0 && t <= max).then_some((t, 0))
            },
        );
        assert_eq!(loads.len(), 1);
        let f = loads[0].force_n;
        assert!((f.z - 10.0 * (1.0 + a.cos()) / 2.0).abs() < 1e-12, "{f}");
        assert!(f.x.abs() < 1e-12 && f.y.abs() < 1e-12, "{f}");
        // Symmetric about the axis: no moment about the plate's centre.
        assert!(loads[0].moment_nm.norm() < 1e-12, "{}", loads[0].moment_nm);
    }
}
