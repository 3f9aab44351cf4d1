//! Analytic local Jacobians of the constraints (the fast path; the generic
//! [`Constraint::eval`] with forward-mode duals is its reference, compared
//! in the tests below).
//!
//! Every constraint is `C = [s(n)·W, t(n)·W] − k` with `(s, t)` the
//! transported frame at `n` and `W` a direction built from
//! `ŵi = (a − x)/ℓi`, `ŵo = (b − x)/ℓo`. With `P_w = I − w wᵀ`:
//! `∂ŵ/∂(end) = P_ŵ/ℓ`, so `∂C_r/∂a`, `∂C_r/∂b` are `(∂W/∂·)ᵀ r` for the
//! frame rows `r ∈ {s, t}`, `∂C_r/∂x = −(∂C_r/∂a + ∂C_r/∂b)`, and
//! `∂C_r/∂n` comes from [`crate::frame::BaseFrame::project_gradient`]. The value itself is
//! always [`Constraint::eval`]'s.

use glam::DVec3;

use super::{Constraint, ConstraintKind, Local};
use crate::pixel::glam3;

/// `(P_w / ℓ) v` for a unit `w` (symmetric, so also its transpose).
fn tangent(w: DVec3, len: f64, v: DVec3) -> DVec3 {
    (v - w * w.dot(v)) / len
}

impl Constraint {
    /// The value and the 2×12 local Jacobian `∂C/∂(a, x, b, n)` at one point.
    pub fn local(&self, a: DVec3, x: DVec3, b: DVec3, n: DVec3) -> Local {
        let (da, db) = (a - x, b - x);
        let (la, lb) = (da.length(), db.length());
        let (wi, wo) = (da / la, db / lb);
        let f = &self.frame;
        let [s, t] = f
            .tangents(&crate::constraints::na::<f64>(n))
            .map(|v| glam3(&v));
        // W and the frame rows; r ↦ ((∂W/∂a)ᵀ r, (∂W/∂b)ᵀ r) below.
        let (w, frame_rows): (DVec3, [DVec3; 2]) = match self.kind {
            ConstraintKind::Specular { eta, .. } => (wi + wo * eta, [s, t]),
            ConstraintKind::Glossy { .. } => ((wi + wo).normalize(), [s, t]),
            ConstraintKind::FixedDirection { .. } => (wo, [s, t]),
            ConstraintKind::Collinear => (wi - wo, [s, t]),
            #[cfg(test)]
            ConstraintKind::Segment { .. } => ((b - a).normalize(), [f.s0, f.t0]),
        };
        let ends = |r: DVec3| -> [DVec3; 2] {
            match self.kind {
                ConstraintKind::Specular { eta, .. } => {
                    [tangent(wi, la, r), tangent(wo, lb, r) * eta]
                }
                ConstraintKind::Glossy { .. } => {
                    let q = tangent(w, (wi + wo).length(), r);
                    [tangent(wi, la, q), tangent(wo, lb, q)]
                }
                ConstraintKind::FixedDirection { .. } => [DVec3::ZERO, tangent(wo, lb, r)],
                ConstraintKind::Collinear => [tangent(wi, la, r), -tangent(wo, lb, r)],
                #[cfg(test)]
                ConstraintKind::Segment { .. } => {
                    let g = tangent(w, (b - a).length(), r);
                    [-g, g]
                }
            }
        };
        let grad_n = match self.kind {
            #[cfg(test)]
            ConstraintKind::Segment { .. } => [DVec3::ZERO; 2],
            _ => f.project_gradient(n, w),
        };
        let mut grad = [[DVec3::ZERO; 4]; 2];
        for (row, r) in frame_rows.into_iter().enumerate() {
            let [ga, gb] = ends(r);
            let gx = match self.kind {
                #[cfg(test)]
                ConstraintKind::Segment { .. } => DVec3::ZERO,
                _ => -(ga + gb),
            };
            grad[row] = [ga, gx, gb, grad_n[row]];
        }
        Local {
            // The value from the one generic definition of C.
            value: self.value(a, x, b, n),
            grad,
        }
    }
}
