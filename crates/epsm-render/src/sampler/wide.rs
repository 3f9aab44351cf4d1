//! The streams of sixteen paths at once, one per lane, for the wide tracer:
//! a lane's numbers are those of [`PixelSampler::get_1d`] for its own pixel,
//! sample and dimension, so they are bit-identical (tests compare them).
//!
//! A path's first bounce block (stratified) is drawn once, when a lane takes
//! the path, by the scalar [`PixelSampler`] (whose block draws the eight
//! numbers together with AVX2): lanes gathering their pixels' permutation
//! keys at every bounce would cost more than the scalar draws of the few
//! paths that start per bounce. The unstratified numbers of later bounces
//! are hashed for all sixteen lanes at once.

use super::{BLOCK, GOLDEN, MIX_WEYL, PixelSampler, UNIT};
use crate::simd::{Avx512, F32x16, LANES, Mask16, U32x16, U64x16};

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

/// The random streams of sixteen paths, one per lane.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Streams16 {
    /// Each lane's per-sample key ([`PixelSampler`]'s `sample_key`).
    key: [u64; LANES],
    /// Each lane's first bounce block (dimensions `first_block ..
    /// first_block + BLOCK`).
    first: [[f32; LANES]; BLOCK],
}

impl Streams16 {
    /// Streams with nothing drawn (lanes get theirs from [`Self::start`]).
    pub fn new() -> Self {
        Self {
            key: [0; LANES],
            first: [[0.0; LANES]; BLOCK],
        }
    }

    /// Gives lane `lane` the stream `sampler`: its key, and its first
    /// bounce block (dimensions `first_block ..`) drawn by it.
    #[inline(always)]
    pub fn start(&mut self, lane: usize, sampler: &PixelSampler<'_>, first_block: u32) {
        self.key[lane] = sampler.sample_key;
        let block = sampler.block(first_block);
        for (offset, numbers) in self.first.iter_mut().enumerate() {
            numbers[lane] = block.numbers[offset];
        }
    }

    /// The numbers of dimensions `first .. first + BLOCK`, `first` per lane:
    /// the first bounce block drawn by [`Self::start`] in the lanes of
    /// `first_bounce`, the unstratified dimensions from `first` on in the
    /// others (a path's later blocks lie past the stratified dimensions).
    #[inline(always)]
    pub fn block16(&self, k: Avx512, first: U32x16, first_bounce: Mask16) -> Block16 {
        let golden = k.u64(GOLDEN);
        let key = U64x16::from_array(k, self.key);
        // weyl(key, first) = key + (first + 1)·φ; the next dimensions add φ each.
        let mut x = key + (U64x16::from_u32(first) + k.u64(1)) * golden;
        let mut numbers = [k.f32(0.0); BLOCK];
        for (number, drawn) in numbers.iter_mut().zip(&self.first) {
            // `to_unit(mix_weyl(x))`.
            let bits = (((x ^ (x >> 32)) * k.u64(MIX_WEYL)) >> 32).low_u32();
            x = x + golden;
            let hashed = F32x16::from_u32(bits >> 8) * k.f32(UNIT);
            *number = F32x16::select(first_bounce, F32x16::from_array(k, *drawn), hashed);
        }
        Block16 { numbers }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampler::{PixelKeys, STRATIFIED_DIMENSIONS};

    /// Every lane's block is the scalar sampler's block of its own sample
    /// and dimensions, at the first bounce and at later ones.
    #[test]
    fn lane_blocks_are_the_scalar_blocks() {
        let Some(k) = Avx512::detect() else {
            eprintln!("no AVX-512 on this CPU: nothing to test");
            return;
        };
        for spp in [1u32, 7, 64] {
            let keys: Vec<PixelKeys> = (0..LANES as u32)
                .map(|p| PixelKeys::new(5, p * 977, spp))
                .collect();
            let mut streams = Streams16::new();
            let samples: [u32; LANES] = std::array::from_fn(|i| (i as u32 * 5) % spp);
            for lane in 0..LANES {
                let sampler = keys[lane].sampler(samples[lane]);
                streams.start(lane, &sampler, STRATIFIED_DIMENSIONS - BLOCK as u32);
            }
            for round in 0..6u32 {
                // Lanes at mixed bounces: the first in some, later ones in others.
                let bounce: [u32; LANES] = std::array::from_fn(|i| (i as u32 + round) % 4);
                let first = bounce.map(|b| STRATIFIED_DIMENSIONS - BLOCK as u32 + b * BLOCK as u32);
                let mut first_bounce = Mask16::NONE;
                for (lane, &b) in bounce.iter().enumerate() {
                    first_bounce.0 |= u16::from(b == 0) << lane;
                }
                let block = streams.block16(k, U32x16::from_array(k, first), first_bounce);
                for lane in 0..LANES {
                    let scalar = keys[lane].sampler(samples[lane]).block(first[lane]);
                    for offset in 0..BLOCK as u32 {
                        assert_eq!(
                            block.get_1d(offset).lane(lane).to_bits(),
                            scalar.get_1d(offset).to_bits(),
                            "spp {spp}, lane {lane}, dimension {}",
                            first[lane] + offset
                        );
                    }
                }
            }
        }
    }
}
