//! Lambertian (ideal diffuse) reflection.
//!
//! `f = albedo / π`; directions are sampled with the cosine-weighted
//! hemisphere (Malley's method over Shirley & Chiu's concentric disk mapping,
//! pbrt-v4 §A.5.3), so the sample weight is exactly the albedo.
//!
//! | key | unit | default | range |
//! |---|---|---|---|
//! | `albedo` | linear RGB or texture | — | [0, 1] per channel |
//!
//! ```toml
//! [[materials]]
//! name = "wall"
//! type = "diffuse"
//! albedo = [0.8, 0.8, 0.8]
//! ```

use std::f32::consts::{FRAC_1_PI, FRAC_PI_4};

use glam::{Vec2, Vec3};

use super::{BsdfSample, Lobe, Texture};
use crate::hit::TexCoords;

/// Lambertian reflection.
#[derive(Clone, Debug, PartialEq)]
pub struct Diffuse {
    /// Albedo in [0, 1] per channel.
    pub albedo: Texture,
}

impl Diffuse {
    /// Samples a cosine-distributed `wo` (local, upper hemisphere; `wi.z > 0`).
    #[inline(always)]
    pub(super) fn sample(&self, uv: TexCoords, u: Vec2) -> Option<BsdfSample> {
        let wo = cosine_hemisphere(u);
        let pdf = wo.z * FRAC_1_PI;
        if pdf <= 0.0 {
            return None;
        }
        Some(BsdfSample {
            wo,
            weight: self.albedo.eval(uv),
            pdf,
            lobe: Lobe::DiffuseReflection,
            eta: 1.0,
            m: Vec3::Z,
        })
    }

    /// `albedo/π · cos θo` when both directions are above the surface.
    #[inline]
    pub(super) fn eval(&self, wi: Vec3, wo: Vec3, uv: TexCoords) -> Vec3 {
        if wi.z <= 0.0 || wo.z <= 0.0 {
            return Vec3::ZERO;
        }
        self.albedo.eval(uv) * (FRAC_1_PI * wo.z)
    }

    /// `cos θo / π` when both directions are above the surface.
    #[inline]
    pub(super) fn pdf(&self, wi: Vec3, wo: Vec3) -> f32 {
        if wi.z <= 0.0 || wo.z <= 0.0 {
            return 0.0;
        }
        FRAC_1_PI * wo.z
    }
}

/// Cosine-weighted direction on the upper hemisphere from `u ∈ [0, 1)²`
/// (concentric disk mapping, then projection up).
#[inline]
pub fn cosine_hemisphere(u: Vec2) -> Vec3 {
    let d = 2.0 * u - Vec2::ONE;
    // The disk angle is φ = π/4·(dy/dx) on the sectors where |dx| > |dy|,
    // else π/2 − π/4·(dx/dy), whose cosine and sine are the sine and cosine
    // of π/4·(dx/dy): either way a sine and cosine on [−π/4, π/4].
    let disk = if d == Vec2::ZERO {
        Vec2::ZERO
    } else if d.x.abs() > d.y.abs() {
        let (sin, cos) = sin_cos_quarter(FRAC_PI_4 * (d.y / d.x));
        d.x * Vec2::new(cos, sin)
    } else {
        let (sin, cos) = sin_cos_quarter(FRAC_PI_4 * (d.x / d.y));
        d.y * Vec2::new(sin, cos)
    };
    let z = (1.0 - disk.length_squared()).max(0.0).sqrt();
    Vec3::new(disk.x, disk.y, z)
}

/// `(sin x, cos x)` for `|x| ≤ π/4` by their Taylor polynomials to degree 9
/// and 8 (truncation error below 2e-9 and 3e-8, under an `f32` ulp of the
/// results), a few multiply-adds instead of a libm call.
#[inline]
fn sin_cos_quarter(x: f32) -> (f32, f32) {
    let x2 = x * x;
    let sin = x
        * (1.0
            + x2 * (-1.0 / 6.0
                + x2 * (1.0 / 120.0 + x2 * (-1.0 / 5040.0 + x2 * (1.0 / 362_880.0)))));
    let cos = 1.0 + x2 * (-0.5 + x2 * (1.0 / 24.0 + x2 * (-1.0 / 720.0 + x2 * (1.0 / 40_320.0))));
    (sin, cos)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quarter_sin_cos_matches_libm() {
        for i in -1000..=1000 {
            let x = FRAC_PI_4 * i as f32 / 1000.0;
            let (sin, cos) = sin_cos_quarter(x);
            let (s64, c64) = f64::from(x).sin_cos();
            assert!((f64::from(sin) - s64).abs() < 1.2e-7, "sin {x}");
            assert!((f64::from(cos) - c64).abs() < 1.2e-7, "cos {x}");
        }
    }
}
