//! Which vector instructions the OT kernels use, for the bodies compiled
//! three times (plain x86-64, AVX2 + FMA, AVX-512): the soft-min rows
//! ([`crate::softmin`]), the per-point block cut
//! ([`crate::clusters::PointCut`]) and the `f32` screen of the exact
//! solver's optimality check.
//!
//! By default the kernels take the widest instruction set the running CPU
//! has. [`force_simd`] pins one (for benchmarks: `epsm bench ot --simd`);
//! every body computes the same operations in the same order, so results
//! agree to rounding whichever runs.
//!
//! A kernel is one portable body (plain loops over `f32` slices, every helper
//! `#[inline(always)]`) entered through [`Simd::run`], which calls it inside a
//! function compiled with the instruction set's features, so the compiler
//! vectorises the inlined body for those registers. A closure is compiled as a
//! function of its own, without the caller's features, so the closure passed
//! to `run` is `#[inline(always)]`.

use std::sync::atomic::{AtomicU8, Ordering};

use crate::error::OtError;

/// An instruction set the OT kernels are compiled for.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Simd {
    /// AVX-512 F, BW, DQ and VL (16 `f32` lanes).
    Avx512,
    /// AVX2 and FMA (8 `f32` lanes).
    Avx2,
    /// Baseline x86-64 (SSE2) or another architecture.
    Portable,
}

impl Simd {
    /// Every instruction set, widest first.
    pub const ALL: [Simd; 3] = [Simd::Avx512, Simd::Avx2, Simd::Portable];

    /// Short name: `avx512`, `avx2` or `portable`.
    pub fn name(self) -> &'static str {
        match self {
            Self::Avx512 => "avx512",
            Self::Avx2 => "avx2",
            Self::Portable => "portable",
        }
    }

    /// Whether the running CPU supports it (the standard library caches the detection).
    pub fn available(self) -> bool {
        match self {
            #[cfg(target_arch = "x86_64")]
            Self::Avx512 => {
                std::arch::is_x86_feature_detected!("avx512f")
                    && std::arch::is_x86_feature_detected!("avx512bw")
                    && std::arch::is_x86_feature_detected!("avx512dq")
                    && std::arch::is_x86_feature_detected!("avx512vl")
            }
            #[cfg(target_arch = "x86_64")]
            Self::Avx2 => {
                std::arch::is_x86_feature_detected!("avx2")
                    && std::arch::is_x86_feature_detected!("fma")
            }
            Self::Portable => true,
            #[cfg(not(target_arch = "x86_64"))]
            _ => false,
        }
    }

    /// The instruction sets the running CPU supports, widest first (always ends with `Portable`).
    pub fn supported() -> Vec<Simd> {
        Self::ALL.into_iter().filter(|s| s.available()).collect()
    }

    /// Runs `f` compiled for this instruction set, or for the baseline where the running
    /// CPU lacks it; `f` receives the instruction set it runs with (a constant once
    /// inlined, so a body can pick its chunk width by it).
    ///
    /// `f` must be an `#[inline(always)]` closure (`simd.run(#[inline(always)] |s| ...)`):
    /// only inlined into the feature-enabled function is it compiled with its features.
    #[inline(always)]
    pub(crate) fn run<R>(self, f: impl FnOnce(Simd) -> R) -> R {
        match self {
            #[cfg(target_arch = "x86_64")]
            Self::Avx512 if self.available() => {
                #[target_feature(enable = "avx512f,avx512bw,avx512dq,avx512vl")]
                fn run<R>(f: impl FnOnce(Simd) -> R) -> R {
                    f(Simd::Avx512)
                }
                #[allow(unsafe_code)]
                // SAFETY: `run` requires only the four AVX-512 subsets it enables, which
                // the guard detected on the running CPU; `f` is safe code.
                unsafe {
                    run(f)
                }
            }
            #[cfg(target_arch = "x86_64")]
            Self::Avx2 if self.available() => {
                #[target_feature(enable = "avx2,fma")]
                fn run<R>(f: impl FnOnce(Simd) -> R) -> R {
                    f(Simd::Avx2)
                }
                #[allow(unsafe_code)]
                // SAFETY: `run` requires only AVX2 and FMA, which the guard detected on
                // the running CPU; `f` is safe code.
                unsafe {
                    run(f)
                }
            }
            _ => f(Simd::Portable),
        }
    }
}

/// The forced instruction set: 0 for none, else 1 + its index in [`Simd::ALL`].
static FORCED: AtomicU8 = AtomicU8::new(0);

/// Makes every OT kernel of this process use `simd` (`None`: the widest the
/// CPU has, the default). Fails with [`OtError::SimdUnavailable`] when the
/// running CPU lacks it.
pub fn force_simd(simd: Option<Simd>) -> Result<(), OtError> {
    let code = match simd {
        None => 0,
        Some(s) if s.available() => 1 + Simd::ALL.iter().position(|&t| t == s).unwrap_or(0) as u8,
        Some(s) => return Err(OtError::SimdUnavailable { simd: s.name() }),
    };
    FORCED.store(code, Ordering::Relaxed);
    Ok(())
}

/// The instruction set the kernels use: the forced one, else the widest the running CPU has.
pub fn active_simd() -> Simd {
    match FORCED.load(Ordering::Relaxed) {
        0 => Simd::ALL
            .into_iter()
            .find(|s| s.available())
            .unwrap_or(Simd::Portable),
        code => Simd::ALL[usize::from(code - 1)],
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_portable_body_is_always_supported_and_names_are_distinct() {
        let supported = Simd::supported();
        assert_eq!(supported.last(), Some(&Simd::Portable));
        let names: Vec<&str> = Simd::ALL.iter().map(|s| s.name()).collect();
        assert_eq!(names, ["avx512", "avx2", "portable"]);
        // Forcing an instruction set the CPU lacks is an error and changes nothing.
        for s in Simd::ALL.into_iter().filter(|s| !s.available()) {
            assert_eq!(
                force_simd(Some(s)),
                Err(OtError::SimdUnavailable { simd: s.name() })
            );
        }
        assert_eq!(active_simd(), supported[0]);
    }
}
