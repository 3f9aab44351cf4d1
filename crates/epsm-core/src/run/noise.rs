//! The automatic `render.spp_match`: the samples per pixel of the image the
//! loss compares, from the noise measured when a run starts.
//!
//! Matching a noisy image to a clean target is biased, and the bias falls
//! with the matched image's variance (`docs/suite.md`, "Glass box"). Two
//! renders of the initial scene at the match resolution with
//! [`PROBE_SPP`] samples and different seeds give the per-pixel variance
//! of one sample, `σ² = s · mean((a − b)²) / 2` over pixels and channels of
//! the tone-mapped colours (the OT's colours). The predicted noise of an
//! `n`-sample image, `σ² / n`, is compared with the target's signal, the
//! variance of its tone-mapped colours over the pixels: the matched render
//! takes the fewest samples (a power of two) whose noise is at most
//! [`NOISE_FRACTION`] of the signal, at most [`MAX_SPP`]. When the
//! gradient pass's own samples already meet it, the loss compares the
//! gradient pass's image (no extra render).

use epsm_render::{Image, Scene};

use super::render_image;
use crate::loss::tone_map;

/// Samples per pixel of each of the two probe renders.
pub const PROBE_SPP: u32 = 4;

/// The matched image's predicted noise may be at most this fraction of the
/// target's signal.
pub const NOISE_FRACTION: f64 = 0.02;

/// The most samples per pixel the automatic matched render takes.
pub const MAX_SPP: u32 = 256;

/// The noise of a scene's render against its target's signal.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Noise {
    /// Variance of one sample's tone-mapped colour, mean over pixels and
    /// channels.
    pub per_sample: f64,
    /// Variance of the target's tone-mapped colours over its pixels, mean
    /// over channels.
    pub signal: f64,
}

impl Noise {
    /// Measures the noise of `scene` (at the match resolution) with two
    /// renders seeded `seeds`, against `target` (the same resolution).
    pub fn measure(scene: &Scene, target: &Image, seeds: [u32; 2]) -> Self {
        let a = render_image(scene, PROBE_SPP, seeds[0]);
        let b = render_image(scene, PROBE_SPP, seeds[1]);
        let n = (3 * a.pixels.len().max(1)) as f64;
        let tone = |c: f32| f64::from(tone_map(c));
        let mut diff = 0.0;
        for (p, q) in a.pixels.iter().zip(&b.pixels) {
            for k in 0..3 {
                diff += (tone(p[k]) - tone(q[k])).powi(2);
            }
        }
        let mut mean = [0.0; 3];
        for c in &target.pixels {
            for (k, m) in mean.iter_mut().enumerate() {
                *m += tone(c[k]);
            }
        }
        let count = target.pixels.len().max(1) as f64;
        mean.iter_mut().for_each(|m| *m /= count);
        let mut signal = 0.0;
        for c in &target.pixels {
            for (k, m) in mean.iter().enumerate() {
                signal += (tone(c[k]) - m).powi(2);
            }
        }
        Self {
            per_sample: f64::from(PROBE_SPP) * diff / (2.0 * n),
            signal: signal / (3.0 * count),
        }
    }

    /// The samples per pixel of an image whose predicted noise is at most
    /// [`NOISE_FRACTION`] of the signal (unrounded).
    pub fn needed_spp(&self) -> f64 {
        self.per_sample / (NOISE_FRACTION * self.signal.max(1e-12))
    }

    /// The matched render's samples per pixel for a gradient pass of
    /// `spp_grad` samples: 0 when the gradient pass meets the bound,
    /// else the power of two that does, in `[spp_grad, MAX_SPP]`.
    pub fn spp_match(&self, spp_grad: u32) -> u32 {
        let need = self.needed_spp();
        if need <= f64::from(spp_grad) {
            return 0;
        }
        let pow2 = need.min(f64::from(MAX_SPP)).log2().ceil().exp2() as u32;
        pow2.clamp(spp_grad, MAX_SPP)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_matched_samples_grow_with_the_noise_and_stop_at_the_cap() {
        let quiet = Noise {
            per_sample: 0.001,
            signal: 0.05,
        };
        assert_eq!(quiet.spp_match(4), 0, "{}", quiet.needed_spp());
        let noisy = Noise {
            per_sample: 0.05,
            signal: 0.05,
        };
        assert_eq!(noisy.spp_match(4), 64);
        assert_eq!(noisy.spp_match(128), 0);
        let very = Noise {
            per_sample: 1.0,
            signal: 0.01,
        };
        assert_eq!(very.spp_match(4), MAX_SPP);
    }
}
