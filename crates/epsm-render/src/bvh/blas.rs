//! Bottom level: a compressed wide BVH (CWBVH) built by obvhs over triangles
//! (one per instanced mesh in object space, and one over the static objects
//! in world space), with the triangles reordered by the BVH's
//! `primitive_indices` so a leaf slot indexes them directly, then converted
//! to the traversal layout of module `flat`.
//!
//! Model: PLOC build with light reinsertion, collapsed to an 8-wide BVH with
//! at most three triangles per leaf (obvhs `BvhBuildParams::very_fast_build`).
//! Instructions per ray (callgrind) against the other presets: on the
//! bench's bumpy sphere `very_fast` 322 M per 200 k rays, `fastest` 327 M,
//! `medium` 338 M, `fast` 339 M, `slow` without spatial splits 349 M (`slow`
//! with them: 3 % more than `medium`, and twice its build time); on a mixed
//! scene (a sphere, a 5000-triangle random soup and a height field)
//! `very_fast` 1.4 % fewer than `medium`, with fewer cache misses. The more
//! thorough presets optimise the binary tree's SAH, which the 8-wide collapse
//! does not preserve.
//!
//! Triangles with zero `f32` area or a non-finite vertex are left out of the
//! tree (they could never be hit) and counted.
//!
//! No parameters.

use std::time::Duration;

use glam::Vec3A;
use obvhs::BvhBuildParams;
use obvhs::aabb::Aabb;
use obvhs::cwbvh::CwBvh;
use obvhs::cwbvh::builder::build_cwbvh_from_tris;
use obvhs::triangle::Triangle;

use super::box_test::BoxTest;
use super::flat::{FlatBvh, FlatHit};
use super::node::TraceRay;
use super::triangle::PackedTriangle;
#[cfg(target_arch = "x86_64")]
use super::wide::Blas16;
use crate::scene::Mesh;

/// An obvhs CWBVH over packed triangles, the triangles and their ids in leaf
/// slot order (reordered by the BVH's `primitive_indices`).
pub(crate) struct SlotTriangles {
    /// The BVH; leaf slots index `triangles` and `ids`.
    pub bvh: CwBvh,
    /// The triangles by slot.
    pub triangles: Vec<PackedTriangle>,
    /// The caller's id of each slot's triangle.
    pub ids: Vec<u32>,
    /// Bounds of the triangles.
    pub bounds: Aabb,
}

impl SlotTriangles {
    /// Builds the BVH of `(id, vertices)` triangles with `params`, leaving
    /// out those [`PackedTriangle::new`] rejects; `None` when none is left.
    pub fn build(
        triangles: impl Iterator<Item = (u32, [Vec3A; 3])>,
        params: BvhBuildParams,
    ) -> Option<Self> {
        let mut packed = Vec::new();
        let mut ids = Vec::new();
        let mut tris = Vec::new();
        for (id, [v0, v1, v2]) in triangles {
            if let Some(p) = PackedTriangle::new([v0, v1, v2]) {
                packed.push(p);
                ids.push(id);
                tris.push(Triangle { v0, v1, v2 });
            }
        }
        if packed.is_empty() {
            return None;
        }
        let bvh = build_cwbvh_from_tris(&tris, params, &mut Duration::default());
        let by_slot = |i: &u32| (packed[*i as usize], ids[*i as usize]);
        let (triangles, ids) = bvh.primitive_indices.iter().map(by_slot).unzip();
        let bounds = tris.iter().fold(Aabb::empty(), |b, t| b.union(&t.aabb()));
        Some(Self {
            bvh,
            triangles,
            ids,
            bounds,
        })
    }
}

/// A BVH over packed triangles, each tagged with a caller-chosen id, in the
/// traversal layout of module `flat`.
#[derive(Clone, Debug)]
pub(crate) struct Blas {
    /// The BVH; triangle ids are the mesh's triangle indices.
    pub(super) bvh: FlatBvh,
    /// Bounds of the hittable triangles.
    pub bounds: Aabb,
    /// The tables of the sixteen-ray walks (module `wide`).
    #[cfg(target_arch = "x86_64")]
    pub(super) wide: Blas16,
}

impl Blas {
    /// Builds the object-space BVH of `mesh` (obvhs `very_fast_build`),
    /// ids = the mesh's triangle indices; `None` when it has no hittable
    /// triangle.
    pub fn build(mesh: &Mesh) -> Option<Self> {
        let built = SlotTriangles::build(
            (0..mesh.len() as u32).map(|tri| (tri, mesh.triangle(tri).map(Vec3A::from))),
            BvhBuildParams::very_fast_build(),
        )?;
        let bvh = FlatBvh::new(&built);
        Some(Self {
            #[cfg(target_arch = "x86_64")]
            wide: Blas16::new(&bvh),
            bvh,
            bounds: built.bounds,
        })
    }

    /// Number of hittable triangles.
    pub fn len(&self) -> usize {
        self.bvh.len()
    }

    /// Approximate heap size in bytes.
    pub fn bytes(&self) -> usize {
        #[cfg(target_arch = "x86_64")]
        let wide = self.wide.bytes();
        #[cfg(not(target_arch = "x86_64"))]
        let wide = 0;
        wide + self.bvh.bytes()
    }

    /// Traces the object-space `ray`, box tests by `boxes` (see
    /// [`FlatBvh::trace`]); the hit's id is the mesh's triangle index.
    #[inline(always)]
    pub fn trace<const ANY: bool>(
        &self,
        ray: &mut TraceRay,
        boxes: impl BoxTest,
    ) -> Option<FlatHit> {
        self.bvh.trace::<ANY>(ray, boxes)
    }
}
