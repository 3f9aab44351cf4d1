//! Random inputs for the bit-identity tests: materials of every kind and
//! sidedness (α over `[1e-4, 1]` and outside it, IORs above and below 1, an
//! image albedo), several kinds in one call, random, grazing, tangent,
//! normal and degenerate directions on both sides, sample numbers at 0 and
//! just below 1, and lobe numbers at the Fresnel reflectance.

use std::sync::Arc;

use glam::{Vec2, Vec3};

use super::*;
use crate::film::Image;
use crate::hit::TexCoords;
use crate::materials::fresnel::fresnel_dielectric;
use crate::materials::test_support::Rng;
use crate::materials::{Bsdf, Conductor, Dielectric, Diffuse, Material, RoughConductor, Texture};
use crate::simd::LANES;

/// A random colour in `[0, 1)³`.
fn colour(rng: &mut Rng) -> Vec3 {
    Vec3::new(rng.f32(), rng.f32(), rng.f32())
}

/// Every kind with both sidedness values: constant and image albedos, α
/// at and between its bounds (and beyond them, clamped), IORs from 1.0001 to
/// 2.4 and below 1.
pub(super) fn materials(rng: &mut Rng) -> Vec<Material> {
    let mut image = Image::new(3, 2);
    for (x, y) in [(0, 0), (1, 0), (2, 0), (0, 1), (1, 1), (2, 1)] {
        image.set(x, y, colour(rng));
    }
    let image = Texture::Image(Arc::new(image));
    let log_alpha = |rng: &mut Rng| 10f64.powf(rng.range(-4.0, 0.0)) as f32;
    let mut bsdfs = vec![
        Bsdf::Diffuse(Diffuse {
            albedo: Texture::Constant(colour(rng)),
        }),
        Bsdf::Diffuse(Diffuse { albedo: image }),
        Bsdf::Conductor(Conductor { tint: colour(rng) }),
    ];
    for alpha in [1e-4, 1.0, 0.0, 2.0, log_alpha(rng), log_alpha(rng)] {
        bsdfs.push(Bsdf::RoughConductor(RoughConductor {
            alpha,
            tint: colour(rng),
        }));
    }
    let above = rng.range(1.0001, 2.4) as f32;
    let below = rng.range(0.3, 0.9999) as f32;
    for ior in [1.0001, 1.5, 2.4, 0.7, above, below] {
        bsdfs.push(Bsdf::Dielectric(Dielectric { ior }));
    }
    let mut out = Vec::new();
    for bsdf in bsdfs {
        for two_sided in [false, true] {
            out.push(Material {
                name: String::new(),
                bsdf: bsdf.clone(),
                two_sided,
            });
        }
    }
    out
}

/// A local direction: uniform, grazing, exactly tangent (`z = ±0`), along
/// `±z`, or degenerate (zero, or with a NaN component when `nan`).
pub(super) fn direction(rng: &mut Rng, nan: bool) -> Vec3 {
    let sign = |rng: &mut Rng| if rng.below(2) == 0 { 1.0 } else { -1.0 };
    let tangent = |rng: &mut Rng, z: f32| {
        let phi = rng.range(0.0, std::f64::consts::TAU);
        let r = (1.0 - f64::from(z) * f64::from(z)).sqrt();
        Vec3::new((r * phi.cos()) as f32, (r * phi.sin()) as f32, z)
    };
    match rng.below(16) {
        0..=7 => rng.sphere(),
        8 | 9 => {
            let z = sign(rng) * 10f64.powf(rng.range(-8.0, -1.0)) as f32;
            tangent(rng, z)
        }
        10 => {
            let z = sign(rng) * 0.0;
            tangent(rng, z)
        }
        11 => Vec3::Z * sign(rng),
        12 => Vec3::ZERO,
        13 if nan => {
            let mut v = rng.sphere();
            v[rng.below(3)] = f32::NAN;
            v
        }
        _ => rng.sphere() * sign(rng),
    }
}

/// A sample number in `[0, 1)`: uniform, 0, or just below 1.
fn unit(rng: &mut Rng) -> f32 {
    match rng.below(8) {
        0 => 0.0,
        1 => 1.0 - f32::EPSILON / 2.0,
        2 => 1e-7,
        _ => rng.f32(),
    }
}

/// Sixteen lanes of inputs to the material functions.
pub(super) struct Case {
    /// Material indices.
    pub(super) material: [u32; LANES],
    /// The lanes to compute.
    pub(super) active: Mask16,
    /// Incident directions, local.
    pub(super) wi: [Vec3; LANES],
    /// Outgoing directions for `eval` and `pdf`, local.
    pub(super) wo: [Vec3; LANES],
    /// Texture coordinates.
    pub(super) uv: [TexCoords; LANES],
    /// Lobe-choice numbers.
    pub(super) u_lobe: [f32; LANES],
    /// Direction numbers.
    pub(super) u: [Vec2; LANES],
}

impl Case {
    /// Random lanes over `materials`: all on one material (either
    /// sidedness) in some cases, mixed kinds in others; `wo` sometimes the scalar sample's direction from `wi`.
    pub(super) fn random(rng: &mut Rng, materials: &[Material]) -> Self {
        let one_kind = rng.below(4) == 0;
        let first = rng.below(materials.len());
        let material: [u32; LANES] = std::array::from_fn(|_| {
            if one_kind {
                // The two sidedness variants of one material are adjacent.
                (first & !1 | rng.below(2)) as u32
            } else {
                rng.below(materials.len()) as u32
            }
        });
        let active = if rng.below(2) == 0 {
            Mask16::ALL
        } else {
            Mask16(rng.u64() as u16)
        };
        let mut case = Self {
            material,
            active,
            wi: [Vec3::ZERO; LANES],
            wo: [Vec3::ZERO; LANES],
            uv: [TexCoords::Uv(Vec2::ZERO); LANES],
            u_lobe: [0.0; LANES],
            u: [Vec2::ZERO; LANES],
        };
        for lane in 0..LANES {
            let m = &materials[material[lane] as usize];
            let dielectric = matches!(m.bsdf, Bsdf::Dielectric(_));
            // The scalar `refract` debug-asserts a non-NaN cosine.
            case.wi[lane] = direction(rng, !dielectric);
            case.u[lane] = Vec2::new(unit(rng), unit(rng));
            case.u_lobe[lane] = unit(rng);
            if let (Bsdf::Dielectric(d), 0..=1) = (&m.bsdf, rng.below(4)) {
                // At and just below F: the lobe choice's edge.
                let wi = case.wi[lane];
                let eta = if wi.z >= 0.0 { d.ior } else { 1.0 / d.ior };
                let f = fresnel_dielectric(wi.z.abs(), eta);
                case.u_lobe[lane] = if rng.below(2) == 0 { f } else { f.next_down() };
            }
            case.uv[lane] = if rng.below(2) == 0 {
                TexCoords::Sphere(rng.sphere())
            } else {
                TexCoords::Uv(Vec2::new(rng.range(-1.0, 2.0) as f32, rng.f32()))
            };
            let sampled = (rng.below(4) == 0)
                .then(|| m.sample(case.wi[lane], case.uv[lane], unit(rng), rng.vec2()))
                .flatten();
            case.wo[lane] = match sampled {
                Some(s) => s.wo,
                None => direction(rng, true),
            };
        }
        case
    }

    /// The material indices as lanes.
    pub(super) fn material<B: Lanes>(&self, k: B) -> U32x16<B> {
        U32x16::from_array(k, self.material)
    }

    /// The texture coordinates as lanes.
    pub(super) fn uv<B: Lanes>(&self, k: B) -> TexCoords16<B> {
        let mut sphere = Mask16::NONE;
        let a = std::array::from_fn(|lane| match self.uv[lane] {
            TexCoords::Uv(uv) => uv.extend(0.0),
            TexCoords::Sphere(p) => {
                sphere.0 |= 1 << lane;
                p
            }
        });
        TexCoords16 {
            sphere,
            a: Vec3x16::from_lanes(k, &a),
        }
    }
}
