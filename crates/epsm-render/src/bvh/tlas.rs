//! Top level: instances (an object's placement, traced through its mesh's
//! own bottom-level BVH, as part of the static world-space BVH, or as an
//! exact sphere) and a CWBVH over the world-space bounds of those not in the
//! static BVH.
//!
//! Model: an instance's world box is the box of the eight transformed corners
//! of its mesh's object-space box, computed in `f64` and padded outwards by a
//! relative 1e-5 so `f32` rounding never clips geometry. The top level is
//! rebuilt (PLOC, obvhs `fastest_build`) whenever an instance moves. Measured
//! per moved instance (release, 2 loaded cores), rebuild versus refitting a
//! binary BVH (obvhs `Bvh2::refit_from`) and converting it to a CWBVH:
//!
//! | instances | rebuild | refit | refit + convert |
//! |---|---|---|---|
//! | 10 | 5 µs | 0.7 µs | 2 µs |
//! | 100 | 15 µs | 0.2 µs | 9 µs |
//! | 1000 | 0.3–1 ms | 0.4 µs | 0.09 ms |
//!
//! All are negligible next to rendering a frame, and only the rebuild keeps
//! the tree as good as a fresh build as objects move (a refit's boxes grow
//! and overlap), so the top level is rebuilt; moving many objects at once
//! goes through `Accel::update_instances` for a single rebuild.
//!
//! No parameters.

use std::time::Duration;

use glam::{DAffine3, DVec3, Vec3A};
use obvhs::BvhBuildParams;
use obvhs::aabb::Aabb;
use obvhs::cwbvh::builder::build_cwbvh;

use super::cwbvh::WideBvh;
use crate::hit::Placement;
use crate::scene::ObjectId;

/// Relative padding of instance boxes.
const PAD: f64 = 1e-5;

/// Where an instance's triangles are traced.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Traced {
    /// In the static world-space BVH.
    World,
    /// Through bottom-level BVH `index` of its mesh, behind the top level.
    Blas(u32),
    /// As the exact unit sphere ([`crate::sphere`]), behind the top level.
    Sphere,
    /// As the exact unit sphere, tested after the static BVH's walk (not in
    /// the top level).
    Listed,
}

/// One placed object with hittable triangles.
#[derive(Clone, Debug)]
pub(crate) struct Instance {
    /// The object it places.
    pub object: ObjectId,
    /// Where its triangles are traced.
    pub traced: Traced,
    /// Object-space bounds of its hittable triangles.
    pub local: Aabb,
    /// Its `f32` placement; `None` while the transform is singular (the
    /// instance is then never hit).
    pub placement: Option<Placement>,
    /// World-space bounds, `f64` (unpadded); meaningful with a placement.
    pub bounds: [DVec3; 2],
}

impl Instance {
    /// Places `object` (traced as `traced`, object-space bounds `local`) by `world_from_object`.
    pub fn new(
        object: ObjectId,
        traced: Traced,
        local: Aabb,
        world_from_object: &DAffine3,
    ) -> Self {
        let mut instance = Self {
            object,
            traced,
            local,
            placement: None,
            bounds: [DVec3::ZERO; 2],
        };
        instance.place(world_from_object);
        instance
    }

    /// Re-reads the transform.
    pub fn place(&mut self, world_from_object: &DAffine3) {
        self.placement = Placement::new(world_from_object);
        let (lo, hi) = (self.local.min.as_dvec3(), self.local.max.as_dvec3());
        let mut bounds = [DVec3::INFINITY, DVec3::NEG_INFINITY];
        for corner in 0..8 {
            let pick = |bit: usize, a: f64, b: f64| if corner & bit == 0 { a } else { b };
            let c = DVec3::new(
                pick(1, lo.x, hi.x),
                pick(2, lo.y, hi.y),
                pick(4, lo.z, hi.z),
            );
            let w = world_from_object.transform_point3(c);
            bounds = [bounds[0].min(w), bounds[1].max(w)];
        }
        self.bounds = bounds;
    }

    /// The padded `f32` world box.
    fn padded_box(&self) -> Aabb {
        let [lo, hi] = self.bounds;
        let pad =
            DVec3::splat(PAD * ((hi - lo).max_element() + lo.abs().max(hi.abs()).max_element()));
        Aabb::new(
            Vec3A::from((lo - pad).as_vec3()),
            Vec3A::from((hi + pad).as_vec3()),
        )
    }
}

/// The top-level BVH: a CWBVH whose leaf slots map to instances.
#[derive(Clone, Debug, Default)]
pub(crate) struct Tlas {
    /// The BVH over instance boxes.
    pub bvh: WideBvh,
    /// Instance index of each leaf slot.
    pub slots: Vec<u32>,
    /// The padded world box of each leaf slot's instance (the top-level
    /// BVH's leaf boxes).
    pub boxes: Vec<Aabb>,
}

impl Tlas {
    /// Builds the top level over the placed instances with their own BVH.
    pub fn build(instances: &[Instance]) -> Self {
        let placed: Vec<u32> = (0..instances.len() as u32)
            .filter(|&i| {
                let instance = &instances[i as usize];
                instance.placement.is_some()
                    && matches!(instance.traced, Traced::Blas(_) | Traced::Sphere)
            })
            .collect();
        if placed.is_empty() {
            return Self::default();
        }
        let boxes: Vec<Aabb> = placed
            .iter()
            .map(|&i| instances[i as usize].padded_box())
            .collect();
        let bvh = build_cwbvh(
            &boxes,
            BvhBuildParams::fastest_build(),
            &mut Duration::default(),
        );
        let slots = bvh
            .primitive_indices
            .iter()
            .map(|&p| placed[p as usize])
            .collect();
        let slot_boxes = bvh
            .primitive_indices
            .iter()
            .map(|&p| boxes[p as usize])
            .collect();
        Self {
            bvh: WideBvh::new(&bvh, |slot| {
                boxes[bvh.primitive_indices[slot as usize] as usize]
            }),
            slots,
            boxes: slot_boxes,
        }
    }

    /// Approximate heap size in bytes.
    pub fn bytes(&self) -> usize {
        self.bvh.bytes() + self.slots.len() * 4 + self.boxes.len() * size_of::<Aabb>()
    }
}
