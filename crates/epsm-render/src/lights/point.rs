//! Point lights: isotropic emitters of radiant intensity `I` (W·sr⁻¹).
//!
//! Irradiance at distance `d` is `I·cos θ / d²`; a sample is a delta
//! connection (`pdf` = the selection probability alone) whose `radiance` field
//! carries `I / d²`. Power is `4π · mean(I)`.
//!
//! | key | unit | default | range |
//! |---|---|---|---|
//! | `position` | scene units, world | — | any |
//! | `intensity` | W·sr⁻¹, linear RGB | — | ≥ 0 per channel |
//!
//! ```toml
//! [[point_lights]]
//! name = "bulb"
//! position = [0.0, 2.0, 0.0]
//! intensity = [10.0, 10.0, 10.0]
//! ```

use glam::{DVec3, Vec3};

use super::area::mean;

/// An isotropic point light.
#[derive(Clone, Debug, PartialEq)]
pub struct PointLight {
    /// Unique name; parameters bind to it.
    pub name: String,
    /// Position, world space.
    pub position: DVec3,
    /// Radiant intensity, W·sr⁻¹ per channel.
    pub intensity: Vec3,
}

/// A connection from a reference point to a point light.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PointConnection {
    /// Unit direction from the reference point toward the light.
    pub wo: Vec3,
    /// Distance to the light.
    pub dist: f32,
    /// `I / d²`.
    pub radiance: Vec3,
}

impl PointLight {
    /// Radiant power `4π · mean(I)` (W).
    pub fn power(&self) -> f64 {
        4.0 * std::f64::consts::PI * mean(self.intensity)
    }

    /// The connection from `p`; `None` when `p` is at the light.
    pub fn connect(&self, p: Vec3) -> Option<PointConnection> {
        let d = (self.position - p.as_dvec3()).as_vec3();
        let dist2 = d.length_squared();
        if dist2 == 0.0 || !dist2.is_finite() {
            return None;
        }
        let dist = dist2.sqrt();
        Some(PointConnection {
            wo: d / dist,
            dist,
            radiance: self.intensity / dist2,
        })
    }
}
