//! Per lane, the closest hit a walk of the static BVH has found so far,
//! and the scalar walks of subtrees that few lanes enter.
//!
//! Model: a lane's hit is its `t` (the lane's `t_max` from then on),
//! barycentrics, triangle id and the triangle's half-packet (for the
//! scalar packet test's rule among equal `t`, module `leaves`). A subtree
//! walked lane by lane (module `walk`) is the scalar walk
//! (`FlatBvh::trace_from`) from the lane's current `t_max` (module
//! `lanes`): its hit, if any, is closer or equal, and replaces the lane's.
//!
//! No parameters.

use super::lanes;
use super::rays::RayLanes;
use super::triangles::TriangleHits;
use crate::bvh::flat::FlatBvh;
use crate::simd::{F32x16, Lanes, Mask16, U32x16};

/// Per lane, the closest hit found so far in a bottom-level BVH.
#[derive(Clone, Copy, Debug)]
pub(super) struct Closest16<B: Lanes> {
    /// Lanes with a hit.
    pub found: Mask16,
    /// The lane's `t_max`: its hit's `t` in `found`, else the ray's own.
    pub t: F32x16<B>,
    /// Barycentric weight of `p1` (meaningful in `found`).
    pub b1: F32x16<B>,
    /// Barycentric weight of `p2` (meaningful in `found`).
    pub b2: F32x16<B>,
    /// The caller's id of the triangle hit (meaningful in `found`).
    pub id: U32x16<B>,
    /// The half-packet of the triangle hit
    /// ([`Tree16::groups`](super::tree::Tree16::groups); `u32::MAX` before a
    /// hit).
    pub group: U32x16<B>,
}

impl<B: Lanes> Closest16<B> {
    /// No hit yet, rays ending at `t_max`.
    #[inline(always)]
    pub fn none(rays: &RayLanes<B>) -> Self {
        let zero = F32x16::splat(rays.k, 0.0);
        Self {
            found: Mask16::NONE,
            t: rays.t_max,
            b1: zero,
            b2: zero,
            id: U32x16::splat(rays.k, 0),
            group: U32x16::splat(rays.k, u32::MAX),
        }
    }
}

impl<B: Lanes> Closest16<B> {
    /// Takes the hits `hit` in the lanes `lanes`, of the triangle with id
    /// `id` in half-packet `group` (per lane).
    #[inline(always)]
    pub fn take(&mut self, lanes: Mask16, hit: &TriangleHits<B>, id: U32x16<B>, group: U32x16<B>) {
        self.found = self.found | lanes;
        self.t = F32x16::select(lanes, hit.t, self.t);
        self.b1 = F32x16::select(lanes, hit.b1, self.b1);
        self.b2 = F32x16::select(lanes, hit.b2, self.b2);
        self.id = U32x16::select(lanes, id, self.id);
        self.group = U32x16::select(lanes, group, self.group);
    }
}

/// [`Tree16::groups`](super::tree::Tree16::groups) of a hit found by a scalar subtree walk: no
/// half-packet's, so an equal `t` from any later node wins over it, as in
/// the scalar walk.
const NO_GROUP: u32 = u32::MAX - 1;

impl<B: Lanes> Closest16<B> {
    /// Walks the subtree under `node` of `flat` for each lane of `lanes` by
    /// the scalar walk, each up to its current `t`, and takes its hits.
    #[inline(always)]
    pub fn walk_lanes<const ANY: bool>(
        &mut self,
        flat: &FlatBvh,
        rays: &RayLanes<B>,
        node: usize,
        lanes: Mask16,
        plain: &mut Option<lanes::PlainRays>,
    ) {
        if plain.is_none() {
            *plain = Some(rays.plain());
        }
        let Some(plain) = plain else {
            return;
        };
        let mut t = self.t.to_array();
        let hits = lanes::subtrees::<ANY, _>(rays.k, flat, node, lanes, plain, &t);
        if ANY {
            for (lane, hit) in hits.iter().enumerate() {
                self.found.0 |= u16::from(hit.is_some()) << lane;
            }
            return;
        }
        let (mut b1, mut b2) = (self.b1.to_array(), self.b2.to_array());
        let (mut id, mut group) = (self.id.to_array(), self.group.to_array());
        for (lane, hit) in hits.iter().enumerate() {
            if let Some(hit) = hit {
                self.found.0 |= 1 << lane;
                (t[lane], b1[lane], b2[lane]) = (hit.t, hit.b1, hit.b2);
                (id[lane], group[lane]) = (hit.id, NO_GROUP);
            }
        }
        self.t = F32x16::from_array(rays.k, t);
        self.b1 = F32x16::from_array(rays.k, b1);
        self.b2 = F32x16::from_array(rays.k, b2);
        self.id = U32x16::from_array(rays.k, id);
        self.group = U32x16::from_array(rays.k, group);
    }
}
