//! The OT phase's screen-space Gauss–Newton step (docs/design.md §5.8).
//!
//! The matching pulls every pixel toward a position; the pass's
//! [`ScreenSystem`] holds the least-squares problem "move the driven pixels
//! onto their matches": `min_Δ Σ_p |J_p Δ − r_p|²`. Its Levenberg–Marquardt
//! solution `Δ = (H + μ diag H)⁻¹ b` moves the parameters jointly, so
//! parameters whose pixel motions are alike (a camera's pitch and its
//! vertical move, an object's turn and its slide) are told apart by what
//! differs between their motions (parallax, the far side of the object)
//! instead of each following its own share of the pull, as Adam's
//! per-parameter steps do. The step is scaled down as a whole until no
//! parameter moves more than its trust radius (its learning rate at this
//! iteration times [`TRUST`]).

use nalgebra::{DMatrix, DVector};

use crate::backprop::ScreenSystem;

/// Marquardt's damping μ, relative to each diagonal entry of `H`.
pub const DAMPING: f64 = 0.05;

/// A parameter's trust radius in multiples of its learning rate at the
/// iteration.
pub const TRUST: f64 = 2.0;

/// `grad` preconditioned by the system: `(H + μ diag H)⁻¹ grad` on the
/// parameters with a pixel motion, scaled by the mean of their `H`
/// diagonal (so its magnitude stays that of `grad`); the other entries, and
/// all of them when the system is singular, are `grad`'s.
pub fn precondition(system: &ScreenSystem, grad: &[f64]) -> Vec<f64> {
    let n = system.b.len();
    let mut out = grad.to_vec();
    let moving: Vec<usize> = (0..n.min(grad.len()))
        .filter(|&k| system.h[k * n + k] > 0.0 && system.h[k * n + k].is_finite())
        .collect();
    if moving.is_empty() {
        return out;
    }
    let m = moving.len();
    let h = DMatrix::from_fn(m, m, |i, j| {
        let v = system.h[moving[i] * n + moving[j]];
        if i == j { v * (1.0 + DAMPING) } else { v }
    });
    let mean = h.diagonal().mean();
    let g = DVector::from_fn(m, |i, _| grad[moving[i]]);
    let Some(d) = h.cholesky().map(|c| c.solve(&g) * mean) else {
        return out;
    };
    if d.iter().all(|x| x.is_finite()) {
        for (&k, x) in moving.iter().zip(d.iter()) {
            out[k] = *x;
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two parameters whose motions are nearly alike: the joint step
    /// recovers each, where the gradient `b` alone points mostly along
    /// their common direction.
    #[test]
    fn joint_step_separates_correlated_parameters() {
        // J rows for pixels: parameter 0 moves every pixel by 1, parameter
        // 1 by 1 on the near half and 0.8 on the far half.
        let rows: Vec<[f64; 2]> = (0..100)
            .map(|i| [1.0, if i < 50 { 1.0 } else { 0.8 }])
            .collect();
        let truth = [0.3, -0.2];
        let mut system = ScreenSystem {
            h: vec![0.0; 4],
            b: vec![0.0; 2],
            pixels: 100,
        };
        for j in &rows {
            let r = j[0] * truth[0] + j[1] * truth[1];
            for a in 0..2 {
                system.b[a] += j[a] * r;
                for c in 0..2 {
                    system.h[a * 2 + c] += j[a] * j[c];
                }
            }
        }
        let step = screen_step(&system, &[10.0, 10.0]);
        // Marquardt's damping shortens the step a little along the valley.
        assert!((step[0].unwrap() - truth[0]).abs() < 0.05, "{step:?}");
        assert!((step[1].unwrap() - truth[1]).abs() < 0.05, "{step:?}");
        // The gradient direction gets the second parameter's sign wrong.
        assert!(system.b[1] > 0.0);
        // The trust radius scales the whole step.
        let small = screen_step(&system, &[0.01, 10.0]);
        let ratio = small[1].unwrap() / step[1].unwrap();
        assert!((small[0].unwrap().abs() - 0.01).abs() < 1e-12);
        assert!((ratio - small[0].unwrap() / step[0].unwrap()).abs() < 1e-12);
    }

    #[test]
    fn parameters_without_motion_get_no_step() {
        let system = ScreenSystem {
            h: vec![4.0, 0.0, 0.0, 0.0],
            b: vec![2.0, 0.0],
            pixels: 4,
        };
        let step = screen_step(&system, &[1.0, 1.0]);
        assert!(step[1].is_none());
        assert!((step[0].unwrap() - 2.0 / 4.2).abs() < 1e-12);
    }
}
