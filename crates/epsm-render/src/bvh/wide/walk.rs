//! The packet walk of the static BVH: sixteen rays through a [`Tree16`]
//! together, each lane with its own closest hit and `t_max`.
//!
//! Model: the scalar walk of module `flat`, with a set of lanes in place of
//! its one ray. At a node, each present child's box is tested against the
//! node's lanes with the `t_max` each had on arriving (as the scalar walk
//! tests the eight boxes once); then each leaf child's triangles are tested
//! against the lanes that enter its box (each hit lowering that lane's
//! `t_max`; among equal `t`, the scalar packet test's choice: the first
//! within a half-packet, the later across halves), then the inner children
//! entered by some lane not yet past its
//! `t_max` are pushed, with their lanes and per-lane entry distances, on a
//! stack sorted by their nearest entry, nearest on top. A popped node is
//! visited by the lanes that entered it and whose `t_max` has not fallen
//! below their entry since; it is skipped when none is left. With `ANY`
//! (occlusion) a lane leaves the walk at its first hit.
//!
//! So a lane's box tests, culls and triangle tests are the scalar ones on
//! its ray with its current `t_max`; only the order of the nodes differs
//! (the packet's, not the lane's own), and with it which `t_max` a lane
//! carries into a test. The closest hit is the same unless two primitives
//! in different nodes are hit at the same `t` to within the tests'
//! rounding (a tie the scalar walk breaks by its visiting order; see module
//! `wide`); a tie within one node is broken as the scalar walk breaks it.
//!
//! The stack holds [`STACK`] nodes, as the scalar walk's, and drops pushes
//! beyond it as that one does (no tree of up to 18 levels reaches it).
//!
//! No parameters.

use std::mem::MaybeUninit;

use super::rays::RayLanes;
use super::tree::Tree16;
use super::triangles::hit_triangle;
use crate::simd::{F32x16, Mask16, U32x16};

/// Capacity of the traversal stack, in nodes.
const STACK: usize = 128;

/// Per lane, the closest hit found so far in a bottom-level BVH.
#[derive(Clone, Copy, Debug)]
pub(super) struct Closest16 {
    /// Lanes with a hit.
    pub found: Mask16,
    /// The lane's `t_max`: its hit's `t` in `found`, else the ray's own.
    pub t: F32x16,
    /// Barycentric weight of `p1` (meaningful in `found`).
    pub b1: F32x16,
    /// Barycentric weight of `p2` (meaningful in `found`).
    pub b2: F32x16,
    /// The caller's id of the triangle hit (meaningful in `found`).
    pub id: U32x16,
    /// The half-packet of the triangle hit ([`Tree16::groups`]; `u32::MAX`
    /// before a hit).
    group: U32x16,
}

impl Closest16 {
    /// No hit yet, rays ending at `t_max`.
    #[inline(always)]
    pub fn none(rays: &RayLanes) -> Self {
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

/// A node waiting on the stack.
#[derive(Clone, Copy)]
struct Pending {
    /// Its index.
    node: u32,
    /// The lanes that entered it.
    lanes: Mask16,
    /// The nearest of their entry distances (the stack's order).
    nearest: f32,
}

impl Tree16 {
    /// Walks the rays of `lanes`, each from its `t_min` to its `best.t`,
    /// lowering `best` to closer hits (see the module docs); with `ANY`
    /// stops each lane at its first hit.
    #[inline(always)]
    #[allow(unsafe_code)]
    pub fn walk<const ANY: bool>(&self, rays: &RayLanes, lanes: Mask16, best: &mut Closest16) {
        if self.nodes.is_empty() || !lanes.any() {
            return;
        }
        let mut pending = [MaybeUninit::<Pending>::uninit(); STACK];
        let mut entries = [MaybeUninit::<F32x16>::uninit(); STACK];
        let mut depth = 0usize;
        // Lanes still walking (with `ANY`, those without a hit yet).
        let mut todo = lanes;
        let (mut node, mut at) = (0usize, lanes);
        loop {
            let n = &self.nodes[node];
            let t_node = best.t;
            // Leaf children: box tests, then their triangles.
            let mut leaves = u32::from(n.leaves);
            while leaves != 0 {
                let child = leaves.trailing_zeros() as usize;
                leaves &= leaves - 1;
                let mut m = n.enter(child, rays, t_node).lanes & at & todo;
                let first = n.first[child & 7] as usize;
                let count = usize::from(n.count[child & 7]);
                for i in first..first + count {
                    if !m.any() {
                        break;
                    }
                    let mut hit = hit_triangle(&self.corners[i], rays, best.t, m);
                    let group = U32x16::splat(rays.k, self.groups[i]);
                    if !ANY && hit.lanes.any() {
                        // Equal `t` within a half-packet: the first stays.
                        let tie = hit.t.eq(best.t) & best.group.eq(group);
                        hit.lanes = hit.lanes.and_not(tie);
                    }
                    if !hit.lanes.any() {
                        continue;
                    }
                    best.found = best.found | hit.lanes;
                    best.t = F32x16::select(hit.lanes, hit.t, best.t);
                    best.b1 = F32x16::select(hit.lanes, hit.b1, best.b1);
                    best.b2 = F32x16::select(hit.lanes, hit.b2, best.b2);
                    let id = U32x16::splat(rays.k, self.ids[i]);
                    best.id = U32x16::select(hit.lanes, id, best.id);
                    best.group = U32x16::select(hit.lanes, group, best.group);
                    if ANY {
                        todo = todo.and_not(hit.lanes);
                        m = m.and_not(hit.lanes);
                        if !todo.any() {
                            return;
                        }
                    }
                }
            }
            // Inner children entered before `t_max`, sorted into the stack
            // above the entries of earlier nodes: nearest on top.
            let mut inner = u32::from(n.inner);
            let base = depth;
            while inner != 0 {
                let child = inner.trailing_zeros() as usize;
                inner &= inner - 1;
                let entered = n.enter(child, rays, t_node);
                let m = entered.lanes & at & todo & !entered.entry.gt(best.t);
                if !m.any() || depth >= STACK {
                    continue;
                }
                let nearest = entered.entry.reduce_min(m);
                let mut slot = depth;
                // SAFETY: entries below `depth` have been written (`slot - 1`
                // is in `base..depth`).
                while slot > base && unsafe { pending[slot - 1].assume_init().nearest } < nearest {
                    pending[slot] = pending[slot - 1];
                    entries[slot] = entries[slot - 1];
                    slot -= 1;
                }
                pending[slot] = MaybeUninit::new(Pending {
                    node: n.first[child & 7],
                    lanes: m,
                    nearest,
                });
                entries[slot] = MaybeUninit::new(entered.entry);
                depth += 1;
            }
            // The nearest pending node some lane still enters.
            loop {
                if depth == 0 {
                    return;
                }
                depth = (depth - 1) & (STACK - 1);
                // SAFETY: `depth` only grows right after a write at or below
                // it (the pushes above), so every entry below the old
                // `depth` has been written, in both arrays.
                let (next, entry) =
                    unsafe { (pending[depth].assume_init(), entries[depth].assume_init()) };
                let m = next.lanes & todo & !entry.gt(best.t);
                if m.any() {
                    (node, at) = (next.node as usize, m);
                    break;
                }
            }
        }
    }
}
