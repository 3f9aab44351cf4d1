//! Up to eight triangles tested against one ray at once.
//!
//! Model: the watertight test of module `triangle` (Woop, Benthin and Wald,
//! JCGT 2013) with one triangle per lane: the vertices are stored per
//! coordinate (structure of arrays), so the ray's axis permutation
//! `(kx, ky, kz)` only picks which lanes to load. Every lane rounds exactly as
//! the one-triangle reference `PackedTriangle::intersect` (test builds) does
//! (the shear `v[kx] + (−Sx)·v[kz]` is the product `M·v` of its matrix
//! without the exact zero terms; no fused
//! multiply–add), so a lane hits exactly when the scalar test hits, with the
//! same `t` and barycentrics; an edge function that rounds to zero is
//! recomputed in `f64` for that lane, as there. Unused lanes hold NaN
//! vertices, which every range test fails.
//!
//! Two ways to test a packet, with the same result: all eight lanes in one
//! pass of 256-bit AVX operations (`TrianglePacket::intersect_8`, module
//! `avx`), or as
//! two halves of four lanes in 128-bit operations
//! ([`TrianglePacket::intersect_4x2`], on every CPU).
//!
//! Each lane carries the bit of the node child its triangle belongs to, so a
//! walk tests only the lanes of the children whose boxes the ray enters. The
//! winner among the lanes hit is the one of testing the halves in order
//! (lanes 0–3, then 4–7), each half's hit lowering `t_max` for the next
//! half: the closest lane of the first half, replaced by the closest lane of
//! the second half that passes the range tests against that `t` (so among
//! equal `t` across halves the second half wins, within a half the lowest
//! lane). This is the order of the four-lane packets of earlier versions, so
//! walks return the same hits as they did.
//!
//! No parameters.

#[cfg(target_arch = "x86_64")]
mod avx;

use glam::{Vec3A, Vec4};

use super::node::{Lanes8, TraceRay};
use super::triangle::PackedTriangle;

/// Triangles per packet.
pub(crate) const LANES: usize = 8;

/// Lanes per half of a packet (one 128-bit vector).
const HALF: usize = LANES / 2;

/// Up to [`LANES`] triangles, coordinates by vertex and axis, with the
/// caller's id of each.
#[derive(Clone, Copy, Debug)]
pub(crate) struct TrianglePacket {
    /// `p[vertex][axis]`, lane `i` = triangle `i` (NaN in unused lanes).
    p: [[Lanes8; 3]; 3],
    /// The id of each lane's triangle (`u32::MAX` in unused lanes).
    ids: [u32; LANES],
    /// Byte `i`: the caller's child bit of lane `i`'s triangle (the node's
    /// leaf child it belongs to; 0 in unused lanes).
    children: u64,
}

/// One lane of a [`TrianglePacket`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct PacketLane {
    /// The vertices `[p0, p1, p2]`.
    pub vertices: [Vec3A; 3],
    /// The caller's id.
    pub id: u32,
    /// The caller's child bit.
    pub child: u8,
}

/// The closest hit in a packet.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct PacketHit {
    /// The lane (triangle) hit.
    pub lane: usize,
    /// Ray parameter, in units of the ray's direction.
    pub t: f32,
    /// Barycentric weight of `p1`.
    pub b1: f32,
    /// Barycentric weight of `p2`.
    pub b2: f32,
}

/// Vertices relative to the ray origin, sheared (`x, y` across the ray, `z`
/// along it), one lane per triangle.
#[derive(Clone, Copy)]
struct Sheared {
    x: Vec4,
    y: Vec4,
    z: Vec4,
}

impl TrianglePacket {
    /// The packet of `triangles` (one to [`LANES`]) in lane order, with
    /// their `ids` and child bits `children` (as many, one bit set in each).
    pub fn new(triangles: &[PackedTriangle], ids: &[u32], children: &[u8]) -> Self {
        debug_assert!((1..=LANES).contains(&triangles.len()));
        debug_assert!(children.iter().all(|c| c.count_ones() == 1));
        debug_assert_eq!(triangles.len(), ids.len());
        debug_assert_eq!(triangles.len(), children.len());
        let mut lane_children = [0u8; LANES];
        lane_children[..children.len()].copy_from_slice(children);
        let mut lane_ids = [u32::MAX; LANES];
        lane_ids[..ids.len()].copy_from_slice(ids);
        let mut p = [[Lanes8([f32::NAN; LANES]); 3]; 3];
        for (lane, triangle) in triangles.iter().enumerate() {
            for (vertex, v) in triangle.vertices().iter().enumerate() {
                for axis in 0..3 {
                    p[vertex][axis].0[lane] = v[axis];
                }
            }
        }
        Self {
            p,
            ids: lane_ids,
            children: u64::from_le_bytes(lane_children),
        }
    }

    /// The lanes (bit `i` for lane `i`) whose triangles belong to a child in
    /// `children` (bit `c` for child `c`, `c < 8`).
    #[inline(always)]
    pub fn lanes_of(&self, children: u32) -> u32 {
        const BYTES: u64 = 0x0101_0101_0101_0101;
        // Per byte: nonzero → bit 7 set. A byte holds at most one child bit,
        // at most 0x80, so adding 0x7f carries into no other byte.
        let x = self.children & (u64::from(children) * BYTES);
        let high = (x + 0x7f * BYTES) & (0x80 * BYTES);
        // Bit 8i + 7 to bit 56 + i by one multiply (by the sum of 2^(7j):
        // copy j = 7 − i of bit 8i + 7 lands there, and the shifted copies
        // land on distinct bits, so nothing carries).
        (high.wrapping_mul(0x0002_0408_1020_4081) >> 56) as u32
    }

    /// The triangle in `lane` (`< LANES`; `None` for an unused lane).
    pub fn lane(&self, lane: usize) -> Option<PacketLane> {
        let child = self.children.to_le_bytes()[lane];
        (child != 0).then(|| PacketLane {
            vertices: self
                .p
                .map(|v| Vec3A::new(v[0].0[lane], v[1].0[lane], v[2].0[lane])),
            id: self.ids[lane],
            child,
        })
    }

    /// The id of the triangle in `lane`.
    #[inline(always)]
    pub fn id(&self, lane: usize) -> u32 {
        self.ids[lane % LANES]
    }

    /// The closest hit of `ray` with `t` in its range, if any lane in
    /// `lanes` (bit `i` for lane `i`) has one: the two halves one after the
    /// other with 128-bit vectors (SSE2 on x86-64).
    #[inline(always)]
    pub fn intersect_4x2(&self, ray: &TraceRay, lanes: u32) -> Option<PacketHit> {
        let mut best = None;
        let mut t_max = ray.t_max;
        for half in 0..2 {
            let half_lanes = (lanes >> (HALF * half)) & 0xf;
            if half_lanes == 0 {
                continue;
            }
            if let Some(hit) = self.intersect_half(half, ray, t_max, half_lanes) {
                t_max = hit.t;
                best = Some(hit);
            }
        }
        best
    }

    /// [`TrianglePacket::intersect_4x2`] for lanes `HALF·half ..` (`lanes`:
    /// bit `i` for lane `HALF·half + i`) and `t` in `[ray.t_min, t_max]`.
    #[inline(always)]
    fn intersect_half(
        &self,
        half: usize,
        ray: &TraceRay,
        t_max: f32,
        lanes: u32,
    ) -> Option<PacketHit> {
        let (shear, t_min) = (&ray.shear, ray.t_min);
        // Clamped (a no-op) so that the loads below need no bounds checks.
        let [kx, ky, kz] = shear.axes().map(|k| k.min(2));
        let range = HALF * (half & 1)..HALF * (half & 1) + HALF;
        let load = |p: &Lanes8| Vec4::from_slice(&p.0[range.clone()]);
        let o = ray.origin.to_array();
        let (ox, oy, oz) = (Vec4::splat(o[kx]), Vec4::splat(o[ky]), Vec4::splat(o[kz]));
        let [nsx, nsy, sz] = shear.kz_col.map(Vec4::splat);
        let sheared = |p: &[Lanes8; 3]| {
            let z = load(&p[kz]) - oz;
            Sheared {
                x: (load(&p[kx]) - ox) + nsx * z,
                y: (load(&p[ky]) - oy) + nsy * z,
                z: sz * z,
            }
        };
        let [a, b, c] = [
            sheared(&self.p[0]),
            sheared(&self.p[1]),
            sheared(&self.p[2]),
        ];
        let edge = |p: &Sheared, q: &Sheared| p.x * q.y - p.y * q.x;
        let (mut u, mut v, mut w) = (edge(&c, &b), edge(&a, &c), edge(&b, &a));
        let zero = u.cmpeq(Vec4::ZERO) | v.cmpeq(Vec4::ZERO) | w.cmpeq(Vec4::ZERO);
        if zero.any() {
            let xy = |s: &Sheared| [s.x.to_array(), s.y.to_array()];
            let uvw = [u, v, w].map(|x| x.to_array());
            [u, v, w] =
                edges_f64(zero.bitmask(), [xy(&a), xy(&b), xy(&c)], uvw).map(Vec4::from_array);
        }
        let negative = u.cmplt(Vec4::ZERO) | v.cmplt(Vec4::ZERO) | w.cmplt(Vec4::ZERO);
        let positive = u.cmpgt(Vec4::ZERO) | v.cmpgt(Vec4::ZERO) | w.cmpgt(Vec4::ZERO);
        let det = u + v + w;
        // `flip` of the scalar test (negate when det's sign bit is set); a
        // lane where that differs from `det < 0` (det = −0 or NaN) fails
        // `den > 0` below.
        let flip = det.cmplt(Vec4::ZERO);
        let t_raw = u * a.z + v * b.z + w * c.z;
        let t_num = Vec4::select(flip, -t_raw, t_raw);
        let den = det.abs();
        let in_range = den.cmpgt(Vec4::ZERO)
            & t_num.cmpge(Vec4::splat(t_min) * den)
            & t_num.cmple(Vec4::splat(t_max) * den);
        let mut mask = (in_range & !(negative & positive)).bitmask() & lanes;
        if mask == 0 {
            return None;
        }
        let inv = Vec4::ONE / den;
        let t = t_num * inv;
        mask &= (t.abs().cmplt(Vec4::splat(f32::INFINITY))
            & t.cmpge(Vec4::splat(t_min))
            & t.cmple(Vec4::splat(t_max)))
        .bitmask();
        if mask == 0 {
            return None;
        }
        let t = t.to_array();
        let lane = closest(mask, &t);
        let sign = if flip.test(lane) { -1.0 } else { 1.0 };
        let inv = inv.to_array()[lane];
        Some(PacketHit {
            lane: HALF * (half & 1) + lane,
            t: t[lane],
            b1: (sign * v.to_array()[lane]) * inv,
            b2: (sign * w.to_array()[lane]) * inv,
        })
    }
}

/// The lane of `mask` (not empty) with the smallest `t`; among equal `t`,
/// the lowest.
#[inline(always)]
fn closest<const N: usize>(mut mask: u32, t: &[f32; N]) -> usize {
    let mut lane = mask.trailing_zeros() as usize % N;
    mask &= mask - 1;
    while mask != 0 {
        let other = mask.trailing_zeros() as usize % N;
        mask &= mask - 1;
        if t[other] < t[lane] {
            lane = other;
        }
    }
    lane
}

/// The edge functions `[u, v, w]` of a half (per lane) with those of the
/// lanes in `lanes` recomputed in `f64` from the sheared vertices `[a, b, c]`
/// (each `[x, y]`, per lane).
#[cold]
#[inline(never)]
fn edges_f64(
    lanes: u32,
    [a, b, c]: [[[f32; HALF]; 2]; 3],
    mut uvw: [[f32; HALF]; 3],
) -> [[f32; HALF]; 3] {
    for lane in (0..HALF).filter(|&l| lanes & (1 << l) != 0) {
        let edge64 = |p: &[[f32; HALF]; 2], q: &[[f32; HALF]; 2]| {
            (f64::from(p[0][lane]) * f64::from(q[1][lane])
                - f64::from(p[1][lane]) * f64::from(q[0][lane])) as f32
        };
        uvw[0][lane] = edge64(&c, &b);
        uvw[1][lane] = edge64(&a, &c);
        uvw[2][lane] = edge64(&b, &a);
    }
    uvw
}
