//! Delta (specular) vertices in the L2 convention: the vertex after a
//! mirror or glass interface stays on the ray the interface scatters
//! toward, as a conventional renderer re-tracing fixed sample numbers
//! would find it (the pixel's own vertex stays on its camera ray the same
//! way, [`super::geometry`]).
//!
//! The scattered direction `r(wi, n)` (mirror reflection, or Snell
//! refraction with the recorded relative IOR `η`) is differentiated by
//! forward-mode duals; the next vertex's tangent step `du` then solves
//! `P⊥(∂x/∂u du) = t·dr − P⊥(dx_attached − dx_prev)` on the two directions
//! perpendicular to `r` (`t` = segment length, `P⊥ = I − r rᵀ`). The delta
//! lobe's weight over its fixed choice probability is `F(cos θi)` or
//! `(1 − F)/η²` for a dielectric and the constant tint for a conductor.

use epsm_render::frame::basis_f64;
use epsm_render::materials::fresnel::{FresnelRates, fresnel_dielectric_rates};
use epsm_render::materials::{Bsdf, Lobe, Material};
use glam::{DVec2, DVec3};
use nalgebra::{RealField, Vector3};
use num_dual::Dual64;

use crate::drops::DropReason;

/// The direction `wi` (unit, away from the surface) scatters into at a
/// surface of unit normal `n`: mirror reflection, or refraction with
/// relative IOR `eta` (`η(wo side)/η(wi side)`). `None` under total
/// internal reflection.
fn scatter<T: RealField + Copy>(
    wi: &Vector3<T>,
    n: &Vector3<T>,
    eta: T,
    transmit: bool,
) -> Option<Vector3<T>> {
    let c = n.dot(wi);
    let two: T = nalgebra::convert(2.0);
    if !transmit {
        return Some(n * (c * two) - wi);
    }
    // The normal on the side of wi.
    let (n, c) = if c >= T::zero() { (*n, c) } else { (-n, -c) };
    let inv: T = T::one() / eta;
    let s2 = inv * inv * (T::one() - c * c);
    if s2 >= T::one() {
        return None;
    }
    let ct = (T::one() - s2).sqrt();
    Some(-wi * inv + n * (inv * c - ct))
}

fn dual(v: DVec3, d: DVec3) -> Vector3<Dual64> {
    Vector3::new(
        Dual64::new(v.x, d.x),
        Dual64::new(v.y, d.y),
        Dual64::new(v.z, d.z),
    )
}

/// The scattered direction at a delta vertex and its derivative, given
/// `wi`, the normal and the relative IOR `eta` with their derivatives.
pub(super) fn scattered(
    wi: DVec3,
    dwi: DVec3,
    n: DVec3,
    dn: DVec3,
    [eta, deta]: [f64; 2],
    transmit: bool,
) -> Option<[DVec3; 2]> {
    let r = scatter(
        &dual(wi, dwi),
        &dual(n, dn),
        Dual64::new(eta, deta),
        transmit,
    )?;
    Some([
        DVec3::new(r[0].re, r[1].re, r[2].re),
        DVec3::new(r[0].eps, r[1].eps, r[2].eps),
    ])
}

/// The tangent step `du` keeping the next vertex on the scattered ray:
/// `delta = x_next − x_delta` at θ, `r, dr` the direction and its
/// derivative, `d_rel = dx_next(attached) − dx_delta`, `dx_du` the next
/// vertex's tangents. `None` when the ray grazes the next surface.
pub(super) fn ray_step(
    delta: DVec3,
    r: DVec3,
    dr: DVec3,
    d_rel: DVec3,
    dx_du: [DVec3; 2],
) -> Option<DVec2> {
    let t = delta.dot(r);
    let (e1, e2) = basis_f64(r);
    let rhs = r_perp(t * dr - d_rel, e1, e2);
    let [a, b] = dx_du.map(|v| r_perp(v, e1, e2));
    let det = a.perp_dot(b);
    if det.abs() < 1e-9 * a.length_squared().max(b.length_squared()) {
        return None;
    }
    Some(DVec2::new(rhs.perp_dot(b), a.perp_dot(rhs)) / det)
}

fn r_perp(v: DVec3, e1: DVec3, e2: DVec3) -> DVec2 {
    DVec2::new(e1.dot(v), e2.dot(v))
}

/// `∂ ln w/∂θ` of a delta lobe's weight with `cos θi` changing at rate
/// `dcos` (`cos` signed: negative from inside a dielectric), from the
/// analytic `∂F/∂cos` in `f64`. Fails with
/// [`DropReason::TotalInternalReflection`] when the weight vanishes or
/// `cos` is [`near_critical`]: the rate grows as `1/(|cos| − cos_c)`
/// there, so a first-order step describes the weight only over changes of
/// `cos` smaller than that distance.
pub(super) fn weight_rate(
    material: &Material,
    lobe: Lobe,
    eta: f32,
    cos: f64,
    dcos: f64,
) -> Result<f64, DropReason> {
    let Bsdf::Dielectric(_) = material.bsdf else {
        return Ok(0.0);
    };
    let eta = f64::from(eta_of(lobe, eta, cos, material));
    let w = lobe_fresnel(lobe, cos, eta)?;
    Ok(w.d_cos / w.f * cos.signum() * dcos)
}

/// The Fresnel factor of a dielectric's delta `lobe` at signed `cos` and
/// relative IOR `eta`, with its rates: `F` for reflection, `1 − F` for
/// transmission (whose `1/η²` is the caller's). Fails with
/// [`DropReason::TotalInternalReflection`] when `cos` is [`near_critical`]
/// or the factor vanishes, where `ln` of it has no derivative to take.
pub(super) fn lobe_fresnel(lobe: Lobe, cos: f64, eta: f64) -> Result<FresnelRates, DropReason> {
    if near_critical(eta, cos) {
        return Err(DropReason::TotalInternalReflection);
    }
    let r = fresnel_dielectric_rates(cos.abs().min(1.0), eta);
    let w = if lobe.is_transmission() {
        FresnelRates {
            f: 1.0 - r.f,
            d_cos: -r.d_cos,
            d_eta: -r.d_eta,
        }
    } else {
        r
    };
    if w.f <= 0.0 {
        return Err(DropReason::TotalInternalReflection);
    }
    Ok(w)
}

/// Whether `|cos|` lies within `1e-3·max(|cos|, 1e-2)` of the critical
/// cosine `√(1 − η²)` of a relative IOR `eta < 1`, where the Fresnel
/// term's rates grow without bound and a first-order step is trusted only
/// over a smaller change.
pub(super) fn near_critical(eta: f64, cos: f64) -> bool {
    let critical = (1.0 - eta * eta).max(0.0).sqrt();
    eta < 1.0 && (cos.abs() - critical).abs() <= 1e-3 * cos.abs().max(1e-2)
}

/// The relative IOR `η(transmitted side)/η(wi side)` the Fresnel term uses.
fn eta_of(lobe: Lobe, eta: f32, cos: f64, material: &Material) -> f32 {
    match (&material.bsdf, lobe.is_transmission()) {
        (_, true) => eta,
        (Bsdf::Dielectric(d), false) => {
            if cos >= 0.0 {
                d.ior
            } else {
                1.0 / d.ior
            }
        }
        _ => 1.0,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use epsm_render::materials::fresnel::fresnel_dielectric;

    /// `∂ ln w/∂cos` by Richardson-extrapolated central differences of the
    /// `f64` Fresnel term, with a step 1e-2 of the distance from `cos` to
    /// the nearest point where `w` is not smooth (`|cos|` = 0 or 1, the
    /// critical cosine): truncation error ~1e-8 of the rate, rounding error
    /// ~1e-16 of `ln w` over the step.
    fn reference_rate(material: &Material, lobe: Lobe, eta: f32, cos: f64) -> f64 {
        let eta = f64::from(eta_of(lobe, eta, cos, material));
        let ln_w = |c: f64| {
            let f = fresnel_dielectric(c.abs(), eta);
            if lobe.is_transmission() { 1.0 - f } else { f }.ln()
        };
        let critical = (1.0 - eta * eta).max(0.0).sqrt();
        let room = cos
            .abs()
            .min(1.0 - cos.abs())
            .min((cos.abs() - critical).abs());
        super::super::richardson(ln_w, cos, 1e-2 * room)
    }

    #[test]
    fn the_weight_rate_matches_an_f64_reference_at_grazing_critical_and_normal_incidence() {
        let glass = super::super::glass();
        let (reflect, transmit) = (Lobe::SpecularReflection, Lobe::SpecularTransmission);
        // (lobe, recorded η, signed cos): entering at grazing incidence,
        // leaving near the critical cosine √(1 − 1/1.5²) ≈ 0.7454 (outside
        // total internal reflection), and near normal incidence both ways.
        let cases = [
            (transmit, 1.5, 1e-3),
            (reflect, 1.0, 1e-3),
            (transmit, 1.5, 1e-2),
            (reflect, 1.0, 1e-2),
            (transmit, 1.0 / 1.5, -0.75),
            (reflect, 1.0, -0.75),
            (transmit, 1.0 / 1.5, -0.76),
            (reflect, 1.0, -0.76),
            (transmit, 1.5, 0.9995),
            (reflect, 1.0, 0.9995),
            (transmit, 1.0 / 1.5, -0.9995),
            (reflect, 1.0, -0.9995),
        ];
        let mut worst = 0.0f64;
        let mut table = String::new();
        for (lobe, eta, cos) in cases {
            let rate = weight_rate(&glass, lobe, eta, cos, 1.0).expect("not near TIR");
            let reference = reference_rate(&glass, lobe, eta, cos);
            let error = ((rate - reference) / reference).abs();
            worst = worst.max(error);
            table +=
                &format!("\n{lobe:?} cos {cos}: {rate} vs {reference}, relative error {error:.2e}");
        }
        assert!(worst < 1e-6, "worst relative error {worst:.2e}:{table}");
    }

    #[test]
    fn a_refraction_weight_reaching_total_internal_reflection_is_dropped() {
        let glass = super::super::glass();
        let lobe = Lobe::SpecularTransmission;
        let eta = 1.0 / 1.5;
        // From inside: the critical cosine is √(1 − η²) ≈ 0.7454.
        assert_eq!(
            weight_rate(&glass, lobe, eta, -0.7456, 1.0),
            Err(DropReason::TotalInternalReflection)
        );
        let away = weight_rate(&glass, lobe, eta, -0.9, 1.0).expect("far from critical");
        assert!(away.is_finite() && away != 0.0);
    }
}
