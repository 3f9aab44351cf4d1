//! Adam (Kingma & Ba 2015) with per-parameter learning rates and bounds,
//! exponential learning-rate decay and reset; its state serialises for
//! checkpoints.
//!
//! Step `t` (1-based since the last reset), per parameter `k`:
//! `m ← β₁m + (1−β₁)g`, `v ← β₂v + (1−β₂)g²`,
//! `θ ← clamp(θ − lr_k · decay^i · m̂ / (√v̂ + ε), lo_k, hi_k)` with
//! `m̂ = m/(1−β₁ᵗ)`, `v̂ = v/(1−β₂ᵗ)` and `i` the decay step: the iteration,
//! halved at each reset.
//!
//! A reset starts a new phase (the hybrid schedule's switch from OT to L2):
//! the moments are forgotten, and the step size goes back to where it stood
//! at half the iterations run so far, from where it decays again. A phase
//! that starts late would otherwise take steps of a tenth of the first ones
//! or less: the L2 phase then stops where the OT phase left θ, instead of
//! correcting what the OT loss could not resolve.
//!
//! | key (`[optimizer]`) | default | range |
//! |---|---|---|
//! | `lr` | automatic per parameter ([`crate::problem::auto`]) | > 0 (per parameter: `parameters[i].lr`) |
//! | `decay` | automatic: `(1/20)^(1/iterations)` | (0, 1] |
//! | `beta1` | 0.5 ([`crate::problem::auto::BETA1`]) | [0, 1) |
//! | `beta2` | 0.999 | [0, 1) |

use serde::{Deserialize, Serialize};

/// Adam's settings.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct AdamSettings {
    /// Learning rate of each parameter (user units per step).
    pub lr: Vec<f64>,
    /// Bounds `[lo, hi]` of each parameter (`±f64::MAX` when unbounded).
    pub bounds: Vec<[f64; 2]>,
    /// Multiplicative decay of the learning rate per iteration.
    pub decay: f64,
    /// First-moment decay β₁.
    pub beta1: f64,
    /// Second-moment decay β₂.
    pub beta2: f64,
    /// ε of the denominator.
    pub epsilon: f64,
}

/// Adam's moments: everything a checkpoint needs besides θ.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Adam {
    /// The settings.
    pub settings: AdamSettings,
    /// First moments.
    pub m: Vec<f64>,
    /// Second moments.
    pub v: Vec<f64>,
    /// Steps since the last reset.
    pub t: u32,
    /// Decay step `i`: steps since the start, halved at each reset.
    pub iteration: u32,
}

impl Adam {
    /// A fresh optimizer for `settings.lr.len()` parameters.
    pub fn new(settings: AdamSettings) -> Self {
        let n = settings.lr.len();
        Self {
            settings,
            m: vec![0.0; n],
            v: vec![0.0; n],
            t: 0,
            iteration: 0,
        }
    }

    /// Starts a new phase: forgets the moments and halves the decay step
    /// (module docs).
    pub fn reset(&mut self) {
        self.m.iter_mut().for_each(|x| *x = 0.0);
        self.v.iter_mut().for_each(|x| *x = 0.0);
        self.t = 0;
        self.iteration /= 2;
    }

    /// Clamps `theta` into the bounds.
    pub fn clamp(&self, theta: &mut [f64]) {
        for (x, [lo, hi]) in theta.iter_mut().zip(&self.settings.bounds) {
            *x = x.clamp(*lo, *hi);
        }
    }

    /// One step on `theta` with gradient `grad`. A non-finite entry (every
    /// path guard drops and counts before one could reach here) is refused
    /// with its index, leaving `theta` and the moments unchanged.
    pub fn step(&mut self, theta: &mut [f64], grad: &[f64]) -> Result<(), NonFiniteGradient> {
        if let Some(param) = grad.iter().position(|g| !g.is_finite()) {
            return Err(NonFiniteGradient { param });
        }
        self.t += 1;
        let s = &self.settings;
        let scale = s.decay.powi(self.iteration as i32);
        let (c1, c2) = (
            1.0 - s.beta1.powi(self.t as i32),
            1.0 - s.beta2.powi(self.t as i32),
        );
        for k in 0..theta.len().min(grad.len()) {
            let g = grad[k];
            self.m[k] = s.beta1 * self.m[k] + (1.0 - s.beta1) * g;
            self.v[k] = s.beta2 * self.v[k] + (1.0 - s.beta2) * g * g;
            let step = s.lr[k] * scale * (self.m[k] / c1) / ((self.v[k] / c2).sqrt() + s.epsilon);
            theta[k] -= step;
        }
        self.iteration += 1;
        self.clamp(theta);
        Ok(())
    }
}

/// A gradient entry that is NaN or infinite, by parameter index.
#[derive(Clone, Copy, Debug, PartialEq, Eq, thiserror::Error)]
#[error("the gradient of parameter {param} is not finite")]
pub struct NonFiniteGradient {
    /// Index of the parameter.
    pub param: usize,
}

#[cfg(test)]
mod tests {
    use super::*;

    fn adam(lr: f64, bounds: [f64; 2]) -> Adam {
        Adam::new(AdamSettings {
            lr: vec![lr],
            bounds: vec![bounds],
            decay: 1.0,
            beta1: 0.9,
            beta2: 0.999,
            epsilon: 1e-12,
        })
    }

    #[test]
    fn minimises_a_quadratic_within_bounds() {
        let mut a = adam(0.1, [-10.0, 10.0]);
        let mut x = [3.0];
        for _ in 0..300 {
            let g = [2.0 * (x[0] - 1.0)];
            a.step(&mut x, &g).expect("finite");
        }
        assert!((x[0] - 1.0).abs() < 0.05, "x = {}", x[0]);
        let mut b = adam(0.5, [2.0, 5.0]);
        let mut y = [3.0];
        for _ in 0..50 {
            let g = [2.0 * y[0]];
            b.step(&mut y, &g).expect("finite");
        }
        assert_eq!(y[0], 2.0);
    }

    #[test]
    fn first_step_has_the_learning_rate_and_reset_forgets() {
        let mut a = adam(0.25, [-f64::MAX, f64::MAX]);
        let mut x = [0.0];
        a.step(&mut x, &[-3.0]).expect("finite");
        assert!((x[0] - 0.25).abs() < 1e-9);
        a.reset();
        assert_eq!((a.t, a.m[0], a.v[0], a.iteration), (0, 0.0, 0.0, 0));
        let json = serde_json::to_string(&a).expect("serialise");
        let back: Adam = serde_json::from_str(&json).expect("parse");
        assert_eq!(back, a);
    }

    #[test]
    fn a_reset_steps_the_decay_back_to_half_the_iterations_run() {
        let mut a = adam(1.0, [-f64::MAX, f64::MAX]);
        a.settings.decay = 0.9;
        let mut x = [0.0];
        for _ in 0..10 {
            a.step(&mut x, &[-1.0]).expect("finite");
        }
        a.reset();
        // The first step of the new phase has Adam's unit normalised step
        // times the step size of iteration 5, not of iteration 10.
        let before = x[0];
        a.step(&mut x, &[-1.0]).expect("finite");
        assert!(
            (x[0] - before - 0.9f64.powi(5)).abs() < 1e-9,
            "{}",
            x[0] - before
        );
        assert_eq!((a.t, a.iteration), (1, 6));
    }

    #[test]
    fn a_non_finite_gradient_is_refused_not_zeroed() {
        let mut a = adam(0.25, [-f64::MAX, f64::MAX]);
        let mut x = [1.0];
        assert_eq!(
            a.step(&mut x, &[f64::NAN]),
            Err(NonFiniteGradient { param: 0 })
        );
        assert_eq!((x[0], a.t, a.iteration, a.m[0]), (1.0, 0, 0, 0.0));
    }
}
