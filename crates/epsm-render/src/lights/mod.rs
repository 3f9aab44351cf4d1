//! Lights: emissive objects (area lights), point lights and the background
//! (constant or an importance-sampled lat-long environment map), with one
//! table that selects among them in proportion to their power.

use std::sync::Arc;

use glam::{DVec3, Vec2, Vec3};

use crate::film::Image;
use crate::scene::{Object, ObjectId};

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

/// A lat-long environment map.
#[derive(Clone, Debug)]
pub struct EnvMap {
    /// Linear radiance image (lat-long; row 0 is straight up, `+y`).
    pub image: Image,
    /// Multiplier on the image.
    pub scale: f32,
    /// Rotation about `+y`, radians.
    pub rotate_y: f32,
}

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
    /// Distance to the light point (infinite for the background).
    pub dist: f32,
    /// Light position, world space (reference + wo·dist for finite lights).
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

/// Precomputed selection and sampling tables for every emitter of a scene.
#[derive(Clone, Debug, Default)]
pub struct LightTable {
    _todo: (),
}

impl LightTable {
    /// Builds the tables (world-space emissive triangles, power-proportional selection).
    pub fn build(objects: &[Object], point_lights: &[PointLight], background: &Background) -> Self {
        let _ = (objects, point_lights, background);
        Self::default()
    }

    /// Whether the scene has no emitter at all.
    pub fn is_empty(&self) -> bool {
        true
    }

    /// Samples a light point as seen from `p`. `None` when there is no light
    /// or the sample carries no energy.
    pub fn sample(&self, p: Vec3, u_select: f32, u: Vec2) -> Option<LightSample> {
        let _ = (p, u_select, u);
        unimplemented!("lights: implemented on the lights branch")
    }

    /// Solid-angle pdf (selection included) that `sample` from `p` returns the
    /// point `y` on triangle `triangle` of emissive object `object` with unit normal `n`.
    pub fn pdf_area(&self, object: ObjectId, triangle: u32, p: Vec3, y: Vec3, n: Vec3) -> f32 {
        let _ = (object, triangle, p, y, n);
        unimplemented!("lights: implemented on the lights branch")
    }

    /// Solid-angle pdf (selection included) of sampling background direction `dir`.
    pub fn pdf_background(&self, dir: Vec3) -> f32 {
        let _ = dir;
        unimplemented!("lights: implemented on the lights branch")
    }
}

impl Background {
    /// Radiance seen along world direction `dir` (unit).
    pub fn eval(&self, dir: Vec3) -> Vec3 {
        match self {
            Background::Constant(c) => {
                let _ = dir;
                *c
            }
            Background::EnvMap(_) => unimplemented!("lights: implemented on the lights branch"),
        }
    }
}
