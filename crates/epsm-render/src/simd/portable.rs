//! The portable backend: plain arrays, one scalar operation per lane, on
//! every CPU. The reference the x86 backends are tested against, and the
//! wide tracer's body where neither of them runs.

use super::{Cmp, LANES, Lanes, Mask16};

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

#[allow(unsafe_code)]
impl Lanes for Portable {
    type F32 = [f32; LANES];
    type F64 = [f64; LANES];
    type U32 = [u32; LANES];
    type U64 = [u64; LANES];
    type Boxes = crate::bvh::Portable;

    #[inline(always)]
    fn boxes(self) -> Self::Boxes {
        crate::bvh::Portable
    }

    #[inline(always)]
    fn run<R>(self, f: impl FnOnce() -> R) -> R {
        f()
    }

    #[inline(always)]
    fn f32_splat(self, x: f32) -> Self::F32 {
        [x; LANES]
    }
    #[inline(always)]
    fn f32_load(self, lanes: [f32; LANES]) -> Self::F32 {
        lanes
    }
    #[inline(always)]
    fn f32_store(self, v: Self::F32) -> [f32; LANES] {
        v
    }
    #[inline(always)]
    fn f32_add(self, a: Self::F32, b: Self::F32) -> Self::F32 {
        zip(a, b, |a, b| a + b)
    }
    #[inline(always)]
    fn f32_sub(self, a: Self::F32, b: Self::F32) -> Self::F32 {
        zip(a, b, |a, b| a - b)
    }
    #[inline(always)]
    fn f32_mul(self, a: Self::F32, b: Self::F32) -> Self::F32 {
        zip(a, b, |a, b| a * b)
    }
    #[inline(always)]
    fn f32_div(self, a: Self::F32, b: Self::F32) -> Self::F32 {
        zip(a, b, |a, b| a / b)
    }
    #[inline(always)]
    fn f32_neg(self, a: Self::F32) -> Self::F32 {
        map(a, |a| -a)
    }
    #[inline(always)]
    fn f32_sqrt(self, a: Self::F32) -> Self::F32 {
        map(a, f32::sqrt)
    }
    #[inline(always)]
    fn f32_abs(self, a: Self::F32) -> Self::F32 {
        map(a, f32::abs)
    }
    #[inline(always)]
    fn f32_min(self, a: Self::F32, b: Self::F32) -> Self::F32 {
        zip(a, b, |a, b| if a < b { a } else { b })
    }
    #[inline(always)]
    fn f32_max(self, a: Self::F32, b: Self::F32) -> Self::F32 {
        zip(a, b, |a, b| if a > b { a } else { b })
    }
    #[inline(always)]
    fn f32_select(self, m: Mask16, a: Self::F32, b: Self::F32) -> Self::F32 {
        select(m, a, b)
    }
    #[inline(always)]
    fn f32_copysign(self, magnitude: Self::F32, sign: Self::F32) -> Self::F32 {
        zip(magnitude, sign, f32::copysign)
    }
    #[inline(always)]
    fn f32_cmp(self, a: Self::F32, b: Self::F32, c: Cmp) -> Mask16 {
        mask(|i| c.scalar(a[i], b[i]))
    }
    #[inline(always)]
    fn f32_to_bits(self, a: Self::F32) -> Self::U32 {
        map(a, f32::to_bits)
    }
    #[inline(always)]
    fn f32_from_bits(self, a: Self::U32) -> Self::F32 {
        map(a, f32::from_bits)
    }
    #[inline(always)]
    fn f32_from_u32(self, a: Self::U32) -> Self::F32 {
        map(a, |u| u as f32)
    }
    #[inline(always)]
    fn f32_trunc_i32(self, a: Self::F32) -> Self::U32 {
        // The instructions' rule: `i32::MIN` outside the range (and on NaN).
        map(a, |x| {
            if (-2_147_483_648.0..2_147_483_648.0).contains(&x) {
                x as i32 as u32
            } else {
                i32::MIN as u32
            }
        })
    }
    #[inline(always)]
    fn f32_to_f64(self, a: Self::F32) -> Self::F64 {
        map(a, f64::from)
    }
    #[inline(always)]
    fn f32_permute(self, a: Self::F32, index: Self::U32) -> Self::F32 {
        map(index, |i| a[i as usize % LANES])
    }
    #[inline(always)]
    fn f32_reduce_min(self, a: Self::F32, m: Mask16) -> f32 {
        m.lanes()
            .fold(f32::INFINITY, |s, i| if a[i] < s { a[i] } else { s })
    }
    #[inline(always)]
    unsafe fn f32_gather(
        self,
        table: &[f32],
        index: Self::U32,
        m: Mask16,
        fallback: Self::F32,
    ) -> Self::F32 {
        gather(table, index, m, fallback)
    }
    #[inline(always)]
    unsafe fn f32_expand(self, a: Self::F32, m: Mask16, src: &[f32]) -> Self::F32 {
        expand(a, m, src)
    }

    #[inline(always)]
    fn f64_splat(self, x: f64) -> Self::F64 {
        [x; LANES]
    }
    #[inline(always)]
    fn f64_load(self, lanes: [f64; LANES]) -> Self::F64 {
        lanes
    }
    #[inline(always)]
    fn f64_store(self, v: Self::F64) -> [f64; LANES] {
        v
    }
    #[inline(always)]
    fn f64_add(self, a: Self::F64, b: Self::F64) -> Self::F64 {
        zip(a, b, |a, b| a + b)
    }
    #[inline(always)]
    fn f64_sub(self, a: Self::F64, b: Self::F64) -> Self::F64 {
        zip(a, b, |a, b| a - b)
    }
    #[inline(always)]
    fn f64_mul(self, a: Self::F64, b: Self::F64) -> Self::F64 {
        zip(a, b, |a, b| a * b)
    }
    #[inline(always)]
    fn f64_div(self, a: Self::F64, b: Self::F64) -> Self::F64 {
        zip(a, b, |a, b| a / b)
    }
    #[inline(always)]
    fn f64_neg(self, a: Self::F64) -> Self::F64 {
        map(a, |a| -a)
    }
    #[inline(always)]
    fn f64_sqrt(self, a: Self::F64) -> Self::F64 {
        map(a, f64::sqrt)
    }
    #[inline(always)]
    fn f64_abs(self, a: Self::F64) -> Self::F64 {
        map(a, f64::abs)
    }
    #[inline(always)]
    fn f64_min(self, a: Self::F64, b: Self::F64) -> Self::F64 {
        zip(a, b, |a, b| if a < b { a } else { b })
    }
    #[inline(always)]
    fn f64_select(self, m: Mask16, a: Self::F64, b: Self::F64) -> Self::F64 {
        select(m, a, b)
    }
    #[inline(always)]
    fn f64_copysign(self, magnitude: Self::F64, sign: Self::F64) -> Self::F64 {
        zip(magnitude, sign, f64::copysign)
    }
    #[inline(always)]
    fn f64_cmp(self, a: Self::F64, b: Self::F64, c: Cmp) -> Mask16 {
        mask(|i| c.scalar(a[i], b[i]))
    }
    #[inline(always)]
    fn f64_to_f32(self, a: Self::F64) -> Self::F32 {
        map(a, |x| x as f32)
    }

    #[inline(always)]
    fn u32_splat(self, x: u32) -> Self::U32 {
        [x; LANES]
    }
    #[inline(always)]
    fn u32_load(self, lanes: [u32; LANES]) -> Self::U32 {
        lanes
    }
    #[inline(always)]
    fn u32_store(self, v: Self::U32) -> [u32; LANES] {
        v
    }
    #[inline(always)]
    fn u32_add(self, a: Self::U32, b: Self::U32) -> Self::U32 {
        zip(a, b, u32::wrapping_add)
    }
    #[inline(always)]
    fn u32_sub(self, a: Self::U32, b: Self::U32) -> Self::U32 {
        zip(a, b, u32::wrapping_sub)
    }
    #[inline(always)]
    fn u32_mul(self, a: Self::U32, b: Self::U32) -> Self::U32 {
        zip(a, b, u32::wrapping_mul)
    }
    #[inline(always)]
    fn u32_and(self, a: Self::U32, b: Self::U32) -> Self::U32 {
        zip(a, b, |a, b| a & b)
    }
    #[inline(always)]
    fn u32_or(self, a: Self::U32, b: Self::U32) -> Self::U32 {
        zip(a, b, |a, b| a | b)
    }
    #[inline(always)]
    fn u32_xor(self, a: Self::U32, b: Self::U32) -> Self::U32 {
        zip(a, b, |a, b| a ^ b)
    }
    #[inline(always)]
    fn u32_shr(self, a: Self::U32, n: u32) -> Self::U32 {
        map(a, |a| a.checked_shr(n).unwrap_or(0))
    }
    #[inline(always)]
    fn u32_shl(self, a: Self::U32, n: u32) -> Self::U32 {
        map(a, |a| a.checked_shl(n).unwrap_or(0))
    }
    #[inline(always)]
    fn u32_shr_signed(self, a: Self::U32, n: u32) -> Self::U32 {
        map(a, |a| ((a as i32) >> n.min(31)) as u32)
    }
    #[inline(always)]
    fn u32_select(self, m: Mask16, a: Self::U32, b: Self::U32) -> Self::U32 {
        select(m, a, b)
    }
    #[inline(always)]
    fn u32_lt(self, a: Self::U32, b: Self::U32) -> Mask16 {
        mask(|i| a[i] < b[i])
    }
    #[inline(always)]
    fn u32_eq(self, a: Self::U32, b: Self::U32) -> Mask16 {
        mask(|i| a[i] == b[i])
    }
    #[inline(always)]
    unsafe fn u32_gather(
        self,
        table: &[u32],
        index: Self::U32,
        m: Mask16,
        fallback: Self::U32,
    ) -> Self::U32 {
        gather(table, index, m, fallback)
    }

    #[inline(always)]
    fn u64_splat(self, x: u64) -> Self::U64 {
        [x; LANES]
    }
    #[inline(always)]
    fn u64_load(self, lanes: [u64; LANES]) -> Self::U64 {
        lanes
    }
    #[inline(always)]
    fn u64_store(self, v: Self::U64) -> [u64; LANES] {
        v
    }
    #[inline(always)]
    fn u64_add(self, a: Self::U64, b: Self::U64) -> Self::U64 {
        zip(a, b, u64::wrapping_add)
    }
    #[inline(always)]
    fn u64_mul(self, a: Self::U64, b: Self::U64) -> Self::U64 {
        zip(a, b, u64::wrapping_mul)
    }
    #[inline(always)]
    fn u64_xor(self, a: Self::U64, b: Self::U64) -> Self::U64 {
        zip(a, b, |a, b| a ^ b)
    }
    #[inline(always)]
    fn u64_shr(self, a: Self::U64, n: u32) -> Self::U64 {
        map(a, |a| a.checked_shr(n).unwrap_or(0))
    }
    #[inline(always)]
    fn u64_from_u32(self, a: Self::U32) -> Self::U64 {
        map(a, u64::from)
    }
    #[inline(always)]
    fn u64_low_u32(self, a: Self::U64) -> Self::U32 {
        map(a, |a| a as u32)
    }
    #[inline(always)]
    unsafe fn u64_gather(
        self,
        table: &[u64],
        index: Self::U32,
        m: Mask16,
        fallback: Self::U64,
    ) -> Self::U64 {
        gather(table, index, m, fallback)
    }
    #[inline(always)]
    unsafe fn u64_expand(self, a: Self::U64, m: Mask16, src: &[u64]) -> Self::U64 {
        expand(a, m, src)
    }
}
