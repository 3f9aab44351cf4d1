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
//! `t` is in units of the world ray's direction as for instances. Each
//! triangle's world-space shading data (module `shading`) is kept beside it,
//! so a static hit's shading point needs no transform.
//!
//! Built with obvhs `fast_build` (PLOC with a wider search and more
//! reinsertion than the per-mesh `very_fast_build`), then converted to the
//! traversal layout of module `flat`: large and small
//! triangles mix here, and on `scenes/caustic-box.toml` (six wall rectangles,
//! a light rectangle and a 5120-triangle sphere) it visits 1.93 nodes per ray
//! instead of 2.48, 4 % fewer instructions per sample (callgrind); `medium`
//! and `slow` do no better, `very_slow` 0.5 % better at twice the build time.
//!
//! No parameters.

use glam::{DMat3, Vec3A};
use obvhs::BvhBuildParams;

use super::blas::SlotTriangles;
use super::flat::FlatBvh;
use super::shading::ShadingTriangle;
use super::triangle::PackedTriangle;
#[cfg(target_arch = "x86_64")]
use super::wide::World16;
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
    /// The BVH; its triangle ids index `refs`.
    pub bvh: FlatBvh,
    /// The source of each input triangle.
    refs: Vec<TriangleRef>,
    /// The shading data of each input triangle (same indices as `refs`).
    shading: Vec<ShadingTriangle>,
    /// Input triangles left out (degenerate or singular placement).
    pub left_out: usize,
    /// The tables of the sixteen-ray walks and shading points (module
    /// `wide`).
    #[cfg(target_arch = "x86_64")]
    pub wide: World16,
}

impl WorldBlas {
    /// Builds the BVH of the world-space triangles of `members`; `None` when
    /// none of them has a hittable triangle.
    pub fn build(objects: &[Object], members: &[ObjectId]) -> Option<Self> {
        let mut refs = Vec::new();
        let mut shading = Vec::new();
        let mut world = Vec::new();
        let mut inputs = 0;
        for &id in members {
            let object = &objects[id as usize];
            let mesh = &object.mesh;
            let normal_from_object: DMat3 = object.world_from_object.matrix3.inverse().transpose();
            inputs += mesh.len();
            for triangle in 0..mesh.len() as u32 {
                let local = mesh.triangle(triangle);
                if PackedTriangle::new(local.map(Vec3A::from)).is_none() {
                    continue;
                }
                let placed = local.map(|p| object.world_from_object.transform_point3(p.as_dvec3()));
                world.push((refs.len() as u32, placed.map(|p| Vec3A::from(p.as_vec3()))));
                shading.push(ShadingTriangle::new(
                    object,
                    &normal_from_object,
                    triangle,
                    placed,
                ));
                refs.push(TriangleRef {
                    object: id,
                    triangle,
                });
            }
        }
        let built = SlotTriangles::build(world.into_iter(), BvhBuildParams::fast_build())?;
        let bvh = FlatBvh::new(&built);
        let left_out = inputs - bvh.len();
        Some(Self {
            #[cfg(target_arch = "x86_64")]
            wide: World16::new(&bvh, &refs, &shading),
            bvh,
            refs,
            shading,
            left_out,
        })
    }

    /// The source of the triangle with table index `index` (a hit's id).
    #[inline(always)]
    pub fn source(&self, index: u32) -> TriangleRef {
        self.refs[index as usize]
    }

    /// The shading data of the triangle with table index `index`, if that
    /// entry is `triangle` of `object` (a hit from before a rebuild, or from
    /// another BVH, finds nothing).
    #[inline(always)]
    pub fn shading(&self, index: u32, object: ObjectId, triangle: u32) -> Option<&ShadingTriangle> {
        let source = self.refs.get(index as usize)?;
        (source.object == object && source.triangle == triangle)
            .then(|| self.shading.get(index as usize))
            .flatten()
    }

    /// Approximate heap size in bytes.
    pub fn bytes(&self) -> usize {
        #[cfg(target_arch = "x86_64")]
        let wide = self.wide.bytes();
        #[cfg(not(target_arch = "x86_64"))]
        let wide = 0;
        wide + self.bvh.bytes()
            + self.refs.len() * size_of::<TriangleRef>()
            + self.shading.len() * size_of::<ShadingTriangle>()
    }
}
