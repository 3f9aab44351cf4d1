//! The streams of sixteen paths at once, one per lane, for the wide tracer:
//! a lane's numbers are those of
//! [`PixelSampler::get_1d`](super::PixelSampler::get_1d) for its own
//! pixel, sample and dimension, so they are bit-identical (tests compare
//! them).
//!
//! A path's stratified numbers (the film position and the first bounce's
//! block) are drawn when it starts, sixteen starting samples at once
//! ([`TileKeys::starts16`], the pixels' permutation keys splatted or
//! gathered), and its first bounce block is kept per lane; the unstratified
//! numbers of later bounces are hashed for all sixteen lanes at once
//! ([`Streams16::block16`]).

use super::{
    BLOCK, GOLDEN, MIX_WEYL, MIX64, ONE_MINUS_EPSILON, PERMUTE_MUL, PixelKeys, SAMPLE_STEP,
    STRATIFIED, UNIT, Word, permute,
};
use crate::simd::{F32x16, Lanes, Mask16, U32x16, U64x16};

impl<B: Lanes> Word for U32x16<B> {
    #[inline(always)]
    fn times(self, other: Self) -> Self {
        self * other
    }
}

/// A tile's pixels' keys, for drawing the first numbers of sixteen of its
/// samples at once.
#[derive(Clone, Debug)]
pub(crate) struct TileKeys {
    /// Each pixel's [`PixelKeys`], in the tile's order.
    pixels: Vec<PixelKeys>,
    /// Each pixel's key (what its samples' keys hash).
    key: Vec<u64>,
    /// `xor[r][d·n + i]`: round `r`'s xor key of dimension `d` of pixel `i`
    /// (of `n`).
    xor: [Vec<u32>; 3],
    /// `mul[r][d·n + i]`: round `r`'s multiplier of dimension `d` of pixel
    /// `i`.
    mul: [Vec<u32>; 2],
}

/// The first numbers of sixteen samples, one per lane.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Starts16<B: Lanes> {
    /// The per-sample keys ([`PixelSampler`](super::PixelSampler)'s).
    pub key: U64x16<B>,
    /// The film position's numbers (dimensions 0 and 1).
    pub film: [F32x16<B>; 2],
    /// The first bounce block (dimensions `2 .. 2 + BLOCK`).
    pub first: [F32x16<B>; BLOCK],
}

impl TileKeys {
    /// The keys of `pixels` (linear pixel indices, e.g. `y·width + x`) under
    /// `seed` for `spp` samples per pixel.
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
            key: pixels.iter().map(|p| p.key).collect(),
            xor: [
                table(|p| &p.xor[0]),
                table(|p| &p.xor[1]),
                table(|p| &p.xor[2]),
            ],
            mul: [table(|p| &p.mul[0]), table(|p| &p.mul[1])],
            pixels,
        }
    }

    /// The first numbers of sample `sample` of pixel `pixel` (its index in
    /// the tile) in every lane of `m`: exactly what the scalar
    /// [`PixelSampler`](super::PixelSampler) of that sample draws (other lanes unspecified).
    /// Lanes of one pixel use its keys as they are; lanes of several pixels
    /// gather theirs.
    #[inline(always)]
    pub fn starts16<B: Lanes>(
        &self,
        k: B,
        pixel: U32x16<B>,
        sample: U32x16<B>,
        m: Mask16,
    ) -> Starts16<B> {
        let zero64 = k.u64(0);
        let pixel_key = U64x16::gather(&self.key, pixel, m, zero64);
        let key = mix64_16(
            k,
            pixel_key ^ (U64x16::from_u32(sample) * k.u64(SAMPLE_STEP)),
        );
        let first_lane = m.lanes().next().unwrap_or(0);
        let one_pixel = (pixel.eq(k.u32(pixel.lane(first_lane))) | !m).all();
        let keys = &self.pixels[pixel.lane(first_lane) as usize];
        let n = k.u32(self.pixels.len() as u32);
        let mut numbers = [k.f32(0.0); STRATIFIED];
        let mut x = key + k.u64(GOLDEN);
        for (dim, number) in numbers.iter_mut().enumerate() {
            let jitter = unit16(k, x);
            x = x + k.u64(GOLDEN);
            let (xor, mul) = if one_pixel {
                let [x0, x1, x2] = [keys.xor[0][dim], keys.xor[1][dim], keys.xor[2][dim]];
                let [m0, m1] = [keys.mul[0][dim], keys.mul[1][dim]];
                (
                    [k.u32(x0), k.u32(x1), k.u32(x2)],
                    [k.u32(m0), k.u32(m1), k.u32(PERMUTE_MUL)],
                )
            } else {
                let index = k.u32(dim as u32) * n + pixel;
                let zero = k.u32(0);
                (
                    [
                        U32x16::gather(&self.xor[0], index, m, zero),
                        U32x16::gather(&self.xor[1], index, m, zero),
                        U32x16::gather(&self.xor[2], index, m, zero),
                    ],
                    [
                        U32x16::gather(&self.mul[0], index, m, zero),
                        U32x16::gather(&self.mul[1], index, m, zero),
                        k.u32(PERMUTE_MUL),
                    ],
                )
            };
            let (mask, shifts) = (k.u32(keys.mask), keys.shifts);
            let mut stratum = permute(sample, xor, mul, mask, shifts);
            // Cycle-walking, until every lane of `m` is in range.
            loop {
                let outside = m & stratum.ge(k.u32(keys.count));
                if !outside.any() {
                    break;
                }
                stratum =
                    U32x16::select(outside, permute(stratum, xor, mul, mask, shifts), stratum);
            }
            *number = ((F32x16::from_u32(stratum) + jitter) * k.f32(keys.inv_count))
                .min(k.f32(ONE_MINUS_EPSILON));
        }
        let mut first = [k.f32(0.0); BLOCK];
        first.copy_from_slice(&numbers[STRATIFIED - BLOCK..]);
        Starts16 {
            key,
            film: [numbers[0], numbers[1]],
            first,
        }
    }
}

/// `to_unit(mix_weyl(x))` in every lane: the number of a Weyl step.
#[inline(always)]
fn unit16<B: Lanes>(k: B, x: U64x16<B>) -> F32x16<B> {
    let bits = (((x ^ (x >> 32)) * k.u64(MIX_WEYL)) >> 32).low_u32();
    F32x16::from_u32(bits >> 8) * k.f32(UNIT)
}

/// `mix64` in every lane.
#[inline(always)]
fn mix64_16<B: Lanes>(k: B, z: U64x16<B>) -> U64x16<B> {
    let z = (z ^ (z >> 30)) * k.u64(MIX64[0]);
    let z = (z ^ (z >> 27)) * k.u64(MIX64[1]);
    z ^ (z >> 31)
}

/// Sixteen lanes' numbers of dimensions `first .. first + BLOCK`, each lane
/// with its own `first`: the wide [`Block`](super::Block).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Block16<B: Lanes> {
    numbers: [F32x16<B>; BLOCK],
}

impl<B: Lanes> Block16<B> {
    /// The numbers of dimension `first + offset` (`offset < BLOCK`).
    #[inline(always)]
    pub fn get_1d(&self, offset: u32) -> F32x16<B> {
        self.numbers[offset as usize]
    }

    /// The numbers of dimensions `first + offset` and `first + offset + 1`.
    #[inline(always)]
    pub fn get_2d(&self, offset: u32) -> [F32x16<B>; 2] {
        [self.get_1d(offset), self.get_1d(offset + 1)]
    }
}

/// The random streams of sixteen paths, one per lane: what a lane keeps of
/// its sample's [`Starts16`].
#[derive(Clone, Copy, Debug)]
pub(crate) struct Streams16<B: Lanes> {
    /// Each lane's per-sample key ([`PixelSampler`](super::PixelSampler)(super::PixelSampler)'s).
    pub key: U64x16<B>,
    /// Each lane's first bounce block.
    pub first: [F32x16<B>; BLOCK],
}

impl<B: Lanes> Streams16<B> {
    /// Streams of key 0 and zero numbers (lanes get theirs as they start).
    #[inline(always)]
    pub fn new(k: B) -> Self {
        Self {
            key: k.u64(0),
            first: [k.f32(0.0); BLOCK],
        }
    }

    /// The numbers of dimensions `first .. first + BLOCK`, `first` per lane:
    /// the first bounce block in the lanes of `first_bounce`, the
    /// unstratified dimensions from `first` on in the others (a path's later
    /// blocks lie past the stratified dimensions).
    #[inline(always)]
    pub fn block16(&self, k: B, first: U32x16<B>, first_bounce: Mask16) -> Block16<B> {
        let golden = k.u64(GOLDEN);
        // weyl(key, first) = key + (first + 1)·φ; the next dimensions add φ each.
        let mut x = self.key + (U64x16::from_u32(first) + k.u64(1)) * golden;
        let mut numbers = self.first;
        for number in &mut numbers {
            let hashed = unit16(k, x);
            x = x + golden;
            *number = F32x16::select(first_bounce, *number, hashed);
        }
        Block16 { numbers }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampler::STRATIFIED_DIMENSIONS;
    use crate::simd::LANES;

    /// Every lane's first numbers and later blocks are the scalar sampler's
    /// for its own pixel and sample: batches of one pixel (splatted keys)
    /// and of several (gathered keys), spp powers of two and not.
    #[test]
    fn lane_numbers_are_the_scalar_numbers() {
        fn on<B: Lanes>(k: B) {
            for spp in [1u32, 7, 16, 64, 100] {
                let pixels: Vec<u32> = (0..40).map(|p| p * 977 + 3).collect();
                let keys = TileKeys::new(5, pixels.iter().copied(), spp);
                for batch in 0..12u64 {
                    let seq: [u64; LANES] = std::array::from_fn(|i| batch * 13 + i as u64);
                    let pixel = seq.map(|s| ((s / u64::from(spp)) % 40) as u32);
                    let sample = seq.map(|s| (s % u64::from(spp)) as u32);
                    let m = Mask16::first(LANES - batch as usize % 3);
                    let px = U32x16::from_array(k, pixel);
                    let starts = keys.starts16(k, px, U32x16::from_array(k, sample), m);
                    let streams = Streams16 {
                        key: starts.key,
                        first: starts.first,
                    };
                    for lane in m.lanes() {
                        let scalar = keys.pixels[pixel[lane] as usize].sampler(sample[lane]);
                        assert_eq!(starts.key.to_array()[lane], scalar.sample_key);
                        for d in 0..2 {
                            assert_eq!(
                                starts.film[d].lane(lane).to_bits(),
                                scalar.get_1d(d as u32).to_bits()
                            );
                        }
                    }
                    // Lanes at mixed bounces: the first in some, later ones in others.
                    for round in 0..4u32 {
                        let bounce: [u32; LANES] = std::array::from_fn(|i| (i as u32 + round) % 4);
                        let first =
                            bounce.map(|b| STRATIFIED_DIMENSIONS - BLOCK as u32 + b * BLOCK as u32);
                        let mut first_bounce = Mask16::NONE;
                        for (lane, &b) in bounce.iter().enumerate() {
                            first_bounce.0 |= u16::from(b == 0) << lane;
                        }
                        let block = streams.block16(k, U32x16::from_array(k, first), first_bounce);
                        for lane in m.lanes() {
                            let scalar = keys.pixels[pixel[lane] as usize].sampler(sample[lane]);
                            let expected = scalar.block(first[lane]);
                            for offset in 0..BLOCK as u32 {
                                assert_eq!(
                                    block.get_1d(offset).lane(lane).to_bits(),
                                    expected.get_1d(offset).to_bits(),
                                    "spp {spp}, lane {lane}, dimension {}",
                                    first[lane] + offset
                                );
                            }
                        }
                    }
                }
            }
        }
        crate::simd::each_backend!(on);
    }
}
