//! The AVX2 backend, for the token [`Avx2`]: sixteen `f32` or `u32` lanes in
//! two 256-bit registers (lanes 0–7, 8–15), sixteen `f64` or `u64` lanes in
//! four (lanes 0–3, 4–7, 8–11, 12–15). Masks live in the lane types as
//! `u16` bits (as on AVX-512): a compare's vector mask is packed with
//! `movemask`, and a select or masked gather unpacks the bits again, each
//! into its lane's sign bit (one broadcast and a variable shift per
//! register). No closures: a closure is compiled without the backend's
//! features, so the intrinsics in it would stay calls (module `simd`). No fused multiply–add:
//! every operation rounds as the scalar one.

#![allow(unsafe_code)]

use std::arch::asm;
use std::arch::x86_64::*;

use super::{Cmp, LANES, Lanes, Mask16, Portable, Registers};
use crate::bvh::Avx2;

/// Runs an AVX2 intrinsic expression.
///
/// SAFETY (every use): the expression calls AVX and AVX2 intrinsics (or
/// this module's functions that require AVX) inside a method of [`Avx2`]
/// or a helper only those methods call, and a value of [`Avx2`] exists
/// only after [`Avx2::detect`] found AVX, AVX2, BMI1, BMI2, LZCNT and
/// POPCNT; pointer arguments, where an intrinsic takes one, are stated at
/// the use.
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

/// The lanes of `m` as two 32-bit-lane vector masks, in the lanes' sign
/// bits (what `blendv` and the masked gathers read; the other bits are
/// unspecified): bit `i` of `m` shifted to bit 31 of lane `i`.
#[inline(always)]
fn mask32(m: Mask16) -> [__m256i; 2] {
    let bits = avx!(_mm256_set1_epi32(i32::from(m.0)));
    avx!([
        _mm256_sllv_epi32(bits, _mm256_setr_epi32(31, 30, 29, 28, 27, 26, 25, 24)),
        _mm256_sllv_epi32(bits, _mm256_setr_epi32(23, 22, 21, 20, 19, 18, 17, 16)),
    ])
}

/// The lanes of `m` as four 64-bit-lane vector masks, in the lanes' sign
/// bits (the other bits unspecified): bit `i` of `m` shifted to bit 63 of
/// lane `i`.
#[inline(always)]
fn mask64(m: Mask16) -> [__m256i; 4] {
    let bits = avx!(_mm256_set1_epi64x(i64::from(m.0)));
    avx!([
        _mm256_sllv_epi64(bits, _mm256_setr_epi64x(63, 62, 61, 60)),
        _mm256_sllv_epi64(bits, _mm256_setr_epi64x(59, 58, 57, 56)),
        _mm256_sllv_epi64(bits, _mm256_setr_epi64x(55, 54, 53, 52)),
        _mm256_sllv_epi64(bits, _mm256_setr_epi64x(51, 50, 49, 48)),
    ])
}

/// The byte indices that spread a register's first values over the lanes
/// set in `b`, each value `width` 32-bit lanes wide (1 for `f32`, 2 for
/// `u64`): for each set bit `i` of `b` with `r` set bits below it, bytes
/// `width·i + j` (`j < width`) hold `width·r + j`; the other bytes 0.
const fn expand_bytes(b: usize, width: usize) -> u64 {
    let (mut out, mut rank, mut i) = (0u64, 0, 0);
    while i < 8 / width {
        if b >> i & 1 != 0 {
            let mut j = 0;
            while j < width {
                out |= ((width * rank + j) as u64) << (8 * (width * i + j));
                j += 1;
            }
            rank += 1;
        }
        i += 1;
    }
    out
}

/// [`expand_bytes`] of every byte, width 1: the `f32` expanding loads'
/// indices by the eight lanes' mask bits.
const EXPAND32: [u64; 256] = {
    let mut table = [0; 256];
    let mut b = 0;
    while b < 256 {
        table[b] = expand_bytes(b, 1);
        b += 1;
    }
    table
};

/// [`expand_bytes`] of every nibble, width 2: the `u64` expanding loads'
/// indices by the four lanes' mask bits.
const EXPAND64: [u64; 16] = {
    let mut table = [0; 16];
    let mut b = 0;
    while b < 16 {
        table[b] = expand_bytes(b, 2);
        b += 1;
    }
    table
};

/// The first `n ≤ 8` lanes of a register of eight 32-bit lanes, as a
/// vector mask (all ones where set).
#[inline(always)]
fn first32(n: u32) -> __m256i {
    avx!(_mm256_cmpgt_epi32(
        _mm256_set1_epi32(n as i32),
        _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7)
    ))
}

/// Eight bytes as the eight 32-bit lanes of a register (the indices of
/// [`EXPAND32`] and [`EXPAND64`]).
#[inline(always)]
fn byte_lanes(bytes: u64) -> __m256i {
    avx!(_mm256_cvtepu8_epi32(_mm_cvtsi64_si128(bytes as i64)))
}

/// `vmovmskps`: the sign bits of the eight lanes of `v` (bit `i`: lane
/// `i`). In inline assembly: LLVM rewrites two `_mm256_movemask_ps` joined
/// into one `u16` (what [`pack32`] does) as a chain of packs and shuffles,
/// twice the instructions, on the port the broadcasts and permutes need.
#[target_feature(enable = "avx")]
#[inline]
fn movemask_ps(v: __m256) -> u32 {
    let bits: u32;
    // SAFETY: `vmovmskps` (AVX, which this function requires) reads one
    // register and writes another: no memory, no stack, no flags.
    unsafe {
        asm!(
            "vmovmskps {bits:e}, {v}",
            bits = out(reg) bits,
            v = in(ymm_reg) v,
            options(pure, nomem, nostack, preserves_flags),
        );
    }
    bits
}

/// `vmovmskpd`: the sign bits of the four lanes of `v`, in inline
/// assembly as [`movemask_ps`] (LLVM rewrites four `_mm256_movemask_pd`
/// joined into one `u16` likewise).
#[target_feature(enable = "avx")]
#[inline]
fn movemask_pd(v: __m256d) -> u32 {
    let bits: u32;
    // SAFETY: `vmovmskpd` (AVX, which this function requires) reads one
    // register and writes another: no memory, no stack, no flags.
    unsafe {
        asm!(
            "vmovmskpd {bits:e}, {v}",
            bits = out(reg) bits,
            v = in(ymm_reg) v,
            options(pure, nomem, nostack, preserves_flags),
        );
    }
    bits
}

/// The mask of two 32-bit-lane vector masks (their sign bits).
#[inline(always)]
fn pack32(m: [__m256; 2]) -> Mask16 {
    let [lo, hi] = each!(2, movemask_ps(m));
    Mask16(lo as u16 | (hi as u16) << 8)
}

/// The mask of four 64-bit-lane vector masks (their sign bits).
#[inline(always)]
fn pack64(m: [__m256d; 4]) -> Mask16 {
    let q = each!(4, movemask_pd(m));
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
