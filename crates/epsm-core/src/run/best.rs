//! The best θ of a run, judged on an independent render.
//!
//! Every [`Judge::every`] iterations, and at the final θ, the scene is
//! rendered twice at the match resolution, each with half of [`Judge::spp`]
//! samples per pixel and a seed of its own that does not change from one
//! evaluation to the next (common random numbers: two θ are compared under
//! the same noise). Its loss is the mean product of the two renders'
//! tone-mapped differences from the target ([`judged_loss`]): unlike the
//! squared difference of one render, whose expectation adds the render's
//! variance, and so prefers a θ that renders with less noise (a dimmer
//! light, a rougher lobe), its expectation is the squared difference of
//! the expected image. The θ with the lowest is kept ([`Best`]), reported
//! beside the last and used for the final images.

use epsm_render::Image;
use serde::{Deserialize, Serialize};

use super::{Optimization, render_image, stream_seed};
use crate::loss::tone_map;

/// The lowest judged loss so far and where it was met.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Best {
    /// The iteration whose θ it is (the iteration count for the final θ
    /// and for a tail mean).
    pub iteration: u32,
    /// How many iterates' mean θ is ([`tail_mean`]); 0 for one iterate.
    #[serde(default)]
    pub averaged: u32,
    /// θ (user units).
    pub theta: Vec<f64>,
    /// Its judged loss.
    pub loss: f64,
}

/// How θ is judged.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Judge {
    /// Samples per pixel of the judged render.
    pub spp: u32,
    /// Evaluate every this many iterations (and at the final θ).
    pub every: u32,
}

impl Judge {
    /// Fewest samples per pixel of the judged render.
    pub const MIN_SPP: u32 = 16;
    /// Most samples per pixel of the judged render.
    pub const MAX_SPP: u32 = 64;

    /// The judge of a run of `iterations` whose matched image has
    /// `spp_match` samples (0: the gradient pass's `spp_grad`): at least
    /// as many samples as the matched image, within
    /// `[MIN_SPP, MAX_SPP]`, about twenty evaluations per run.
    pub fn new(iterations: u32, spp_match: u32, spp_grad: u32) -> Self {
        Self {
            spp: spp_match.max(spp_grad).clamp(Self::MIN_SPP, Self::MAX_SPP),
            every: (iterations / 20).max(1),
        }
    }

    /// Whether the θ of `iteration` is judged (`done`: it is the final θ).
    pub fn judges(&self, iteration: u32, done: bool) -> bool {
        done || iteration.is_multiple_of(self.every)
    }
}

/// Mean over pixels and channels of `(a − t)(b − t)` for the tone-mapped
/// colours of two independent renders `a`, `b` of the same θ and of the
/// `target` `t`: an unbiased estimate of the squared difference between
/// the expected tone-mapped render and the target (it can be slightly
/// negative at the optimum). All three images have the same size.
pub fn judged_loss(a: &Image, b: &Image, target: &Image) -> f64 {
    mean_loss(&judged_pixels(a, b, target))
}

/// The judged loss ([`judged_loss`]) of per-pixel sums ([`judged_pixels`]).
fn mean_loss(pixels: &[f64]) -> f64 {
    pixels.iter().sum::<f64>() / (3 * pixels.len().max(1)) as f64
}

/// [`judged_loss`] pixel by pixel: the sum over the three channels of
/// `(a − t)(b − t)`, row-major.
pub fn judged_pixels(a: &Image, b: &Image, target: &Image) -> Vec<f64> {
    a.pixels
        .iter()
        .zip(&b.pixels)
        .zip(&target.pixels)
        .map(|((a, b), t)| {
            (0..3)
                .map(|k| {
                    let t = tone_map(t[k]);
                    f64::from(tone_map(a[k]) - t) * f64::from(tone_map(b[k]) - t)
                })
                .sum::<f64>()
        })
        .collect()
}

/// Standard errors by which one θ's judged loss must undercut another's to
/// count as lower ([`clearly_lower`]).
pub const SIGNIFICANCE: f64 = 2.0;

/// Whether the per-pixel judged losses `lower` ([`judged_pixels`]) are
/// lower than `other` (the same pixels, judged under the same noise)
/// beyond the judge's noise: their mean paired difference exceeds
/// [`SIGNIFICANCE`] standard errors of the per-pixel differences.
pub fn clearly_lower(lower: &[f64], other: &[f64]) -> bool {
    let d: Vec<f64> = other.iter().zip(lower).map(|(o, l)| o - l).collect();
    if d.len() < 2 {
        return false;
    }
    let n = d.len() as f64;
    let mean = d.iter().sum::<f64>() / n;
    let var = d.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0);
    mean > SIGNIFICANCE * (var / n).sqrt()
}

impl Best {
    /// Keeps `theta` of `iteration` when its `loss` is lower than the best
    /// so far (`best` is `None` before the first evaluation); returns
    /// whether it did.
    pub fn offer(best: &mut Option<Best>, iteration: u32, theta: &[f64], loss: f64) -> bool {
        if best.as_ref().is_some_and(|b| b.loss <= loss) {
            return false;
        }
        *best = Some(Best {
            iteration,
            averaged: 0,
            theta: theta.to_vec(),
            loss,
        });
        true
    }
}

/// The mean of `iterates` (each a θ), when there are at least
/// [`MIN_TAIL`] of them. In the last iterations Adam's steps scatter θ
/// about the optimum by the gradient's noise (an albedo by ±3 % on the
/// material problem); the mean of the scatter lies closer to it.
pub fn tail_mean(iterates: &[&[f64]]) -> Option<Vec<f64>> {
    let first = iterates.first()?;
    if iterates.len() < MIN_TAIL {
        return None;
    }
    let n = iterates.len() as f64;
    Some(
        (0..first.len())
            .map(|k| iterates.iter().map(|t| t[k]).sum::<f64>() / n)
            .collect(),
    )
}

/// Fewest iterates a tail mean averages.
pub const MIN_TAIL: usize = 4;

/// Salt of the judged render's stream (the same at every iteration).
const JUDGE_SALT: u32 = 0x0B35_7E11;

/// The final comparison of the best θ with the tail mean takes this many
/// times the judge's samples.
const FINAL_JUDGE_FACTOR: u32 = 4;

impl Optimization {
    /// The judged loss of the current θ.
    pub(super) fn judged(&self) -> f64 {
        self.judged_at(self.judge.spp)
    }

    /// The judged loss of the current θ with `spp` samples in all.
    fn judged_at(&self, spp: u32) -> f64 {
        mean_loss(&self.judged_pixels_at(spp))
    }

    /// The per-pixel judged losses ([`judged_pixels`]) of the current θ
    /// with `spp` samples in all.
    fn judged_pixels_at(&self, spp: u32) -> Vec<f64> {
        let spp = (spp / 2).max(1);
        let [a, b] = [JUDGE_SALT, JUDGE_SALT ^ 1].map(|salt| {
            let seed = stream_seed(self.problem.optimizer.seed, 0, salt);
            render_image(&self.grad.scene, spp, seed)
        });
        judged_pixels(&a, &b, &self.target_match)
    }

    /// Compares the mean θ of the L2 phase's last iterations ([`tail_mean`])
    /// with the best θ so far under a finer judge ([`FINAL_JUDGE_FACTOR`]
    /// times the samples: near the optimum the two differ by less than the
    /// regular judge's noise). θ is left at the final iterate.
    ///
    /// Without a late phase ([`crate::problem::auto::late_samples`]) the
    /// mean spans at most the last quarter of the run (the final θ
    /// included) and the lower judged loss wins. With one, the mean spans
    /// the late phase and is the result unless the best θ's judged loss is
    /// lower beyond the judge's noise ([`clearly_lower`]): there the
    /// iterates scatter about the optimum by less than the judge resolves,
    /// and a single iterate the judge prefers is as often off by the
    /// judge's own noise.
    pub(super) fn offer_tail_mean(&mut self) {
        let late = self.problem.passes.late;
        let quarter = self.schedule.iterations.div_ceil(4);
        let from = late.map_or_else(|| self.iteration.saturating_sub(quarter), |l| l.from);
        let from = self.schedule.switch().max(from);
        let iterates: Vec<&[f64]> = (self.rows.iter())
            .filter(|r| r.iteration >= from)
            .map(|r| r.theta.as_slice())
            .chain([self.theta.as_slice()])
            .collect();
        let averaged = iterates.len() as u32;
        let Some(mean) = tail_mean(&iterates) else {
            return;
        };
        let last = self.theta.clone();
        let fine = self.judge.spp * FINAL_JUDGE_FACTOR;
        let mut best_pixels = None;
        if let Some(b) = self.best.clone() {
            self.set_theta(&b.theta);
            let pixels = self.judged_pixels_at(fine);
            self.best = Some(Best {
                loss: mean_loss(&pixels),
                ..b
            });
            best_pixels = Some(pixels);
        }
        self.set_theta(&mean);
        let pixels = self.judged_pixels_at(fine);
        let loss = mean_loss(&pixels);
        let kept = match (late, &best_pixels) {
            (Some(_), Some(best)) => !clearly_lower(best, &pixels),
            _ => self.best.as_ref().is_none_or(|b| loss < b.loss),
        };
        if kept {
            self.best = Some(Best {
                iteration: self.iteration,
                averaged,
                theta: self.theta.clone(),
                loss,
            });
        }
        self.set_theta(&last);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    #[test]
    fn the_best_keeps_the_lowest_loss_and_the_judge_its_rhythm() {
        let mut best = None;
        assert!(Best::offer(&mut best, 0, &[1.0], 0.5));
        assert!(Best::offer(&mut best, 2, &[0.5], 0.2));
        assert!(!Best::offer(&mut best, 4, &[0.7], 0.3));
        let b = best.expect("kept");
        assert_eq!((b.iteration, b.theta[0]), (2, 0.5));
        let j = Judge::new(40, 128, 4);
        assert_eq!((j.spp, j.every), (Judge::MAX_SPP, 2));
        assert!(j.judges(4, false) && !j.judges(5, false) && j.judges(5, true));
        assert_eq!(Judge::new(10, 0, 4).spp, Judge::MIN_SPP);
    }

    #[test]
    fn the_tail_mean_averages_each_parameter() {
        let a = [1.0, 4.0];
        let b = [3.0, 0.0];
        assert_eq!(tail_mean(&[&a, &b, &a, &b]), Some(vec![2.0, 2.0]));
        assert_eq!(tail_mean(&[&a, &b, &a]), None);
        assert_eq!(tail_mean(&[]), None);
    }

    #[test]
    fn a_lower_loss_counts_only_beyond_the_judges_noise() {
        // Pixel differences of mean 1 and spread ±1 over 100 pixels: the
        // standard error is 0.1, so the mean difference is 10 of them.
        let other: Vec<f64> = (0..100).map(|i| 5.0 + f64::from(i % 2)).collect();
        let lower: Vec<f64> = (0..100)
            .map(|i| 4.0 + 2.0 * f64::from(i % 2) - 0.5)
            .collect();
        assert!(clearly_lower(&lower, &other));
        assert!(!clearly_lower(&other, &lower));
        // The same mean difference under noise twenty times wider is not
        // resolved.
        let noisy: Vec<f64> = (0..100)
            .map(|i| other[i as usize] - 1.0 + if i % 2 == 0 { 20.0 } else { -20.0 })
            .collect();
        assert!(!clearly_lower(&noisy, &other));
        assert!(!clearly_lower(&[1.0], &[2.0]));
    }

    #[test]
    fn the_judged_loss_compares_tone_mapped_colours() {
        let mut a = Image::new(2, 1);
        let t = Image::new(2, 1);
        assert_eq!(judged_loss(&a, &a, &t), 0.0);
        a.pixels[0] = Vec3::splat(1.0);
        // tone_map(1) = 0.5 in 3 of 6 channels: the squared difference.
        assert!((judged_loss(&a, &a, &t) - 0.25 * 3.0 / 6.0).abs() < 1e-9);
        // Two renders scattered to either side of the target: their noise
        // cancels, where one render's squared difference counts it.
        let mut b = Image::new(2, 1);
        b.pixels[0] = Vec3::splat(1.0);
        let mut t = Image::new(2, 1);
        t.pixels[0] = Vec3::splat(1.0 / 3.0);
        a.pixels[0] = Vec3::ZERO;
        assert!((judged_loss(&a, &b, &t) + 0.0625 * 3.0 / 6.0).abs() < 1e-6);
        assert!(judged_loss(&a, &a, &t) > 0.0);
    }
}
