//! Sixteen lanes at a time: light sampling and the MIS light pdfs for the
//! wide tracer, one lane per path.
//!
//! Model: lane `i` of every function here returns, bit for bit, what the
//! scalar function returns for lane `i`'s inputs — [`LightTable::sample`]
//! for [`LightTable::sample16`], [`LightTable::pdf_area`],
//! [`LightTable::pdf_background`] and [`Background::eval`] for their
//! sixteen-lane twins — by doing the scalar code's IEEE operations in the
//! scalar code's order (`f64` where it uses `f64`, its libm calls per lane).
//!
//! | case | how |
//! |---|---|
//! | selection table and triangle choice: one entry of non-zero weight, or ≤ 16 entries | lanes ([`discrete`]) |
//! | … more than 16 entries | the scalar search per lane |
//! | area emitters: point, side test, solid-angle pdf, MIS pdf | lanes ([`area`]) |
//! | constant background: sample (libm `cos`/`sin` per lane), radiance, pdf | lanes ([`background`]) |
//! | point lights: connection, `I / d²` | lanes ([`point`]) |
//! | environment maps | the scalar function per lane |
//!
//! Lanes that select different kinds of light are handled kind by kind
//! under each kind's mask. Only what the tracer's inner loop reads is
//! returned: a sample's [`super::LightPoint`] (for path records, which the
//! scalar tracer makes) is not.

mod area;
mod background;
mod discrete;
mod point;
#[cfg(test)]
mod tests;

pub(super) use area::Tables;

use glam::{Vec2, Vec3};

use super::{Background, LightSample, LightTable};
use crate::simd::{F32x16, LANES, Lanes, Mask16, U32x16, Vec3x16};

/// Sixteen light samples: [`LightSample`]'s fields by lane, without
/// `source`. Lanes outside `found` hold no sample (their other fields are
/// unspecified).
#[derive(Clone, Copy, Debug)]
pub(crate) struct LightSamples16<B: Lanes> {
    /// Lanes for which the scalar `sample` returns `Some`.
    pub found: Mask16,
    /// Unit direction from the reference point toward the light.
    pub wo: Vec3x16<B>,
    /// Distance to the light point (`f32::INFINITY` for the background).
    pub dist: F32x16<B>,
    /// Light position, world space (the direction `wo` for the background).
    pub position: Vec3x16<B>,
    /// Unit light-surface normal (zero for point lights and the background).
    pub normal: Vec3x16<B>,
    /// Arriving radiance (`I / d²` for point lights).
    pub radiance: Vec3x16<B>,
    /// Solid-angle pdf including the light selection (the selection
    /// probability alone for point lights).
    pub pdf: F32x16<B>,
    /// Lanes whose light is a delta light (point lights).
    pub delta: Mask16,
}

impl<B: Lanes> LightSamples16<B> {
    /// No sample in any lane (every field zero).
    #[inline(always)]
    fn none(k: B) -> Self {
        let zero = Vec3x16::splat(k, Vec3::ZERO);
        Self {
            found: Mask16::NONE,
            wo: zero,
            dist: F32x16::splat(k, 0.0),
            position: zero,
            normal: zero,
            radiance: zero,
            pdf: F32x16::splat(k, 0.0),
            delta: Mask16::NONE,
        }
    }

    /// The samples of `samples` by lane (`None`: not found, and zeros).
    /// (The closures only gather scalars: one that made lane values would be
    /// compiled without the caller's CPU features.)
    #[inline(always)]
    fn from_lanes(k: B, samples: &[Option<LightSample>; LANES]) -> Self {
        let vector =
            |f: fn(&LightSample) -> Vec3| samples.map(|s| s.as_ref().map_or(Vec3::ZERO, f));
        let float = |f: fn(&LightSample) -> f32| samples.map(|s| s.as_ref().map_or(0.0, f));
        let (mut found, mut delta) = (Mask16::NONE, Mask16::NONE);
        for (lane, s) in samples.iter().enumerate() {
            found.0 |= u16::from(s.is_some()) << lane;
            delta.0 |= u16::from(s.is_some_and(|s| s.delta)) << lane;
        }
        Self {
            found,
            wo: Vec3x16::from_lanes(k, &vector(|s| s.wo)),
            dist: F32x16::from_array(k, float(|s| s.dist)),
            position: Vec3x16::from_lanes(k, &vector(|s| s.position)),
            normal: Vec3x16::from_lanes(k, &vector(|s| s.normal)),
            radiance: Vec3x16::from_lanes(k, &vector(|s| s.radiance)),
            pdf: F32x16::from_array(k, float(|s| s.pdf)),
            delta,
        }
    }

    /// `a`'s lanes in `m`, `b`'s in the others.
    #[inline(always)]
    fn select(m: Mask16, a: Self, b: Self) -> Self {
        let pick = |x: Mask16, y: Mask16| (x & m) | y.and_not(m);
        Self {
            found: pick(a.found, b.found),
            wo: Vec3x16::select(m, a.wo, b.wo),
            dist: F32x16::select(m, a.dist, b.dist),
            position: Vec3x16::select(m, a.position, b.position),
            normal: Vec3x16::select(m, a.normal, b.normal),
            radiance: Vec3x16::select(m, a.radiance, b.radiance),
            pdf: F32x16::select(m, a.pdf, b.pdf),
            delta: pick(a.delta, b.delta),
        }
    }
}

impl LightTable {
    /// Sixteen [`Self::sample`]s: lane `i` in `active` is
    /// `self.sample(p.lane(i), u_select.lane(i), Vec2::new(u[0].lane(i), u[1].lane(i)))`,
    /// `found` set iff that is `Some`, and then every field bit for bit.
    /// Lanes outside `active` are not found. Always inlined (module docs of
    /// `simd`).
    #[inline(always)]
    pub(crate) fn sample16<B: Lanes>(
        &self,
        k: B,
        p: Vec3x16<B>,
        u_select: F32x16<B>,
        u: [F32x16<B>; 2],
        active: Mask16,
    ) -> LightSamples16<B> {
        let Some(selection) = &self.selection else {
            return LightSamples16::none(k);
        };
        // Select a light per lane, then sample each kind under its mask.
        let pick = selection.sample_discrete16(k, u_select.to_f64(), active);
        let area = active & pick.index.lt(U32x16::splat(k, self.area.len() as u32));
        let background = active
            & pick
                .index
                .eq(U32x16::splat(k, self.background_index() as u32));
        let mut out = LightSamples16::none(k);
        if area.any() {
            out = self.sample_area16(k, &pick, p, u, area);
        }
        let points = active.and_not(area | background);
        if points.any() {
            let connected = self.sample_points16(k, &pick, p, points);
            out = LightSamples16::select(points, connected, out);
        }
        let rest = match &self.background {
            Background::Constant(radiance) => {
                if background.any() {
                    let sky = background::sample_constant16(k, *radiance, pick.pmf, u, background);
                    out = LightSamples16::select(background, sky, out);
                }
                Mask16::NONE
            }
            Background::EnvMap(_) => background,
        };
        // Environment maps: the scalar function per lane.
        if rest.any() {
            let u = [u[0].to_array(), u[1].to_array()];
            let samples = self.sample_lanes(
                &p.to_lanes(),
                &u_select.to_array(),
                &std::array::from_fn(|i| Vec2::new(u[0][i], u[1][i])),
                rest,
            );
            out = LightSamples16::select(rest, LightSamples16::from_lanes(k, &samples), out);
        }
        out
    }

    /// [`Self::sample`] for each lane of `lanes` (`None` in the others).
    #[inline(never)]
    fn sample_lanes(
        &self,
        p: &[Vec3; LANES],
        u_select: &[f32; LANES],
        u: &[Vec2; LANES],
        lanes: Mask16,
    ) -> [Option<LightSample>; LANES] {
        let mut samples = [None; LANES];
        for lane in lanes.lanes() {
            samples[lane] = self.sample(p[lane], u_select[lane], u[lane]);
        }
        samples
    }
}
