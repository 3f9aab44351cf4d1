//! Bottom level: a compressed wide BVH (CWBVH, obvhs) over triangles (one
//! per instanced mesh in object space, and one over the static objects in
//! world space), with the triangles packed for intersection and reordered by
//! the BVH's `primitive_indices` so a leaf slot indexes them directly.
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
use obvhs::cwbvh::builder::build_cwbvh_from_tris;
use obvhs::triangle::Triangle;

use super::node::{BoxTest, TraceRay, WideBvh};
use super::triangle::PackedTriangle;
use super::walk::walk;
use crate::scene::Mesh;

/// The closest hit found so far in one bottom-level BVH.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct SlotHit {
    /// Leaf slot of the triangle (index into the packed triangles).
    pub slot: u32,
    /// Barycentric `b1`.
    pub b1: f32,
    /// Barycentric `b2`.
    pub b2: f32,
}

/// A BVH over packed triangles, each tagged with a caller-chosen id.
#[derive(Clone, Debug)]
pub(crate) struct Blas {
    bvh: WideBvh,
    triangles: Vec<PackedTriangle>,
    ids: Vec<u32>,
    /// Bounds of the hittable triangles.
    pub bounds: Aabb,
}

impl Blas {
    /// Builds the object-space BVH of `mesh` (obvhs `very_fast_build`),
    /// ids = the mesh's triangle indices; `None` when it has no hittable
    /// triangle.
    pub fn build(mesh: &Mesh) -> Option<Self> {
        Self::from_triangles(
            (0..mesh.len() as u32).map(|tri| (tri, mesh.triangle(tri).map(Vec3A::from))),
            BvhBuildParams::very_fast_build(),
        )
    }

    /// Builds the BVH of `(id, vertices)` triangles with `params`, leaving
    /// out those [`PackedTriangle::new`] rejects; `None` when none is left.
    pub fn from_triangles(
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
        let triangles: Vec<PackedTriangle> = bvh
            .primitive_indices
            .iter()
            .map(|&i| packed[i as usize])
            .collect();
        let ids = bvh
            .primitive_indices
            .iter()
            .map(|&i| ids[i as usize])
            .collect();
        let bounds = tris.iter().fold(Aabb::empty(), |b, t| b.union(&t.aabb()));
        let bvh = WideBvh::new(&bvh, |slot| triangles[slot as usize].aabb());
        Some(Self {
            bvh,
            triangles,
            ids,
            bounds,
        })
    }

    /// Number of hittable triangles.
    pub fn len(&self) -> usize {
        self.ids.len()
    }

    /// The id of the triangle in a leaf slot.
    #[inline(always)]
    pub fn id(&self, slot: u32) -> u32 {
        self.ids[slot as usize]
    }

    /// Approximate heap size in bytes.
    pub fn bytes(&self) -> usize {
        self.bvh.bytes() + self.triangles.len() * size_of::<PackedTriangle>() + self.ids.len() * 4
    }

    /// Traces the object-space `ray`, box tests by `boxes`. Without `ANY`,
    /// lowers `ray.t_max` to each closer hit and records it in `best`; with
    /// `ANY`, stops at the first hit. Returns whether anything was hit.
    #[inline(always)]
    pub fn trace<const ANY: bool>(
        &self,
        ray: &mut TraceRay,
        boxes: impl BoxTest,
        best: &mut SlotHit,
    ) -> bool {
        let mut found = false;
        walk(&self.bvh, ray, boxes, |slot, ray| {
            let Some(hit) = self.triangles[slot as usize]
                .intersect(ray.origin, &ray.shear, ray.t_min, ray.t_max)
            else {
                return false;
            };
            found = true;
            ray.t_max = hit.t;
            *best = SlotHit {
                slot,
                b1: hit.b1,
                b2: hit.b2,
            };
            ANY
        });
        found
    }
}
