//! Orthonormal shading frames and cosine functions.
//!
//! [`Frame::from_normal`] is the branchless construction of Duff et al.,
//! "Building an Orthonormal Basis, Revisited" (JCGT 2017). Unlike
//! `(0, −n_z, n_y)`-style constructions it never degenerates: for every unit
//! normal the tangents are unit and orthogonal. It is smooth everywhere except
//! across the plane `n_z = 0`, where the tangents flip sign; derivative code that
//! needs one frame along a whole manifold walk should build it once and keep it.

use glam::{DVec3, Vec3};

/// An orthonormal frame: tangent `s`, bitangent `t`, normal `n` (right-handed,
/// `s × t = n`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Frame {
    /// First tangent.
    pub s: Vec3,
    /// Second tangent.
    pub t: Vec3,
    /// Normal; `+z` of the local frame.
    pub n: Vec3,
}

impl Frame {
    /// The frame around a unit normal `n` (Duff et al. 2017).
    #[inline]
    pub fn from_normal(n: Vec3) -> Self {
        let (s, t) = basis_f32(n);
        Self { s, t, n }
    }

    /// World direction → local coordinates (`n` becomes `+z`).
    #[inline]
    pub fn to_local(&self, v: Vec3) -> Vec3 {
        Vec3::new(v.dot(self.s), v.dot(self.t), v.dot(self.n))
    }

    /// Local coordinates → world direction.
    #[inline]
    pub fn to_world(&self, v: Vec3) -> Vec3 {
        self.s * v.x + self.t * v.y + self.n * v.z
    }
}

#[inline]
fn basis_f32(n: Vec3) -> (Vec3, Vec3) {
    let sign = 1.0f32.copysign(n.z);
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    (
        Vec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x),
        Vec3::new(b, sign + n.y * n.y * a, -n.y),
    )
}

/// The same construction in `f64`, for the derivative side: returns `(s, t)`
/// with `s × t = n` for a unit `n`.
#[inline]
pub fn basis_f64(n: DVec3) -> (DVec3, DVec3) {
    let sign = 1.0f64.copysign(n.z);
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    (
        DVec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x),
        DVec3::new(b, sign + n.y * n.y * a, -n.y),
    )
}

/// `cos θ` of a local direction.
#[inline]
pub fn cos_theta(w: Vec3) -> f32 {
    w.z
}

/// `|cos θ|` of a local direction.
#[inline]
pub fn abs_cos_theta(w: Vec3) -> f32 {
    w.z.abs()
}

/// Whether two local directions lie in the same hemisphere.
#[inline]
pub fn same_hemisphere(a: Vec3, b: Vec3) -> bool {
    a.z * b.z > 0.0
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frames_are_orthonormal_for_normals_along_every_axis_and_random() {
        let mut normals = vec![Vec3::X, -Vec3::X, Vec3::Y, -Vec3::Y, Vec3::Z, -Vec3::Z];
        let mut state = 12345u32;
        for _ in 0..1000 {
            let mut next = || {
                state = state.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
                (state >> 8) as f32 / (1u32 << 24) as f32 * 2.0 - 1.0
            };
            let v = Vec3::new(next(), next(), next());
            if v.length() > 1e-3 {
                normals.push(v.normalize());
            }
        }
        normals.push(Vec3::new(1e-8, 0.0, -1.0).normalize());
        for n in normals {
            let f = Frame::from_normal(n);
            assert!((f.s.length() - 1.0).abs() < 1e-5, "{n}");
            assert!((f.t.length() - 1.0).abs() < 1e-5, "{n}");
            assert!(
                f.s.dot(f.t).abs() < 1e-5 && f.s.dot(n).abs() < 1e-5 && f.t.dot(n).abs() < 1e-5
            );
            assert!(f.s.cross(f.t).distance(n) < 1e-5, "right-handed for {n}");
            let v = Vec3::new(0.3, -0.4, 0.5);
            assert!(f.to_world(f.to_local(v)).distance(v) < 1e-5);
            let (s, t) = basis_f64(n.as_dvec3());
            assert!(s.cross(t).distance(n.as_dvec3()) < 1e-6);
        }
    }
}
