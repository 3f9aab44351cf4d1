//! The AVX-512 backend: sixteen `f32` or `u32` lanes in one 512-bit
//! register, sixteen `f64` or `u64` lanes in two (lanes 0–7, 8–15).

#![allow(unsafe_code)]

use std::arch::x86_64::*;

use super::{Cmp, LANES, Lanes, Mask16};

/// Runs an AVX-512 intrinsic expression.
///
/// SAFETY (every use): the expression calls AVX-512 F/VL/DQ/BW intrinsics
/// (and the AVX2 ones they imply) inside a method of [`Avx512`], whose
/// `self` exists only after [`Avx512::detect`] found those features;
/// pointer arguments, where an intrinsic takes one, are stated at the use.
macro_rules! avx {
    ($e:expr) => {
        // SAFETY: see the macro's documentation.
        unsafe { $e }
    };
}

/// Proof that the CPU has AVX-512 F, VL, DQ and BW, and with them AVX2,
/// BMI1, BMI2, LZCNT and POPCNT: code compiled with
/// `#[target_feature(enable = "avx512f,avx512vl,avx512dq,avx512bw,avx2,bmi1,bmi2,lzcnt,popcnt")]`
/// may run while one is held ([`Lanes::run`]).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Avx512(());

impl Avx512 {
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

/// `$f` applied to both registers of a two-register value (`f64`, `u64`).
macro_rules! both {
    ($f:ident $(::<$g:tt>)? ($($a:expr),*)) => {
        [avx!($f$(::<$g>)?($($a[0]),*)), avx!($f$(::<$g>)?($($a[1]),*))]
    };
}

/// The mask's low and high byte: the lanes of the first and the second
/// register of a two-register value.
#[inline(always)]
fn halves(m: Mask16) -> [u8; 2] {
    [m.0 as u8, (m.0 >> 8) as u8]
}

impl Lanes for Avx512 {
    type F32 = __m512;
    type F64 = [__m512d; 2];
    type U32 = __m512i;
    type U64 = [__m512i; 2];
    type Boxes = crate::bvh::Avx;

    #[inline(always)]
    fn boxes(self) -> Self::Boxes {
        crate::bvh::Avx::from_avx512(self)
    }

    #[inline(always)]
    fn run<R>(self, f: impl FnOnce() -> R) -> R {
        #[target_feature(enable = "avx512f,avx512vl,avx512dq,avx512bw,avx2,bmi1,bmi2,lzcnt,popcnt")]
        fn run<R>(f: impl FnOnce() -> R) -> R {
            f()
        }
        // SAFETY: `run` requires only the features it enables, and `self`
        // exists only on a CPU found to have each of them.
        unsafe { run(f) }
    }

    #[inline(always)]
    fn f32_splat(self, x: f32) -> Self::F32 {
        avx!(_mm512_set1_ps(x))
    }
    #[inline(always)]
    fn f32_load(self, lanes: [f32; LANES]) -> Self::F32 {
        // `loadu` reads the sixteen `f32` of `lanes` (unaligned is allowed).
        avx!(_mm512_loadu_ps(lanes.as_ptr()))
    }
    #[inline(always)]
    fn f32_store(self, v: Self::F32) -> [f32; LANES] {
        let mut out = [0.0; LANES];
        // `storeu` writes the sixteen `f32` of `out`.
        avx!(_mm512_storeu_ps(out.as_mut_ptr(), v));
        out
    }
    #[inline(always)]
    fn f32_add(self, a: Self::F32, b: Self::F32) -> Self::F32 {
        avx!(_mm512_add_ps(a, b))
    }
    #[inline(always)]
    fn f32_sub(self, a: Self::F32, b: Self::F32) -> Self::F32 {
        avx!(_mm512_sub_ps(a, b))
    }
    #[inline(always)]
    fn f32_mul(self, a: Self::F32, b: Self::F32) -> Self::F32 {
        avx!(_mm512_mul_ps(a, b))
    }
    #[inline(always)]
    fn f32_div(self, a: Self::F32, b: Self::F32) -> Self::F32 {
        avx!(_mm512_div_ps(a, b))
    }
    #[inline(always)]
    fn f32_neg(self, a: Self::F32) -> Self::F32 {
        avx!(_mm512_xor_ps(a, _mm512_set1_ps(-0.0)))
    }
    #[inline(always)]
    fn f32_sqrt(self, a: Self::F32) -> Self::F32 {
        avx!(_mm512_sqrt_ps(a))
    }
    #[inline(always)]
    fn f32_abs(self, a: Self::F32) -> Self::F32 {
        avx!(_mm512_abs_ps(a))
    }
    #[inline(always)]
    fn f32_min(self, a: Self::F32, b: Self::F32) -> Self::F32 {
        avx!(_mm512_min_ps(a, b))
    }
    #[inline(always)]
    fn f32_max(self, a: Self::F32, b: Self::F32) -> Self::F32 {
        avx!(_mm512_max_ps(a, b))
    }
    #[inline(always)]
    fn f32_select(self, m: Mask16, a: Self::F32, b: Self::F32) -> Self::F32 {
        avx!(_mm512_mask_blend_ps(m.0, b, a))
    }
    #[inline(always)]
    fn f32_copysign(self, magnitude: Self::F32, sign: Self::F32) -> Self::F32 {
        // Ternary logic 0xCA (`a ? b : c` bitwise): bits of `sign` where the
        // sign mask is set, of `magnitude` elsewhere.
        avx!(_mm512_castsi512_ps(_mm512_ternarylogic_epi32::<0xCA>(
            _mm512_castps_si512(_mm512_set1_ps(-0.0)),
            _mm512_castps_si512(sign),
            _mm512_castps_si512(magnitude),
        )))
    }
    #[inline(always)]
    fn f32_cmp(self, a: Self::F32, b: Self::F32, c: Cmp) -> Mask16 {
        Mask16(match c {
            Cmp::Lt => avx!(_mm512_cmp_ps_mask::<_CMP_LT_OQ>(a, b)),
            Cmp::Le => avx!(_mm512_cmp_ps_mask::<_CMP_LE_OQ>(a, b)),
            Cmp::Gt => avx!(_mm512_cmp_ps_mask::<_CMP_GT_OQ>(a, b)),
            Cmp::Ge => avx!(_mm512_cmp_ps_mask::<_CMP_GE_OQ>(a, b)),
            Cmp::Eq => avx!(_mm512_cmp_ps_mask::<_CMP_EQ_OQ>(a, b)),
        })
    }
    #[inline(always)]
    fn f32_to_bits(self, a: Self::F32) -> Self::U32 {
        avx!(_mm512_castps_si512(a))
    }
    #[inline(always)]
    fn f32_from_bits(self, a: Self::U32) -> Self::F32 {
        avx!(_mm512_castsi512_ps(a))
    }
    #[inline(always)]
    fn f32_from_u32(self, a: Self::U32) -> Self::F32 {
        avx!(_mm512_cvtepu32_ps(a))
    }
    #[inline(always)]
    fn f32_trunc_i32(self, a: Self::F32) -> Self::U32 {
        avx!(_mm512_cvttps_epi32(a))
    }
    #[inline(always)]
    fn f32_to_f64(self, a: Self::F32) -> Self::F64 {
        avx!([
            _mm512_cvtps_pd(_mm512_castps512_ps256(a)),
            _mm512_cvtps_pd(_mm256_castpd_ps(_mm512_extractf64x4_pd::<1>(
                _mm512_castps_pd(a)
            ))),
        ])
    }
    #[inline(always)]
    fn f32_permute(self, a: Self::F32, index: Self::U32) -> Self::F32 {
        avx!(_mm512_permutexvar_ps(index, a))
    }
    #[inline(always)]
    fn f32_reduce_min(self, a: Self::F32, m: Mask16) -> f32 {
        avx!(_mm512_mask_reduce_min_ps(m.0, a))
    }
    #[inline(always)]
    unsafe fn f32_gather(
        self,
        table: &[f32],
        index: Self::U32,
        m: Mask16,
        fallback: Self::F32,
    ) -> Self::F32 {
        // Every lane read (those of `m`) indexes `table` in bounds (the
        // caller's contract).
        avx!(_mm512_mask_i32gather_ps::<4>(
            fallback,
            m.0,
            index,
            table.as_ptr()
        ))
    }
    #[inline(always)]
    unsafe fn f32_expand(self, a: Self::F32, m: Mask16, src: &[f32]) -> Self::F32 {
        // Reads `m.count()` consecutive `f32`s from `src`, in bounds (the
        // caller's contract).
        avx!(_mm512_mask_expandloadu_ps(a, m.0, src.as_ptr()))
    }

    #[inline(always)]
    fn f64_splat(self, x: f64) -> Self::F64 {
        let v = avx!(_mm512_set1_pd(x));
        [v, v]
    }
    #[inline(always)]
    fn f64_load(self, lanes: [f64; LANES]) -> Self::F64 {
        // Each `loadu` reads eight of the sixteen `f64` of `lanes`.
        [
            avx!(_mm512_loadu_pd(lanes.as_ptr())),
            avx!(_mm512_loadu_pd(lanes[8..].as_ptr())),
        ]
    }
    #[inline(always)]
    fn f64_store(self, v: Self::F64) -> [f64; LANES] {
        let mut out = [0.0; LANES];
        // Each `storeu` writes eight of the sixteen `f64` of `out`.
        avx!(_mm512_storeu_pd(out.as_mut_ptr(), v[0]));
        avx!(_mm512_storeu_pd(out[8..].as_mut_ptr(), v[1]));
        out
    }
    #[inline(always)]
    fn f64_add(self, a: Self::F64, b: Self::F64) -> Self::F64 {
        both!(_mm512_add_pd(a, b))
    }
    #[inline(always)]
    fn f64_sub(self, a: Self::F64, b: Self::F64) -> Self::F64 {
        both!(_mm512_sub_pd(a, b))
    }
    #[inline(always)]
    fn f64_mul(self, a: Self::F64, b: Self::F64) -> Self::F64 {
        both!(_mm512_mul_pd(a, b))
    }
    #[inline(always)]
    fn f64_div(self, a: Self::F64, b: Self::F64) -> Self::F64 {
        both!(_mm512_div_pd(a, b))
    }
    #[inline(always)]
    fn f64_neg(self, a: Self::F64) -> Self::F64 {
        let sign = avx!(_mm512_set1_pd(-0.0));
        both!(_mm512_xor_pd(a, [sign, sign]))
    }
    #[inline(always)]
    fn f64_sqrt(self, a: Self::F64) -> Self::F64 {
        both!(_mm512_sqrt_pd(a))
    }
    #[inline(always)]
    fn f64_abs(self, a: Self::F64) -> Self::F64 {
        both!(_mm512_abs_pd(a))
    }
    #[inline(always)]
    fn f64_min(self, a: Self::F64, b: Self::F64) -> Self::F64 {
        both!(_mm512_min_pd(a, b))
    }
    #[inline(always)]
    fn f64_select(self, m: Mask16, a: Self::F64, b: Self::F64) -> Self::F64 {
        both!(_mm512_mask_blend_pd(halves(m), b, a))
    }
    #[inline(always)]
    fn f64_copysign(self, magnitude: Self::F64, sign: Self::F64) -> Self::F64 {
        // Ternary logic 0xCA (`a ? b : c` bitwise): bits of `sign` where the
        // sign mask is set, of `magnitude` elsewhere.
        let mask = avx!(_mm512_castpd_si512(_mm512_set1_pd(-0.0)));
        let half = |m: __m512d, s: __m512d| {
            avx!(_mm512_castsi512_pd(_mm512_ternarylogic_epi64::<0xCA>(
                mask,
                _mm512_castpd_si512(s),
                _mm512_castpd_si512(m),
            )))
        };
        [half(magnitude[0], sign[0]), half(magnitude[1], sign[1])]
    }
    #[inline(always)]
    fn f64_cmp(self, a: Self::F64, b: Self::F64, c: Cmp) -> Mask16 {
        let [lo, hi] = match c {
            Cmp::Lt => both!(_mm512_cmp_pd_mask::<_CMP_LT_OQ>(a, b)),
            Cmp::Le => both!(_mm512_cmp_pd_mask::<_CMP_LE_OQ>(a, b)),
            Cmp::Gt => both!(_mm512_cmp_pd_mask::<_CMP_GT_OQ>(a, b)),
            Cmp::Ge => both!(_mm512_cmp_pd_mask::<_CMP_GE_OQ>(a, b)),
            Cmp::Eq => both!(_mm512_cmp_pd_mask::<_CMP_EQ_OQ>(a, b)),
        };
        Mask16(u16::from(lo) | u16::from(hi) << 8)
    }
    #[inline(always)]
    fn f64_to_f32(self, a: Self::F64) -> Self::F32 {
        let [lo, hi] = both!(_mm512_cvtpd_ps(a));
        avx!(_mm512_insertf32x8::<1>(_mm512_castps256_ps512(lo), hi))
    }

    #[inline(always)]
    fn u32_splat(self, x: u32) -> Self::U32 {
        avx!(_mm512_set1_epi32(x as i32))
    }
    #[inline(always)]
    fn u32_load(self, lanes: [u32; LANES]) -> Self::U32 {
        // `loadu` reads the sixteen `u32` of `lanes`.
        avx!(_mm512_loadu_si512(lanes.as_ptr().cast()))
    }
    #[inline(always)]
    fn u32_store(self, v: Self::U32) -> [u32; LANES] {
        let mut out = [0; LANES];
        // `storeu` writes the sixteen `u32` of `out`.
        avx!(_mm512_storeu_si512(out.as_mut_ptr().cast(), v));
        out
    }
    #[inline(always)]
    fn u32_add(self, a: Self::U32, b: Self::U32) -> Self::U32 {
        avx!(_mm512_add_epi32(a, b))
    }
    #[inline(always)]
    fn u32_sub(self, a: Self::U32, b: Self::U32) -> Self::U32 {
        avx!(_mm512_sub_epi32(a, b))
    }
    #[inline(always)]
    fn u32_mul(self, a: Self::U32, b: Self::U32) -> Self::U32 {
        avx!(_mm512_mullo_epi32(a, b))
    }
    #[inline(always)]
    fn u32_and(self, a: Self::U32, b: Self::U32) -> Self::U32 {
        avx!(_mm512_and_si512(a, b))
    }
    #[inline(always)]
    fn u32_or(self, a: Self::U32, b: Self::U32) -> Self::U32 {
        avx!(_mm512_or_si512(a, b))
    }
    #[inline(always)]
    fn u32_xor(self, a: Self::U32, b: Self::U32) -> Self::U32 {
        avx!(_mm512_xor_si512(a, b))
    }
    #[inline(always)]
    fn u32_shr(self, a: Self::U32, n: u32) -> Self::U32 {
        avx!(_mm512_srlv_epi32(a, _mm512_set1_epi32(n as i32)))
    }
    #[inline(always)]
    fn u32_shl(self, a: Self::U32, n: u32) -> Self::U32 {
        avx!(_mm512_sllv_epi32(a, _mm512_set1_epi32(n as i32)))
    }
    #[inline(always)]
    fn u32_shr_signed(self, a: Self::U32, n: u32) -> Self::U32 {
        avx!(_mm512_srav_epi32(a, _mm512_set1_epi32(n as i32)))
    }
    #[inline(always)]
    fn u32_select(self, m: Mask16, a: Self::U32, b: Self::U32) -> Self::U32 {
        avx!(_mm512_mask_blend_epi32(m.0, b, a))
    }
    #[inline(always)]
    fn u32_lt(self, a: Self::U32, b: Self::U32) -> Mask16 {
        Mask16(avx!(_mm512_cmplt_epu32_mask(a, b)))
    }
    #[inline(always)]
    fn u32_eq(self, a: Self::U32, b: Self::U32) -> Mask16 {
        Mask16(avx!(_mm512_cmpeq_epu32_mask(a, b)))
    }
    #[inline(always)]
    unsafe fn u32_gather(
        self,
        table: &[u32],
        index: Self::U32,
        m: Mask16,
        fallback: Self::U32,
    ) -> Self::U32 {
        // Every lane read (those of `m`) indexes `table` in bounds (the
        // caller's contract).
        avx!(_mm512_mask_i32gather_epi32::<4>(
            fallback,
            m.0,
            index,
            table.as_ptr().cast()
        ))
    }

    #[inline(always)]
    fn u64_splat(self, x: u64) -> Self::U64 {
        let v = avx!(_mm512_set1_epi64(x as i64));
        [v, v]
    }
    #[inline(always)]
    fn u64_load(self, lanes: [u64; LANES]) -> Self::U64 {
        // Each `loadu` reads eight of the sixteen `u64` of `lanes`.
        [
            avx!(_mm512_loadu_si512(lanes.as_ptr().cast())),
            avx!(_mm512_loadu_si512(lanes[8..].as_ptr().cast())),
        ]
    }
    #[inline(always)]
    fn u64_store(self, v: Self::U64) -> [u64; LANES] {
        let mut out = [0; LANES];
        // Each `storeu` writes eight of the sixteen `u64` of `out`.
        avx!(_mm512_storeu_si512(out.as_mut_ptr().cast(), v[0]));
        avx!(_mm512_storeu_si512(out[8..].as_mut_ptr().cast(), v[1]));
        out
    }
    #[inline(always)]
    fn u64_add(self, a: Self::U64, b: Self::U64) -> Self::U64 {
        both!(_mm512_add_epi64(a, b))
    }
    #[inline(always)]
    fn u64_mul(self, a: Self::U64, b: Self::U64) -> Self::U64 {
        both!(_mm512_mullo_epi64(a, b))
    }
    #[inline(always)]
    fn u64_xor(self, a: Self::U64, b: Self::U64) -> Self::U64 {
        both!(_mm512_xor_si512(a, b))
    }
    #[inline(always)]
    fn u64_shr(self, a: Self::U64, n: u32) -> Self::U64 {
        let n = avx!(_mm512_set1_epi64(i64::from(n)));
        both!(_mm512_srlv_epi64(a, [n, n]))
    }
    #[inline(always)]
    fn u64_from_u32(self, a: Self::U32) -> Self::U64 {
        [
            avx!(_mm512_cvtepu32_epi64(_mm512_castsi512_si256(a))),
            avx!(_mm512_cvtepu32_epi64(_mm512_extracti64x4_epi64::<1>(a))),
        ]
    }
    #[inline(always)]
    fn u64_low_u32(self, a: Self::U64) -> Self::U32 {
        let [lo, hi] = both!(_mm512_cvtepi64_epi32(a));
        avx!(_mm512_inserti64x4::<1>(_mm512_castsi256_si512(lo), hi))
    }
    #[inline(always)]
    unsafe fn u64_gather(
        self,
        table: &[u64],
        index: Self::U32,
        m: Mask16,
        fallback: Self::U64,
    ) -> Self::U64 {
        let [lo, hi] = halves(m);
        // Every lane read (those of `m`) indexes `table` in bounds (the
        // caller's contract).
        [
            avx!(_mm512_mask_i32gather_epi64::<8>(
                fallback[0],
                lo,
                _mm512_castsi512_si256(index),
                table.as_ptr().cast()
            )),
            avx!(_mm512_mask_i32gather_epi64::<8>(
                fallback[1],
                hi,
                _mm512_extracti64x4_epi64::<1>(index),
                table.as_ptr().cast()
            )),
        ]
    }
    #[inline(always)]
    unsafe fn u64_expand(self, a: Self::U64, m: Mask16, src: &[u64]) -> Self::U64 {
        let [lo, hi] = halves(m);
        let rest = &src[lo.count_ones() as usize..];
        // Each load reads as many consecutive `u64`s as its half of `m` has
        // lanes: `src` from 0, then from the first half's count, both in
        // bounds (the caller's contract).
        [
            avx!(_mm512_mask_expandloadu_epi64(a[0], lo, src.as_ptr().cast())),
            avx!(_mm512_mask_expandloadu_epi64(
                a[1],
                hi,
                rest.as_ptr().cast()
            )),
        ]
    }
}
