//! The GGX conductor in lanes ([`crate::materials::RoughConductor`] over
//! [`Ggx`]), in the front-side frame (mirroring is the caller's): `D` and
//! `Λ` share the scalar formulas, visible normals are sampled with the
//! scalar libm `cos` and `sin` per lane, and the rejections of the scalar
//! code (`None`) are masks.

use std::f32::consts::PI;

use super::{BsdfSamples16, Materials16};
#[cfg(doc)]
use crate::materials::microfacet::Ggx;
use crate::materials::microfacet::{d_above, lambda_off_horizon};
use crate::simd::{F32x16, LANES, Lanes, Mask16, U32x16, Vec3x16};

/// `RoughConductor::sample` in the `lanes` (`found` a subset of them), `wi`
/// local.
#[inline(always)]
pub(super) fn sample<B: Lanes>(
    t: &Materials16,
    k: B,
    material: U32x16<B>,
    wi: Vec3x16<B>,
    u: [F32x16<B>; 2],
    lanes: Mask16,
) -> BsdfSamples16<B> {
    let (zero, one) = (F32x16::splat(k, 0.0), F32x16::splat(k, 1.0));
    let alpha = Materials16::param(&t.alpha, k, material, lanes);
    let (m, visible) = sample_visible(k, alpha, wi, u, lanes.and_not(wi.z.le(zero)));
    let cos_im = wi.dot(m);
    let wo = reflect(k, wi, m);
    let pdf = reflection_pdf(k, alpha, wi, m);
    let lambda_i = lambda(k, alpha, wi);
    let g2_over_g1 = (one + lambda_i) / (one + lambda_i + lambda(k, alpha, wo));
    let found = visible.and_not(cos_im.le(zero) | wo.z.le(zero)) & pdf.gt(zero) & pdf.is_finite();
    BsdfSamples16 {
        found,
        wo,
        weight: t.colour(k, material, found) * g2_over_g1,
        pdf,
        m,
        ..BsdfSamples16::none(k)
    }
}

/// `RoughConductor::eval` in the `lanes` (0 in the other lanes), `wi`, `wo`
/// local.
#[inline(always)]
pub(super) fn eval<B: Lanes>(
    t: &Materials16,
    k: B,
    material: U32x16<B>,
    wi: Vec3x16<B>,
    wo: Vec3x16<B>,
    lanes: Mask16,
) -> Vec3x16<B> {
    let zero = F32x16::splat(k, 0.0);
    let (m, lanes, alpha) = reflection(t, k, material, wi, wo, lanes);
    let f = d(k, alpha, m) * g2(k, alpha, wi, wo) / (F32x16::splat(k, 4.0) * wi.z);
    Vec3x16::select(
        lanes,
        t.colour(k, material, lanes) * f,
        Vec3x16::new(zero, zero, zero),
    )
}

/// `RoughConductor::pdf` in the `lanes` (0 in the other lanes), `wi`, `wo`
/// local.
#[inline(always)]
pub(super) fn pdf<B: Lanes>(
    t: &Materials16,
    k: B,
    material: U32x16<B>,
    wi: Vec3x16<B>,
    wo: Vec3x16<B>,
    lanes: Mask16,
) -> F32x16<B> {
    let (m, lanes, alpha) = reflection(t, k, material, wi, wo, lanes);
    F32x16::select(
        lanes,
        reflection_pdf(k, alpha, wi, m),
        F32x16::splat(k, 0.0),
    )
}

/// What `eval` and `pdf` start with: the half vector of `wi` and `wo`, the
/// `lanes` where it exists ([`half_vector`]), and the roughness of those
/// lanes' materials.
#[inline(always)]
fn reflection<B: Lanes>(
    t: &Materials16,
    k: B,
    material: U32x16<B>,
    wi: Vec3x16<B>,
    wo: Vec3x16<B>,
    lanes: Mask16,
) -> (Vec3x16<B>, Mask16, F32x16<B>) {
    let (m, reflects) = half_vector(k, wi, wo);
    let lanes = lanes & reflects;
    (m, lanes, Materials16::param(&t.alpha, k, material, lanes))
}

/// The solid-angle pdf of sampling the reflection about the visible normal
/// `m` from `wi`: `G1(wi) · D(m) / (4 wi.z)`, as the scalar `sample` and
/// `pdf` compute it.
#[inline(always)]
fn reflection_pdf<B: Lanes>(k: B, alpha: F32x16<B>, wi: Vec3x16<B>, m: Vec3x16<B>) -> F32x16<B> {
    g1(k, alpha, wi) * d(k, alpha, m) / (F32x16::splat(k, 4.0) * wi.z)
}

/// The reflection half vector, and the lanes where it exists (both
/// directions above the surface, and a normalisable sum).
#[inline(always)]
fn half_vector<B: Lanes>(k: B, wi: Vec3x16<B>, wo: Vec3x16<B>) -> (Vec3x16<B>, Mask16) {
    let zero = F32x16::splat(k, 0.0);
    let (m, normalised) = try_normalize(k, wi + wo);
    (m, normalised.and_not(wi.z.le(zero) | wo.z.le(zero)))
}

/// [`Ggx::d`] in every lane.
#[inline(always)]
fn d<B: Lanes>(k: B, alpha: F32x16<B>, m: Vec3x16<B>) -> F32x16<B> {
    let zero = F32x16::splat(k, 0.0);
    F32x16::select(m.z.le(zero), zero, d_above(k, alpha, m.x, m.y, m.z))
}

/// [`Ggx::lambda`] in every lane.
#[inline(always)]
fn lambda<B: Lanes>(k: B, alpha: F32x16<B>, w: Vec3x16<B>) -> F32x16<B> {
    let z2 = w.z * w.z;
    F32x16::select(
        z2.eq(F32x16::splat(k, 0.0)),
        F32x16::splat(k, f32::INFINITY),
        lambda_off_horizon(k, alpha, w.x, w.y, z2),
    )
}

/// [`Ggx::g1`] in every lane.
#[inline(always)]
fn g1<B: Lanes>(k: B, alpha: F32x16<B>, w: Vec3x16<B>) -> F32x16<B> {
    let one = F32x16::splat(k, 1.0);
    one / (one + lambda(k, alpha, w))
}

/// [`Ggx::g2`] in every lane.
#[inline(always)]
fn g2<B: Lanes>(k: B, alpha: F32x16<B>, wi: Vec3x16<B>, wo: Vec3x16<B>) -> F32x16<B> {
    let one = F32x16::splat(k, 1.0);
    one / (one + lambda(k, alpha, wi) + lambda(k, alpha, wo))
}

/// [`Ggx::sample_visible`] in the `lanes`: the normals, and the lanes where
/// the scalar function returns `Some`.
#[inline(always)]
fn sample_visible<B: Lanes>(
    k: B,
    alpha: F32x16<B>,
    wi: Vec3x16<B>,
    u: [F32x16<B>; 2],
    lanes: Mask16,
) -> (Vec3x16<B>, Mask16) {
    let (zero, one) = (F32x16::splat(k, 0.0), F32x16::splat(k, 1.0));
    // Stretch to the hemisphere configuration (α = 1).
    let (wi_std, stretched) = try_normalize(k, Vec3x16::new(alpha * wi.x, alpha * wi.y, wi.z));
    let lanes = lanes & stretched;
    // Sample the spherical cap of directions seen from wi_std.
    let phi = F32x16::splat(k, 2.0 * PI) * u[0];
    let z = (one - u[1]) * (one + wi_std.z) - wi_std.z;
    let sin_theta = (one - z * z).clamp(zero, one).sqrt();
    let (cos_phi, sin_phi) = cos_sin(k, phi, lanes);
    let h = Vec3x16::new(sin_theta * cos_phi, sin_theta * sin_phi, z) + wi_std;
    // Unstretch back to the ellipsoid configuration.
    let (m, normalised) = try_normalize(k, Vec3x16::new(alpha * h.x, alpha * h.y, h.z.max(zero)));
    (m, lanes & normalised)
}

/// `(cos φ, sin φ)` by the scalar libm functions in the `lanes` (0 in the
/// others).
#[inline(always)]
fn cos_sin<B: Lanes>(k: B, phi: F32x16<B>, lanes: Mask16) -> (F32x16<B>, F32x16<B>) {
    let phi = phi.to_array();
    let (mut cos, mut sin) = ([0.0; LANES], [0.0; LANES]);
    for lane in lanes.lanes() {
        cos[lane] = phi[lane].cos();
        sin[lane] = phi[lane].sin();
    }
    (F32x16::from_array(k, cos), F32x16::from_array(k, sin))
}

/// glam's `try_normalize` in every lane: `v · (1/|v|)`, and the lanes where
/// `1/|v|` is finite and positive (where glam returns `Some`).
#[inline(always)]
fn try_normalize<B: Lanes>(k: B, v: Vec3x16<B>) -> (Vec3x16<B>, Mask16) {
    let rcp = F32x16::splat(k, 1.0) / v.length();
    (v * rcp, rcp.is_finite() & rcp.gt(F32x16::splat(k, 0.0)))
}

/// [`reflect`](crate::materials::fresnel::reflect) in every lane.
#[inline(always)]
fn reflect<B: Lanes>(k: B, wi: Vec3x16<B>, m: Vec3x16<B>) -> Vec3x16<B> {
    -wi + m * (F32x16::splat(k, 2.0) * wi.dot(m))
}
