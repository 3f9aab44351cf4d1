//! Sixteen `f32` lanes.

use super::{Cmp, F64x16, LANES, Lanes, Mask16, U32x16};

/// Sixteen `f32` lanes (module docs of `simd`): the backend's register and
/// its token.
#[derive(Clone, Copy, Debug)]
pub(crate) struct F32x16<B: Lanes>(pub(super) B::F32, pub(super) B);

binary!(F32x16;
    Add, add, f32_add;
    Sub, sub, f32_sub;
    Mul, mul, f32_mul;
    Div, div, f32_div;
);

impl<B: Lanes> std::ops::Neg for F32x16<B> {
    type Output = Self;
    /// Flips the sign bit, as scalar negation does.
    #[inline(always)]
    fn neg(self) -> Self {
        Self(self.1.f32_neg(self.0), self.1)
    }
}

impl<B: Lanes> F32x16<B> {
    /// Every lane `x`.
    #[inline(always)]
    pub fn splat(k: B, x: f32) -> Self {
        Self(k.f32_splat(x), k)
    }

    /// Lane `i` is `lanes[i]`.
    #[inline(always)]
    pub fn from_array(k: B, lanes: [f32; LANES]) -> Self {
        Self(k.f32_load(lanes), k)
    }

    /// The lanes as an array.
    #[inline(always)]
    pub fn to_array(self) -> [f32; LANES] {
        self.1.f32_store(self.0)
    }

    /// Lane `lane` (`< 16`).
    #[inline(always)]
    pub fn lane(self, lane: usize) -> f32 {
        self.to_array()[lane]
    }

    /// Square root.
    #[inline(always)]
    pub fn sqrt(self) -> Self {
        Self(self.1.f32_sqrt(self.0), self.1)
    }

    /// Absolute value (sign bit cleared).
    #[inline(always)]
    pub fn abs(self) -> Self {
        Self(self.1.f32_abs(self.0), self.1)
    }

    /// `if self < o { self } else { o }` (module docs).
    #[inline(always)]
    pub fn min(self, o: Self) -> Self {
        Self(self.1.f32_min(self.0, o.0), self.1)
    }

    /// `if self > o { self } else { o }` (module docs).
    #[inline(always)]
    pub fn max(self, o: Self) -> Self {
        Self(self.1.f32_max(self.0, o.0), self.1)
    }

    clamp!("f32");

    /// `a` in the lanes of `m`, `b` in the others.
    #[inline(always)]
    pub fn select(m: Mask16, a: Self, b: Self) -> Self {
        Self(a.1.f32_select(m, a.0, b.0), a.1)
    }

    /// The magnitude of `self` with the sign bit of `sign`.
    #[inline(always)]
    pub fn copysign(self, sign: Self) -> Self {
        Self(self.1.f32_copysign(self.0, sign.0), self.1)
    }

    compare! { f32_cmp;
        /// `self < o` (false on NaN).
        lt, Lt;
        /// `self <= o` (false on NaN).
        le, Le;
        /// `self > o` (false on NaN).
        gt, Gt;
        /// `self >= o` (false on NaN).
        ge, Ge;
        /// `self == o` (false on NaN).
        eq, Eq;
    }

    /// Lanes neither infinite nor NaN.
    #[inline(always)]
    pub fn is_finite(self) -> Mask16 {
        self.abs().lt(Self::splat(self.1, f32::INFINITY))
    }

    /// The lanes' bit patterns.
    #[inline(always)]
    pub fn to_bits(self) -> U32x16<B> {
        U32x16(self.1.f32_to_bits(self.0), self.1)
    }

    /// Lanes with the bit patterns of `bits`.
    #[inline(always)]
    pub fn from_bits(bits: U32x16<B>) -> Self {
        Self(bits.1.f32_from_bits(bits.0), bits.1)
    }

    /// `u as f32` per lane (rounded to nearest).
    #[inline(always)]
    pub fn from_u32(u: U32x16<B>) -> Self {
        Self(u.1.f32_from_u32(u.0), u.1)
    }

    /// `self as i32` per lane for finite lanes in `i32`'s range (truncated
    /// toward zero), as `u32` bit patterns; other lanes give `i32::MIN`
    /// (Rust's `as` saturates instead: callers keep to the range).
    #[inline(always)]
    pub fn trunc_i32(self) -> U32x16<B> {
        U32x16(self.1.f32_trunc_i32(self.0), self.1)
    }

    /// The lanes widened to `f64` (exact).
    #[inline(always)]
    pub fn to_f64(self) -> F64x16<B> {
        F64x16(self.1.f32_to_f64(self.0), self.1)
    }

    /// `table[index]` in the lanes of `m`, `fallback` in the others.
    ///
    /// # Panics
    /// If an index of a lane in `m` is out of bounds.
    #[inline(always)]
    #[allow(unsafe_code)]
    pub fn gather(table: &[f32], index: U32x16<B>, m: Mask16, fallback: Self) -> Self {
        index.assert_gather_indices(m, table.len());
        // SAFETY: every lane of `m` indexes `table` in bounds, below
        // `i32::MAX` (asserted above).
        Self(
            unsafe { index.1.f32_gather(table, index.0, m, fallback.0) },
            index.1,
        )
    }

    /// Lane `i` is lane `index[i] % 16` of `self`.
    #[inline(always)]
    pub fn permute(self, index: U32x16<B>) -> Self {
        Self(self.1.f32_permute(self.0, index.0), self.1)
    }

    /// The smallest of the lanes of `m` (`+∞` without any), for orderings
    /// only: which lane a NaN or a `±0` tie yields is unspecified.
    #[inline(always)]
    pub fn reduce_min(self, m: Mask16) -> f32 {
        self.1.f32_reduce_min(self.0, m)
    }

    /// `self` with the lanes of `m` replaced by `src[0]`, `src[1]`, … in
    /// lane order (an expanding load).
    ///
    /// # Panics
    /// If `src` holds fewer values than `m` has lanes.
    #[inline(always)]
    #[allow(unsafe_code)]
    pub fn expand_from(self, m: Mask16, src: &[f32]) -> Self {
        m.assert_expand_len(src.len());
        // SAFETY: `src` holds at least `m.count()` values (asserted above).
        Self(unsafe { self.1.f32_expand(self.0, m, src) }, self.1)
    }
}
