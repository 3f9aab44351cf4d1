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
/// reflectance `tint` (constant over angle). `alpha` outside `[1e-4, 1]` is
/// clamped into it.
#[derive(Clone, Debug, PartialEq)]
pub struct RoughConductor {
    /// GGX roughness α (isotropic), in [1e-4, 1] (clamped when used).
    pub alpha: f32,
    /// Reflectance per channel, in [0, 1].
    pub tint: Vec3,
}

impl RoughConductor {
    /// The microfacet distribution (α clamped into `[1e-4, 1]`).
    pub(super) fn ggx(&self) -> Ggx {
        Ggx::new(self.alpha)
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

#[cfg(test)]
mod tests {
    use std::f64::consts::{FRAC_PI_2, PI};

    use super::*;
    use crate::materials::test_support::{Rng, spherical};

    const ALPHAS: [f32; 6] = [0.01, 0.05, 0.1, 0.3, 0.6, 1.0];

    fn white(alpha: f32) -> RoughConductor {
        RoughConductor {
            alpha,
            tint: Vec3::ONE,
        }
    }

    /// Directional albedo `E(α, μ) = ∫ eval(wi, wo) dωo` by midpoint quadrature
    /// over the microfacet normal (`dωo = 4 |wi·m| dωm`). The polar grid is
    /// stretched by `θm = atan(α tan(sπ/2))` so that it resolves `D` at any α,
    /// and for each azimuth it ends exactly where the reflected direction
    /// reaches the horizon: `wo.z = A sin 2θ + B cos 2θ > 0` with
    /// `A = sin θi cos φ`, `B = cos θi`, i.e. `θ < (atan2(A, B) + π/2) / 2`.
    /// The integrand is then smooth and the rule converges fast.
    fn albedo_quadrature(alpha: f32, mu: f64, n: usize) -> f64 {
        let bsdf = white(alpha);
        let sin_i = (1.0 - mu * mu).sqrt();
        let wi = spherical(mu.acos(), 0.0);
        let a = alpha as f64;
        let dphi = PI / n as f64;
        let mut sum = 0.0;
        for j in 0..n {
            // wi lies in the xz plane: the integrand is even in φ.
            let phi = (j as f64 + 0.5) * dphi;
            let theta_max = 0.5 * ((sin_i * phi.cos()).atan2(mu) + FRAC_PI_2);
            let s_max = (theta_max.tan() / a).atan() / FRAC_PI_2;
            let ds = s_max / n as f64;
            for i in 0..n {
                let t = ((i as f64 + 0.5) * ds * FRAC_PI_2).tan();
                let theta = (a * t).atan();
                let dtheta_ds = a * FRAC_PI_2 * (1.0 + t * t) / (1.0 + a * a * t * t);
                let m = spherical(theta, phi);
                let cos_im = wi.dot(m) as f64;
                let f = bsdf.eval(wi, reflect(wi, m)).x as f64;
                sum += 2.0 * f * 4.0 * cos_im * theta.sin() * dtheta_ds * ds * dphi;
            }
        }
        sum
    }

    #[test]
    fn white_furnace_albedo_matches_quadrature_table_and_never_exceeds_one() {
        let mut rng = Rng::new(21);
        let n = 20_000;
        for alpha in ALPHAS {
            for k in 1..=10 {
                let mu = k as f64 / 10.0;
                // The rule is second order: Richardson-extrapolate, and take the
                // step-halving difference as a (generous) error bound.
                let (coarse, fine) = (
                    albedo_quadrature(alpha, mu, 160),
                    albedo_quadrature(alpha, mu, 320),
                );
                let table = fine + (fine - coarse) / 3.0;
                let quad_err = (fine - coarse).abs();
                assert!(table <= 1.0 + 1e-4, "E({alpha}, {mu}) = {table}");
                assert!(quad_err < 1e-3, "quadrature unconverged: {quad_err}");
                let wi = spherical(mu.acos(), 0.0);
                let (mut sum, mut sum2) = (0.0f64, 0.0f64);
                for _ in 0..n {
                    let w = white(alpha)
                        .sample(wi, rng.vec2())
                        .map_or(0.0, |s| s.weight.x as f64);
                    sum += w;
                    sum2 += w * w;
                }
                let mean = sum / n as f64;
                // Weights lie in [0, 1], so their variance is at most
                // E(1 − E): near E = 1 the loss is a rare event (masking) and
                // the sample variance of 20 000 draws can miss it entirely.
                let se = ((sum2 / n as f64 - mean * mean).max(0.0) / n as f64)
                    .sqrt()
                    .max((table * (1.0 - table)).max(0.0).sqrt() / (n as f64).sqrt());
                assert!(
                    (mean - table).abs() <= 3.0 * se + quad_err + 1e-6,
                    "α {alpha} μ {mu}: MC {mean} ± {se} vs table {table}"
                );
            }
        }
    }

    #[test]
    fn extreme_roughness_and_grazing_incidence_stay_finite() {
        for alpha in [1e-4f32, 1e-3, 1e-2, 0.1, 0.5, 1.0] {
            let bsdf = white(alpha);
            for mu in [1e-3f64, 1e-2, 0.5, 1.0] {
                let wi = spherical(mu.acos(), 0.3);
                let mut accepted = 0;
                for i in 0..32 {
                    for j in 0..32 {
                        let u = Vec2::new(i as f32 / 31.0 * 0.999_999, j as f32 / 31.0 * 0.999_999);
                        let Some(s) = bsdf.sample(wi, u) else {
                            continue;
                        };
                        accepted += 1;
                        assert!(s.wo.is_finite() && s.m.is_finite() && s.wo.z > 0.0);
                        assert!(
                            s.pdf.is_finite() && s.pdf > 0.0,
                            "α {alpha} μ {mu}: {}",
                            s.pdf
                        );
                        assert!(s.weight.is_finite() && s.weight.max_element() <= 1.0 + 1e-6);
                        let (f, pdf) = (bsdf.eval(wi, s.wo), bsdf.pdf(wi, s.wo));
                        assert!(f.is_finite() && pdf.is_finite(), "α {alpha} μ {mu}");
                    }
                }
                assert!(accepted > 0, "α {alpha} μ {mu}: every sample rejected");
                let mut rng = Rng::new(22);
                for _ in 0..200 {
                    let wo = rng.sphere();
                    assert!(bsdf.eval(wi, wo).is_finite() && bsdf.pdf(wi, wo).is_finite());
                }
                assert!(bsdf.eval(wi, wi).is_finite() && bsdf.pdf(wi, Vec3::Z).is_finite());
            }
        }
    }
}
