//! The top level's instances against sixteen rays: `Accel::trace_instances`
//! with one ray per lane, for scenes with few instances (dynamic objects,
//! instanced large meshes, exact spheres beyond the listed two).
//!
//! Model: the instances are taken one after another in the top level's
//! slot order, each against the lanes still walking that enter its padded
//! world box (the top level's leaf box, by the scalar walk's box test at
//! the lane's best `t` so far). A mesh instance maps
//! the lanes' world-space rays to its object space by its cached `f32`
//! `object_from_world` (glam's `transform_point3a`/`transform_vector3a`,
//! term for term, module `affine`), each lane ending at its best hit so far,
//! and walks its bottom-level BVH as a packet (module `walk`, over the
//! layout of module `tree`), exactly as the static BVH is walked; a sphere
//! instance takes the listed spheres' lanes (module `spheres`). A lane's
//! hit is thus the scalar walk's: the same `t`, barycentrics and triangle,
//! but where two instances are hit at the same `t`. The scalar walk meets
//! the instances in the order of the top level's BVH, lowering `t_max` as
//! it goes, and keeps the hit its order meets last within the range tests'
//! rounding; here the slot order decides (module `wide`).
//!
//! Past [`LINEAR_INSTANCES`] instances, a box test per instance costs more
//! than the top level's BVH, and the scalar walk runs per lane (module
//! `lanes`).
//!
//! No parameters.

use super::closest::Closest16;
use super::rays::RayLanes;
use super::tree::enter_box;
use super::walk::Policy;
use super::{Hits16, Rays16, affine, spheres};
use crate::bvh::tlas::Traced;
use crate::bvh::{Accel, NO_WORLD_INDEX};
use crate::simd::{F32x16, Lanes, Mask16, U32x16};

/// The most instances tested one after another for sixteen rays; beyond,
/// the scalar top-level walk runs per lane.
pub(super) const LINEAR_INSTANCES: usize = 64;

impl Accel {
    /// Whether the instances are walked sixteen rays at a time
    /// ([`Accel::instances16`]) rather than per lane.
    #[inline(always)]
    pub(super) fn instances_in_lanes(&self) -> bool {
        self.tlas.slots.len() <= LINEAR_INSTANCES
    }

    /// The hits of the world-space rays `world` in `lanes` on the instances,
    /// each lane from its best hit so far in `hits` on (its `t`, the ray's
    /// `t_max` outside `hits.found`), taken into `hits`; with `ANY`, the
    /// lanes with any hit (the others' fields unspecified).
    #[inline(never)]
    pub(super) fn instances16<const ANY: bool, B: Lanes>(
        &self,
        world: &RayLanes<B>,
        lanes: Mask16,
        hits: &mut Hits16<B>,
    ) {
        let k = world.k;
        k.run(
            #[inline(always)]
            || {
                let world = *world;
                let mut todo = lanes;
                for (&slot, bounds) in self.tlas.slots.iter().zip(&self.tlas.boxes) {
                    if ANY && !todo.any() {
                        return;
                    }
                    let instance = &self.instances[slot as usize];
                    let Some(placement) = &instance.placement else {
                        continue;
                    };
                    let (lo, hi) = (bounds.min.to_array(), bounds.max.to_array());
                    let entering = todo & enter_box(&world, lo, hi, hits.t).lanes;
                    if !entering.any() {
                        continue;
                    }
                    let (found, t, b1, b2, triangle) = match instance.traced {
                        Traced::Blas(blas) => {
                            let blas = &self.blases[blas as usize];
                            let to_object = &placement.object_from_world;
                            let local = RayLanes::new(
                                k,
                                &Rays16 {
                                    origin: affine::transform_point(k, to_object, world.origin),
                                    dir: affine::transform_vector(k, to_object, world.dir),
                                    t_min: world.test.t_min,
                                    t_max: hits.t,
                                },
                            );
                            let mut best = Closest16::none(&local);
                            blas.wide.tree.walk::<ANY, _>(
                                &blas.bvh,
                                &local,
                                entering,
                                &mut best,
                                Policy::MEASURED,
                            );
                            (best.found, best.t, best.b1, best.b2, best.id)
                        }
                        Traced::Sphere => {
                            let tested =
                                entering.and_not(spheres::misses(&placement.sphere, &world));
                            if !tested.any() {
                                continue;
                            }
                            let Some(s) =
                                spheres::in_lanes::<ANY, _>(k, placement, &world, tested, hits.t)
                            else {
                                continue;
                            };
                            (s.found, s.t, s.b1, s.b2, U32x16::splat(k, 0))
                        }
                        Traced::World | Traced::Listed => continue,
                    };
                    hits.found = hits.found | found;
                    if ANY {
                        todo = todo.and_not(found);
                        continue;
                    }
                    hits.t = F32x16::select(found, t, hits.t);
                    hits.b1 = F32x16::select(found, b1, hits.b1);
                    hits.b2 = F32x16::select(found, b2, hits.b2);
                    hits.triangle = U32x16::select(found, triangle, hits.triangle);
                    let object = U32x16::splat(k, instance.object);
                    hits.object = U32x16::select(found, object, hits.object);
                    let none = U32x16::splat(k, NO_WORLD_INDEX);
                    hits.world_index = U32x16::select(found, none, hits.world_index);
                }
            },
        )
    }
}
