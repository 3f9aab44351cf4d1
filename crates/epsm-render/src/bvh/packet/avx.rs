//! The eight lanes of a [`TrianglePacket`] tested at once with 256-bit AVX
//! vectors: the operations of [`TrianglePacket::intersect_4x2`] in the same
//! operand order, so the same hits (module `packet`).
//!
//! Two rare cases are handed to [`TrianglePacket::intersect_4x2`] itself
//! (which gives the same hit by definition): a lane asked for with an edge
//! function that rounds to exactly zero (the `f64` fallback; none in the
//! spp-8 run of `scenes/caustic-box.toml`), and hits in both halves (whose
//! winner is the one of testing the halves in order; 124 of 1.18 M hits
//! there). Without them every tested edge function is nonzero, so a lane is
//! inside exactly when the signs of its `U, V, W` agree, which the sign bits
//! of their bitwise `or` and `and` tell in five operations instead of eleven
//! comparisons: a lane where any of them is NaN has a NaN `det` and fails
//! `den > 0` whatever its sign bits say.
//!
//! The `t_max` comparisons come before the division, with the other range
//! tests. Moving them after it (so that the first branch does not wait for
//! the `t_max` of the previous hit) was no faster: 51.4 against 50.8 ns
//! per closest-hit ray, the walks timed alone.
//!
//! No parameters.

use super::{HALF, LANES, PacketHit, TrianglePacket, closest};
use crate::bvh::node::{Lanes8, TraceRay};

impl TrianglePacket {
    /// [`TrianglePacket::intersect_4x2`] on all eight lanes at once with
    /// 256-bit AVX vectors: the same operations in the same operand order,
    /// so the same hit (the rare cases of the module docs are passed to
    /// [`TrianglePacket::intersect_4x2`]).
    ///
    /// It calls nothing on its common paths, so it saves no registers and
    /// needs no stack frame. The walks call it through
    /// [`TrianglePacket::intersect_8_outlined`].
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx")]
    #[inline]
    #[allow(unsafe_code)]
    pub fn intersect_8(&self, ray: &TraceRay, lanes: u32) -> Option<PacketHit> {
        use std::arch::x86_64::{
            __m256, _CMP_EQ_OQ, _CMP_GE_OQ, _CMP_GT_OQ, _CMP_LE_OQ, _CMP_LT_OQ, _mm256_add_ps,
            _mm256_and_ps, _mm256_andnot_ps, _mm256_broadcast_ss, _mm256_cmp_ps, _mm256_div_ps,
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
        let [kx, ky, kz] = ray.shear.axes();
        debug_assert!(kx < 3 && ky < 3 && kz < 3);
        let o = ray.origin.to_array();
        let [nsx, nsy, sz] = &ray.shear.kz_col;
        // SAFETY: the aligned loads and stores access `Lanes8`s, eight `f32`
        // aligned to 32 bytes, exactly what they read and write; the
        // broadcasts read one `f32` each through a reference; the unchecked
        // indices are the ray's axes, below 3 by `RayShear::new` (the only
        // code that sets them), into arrays of 3; AVX is enabled on this
        // function.
        unsafe {
            let (ox, oy, oz) = (
                _mm256_broadcast_ss(o.get_unchecked(kx)),
                _mm256_broadcast_ss(o.get_unchecked(ky)),
                _mm256_broadcast_ss(o.get_unchecked(kz)),
            );
            let (nsx, nsy, sz) = (
                _mm256_broadcast_ss(nsx),
                _mm256_broadcast_ss(nsy),
                _mm256_broadcast_ss(sz),
            );
            // `(x, y, z)` of a vertex, sheared as in `intersect_half`.
            macro_rules! sheared {
                ($p:expr) => {{
                    let [x, y, z] = [kx, ky, kz].map(|k| load!($p.get_unchecked(k)));
                    let z = _mm256_sub_ps(z, oz);
                    [
                        _mm256_add_ps(_mm256_sub_ps(x, ox), _mm256_mul_ps(nsx, z)),
                        _mm256_add_ps(_mm256_sub_ps(y, oy), _mm256_mul_ps(nsy, z)),
                        _mm256_mul_ps(sz, z),
                    ]
                }};
            }
            let a: [__m256; 3] = sheared!(self.p[0]);
            let b: [__m256; 3] = sheared!(self.p[1]);
            let c: [__m256; 3] = sheared!(self.p[2]);
            let zero = _mm256_setzero_ps();
            let (u, v, w) = (edge!(c, b), edge!(a, c), edge!(b, a));
            let zeros = _mm256_or_ps(
                _mm256_or_ps(
                    _mm256_cmp_ps::<_CMP_EQ_OQ>(u, zero),
                    _mm256_cmp_ps::<_CMP_EQ_OQ>(v, zero),
                ),
                _mm256_cmp_ps::<_CMP_EQ_OQ>(w, zero),
            );
            if _mm256_movemask_ps(zeros) as u32 & lanes != 0 {
                return self.intersect_4x2_cold(ray, lanes);
            }
            // Sign bit set where the signs of `u, v, w` differ.
            let mixed = _mm256_xor_ps(
                _mm256_or_ps(_mm256_or_ps(u, v), w),
                _mm256_and_ps(_mm256_and_ps(u, v), w),
            );
            let det = _mm256_add_ps(_mm256_add_ps(u, v), w);
            let sign_bit = _mm256_set1_ps(-0.0);
            // The sign of `det`, as the scalar test flips by (a lane where
            // it differs from `det < 0`, det = −0 or NaN, fails `den > 0`).
            let flip = _mm256_and_ps(sign_bit, det);
            let t_raw = _mm256_add_ps(
                _mm256_add_ps(_mm256_mul_ps(u, a[2]), _mm256_mul_ps(v, b[2])),
                _mm256_mul_ps(w, c[2]),
            );
            let t_num = _mm256_xor_ps(flip, t_raw);
            let den = _mm256_andnot_ps(sign_bit, det);
            let (t_min, t_max) = (
                _mm256_broadcast_ss(&ray.t_min),
                _mm256_broadcast_ss(&ray.t_max),
            );
            let in_range = _mm256_and_ps(
                _mm256_and_ps(
                    _mm256_cmp_ps::<_CMP_GT_OQ>(den, zero),
                    _mm256_cmp_ps::<_CMP_GE_OQ>(t_num, _mm256_mul_ps(t_min, den)),
                ),
                _mm256_cmp_ps::<_CMP_LE_OQ>(t_num, _mm256_mul_ps(t_max, den)),
            );
            let inside = _mm256_andnot_ps(mixed, in_range);
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
                    _mm256_cmp_ps::<_CMP_GE_OQ>(t, t_min),
                ),
                _mm256_cmp_ps::<_CMP_LE_OQ>(t, t_max),
            );
            mask &= _mm256_movemask_ps(t_ok) as u32;
            if mask == 0 {
                return None;
            }
            if mask >> HALF != 0 && mask & 0xf != 0 {
                return self.intersect_4x2_cold(ray, lanes);
            }
            let t = store!(t);
            let lane = closest(mask, &t);
            let b1 = store!(_mm256_mul_ps(_mm256_xor_ps(flip, v), inv));
            let b2 = store!(_mm256_mul_ps(_mm256_xor_ps(flip, w), inv));
            Some(PacketHit {
                lane,
                t: t[lane],
                b1: b1[lane],
                b2: b2[lane],
            })
        }
    }

    /// [`TrianglePacket::intersect_8`] out of line: the walks' packet test.
    /// Not a `#[target_feature]` function: rustc does not keep
    /// `#[inline(never)]` on those, and LLVM inlined `intersect_8` into the
    /// closest-hit walks of the AVX2 tile loop, and with some changes to the
    /// ray set-up also into the occlusion walks, for 5 M to 31 M more
    /// instructions in the spp-8 run of `scenes/caustic-box.toml` than this
    /// call (1 707.4 M); forcing it inline through a plain
    /// `#[inline(always)]` function gave 1 745.8 M. Timed with the walks
    /// alone (the rays of a render of that scene): called
    /// without this wrapper (LLVM's choice of where to inline it) 49.9
    /// against 49.6 ns per closest-hit ray; forced inline 51.2 ns, and
    /// shadow rays 14.6 against 13.6 ns.
    ///
    /// # Safety
    /// The CPU must have AVX.
    #[cfg(target_arch = "x86_64")]
    #[inline(never)]
    #[allow(unsafe_code)]
    pub unsafe fn intersect_8_outlined(&self, ray: &TraceRay, lanes: u32) -> Option<PacketHit> {
        // SAFETY: the CPU has AVX (this function's contract), all that
        // `intersect_8` requires.
        unsafe { self.intersect_8(ray, lanes) }
    }

    /// [`TrianglePacket::intersect_4x2`], out of line for the rare cases of
    /// [`TrianglePacket::intersect_8`].
    #[cold]
    #[inline(never)]
    fn intersect_4x2_cold(&self, ray: &TraceRay, lanes: u32) -> Option<PacketHit> {
        self.intersect_4x2(ray, lanes)
    }
}
