//! The portable backend's `f32` lanes.

use super::*;
use crate::simd::F32Ops;

#[allow(unsafe_code)]
impl F32Ops for Portable {
    #[inline(always)]
    fn f32_splat(self, x: f32) -> Self::F32 {
        [x; LANES]
    }
    #[inline(always)]
    fn f32_load(self, lanes: [f32; LANES]) -> Self::F32 {
        lanes
    }
    #[inline(always)]
    fn f32_store(self, v: Self::F32) -> [f32; LANES] {
        v
    }
    #[inline(always)]
    fn f32_add(self, a: Self::F32, b: Self::F32) -> Self::F32 {
        zip(a, b, |a, b| a + b)
    }
    #[inline(always)]
    fn f32_sub(self, a: Self::F32, b: Self::F32) -> Self::F32 {
        zip(a, b, |a, b| a - b)
    }
    #[inline(always)]
    fn f32_mul(self, a: Self::F32, b: Self::F32) -> Self::F32 {
        zip(a, b, |a, b| a * b)
    }
    #[inline(always)]
    fn f32_div(self, a: Self::F32, b: Self::F32) -> Self::F32 {
        zip(a, b, |a, b| a / b)
    }
    #[inline(always)]
    fn f32_neg(self, a: Self::F32) -> Self::F32 {
        map(a, |a| -a)
    }
    #[inline(always)]
    fn f32_sqrt(self, a: Self::F32) -> Self::F32 {
        map(a, f32::sqrt)
    }
    #[inline(always)]
    fn f32_abs(self, a: Self::F32) -> Self::F32 {
        map(a, f32::abs)
    }
    #[inline(always)]
    fn f32_min(self, a: Self::F32, b: Self::F32) -> Self::F32 {
        zip(a, b, |a, b| if a < b { a } else { b })
    }
    #[inline(always)]
    fn f32_max(self, a: Self::F32, b: Self::F32) -> Self::F32 {
        zip(a, b, |a, b| if a > b { a } else { b })
    }
    #[inline(always)]
    fn f32_select(self, m: Mask16, a: Self::F32, b: Self::F32) -> Self::F32 {
        select(m, a, b)
    }
    #[inline(always)]
    fn f32_copysign(self, magnitude: Self::F32, sign: Self::F32) -> Self::F32 {
        zip(magnitude, sign, f32::copysign)
    }
    #[inline(always)]
    fn f32_cmp(self, a: Self::F32, b: Self::F32, c: Cmp) -> Mask16 {
        mask(|i| c.scalar(a[i], b[i]))
    }
    #[inline(always)]
    fn f32_to_bits(self, a: Self::F32) -> Self::U32 {
        map(a, f32::to_bits)
    }
    #[inline(always)]
    fn f32_from_bits(self, a: Self::U32) -> Self::F32 {
        map(a, f32::from_bits)
    }
    #[inline(always)]
    fn f32_from_u32(self, a: Self::U32) -> Self::F32 {
        map(a, |u| u as f32)
    }
    #[inline(always)]
    fn f32_trunc_i32(self, a: Self::F32) -> Self::U32 {
        // The instructions' rule: `i32::MIN` outside the range (and on NaN).
        map(a, |x| {
            if (-2_147_483_648.0..2_147_483_648.0).contains(&x) {
                x as i32 as u32
            } else {
                i32::MIN as u32
            }
        })
    }
    #[inline(always)]
    fn f32_to_f64(self, a: Self::F32) -> Self::F64 {
        map(a, f64::from)
    }
    #[inline(always)]
    fn f32_permute(self, a: Self::F32, index: Self::U32) -> Self::F32 {
        map(index, |i| a[i as usize % LANES])
    }
    #[inline(always)]
    fn f32_reduce_min(self, a: Self::F32, m: Mask16) -> f32 {
        m.lanes()
            .fold(f32::INFINITY, |s, i| if a[i] < s { a[i] } else { s })
    }
    #[inline(always)]
    unsafe fn f32_gather(
        self,
        table: &[f32],
        index: Self::U32,
        m: Mask16,
        fallback: Self::F32,
    ) -> Self::F32 {
        gather(table, index, m, fallback)
    }
    #[inline(always)]
    unsafe fn f32_expand(self, a: Self::F32, m: Mask16, src: &[f32]) -> Self::F32 {
        expand(a, m, src)
    }
}
