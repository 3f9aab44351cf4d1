//! The portable backend's `u64` lanes.

use super::*;
use crate::simd::U64Ops;

#[allow(unsafe_code)]
impl U64Ops for Portable {
    #[inline(always)]
    fn u64_splat(self, x: u64) -> Self::U64 {
        [x; LANES]
    }
    #[cfg(test)]
    #[inline(always)]
    fn u64_load(self, lanes: [u64; LANES]) -> Self::U64 {
        lanes
    }
    #[inline(always)]
    fn u64_store(self, v: Self::U64) -> [u64; LANES] {
        v
    }
    #[inline(always)]
    fn u64_add(self, a: Self::U64, b: Self::U64) -> Self::U64 {
        zip(a, b, u64::wrapping_add)
    }
    #[inline(always)]
    fn u64_mul(self, a: Self::U64, b: Self::U64) -> Self::U64 {
        zip(a, b, u64::wrapping_mul)
    }
    #[inline(always)]
    fn u64_xor(self, a: Self::U64, b: Self::U64) -> Self::U64 {
        zip(a, b, |a, b| a ^ b)
    }
    #[inline(always)]
    fn u64_shr(self, a: Self::U64, n: u32) -> Self::U64 {
        map(a, |a| a.checked_shr(n).unwrap_or(0))
    }
    #[inline(always)]
    fn u64_from_u32(self, a: Self::U32) -> Self::U64 {
        map(a, u64::from)
    }
    #[inline(always)]
    fn u64_low_u32(self, a: Self::U64) -> Self::U32 {
        map(a, |a| a as u32)
    }
    #[inline(always)]
    unsafe fn u64_gather(
        self,
        table: &[u64],
        index: Self::U32,
        m: Mask16,
        fallback: Self::U64,
    ) -> Self::U64 {
        gather(table, index, m, fallback)
    }
    #[inline(always)]
    unsafe fn u64_expand(self, a: Self::U64, m: Mask16, src: &[u64]) -> Self::U64 {
        expand(a, m, src)
    }
}
