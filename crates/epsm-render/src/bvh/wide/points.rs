//! Shading points of sixteen hits: `Accel::surface_point` per lane, with the
//! static triangles' points and the listed exact spheres' computed in
//! lanes.
//!
//! Model: a static triangle's point is `ShadingTriangle::point` (module
//! `shading`) on its record gathered from a flat table ([`ShadingTable`]:
//! [`RECORD`] floats per triangle, so a lane's fields share two cache
//! lines): `p = (p0 + b1·e1) + b2·e2`; a constant shading frame as stored, or
//! the interpolated normal `(n0 + b1·d1) + b2·d2` normalised as glam's
//! `try_normalize` (`v · (1/|v|)` when that reciprocal is finite and
//! positive, else the geometric normal), the geometric normal flipped into
//! its hemisphere and `Frame::from_normal` of it; texture coordinates
//! `((1 − b1) − b2)·uv0 + b1·uv1 + b2·uv2`, or `(b1, b2)` without. A listed
//! sphere's point is `hit::sphere_point` with its cached placement: the
//! octahedral decode ([`sphere::point`](crate::sphere::point)) in `f64`
//! lanes, rounded to `f32`, then the `f32` normal and position. Every
//! other hit (instances behind the top level) is computed per lane by the
//! scalar `Accel::surface_point`.
//!
//! No parameters.

use super::affine::{mat_mul, transform_point};
use super::{Frames16, SurfacePoints16, TexCoords16};
use crate::bvh::shading::{Normals, ShadingTriangle};
use crate::hit::Placement;
use crate::simd::{F32x16, F64x16, Lanes, Mask16, U32x16, Vec3x16};

/// Floats per record of [`ShadingTable`].
pub(super) const RECORD: usize = 32;

/// Record offsets: first vertex, edges `p1 − p0` and `p2 − p0`, geometric
/// normal, then nine floats of normals (a constant frame's `s, t, n`, or
/// `n0, n1 − n0, n2 − n0`), six of texture coordinates, and flags.
const P0: u32 = 0;
const E1: u32 = 3;
const E2: u32 = 6;
const NG: u32 = 9;
const NORMALS: u32 = 12;
const UVS: u32 = 21;
const FLAGS: u32 = 27;

/// Flag: the normals are interpolated.
const INTERPOLATED: u32 = 1;
/// Flag: the record has texture coordinates.
const HAS_UVS: u32 = 2;

/// The static triangles' shading data ([`ShadingTriangle`]) as `f32`
/// records of [`RECORD`] floats, indexed by a hit's id (flags stored as
/// bits).
#[derive(Clone, Debug, Default)]
pub(super) struct ShadingTable {
    records: Vec<f32>,
}

impl ShadingTable {
    /// The records of `triangles`.
    pub fn new(triangles: &[ShadingTriangle]) -> Self {
        let mut records = vec![0.0; triangles.len() * RECORD];
        for (tri, record) in triangles.iter().zip(records.chunks_exact_mut(RECORD)) {
            let mut put = |offset: u32, values: &[f32]| {
                let at = offset as usize;
                record[at..at + values.len()].copy_from_slice(values);
            };
            put(P0, &tri.p0.to_array());
            put(E1, &tri.e1.to_array());
            put(E2, &tri.e2.to_array());
            put(NG, &tri.ng.to_array());
            let (normals, mut flags) = match tri.normals {
                Normals::Flat(f) => ([f.s, f.t, f.n], 0),
                Normals::Interpolated(n) => (n, INTERPOLATED),
            };
            for (i, n) in normals.iter().enumerate() {
                put(NORMALS + 3 * i as u32, &n.to_array());
            }
            if let Some(uvs) = tri.uvs {
                flags |= HAS_UVS;
                for (i, uv) in uvs.iter().enumerate() {
                    put(UVS + 2 * i as u32, &uv.to_array());
                }
            }
            put(FLAGS, &[f32::from_bits(flags)]);
        }
        Self { records }
    }

    /// Approximate heap size in bytes.
    pub fn bytes(&self) -> usize {
        self.records.len() * 4
    }

    /// The points at `(b1, b2)` on the triangles `index` (table indices,
    /// each in bounds in `lanes`); other lanes unspecified.
    #[inline(always)]
    pub fn points<B: Lanes>(
        &self,
        k: B,
        index: U32x16<B>,
        lanes: Mask16,
        b1: F32x16<B>,
        b2: F32x16<B>,
    ) -> SurfacePoints16<B> {
        let zero = F32x16::splat(k, 0.0);
        let record = Record {
            k,
            records: &self.records,
            base: index * U32x16::splat(k, RECORD as u32),
            lanes,
        };
        let (p0, e1, e2, ng) = (
            record.vec(P0),
            record.vec(E1),
            record.vec(E2),
            record.vec(NG),
        );
        let normals = [
            record.vec(NORMALS),
            record.vec(NORMALS + 3),
            record.vec(NORMALS + 6),
        ];
        let flags = record.get(FLAGS).to_bits();
        let mut point = SurfacePoints16 {
            p: p0 + e1 * b1 + e2 * b2,
            ng,
            uv: TexCoords16 {
                sphere: Mask16::NONE,
                a: Vec3x16::new(b1, b2, zero),
            },
            frame: Frames16 {
                s: normals[0],
                t: normals[1],
                n: normals[2],
            },
        };
        let interpolated = lanes & has(k, flags, INTERPOLATED);
        if interpolated.any() {
            let [n0, d1, d2] = normals;
            let ns = try_normalize(k, n0 + d1 * b1 + d2 * b2).unwrap_or(ng);
            let flipped = Vec3x16::select(ng.dot(ns).lt(zero), -ng, ng);
            point.ng = Vec3x16::select(interpolated, flipped, ng);
            point.frame =
                Frames16::select(interpolated, &Frames16::from_normal(k, ns), &point.frame);
        }
        let with_uvs = lanes & has(k, flags, HAS_UVS);
        if with_uvs.any() {
            let b0 = F32x16::splat(k, 1.0) - b1 - b2;
            let u = b0 * record.get(UVS) + b1 * record.get(UVS + 2) + b2 * record.get(UVS + 4);
            let v = b0 * record.get(UVS + 1) + b1 * record.get(UVS + 3) + b2 * record.get(UVS + 5);
            let a = &mut point.uv.a;
            (a.x, a.y) = (
                F32x16::select(with_uvs, u, b1),
                F32x16::select(with_uvs, v, b2),
            );
        }
        point
    }
}

/// The records of sixteen lanes, for gathers.
struct Record<'a, B: Lanes> {
    k: B,
    records: &'a [f32],
    /// Per lane, the index of its record's first float.
    base: U32x16<B>,
    /// The lanes read.
    lanes: Mask16,
}

impl<B: Lanes> Record<'_, B> {
    /// Float `at` of each lane's record (0 outside `lanes`).
    #[inline(always)]
    fn get(&self, at: u32) -> F32x16<B> {
        let index = self.base + U32x16::splat(self.k, at);
        F32x16::gather(self.records, index, self.lanes, F32x16::splat(self.k, 0.0))
    }

    /// Floats `at..at + 3` of each lane's record.
    #[inline(always)]
    fn vec(&self, at: u32) -> Vec3x16<B> {
        Vec3x16::new(self.get(at), self.get(at + 1), self.get(at + 2))
    }
}

/// Lanes whose `flags` have `flag`.
#[inline(always)]
fn has<B: Lanes>(k: B, flags: U32x16<B>, flag: u32) -> Mask16 {
    let flag = U32x16::splat(k, flag);
    (flags & flag).eq(flag)
}

/// glam's `try_normalize` per lane: `v · (1/|v|)` where that reciprocal is
/// finite and positive; `fallback` elsewhere (through [`Normalized`]).
#[inline(always)]
fn try_normalize<B: Lanes>(k: B, v: Vec3x16<B>) -> Normalized<B> {
    let rcp = F32x16::splat(k, 1.0) / v.length();
    Normalized {
        ok: rcp.is_finite() & rcp.gt(F32x16::splat(k, 0.0)),
        v: v * rcp,
    }
}

/// A per-lane [`try_normalize`] result.
#[derive(Clone, Copy)]
struct Normalized<B: Lanes> {
    /// Lanes that normalised.
    ok: Mask16,
    /// The normalised vectors (meaningful in `ok`).
    v: Vec3x16<B>,
}

impl<B: Lanes> Normalized<B> {
    /// The normalised vector, `fallback` in lanes that did not normalise.
    #[inline(always)]
    fn unwrap_or(self, fallback: Vec3x16<B>) -> Vec3x16<B> {
        Vec3x16::select(self.ok, self.v, fallback)
    }
}

/// `hit::sphere_point(placement, b1, b2)` per lane.
#[inline(always)]
pub(super) fn sphere_points<B: Lanes>(
    k: B,
    placement: &Placement,
    b1: F32x16<B>,
    b2: F32x16<B>,
) -> SurfacePoints16<B> {
    // `sphere::point` in `f64`: clamp, unfold the lower half, normalise.
    let one = F64x16::splat(k, 1.0);
    let (x, y) = (b1.to_f64().clamp(-one, one), b2.to_f64().clamp(-one, one));
    let z = one - x.abs() - y.abs();
    let upper = z.ge(F64x16::splat(k, 0.0));
    let x_folded = (one - y.abs()).copysign(x);
    let y_folded = (one - x.abs()).copysign(y);
    let (x, y) = (
        F64x16::select(upper, x, x_folded),
        F64x16::select(upper, y, y_folded),
    );
    let r = one / (x * x + y * y + z * z).sqrt();
    let local = Vec3x16::new((x * r).to_f32(), (y * r).to_f32(), (z * r).to_f32());
    let n = try_normalize(k, mat_mul(k, &placement.normal_from_object, local)).unwrap_or(local);
    SurfacePoints16 {
        p: transform_point(k, &placement.world_from_object, local),
        ng: n,
        uv: TexCoords16 {
            sphere: Mask16::ALL,
            a: local,
        },
        frame: Frames16::from_normal(k, n),
    }
}

/// Points with every field zero (a start for [`select`]).
#[inline(always)]
pub(super) fn blank<B: Lanes>(k: B) -> SurfacePoints16<B> {
    let zero = Vec3x16::splat(k, glam::Vec3::ZERO);
    SurfacePoints16 {
        p: zero,
        ng: zero,
        uv: TexCoords16 {
            sphere: Mask16::NONE,
            a: zero,
        },
        frame: Frames16 {
            s: zero,
            t: zero,
            n: zero,
        },
    }
}

/// `a` in the lanes of `m`, `b` in the others.
#[inline(always)]
pub(super) fn select<B: Lanes>(
    m: Mask16,
    a: &SurfacePoints16<B>,
    b: &SurfacePoints16<B>,
) -> SurfacePoints16<B> {
    SurfacePoints16 {
        p: Vec3x16::select(m, a.p, b.p),
        ng: Vec3x16::select(m, a.ng, b.ng),
        uv: TexCoords16 {
            sphere: (a.uv.sphere & m) | b.uv.sphere.and_not(m),
            a: Vec3x16::select(m, a.uv.a, b.uv.a),
        },
        frame: Frames16::select(m, &a.frame, &b.frame),
    }
}
