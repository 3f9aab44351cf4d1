//! Smooth dielectric interface (glass, water): exact unpolarised Fresnel
//! reflection and Snell refraction, both delta lobes.
//!
//! The exterior has IOR 1 and the interior `ior`; the interior is the side
//! opposite the shading normal, so `wi.z < 0` means the camera-side vertex is
//! inside. `sample` reflects with probability `F` (weight 1, pdf `F`) and
//! refracts otherwise (pdf `1 − F`, weight `1/η²` with `η = η(wo side) /
//! η(wi side)`: camera paths carry radiance, which scales by the squared IOR
//! ratio across the interface; Veach 1997 §5.2). Under total internal reflection
//! `F = 1`. The returned `m` is always `+z` (the shading normal, not oriented
//! toward `wi`); `normalize(wi + η·wo)` is `±z` for both lobes.
//! `eval` and `pdf` are zero.
//!
//! | key | unit | default | range |
//! |---|---|---|---|
//! | `ior` | — (interior / exterior) | 1.5 | > 0, ≠ 1 in practice |
//!
//! ```toml
//! [[materials]]
//! name = "glass"
//! type = "dielectric"
//! ior = 1.5
//! ```

use glam::Vec3;

use super::fresnel::{fresnel_dielectric, refract};
use super::{BsdfSample, Lobe};

/// Smooth dielectric interface (glass), exterior IOR 1.
#[derive(Clone, Debug, PartialEq)]
pub struct Dielectric {
    /// Interior index of refraction relative to the exterior (> 0, ≠ 1 in practice).
    pub ior: f32,
}

impl Dielectric {
    /// Chooses reflection (`u_lobe < F`) or refraction of `wi` (local, either side).
    pub(super) fn sample(&self, wi: Vec3, u_lobe: f32) -> Option<BsdfSample> {
        // η(transmitted side) / η(wi side), and the normal on the side of wi.
        let (eta, n) = if wi.z >= 0.0 {
            (self.ior, Vec3::Z)
        } else {
            (1.0 / self.ior, -Vec3::Z)
        };
        let f = fresnel_dielectric(wi.z.abs(), eta);
        let reflection = BsdfSample {
            wo: Vec3::new(-wi.x, -wi.y, wi.z),
            weight: Vec3::ONE,
            pdf: f,
            lobe: Lobe::SpecularReflection,
            eta: 1.0,
            m: Vec3::Z,
        };
        if u_lobe < f {
            return Some(reflection);
        }
        match refract(wi, n, eta) {
            Some(wo) => Some(BsdfSample {
                wo,
                weight: Vec3::splat(1.0 / (eta * eta)),
                pdf: 1.0 - f,
                lobe: Lobe::SpecularTransmission,
                eta,
                m: Vec3::Z,
            }),
            // Only reachable when rounding puts F just below 1 at the critical angle.
            None => Some(BsdfSample {
                pdf: 1.0,
                ..reflection
            }),
        }
    }
}
