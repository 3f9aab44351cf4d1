//! Which vector instructions the running CPU has, for the bodies compiled
//! three times (plain x86-64, AVX2 + FMA, AVX-512): the soft-min rows
//! ([`crate::softmin`]) and the per-point block cut
//! ([`crate::clusters::PointCut`]).

/// The widest instruction set the running CPU supports among those our SIMD bodies are compiled for.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Simd {
    /// AVX-512 F, BW, DQ and VL (16 `f32` lanes).
    Avx512,
    /// AVX2 and FMA (8 `f32` lanes).
    Avx2,
    /// Baseline x86-64 (SSE2) or another architecture.
    Portable,
}

/// Detects [`Simd`] on the running CPU (the standard library caches the detection).
pub(crate) fn simd() -> Simd {
    #[cfg(target_arch = "x86_64")]
    {
        if std::arch::is_x86_feature_detected!("avx512f")
            && std::arch::is_x86_feature_detected!("avx512bw")
            && std::arch::is_x86_feature_detected!("avx512dq")
            && std::arch::is_x86_feature_detected!("avx512vl")
        {
            return Simd::Avx512;
        }
        if std::arch::is_x86_feature_detected!("avx2") && std::arch::is_x86_feature_detected!("fma")
        {
            return Simd::Avx2;
        }
    }
    Simd::Portable
}
