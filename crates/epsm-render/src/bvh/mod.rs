//! Two-level BVH over the scene's objects (obvhs CWBVH at both levels, built
//! by obvhs): every bottom-level BVH (the static one and each instanced
//! mesh's) converted to our own traversal layout (module `flat`), the top
//! level walked in obvhs's layout by our own loop (module `walk`).
//!
//! Static objects (all objects not made dynamic, except copies of a large
//! shared mesh) are traced through one bottom-level BVH over their
//! world-space triangles (module `world`), with no top level and no transform.
//! Dynamic objects and instanced large meshes get one bottom-level BVH per
//! distinct mesh (objects sharing an `Arc<Mesh>` share it), built in object
//! space, behind a top-level BVH over their world boxes. A ray is traced into
//! an instance by mapping it to object space with the cached `f32`
//! `object_from_world` *without* normalising the direction, so the ray
//! parameter `t` is the same at both levels and in [`Hit::t`].
//!
//! Exact spheres ([`Surface::Sphere`]) have no bottom level: a ray mapped to
//! object space is tested against the unit sphere ([`sphere`]). A scene with
//! at most `MAX_LISTED_SPHERES` of them lists them and tests each one
//! directly: the tracer's tile loop for such a scene is compiled to test
//! them inline before the static BVH's walk, independent of it
//! (`SpheresFirst`); other walks test them out of line after it, so the
//! code of scenes without spheres carries nothing of theirs. More spheres
//! stand behind the top level like any instance.
//!
//! Many rays at once ([`Accel::closest_hits`], [`Accel::occluded_rays`],
//! [`Accel::surface_points`], module `batch`) are traced sixteen at a time
//! where the CPU has AVX-512 or AVX2 (module `wide`: the static BVH walked as a
//! packet from tables built beside it, the listed spheres in `f64` lanes,
//! instances lane by lane by the scalar code), with the scalar walks'
//! answers (but for ties, module `wide`).
//!
//! Moving an object ([`Accel::update_instance`]) re-reads its transform and
//! rebuilds only the top level; the first move of a static object makes it
//! dynamic, which rebuilds the static BVH once without it
//! ([`Accel::update_instances`] on the objects that will move, before
//! moving them, does that up front). Mesh objects with empty meshes (or
//! only zero-area triangles) and objects with singular transforms are never
//! hit.
//!
//! | constant | value | meaning |
//! |---|---|---|
//! | `MAX_MERGED_SHARED` | 1024 | a static object whose mesh other objects share is merged into the static BVH only up to this many triangles |
//! | `MAX_LISTED_SPHERES` | 2 | a scene with at most this many exact spheres tests each directly, without the top level |
//!
//! No parameters.

mod batch;
mod blas;
mod flat;
mod node;
mod packet;
mod shading;
#[cfg(test)]
mod test_support;
mod tlas;
mod triangle;
mod walk;
#[cfg(target_arch = "x86_64")]
mod wide;
mod world;

use std::collections::HashMap;
use std::fmt;
use std::sync::Arc;
use std::time::Instant;

use glam::{DVec3, Vec3A};
use obvhs::aabb::Aabb;

use crate::hit::{self, Hit, SurfacePoint};
use crate::ray::Ray;
use crate::scene::{Mesh, Object, ObjectId, Surface};
use crate::sphere;
use blas::Blas;
use flat::FlatHit;
use node::TraceRay;
#[cfg(target_arch = "x86_64")]
pub(crate) use node::{Avx, Avx2};
pub(crate) use node::{BoxTest, Portable, SpheresFirst};
use tlas::{Instance, Tlas, Traced};
use triangle::PackedTriangle;
use walk::walk;
#[cfg(target_arch = "x86_64")]
pub(crate) use wide::{Frames16, Hits16, Rays16, TexCoords16};
use world::WorldBlas;

/// Marks an object without an instance.
const NO_INSTANCE: u32 = u32::MAX;

/// [`Hit::world_index`] of a hit on an instance.
const NO_WORLD_INDEX: u32 = u32::MAX;

/// Scenes with at most this many exact spheres test each of them directly
/// (before or after the static BVH's walk) instead of walking them through
/// the top level. Measured on the Cornell box with 1–8 spheres of radius
/// 0.22 on its floor (`epsm bench render`, 128 spp): listed, one sphere
/// renders 6–8 % faster than through the top level, two the same, three
/// and more slower (8 spheres 20–25 %).
const MAX_LISTED_SPHERES: usize = 2;

/// Copies of a shared mesh with more triangles than this stay instanced
/// (merging them would copy the mesh once per object).
const MAX_MERGED_SHARED: usize = 1024;

/// Size and build cost of an [`Accel`].
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct AccelStats {
    /// Objects with an instance (non-empty mesh).
    pub objects: usize,
    /// Bottom-level BVHs (distinct instanced meshes, plus the static one).
    pub blas_count: usize,
    /// Hittable triangles summed over the bottom levels (instanced meshes
    /// once, static objects once each).
    pub triangles: usize,
    /// Triangles left out for zero area or non-finite vertices.
    pub degenerate_triangles: usize,
    /// Exact spheres ([`Surface::Sphere`] objects with an instance).
    pub spheres: usize,
    /// Time of the whole build, seconds.
    pub build_seconds: f64,
    /// Time of the last top-level build, seconds.
    pub tlas_seconds: f64,
    /// Time of the last build of the static BVH, seconds.
    pub static_seconds: f64,
    /// Approximate heap size, bytes.
    pub bytes: usize,
}

/// The static world-space BVH, per-mesh BVHs and a top level over their
/// instances. Cloning is cheap in the BVHs (shared, immutable); `Debug`
/// prints the statistics only.
#[derive(Clone, Default)]
pub struct Accel {
    world: Option<Arc<WorldBlas>>,
    blases: Vec<Arc<Blas>>,
    instances: Vec<Instance>,
    instance_of_object: Vec<u32>,
    /// Instances of the exact spheres tested one by one beside the static
    /// BVH's walk (all of them while there are at most [`MAX_LISTED_SPHERES`]).
    listed: Vec<u32>,
    tlas: Tlas,
    /// No listed spheres and an empty top level: a trace ends after the
    /// static BVH (one flag, read after its walk).
    static_only: bool,
    stats: AccelStats,
}

impl fmt::Debug for Accel {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("Accel")
            .field("stats", &self.stats)
            .finish_non_exhaustive()
    }
}

/// The BVH a trace's best hit so far lies in.
#[derive(Clone, Copy, Debug)]
enum Found<'a> {
    /// No hit yet.
    Nothing,
    /// The static BVH.
    World(&'a WorldBlas),
    /// The BVH of an instance of this object.
    Instance(ObjectId),
}

impl Accel {
    /// Builds the acceleration structure with every object static (see
    /// [`Accel::build_with_dynamic`]).
    pub fn build(objects: &[Object]) -> Self {
        Self::build_with_dynamic(objects, &[])
    }

    /// Builds the static world-space BVH, one BVH per distinct instanced
    /// mesh and the top level; objects `dynamic` are instanced (moving them
    /// rebuilds only the top level).
    pub fn build_with_dynamic(objects: &[Object], dynamic: &[ObjectId]) -> Self {
        let start = Instant::now();
        let mut accel = Self {
            instance_of_object: vec![NO_INSTANCE; objects.len()],
            ..Self::default()
        };
        let mut users: HashMap<*const Mesh, usize> = HashMap::new();
        for object in objects {
            *users.entry(Arc::as_ptr(&object.mesh)).or_default() += 1;
        }
        let spheres = objects
            .iter()
            .filter(|o| o.surface == Surface::Sphere)
            .count();
        let sphere = if spheres <= MAX_LISTED_SPHERES {
            Traced::Listed
        } else {
            Traced::Sphere
        };
        for (id, object) in objects.iter().enumerate() {
            let shared_large =
                users[&Arc::as_ptr(&object.mesh)] > 1 && object.mesh.len() > MAX_MERGED_SHARED;
            let placed = if object.surface == Surface::Sphere {
                Some((sphere, Aabb::new(Vec3A::NEG_ONE, Vec3A::ONE)))
            } else if shared_large || dynamic.contains(&(id as ObjectId)) {
                accel.blas_of(objects, id as ObjectId)
            } else {
                let local = mesh_bounds(&object.mesh);
                (local.min.cmple(local.max).all()).then_some((Traced::World, local))
            };
            if let Some((traced, local)) = placed {
                accel.instance_of_object[id] = accel.instances.len() as u32;
                if traced == Traced::Listed {
                    accel.listed.push(accel.instances.len() as u32);
                }
                accel.instances.push(Instance::new(
                    id as ObjectId,
                    traced,
                    local,
                    &object.world_from_object,
                ));
            }
        }
        accel.rebuild_world(objects);
        accel.rebuild_tlas();
        accel.stats.build_seconds = start.elapsed().as_secs_f64();
        accel
    }

    /// The bottom-level BVH of object `id`'s mesh (built unless an instance
    /// already has it) and its bounds; `None` without hittable triangles.
    fn blas_of(&mut self, objects: &[Object], id: ObjectId) -> Option<(Traced, Aabb)> {
        let mesh = &objects[id as usize].mesh;
        let existing = self.instances.iter().find_map(|i| match i.traced {
            Traced::Blas(b) if Arc::ptr_eq(&objects[i.object as usize].mesh, mesh) => Some(b),
            _ => None,
        });
        let index = match existing {
            Some(b) => b,
            None => {
                self.blases.push(Arc::new(Blas::build(mesh)?));
                self.blases.len() as u32 - 1
            }
        };
        Some((Traced::Blas(index), self.blases[index as usize].bounds))
    }

    /// Re-reads object `id`'s transform and rebuilds the top level (no
    /// bottom-level BVH is touched once the object is dynamic). Ids without
    /// an instance are ignored. The object's mesh must be the one the BVH was
    /// built with.
    pub fn update_instance(&mut self, objects: &[Object], id: ObjectId) {
        self.update_instances(objects, &[id]);
    }

    /// [`Accel::update_instance`] for several objects with one top-level
    /// rebuild (moving many objects at once costs one rebuild, not one each).
    /// Static objects among `ids` become dynamic: the static BVH is rebuilt
    /// once without them.
    pub fn update_instances(&mut self, objects: &[Object], ids: &[ObjectId]) {
        let mut world_changed = false;
        for &id in ids {
            let Some(&index) = self.instance_of_object.get(id as usize) else {
                continue;
            };
            let Some(traced) = self.instances.get(index as usize).map(|i| i.traced) else {
                continue;
            };
            if traced == Traced::World
                && let Some((traced, local)) = self.blas_of(objects, id)
            {
                let instance = &mut self.instances[index as usize];
                (instance.traced, instance.local) = (traced, local);
                world_changed = true;
            }
            self.instances[index as usize].place(&objects[id as usize].world_from_object);
        }
        if world_changed {
            self.rebuild_world(objects);
        }
        self.rebuild_tlas();
    }

    fn rebuild_world(&mut self, objects: &[Object]) {
        let start = Instant::now();
        let members: Vec<ObjectId> = self
            .instances
            .iter()
            .filter(|i| i.traced == Traced::World && i.placement.is_some())
            .map(|i| i.object)
            .collect();
        self.world = WorldBlas::build(objects, &members).map(Arc::new);
        self.stats.static_seconds = start.elapsed().as_secs_f64();
        let mut degenerate = self.world.as_ref().map_or(0, |w| w.left_out);
        let mut counted: Vec<u32> = Vec::new();
        for instance in &self.instances {
            if let Traced::Blas(b) = instance.traced
                && !counted.contains(&b)
            {
                counted.push(b);
                let mesh = &objects[instance.object as usize].mesh;
                degenerate += mesh.len() - self.blases[b as usize].len();
            }
        }
        self.stats.degenerate_triangles = degenerate;
    }

    fn rebuild_tlas(&mut self) {
        let start = Instant::now();
        self.tlas = Tlas::build(&self.instances);
        self.static_only = self.tlas.slots.is_empty() && self.listed.is_empty();
        self.stats.tlas_seconds = start.elapsed().as_secs_f64();
        let world = self.world.as_deref();
        self.stats.objects = self.instances.len();
        self.stats.spheres = self
            .instances
            .iter()
            .filter(|i| matches!(i.traced, Traced::Listed | Traced::Sphere))
            .count();
        self.stats.blas_count = self.blases.len() + usize::from(world.is_some());
        self.stats.triangles =
            self.blases.iter().map(|b| b.len()).sum::<usize>() + world.map_or(0, |w| w.bvh.len());
        self.stats.bytes = self.blases.iter().map(|b| b.bytes()).sum::<usize>()
            + world.map_or(0, WorldBlas::bytes)
            + self.tlas.bytes()
            + self.instances.len() * size_of::<Instance>()
            + self.instance_of_object.len() * 4;
    }

    /// Size and timings.
    pub fn stats(&self) -> AccelStats {
        self.stats
    }

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
    fn trace<const ANY: bool>(&self, ray: &Ray, boxes: impl BoxTest) -> Option<Hit> {
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
    fn trace_instances<const ANY: bool>(
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

    /// The shading point of `hit` (unit normals, world space): from the
    /// static BVH's shading table for static geometry, else from the cached
    /// `f32` transform of the hit object.
    #[inline(always)]
    pub fn surface_point(&self, objects: &[Object], hit: &Hit) -> SurfacePoint {
        if let Some(tri) = self
            .world
            .as_deref()
            .and_then(|w| w.shading(hit.world_index, hit.object, hit.triangle))
        {
            return tri.point(hit.b1, hit.b2);
        }
        let object = &objects[hit.object as usize];
        let cached = self
            .instance_of_object
            .get(hit.object as usize)
            .and_then(|&index| self.instances.get(index as usize))
            .and_then(|i| i.placement.as_ref());
        let computed;
        let placement = match cached {
            Some(placement) => placement,
            None => {
                computed = hit::Placement::new(&object.world_from_object)
                    .unwrap_or(hit::Placement::IDENTITY);
                &computed
            }
        };
        match object.surface {
            Surface::Mesh => {
                hit::surface_point(&object.mesh, placement, hit.triangle, hit.b1, hit.b2)
            }
            Surface::Sphere => hit::sphere_point(placement, hit.b1, hit.b2),
        }
    }

    /// World-space bounds of all placed geometry (`None` without any).
    pub fn world_bounds(&self) -> Option<(DVec3, DVec3)> {
        self.instances
            .iter()
            .filter(|i| i.placement.is_some())
            .map(|i| (i.bounds[0], i.bounds[1]))
            .reduce(|a, b| (a.0.min(b.0), a.1.max(b.1)))
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
fn exact_sphere_hit(
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

/// Object-space bounds of the hittable triangles of `mesh` (empty without).
fn mesh_bounds(mesh: &Mesh) -> Aabb {
    (0..mesh.len() as u32)
        .filter_map(|tri| PackedTriangle::new(mesh.triangle(tri).map(Vec3A::from)))
        .fold(Aabb::empty(), |b, t| b.union(&t.aabb()))
}

#[cfg(test)]
mod tests {
    use super::*;
    #[cfg(target_arch = "x86_64")]
    use crate::bvh::node::Avx;
    use epsm_testkit::Rng;
    use glam::{DAffine3, DQuat};

    /// A triangle soup of `count` triangles in `[-1, 1]³`.
    fn soup(rng: &mut Rng, count: usize) -> Arc<Mesh> {
        let mut mesh = Mesh::default();
        for _ in 0..count {
            let a = rng.dvec3(-1.0, 1.0).as_vec3();
            let base = mesh.positions.len() as u32;
            mesh.positions.extend([
                a,
                a + rng.dvec3(-0.4, 0.4).as_vec3(),
                a + rng.dvec3(-0.4, 0.4).as_vec3(),
            ]);
            mesh.indices.push([base, base + 1, base + 2]);
        }
        Arc::new(mesh)
    }

    /// An object of `mesh` (empty for a sphere) and `surface`, scaled by
    /// `scale`, then rotated about a random axis and moved into `[-2, 2]³`.
    fn placed(rng: &mut Rng, mesh: Arc<Mesh>, surface: Surface, scale: DVec3) -> Object {
        Object {
            name: "placed".into(),
            mesh,
            world_from_object: DAffine3::from_scale_rotation_translation(
                scale,
                DQuat::from_axis_angle(rng.unit(), rng.range(0.0, 6.0)),
                rng.dvec3(-2.0, 2.0),
            ),
            material: 0,
            emission: None,
            surface,
        }
    }

    /// Listed spheres tested first ([`SpheresFirst`]) or after the static
    /// walk give the same closest hit and the same occlusion, with portable
    /// and (when the CPU has it) AVX tests, on scenes with static and
    /// dynamic meshes and spheres, one of them mirrored.
    #[test]
    fn spheres_first_and_after_find_the_same_hits() {
        let mut rng = Rng::new(23);
        let (big, small) = (soup(&mut rng, 2000), soup(&mut rng, 40));
        let mut objects: Vec<Object> = (0..4)
            .map(|i| {
                let mesh = Arc::clone(if i % 2 == 0 { &big } else { &small });
                let scale = rng.dvec3(0.3, 1.5);
                placed(&mut rng, mesh, Surface::Mesh, scale)
            })
            .collect();
        for i in 0..MAX_LISTED_SPHERES {
            let mut scale = rng.dvec3(0.7, 1.5);
            if i == 1 {
                scale.y = -scale.y;
            }
            let sphere = placed(&mut rng, Arc::default(), Surface::Sphere, scale);
            objects.push(sphere);
        }
        let first = SpheresFirst(Portable);
        #[cfg(target_arch = "x86_64")]
        let avx = Avx::detect().map(|avx| (avx, SpheresFirst(avx)));
        for dynamic in [&[][..], &[1, 5]] {
            let accel = Accel::build_with_dynamic(&objects, dynamic);
            assert!(accel.lists_spheres());
            let mut on_spheres = 0;
            for i in 0..20_000 {
                let origin = rng.dvec3(-4.0, 4.0).as_vec3();
                let mut ray = Ray::new(origin, rng.unit().as_vec3() * rng.range(0.5, 2.0) as f32);
                if i % 3 == 0 {
                    ray.t_max = rng.range(0.0, 4.0) as f32;
                }
                let after = accel.trace::<false>(&ray, Portable);
                let occluded = accel.trace::<true>(&ray, Portable).is_some();
                assert_eq!(accel.trace::<false>(&ray, first), after, "ray {i}: {ray:?}");
                assert_eq!(accel.trace::<true>(&ray, first).is_some(), occluded);
                assert_eq!(occluded, after.is_some());
                #[cfg(target_arch = "x86_64")]
                if let Some((avx, avx_first)) = avx {
                    assert_eq!(accel.trace::<false>(&ray, avx), after, "ray {i}");
                    assert_eq!(accel.trace::<false>(&ray, avx_first), after, "ray {i}");
                    assert_eq!(accel.trace::<true>(&ray, avx).is_some(), occluded);
                    assert_eq!(accel.trace::<true>(&ray, avx_first).is_some(), occluded);
                }
                on_spheres += usize::from(after.is_some_and(|h| h.object >= 4));
            }
            assert!(on_spheres > 500, "{on_spheres} sphere hits");
        }
    }

    /// The AVX box tests (when the CPU has AVX) find exactly the hits of the
    /// portable ones, through the static BVH and through instances.
    #[test]
    fn avx_and_portable_box_tests_agree() {
        // Without AVX, the portable tests against themselves: the walk's
        // hit counts are still checked.
        #[cfg(target_arch = "x86_64")]
        match Avx::detect() {
            Some(avx) => box_tests_agree(avx),
            None => box_tests_agree(Portable),
        }
        #[cfg(not(target_arch = "x86_64"))]
        box_tests_agree(Portable);
    }

    /// [`avx_and_portable_box_tests_agree`] with the box tests `avx`.
    fn box_tests_agree(avx: impl BoxTest) {
        let mut rng = Rng::new(17);
        let (big, small) = (soup(&mut rng, 3000), soup(&mut rng, 50));
        let objects: Vec<Object> = (0..6)
            .map(|i| {
                let mesh = Arc::clone(if i % 2 == 0 { &big } else { &small });
                let scale = rng.dvec3(0.3, 2.0);
                placed(&mut rng, mesh, Surface::Mesh, scale)
            })
            .collect();
        let accel = Accel::build_with_dynamic(&objects, &[1, 4]);
        let (mut hits, mut occluded) = (0, 0);
        for i in 0..20_000 {
            let origin = rng.dvec3(-4.0, 4.0).as_vec3();
            let mut dir = rng.unit().as_vec3();
            if i % 5 == 0 {
                dir[rng.below(3)] = 0.0;
            }
            let mut ray = Ray::new(origin, dir * rng.range(0.5, 2.0) as f32);
            if i % 3 == 0 {
                ray.t_max = rng.range(0.0, 4.0) as f32;
            }
            let portable = accel.trace::<false>(&ray, Portable);
            assert_eq!(
                accel.trace::<false>(&ray, avx),
                portable,
                "ray {i}: {ray:?}"
            );
            let any = accel.trace::<true>(&ray, Portable).is_some();
            assert_eq!(accel.trace::<true>(&ray, avx).is_some(), any);
            assert_eq!(any, portable.is_some());
            hits += usize::from(portable.is_some());
            occluded += usize::from(any);
        }
        assert!(hits > 2000 && occluded == hits, "{hits} hits");
    }

    /// A random placement of the unit sphere: a rotation, a scale (uniform,
    /// 0.003 to 10, or per axis up to 25 : 1 with some axes mirrored) and a
    /// translation of up to `reach` per axis.
    fn sphere_placement(rng: &mut Rng, uniform: bool, reach: f64) -> DAffine3 {
        let scale = if uniform {
            DVec3::splat(10f64.powf(rng.range(-2.5, 1.0)))
        } else {
            rng.dvec3(0.2, 5.0) * DVec3::new(1.0, if rng.below(3) == 0 { -1.0 } else { 1.0 }, 1.0)
        };
        DAffine3::from_scale_rotation_translation(
            scale,
            DQuat::from_axis_angle(rng.unit(), rng.range(0.0, 6.3)),
            rng.dvec3(-reach, reach),
        )
    }

    /// A world-space ray whose line passes at object-space distance
    /// `1 + gap` from the centre of the sphere placed by `w`, its origin
    /// `back` units (object space) before the closest point, and its
    /// direction of random length.
    fn ray_at_distance(rng: &mut Rng, w: &DAffine3, gap: f64, back: f64) -> (Vec3A, Vec3A) {
        let q = rng.unit();
        let u = q.cross(rng.unit()).normalize();
        let origin = w.transform_point3(q * (1.0 + gap) - u * back);
        let dir = w.transform_vector3(u) * rng.range(0.1, 10.0);
        (origin.as_vec3a(), dir.as_vec3a())
    }

    /// The miss test of a placed sphere never rejects a ray the exact test
    /// (the ray mapped to object space in `f32`, solved in `f64`) hits:
    /// rays grazing the surface (in or out by 10⁻⁸ to 1 % of the radius,
    /// where the `f32` mapping decides) from near and far (up to 10⁴
    /// object-space units), on uniform and skewed, mirrored placements up to
    /// 10³ from the origin, and random rays.
    #[test]
    fn sphere_miss_test_never_rejects_a_hit() {
        let mut rng = Rng::new(41);
        let (mut grazing_hits, mut rejected) = (0, 0);
        for i in 0..400 {
            let w = sphere_placement(&mut rng, i % 2 == 0, if i % 4 < 2 { 1e3 } else { 2.0 });
            let placement = hit::Placement::new(&w).expect("invertible");
            for j in 0..200 {
                let (origin, dir) = if j % 4 == 0 {
                    let origin = w.translation + rng.dvec3(-8.0, 8.0) * w.matrix3.x_axis.length();
                    (origin.as_vec3a(), rng.unit().as_vec3a())
                } else {
                    let sign = if rng.below(2) == 0 { -1.0 } else { 1.0 };
                    let gap = sign * 10f64.powf(rng.range(-8.0, -2.0));
                    let back = 10f64.powf(rng.range(-1.0, 4.0));
                    ray_at_distance(&mut rng, &w, gap, back)
                };
                let exact = exact_sphere_hit(&placement, origin, dir, 0.0, f32::INFINITY).is_some();
                let misses = placement.sphere.misses(origin, dir);
                assert!(!(exact && misses), "{w:?}: {origin} {dir}");
                grazing_hits += usize::from(exact && j % 4 != 0);
                rejected += usize::from(misses);
            }
        }
        assert!(
            grazing_hits > 10_000 && rejected > 5_000,
            "{grazing_hits} grazing hits, {rejected} rejected"
        );
    }

    /// On rotated, uniformly scaled spheres near the origin (within 1 per
    /// axis), the miss test
    /// rejects every ray that passes 1 % of the radius or more outside,
    /// from up to ten radii away; the identity's test is
    /// [`MissTest::UNIT`](sphere::MissTest::UNIT).
    #[test]
    fn sphere_miss_test_rejects_clear_misses() {
        let mut rng = Rng::new(43);
        for _ in 0..200 {
            let w = sphere_placement(&mut rng, true, 1.0);
            let placement = hit::Placement::new(&w).expect("invertible");
            for _ in 0..200 {
                let (gap, back) = (10f64.powf(rng.range(-2.0, 1.0)), rng.range(0.0, 10.0));
                let (origin, dir) = ray_at_distance(&mut rng, &w, gap, back);
                assert!(
                    placement.sphere.misses(origin, dir),
                    "{w:?}: {origin} {dir}"
                );
            }
        }
        assert_eq!(
            sphere::MissTest::new(&DAffine3::IDENTITY),
            sphere::MissTest::UNIT
        );
    }
}
