//! A [`Block`]'s eight numbers with AVX2: the same integer hashes and `f32`
//! operations as the scalar
//! [`PixelSampler::get_1d`](super::PixelSampler::get_1d), eight dimensions
//! per instruction, so the numbers are bit-identical (the sampler's tests
//! compare the two).

use std::arch::x86_64::{
    __m256, __m256i, _mm_cvtsi32_si128, _mm256_add_epi64, _mm256_add_ps, _mm256_and_si256,
    _mm256_blend_epi32, _mm256_castsi256_ps, _mm256_cmpgt_epi32, _mm256_cvtepi32_ps,
    _mm256_loadu_si256, _mm256_min_ps, _mm256_movemask_ps, _mm256_mul_epu32, _mm256_mul_ps,
    _mm256_mullo_epi32, _mm256_set1_epi32, _mm256_set1_epi64x, _mm256_set1_ps, _mm256_setr_epi64x,
    _mm256_slli_epi64, _mm256_srl_epi32, _mm256_srli_epi32, _mm256_srli_epi64, _mm256_storeu_ps,
    _mm256_storeu_si256, _mm256_xor_si256,
};

use super::{
    BLOCK, Block, GOLDEN, MIX_WEYL, ONE_MINUS_EPSILON, PERMUTE_MUL, PixelKeys, STRATIFIED, UNIT,
};

/// The numbers of the unstratified dimensions `first .. first + BLOCK`
/// (`first ≥ STRATIFIED`) whose first Weyl step is `weyl_first`. Small, so
/// that it inlines into the AVX2 tile loop.
#[target_feature(enable = "avx2")]
#[inline]
pub(super) fn unstratified(weyl_first: u64) -> Block {
    store(jitters(weyl_first))
}

/// The largest stratum count [`stratified`] takes: its strata and their
/// permutations' masks stay below `2^31`, as signed 32-bit lanes.
pub(super) const MAX_COUNT: u32 = 1 << 30;

/// The numbers of the stratified dimensions `first .. first + BLOCK`
/// (`first + BLOCK ≤ STRATIFIED`) of the sample with index `sample` and
/// first Weyl step `weyl_first` under `keys` (`keys.count ≤ MAX_COUNT`).
#[target_feature(enable = "avx2")]
pub(super) fn stratified(keys: &PixelKeys, sample: u32, first: usize, weyl_first: u64) -> Block {
    let strata = strata(keys, sample, first);
    let count = _mm256_set1_ps(keys.inv_count);
    let x = _mm256_mul_ps(
        _mm256_add_ps(_mm256_cvtepi32_ps(strata), jitters(weyl_first)),
        count,
    );
    store(_mm256_min_ps(x, _mm256_set1_ps(ONE_MINUS_EPSILON)))
}

/// A block of the eight numbers in `x`.
#[target_feature(enable = "avx2")]
#[inline]
#[allow(unsafe_code)]
fn store(x: __m256) -> Block {
    let mut numbers = [0.0f32; BLOCK];
    // SAFETY: `numbers` holds eight `f32`s, the 32 bytes an unaligned store
    // writes.
    unsafe { _mm256_storeu_ps(numbers.as_mut_ptr(), x) };
    Block { numbers }
}

/// `to_unit(mix_weyl(x + k·φ))` for `k < 8`. Lanes hold the Weyl steps of
/// the even and the odd `k` as 64-bit numbers; `mix_weyl`'s 64-bit product
/// is `lo(y)·lo(c) + (lo(y)·hi(c) + hi(y)·lo(c))·2^32` (mod 2^64), whose
/// high half lands in each odd 32-bit lane, so one blend interleaves the
/// eight results in order.
#[target_feature(enable = "avx2")]
#[inline]
fn jitters(x: u64) -> __m256 {
    let step = |k: u64| GOLDEN.wrapping_mul(k) as i64;
    let base = _mm256_set1_epi64x(x as i64);
    let even = _mm256_add_epi64(base, _mm256_setr_epi64x(0, step(2), step(4), step(6)));
    let odd = _mm256_add_epi64(base, _mm256_setr_epi64x(step(1), step(3), step(5), step(7)));
    let c_lo = _mm256_set1_epi64x((MIX_WEYL & 0xFFFF_FFFF) as i64);
    let c_hi = _mm256_set1_epi64x((MIX_WEYL >> 32) as i64);
    let high_half = |x: __m256i| {
        let y = _mm256_xor_si256(x, _mm256_srli_epi64::<32>(x));
        let cross = _mm256_add_epi64(
            _mm256_mul_epu32(y, c_hi),
            _mm256_mul_epu32(_mm256_srli_epi64::<32>(y), c_lo),
        );
        _mm256_add_epi64(_mm256_mul_epu32(y, c_lo), _mm256_slli_epi64::<32>(cross))
    };
    let bits =
        _mm256_blend_epi32::<0b1010_1010>(_mm256_srli_epi64::<32>(high_half(even)), high_half(odd));
    let unit = _mm256_cvtepi32_ps(_mm256_srli_epi32::<8>(bits));
    _mm256_mul_ps(unit, _mm256_set1_ps(UNIT))
}

/// The strata of sample `sample` in stratified dimensions `first ..
/// first + 8` (`first + 8 ≤ STRATIFIED`): [`PixelKeys::stratum`] eight
/// dimensions at a time, cycle-walking the lanes that land past `count`
/// one by one.
#[target_feature(enable = "avx2")]
#[inline]
#[allow(unsafe_code)]
fn strata(keys: &PixelKeys, sample: u32, first: usize) -> __m256i {
    let load = |row: &[u32; STRATIFIED]| {
        let lanes: &[u32; BLOCK] = row[first..first + BLOCK]
            .try_into()
            .expect("first + BLOCK ≤ STRATIFIED");
        // SAFETY: `lanes` holds eight `u32`s, the 32 bytes an unaligned
        // load reads.
        unsafe { _mm256_loadu_si256(lanes.as_ptr().cast()) }
    };
    let mask = _mm256_set1_epi32(keys.mask as i32);
    let [r0, r1, r2] = keys.shifts.map(|r| _mm_cvtsi32_si128(r as i32));
    let mut i = _mm256_set1_epi32(sample as i32);
    let round = |i: __m256i, xor: __m256i, mul: __m256i, shift| {
        let i = _mm256_and_si256(_mm256_mullo_epi32(_mm256_xor_si256(i, xor), mul), mask);
        _mm256_xor_si256(i, _mm256_srl_epi32(i, shift))
    };
    i = round(i, load(&keys.xor[0]), load(&keys.mul[0]), r0);
    i = round(i, load(&keys.xor[1]), load(&keys.mul[1]), r1);
    i = round(
        i,
        load(&keys.xor[2]),
        _mm256_set1_epi32(PERMUTE_MUL as i32),
        r2,
    );
    // With `count ≤ MAX_COUNT`, `mask < 2^31`: the signed compare is exact.
    let past = _mm256_cmpgt_epi32(i, _mm256_set1_epi32(keys.count as i32 - 1));
    if _mm256_movemask_ps(_mm256_castsi256_ps(past)) == 0 {
        return i;
    }
    let mut lanes = [0u32; BLOCK];
    // SAFETY: `lanes` holds eight `u32`s, the 32 bytes an unaligned store
    // writes.
    unsafe { _mm256_storeu_si256(lanes.as_mut_ptr().cast(), i) };
    for (k, s) in lanes.iter_mut().enumerate() {
        *s = keys.walk_into_range(*s, first + k);
    }
    // SAFETY: as the store above.
    unsafe { _mm256_loadu_si256(lanes.as_ptr().cast()) }
}
