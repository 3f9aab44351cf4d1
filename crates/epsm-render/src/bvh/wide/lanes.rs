//! The wide functions' per-lane fallbacks: the scalar code itself, lane by
//! lane, where lanes would mostly idle or the case is rare: a subtree of
//! the static BVH that few of a packet's rays enter (module `walk`), the
//! top level's instances, and shading points off the static tables.
//!
//! Model: each lane's ray (or hit) is handed, as plain values, to the
//! scalar function the wide one stands for (`FlatBvh::trace_from`,
//! `Accel::trace_instances`, `Accel::surface_point`), so its result is the
//! scalar one by construction. They run compiled for
//! the CPU level the caller's token proves ([`Lanes::run`]), so the scalar
//! walks' AVX box and packet tests inline as in the tracer's AVX2 build.
//!
//! No parameters.

use glam::{Vec2, Vec3, Vec3A};

use super::super::box_test::BoxTest;
use super::super::flat::{FlatBvh, FlatHit};
use super::super::node::TraceRay;
use super::super::{Accel, Found, NO_WORLD_INDEX};
use super::Rays16;
use crate::frame::Frame;
use crate::hit::{Hit, SurfacePoint, TexCoords};
use crate::ray::Ray;
use crate::scene::Object;
use crate::simd::{LANES, Lanes, Mask16};

/// The scalar walk of the subtree under `node` of `flat` for each lane of
/// `lanes`, its ray `rays.lane(i)` ending at `t_max[i]`: the lane's hit there.
#[inline(never)]
pub(super) fn subtrees<const ANY: bool, B: Lanes>(
    k: B,
    flat: &FlatBvh,
    node: usize,
    lanes: Mask16,
    rays: &PlainRays,
    t_max: &[f32; LANES],
) -> [Option<FlatHit>; LANES] {
    k.run(
        #[inline(always)]
        || {
            let boxes = k.boxes();
            let mut hits = [None; LANES];
            for lane in lanes.lanes() {
                let ray = rays.lane(lane);
                let (origin, dir) = (Vec3A::from(ray.origin), Vec3A::from(ray.dir));
                let mut walk = TraceRay::for_walk::<ANY>(origin, dir, ray.t_min, t_max[lane]);
                hits[lane] = flat.trace_from::<ANY>(node, &mut walk, boxes);
            }
            hits
        },
    )
}

impl Accel {
    /// The scalar top-level walk per lane: for each `(active, ray, best)`
    /// with `active`, the trace's hit from its best hit so far on; `None`
    /// for the others.
    #[inline(never)]
    pub(super) fn instances_per_lane<const ANY: bool, B: Lanes>(
        &self,
        k: B,
        lanes: &[(bool, Ray, Option<Hit>); LANES],
    ) -> [Option<Hit>; LANES] {
        k.run(
            #[inline(always)]
            || {
                let boxes = k.boxes();
                let mut hits = [None; LANES];
                for (hit, &(active, ray, best)) in hits.iter_mut().zip(lanes) {
                    if active {
                        *hit = self.instances_of_lane::<ANY>(&ray, best, boxes);
                    }
                }
                hits
            },
        )
    }

    /// The scalar trace's end for `ray` from its best hit so far `best`.
    #[inline(always)]
    fn instances_of_lane<const ANY: bool>(
        &self,
        ray: &Ray,
        best: Option<Hit>,
        boxes: impl BoxTest,
    ) -> Option<Hit> {
        let t_max = best.map_or(ray.t_max, |h| h.t);
        let (origin, dir) = (Vec3A::from(ray.origin), Vec3A::from(ray.dir));
        let mut world = TraceRay::for_walk::<ANY>(origin, dir, ray.t_min, t_max);
        let found = match best {
            None => Found::Nothing,
            Some(h) if h.world_index == NO_WORLD_INDEX => Found::Instance(h.object),
            Some(_) => self.world.as_deref().map_or(Found::Nothing, Found::World),
        };
        let flat = best.map(|h| FlatHit {
            id: if h.world_index == NO_WORLD_INDEX {
                h.triangle
            } else {
                h.world_index
            },
            t: h.t,
            b1: h.b1,
            b2: h.b2,
        });
        self.trace_instances::<ANY>(&mut world, found, flat, boxes)
    }

    /// [`Accel::surface_point`] of each hit (a placeholder point for
    /// `None`).
    #[inline(never)]
    pub(super) fn points_per_lane<B: Lanes>(
        &self,
        k: B,
        objects: &[Object],
        hits: &[Option<Hit>; LANES],
    ) -> [SurfacePoint; LANES] {
        k.run(
            #[inline(always)]
            || {
                hits.map(|hit| match hit {
                    Some(hit) => self.surface_point(objects, &hit),
                    None => SurfacePoint {
                        p: Vec3::ZERO,
                        ng: Vec3::Z,
                        uv: TexCoords::Uv(Vec2::ZERO),
                        frame: Frame::from_normal(Vec3::Z),
                    },
                })
            },
        )
    }
}

/// Sixteen rays as plain arrays by field (stored once), from which the
/// per-lane fallbacks read the rays of the lanes they walk.
#[derive(Clone, Copy, Debug)]
pub(super) struct PlainRays {
    origin: [[f32; LANES]; 3],
    dir: [[f32; LANES]; 3],
    t_min: [f32; LANES],
    t_max: [f32; LANES],
}

impl PlainRays {
    /// The arrays of `rays`.
    #[inline(always)]
    pub fn new<B: Lanes>(rays: &Rays16<B>) -> Self {
        let (o, d) = (&rays.origin, &rays.dir);
        Self {
            origin: [o.x.to_array(), o.y.to_array(), o.z.to_array()],
            dir: [d.x.to_array(), d.y.to_array(), d.z.to_array()],
            t_min: rays.t_min.to_array(),
            t_max: rays.t_max.to_array(),
        }
    }

    /// Lane `i`'s ray.
    #[inline(always)]
    pub fn lane(&self, i: usize) -> Ray {
        let (o, d) = (&self.origin, &self.dir);
        Ray {
            origin: Vec3::new(o[0][i], o[1][i], o[2][i]),
            dir: Vec3::new(d[0][i], d[1][i], d[2][i]),
            t_min: self.t_min[i],
            t_max: self.t_max[i],
        }
    }
}
