//! Fresnel reflectance of a smooth dielectric interface (with its analytic
//! partial derivatives), and the reflection and refraction directions.
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
use num_traits::Float;

use super::real::Real;

/// Unpolarised Fresnel reflectance for incidence cosine `cos_i ∈ [0, 1]` and
/// relative IOR `eta = η_t / η_i`. Returns 1 under total internal reflection.
/// The renderer evaluates it in `f32`; derivatives evaluate it in `f64`
/// ([`fresnel_dielectric_rates`]).
#[inline]
pub fn fresnel_dielectric<T: Float>(cos_i: T, eta: T) -> T {
    debug_assert!(eta > T::zero());
    match amplitudes(cos_i.clamp(T::zero(), T::one()), eta) {
        Some(a) => a.reflectance(()).clamp(T::zero(), T::one()),
        None => T::one(),
    }
}

/// The reflectance `F` of [`fresnel_dielectric`] in `f64` with its partial
/// derivatives, by differentiating the Fresnel equations analytically.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FresnelRates {
    /// `F(cos_i, eta)`.
    pub f: f64,
    /// `∂F/∂cos_i`.
    pub d_cos: f64,
    /// `∂F/∂eta`.
    pub d_eta: f64,
}

/// [`FresnelRates`] at `cos_i ∈ [0, 1]` and `eta > 0`. Under total internal
/// reflection `F ≡ 1` and both derivatives are 0; they grow without bound
/// as `cos_i` approaches the critical cosine `√(1 − eta²)` from above
/// (infinite at it), so callers keep a distance from it.
pub fn fresnel_dielectric_rates(cos_i: f64, eta: f64) -> FresnelRates {
    debug_assert!((0.0..=1.0).contains(&cos_i) && eta > 0.0);
    let Some(a) = amplitudes(cos_i, eta) else {
        return FresnelRates {
            f: 1.0,
            d_cos: 0.0,
            d_eta: 0.0,
        };
    };
    let Amplitudes { cos_t, r_s, r_p } = a;
    let c = cos_i;
    // r_s = (c − η·cos_t)/(c + η·cos_t) and r_p = (η·c − cos_t)/(η·c + cos_t),
    // with ∂cos_t/∂c = c/(η²·cos_t) and ∂cos_t/∂η = (1 − c²)/(η³·cos_t).
    let (b, p) = (eta * cos_t, eta * c);
    let d_s = |da: f64, db: f64| 2.0 * (b * da - c * db) / ((c + b) * (c + b));
    let d_p = |dp: f64, dq: f64| 2.0 * (cos_t * dp - p * dq) / ((p + cos_t) * (p + cos_t));
    let dt_dc = c / (eta * eta * cos_t);
    let dt_deta = (1.0 - c * c) / (eta * eta * eta * cos_t);
    FresnelRates {
        f: a.reflectance(()),
        d_cos: r_s * d_s(1.0, eta * dt_dc) + r_p * d_p(eta, dt_dc),
        d_eta: r_s * d_s(0.0, cos_t + eta * dt_deta) + r_p * d_p(c, dt_deta),
    }
}

/// The transmitted cosine and the s- and p-polarised reflection amplitudes
/// (on one value or on sixteen lanes, [`Real`]).
#[derive(Clone, Copy)]
pub(super) struct Amplitudes<T> {
    /// `cos θt`.
    cos_t: T,
    /// s-polarised amplitude.
    r_s: T,
    /// p-polarised amplitude.
    r_p: T,
}

impl<T: Real> Amplitudes<T> {
    /// The amplitudes at `cos_i ∈ [0, 1]` given
    /// `sin2_t = `[`sin2_transmitted`]`(cos_i, eta) < 1` (at or above 1,
    /// total internal reflection, the values mean nothing).
    #[inline(always)]
    pub(super) fn below_critical(k: T::Token, cos_i: T, eta: T, sin2_t: T) -> Self {
        let cos_t = (T::constant(k, 1.0) - sin2_t)
            .max(T::constant(k, 0.0))
            .sqrt();
        Self {
            cos_t,
            r_s: (cos_i - eta * cos_t) / (cos_i + eta * cos_t),
            r_p: (eta * cos_i - cos_t) / (eta * cos_i + cos_t),
        }
    }

    /// The unpolarised reflectance, the mean of the two polarisations.
    #[inline(always)]
    pub(super) fn reflectance(&self, k: T::Token) -> T {
        T::constant(k, 0.5) * (self.r_s * self.r_s + self.r_p * self.r_p)
    }
}

/// `sin² θt = (1 − cos_i²) / eta²` (Snell's law); at or above 1 under total
/// internal reflection.
#[inline(always)]
pub(super) fn sin2_transmitted<T: Real>(k: T::Token, cos_i: T, eta: T) -> T {
    (T::constant(k, 1.0) - cos_i * cos_i) / (eta * eta)
}

/// The amplitudes at `cos_i ∈ [0, 1]`; `None` under total internal reflection.
#[inline]
fn amplitudes<T: Float>(cos_i: T, eta: T) -> Option<Amplitudes<T>> {
    let sin2_t = sin2_transmitted((), cos_i, eta);
    if sin2_t >= T::one() {
        return None;
    }
    Some(Amplitudes::below_critical((), cos_i, eta, sin2_t))
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
    fn fresnel_rates_match_f64_central_differences() {
        let central = |g: &dyn Fn(f64) -> f64, x: f64, h: f64| (g(x + h) - g(x - h)) / (2.0 * h);
        // Critical cosine √(1 − η²) for η < 1: 0.7454 (1/1.5), 0.9105 (1/2.4).
        for eta in [1.0001, 1.5, 2.4, 1.0 / 1.5, 1.0 / 2.4] {
            for cos in [1e-3, 0.05, 0.3, 0.76, 0.92, 0.999] {
                let r = fresnel_dielectric_rates(cos, eta);
                assert_eq!(r.f, fresnel_dielectric(cos, eta), "{eta} {cos}");
                let d_cos = central(&|c| fresnel_dielectric(c, eta), cos, 1e-7);
                let d_eta = central(&|e| fresnel_dielectric(cos, e), eta, 1e-7);
                for (exact, fd) in [(r.d_cos, d_cos), (r.d_eta, d_eta)] {
                    // The differences round F by ~1e-16·F/|η − 1| (the
                    // amplitudes cancel as η → 1) over a 2e-7 step.
                    let tol = 1e-6 * exact.abs() + 1e-8 * r.f / (eta - 1.0).abs();
                    assert!((exact - fd).abs() < tol, "{eta} {cos}: {exact} vs {fd}");
                }
            }
        }
        let tir = fresnel_dielectric_rates(0.5, 1.0 / 1.5);
        assert_eq!((tir.f, tir.d_cos, tir.d_eta), (1.0, 0.0, 0.0));
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
