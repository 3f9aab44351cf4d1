//! The static part of the scene: the triangles of every object that is not
//! traced as an instance, transformed to world space and put into one
//! bottom-level BVH, so a ray walks no top level and transforms nothing to
//! reach them.
//!
//! Model: vertices are transformed in `f64` and rounded to `f32` once (the
//! same world triangles the area lights sample). A triangle is left out when
//! it is degenerate in object space or in world space, or when its object's
//! transform is singular. Barycentrics are invariant under affine maps, so a
//! hit reports the same `(b1, b2)` (to rounding) as an instance would, and
//! `t` is in units of the world ray's direction as for instances.
//!
//! Measured on `scenes/caustic-box.toml` (6 wall rectangles, a light
//! rectangle and a 5120-triangle sphere; release, 1 thread, CPU time):
//! see `docs/performance.md`.
//!
//! No parameters.

use glam::Vec3A;

use super::blas::Blas;
use super::triangle::PackedTriangle;
use crate::scene::{Object, ObjectId};

/// Where a triangle of the static BVH comes from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct TriangleRef {
    /// The object.
    pub object: ObjectId,
    /// Triangle index in its mesh.
    pub triangle: u32,
}

/// The static objects' world-space triangles and their BVH.
#[derive(Clone, Debug)]
pub(crate) struct WorldBlas {
    /// The BVH; slot ids index `refs`.
    pub blas: Blas,
    /// The source of each input triangle.
    refs: Vec<TriangleRef>,
    /// Input triangles left out (degenerate or singular placement).
    pub left_out: usize,
}

impl WorldBlas {
    /// Builds the BVH of the world-space triangles of `members`; `None` when
    /// none of them has a hittable triangle.
    pub fn build(objects: &[Object], members: &[ObjectId]) -> Option<Self> {
        let mut refs = Vec::new();
        let mut world = Vec::new();
        let mut inputs = 0;
        for &id in members {
            let object = &objects[id as usize];
            let mesh = &object.mesh;
            inputs += mesh.len();
            for triangle in 0..mesh.len() as u32 {
                let local = mesh.triangle(triangle);
                if PackedTriangle::new(local.map(Vec3A::from)).is_none() {
                    continue;
                }
                let placed = local.map(|p| {
                    Vec3A::from(
                        object
                            .world_from_object
                            .transform_point3(p.as_dvec3())
                            .as_vec3(),
                    )
                });
                world.push((refs.len() as u32, placed));
                refs.push(TriangleRef {
                    object: id,
                    triangle,
                });
            }
        }
        let blas = Blas::from_triangles(world.into_iter())?;
        let left_out = inputs - blas.len();
        Some(Self {
            blas,
            refs,
            left_out,
        })
    }

    /// The source of the triangle in leaf slot `slot`.
    #[inline(always)]
    pub fn source(&self, slot: u32) -> TriangleRef {
        self.refs[self.blas.id(slot) as usize]
    }

    /// Approximate heap size in bytes.
    pub fn bytes(&self) -> usize {
        self.blas.bytes() + self.refs.len() * size_of::<TriangleRef>()
    }
}
