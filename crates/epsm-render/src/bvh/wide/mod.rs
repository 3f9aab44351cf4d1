//! Sixteen rays at a time, one per vector lane, for the wide tracer:
//! closest hits ([`Accel::closest_hits16`]), occlusion
//! ([`Accel::occluded16`]) and shading points
//! ([`Accel::surface_points16`]), each lane what the scalar function gives
//! for its ray or hit.
//!
//! Model: the scalar trace's steps with a lane per ray. The listed exact
//! spheres are tested first in `f64` lanes (module `spheres`), as the
//! tracer's `SpheresFirst` walk does, and kept aside. The static BVH is
//! walked as a packet (module `walk`, over the layout of module `tree`): at
//! each node the lanes that reached it are tested against each child box,
//! and a leaf child's triangles against the lanes that enter its box by
//! the watertight test per lane (module `triangles`), one triangle against
//! all those lanes or, where few lanes enter each leaf, each lane its own
//! list in rounds (module `leaves`), each lane keeping its own closest `t`
//! and triangle (module `closest`); a node that few lanes enter is walked
//! lane by lane by the scalar walk. A sphere then wins a lane whose static
//! hit is no closer (`t_sphere ≤ t_triangle`: the scalar rule that a listed
//! sphere wins a tie). Instances behind the top level (dynamic objects,
//! instanced large meshes, scenes with more than two exact spheres) come
//! next, each lane starting from its best hit so far, as the scalar trace
//! does after the static BVH: up to 64 one after another, a mesh's
//! bottom-level BVH walked as a packet in the mesh's object space (module
//! `instances`); more per lane by the scalar code itself
//! (`Accel::trace_instances`, module `lanes`). Occlusion runs the same steps, each
//! lane leaving at its first hit. Shading points come from tables of the
//! static triangles and from the listed spheres' placements in lanes
//! (module `points`), others per lane from the scalar code.
//!
//! Every lane's tests round exactly as the scalar ones (the same operations
//! in the same order, `f64` where the scalar code uses it), so a lane finds
//! every hit the scalar walk finds, with the same `t`, barycentrics and
//! ids. The one difference: two primitives hit at the same `t` (to within
//! the rounding of the range tests against the `t_max` a walk carries), in
//! different nodes of a BVH, as for a ray through a vertex shared by
//! triangles in two leaves, or in two instances. The scalar walk keeps
//! the one its visiting order meets last, and the packet visits nodes (and
//! instances) in its own order, so it may report the other. Within a node the scalar packet test's rule is
//! kept (so a BVH of one node, as `scenes/cornell-box.toml`'s, has no such
//! difference); occlusion has none (any hit will do), nor has a sphere
//! tying with a triangle (the sphere wins both ways). The unit tests count
//! these ties (2 of 40 k lanes in their random scenes, all on rays aimed at
//! vertices); `tests/wide.rs` bounds them on the rays of renders of the
//! shipped scenes through the batch walks (none in the Cornell box).
//!
//! The tables (module `tree`: 64 bytes per static triangle and 704 per
//! node with up to sixteen leaf triangles; module `points`: 128 bytes per
//! static triangle) are built with the static BVH (module `tree`'s also
//! with each bottom-level BVH), on x86-64 only.
//!
//! No parameters.

mod affine;
mod closest;
mod instances;
mod lanes;
mod leaves;
mod points;
mod rays;
mod spheres;
mod tree;
mod triangles;
mod values;
mod walk;

#[cfg(test)]
mod tests;

use super::Accel;
use super::NO_WORLD_INDEX;
use super::flat::FlatBvh;
use super::shading::ShadingTriangle;
use super::world::TriangleRef;
use crate::scene::Object;
use crate::simd::{F32x16, Lanes, Mask16, U32x16};
use closest::Closest16;
use points::ShadingTable;
use rays::RayLanes;
use tree::Tree16;
pub(crate) use values::{Frames16, Hits16, Rays16, SurfacePoints16, TexCoords16};
use walk::Policy;

/// The static BVH's tables for sixteen rays at a time.
#[derive(Clone, Debug)]
pub(crate) struct World16 {
    /// The packet walk's layout of the static BVH.
    tree: Tree16,
    /// Per static triangle (a hit's id): its object.
    objects: Vec<u32>,
    /// Per static triangle: its index in its object's mesh.
    triangles: Vec<u32>,
    /// Per static triangle: its shading data.
    shading: ShadingTable,
}

impl World16 {
    /// The tables of the static BVH `bvh` over the triangles `refs` with
    /// shading data `shading` (same indices).
    pub fn new(bvh: &FlatBvh, refs: &[TriangleRef], shading: &[ShadingTriangle]) -> Self {
        Self {
            tree: Tree16::new(bvh),
            objects: refs.iter().map(|r| r.object).collect(),
            triangles: refs.iter().map(|r| r.triangle).collect(),
            shading: ShadingTable::new(shading),
        }
    }

    /// Approximate heap size in bytes.
    pub fn bytes(&self) -> usize {
        self.tree.bytes() + 8 * self.objects.len() + self.shading.bytes()
    }
}

/// A bottom-level BVH's tables for sixteen rays at a time.
#[derive(Clone, Debug)]
pub(crate) struct Blas16 {
    /// The packet walk's layout of the BVH.
    tree: Tree16,
}

impl Blas16 {
    /// The tables of the bottom-level BVH `bvh`.
    pub fn new(bvh: &FlatBvh) -> Self {
        Self {
            tree: Tree16::new(bvh),
        }
    }

    /// Approximate heap size in bytes.
    pub fn bytes(&self) -> usize {
        self.tree.bytes()
    }
}

impl Accel {
    /// Lane `i` in `active`: exactly `self.closest_hit` of lane `i`'s ray
    /// (but for ties, module docs); other lanes: `found` unset.
    #[inline(always)]
    pub(crate) fn closest_hits16<B: Lanes>(
        &self,
        k: B,
        rays: &Rays16<B>,
        active: Mask16,
    ) -> Hits16<B> {
        self.closest_hits16_by(k, rays, active, Policy::MEASURED)
    }

    /// [`Accel::closest_hits16`] with the static BVH walked by `policy`.
    #[inline(always)]
    fn closest_hits16_by<B: Lanes>(
        &self,
        k: B,
        rays: &Rays16<B>,
        active: Mask16,
        policy: Policy,
    ) -> Hits16<B> {
        let lanes = RayLanes::new(k, rays);
        let spheres = if self.listed.is_empty() {
            None
        } else {
            Some(self.listed_hits16::<false, _>(&lanes, active))
        };
        let mut best = Closest16::none(&lanes);
        let (zero, none) = (U32x16::splat(k, 0), U32x16::splat(k, NO_WORLD_INDEX));
        let mut hits = Hits16::none(k, rays);
        if let Some(world) = self.world.as_deref() {
            let w = &world.wide;
            w.tree
                .walk::<false, _>(&world.bvh, &lanes, active, &mut best, policy);
            hits = Hits16 {
                found: best.found,
                object: U32x16::gather(&w.objects, best.id, best.found, zero),
                triangle: U32x16::gather(&w.triangles, best.id, best.found, zero),
                b1: best.b1,
                b2: best.b2,
                t: best.t,
                world_index: best.id,
            };
        }
        if let Some(s) = spheres {
            // A sphere wins a tie with a triangle.
            let wins = s.found & s.t.le(best.t);
            hits = Hits16 {
                found: hits.found | wins,
                object: U32x16::select(wins, s.object, hits.object),
                triangle: U32x16::select(wins, zero, hits.triangle),
                b1: F32x16::select(wins, s.b1, hits.b1),
                b2: F32x16::select(wins, s.b2, hits.b2),
                t: F32x16::select(wins, s.t, hits.t),
                world_index: U32x16::select(wins, none, hits.world_index),
            };
        }
        if !self.tlas.slots.is_empty() && active.any() {
            if self.instances_in_lanes() {
                self.instances16::<false, _>(&lanes, active, &mut hits);
            } else {
                let (rays, best) = (lanes::PlainRays::new(rays), hits.to_lanes());
                let lanes = std::array::from_fn(|i| (active.test(i), rays.lane(i), best[i]));
                hits = Hits16::from_lanes(k, &self.instances_per_lane::<false, _>(k, &lanes));
            }
        }
        hits
    }

    /// Lane `i` in `active`: exactly `self.occluded` of lane `i`'s ray; other
    /// lanes unset.
    #[inline(always)]
    pub(crate) fn occluded16<B: Lanes>(&self, k: B, rays: &Rays16<B>, active: Mask16) -> Mask16 {
        self.occluded16_by(k, rays, active, Policy::MEASURED)
    }

    /// [`Accel::occluded16`] with the static BVH walked by `policy`.
    #[inline(always)]
    fn occluded16_by<B: Lanes>(
        &self,
        k: B,
        rays: &Rays16<B>,
        active: Mask16,
        policy: Policy,
    ) -> Mask16 {
        let lanes = RayLanes::new(k, rays);
        let mut occluded = Mask16::NONE;
        if !self.listed.is_empty() {
            occluded = self.listed_hits16::<true, _>(&lanes, active).found;
        }
        if let Some(world) = self.world.as_deref() {
            let mut best = Closest16::none(&lanes);
            let left = active.and_not(occluded);
            world
                .wide
                .tree
                .walk::<true, _>(&world.bvh, &lanes, left, &mut best, policy);
            occluded = occluded | best.found;
        }
        let rest = active.and_not(occluded);
        if !self.tlas.slots.is_empty() && rest.any() {
            if self.instances_in_lanes() {
                let mut hits = Hits16::none(k, rays);
                self.instances16::<true, _>(&lanes, rest, &mut hits);
                occluded = occluded | hits.found;
            } else {
                let rays = lanes::PlainRays::new(rays);
                let lanes = std::array::from_fn(|i| (rest.test(i), rays.lane(i), None));
                let found = self.instances_per_lane::<true, _>(k, &lanes);
                for (lane, hit) in found.iter().enumerate() {
                    occluded.0 |= u16::from(hit.is_some()) << lane;
                }
            }
        }
        occluded
    }

    /// Lane `i` in `hits.found`: exactly `self.surface_point(objects,
    /// &hits.lane(i).unwrap())`; other lanes unspecified.
    #[inline(always)]
    pub(crate) fn surface_points16<B: Lanes>(
        &self,
        k: B,
        objects: &[Object],
        hits: &Hits16<B>,
    ) -> SurfacePoints16<B> {
        let mut done = Mask16::NONE;
        let mut out = points::blank(k);
        if let Some(world) = self.world.as_deref() {
            // The scalar test: the hit's index names this triangle.
            let w = &world.wide;
            let valid = hits.found
                & hits
                    .world_index
                    .lt(U32x16::splat(k, w.objects.len() as u32));
            let zero = U32x16::splat(k, 0);
            let object = U32x16::gather(&w.objects, hits.world_index, valid, zero);
            let triangle = U32x16::gather(&w.triangles, hits.world_index, valid, zero);
            done = valid & object.eq(hits.object) & triangle.eq(hits.triangle);
            if done.any() {
                out = w
                    .shading
                    .points(k, hits.world_index, done, hits.b1, hits.b2);
            }
        }
        for &index in &self.listed {
            let instance = &self.instances[index as usize];
            let on = hits.found.and_not(done) & hits.object.eq(U32x16::splat(k, instance.object));
            if let Some(placement) = &instance.placement
                && on.any()
            {
                let sphere = points::sphere_points(k, placement, hits.b1, hits.b2);
                out = points::select(on, &sphere, &out);
                done = done | on;
            }
        }
        let rest = hits.found.and_not(done);
        if rest.any() {
            let lanes = hits.to_lanes();
            let lanes = std::array::from_fn(|i| lanes[i].filter(|_| rest.test(i)));
            let scalar = SurfacePoints16::from_lanes(k, &self.points_per_lane(k, objects, &lanes));
            out = points::select(rest, &scalar, &out);
        }
        out
    }
}
