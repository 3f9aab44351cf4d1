//! The streams of sixteen paths at once, one per lane, for the wide tracer:
//! a lane's numbers are those of [`PixelSampler::get_1d`] for its own pixel,
//! sample and dimension, by the same integer hashes and `f32` operations,
//! so they are bit-identical (tests compare them).
//!
//! A tile's pixels keep their stratified dimensions' permutation keys in
//! [`TileKeys`], by round, dimension and pixel, so a lane gathers its
//! pixel's keys; the stratum count (samples per pixel) and the shifts are
//! the same for every pixel of a render.

use super::{
    BLOCK, GOLDEN, MIX_WEYL, ONE_MINUS_EPSILON, PERMUTE_MUL, PixelKeys, PixelSampler, STRATIFIED,
    UNIT,
};
use crate::simd::{Avx512, F32x16, LANES, Mask16, U32x16, U64x16};

/// The permutation keys of a list of pixels (a tile's), for gathers by the
/// pixel's position in the list.
#[derive(Clone, Debug)]
pub(crate) struct TileKeys {
    /// Each pixel's [`PixelKeys`], in list order.
    pixels: Vec<PixelKeys>,
    /// `xor[r][d·n + i]`: round `r`'s xor key of dimension `d` of pixel
    /// `i` (of `n`).
    xor: [Vec<u32>; 3],
    /// `mul[r][d·n + i]`: round `r`'s odd multiplier of dimension `d` of
    /// pixel `i` (of `n`).
    mul: [Vec<u32>; 2],
}

/// Sixteen lanes' numbers of dimensions `first .. first + BLOCK`, each lane
/// with its own `first`: the wide [`Block`](super::Block).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Block16 {
    numbers: [F32x16; BLOCK],
}

impl Block16 {
    /// The numbers of dimension `first + offset` (`offset < BLOCK`).
    #[inline(always)]
    pub fn get_1d(&self, offset: u32) -> F32x16 {
        self.numbers[offset as usize]
    }

    /// The numbers of dimensions `first + offset` and `first + offset + 1`.
    #[inline(always)]
    pub fn get_2d(&self, offset: u32) -> [F32x16; 2] {
        [self.get_1d(offset), self.get_1d(offset + 1)]
    }
}

/// The per-path state of a lane's stream: which pixel of the [`TileKeys`]
/// list, which sample, and the sample's key.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Streams16 {
    /// The pixel's position in the [`TileKeys`] list.
    pub pixel: U32x16,
    /// The sample index within the pixel.
    pub sample: U32x16,
    /// The per-sample key ([`PixelSampler`]'s `sample_key`).
    pub key: U64x16,
}

impl TileKeys {
    /// The keys of `pixels` (linear pixel indices, e.g. `y·width + x`)
    /// under `seed` for `spp` samples.
    pub fn new(seed: u32, pixels: impl Iterator<Item = u32>, spp: u32) -> Self {
        let pixels: Vec<PixelKeys> = pixels.map(|p| PixelKeys::new(seed, p, spp)).collect();
        let table = |keys: fn(&PixelKeys) -> &[u32; STRATIFIED]| {
            let mut flat = Vec::with_capacity(STRATIFIED * pixels.len());
            for d in 0..STRATIFIED {
                flat.extend(pixels.iter().map(|p| keys(p)[d]));
            }
            flat
        };
        Self {
            xor: [
                table(|p| &p.xor[0]),
                table(|p| &p.xor[1]),
                table(|p| &p.xor[2]),
            ],
            mul: [table(|p| &p.mul[0]), table(|p| &p.mul[1])],
            pixels,
        }
    }

    /// The stream of sample `sample` of the pixel at `index` in the list
    /// (what a scalar path of it would draw from).
    pub fn sampler(&self, index: usize, sample: u32) -> PixelSampler<'_> {
        self.pixels[index].sampler(sample)
    }

    /// The numbers of dimensions `first .. first + BLOCK` in every lane of
    /// `active`, `first` per lane: the stratified dimensions where `first +
    /// BLOCK ≤ STRATIFIED`, the unstratified ones where `first ≥
    /// STRATIFIED` (the blocks a path draws never straddle the two). Other
    /// lanes hold unspecified numbers.
    #[inline(always)]
    pub fn block16(
        &self,
        k: Avx512,
        streams: &Streams16,
        first: U32x16,
        active: Mask16,
    ) -> Block16 {
        let jitters = jitters16::<BLOCK>(k, streams.key, first);
        let stratified = active & first.lt(U32x16::splat(k, STRATIFIED as u32));
        if !stratified.any() {
            return Block16 { numbers: jitters };
        }
        let mut numbers = jitters;
        for (offset, number) in numbers.iter_mut().enumerate() {
            let dim = first + U32x16::splat(k, offset as u32);
            let value = self.stratified16(k, streams, dim, *number, stratified);
            *number = F32x16::select(stratified, value, *number);
        }
        Block16 { numbers }
    }

    /// The stratified number of dimension `dim` (per lane, `< STRATIFIED`)
    /// with jitter `jitter`, in the lanes of `m`: the stratum of the lane's
    /// sample under the dimension's permutation, plus the jitter, scaled.
    #[inline(always)]
    pub fn stratified16(
        &self,
        k: Avx512,
        streams: &Streams16,
        dim: U32x16,
        jitter: F32x16,
        m: Mask16,
    ) -> F32x16 {
        let keys = &self.pixels[0];
        let count = U32x16::splat(k, keys.count);
        // Gather index of (dimension, pixel) in the flattened key tables.
        let index = dim * U32x16::splat(k, self.pixels.len() as u32) + streams.pixel;
        let zero = U32x16::splat(k, 0);
        let gather = |table: &[u32]| U32x16::gather(table, index, m, zero);
        let xor = [
            gather(&self.xor[0]),
            gather(&self.xor[1]),
            gather(&self.xor[2]),
        ];
        let mul = [gather(&self.mul[0]), gather(&self.mul[1])];
        let rounds = |i: U32x16| {
            let [r0, r1, r2] = keys.shifts;
            let mask = U32x16::splat(k, keys.mask);
            let mut i = ((i ^ xor[0]) * mul[0]) & mask;
            i = i ^ (i >> r0);
            i = ((i ^ xor[1]) * mul[1]) & mask;
            i = i ^ (i >> r1);
            i = ((i ^ xor[2]) * U32x16::splat(k, PERMUTE_MUL)) & mask;
            i ^ (i >> r2)
        };
        let mut stratum = rounds(streams.sample);
        // Cycle-walking, lane by lane until every lane of `m` is in range.
        loop {
            let outside = m & stratum.ge(count);
            if !outside.any() {
                break;
            }
            stratum = U32x16::select(outside, rounds(stratum), stratum);
        }
        ((F32x16::from_u32(stratum) + jitter) * F32x16::splat(k, keys.inv_count))
            .min(F32x16::splat(k, ONE_MINUS_EPSILON))
    }

    /// The film position's two numbers (dimensions 0 and 1, stratified) in
    /// the lanes of `m`.
    #[inline(always)]
    pub fn film16(&self, k: Avx512, streams: &Streams16, m: Mask16) -> [F32x16; 2] {
        let zero = U32x16::splat(k, 0);
        let jitters = jitters16::<2>(k, streams.key, zero);
        std::array::from_fn(|d| {
            let dim = U32x16::splat(k, d as u32);
            self.stratified16(k, streams, dim, jitters[d], m)
        })
    }
}

/// `to_unit(mix_weyl(weyl(key, first + d)))` for `d < N` in every lane:
/// the jitters (and unstratified numbers) of a lane's dimensions from
/// `first` on.
#[inline(always)]
fn jitters16<const N: usize>(k: Avx512, key: U64x16, first: U32x16) -> [F32x16; N] {
    let golden = U64x16::splat(k, GOLDEN);
    // weyl(key, first) = key + (first + 1)·φ; the next dimensions add φ each.
    let mut x = key + (U64x16::from_u32(first) + U64x16::splat(k, 1)) * golden;
    let mix = U64x16::splat(k, MIX_WEYL);
    std::array::from_fn(|_| {
        let bits = ((x ^ (x >> 32)) * mix >> 32).low_u32();
        x = x + golden;
        F32x16::from_u32(bits >> 8) * F32x16::splat(k, UNIT)
    })
}

impl Streams16 {
    /// Streams with every lane at pixel 0, sample 0 and key 0 (lanes are
    /// set with [`Streams16::set`] before use).
    pub fn new(k: Avx512) -> Self {
        Self {
            pixel: U32x16::splat(k, 0),
            sample: U32x16::splat(k, 0),
            key: U64x16::splat(k, 0),
        }
    }

    /// Gives the lanes of `m` the streams of consecutive samples: lane
    /// after lane (lowest first), `(pixel, sample)` of each from `next`,
    /// which is advanced past them, with `spp` samples per pixel.
    pub fn set(&mut self, k: Avx512, keys: &TileKeys, m: Mask16, next: &mut (u32, u32), spp: u32) {
        let (mut pixel, mut sample, mut key) = (
            self.pixel.to_array(),
            self.sample.to_array(),
            self.key.to_array(),
        );
        for lane in m.lanes() {
            let (p, s) = *next;
            pixel[lane] = p;
            sample[lane] = s;
            key[lane] = keys.sampler(p as usize, s).sample_key;
            *next = if s + 1 < spp { (p, s + 1) } else { (p + 1, 0) };
        }
        debug_assert!(m.lanes().all(|lane| lane < LANES));
        *self = Self {
            pixel: U32x16::from_array(k, pixel),
            sample: U32x16::from_array(k, sample),
            key: U64x16::from_array(k, key),
        };
    }
}
