//! The portable backend's `f64` lanes.

use super::*;
use crate::simd::F64Ops;

#[allow(unsafe_code)]
impl F64Ops for Portable {
    #[inline(always)]
    fn f64_splat(self, x: f64) -> Self::F64 {
        [x; LANES]
    }
    #[inline(always)]
    fn f64_load(self, lanes: [f64; LANES]) -> Self::F64 {
        lanes
    }
    #[inline(always)]
    fn f64_store(self, v: Self::F64) -> [f64; LANES] {
        v
    }
    #[inline(always)]
    fn f64_add(self, a: Self::F64, b: Self::F64) -> Self::F64 {
        zip(a, b, |a, b| a + b)
    }
    #[inline(always)]
    fn f64_sub(self, a: Self::F64, b: Self::F64) -> Self::F64 {
        zip(a, b, |a, b| a - b)
    }
    #[inline(always)]
    fn f64_mul(self, a: Self::F64, b: Self::F64) -> Self::F64 {
        zip(a, b, |a, b| a * b)
    }
    #[inline(always)]
    fn f64_div(self, a: Self::F64, b: Self::F64) -> Self::F64 {
        zip(a, b, |a, b| a / b)
    }
    #[inline(always)]
    fn f64_neg(self, a: Self::F64) -> Self::F64 {
        map(a, |a| -a)
    }
    #[inline(always)]
    fn f64_sqrt(self, a: Self::F64) -> Self::F64 {
        map(a, f64::sqrt)
    }
    #[inline(always)]
    fn f64_abs(self, a: Self::F64) -> Self::F64 {
        map(a, f64::abs)
    }
    #[inline(always)]
    fn f64_min(self, a: Self::F64, b: Self::F64) -> Self::F64 {
        zip(a, b, |a, b| if a < b { a } else { b })
    }
    #[inline(always)]
    fn f64_max(self, a: Self::F64, b: Self::F64) -> Self::F64 {
        zip(a, b, |a, b| if a > b { a } else { b })
    }
    #[inline(always)]
    fn f64_select(self, m: Mask16, a: Self::F64, b: Self::F64) -> Self::F64 {
        select(m, a, b)
    }
    #[inline(always)]
    fn f64_copysign(self, magnitude: Self::F64, sign: Self::F64) -> Self::F64 {
        zip(magnitude, sign, f64::copysign)
    }
    #[inline(always)]
    fn f64_cmp(self, a: Self::F64, b: Self::F64, c: Cmp) -> Mask16 {
        mask(|i| c.scalar(a[i], b[i]))
    }
    #[inline(always)]
    fn f64_to_f32(self, a: Self::F64) -> Self::F32 {
        map(a, |x| x as f32)
    }
}
