//! Deterministic synthetic point clouds for tests and benchmarks.
//!
//! [`blobs_pair`] is the benchmark fixture: two `side × side` images
//! (`side = ⌈√n⌉`, the first `n` pixels in row-major order) of coloured
//! discs on a dark noisy background. Between the two images each disc is
//! moved (up to 0.25 of the image), resized (×0.7 to ×1.4) and recoloured
//! (±0.2 per channel). Points are `(r, g, b, x, y)` with colours in `[0, 1]`,
//! `x, y` the pixel centres in `[0, 1]` and λ = 1. Same `(n, seed)`, same clouds.

use crate::points::{Point, PointCloud};

/// A small deterministic generator (SplitMix64); not for cryptography.
#[derive(Debug, Clone)]
pub struct Rng(u64);

impl Rng {
    /// A generator seeded with `seed`.
    pub fn new(seed: u64) -> Self {
        Self(seed ^ 0x853c_49e6_748f_ea9b)
    }

    /// Next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }

    /// Uniform in `[0, 1)`.
    pub fn uniform(&mut self) -> f32 {
        (self.next_u64() >> 40) as f32 / (1u64 << 24) as f32
    }

    /// Uniform in `[lo, hi)`.
    pub fn range(&mut self, lo: f32, hi: f32) -> f32 {
        lo + (hi - lo) * self.uniform()
    }

    /// Uniform index in `0..n` (`n > 0`).
    pub fn index(&mut self, n: usize) -> usize {
        (self.next_u64() % n as u64) as usize
    }
}

/// `n` points uniform in `[0, 1]⁵`. Returns `None` for `n = 0`.
pub fn uniform_cloud(n: usize, seed: u64) -> Option<PointCloud> {
    let mut rng = Rng::new(seed);
    let points: Vec<Point> = (0..n)
        .map(|_| std::array::from_fn(|_| rng.uniform()))
        .collect();
    PointCloud::from_points(&points).ok()
}

#[derive(Debug, Clone, Copy)]
struct Disc {
    centre: [f32; 2],
    radius: f32,
    colour: [f32; 3],
}

fn render(discs: &[Disc], n: usize, side: usize, rng: &mut Rng) -> Option<PointCloud> {
    let points: Vec<Point> = (0..n)
        .map(|k| {
            let (x, y) = (
                ((k % side) as f32 + 0.5) / side as f32,
                ((k / side) as f32 + 0.5) / side as f32,
            );
            let mut colour = [0.0f32; 3].map(|_| 0.04 + 0.04 * rng.uniform());
            for d in discs {
                if (x - d.centre[0]).powi(2) + (y - d.centre[1]).powi(2) <= d.radius * d.radius {
                    colour = d
                        .colour
                        .map(|c| (c + 0.02 * (rng.uniform() - 0.5)).clamp(0.0, 1.0));
                }
            }
            [colour[0], colour[1], colour[2], x, y]
        })
        .collect();
    PointCloud::from_points(&points).ok()
}

/// The benchmark pair: (rendered, target) images of moved, resized, recoloured blobs.
///
/// Returns `None` for `n = 0`.
pub fn blobs_pair(n: usize, seed: u64) -> Option<(PointCloud, PointCloud)> {
    let side = (n as f64).sqrt().ceil() as usize;
    let mut rng = Rng::new(seed);
    let count = 5;
    let a: Vec<Disc> = (0..count)
        .map(|_| Disc {
            centre: [rng.range(0.2, 0.8), rng.range(0.2, 0.8)],
            radius: rng.range(0.06, 0.16),
            colour: [
                rng.range(0.2, 1.0),
                rng.range(0.2, 1.0),
                rng.range(0.2, 1.0),
            ],
        })
        .collect();
    let b: Vec<Disc> = a
        .iter()
        .map(|d| Disc {
            centre: [
                (d.centre[0] + rng.range(-0.25, 0.25)).clamp(0.1, 0.9),
                (d.centre[1] + rng.range(-0.25, 0.25)).clamp(0.1, 0.9),
            ],
            radius: d.radius * rng.range(0.7, 1.4),
            colour: d.colour.map(|c| (c + rng.range(-0.2, 0.2)).clamp(0.0, 1.0)),
        })
        .collect();
    Some((
        render(&a, n, side, &mut rng)?,
        render(&b, n, side, &mut rng)?,
    ))
}
