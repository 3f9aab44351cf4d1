//! Area lights in sixteen lanes: a point sampled on the emitter each lane
//! selected, and the MIS pdf of a point hit on an emitter, bit for bit
//! [`LightTable::sample`]'s area branch and [`LightTable::pdf_area`].
//!
//! Lanes may select different emitters: the triangle choice runs once per
//! distinct emitter among the lanes (under its mask, with that emitter's
//! table), and everything after it — the square-root parameterised point,
//! the side test, the solid-angle pdf — once for all lanes, on triangle
//! data gathered from one table of every emitter's triangles.

use glam::Vec3;

use super::super::LightTable;
use super::LightSamples16;
use super::discrete::DiscreteSamples16;
use crate::simd::{F32x16, F64x16, Lanes, Mask16, U32x16, Vec3x16};

/// `f32`s per triangle in [`Tables::triangles`]: `p0`, `e1`, `e2`, normal.
const RECORD: u32 = 12;

/// Offset of a triangle record's `p0`.
const P0: u32 = 0;
/// Offset of a triangle record's `e1 = p1 − p0`.
const E1: u32 = 3;
/// Offset of a triangle record's `e2 = p2 − p0`.
const E2: u32 = 6;
/// Offset of a triangle record's unit front normal.
const NORMAL: u32 = 9;

/// What the area lanes gather, built with the [`LightTable`].
#[derive(Clone, Debug, Default)]
pub(in crate::lights) struct Tables {
    /// For each object, its emitter index; [`NOT_EMITTER`] for the others.
    emitter_of_object: Vec<u32>,
    /// For each emitter, the index of its first triangle in `triangles`
    /// (emitters in order, triangles in mesh order).
    first_triangle: Vec<u32>,
    /// For each emitter, [`LightTable::selected_pdf_area`].
    selected_pdf_area: Vec<f32>,
    /// Every emitter's triangles, [`RECORD`] `f32` each: `p0`, `e1`, `e2` and
    /// the unit front normal (x, y, z each), as the scalar emitter holds them.
    triangles: Vec<f32>,
}

/// [`Tables::emitter_of_object`]'s mark of a non-emitter.
const NOT_EMITTER: u32 = u32::MAX;

impl Tables {
    /// The tables of `lights`' area emitters.
    pub(in crate::lights) fn new(lights: &LightTable) -> Self {
        let mut first_triangle = Vec::with_capacity(lights.area.len());
        let mut triangles = Vec::new();
        for emitter in &lights.area {
            first_triangle.push((triangles.len() as u32) / RECORD);
            for t in emitter.triangles() {
                triangles.extend([t.p0, t.e1, t.e2, t.normal].iter().flat_map(Vec3::to_array));
            }
        }
        Self {
            emitter_of_object: (lights.emitter_of_object.iter())
                .map(|e| e.unwrap_or(NOT_EMITTER))
                .collect(),
            first_triangle,
            selected_pdf_area: (0..lights.area.len())
                .map(|index| lights.selected_pdf_area(index))
                .collect(),
            triangles,
        }
    }

    /// The vector at offset `at` of the records `record` (indices of their
    /// first `f32`) in the lanes of `m`, zero in the others. (No closure:
    /// one would be compiled without the caller's CPU features.)
    #[inline(always)]
    fn vector<B: Lanes>(&self, k: B, record: U32x16<B>, at: u32, m: Mask16) -> Vec3x16<B> {
        let (zero, x) = (F32x16::splat(k, 0.0), record + U32x16::splat(k, at));
        let (y, z) = (x + U32x16::splat(k, 1), x + U32x16::splat(k, 2));
        Vec3x16::new(
            F32x16::gather(&self.triangles, x, m, zero),
            F32x16::gather(&self.triangles, y, m, zero),
            F32x16::gather(&self.triangles, z, m, zero),
        )
    }
}

impl LightTable {
    /// The area branch of [`Self::sample`] for the lanes of `lanes`, which
    /// `pick` (the light selection) sent to an area emitter: lane `i` found
    /// and equal to the scalar sample exactly where that is `Some`.
    #[inline(always)]
    pub(super) fn sample_area16<B: Lanes>(
        &self,
        k: B,
        pick: &DiscreteSamples16<B>,
        p: Vec3x16<B>,
        u: [F32x16<B>; 2],
        lanes: Mask16,
    ) -> LightSamples16<B> {
        // Per emitter among the lanes: its triangle choice and constants.
        let emitters = pick.index.to_array();
        let mut todo = lanes;
        let mut sampled = Mask16::NONE;
        let mut triangle = U32x16::splat(k, 0);
        let mut pdf_area = F64x16::splat(k, 0.0);
        let mut radiance = Vec3x16::splat(k, Vec3::ZERO);
        while todo.any() {
            let index = emitters[todo.0.trailing_zeros() as usize];
            let same = todo & pick.index.eq(U32x16::splat(k, index));
            todo = todo.and_not(same);
            let emitter = &self.area[index as usize];
            let Some(by_area) = emitter.by_area() else {
                continue;
            };
            let chosen = by_area.sample_discrete16(k, pick.u_remapped, same).index;
            let first = U32x16::splat(k, self.wide.first_triangle[index as usize]);
            triangle = U32x16::select(same, first + chosen, triangle);
            pdf_area = F64x16::select(same, F64x16::splat(k, emitter.pdf_area()), pdf_area);
            radiance = Vec3x16::select(same, Vec3x16::splat(k, emitter.emission), radiance);
            sampled = sampled | same;
        }

        // The uniform point on the triangle, and its density from `p`.
        let record = triangle * U32x16::splat(k, RECORD);
        let p0 = self.wide.vector(k, record, P0, sampled);
        let e1 = self.wide.vector(k, record, E1, sampled);
        let e2 = self.wide.vector(k, record, E2, sampled);
        let normal = self.wide.vector(k, record, NORMAL, sampled);
        let su = u[0].sqrt();
        let (b1, b2) = (su * (F32x16::splat(k, 1.0) - u[1]), su * u[1]);
        let position = p0 + e1 * b1 + e2 * b2;
        let d = position - p;
        let pdf = solid_angle_pdf16(k, (pick.pmf * pdf_area).to_f32(), d, normal);
        let found = sampled & in_front16(k, d, normal) & !pdf.le(F32x16::splat(k, 0.0));
        let dist = d.length();
        LightSamples16 {
            found,
            wo: d.div(dist),
            dist,
            position,
            normal,
            radiance,
            pdf,
            delta: Mask16::NONE,
        }
    }

    /// Sixteen [`Self::pdf_area`]s: lane `i` in `active` is
    /// `self.pdf_area(object.lane(i), triangle.lane(i), p.lane(i), y.lane(i), n.lane(i))`
    /// bit for bit (other lanes unspecified). `triangle` must be a triangle
    /// of `object` where `object` is an emitter (the scalar function panics
    /// otherwise; checked here in debug builds). Always inlined (module docs
    /// of `simd`).
    #[inline(always)]
    #[allow(clippy::too_many_arguments)] // the scalar function's five inputs, the token, the lanes
    pub(crate) fn pdf_area16<B: Lanes>(
        &self,
        k: B,
        object: U32x16<B>,
        triangle: U32x16<B>,
        p: Vec3x16<B>,
        y: Vec3x16<B>,
        n: Vec3x16<B>,
        active: Mask16,
    ) -> F32x16<B> {
        let tables = &self.wide;
        let zero = F32x16::splat(k, 0.0);
        let objects = U32x16::splat(k, tables.emitter_of_object.len() as u32);
        let not_emitter = U32x16::splat(k, NOT_EMITTER);
        let known = active & object.lt(objects);
        let emitter = U32x16::gather(&tables.emitter_of_object, object, known, not_emitter);
        let lanes = known & !emitter.eq(not_emitter);
        if !lanes.any() {
            return zero;
        }
        let first = U32x16::gather(&tables.first_triangle, emitter, lanes, U32x16::splat(k, 0));
        debug_assert!(
            {
                let (emitter, triangle) = (emitter.to_array(), triangle.to_array());
                (lanes.lanes()).all(|i| {
                    (triangle[i] as usize) < self.area[emitter[i] as usize].triangles().len()
                })
            },
            "a triangle index beyond its emitter's triangles"
        );
        let record = (first + triangle) * U32x16::splat(k, RECORD);
        let d = y - p;
        let front = lanes & in_front16(k, d, tables.vector(k, record, NORMAL, lanes));
        let pdf_area = F32x16::gather(&tables.selected_pdf_area, emitter, front, zero);
        F32x16::select(front, solid_angle_pdf16(k, pdf_area, d, n), zero)
    }
}

/// Lane by lane `area::solid_angle_pdf`: `pdf_area · r² · r / |n · d|`
/// with `r² = d · d`, zero where that is not below +∞.
#[inline(always)]
fn solid_angle_pdf16<B: Lanes>(
    k: B,
    pdf_area: F32x16<B>,
    d: Vec3x16<B>,
    n: Vec3x16<B>,
) -> F32x16<B> {
    let dist2 = d.length_squared();
    let pdf = pdf_area * dist2 * dist2.sqrt() / n.dot(d).abs();
    let finite = pdf.lt(F32x16::splat(k, f32::INFINITY));
    F32x16::select(finite, pdf, F32x16::splat(k, 0.0))
}

/// Lane by lane `area::in_front`: `n · d < 0`.
#[inline(always)]
fn in_front16<B: Lanes>(k: B, d: Vec3x16<B>, n: Vec3x16<B>) -> Mask16 {
    n.dot(d).lt(F32x16::splat(k, 0.0))
}
