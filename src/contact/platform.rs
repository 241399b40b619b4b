//! The attenuation platform of a soft-capture docking system (f64, Bevy-free): a capture ring,
//! a rigid body, carried by six (or any number of) spring–damper legs between attach points on
//! the chaser and on the ring (a Stewart/hexapod platform).
//!
//! # Frames
//! - **Platform frame P**: the chaser's docking port frame, origin at the port, +z along the
//!   port axis (out of the chaser, toward the target). The base attach points b_i are given in P.
//! - **Ring frame R**: origin at the ring's centre of mass, +z along the ring's axis. At the
//!   neutral pose R is P translated by `height_m` along +z. The ring attach points r_i are
//!   given in R.
//!
//! States and forces are in the world frame (any inertial frame); [`RigidState`] holds the
//! ring's pose and velocities there, and [`Base`] the pose and velocities of P.
//!
//! # Legs
//! Leg i runs from b_i (on the chaser) to r_i (on the ring); its length L_i = |r_i − b_i| (world),
//! its neutral length L0_i the length at the neutral pose, its stroke s_i = L_i − L0_i
//! (positive: extended) and its stroke rate ṡ_i = (v(r_i) − v(b_i))·u_i with u_i the unit vector
//! from b_i to r_i. Its axial force, positive in compression (pushing the ring away from the
//! chaser along u_i), is
//!
//! ```text
//! f_i = F_pre − k·s_i − c·ṡ_i − k_stop·(s_i − s_max)   for s_i > s_max   (extension stop)
//!                             + k_stop·(s_min − s_i)   for s_i < s_min   (compression stop)
//! ```
//!
//! with F_pre the preload (`preload_n`, ≥ 0: a spring that pushes the ring out; with s_max = 0
//! the ring rests on its extension stops, as flight soft-capture rings do, until a load beyond
//! the preload arrives), k the stiffness, c the damping and k_stop the stiffness of the hard stops
//! (elastic, no damping: a stop conserves energy, the legs' dampers are what dissipate). The
//! ring gets f_i·u_i at r_i, the chaser −f_i·u_i at b_i, so the pair's momentum is conserved.
//!
//! # Energy
//! The potential of leg i is ½k·s² − F_pre·s (+ ½k_stop·(s − s_max)² beyond a stop); the
//! dampers dissipate Σ c·ṡ_i² (W). [`Platform::step_fixed_base`] integrates both, so that the
//! mechanical energy plus what was dissipated is constant up to the integration error
//! (`tests/val_soft_capture.rs`).
//!
//! # Integration
//! Kick–drift–kick (velocity Verlet, the second half-kick's damping from predicted end-of-step
//! velocities so that it stays second order) in sub-steps h ≤ T/`substeps_per_period` with
//! T = 2π·√(m_min/K_max), K_max = n·(k + k_stop) the stiffest the legs can be together and
//! m_min = min(m, J_min/ρ²) the smallest effective mass of the ring at its attach points
//! (ρ the largest attach radius), and h ≤ m_min/(5·n·c) (a fifth of the fastest damping time
//! constant; the damping is explicit). The rotation drifts
//! torque-free by [`crate::math::rigid::rotate_rk4`], as the docking contact does.

use crate::math::rigid::rotate_rk4;
use nalgebra::{Isometry3, Matrix3, Translation3, UnitQuaternion, Vector3};
use serde::{Deserialize, Serialize};

/// Where the legs attach.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub enum LegLayout {
    /// The 6-6 Stewart layout: three pairs of base points at 0°, 120°, 240° (each pair at
    /// ±`base_pair_half_angle_deg` about its centre, radius `base_radius_m`, z = 0 in P) and
    /// three pairs of ring points at 60°, 180°, 300° (±`ring_pair_half_angle_deg`, radius
    /// `ring_radius_m`, z = 0 in R). The base point at c − β joins the ring point at
    /// c − 60° + γ, the one at c + β the ring point at c + 60° − γ (c = 0°, 120°, 240°), so
    /// neighbouring legs mirror each other and an axial load does not twist the ring. Angles
    /// are measured about +z from +x of each frame.
    Hexapod {
        /// Radius of the base attach points in P, m.
        base_radius_m: f64,
        /// Radius of the ring attach points in R, m.
        ring_radius_m: f64,
        /// Half the angle between the two base points of a pair, degrees.
        base_pair_half_angle_deg: f64,
        /// Half the angle between the two ring points of a pair, degrees.
        ring_pair_half_angle_deg: f64,
    },
    /// Explicit attach points: (base point in P, ring point in R) per leg, m.
    Legs(Vec<([f64; 3], [f64; 3])>),
}

/// The platform's design, in RON as in `tests/val_soft_capture.rs`; a scene carries it in
/// `docking.mechanism: SoftCapture((platform: (...), ...))` ([`crate::scene::SoftCaptureSpec`]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PlatformSpec {
    /// Ring mass, kg.
    pub ring_mass_kg: f64,
    /// Ring principal moments of inertia about its centre of mass, ring frame (x, y, z), kg·m².
    pub ring_inertia_kg_m2: [f64; 3],
    /// Ring centre above the port along +z at the neutral pose, m.
    pub height_m: f64,
    /// Attach points.
    pub layout: LegLayout,
    /// Leg stiffness k, N/m.
    pub stiffness_n_m: f64,
    /// Leg damping c, N·s/m.
    pub damping_n_s_m: f64,
    /// Compression limit s_min (a negative stroke), m.
    pub stroke_min_m: f64,
    /// Extension limit s_max (≥ 0), m.
    pub stroke_max_m: f64,
    /// Stiffness of the hard stops beyond the stroke limits, N/m.
    pub stop_stiffness_n_m: f64,
    /// Preload F_pre (≥ 0), N: each leg's force at zero stroke, pushing the ring out.
    #[serde(default)]
    pub preload_n: f64,
    /// Sub-steps per period of the stiffest mode (see the module notes).
    #[serde(default = "default_substeps")]
    pub substeps_per_period: u32,
}

fn default_substeps() -> u32 {
    40
}

/// A bad platform description: the field (relative to the platform) and why.
#[derive(Debug, Clone, PartialEq)]
pub struct PlatformError {
    /// Field path relative to the platform, e.g. `stiffness_n_m` or `layout.Legs[2]`.
    pub field: String,
    /// Why.
    pub why: String,
}

impl std::fmt::Display for PlatformError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}: {}", self.field, self.why)
    }
}

fn err(field: &str, why: impl Into<String>) -> PlatformError {
    PlatformError {
        field: field.to_string(),
        why: why.into(),
    }
}

/// One leg's geometry and neutral length.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Leg {
    /// Attach point on the chaser, platform frame P, m.
    pub base_p_m: Vector3<f64>,
    /// Attach point on the ring, ring frame R, m.
    pub ring_r_m: Vector3<f64>,
    /// Length at the neutral pose, m.
    pub neutral_length_m: f64,
}

/// A leg at one configuration.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct LegState {
    /// Length, m.
    pub length_m: f64,
    /// Stroke s = L − L0, m (positive extended).
    pub stroke_m: f64,
    /// Stroke rate, m/s.
    pub stroke_rate_m_s: f64,
    /// Axial force, N (positive in compression: pushing the ring away from the chaser).
    pub force_n: f64,
    /// Unit vector from the base attach point to the ring attach point, world.
    pub axis: Vector3<f64>,
    /// Ring attach point, world, m.
    pub ring_point_m: Vector3<f64>,
    /// Base attach point, world, m.
    pub base_point_m: Vector3<f64>,
}

/// The platform frame's motion (the chaser port), world frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Base {
    /// Pose of P in the world.
    pub pose: Isometry3<f64>,
    /// Velocity of P's origin, m/s.
    pub vel_m_s: Vector3<f64>,
    /// Angular velocity of P, rad/s.
    pub omega_rad_s: Vector3<f64>,
}

impl Base {
    /// A base at rest at `pose`.
    pub fn at_rest(pose: Isometry3<f64>) -> Self {
        Base {
            pose,
            vel_m_s: Vector3::zeros(),
            omega_rad_s: Vector3::zeros(),
        }
    }
    fn point_vel(&self, p: &Vector3<f64>) -> Vector3<f64> {
        self.vel_m_s + self.omega_rad_s.cross(&(p - self.pose.translation.vector))
    }
}

/// A rigid body's state (the ring's, or the chaser's), world frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RigidState {
    /// Centre of mass, m.
    pub pos_m: Vector3<f64>,
    /// Velocity of the centre of mass, m/s.
    pub vel_m_s: Vector3<f64>,
    /// Attitude (body frame → world; for the ring, R → world).
    pub att: UnitQuaternion<f64>,
    /// Angular velocity, rad/s.
    pub omega_rad_s: Vector3<f64>,
}

/// The chaser as a free rigid body carrying the platform ([`Platform::step_free_base`]);
/// built by [`Carrier::new`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Carrier {
    /// Mass, kg.
    pub mass_kg: f64,
    /// Inertia about the centre of mass, body frame, kg·m².
    pub inertia_kg_m2: Matrix3<f64>,
    /// Its inverse, 1/(kg·m²).
    inertia_inv: Matrix3<f64>,
    /// The platform frame P in the body frame (whose origin is the centre of mass).
    pub port_body: Isometry3<f64>,
}

impl Carrier {
    /// A carrier of positive finite mass and a symmetric positive-definite inertia (else an
    /// error naming `mass_kg` or `inertia_kg_m2`).
    pub fn new(
        mass_kg: f64,
        inertia_kg_m2: Matrix3<f64>,
        port_body: Isometry3<f64>,
    ) -> Result<Self, PlatformError> {
        positive("mass_kg", mass_kg)?;
        let symmetric =
            (inertia_kg_m2 - inertia_kg_m2.transpose()).norm() <= 1e-12 * inertia_kg_m2.norm();
        let inertia_inv = inertia_kg_m2
            .try_inverse()
            .filter(|_| {
                symmetric
                    && inertia_kg_m2.iter().all(|x| x.is_finite())
                    && inertia_kg_m2.symmetric_eigenvalues().min() > 0.0
            })
            .ok_or_else(|| err("inertia_kg_m2", "must be symmetric positive definite"))?;
        Ok(Carrier {
            mass_kg,
            inertia_kg_m2,
            inertia_inv,
            port_body,
        })
    }

    /// The platform frame's motion with the chaser in state `s`.
    pub fn base(&self, s: &RigidState) -> Base {
        let pose = Isometry3::from_parts(Translation3::from(s.pos_m), s.att) * self.port_body;
        let p = pose.translation.vector;
        Base {
            pose,
            vel_m_s: s.vel_m_s + s.omega_rad_s.cross(&(p - s.pos_m)),
            omega_rad_s: s.omega_rad_s,
        }
    }

    /// The chaser's kinetic energy, J.
    pub fn kinetic_energy_j(&self, s: &RigidState) -> f64 {
        let w_b = s.att.inverse() * s.omega_rad_s;
        0.5 * self.mass_kg * s.vel_m_s.norm_squared() + 0.5 * w_b.dot(&(self.inertia_kg_m2 * w_b))
    }
}

/// External wrenches held over a step: (force on the ring at its centre of mass, moment on
/// it, force on the chaser at its centre of mass, moment on it), world, N and N·m.
pub type HeldWrenches = [Vector3<f64>; 4];

/// The legs' loads at one configuration.
#[derive(Debug, Clone, PartialEq)]
pub struct PlatformLoads {
    /// Per leg.
    pub legs: Vec<LegState>,
    /// Total leg force on the ring, world, N.
    pub force_on_ring_n: Vector3<f64>,
    /// Total leg moment on the ring about its centre of mass, world, N·m.
    pub moment_on_ring_nm: Vector3<f64>,
    /// Total leg force on the chaser (= −force_on_ring_n), world, N.
    pub force_on_base_n: Vector3<f64>,
    /// Total leg moment on the chaser about the port origin, world, N·m.
    pub moment_on_base_nm: Vector3<f64>,
    /// Power dissipated by the dampers, W (≥ 0).
    pub damper_power_w: f64,
    /// Potential energy stored in the legs (springs, preload, stops), J.
    pub potential_j: f64,
}

/// A validated platform.
#[derive(Debug, Clone, PartialEq)]
pub struct Platform {
    /// The description it was built from.
    pub spec: PlatformSpec,
    /// The legs.
    pub legs: Vec<Leg>,
    /// Ring inertia (ring frame), kg·m².
    pub inertia: Matrix3<f64>,
    /// Its inverse.
    pub inertia_inv: Matrix3<f64>,
    /// Largest sub-step with the base fixed, s.
    pub h_max_s: f64,
    /// Smallest effective mass of the ring at its attach points, min(m, J_min/ρ²), kg.
    pub ring_min_mass_kg: f64,
}

fn positive(field: &str, v: f64) -> Result<(), PlatformError> {
    if v.is_finite() && v > 0.0 {
        Ok(())
    } else {
        Err(err(
            field,
            format!("must be a positive finite number, got {v}"),
        ))
    }
}

impl Platform {
    /// Checks a description and computes the legs' neutral lengths and the sub-step bound.
    pub fn new(spec: &PlatformSpec) -> Result<Self, PlatformError> {
        positive("ring_mass_kg", spec.ring_mass_kg)?;
        for (i, j) in spec.ring_inertia_kg_m2.iter().enumerate() {
            positive(&format!("ring_inertia_kg_m2[{i}]"), *j)?;
        }
        let [jx, jy, jz] = spec.ring_inertia_kg_m2;
        if jx + jy < jz || jy + jz < jx || jz + jx < jy {
            return Err(err(
                "ring_inertia_kg_m2",
                "principal moments violate the triangle inequality (no rigid body has them)",
            ));
        }
        positive("height_m", spec.height_m)?;
        positive("stiffness_n_m", spec.stiffness_n_m)?;
        positive("damping_n_s_m", spec.damping_n_s_m)?;
        positive("stop_stiffness_n_m", spec.stop_stiffness_n_m)?;
        if !(spec.stroke_min_m.is_finite() && spec.stroke_min_m < 0.0) {
            return Err(err(
                "stroke_min_m",
                format!(
                    "the compression limit must be a negative finite stroke, got {}",
                    spec.stroke_min_m
                ),
            ));
        }
        if !(spec.stroke_max_m.is_finite() && spec.stroke_max_m >= 0.0) {
            return Err(err(
                "stroke_max_m",
                format!(
                    "the extension limit must be a finite stroke ≥ 0, got {}",
                    spec.stroke_max_m
                ),
            ));
        }
        if !(spec.preload_n.is_finite() && spec.preload_n >= 0.0) {
            return Err(err(
                "preload_n",
                format!("must be a finite force ≥ 0, got {}", spec.preload_n),
            ));
        }
        if spec.substeps_per_period < 4 {
            return Err(err(
                "substeps_per_period",
                format!("must be at least 4, got {}", spec.substeps_per_period),
            ));
        }
        let points: Vec<(Vector3<f64>, Vector3<f64>)> = match &spec.layout {
            LegLayout::Hexapod {
                base_radius_m,
                ring_radius_m,
                base_pair_half_angle_deg,
                ring_pair_half_angle_deg,
            } => {
                positive("layout.Hexapod.base_radius_m", *base_radius_m)?;
                positive("layout.Hexapod.ring_radius_m", *ring_radius_m)?;
                for (f, a) in [
                    (
                        "layout.Hexapod.base_pair_half_angle_deg",
                        base_pair_half_angle_deg,
                    ),
                    (
                        "layout.Hexapod.ring_pair_half_angle_deg",
                        ring_pair_half_angle_deg,
                    ),
                ] {
                    if !(a.is_finite() && *a > 0.0 && *a < 60.0) {
                        return Err(err(f, format!("must be in (0°, 60°), got {a}")));
                    }
                }
                let at = |r: f64, deg: f64| {
                    let a = deg.to_radians();
                    Vector3::new(r * a.cos(), r * a.sin(), 0.0)
                };
                let (b, g) = (*base_pair_half_angle_deg, *ring_pair_half_angle_deg);
                let mut v = Vec::with_capacity(6);
                for c in [0.0, 120.0, 240.0] {
                    v.push((at(*base_radius_m, c - b), at(*ring_radius_m, c - 60.0 + g)));
                    v.push((at(*base_radius_m, c + b), at(*ring_radius_m, c + 60.0 - g)));
                }
                v
            }
            LegLayout::Legs(l) => {
                if l.is_empty() {
                    return Err(err("layout.Legs", "no legs"));
                }
                let mut v = Vec::with_capacity(l.len());
                for (i, (b, r)) in l.iter().enumerate() {
                    if !b.iter().chain(r.iter()).all(|x| x.is_finite()) {
                        return Err(err(&format!("layout.Legs[{i}]"), "non-finite coordinate"));
                    }
                    v.push((Vector3::from(*b), Vector3::from(*r)));
                }
                v
            }
        };
        let mut legs = Vec::with_capacity(points.len());
        for (i, (b, r)) in points.into_iter().enumerate() {
            let l0 = (r + Vector3::z() * spec.height_m - b).norm();
            // A leg shorter than its compression stroke could pass through zero length within
            // its limits; one of (near) zero length has no axis.
            if l0 <= -spec.stroke_min_m || l0 < 1e-6 {
                return Err(err(
                    &format!("leg {i}"),
                    format!(
                        "neutral length {l0:.6} m does not exceed the compression stroke {:.6} m: \
                         the leg cannot reach the ring through its stroke",
                        -spec.stroke_min_m
                    ),
                ));
            }
            legs.push(Leg {
                base_p_m: b,
                ring_r_m: r,
                neutral_length_m: l0,
            });
        }
        let inertia = Matrix3::from_diagonal(&Vector3::from(spec.ring_inertia_kg_m2));
        let inertia_inv =
            Matrix3::from_diagonal(&Vector3::from(spec.ring_inertia_kg_m2.map(|j| 1.0 / j)));
        let rho = legs
            .iter()
            .map(|l| l.ring_r_m.norm())
            .fold(0.0_f64, f64::max);
        let j_min = jx.min(jy).min(jz);
        let m_min = if rho > 0.0 {
            spec.ring_mass_kg.min(j_min / (rho * rho))
        } else {
            spec.ring_mass_kg
        };
        let mut p = Platform {
            spec: spec.clone(),
            legs,
            inertia,
            inertia_inv,
            h_max_s: 0.0,
            ring_min_mass_kg: m_min,
        };
        p.h_max_s = p.h_bound(m_min);
        Ok(p)
    }

    /// The largest sub-step for a smallest effective mass `m_min` (kg) at the legs, s.
    fn h_bound(&self, m_min: f64) -> f64 {
        let n = self.legs.len() as f64;
        let k_max = n * (self.spec.stiffness_n_m + self.spec.stop_stiffness_n_m);
        let period = 2.0 * std::f64::consts::PI * (m_min / k_max).sqrt();
        (period / f64::from(self.spec.substeps_per_period))
            .min(m_min / (5.0 * n * self.spec.damping_n_s_m))
    }

    /// The ring's state at the neutral pose of a base, moving with it (rigidly attached).
    pub fn neutral_state(&self, base: &Base) -> RigidState {
        let pos = base
            .pose
            .transform_point(&(Vector3::z() * self.spec.height_m).into())
            .coords;
        RigidState {
            pos_m: pos,
            vel_m_s: base.point_vel(&pos),
            att: base.pose.rotation,
            omega_rad_s: base.omega_rad_s,
        }
    }

    /// The ring's pose relative to the platform frame P (R in P).
    pub fn ring_pose_in_base(&self, base: &Base, ring: &RigidState) -> Isometry3<f64> {
        base.pose.inverse() * Isometry3::from_parts(Translation3::from(ring.pos_m), ring.att)
    }

    /// Leg axial force (positive in compression) at stroke `s` and stroke rate `sd`, N; and the
    /// leg's potential energy there, J.
    pub fn leg_force(&self, s: f64, sd: f64) -> (f64, f64) {
        let sp = &self.spec;
        let mut f = sp.preload_n - sp.stiffness_n_m * s - sp.damping_n_s_m * sd;
        let mut u = 0.5 * sp.stiffness_n_m * s * s - sp.preload_n * s;
        if s > sp.stroke_max_m {
            let d = s - sp.stroke_max_m;
            f -= sp.stop_stiffness_n_m * d;
            u += 0.5 * sp.stop_stiffness_n_m * d * d;
        } else if s < sp.stroke_min_m {
            let d = sp.stroke_min_m - s;
            f += sp.stop_stiffness_n_m * d;
            u += 0.5 * sp.stop_stiffness_n_m * d * d;
        }
        (f, u)
    }

    /// The legs' loads with the base and the ring in the given states.
    pub fn loads(&self, base: &Base, ring: &RigidState) -> PlatformLoads {
        self.loads_retracted(base, ring, 0.0)
    }

    /// Neutral length of leg `leg` with the platform retracted by `retraction_m` (the ring's
    /// neutral pose `height_m − retraction_m` above P), m.
    pub fn neutral_length_retracted_m(&self, leg: &Leg, retraction_m: f64) -> f64 {
        if retraction_m == 0.0 {
            leg.neutral_length_m
        } else {
            (leg.ring_r_m + Vector3::z() * (self.spec.height_m - retraction_m) - leg.base_p_m)
                .norm()
        }
    }

    /// The legs' loads with the platform retracted by `retraction_m` (m ≥ 0: the legs'
    /// actuators have shortened every leg to the neutral length of a platform `retraction_m`
    /// lower, [`Platform::neutral_length_retracted_m`]; strokes are measured from those
    /// lengths, so the stroke limits and the spring act about the retracted pose).
    pub fn loads_retracted(
        &self,
        base: &Base,
        ring: &RigidState,
        retraction_m: f64,
    ) -> PlatformLoads {
        let mut out = PlatformLoads {
            legs: Vec::with_capacity(self.legs.len()),
            force_on_ring_n: Vector3::zeros(),
            moment_on_ring_nm: Vector3::zeros(),
            force_on_base_n: Vector3::zeros(),
            moment_on_base_nm: Vector3::zeros(),
            damper_power_w: 0.0,
            potential_j: 0.0,
        };
        let origin = base.pose.translation.vector;
        for leg in &self.legs {
            let b = base.pose.transform_point(&leg.base_p_m.into()).coords;
            let r = ring.pos_m + ring.att * leg.ring_r_m;
            let d = r - b;
            let len = d.norm();
            let u = if len > 0.0 { d / len } else { Vector3::z() };
            let vr = ring.vel_m_s + ring.omega_rad_s.cross(&(r - ring.pos_m));
            let sd = (vr - base.point_vel(&b)).dot(&u);
            let s = len - self.neutral_length_retracted_m(leg, retraction_m);
            let (f, pot) = self.leg_force(s, sd);
            let fv = u * f;
            out.force_on_ring_n += fv;
            out.moment_on_ring_nm += (r - ring.pos_m).cross(&fv);
            out.force_on_base_n -= fv;
            out.moment_on_base_nm += (b - origin).cross(&(-fv));
            out.damper_power_w += self.spec.damping_n_s_m * sd * sd;
            out.potential_j += pot;
            out.legs.push(LegState {
                length_m: len,
                stroke_m: s,
                stroke_rate_m_s: sd,
                force_n: f,
                axis: u,
                ring_point_m: r,
                base_point_m: b,
            });
        }
        out
    }

    /// The ring's kinetic energy, J.
    pub fn kinetic_energy_j(&self, ring: &RigidState) -> f64 {
        let w_b = ring.att.inverse() * ring.omega_rad_s;
        0.5 * self.spec.ring_mass_kg * ring.vel_m_s.norm_squared()
            + 0.5 * w_b.dot(&(self.inertia * w_b))
    }

    /// Advances the ring over `dt` with the base held at `base` (a base that does not move
    /// within the step: at rest, or an inertial test stand), an external force `f_ext_n`
    /// (world, at the ring's centre of mass) and moment `m_ext_nm` held over the step.
    /// Returns the energy the dampers dissipated over the step (trapezoidal rule over the
    /// sub-steps), J, and the largest |leg force| within it, N.
    pub fn step_fixed_base(
        &self,
        base: &Base,
        ring: &mut RigidState,
        f_ext_n: &Vector3<f64>,
        m_ext_nm: &Vector3<f64>,
        dt: f64,
    ) -> (f64, f64) {
        let n = ((dt / self.h_max_s).ceil() as u32).max(1);
        let mut unused = self.neutral_state(base);
        let held = [*f_ext_n, *m_ext_nm, Vector3::zeros(), Vector3::zeros()];
        self.advance(None, base, &mut unused, ring, &held, dt, n)
    }

    /// Advances the chaser (a free rigid body carrying the platform) and the ring together
    /// over `dt` with the held external wrenches; the legs' loads act on both, equal and
    /// opposite, so the pair's momentum and angular momentum change only by the external
    /// wrenches. The sub-step bound uses half the smaller of the two bodies' smallest effective
    /// masses at the legs (a lower bound on the pair's reduced mass there). Returns what
    /// [`Platform::step_fixed_base`] does.
    pub fn step_free_base(
        &self,
        carrier: &Carrier,
        chaser: &mut RigidState,
        ring: &mut RigidState,
        held: &HeldWrenches,
        dt: f64,
    ) -> (f64, f64) {
        let j_min = carrier.inertia_kg_m2.symmetric_eigenvalues().min();
        let rho = self
            .legs
            .iter()
            .map(|l| {
                (carrier.port_body * nalgebra::Point3::from(l.base_p_m))
                    .coords
                    .norm()
            })
            .fold(0.0_f64, f64::max);
        let m_c = if rho > 0.0 {
            carrier.mass_kg.min(j_min / (rho * rho))
        } else {
            carrier.mass_kg
        };
        let h = self.h_bound(0.5 * self.ring_min_mass_kg.min(m_c));
        let n = ((dt / h).ceil() as u32).max(1);
        let base = carrier.base(chaser);
        self.advance(Some(carrier), &base, chaser, ring, held, dt, n)
    }

    /// The sub-stepped kick–drift–kick of the ring and, with a carrier, the chaser.
    #[allow(clippy::too_many_arguments)]
    fn advance(
        &self,
        carrier: Option<&Carrier>,
        fixed: &Base,
        chaser: &mut RigidState,
        ring: &mut RigidState,
        held: &HeldWrenches,
        dt: f64,
        n: u32,
    ) -> (f64, f64) {
        let h = dt / f64::from(n);
        let m = self.spec.ring_mass_kg;
        let world_inv = |att: &UnitQuaternion<f64>, j_inv: &Matrix3<f64>| {
            let r = att.to_rotation_matrix().into_inner();
            r * j_inv * r.transpose()
        };
        let base_of = |c: &RigidState| carrier.map_or(*fixed, |k| k.base(c));
        let loads_at = |c: &RigidState, r: &RigidState| self.loads(&base_of(c), r);
        // Half-kicks of both bodies by the legs' loads and the held wrenches.
        let kick = |c: &mut RigidState, r: &mut RigidState, l: &PlatformLoads| {
            r.vel_m_s += (l.force_on_ring_n + held[0]) * (0.5 * h / m);
            r.omega_rad_s +=
                world_inv(&r.att, &self.inertia_inv) * (l.moment_on_ring_nm + held[1]) * (0.5 * h);
            if let Some(k) = carrier {
                let p = base_of(c).pose.translation.vector;
                let tau = l.moment_on_base_nm + (p - c.pos_m).cross(&l.force_on_base_n) + held[3];
                c.vel_m_s += (l.force_on_base_n + held[2]) * (0.5 * h / k.mass_kg);
                c.omega_rad_s += world_inv(&c.att, &k.inertia_inv) * tau * (0.5 * h);
            }
        };
        let drift = |s: &mut RigidState, j: &Matrix3<f64>, j_inv: &Matrix3<f64>| {
            s.pos_m += s.vel_m_s * h;
            let (att, om) = rotate_rk4(&s.att, &s.omega_rad_s, &Vector3::zeros(), j, j_inv, h);
            s.att = att;
            s.omega_rad_s = om;
        };
        let mut loads = loads_at(chaser, ring);
        let mut dissipated = 0.0;
        let mut peak = loads
            .legs
            .iter()
            .fold(0.0_f64, |a, l| a.max(l.force_n.abs()));
        for _ in 0..n {
            let p0 = loads.damper_power_w;
            kick(chaser, ring, &loads);
            drift(ring, &self.inertia, &self.inertia_inv);
            if let Some(k) = carrier {
                drift(chaser, &k.inertia_kg_m2, &k.inertia_inv);
            }
            // The second half-kick at the drifted poses: the damping needs the end-of-step
            // velocities, so one fixed-point iteration of the implicit half-kick
            // v₁ = v½ + ½h·a(x₁, v₁) from v½ (a trial half-kick with the loads at v½, then the
            // half-kick from v½ with the loads at the trial velocities) keeps it second order.
            let (c_half, r_half) = (*chaser, *ring);
            kick(chaser, ring, &loads_at(chaser, ring));
            let trial = loads_at(chaser, ring);
            (*chaser, *ring) = (c_half, r_half);
            kick(chaser, ring, &trial);
            // The loads at the end of the sub-step (its velocities): the dissipated power for
            // the energy balance, and the next sub-step's first half-kick.
            loads = loads_at(chaser, ring);
            dissipated += 0.5 * (p0 + loads.damper_power_w) * h;
            peak = loads.legs.iter().fold(peak, |a, l| a.max(l.force_n.abs()));
        }
        (dissipated, peak)
    }
}
