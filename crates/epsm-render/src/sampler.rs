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
//! permutation; later dimensions are independent hashed numbers, four times
//! cheaper.
//!
//! Each number starts from a hash of `(seed, pixel, dimension)` that does not
//! depend on the sample; [`PixelKeys`] computes those once per pixel for all
//! its samples (the same numbers, one 64-bit hash fewer per number).

use glam::Vec2;

/// The sample-independent hashes of one pixel's dimensions, computed once
/// and shared by the pixel's samples.
#[derive(Clone, Debug, Default)]
pub struct PixelKeys {
    key: u64,
    dims: Vec<u64>,
}

impl PixelKeys {
    /// The hashes of dimensions `0..dims` of pixel `pixel` (a linear index,
    /// e.g. `y·width + x`) under `seed`; later dimensions are hashed as they
    /// are drawn.
    pub fn new(seed: u32, pixel: u32, dims: u32) -> Self {
        let mut keys = Self::default();
        keys.set_pixel(seed, pixel, dims);
        keys
    }

    /// [`PixelKeys::new`] in place, keeping the allocation.
    #[inline]
    pub fn set_pixel(&mut self, seed: u32, pixel: u32, dims: u32) {
        let key = pixel_key(seed, pixel);
        self.key = key;
        self.dims.clear();
        self.dims.extend((0..dims).map(|d| dim_hash(key, d)));
    }

    /// The stream of sample `sample` (of `spp`) of this pixel.
    #[inline]
    pub fn sampler(&self, sample: u32, spp: u32) -> PixelSampler<'_> {
        PixelSampler {
            key: self.key,
            dims: &self.dims,
            sample,
            spp: spp.max(1),
            dim: 0,
        }
    }
}

/// The random stream of one pixel sample.
#[derive(Clone, Copy, Debug)]
pub struct PixelSampler<'a> {
    key: u64,
    /// Hashes of the first dimensions ([`PixelKeys`]), possibly none.
    dims: &'a [u64],
    sample: u32,
    spp: u32,
    dim: u32,
}

impl PixelSampler<'static> {
    /// The stream of sample `sample` (of `spp`) of pixel `pixel` (a linear
    /// index, e.g. `y·width + x`) under `seed`, hashing every dimension as
    /// it is drawn.
    #[inline]
    pub fn new(seed: u32, pixel: u32, sample: u32, spp: u32) -> Self {
        Self {
            key: pixel_key(seed, pixel),
            dims: &[],
            sample,
            spp: spp.max(1),
            dim: 0,
        }
    }
}

impl PixelSampler<'_> {
    /// Jumps to dimension `dim` (paths give each bounce a fixed block of
    /// dimensions so that a path's numbers do not depend on earlier branches).
    #[inline]
    pub fn set_dimension(&mut self, dim: u32) {
        self.dim = dim;
    }

    /// The next number in `[0, 1)`.
    #[inline]
    pub fn next_1d(&mut self) -> f32 {
        let h = match self.dims.get(self.dim as usize) {
            Some(&h) => h,
            None => dim_hash(self.key, self.dim),
        };
        self.dim += 1;
        if self.dim > STRATIFIED_DIMENSIONS {
            return to_unit((mix64(h ^ self.sample as u64) >> 32) as u32);
        }
        let stratum = permute(self.sample, self.spp, h as u32);
        let jitter =
            to_unit((h >> 32) as u32 ^ hash32(self.sample.wrapping_mul(0x2C1B_3C6D) ^ h as u32));
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

/// The sample-independent hash of dimension `dim` of the pixel with `key`.
#[inline]
fn dim_hash(key: u64, dim: u32) -> u64 {
    mix64(key ^ (dim as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15))
}

/// A 64-bit finaliser (Stafford's variant 13 of MurmurHash3's fmix64).
#[inline]
fn mix64(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// A 32-bit integer hash (Wellons' lowbias32).
#[inline]
fn hash32(mut x: u32) -> u32 {
    x ^= x >> 16;
    x = x.wrapping_mul(0x7FEB_352D);
    x ^= x >> 15;
    x = x.wrapping_mul(0x846C_A68B);
    x ^ (x >> 16)
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
    (i.wrapping_add(p)) % l
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
                let mut r = PixelSampler::new(7, 1234, s, spp);
                r.set_dimension(dim);
                let x = r.next_1d();
                assert!((0.0..1.0).contains(&x));
                strata[(x * spp as f32) as usize] += 1;
            }
            assert!(strata.iter().all(|&c| c == 1), "dim {dim}: {strata:?}");
        }
    }

    #[test]
    fn cached_keys_give_the_same_streams() {
        for spp in [1u32, 4, 37] {
            for dims in [0u32, 3, 10, 66] {
                let keys = PixelKeys::new(9, 4321, dims);
                for s in 0..spp {
                    let mut cached = keys.sampler(s, spp);
                    let mut direct = PixelSampler::new(9, 4321, s, spp);
                    for d in 0..80 {
                        if d % 7 == 3 {
                            cached.set_dimension(d);
                            direct.set_dimension(d);
                        }
                        let (a, b) = (cached.next_1d(), direct.next_1d());
                        assert_eq!(a.to_bits(), b.to_bits(), "spp {spp} dims {dims} dim {d}");
                    }
                }
            }
        }
    }

    #[test]
    fn streams_are_pure_functions_of_their_key_and_differ_between_keys() {
        let a = PixelSampler::new(1, 2, 3, 16).next_2d();
        assert_eq!(a, PixelSampler::new(1, 2, 3, 16).next_2d());
        assert_ne!(a, PixelSampler::new(1, 3, 3, 16).next_2d());
        assert_ne!(a, PixelSampler::new(2, 2, 3, 16).next_2d());
    }

    #[test]
    fn pairs_of_dimensions_are_uncorrelated() {
        // Correlation between two dimensions over many pixels must be ~0.
        let n = 20_000u32;
        let (mut sx, mut sy, mut sxy, mut sxx, mut syy) = (0.0f64, 0.0, 0.0, 0.0, 0.0);
        for px in 0..n {
            let v = PixelSampler::new(3, px, px % 4, 4).next_2d();
            let (x, y) = (v.x as f64, v.y as f64);
            sx += x;
            sy += y;
            sxy += x * y;
            sxx += x * x;
            syy += y * y;
        }
        let nf = n as f64;
        let cov = sxy / nf - sx * sy / (nf * nf);
        let corr = cov / ((sxx / nf - (sx / nf).powi(2)) * (syy / nf - (sy / nf).powi(2))).sqrt();
        assert!(corr.abs() < 0.03, "correlation {corr}");
        assert!((sx / nf - 0.5).abs() < 0.01);
    }
}
