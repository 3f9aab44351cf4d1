//! The traversal layout of the bottom-level BVHs: obvhs's CWBVH converted
//! once into 8-wide nodes with exact `f32` child boxes and direct child
//! references, and each node's leaves as packets of up to eight triangles
//! tested at once.
//!
//! Model: the tree is the one obvhs builds (same nodes, same leaves, same
//! triangles per leaf); only its encoding and the walk change. A CWBVH node
//! stores its children relative to base indices with per-child metadata
//! bytes that every visit decodes (Ylitie, Karras and Laine, HPG 2017, made
//! for GPUs' memory bandwidth); here each inner child slot holds its node's
//! index, and masks say which children are leaves and which inner nodes.
//! The triangles of all leaf children of a node (a CWBVH leaf has at most
//! three; PLOC's average here is 1.5) are packed, in child order, into that
//! node's run of [`TrianglePacket`]s, each lane tagged with its child: a
//! visit tests the packets holding a leaf child whose box the ray enters,
//! with the lanes of the other children masked off. One packet per leaf
//! instead left half the lanes empty and doubled the memory of large meshes
//! (14.1 against 7.8 MB on `bench rays`' 100 k-triangle sphere). Packets
//! have eight lanes (one AVX pass) rather than four, so a node whose hit
//! leaves held five to eight triangles needs one packet test instead of two
//! (3 % fewer instructions per sample on `scenes/caustic-box.toml`, 8.5
//! instead of 7.8 MB on that sphere: nodes with few leaf triangles leave
//! more lanes empty).
//!
//! The walk (closest hit) tests a node's eight boxes at once, then first the
//! packets of the leaf children hit (their hits lower `t_max`), then pushes
//! the inner children entered before `t_max` on a stack sorted by entry
//! distance, nearest on top, and continues with the nearest pending node not
//! culled by the current `t_max`. With `ANY` (occlusion, shadow rays) it
//! returns at the first hit within `[t_min, t_max]`, and computes the ray's
//! shear only when it reaches a packet (module `node`, [`TraceRay`]).
//!
//! The packet loop runs over the node's packets in order and skips one
//! without a leaf child hit by a byte the node stores per packet (the union
//! of its lanes' children), so that branch waits only for the box test, not
//! for a load from the packet: samples per CPU-second on
//! `scenes/caustic-box.toml` +1.8 % on one thread and +1.4 % on two at
//! load 1 (8 rounds back to back, ahead in 7 and 5 of 8), +0.5 % at load
//! 1.7–2.9 (11 rounds, ahead in 15 of 22 pairs). Visiting only the
//! packets with a leaf hit by their bit mask, or ending the loop after the
//! last of them, made the packet addresses or the loop's end depend on the
//! box test, and cost 5–9 % in time although the simulated mispredicts
//! fell (by 18 % with the mask). Dropping the skip (every packet of a node
//! with a leaf hit tested, an empty lane mask for those without one) made
//! the closest-hit walks 11 % slower, timed alone on the rays of a render
//! (55.2 against 49.8 ns per ray).
//!
//! The inner children are pushed by one loop over the bits of those hit
//! (its test is 1.07 M of the 6.85 M simulated mispredicts at spp 8) and
//! the next node is always popped. Measured and dropped (time per
//! CPU-second): continuing straight with a lone inner child (no push and
//! pop; with the vector cull below), −4 %; continuing with the nearest
//! child just pushed, without the pop loop's checks, −2 to −4 % on two
//! threads; culling the children past `t_max` by one vector compare before
//! the loop, −5 %; the walk out of line (its own register allocation), −4
//! to −6 %. In the listings looked at (the lone child, the packet mask),
//! the AVX2 tile loop that the walk is inlined into then reloaded the
//! ray's box-test constants for every node instead of keeping them in
//! registers.
//!
//! The stack holds [`STACK`] nodes; a node pushes at most seven entries
//! beyond the one it continues with, so trees up to 18 levels deep never
//! overflow it (the tests check the bound `stack_need` of their trees). A
//! deeper tree (obvhs's PLOC builds give about `log8(triangles) + 3` levels)
//! would lose pending nodes past the capacity, as obvhs's own walk does past
//! 32 levels.
//!
//! No parameters.

use std::mem::MaybeUninit;

use super::blas::SlotTriangles;
use super::box_test::BoxTest;
use super::cwbvh::exact_child_boxes;
use super::node::{ChildBoxes, TraceRay};
use super::packet::{LANES, TrianglePacket};
use super::triangle::RayShear;

/// Capacity of the traversal stack, in nodes (a power of two).
const STACK: usize = 128;

/// One node: eight child boxes and what each child is.
#[derive(Clone, Copy, Debug)]
struct FlatNode {
    /// The child boxes (absent children: inverted boxes, which the box test
    /// reports as entered).
    boxes: ChildBoxes,
    /// Per child slot: the node index of an inner child (0 for leaf and
    /// absent children).
    children: [u32; 8],
    /// The first of the packets holding the leaf children's triangles.
    first_packet: u32,
    /// How many packets (up to three: eight leaves of at most three
    /// triangles).
    packet_count: u32,
    /// Byte `p`: the children (bit `c` for child `c`) with a triangle in
    /// packet `first_packet + p`.
    packet_children: u32,
    /// Bit `c` set when child `c` is a leaf.
    leaves: u8,
    /// Bit `c` set when child `c` is an inner node (the box test reports
    /// absent children as entered: only these two masks say which children
    /// exist).
    inner: u8,
}

/// A hit in a bottom-level BVH.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct FlatHit {
    /// The caller's id of the triangle hit.
    pub id: u32,
    /// Ray parameter, in units of the ray's direction.
    pub t: f32,
    /// Barycentric weight of `p1`.
    pub b1: f32,
    /// Barycentric weight of `p2`.
    pub b2: f32,
}

/// One node of a [`FlatBvh`] as [`FlatBvh::node_parts`] shows it.
pub(super) struct NodeParts<'a> {
    /// The child boxes.
    pub boxes: &'a ChildBoxes,
    /// Per child slot: the node index of an inner child (0 for leaf and
    /// absent children).
    pub children: [u32; 8],
    /// Bit `c` set when child `c` is a leaf.
    pub leaves: u8,
    /// Bit `c` set when child `c` is an inner node.
    pub inner: u8,
    /// The packets of the leaf children's triangles, in child order.
    pub packets: &'a [TrianglePacket],
}

/// 8-wide nodes over triangle packets, root first.
#[derive(Clone, Debug)]
pub(crate) struct FlatBvh {
    nodes: Vec<FlatNode>,
    packets: Vec<TrianglePacket>,
    /// Triangles in the packets.
    len: usize,
}

impl FlatBvh {
    /// Converts the obvhs CWBVH of `built` (its nodes and leaves unchanged).
    pub fn new(built: &SlotTriangles) -> Self {
        let boxes = exact_child_boxes(&built.bvh, |slot| built.triangles[slot as usize].aabb());
        let mut packets = Vec::new();
        let mut nodes = Vec::with_capacity(built.bvh.nodes.len());
        for (node, children_boxes) in built.bvh.nodes.iter().zip(&boxes) {
            let mut children = [0u32; 8];
            let (mut leaves, mut inner) = (0u8, 0u8);
            // The leaf children's triangles, in child order, and the child
            // bit of each.
            let mut slots = Vec::new();
            for (child, slot) in children.iter_mut().enumerate() {
                if node.is_child_empty(child) {
                    continue;
                }
                if !node.is_leaf(child) {
                    *slot = node.child_node_index(child);
                    inner |= 1 << child;
                    continue;
                }
                let (start, count) = node.child_primitives(child);
                let range = start as usize..(start + count) as usize;
                debug_assert!((1..=3).contains(&range.len()), "CWBVH leaf of {count}");
                slots.extend(range.map(|slot| (slot, 1u8 << child)));
                leaves |= 1 << child;
            }
            let first_packet = packets.len() as u32;
            let mut packet_children = 0u32;
            for (p, chunk) in slots.chunks(LANES).enumerate() {
                let triangles: Vec<_> = chunk.iter().map(|&(s, _)| built.triangles[s]).collect();
                let ids: Vec<_> = chunk.iter().map(|&(s, _)| built.ids[s]).collect();
                let bits: Vec<_> = chunk.iter().map(|&(_, bit)| bit).collect();
                packets.push(TrianglePacket::new(&triangles, &ids, &bits));
                packet_children |= u32::from(bits.iter().fold(0, |m, b| m | b)) << (8 * p);
            }
            let present = std::array::from_fn(|child| !node.is_child_empty(child));
            nodes.push(FlatNode {
                boxes: ChildBoxes::new(children_boxes, present),
                children,
                first_packet,
                packet_count: packets.len() as u32 - first_packet,
                packet_children,
                leaves,
                inner,
            });
        }
        // The walk indexes nodes by these unchecked.
        assert!(
            nodes
                .iter()
                .all(|n| n.children.iter().all(|&c| (c as usize) < nodes.len()))
        );
        Self {
            nodes,
            packets,
            len: built.triangles.len(),
        }
    }

    /// The nodes as other traversal layouts read them, root first (module
    /// `wide` builds its sixteen-ray layout from them).
    pub fn node_parts(&self) -> impl Iterator<Item = NodeParts<'_>> {
        self.nodes.iter().map(|n| {
            let first = n.first_packet as usize;
            NodeParts {
                boxes: &n.boxes,
                children: n.children,
                leaves: n.leaves,
                inner: n.inner,
                packets: &self.packets[first..first + n.packet_count as usize],
            }
        })
    }

    /// Number of triangles.
    pub fn len(&self) -> usize {
        self.len
    }

    /// Approximate heap size in bytes.
    pub fn bytes(&self) -> usize {
        self.nodes.len() * size_of::<FlatNode>() + self.packets.len() * size_of::<TrianglePacket>()
    }

    /// The most stack entries a walk can hold at once (at most [`STACK`]
    /// for the walk to be exact).
    #[cfg(test)]
    fn stack_need(&self) -> usize {
        fn need(bvh: &FlatBvh, node: usize) -> usize {
            let n = &bvh.nodes[node];
            let inner = (0..8).filter(|&c| n.inner & (1 << c) != 0);
            let deepest = inner.clone().map(|c| need(bvh, n.children[c] as usize));
            let count = inner.count();
            // All inner children are pushed, then the nearest popped.
            count.max(count.saturating_sub(1) + deepest.max().unwrap_or(0))
        }
        if self.nodes.is_empty() {
            0
        } else {
            need(self, 0)
        }
    }

    /// Traces `ray`, box tests by `boxes`: without `ANY` the closest hit
    /// with `t` in `[t_min, t_max]` (lowering `ray.t_max` to it), with `ANY`
    /// the first hit found. With `ANY` the walk sets `ray.shear` itself
    /// before each packet test, so `ray` may come
    /// [`TraceRay::without_shear`].
    #[inline(always)]
    pub fn trace<const ANY: bool>(
        &self,
        ray: &mut TraceRay,
        boxes: impl BoxTest,
    ) -> Option<FlatHit> {
        self.trace_from::<ANY>(0, ray, boxes)
    }

    /// [`FlatBvh::trace`] of the subtree under node `start` (a node index,
    /// as in [`FlatBvh::node_parts`]; the packet walk of module `wide`
    /// hands a subtree that few of its rays enter to this walk, ray by
    /// ray).
    #[inline(always)]
    #[allow(unsafe_code)]
    pub fn trace_from<const ANY: bool>(
        &self,
        start: usize,
        ray: &mut TraceRay,
        boxes: impl BoxTest,
    ) -> Option<FlatHit> {
        if start >= self.nodes.len() {
            return None;
        }
        let mut best = None;
        let mut stack = [MaybeUninit::<(u32, f32)>::uninit(); STACK];
        let mut depth = 0usize;
        let mut node = start;
        loop {
            // SAFETY: `node` is `start` (below `nodes.len()`) or a child
            // index of a node, below `nodes.len()` (asserted by
            // `FlatBvh::new`; nothing changes the nodes after).
            let n = unsafe { self.nodes.get_unchecked(node) };
            let hits = boxes.hits(&n.boxes, ray);
            // Leaf children first: their hits lower `t_max`, which culls the
            // inner children below.
            let leaves = hits.mask & u32::from(n.leaves);
            let first = n.first_packet as usize;
            let node_packets = if leaves == 0 {
                &[][..]
            } else {
                // SAFETY: `FlatBvh::new` gives each node the run of packets
                // it pushes right then (`first_packet` and `packet_count`),
                // inside `packets`, and nothing changes them after.
                unsafe {
                    self.packets
                        .get_unchecked(first..first + n.packet_count as usize)
                }
            };
            // Byte `p`: the leaf children hit with a triangle in packet `p`.
            let mut packet_leaves = n.packet_children & (leaves * 0x0101_0101);
            for packet in node_packets {
                let hit_children = packet_leaves & 0xff;
                packet_leaves >>= 8;
                if hit_children == 0 {
                    continue;
                }
                let lanes = packet.lanes_of(hit_children);
                if ANY {
                    // Occlusion rays come without it (`TraceRay::without_shear`).
                    ray.shear = RayShear::new(ray.dir);
                }
                let Some(hit) = boxes.packet_hit(packet, ray, lanes) else {
                    continue;
                };
                ray.t_max = hit.t;
                best = Some(FlatHit {
                    id: packet.id(hit.lane),
                    t: hit.t,
                    b1: hit.b1,
                    b2: hit.b2,
                });
                if ANY {
                    return best;
                }
            }
            // Inner children entered before `t_max`, sorted into the stack
            // above the entries of earlier nodes: nearest on top.
            let mut inner = hits.mask & u32::from(n.inner);
            let base = depth;
            while inner != 0 {
                let child = inner.trailing_zeros() as usize;
                inner &= inner - 1;
                let entry = hits.entry.0[child];
                if entry > ray.t_max || depth >= STACK {
                    continue;
                }
                let mut at = depth;
                // SAFETY: entries below `depth` have been written (`at - 1`
                // is in `base..depth`).
                while at > base && unsafe { stack[at - 1].assume_init().1 } < entry {
                    stack[at] = stack[at - 1];
                    at -= 1;
                }
                stack[at] = MaybeUninit::new((n.children[child], entry));
                depth += 1;
            }
            // The nearest pending node not culled by `t_max`.
            loop {
                if depth == 0 {
                    return best;
                }
                // `depth ≤ STACK`, so the mask keeps `depth − 1` (and saves
                // a bounds check).
                depth = (depth - 1) & (STACK - 1);
                // SAFETY: `depth` only grows right after a write at or below
                // it, so every entry below the old `depth` has been written.
                let (next, entry) = unsafe { stack[depth].assume_init() };
                if entry <= ray.t_max {
                    node = next as usize;
                    break;
                }
            }
        }
    }
}

#[cfg(test)]
mod tests;
