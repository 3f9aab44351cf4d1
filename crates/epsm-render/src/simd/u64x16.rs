//! Sixteen `u64` lanes in two registers (wrapping arithmetic, as
//! `u64::wrapping_*`), for the sampler's 64-bit hashes.

use std::arch::x86_64::*;
use std::ops::Shr;

use super::{Avx512, LANES, Mask16, U32x16};

/// Sixteen `u64` lanes: lanes 0–7 in the first register, 8–15 in the
/// second (module docs of `simd`).
#[derive(Clone, Copy, Debug)]
pub(crate) struct U64x16(pub(super) [__m512i; 2]);

binary!(two U64x16;
    Add, add, _mm512_add_epi64;
    Mul, mul, _mm512_mullo_epi64;
    BitXor, bitxor, _mm512_xor_si512;
);

impl Shr<u32> for U64x16 {
    type Output = Self;
    /// Logical shift right of every lane by `n` (`≥ 64` gives 0).
    #[inline(always)]
    fn shr(self, n: u32) -> Self {
        let n = avx!(_mm512_set1_epi64(i64::from(n)));
        Self([
            avx!(_mm512_srlv_epi64(self.0[0], n)),
            avx!(_mm512_srlv_epi64(self.0[1], n)),
        ])
    }
}

impl U64x16 {
    /// Every lane `x`.
    #[inline(always)]
    pub fn splat(_: Avx512, x: u64) -> Self {
        let v = avx!(_mm512_set1_epi64(x as i64));
        Self([v, v])
    }

    #[cfg(test)]
    /// Lane `i` is `lanes[i]`.
    #[inline(always)]
    pub fn from_array(_: Avx512, lanes: [u64; LANES]) -> Self {
        // Each `loadu` reads eight of the sixteen `u64` of `lanes`.
        Self([
            avx!(_mm512_loadu_si512(lanes.as_ptr().cast())),
            avx!(_mm512_loadu_si512(lanes[8..].as_ptr().cast())),
        ])
    }

    /// The lanes as an array.
    #[inline(always)]
    pub fn to_array(self) -> [u64; LANES] {
        let mut out = [0; LANES];
        // Each `storeu` writes eight of the sixteen `u64` of `out`.
        avx!(_mm512_storeu_si512(out.as_mut_ptr().cast(), self.0[0]));
        avx!(_mm512_storeu_si512(out[8..].as_mut_ptr().cast(), self.0[1]));
        out
    }

    /// Each lane of `u` zero-extended.
    #[inline(always)]
    pub fn from_u32(u: U32x16) -> Self {
        Self([
            avx!(_mm512_cvtepu32_epi64(_mm512_castsi512_si256(u.0))),
            avx!(_mm512_cvtepu32_epi64(_mm512_extracti64x4_epi64::<1>(u.0))),
        ])
    }

    /// The low 32 bits of each lane (`as u32`).
    #[inline(always)]
    pub fn low_u32(self) -> U32x16 {
        let (lo, hi) = (
            avx!(_mm512_cvtepi64_epi32(self.0[0])),
            avx!(_mm512_cvtepi64_epi32(self.0[1])),
        );
        U32x16(avx!(_mm512_inserti64x4::<1>(
            _mm512_castsi256_si512(lo),
            hi
        )))
    }

    /// `self` with the lanes of `m` replaced by `src[0]`, `src[1]`, … in
    /// lane order (an expanding load).
    ///
    /// # Panics
    /// If `src` holds fewer values than `m` has lanes.
    #[inline(always)]
    pub fn expand_from(self, m: Mask16, src: &[u64]) -> Self {
        m.assert_expand_len(src.len());
        let (lo, hi) = (m.0 as u8, (m.0 >> 8) as u8);
        let rest = &src[lo.count_ones() as usize..];
        // Each load reads as many consecutive `u64`s as its half of `m` has
        // lanes: `src` from 0, then from the first half's count, both in
        // bounds (asserted).
        Self([
            avx!(_mm512_mask_expandloadu_epi64(
                self.0[0],
                lo,
                src.as_ptr().cast()
            )),
            avx!(_mm512_mask_expandloadu_epi64(
                self.0[1],
                hi,
                rest.as_ptr().cast()
            )),
        ])
    }

    /// `table[index]` in the lanes of `m`, `fallback` in the others.
    ///
    /// # Panics
    /// If an index of a lane in `m` is out of bounds.
    #[inline(always)]
    pub fn gather(table: &[u64], index: U32x16, m: Mask16, fallback: Self) -> Self {
        index.assert_gather_indices(m, table.len());
        let (lo, hi) = (m.0 as u8, (m.0 >> 8) as u8);
        // Every lane read (those of `m`) indexes `table` in bounds (asserted
        // above, and below `i32::MAX`, so the signed indices are the same).
        Self([
            avx!(_mm512_mask_i32gather_epi64::<8>(
                fallback.0[0],
                lo,
                _mm512_castsi512_si256(index.0),
                table.as_ptr().cast()
            )),
            avx!(_mm512_mask_i32gather_epi64::<8>(
                fallback.0[1],
                hi,
                _mm512_extracti64x4_epi64::<1>(index.0),
                table.as_ptr().cast()
            )),
        ])
    }
}
