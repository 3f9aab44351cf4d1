//! The AVX2 backend, for the token [`Avx2`]: sixteen `f32` or `u32` lanes in
//! two 256-bit registers (lanes 0–7, 8–15), sixteen `f64` or `u64` lanes in
//! four (lanes 0–3, 4–7, 8–11, 12–15). Masks live in the lane types as
//! `u16` bits (as on AVX-512): a compare's vector mask is packed with
//! `movemask`, and a select unpacks the bits again. No fused multiply–add:
//! every operation rounds as the scalar one.

#![allow(unsafe_code)]

use std::arch::x86_64::*;

use super::{Cmp, LANES, Lanes, Mask16, Portable};
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

impl Lanes for Avx2 {
    type F32 = [__m256; 2];
    type F64 = [__m256d; 4];
    type U32 = [__m256i; 2];
    type U64 = [__m256i; 4];
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

    #[inline(always)]
    fn f32_splat(self, x: f32) -> Self::F32 {
        let v = avx!(_mm256_set1_ps(x));
        [v, v]
    }
    #[inline(always)]
    fn f32_load(self, lanes: [f32; LANES]) -> Self::F32 {
        // Each `loadu` reads eight of the sixteen `f32` of `lanes`.
        avx!([
            _mm256_loadu_ps(lanes.as_ptr()),
            _mm256_loadu_ps(lanes[8..].as_ptr()),
        ])
    }
    #[inline(always)]
    fn f32_store(self, v: Self::F32) -> [f32; LANES] {
        let mut out = [0.0; LANES];
        // Each `storeu` writes eight of the sixteen `f32` of `out`.
        avx!(_mm256_storeu_ps(out.as_mut_ptr(), v[0]));
        avx!(_mm256_storeu_ps(out[8..].as_mut_ptr(), v[1]));
        out
    }
    #[inline(always)]
    fn f32_add(self, a: Self::F32, b: Self::F32) -> Self::F32 {
        each!(2, _mm256_add_ps(a, b))
    }
    #[inline(always)]
    fn f32_sub(self, a: Self::F32, b: Self::F32) -> Self::F32 {
        each!(2, _mm256_sub_ps(a, b))
    }
    #[inline(always)]
    fn f32_mul(self, a: Self::F32, b: Self::F32) -> Self::F32 {
        each!(2, _mm256_mul_ps(a, b))
    }
    #[inline(always)]
    fn f32_div(self, a: Self::F32, b: Self::F32) -> Self::F32 {
        each!(2, _mm256_div_ps(a, b))
    }
    #[inline(always)]
    fn f32_neg(self, a: Self::F32) -> Self::F32 {
        let sign = self.f32_splat(-0.0);
        each!(2, _mm256_xor_ps(a, sign))
    }
    #[inline(always)]
    fn f32_sqrt(self, a: Self::F32) -> Self::F32 {
        each!(2, _mm256_sqrt_ps(a))
    }
    #[inline(always)]
    fn f32_abs(self, a: Self::F32) -> Self::F32 {
        let sign = self.f32_splat(-0.0);
        each!(2, _mm256_andnot_ps(sign, a))
    }
    #[inline(always)]
    fn f32_min(self, a: Self::F32, b: Self::F32) -> Self::F32 {
        each!(2, _mm256_min_ps(a, b))
    }
    #[inline(always)]
    fn f32_max(self, a: Self::F32, b: Self::F32) -> Self::F32 {
        each!(2, _mm256_max_ps(a, b))
    }
    #[inline(always)]
    fn f32_select(self, m: Mask16, a: Self::F32, b: Self::F32) -> Self::F32 {
        let m = each!(2, _mm256_castsi256_ps(mask32(m)));
        each!(2, _mm256_blendv_ps(b, a, m))
    }
    #[inline(always)]
    fn f32_copysign(self, magnitude: Self::F32, sign: Self::F32) -> Self::F32 {
        let bit = self.f32_splat(-0.0);
        let (s, m) = (
            each!(2, _mm256_and_ps(bit, sign)),
            each!(2, _mm256_andnot_ps(bit, magnitude)),
        );
        each!(2, _mm256_or_ps(s, m))
    }
    #[inline(always)]
    fn f32_cmp(self, a: Self::F32, b: Self::F32, c: Cmp) -> Mask16 {
        pack32(cmp_ps(a, b, c))
    }
    #[inline(always)]
    fn f32_to_bits(self, a: Self::F32) -> Self::U32 {
        each!(2, _mm256_castps_si256(a))
    }
    #[inline(always)]
    fn f32_from_bits(self, a: Self::U32) -> Self::F32 {
        each!(2, _mm256_castsi256_ps(a))
    }
    #[inline(always)]
    fn f32_from_u32(self, a: Self::U32) -> Self::F32 {
        // `hi · 2¹⁶ + lo` with both halves below 2¹⁶: the product and the
        // halves are exact in `f32`, so the sum rounds once, to nearest, as
        // a direct conversion does.
        let low = self.u32_splat(0xFFFF);
        let (hi, lo) = (
            each!(2, _mm256_cvtepi32_ps(self.u32_shr(a, 16))),
            each!(2, _mm256_cvtepi32_ps(self.u32_and(a, low))),
        );
        self.f32_add(self.f32_mul(hi, self.f32_splat(65536.0)), lo)
    }
    #[inline(always)]
    fn f32_trunc_i32(self, a: Self::F32) -> Self::U32 {
        each!(2, _mm256_cvttps_epi32(a))
    }
    #[inline(always)]
    fn f32_to_f64(self, a: Self::F32) -> Self::F64 {
        let q = avx!([
            _mm256_castps256_ps128(a[0]),
            _mm256_extractf128_ps::<1>(a[0]),
            _mm256_castps256_ps128(a[1]),
            _mm256_extractf128_ps::<1>(a[1]),
        ]);
        each!(4, _mm256_cvtps_pd(q))
    }
    #[inline(always)]
    fn f32_permute(self, a: Self::F32, index: Self::U32) -> Self::F32 {
        // Each output register picks from both input registers by the
        // index's low three bits, then by its bit 3 between the two.
        let eight = self.u32_splat(8);
        let high = each!(2, _mm256_cmpeq_epi32(self.u32_and(index, eight), eight));
        let from = |r: usize| each!(2, _mm256_permutevar8x32_ps([a[r], a[r]], index));
        let (lo, hi) = (from(0), from(1));
        let high = each!(2, _mm256_castsi256_ps(high));
        each!(2, _mm256_blendv_ps(lo, hi, high))
    }
    #[inline(always)]
    fn f32_reduce_min(self, a: Self::F32, m: Mask16) -> f32 {
        Portable.f32_reduce_min(self.f32_store(a), m)
    }
    #[inline(always)]
    unsafe fn f32_gather(
        self,
        table: &[f32],
        index: Self::U32,
        m: Mask16,
        fallback: Self::F32,
    ) -> Self::F32 {
        let m = each!(2, _mm256_castsi256_ps(mask32(m)));
        let base = [table.as_ptr(), table.as_ptr()];
        // Every lane read (those of `m`) indexes `table` in bounds (the
        // caller's contract).
        each!(2, _mm256_mask_i32gather_ps::<4>(fallback, base, index, m))
    }
    #[inline(always)]
    unsafe fn f32_expand(self, a: Self::F32, m: Mask16, src: &[f32]) -> Self::F32 {
        // SAFETY: the caller's contract is the portable method's.
        self.f32_load(unsafe { Portable.f32_expand(self.f32_store(a), m, src) })
    }

    #[inline(always)]
    fn f64_splat(self, x: f64) -> Self::F64 {
        let v = avx!(_mm256_set1_pd(x));
        [v; 4]
    }
    #[inline(always)]
    fn f64_load(self, lanes: [f64; LANES]) -> Self::F64 {
        // Each `loadu` reads four of the sixteen `f64` of `lanes`.
        std::array::from_fn(|q| avx!(_mm256_loadu_pd(lanes[4 * q..].as_ptr())))
    }
    #[inline(always)]
    fn f64_store(self, v: Self::F64) -> [f64; LANES] {
        let mut out = [0.0; LANES];
        for (q, v) in v.into_iter().enumerate() {
            // Writes four of the sixteen `f64` of `out`.
            avx!(_mm256_storeu_pd(out[4 * q..].as_mut_ptr(), v));
        }
        out
    }
    #[inline(always)]
    fn f64_add(self, a: Self::F64, b: Self::F64) -> Self::F64 {
        each!(4, _mm256_add_pd(a, b))
    }
    #[inline(always)]
    fn f64_sub(self, a: Self::F64, b: Self::F64) -> Self::F64 {
        each!(4, _mm256_sub_pd(a, b))
    }
    #[inline(always)]
    fn f64_mul(self, a: Self::F64, b: Self::F64) -> Self::F64 {
        each!(4, _mm256_mul_pd(a, b))
    }
    #[inline(always)]
    fn f64_div(self, a: Self::F64, b: Self::F64) -> Self::F64 {
        each!(4, _mm256_div_pd(a, b))
    }
    #[inline(always)]
    fn f64_neg(self, a: Self::F64) -> Self::F64 {
        let sign = self.f64_splat(-0.0);
        each!(4, _mm256_xor_pd(a, sign))
    }
    #[inline(always)]
    fn f64_sqrt(self, a: Self::F64) -> Self::F64 {
        each!(4, _mm256_sqrt_pd(a))
    }
    #[inline(always)]
    fn f64_abs(self, a: Self::F64) -> Self::F64 {
        let sign = self.f64_splat(-0.0);
        each!(4, _mm256_andnot_pd(sign, a))
    }
    #[inline(always)]
    fn f64_min(self, a: Self::F64, b: Self::F64) -> Self::F64 {
        each!(4, _mm256_min_pd(a, b))
    }
    #[inline(always)]
    fn f64_select(self, m: Mask16, a: Self::F64, b: Self::F64) -> Self::F64 {
        let m = each!(4, _mm256_castsi256_pd(mask64(m)));
        each!(4, _mm256_blendv_pd(b, a, m))
    }
    #[inline(always)]
    fn f64_copysign(self, magnitude: Self::F64, sign: Self::F64) -> Self::F64 {
        let bit = self.f64_splat(-0.0);
        let (s, m) = (
            each!(4, _mm256_and_pd(bit, sign)),
            each!(4, _mm256_andnot_pd(bit, magnitude)),
        );
        each!(4, _mm256_or_pd(s, m))
    }
    #[inline(always)]
    fn f64_cmp(self, a: Self::F64, b: Self::F64, c: Cmp) -> Mask16 {
        pack64(match c {
            Cmp::Lt => each!(4, _mm256_cmp_pd::<_CMP_LT_OQ>(a, b)),
            Cmp::Le => each!(4, _mm256_cmp_pd::<_CMP_LE_OQ>(a, b)),
            Cmp::Gt => each!(4, _mm256_cmp_pd::<_CMP_GT_OQ>(a, b)),
            Cmp::Ge => each!(4, _mm256_cmp_pd::<_CMP_GE_OQ>(a, b)),
            Cmp::Eq => each!(4, _mm256_cmp_pd::<_CMP_EQ_OQ>(a, b)),
        })
    }
    #[inline(always)]
    fn f64_to_f32(self, a: Self::F64) -> Self::F32 {
        let q = each!(4, _mm256_cvtpd_ps(a));
        avx!([_mm256_set_m128(q[1], q[0]), _mm256_set_m128(q[3], q[2])])
    }

    #[inline(always)]
    fn u32_splat(self, x: u32) -> Self::U32 {
        let v = avx!(_mm256_set1_epi32(x as i32));
        [v, v]
    }
    #[inline(always)]
    fn u32_load(self, lanes: [u32; LANES]) -> Self::U32 {
        // Each `loadu` reads eight of the sixteen `u32` of `lanes`.
        avx!([
            _mm256_loadu_si256(lanes.as_ptr().cast()),
            _mm256_loadu_si256(lanes[8..].as_ptr().cast()),
        ])
    }
    #[inline(always)]
    fn u32_store(self, v: Self::U32) -> [u32; LANES] {
        let mut out = [0; LANES];
        // Each `storeu` writes eight of the sixteen `u32` of `out`.
        avx!(_mm256_storeu_si256(out.as_mut_ptr().cast(), v[0]));
        avx!(_mm256_storeu_si256(out[8..].as_mut_ptr().cast(), v[1]));
        out
    }
    #[inline(always)]
    fn u32_add(self, a: Self::U32, b: Self::U32) -> Self::U32 {
        each!(2, _mm256_add_epi32(a, b))
    }
    #[inline(always)]
    fn u32_sub(self, a: Self::U32, b: Self::U32) -> Self::U32 {
        each!(2, _mm256_sub_epi32(a, b))
    }
    #[inline(always)]
    fn u32_mul(self, a: Self::U32, b: Self::U32) -> Self::U32 {
        each!(2, _mm256_mullo_epi32(a, b))
    }
    #[inline(always)]
    fn u32_and(self, a: Self::U32, b: Self::U32) -> Self::U32 {
        each!(2, _mm256_and_si256(a, b))
    }
    #[inline(always)]
    fn u32_or(self, a: Self::U32, b: Self::U32) -> Self::U32 {
        each!(2, _mm256_or_si256(a, b))
    }
    #[inline(always)]
    fn u32_xor(self, a: Self::U32, b: Self::U32) -> Self::U32 {
        each!(2, _mm256_xor_si256(a, b))
    }
    #[inline(always)]
    fn u32_shr(self, a: Self::U32, n: u32) -> Self::U32 {
        let n = self.u32_splat(n);
        each!(2, _mm256_srlv_epi32(a, n))
    }
    #[inline(always)]
    fn u32_shl(self, a: Self::U32, n: u32) -> Self::U32 {
        let n = self.u32_splat(n);
        each!(2, _mm256_sllv_epi32(a, n))
    }
    #[inline(always)]
    fn u32_shr_signed(self, a: Self::U32, n: u32) -> Self::U32 {
        let n = self.u32_splat(n);
        each!(2, _mm256_srav_epi32(a, n))
    }
    #[inline(always)]
    fn u32_select(self, m: Mask16, a: Self::U32, b: Self::U32) -> Self::U32 {
        let m = mask32(m);
        each!(2, _mm256_blendv_epi8(b, a, m))
    }
    #[inline(always)]
    fn u32_lt(self, a: Self::U32, b: Self::U32) -> Mask16 {
        // Unsigned order is the signed order with the sign bits flipped.
        let flip = self.u32_splat(1 << 31);
        let (a, b) = (self.u32_xor(a, flip), self.u32_xor(b, flip));
        let lt = each!(2, _mm256_cmpgt_epi32(b, a));
        pack32(each!(2, _mm256_castsi256_ps(lt)))
    }
    #[inline(always)]
    fn u32_eq(self, a: Self::U32, b: Self::U32) -> Mask16 {
        let eq = each!(2, _mm256_cmpeq_epi32(a, b));
        pack32(each!(2, _mm256_castsi256_ps(eq)))
    }
    #[inline(always)]
    unsafe fn u32_gather(
        self,
        table: &[u32],
        index: Self::U32,
        m: Mask16,
        fallback: Self::U32,
    ) -> Self::U32 {
        let m = mask32(m);
        let base: [*const i32; 2] = [table.as_ptr().cast(), table.as_ptr().cast()];
        // Every lane read (those of `m`) indexes `table` in bounds (the
        // caller's contract).
        each!(
            2,
            _mm256_mask_i32gather_epi32::<4>(fallback, base, index, m)
        )
    }

    #[inline(always)]
    fn u64_splat(self, x: u64) -> Self::U64 {
        let v = avx!(_mm256_set1_epi64x(x as i64));
        [v; 4]
    }
    #[inline(always)]
    fn u64_load(self, lanes: [u64; LANES]) -> Self::U64 {
        // Each `loadu` reads four of the sixteen `u64` of `lanes`.
        std::array::from_fn(|q| avx!(_mm256_loadu_si256(lanes[4 * q..].as_ptr().cast())))
    }
    #[inline(always)]
    fn u64_store(self, v: Self::U64) -> [u64; LANES] {
        let mut out = [0; LANES];
        for (q, v) in v.into_iter().enumerate() {
            // Writes four of the sixteen `u64` of `out`.
            avx!(_mm256_storeu_si256(out[4 * q..].as_mut_ptr().cast(), v));
        }
        out
    }
    #[inline(always)]
    fn u64_add(self, a: Self::U64, b: Self::U64) -> Self::U64 {
        each!(4, _mm256_add_epi64(a, b))
    }
    #[inline(always)]
    fn u64_mul(self, a: Self::U64, b: Self::U64) -> Self::U64 {
        // a·b mod 2⁶⁴ = lo(a)·lo(b) + (hi(a)·lo(b) + lo(a)·hi(b)) · 2³².
        let (a_hi, b_hi) = (
            each!(4, _mm256_srli_epi64::<32>(a)),
            each!(4, _mm256_srli_epi64::<32>(b)),
        );
        let low = each!(4, _mm256_mul_epu32(a, b));
        let cross = self.u64_add(
            each!(4, _mm256_mul_epu32(a_hi, b)),
            each!(4, _mm256_mul_epu32(a, b_hi)),
        );
        self.u64_add(low, each!(4, _mm256_slli_epi64::<32>(cross)))
    }
    #[inline(always)]
    fn u64_xor(self, a: Self::U64, b: Self::U64) -> Self::U64 {
        each!(4, _mm256_xor_si256(a, b))
    }
    #[inline(always)]
    fn u64_shr(self, a: Self::U64, n: u32) -> Self::U64 {
        let n = avx!(_mm256_set1_epi64x(i64::from(n)));
        each!(4, _mm256_srlv_epi64(a, [n; 4]))
    }
    #[inline(always)]
    fn u64_from_u32(self, a: Self::U32) -> Self::U64 {
        each!(4, _mm256_cvtepu32_epi64(quarters(a)))
    }
    #[inline(always)]
    fn u64_low_u32(self, a: Self::U64) -> Self::U32 {
        // The even 32-bit words of each register into its low half.
        let even = avx!(_mm256_setr_epi32(0, 2, 4, 6, 0, 2, 4, 6));
        let q = each!(4, _mm256_permutevar8x32_epi32(a, [even; 4]));
        let q = each!(4, _mm256_castsi256_si128(q));
        avx!([_mm256_set_m128i(q[1], q[0]), _mm256_set_m128i(q[3], q[2])])
    }
    #[inline(always)]
    unsafe fn u64_gather(
        self,
        table: &[u64],
        index: Self::U32,
        m: Mask16,
        fallback: Self::U64,
    ) -> Self::U64 {
        let (m, index) = (mask64(m), quarters(index));
        let base: [*const i64; 4] = [table.as_ptr().cast(); 4];
        // Every lane read (those of `m`) indexes `table` in bounds (the
        // caller's contract).
        each!(
            4,
            _mm256_mask_i32gather_epi64::<8>(fallback, base, index, m)
        )
    }
    #[inline(always)]
    unsafe fn u64_expand(self, a: Self::U64, m: Mask16, src: &[u64]) -> Self::U64 {
        // SAFETY: the caller's contract is the portable method's.
        self.u64_load(unsafe { Portable.u64_expand(self.u64_store(a), m, src) })
    }
}
