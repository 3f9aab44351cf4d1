//! Sixteen `u64` lanes (wrapping arithmetic, as `u64::wrapping_*`), for the
//! sampler's 64-bit hashes.

use std::ops::Shr;

use super::{LANES, Lanes, Mask16, U32x16};

/// Sixteen `u64` lanes (module docs of `simd`): the backend's register and
/// its token.
#[derive(Clone, Copy, Debug)]
pub(crate) struct U64x16<B: Lanes>(pub(super) B::U64, pub(super) B);

binary!(U64x16;
    Add, add, u64_add;
    Mul, mul, u64_mul;
    BitXor, bitxor, u64_xor;
);

impl<B: Lanes> Shr<u32> for U64x16<B> {
    type Output = Self;
    /// Logical shift right of every lane by `n` (`≥ 64` gives 0).
    #[inline(always)]
    fn shr(self, n: u32) -> Self {
        Self(self.1.u64_shr(self.0, n), self.1)
    }
}

impl<B: Lanes> U64x16<B> {
    /// Every lane `x`.
    #[inline(always)]
    pub fn splat(k: B, x: u64) -> Self {
        Self(k.u64_splat(x), k)
    }

    #[cfg(test)]
    /// Lane `i` is `lanes[i]`.
    #[inline(always)]
    pub fn from_array(k: B, lanes: [u64; LANES]) -> Self {
        Self(k.u64_load(lanes), k)
    }

    /// The lanes as an array.
    #[inline(always)]
    pub fn to_array(self) -> [u64; LANES] {
        self.1.u64_store(self.0)
    }

    /// Each lane of `u` zero-extended.
    #[inline(always)]
    pub fn from_u32(u: U32x16<B>) -> Self {
        Self(u.1.u64_from_u32(u.0), u.1)
    }

    /// The low 32 bits of each lane (`as u32`).
    #[inline(always)]
    pub fn low_u32(self) -> U32x16<B> {
        U32x16(self.1.u64_low_u32(self.0), self.1)
    }

    /// `self` with the lanes of `m` replaced by `src[0]`, `src[1]`, … in
    /// lane order (an expanding load).
    ///
    /// # Panics
    /// If `src` holds fewer values than `m` has lanes.
    #[inline(always)]
    #[allow(unsafe_code)]
    pub fn expand_from(self, m: Mask16, src: &[u64]) -> Self {
        m.assert_expand_len(src.len());
        // SAFETY: `src` holds at least `m.count()` values (asserted above).
        Self(unsafe { self.1.u64_expand(self.0, m, src) }, self.1)
    }

    /// `table[index]` in the lanes of `m`, `fallback` in the others.
    ///
    /// # Panics
    /// If an index of a lane in `m` is out of bounds.
    #[inline(always)]
    #[allow(unsafe_code)]
    pub fn gather(table: &[u64], index: U32x16<B>, m: Mask16, fallback: Self) -> Self {
        index.assert_gather_indices(m, table.len());
        // SAFETY: every lane of `m` indexes `table` in bounds, below
        // `i32::MAX` (asserted above).
        Self(
            unsafe { index.1.u64_gather(table, index.0, m, fallback.0) },
            index.1,
        )
    }
}
