//! Colour derivatives for material values at fixed sampled directions:
//! each parameter's material is evaluated at `θ ± h` ([`Probe`]; a
//! dielectric's IOR uses the analytic Fresnel derivative instead) and the
//! path's terms after a vertex of that material scale by `∂ ln f/∂θ`.
//!
//! | parameter | factor | derivative |
//! |---|---|---|
//! | `albedo.r/g/b` (diffuse) | `f·|cos|` | central difference (exact: linear) |
//! | `alpha` (rough conductor) | `f·|cos|` | central difference, `h = 1e-3·max(α, 1e-3)` |
//! | `ior` (dielectric) | the lobe's weight over its fixed choice probability: `F` (reflection), `(1 − F)/η²` (refraction) | analytic `∂F/∂η` in `f64` |
//!
//! The refracted direction's change with `ior` moves the vertices behind
//! the interface: in L2 iterations a geometric term (`place.rs`, the next
//! vertex on the turned ray), with OT a position effect through `dp/dθ`.

use epsm_render::materials::{Bsdf, Lobe, Material, Texture};
use glam::{Vec2, Vec3};

use super::chain::lobe_fresnel;
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
    /// The IOR at θ when the parameter is this dielectric's IOR.
    ior: Option<f64>,
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
        let ior = match (&material.bsdf, target) {
            (Bsdf::Dielectric(_), Target::Ior { .. }) => Some(f64::from(v)),
            _ => None,
        };
        Self {
            param,
            width: v + h - lo,
            plus: with_value(material, target, v + h),
            minus: with_value(material, target, lo),
            ior,
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

    /// `∂ ln w/∂θ` of a delta lobe's weight `w` for local `wi`, from the
    /// analytic `∂F/∂η` in `f64` (0 unless θ is this dielectric's IOR).
    /// Fails with [`DropReason::TotalInternalReflection`] when the weight
    /// vanishes or `wi` is [`near_critical`](super::chain::near_critical).
    pub(super) fn delta_ratio(&self, wi: Vec3, lobe: Lobe) -> Result<Vec3, DropReason> {
        let Some(ior) = self.ior else {
            return Ok(Vec3::ZERO);
        };
        let cos = f64::from(wi.z);
        // η(wo side)/η(wi side) and its rate with the IOR.
        let (eta, deta) = if cos >= 0.0 {
            (ior, 1.0)
        } else {
            (1.0 / ior, -1.0 / (ior * ior))
        };
        let w = lobe_fresnel(lobe, cos, eta)?;
        let rate = if lobe.is_transmission() {
            w.d_eta / w.f - 2.0 / eta
        } else {
            w.d_eta / w.f
        };
        Ok(Vec3::splat((rate * deta) as f32))
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
    use epsm_render::materials::fresnel::fresnel_dielectric;

    #[test]
    fn log_rate_of_a_small_positive_value_is_not_zeroed() {
        let r = log_rate(Vec3::splat(2e-21), Vec3::splat(1e-21), 1.0);
        assert!(
            (r - Vec3::splat(2.0 / 3.0)).abs().max_element() < 1e-6,
            "{r}"
        );
        assert_eq!(log_rate(Vec3::ZERO, Vec3::ZERO, 1.0), Vec3::ZERO);
    }

    /// `∂ ln w/∂ior` by Richardson-extrapolated central differences of the
    /// `f64` Fresnel term, with a step 1e-2 of the distance from `ior` to
    /// the IOR whose critical cosine is `|cos|` (from inside) or to `ior/2`.
    fn reference_rate(lobe: Lobe, ior: f64, cos: f64) -> f64 {
        let ln_w = |ior: f64| {
            let eta = if cos >= 0.0 { ior } else { 1.0 / ior };
            let f = fresnel_dielectric(cos.abs(), eta);
            if lobe.is_transmission() {
                (1.0 - f) / (eta * eta)
            } else {
                f
            }
            .ln()
        };
        let critical = 1.0 / (1.0 - cos * cos).sqrt();
        let room = if cos < 0.0 {
            (ior - critical).abs().min(0.5 * ior)
        } else {
            0.5 * ior
        };
        super::super::richardson(ln_w, ior, 1e-2 * room)
    }

    #[test]
    fn the_ior_rate_of_a_delta_lobe_matches_an_f64_reference() {
        let glass = super::super::glass();
        let probe = Probe::new(0, &glass, Target::Ior { material: 0 }, 1.5);
        let mut worst = 0.0f64;
        let mut table = String::new();
        // Entering at grazing, oblique and normal incidence; leaving near
        // the critical cosine 0.7454 and at normal incidence.
        for cos in [1e-3f32, 1e-2, 0.5, 0.9995, -0.76, -0.9995] {
            let wi = Vec3::new((1.0 - cos * cos).sqrt(), 0.0, cos);
            for lobe in [Lobe::SpecularReflection, Lobe::SpecularTransmission] {
                let rate = probe.delta_ratio(wi, lobe).expect("not near TIR");
                let reference = reference_rate(lobe, 1.5, f64::from(cos));
                let error = ((f64::from(rate.x) - reference) / reference).abs();
                worst = worst.max(error);
                table += &format!(
                    "\n{lobe:?} cos {cos}: {} vs {reference}, relative error {error:.2e}",
                    rate.x
                );
            }
        }
        assert!(worst < 1e-6, "worst relative error {worst:.2e}:{table}");
    }

    #[test]
    fn an_ior_rate_near_the_critical_angle_is_dropped() {
        let glass = super::super::glass();
        let probe = Probe::new(0, &glass, Target::Ior { material: 0 }, 1.5);
        let lobe = Lobe::SpecularTransmission;
        // From inside, 2.4e-5 past the critical cosine of ior 1.5 (0.745356),
        // within near_critical's 7.5e-4.
        let wi = |z: f32| Vec3::new((1.0 - z * z).sqrt(), 0.0, -z);
        assert_eq!(
            probe.delta_ratio(wi(0.74538), lobe),
            Err(DropReason::TotalInternalReflection)
        );
        // Total internal reflection well inside: the weight F = 1 is constant.
        assert_eq!(
            probe.delta_ratio(wi(0.5), Lobe::SpecularReflection),
            Ok(Vec3::ZERO)
        );
        let away = probe.delta_ratio(wi(0.9), lobe).expect("far from critical");
        assert!(away.is_finite() && away != Vec3::ZERO);
    }
}
