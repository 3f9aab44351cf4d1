//! Two-level BVH over the scene's objects (obvhs).

use glam::DVec3;

use crate::hit::{Hit, SurfacePoint};
use crate::ray::Ray;
use crate::scene::{Object, ObjectId};

/// Per-object BVHs and a top level over their instances.
#[derive(Clone, Debug, Default)]
pub struct Accel {
    _todo: (),
}

impl Accel {
    /// Builds one BVH per object and the top level.
    pub fn build(objects: &[Object]) -> Self {
        let _ = objects;
        Self::default()
    }
    /// Re-reads object `id`'s transform and refits the top level.
    pub fn update_instance(&mut self, objects: &[Object], id: ObjectId) {
        let _ = (objects, id);
    }
    /// The closest hit within `[ray.t_min, ray.t_max]`.
    pub fn closest_hit(&self, ray: &Ray) -> Option<Hit> {
        let _ = ray;
        unimplemented!("bvh: implemented on the bvh branch")
    }
    /// Whether anything lies within `[ray.t_min, ray.t_max]`.
    pub fn occluded(&self, ray: &Ray) -> bool {
        let _ = ray;
        unimplemented!("bvh: implemented on the bvh branch")
    }
    /// The surface point of a hit.
    pub fn surface_point(&self, objects: &[Object], hit: &Hit) -> SurfacePoint {
        let _ = (objects, hit);
        unimplemented!("bvh: implemented on the bvh branch")
    }
    /// World-space bounds of all geometry.
    pub fn world_bounds(&self) -> Option<(DVec3, DVec3)> {
        None
    }
}
