//! The avx512 backend's `u32` lanes.

use super::*;
use crate::simd::U32Ops;

impl U32Ops for Avx512 {
    #[inline(always)]
    fn u32_splat(self, x: u32) -> Self::U32 {
        avx!(_mm512_set1_epi32(x as i32))
    }
    #[inline(always)]
    fn u32_load(self, lanes: [u32; LANES]) -> Self::U32 {
        // `loadu` reads the sixteen `u32` of `lanes`.
        avx!(_mm512_loadu_si512(lanes.as_ptr().cast()))
    }
    #[inline(always)]
    fn u32_store(self, v: Self::U32) -> [u32; LANES] {
        let mut out = [0; LANES];
        // `storeu` writes the sixteen `u32` of `out`.
        avx!(_mm512_storeu_si512(out.as_mut_ptr().cast(), v));
        out
    }
    #[inline(always)]
    fn u32_add(self, a: Self::U32, b: Self::U32) -> Self::U32 {
        avx!(_mm512_add_epi32(a, b))
    }
    #[inline(always)]
    fn u32_sub(self, a: Self::U32, b: Self::U32) -> Self::U32 {
        avx!(_mm512_sub_epi32(a, b))
    }
    #[inline(always)]
    fn u32_mul(self, a: Self::U32, b: Self::U32) -> Self::U32 {
        avx!(_mm512_mullo_epi32(a, b))
    }
    #[inline(always)]
    fn u32_and(self, a: Self::U32, b: Self::U32) -> Self::U32 {
        avx!(_mm512_and_si512(a, b))
    }
    #[inline(always)]
    fn u32_or(self, a: Self::U32, b: Self::U32) -> Self::U32 {
        avx!(_mm512_or_si512(a, b))
    }
    #[inline(always)]
    fn u32_xor(self, a: Self::U32, b: Self::U32) -> Self::U32 {
        avx!(_mm512_xor_si512(a, b))
    }
    #[inline(always)]
    fn u32_shr(self, a: Self::U32, n: u32) -> Self::U32 {
        avx!(_mm512_srlv_epi32(a, _mm512_set1_epi32(n as i32)))
    }
    #[inline(always)]
    fn u32_shl(self, a: Self::U32, n: u32) -> Self::U32 {
        avx!(_mm512_sllv_epi32(a, _mm512_set1_epi32(n as i32)))
    }
    #[inline(always)]
    fn u32_shr_signed(self, a: Self::U32, n: u32) -> Self::U32 {
        avx!(_mm512_srav_epi32(a, _mm512_set1_epi32(n as i32)))
    }
    #[inline(always)]
    fn u32_select(self, m: Mask16, a: Self::U32, b: Self::U32) -> Self::U32 {
        avx!(_mm512_mask_blend_epi32(m.0, b, a))
    }
    #[inline(always)]
    fn u32_lt(self, a: Self::U32, b: Self::U32) -> Mask16 {
        Mask16(avx!(_mm512_cmplt_epu32_mask(a, b)))
    }
    #[inline(always)]
    fn u32_eq(self, a: Self::U32, b: Self::U32) -> Mask16 {
        Mask16(avx!(_mm512_cmpeq_epu32_mask(a, b)))
    }
    #[inline(always)]
    unsafe fn u32_gather(
        self,
        table: &[u32],
        index: Self::U32,
        m: Mask16,
        fallback: Self::U32,
    ) -> Self::U32 {
        // Every lane read (those of `m`) indexes `table` in bounds (the
        // caller's contract).
        avx!(_mm512_mask_i32gather_epi32::<4>(
            fallback,
            m.0,
            index,
            table.as_ptr().cast()
        ))
    }
}
