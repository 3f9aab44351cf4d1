//! The isotropic GGX (Trowbridge–Reitz) microfacet distribution: normal
//! distribution `D`, Smith masking `G1` and height-correlated masking–shadowing
//! `G2`, and sampling of visible normals.
//!
//! - `D(m) = α² / (π (α² cos²θm + sin²θm)²)`, written with `sin²θm = mx² + my²`
//!   so that it stays accurate for α down to 1e-4 (Walter et al., "Microfacet
//!   Models for Refraction through Rough Surfaces", EGSR 2007).
//! - `Λ(w) = (√(1 + α² tan²θ) − 1) / 2`, evaluated without cancellation;
//!   `G1 = 1 / (1 + Λ)`; `G2 = 1 / (1 + Λ(wi) + Λ(wo))`, the
//!   **height-correlated** Smith form (Heitz, "Understanding the
//!   Masking-Shadowing Function", JCGT 2014).
//! - Visible normals are sampled with spherical caps (Dupuy & Benyoub,
//!   "Sound and Robust Sampling of the GGX Distribution of Visible Normals",
//!   HPG 2023), exactly the density `G1(wi) D(m) max(0, wi·m) / cos θi`
//!   (Heitz 2018).
//!
//! | parameter | unit | default | range |
//! |---|---|---|---|
//! | `alpha` | — (GGX roughness) | — | [1e-4, 1] |
//!
//! All directions are local (`+z` = macro-surface normal), unit, and the
//! functions assume the upper hemisphere for `wi`.

use std::f32::consts::PI;

use glam::{Vec2, Vec3};

use super::real::Real;

/// An isotropic GGX distribution with roughness `alpha`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ggx {
    /// Roughness α.
    pub alpha: f32,
}

impl Ggx {
    /// The distribution with roughness `alpha` clamped to `[1e-4, 1]` (α = 0
    /// would make `D` a delta and its evaluation 0/0).
    #[inline]
    pub fn new(alpha: f32) -> Self {
        Self {
            alpha: alpha.clamp(1e-4, 1.0),
        }
    }

    /// The normal distribution `D(m)` (per steradian of `m`, projected area
    /// normalised: `∫ D(m) cos θm dm = 1`). Zero for `m` below the surface.
    #[inline]
    pub fn d(&self, m: Vec3) -> f32 {
        if m.z <= 0.0 {
            return 0.0;
        }
        d_above((), self.alpha, m.x, m.y, m.z)
    }

    /// Smith's `Λ(w)`; infinite at grazing `w.z = 0`.
    #[inline]
    pub fn lambda(&self, w: Vec3) -> f32 {
        let z2 = w.z * w.z;
        if z2 == 0.0 {
            return f32::INFINITY;
        }
        lambda_off_horizon((), self.alpha, w.x, w.y, z2)
    }

    /// Smith masking `G1(w) = 1 / (1 + Λ(w))`.
    #[inline]
    pub fn g1(&self, w: Vec3) -> f32 {
        1.0 / (1.0 + self.lambda(w))
    }

    /// Height-correlated masking–shadowing `G2 = 1 / (1 + Λ(wi) + Λ(wo))`.
    #[inline]
    pub fn g2(&self, wi: Vec3, wo: Vec3) -> f32 {
        1.0 / (1.0 + self.lambda(wi) + self.lambda(wo))
    }

    /// Density of visible normals `D_wi(m) = G1(wi) D(m) max(0, wi·m) / cos θi`
    /// (per steradian of `m`) for `wi.z > 0`.
    #[inline]
    pub fn visible_pdf(&self, wi: Vec3, m: Vec3) -> f32 {
        let cos_im = wi.dot(m);
        if wi.z <= 0.0 || cos_im <= 0.0 {
            return 0.0;
        }
        self.g1(wi) * self.d(m) * cos_im / wi.z
    }

    /// Samples a visible normal from `wi` (`wi.z > 0`) with two uniform
    /// numbers in `[0, 1)`. `None` only in the measure-zero degenerate case.
    #[inline]
    pub fn sample_visible(&self, wi: Vec3, u: Vec2) -> Option<Vec3> {
        // Stretch to the hemisphere configuration (α = 1).
        let wi_std = Vec3::new(self.alpha * wi.x, self.alpha * wi.y, wi.z).try_normalize()?;
        // Sample the spherical cap of directions seen from wi_std.
        let phi = 2.0 * PI * u.x;
        let z = (1.0 - u.y) * (1.0 + wi_std.z) - wi_std.z;
        let sin_theta = (1.0 - z * z).clamp(0.0, 1.0).sqrt();
        let c = Vec3::new(sin_theta * phi.cos(), sin_theta * phi.sin(), z);
        let h = c + wi_std;
        // Unstretch back to the ellipsoid configuration.
        Vec3::new(self.alpha * h.x, self.alpha * h.y, h.z.max(0.0)).try_normalize()
    }
}

/// [`Ggx::d`] of the normal `(x, y, z)` with `z > 0`, roughness `alpha`
/// (on one value or on sixteen lanes, [`Real`]).
#[inline(always)]
pub(super) fn d_above<T: Real>(k: T::Token, alpha: T, x: T, y: T, z: T) -> T {
    let a2 = alpha * alpha;
    let sin2 = x * x + y * y;
    let denom = a2 * z * z + sin2;
    a2 / (T::constant(k, PI) * denom * denom)
}

/// [`Ggx::lambda`] of the direction `(x, y, z)` with `z2 = z² ≠ 0`,
/// roughness `alpha` (on one value or on sixteen lanes, [`Real`]).
#[inline(always)]
pub(super) fn lambda_off_horizon<T: Real>(k: T::Token, alpha: T, x: T, y: T, z2: T) -> T {
    let a2t2 = alpha * alpha * (x * x + y * y) / z2;
    let one = T::constant(k, 1.0);
    a2t2 / (T::constant(k, 2.0) * (one + (one + a2t2).sqrt()))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// ∫ D(m) cos θm dω over the hemisphere, in (cos θ, φ) midpoint quadrature
    /// refined toward the normal where D peaks.
    fn projected_area(ggx: Ggx) -> f64 {
        let n = 4000;
        let mut sum = 0.0f64;
        // Substitute t = sin θ / α-ish: integrate over θ with a grid dense near 0.
        for i in 0..n {
            let s0 = (i as f64 / n as f64).powi(4);
            let s1 = ((i + 1) as f64 / n as f64).powi(4);
            let theta = 0.5 * (s0 + s1) * std::f64::consts::FRAC_PI_2;
            let dtheta = (s1 - s0) * std::f64::consts::FRAC_PI_2;
            let m = Vec3::new(theta.sin() as f32, 0.0, theta.cos() as f32);
            sum +=
                ggx.d(m) as f64 * theta.cos() * theta.sin() * dtheta * 2.0 * std::f64::consts::PI;
        }
        sum
    }

    #[test]
    fn d_is_normalised_in_projected_area() {
        for alpha in [0.01f32, 0.1, 0.5, 1.0] {
            let a = projected_area(Ggx::new(alpha));
            assert!((a - 1.0).abs() < 2e-3, "α = {alpha}: {a}");
        }
    }

    #[test]
    fn smith_terms_are_finite_and_bounded_for_extreme_alpha_and_grazing() {
        for alpha in [1e-4f32, 1e-2, 0.5, 1.0] {
            let ggx = Ggx::new(alpha);
            for z in [1e-3f32, 0.1, 1.0] {
                let w = Vec3::new((1.0 - z * z).sqrt(), 0.0, z);
                let g1 = ggx.g1(w);
                assert!(g1.is_finite() && g1 > 0.0 && g1 <= 1.0, "{alpha} {z} {g1}");
                let g2 = ggx.g2(w, Vec3::Z);
                assert!(g2 <= g1 + 1e-7);
                let m = ggx.sample_visible(w, Vec2::new(0.3, 0.7)).expect("sample");
                assert!(m.is_finite() && m.z >= 0.0);
                assert!(ggx.d(m).is_finite() && ggx.visible_pdf(w, m).is_finite());
            }
            assert_eq!(ggx.g1(Vec3::X), 0.0);
        }
    }
}
