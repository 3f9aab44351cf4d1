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

use std::f32::consts::{FRAC_1_PI, FRAC_PI_2, FRAC_PI_4};

use glam::{Vec2, Vec3};

use super::{BsdfSample, Lobe, Texture};

/// Lambertian reflection.
#[derive(Clone, Debug, PartialEq)]
pub struct Diffuse {
    /// Albedo in [0, 1] per channel.
    pub albedo: Texture,
}

impl Diffuse {
    /// Samples a cosine-distributed `wo` (local, upper hemisphere; `wi.z > 0`).
    pub(super) fn sample(&self, uv: Vec2, u: Vec2) -> Option<BsdfSample> {
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
    pub(super) fn eval(&self, wi: Vec3, wo: Vec3, uv: Vec2) -> Vec3 {
        if wi.z <= 0.0 || wo.z <= 0.0 {
            return Vec3::ZERO;
        }
        self.albedo.eval(uv) * (FRAC_1_PI * wo.z)
    }

    /// `cos θo / π` when both directions are above the surface.
    pub(super) fn pdf(&self, wi: Vec3, wo: Vec3) -> f32 {
        if wi.z <= 0.0 || wo.z <= 0.0 {
            return 0.0;
        }
        FRAC_1_PI * wo.z
    }
}

/// Cosine-weighted direction on the upper hemisphere from `u ∈ [0, 1)²`
/// (concentric disk mapping, then projection up).
pub fn cosine_hemisphere(u: Vec2) -> Vec3 {
    let d = 2.0 * u - Vec2::ONE;
    let disk = if d == Vec2::ZERO {
        Vec2::ZERO
    } else if d.x.abs() > d.y.abs() {
        let phi = FRAC_PI_4 * (d.y / d.x);
        d.x * Vec2::new(phi.cos(), phi.sin())
    } else {
        let phi = FRAC_PI_2 - FRAC_PI_4 * (d.x / d.y);
        d.y * Vec2::new(phi.cos(), phi.sin())
    };
    let z = (1.0 - disk.length_squared()).max(0.0).sqrt();
    Vec3::new(disk.x, disk.y, z)
}
