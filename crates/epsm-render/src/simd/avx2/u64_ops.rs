//! The avx2 backend's `u64` lanes.

use super::*;
use crate::simd::U64Ops;

impl U64Ops for Avx2 {
    #[inline(always)]
    fn u64_splat(self, x: u64) -> Self::U64 {
        let v = avx!(_mm256_set1_epi64x(x as i64));
        [v; 4]
    }
    #[cfg(test)]
    #[inline(always)]
    fn u64_load(self, lanes: [u64; LANES]) -> Self::U64 {
        // Each `loadu` reads four of the sixteen `u64` of `lanes`.
        avx!([
            _mm256_loadu_si256(lanes.as_ptr().cast()),
            _mm256_loadu_si256(lanes[4..].as_ptr().cast()),
            _mm256_loadu_si256(lanes[8..].as_ptr().cast()),
            _mm256_loadu_si256(lanes[12..].as_ptr().cast()),
        ])
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
        // Each quarter loads its lanes' values (from past those of the
        // quarters before it) and spreads them over its lanes: 64-bit lane
        // `r` is 32-bit lanes `2r` and `2r + 1`.
        let set = mask64(m);
        let mut out = a;
        let mut from = 0usize;
        for q in 0..4 {
            let take = u32::from(m.0 >> (4 * q) & 0xF);
            let n = take.count_ones();
            let index = byte_lanes(EXPAND64[take as usize]);
            let first = avx!(_mm256_cmpgt_epi64(
                _mm256_set1_epi64x(i64::from(n)),
                _mm256_setr_epi64x(0, 1, 2, 3)
            ));
            // SAFETY: the CPU has AVX2 (the token, macro `avx`); the masked load reads `src[from + j]` for `j < n`
            // only (masked-off lanes are not accessed and do not fault):
            // `from + n ≤ m.count() ≤ src.len()` by the caller's contract,
            // so the pointer (at most one past the end) and every read are
            // in bounds.
            let values = unsafe { _mm256_maskload_epi64(src.as_ptr().add(from).cast(), first) };
            let spread = avx!(_mm256_permutevar8x32_epi32(values, index));
            let blend = avx!(_mm256_blendv_pd(
                _mm256_castsi256_pd(a[q]),
                _mm256_castsi256_pd(spread),
                _mm256_castsi256_pd(set[q])
            ));
            out[q] = avx!(_mm256_castpd_si256(blend));
            from += n as usize;
        }
        out
    }
}
