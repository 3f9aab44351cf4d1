//! The avx512 backend's `f64` lanes.

use super::*;
use crate::simd::F64Ops;

impl F64Ops for Avx512 {
    #[inline(always)]
    fn f64_splat(self, x: f64) -> Self::F64 {
        let v = avx!(_mm512_set1_pd(x));
        [v, v]
    }
    #[inline(always)]
    fn f64_load(self, lanes: [f64; LANES]) -> Self::F64 {
        // Each `loadu` reads eight of the sixteen `f64` of `lanes`.
        [
            avx!(_mm512_loadu_pd(lanes.as_ptr())),
            avx!(_mm512_loadu_pd(lanes[8..].as_ptr())),
        ]
    }
    #[inline(always)]
    fn f64_store(self, v: Self::F64) -> [f64; LANES] {
        let mut out = [0.0; LANES];
        // Each `storeu` writes eight of the sixteen `f64` of `out`.
        avx!(_mm512_storeu_pd(out.as_mut_ptr(), v[0]));
        avx!(_mm512_storeu_pd(out[8..].as_mut_ptr(), v[1]));
        out
    }
    #[inline(always)]
    fn f64_add(self, a: Self::F64, b: Self::F64) -> Self::F64 {
        both!(_mm512_add_pd(a, b))
    }
    #[inline(always)]
    fn f64_sub(self, a: Self::F64, b: Self::F64) -> Self::F64 {
        both!(_mm512_sub_pd(a, b))
    }
    #[inline(always)]
    fn f64_mul(self, a: Self::F64, b: Self::F64) -> Self::F64 {
        both!(_mm512_mul_pd(a, b))
    }
    #[inline(always)]
    fn f64_div(self, a: Self::F64, b: Self::F64) -> Self::F64 {
        both!(_mm512_div_pd(a, b))
    }
    #[inline(always)]
    fn f64_neg(self, a: Self::F64) -> Self::F64 {
        let sign = avx!(_mm512_set1_pd(-0.0));
        both!(_mm512_xor_pd(a, [sign, sign]))
    }
    #[inline(always)]
    fn f64_sqrt(self, a: Self::F64) -> Self::F64 {
        both!(_mm512_sqrt_pd(a))
    }
    #[inline(always)]
    fn f64_abs(self, a: Self::F64) -> Self::F64 {
        both!(_mm512_abs_pd(a))
    }
    #[inline(always)]
    fn f64_min(self, a: Self::F64, b: Self::F64) -> Self::F64 {
        both!(_mm512_min_pd(a, b))
    }
    #[inline(always)]
    fn f64_max(self, a: Self::F64, b: Self::F64) -> Self::F64 {
        both!(_mm512_max_pd(a, b))
    }
    #[inline(always)]
    fn f64_select(self, m: Mask16, a: Self::F64, b: Self::F64) -> Self::F64 {
        both!(_mm512_mask_blend_pd(halves(m), b, a))
    }
    #[inline(always)]
    fn f64_copysign(self, magnitude: Self::F64, sign: Self::F64) -> Self::F64 {
        // Ternary logic 0xCA (`a ? b : c` bitwise): bits of `sign` where the
        // sign mask is set, of `magnitude` elsewhere.
        let mask = avx!(_mm512_castpd_si512(_mm512_set1_pd(-0.0)));
        let half = |m: __m512d, s: __m512d| {
            avx!(_mm512_castsi512_pd(_mm512_ternarylogic_epi64::<0xCA>(
                mask,
                _mm512_castpd_si512(s),
                _mm512_castpd_si512(m),
            )))
        };
        [half(magnitude[0], sign[0]), half(magnitude[1], sign[1])]
    }
    #[inline(always)]
    fn f64_cmp(self, a: Self::F64, b: Self::F64, c: Cmp) -> Mask16 {
        let [lo, hi] = match c {
            Cmp::Lt => both!(_mm512_cmp_pd_mask::<_CMP_LT_OQ>(a, b)),
            Cmp::Le => both!(_mm512_cmp_pd_mask::<_CMP_LE_OQ>(a, b)),
            Cmp::Gt => both!(_mm512_cmp_pd_mask::<_CMP_GT_OQ>(a, b)),
            Cmp::Ge => both!(_mm512_cmp_pd_mask::<_CMP_GE_OQ>(a, b)),
            Cmp::Eq => both!(_mm512_cmp_pd_mask::<_CMP_EQ_OQ>(a, b)),
        };
        Mask16(u16::from(lo) | u16::from(hi) << 8)
    }
    #[inline(always)]
    fn f64_to_f32(self, a: Self::F64) -> Self::F32 {
        let [lo, hi] = both!(_mm512_cvtpd_ps(a));
        avx!(_mm512_insertf32x8::<1>(_mm512_castps256_ps512(lo), hi))
    }
}
