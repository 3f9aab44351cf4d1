//! Sixteen `f32` lanes, and the lane masks every lane type's comparisons
//! return.

use std::arch::x86_64::*;
use std::ops::{BitAnd, BitOr, BitXor, Not};

use super::{Avx512, F64x16, LANES, U32x16};

/// Sixteen `f32` lanes (module docs of `simd`).
#[derive(Clone, Copy, Debug)]
pub(crate) struct F32x16(pub(super) __m512);

/// One bit per lane: bit `i` set when lane `i` is selected. A plain `u16`,
/// so masks need no token and cost no vector register.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub(crate) struct Mask16(pub u16);

impl Mask16 {
    /// No lane.
    pub const NONE: Self = Self(0);
    /// Every lane.
    pub const ALL: Self = Self(u16::MAX);

    /// Lanes `0..n` (`n ≤ 16`).
    #[inline(always)]
    pub fn first(n: usize) -> Self {
        debug_assert!(n <= LANES);
        Self(((1u32 << n) - 1) as u16)
    }

    /// The lowest `n` lanes of `self` (all of them when it has fewer).
    #[inline(always)]
    pub fn first_of(self, n: u32) -> Self {
        let mut bits = self.0;
        let mut out = 0u16;
        for _ in 0..n.min(LANES as u32) {
            let lowest = bits & bits.wrapping_neg();
            out |= lowest;
            bits ^= lowest;
        }
        Self(out)
    }

    /// Whether any lane is set.
    #[inline(always)]
    pub fn any(self) -> bool {
        self.0 != 0
    }

    /// Whether every lane is set.
    #[inline(always)]
    pub fn all(self) -> bool {
        self.0 == u16::MAX
    }

    /// Whether lane `lane` is set.
    #[inline(always)]
    pub fn test(self, lane: usize) -> bool {
        self.0 >> (lane & (LANES - 1)) & 1 != 0
    }

    /// How many lanes are set.
    #[inline(always)]
    pub fn count(self) -> u32 {
        self.0.count_ones()
    }

    /// The lanes set, lowest first.
    #[inline(always)]
    pub fn lanes(self) -> impl Iterator<Item = usize> {
        let mut bits = self.0;
        std::iter::from_fn(move || {
            (bits != 0).then(|| {
                let lane = bits.trailing_zeros() as usize;
                bits &= bits - 1;
                lane
            })
        })
    }

    /// Lanes of `self` not in `other`.
    #[inline(always)]
    pub fn and_not(self, other: Self) -> Self {
        Self(self.0 & !other.0)
    }

    /// Panics unless `len ≥ self.count()`: that a slice of `len` values
    /// holds enough for an expanding load into the lanes of `self` (the
    /// `expand_from` methods).
    #[inline(always)]
    pub(super) fn assert_expand_len(self, len: usize) {
        assert!(
            len >= self.count() as usize,
            "expanding load past the slice"
        );
    }
}

impl BitAnd for Mask16 {
    type Output = Self;
    #[inline(always)]
    fn bitand(self, o: Self) -> Self {
        Self(self.0 & o.0)
    }
}

impl BitOr for Mask16 {
    type Output = Self;
    #[inline(always)]
    fn bitor(self, o: Self) -> Self {
        Self(self.0 | o.0)
    }
}

impl BitXor for Mask16 {
    type Output = Self;
    #[inline(always)]
    fn bitxor(self, o: Self) -> Self {
        Self(self.0 ^ o.0)
    }
}

impl Not for Mask16 {
    type Output = Self;
    #[inline(always)]
    fn not(self) -> Self {
        Self(!self.0)
    }
}

binary!(one F32x16;
    Add, add, _mm512_add_ps;
    Sub, sub, _mm512_sub_ps;
    Mul, mul, _mm512_mul_ps;
    Div, div, _mm512_div_ps;
);

negate!(one F32x16; _mm512_xor_ps, _mm512_set1_ps);

impl F32x16 {
    /// Every lane `x`.
    #[inline(always)]
    pub fn splat(_: Avx512, x: f32) -> Self {
        Self(avx!(_mm512_set1_ps(x)))
    }

    /// Lane `i` is `lanes[i]`.
    #[inline(always)]
    pub fn from_array(_: Avx512, lanes: [f32; LANES]) -> Self {
        // `loadu` reads the sixteen `f32` of `lanes` (unaligned is allowed).
        Self(avx!(_mm512_loadu_ps(lanes.as_ptr())))
    }

    /// The lanes as an array.
    #[inline(always)]
    pub fn to_array(self) -> [f32; LANES] {
        let mut out = [0.0; LANES];
        // `storeu` writes the sixteen `f32` of `out`.
        avx!(_mm512_storeu_ps(out.as_mut_ptr(), self.0));
        out
    }

    /// Lane `lane` (`< 16`).
    #[inline(always)]
    pub fn lane(self, lane: usize) -> f32 {
        self.to_array()[lane]
    }

    /// Square root.
    #[inline(always)]
    pub fn sqrt(self) -> Self {
        Self(avx!(_mm512_sqrt_ps(self.0)))
    }

    /// Absolute value (sign bit cleared).
    #[inline(always)]
    pub fn abs(self) -> Self {
        Self(avx!(_mm512_abs_ps(self.0)))
    }

    /// `if self < o { self } else { o }` (module docs).
    #[inline(always)]
    pub fn min(self, o: Self) -> Self {
        Self(avx!(_mm512_min_ps(self.0, o.0)))
    }

    /// `if self > o { self } else { o }` (module docs).
    #[inline(always)]
    pub fn max(self, o: Self) -> Self {
        Self(avx!(_mm512_max_ps(self.0, o.0)))
    }

    clamp!("f32");

    /// `a` in the lanes of `m`, `b` in the others.
    #[inline(always)]
    pub fn select(m: Mask16, a: Self, b: Self) -> Self {
        Self(avx!(_mm512_mask_blend_ps(m.0, b.0, a.0)))
    }

    /// The magnitude of `self` with the sign bit of `sign`.
    #[inline(always)]
    pub fn copysign(self, sign: Self) -> Self {
        // Ternary logic 0xCA (`a ? b : c` bitwise): bits of `sign` where the sign mask is set, of
        // `self` elsewhere.
        let bits = avx!(_mm512_ternarylogic_epi32::<0xCA>(
            _mm512_castps_si512(_mm512_set1_ps(-0.0)),
            _mm512_castps_si512(sign.0),
            _mm512_castps_si512(self.0),
        ));
        Self(avx!(_mm512_castsi512_ps(bits)))
    }

    compare! { one _mm512_cmp_ps_mask;
        /// `self < o` (false on NaN).
        lt, _CMP_LT_OQ;
        /// `self <= o` (false on NaN).
        le, _CMP_LE_OQ;
        /// `self > o` (false on NaN).
        gt, _CMP_GT_OQ;
        /// `self >= o` (false on NaN).
        ge, _CMP_GE_OQ;
        /// `self == o` (false on NaN).
        eq, _CMP_EQ_OQ;
    }

    /// Lanes neither infinite nor NaN.
    #[inline(always)]
    pub fn is_finite(self) -> Mask16 {
        Mask16(avx!(_mm512_cmp_ps_mask::<_CMP_LT_OQ>(
            _mm512_abs_ps(self.0),
            _mm512_set1_ps(f32::INFINITY),
        )))
    }

    /// The lanes' bit patterns.
    #[inline(always)]
    pub fn to_bits(self) -> U32x16 {
        U32x16(avx!(_mm512_castps_si512(self.0)))
    }

    /// Lanes with the bit patterns of `bits`.
    #[inline(always)]
    pub fn from_bits(bits: U32x16) -> Self {
        Self(avx!(_mm512_castsi512_ps(bits.0)))
    }

    /// `u as f32` per lane (rounded to nearest).
    #[inline(always)]
    pub fn from_u32(u: U32x16) -> Self {
        Self(avx!(_mm512_cvtepu32_ps(u.0)))
    }

    /// `self as i32` per lane for finite lanes in `i32`'s range (truncated
    /// toward zero), as `u32` bit patterns; other lanes give `i32::MIN`
    /// (Rust's `as` saturates instead: callers keep to the range).
    #[inline(always)]
    pub fn trunc_i32(self) -> U32x16 {
        U32x16(avx!(_mm512_cvttps_epi32(self.0)))
    }

    /// The lanes widened to `f64` (exact).
    #[inline(always)]
    pub fn to_f64(self) -> F64x16 {
        avx!(F64x16([
            _mm512_cvtps_pd(_mm512_castps512_ps256(self.0)),
            _mm512_cvtps_pd(_mm256_castpd_ps(_mm512_extractf64x4_pd::<1>(
                _mm512_castps_pd(self.0)
            ))),
        ]))
    }

    /// `table[index]` in the lanes of `m`, `fallback` in the others.
    ///
    /// # Panics
    /// If an index of a lane in `m` is out of bounds.
    #[inline(always)]
    pub fn gather(table: &[f32], index: U32x16, m: Mask16, fallback: Self) -> Self {
        index.assert_gather_indices(m, table.len());
        // Every lane read (those of `m`) indexes `table` in bounds (asserted
        // above, and below `i32::MAX`, so the signed indices are the same).
        Self(avx!(_mm512_mask_i32gather_ps::<4>(
            fallback.0,
            m.0,
            index.0,
            table.as_ptr()
        )))
    }

    /// Lane `i` is lane `index[i] % 16` of `self` (one `vpermps`).
    #[inline(always)]
    pub fn permute(self, index: U32x16) -> Self {
        Self(avx!(_mm512_permutexvar_ps(index.0, self.0)))
    }

    /// The smallest of the lanes of `m` (`+∞` without any), for orderings
    /// only: which lane a NaN or a `±0` tie yields is unspecified.
    #[inline(always)]
    pub fn reduce_min(self, m: Mask16) -> f32 {
        avx!(_mm512_mask_reduce_min_ps(m.0, self.0))
    }

    /// `self` with the lanes of `m` replaced by `src[0]`, `src[1]`, … in
    /// lane order (an expanding load).
    ///
    /// # Panics
    /// If `src` holds fewer values than `m` has lanes.
    #[inline(always)]
    pub fn expand_from(self, m: Mask16, src: &[f32]) -> Self {
        m.assert_expand_len(src.len());
        // Reads `m.count()` consecutive `f32`s from `src`, in bounds (asserted).
        Self(avx!(_mm512_mask_expandloadu_ps(self.0, m.0, src.as_ptr())))
    }
}
