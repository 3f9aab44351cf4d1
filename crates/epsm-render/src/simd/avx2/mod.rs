//! The AVX2 backend, for the token [`Avx2`]: sixteen `f32` or `u32` lanes in
//! two 256-bit registers (lanes 0–7, 8–15), sixteen `f64` or `u64` lanes in
//! four (lanes 0–3, 4–7, 8–11, 12–15). Masks live in the lane types as
//! `u16` bits (as on AVX-512): a compare's vector mask is packed with
//! `movemask`, and a select unpacks the bits again. No fused multiply–add:
//! every operation rounds as the scalar one.

#![allow(unsafe_code)]

use std::arch::x86_64::*;

use super::{Cmp, LANES, Lanes, Mask16, Portable, Registers};
use crate::bvh::Avx2;

/// Runs an AVX2 intrinsic expression.
///
/// SAFETY (every use): the expression calls AVX and AVX2 intrinsics inside
/// a method of [`Avx2`], whose `self` exists only after
/// [`Avx2::detect`] found AVX, AVX2, BMI1, BMI2, LZCNT and POPCNT; pointer
/// arguments, where an intrinsic takes one, are stated at the use.
macro_rules! avx {
    ($e:expr) => {
        // SAFETY: see the macro's documentation.
        unsafe { $e }
    };
}

/// `$f` applied register by register to an `$n`-register value
/// (`[$a[0], …]`).
macro_rules! each {
    (2, $f:ident $(::<$g:tt>)? ($($a:expr),*)) => {
        [avx!($f$(::<$g>)?($($a[0]),*)), avx!($f$(::<$g>)?($($a[1]),*))]
    };
    (4, $f:ident $(::<$g:tt>)? ($($a:expr),*)) => {
        [
            avx!($f$(::<$g>)?($($a[0]),*)),
            avx!($f$(::<$g>)?($($a[1]),*)),
            avx!($f$(::<$g>)?($($a[2]),*)),
            avx!($f$(::<$g>)?($($a[3]),*)),
        ]
    };
}

/// The lanes of `m` as two 32-bit-lane vector masks (all ones where set).
#[inline(always)]
fn mask32(m: Mask16) -> [__m256i; 2] {
    let bits = avx!(_mm256_setr_epi32(1, 2, 4, 8, 16, 32, 64, 128));
    let half = |b: u16| {
        avx!(_mm256_cmpeq_epi32(
            _mm256_and_si256(_mm256_set1_epi32(i32::from(b & 0xFF)), bits),
            bits
        ))
    };
    [half(m.0), half(m.0 >> 8)]
}

/// The lanes of `m` as four 64-bit-lane vector masks (all ones where set).
#[inline(always)]
fn mask64(m: Mask16) -> [__m256i; 4] {
    let bits = avx!(_mm256_setr_epi64x(1, 2, 4, 8));
    let quarter = |q: u16| {
        avx!(_mm256_cmpeq_epi64(
            _mm256_and_si256(_mm256_set1_epi64x(i64::from(m.0 >> (4 * q) & 0xF)), bits),
            bits
        ))
    };
    [quarter(0), quarter(1), quarter(2), quarter(3)]
}

/// The mask of two 32-bit-lane vector masks (their sign bits).
#[inline(always)]
fn pack32(m: [__m256; 2]) -> Mask16 {
    let [lo, hi] = each!(2, _mm256_movemask_ps(m));
    Mask16(lo as u16 | (hi as u16) << 8)
}

/// The mask of four 64-bit-lane vector masks (their sign bits).
#[inline(always)]
fn pack64(m: [__m256d; 4]) -> Mask16 {
    let q = each!(4, _mm256_movemask_pd(m));
    Mask16((q[0] | q[1] << 4 | q[2] << 8 | q[3] << 12) as u16)
}

/// The `f32` compare `c` of `a` and `b`, register by register.
#[inline(always)]
fn cmp_ps(a: [__m256; 2], b: [__m256; 2], c: Cmp) -> [__m256; 2] {
    match c {
        Cmp::Lt => each!(2, _mm256_cmp_ps::<_CMP_LT_OQ>(a, b)),
        Cmp::Le => each!(2, _mm256_cmp_ps::<_CMP_LE_OQ>(a, b)),
        Cmp::Gt => each!(2, _mm256_cmp_ps::<_CMP_GT_OQ>(a, b)),
        Cmp::Ge => each!(2, _mm256_cmp_ps::<_CMP_GE_OQ>(a, b)),
        Cmp::Eq => each!(2, _mm256_cmp_ps::<_CMP_EQ_OQ>(a, b)),
    }
}

/// The sixteen 32-bit lanes as four quarters of four (for the `f64` and
/// `u64` conversions and gathers).
#[inline(always)]
fn quarters(a: [__m256i; 2]) -> [__m128i; 4] {
    avx!([
        _mm256_castsi256_si128(a[0]),
        _mm256_extracti128_si256::<1>(a[0]),
        _mm256_castsi256_si128(a[1]),
        _mm256_extracti128_si256::<1>(a[1]),
    ])
}

impl Registers for Avx2 {
    type F32 = [__m256; 2];
    type F64 = [__m256d; 4];
    type U32 = [__m256i; 2];
    type U64 = [__m256i; 4];
}

impl Lanes for Avx2 {
    type Boxes = crate::bvh::Avx;

    #[inline(always)]
    fn boxes(self) -> Self::Boxes {
        Avx2::boxes(self)
    }

    #[inline(always)]
    fn run<R>(self, f: impl FnOnce() -> R) -> R {
        #[target_feature(enable = "avx2,bmi1,bmi2,lzcnt,popcnt")]
        fn run<R>(f: impl FnOnce() -> R) -> R {
            f()
        }
        // SAFETY: `run` requires only the features it enables, and `self`
        // exists only on a CPU found to have each of them.
        unsafe { run(f) }
    }
}

mod f32_ops;
mod f64_ops;
mod u32_ops;
mod u64_ops;
