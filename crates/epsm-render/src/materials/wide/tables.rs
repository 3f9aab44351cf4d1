//! [`Materials16`]'s tables: per material its kind and flags (one `u32`),
//! colour, α and IOR, each a column gathered by material index, and the
//! image albedos read per lane.

use glam::Vec3;

use crate::materials::{Bsdf, Material, Texture};
use crate::simd::{F32x16, Lanes, Mask16, U32x16, Vec3x16};

/// Kind codes in the low bits of [`Materials16`]'s `class`.
const DIFFUSE: u32 = 0;
/// Smooth conductor.
const CONDUCTOR: u32 = 1;
/// GGX conductor.
const ROUGH_CONDUCTOR: u32 = 2;
/// Smooth dielectric.
const DIELECTRIC: u32 = 3;
/// The bits of `class` that hold the kind.
const KIND: u32 = 3;
/// Flag of `class`: the material is two-sided.
const TWO_SIDED: u32 = 4;
/// Flag of `class`: the diffuse albedo is an image.
const IMAGE: u32 = 8;

/// The scene's materials as lane tables: per material its kind,
/// two-sidedness and parameters (gathered by material index).
#[derive(Clone, Debug)]
pub(crate) struct Materials16 {
    /// Kind code, `TWO_SIDED` and `IMAGE` flags.
    pub(super) class: Vec<u32>,
    /// Linear-RGB constant albedo (diffuse) or tint (conductors) by channel;
    /// 0 for other materials and image albedos.
    pub(super) colour: [Vec<f32>; 3],
    /// GGX α as the scalar code uses it (clamped into `[1e-4, 1]`) for rough
    /// conductors; 0 for others.
    pub(super) alpha: Vec<f32>,
    /// Interior IOR for dielectrics; 0 for others.
    pub(super) ior: Vec<f32>,
    /// The image albedo of diffuse materials that have one.
    pub(super) images: Vec<Option<Texture>>,
}

/// The active lanes of each kind, and of each flag.
#[derive(Clone, Copy, Debug)]
pub(super) struct Kinds {
    /// Lambertian lanes.
    pub(super) diffuse: Mask16,
    /// Smooth-conductor lanes.
    pub(super) conductor: Mask16,
    /// GGX-conductor lanes.
    pub(super) rough: Mask16,
    /// Dielectric lanes.
    pub(super) dielectric: Mask16,
    /// Lanes of two-sided materials.
    pub(super) two_sided: Mask16,
    /// Lanes whose diffuse albedo is an image.
    pub(super) image: Mask16,
}

impl Materials16 {
    /// The tables of `materials` (indexed as the slice).
    pub(crate) fn new(materials: &[Material]) -> Self {
        let mut t = Self {
            class: Vec::with_capacity(materials.len()),
            colour: Default::default(),
            alpha: Vec::with_capacity(materials.len()),
            ior: Vec::with_capacity(materials.len()),
            images: Vec::with_capacity(materials.len()),
        };
        for material in materials {
            let (mut colour, mut alpha, mut ior, mut image) = (Vec3::ZERO, 0.0, 0.0, None);
            let kind = match &material.bsdf {
                Bsdf::Diffuse(d) => {
                    match &d.albedo {
                        Texture::Constant(c) => colour = *c,
                        Texture::Image(_) => image = Some(d.albedo.clone()),
                    }
                    DIFFUSE
                }
                Bsdf::Conductor(c) => {
                    colour = c.tint;
                    CONDUCTOR
                }
                Bsdf::RoughConductor(r) => {
                    colour = r.tint;
                    alpha = r.ggx().alpha;
                    ROUGH_CONDUCTOR
                }
                Bsdf::Dielectric(d) => {
                    ior = d.ior;
                    DIELECTRIC
                }
            };
            let flag = |on: bool, bit: u32| if on { bit } else { 0 };
            t.class
                .push(kind | flag(material.two_sided, TWO_SIDED) | flag(image.is_some(), IMAGE));
            for (channel, c) in t.colour.iter_mut().zip(colour.to_array()) {
                channel.push(c);
            }
            t.alpha.push(alpha);
            t.ior.push(ior);
            t.images.push(image);
        }
        t
    }

    /// The kinds and flags of the materials of the `active` lanes.
    #[inline(always)]
    pub(super) fn kinds<B: Lanes>(&self, k: B, material: U32x16<B>, active: Mask16) -> Kinds {
        let class = U32x16::gather(&self.class, material, active, k.u32(0));
        let kind = class & k.u32(KIND);
        // The lanes of kind `code`; the lanes with flag `bit` (plain
        // functions, not closures: module `simd`).
        #[inline(always)]
        fn of<B: Lanes>(k: B, kind: U32x16<B>, code: u32) -> Mask16 {
            kind.eq(k.u32(code))
        }
        #[inline(always)]
        fn flag<B: Lanes>(k: B, class: U32x16<B>, bit: u32) -> Mask16 {
            (class & k.u32(bit)).eq(k.u32(bit))
        }
        Kinds {
            diffuse: of(k, kind, DIFFUSE) & active,
            conductor: of(k, kind, CONDUCTOR) & active,
            rough: of(k, kind, ROUGH_CONDUCTOR) & active,
            dielectric: of(k, kind, DIELECTRIC) & active,
            two_sided: flag(k, class, TWO_SIDED) & active,
            image: flag(k, class, IMAGE) & active,
        }
    }

    /// The constant colour (albedo or tint) of the materials of the `lanes`;
    /// 0 in the other lanes.
    #[inline(always)]
    pub(super) fn colour<B: Lanes>(&self, k: B, material: U32x16<B>, lanes: Mask16) -> Vec3x16<B> {
        let zero = F32x16::splat(k, 0.0);
        let [r, g, b] = &self.colour;
        Vec3x16::new(
            F32x16::gather(r, material, lanes, zero),
            F32x16::gather(g, material, lanes, zero),
            F32x16::gather(b, material, lanes, zero),
        )
    }

    /// A per-material parameter of the `lanes`; 0 in the other lanes.
    #[inline(always)]
    pub(super) fn param<B: Lanes>(
        table: &[f32],
        k: B,
        material: U32x16<B>,
        lanes: Mask16,
    ) -> F32x16<B> {
        F32x16::gather(table, material, lanes, F32x16::splat(k, 0.0))
    }
}
