//! Ray against the eight quantised child boxes of an obvhs CWBVH node.
//!
//! Model: Ylitie, Karras and Laine, "Efficient Incoherent Ray Traversal on
//! GPUs Through Compressed Wide BVHs" (HPG 2017), as in obvhs's
//! `CwBvhNode::intersect_ray_simd`, written in safe code on glam's SIMD
//! `Vec4`, with two differences that matter to a path tracer:
//! - the ray's own `t_min` bounds the slabs (obvhs clamps at a fixed 1e-4,
//!   which culls geometry closer than that whatever the scene's scale);
//! - a direction component smaller than [`TINY_DIR`] in magnitude is replaced
//!   by `±TINY_DIR` for the slab test only (obvhs uses `±f32::EPSILON`, which
//!   can cull boxes the ray runs along a few ULPs inside), with the sign
//!   matching the octant test `dir < 0`, so rays with zero components never
//!   produce NaN.
//!
//! No parameters.

use glam::{Vec3A, Vec4};
use obvhs::cwbvh::node::{CwBvhNode, extract_byte64};

/// Smallest direction magnitude used in slab tests.
const TINY_DIR: f32 = 1e-18;

/// A ray prepared for box tests: origin, direction, clamped reciprocal
/// direction, `t` range and the octant code obvhs's traversal order uses.
#[derive(Clone, Copy, Debug)]
pub(crate) struct TraceRay {
    /// Origin.
    pub origin: Vec3A,
    /// Direction (not normalised; not clamped).
    pub dir: Vec3A,
    /// Reciprocal of the clamped direction.
    pub inv_dir: Vec3A,
    /// Smallest accepted `t`.
    pub t_min: f32,
    /// Largest accepted `t`; traversal lowers it to the closest hit so far.
    pub t_max: f32,
    /// Octant code (`ray_get_octant_inv4` of obvhs).
    pub oct_inv4: u32,
    neg: [bool; 3],
}

impl TraceRay {
    /// Prepares `origin + t·dir`, `t` in `[t_min, t_max]`.
    #[inline(always)]
    pub fn new(origin: Vec3A, dir: Vec3A, t_min: f32, t_max: f32) -> Self {
        let neg = [dir.x < 0.0, dir.y < 0.0, dir.z < 0.0];
        let clamp = |d: f32, n: bool| {
            if d.abs() >= TINY_DIR {
                d
            } else if n {
                -TINY_DIR
            } else {
                TINY_DIR
            }
        };
        let safe = Vec3A::new(
            clamp(dir.x, neg[0]),
            clamp(dir.y, neg[1]),
            clamp(dir.z, neg[2]),
        );
        let oct_inv4 = (if neg[0] { 0 } else { 0x0404_0404 })
            | (if neg[1] { 0 } else { 0x0202_0202 })
            | (if neg[2] { 0 } else { 0x0101_0101 });
        Self {
            origin,
            dir,
            inv_dir: safe.recip(),
            t_min,
            t_max,
            oct_inv4,
            neg,
        }
    }
}

/// The CWBVH hit mask of `ray` against the children of `node`: bits 24..32
/// are inner children to visit (in traversal order), bits 0..24 the leaf
/// primitives to test.
#[inline(always)]
pub(crate) fn intersect_node(node: &CwBvhNode, ray: &TraceRay) -> u32 {
    let scale = node.compute_extent() * ray.inv_dir;
    let shift = (Vec3A::from(node.p) - ray.origin) * ray.inv_dir;
    let (child_bits8, bit_index8) = node.get_child_and_index_bits(ray.oct_inv4);
    let mut hit_children = 0u32;
    for half in 0..2 {
        let q = |v: &[u8; 8]| {
            let i = half * 4;
            Vec4::new(v[i] as f32, v[i + 1] as f32, v[i + 2] as f32, v[i + 3] as f32)
        };
        let slab = |lo: &[u8; 8], hi: &[u8; 8], neg: bool, scale: f32, shift: f32| {
            let (near, far) = if neg { (q(hi), q(lo)) } else { (q(lo), q(hi)) };
            let (s, o) = (Vec4::splat(scale), Vec4::splat(shift));
            (near * s + o, far * s + o)
        };
        let (x0, x1) = slab(&node.child_min_x, &node.child_max_x, ray.neg[0], scale.x, shift.x);
        let (y0, y1) = slab(&node.child_min_y, &node.child_max_y, ray.neg[1], scale.y, shift.y);
        let (z0, z1) = slab(&node.child_min_z, &node.child_max_z, ray.neg[2], scale.z, shift.z);
        let t0 = x0.max(y0).max(z0).max(Vec4::splat(ray.t_min));
        let t1 = x1.min(y1).min(z1).min(Vec4::splat(ray.t_max));
        hit_children |= t0.cmple(t1).bitmask() << (4 * half);
    }
    // One iteration per child hit (a loop over set bits mispredicts once,
    // a test per child up to eight times).
    let mut hit_mask = 0u32;
    while hit_children != 0 {
        let child = hit_children.trailing_zeros() as usize;
        hit_children &= hit_children - 1;
        hit_mask |= extract_byte64(child_bits8, child) << extract_byte64(bit_index8, child);
    }
    hit_mask
}
