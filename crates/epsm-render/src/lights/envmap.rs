//! Lat-long environment maps, importance-sampled by luminance.
//!
//! A world direction `d` (`+y` up) maps to image coordinates
//! `φ = atan2(d.x, −d.z) − rotate_y`, `u = φ/2π + 0.5` (wrapped), `θ = acos d.y`,
//! `v = θ/π` (row 0 straight up). Radiance is the nearest pixel times `scale`
//! (piecewise constant), and directions are sampled from a 2D piecewise-constant
//! distribution over the pixels proportional to `luminance · sin θ` at the
//! row centre (pbrt-v4 §12.5.2), whose density in `(u, v)` converts to solid
//! angle as `pdf_ω = pdf_uv / (2π² sin θ)`. The poles (`sin θ = 0`) have
//! density zero.
//!
//! | key | unit | default | range |
//! |---|---|---|---|
//! | `background.envmap` | lat-long EXR (linear) or PNG (sRGB) | — | any size |
//! | `background.scale` | — | 1 | ≥ 0 |
//! | `background.rotate_y` | degrees (file), radians (code) | 0 | any |
//!
//! ```toml
//! [background]
//! envmap = "sky.exr"
//! scale = 1.0
//! rotate_y = 90.0
//! ```

use std::f32::consts::PI;

use glam::{Vec2, Vec3};

use super::distribution::Distribution2D;
use crate::film::Image;

/// A lat-long environment map with its sampling table. Build it with
/// [`EnvMap::new`]; `scale` and `rotate_y` may be changed afterwards (the table
/// depends on the image only).
#[derive(Clone, Debug)]
pub struct EnvMap {
    /// Linear radiance image (lat-long; row 0 is straight up, `+y`).
    image: Image,
    /// Multiplier on the image.
    pub scale: f32,
    /// Rotation about `+y`, radians.
    pub rotate_y: f32,
    /// Texel selection ∝ luminance · sin θ; `None` for a black map.
    distribution: Option<Distribution2D>,
    /// Solid-angle mean of the image (before `scale`).
    mean: Vec3,
}

/// A sampled background direction.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DirectionSample {
    /// Unit world direction.
    pub dir: Vec3,
    /// Solid-angle density (background selection excluded).
    pub pdf: f32,
}

impl EnvMap {
    /// Precomputes the sampling table and the mean radiance of `image`.
    pub fn new(image: Image, scale: f32, rotate_y: f32) -> Self {
        let (w, h) = (image.width as usize, image.height as usize);
        let mut weights = Vec::with_capacity(w * h);
        let mut mean = glam::DVec3::ZERO;
        for y in 0..h {
            let (t0, t1) = (y as f64 / h as f64, (y + 1) as f64 / h as f64);
            let sin_centre = (std::f64::consts::PI * 0.5 * (t0 + t1)).sin();
            let row_solid_angle = 2.0 * std::f64::consts::PI / w as f64
                * ((std::f64::consts::PI * t0).cos() - (std::f64::consts::PI * t1).cos());
            for x in 0..w {
                let c = image.get(x as u32, y as u32);
                weights.push(luminance(c) as f64 * sin_centre);
                mean += c.as_dvec3() * row_solid_angle;
            }
        }
        Self {
            distribution: Distribution2D::new(&weights, w, h),
            mean: (mean / (4.0 * std::f64::consts::PI)).as_vec3(),
            image,
            scale,
            rotate_y,
        }
    }

    /// The radiance image.
    pub fn image(&self) -> &Image {
        &self.image
    }

    /// Mean radiance over the sphere, `scale` included.
    pub fn mean_radiance(&self) -> Vec3 {
        self.mean * self.scale
    }

    /// Image coordinates `(u, v) ∈ [0, 1)²` of a unit world direction.
    pub fn uv(&self, dir: Vec3) -> Vec2 {
        let phi = dir.x.atan2(-dir.z) - self.rotate_y;
        let u = (phi / (2.0 * PI) + 0.5).rem_euclid(1.0);
        let v = dir.y.clamp(-1.0, 1.0).acos() / PI;
        Vec2::new(u, v)
    }

    /// The unit world direction at image coordinates `uv`.
    pub fn direction(&self, uv: Vec2) -> Vec3 {
        let phi = (uv.x - 0.5) * 2.0 * PI + self.rotate_y;
        let theta = uv.y * PI;
        let sin_theta = theta.sin();
        Vec3::new(sin_theta * phi.sin(), theta.cos(), -sin_theta * phi.cos())
    }

    /// Radiance along `dir`: the nearest pixel times `scale`.
    pub fn eval(&self, dir: Vec3) -> Vec3 {
        if self.image.width == 0 || self.image.height == 0 {
            return Vec3::ZERO;
        }
        let uv = self.uv(dir);
        let x = ((uv.x * self.image.width as f32) as u32).min(self.image.width - 1);
        let y = ((uv.y * self.image.height as f32) as u32).min(self.image.height - 1);
        self.image.get(x, y) * self.scale
    }

    /// Solid-angle density of [`Self::sample`] at `dir` (zero at the poles and
    /// for a black map).
    pub fn pdf(&self, dir: Vec3) -> f32 {
        let Some(distribution) = &self.distribution else {
            return 0.0;
        };
        let sin_theta = (1.0 - dir.y * dir.y).max(0.0).sqrt();
        if sin_theta <= 0.0 {
            return 0.0;
        }
        let pdf_uv = distribution.pdf(self.uv(dir));
        (pdf_uv / (2.0 * std::f64::consts::PI * std::f64::consts::PI * sin_theta as f64)) as f32
    }

    /// Samples a direction ∝ luminance; `None` for a black map or a pole.
    pub fn sample(&self, u: Vec2) -> Option<DirectionSample> {
        let s = self.distribution.as_ref()?.sample(u)?;
        let dir = self.direction(s.uv);
        let pdf = self.pdf(dir);
        (pdf > 0.0 && pdf.is_finite()).then_some(DirectionSample { dir, pdf })
    }
}

/// Rec. 709 luminance of linear RGB, clamped at zero.
pub fn luminance(c: Vec3) -> f32 {
    (0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z).max(0.0)
}
