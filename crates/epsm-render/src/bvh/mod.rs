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
//! object space is tested against the unit sphere ([`crate::sphere`]). A scene with
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
//! a few instances one after another with their bottom-level BVHs walked as
//! packets, many lane by lane by the scalar code), with the scalar walks'
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
mod box_test;
mod cwbvh;
mod flat;
mod node;
mod packet;
mod shading;
#[cfg(test)]
mod test_support;
#[cfg(test)]
mod tests;
mod tlas;
mod trace;
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
use crate::scene::{Mesh, Object, ObjectId, Surface};
use blas::Blas;
#[cfg(target_arch = "x86_64")]
pub(crate) use box_test::{Avx, Avx2};
pub(crate) use box_test::{BoxTest, Portable, SpheresFirst};
use tlas::{Instance, Tlas, Traced};
use triangle::PackedTriangle;
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

/// Object-space bounds of the hittable triangles of `mesh` (empty without).
fn mesh_bounds(mesh: &Mesh) -> Aabb {
    (0..mesh.len() as u32)
        .filter_map(|tri| PackedTriangle::new(mesh.triangle(tri).map(Vec3A::from)))
        .fold(Aabb::empty(), |b, t| b.union(&t.aabb()))
}
