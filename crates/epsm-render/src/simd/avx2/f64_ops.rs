//! The avx2 backend's `f64` lanes.

use super::*;
use crate::simd::F64Ops;

impl F64Ops for Avx2 {
    #[inline(always)]
    fn f64_splat(self, x: f64) -> Self::F64 {
        let v = avx!(_mm256_set1_pd(x));
        [v; 4]
    }
    #[inline(always)]
    fn f64_load(self, lanes: [f64; LANES]) -> Self::F64 {
        // Each `loadu` reads four of the sixteen `f64` of `lanes`.
        avx!([
            _mm256_loadu_pd(lanes.as_ptr()),
            _mm256_loadu_pd(lanes[4..].as_ptr()),
            _mm256_loadu_pd(lanes[8..].as_ptr()),
            _mm256_loadu_pd(lanes[12..].as_ptr()),
        ])
    }
    #[inline(always)]
    fn f64_store(self, v: Self::F64) -> [f64; LANES] {
        let mut out = [0.0; LANES];
        for (q, v) in v.into_iter().enumerate() {
            // Writes four of the sixteen `f64` of `out`.
            avx!(_mm256_storeu_pd(out[4 * q..].as_mut_ptr(), v));
        }
        out
    }
    #[inline(always)]
    fn f64_add(self, a: Self::F64, b: Self::F64) -> Self::F64 {
        each!(4, _mm256_add_pd(a, b))
    }
    #[inline(always)]
    fn f64_sub(self, a: Self::F64, b: Self::F64) -> Self::F64 {
        each!(4, _mm256_sub_pd(a, b))
    }
    #[inline(always)]
    fn f64_mul(self, a: Self::F64, b: Self::F64) -> Self::F64 {
        each!(4, _mm256_mul_pd(a, b))
    }
    #[inline(always)]
    fn f64_div(self, a: Self::F64, b: Self::F64) -> Self::F64 {
        each!(4, _mm256_div_pd(a, b))
    }
    #[inline(always)]
    fn f64_neg(self, a: Self::F64) -> Self::F64 {
        let sign = self.f64_splat(-0.0);
        each!(4, _mm256_xor_pd(a, sign))
    }
    #[inline(always)]
    fn f64_sqrt(self, a: Self::F64) -> Self::F64 {
        each!(4, _mm256_sqrt_pd(a))
    }
    #[inline(always)]
    fn f64_abs(self, a: Self::F64) -> Self::F64 {
        let sign = self.f64_splat(-0.0);
        each!(4, _mm256_andnot_pd(sign, a))
    }
    #[inline(always)]
    fn f64_min(self, a: Self::F64, b: Self::F64) -> Self::F64 {
        each!(4, _mm256_min_pd(a, b))
    }
    #[inline(always)]
    fn f64_max(self, a: Self::F64, b: Self::F64) -> Self::F64 {
        each!(4, _mm256_max_pd(a, b))
    }
    #[inline(always)]
    fn f64_select(self, m: Mask16, a: Self::F64, b: Self::F64) -> Self::F64 {
        let m = each!(4, _mm256_castsi256_pd(mask64(m)));
        each!(4, _mm256_blendv_pd(b, a, m))
    }
    #[inline(always)]
    fn f64_copysign(self, magnitude: Self::F64, sign: Self::F64) -> Self::F64 {
        let bit = self.f64_splat(-0.0);
        let (s, m) = (
            each!(4, _mm256_and_pd(bit, sign)),
            each!(4, _mm256_andnot_pd(bit, magnitude)),
        );
        each!(4, _mm256_or_pd(s, m))
    }
    #[inline(always)]
    fn f64_cmp(self, a: Self::F64, b: Self::F64, c: Cmp) -> Mask16 {
        pack64(match c {
            Cmp::Lt => each!(4, _mm256_cmp_pd::<_CMP_LT_OQ>(a, b)),
            Cmp::Le => each!(4, _mm256_cmp_pd::<_CMP_LE_OQ>(a, b)),
            Cmp::Gt => each!(4, _mm256_cmp_pd::<_CMP_GT_OQ>(a, b)),
            Cmp::Ge => each!(4, _mm256_cmp_pd::<_CMP_GE_OQ>(a, b)),
            Cmp::Eq => each!(4, _mm256_cmp_pd::<_CMP_EQ_OQ>(a, b)),
        })
    }
    #[inline(always)]
    fn f64_to_f32(self, a: Self::F64) -> Self::F32 {
        let q = each!(4, _mm256_cvtpd_ps(a));
        avx!([_mm256_set_m128(q[1], q[0]), _mm256_set_m128(q[3], q[2])])
    }
}
