//! The number types the BSDF formulas are written over, so that one
//! function serves the scalar tracer (one `f32` path, or `f64` for
//! derivatives) and the wide tracer (sixteen `f32` lanes, one path each).
//!
//! Model: a formula generic over [`Real`] is a fixed sequence of IEEE
//! operations, so each lane of the wide instance rounds exactly as the
//! scalar instance does for that lane's inputs. Branches stay with the
//! callers (a scalar `if`, a lane select), which share the branch-free parts.
//!
//! | implementor | constants from | `max` |
//! |---|---|---|
//! | every [`num_traits::Float`] (`f32`, `f64`) | `()` | the type's own (`f32::max`) |
//! | `F32x16` (x86-64, `materials::wide`) | the backend's token | the lane method |

use std::ops::{Add, Div, Mul, Sub};

use num_traits::Float;

/// A real number type: one value or sixteen lanes (module docs).
pub(crate) trait Real:
    Copy + Add<Output = Self> + Sub<Output = Self> + Mul<Output = Self> + Div<Output = Self>
{
    /// What it takes to make a constant: nothing for plain floats, the CPU
    /// token for lanes.
    type Token: Copy;

    /// The constant `c` (exact: every `f32` is an `f32` and an `f64`).
    fn constant(k: Self::Token, c: f32) -> Self;

    /// Square root (IEEE, correctly rounded).
    fn sqrt(self) -> Self;

    /// The larger of `self` and `o`. Implementors agree (and equal
    /// `if self > o { self } else { o }`) when `o` is not NaN and `self` is
    /// not `−0`: every use passes a constant `o` and a `self` that is never
    /// `−0`.
    fn max(self, o: Self) -> Self;
}

impl<T: Float> Real for T {
    type Token = ();

    #[inline(always)]
    fn constant((): (), c: f32) -> Self {
        // `f32` and `f64` hold every `f32`, so the fallback is never taken.
        <T as num_traits::NumCast>::from(c).unwrap_or_else(T::nan)
    }

    #[inline(always)]
    fn sqrt(self) -> Self {
        Float::sqrt(self)
    }

    #[inline(always)]
    fn max(self, o: Self) -> Self {
        Float::max(self, o)
    }
}
