//! One triangle against sixteen rays, or sixteen (ray, triangle) pairs:
//! the watertight test of `PackedTriangle::intersect` (module `triangle`)
//! with one ray per lane.
//!
//! Model: Woop, Benthin and Wald (JCGT 2013) as the scalar test does it,
//! operation for operation: each lane shears its triangle's vertices
//! relative to its own origin along its own axes
//! (`v[kx] − o[kx] + (−Sx)·(v[kz] − o[kz])`, …), evaluates the edge
//! functions `U, V, W`, recomputes all three in `f64` where one rounds to
//! exactly zero (here in `f64` lanes, which round as the scalar `f64`
//! code), rejects mixed signs (by the comparisons there, by the sign bits
//! when no edge function is zero, which is the same test), runs the range
//! tests before the division (`t_min·det ≤ T ≤ t_max·det` on the
//! sign-flipped `T`) and after it (`t` finite and in `[t_min, t_max]`), and
//! gives `t = T/det`, `(b1, b2) = (V, W)/det` by the same reciprocal. A
//! lane's hit is therefore exactly the scalar test's for its ray, triangle
//! and `t_max`. The vertices come per lane along the lane's axes: permuted
//! out of one triangle's corner vector ([`hit_triangle`]), or gathered from
//! each lane's own triangle (module `pairs`).
//!
//! No parameters.

use super::rays::RayLanes;
use super::tree::Corners;
use crate::simd::{F32x16, Lanes, Mask16, U32x16};

/// The lanes that hit a triangle, with their `t` and barycentrics.
#[derive(Clone, Copy, Debug)]
pub(super) struct TriangleHits<B: Lanes> {
    /// Lanes with a hit in their `t` range.
    pub lanes: Mask16,
    /// Ray parameter (meaningful in `lanes`).
    pub t: F32x16<B>,
    /// Barycentric weight of `p1`.
    pub b1: F32x16<B>,
    /// Barycentric weight of `p2`.
    pub b2: F32x16<B>,
}

/// Per lane, the ray constants of the test (a packet's rays, or the rays
/// of a chunk of (ray, triangle) pairs).
#[derive(Clone, Copy, Debug)]
pub(super) struct TestRays<B: Lanes> {
    /// The origins' coordinates along `[kx, ky, kz]`.
    pub origin_k: [F32x16<B>; 3],
    /// `(−Sx, −Sy, Sz)`.
    pub kz_col: [F32x16<B>; 3],
    /// Smallest accepted `t`.
    pub t_min: F32x16<B>,
}

/// A vertex's coordinates along each lane's `[kx, ky, kz]`.
pub(super) type Along<B> = [F32x16<B>; 3];

/// A vertex relative to each lane's origin, sheared: `[x, y]` across the
/// ray, `z` along it.
type Sheared<B> = [F32x16<B>; 3];

/// The hits of the rays of `lanes` on the triangle `corners`, `t` in
/// `[rays.t_min, t_max]` per lane.
#[inline(always)]
pub(super) fn hit_triangle<B: Lanes>(
    corners: &Corners,
    rays: &RayLanes<B>,
    t_max: F32x16<B>,
    lanes: Mask16,
) -> TriangleHits<B> {
    let p = F32x16::from_array(rays.k, corners.0);
    let [ia, ib, ic] = &rays.index;
    let vertices = [along(p, ia), along(p, ib), along(p, ic)];
    watertight(rays.k, &rays.test, vertices, t_max, lanes)
}

/// The coordinates at positions `index` of the corner vector `p`.
#[inline(always)]
fn along<B: Lanes>(p: F32x16<B>, index: &[U32x16<B>; 3]) -> Along<B> {
    [
        p.permute(index[0]),
        p.permute(index[1]),
        p.permute(index[2]),
    ]
}

/// The watertight test of the triangle with vertices `[a, b, c]` (per lane,
/// along the lane's axes) against the rays `rays` of `lanes`, `t` in
/// `[rays.t_min, t_max]`.
#[inline(always)]
pub(super) fn watertight<B: Lanes>(
    k: B,
    rays: &TestRays<B>,
    [a, b, c]: [Along<B>; 3],
    t_max: F32x16<B>,
    lanes: Mask16,
) -> TriangleHits<B> {
    let zero = F32x16::splat(k, 0.0);
    let (a, b, c) = (shear(a, rays), shear(b, rays), shear(c, rays));
    let (mut u, mut v, mut w) = (edge(&c, &b), edge(&a, &c), edge(&b, &a));
    let on_edge = (u.eq(zero) | v.eq(zero) | w.eq(zero)) & lanes;
    let mixed = if on_edge.any() {
        [u, v, w] = edges_f64(on_edge, [a, b, c], [u, v, w]);
        let negative = u.lt(zero) | v.lt(zero) | w.lt(zero);
        let positive = u.gt(zero) | v.gt(zero) | w.gt(zero);
        negative & positive
    } else {
        // No zero edge function: mixed signs are differing sign bits (a
        // NaN lane, whatever its bits, fails `den > 0` below).
        let (ub, vb, wb) = (u.to_bits(), v.to_bits(), w.to_bits());
        ((ub | vb | wb) ^ (ub & vb & wb)).ge(U32x16::splat(k, 0x8000_0000))
    };
    let det = u + v + w;
    // The scalar `flip`: negate where `det`'s sign bit is set.
    let sign = det.to_bits() & U32x16::splat(k, 0x8000_0000);
    let t_num = flip(u * a[2] + v * b[2] + w * c[2], sign);
    let den = det.abs();
    let in_range = den.gt(zero) & t_num.ge(rays.t_min * den) & t_num.le(t_max * den);
    let mut hit = in_range.and_not(mixed) & lanes;
    if !hit.any() {
        return TriangleHits {
            lanes: hit,
            t: zero,
            b1: zero,
            b2: zero,
        };
    }
    let inv = F32x16::splat(k, 1.0) / den;
    let t = t_num * inv;
    hit = hit & t.is_finite() & t.ge(rays.t_min) & t.le(t_max);
    TriangleHits {
        lanes: hit,
        t,
        b1: flip(v, sign) * inv,
        b2: flip(w, sign) * inv,
    }
}

/// The vertex `p` (along the lane's axes) relative to each lane's origin,
/// sheared: `(p[kx] − o[kx]) + (−Sx)·(p[kz] − o[kz])`, …,
/// `Sz·(p[kz] − o[kz])`.
#[inline(always)]
fn shear<B: Lanes>(p: Along<B>, rays: &TestRays<B>) -> Sheared<B> {
    let [ox, oy, oz] = rays.origin_k;
    let [nsx, nsy, sz] = rays.kz_col;
    let z = p[2] - oz;
    [(p[0] - ox) + nsx * z, (p[1] - oy) + nsy * z, sz * z]
}

/// The edge function `p.x·q.y − p.y·q.x`.
#[inline(always)]
fn edge<B: Lanes>(p: &Sheared<B>, q: &Sheared<B>) -> F32x16<B> {
    p[0] * q[1] - p[1] * q[0]
}

/// [`edge`] in `f64`, rounded to `f32`.
#[inline(always)]
fn edge_f64<B: Lanes>(p: &Sheared<B>, q: &Sheared<B>) -> F32x16<B> {
    (p[0].to_f64() * q[1].to_f64() - p[1].to_f64() * q[0].to_f64()).to_f32()
}

/// `x` with its sign bit flipped where `sign` has it set.
#[inline(always)]
fn flip<B: Lanes>(x: F32x16<B>, sign: U32x16<B>) -> F32x16<B> {
    F32x16::from_bits(x.to_bits() ^ sign)
}

/// The edge functions `[u, v, w]` with those of the lanes in `lanes`
/// recomputed in `f64` from the sheared vertices `[a, b, c]`, as the scalar
/// test's fallback for an edge function that rounds to zero (rare: rays
/// through an edge or vertex).
#[inline(always)]
fn edges_f64<B: Lanes>(
    lanes: Mask16,
    [a, b, c]: [Sheared<B>; 3],
    [u, v, w]: [F32x16<B>; 3],
) -> [F32x16<B>; 3] {
    [
        F32x16::select(lanes, edge_f64(&c, &b), u),
        F32x16::select(lanes, edge_f64(&a, &c), v),
        F32x16::select(lanes, edge_f64(&b, &a), w),
    ]
}
