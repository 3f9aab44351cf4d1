//! The avx512 backend's `u64` lanes.

use super::*;
use crate::simd::U64Ops;

impl U64Ops for Avx512 {
    #[inline(always)]
    fn u64_splat(self, x: u64) -> Self::U64 {
        let v = avx!(_mm512_set1_epi64(x as i64));
        [v, v]
    }
    #[cfg(test)]
    #[inline(always)]
    fn u64_load(self, lanes: [u64; LANES]) -> Self::U64 {
        // Each `loadu` reads eight of the sixteen `u64` of `lanes`.
        [
            avx!(_mm512_loadu_si512(lanes.as_ptr().cast())),
            avx!(_mm512_loadu_si512(lanes[8..].as_ptr().cast())),
        ]
    }
    #[inline(always)]
    fn u64_store(self, v: Self::U64) -> [u64; LANES] {
        let mut out = [0; LANES];
        // Each `storeu` writes eight of the sixteen `u64` of `out`.
        avx!(_mm512_storeu_si512(out.as_mut_ptr().cast(), v[0]));
        avx!(_mm512_storeu_si512(out[8..].as_mut_ptr().cast(), v[1]));
        out
    }
    #[inline(always)]
    fn u64_add(self, a: Self::U64, b: Self::U64) -> Self::U64 {
        both!(_mm512_add_epi64(a, b))
    }
    #[inline(always)]
    fn u64_mul(self, a: Self::U64, b: Self::U64) -> Self::U64 {
        both!(_mm512_mullo_epi64(a, b))
    }
    #[inline(always)]
    fn u64_xor(self, a: Self::U64, b: Self::U64) -> Self::U64 {
        both!(_mm512_xor_si512(a, b))
    }
    #[inline(always)]
    fn u64_shr(self, a: Self::U64, n: u32) -> Self::U64 {
        let n = avx!(_mm512_set1_epi64(i64::from(n)));
        both!(_mm512_srlv_epi64(a, [n, n]))
    }
    #[inline(always)]
    fn u64_from_u32(self, a: Self::U32) -> Self::U64 {
        [
            avx!(_mm512_cvtepu32_epi64(_mm512_castsi512_si256(a))),
            avx!(_mm512_cvtepu32_epi64(_mm512_extracti64x4_epi64::<1>(a))),
        ]
    }
    #[inline(always)]
    fn u64_low_u32(self, a: Self::U64) -> Self::U32 {
        let [lo, hi] = both!(_mm512_cvtepi64_epi32(a));
        avx!(_mm512_inserti64x4::<1>(_mm512_castsi256_si512(lo), hi))
    }
    #[inline(always)]
    unsafe fn u64_gather(
        self,
        table: &[u64],
        index: Self::U32,
        m: Mask16,
        fallback: Self::U64,
    ) -> Self::U64 {
        let [lo, hi] = halves(m);
        // Every lane read (those of `m`) indexes `table` in bounds (the
        // caller's contract).
        [
            avx!(_mm512_mask_i32gather_epi64::<8>(
                fallback[0],
                lo,
                _mm512_castsi512_si256(index),
                table.as_ptr().cast()
            )),
            avx!(_mm512_mask_i32gather_epi64::<8>(
                fallback[1],
                hi,
                _mm512_extracti64x4_epi64::<1>(index),
                table.as_ptr().cast()
            )),
        ]
    }
    #[inline(always)]
    unsafe fn u64_expand(self, a: Self::U64, m: Mask16, src: &[u64]) -> Self::U64 {
        let [lo, hi] = halves(m);
        let rest = &src[lo.count_ones() as usize..];
        // Each load reads as many consecutive `u64`s as its half of `m` has
        // lanes: `src` from 0, then from the first half's count, both in
        // bounds (the caller's contract).
        [
            avx!(_mm512_mask_expandloadu_epi64(a[0], lo, src.as_ptr().cast())),
            avx!(_mm512_mask_expandloadu_epi64(
                a[1],
                hi,
                rest.as_ptr().cast()
            )),
        ]
    }
}
