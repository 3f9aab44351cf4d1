//! Half-vector constraints at specular and glossy vertices (docs/design.md §5.3).
//!
//! - Smooth reflection / refraction: `C = [F·(wi + η wo)]_xy`, unnormalised.
//!   Its zero set is the law of reflection (η = 1) or Snell's law with
//!   η = η(wo side)/η(wi side) (the record's relative IOR): the tangential
//!   parts of `η_i wi` and `η_o wo` cancel. Unlike the normalised half vector
//!   it stays well conditioned when η → 1 (IOR 1.0001), where
//!   `|wi + η wo| → 0`; at `C = 0` both give the same `dx/dθ` (A and B scale by
//!   the same `1/|h|`).
//! - Glossy reflection: `C = [F·normalize(wi + wo)]_xy − m_xy`, `m` the
//!   microfacet normal at the base configuration in the base frame: the path
//!   keeps its sampled microfacet normal.

use nalgebra::{RealField, Vector3};

use crate::frame::BaseFrame;

/// `[F(n)·(wi + η wo)]_xy`.
pub(crate) fn smooth<T: RealField + Copy>(
    frame: &BaseFrame,
    n: &Vector3<T>,
    wi: &Vector3<T>,
    wo: &Vector3<T>,
    eta: f64,
) -> [T; 2] {
    frame.project(n, &(wi + wo * nalgebra::convert::<f64, T>(eta)))
}

/// `[F(n)·normalize(wi + wo)]_xy − m`.
pub(crate) fn glossy<T: RealField + Copy>(
    frame: &BaseFrame,
    n: &Vector3<T>,
    wi: &Vector3<T>,
    wo: &Vector3<T>,
    m: [f64; 2],
) -> [T; 2] {
    let [hx, hy] = frame.project(n, &(wi + wo).normalize());
    [
        hx - nalgebra::convert::<f64, T>(m[0]),
        hy - nalgebra::convert::<f64, T>(m[1]),
    ]
}
