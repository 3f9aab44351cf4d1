//! Sixteen lanes at a time: the value types of the wide tracer
//! (`tracer::wide`), one lane per path, on CPUs with AVX-512.
//!
//! | type | lanes | holds |
//! |---|---|---|
//! | [`F32x16`] | 16 × `f32` | one `__m512` |
//! | [`F64x16`] | 16 × `f64` | two `__m512d` (lanes 0–7, 8–15) |
//! | [`U32x16`] | 16 × `u32` | one `__m512i` |
//! | [`U64x16`] | 16 × `u64` | two `__m512i` (lanes 0–7, 8–15) |
//! | [`Mask16`] | 16 × `bool` | one `__mmask16` (bit `i`: lane `i`) |
//! | [`Vec3x16`] | 16 × [`glam::Vec3`] | three [`F32x16`] |
//!
//! Model: every lane operation is the IEEE operation the scalar code does on
//! one value (no fused multiply–add, no approximate reciprocals), so a lane
//! computes bit for bit what the scalar tracer computes for its path when
//! the operations come in the same order. Where Rust's scalar semantics and
//! the instruction's differ, the method says which it follows: `min` and
//! `max` are `if a < b { a } else { b }` and `if a > b { a } else { b }`
//! (the instructions' rule, and glam's `min_element`/`max_element`; Rust's
//! `f32::min(x, c)` agrees with it for a constant `c` that is not NaN);
//! comparisons are ordered (false on NaN) except `ne`.
//!
//! Soundness: the lane types wrap AVX-512 registers and their methods call
//! the intrinsics without checking the CPU. A value of any of them can only
//! be made from an [`Avx512`] token (the constructors take one) or from other
//! values, and a token exists only on a CPU found to have AVX-512 F, VL, DQ
//! and BW ([`Avx512::detect`]), so every intrinsic call runs on such a CPU
//! (the `avx!` macro below states this once for every `unsafe` block). The
//! methods are `#[inline(always)]` so that they compile into the caller's
//! `#[target_feature]` function as single instructions.
//!
//! Inlining: an intrinsic inlines only into a function compiled with its
//! features, and a closure is compiled as a function of its own, without
//! them. Lane code called from a closure (a `let` closure, or one passed to
//! `array::from_fn` or `map`) therefore stays a call per operation unless
//! the closure is `#[inline(always)]` (allowed on closures passed as
//! arguments, not on `let` ones): wide code uses plain loops, nested
//! `#[inline(always)]` functions, and the token's constant makers
//! ([`Avx512::f32`] and the like) instead.

#![allow(unsafe_code)]

/// Runs an AVX-512 intrinsic expression.
///
/// SAFETY (every use): the expression calls AVX-512 F/VL/DQ/BW intrinsics
/// (and the AVX2 ones they imply) on values of this module's lane types,
/// which exist only after [`Avx512::detect`] found those features (module
/// docs); pointer arguments, where an intrinsic takes one, are stated at the
/// use.
macro_rules! avx {
    ($e:expr) => {
        // SAFETY: see the macro's documentation.
        unsafe { $e }
    };
}

/// Implements operator traits for a lane type by one intrinsic each, applied
/// register by register: `binary!(one T; Add, add, _mm512_add_ps; …)` for a
/// type wrapping one register, `binary!(two T; …)` for one wrapping two
/// (lanes 0–7, 8–15). Every impl is `#[inline(always)]`.
macro_rules! binary {
    (one $ty:ident; $($trait:ident, $method:ident, $intrinsic:ident;)*) => {
        $(
            impl std::ops::$trait for $ty {
                type Output = Self;
                #[inline(always)]
                fn $method(self, o: Self) -> Self {
                    Self(avx!($intrinsic(self.0, o.0)))
                }
            }
        )*
    };
    (two $ty:ident; $($trait:ident, $method:ident, $intrinsic:ident;)*) => {
        $(
            impl std::ops::$trait for $ty {
                type Output = Self;
                #[inline(always)]
                fn $method(self, o: Self) -> Self {
                    Self([
                        avx!($intrinsic(self.0[0], o.0[0])),
                        avx!($intrinsic(self.0[1], o.0[1])),
                    ])
                }
            }
        )*
    };
}

/// Implements `Neg` for a float lane type as scalar negation does it: the
/// sign bit flipped (`$xor` with `$set1(-0.0)`), register by register
/// (`one` or `two` registers, as for [`binary!`]).
macro_rules! negate {
    (one $ty:ident; $xor:ident, $set1:ident) => {
        impl std::ops::Neg for $ty {
            type Output = Self;
            /// Flips the sign bit, as scalar negation does.
            #[inline(always)]
            fn neg(self) -> Self {
                Self(avx!($xor(self.0, $set1(-0.0))))
            }
        }
    };
    (two $ty:ident; $xor:ident, $set1:ident) => {
        impl std::ops::Neg for $ty {
            type Output = Self;
            /// Flips the sign bit, as scalar negation does.
            #[inline(always)]
            fn neg(self) -> Self {
                let sign = avx!($set1(-0.0));
                Self([avx!($xor(self.0[0], sign)), avx!($xor(self.0[1], sign))])
            }
        }
    };
}

/// Defines the ordered comparison methods of a float lane type (inside its
/// `impl`), each returning the [`Mask16`] of the lanes where it holds:
/// `compare!(one _mm512_cmp_ps_mask; /// doc lt, _CMP_LT_OQ; …)` for a type
/// wrapping one register, `compare!(two _mm512_cmp_pd_mask; …)` for one
/// wrapping two (the first register's mask in the low byte).
macro_rules! compare {
    (one $cmp:ident; $(#[$doc:meta] $method:ident, $predicate:ident;)*) => {
        $(
            #[$doc]
            #[inline(always)]
            pub fn $method(self, o: Self) -> Mask16 {
                Mask16(avx!($cmp::<$predicate>(self.0, o.0)))
            }
        )*
    };
    (two $cmp:ident; $(#[$doc:meta] $method:ident, $predicate:ident;)*) => {
        $(
            #[$doc]
            #[inline(always)]
            pub fn $method(self, o: Self) -> Mask16 {
                let lo = avx!($cmp::<$predicate>(self.0[0], o.0[0]));
                let hi = avx!($cmp::<$predicate>(self.0[1], o.0[1]));
                Mask16(u16::from(lo) | u16::from(hi) << 8)
            }
        )*
    };
}

/// Defines `clamp` for a float lane type (inside its `impl`), from its
/// `select`, `lt` and `gt`: the scalar type's `clamp` per lane (`lo` below
/// it, `hi` above it, NaN stays NaN), the same two comparisons in the same
/// order.
macro_rules! clamp {
    ($scalar:literal) => {
        #[doc = concat!("Rust's `", $scalar, "::clamp`: `lo` below it, `hi` above it, NaN stays NaN.")]
        #[inline(always)]
        pub fn clamp(self, lo: Self, hi: Self) -> Self {
            let x = Self::select(self.lt(lo), lo, self);
            Self::select(x.gt(hi), hi, x)
        }
    };
}

mod f32x16;
mod f64x16;
mod u32x16;
mod u64x16;
mod vec3;

#[cfg(test)]
mod tests;

pub(crate) use f32x16::{F32x16, Mask16};
pub(crate) use f64x16::F64x16;
pub(crate) use u32x16::U32x16;
pub(crate) use u64x16::U64x16;
pub(crate) use vec3::Vec3x16;

/// Lanes per vector.
pub(crate) const LANES: usize = 16;

/// Proof that the CPU has AVX-512 F, VL, DQ and BW, and with them AVX2,
/// BMI1, BMI2, LZCNT and POPCNT: code compiled with
/// `#[target_feature(enable = "avx512f,avx512vl,avx512dq,avx512bw,avx2,bmi1,bmi2,lzcnt,popcnt")]`
/// may run while one is held, and it makes the lane types' constants.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Avx512(());

impl Avx512 {
    /// Every lane `x` ([`F32x16::splat`]).
    #[inline(always)]
    pub fn f32(self, x: f32) -> F32x16 {
        F32x16::splat(self, x)
    }

    /// Every lane `x` ([`U32x16::splat`]).
    #[inline(always)]
    pub fn u32(self, x: u32) -> U32x16 {
        U32x16::splat(self, x)
    }

    /// Every lane `x` ([`U64x16::splat`]).
    #[inline(always)]
    pub fn u64(self, x: u64) -> U64x16 {
        U64x16::splat(self, x)
    }

    /// Every lane `v` ([`Vec3x16::splat`]).
    #[inline(always)]
    pub fn vec3(self, v: glam::Vec3) -> Vec3x16 {
        Vec3x16::splat(self, v)
    }

    /// The token, when the CPU has every feature it stands for.
    pub fn detect() -> Option<Self> {
        use std::arch::is_x86_feature_detected as has;
        (has!("avx512f")
            && has!("avx512vl")
            && has!("avx512dq")
            && has!("avx512bw")
            && has!("avx2")
            && has!("bmi1")
            && has!("bmi2")
            && has!("lzcnt")
            && has!("popcnt"))
        .then_some(Self(()))
    }
}
