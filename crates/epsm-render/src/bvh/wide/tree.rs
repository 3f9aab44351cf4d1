//! The static BVH laid out for sixteen rays at a time: the nodes of its
//! [`FlatBvh`] (same indices, same child boxes, same triangles per leaf)
//! with each leaf child's triangles as a run of [`Corners`], each node's
//! (up to sixteen) leaf triangles also as a [`Table`] by field, and the
//! slab test of one child box against sixteen rays.
//!
//! Model: the scalar walk tests one ray against a node's eight boxes at
//! once; here one box is tested against sixteen rays at once, each lane by
//! the scalar test's operations in its order (`ChildBoxes::hits_4x2`:
//! per axis the smaller and larger of the distances to the two planes,
//! entry `max(x, y, z, t_min)`, exit widened by `EXIT_SCALE` and capped by
//! `t_max`), so a lane enters a box exactly when the scalar ray with the
//! same `t_max` does, with the same entry distance. A leaf child's
//! triangles are the ones the scalar walk tests (its packet lanes of that
//! child), in packet order, each tagged with its half-packet (for the
//! scalar packet test's rule among equal `t`); each is one 64-byte record
//! holding its nine coordinates ([`Corners`]), loaded whole and permuted
//! per lane, and a node's table holds the same coordinates, ids and
//! half-packets by field, sixteen triangles to a row, for per-lane picks by
//! permutes (module `leaves`).
//!
//! No parameters.

use super::rays::RayLanes;
use crate::bvh::flat::FlatBvh;
use crate::bvh::node::EXIT_SCALE;
use crate::bvh::packet::LANES;
use crate::simd::{F32x16, Lanes, Mask16};

/// One node's children.
#[derive(Clone, Copy, Debug)]
pub(super) struct Node16 {
    /// `planes[axis][0 = min, 1 = max][child]`.
    planes: [[[f32; 8]; 2]; 3],
    /// Per child slot: an inner child's node index, a leaf child's first
    /// triangle (index into [`Tree16::corners`]); 0 for absent children.
    pub first: [u32; 8],
    /// Per child slot: a leaf child's triangle count (0 otherwise).
    pub count: [u8; 8],
    /// Bit `c` set when child `c` is a leaf.
    pub leaves: u8,
    /// Bit `c` set when child `c` is an inner node.
    pub inner: u8,
    /// The first of the leaf children's triangles (all consecutive).
    pub base: u32,
    /// The index in [`Tree16::tables`] of the leaf triangles' table, or
    /// [`NO_TABLE`] (no leaf triangles, or more than sixteen).
    pub table: u32,
    /// Per child slot (with a table): bit `i` set when triangle `base + i`
    /// belongs to that leaf child.
    pub bits: [u16; 8],
}

/// [`Node16::table`] of a node without a table.
pub(super) const NO_TABLE: u32 = u32::MAX;

/// A node's leaf triangles (up to sixteen, in order) by field, triangle
/// `base + i` in lane `i`, so a permute by `i` picks sixteen lanes' own.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(64))]
pub(super) struct Table {
    /// `coords[3·v + a]`: coordinate `a` of vertex `v`.
    pub coords: [[f32; 16]; 9],
    /// The caller's ids ([`Tree16::ids`]).
    pub ids: [u32; 16],
    /// The half-packets ([`Tree16::groups`]).
    pub groups: [u32; 16],
}

/// A triangle's vertices `[p0.x, p0.y, p0.z, p1.x, … p2.z]` and seven zeros:
/// one 64-byte load.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(64))]
pub(super) struct Corners(pub [f32; 16]);

/// The nodes and triangles of a [`FlatBvh`] for the packet walk.
#[derive(Clone, Debug, Default)]
pub(super) struct Tree16 {
    /// The nodes, root first (the indices of the [`FlatBvh`]'s).
    pub nodes: Vec<Node16>,
    /// The triangles, each leaf child's in a run.
    pub corners: Vec<Corners>,
    /// The caller's id of each triangle (as in the [`FlatBvh`]).
    pub ids: Vec<u32>,
    /// The tables of the nodes with one to sixteen leaf triangles.
    pub tables: Vec<Table>,
    /// The half-packet of the [`FlatBvh`] each triangle is in (a number
    /// per half, in the scalar walk's test order within a node): the
    /// scalar packet test keeps the first of equal `t` within a half, and
    /// the later of equal `t` across halves.
    pub groups: Vec<u32>,
}

/// Sixteen rays against one box.
#[derive(Clone, Copy, Debug)]
pub(super) struct Entered<B: Lanes> {
    /// Lanes that enter the box within their `t` range.
    pub lanes: Mask16,
    /// Per lane, the entry distance (meaningful in `lanes`).
    pub entry: F32x16<B>,
}

impl Tree16 {
    /// The layout of `bvh`.
    pub fn new(bvh: &FlatBvh) -> Self {
        let mut tree = Self::default();
        let mut packets = 0u32;
        for parts in bvh.node_parts() {
            let mut node = Node16 {
                planes: [[[0.0; 8]; 2]; 3],
                first: parts.children,
                count: [0; 8],
                leaves: parts.leaves,
                inner: parts.inner,
                base: tree.corners.len() as u32,
                table: NO_TABLE,
                bits: [0; 8],
            };
            for child in 0..8 {
                let b = parts.boxes.child(child);
                for axis in 0..3 {
                    node.planes[axis][0][child] = b.min[axis];
                    node.planes[axis][1][child] = b.max[axis];
                }
            }
            // The packets hold the leaf children's triangles in child
            // order, so each child's are consecutive.
            let lanes = parts.packets.iter().enumerate().flat_map(|(p, packet)| {
                (0..LANES).filter_map(move |l| Some((p, l, packet.lane(l)?)))
            });
            for (p, l, lane) in lanes {
                let child = lane.child.trailing_zeros() as usize;
                if node.count[child] == 0 {
                    node.first[child] = tree.corners.len() as u32;
                }
                node.count[child] += 1;
                let mut corners = [0.0; 16];
                for (v, p) in lane.vertices.iter().enumerate() {
                    corners[3 * v..3 * v + 3].copy_from_slice(&p.to_array());
                }
                tree.corners.push(Corners(corners));
                tree.ids.push(lane.id);
                tree.groups
                    .push(2 * (packets + p as u32) + u32::from(l >= LANES / 2));
            }
            packets += parts.packets.len() as u32;
            let base = node.base as usize;
            if (1..=16).contains(&(tree.corners.len() - base)) {
                let mut table = Table {
                    coords: [[0.0; 16]; 9],
                    ids: [0; 16],
                    groups: [0; 16],
                };
                for (i, corners) in tree.corners[base..].iter().enumerate() {
                    for (c, column) in table.coords.iter_mut().enumerate() {
                        column[i] = corners.0[c];
                    }
                    (table.ids[i], table.groups[i]) = (tree.ids[base + i], tree.groups[base + i]);
                }
                for child in (0..8).filter(|&c| node.leaves & (1 << c) != 0) {
                    let first = node.first[child] - node.base;
                    node.bits[child] = (((1u32 << node.count[child]) - 1) << first) as u16;
                }
                node.table = tree.tables.len() as u32;
                tree.tables.push(table);
            }
            tree.nodes.push(node);
        }
        tree
    }

    /// Approximate heap size in bytes.
    pub fn bytes(&self) -> usize {
        self.nodes.len() * size_of::<Node16>()
            + self.corners.len() * (size_of::<Corners>() + 8)
            + self.tables.len() * size_of::<Table>()
    }
}

impl Node16 {
    /// The lanes of `rays` (with `t` up to `t_max`) that enter child
    /// `child`'s box, and their entry distances.
    #[inline(always)]
    pub fn enter<B: Lanes>(
        &self,
        child: usize,
        rays: &RayLanes<B>,
        t_max: F32x16<B>,
    ) -> Entered<B> {
        let child = child & 7;
        let [x, y, z] = &self.planes;
        let lo = [x[0][child], y[0][child], z[0][child]];
        let hi = [x[1][child], y[1][child], z[1][child]];
        enter_box(rays, lo, hi, t_max)
    }
}

/// The lanes of `rays` (with `t` up to `t_max`) that enter the box from
/// `lo` to `hi`, and their entry distances: the scalar walk's child box
/// test per lane.
#[inline(always)]
pub(super) fn enter_box<B: Lanes>(
    rays: &RayLanes<B>,
    lo: [f32; 3],
    hi: [f32; 3],
    t_max: F32x16<B>,
) -> Entered<B> {
    let k = rays.k;
    let (x0, x1) = slab(k, lo[0], hi[0], rays.origin.x, rays.inv_dir.x);
    let (y0, y1) = slab(k, lo[1], hi[1], rays.origin.y, rays.inv_dir.y);
    let (z0, z1) = slab(k, lo[2], hi[2], rays.origin.z, rays.inv_dir.z);
    let t0 = x0.max(y0).max(z0).max(rays.test.t_min);
    let t1 = (x1.min(y1).min(z1) * F32x16::splat(k, EXIT_SCALE)).min(t_max);
    Entered {
        lanes: t0.le(t1),
        entry: t0,
    }
}

/// The distances `(near, far)` along one axis to the planes `lo` and `hi`
/// of rays from `o` with reciprocal direction `inv`: the smaller and the
/// larger of `(lo − o)·inv` and `(hi − o)·inv`.
#[inline(always)]
fn slab<B: Lanes>(k: B, lo: f32, hi: f32, o: F32x16<B>, inv: F32x16<B>) -> (F32x16<B>, F32x16<B>) {
    let lo = (F32x16::splat(k, lo) - o) * inv;
    let hi = (F32x16::splat(k, hi) - o) * inv;
    (lo.min(hi), lo.max(hi))
}
