//! Lights: emissive objects (area lights), point lights and the background
//! (constant or an importance-sampled lat-long environment map), with one
//! table that selects among them in proportion to their power.
//!
//! Powers used for selection ([`select`]): area light `mean(L)·A·π`, point
//! light `4π·mean(I)`, background `π·mean(L̄)·πr²` (`L̄` the mean radiance over
//! the sphere, `r` the radius of the scene bounds, 1 without bounds). A light of
//! zero power is never selected. Every pdf a [`LightSample`] carries is a
//! solid-angle density at the reference point with the selection probability
//! included, and [`LightTable::pdf_area`] / [`LightTable::pdf_background`]
//! return exactly that value for a given light point (for MIS).

pub mod area;
pub mod distribution;
pub mod envmap;
pub mod point;
pub mod select;
#[cfg(target_arch = "x86_64")]
mod wide;

#[cfg(test)]
mod tests;

use std::f32::consts::PI;
use std::sync::Arc;

use glam::{DVec3, Vec2, Vec3};

pub use area::AreaEmitter;
pub use envmap::{DirectionSample, EnvMap};
pub use point::PointLight;
pub use select::LightTable;

use crate::scene::ObjectId;

/// What rays leaving the scene see.
#[derive(Clone, Debug)]
pub enum Background {
    /// Uniform radiance (black for none).
    Constant(Vec3),
    /// An environment map.
    EnvMap(Arc<EnvMap>),
}

/// Where a light sample lies, in the terms `epsm-core` needs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum LightPoint {
    /// A point on an emissive triangle.
    Area {
        /// The emissive object.
        object: ObjectId,
        /// The triangle.
        triangle: u32,
        /// Barycentric `b1`.
        b1: f32,
        /// Barycentric `b2`.
        b2: f32,
    },
    /// A point light.
    Point {
        /// Index in the scene's point lights.
        index: u32,
    },
    /// A direction of the background.
    Background,
}

/// A sampled light connection from a reference point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightSample {
    /// Unit direction from the reference point toward the light.
    pub wo: Vec3,
    /// Distance to the light point (`f32::INFINITY` for the background).
    pub dist: f32,
    /// Light position, world space (reference + wo·dist for finite lights).
    /// For the background there is no position: this holds the direction `wo`.
    pub position: Vec3,
    /// Unit light-surface normal (zero for point lights and the background).
    pub normal: Vec3,
    /// Arriving radiance; for point lights `I / d²` (so the estimate is
    /// `f · radiance / pdf` in every case).
    pub radiance: Vec3,
    /// Solid-angle pdf including the light selection; for point lights the
    /// selection probability alone.
    pub pdf: f32,
    /// Whether the light is a delta light (point lights: no MIS).
    pub delta: bool,
    /// Where on which light.
    pub source: LightPoint,
}

impl Background {
    /// Radiance seen along world direction `dir` (unit).
    pub fn eval(&self, dir: Vec3) -> Vec3 {
        match self {
            Background::Constant(c) => *c,
            Background::EnvMap(map) => map.eval(dir),
        }
    }

    /// Mean radiance over the sphere of directions.
    pub fn mean_radiance(&self) -> Vec3 {
        match self {
            Background::Constant(c) => *c,
            Background::EnvMap(map) => map.mean_radiance(),
        }
    }

    /// Power estimate `π·mean(L̄)·πr²` for scene `bounds` (radius 1 without).
    pub fn power(&self, bounds: Option<(DVec3, DVec3)>) -> f64 {
        let r = bounds.map_or(1.0, |(lo, hi)| 0.5 * (hi - lo).length());
        std::f64::consts::PI * area::mean(self.mean_radiance()) * std::f64::consts::PI * r * r
    }

    /// Samples a direction: uniform on the sphere for a constant background,
    /// by luminance for an environment map. `None` when nothing can be sampled.
    pub fn sample(&self, u: Vec2) -> Option<DirectionSample> {
        match self {
            Background::Constant(_) => {
                let z = 1.0 - 2.0 * u.x;
                let r = (1.0 - z * z).max(0.0).sqrt();
                let phi = 2.0 * PI * u.y;
                Some(DirectionSample {
                    dir: Vec3::new(r * phi.cos(), r * phi.sin(), z),
                    pdf: 1.0 / (4.0 * PI),
                })
            }
            Background::EnvMap(map) => map.sample(u),
        }
    }

    /// Solid-angle density of [`Self::sample`] at `dir`.
    pub fn pdf(&self, dir: Vec3) -> f32 {
        match self {
            Background::Constant(_) => 1.0 / (4.0 * PI),
            Background::EnvMap(map) => map.pdf(dir),
        }
    }
}
