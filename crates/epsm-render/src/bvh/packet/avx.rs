//! The eight lanes of a [`TrianglePacket`] tested at once with 256-bit AVX
//! vectors: the operations of [`TrianglePacket::intersect_4x2`] in the same
//! operand order, so the same hits (module `packet`).
//!
//! No parameters.

use super::{HALF, LANES, PacketHit, TrianglePacket, closest, edges_f64};
use crate::bvh::node::{Lanes8, TraceRay};

impl TrianglePacket {
    /// [`TrianglePacket::intersect_4x2`] on all eight lanes at once with
    /// 256-bit AVX vectors: the same operations in the same operand order,
    /// then the winner of the halves' order (module docs), so the same hit.
    ///
    /// Not inlined into the walk (LLVM declines, and forcing it cost 1 %
    /// more instructions per sample on `scenes/caustic-box.toml`: the walk's
    /// registers spill).
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx")]
    #[inline]
    #[allow(unsafe_code)]
    pub fn intersect_8(&self, ray: &TraceRay, lanes: u32) -> Option<PacketHit> {
        use std::arch::x86_64::{
            __m256, _CMP_EQ_OQ, _CMP_GE_OQ, _CMP_GT_OQ, _CMP_LE_OQ, _CMP_LT_OQ, _mm256_add_ps,
            _mm256_and_ps, _mm256_andnot_ps, _mm256_blendv_ps, _mm256_cmp_ps, _mm256_div_ps,
            _mm256_load_ps, _mm256_movemask_ps, _mm256_mul_ps, _mm256_or_ps, _mm256_set1_ps,
            _mm256_setzero_ps, _mm256_store_ps, _mm256_sub_ps, _mm256_xor_ps,
        };
        macro_rules! load {
            ($lanes:expr) => {
                _mm256_load_ps($lanes.0.as_ptr())
            };
        }
        macro_rules! store {
            ($x:expr) => {{
                let mut out = Lanes8([0.0; LANES]);
                _mm256_store_ps(out.0.as_mut_ptr(), $x);
                out.0
            }};
        }
        macro_rules! edge {
            ($p:expr, $q:expr) => {
                _mm256_sub_ps(_mm256_mul_ps($p[0], $q[1]), _mm256_mul_ps($p[1], $q[0]))
            };
        }
        let (t_min, t_max) = (ray.t_min, ray.t_max);
        let [kx, ky, kz] = ray.shear.axes.map(|k| k.min(2));
        let o = ray.origin.to_array();
        let [nsx, nsy, sz] = ray.shear.kz_col;
        // SAFETY: the aligned loads and stores access `Lanes8`s, eight `f32`
        // aligned to 32 bytes, exactly what they read and write; AVX is
        // enabled on this function.
        unsafe {
            let (ox, oy, oz) = (
                _mm256_set1_ps(o[kx]),
                _mm256_set1_ps(o[ky]),
                _mm256_set1_ps(o[kz]),
            );
            let (nsx, nsy, sz) = (_mm256_set1_ps(nsx), _mm256_set1_ps(nsy), _mm256_set1_ps(sz));
            // `(x, y, z)` of a vertex, sheared as in `intersect_half`.
            macro_rules! sheared {
                ($p:expr) => {{
                    let z = _mm256_sub_ps(load!($p[kz]), oz);
                    [
                        _mm256_add_ps(_mm256_sub_ps(load!($p[kx]), ox), _mm256_mul_ps(nsx, z)),
                        _mm256_add_ps(_mm256_sub_ps(load!($p[ky]), oy), _mm256_mul_ps(nsy, z)),
                        _mm256_mul_ps(sz, z),
                    ]
                }};
            }
            let a: [__m256; 3] = sheared!(self.p[0]);
            let b: [__m256; 3] = sheared!(self.p[1]);
            let c: [__m256; 3] = sheared!(self.p[2]);
            let zero = _mm256_setzero_ps();
            let (mut u, mut v, mut w) = (edge!(c, b), edge!(a, c), edge!(b, a));
            // Lanes where any of `u, v, w` compares `$cmp` against zero.
            macro_rules! any_uvw {
                ($cmp:ident) => {
                    _mm256_or_ps(
                        _mm256_or_ps(
                            _mm256_cmp_ps::<$cmp>(u, zero),
                            _mm256_cmp_ps::<$cmp>(v, zero),
                        ),
                        _mm256_cmp_ps::<$cmp>(w, zero),
                    )
                };
            }
            let zeros = _mm256_movemask_ps(any_uvw!(_CMP_EQ_OQ)) as u32;
            if zeros != 0 {
                let xy = [
                    [store!(a[0]), store!(a[1])],
                    [store!(b[0]), store!(b[1])],
                    [store!(c[0]), store!(c[1])],
                ];
                let [u64, v64, w64] = edges_f64(zeros, xy, [store!(u), store!(v), store!(w)]);
                (u, v, w) = (load!(Lanes8(u64)), load!(Lanes8(v64)), load!(Lanes8(w64)));
            }
            let negative = any_uvw!(_CMP_LT_OQ);
            let positive = any_uvw!(_CMP_GT_OQ);
            let det = _mm256_add_ps(_mm256_add_ps(u, v), w);
            let sign_bit = _mm256_set1_ps(-0.0);
            let flip = _mm256_cmp_ps::<_CMP_LT_OQ>(det, zero);
            let t_raw = _mm256_add_ps(
                _mm256_add_ps(_mm256_mul_ps(u, a[2]), _mm256_mul_ps(v, b[2])),
                _mm256_mul_ps(w, c[2]),
            );
            let t_num = _mm256_blendv_ps(t_raw, _mm256_xor_ps(sign_bit, t_raw), flip);
            let den = _mm256_andnot_ps(sign_bit, det);
            let in_range = _mm256_and_ps(
                _mm256_and_ps(
                    _mm256_cmp_ps::<_CMP_GT_OQ>(den, zero),
                    _mm256_cmp_ps::<_CMP_GE_OQ>(t_num, _mm256_mul_ps(_mm256_set1_ps(t_min), den)),
                ),
                _mm256_cmp_ps::<_CMP_LE_OQ>(t_num, _mm256_mul_ps(_mm256_set1_ps(t_max), den)),
            );
            let inside = _mm256_andnot_ps(_mm256_and_ps(negative, positive), in_range);
            let mut mask = _mm256_movemask_ps(inside) as u32 & lanes;
            if mask == 0 {
                return None;
            }
            let inv = _mm256_div_ps(_mm256_set1_ps(1.0), den);
            let t = _mm256_mul_ps(t_num, inv);
            let t_ok = _mm256_and_ps(
                _mm256_and_ps(
                    _mm256_cmp_ps::<_CMP_LT_OQ>(
                        _mm256_andnot_ps(sign_bit, t),
                        _mm256_set1_ps(f32::INFINITY),
                    ),
                    _mm256_cmp_ps::<_CMP_GE_OQ>(t, _mm256_set1_ps(t_min)),
                ),
                _mm256_cmp_ps::<_CMP_LE_OQ>(t, _mm256_set1_ps(t_max)),
            );
            mask &= _mm256_movemask_ps(t_ok) as u32;
            if mask == 0 {
                return None;
            }
            let t = store!(t);
            if mask & 0xf != 0 && mask >> HALF != 0 {
                mask = in_halves_order(mask, &t, &store!(t_num), &store!(den));
            }
            let lane = closest(mask, &t);
            let flipped = _mm256_movemask_ps(flip) as u32 & (1 << lane) != 0;
            let sign = if flipped { -1.0 } else { 1.0 };
            let inv = store!(inv)[lane];
            Some(PacketHit {
                lane,
                t: t[lane],
                b1: (sign * store!(v)[lane]) * inv,
                b2: (sign * store!(w)[lane]) * inv,
            })
        }
    }
}

/// The lanes of `mask` (hits in both halves, given their `t` and the range
/// test's `t_num` and `den`) that can win in the halves' order: the closest
/// lane of the first half, unless lanes of the second half pass the range
/// tests against its `t` as `t_max`, which are then kept instead.
#[cold]
#[inline(never)]
fn in_halves_order(mask: u32, t: &[f32; LANES], t_num: &[f32; LANES], den: &[f32; LANES]) -> u32 {
    let first = closest(mask & 0xf, t);
    let t_first = t[first];
    let mut second = mask >> HALF << HALF;
    let mut kept = 0;
    while second != 0 {
        let lane = second.trailing_zeros() as usize % LANES;
        second &= second - 1;
        if t_num[lane] <= t_first * den[lane] && t[lane] <= t_first {
            kept |= 1 << lane;
        }
    }
    if kept == 0 { 1 << first } else { kept }
}
