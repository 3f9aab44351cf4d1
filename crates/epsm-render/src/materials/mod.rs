//! Materials: a closed set of BSDFs dispatched by `match` (STYLE habit 3).
//!
//! All functions work in the local shading frame (`+z` = shading normal) with
//! the crate's `wi`/`wo` convention. `eval` includes `|cos θo|`.

use std::sync::Arc;

use glam::{Vec2, Vec3};

use crate::film::Image;

/// A colour that is constant or looked up in an image by texture coordinates.
#[derive(Clone, Debug, PartialEq)]
pub enum Texture {
    /// The same linear RGB everywhere.
    Constant(Vec3),
    /// A linear-RGB image (decoded from sRGB PNG or linear EXR), bilinear, wrapping.
    Image(Arc<Image>),
}

/// Lambertian reflection.
#[derive(Clone, Debug, PartialEq)]
pub struct Diffuse {
    /// Albedo in [0, 1] per channel.
    pub albedo: Texture,
}

/// Smooth conductor: a perfect mirror whose Fresnel reflectance is `tint`.
#[derive(Clone, Debug, PartialEq)]
pub struct Conductor {
    /// Reflectance per channel, in [0, 1].
    pub tint: Vec3,
}

/// Rough conductor: GGX microfacets with visible-normal sampling; Fresnel
/// reflectance `tint` (constant over angle).
#[derive(Clone, Debug, PartialEq)]
pub struct RoughConductor {
    /// GGX roughness α (isotropic), in [1e-4, 1].
    pub alpha: f32,
    /// Reflectance per channel, in [0, 1].
    pub tint: Vec3,
}

/// Smooth dielectric interface (glass), exterior IOR 1.
#[derive(Clone, Debug, PartialEq)]
pub struct Dielectric {
    /// Interior index of refraction relative to the exterior (> 0, ≠ 1 in practice).
    pub ior: f32,
}

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

/// What kind of manifold vertex a material makes (DESIGN §5.4).
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
    pub fn vertex_kind(&self) -> VertexKind {
        match self.bsdf {
            Bsdf::Diffuse(_) => VertexKind::Diffuse,
            Bsdf::Conductor(_) | Bsdf::Dielectric(_) => VertexKind::Specular,
            Bsdf::RoughConductor(_) => VertexKind::Glossy,
        }
    }

    /// Whether every lobe is a delta (no next-event estimation possible).
    pub fn is_delta(&self) -> bool {
        self.vertex_kind() == VertexKind::Specular
    }

    /// Samples `wo` given `wi` (local), texture coordinates, one number for
    /// the lobe choice and two for the direction. `None` when the sample
    /// carries no energy (back face of a one-sided material, below horizon).
    pub fn sample(&self, wi: Vec3, uv: Vec2, u_lobe: f32, u: Vec2) -> Option<BsdfSample> {
        let _ = (wi, uv, u_lobe, u);
        unimplemented!("materials: implemented on the materials branch")
    }

    /// `f(wi, wo)·|cos θo|` for the non-delta lobes (local directions).
    pub fn eval(&self, wi: Vec3, wo: Vec3, uv: Vec2) -> Vec3 {
        let _ = (wi, wo, uv);
        unimplemented!("materials: implemented on the materials branch")
    }

    /// Solid-angle pdf with which `sample` returns `wo` through a non-delta lobe.
    pub fn pdf(&self, wi: Vec3, wo: Vec3, uv: Vec2) -> f32 {
        let _ = (wi, wo, uv);
        unimplemented!("materials: implemented on the materials branch")
    }
}
