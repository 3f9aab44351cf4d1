//! The PRDPT baseline (Fischer & Ritschel, "Plateau-reduced differentiable
//! path tracing", CVPR 2023; docs/design.md §6): the gradient of the L2
//! loss convolved with a Gaussian in parameter space, estimated from
//! forward renders alone.
//!
//! With per-parameter widths `σ_k`, the smoothed loss is
//! `L_σ(θ) = E[L(θ + σ∘ε)]`, `ε ~ N(0, I)`, and its gradient
//! `∂L_σ/∂θ_k = E[ε_k · L(θ + σ∘ε)] / σ_k`. Each of [`PAIRS`] antithetic
//! pairs renders `θ + σ∘ε` and `θ − σ∘ε` with the same sample stream
//! (common random numbers, so the pair's difference holds little render
//! noise) and adds `ε_k · (L₊ − L₋) / (2σ_k)`; the estimate is their mean.
//! The widths start at [`SIGMA_FRACTION`] of each parameter's scale (the
//! scale its automatic learning rate follows, `crate::problem::auto`) and
//! anneal with the learning rate's decay, so the smoothing that bridges a
//! plateau early leaves the minimum unblurred late.

use rand::{Rng, SeedableRng};
use rand_distr::StandardNormal;
use rand_pcg::Pcg64;

use std::time::Instant;

use super::{GradientEval, Optimization, PRDPT_SALT, render_image};
use crate::backprop::PassStats;
use crate::loss::{LossKind, evaluate};
use crate::problem::ParamSpec;
use crate::problem::auto::CROSSING;
use crate::report::Timings;
use crate::run::OptResult;

/// Antithetic pairs per gradient estimate (two forward renders each).
pub const PAIRS: u32 = 4;

/// The first smoothing width as a fraction of a parameter's scale.
pub const SIGMA_FRACTION: f64 = 0.1;

/// The per-parameter smoothing widths of a run and their annealing.
#[derive(Clone, Debug, PartialEq)]
pub struct Smoothing {
    /// `σ_k` at iteration 0 (user units).
    pub sigma0: Vec<f64>,
    /// Factor per iteration (the learning rate's decay).
    pub decay: f64,
}

impl Smoothing {
    /// The widths of `params` in a run of `iterations` whose learning rate
    /// decays by `decay` per iteration. A parameter's scale is its
    /// automatic step's, or the one its explicit learning rate implies
    /// (`lr × iterations / CROSSING`).
    pub fn new(params: &[ParamSpec], iterations: u32, decay: f64) -> Self {
        let sigma0 = params
            .iter()
            .map(|p| {
                let scale = p.step.as_ref().map_or_else(
                    || p.lr * f64::from(iterations.max(1)) / CROSSING,
                    |s| s.scale,
                );
                SIGMA_FRACTION * scale
            })
            .collect();
        Self { sigma0, decay }
    }

    /// `σ` at `iteration`.
    pub fn sigma(&self, iteration: u32) -> Vec<f64> {
        let f = self.decay.powf(f64::from(iteration));
        self.sigma0.iter().map(|s| s * f).collect()
    }
}

/// The perturbations `ε` (one per pair, each of `n` standard normal
/// components) drawn from the stream seeded `seed`.
pub fn perturbations(n: usize, seed: u64) -> Vec<Vec<f64>> {
    let mut rng = Pcg64::seed_from_u64(seed);
    (0..PAIRS)
        .map(|_| (0..n).map(|_| rng.sample(StandardNormal)).collect())
        .collect()
}

/// The gradient estimate from the pairs' losses: `losses[i] = (L₊, L₋)`
/// for perturbation `eps[i]`, widths `sigma`.
pub fn estimate(eps: &[Vec<f64>], losses: &[(f64, f64)], sigma: &[f64]) -> Vec<f64> {
    let mut g = vec![0.0; sigma.len()];
    for (e, (plus, minus)) in eps.iter().zip(losses) {
        for ((gk, ek), sk) in g.iter_mut().zip(e).zip(sigma) {
            *gk += ek * (plus - minus) / (2.0 * sk);
        }
    }
    let n = eps.len().max(1) as f64;
    g.iter_mut().for_each(|gk| *gk /= n);
    g
}

impl Optimization {
    /// The `prdpt` method's gradient: [`PAIRS`] antithetic pairs of
    /// forward renders at the match resolution, `render.spp_grad` samples
    /// each, and the L2 loss of a render at θ for the row.
    pub(super) fn smoothed_gradient(&self, smoothing: &Smoothing) -> OptResult<GradientEval> {
        let t0 = Instant::now();
        let spp = self.problem.passes.spp_grad;
        let lambda = self.problem.loss.lambda;
        let sigma = smoothing.sigma(self.iteration);
        let eps = perturbations(self.theta.len(), u64::from(self.seed(PRDPT_SALT)));
        let mut view = self.grad.clone();
        let mut losses = Vec::with_capacity(eps.len());
        for (i, e) in (0u32..).zip(&eps) {
            let seed = self.seed(PRDPT_SALT + 1 + i);
            let mut pair = [0.0; 2];
            for (l, sign) in pair.iter_mut().zip([1.0, -1.0]) {
                let mut theta: Vec<f64> = (self.theta.iter().zip(e).zip(&sigma))
                    .map(|((t, ek), sk)| t + sign * sk * ek)
                    .collect();
                self.adam.clamp(&mut theta);
                view.set(&theta);
                let image = render_image(&view.scene, spp, seed);
                *l = evaluate(LossKind::L2, &image, &self.target_match, lambda, None)?.value;
            }
            losses.push((pair[0], pair[1]));
        }
        let image = render_image(&self.grad.scene, spp, self.seed(0));
        let loss = evaluate(LossKind::L2, &image, &self.target_match, lambda, None)?;
        let traced = u64::from(spp) * u64::from(image.width * image.height);
        Ok(GradientEval {
            grad: estimate(&eps, &losses, &sigma),
            loss,
            image,
            stats: PassStats {
                traced: traced * (2 * eps.len() as u64 + 1),
                ..PassStats::default()
            },
            timings: Timings {
                primal: 0.0,
                trace: t0.elapsed().as_secs_f64(),
                matching: 0.0,
                solve: 0.0,
            },
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// On a quadratic the smoothed gradient is the gradient itself: the
    /// estimator's mean over many perturbations is within its standard error.
    #[test]
    fn estimate_is_unbiased_on_a_quadratic() {
        let a = [2.0, -1.0, 0.5];
        let loss = |t: &[f64]| -> f64 { t.iter().zip(a).map(|(x, c)| c * x * x).sum() };
        let theta = [0.3, -0.2, 1.0];
        let sigma = [0.05, 0.2, 0.1];
        let truth: Vec<f64> = theta.iter().zip(a).map(|(x, c)| 2.0 * c * x).collect();
        let mut mean = [0.0; 3];
        let runs = 4000;
        for s in 0..runs {
            let eps = perturbations(3, s);
            let losses: Vec<(f64, f64)> = eps
                .iter()
                .map(|e| {
                    let at = |sign: f64| -> Vec<f64> {
                        theta
                            .iter()
                            .zip(e)
                            .zip(sigma)
                            .map(|((t, ek), sk)| t + sign * sk * ek)
                            .collect()
                    };
                    (loss(&at(1.0)), loss(&at(-1.0)))
                })
                .collect();
            for (m, g) in mean.iter_mut().zip(estimate(&eps, &losses, &sigma)) {
                *m += g / runs as f64;
            }
        }
        for (k, (m, t)) in mean.iter().zip(&truth).enumerate() {
            // Per-sample spread of ε_k·Σ_j ε_j·g_j·σ_j/σ_k is about
            // |g|·max σ/σ_k; 4000 × 4 samples give 1/126 of it.
            let spread: f64 = truth
                .iter()
                .zip(sigma)
                .map(|(g, s)| (g * s).powi(2))
                .sum::<f64>()
                .sqrt()
                / sigma[k];
            let se = spread / ((runs * u64::from(PAIRS)) as f64).sqrt();
            assert!(
                (m - t).abs() < 4.0 * se,
                "param {k}: mean {m}, truth {t}, se {se}"
            );
        }
    }

    #[test]
    fn widths_follow_the_scale_and_anneal() {
        let mut p = ParamSpec::new("a.translate.x", 0.0, 0.1);
        p.step = Some(crate::problem::auto::Step {
            scale: 2.0,
            why: String::new(),
        });
        let q = ParamSpec::new("b.translate.x", 0.0, 0.1);
        let s = Smoothing::new(&[p, q], 60, 0.9);
        assert!((s.sigma0[0] - 0.2).abs() < 1e-12);
        assert!((s.sigma0[1] - SIGMA_FRACTION * 0.1 * 60.0 / CROSSING).abs() < 1e-12);
        assert!((s.sigma(2)[0] - 0.2 * 0.81).abs() < 1e-12);
    }
}
