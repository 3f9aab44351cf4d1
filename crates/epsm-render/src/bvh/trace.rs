//! Tracing one ray through an [`Accel`]: the static BVH's walk, the listed
//! exact spheres and the instances behind the top level, each compiled for
//! the box tests the CPU has; the hit of the nearest bottom level.

use glam::{DVec3, Vec3A};

#[cfg(target_arch = "x86_64")]
use super::box_test::Avx2;
use super::box_test::{BoxTest, Portable, SpheresFirst};
use super::flat::FlatHit;
use super::node::TraceRay;
use super::tlas::Traced;
use super::walk::walk;
use super::{Accel, Found, NO_WORLD_INDEX};
use crate::hit::{self, Hit};
use crate::ray::Ray;
use crate::scene::ObjectId;
use crate::sphere;

impl Accel {
    /// The closest hit with `t` in `[ray.t_min, ray.t_max]`, walked with the
    /// code the renderer's tile loop uses (compiled for AVX2 where the CPU
    /// has it, detected at run time), so a benchmark of these calls times
    /// the render's walks.
    #[inline(always)]
    pub fn closest_hit(&self, ray: &Ray) -> Option<Hit> {
        self.trace_detected::<false>(ray)
    }

    /// Whether anything lies within `[ray.t_min, ray.t_max]` (stops at the
    /// first hit found).
    #[inline(always)]
    pub fn occluded(&self, ray: &Ray) -> bool {
        self.trace_detected::<true>(ray).is_some()
    }

    /// [`Accel::closest_hit`] with box tests by `boxes` (the tracer passes
    /// the widest its CPU has once per tile).
    #[inline(always)]
    pub(crate) fn closest_hit_with(&self, ray: &Ray, boxes: impl BoxTest) -> Option<Hit> {
        self.trace::<false>(ray, boxes)
    }

    /// [`Accel::occluded`] with box tests by `boxes`.
    #[inline(always)]
    pub(crate) fn occluded_with(&self, ray: &Ray, boxes: impl BoxTest) -> bool {
        self.trace::<true>(ray, boxes).is_some()
    }

    /// Whether the scene has listed exact spheres: its tile loop is then
    /// compiled [`SpheresFirst`].
    #[inline(always)]
    pub(crate) fn lists_spheres(&self) -> bool {
        !self.listed.is_empty()
    }

    /// [`Accel::trace`] compiled as the tracer's tile loop is: for AVX2 with
    /// AVX box tests where the CPU has them ([`Avx2`]), else portable, and
    /// [`SpheresFirst`] when the scene lists spheres.
    #[inline(always)]
    fn trace_detected<const ANY: bool>(&self, ray: &Ray) -> Option<Hit> {
        #[cfg(target_arch = "x86_64")]
        if let Some(avx2) = Avx2::detect() {
            return if self.lists_spheres() {
                self.trace_avx2::<ANY>(ray, avx2, SpheresFirst(avx2.boxes()))
            } else {
                self.trace_avx2::<ANY>(ray, avx2, avx2.boxes())
            };
        }
        if self.lists_spheres() {
            self.trace::<ANY>(ray, SpheresFirst(Portable))
        } else {
            self.trace::<ANY>(ray, Portable)
        }
    }

    /// [`Accel::trace`] with `boxes`, compiled with the CPU features of
    /// [`Avx2`] (as the tile loop), so the AVX box tests inline and the
    /// walk's bit scans are single instructions (`_avx2` proves the CPU has
    /// them).
    #[cfg(target_arch = "x86_64")]
    #[allow(unsafe_code)]
    fn trace_avx2<const ANY: bool>(
        &self,
        ray: &Ray,
        _avx2: Avx2,
        boxes: impl BoxTest,
    ) -> Option<Hit> {
        #[target_feature(enable = "avx2,bmi1,bmi2,lzcnt,popcnt")]
        fn with_avx2<const ANY: bool>(
            accel: &Accel,
            ray: &Ray,
            boxes: impl BoxTest,
        ) -> Option<Hit> {
            accel.trace::<ANY>(ray, boxes)
        }
        // SAFETY: `with_avx2` requires only the features it enables, and an
        // `Avx2` token exists only on a CPU found to have each of them.
        unsafe { with_avx2::<ANY>(self, ray, boxes) }
    }

    /// Traces `ray` through the listed spheres (when `boxes` is
    /// [`SpheresFirst`]), the static BVH, the listed spheres (otherwise) and
    /// then the top level: the closest hit, or with `ANY` the first hit found
    /// (whose barycentrics are then meaningless).
    #[inline(always)]
    pub(super) fn trace<const ANY: bool>(&self, ray: &Ray, boxes: impl BoxTest) -> Option<Hit> {
        let mut world = TraceRay::for_walk::<ANY>(
            Vec3A::from(ray.origin),
            Vec3A::from(ray.dir),
            ray.t_min,
            ray.t_max,
        );
        let mut best = None;
        let mut found = Found::Nothing;
        let first = if boxes.spheres_first() && !self.listed.is_empty() {
            self.listed_hit::<ANY>(world.origin, world.dir, world.t_min, world.t_max)
        } else {
            None
        };
        if ANY && let Some((object, flat)) = first {
            return hit(Found::Instance(object), Some(flat));
        }
        if let Some(statics) = self.world.as_deref()
            && let Some(flat) = statics.bvh.trace::<ANY>(&mut world, boxes)
        {
            found = Found::World(statics);
            best = Some(flat);
            if ANY || self.static_only {
                return hit(found, best);
            }
        }
        if self.static_only {
            return None;
        }
        // A sphere wins a tie with a triangle, whichever went first.
        let listed = if boxes.spheres_first() {
            first.filter(|(_, flat)| flat.t <= world.t_max)
        } else if self.listed.is_empty() {
            None
        } else {
            self.listed_hit_outlined::<ANY>(world.origin, world.dir, world.t_min, world.t_max)
        };
        if let Some((object, flat)) = listed {
            found = Found::Instance(object);
            best = Some(flat);
            world.t_max = flat.t;
            if ANY {
                return hit(found, best);
            }
        }
        self.trace_instances::<ANY>(&mut world, found, best, boxes)
    }

    /// The end of [`Accel::trace`]: the top level's instances walked by
    /// `world` (its `t_max` lowered to the best hit so far, `best` in
    /// `found`), and the [`Hit`] of the best hit then.
    #[inline(always)]
    pub(super) fn trace_instances<const ANY: bool>(
        &self,
        world: &mut TraceRay,
        mut found: Found<'_>,
        mut best: Option<FlatHit>,
        boxes: impl BoxTest,
    ) -> Option<Hit> {
        if self.tlas.slots.is_empty() {
            return hit(found, best);
        }
        walk(
            &self.tlas.bvh,
            world,
            boxes,
            #[inline(always)]
            |slot, world| {
                let index = self.tlas.slots[slot as usize];
                let instance = &self.instances[index as usize];
                let Some(placement) = &instance.placement else {
                    return false;
                };
                let flat = match instance.traced {
                    Traced::Blas(blas) => {
                        let to_object = &placement.object_from_world;
                        let mut local = TraceRay::for_walk::<ANY>(
                            to_object.transform_point3a(world.origin),
                            to_object.transform_vector3a(world.dir),
                            world.t_min,
                            world.t_max,
                        );
                        self.blases[blas as usize].trace::<ANY>(&mut local, boxes)
                    }
                    Traced::Sphere => placed_sphere_hit::<ANY>(
                        placement,
                        world.origin,
                        world.dir,
                        world.t_min,
                        world.t_max,
                    ),
                    Traced::World | Traced::Listed => None,
                };
                let Some(flat) = flat else {
                    return false;
                };
                found = Found::Instance(instance.object);
                best = Some(flat);
                world.t_max = flat.t;
                ANY
            },
        );
        hit(found, best)
    }

    /// [`Accel::listed_hit`] out of line, after the static BVH's walk (for
    /// walks not compiled [`SpheresFirst`]): inlined, it made the tile loop
    /// of scenes without spheres 1.7 % more instructions (callgrind).
    #[inline(never)]
    fn listed_hit_outlined<const ANY: bool>(
        &self,
        origin: Vec3A,
        dir: Vec3A,
        t_min: f32,
        t_max: f32,
    ) -> Option<(ObjectId, FlatHit)> {
        self.listed_hit::<ANY>(origin, dir, t_min, t_max)
    }

    /// The closest hit of the world-space ray `origin + t·dir`, `t` in
    /// `[t_min, t_max]`, on the listed exact spheres (with `ANY`, the first
    /// found).
    #[inline(always)]
    fn listed_hit<const ANY: bool>(
        &self,
        origin: Vec3A,
        dir: Vec3A,
        t_min: f32,
        mut t_max: f32,
    ) -> Option<(ObjectId, FlatHit)> {
        let mut best = None;
        for &index in &self.listed {
            let instance = &self.instances[index as usize];
            if let Some(placement) = &instance.placement
                && let Some(flat) = placed_sphere_hit::<ANY>(placement, origin, dir, t_min, t_max)
            {
                t_max = flat.t;
                best = Some((instance.object, flat));
                if ANY {
                    break;
                }
            }
        }
        best
    }
}

/// The [`Hit`] of bottom-level hit `best` in `found`.
#[inline(always)]
fn hit(found: Found<'_>, best: Option<FlatHit>) -> Option<Hit> {
    let best = best?;
    let (object, triangle, world_index) = match found {
        Found::Nothing => return None,
        Found::World(world) => {
            let source = world.source(best.id);
            (source.object, source.triangle, best.id)
        }
        Found::Instance(object) => (object, best.id, NO_WORLD_INDEX),
    };
    Some(Hit {
        object,
        triangle,
        b1: best.b1,
        b2: best.b2,
        t: best.t,
        world_index,
    })
}

/// The hit of the world-space ray `origin + t·dir` on the exact unit sphere
/// placed by `placement`, with `t` in `[t_min, t_max]` (mapped to object
/// space in `f32`, solved in `f64`, unless the placement's world-space
/// [`sphere::MissTest`] rules it out first), its local coordinates octahedral
/// ([`sphere`]; with `ANY`, which asks only whether there is a hit, zero).
#[inline(always)]
fn placed_sphere_hit<const ANY: bool>(
    placement: &hit::Placement,
    origin: Vec3A,
    dir: Vec3A,
    t_min: f32,
    t_max: f32,
) -> Option<FlatHit> {
    if placement.sphere.misses(origin, dir) {
        return None;
    }
    let (o, d, t) = exact_sphere_hit(placement, origin, dir, t_min, t_max)?;
    let [b1, b2] = if ANY {
        [0.0; 2]
    } else {
        sphere::local_coords(o + d * t)
    };
    Some(FlatHit {
        id: 0,
        t: t as f32,
        b1: b1 as f32,
        b2: b2 as f32,
    })
}

/// The ray `origin + t·dir` mapped to the object space of the unit sphere
/// placed by `placement` (in `f32`, then widened) and its first `t` in
/// `[t_min, t_max]` there (solved in `f64`), without the miss test.
#[inline(always)]
pub(super) fn exact_sphere_hit(
    placement: &hit::Placement,
    origin: Vec3A,
    dir: Vec3A,
    t_min: f32,
    t_max: f32,
) -> Option<(DVec3, DVec3, f64)> {
    let to_object = &placement.object_from_world;
    let o = to_object.transform_point3a(origin).as_dvec3();
    let d = to_object.transform_vector3a(dir).as_dvec3();
    let t = sphere::intersect(o, d, f64::from(t_min), f64::from(t_max))?;
    Some((o, d, t))
}
