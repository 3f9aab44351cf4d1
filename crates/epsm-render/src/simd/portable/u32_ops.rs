//! The portable backend's `u32` lanes.

use super::*;
use crate::simd::U32Ops;

#[allow(unsafe_code)]
impl U32Ops for Portable {
    #[inline(always)]
    fn u32_splat(self, x: u32) -> Self::U32 {
        [x; LANES]
    }
    #[inline(always)]
    fn u32_load(self, lanes: [u32; LANES]) -> Self::U32 {
        lanes
    }
    #[inline(always)]
    fn u32_store(self, v: Self::U32) -> [u32; LANES] {
        v
    }
    #[inline(always)]
    fn u32_add(self, a: Self::U32, b: Self::U32) -> Self::U32 {
        zip(a, b, u32::wrapping_add)
    }
    #[inline(always)]
    fn u32_sub(self, a: Self::U32, b: Self::U32) -> Self::U32 {
        zip(a, b, u32::wrapping_sub)
    }
    #[inline(always)]
    fn u32_mul(self, a: Self::U32, b: Self::U32) -> Self::U32 {
        zip(a, b, u32::wrapping_mul)
    }
    #[inline(always)]
    fn u32_and(self, a: Self::U32, b: Self::U32) -> Self::U32 {
        zip(a, b, |a, b| a & b)
    }
    #[inline(always)]
    fn u32_or(self, a: Self::U32, b: Self::U32) -> Self::U32 {
        zip(a, b, |a, b| a | b)
    }
    #[inline(always)]
    fn u32_xor(self, a: Self::U32, b: Self::U32) -> Self::U32 {
        zip(a, b, |a, b| a ^ b)
    }
    #[inline(always)]
    fn u32_shr(self, a: Self::U32, n: u32) -> Self::U32 {
        map(a, |a| a.checked_shr(n).unwrap_or(0))
    }
    #[inline(always)]
    fn u32_shl(self, a: Self::U32, n: u32) -> Self::U32 {
        map(a, |a| a.checked_shl(n).unwrap_or(0))
    }
    #[inline(always)]
    fn u32_shr_signed(self, a: Self::U32, n: u32) -> Self::U32 {
        map(a, |a| ((a as i32) >> n.min(31)) as u32)
    }
    #[inline(always)]
    fn u32_select(self, m: Mask16, a: Self::U32, b: Self::U32) -> Self::U32 {
        select(m, a, b)
    }
    #[inline(always)]
    fn u32_lt(self, a: Self::U32, b: Self::U32) -> Mask16 {
        mask(|i| a[i] < b[i])
    }
    #[inline(always)]
    fn u32_eq(self, a: Self::U32, b: Self::U32) -> Mask16 {
        mask(|i| a[i] == b[i])
    }
    #[inline(always)]
    unsafe fn u32_gather(
        self,
        table: &[u32],
        index: Self::U32,
        m: Mask16,
        fallback: Self::U32,
    ) -> Self::U32 {
        gather(table, index, m, fallback)
    }
}
