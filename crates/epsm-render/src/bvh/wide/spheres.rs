//! The scene's listed exact spheres against sixteen rays: `Accel::listed_hit`
//! (and `placed_sphere_hit`) with one ray per lane.
//!
//! Model: per sphere, in the scalar order: the world-space
//! [`MissTest`] in `f32` lanes; the rays it does not rule out mapped to
//! object space by the cached `f32` `object_from_world` (glam's
//! `Affine3A::transform_point3a`/`transform_vector3a`, term for term) and
//! widened to `f64`; [`sphere::intersect`](crate::sphere::intersect) in
//! `f64` lanes (the same closest-point discriminant, the same root choice
//! and inclusive range tests); the hit's `t` rounded to `f32`, which lowers
//! the lane's `t_max` for the next sphere (so the later sphere wins an
//! exact tie, as in the scalar loop); and the octahedral local coordinates
//! ([`sphere::local_coords`](crate::sphere::local_coords)) of the `f64`
//! hit point, rounded to `f32`. With `ANY` a lane stops at its first hit
//! and gets no local coordinates.
//!
//! Solving lane by lane by the scalar `placed_sphere_hit` when at most
//! three lanes pass the miss test measured slower on
//! `scenes/cornell-box.toml` (continuation rays 42.6 against 50.7, shadow
//! rays 91 against 127 M rays per CPU-second, `epsm bench rays`) and was
//! dropped.
//!
//! No parameters.

use super::affine::{transform_point, transform_vector};
use super::rays::RayLanes;
use crate::bvh::Accel;
use crate::hit::Placement;
use crate::simd::{F32x16, F64x16, Lanes, Mask16, U32x16, Vec3x16};
use crate::sphere::MissTest;

/// A 3-vector per lane in `f64`.
type Vec3d<B> = [F64x16<B>; 3];

/// Per lane, the hit on the listed spheres.
#[derive(Clone, Copy, Debug)]
pub(super) struct SphereHits<B: Lanes> {
    /// Lanes with a hit.
    pub found: Mask16,
    /// The hit's `t` in `found` (rounded to `f32`), else the ray's `t_max`.
    pub t: F32x16<B>,
    /// First octahedral coordinate (meaningful in `found`, without `ANY`).
    pub b1: F32x16<B>,
    /// Second octahedral coordinate.
    pub b2: F32x16<B>,
    /// The object hit (meaningful in `found`).
    pub object: U32x16<B>,
}

impl Accel {
    /// The closest hits (with `ANY`, the first) of the rays of `lanes` on
    /// the listed spheres, each ray within `[t_min, t_max]`.
    #[inline(always)]
    pub(super) fn listed_hits16<const ANY: bool, B: Lanes>(
        &self,
        rays: &RayLanes<B>,
        lanes: Mask16,
    ) -> SphereHits<B> {
        let k = rays.k;
        let zero = F32x16::splat(k, 0.0);
        let mut out = SphereHits {
            found: Mask16::NONE,
            t: rays.t_max,
            b1: zero,
            b2: zero,
            object: U32x16::splat(k, 0),
        };
        let mut todo = lanes;
        for &index in &self.listed {
            let instance = &self.instances[index as usize];
            let Some(placement) = &instance.placement else {
                continue;
            };
            let tested = todo.and_not(misses(&placement.sphere, rays));
            if !tested.any() {
                continue;
            }
            let hit = in_lanes::<ANY, _>(k, placement, rays, tested, out.t);
            let Some(hit) = hit else {
                continue;
            };
            let m = hit.found;
            out.found = out.found | m;
            out.t = F32x16::select(m, hit.t, out.t);
            out.object = U32x16::select(m, U32x16::splat(k, instance.object), out.object);
            out.b1 = F32x16::select(m, hit.b1, out.b1);
            out.b2 = F32x16::select(m, hit.b2, out.b2);
            if ANY {
                todo = todo.and_not(m);
            }
        }
        out
    }
}

/// A sphere's hits: in lanes of `found`, `t` (rounded to `f32`) and the
/// octahedral coordinates (zero with `ANY`).
#[derive(Clone, Copy, Debug)]
pub(super) struct Hits<B: Lanes> {
    pub found: Mask16,
    pub t: F32x16<B>,
    pub b1: F32x16<B>,
    pub b2: F32x16<B>,
}

/// The hits of the rays of `lanes` (each ending at `t_max`) on the sphere
/// placed by `placement`, in `f64` lanes; `None` without any.
#[inline(always)]
pub(super) fn in_lanes<const ANY: bool, B: Lanes>(
    k: B,
    placement: &Placement,
    rays: &RayLanes<B>,
    lanes: Mask16,
    t_max: F32x16<B>,
) -> Option<Hits<B>> {
    let to_object = &placement.object_from_world;
    let o = widen(transform_point(k, to_object, rays.origin));
    let d = widen(transform_vector(k, to_object, rays.dir));
    let (found, t) = intersect(k, o, d, rays.test.t_min.to_f64(), t_max.to_f64(), lanes)?;
    let zero = F32x16::splat(k, 0.0);
    let [b1, b2] = if ANY {
        [zero, zero]
    } else {
        let p = [o[0] + d[0] * t, o[1] + d[1] * t, o[2] + d[2] * t];
        let [b1, b2] = local_coords(k, p);
        [b1.to_f32(), b2.to_f32()]
    };
    Some(Hits {
        found,
        t: t.to_f32(),
        b1,
        b2,
    })
}

/// [`MissTest::misses`] per lane: the lanes whose line surely misses.
#[inline(always)]
pub(super) fn misses<B: Lanes>(test: &MissTest, rays: &RayLanes<B>) -> Mask16 {
    let k = rays.k;
    let center = Vec3x16::splat(k, test.center.into());
    let oc = center - rays.origin;
    let a = rays.dir.length_squared();
    let h = oc.dot(rays.dir);
    let oc2 = oc.length_squared();
    let far = oc2 * a - h * h;
    let bound = a * (F32x16::splat(k, test.r2) + F32x16::splat(k, test.k) * oc2);
    far.gt(bound) & far.lt(F32x16::splat(k, f32::INFINITY))
}

/// The lanes of `v` widened to `f64`.
#[inline(always)]
fn widen<B: Lanes>(v: Vec3x16<B>) -> Vec3d<B> {
    [v.x.to_f64(), v.y.to_f64(), v.z.to_f64()]
}

/// `(x·x' + y·y') + z·z'` per lane (glam's `DVec3::dot`).
#[inline(always)]
fn dot<B: Lanes>(p: &Vec3d<B>, q: &Vec3d<B>) -> F64x16<B> {
    p[0] * q[0] + p[1] * q[1] + p[2] * q[2]
}

/// [`sphere::intersect`](crate::sphere::intersect) per lane of `lanes`: the
/// lanes with a root in `[t_min, t_max]` and that root; `None` when no lane
/// has one.
#[inline(always)]
fn intersect<B: Lanes>(
    k: B,
    o: Vec3d<B>,
    d: Vec3d<B>,
    t_min: F64x16<B>,
    t_max: F64x16<B>,
    lanes: Mask16,
) -> Option<(Mask16, F64x16<B>)> {
    let a = dot(&d, &d);
    let h = -dot(&o, &d);
    let m: Vec3d<B> = [
        o[0] * a + d[0] * h,
        o[1] * a + d[1] * h,
        o[2] * a + d[2] * h,
    ];
    let a_disc = a * a - dot(&m, &m);
    let (zero, one) = (F64x16::splat(k, 0.0), F64x16::splat(k, 1.0));
    let ok = lanes & a_disc.ge(zero) & a.gt(zero);
    if !ok.any() {
        return None;
    }
    let inv_a = one / a;
    let disc = a_disc * inv_a;
    let q = h + disc.sqrt().copysign(h);
    let c = dot(&o, &o) - one;
    let (r0, r1) = (c / q, q * inv_a);
    let order = r0.le(r1);
    let near = F64x16::select(order, r0, r1);
    let far = F64x16::select(order, r1, r0);
    let near_in = t_min.le(near) & near.le(t_max);
    let far_in = t_min.le(far) & far.le(t_max);
    let hit = ok & (near_in | far_in);
    if !hit.any() {
        return None;
    }
    Some((hit, F64x16::select(near_in, near, far)))
}

/// [`sphere::local_coords`](crate::sphere::local_coords) per lane: the
/// octahedral coordinates of the direction of `p`.
#[inline(always)]
fn local_coords<B: Lanes>(k: B, p: Vec3d<B>) -> [F64x16<B>; 2] {
    let one = F64x16::splat(k, 1.0);
    let s = p[0].abs() + p[1].abs() + p[2].abs();
    let q = [p[0] / s, p[1] / s, p[2] / s];
    let upper = q[2].ge(F64x16::splat(k, 0.0));
    let folded = [
        (one - q[1].abs()).copysign(q[0]),
        (one - q[0].abs()).copysign(q[1]),
    ];
    [
        F64x16::select(upper, q[0], folded[0]),
        F64x16::select(upper, q[1], folded[1]),
    ]
}
