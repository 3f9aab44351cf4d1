//! The avx512 backend's `f32` lanes.

use super::*;
use crate::simd::F32Ops;

impl F32Ops for Avx512 {
    #[inline(always)]
    fn f32_splat(self, x: f32) -> Self::F32 {
        avx!(_mm512_set1_ps(x))
    }
    #[inline(always)]
    fn f32_load(self, lanes: [f32; LANES]) -> Self::F32 {
        // `loadu` reads the sixteen `f32` of `lanes` (unaligned is allowed).
        avx!(_mm512_loadu_ps(lanes.as_ptr()))
    }
    #[inline(always)]
    fn f32_store(self, v: Self::F32) -> [f32; LANES] {
        let mut out = [0.0; LANES];
        // `storeu` writes the sixteen `f32` of `out`.
        avx!(_mm512_storeu_ps(out.as_mut_ptr(), v));
        out
    }
    #[inline(always)]
    fn f32_add(self, a: Self::F32, b: Self::F32) -> Self::F32 {
        avx!(_mm512_add_ps(a, b))
    }
    #[inline(always)]
    fn f32_sub(self, a: Self::F32, b: Self::F32) -> Self::F32 {
        avx!(_mm512_sub_ps(a, b))
    }
    #[inline(always)]
    fn f32_mul(self, a: Self::F32, b: Self::F32) -> Self::F32 {
        avx!(_mm512_mul_ps(a, b))
    }
    #[inline(always)]
    fn f32_div(self, a: Self::F32, b: Self::F32) -> Self::F32 {
        avx!(_mm512_div_ps(a, b))
    }
    #[inline(always)]
    fn f32_neg(self, a: Self::F32) -> Self::F32 {
        avx!(_mm512_xor_ps(a, _mm512_set1_ps(-0.0)))
    }
    #[inline(always)]
    fn f32_sqrt(self, a: Self::F32) -> Self::F32 {
        avx!(_mm512_sqrt_ps(a))
    }
    #[inline(always)]
    fn f32_abs(self, a: Self::F32) -> Self::F32 {
        avx!(_mm512_abs_ps(a))
    }
    #[inline(always)]
    fn f32_min(self, a: Self::F32, b: Self::F32) -> Self::F32 {
        avx!(_mm512_min_ps(a, b))
    }
    #[inline(always)]
    fn f32_max(self, a: Self::F32, b: Self::F32) -> Self::F32 {
        avx!(_mm512_max_ps(a, b))
    }
    #[inline(always)]
    fn f32_select(self, m: Mask16, a: Self::F32, b: Self::F32) -> Self::F32 {
        avx!(_mm512_mask_blend_ps(m.0, b, a))
    }
    #[inline(always)]
    fn f32_copysign(self, magnitude: Self::F32, sign: Self::F32) -> Self::F32 {
        // Ternary logic 0xCA (`a ? b : c` bitwise): bits of `sign` where the
        // sign mask is set, of `magnitude` elsewhere.
        avx!(_mm512_castsi512_ps(_mm512_ternarylogic_epi32::<0xCA>(
            _mm512_castps_si512(_mm512_set1_ps(-0.0)),
            _mm512_castps_si512(sign),
            _mm512_castps_si512(magnitude),
        )))
    }
    #[inline(always)]
    fn f32_cmp(self, a: Self::F32, b: Self::F32, c: Cmp) -> Mask16 {
        Mask16(match c {
            Cmp::Lt => avx!(_mm512_cmp_ps_mask::<_CMP_LT_OQ>(a, b)),
            Cmp::Le => avx!(_mm512_cmp_ps_mask::<_CMP_LE_OQ>(a, b)),
            Cmp::Gt => avx!(_mm512_cmp_ps_mask::<_CMP_GT_OQ>(a, b)),
            Cmp::Ge => avx!(_mm512_cmp_ps_mask::<_CMP_GE_OQ>(a, b)),
            Cmp::Eq => avx!(_mm512_cmp_ps_mask::<_CMP_EQ_OQ>(a, b)),
        })
    }
    #[inline(always)]
    fn f32_to_bits(self, a: Self::F32) -> Self::U32 {
        avx!(_mm512_castps_si512(a))
    }
    #[inline(always)]
    fn f32_from_bits(self, a: Self::U32) -> Self::F32 {
        avx!(_mm512_castsi512_ps(a))
    }
    #[inline(always)]
    fn f32_from_u32(self, a: Self::U32) -> Self::F32 {
        avx!(_mm512_cvtepu32_ps(a))
    }
    #[inline(always)]
    fn f32_trunc_i32(self, a: Self::F32) -> Self::U32 {
        avx!(_mm512_cvttps_epi32(a))
    }
    #[inline(always)]
    fn f32_to_f64(self, a: Self::F32) -> Self::F64 {
        avx!([
            _mm512_cvtps_pd(_mm512_castps512_ps256(a)),
            _mm512_cvtps_pd(_mm256_castpd_ps(_mm512_extractf64x4_pd::<1>(
                _mm512_castps_pd(a)
            ))),
        ])
    }
    #[inline(always)]
    fn f32_permute(self, a: Self::F32, index: Self::U32) -> Self::F32 {
        avx!(_mm512_permutexvar_ps(index, a))
    }
    #[inline(always)]
    fn f32_reduce_min(self, a: Self::F32, m: Mask16) -> f32 {
        avx!(_mm512_mask_reduce_min_ps(m.0, a))
    }
    #[inline(always)]
    unsafe fn f32_gather(
        self,
        table: &[f32],
        index: Self::U32,
        m: Mask16,
        fallback: Self::F32,
    ) -> Self::F32 {
        // Every lane read (those of `m`) indexes `table` in bounds (the
        // caller's contract).
        avx!(_mm512_mask_i32gather_ps::<4>(
            fallback,
            m.0,
            index,
            table.as_ptr()
        ))
    }
    #[inline(always)]
    unsafe fn f32_expand(self, a: Self::F32, m: Mask16, src: &[f32]) -> Self::F32 {
        // Reads `m.count()` consecutive `f32`s from `src`, in bounds (the
        // caller's contract).
        avx!(_mm512_mask_expandloadu_ps(a, m.0, src.as_ptr()))
    }
}
