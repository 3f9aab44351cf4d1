//! The backends of the lane types: the traits a backend implements
//! ([`Lanes`] and its operation traits over [`Registers`]), and the choice
//! of one at run time ([`Backend`]).

use std::fmt::Debug;

#[cfg(target_arch = "x86_64")]
use super::Avx512;
use super::{F32x16, LANES, Mask16, Portable, U32x16, U64x16, Vec3x16};
use crate::bvh::BoxTest;

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
/// The operations come in one trait per lane type ([`F32Ops`], …, over the
/// [`Registers`]); every method is the lane-by-lane IEEE (or wrapping
/// integer) operation its lane-type method documents. Lane `i` of a
/// register is lane `i` of the array its `*_load` takes and its `*_store`
/// returns.
pub(crate) trait Lanes: F32Ops + F64Ops + U32Ops + U64Ops {
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
}

/// A backend's registers: what each lane type holds.
pub(crate) trait Registers: Copy + Debug + Send + Sync + 'static {
    /// Sixteen `f32`.
    type F32: Copy + Debug;
    /// Sixteen `f64`.
    type F64: Copy + Debug;
    /// Sixteen `u32`.
    type U32: Copy + Debug;
    /// Sixteen `u64`.
    type U64: Copy + Debug;
}

/// The `f32` lane operations ([`F32x16`]).
#[allow(unsafe_code)]
pub(crate) trait F32Ops: Registers {
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
}

/// The `f64` lane operations ([`F64x16`]).
pub(crate) trait F64Ops: Registers {
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
    fn f64_max(self, a: Self::F64, b: Self::F64) -> Self::F64;
    fn f64_select(self, m: Mask16, a: Self::F64, b: Self::F64) -> Self::F64;
    fn f64_copysign(self, magnitude: Self::F64, sign: Self::F64) -> Self::F64;
    fn f64_cmp(self, a: Self::F64, b: Self::F64, c: Cmp) -> Mask16;
    fn f64_to_f32(self, a: Self::F64) -> Self::F32;
}

/// The `u32` lane operations ([`U32x16`]).
#[allow(unsafe_code)]
pub(crate) trait U32Ops: Registers {
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
}

/// The `u64` lane operations ([`U64x16`]).
#[allow(unsafe_code)]
pub(crate) trait U64Ops: Registers {
    fn u64_splat(self, x: u64) -> Self::U64;
    #[cfg(test)]
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
