//! Point lights in sixteen lanes: the connection to the point light each
//! lane selected, bit for bit [`LightTable::sample`]'s point-light branch
//! ([`PointLight::connect`](crate::lights::PointLight::connect)): the
//! offset `position − p` in `f64` rounded to `f32`, `d² = d·d` in glam's
//! order, `wo = d / |d|`, `I / d²`, and the selection probability as the
//! pdf. The lanes of each distinct light run under its mask.

use super::super::LightTable;
use super::LightSamples16;
use super::discrete::DiscreteSamples16;
use crate::simd::{F32x16, F64x16, Lanes, Mask16, U32x16, Vec3x16};

impl LightTable {
    /// The samples of the lanes of `lanes`, each of which selected a point
    /// light (`pick.index` in `area.len() .. background_index()`), from the
    /// reference points `p`. A lane is found unless `p` is at its light or
    /// `d²` is not finite.
    #[inline(always)]
    pub(super) fn sample_points16<B: Lanes>(
        &self,
        k: B,
        pick: &DiscreteSamples16<B>,
        p: Vec3x16<B>,
        lanes: Mask16,
    ) -> LightSamples16<B> {
        let zero = F32x16::splat(k, 0.0);
        let p64 = [p.x.to_f64(), p.y.to_f64(), p.z.to_f64()];
        let mut out = LightSamples16::none(k);
        out.pdf = pick.pmf.to_f32();
        out.delta = lanes;
        let emitters = pick.index.to_array();
        let mut todo = lanes;
        while todo.any() {
            let index = emitters[todo.0.trailing_zeros() as usize];
            let same = todo & pick.index.eq(U32x16::splat(k, index));
            todo = todo.and_not(same);
            let light = &self.points[index as usize - self.area.len()];
            let d = Vec3x16::new(
                offset(k, light.position.x, p64[0]),
                offset(k, light.position.y, p64[1]),
                offset(k, light.position.z, p64[2]),
            );
            let dist2 = d.length_squared();
            let dist = dist2.sqrt();
            let found = same & !dist2.eq(zero) & dist2.is_finite();
            out.found = out.found | found;
            out.wo = Vec3x16::select(same, d.div(dist), out.wo);
            out.dist = F32x16::select(same, dist, out.dist);
            out.position = Vec3x16::select(
                same,
                Vec3x16::splat(k, light.position.as_vec3()),
                out.position,
            );
            out.radiance = Vec3x16::select(
                same,
                Vec3x16::splat(k, light.intensity).div(dist2),
                out.radiance,
            );
        }
        out
    }
}

/// `(c − p) as f32` per lane: one component of `position − p`.
#[inline(always)]
fn offset<B: Lanes>(k: B, c: f64, p: F64x16<B>) -> F32x16<B> {
    (F64x16::splat(k, c) - p).to_f32()
}
