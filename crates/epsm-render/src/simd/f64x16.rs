//! Sixteen `f64` lanes, for the parts of the scalar tracer done in `f64`
//! (exact spheres, light selection).

use super::{Cmp, F32x16, LANES, Lanes, Mask16};

/// Sixteen `f64` lanes (module docs of `simd`): the backend's register and
/// its token.
#[derive(Clone, Copy, Debug)]
pub(crate) struct F64x16<B: Lanes>(pub(super) B::F64, pub(super) B);

binary!(F64x16;
    Add, add, f64_add;
    Sub, sub, f64_sub;
    Mul, mul, f64_mul;
    Div, div, f64_div;
);

impl<B: Lanes> std::ops::Neg for F64x16<B> {
    type Output = Self;
    /// Flips the sign bit, as scalar negation does.
    #[inline(always)]
    fn neg(self) -> Self {
        Self(self.1.f64_neg(self.0), self.1)
    }
}

impl<B: Lanes> F64x16<B> {
    /// Every lane `x`.
    #[inline(always)]
    pub fn splat(k: B, x: f64) -> Self {
        Self(k.f64_splat(x), k)
    }

    /// Lane `i` is `lanes[i]`.
    #[inline(always)]
    pub fn from_array(k: B, lanes: [f64; LANES]) -> Self {
        Self(k.f64_load(lanes), k)
    }

    /// The lanes as an array.
    #[inline(always)]
    pub fn to_array(self) -> [f64; LANES] {
        self.1.f64_store(self.0)
    }

    /// Square root.
    #[inline(always)]
    pub fn sqrt(self) -> Self {
        Self(self.1.f64_sqrt(self.0), self.1)
    }

    /// Absolute value (sign bit cleared).
    #[inline(always)]
    pub fn abs(self) -> Self {
        Self(self.1.f64_abs(self.0), self.1)
    }

    /// `if self < o { self } else { o }` (module docs of `simd`).
    #[inline(always)]
    pub fn min(self, o: Self) -> Self {
        Self(self.1.f64_min(self.0, o.0), self.1)
    }

    /// `if self > o { self } else { o }` (module docs of `simd`).
    #[inline(always)]
    pub fn max(self, o: Self) -> Self {
        Self(self.1.f64_max(self.0, o.0), self.1)
    }

    clamp!("f64");

    /// `a` in the lanes of `m`, `b` in the others.
    #[inline(always)]
    pub fn select(m: Mask16, a: Self, b: Self) -> Self {
        Self(a.1.f64_select(m, a.0, b.0), a.1)
    }

    compare! { f64_cmp;
        /// `self <= o` (false on NaN).
        le, Le;
        /// `self > o` (false on NaN).
        gt, Gt;
        /// `self >= o` (false on NaN).
        ge, Ge;
    }

    /// The lanes rounded to `f32` (to nearest, as `as f32`).
    #[inline(always)]
    pub fn to_f32(self) -> F32x16<B> {
        F32x16(self.1.f64_to_f32(self.0), self.1)
    }

    /// The magnitude of `self` with the sign bit of `sign` (`f64::copysign`).
    #[inline(always)]
    pub fn copysign(self, sign: Self) -> Self {
        Self(self.1.f64_copysign(self.0, sign.0), self.1)
    }
}
