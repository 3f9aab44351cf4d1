//! Transported shading frames that cannot flip during a manifold walk.
//!
//! Each constrained vertex takes the Duff et al. frame `(s₀, t₀)` of its base
//! normal `n₀` once (`epsm_render::frame::basis_f64`) and defines, for any
//! normal `n`, `F(n) = (R s₀, R t₀, n)` with `R` the minimal rotation taking
//! `n₀` to `n` (Rodrigues, with `a = n₀`, `b = n`):
//! `R v = v (a·b) + (a×b)×v + ((a×b)·v)(a×b) / (1 + a·b)`.
//! It is smooth everywhere except at `n = −n₀`, far from any Newton walk.

use epsm_render::frame::basis_f64;
use glam::DVec3;
use nalgebra::{RealField, Vector3};

/// A frame at the base configuration: the normal `n₀` and its Duff tangents.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BaseFrame {
    /// Base unit normal `n₀`.
    pub n0: DVec3,
    /// First base tangent `s₀`.
    pub s0: DVec3,
    /// Second base tangent `t₀` (`s₀ × t₀ = n₀`).
    pub t0: DVec3,
}

fn lift<T: RealField>(v: DVec3) -> Vector3<T> {
    Vector3::new(v.x, v.y, v.z).map(nalgebra::convert)
}

impl BaseFrame {
    /// The frame of unit normal `n0`.
    pub fn new(n0: DVec3) -> Self {
        let (s0, t0) = basis_f64(n0);
        Self { n0, s0, t0 }
    }

    /// The tangents `(s, t)` of the transported frame `F(n)` for unit `n`.
    pub fn tangents<T: RealField + Copy>(&self, n: &Vector3<T>) -> [Vector3<T>; 2] {
        let a = lift::<T>(self.n0);
        let axb = a.cross(n);
        let k = T::one() / (T::one() + a.dot(n));
        let cos = a.dot(n);
        [self.s0, self.t0].map(|v| {
            let v = lift::<T>(v);
            v * cos + axb.cross(&v) + axb * (axb.dot(&v) * k)
        })
    }

    /// `∂[F(n)·w]_xy/∂n` for fixed `w` (two gradient vectors, `n` treated as
    /// a free 3-vector as in [`BaseFrame::project`]). With `a = n₀`,
    /// `k = a×n`, `c = a·n` and `v ∈ {s₀, t₀}`:
    /// `∂(w·Rv)/∂n = (w·v) a − (w·a) v + ((k·w)(v×a) + (k·v)(w×a))/(1+c) − (k·v)(k·w) a/(1+c)²`.
    pub fn project_gradient(&self, n: DVec3, w: DVec3) -> [DVec3; 2] {
        let a = self.n0;
        let k = a.cross(n);
        let inv = 1.0 / (1.0 + a.dot(n));
        let (kw, wa) = (k.dot(w), w.cross(a));
        [self.s0, self.t0].map(|v| {
            let kv = k.dot(v);
            a * w.dot(v) - v * w.dot(a) + (v.cross(a) * kw + wa * kv) * inv
                - a * (kv * kw * inv * inv)
        })
    }

    /// `[F(n)·w]_xy`: the tangent components of `w` in the transported frame.
    pub fn project<T: RealField + Copy>(&self, n: &Vector3<T>, w: &Vector3<T>) -> [T; 2] {
        let [s, t] = self.tangents(n);
        [s.dot(w), t.dot(w)]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn transported_frames_are_orthonormal_and_continuous() {
        for n0 in [
            DVec3::X,
            -DVec3::Y,
            DVec3::Z,
            -DVec3::Z,
            DVec3::new(0.3, -0.5, 0.8).normalize(),
        ] {
            let f = BaseFrame::new(n0);
            let [s, t] = f.tangents(&lift::<f64>(n0));
            assert!((crate::pixel::glam3(&s) - f.s0).length() < 1e-15);
            assert!((crate::pixel::glam3(&t) - f.t0).length() < 1e-15);
            // Normals crossing the Duff seam (n_z = 0) keep a continuous frame.
            let mut prev: Option<[Vector3<f64>; 2]> = None;
            for i in 0..=200 {
                let a = -1.2 + 2.4 * f64::from(i) / 200.0;
                let n = (n0 + DVec3::new(a.sin(), 0.7 * a.cos() - 0.7, 0.4 * a)).normalize();
                let [s, t] = f.tangents(&lift::<f64>(n));
                let nn = lift::<f64>(n);
                assert!((s.norm() - 1.0).abs() < 1e-12 && (t.norm() - 1.0).abs() < 1e-12);
                assert!(s.dot(&t).abs() < 1e-12 && s.dot(&nn).abs() < 1e-12);
                assert!((s.cross(&t) - nn).norm() < 1e-12, "right-handed");
                if let Some([ps, pt]) = prev {
                    assert!((s - ps).norm() < 0.1 && (t - pt).norm() < 0.1, "no flip");
                }
                prev = Some([s, t]);
            }
        }
    }
}
