//! The avx2 backend's `f32` lanes.

use super::*;
use crate::simd::{F32Ops, U32Ops};

impl F32Ops for Avx2 {
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
        // index's low three bits, then by its bit 3 (shifted to the sign
        // bit, which `blendv` reads) between the two.
        let lo = avx!([
            _mm256_permutevar8x32_ps(a[0], index[0]),
            _mm256_permutevar8x32_ps(a[0], index[1]),
        ]);
        let hi = avx!([
            _mm256_permutevar8x32_ps(a[1], index[0]),
            _mm256_permutevar8x32_ps(a[1], index[1]),
        ]);
        let high = each!(2, _mm256_slli_epi32::<28>(index));
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
        // Each half loads its lanes' values (the first of `src` for lanes
        // 0–7, the next for lanes 8–15) and spreads them over its lanes.
        let take = [u32::from(m.0 & 0xFF), u32::from(m.0 >> 8)];
        let from = [0, take[0].count_ones() as usize];
        let set = mask32(m);
        let mut out = a;
        for h in 0..2 {
            let n = take[h].count_ones();
            // SAFETY: the CPU has AVX2 (the token, macro `avx`); the masked load reads `src[from[h] + j]` for `j < n`
            // only (masked-off lanes are not accessed and do not fault):
            // `from[h] + n ≤ m.count() ≤ src.len()` by the caller's
            // contract, so the pointer (at most one past the end) and every
            // read are in bounds.
            let values = unsafe { _mm256_maskload_ps(src.as_ptr().add(from[h]), first32(n)) };
            let spread = avx!(_mm256_permutevar8x32_ps(
                values,
                byte_lanes(EXPAND32[take[h] as usize])
            ));
            out[h] = avx!(_mm256_blendv_ps(a[h], spread, _mm256_castsi256_ps(set[h])));
        }
        out
    }
}
