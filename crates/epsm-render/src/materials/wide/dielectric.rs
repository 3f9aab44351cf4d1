//! The smooth dielectric in lanes ([`crate::materials::Dielectric`]): the
//! Fresnel reflectance ([`fresnel_dielectric`]`::<f32>`, sharing its
//! formulas), Snell refraction ([`refract`](fresnel::refract)) and the choice
//! between them. Never mirrored: `wi` below the surface is inside.

use glam::Vec3;

use super::{BsdfSamples16, Materials16};
#[cfg(doc)]
use crate::materials::fresnel::{self, fresnel_dielectric};
use crate::materials::fresnel::{Amplitudes, sin2_transmitted};
use crate::simd::{F32x16, Lanes, Mask16, U32x16, Vec3x16};

/// `Dielectric::sample` in the `lanes` (all found), `wi` local.
#[inline(always)]
pub(super) fn sample<B: Lanes>(
    t: &Materials16,
    k: B,
    material: U32x16<B>,
    wi: Vec3x16<B>,
    u_lobe: F32x16<B>,
    lanes: Mask16,
) -> BsdfSamples16<B> {
    let (zero, one) = (F32x16::splat(k, 0.0), F32x16::splat(k, 1.0));
    let ior = Materials16::param(&t.ior, k, material, lanes);
    // η(transmitted side) / η(wi side), and the normal on the side of wi.
    let outside = wi.z.ge(zero);
    let eta = F32x16::select(outside, ior, one / ior);
    let n = Vec3x16::select(
        outside,
        Vec3x16::splat(k, Vec3::Z),
        Vec3x16::splat(k, -Vec3::Z),
    );
    let f = fresnel(k, wi.z.abs(), eta);
    let reflect = lanes & u_lobe.lt(f);
    let (refracted, refracts) = refract(k, wi, n, eta);
    let transmit = lanes.and_not(reflect) & refracts;
    // Reflection has pdf F when chosen, 1 when refraction fails (rounding
    // at the critical angle).
    let pdf = F32x16::select(transmit, one - f, F32x16::select(reflect, f, one));
    BsdfSamples16 {
        found: lanes,
        wo: Vec3x16::select(transmit, refracted, Vec3x16::new(-wi.x, -wi.y, wi.z)),
        weight: {
            let w = F32x16::select(transmit, one / (eta * eta), one);
            Vec3x16::new(w, w, w)
        },
        pdf,
        eta: F32x16::select(transmit, eta, one),
        delta: lanes,
        transmission: transmit,
        ..BsdfSamples16::none(k)
    }
}

/// [`fresnel_dielectric`]`::<f32>(cos_i, eta)` in every lane.
#[inline(always)]
fn fresnel<B: Lanes>(k: B, cos_i: F32x16<B>, eta: F32x16<B>) -> F32x16<B> {
    let (zero, one) = (F32x16::splat(k, 0.0), F32x16::splat(k, 1.0));
    let cos_i = cos_i.clamp(zero, one);
    let sin2_t = sin2_transmitted(k, cos_i, eta);
    let f = Amplitudes::below_critical(k, cos_i, eta, sin2_t)
        .reflectance(k)
        .clamp(zero, one);
    F32x16::select(sin2_t.ge(one), one, f)
}

/// [`refract`](fresnel::refract) in every lane: the transmitted direction, and the lanes
/// where it exists (not total internal reflection).
#[inline(always)]
fn refract<B: Lanes>(k: B, wi: Vec3x16<B>, n: Vec3x16<B>, eta: F32x16<B>) -> (Vec3x16<B>, Mask16) {
    let (zero, one) = (F32x16::splat(k, 0.0), F32x16::splat(k, 1.0));
    let cos_i = wi.dot(n);
    let sin2_i = (one - cos_i * cos_i).max(zero);
    let sin2_t = sin2_i / (eta * eta);
    let cos_t = (one - sin2_t).sqrt();
    let wo = (-wi).div(eta) + n * (cos_i / eta - cos_t);
    (wo, !sin2_t.ge(one))
}
