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

use glam::{Vec2, Vec2Swizzles, Vec3, Vec4, Vec4Swizzles};

use super::real::Real;
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
    // of π/4·(dx/dy): either way a sine and cosine on [−π/4, π/4]. Which
    // sector is a coin flip, so the two are one computation on swapped
    // operands, picked by vector blends: a branch there mispredicted on 1.5
    // of `scenes/cornell-box.toml`'s 12 simulated mispredicts per sample,
    // and LLVM compiles a scalar `f32` select (even
    // `std::hint::select_unpredictable`) as a branch around a move.
    let steep = Vec4::splat(d.x.abs()).cmple(Vec4::splat(d.y.abs()));
    let pick = |if_steep: Vec2, otherwise: Vec2| {
        Vec4::select(
            steep,
            if_steep.extend(0.0).extend(0.0),
            otherwise.extend(0.0).extend(0.0),
        )
        .xy()
    };
    let ratio = pick(d.yx(), d);
    let (sin, cos) = sin_cos_quarter((), FRAC_PI_4 * (ratio.y / ratio.x));
    let disk = ratio.x * pick(Vec2::new(sin, cos), Vec2::new(cos, sin));
    // The centre (0/0 above) maps to itself.
    let disk = if d == Vec2::ZERO { Vec2::ZERO } else { disk };
    let z = (1.0 - disk.length_squared()).max(0.0).sqrt();
    Vec3::new(disk.x, disk.y, z)
}

/// `(sin x, cos x)` for `|x| ≤ π/4` by their Taylor polynomials to degree 9
/// and 8 (truncation error below 2e-9 and 3e-8, under an `f32` ulp of the
/// results), a few multiplies and adds instead of a libm call; on one value
/// or on sixteen lanes ([`Real`]). Each coefficient is an `f32` constant
/// (the quotient rounded once, at compile time). (The constants are not made
/// by a closure: that changed the scalar tracer's code generation.)
#[inline(always)]
pub(super) fn sin_cos_quarter<T: Real>(k: T::Token, x: T) -> (T, T) {
    let one = T::constant(k, 1.0);
    let (s3, s5, s7, s9) = (
        T::constant(k, -1.0 / 6.0),
        T::constant(k, 1.0 / 120.0),
        T::constant(k, -1.0 / 5040.0),
        T::constant(k, 1.0 / 362_880.0),
    );
    let (c2, c4, c6, c8) = (
        T::constant(k, -0.5),
        T::constant(k, 1.0 / 24.0),
        T::constant(k, -1.0 / 720.0),
        T::constant(k, 1.0 / 40_320.0),
    );
    let x2 = x * x;
    let sin = x * (one + x2 * (s3 + x2 * (s5 + x2 * (s7 + x2 * s9))));
    let cos = one + x2 * (c2 + x2 * (c4 + x2 * (c6 + x2 * c8)));
    (sin, cos)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quarter_sin_cos_matches_libm() {
        for i in -1000..=1000 {
            let x = FRAC_PI_4 * i as f32 / 1000.0;
            let (sin, cos) = sin_cos_quarter((), x);
            let (s64, c64) = f64::from(x).sin_cos();
            assert!((f64::from(sin) - s64).abs() < 1.2e-7, "sin {x}");
            assert!((f64::from(cos) - c64).abs() < 1.2e-7, "cos {x}");
        }
    }

    /// Shirley and Chiu's concentric map in `f64` with libm, both sectors
    /// written out, on a grid that holds the diagonals, the axes and the
    /// centre.
    #[test]
    fn cosine_directions_follow_the_concentric_map_in_both_sectors() {
        use std::f64::consts::{FRAC_PI_2, FRAC_PI_4};
        for i in 0..=64 {
            for j in 0..=64 {
                let u = Vec2::new(i as f32, j as f32) / 64.0;
                let (dx, dy) = (2.0 * f64::from(u.x) - 1.0, 2.0 * f64::from(u.y) - 1.0);
                let (r, phi) = if dx == 0.0 && dy == 0.0 {
                    (0.0, 0.0)
                } else if dx.abs() > dy.abs() {
                    (dx, FRAC_PI_4 * (dy / dx))
                } else {
                    (dy, FRAC_PI_2 - FRAC_PI_4 * (dx / dy))
                };
                let expected = [r * phi.cos(), r * phi.sin()];
                let got = cosine_hemisphere(u);
                for (g, e) in [got.x, got.y].into_iter().zip(expected) {
                    assert!(
                        (f64::from(g) - e).abs() < 1e-6,
                        "{u}: {got} against {expected:?}"
                    );
                }
                // At the rim `z` is the root of an `f32` cancellation.
                let z2 = f64::from(got.z).powi(2);
                assert!((z2 - (1.0 - r * r).max(0.0)).abs() < 1e-6, "{u}: {got}");
            }
        }
    }
}
