//! glam's `f32` matrix products in sixteen lanes, term for term:
//! `Mat3A * v = (x_axis·x + y_axis·y) + z_axis·z` and
//! `Affine3A::transform_point3a(v) = Mat3A * v + translation` (the same
//! values as `transform_point3` on a `Vec3`), one vector per lane, the
//! matrix shared.
//!
//! No parameters.

use glam::{Affine3A, Mat3A};

use crate::simd::{F32x16, Lanes, Vec3x16};

/// `m * v` per lane.
#[inline(always)]
pub(super) fn mat_mul<B: Lanes>(k: B, m: &Mat3A, v: Vec3x16<B>) -> Vec3x16<B> {
    Vec3x16::new(row(k, m, 0, v), row(k, m, 1, v), row(k, m, 2, v))
}

/// Component `c` of `m * v`: `(x_axis[c]·x + y_axis[c]·y) + z_axis[c]·z`.
#[inline(always)]
fn row<B: Lanes>(k: B, m: &Mat3A, c: usize, v: Vec3x16<B>) -> F32x16<B> {
    let (x, y, z) = (m.x_axis[c], m.y_axis[c], m.z_axis[c]);
    F32x16::splat(k, x) * v.x + F32x16::splat(k, y) * v.y + F32x16::splat(k, z) * v.z
}

/// `a.transform_point3a(v)` per lane.
#[inline(always)]
pub(super) fn transform_point<B: Lanes>(k: B, a: &Affine3A, v: Vec3x16<B>) -> Vec3x16<B> {
    mat_mul(k, &a.matrix3, v) + Vec3x16::splat(k, a.translation.into())
}

/// `a.transform_vector3a(v)` per lane.
#[inline(always)]
pub(super) fn transform_vector<B: Lanes>(k: B, a: &Affine3A, v: Vec3x16<B>) -> Vec3x16<B> {
    mat_mul(k, &a.matrix3, v)
}
