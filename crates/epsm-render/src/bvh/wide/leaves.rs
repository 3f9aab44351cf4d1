//! A node's leaf triangles against the lanes that enter their leaves' boxes:
//! one triangle at a time against all those lanes, or in rounds, each lane
//! testing the next triangle of its own list, where few lanes enter each
//! leaf.
//!
//! Model, one at a time: each leaf child's triangles in packet order, each
//! against the lanes that enter the child's box; a hit replaces a lane's
//! best unless its `t` equals that of a hit from the same half-packet (the
//! scalar packet test keeps the first of equal `t` within a half, and the
//! later across halves and packets, which the inclusive `t_max` gives).
//!
//! Model, in rounds: testing one triangle against all sixteen lanes costs
//! the same however few of them enter its leaf; a render's continuation
//! rays enter about a quarter of a node's leaf triangles each on
//! `scenes/cornell-box.toml`. Here each lane lists the triangles of the
//! leaves it enters (bits of the node's [`Table`], which holds up to
//! sixteen leaf triangles by field), and each round tests, in every lane
//! with triangles left, its lowest-numbered one, whose coordinates along
//! the lane's axes come by permutes of the table: as many rounds as the
//! longest list, each one watertight test ([`watertight`]). A lane meets
//! its triangles in the order of the per-triangle loop, with the same
//! `t_max` before each, and keeps a hit by the same rule, so it ends with
//! the same hit. A round costs a little more than one triangle against all
//! lanes (its coordinates come by permutes and selects instead of one
//! load); [`Policy`] weighs the two.
//!
//! No parameters.

use super::closest::Closest16;
use super::rays::RayLanes;
use super::tree::{Node16, Table, Tree16};
use super::triangles::{Along, hit_triangle, watertight};
use super::walk::Policy;
use crate::simd::{F32x16, Lanes, Mask16, U32x16};

impl Tree16 {
    /// Tests the leaf triangles of node `n` against the lanes of `at` that
    /// enter their leaves' boxes (with the `t_max` each lane had on
    /// arriving), one at a time or in rounds as `policy` weighs them,
    /// lowering `best`; with `ANY` a lane's first hit removes it from
    /// `todo`.
    #[inline(always)]
    pub(super) fn test_leaves<const ANY: bool, B: Lanes>(
        &self,
        n: &Node16,
        at: Mask16,
        rays: &RayLanes<B>,
        best: &mut Closest16<B>,
        todo: &mut Mask16,
        policy: Policy,
    ) {
        let t_node = best.t;
        let mut entered = [Mask16::NONE; 8];
        // The triangles some lane tests.
        let mut triangles = 0u32;
        let mut leaves = u32::from(n.leaves);
        while leaves != 0 {
            let child = leaves.trailing_zeros() as usize & 7;
            leaves &= leaves - 1;
            let m = n.enter(child, rays, t_node).lanes & at & *todo;
            entered[child] = m;
            triangles += u32::from(n.count[child]) * u32::from(m.any());
        }
        if triangles == 0 {
            return;
        }
        if let Some(table) = self.tables.get(n.table as usize) {
            let lists = lists(rays.k, n, &entered);
            if rounds(lists) * policy.round_cost < triangles * policy.triangle_cost {
                test_rounds::<ANY, _>(table, lists, rays, best, todo);
                return;
            }
        }
        self.test_triangles::<ANY, _>(n, &entered, rays, best, todo);
    }

    /// Tests the leaf triangles of `n` one at a time, each against the
    /// lanes that enter its leaf (`entered[c]` for child `c`).
    #[inline(always)]
    fn test_triangles<const ANY: bool, B: Lanes>(
        &self,
        n: &Node16,
        entered: &[Mask16; 8],
        rays: &RayLanes<B>,
        best: &mut Closest16<B>,
        todo: &mut Mask16,
    ) {
        let mut leaves = u32::from(n.leaves);
        while leaves != 0 {
            let child = leaves.trailing_zeros() as usize & 7;
            leaves &= leaves - 1;
            let mut m = entered[child] & *todo;
            let first = n.first[child] as usize;
            for i in first..first + usize::from(n.count[child]) {
                if !m.any() {
                    break;
                }
                let mut hit = hit_triangle(&self.corners[i], rays, best.t, m);
                if !hit.lanes.any() {
                    continue;
                }
                let group = U32x16::splat(rays.k, self.groups[i]);
                if ANY {
                    best.found = best.found | hit.lanes;
                    *todo = todo.and_not(hit.lanes);
                    m = m.and_not(hit.lanes);
                    continue;
                }
                // Equal `t` within a half-packet: the first stays.
                hit.lanes = hit.lanes.and_not(hit.t.eq(best.t) & best.group.eq(group));
                best.take(hit.lanes, &hit, U32x16::splat(rays.k, self.ids[i]), group);
            }
        }
    }
}

/// Per lane, the node's leaf triangles (bit `i`: triangle `base + i`) of
/// the leaf children it enters (`entered[c]` for child `c`).
#[inline(always)]
fn lists<B: Lanes>(k: B, node: &Node16, entered: &[Mask16; 8]) -> U32x16<B> {
    let mut lists = U32x16::splat(k, 0);
    let mut leaves = u32::from(node.leaves);
    while leaves != 0 {
        let child = leaves.trailing_zeros() as usize & 7;
        leaves &= leaves - 1;
        let bits = U32x16::splat(k, u32::from(node.bits[child]));
        lists = U32x16::select(entered[child], lists | bits, lists);
    }
    lists
}

/// The longest of the lists (the rounds they take).
#[inline(always)]
fn rounds<B: Lanes>(lists: U32x16<B>) -> u32 {
    let lengths = lists.to_array().map(u32::count_ones);
    lengths.into_iter().max().unwrap_or(0)
}

/// Tests each lane's triangles of `lists` (in `table`) in rounds (module
/// docs).
#[inline(always)]
fn test_rounds<const ANY: bool, B: Lanes>(
    table: &Table,
    mut lists: U32x16<B>,
    rays: &RayLanes<B>,
    best: &mut Closest16<B>,
    todo: &mut Mask16,
) {
    let k = rays.k;
    let zero = U32x16::splat(k, 0);
    loop {
        let mut active = !lists.eq(zero);
        if ANY {
            active = active & *todo;
        }
        if !active.any() {
            return;
        }
        // The lowest bit of each list: its exponent as an `f32` (exact, a
        // power of two) is the triangle's index.
        let low = lists & (zero - lists);
        lists = lists - low;
        let local = (F32x16::from_u32(low).to_bits() >> 23) - U32x16::splat(k, 127);
        let vertices = [
            along(k, table, 0, local, rays),
            along(k, table, 1, local, rays),
            along(k, table, 2, local, rays),
        ];
        let mut hit = watertight(k, &rays.test, vertices, best.t, active);
        if !hit.lanes.any() {
            continue;
        }
        if ANY {
            best.found = best.found | hit.lanes;
            *todo = todo.and_not(hit.lanes);
            continue;
        }
        let group = permute_u(U32x16::from_array(k, table.groups), local);
        // Equal `t` within a half-packet: the first stays.
        hit.lanes = hit.lanes.and_not(hit.t.eq(best.t) & best.group.eq(group));
        let id = permute_u(U32x16::from_array(k, table.ids), local);
        best.take(hit.lanes, &hit, id, group);
    }
}

/// Per lane, vertex `v` of its triangle `local` of `table` along the lane's
/// axes.
#[inline(always)]
fn along<B: Lanes>(
    k: B,
    table: &Table,
    v: usize,
    local: U32x16<B>,
    rays: &RayLanes<B>,
) -> Along<B> {
    let x = F32x16::from_array(k, table.coords[3 * v]).permute(local);
    let y = F32x16::from_array(k, table.coords[3 * v + 1]).permute(local);
    let z = F32x16::from_array(k, table.coords[3 * v + 2]).permute(local);
    let [a, b, c] = &rays.axis_is;
    [
        F32x16::select(a[0], x, F32x16::select(a[1], y, z)),
        F32x16::select(b[0], x, F32x16::select(b[1], y, z)),
        F32x16::select(c[0], x, F32x16::select(c[1], y, z)),
    ]
}

/// Lane `i` of `v` is lane `index[i]` (`< 16`) of `v`.
#[inline(always)]
fn permute_u<B: Lanes>(v: U32x16<B>, index: U32x16<B>) -> U32x16<B> {
    F32x16::from_bits(v).permute(index).to_bits()
}
