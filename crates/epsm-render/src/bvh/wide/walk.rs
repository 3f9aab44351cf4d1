//! The packet walk of the static BVH: sixteen rays through a [`Tree16`]
//! together, each lane with its own closest hit and `t_max`.
//!
//! Model: the scalar walk of module `flat`, with a set of lanes in place of
//! its one ray. At a node, each present child's box is tested against the
//! node's lanes with the `t_max` each had on arriving (as the scalar walk
//! tests the eight boxes once); then the leaf children's triangles against
//! the lanes that enter their boxes (module `leaves`; each hit lowering
//! that lane's `t_max`), then the inner children entered by some lane not
//! yet past its `t_max` are pushed, with their lanes and per-lane entry
//! distances, on a stack sorted by their nearest entry, nearest on top. A
//! popped node is visited by the lanes that entered it and whose `t_max`
//! has not fallen below their entry since; it is skipped when none is
//! left. With `ANY` (occlusion) a lane leaves the walk at its first hit.
//!
//! Incoherent rays soon part ways: on the continuation rays of
//! `scenes/caustic-box.toml` a node is visited by 3 of the 16 lanes on
//! average, and the packet walk alone lost to the scalar walk (7.4 against
//! 10.4 M rays per CPU-second). So a node that few lanes enter
//! ([`Policy::scalar_lanes`]) is handed to the scalar walk of its subtree
//! (`FlatBvh::trace_from`), lane by lane, from the lane's current `t_max`
//! (module `lanes`), as is a whole packet of so few lanes.
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

use super::closest::Closest16;
use super::rays::RayLanes;
use super::tree::Tree16;
use crate::bvh::flat::FlatBvh;
use crate::simd::{F32x16, Lanes, Mask16};

/// Capacity of the traversal stack, in nodes.
const STACK: usize = 128;

/// How the packet walk divides its work. [`Policy::MEASURED`] is the one
/// the wide functions use; the tests force each way with the others. Every
/// way gives the same hits (but for ties, module `wide`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) struct Policy {
    /// The cost of a round of a node's leaf triangles (module `leaves`)
    /// relative to `triangle_cost`, that of one leaf triangle against all
    /// lanes: a node's leaf triangles are tested in rounds when those cost
    /// less.
    pub round_cost: u32,
    /// See `round_cost`.
    pub triangle_cost: u32,
    /// A node that at most this many lanes enter is walked lane by lane by
    /// the scalar walk (`FlatBvh::trace_from`): its box and triangle tests
    /// cost the same for one lane as for sixteen.
    pub scalar_lanes: u32,
}

impl Policy {
    /// The costs measured on the rays of renders of the shipped scenes
    /// (`epsm bench rays --scene`, batched, one thread, best of 3 to 4
    /// rounds on a shared machine): rounds weighed 6 : 5 against triangles
    /// (continuation rays of `scenes/cornell-box.toml`: 50.7 M rays per
    /// CPU-second, 32.7 with triangles alone, 50.9 with rounds always but
    /// camera rays 81 against 84); subtrees that at most 6 lanes enter
    /// walked lane by lane (continuation rays of `scenes/caustic-box.toml`:
    /// 13.1 M rays per CPU-second, 11.0 without, 11.5, 12.1 and 13.4 at 2,
    /// 4 and 8 lanes; on an 82 k-triangle sphere in that box 9.3 against
    /// 6.1 without, 7.2 with every lane walked alone).
    pub const MEASURED: Self = Self {
        round_cost: 6,
        triangle_cost: 5,
        scalar_lanes: 6,
    };

    /// Every node's leaf triangles one by one against all lanes, no
    /// subtree lane by lane.
    #[cfg(test)]
    pub const TRIANGLES: Self = Self {
        round_cost: 1,
        triangle_cost: 0,
        scalar_lanes: 0,
    };

    /// Every node's leaf triangles in rounds where it has a table, no
    /// subtree lane by lane.
    #[cfg(test)]
    pub const ROUNDS: Self = Self {
        round_cost: 0,
        triangle_cost: 1,
        scalar_lanes: 0,
    };

    /// Subtrees that up to half the lanes enter lane by lane.
    #[cfg(test)]
    pub const HALF_SCALAR: Self = Self {
        scalar_lanes: 8,
        ..Self::MEASURED
    };
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
    pub fn walk<const ANY: bool, B: Lanes>(
        &self,
        flat: &FlatBvh,
        rays: &RayLanes<B>,
        lanes: Mask16,
        best: &mut Closest16<B>,
        policy: Policy,
    ) {
        if self.nodes.is_empty() || !lanes.any() {
            return;
        }
        // The lanes' rays as plain values, made when a subtree is first
        // walked lane by lane.
        let mut plain = None;
        if lanes.count() <= policy.scalar_lanes {
            best.walk_lanes::<ANY>(flat, rays, 0, lanes, &mut plain);
            return;
        }
        let mut pending = [MaybeUninit::<Pending>::uninit(); STACK];
        let mut entries = [MaybeUninit::<F32x16<B>>::uninit(); STACK];
        let mut depth = 0usize;
        // Lanes still walking (with `ANY`, those without a hit yet).
        let mut todo = lanes;
        let (mut node, mut at) = (0usize, lanes);
        loop {
            let n = &self.nodes[node];
            let t_node = best.t;
            // Leaf children: box tests, then their triangles.
            self.test_leaves::<ANY, _>(n, at, rays, best, &mut todo, policy);
            if ANY && !todo.any() {
                return;
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
                if m.count() > policy.scalar_lanes {
                    (node, at) = (next.node as usize, m);
                    break;
                }
                if m.any() {
                    best.walk_lanes::<ANY>(flat, rays, next.node as usize, m, &mut plain);
                    if ANY {
                        todo = todo.and_not(best.found);
                        if !todo.any() {
                            return;
                        }
                    }
                }
            }
        }
    }
}
