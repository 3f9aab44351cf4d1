//! A seeded random stream for tests: the same seed gives the same draws on
//! every platform and thread count (PCG64-MCG, `rand_pcg`), so a failing
//! random case can be replayed from its seed.

use glam::{DVec3, Vec2, Vec3};
use rand::{Rng as _, SeedableRng};
use rand_pcg::Pcg64Mcg;

/// A deterministic stream of uniform draws.
pub struct Rng(Pcg64Mcg);

impl Rng {
    /// A stream from a seed.
    pub fn new(seed: u64) -> Self {
        Self(Pcg64Mcg::seed_from_u64(seed))
    }

    /// Uniform 64-bit integer.
    pub fn u64(&mut self) -> u64 {
        self.0.random()
    }

    /// Uniform in `[0, 1)`, 53 bits.
    pub fn f64(&mut self) -> f64 {
        self.0.random()
    }

    /// Uniform in `[0, 1)`, 24 bits.
    pub fn f32(&mut self) -> f32 {
        self.0.random()
    }

    /// Uniform in `[lo, hi)` (`lo` when the range is empty).
    pub fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.f64()
    }

    /// Uniform integer in `0..n`; `n` must be positive.
    pub fn below(&mut self, n: usize) -> usize {
        self.0.random_range(0..n)
    }

    /// A point uniform in the cube `[lo, hi)³`.
    pub fn dvec3(&mut self, lo: f64, hi: f64) -> DVec3 {
        DVec3::new(self.range(lo, hi), self.range(lo, hi), self.range(lo, hi))
    }

    /// A uniform unit direction (f64), by rejection from the cube; lengths
    /// below 0.1 are rejected too so the normalisation is well conditioned.
    pub fn unit(&mut self) -> DVec3 {
        loop {
            let v = self.dvec3(-1.0, 1.0);
            if (0.01..1.0).contains(&v.length_squared()) {
                return v.normalize();
            }
        }
    }

    /// Two uniforms in `[0, 1)`.
    pub fn vec2(&mut self) -> Vec2 {
        Vec2::new(self.f32(), self.f32())
    }

    /// A uniform unit direction (f32), by inverting the sphere's area measure.
    pub fn sphere(&mut self) -> Vec3 {
        let z = 1.0 - 2.0 * self.f32();
        let r = (1.0 - z * z).max(0.0).sqrt();
        let phi = std::f32::consts::TAU * self.f32();
        Vec3::new(r * phi.cos(), r * phi.sin(), z)
    }
}

#[cfg(test)]
mod tests {
    use super::Rng;

    #[test]
    fn same_seed_same_stream_and_draws_in_range() {
        let (mut a, mut b) = (Rng::new(7), Rng::new(7));
        for _ in 0..1000 {
            assert_eq!(a.u64(), b.u64());
            let x = a.range(-2.0, 3.0);
            assert!((-2.0..3.0).contains(&x));
            assert_eq!(x, b.range(-2.0, 3.0));
            assert!(a.below(5) < 5);
            b.below(5);
            assert!((a.unit().length() - 1.0).abs() < 1e-12);
            assert!((a.sphere().length() - 1.0).abs() < 1e-5);
            b.unit();
            b.sphere();
        }
        assert_ne!(Rng::new(1).u64(), Rng::new(2).u64());
    }
}
