//! Materials: a closed set of BSDFs dispatched by `match`.
//!
//! All functions work in the local shading frame (`+z` = shading normal) with
//! the crate's `wi`/`wo` convention. `eval` includes `|cos θo|`.
//!
//! | variant | file | vertex kind | lobes |
//! |---|---|---|---|
//! | [`Diffuse`] | `diffuse.rs` | diffuse | cosine-weighted reflection |
//! | [`Conductor`] | `conductor.rs` | specular | mirror reflection |
//! | [`RoughConductor`] | `rough_conductor.rs` | glossy | GGX reflection ([`microfacet`]) |
//! | [`Dielectric`] | `dielectric.rs` | specular | Fresnel reflection + refraction ([`fresnel`]) |
//!
//! Sidedness: a one-sided material (`two_sided = false`) does not scatter
//! light arriving from behind (`wi.z ≤ 0`: `sample` is `None`, `eval` and `pdf`
//! are 0). A two-sided material seen from behind is mirrored through the
//! tangent plane. Reflection lobes need `wo` on the side of `wi`.

pub mod conductor;
pub mod dielectric;
pub mod diffuse;
pub mod fresnel;
pub mod microfacet;
mod real;
pub mod rough_conductor;
pub mod texture;
#[cfg(target_arch = "x86_64")]
pub(crate) mod wide;

#[cfg(test)]
pub(crate) mod test_support;
#[cfg(test)]
mod tests;

use glam::{Vec2, Vec3};

pub use conductor::Conductor;
pub use dielectric::Dielectric;
pub use diffuse::Diffuse;
pub use rough_conductor::RoughConductor;
pub use texture::Texture;

use crate::frame::Frame;
use crate::hit::TexCoords;

/// The BSDF of a material.
#[derive(Clone, Debug, PartialEq)]
pub enum Bsdf {
    /// Lambertian.
    Diffuse(Diffuse),
    /// Smooth conductor (mirror).
    Conductor(Conductor),
    /// GGX conductor.
    RoughConductor(RoughConductor),
    /// Smooth dielectric.
    Dielectric(Dielectric),
}

/// A named material.
#[derive(Clone, Debug, PartialEq)]
pub struct Material {
    /// Unique name in its scene.
    pub name: String,
    /// The BSDF.
    pub bsdf: Bsdf,
    /// Whether the back face reflects like the front face. Dielectrics are
    /// always two-sided (they have an inside).
    pub two_sided: bool,
}

/// What kind of manifold vertex a material makes (docs/design.md §5.4).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum VertexKind {
    /// Ends a specular chain (Lambertian).
    Diffuse,
    /// Delta reflection or refraction.
    Specular,
    /// Rough microfacet lobe; the sampled microfacet normal is kept.
    Glossy,
}

/// The lobe that scattered a path.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Lobe {
    /// Lambertian reflection.
    DiffuseReflection,
    /// Delta reflection (mirror or dielectric reflection).
    SpecularReflection,
    /// Delta refraction.
    SpecularTransmission,
    /// Microfacet reflection.
    GlossyReflection,
}

impl Lobe {
    /// Whether the lobe is a delta distribution.
    pub fn is_delta(self) -> bool {
        matches!(self, Lobe::SpecularReflection | Lobe::SpecularTransmission)
    }
    /// Whether the lobe transmits.
    pub fn is_transmission(self) -> bool {
        matches!(self, Lobe::SpecularTransmission)
    }
}

/// A sampled scattering direction.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BsdfSample {
    /// Sampled direction, local frame, unit.
    pub wo: Vec3,
    /// `f·|cos θo| / pdf` (for delta lobes: the lobe's weight, e.g. tint or 1 after the Fresnel choice, including the radiance scaling 1/η² on refraction).
    pub weight: Vec3,
    /// Solid-angle pdf of `wo`; for delta lobes the discrete probability of the lobe choice.
    pub pdf: f32,
    /// Which lobe scattered.
    pub lobe: Lobe,
    /// Relative IOR `η(wo side) / η(wi side)`; 1 for reflection.
    pub eta: f32,
    /// The microfacet normal, local frame: the sampled one for glossy lobes,
    /// `+z` (the shading normal) for smooth lobes, and `+z` for diffuse.
    pub m: Vec3,
}

impl Material {
    /// The kind of manifold vertex this material makes.
    #[inline(always)]
    pub fn vertex_kind(&self) -> VertexKind {
        match self.bsdf {
            Bsdf::Diffuse(_) => VertexKind::Diffuse,
            Bsdf::Conductor(_) | Bsdf::Dielectric(_) => VertexKind::Specular,
            Bsdf::RoughConductor(_) => VertexKind::Glossy,
        }
    }

    /// World direction `v` in `frame`'s local coordinates as far as this
    /// material reads them: the full [`Frame::to_local`], except for
    /// Lambertian reflection, whose `sample`, `eval` and `pdf` read only
    /// `cos θ` (`z`, the same value bit for bit) and not the azimuth, so the
    /// tangent components are left at 0 (two dot products fewer per
    /// direction).
    #[inline(always)]
    pub fn to_local(&self, frame: &Frame, v: Vec3) -> Vec3 {
        match self.bsdf {
            Bsdf::Diffuse(_) => Vec3::new(0.0, 0.0, v.dot(frame.n)),
            _ => frame.to_local(v),
        }
    }

    /// Whether every lobe is a delta (no next-event estimation possible).
    #[inline(always)]
    pub fn is_delta(&self) -> bool {
        self.vertex_kind() == VertexKind::Specular
    }

    /// Samples `wo` given `wi` (local), texture coordinates, one number for
    /// the lobe choice and two for the direction. `None` when the sample
    /// carries no energy (back face of a one-sided material, below horizon).
    ///
    /// Two-sided materials seen from the back (`wi.z < 0`) are mirrored
    /// through the tangent plane: the returned `wo` and `m` are flipped back,
    /// so for reflection `m = normalize(wi + wo)` lies on the side of `wi`
    /// (`−z` for the smooth conductor and diffuse seen from the back).
    /// Dielectrics have an inside and are never mirrored (`m = +z` always).
    #[inline(always)]
    pub fn sample(
        &self,
        wi: Vec3,
        uv: impl Into<TexCoords>,
        u_lobe: f32,
        u: Vec2,
    ) -> Option<BsdfSample> {
        let side = match &self.bsdf {
            Bsdf::Dielectric(d) => return d.sample(wi, u_lobe),
            _ => self.side(wi)?,
        };
        let wi = side.apply(wi);
        let s = match &self.bsdf {
            Bsdf::Diffuse(d) => d.sample(uv.into(), u),
            Bsdf::Conductor(c) => c.sample(wi),
            Bsdf::RoughConductor(r) => r.sample(wi, u),
            Bsdf::Dielectric(_) => None,
        }?;
        Some(BsdfSample {
            wo: side.apply(s.wo),
            m: side.apply(s.m),
            ..s
        })
    }

    /// `f(wi, wo)·|cos θo|` for the non-delta lobes (local directions); zero
    /// for delta lobes, for directions in opposite hemispheres and for the
    /// back face of one-sided materials.
    #[inline(always)]
    pub fn eval(&self, wi: Vec3, wo: Vec3, uv: impl Into<TexCoords>) -> Vec3 {
        let Some(side) = self.side(wi) else {
            return Vec3::ZERO;
        };
        let (wi, wo) = (side.apply(wi), side.apply(wo));
        match &self.bsdf {
            Bsdf::Diffuse(d) => d.eval(wi, wo, uv.into()),
            Bsdf::RoughConductor(r) => r.eval(wi, wo),
            Bsdf::Conductor(_) | Bsdf::Dielectric(_) => Vec3::ZERO,
        }
    }

    /// Solid-angle pdf with which `sample` returns `wo` through a non-delta
    /// lobe (zero where `eval` is zero by construction, and for delta lobes).
    /// No current lobe's pdf depends on the texture coordinates `_uv`.
    #[inline(always)]
    pub fn pdf(&self, wi: Vec3, wo: Vec3, _uv: impl Into<TexCoords>) -> f32 {
        let Some(side) = self.side(wi) else {
            return 0.0;
        };
        let (wi, wo) = (side.apply(wi), side.apply(wo));
        match &self.bsdf {
            Bsdf::Diffuse(d) => d.pdf(wi, wo),
            Bsdf::RoughConductor(r) => r.pdf(wi, wo),
            Bsdf::Conductor(_) | Bsdf::Dielectric(_) => 0.0,
        }
    }

    /// Which side `wi` sees: `None` for the back of a one-sided material.
    #[inline(always)]
    fn side(&self, wi: Vec3) -> Option<Side> {
        if wi.z > 0.0 {
            Some(Side::Front)
        } else if wi.z < 0.0 && self.two_sided {
            Some(Side::Back)
        } else {
            None
        }
    }
}

/// The side of the surface `wi` lies on; the back is handled by mirroring
/// through the tangent plane.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Side {
    Front,
    Back,
}

impl Side {
    /// Maps a local direction into (and, being an involution, back out of)
    /// the front-side frame.
    #[inline]
    fn apply(self, w: Vec3) -> Vec3 {
        match self {
            Side::Front => w,
            Side::Back => Vec3::new(w.x, w.y, -w.z),
        }
    }
}
