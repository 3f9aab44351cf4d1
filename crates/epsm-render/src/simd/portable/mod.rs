//! The portable backend: plain arrays, one scalar operation per lane, on
//! every CPU. The reference the x86 backends are tested against, and the
//! wide tracer's body where neither of them runs.

use super::{Cmp, LANES, Lanes, Mask16, Registers};

/// The portable backend's token (module docs of `simd`): needs no CPU
/// feature, so anyone may make one.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Portable;

/// `f(a[i])` per lane.
#[inline(always)]
fn map<T: Copy, R>(a: [T; LANES], f: impl Fn(T) -> R) -> [R; LANES] {
    std::array::from_fn(|i| f(a[i]))
}

/// `f(a[i], b[i])` per lane.
#[inline(always)]
fn zip<T: Copy, U: Copy, R>(a: [T; LANES], b: [U; LANES], f: impl Fn(T, U) -> R) -> [R; LANES] {
    std::array::from_fn(|i| f(a[i], b[i]))
}

/// The mask of the lanes where `f(i)` holds.
#[inline(always)]
fn mask(f: impl Fn(usize) -> bool) -> Mask16 {
    Mask16((0..LANES).fold(0, |m, i| m | u16::from(f(i)) << i))
}

/// `a` in the lanes of `m`, `b` in the others.
#[inline(always)]
fn select<T: Copy>(m: Mask16, a: [T; LANES], b: [T; LANES]) -> [T; LANES] {
    std::array::from_fn(|i| if m.test(i) { a[i] } else { b[i] })
}

/// `table[index[i]]` in the lanes of `m`, `fallback` in the others.
#[inline(always)]
fn gather<T: Copy>(
    table: &[T],
    index: [u32; LANES],
    m: Mask16,
    fallback: [T; LANES],
) -> [T; LANES] {
    std::array::from_fn(|i| {
        if m.test(i) {
            table[index[i] as usize]
        } else {
            fallback[i]
        }
    })
}

/// `a` with the lanes of `m` replaced by `src[0]`, `src[1]`, … in order.
#[inline(always)]
fn expand<T: Copy>(mut a: [T; LANES], m: Mask16, src: &[T]) -> [T; LANES] {
    for (lane, &v) in m.lanes().zip(src) {
        a[lane] = v;
    }
    a
}

impl Registers for Portable {
    type F32 = [f32; LANES];
    type F64 = [f64; LANES];
    type U32 = [u32; LANES];
    type U64 = [u64; LANES];
}

impl Lanes for Portable {
    type Boxes = crate::bvh::Portable;

    #[inline(always)]
    fn boxes(self) -> Self::Boxes {
        crate::bvh::Portable
    }

    #[inline(always)]
    fn run<R>(self, f: impl FnOnce() -> R) -> R {
        f()
    }
}

mod f32_ops;
mod f64_ops;
mod u32_ops;
mod u64_ops;
