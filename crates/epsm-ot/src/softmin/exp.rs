//! The exponential of the soft-min rows: a branch-free polynomial for
//! non-positive arguments, so loops over it vectorise.

/// `exp(x)` for `x ≤ 0` (including `−∞`), relative error below 5e-6 (it grows with |x| through the rounding of `x log2 e`), zero below −87.
///
/// Cody–Waite style: `2^t` with `t = x log2 e` split into the nearest integer
/// `n` (by the 1.5·2²³ rounding trick, so no `floor` call is needed) and a
/// fraction in `[−½, ½]` handled by Cephes' `exp2f` polynomial; `2^n` is built
/// in the exponent bits. Every step is branch-free so loops over it vectorise.
#[inline(always)]
pub(crate) fn exp_nonpositive(x: f32) -> f32 {
    const MAGIC: f32 = 12_582_912.0;
    let underflow = x < -87.0;
    let t = if underflow { -87.0 } else { x } * std::f32::consts::LOG2_E;
    let r = t + MAGIC;
    let n = r - MAGIC;
    let f = t - n;
    let p = 1.535_336_2e-4_f32;
    let p = p * f + 1.339_887_4e-3;
    let p = p * f + 9.618_437e-3;
    let p = p * f + 5.550_332_5e-2;
    let p = p * f + 2.402_264_8e-1;
    let p = p * f + 6.931_472e-1;
    let p = p * f + 1.0;
    let scale = f32::from_bits(r.to_bits().wrapping_add(127) << 23);
    if underflow { 0.0 } else { p * scale }
}
