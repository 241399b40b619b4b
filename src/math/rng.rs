//! A deterministic 64-bit linear congruential generator (Knuth's MMIX constants) for seeded
//! campaigns and randomised tests: the same seed gives the same numbers on every machine, with
//! no dependency. Not for statistics that need more than 53-bit uniforms and short-range
//! independence (the trials module uses SplitMix64 per trial and parameter).

use nalgebra::{Quaternion, UnitQuaternion, Vector3};

/// The generator state; `Lcg(seed)` starts a sequence.
#[derive(Debug, Clone)]
pub struct Lcg(pub u64);

impl Lcg {
    /// Next uniform number in [0, 1) (the state's top 53 bits).
    pub fn uniform(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }

    /// Next uniform number in [−1, 1).
    pub fn symmetric(&mut self) -> f64 {
        self.uniform() * 2.0 - 1.0
    }

    /// A vector with components uniform in [−scale, scale).
    pub fn vec3(&mut self, scale: f64) -> Vector3<f64> {
        Vector3::new(
            self.symmetric() * scale,
            self.symmetric() * scale,
            self.symmetric() * scale,
        )
    }

    /// A rotation from a normalised random 4-vector (not uniform on SO(3); for tests that need
    /// varied, reproducible attitudes).
    pub fn quat(&mut self) -> UnitQuaternion<f64> {
        let v = self.vec3(1.0);
        UnitQuaternion::from_quaternion(Quaternion::new(self.symmetric(), v.x, v.y, v.z))
    }
}

/// Seeded standard-normal generator (SplitMix64 → Box–Muller), deterministic across runs and
/// platforms; used for the measurement noise.
#[derive(Debug, Clone)]
pub struct GaussianNoise {
    state: u64,
    spare: Option<f64>,
}

impl GaussianNoise {
    /// A generator seeded with `seed`.
    pub fn new(seed: u64) -> Self {
        Self {
            state: seed,
            spare: None,
        }
    }

    fn next_u64(&mut self) -> u64 {
        self.state = self.state.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.state;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform on (0, 1].
    fn uniform(&mut self) -> f64 {
        ((self.next_u64() >> 11) as f64 + 1.0) / (1u64 << 53) as f64
    }

    /// One N(0, 1) sample.
    pub fn standard_normal(&mut self) -> f64 {
        if let Some(s) = self.spare.take() {
            return s;
        }
        let (u1, u2) = (self.uniform(), self.uniform());
        let r = (-2.0 * u1.ln()).sqrt();
        let (s, c) = (std::f64::consts::TAU * u2).sin_cos();
        self.spare = Some(r * s);
        r * c
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Reference: the recurrence x' = a·x + c mod 2⁶⁴ evaluated by hand in u128 arithmetic.
    #[test]
    fn invariant_lcg_recurrence_and_ranges() {
        let mut r = Lcg(42);
        let x1 = ((42u128 * 6_364_136_223_846_793_005 + 1_442_695_040_888_963_407) % (1u128 << 64))
            as u64;
        let u = r.uniform();
        assert_eq!(r.0, x1);
        assert_eq!(u, (x1 >> 11) as f64 / (1u64 << 53) as f64);
        for _ in 0..10_000 {
            let u = r.uniform();
            assert!((0.0..1.0).contains(&u));
            let s = r.symmetric();
            assert!((-1.0..1.0).contains(&s));
        }
    }
}
