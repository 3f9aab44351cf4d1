//! The avx2 backend's `u32` lanes.

use super::*;
use crate::simd::U32Ops;

impl U32Ops for Avx2 {
    #[inline(always)]
    fn u32_splat(self, x: u32) -> Self::U32 {
        let v = avx!(_mm256_set1_epi32(x as i32));
        [v, v]
    }
    #[inline(always)]
    fn u32_load(self, lanes: [u32; LANES]) -> Self::U32 {
        // Each `loadu` reads eight of the sixteen `u32` of `lanes`.
        avx!([
            _mm256_loadu_si256(lanes.as_ptr().cast()),
            _mm256_loadu_si256(lanes[8..].as_ptr().cast()),
        ])
    }
    #[inline(always)]
    fn u32_store(self, v: Self::U32) -> [u32; LANES] {
        let mut out = [0; LANES];
        // Each `storeu` writes eight of the sixteen `u32` of `out`.
        avx!(_mm256_storeu_si256(out.as_mut_ptr().cast(), v[0]));
        avx!(_mm256_storeu_si256(out[8..].as_mut_ptr().cast(), v[1]));
        out
    }
    #[inline(always)]
    fn u32_add(self, a: Self::U32, b: Self::U32) -> Self::U32 {
        each!(2, _mm256_add_epi32(a, b))
    }
    #[inline(always)]
    fn u32_sub(self, a: Self::U32, b: Self::U32) -> Self::U32 {
        each!(2, _mm256_sub_epi32(a, b))
    }
    #[inline(always)]
    fn u32_mul(self, a: Self::U32, b: Self::U32) -> Self::U32 {
        each!(2, _mm256_mullo_epi32(a, b))
    }
    #[inline(always)]
    fn u32_and(self, a: Self::U32, b: Self::U32) -> Self::U32 {
        each!(2, _mm256_and_si256(a, b))
    }
    #[inline(always)]
    fn u32_or(self, a: Self::U32, b: Self::U32) -> Self::U32 {
        each!(2, _mm256_or_si256(a, b))
    }
    #[inline(always)]
    fn u32_xor(self, a: Self::U32, b: Self::U32) -> Self::U32 {
        each!(2, _mm256_xor_si256(a, b))
    }
    #[inline(always)]
    fn u32_shr(self, a: Self::U32, n: u32) -> Self::U32 {
        let n = self.u32_splat(n);
        each!(2, _mm256_srlv_epi32(a, n))
    }
    #[inline(always)]
    fn u32_shl(self, a: Self::U32, n: u32) -> Self::U32 {
        let n = self.u32_splat(n);
        each!(2, _mm256_sllv_epi32(a, n))
    }
    #[inline(always)]
    fn u32_shr_signed(self, a: Self::U32, n: u32) -> Self::U32 {
        let n = self.u32_splat(n);
        each!(2, _mm256_srav_epi32(a, n))
    }
    #[inline(always)]
    fn u32_select(self, m: Mask16, a: Self::U32, b: Self::U32) -> Self::U32 {
        // `blendv_ps` reads each lane's sign bit, as `mask32` sets it.
        let m = each!(2, _mm256_castsi256_ps(mask32(m)));
        let (a, b) = (
            each!(2, _mm256_castsi256_ps(a)),
            each!(2, _mm256_castsi256_ps(b)),
        );
        let blend = each!(2, _mm256_blendv_ps(b, a, m));
        each!(2, _mm256_castps_si256(blend))
    }
    #[inline(always)]
    fn u32_lt(self, a: Self::U32, b: Self::U32) -> Mask16 {
        // Unsigned order is the signed order with the sign bits flipped.
        let flip = self.u32_splat(1 << 31);
        let (a, b) = (self.u32_xor(a, flip), self.u32_xor(b, flip));
        let lt = each!(2, _mm256_cmpgt_epi32(b, a));
        pack32(each!(2, _mm256_castsi256_ps(lt)))
    }
    #[inline(always)]
    fn u32_eq(self, a: Self::U32, b: Self::U32) -> Mask16 {
        let eq = each!(2, _mm256_cmpeq_epi32(a, b));
        pack32(each!(2, _mm256_castsi256_ps(eq)))
    }
    #[inline(always)]
    unsafe fn u32_gather(
        self,
        table: &[u32],
        index: Self::U32,
        m: Mask16,
        fallback: Self::U32,
    ) -> Self::U32 {
        let m = mask32(m);
        let base: [*const i32; 2] = [table.as_ptr().cast(), table.as_ptr().cast()];
        // Every lane read (those of `m`) indexes `table` in bounds (the
        // caller's contract).
        each!(
            2,
            _mm256_mask_i32gather_epi32::<4>(fallback, base, index, m)
        )
    }
}
