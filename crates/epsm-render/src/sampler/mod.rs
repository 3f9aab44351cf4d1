//! Deterministic random streams keyed by `(seed, pixel, sample, dimension)`.
//!
//! Every number a path consumes is a pure function of its key, so an image
//! is bit-identical whatever the thread count or tile order, and the
//! differentiation side can replay a path with the same numbers.
//!
//! Samples are stratified per dimension (Latin hypercube): for a pixel with
//! `spp` samples, dimension `d` of sample `s` falls in stratum
//! `π_d(s)` of `[0, 1)` split into `spp` equal strata, where `π_d` is a
//! hashed permutation and the position inside the stratum is a hashed
//! jitter. Each 1-D projection is thereby evenly covered while dimensions
//! stay decorrelated. Only the first [`STRATIFIED_DIMENSIONS`] dimensions
//! (the film position and the first bounce, where stratification pays) use
//! the permutation; later dimensions are independent hashed numbers, several
//! times cheaper.
//!
//! The permutation works on `k`-bit numbers, `2^k` the smallest power of two
//! `≥ spp`: three rounds of `x ← ((x ⊕ key) · odd) mod 2^k` and a xorshift
//! `x ← x ⊕ (x >> r)` (each a bijection of `0..2^k`), with shifts `r` of
//! about `k/2` and `k/4` so that high bits reach the low ones (multiplying
//! only carries low bits up), and two of the three odd multipliers drawn
//! from the dimension's hash. For `spp` not a
//! power of two, indices that land at or past `spp` are permuted again
//! (cycle-walking, as in Kensler, "Correlated Multi-Jittered Sampling",
//! Pixar TM 13-01, 2013, whose 16-step hash this replaces at about a third
//! of the cost). Pairs of stratified dimensions look like those of random
//! permutations (tested for 16–256 strata).
//!
//! Cost: the permutation keys of each stratified dimension come from a hash
//! of `(seed, pixel, dimension)` that does not depend on the sample;
//! [`PixelKeys`] computes those once per pixel for all its samples. Every
//! other bit of randomness (the stratified jitters and all later numbers) is
//! one multiply–xorshift of a Weyl step `k + (d + 1)·φ` from a per-sample
//! key `k` (one 64-bit finaliser of `(seed, pixel, sample)`, computed when
//! the sample's stream is made), so a path's ~50 numbers cost one strong
//! hash plus a handful of instructions each. The streams stay
//! counter-based: every number is still a pure function of `(seed, pixel,
//! sample, dimension)`.
//!
//! A bounce draws its numbers as one [`Block`] of eight dimensions. On CPUs
//! with AVX2 a block's hashes (and, for the first bounce, its eight
//! permutations) run eight dimensions per vector instruction, with the same
//! integer and `f32` operations as the scalar [`PixelSampler::get_1d`], so
//! the numbers are bit-identical either way (`avx2.rs`; 6 % fewer
//! instructions per sample on `scenes/cornell-box.toml`).

use std::ops::{BitAnd, BitXor, Shr};

use glam::Vec2;

#[cfg(target_arch = "x86_64")]
mod avx2;
#[cfg(target_arch = "x86_64")]
pub(crate) mod wide;

/// The sample-independent part of one pixel's streams (its stratified
/// dimensions' permutation keys and the stratum count), computed once and
/// shared by the pixel's samples.
#[derive(Clone, Copy, Debug)]
pub struct PixelKeys {
    key: u64,
    /// The permutation keys of the stratified dimensions, by dimension
    /// (arrays over dimensions, so that a [`Block`] loads eight
    /// dimensions' keys at once): xored into the index at the start of each
    /// of the three rounds.
    xor: [[u32; STRATIFIED]; 3],
    /// The odd multipliers of the first two rounds, by dimension.
    mul: [[u32; STRATIFIED]; 2],
    /// Strata per dimension (the samples per pixel), `≥ 1`.
    count: u32,
    /// `2^k − 1`, `2^k` the smallest power of two `≥ count`.
    mask: u32,
    /// The xorshift amounts of the permutation's three rounds:
    /// `⌊k/2⌋ + 1`, `⌊k/4⌋` and `⌈k/2⌉`, each clamped to `1..=max(k − 1, 1)`.
    shifts: [u32; 3],
    /// `1 / count`.
    inv_count: f32,
}

/// [`STRATIFIED_DIMENSIONS`] as an array length.
const STRATIFIED: usize = STRATIFIED_DIMENSIONS as usize;

impl PixelKeys {
    /// The keys of pixel `pixel` (a linear index, e.g. `y·width + x`) under
    /// `seed`, for `spp` samples (0 counts as 1).
    #[inline]
    pub fn new(seed: u32, pixel: u32, spp: u32) -> Self {
        let key = pixel_key(seed, pixel);
        let (mut xor, mut mul) = ([[0; STRATIFIED]; 3], [[0; STRATIFIED]; 2]);
        for d in 0..STRATIFIED {
            // A dimension's keys are drawn from its 64-bit hash.
            let h = dim_hash(key, d as u32);
            let (a, b) = (h as u32, (h >> 32) as u32);
            [xor[0][d], xor[1][d], xor[2][d]] = [a, b >> 16, a >> 16];
            [mul[0][d], mul[1][d]] = [b | 1, (a >> 8) | 1];
        }
        let count = spp.max(1);
        let mask = count
            .checked_next_power_of_two()
            .map_or(u32::MAX, |p| p - 1);
        let k = mask.count_ones();
        let shift = |r: u32| r.clamp(1, k.saturating_sub(1).max(1));
        Self {
            key,
            xor,
            mul,
            count,
            mask,
            shifts: [shift(k / 2 + 1), shift(k / 4), shift(k.div_ceil(2))],
            inv_count: 1.0 / count as f32,
        }
    }

    /// The stream of sample `sample` (`< spp`) of this pixel.
    #[inline]
    pub fn sampler(&self, sample: u32) -> PixelSampler<'_> {
        PixelSampler {
            keys: self,
            sample_key: mix64(self.key ^ u64::from(sample).wrapping_mul(SAMPLE_STEP)),
            sample,
        }
    }

    /// The three rounds of stratified dimension `dim`'s permutation on
    /// `0..=mask` (module docs), applied once to `i`.
    #[inline(always)]
    fn rounds(&self, i: u32, dim: usize) -> u32 {
        let xor = [self.xor[0][dim], self.xor[1][dim], self.xor[2][dim]];
        let mul = [self.mul[0][dim], self.mul[1][dim], PERMUTE_MUL];
        permute(i, xor, mul, self.mask, self.shifts)
    }

    /// Walks `i`, the rounds' image of a sample, on through the rounds of
    /// dimension `dim` while it is `≥ count` (cycle-walking).
    #[inline(always)]
    fn walk_into_range(&self, mut i: u32, dim: usize) -> u32 {
        while i >= self.count {
            i = self.rounds(i, dim);
        }
        i
    }

    /// Stratum `π(i)` of sample `i < count` under stratified dimension
    /// `dim`'s permutation.
    #[inline(always)]
    fn stratum(&self, i: u32, dim: usize) -> u32 {
        self.walk_into_range(self.rounds(i, dim), dim)
    }

    /// The number of a stratified dimension: its `stratum` plus a `jitter` in
    /// `[0, 1)`, scaled to `[0, 1)`.
    #[inline(always)]
    fn stratified(&self, stratum: u32, jitter: f32) -> f32 {
        ((stratum as f32 + jitter) * self.inv_count).min(ONE_MINUS_EPSILON)
    }
}

/// The random stream of one pixel sample: number `d` of the stream is
/// [`Self::get_1d`]`(d)`, a pure function of `(seed, pixel, sample, d)`, so a
/// caller draws each number by its dimension (paths give each bounce a fixed
/// block of dimensions, so that a path's numbers do not depend on earlier
/// branches) and the stream has no position to keep.
#[derive(Clone, Copy, Debug)]
pub struct PixelSampler<'a> {
    /// The pixel's sample-independent keys ([`PixelKeys`]).
    keys: &'a PixelKeys,
    /// The per-sample key of the jitters and of the dimensions past the
    /// stratified ones.
    sample_key: u64,
    sample: u32,
}

impl PixelSampler<'_> {
    /// The number of dimension `dim`, in `[0, 1)`.
    #[inline(always)]
    pub fn get_1d(&self, dim: u32) -> f32 {
        let jitter = to_unit(mix_weyl(weyl(self.sample_key, dim)));
        let keys = self.keys;
        if dim >= STRATIFIED_DIMENSIONS {
            return jitter;
        }
        keys.stratified(keys.stratum(self.sample, dim as usize), jitter)
    }

    /// The numbers of dimensions `first .. first + BLOCK` ([`Block`]), e.g.
    /// one bounce's block: the numbers of [`Self::get_1d`], drawn together
    /// (eight dimensions per vector instruction on CPUs with AVX2).
    #[inline(always)]
    #[allow(unsafe_code)]
    pub fn block(&self, first: u32) -> Block {
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx2") {
            let weyl_first = weyl(self.sample_key, first);
            let first = first as usize;
            // SAFETY: the `avx2` functions require only AVX2, found on this
            // CPU.
            if first >= STRATIFIED {
                return unsafe { avx2::unstratified(weyl_first) };
            }
            if first + BLOCK <= STRATIFIED && self.keys.count <= avx2::MAX_COUNT {
                return unsafe { avx2::stratified(self.keys, self.sample, first, weyl_first) };
            }
        }
        Block {
            numbers: std::array::from_fn(|k| self.get_1d(first + k as u32)),
        }
    }

    /// The numbers of dimensions `dim` and `dim + 1`, in `[0, 1)²`.
    #[inline(always)]
    pub fn get_2d(&self, dim: u32) -> Vec2 {
        Vec2::new(self.get_1d(dim), self.get_1d(dim + 1))
    }
}

/// The integer words the permutation rounds run on: one `u32`, or sixteen
/// lanes of them (module `wide`).
pub(crate) trait Word:
    Copy + BitXor<Output = Self> + BitAnd<Output = Self> + Shr<u32, Output = Self>
{
    /// The wrapping product.
    fn times(self, other: Self) -> Self;
}

impl Word for u32 {
    #[inline(always)]
    fn times(self, other: Self) -> Self {
        self.wrapping_mul(other)
    }
}

/// The three rounds of a permutation of `0..=mask` (module docs), applied
/// once to `i`: round `r` xors key `xor[r]` in, multiplies by the odd
/// `mul[r]`, keeps the bits of `mask` and xors in the result shifted right
/// by `shifts[r]`.
#[inline(always)]
pub(crate) fn permute<W: Word>(i: W, xor: [W; 3], mul: [W; 3], mask: W, shifts: [u32; 3]) -> W {
    let mut i = i;
    for r in 0..3 {
        i = (i ^ xor[r]).times(mul[r]) & mask;
        i = i ^ (i >> shifts[r]);
    }
    i
}

/// Dimensions per [`Block`].
pub const BLOCK: usize = 8;

/// The numbers of a sample's dimensions `first + offset` for `offset <
/// BLOCK` ([`PixelSampler::block`]): the same as
/// [`PixelSampler::get_1d`]`(first + offset)`.
#[derive(Clone, Copy, Debug)]
pub struct Block {
    numbers: [f32; BLOCK],
}

impl Block {
    /// The number of dimension `first + offset`, in `[0, 1)`.
    ///
    /// # Panics
    /// If `offset ≥ BLOCK`.
    #[inline(always)]
    pub fn get_1d(&self, offset: u32) -> f32 {
        self.numbers[offset as usize]
    }

    /// The numbers of dimensions `first + offset` and `first + offset + 1`.
    ///
    /// # Panics
    /// If `offset + 1 ≥ BLOCK`.
    #[inline(always)]
    pub fn get_2d(&self, offset: u32) -> Vec2 {
        Vec2::new(self.get_1d(offset), self.get_1d(offset + 1))
    }
}

/// Dimensions `0..STRATIFIED_DIMENSIONS` are Latin-hypercube stratified.
pub const STRATIFIED_DIMENSIONS: u32 = 10;

const ONE_MINUS_EPSILON: f32 = 1.0 - f32::EPSILON / 2.0;

#[inline]
fn to_unit(bits: u32) -> f32 {
    (bits >> 8) as f32 * UNIT
}

/// `2^−24`: [`to_unit`]'s scale from 24 bits to `[0, 1)`.
const UNIT: f32 = 1.0 / (1u32 << 24) as f32;

/// The key of pixel `pixel` under `seed`.
#[inline]
fn pixel_key(seed: u32, pixel: u32) -> u64 {
    mix64(((seed as u64) << 32) | pixel as u64)
}

/// The sample-independent hash of dimension `dim` of the pixel with `key`
/// (it keys the dimension's permutation).
#[inline]
fn dim_hash(key: u64, dim: u32) -> u64 {
    mix64(key ^ u64::from(dim).wrapping_mul(GOLDEN))
}

/// Odd constant that spreads sample indices over the 64-bit key space.
const SAMPLE_STEP: u64 = 0xD1B5_4A32_D192_ED03;

/// The golden-ratio Weyl step between unstratified dimensions.
const GOLDEN: u64 = 0x9E37_79B9_7F4A_7C15;

/// The Weyl step `key + (dim + 1)·φ` of dimension `dim` from a per-sample
/// key (wrapping, so steps of dimensions `d` and `d + k` differ by `k·φ`).
#[inline(always)]
fn weyl(key: u64, dim: u32) -> u64 {
    key.wrapping_add(u64::from(dim + 1).wrapping_mul(GOLDEN))
}

/// 32 well-mixed bits of a Weyl step `x`: one xorshift–multiply, high half
/// of the product (it depends on every bit of the multiplicand).
#[inline(always)]
fn mix_weyl(x: u64) -> u32 {
    ((x ^ (x >> 32)).wrapping_mul(MIX_WEYL) >> 32) as u32
}

/// The odd multiplier of the permutation's third round.
const PERMUTE_MUL: u32 = 0x6935_FA69;

/// The multiplier of [`mix_weyl`].
const MIX_WEYL: u64 = 0xD6E8_FEB8_6659_FD93;

/// A 64-bit finaliser (Stafford's variant 13 of MurmurHash3's fmix64).
#[inline]
fn mix64(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(MIX64[0]);
    z = (z ^ (z >> 27)).wrapping_mul(MIX64[1]);
    z ^ (z >> 31)
}

/// [`mix64`]'s two multipliers.
const MIX64: [u64; 2] = [0xBF58_476D_1CE4_E5B9, 0x94D0_49BB_1331_11EB];

#[cfg(test)]
mod tests;
