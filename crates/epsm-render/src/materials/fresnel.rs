//! Fresnel reflectance of a smooth dielectric interface, and the reflection
//! and refraction directions.
//!
//! Exact unpolarised Fresnel equations (the mean of the s- and p-polarised
//! reflectances; Born & Wolf, *Principles of Optics*, §1.5; pbrt-v4 §9.3).
//! All functions take a relative IOR `eta = η_t / η_i` (transmitted side over
//! incident side) and directions pointing away from the surface.
//!
//! | quantity | unit | range |
//! |---|---|---|
//! | `cos_i` | — | [0, 1] |
//! | `eta` | — | > 0 |

use glam::Vec3;

/// Unpolarised Fresnel reflectance for incidence cosine `cos_i ∈ [0, 1]` and
/// relative IOR `eta = η_t / η_i`. Returns 1 under total internal reflection.
#[inline]
pub fn fresnel_dielectric(cos_i: f32, eta: f32) -> f32 {
    debug_assert!(eta > 0.0);
    let cos_i = cos_i.clamp(0.0, 1.0);
    let sin2_t = (1.0 - cos_i * cos_i) / (eta * eta);
    if sin2_t >= 1.0 {
        return 1.0;
    }
    let cos_t = (1.0 - sin2_t).max(0.0).sqrt();
    let r_s = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    let r_p = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    (0.5 * (r_s * r_s + r_p * r_p)).clamp(0.0, 1.0)
}

/// Mirror reflection of `wi` about the unit normal `n`.
#[inline]
pub fn reflect(wi: Vec3, n: Vec3) -> Vec3 {
    -wi + 2.0 * wi.dot(n) * n
}

/// Refraction of `wi` (on the side of the unit normal `n`, `wi·n ≥ 0`) through
/// an interface with relative IOR `eta = η_t / η_i`. Returns the transmitted
/// direction (on the other side, pointing away from the surface), or `None`
/// under total internal reflection.
#[inline]
pub fn refract(wi: Vec3, n: Vec3, eta: f32) -> Option<Vec3> {
    debug_assert!(eta > 0.0);
    let cos_i = wi.dot(n);
    debug_assert!(cos_i >= -1e-6);
    let sin2_i = (1.0 - cos_i * cos_i).max(0.0);
    let sin2_t = sin2_i / (eta * eta);
    if sin2_t >= 1.0 {
        return None;
    }
    let cos_t = (1.0 - sin2_t).sqrt();
    Some(-wi / eta + (cos_i / eta - cos_t) * n)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fresnel_matches_normal_incidence_formula_and_grazing_limit() {
        for eta in [1.0001f32, 1.33, 1.5, 2.4, 1.0 / 1.5] {
            let f0 = ((eta - 1.0) / (eta + 1.0)).powi(2);
            assert!((fresnel_dielectric(1.0, eta) - f0).abs() < 1e-6, "{eta}");
            assert!((fresnel_dielectric(0.0, eta) - 1.0).abs() < 1e-6, "{eta}");
        }
        // Brewster angle: p-polarised reflectance vanishes, F = r_s²/2.
        let eta = 1.5f32;
        let theta_b = eta.atan();
        let f = fresnel_dielectric(theta_b.cos(), eta);
        let theta_t = (theta_b.sin() / eta).asin();
        let r_s = (theta_b - theta_t).sin() / (theta_b + theta_t).sin();
        assert!((f - 0.5 * r_s * r_s).abs() < 1e-5);
    }

    #[test]
    fn refract_obeys_snell_and_fails_beyond_the_critical_angle() {
        let n = Vec3::Z;
        let wi = Vec3::new(0.6, 0.0, 0.8);
        let wt = refract(wi, n, 1.5).expect("no TIR entering glass");
        assert!((wt.length() - 1.0).abs() < 1e-6 && wt.z < 0.0);
        assert!((0.6 - 1.5 * wt.x.abs()).abs() < 1e-6, "Snell");
        assert!(wt.x < 0.0, "refracted ray continues through the surface");
        // From inside glass at 45°: critical angle asin(1/1.5) ≈ 41.8°.
        let wi = Vec3::new(0.5f32.sqrt(), 0.0, 0.5f32.sqrt());
        assert!(refract(wi, n, 1.0 / 1.5).is_none());
        assert!(fresnel_dielectric(wi.z, 1.0 / 1.5) == 1.0);
        let r = reflect(wi, n);
        assert!(r.distance(Vec3::new(-wi.x, 0.0, wi.z)) < 1e-6);
    }
}
