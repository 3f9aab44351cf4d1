//! Rays in world space.

use glam::Vec3;

/// A ray `origin + t·dir` for `t` in `[t_min, t_max]`. `dir` need not be unit
/// (instance traversal keeps `t` by transforming an unnormalised direction),
/// but rays made by the camera and by sampling are unit.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ray {
    /// Origin, world space.
    pub origin: Vec3,
    /// Direction, world space.
    pub dir: Vec3,
    /// Smallest accepted distance.
    pub t_min: f32,
    /// Largest accepted distance.
    pub t_max: f32,
}

impl Ray {
    /// A ray from `origin` along `dir` with `t` in `[0, ∞)`.
    #[inline]
    pub fn new(origin: Vec3, dir: Vec3) -> Self {
        Self {
            origin,
            dir,
            t_min: 0.0,
            t_max: f32::INFINITY,
        }
    }

    /// The point at distance `t`.
    #[inline]
    pub fn at(&self, t: f32) -> Vec3 {
        self.origin + self.dir * t
    }
}

/// Offsets a ray origin `p` off a surface with geometric normal `ng` so that
/// the new ray does not re-hit that surface, whatever the scene's scale
/// (Wächter and Binder, "A Fast and Robust Method for Avoiding
/// Self-Intersection", Ray Tracing Gems, 2019: integer ULP steps away from the
/// origin, a float step near it). Pass `ng` facing the side the ray leaves to.
#[inline]
pub fn offset_origin(p: Vec3, ng: Vec3) -> Vec3 {
    const ORIGIN: f32 = 1.0 / 32.0;
    const FLOAT_SCALE: f32 = 1.0 / 65536.0;
    const INT_SCALE: f32 = 256.0;
    let step = |pc: f32, nc: f32| -> f32 {
        let of_i = (INT_SCALE * nc) as i32;
        let bits = pc.to_bits() as i32;
        let moved = f32::from_bits((bits + if pc < 0.0 { -of_i } else { of_i }) as u32);
        if pc.abs() < ORIGIN {
            pc + FLOAT_SCALE * nc
        } else {
            moved
        }
    };
    Vec3::new(step(p.x, ng.x), step(p.y, ng.y), step(p.z, ng.z))
}
