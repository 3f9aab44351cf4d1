//! Sixteen `u32` lanes (wrapping arithmetic, as `u32::wrapping_*`).

use std::ops::{Shl, Shr};

use super::{LANES, Lanes, Mask16};

/// Sixteen `u32` lanes (module docs of `simd`): the backend's register and
/// its token.
#[derive(Clone, Copy, Debug)]
pub(crate) struct U32x16<B: Lanes>(pub(super) B::U32, pub(super) B);

binary!(U32x16;
    Add, add, u32_add;
    Sub, sub, u32_sub;
    Mul, mul, u32_mul;
    BitAnd, bitand, u32_and;
    BitOr, bitor, u32_or;
    BitXor, bitxor, u32_xor;
);

impl<B: Lanes> Shr<u32> for U32x16<B> {
    type Output = Self;
    /// Logical shift right of every lane by `n` (`≥ 32` gives 0).
    #[inline(always)]
    fn shr(self, n: u32) -> Self {
        Self(self.1.u32_shr(self.0, n), self.1)
    }
}

impl<B: Lanes> Shl<u32> for U32x16<B> {
    type Output = Self;
    /// Shift left of every lane by `n` (`≥ 32` gives 0).
    #[inline(always)]
    fn shl(self, n: u32) -> Self {
        Self(self.1.u32_shl(self.0, n), self.1)
    }
}

impl<B: Lanes> U32x16<B> {
    /// Every lane `x`.
    #[inline(always)]
    pub fn splat(k: B, x: u32) -> Self {
        Self(k.u32_splat(x), k)
    }

    /// Lane `i` is `lanes[i]`.
    #[inline(always)]
    pub fn from_array(k: B, lanes: [u32; LANES]) -> Self {
        Self(k.u32_load(lanes), k)
    }

    /// The lanes as an array.
    #[inline(always)]
    pub fn to_array(self) -> [u32; LANES] {
        self.1.u32_store(self.0)
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
        Self(self.1.u32_shr_signed(self.0, n), self.1)
    }

    /// `a` in the lanes of `m`, `b` in the others.
    #[inline(always)]
    pub fn select(m: Mask16, a: Self, b: Self) -> Self {
        Self(a.1.u32_select(m, a.0, b.0), a.1)
    }

    /// Unsigned `self < o`.
    #[inline(always)]
    pub fn lt(self, o: Self) -> Mask16 {
        self.1.u32_lt(self.0, o.0)
    }

    /// Unsigned `self >= o`.
    #[inline(always)]
    pub fn ge(self, o: Self) -> Mask16 {
        !self.lt(o)
    }

    /// `self == o`.
    #[inline(always)]
    pub fn eq(self, o: Self) -> Mask16 {
        self.1.u32_eq(self.0, o.0)
    }

    /// Panics unless every lane of `m` holds an index below `len` (the
    /// length of the table a gather reads) and below `i32::MAX` (the
    /// gathers read signed indices): what makes the `gather` methods' reads
    /// in bounds.
    #[inline(always)]
    pub(super) fn assert_gather_indices(self, m: Mask16, len: usize) {
        let len = u32::try_from(len).unwrap_or(u32::MAX).min(i32::MAX as u32);
        assert!(
            (self.lt(Self::splat(self.1, len)) | !m).all(),
            "gather index out of bounds"
        );
    }

    /// `table[index]` in the lanes of `m`, `fallback` in the others.
    ///
    /// # Panics
    /// If an index of a lane in `m` is out of bounds.
    #[inline(always)]
    #[allow(unsafe_code)]
    pub fn gather(table: &[u32], index: Self, m: Mask16, fallback: Self) -> Self {
        index.assert_gather_indices(m, table.len());
        // SAFETY: every lane of `m` indexes `table` in bounds, below
        // `i32::MAX` (asserted above).
        Self(
            unsafe { index.1.u32_gather(table, index.0, m, fallback.0) },
            index.1,
        )
    }
}
