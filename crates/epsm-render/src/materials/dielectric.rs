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
    #[inline]
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

#[cfg(test)]
mod tests {
    use glam::Vec2;

    use super::*;
    use crate::materials::test_support::spherical;
    use crate::materials::{Bsdf, Material, VertexKind};

    fn glass(ior: f32) -> Material {
        Material {
            name: "glass".into(),
            bsdf: Bsdf::Dielectric(Dielectric { ior }),
            two_sided: false,
        }
    }

    fn sample(m: &Material, wi: Vec3, u_lobe: f32) -> BsdfSample {
        m.sample(wi, Vec2::ZERO, u_lobe, Vec2::new(0.3, 0.7))
            .expect("a dielectric always scatters")
    }

    #[test]
    fn reflection_plus_transmission_is_one_and_refraction_obeys_snell() {
        for ior in [1.0001f32, 1.33, 1.5, 2.4, 0.7] {
            let m = glass(ior);
            for theta in [0.0f64, 0.2, 0.6, 1.0, 1.4, 1.55, 1.7, 2.2, 2.9, 3.1] {
                let wi = spherical(theta, 0.8);
                let r = sample(&m, wi, 0.0);
                let t = sample(&m, wi, 1.0 - 1e-7);
                assert_eq!(r.lobe, Lobe::SpecularReflection);
                assert!(r.wo.distance(Vec3::new(-wi.x, -wi.y, wi.z)) < 1e-6);
                assert_eq!((r.weight, r.eta, r.m), (Vec3::ONE, 1.0, Vec3::Z));
                if t.lobe == Lobe::SpecularReflection {
                    // Total internal reflection: only possible from the denser side.
                    let eta_inside = if wi.z >= 0.0 { ior } else { 1.0 / ior };
                    assert!(eta_inside < 1.0, "ior {ior} θ {theta}");
                    assert!((1.0 - wi.z * wi.z).sqrt() > eta_inside - 1e-4);
                    assert_eq!(r.pdf, 1.0);
                    continue;
                }
                assert_eq!(t.lobe, Lobe::SpecularTransmission);
                // R + T = 1 once the radiance scaling 1/η² is undone.
                let energy = r.pdf * r.weight.x + t.pdf * t.weight.x * t.eta * t.eta;
                assert!((energy - 1.0).abs() < 1e-6, "ior {ior} θ {theta}: {energy}");
                assert!((r.pdf + t.pdf - 1.0).abs() < 1e-6);
                // Snell: η_i sin θi = η_o sin θo, with η = η_o / η_i.
                let (sin_i, sin_o) = (wi.truncate().length(), t.wo.truncate().length());
                assert!((sin_i - t.eta * sin_o).abs() < 1e-5, "ior {ior} θ {theta}");
                assert!(t.wo.z * wi.z < 0.0 || wi.z == 0.0, "crosses the interface");
                assert!((t.wo.length() - 1.0).abs() < 1e-5);
                // The generalised half vector is the normal.
                let h = wi + t.eta * t.wo;
                assert!(h.truncate().length() < 1e-5 * h.length().max(1e-3));
                let expected_eta = if wi.z >= 0.0 { ior } else { 1.0 / ior };
                assert!((t.eta - expected_eta).abs() < 1e-6);
                assert_eq!(t.m, Vec3::Z);
            }
        }
    }

    #[test]
    fn total_internal_reflection_beyond_the_critical_angle() {
        let m = glass(1.5);
        let critical = (1.0f64 / 1.5).asin();
        // Inside the glass (wi.z < 0), just beyond and just within the critical angle.
        let beyond = spherical(std::f64::consts::PI - critical - 0.01, 0.3);
        let within = spherical(std::f64::consts::PI - critical + 0.01, 0.3);
        for u in [0.0, 0.5, 0.999_999] {
            let s = sample(&m, beyond, u);
            assert_eq!((s.lobe, s.pdf), (Lobe::SpecularReflection, 1.0));
        }
        assert_eq!(
            sample(&m, within, 0.999_999).lobe,
            Lobe::SpecularTransmission
        );
        assert_eq!(m.eval(beyond, -beyond, Vec2::ZERO), Vec3::ZERO);
        assert_eq!(m.pdf(beyond, -beyond, Vec2::ZERO), 0.0);
        assert_eq!(m.vertex_kind(), VertexKind::Specular);
    }
}
