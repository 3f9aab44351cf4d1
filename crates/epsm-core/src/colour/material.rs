//! Colour derivatives for material values at fixed sampled directions:
//! each parameter's material is evaluated at `θ ± h` ([`Probe`]) and the
//! path's terms after a vertex of that material scale by `∂ ln f/∂θ`.
//!
//! | parameter | factor | derivative |
//! |---|---|---|
//! | `albedo.r/g/b` (diffuse) | `f·|cos|` | central difference (exact: linear) |
//! | `alpha` (rough conductor) | `f·|cos|` | central difference, `h = 1e-3·max(α, 1e-3)` |
//! | `ior` (dielectric) | the lobe's weight over its fixed choice probability: `F` (reflection), `(1 − F)/η²` (refraction) | central difference, `h = 1e-4·ior` |
//!
//! The refracted direction's change with `ior` moves the chain: that is a
//! position effect, differentiated through `dp/dθ`.

use epsm_render::materials::fresnel::fresnel_dielectric;
use epsm_render::materials::{Bsdf, Lobe, Material, Texture};
use glam::{Vec2, Vec3};

use crate::drops::DropReason;
use crate::params::Target;

/// One material parameter with the material moved to `θ ± h`.
#[derive(Clone, Debug)]
pub(super) struct Probe {
    pub(super) param: usize,
    /// `(θ + h) − max(θ − h, 0)`: the width of the central difference.
    width: f32,
    plus: Material,
    minus: Material,
}

/// `material` with the value of `target` set to `value` (unchanged when the
/// target does not apply).
fn with_value(material: &Material, target: Target, value: f32) -> Material {
    let mut m = material.clone();
    match (&mut m.bsdf, target) {
        (Bsdf::Diffuse(d), Target::Albedo { channel, .. }) => {
            if let Texture::Constant(c) = &mut d.albedo {
                c[channel] = value;
            }
        }
        (Bsdf::RoughConductor(r), Target::Alpha { .. }) => r.alpha = value,
        (Bsdf::Dielectric(d), Target::Ior { .. }) => d.ior = value,
        _ => {}
    }
    m
}

impl Probe {
    /// The probe of parameter `param` (value `v`, driving `target`) on `material`.
    pub(super) fn new(param: usize, material: &Material, target: Target, v: f32) -> Self {
        let h = match target {
            Target::Alpha { .. } => 1e-3 * v.max(1e-3),
            Target::Ior { .. } => 1e-4 * v.abs().max(1.0),
            _ => 1e-3,
        };
        let lo = (v - h).max(0.0);
        Self {
            param,
            width: v + h - lo,
            plus: with_value(material, target, v + h),
            minus: with_value(material, target, lo),
        }
    }

    /// `∂ ln f/∂θ` per channel of a non-delta scattering from `wi` to `wo`
    /// (local directions; 0 where `f = 0`).
    pub(super) fn ratio(&self, wi: Vec3, wo: Vec3) -> Vec3 {
        let uv = Vec2::ZERO;
        log_rate(
            self.plus.eval(wi, wo, uv),
            self.minus.eval(wi, wo, uv),
            self.width,
        )
    }

    /// `∂ ln w/∂θ` of a delta lobe's weight `w` for local `wi`. Fails with
    /// [`DropReason::TotalInternalReflection`] when the weight vanishes on
    /// one side of the difference only (a refraction at the critical angle
    /// of `ior ± h`).
    pub(super) fn delta_ratio(&self, wi: Vec3, lobe: Lobe) -> Result<Vec3, DropReason> {
        let w = |m: &Material| match &m.bsdf {
            Bsdf::Dielectric(d) => {
                let eta = if wi.z >= 0.0 { d.ior } else { 1.0 / d.ior };
                let f = fresnel_dielectric(wi.z.abs(), eta);
                Vec3::splat(if lobe.is_transmission() {
                    (1.0 - f) / (eta * eta)
                } else {
                    f
                })
            }
            _ => Vec3::ZERO,
        };
        let (p, m) = (w(&self.plus), w(&self.minus));
        if p.cmpgt(Vec3::ZERO) != m.cmpgt(Vec3::ZERO) {
            return Err(DropReason::TotalInternalReflection);
        }
        Ok(log_rate(p, m, self.width))
    }
}

/// `∂ ln f` per channel from `f(θ + h) = p`, `f(θ − h) = m` over `width`
/// (0 where `f = 0`).
fn log_rate(p: Vec3, m: Vec3, width: f32) -> Vec3 {
    let f = 0.5 * (p + m);
    Vec3::select(f.cmpgt(Vec3::ZERO), (p - m) / width / f, Vec3::ZERO)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn log_rate_of_a_small_positive_value_is_not_zeroed() {
        let r = log_rate(Vec3::splat(2e-21), Vec3::splat(1e-21), 1.0);
        assert!(
            (r - Vec3::splat(2.0 / 3.0)).abs().max_element() < 1e-6,
            "{r}"
        );
        assert_eq!(log_rate(Vec3::ZERO, Vec3::ZERO, 1.0), Vec3::ZERO);
    }

    #[test]
    fn an_ior_difference_reaching_total_internal_reflection_is_dropped() {
        let glass = super::super::glass();
        let probe = Probe::new(0, &glass, Target::Ior { material: 0 }, 1.5);
        let lobe = Lobe::SpecularTransmission;
        // From inside, just past the critical cosine of ior 1.5 (0.745356)
        // but not of ior 1.5 + h (0.745415).
        let wi = |z: f32| Vec3::new((1.0 - z * z).sqrt(), 0.0, -z);
        assert_eq!(
            probe.delta_ratio(wi(0.74538), lobe),
            Err(DropReason::TotalInternalReflection)
        );
        let away = probe.delta_ratio(wi(0.9), lobe).expect("far from critical");
        assert!(away.is_finite() && away != Vec3::ZERO);
    }
}
