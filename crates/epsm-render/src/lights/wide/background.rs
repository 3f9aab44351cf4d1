//! The background in sixteen lanes: its radiance, its MIS pdf and the
//! background branch of light sampling, bit for bit [`Background::eval`],
//! [`LightTable::pdf_background`] and [`LightTable::sample`].
//!
//! A constant background is done in lanes: its radiance and pdf do not
//! depend on the direction, and its uniform sphere sample calls libm's
//! `cos` and `sin` per lane, as the scalar code does. An environment map is
//! evaluated by the scalar functions per lane.

use std::f32::consts::PI;

use glam::Vec3;

use super::super::{Background, LightTable};
use super::LightSamples16;
use crate::simd::{F32x16, F64x16, LANES, Lanes, Mask16, Vec3x16};

impl Background {
    /// Sixteen [`Self::eval`]s: lane `i` in `active` is
    /// `self.eval(dir.lane(i))` bit for bit (other lanes unspecified).
    /// Always inlined (module docs of `simd`).
    #[inline(always)]
    pub(crate) fn eval16<B: Lanes>(&self, k: B, dir: Vec3x16<B>, active: Mask16) -> Vec3x16<B> {
        match self {
            Background::Constant(c) => Vec3x16::splat(k, *c),
            Background::EnvMap(_) => {
                Vec3x16::from_lanes(k, &self.eval_lanes(&dir.to_lanes(), active))
            }
        }
    }

    /// [`Self::eval`] for each lane of `lanes` (zero in the others).
    #[inline(never)]
    fn eval_lanes(&self, dir: &[Vec3; LANES], lanes: Mask16) -> [Vec3; LANES] {
        let mut out = [Vec3::ZERO; LANES];
        for lane in lanes.lanes() {
            out[lane] = self.eval(dir[lane]);
        }
        out
    }
}

impl LightTable {
    /// Sixteen [`Self::pdf_background`]s: lane `i` in `active` is
    /// `self.pdf_background(dir.lane(i))` bit for bit (other lanes
    /// unspecified). Always inlined (module docs of `simd`).
    #[inline(always)]
    pub(crate) fn pdf_background16<B: Lanes>(
        &self,
        k: B,
        dir: Vec3x16<B>,
        active: Mask16,
    ) -> F32x16<B> {
        match &self.background {
            // The same value in every direction.
            Background::Constant(_) => F32x16::splat(k, self.pdf_background(Vec3::Z)),
            Background::EnvMap(_) => {
                F32x16::from_array(k, self.pdf_background_lanes(&dir.to_lanes(), active))
            }
        }
    }

    /// [`Self::pdf_background`] for each lane of `lanes` (zero in the others).
    #[inline(never)]
    fn pdf_background_lanes(&self, dir: &[Vec3; LANES], lanes: Mask16) -> [f32; LANES] {
        let mut out = [0.0; LANES];
        for lane in lanes.lanes() {
            out[lane] = self.pdf_background(dir[lane]);
        }
        out
    }
}

/// The background branch of [`LightTable::sample`] for a constant background
/// of radiance `radiance`, in the lanes of `lanes` (selected with
/// probability `pmf`): [`Background::sample`]'s uniform direction on the
/// sphere. Every lane of `lanes` is found; the others are not.
#[inline(always)]
pub(super) fn sample_constant16<B: Lanes>(
    k: B,
    radiance: Vec3,
    pmf: F64x16<B>,
    u: [F32x16<B>; 2],
    lanes: Mask16,
) -> LightSamples16<B> {
    let one = F32x16::splat(k, 1.0);
    let z = one - F32x16::splat(k, 2.0) * u[0];
    let r = (one - z * z).max(F32x16::splat(k, 0.0)).sqrt();
    let phi = (F32x16::splat(k, 2.0 * PI) * u[1]).to_array();
    let (mut cos, mut sin) = ([0.0; LANES], [0.0; LANES]);
    for lane in lanes.lanes() {
        (cos[lane], sin[lane]) = (phi[lane].cos(), phi[lane].sin());
    }
    let dir = Vec3x16::new(
        r * F32x16::from_array(k, cos),
        r * F32x16::from_array(k, sin),
        z,
    );
    let pdf = F64x16::splat(k, f64::from(1.0 / (4.0 * PI)));
    LightSamples16 {
        found: lanes,
        wo: dir,
        dist: F32x16::splat(k, f32::INFINITY),
        position: dir,
        normal: Vec3x16::splat(k, Vec3::ZERO),
        radiance: Vec3x16::splat(k, radiance),
        pdf: (pmf * pdf).to_f32(),
        delta: Mask16::NONE,
    }
}
