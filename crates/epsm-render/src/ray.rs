//! Rays in world space.

use glam::{Vec3, Vec3A};

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
#[inline(always)]
pub fn offset_origin(p: Vec3, ng: Vec3) -> Vec3 {
    #[cfg(target_arch = "x86_64")]
    {
        offset_origin_sse2(p, ng)
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        Vec3::new(
            offset_component(p.x, ng.x),
            offset_component(p.y, ng.y),
            offset_component(p.z, ng.z),
        )
    }
}

/// Near the origin a float step, elsewhere an integer ULP step.
pub(crate) const ORIGIN: f32 = 1.0 / 32.0;
/// The float step per unit of normal.
pub(crate) const FLOAT_SCALE: f32 = 1.0 / 65536.0;
/// ULP steps per unit of normal.
pub(crate) const INT_SCALE: f32 = 256.0;

/// [`offset_origin`] for one coordinate `pc` with normal component `nc`.
#[cfg_attr(target_arch = "x86_64", cfg(test))]
#[inline(always)]
fn offset_component(pc: f32, nc: f32) -> f32 {
    let of_i = (INT_SCALE * nc) as i32;
    let bits = pc.to_bits() as i32;
    let moved = f32::from_bits((bits + if pc < 0.0 { -of_i } else { of_i }) as u32);
    if pc.abs() < ORIGIN {
        pc + FLOAT_SCALE * nc
    } else {
        moved
    }
}

/// [`offset_origin`] on all three coordinates at once with SSE2 (part of
/// x86-64), the same result as `offset_component` (the portable version) per coordinate for
/// `|ng| ≤ 1`: truncation to integers is exact there, and the sign bit
/// stands for `pc < 0` (they differ only at `-0.0`, which takes the float
/// step).
#[cfg(target_arch = "x86_64")]
#[inline(always)]
#[allow(unsafe_code)]
fn offset_origin_sse2(p: Vec3, ng: Vec3) -> Vec3 {
    use std::arch::x86_64::{
        __m128, _mm_add_epi32, _mm_castps_si128, _mm_castsi128_ps, _mm_cvttps_epi32,
        _mm_srai_epi32, _mm_sub_epi32, _mm_xor_si128,
    };
    let (p, ng) = (Vec3A::from(p), Vec3A::from(ng));
    let scaled: __m128 = (ng * INT_SCALE).into();
    let bits_f: __m128 = p.into();
    // SAFETY: these intrinsics need only SSE2, which every x86-64 CPU has
    // (it is part of the `x86_64` target's baseline); they take and return
    // values, no pointers.
    let moved: __m128 = unsafe {
        let of_i = _mm_cvttps_epi32(scaled);
        let bits = _mm_castps_si128(bits_f);
        let negative = _mm_srai_epi32(bits, 31);
        let step = _mm_sub_epi32(_mm_xor_si128(of_i, negative), negative);
        _mm_castsi128_ps(_mm_add_epi32(bits, step))
    };
    let near = p + FLOAT_SCALE * ng;
    Vec3::from(Vec3A::select(
        p.abs().cmplt(Vec3A::splat(ORIGIN)),
        near,
        Vec3A::from(moved),
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A xorshift stream of uniforms in `[0, 1)` (24 bits) from `seed`.
    fn uniforms(seed: u64) -> impl FnMut() -> f32 {
        let mut state = seed;
        move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 40) as f32 / (1u64 << 24) as f32
        }
    }

    #[test]
    fn offset_origin_matches_the_per_coordinate_rule() {
        let mut uniform = uniforms(0x1234_5678_9ABC_DEF1);
        for k in 0..20_000 {
            let scale = [1e-3, 0.02, 1.0, 1e3, 1e6][k % 5];
            let p = (Vec3::new(uniform(), uniform(), uniform()) - 0.5) * 2.0 * scale;
            let n = (Vec3::new(uniform(), uniform(), uniform()) - 0.5).normalize_or_zero();
            let expected = Vec3::new(
                offset_component(p.x, n.x),
                offset_component(p.y, n.y),
                offset_component(p.z, n.z),
            );
            let got = offset_origin(p, n);
            assert_eq!(
                got.to_array().map(f32::to_bits),
                expected.to_array().map(f32::to_bits),
                "p {p} n {n}"
            );
        }
        // Zero coordinates, signed zeros and axis normals.
        for p in [
            Vec3::ZERO,
            Vec3::new(-0.0, 0.5, -2.0),
            Vec3::new(1.0, -1.0, 0.03125),
        ] {
            for n in [Vec3::X, -Vec3::Y, Vec3::Z, Vec3::new(0.6, -0.8, 0.0)] {
                let expected = Vec3::new(
                    offset_component(p.x, n.x),
                    offset_component(p.y, n.y),
                    offset_component(p.z, n.z),
                );
                assert_eq!(
                    offset_origin(p, n).to_array().map(f32::to_bits),
                    expected.to_array().map(f32::to_bits)
                );
            }
        }
    }
}
