//! Lambertian reflection in lanes ([`crate::materials::Diffuse`]), in the
//! front-side frame (mirroring is the caller's): cosine-weighted sampling by
//! the concentric map of [`cosine_hemisphere`](crate::materials::diffuse::cosine_hemisphere),
//! `albedo/π · cos θo`, and
//! `cos θo / π`.
//!
//! The constant albedo is gathered by material; an image albedo is looked up
//! per lane by the scalar [`crate::materials::Texture::eval`].

use std::f32::consts::{FRAC_1_PI, FRAC_PI_4};

use super::{BsdfSamples16, Materials16};
use crate::bvh::TexCoords16;
use crate::materials::diffuse::sin_cos_quarter;
use crate::simd::{F32x16, Lanes, Mask16, U32x16, Vec3x16};

/// `Diffuse::sample` in the `lanes` (`found` a subset of them).
#[inline(always)]
pub(super) fn sample<B: Lanes>(
    t: &Materials16,
    k: B,
    material: U32x16<B>,
    uv: &TexCoords16<B>,
    u: [F32x16<B>; 2],
    lanes: Mask16,
    image: Mask16,
) -> BsdfSamples16<B> {
    let wo = cosine_hemisphere16(k, u);
    let pdf = wo.z * F32x16::splat(k, FRAC_1_PI);
    let found = lanes.and_not(pdf.le(F32x16::splat(k, 0.0)));
    BsdfSamples16 {
        found,
        wo,
        weight: albedo(t, k, material, uv, found, image),
        pdf,
        ..BsdfSamples16::none(k)
    }
}

/// `Diffuse::eval` in the `lanes` (where `wi.z > 0`), `wo` local.
#[inline(always)]
pub(super) fn eval<B: Lanes>(
    t: &Materials16,
    k: B,
    material: U32x16<B>,
    wo: Vec3x16<B>,
    uv: &TexCoords16<B>,
    lanes: Mask16,
    image: Mask16,
) -> Vec3x16<B> {
    let zero = F32x16::splat(k, 0.0);
    let above = lanes.and_not(wo.z.le(zero));
    let f = albedo(t, k, material, uv, above, image) * (F32x16::splat(k, FRAC_1_PI) * wo.z);
    Vec3x16::select(above, f, Vec3x16::new(zero, zero, zero))
}

/// `Diffuse::pdf` in every lane where `wi.z > 0`, `wo` local.
#[inline(always)]
pub(super) fn pdf<B: Lanes>(k: B, wo: Vec3x16<B>) -> F32x16<B> {
    let zero = F32x16::splat(k, 0.0);
    F32x16::select(wo.z.le(zero), zero, F32x16::splat(k, FRAC_1_PI) * wo.z)
}

/// The albedo of the materials of the `lanes` at `uv` (0 elsewhere): gathered
/// constants, and the scalar texture lookup in the `lanes` of `image`.
#[inline(always)]
fn albedo<B: Lanes>(
    t: &Materials16,
    k: B,
    material: U32x16<B>,
    uv: &TexCoords16<B>,
    lanes: Mask16,
    image: Mask16,
) -> Vec3x16<B> {
    let constant = t.colour(k, material, lanes.and_not(image));
    let textured = lanes & image;
    if !textured.any() {
        return constant;
    }
    let mut albedo = constant.to_lanes();
    let index = material.to_array();
    for lane in textured.lanes() {
        if let Some(texture) = &t.images[index[lane] as usize] {
            albedo[lane] = texture.eval(uv.lane(lane));
        }
    }
    Vec3x16::from_lanes(k, &albedo)
}

/// [`cosine_hemisphere`](crate::materials::diffuse::cosine_hemisphere) in
/// every lane: the concentric map's sector swap is
/// a lane select, the quarter-circle sine and cosine the scalar polynomial.
#[inline(always)]
fn cosine_hemisphere16<B: Lanes>(k: B, u: [F32x16<B>; 2]) -> Vec3x16<B> {
    let (zero, one, two) = (
        F32x16::splat(k, 0.0),
        F32x16::splat(k, 1.0),
        F32x16::splat(k, 2.0),
    );
    let (dx, dy) = (two * u[0] - one, two * u[1] - one);
    let steep = dx.abs().le(dy.abs());
    let (rx, ry) = (F32x16::select(steep, dy, dx), F32x16::select(steep, dx, dy));
    let (sin, cos) = sin_cos_quarter(k, F32x16::splat(k, FRAC_PI_4) * (ry / rx));
    let centre = dx.eq(zero) & dy.eq(zero);
    let disk_x = F32x16::select(centre, zero, rx * F32x16::select(steep, sin, cos));
    let disk_y = F32x16::select(centre, zero, rx * F32x16::select(steep, cos, sin));
    let z = (one - (disk_x * disk_x + disk_y * disk_y)).max(zero).sqrt();
    Vec3x16::new(disk_x, disk_y, z)
}
