//! Image losses and their per-pixel gradients (docs/design.md §5.7).
//!
//! Both losses compare a rendered image with the target at the match
//! resolution and return, per pixel, `g_rgb = ∂L/∂c` (linear colour) and
//! `g_xy = ∂L/∂p` (film pixels).
//!
//! - **OT** (Xing et al. 2022): every pixel becomes a 5-D point
//!   `P = (t(r), t(g), t(b), λ x, λ y)` with the tone map `t(c) = c / (1 + c)`
//!   (Reinhard, so already in `[0, 1)`, then clamped) and `x, y ∈ [0, 1]` the
//!   pixel centre over the image size. Rendered and target clouds are matched
//!   by epsm-ot's exact or entropic solver; `L = 1/n Σ ‖P_i − T_i‖²`.
//! - **L2**: `L = 1/(3n) Σ (c − c*)²` on linear colours, summed in `f64`
//!   (finite for all finite pixels); `g_xy = 0`.
//! - **Colour flow** (`flow = true`, [`add_flow`]): adds to each pixel's
//!   `g_xy` the derivative of the loss when the pixel's content moves
//!   (needed for camera moves, which shift the whole image).
//!
//! An OT loss also carries its matcher's guard counts ([`MatchGuards`]):
//! solves that fell back or stopped short but still returned a result, which
//! the run report counts per iteration.
//!
//! Both losses reject a NaN or infinite pixel of either image with
//! [`OptimizeError::NonFinitePixel`] naming the image, the pixel and the
//! channel.
//!
//! | key (`[loss]`) | unit | default | range |
//! |---|---|---|---|
//! | `kind` | — | `ot_exact` | `ot_exact`, `ot_sinkhorn`, `l2` |
//! | `lambda` | — | 1 | > 0 |
//! | `match_resolution` | pixels | `[64, 64]` | each in [4, 512]; OT: within `epsm_ot::MatchLimits` |
//! | `blur` | point units | 0.01 | ≥ 1e-4 (Sinkhorn only) |
//! | `flow` | — | `false` | `true`, `false` |

use epsm_ot::{MatchState, Matcher, SinkhornSettings, SolveStats};
use epsm_render::Image;
use glam::{DVec2, DVec3, Vec2, Vec3};
use serde::{Deserialize, Serialize};

use crate::run::{OptResult, OptimizeError};

mod flow;
mod image;
mod ot;
mod outliers;
#[cfg(test)]
mod tests;

pub use flow::add_flow;
pub use image::{resample, rmse};
pub use ot::{ImageMatch, match_images, matcher_named, points};
pub use outliers::{OUTLIER_RATIO, despeckle};

/// Which loss to use.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum LossKind {
    /// OT with the exact assignment solver.
    OtExact,
    /// OT with the entropic (Sinkhorn) solver of the given blur.
    OtSinkhorn {
        /// Blur, `ε = blur²`.
        blur: f64,
    },
    /// L2 on linear colours.
    L2,
}

impl LossKind {
    /// Whether the loss gives screen-position gradients.
    pub fn is_ot(self) -> bool {
        !matches!(self, LossKind::L2)
    }

    /// The matcher of an OT loss (`None` for L2).
    pub fn matcher(self) -> Option<Matcher> {
        match self {
            LossKind::L2 => None,
            LossKind::OtExact => Some(Matcher::exact()),
            LossKind::OtSinkhorn { blur } => Some(Matcher::Sinkhorn(SinkhornSettings {
                blur,
                ..SinkhornSettings::default()
            })),
        }
    }
}

/// The loss of one image, with its per-pixel gradients.
#[derive(Clone, Debug, PartialEq)]
pub struct LossEval {
    /// The loss value.
    pub value: f64,
    /// Image width (pixels).
    pub width: u32,
    /// Image height (pixels).
    pub height: u32,
    /// `∂L/∂c` per pixel (row-major), linear colour.
    pub g_rgb: Vec<Vec3>,
    /// `∂L/∂p` per pixel, film pixels.
    pub g_xy: Vec<DVec2>,
    /// For OT: the film position (pixels) each pixel is pulled toward.
    pub matched: Option<Vec<Vec2>>,
    /// The matcher's guard counts (all zero for L2).
    pub guards: MatchGuards,
}

/// How often one loss evaluation's matcher fell back or stopped short but
/// still returned a result: the guard counters of [`SolveStats`]. Each is a
/// count of events in one solve (the entropic solver's debiased loss is
/// three solves).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct MatchGuards {
    /// Entropic solves whose marginal error stayed above the tolerance.
    pub unconverged_solves: u64,
    /// Auctions stopped by their bid budget, prices used as reached (exact).
    pub auction_budget_stops: u64,
    /// Warm starts replaced by the cold start (exact).
    pub cold_starts: u64,
    /// Coarse corrections that converged only lumped, with bridges (entropic).
    pub bridged_corrections: u64,
    /// Coarse corrections applied clamped (entropic).
    pub clamped_corrections: u64,
}

impl MatchGuards {
    /// The `run.csv` column of each count, in the order of [`Self::counts`].
    pub const COLUMNS: [&'static str; 5] = [
        "ot_unconverged_solves",
        "ot_auction_budget_stops",
        "ot_cold_starts",
        "ot_bridged_corrections",
        "ot_clamped_corrections",
    ];

    /// The counts of a solve's statistics.
    pub fn of(stats: &SolveStats) -> Self {
        let count = |n: usize| n as u64;
        Self {
            unconverged_solves: count(stats.unconverged_solves),
            auction_budget_stops: count(stats.auction_budget_stops),
            cold_starts: count(stats.cold_starts),
            bridged_corrections: count(stats.bridged_corrections),
            clamped_corrections: count(stats.clamped_corrections),
        }
    }

    /// The counts, in the order of [`Self::COLUMNS`].
    pub fn counts(&self) -> [u64; 5] {
        [
            self.unconverged_solves,
            self.auction_budget_stops,
            self.cold_starts,
            self.bridged_corrections,
            self.clamped_corrections,
        ]
    }
}

/// The tone map of the OT points, `c / (1 + c)` clamped to `[0, 1]`
/// (negative colours map to 0).
///
/// A non-finite colour (NaN, ±∞) is not a colour: it maps to NaN, which
/// [`epsm_ot::PointCloud`] construction rejects, so [`points`] fails with
/// [`epsm_ot::OtError::NonFinite`] naming the point instead of matching it
/// as black ([`evaluate`] rejects such images before, by pixel).
pub fn tone_map(c: f32) -> f32 {
    if !c.is_finite() {
        return f32::NAN;
    }
    (c.max(0.0) / (1.0 + c.max(0.0))).clamp(0.0, 1.0)
}

fn tone_map_slope(c: f32) -> f32 {
    if c < 0.0 {
        0.0
    } else {
        1.0 / ((1.0 + c) * (1.0 + c))
    }
}

/// Evaluates `kind` between `image` and `target` (same size).
///
/// With `warm`, the exact OT loss starts from what the previous evaluation
/// left there and leaves its own ([`MatchState`]): the same optimal loss as
/// a cold solve, much faster along an optimization, the matching (and so the
/// gradient) different only where several matchings have the same cost. The
/// entropic loss always solves cold (a warm start was no faster on noisy
/// renders and would change its result within the marginal tolerance), and
/// L2 has no matching.
pub fn evaluate(
    kind: LossKind,
    image: &Image,
    target: &Image,
    lambda: f64,
    warm: Option<&mut MatchState>,
) -> OptResult<LossEval> {
    let Some(matcher) = kind.matcher() else {
        check_pair(image, target)?;
        return Ok(l2(image, target));
    };
    let warm = warm.filter(|_| kind == LossKind::OtExact);
    Ok(match_images(&matcher, image, target, lambda, warm)?.eval)
}

/// Fails unless `image` and `target` have the same size and finite pixels.
fn check_pair(image: &Image, target: &Image) -> OptResult<()> {
    if (image.width, image.height) != (target.width, target.height) {
        return Err(OptimizeError::Invalid(format!(
            "loss: image is {}x{} but the target is {}x{}",
            image.width, image.height, target.width, target.height
        )));
    }
    check_finite(image, "rendered image")?;
    check_finite(target, "target")
}

/// Fails with [`OptimizeError::NonFinitePixel`] on the first NaN or infinite
/// channel of `image` (named `which` in the error).
fn check_finite(image: &Image, which: &'static str) -> OptResult<()> {
    for (i, c) in image.pixels.iter().enumerate() {
        for (channel, value) in ["r", "g", "b"].into_iter().zip(c.to_array()) {
            if !value.is_finite() {
                let i = i as u32;
                return Err(OptimizeError::NonFinitePixel {
                    image: which,
                    x: i % image.width,
                    y: i / image.width,
                    channel,
                    value,
                });
            }
        }
    }
    Ok(())
}

/// The colour difference `c − c*` of two pixels, in `f64`.
///
/// Its square is finite for all finite `f32` pixels: in `f32`, differences
/// above about 1.8e19 squared to infinity (an L2 loss of +∞ for pixels 1e20
/// and −1e20).
fn difference(c: Vec3, t: Vec3) -> DVec3 {
    c.as_dvec3() - t.as_dvec3()
}

/// `L = 1/(3n) Σ ‖c − c*‖²` and `∂L/∂c = 2 (c − c*) / (3n)`, computed in `f64`.
///
/// The loss is finite for all finite pixels; a gradient entry above
/// `f32::MAX` (only possible for n = 1 and `|c − c*|` above 5e38) rounds
/// to infinity in the `f32` `g_rgb`.
fn l2(image: &Image, target: &Image) -> LossEval {
    let n = image.pixels.len() as f64;
    let mut value = 0.0f64;
    let g_rgb = image
        .pixels
        .iter()
        .zip(&target.pixels)
        .map(|(c, t)| {
            let d = difference(*c, *t);
            value += d.length_squared();
            (2.0 * d / (3.0 * n)).as_vec3()
        })
        .collect();
    LossEval {
        value: value / (3.0 * n),
        width: image.width,
        height: image.height,
        g_rgb,
        g_xy: vec![DVec2::ZERO; image.pixels.len()],
        matched: None,
        guards: MatchGuards::default(),
    }
}
