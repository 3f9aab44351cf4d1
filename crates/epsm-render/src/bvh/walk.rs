//! The traversal loop of a [`WideBvh`]: one ray, front to back.
//!
//! Model: the loop of obvhs's `traverse!` macro (Ylitie, Karras and Laine,
//! HPG 2017: node groups and primitive groups as bit masks, children visited
//! in the octant order the hit mask encodes), with its state in local
//! variables instead of a `Traversal` struct: no struct to build and clear
//! per ray, and a stack of [`STACK`] groups that is never zeroed. Nodes,
//! primitives and the order they are visited in are those of the macro, so
//! closest hits (and hence images) are bit-identical to it.
//!
//! The stack holds one group per level of the tree below the root; a tree
//! deeper than [`STACK`] levels (which the PLOC builds do not produce short
//! of pathological inputs) loses the deepest pending groups, as obvhs's
//! fixed stack of 32 does.
//!
//! No parameters.

use std::mem::MaybeUninit;

use super::box_test::BoxTest;
use super::cwbvh::WideBvh;
use super::node::TraceRay;

/// Capacity of the traversal stack, in node groups.
const STACK: usize = 32;

/// Bits of a node group holding the inner children still to visit.
const INNER_HITS: u32 = 0xff00_0000;

/// Walks `bvh` with `ray`, box tests by `boxes`, calling `leaf(slot, ray)`
/// for each leaf primitive slot whose box the ray enters (`leaf` may lower
/// `ray.t_max`, which culls the boxes tested after it). Stops early when
/// `leaf` returns `true`.
#[inline(always)]
#[allow(unsafe_code)]
pub(crate) fn walk(
    bvh: &WideBvh,
    ray: &mut TraceRay,
    boxes: impl BoxTest,
    mut leaf: impl FnMut(u32, &mut TraceRay) -> bool,
) {
    if bvh.nodes.is_empty() {
        return;
    }
    let oct_inv4 = ray.oct_inv4();
    let oct = oct_inv4 & 0xff;
    let mut stack = [MaybeUninit::<(u32, u32)>::uninit(); STACK];
    let mut depth = 0usize;
    // (index of the first inner child, hit inner children << 24 | inner mask):
    // the root alone.
    let mut group = (0u32, 0x8000_0000u32);
    // (index of the first primitive slot, hit primitive bits).
    let mut primitives = (0u32, 0u32);
    loop {
        while primitives.1 != 0 {
            let local = 31 - primitives.1.leading_zeros();
            primitives.1 &= !(1 << local);
            if leaf(primitives.0 + local, ray) {
                return;
            }
        }
        if group.1 & INNER_HITS != 0 {
            let hits_imask = group.1;
            let offset = 31 - hits_imask.leading_zeros();
            group.1 &= !(1 << offset);
            if group.1 & INNER_HITS != 0 {
                stack[depth] = MaybeUninit::new(group);
                depth = (depth + 1).min(STACK - 1);
            }
            let slot = (offset - 24) ^ oct;
            let relative = (hits_imask & !(u32::MAX << slot)).count_ones();
            let node = &bvh.nodes[(group.0 + relative) as usize];
            let hit_mask = node.intersect(ray, oct_inv4, boxes);
            group = (
                node.child_base_idx,
                (hit_mask & INNER_HITS) | node.imask as u32,
            );
            primitives = (node.primitive_base_idx, hit_mask & 0x00ff_ffff);
        } else {
            group = (0, 0);
        }
        if primitives.1 == 0 && group.1 & INNER_HITS == 0 {
            if depth == 0 {
                return;
            }
            depth -= 1;
            // SAFETY: `depth` only grows right after a write to
            // `stack[depth]`, so every entry below it has been written.
            group = unsafe { stack[depth].assume_init() };
        }
    }
}
