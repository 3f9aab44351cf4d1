//! Sixteen rays prepared for the static BVH's packet walk: per lane the
//! constants a scalar walk prepares for its one ray ([`TraceRay`]): the
//! clamped reciprocal direction of the slab tests and the watertight
//! triangle test's axes and shear ([`RayShear`]), computed by the same
//! operations lane by lane, so every lane holds the scalar ray's bits.
//!
//! Each lane has its own axis permutation `(kx, ky, kz)`; a triangle's nine
//! coordinates sit in one vector and a lane picks its own by a permute
//! ([`RayLanes::index`]), so the triangle test needs no per-lane branches.
//!
//! No parameters.
//!
//! [`TraceRay`]: crate::bvh::node::TraceRay
//! [`RayShear`]: crate::bvh::triangle::RayShear

use super::Rays16;
use super::lanes;
use super::triangles::TestRays;
use crate::bvh::node::TINY_DIR;
use crate::simd::{F32x16, Lanes, Mask16, U32x16, Vec3x16};

/// Sixteen rays with their box-test and triangle-test constants.
#[derive(Clone, Copy, Debug)]
pub(super) struct RayLanes<B: Lanes> {
    /// The token the lanes were made with.
    pub k: B,
    /// Origins.
    pub origin: Vec3x16<B>,
    /// Directions (not normalised).
    pub dir: Vec3x16<B>,
    /// Reciprocals of the directions' components, each clamped to at least
    /// `TINY_DIR` in magnitude first (the scalar `clamped_recip`).
    pub inv_dir: Vec3x16<B>,
    /// Largest accepted `t` (the rays' own; walks keep their lowered one).
    pub t_max: F32x16<B>,
    /// `index[v][a]`: the position of vertex `v`'s coordinate along the
    /// lane's axis `[kx, ky, kz][a]` in a triangle's corner vector
    /// (`3·v + k`).
    pub index: [[U32x16<B>; 3]; 3],
    /// `axis_is[a] = [k == 0, k == 1]` per lane for its axis
    /// `k = [kx, ky, kz][a]`.
    pub axis_is: [[Mask16; 2]; 3],
    /// The triangle test's constants: the origins along `[kx, ky, kz]`,
    /// `(−Sx, −Sy, Sz)` (`RayShear::kz_col`) and `t_min`.
    pub test: TestRays<B>,
}

/// Per lane, `x`, `y` or `z` by axis `axis` (0, 1 or 2).
#[inline(always)]
fn along<B: Lanes>(k: B, axis: U32x16<B>, v: Vec3x16<B>) -> F32x16<B> {
    let y_or_z = F32x16::select(axis.eq(U32x16::splat(k, 1)), v.y, v.z);
    F32x16::select(axis.eq(U32x16::splat(k, 0)), v.x, y_or_z)
}

/// `1 / d` after clamping `d` away from zero as the scalar `clamped_recip`
/// does (with the sign of `d < 0`).
#[inline(always)]
fn clamped_recip<B: Lanes>(k: B, d: F32x16<B>) -> F32x16<B> {
    let tiny = F32x16::splat(k, TINY_DIR);
    let signed = F32x16::select(d.lt(F32x16::splat(k, 0.0)), -tiny, tiny);
    F32x16::splat(k, 1.0) / F32x16::select(d.abs().ge(tiny), d, signed)
}

impl<B: Lanes> RayLanes<B> {
    /// The constants of `rays` (every lane; a caller masks the lanes it
    /// uses).
    #[inline(always)]
    pub fn new(k: B, rays: &Rays16<B>) -> Self {
        let d = rays.dir;
        let [zero, one, two] = [
            U32x16::splat(k, 0),
            U32x16::splat(k, 1),
            U32x16::splat(k, 2),
        ];
        // `RayShear::new`: `kz` is x when |x| is largest, else y when
        // |y| ≥ |z|, else z; `kx, ky` follow, swapped when `dir[kz] < 0`.
        let a = Vec3x16::new(d.x.abs(), d.y.abs(), d.z.abs());
        let x_largest = a.x.ge(a.y) & a.x.ge(a.z);
        let y_ge_z = a.y.ge(a.z);
        let kz_y = !x_largest & y_ge_z;
        let kz_z = !x_largest & !y_ge_z;
        let kz = U32x16::select(kz_y, one, U32x16::select(kz_z, two, zero));
        let dz = along(k, kz, d);
        let neg = dz.lt(F32x16::splat(k, 0.0));
        // AXES_ACROSS: kz = 0 → [1, 2], 1 → [2, 0], 2 → [0, 1]; swapped
        // when negative.
        let first = U32x16::select(kz_y, two, U32x16::select(kz_z, zero, one));
        let second = U32x16::select(kz_y, zero, U32x16::select(kz_z, one, two));
        let kx = U32x16::select(neg, second, first);
        let ky = U32x16::select(neg, first, second);
        let sz = F32x16::splat(k, 1.0) / dz;
        let (three, six) = (U32x16::splat(k, 3), U32x16::splat(k, 6));
        Self {
            k,
            origin: rays.origin,
            dir: d,
            inv_dir: Vec3x16::new(
                clamped_recip(k, d.x),
                clamped_recip(k, d.y),
                clamped_recip(k, d.z),
            ),
            t_max: rays.t_max,
            index: [
                [kx, ky, kz],
                [kx + three, ky + three, kz + three],
                [kx + six, ky + six, kz + six],
            ],
            axis_is: [
                [kx.eq(zero), kx.eq(one)],
                [ky.eq(zero), ky.eq(one)],
                [kz.eq(zero), kz.eq(one)],
            ],
            test: TestRays {
                origin_k: [
                    along(k, kx, rays.origin),
                    along(k, ky, rays.origin),
                    along(k, kz, rays.origin),
                ],
                kz_col: [-(along(k, kx, d) * sz), -(along(k, ky, d) * sz), sz],
                t_min: rays.t_min,
            },
        }
    }

    /// The rays as plain values (for the per-lane fallbacks).
    #[inline(always)]
    pub fn plain(&self) -> lanes::PlainRays {
        lanes::PlainRays::new(&Rays16 {
            origin: self.origin,
            dir: self.dir,
            t_min: self.test.t_min,
            t_max: self.t_max,
        })
    }
}
