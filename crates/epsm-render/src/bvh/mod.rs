//! Two-level BVH over the scene's objects (obvhs CWBVH at both levels).
//!
//! One bottom-level BVH per distinct mesh (objects sharing an `Arc<Mesh>`
//! share it), built in object space; one top-level BVH over the instances'
//! world boxes. A ray is traced into an instance by mapping it to object space
//! with the cached `f32` `object_from_world` *without* normalising the
//! direction, so the ray parameter `t` is the same at both levels and in
//! [`Hit::t`]. Moving one object ([`Accel::update_instance`]) re-reads its
//! transform and rebuilds only the top level. Objects with empty meshes (or
//! only zero-area triangles) and objects with singular transforms are never
//! hit.
//!
//! No parameters.

mod blas;
mod node;
mod tlas;
mod triangle;

use std::collections::HashMap;
use std::fmt;
use std::sync::Arc;
use std::time::Instant;

use glam::{DVec3, UVec2, Vec3A};
use obvhs::cwbvh::Traversal;

use crate::hit::{self, Hit, SurfacePoint};
use crate::ray::Ray;
use crate::scene::{Mesh, Object, ObjectId};
use blas::{Blas, SlotHit};
use node::TraceRay;
use tlas::{Instance, Tlas};

/// Marks an object without an instance.
const NO_INSTANCE: u32 = u32::MAX;

/// Size and build cost of an [`Accel`].
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct AccelStats {
    /// Objects with an instance (non-empty mesh).
    pub objects: usize,
    /// Bottom-level BVHs (distinct non-empty meshes).
    pub blas_count: usize,
    /// Hittable triangles summed over the bottom levels (shared meshes once).
    pub triangles: usize,
    /// Triangles left out for zero area or non-finite vertices.
    pub degenerate_triangles: usize,
    /// Time of the whole build, seconds.
    pub build_seconds: f64,
    /// Time of the last top-level build, seconds.
    pub tlas_seconds: f64,
    /// Approximate heap size, bytes.
    pub bytes: usize,
}

/// Per-mesh BVHs and a top level over their instances. Cloning is cheap in
/// the bottom levels (shared, immutable); `Debug` prints the statistics only.
#[derive(Clone, Default)]
pub struct Accel {
    blases: Vec<Arc<Blas>>,
    instances: Vec<Instance>,
    instance_of_object: Vec<u32>,
    tlas: Tlas,
    stats: AccelStats,
}

impl fmt::Debug for Accel {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("Accel")
            .field("stats", &self.stats)
            .finish_non_exhaustive()
    }
}

impl Accel {
    /// Builds one BVH per distinct mesh and the top level.
    pub fn build(objects: &[Object]) -> Self {
        let start = Instant::now();
        let mut accel = Self {
            instance_of_object: vec![NO_INSTANCE; objects.len()],
            ..Self::default()
        };
        let mut blas_of_mesh: HashMap<*const Mesh, Option<u32>> = HashMap::new();
        let mut all = 0;
        for (id, object) in objects.iter().enumerate() {
            let blases = &mut accel.blases;
            let all = &mut all;
            let blas = *blas_of_mesh
                .entry(Arc::as_ptr(&object.mesh))
                .or_insert_with(|| {
                    *all += object.mesh.len();
                    let built = Blas::build(&object.mesh)?;
                    blases.push(Arc::new(built));
                    Some(blases.len() as u32 - 1)
                });
            if let Some(blas) = blas {
                let local = &accel.blases[blas as usize].bounds;
                accel.instance_of_object[id] = accel.instances.len() as u32;
                accel.instances.push(Instance::new(
                    id as ObjectId,
                    blas,
                    local,
                    &object.world_from_object,
                ));
            }
        }
        let hittable: usize = accel.blases.iter().map(|b| b.len()).sum();
        accel.stats.degenerate_triangles = all - hittable;
        accel.rebuild_tlas();
        accel.stats.build_seconds = start.elapsed().as_secs_f64();
        accel
    }

    /// Re-reads object `id`'s transform and rebuilds the top level (no
    /// bottom-level BVH is touched). Ids without an instance are ignored. The
    /// object's mesh must be the one the BVH was built with.
    pub fn update_instance(&mut self, objects: &[Object], id: ObjectId) {
        self.update_instances(objects, &[id]);
    }

    /// [`Accel::update_instance`] for several objects with one top-level
    /// rebuild (moving many objects at once costs one rebuild, not one each).
    pub fn update_instances(&mut self, objects: &[Object], ids: &[ObjectId]) {
        for &id in ids {
            let Some(&index) = self.instance_of_object.get(id as usize) else {
                continue;
            };
            if let Some(instance) = self.instances.get_mut(index as usize) {
                let local = &self.blases[instance.blas as usize].bounds;
                instance.place(local, &objects[id as usize].world_from_object);
            }
        }
        self.rebuild_tlas();
    }

    fn rebuild_tlas(&mut self) {
        let start = Instant::now();
        self.tlas = Tlas::build(&self.instances);
        self.stats.tlas_seconds = start.elapsed().as_secs_f64();
        self.stats.objects = self.instances.len();
        self.stats.blas_count = self.blases.len();
        self.stats.triangles = self.blases.iter().map(|b| b.len()).sum();
        self.stats.bytes = self.blases.iter().map(|b| b.bytes()).sum::<usize>()
            + self.tlas.bytes()
            + self.instances.len() * size_of::<Instance>()
            + self.instance_of_object.len() * 4;
    }

    /// Size and timings.
    pub fn stats(&self) -> AccelStats {
        self.stats
    }

    /// The closest hit with `t` in `[ray.t_min, ray.t_max]`.
    pub fn closest_hit(&self, ray: &Ray) -> Option<Hit> {
        self.trace::<false>(ray)
    }

    /// Whether anything lies within `[ray.t_min, ray.t_max]` (stops at the
    /// first hit found).
    pub fn occluded(&self, ray: &Ray) -> bool {
        self.trace::<true>(ray).is_some()
    }

    /// Traces `ray` through both levels: the closest hit, or with `ANY` the
    /// first hit found (whose barycentrics are then meaningless).
    #[inline(always)]
    fn trace<const ANY: bool>(&self, ray: &Ray) -> Option<Hit> {
        if self.tlas.slots.is_empty() {
            return None;
        }
        let mut world = TraceRay::new(
            Vec3A::from(ray.origin),
            Vec3A::from(ray.dir),
            ray.t_min,
            ray.t_max,
        );
        let mut best = SlotHit::default();
        let mut best_instance = NO_INSTANCE;
        let mut state = self.tlas.bvh.traversal(&world);
        let mut blas_state = Traversal::default();
        let mut node;
        obvhs::traverse!(self.tlas.bvh, node, state, node.intersect(&world), {
            let index = self.tlas.slots[state.primitive_id as usize];
            let instance = &self.instances[index as usize];
            if let Some(placement) = &instance.placement {
                let to_object = &placement.object_from_world;
                let mut local = TraceRay::new(
                    to_object.transform_point3a(world.origin),
                    to_object.transform_vector3a(world.dir),
                    world.t_min,
                    world.t_max,
                );
                if self.blases[instance.blas as usize].trace::<ANY>(
                    &mut local,
                    &mut blas_state,
                    &mut best,
                ) {
                    if ANY {
                        return Some(self.hit(index, best, local.t_max));
                    }
                    world.t_max = local.t_max;
                    best_instance = index;
                }
            }
        });
        (best_instance != NO_INSTANCE).then(|| self.hit(best_instance, best, world.t_max))
    }

    /// The [`Hit`] of a bottom-level hit in instance `index` at `t`.
    #[inline(always)]
    fn hit(&self, index: u32, best: SlotHit, t: f32) -> Hit {
        let instance = &self.instances[index as usize];
        Hit {
            object: instance.object,
            triangle: self.blases[instance.blas as usize].triangle_id(best.slot),
            b1: best.b1,
            b2: best.b2,
            t,
        }
    }

    /// The shading point of `hit` (unit normals, world space), from the
    /// cached `f32` transform of the hit object.
    pub fn surface_point(&self, objects: &[Object], hit: &Hit) -> SurfacePoint {
        let object = &objects[hit.object as usize];
        let index = self.instance_of_object[hit.object as usize];
        let cached = self.instances.get(index as usize).and_then(|i| i.placement);
        let placement = cached
            .or_else(|| hit::Placement::new(&object.world_from_object))
            .unwrap_or(hit::Placement::IDENTITY);
        hit::surface_point(&object.mesh, &placement, hit.triangle, hit.b1, hit.b2)
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
