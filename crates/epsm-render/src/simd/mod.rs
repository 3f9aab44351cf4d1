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
//! through [`Lanes::run`], which compiles it with the backend's features,
//! so the intrinsics (all `#[inline(always)]`) become single instructions.
//!
//! Inlining: an intrinsic inlines only into a function compiled with its
//! features, and a closure is compiled as a function of its own, without
//! them. Lane code called from a closure (a `let` closure, or one passed to
//! `array::from_fn` or `map`) therefore stays a call per operation unless
//! the closure is `#[inline(always)]` (allowed on closures passed as
//! arguments, not on `let` ones): wide code uses plain loops, nested
//! `#[inline(always)]` functions, and the token's constant makers
//! ([`Lanes::f32`] and the like) instead.

use std::fmt::Debug;

use crate::bvh::BoxTest;

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

#[cfg(target_arch = "x86_64")]
mod avx2;
#[cfg(target_arch = "x86_64")]
mod avx512;
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

/// A computation generic over the backend: what [`Backend::call`] runs
/// (a closure cannot be generic).
pub(crate) trait WithLanes {
    /// What it returns.
    type Output;
    /// Runs it with backend `k` (inlined into [`Lanes::run`]).
    fn call<B: Lanes>(self, k: B) -> Self::Output;
}

/// One of the backends, chosen at run time.
#[derive(Clone, Copy, Debug)]
pub(crate) enum Backend {
    /// AVX-512 lanes.
    #[cfg(target_arch = "x86_64")]
    Avx512(Avx512),
    /// AVX2 lanes.
    #[cfg(target_arch = "x86_64")]
    Avx2(crate::bvh::Avx2),
    /// Plain arrays.
    Portable(Portable),
}

impl Backend {
    /// The fastest vector backend this CPU has: AVX-512, else AVX2; `None`
    /// without either (the portable lanes are slower than the scalar code
    /// there: `docs/performance.md`).
    pub fn fastest() -> Option<Self> {
        #[cfg(target_arch = "x86_64")]
        {
            if let Some(k) = Avx512::detect() {
                return Some(Self::Avx512(k));
            }
            if let Some(k) = crate::bvh::Avx2::detect() {
                return Some(Self::Avx2(k));
            }
        }
        None
    }

    /// Runs `w` with this backend, compiled with its CPU features.
    pub fn call<W: WithLanes>(self, w: W) -> W::Output {
        match self {
            #[cfg(target_arch = "x86_64")]
            Self::Avx512(k) => k.run(
                #[inline(always)]
                || w.call(k),
            ),
            #[cfg(target_arch = "x86_64")]
            Self::Avx2(k) => k.run(
                #[inline(always)]
                || w.call(k),
            ),
            Self::Portable(k) => k.run(
                #[inline(always)]
                || w.call(k),
            ),
        }
    }
}

/// An ordered float comparison (false on NaN).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Cmp {
    /// `a < b`.
    Lt,
    /// `a <= b`.
    Le,
    /// `a > b`.
    Gt,
    /// `a >= b`.
    Ge,
    /// `a == b`.
    Eq,
}

impl Cmp {
    /// The comparison on two scalars.
    #[inline(always)]
    pub fn scalar<T: PartialOrd>(self, a: T, b: T) -> bool {
        match self {
            Self::Lt => a < b,
            Self::Le => a <= b,
            Self::Gt => a > b,
            Self::Ge => a >= b,
            Self::Eq => a == b,
        }
    }
}

/// A backend of the lane types: a token (a value exists only on a CPU with
/// the backend's features) whose methods are the lane operations on its
/// registers. The lane types ([`F32x16`], …) wrap a register and the token
/// and call these; wide code uses the lane types, generic over the backend.
///
/// Every method is the lane-by-lane IEEE (or wrapping integer) operation
/// its lane-type method documents. Lane `i` of a register is lane `i` of
/// the array its `*_load` takes and its `*_store` returns.
#[allow(unsafe_code)]
pub(crate) trait Lanes: Copy + Debug + Send + Sync + 'static {
    /// Sixteen `f32`.
    type F32: Copy + Debug;
    /// Sixteen `f64`.
    type F64: Copy + Debug;
    /// Sixteen `u32`.
    type U32: Copy + Debug;
    /// Sixteen `u64`.
    type U64: Copy + Debug;
    /// The scalar BVH's box tests at this CPU level (for the per-lane
    /// fallbacks of the wide walks).
    type Boxes: BoxTest;

    /// The box tests of this CPU level.
    fn boxes(self) -> Self::Boxes;

    /// Runs `f` compiled with the backend's CPU features (`f` must be
    /// inlined: callers pass an `#[inline(always)]` closure).
    fn run<R>(self, f: impl FnOnce() -> R) -> R;

    /// Every lane `x` ([`F32x16::splat`]).
    #[inline(always)]
    fn f32(self, x: f32) -> F32x16<Self> {
        F32x16::splat(self, x)
    }

    /// Every lane `x` ([`U32x16::splat`]).
    #[inline(always)]
    fn u32(self, x: u32) -> U32x16<Self> {
        U32x16::splat(self, x)
    }

    /// Every lane `x` ([`U64x16::splat`]).
    #[inline(always)]
    fn u64(self, x: u64) -> U64x16<Self> {
        U64x16::splat(self, x)
    }

    /// Every lane `v` ([`Vec3x16::splat`]).
    #[inline(always)]
    fn vec3(self, v: glam::Vec3) -> Vec3x16<Self> {
        Vec3x16::splat(self, v)
    }

    // `f32` lanes.
    fn f32_splat(self, x: f32) -> Self::F32;
    fn f32_load(self, lanes: [f32; LANES]) -> Self::F32;
    fn f32_store(self, v: Self::F32) -> [f32; LANES];
    fn f32_add(self, a: Self::F32, b: Self::F32) -> Self::F32;
    fn f32_sub(self, a: Self::F32, b: Self::F32) -> Self::F32;
    fn f32_mul(self, a: Self::F32, b: Self::F32) -> Self::F32;
    fn f32_div(self, a: Self::F32, b: Self::F32) -> Self::F32;
    fn f32_neg(self, a: Self::F32) -> Self::F32;
    fn f32_sqrt(self, a: Self::F32) -> Self::F32;
    fn f32_abs(self, a: Self::F32) -> Self::F32;
    fn f32_min(self, a: Self::F32, b: Self::F32) -> Self::F32;
    fn f32_max(self, a: Self::F32, b: Self::F32) -> Self::F32;
    fn f32_select(self, m: Mask16, a: Self::F32, b: Self::F32) -> Self::F32;
    fn f32_copysign(self, magnitude: Self::F32, sign: Self::F32) -> Self::F32;
    fn f32_cmp(self, a: Self::F32, b: Self::F32, c: Cmp) -> Mask16;
    fn f32_to_bits(self, a: Self::F32) -> Self::U32;
    fn f32_from_bits(self, a: Self::U32) -> Self::F32;
    fn f32_from_u32(self, a: Self::U32) -> Self::F32;
    fn f32_trunc_i32(self, a: Self::F32) -> Self::U32;
    fn f32_to_f64(self, a: Self::F32) -> Self::F64;
    fn f32_permute(self, a: Self::F32, index: Self::U32) -> Self::F32;
    fn f32_reduce_min(self, a: Self::F32, m: Mask16) -> f32;
    /// # Safety
    /// Every lane of `m` indexes `table` in bounds, below `i32::MAX`.
    unsafe fn f32_gather(
        self,
        table: &[f32],
        index: Self::U32,
        m: Mask16,
        fallback: Self::F32,
    ) -> Self::F32;
    /// # Safety
    /// `src` holds at least `m.count()` values.
    unsafe fn f32_expand(self, a: Self::F32, m: Mask16, src: &[f32]) -> Self::F32;

    // `f64` lanes.
    fn f64_splat(self, x: f64) -> Self::F64;
    fn f64_load(self, lanes: [f64; LANES]) -> Self::F64;
    fn f64_store(self, v: Self::F64) -> [f64; LANES];
    fn f64_add(self, a: Self::F64, b: Self::F64) -> Self::F64;
    fn f64_sub(self, a: Self::F64, b: Self::F64) -> Self::F64;
    fn f64_mul(self, a: Self::F64, b: Self::F64) -> Self::F64;
    fn f64_div(self, a: Self::F64, b: Self::F64) -> Self::F64;
    fn f64_neg(self, a: Self::F64) -> Self::F64;
    fn f64_sqrt(self, a: Self::F64) -> Self::F64;
    fn f64_abs(self, a: Self::F64) -> Self::F64;
    fn f64_min(self, a: Self::F64, b: Self::F64) -> Self::F64;
    fn f64_select(self, m: Mask16, a: Self::F64, b: Self::F64) -> Self::F64;
    fn f64_copysign(self, magnitude: Self::F64, sign: Self::F64) -> Self::F64;
    fn f64_cmp(self, a: Self::F64, b: Self::F64, c: Cmp) -> Mask16;
    fn f64_to_f32(self, a: Self::F64) -> Self::F32;

    // `u32` lanes.
    fn u32_splat(self, x: u32) -> Self::U32;
    fn u32_load(self, lanes: [u32; LANES]) -> Self::U32;
    fn u32_store(self, v: Self::U32) -> [u32; LANES];
    fn u32_add(self, a: Self::U32, b: Self::U32) -> Self::U32;
    fn u32_sub(self, a: Self::U32, b: Self::U32) -> Self::U32;
    fn u32_mul(self, a: Self::U32, b: Self::U32) -> Self::U32;
    fn u32_and(self, a: Self::U32, b: Self::U32) -> Self::U32;
    fn u32_or(self, a: Self::U32, b: Self::U32) -> Self::U32;
    fn u32_xor(self, a: Self::U32, b: Self::U32) -> Self::U32;
    fn u32_shr(self, a: Self::U32, n: u32) -> Self::U32;
    fn u32_shl(self, a: Self::U32, n: u32) -> Self::U32;
    fn u32_shr_signed(self, a: Self::U32, n: u32) -> Self::U32;
    fn u32_select(self, m: Mask16, a: Self::U32, b: Self::U32) -> Self::U32;
    fn u32_lt(self, a: Self::U32, b: Self::U32) -> Mask16;
    fn u32_eq(self, a: Self::U32, b: Self::U32) -> Mask16;
    /// # Safety
    /// Every lane of `m` indexes `table` in bounds, below `i32::MAX`.
    unsafe fn u32_gather(
        self,
        table: &[u32],
        index: Self::U32,
        m: Mask16,
        fallback: Self::U32,
    ) -> Self::U32;

    // `u64` lanes.
    fn u64_splat(self, x: u64) -> Self::U64;
    fn u64_load(self, lanes: [u64; LANES]) -> Self::U64;
    fn u64_store(self, v: Self::U64) -> [u64; LANES];
    fn u64_add(self, a: Self::U64, b: Self::U64) -> Self::U64;
    fn u64_mul(self, a: Self::U64, b: Self::U64) -> Self::U64;
    fn u64_xor(self, a: Self::U64, b: Self::U64) -> Self::U64;
    fn u64_shr(self, a: Self::U64, n: u32) -> Self::U64;
    fn u64_from_u32(self, a: Self::U32) -> Self::U64;
    fn u64_low_u32(self, a: Self::U64) -> Self::U32;
    /// # Safety
    /// Every lane of `m` indexes `table` in bounds, below `i32::MAX`.
    unsafe fn u64_gather(
        self,
        table: &[u64],
        index: Self::U32,
        m: Mask16,
        fallback: Self::U64,
    ) -> Self::U64;
    /// # Safety
    /// `src` holds at least `m.count()` values.
    unsafe fn u64_expand(self, a: Self::U64, m: Mask16, src: &[u64]) -> Self::U64;
}
