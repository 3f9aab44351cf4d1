//! Deterministic random streams keyed by `(seed, pixel, sample, dimension)`.
//!
//! Every number a path consumes is a pure function of its key, so an image
//! is bit-identical whatever the thread count or tile order, and the
//! differentiation side can replay a path with the same numbers.
//!
//! Samples are stratified per dimension (Latin hypercube): for a pixel with
//! `spp` samples, dimension `d` of sample `s` falls in stratum
//! `π_d(s)` of `[0, 1)` split into `spp` equal strata, where `π_d` is a
//! hashed permutation (Kensler, "Correlated Multi-Jittered Sampling", Pixar
//! TM 13-01, 2013) and the position inside the stratum is a hashed jitter.
//! Each 1-D projection is thereby evenly covered while dimensions stay
//! decorrelated. Only the first [`STRATIFIED_DIMENSIONS`] dimensions (the
//! film position and the first bounce, where stratification pays) use the
//! permutation; later dimensions are independent hashed numbers, several
//! times cheaper.
//!
//! Cost: the permutation of each stratified dimension is chosen by a hash of
//! `(seed, pixel, dimension)` that does not depend on the sample;
//! [`PixelKeys`] computes those once per pixel for all its samples. Every
//! other bit of randomness (the stratified jitters and all later numbers) is
//! one multiply–xorshift of a Weyl step `k + (d + 1)·φ` from a per-sample
//! key `k` (one 64-bit finaliser of `(seed, pixel, sample)`, computed when
//! the sample's stream is made), so a path's ~50 numbers cost one strong
//! hash plus a handful of instructions each. The streams stay
//! counter-based: every number is still a pure function of `(seed, pixel,
//! sample, dimension)`.

use glam::Vec2;

/// The sample-independent hashes of one pixel's stratified dimensions,
/// computed once and shared by the pixel's samples.
#[derive(Clone, Copy, Debug, Default)]
pub struct PixelKeys {
    key: u64,
    strata: [u32; STRATIFIED_DIMENSIONS as usize],
}

impl PixelKeys {
    /// The keys of pixel `pixel` (a linear index, e.g. `y·width + x`) under
    /// `seed`.
    #[inline]
    pub fn new(seed: u32, pixel: u32) -> Self {
        let key = pixel_key(seed, pixel);
        let mut strata = [0; STRATIFIED_DIMENSIONS as usize];
        for (d, h) in (0..).zip(&mut strata) {
            *h = dim_hash(key, d) as u32;
        }
        Self { key, strata }
    }

    /// The stream of sample `sample` (of `spp`) of this pixel.
    #[inline]
    pub fn sampler(&self, sample: u32, spp: u32) -> PixelSampler<'_> {
        PixelSampler {
            strata: &self.strata,
            sample_key: mix64(self.key ^ u64::from(sample).wrapping_mul(SAMPLE_STEP)),
            sample,
            spp: spp.max(1),
            dim: 0,
        }
    }
}

/// The random stream of one pixel sample.
#[derive(Clone, Copy, Debug)]
pub struct PixelSampler<'a> {
    /// The pixel's hashes of the stratified dimensions ([`PixelKeys`]).
    strata: &'a [u32; STRATIFIED_DIMENSIONS as usize],
    /// The per-sample key of the dimensions past the stratified ones.
    sample_key: u64,
    sample: u32,
    spp: u32,
    dim: u32,
}

impl PixelSampler<'_> {
    /// Jumps to dimension `dim` (paths give each bounce a fixed block of
    /// dimensions so that a path's numbers do not depend on earlier branches).
    #[inline]
    pub fn set_dimension(&mut self, dim: u32) {
        self.dim = dim;
    }

    /// The next number in `[0, 1)`.
    #[inline(always)]
    pub fn next_1d(&mut self) -> f32 {
        let dim = self.dim;
        self.dim += 1;
        let Some(&h) = self.strata.get(dim as usize) else {
            return to_unit(weyl_mix(self.sample_key, dim));
        };
        let stratum = permute(self.sample, self.spp, h);
        let jitter = to_unit(weyl_mix(self.sample_key, dim));
        ((stratum as f32 + jitter) / self.spp as f32).min(ONE_MINUS_EPSILON)
    }

    /// The next two numbers in `[0, 1)²`.
    #[inline]
    pub fn next_2d(&mut self) -> Vec2 {
        let x = self.next_1d();
        Vec2::new(x, self.next_1d())
    }
}

/// Dimensions `0..STRATIFIED_DIMENSIONS` are Latin-hypercube stratified.
pub const STRATIFIED_DIMENSIONS: u32 = 10;

const ONE_MINUS_EPSILON: f32 = 1.0 - f32::EPSILON / 2.0;

#[inline]
fn to_unit(bits: u32) -> f32 {
    (bits >> 8) as f32 * (1.0 / (1u32 << 24) as f32)
}

/// The key of pixel `pixel` under `seed`.
#[inline]
fn pixel_key(seed: u32, pixel: u32) -> u64 {
    mix64(((seed as u64) << 32) | pixel as u64)
}

/// The sample-independent hash of dimension `dim` of the pixel with `key`
/// (its low half chooses the dimension's permutation).
#[inline]
fn dim_hash(key: u64, dim: u32) -> u64 {
    mix64(key ^ u64::from(dim).wrapping_mul(GOLDEN))
}

/// Odd constant that spreads sample indices over the 64-bit key space.
const SAMPLE_STEP: u64 = 0xD1B5_4A32_D192_ED03;

/// The golden-ratio Weyl step between unstratified dimensions.
const GOLDEN: u64 = 0x9E37_79B9_7F4A_7C15;

/// 32 well-mixed bits of dimension `dim` from a per-sample key: one
/// xorshift–multiply of the Weyl step `key + (dim + 1)·φ`, high half of the
/// product (it depends on every bit of the multiplicand).
#[inline]
fn weyl_mix(key: u64, dim: u32) -> u32 {
    let x = key.wrapping_add(u64::from(dim + 1).wrapping_mul(GOLDEN));
    ((x ^ (x >> 32)).wrapping_mul(0xD6E8_FEB8_6659_FD93) >> 32) as u32
}

/// A 64-bit finaliser (Stafford's variant 13 of MurmurHash3's fmix64).
#[inline]
fn mix64(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// Element `i` of a pseudo-random permutation of `0..l` chosen by `p`
/// (Kensler 2013, cycle-walking over the next power of two).
#[inline]
fn permute(mut i: u32, l: u32, p: u32) -> u32 {
    if l <= 1 {
        return 0;
    }
    let mut w = l - 1;
    w |= w >> 1;
    w |= w >> 2;
    w |= w >> 4;
    w |= w >> 8;
    w |= w >> 16;
    loop {
        i ^= p;
        i = i.wrapping_mul(0xE170_893D);
        i ^= p >> 16;
        i ^= (i & w) >> 4;
        i ^= p >> 8;
        i = i.wrapping_mul(0x0929_EB3F);
        i ^= p >> 23;
        i ^= (i & w) >> 1;
        i = i.wrapping_mul(1 | (p >> 27));
        i = i.wrapping_mul(0x6935_FA69);
        i ^= (i & w) >> 11;
        i = i.wrapping_mul(0x74DC_B303);
        i ^= (i & w) >> 2;
        i = i.wrapping_mul(0x9E50_1CC3);
        i ^= (i & w) >> 2;
        i = i.wrapping_mul(0xC860_A3DF);
        i &= w;
        i ^= i >> 5;
        if i < l {
            break;
        }
    }
    // `% l` is a division; for a power of two `l` (then `w = l − 1`) the
    // mask gives the same value.
    let i = i.wrapping_add(p);
    if w == l - 1 { i & w } else { i % l }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn permutations_are_bijections() {
        for l in [1u32, 2, 3, 7, 16, 17, 64, 100] {
            for p in [0u32, 1, 0xDEAD_BEEF, 12345] {
                let mut seen = vec![false; l as usize];
                for i in 0..l {
                    let j = permute(i, l, p) as usize;
                    assert!(!seen[j], "l={l} p={p}: {j} twice");
                    seen[j] = true;
                }
            }
        }
    }

    #[test]
    fn every_dimension_is_stratified_over_the_pixel_samples() {
        let spp = 37;
        for dim in 0..STRATIFIED_DIMENSIONS {
            let mut strata = vec![0u32; spp as usize];
            for s in 0..spp {
                let keys = PixelKeys::new(7, 1234);
                let mut r = keys.sampler(s, spp);
                r.set_dimension(dim);
                let x = r.next_1d();
                assert!((0.0..1.0).contains(&x));
                strata[(x * spp as f32) as usize] += 1;
            }
            assert!(strata.iter().all(|&c| c == 1), "dim {dim}: {strata:?}");
        }
    }

    /// Pairs of neighbouring unstratified dimensions fill a 16 × 16 grid
    /// evenly (χ² over many pixels and samples) and are uncorrelated.
    #[test]
    fn unstratified_pairs_are_uniform() {
        for first in [STRATIFIED_DIMENSIONS, 17, 40] {
            let mut cells = [0u32; 256];
            let n = 256 * 400;
            for i in 0..n {
                let keys = PixelKeys::new(5, i / 16);
                let mut r = keys.sampler(i % 16, 16);
                r.set_dimension(first);
                let v = r.next_2d();
                cells[(v.x * 16.0) as usize * 16 + (v.y * 16.0) as usize] += 1;
            }
            let expected = n as f64 / 256.0;
            let chi2: f64 = cells
                .iter()
                .map(|&c| (c as f64 - expected).powi(2) / expected)
                .sum();
            // 255 degrees of freedom: mean 255, sd ≈ 22.6; 350 is > 4 sd.
            assert!(chi2 < 350.0, "dims {first}, {}: χ² {chi2}", first + 1);
        }
    }

    #[test]
    fn streams_are_pure_functions_of_their_key_and_differ_between_keys() {
        let stream = |seed, pixel, sample, dim| {
            let keys = PixelKeys::new(seed, pixel);
            let mut r = keys.sampler(sample, 16);
            r.set_dimension(dim);
            r.next_2d()
        };
        for dim in [0, 30] {
            let a = stream(1, 2, 3, dim);
            assert_eq!(a, stream(1, 2, 3, dim));
            assert_ne!(a, stream(1, 3, 3, dim));
            assert_ne!(a, stream(2, 2, 3, dim));
            assert_ne!(a, stream(1, 2, 4, dim));
        }
    }

    #[test]
    fn pairs_of_dimensions_are_uncorrelated() {
        // Correlation between two dimensions over many pixels must be ~0, for
        // a stratified pair and an unstratified one.
        let n = 20_000u32;
        for dim in [0, 12] {
            let (mut sx, mut sy, mut sxy, mut sxx, mut syy) = (0.0f64, 0.0, 0.0, 0.0, 0.0);
            for px in 0..n {
                let keys = PixelKeys::new(3, px);
                let mut r = keys.sampler(px % 4, 4);
                r.set_dimension(dim);
                let v = r.next_2d();
                let (x, y) = (v.x as f64, v.y as f64);
                sx += x;
                sy += y;
                sxy += x * y;
                sxx += x * x;
                syy += y * y;
            }
            let nf = n as f64;
            let cov = sxy / nf - sx * sy / (nf * nf);
            let var = |s: f64, ss: f64| ss / nf - (s / nf).powi(2);
            let corr = cov / (var(sx, sxx) * var(sy, syy)).sqrt();
            assert!(corr.abs() < 0.03, "dim {dim}: correlation {corr}");
            assert!((sx / nf - 0.5).abs() < 0.01);
        }
    }
}
