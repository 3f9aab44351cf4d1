//! Sixteen lanes at a time: the value types of the wide tracer
//! (`tracer::wide`), one lane per path, over three backends chosen at run
//! time.
//!
//! | type | lanes | holds |
//! |---|---|---|
//! | [`F32x16`] | 16 × `f32` | the backend's `F32` |
//! | [`F64x16`] | 16 × `f64` | the backend's `F64` |
//! | [`U32x16`] | 16 × `u32` | the backend's `U32` |
//! | [`U64x16`] | 16 × `u64` | the backend's `U64` |
//! | [`Mask16`] | 16 × `bool` | a `u16` (bit `i`: lane `i`), on every backend |
//! | [`Vec3x16`] | 16 × [`glam::Vec3`] | three [`F32x16`] |
//!
//! | backend ([`Lanes`]) | CPU | `F32` | `F64` |
//! |---|---|---|---|
//! | [`Avx512`] | AVX-512 F, VL, DQ, BW | one `__m512` | two `__m512d` |
//! | [`Avx2`](crate::bvh::Avx2) | AVX2 | two `__m256` | four `__m256d` |
//! | [`Portable`] | any | `[f32; 16]` | `[f64; 16]` |
//!
//! Model: every lane operation is the IEEE operation the scalar code does on
//! one value (no fused multiply–add, no approximate reciprocals), so a lane
//! computes bit for bit what the scalar tracer computes for its path when
//! the operations come in the same order, on every backend. Where Rust's
//! scalar semantics and the instruction's differ, the method says which it
//! follows: `min` and `max` are `if a < b { a } else { b }` and
//! `if a > b { a } else { b }` (the instructions' rule, and glam's
//! `min_element`/`max_element`; Rust's `f32::min(x, c)` agrees with it for
//! a constant `c` that is not NaN); comparisons are ordered (false on NaN).
//!
//! Soundness: a lane value holds its backend's token (a zero-sized value),
//! and every operation is a method of that token. The x86 backends' tokens
//! exist only on CPUs found to have their features ([`Avx512::detect`],
//! [`Avx2::detect`](crate::bvh::Avx2::detect)), so their intrinsics run
//! only there (one SAFETY comment per backend states this for all its
//! `unsafe` blocks). Wide code is generic over the backend and entered
//! through [`Backend::call`] (the backend picked at run time), which runs it
//! in [`Lanes::run`], compiled with the backend's features, so the
//! intrinsics (all `#[inline(always)]`) become single instructions.
//!
//! Inlining: an intrinsic inlines only into a function compiled with its
//! features, and a closure is compiled as a function of its own, without
//! them. Lane code called from a closure (a `let` closure, or one passed to
//! `array::from_fn` or `map`) therefore stays a call per operation unless
//! the closure is `#[inline(always)]` (allowed on closures passed as
//! arguments, not on `let` ones): wide code uses plain loops, nested
//! `#[inline(always)]` functions, and the token's constant makers
//! ([`Lanes::f32`] and the like) instead.

/// Implements operator traits for a lane type by one backend method each:
/// `binary!(F32x16; Add, add, f32_add; …)`. Every impl is
/// `#[inline(always)]`.
macro_rules! binary {
    ($ty:ident; $($trait:ident, $method:ident, $op:ident;)*) => {
        $(
            impl<B: Lanes> std::ops::$trait for $ty<B> {
                type Output = Self;
                #[inline(always)]
                fn $method(self, o: Self) -> Self {
                    Self(self.1.$op(self.0, o.0), self.1)
                }
            }
        )*
    };
}

/// Defines the ordered comparison methods of a float lane type (inside its
/// `impl`), each returning the [`Mask16`] of the lanes where it holds:
/// `compare!(f32_cmp; /// doc lt, Lt; …)`.
macro_rules! compare {
    ($cmp:ident; $(#[$doc:meta] $method:ident, $predicate:ident;)*) => {
        $(
            #[$doc]
            #[inline(always)]
            pub fn $method(self, o: Self) -> Mask16 {
                self.1.$cmp(self.0, o.0, Cmp::$predicate)
            }
        )*
    };
}

/// Defines `clamp` for a float lane type (inside its `impl`), from its
/// `max` and `min`: the scalar type's `clamp` per lane (`lo` below it, `hi`
/// above it, NaN stays NaN). `lo.max(x)` is `if lo > x { lo } else { x }`,
/// the scalar `if x < lo { lo } else { x }`; `hi.min(x)` likewise its
/// `if x > hi { hi } else { x }`: the same two comparisons, in the same
/// order, one instruction each (no mask).
macro_rules! clamp {
    ($scalar:literal) => {
        #[doc = concat!("Rust's `", $scalar, "::clamp`: `lo` below it, `hi` above it, NaN stays NaN.")]
        #[inline(always)]
        pub fn clamp(self, lo: Self, hi: Self) -> Self {
            hi.min(lo.max(self))
        }
    };
}

#[cfg(target_arch = "x86_64")]
mod avx2;
#[cfg(target_arch = "x86_64")]
mod avx512;
mod backend;
mod f32x16;
mod f64x16;
mod mask;
mod portable;
mod u32x16;
mod u64x16;
mod vec3;

#[cfg(test)]
mod tests;

#[cfg(target_arch = "x86_64")]
pub(crate) use avx512::Avx512;
pub(crate) use backend::{
    Backend, Cmp, F32Ops, F64Ops, Lanes, Registers, U32Ops, U64Ops, WithLanes,
};
pub(crate) use f32x16::F32x16;
pub(crate) use f64x16::F64x16;
pub(crate) use mask::Mask16;
pub(crate) use portable::Portable;
pub(crate) use u32x16::U32x16;
pub(crate) use u64x16::U64x16;
pub(crate) use vec3::Vec3x16;

/// Calls the generic function `$f` (taking a backend token) with every
/// backend this CPU has: the portable one always, then AVX2 and AVX-512
/// where detected. Returns the names of the backends it ran, in that order.
#[cfg(test)]
macro_rules! each_backend {
    ($f:expr) => {{
        let mut ran = vec!["portable"];
        $f($crate::simd::Portable);
        #[cfg(target_arch = "x86_64")]
        {
            if let Some(k) = $crate::bvh::Avx2::detect() {
                $f(k);
                ran.push("avx2");
            }
            if let Some(k) = $crate::simd::Avx512::detect() {
                $f(k);
                ran.push("avx512");
            }
        }
        ran
    }};
}
#[cfg(test)]
pub(crate) use each_backend;

/// Lanes per vector.
pub(crate) const LANES: usize = 16;
