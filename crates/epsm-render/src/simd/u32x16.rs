//! Sixteen `u32` lanes (wrapping arithmetic, as `u32::wrapping_*`).

use std::arch::x86_64::*;
use std::ops::{Shl, Shr};

use super::{Avx512, LANES, Mask16};

/// Sixteen `u32` lanes (module docs of `simd`).
#[derive(Clone, Copy, Debug)]
pub(crate) struct U32x16(pub(super) __m512i);

binary!(one U32x16;
    Add, add, _mm512_add_epi32;
    Sub, sub, _mm512_sub_epi32;
    Mul, mul, _mm512_mullo_epi32;
    BitAnd, bitand, _mm512_and_si512;
    BitOr, bitor, _mm512_or_si512;
    BitXor, bitxor, _mm512_xor_si512;
);

impl Shr<u32> for U32x16 {
    type Output = Self;
    /// Logical shift right of every lane by `n` (`≥ 32` gives 0).
    #[inline(always)]
    fn shr(self, n: u32) -> Self {
        Self(avx!(_mm512_srlv_epi32(self.0, _mm512_set1_epi32(n as i32))))
    }
}

impl Shl<u32> for U32x16 {
    type Output = Self;
    /// Shift left of every lane by `n` (`≥ 32` gives 0).
    #[inline(always)]
    fn shl(self, n: u32) -> Self {
        Self(avx!(_mm512_sllv_epi32(self.0, _mm512_set1_epi32(n as i32))))
    }
}

impl U32x16 {
    /// Every lane `x`.
    #[inline(always)]
    pub fn splat(_: Avx512, x: u32) -> Self {
        Self(avx!(_mm512_set1_epi32(x as i32)))
    }

    /// Lane `i` is `lanes[i]`.
    #[inline(always)]
    pub fn from_array(_: Avx512, lanes: [u32; LANES]) -> Self {
        // `loadu` reads the sixteen `u32` of `lanes`.
        Self(avx!(_mm512_loadu_si512(lanes.as_ptr().cast())))
    }

    /// The lanes as an array.
    #[inline(always)]
    pub fn to_array(self) -> [u32; LANES] {
        let mut out = [0; LANES];
        // `storeu` writes the sixteen `u32` of `out`.
        avx!(_mm512_storeu_si512(out.as_mut_ptr().cast(), self.0));
        out
    }

    /// Lane `lane` (`< 16`).
    #[inline(always)]
    pub fn lane(self, lane: usize) -> u32 {
        self.to_array()[lane]
    }

    /// Arithmetic shift right of every lane, read as `i32`, by `n` (`≥ 32`
    /// fills with the sign bit).
    #[inline(always)]
    pub fn shr_signed(self, n: u32) -> Self {
        Self(avx!(_mm512_srav_epi32(self.0, _mm512_set1_epi32(n as i32))))
    }

    /// `a` in the lanes of `m`, `b` in the others.
    #[inline(always)]
    pub fn select(m: Mask16, a: Self, b: Self) -> Self {
        Self(avx!(_mm512_mask_blend_epi32(m.0, b.0, a.0)))
    }

    /// Unsigned `self < o`.
    #[inline(always)]
    pub fn lt(self, o: Self) -> Mask16 {
        Mask16(avx!(_mm512_cmplt_epu32_mask(self.0, o.0)))
    }

    /// Unsigned `self >= o`.
    #[inline(always)]
    pub fn ge(self, o: Self) -> Mask16 {
        Mask16(avx!(_mm512_cmpge_epu32_mask(self.0, o.0)))
    }

    /// `self == o`.
    #[inline(always)]
    pub fn eq(self, o: Self) -> Mask16 {
        Mask16(avx!(_mm512_cmpeq_epu32_mask(self.0, o.0)))
    }

    /// Panics unless every lane of `m` holds an index below `len` (the
    /// length of the table a gather reads) and below `i32::MAX` (the
    /// gathers read signed indices): what makes the `gather` methods' reads
    /// in bounds.
    #[inline(always)]
    pub(super) fn assert_gather_indices(self, m: Mask16, len: usize) {
        let len = u32::try_from(len).unwrap_or(u32::MAX).min(i32::MAX as u32);
        assert!(
            (self.lt(Self(avx!(_mm512_set1_epi32(len as i32)))) | !m).all(),
            "gather index out of bounds"
        );
    }

    /// `table[index]` in the lanes of `m`, `fallback` in the others.
    ///
    /// # Panics
    /// If an index of a lane in `m` is out of bounds.
    #[inline(always)]
    pub fn gather(table: &[u32], index: Self, m: Mask16, fallback: Self) -> Self {
        index.assert_gather_indices(m, table.len());
        // Every lane read (those of `m`) indexes `table` in bounds (asserted
        // above, and below `i32::MAX`, so the signed indices are the same).
        Self(avx!(_mm512_mask_i32gather_epi32::<4>(
            fallback.0,
            m.0,
            index.0,
            table.as_ptr().cast()
        )))
    }
}
