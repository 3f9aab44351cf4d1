//! Sixteen `f64` lanes in two registers, for the parts of the scalar tracer
//! done in `f64` (exact spheres, light selection).

use std::arch::x86_64::*;

use super::{Avx512, F32x16, LANES, Mask16};

/// Sixteen `f64` lanes: lanes 0–7 in the first register, 8–15 in the
/// second (module docs of `simd`).
#[derive(Clone, Copy, Debug)]
pub(crate) struct F64x16(pub(super) [__m512d; 2]);

binary!(two F64x16;
    Add, add, _mm512_add_pd;
    Sub, sub, _mm512_sub_pd;
    Mul, mul, _mm512_mul_pd;
    Div, div, _mm512_div_pd;
);

negate!(two F64x16; _mm512_xor_pd, _mm512_set1_pd);

impl F64x16 {
    /// Every lane `x`.
    #[inline(always)]
    pub fn splat(_: Avx512, x: f64) -> Self {
        let v = avx!(_mm512_set1_pd(x));
        Self([v, v])
    }

    /// Lane `i` is `lanes[i]`.
    #[inline(always)]
    pub fn from_array(_: Avx512, lanes: [f64; LANES]) -> Self {
        // Each `loadu` reads eight of the sixteen `f64` of `lanes`.
        Self([
            avx!(_mm512_loadu_pd(lanes.as_ptr())),
            avx!(_mm512_loadu_pd(lanes[8..].as_ptr())),
        ])
    }

    /// The lanes as an array.
    #[inline(always)]
    pub fn to_array(self) -> [f64; LANES] {
        let mut out = [0.0; LANES];
        // Each `storeu` writes eight of the sixteen `f64` of `out`.
        avx!(_mm512_storeu_pd(out.as_mut_ptr(), self.0[0]));
        avx!(_mm512_storeu_pd(out[8..].as_mut_ptr(), self.0[1]));
        out
    }

    /// Square root.
    #[inline(always)]
    pub fn sqrt(self) -> Self {
        Self([
            avx!(_mm512_sqrt_pd(self.0[0])),
            avx!(_mm512_sqrt_pd(self.0[1])),
        ])
    }

    /// Absolute value (sign bit cleared).
    #[inline(always)]
    pub fn abs(self) -> Self {
        Self([
            avx!(_mm512_abs_pd(self.0[0])),
            avx!(_mm512_abs_pd(self.0[1])),
        ])
    }

    /// `if self < o { self } else { o }` (module docs of `simd`).
    #[inline(always)]
    pub fn min(self, o: Self) -> Self {
        Self([
            avx!(_mm512_min_pd(self.0[0], o.0[0])),
            avx!(_mm512_min_pd(self.0[1], o.0[1])),
        ])
    }

    clamp!("f64");

    /// `a` in the lanes of `m`, `b` in the others.
    #[inline(always)]
    pub fn select(m: Mask16, a: Self, b: Self) -> Self {
        let (lo, hi) = (m.0 as u8, (m.0 >> 8) as u8);
        Self([
            avx!(_mm512_mask_blend_pd(lo, b.0[0], a.0[0])),
            avx!(_mm512_mask_blend_pd(hi, b.0[1], a.0[1])),
        ])
    }

    compare! { two _mm512_cmp_pd_mask;
        /// `self < o` (false on NaN).
        lt, _CMP_LT_OQ;
        /// `self <= o` (false on NaN).
        le, _CMP_LE_OQ;
        /// `self > o` (false on NaN).
        gt, _CMP_GT_OQ;
        /// `self >= o` (false on NaN).
        ge, _CMP_GE_OQ;
    }

    /// The lanes rounded to `f32` (to nearest, as `as f32`).
    #[inline(always)]
    pub fn to_f32(self) -> F32x16 {
        let (lo, hi) = (
            avx!(_mm512_cvtpd_ps(self.0[0])),
            avx!(_mm512_cvtpd_ps(self.0[1])),
        );
        F32x16(avx!(_mm512_insertf32x8::<1>(
            _mm512_castps256_ps512(lo),
            hi
        )))
    }

    /// The magnitude of `self` with the sign bit of `sign` (`f64::copysign`).
    #[inline(always)]
    pub fn copysign(self, sign: Self) -> Self {
        // Ternary logic 0xCA (`a ? b : c` bitwise): bits of `sign` where the
        // sign mask is set, of `self` elsewhere.
        let mask = avx!(_mm512_castpd_si512(_mm512_set1_pd(-0.0)));
        let half = |m: __m512d, s: __m512d| {
            avx!(_mm512_castsi512_pd(_mm512_ternarylogic_epi64::<0xCA>(
                mask,
                _mm512_castpd_si512(s),
                _mm512_castpd_si512(m),
            )))
        };
        Self([half(self.0[0], sign.0[0]), half(self.0[1], sign.0[1])])
    }
}
