//! The AVX-512 backend: sixteen `f32` or `u32` lanes in one 512-bit
//! register, sixteen `f64` or `u64` lanes in two (lanes 0–7, 8–15).

#![allow(unsafe_code)]

use std::arch::x86_64::*;

use super::{Cmp, LANES, Lanes, Mask16, Registers};

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

impl Registers for Avx512 {
    type F32 = __m512;
    type F64 = [__m512d; 2];
    type U32 = __m512i;
    type U64 = [__m512i; 2];
}

impl Lanes for Avx512 {
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
}

mod f32_ops;
mod f64_ops;
mod u32_ops;
mod u64_ops;
