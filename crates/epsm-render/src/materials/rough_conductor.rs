//! Rough conductor: GGX microfacet reflection (Walter et al. 2007) with
//! visible-normal sampling and a constant Fresnel reflectance `tint`.
//!
//! `f·cos θo = tint · D(m) G2(wi, wo) / (4 cos θi)` with `m = normalize(wi + wo)`
//! and the height-correlated Smith `G2` ([`super::microfacet`]). Sampling draws
//! a visible normal `m` from `wi` and reflects, so
//! `pdf = G1(wi) D(m) / (4 cos θi)` and the weight is `tint · G2 / G1(wi)`.
//! Reflections that fall below the surface are rejected (`None`).
//!
//! | key | unit | default | range |
//! |---|---|---|---|
//! | `alpha` | — (GGX roughness) | — | [1e-4, 1] |
//! | `tint` | linear RGB | — | [0, 1] per channel |
//!
//! ```toml
//! [[materials]]
//! name = "brushed"
//! type = "rough_conductor"
//! alpha = 0.2
//! tint = [0.9, 0.6, 0.3]
//! ```

use glam::{Vec2, Vec3};

use super::fresnel::reflect;
use super::microfacet::Ggx;
use super::{BsdfSample, Lobe};

/// Rough conductor: GGX microfacets with visible-normal sampling; Fresnel
/// reflectance `tint` (constant over angle).
#[derive(Clone, Debug, PartialEq)]
pub struct RoughConductor {
    /// GGX roughness α (isotropic), in [1e-4, 1].
    pub alpha: f32,
    /// Reflectance per channel, in [0, 1].
    pub tint: Vec3,
}

impl RoughConductor {
    fn ggx(&self) -> Ggx {
        Ggx { alpha: self.alpha }
    }

    /// Samples a visible normal and reflects `wi` (local, `wi.z > 0`) about it.
    pub(super) fn sample(&self, wi: Vec3, u: Vec2) -> Option<BsdfSample> {
        if wi.z <= 0.0 {
            return None;
        }
        let ggx = self.ggx();
        let m = ggx.sample_visible(wi, u)?;
        let cos_im = wi.dot(m);
        if cos_im <= 0.0 {
            return None;
        }
        let wo = reflect(wi, m);
        if wo.z <= 0.0 {
            return None;
        }
        let pdf = ggx.g1(wi) * ggx.d(m) / (4.0 * wi.z);
        if !(pdf > 0.0 && pdf.is_finite()) {
            return None;
        }
        let lambda_i = ggx.lambda(wi);
        let weight = self.tint * ((1.0 + lambda_i) / (1.0 + lambda_i + ggx.lambda(wo)));
        Some(BsdfSample {
            wo,
            weight,
            pdf,
            lobe: Lobe::GlossyReflection,
            eta: 1.0,
            m,
        })
    }

    /// `tint · D(m) G2 / (4 cos θi)` for both directions above the surface.
    pub(super) fn eval(&self, wi: Vec3, wo: Vec3) -> Vec3 {
        match half_vector(wi, wo) {
            Some(m) => {
                let ggx = self.ggx();
                self.tint * (ggx.d(m) * ggx.g2(wi, wo) / (4.0 * wi.z))
            }
            None => Vec3::ZERO,
        }
    }

    /// `G1(wi) D(m) / (4 cos θi)` for both directions above the surface.
    pub(super) fn pdf(&self, wi: Vec3, wo: Vec3) -> f32 {
        match half_vector(wi, wo) {
            Some(m) => {
                let ggx = self.ggx();
                ggx.g1(wi) * ggx.d(m) / (4.0 * wi.z)
            }
            None => 0.0,
        }
    }
}

/// The reflection half vector when both directions are above the surface.
fn half_vector(wi: Vec3, wo: Vec3) -> Option<Vec3> {
    if wi.z <= 0.0 || wo.z <= 0.0 {
        return None;
    }
    (wi + wo).try_normalize()
}
