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

use epsm_ot::{MatchState, Matcher, OtResult, PointCloud, SinkhornSettings, SolveStats};
use epsm_render::Image;
use glam::{DVec2, DVec3, Vec2, Vec3};
use serde::{Deserialize, Serialize};

use crate::run::{OptResult, OptimizeError};

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
/// [`PointCloud`] construction rejects, so [`points`] fails with
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

/// The OT points of `image` (tone-mapped colour, λ-scaled pixel centres).
pub fn points(image: &Image, lambda: f32) -> OptResult<PointCloud> {
    let (w, h) = (image.width as f32, image.height as f32);
    let mut rgb = Vec::with_capacity(image.pixels.len());
    let mut xy = Vec::with_capacity(image.pixels.len());
    for (i, c) in image.pixels.iter().enumerate() {
        let (x, y) = (
            (i as u32 % image.width) as f32,
            (i as u32 / image.width) as f32,
        );
        rgb.push([tone_map(c.x), tone_map(c.y), tone_map(c.z)]);
        xy.push([(x + 0.5) / w, (y + 0.5) / h]);
    }
    Ok(PointCloud::from_rgb_xy(&rgb, &xy, lambda)?)
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

/// The matcher named `solver` (`exact` or `sinkhorn`, the latter with
/// `blur`, `ε = blur²`, at least [`epsm_ot::MIN_BLUR`]), as `epsm match`
/// and the Python `match` name it.
pub fn matcher_named(solver: &str, blur: f64) -> OptResult<Matcher> {
    let kind = match solver {
        "exact" => LossKind::OtExact,
        "sinkhorn" if blur >= epsm_ot::MIN_BLUR => LossKind::OtSinkhorn { blur },
        "sinkhorn" => {
            return Err(OptimizeError::Invalid(format!(
                "blur: expected a number >= {:e}, found {blur}",
                epsm_ot::MIN_BLUR
            )));
        }
        other => {
            return Err(OptimizeError::Invalid(format!(
                "solver: unknown solver `{other}`; expected exact or sinkhorn"
            )));
        }
    };
    kind.matcher()
        .ok_or_else(|| OptimizeError::Invalid(format!("solver: `{solver}` is not OT")))
}

/// The OT matching of two images: the loss with its per-pixel gradients
/// and the solver's own result.
#[derive(Clone, Debug)]
pub struct ImageMatch {
    /// Loss and per-pixel gradients (linear colour, film pixels).
    pub eval: LossEval,
    /// The solve: per-point gradients in point units, the assignment or the
    /// plan's barycentric targets, statistics.
    pub result: OtResult,
}

/// Matches the OT points ([`points`], weight `lambda > 0` of position
/// against colour) of `image` to those of `target` (same size, finite
/// pixels) with `matcher`, warm-started from `warm` when given (which then
/// keeps what this solve leaves). Sizes are not checked against
/// [`epsm_ot::MatchLimits`]: callers that take sizes from users do that
/// ([`epsm_ot::Matcher::check_size`]).
pub fn match_images(
    matcher: &Matcher,
    image: &Image,
    target: &Image,
    lambda: f64,
    warm: Option<&mut MatchState>,
) -> OptResult<ImageMatch> {
    check_pair(image, target)?;
    if !(lambda > 0.0 && lambda.is_finite()) {
        return Err(OptimizeError::Invalid(format!(
            "lambda: expected a positive number, found {lambda}"
        )));
    }
    let n = image.pixels.len();
    let lambda32 = lambda as f32;
    let source = points(image, lambda32)?;
    let target_points = points(target, lambda32)?;
    let result = match warm {
        Some(state) => matcher.solve_warm(&source, &target_points, state)?,
        None => matcher.solve(&source, &target_points)?,
    };
    let (w, h) = (f64::from(image.width), f64::from(image.height));
    let mut g_rgb = Vec::with_capacity(n);
    let mut g_xy = Vec::with_capacity(n);
    let mut matched = Vec::with_capacity(n);
    for (i, (g, c)) in result.gradient.iter().zip(&image.pixels).enumerate() {
        g_rgb.push(Vec3::new(
            g[0] * tone_map_slope(c.x),
            g[1] * tone_map_slope(c.y),
            g[2] * tone_map_slope(c.z),
        ));
        g_xy.push(DVec2::new(
            f64::from(g[3]) * lambda / w,
            f64::from(g[4]) * lambda / h,
        ));
        let t = result.target(source.point(i), i);
        matched.push(Vec2::new(
            t[3] / lambda32 * w as f32,
            t[4] / lambda32 * h as f32,
        ));
    }
    let eval = LossEval {
        value: result.loss,
        width: image.width,
        height: image.height,
        g_rgb,
        g_xy,
        matched: Some(matched),
        guards: MatchGuards::of(&result.stats),
    };
    Ok(ImageMatch { eval, result })
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

/// Adds the colour-flow term to `eval.g_xy`: per pixel `−(∂c/∂p)ᵀ g_rgb`,
/// what the loss gains when the pixel's content moves by `δp` (the colour
/// at the fixed pixel then changes by `−∂c/∂p · δp`), with `∂c/∂p` (linear
/// colour per film pixel) from central differences of the pixel's
/// neighbours in `image` (one-sided at the border).
///
/// The OT's own `g_xy` sum to zero over the image (both clouds are the same
/// pixel grid and every point is matched once), so a parameter that moves
/// the whole image uniformly (a camera yaw or translation) gets no gradient
/// from them, only from how unevenly it moves the pixels; this term is the
/// derivative of the loss at fixed pixel positions and gives such moves
/// their gradient. It is a finite difference of a noisy render, so problems
/// whose effect is small and bright (highlights) are better without it.
pub fn add_flow(image: &Image, eval: &mut LossEval) -> OptResult<()> {
    let (w, h) = (image.width, image.height);
    if (w, h) != (eval.width, eval.height) {
        return Err(OptimizeError::Invalid(format!(
            "colour flow: image is {w}x{h} but the loss is {}x{}",
            eval.width, eval.height
        )));
    }
    let (g_rgb, g_xy) = (&eval.g_rgb, &mut eval.g_xy);
    let diff = |a: Vec3, b: Vec3, span: u32| (a - b) / span as f32;
    for y in 0..h {
        for x in 0..w {
            let (x0, x1) = (x.saturating_sub(1), (x + 1).min(w - 1));
            let (y0, y1) = (y.saturating_sub(1), (y + 1).min(h - 1));
            let dx = diff(image.get(x1, y), image.get(x0, y), (x1 - x0).max(1));
            let dy = diff(image.get(x, y1), image.get(x, y0), (y1 - y0).max(1));
            let i = (y * w + x) as usize;
            let g = g_rgb[i];
            g_xy[i] -= DVec2::new(f64::from(dx.dot(g)), f64::from(dy.dot(g)));
        }
    }
    Ok(())
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

/// Root-mean-square difference of two images over pixels and channels
/// (`NaN` when their sizes differ).
pub fn rmse(a: &Image, b: &Image) -> f64 {
    if (a.width, a.height) != (b.width, b.height) || a.pixels.is_empty() {
        return f64::NAN;
    }
    let sum: f64 = a
        .pixels
        .iter()
        .zip(&b.pixels)
        .map(|(x, y)| difference(*x, *y).length_squared())
        .sum();
    (sum / (3.0 * a.pixels.len() as f64)).sqrt()
}

/// `image` box-filtered down (or sampled up) to `width × height`.
///
/// Each output pixel is the mean of its box, summed in `f32`; where that
/// sum overflows, the mean is taken in `f64` instead, so finite pixels give
/// a finite mean (and non-finite ones stay non-finite, for the loss's
/// check to report).
pub fn resample(image: &Image, width: u32, height: u32) -> Image {
    let mut out = Image::new(width, height);
    for y in 0..height {
        for x in 0..width {
            let x0 = x * image.width / width;
            let x1 = ((x + 1) * image.width / width).max(x0 + 1);
            let y0 = y * image.height / height;
            let y1 = ((y + 1) * image.height / height).max(y0 + 1);
            let pixels = || (y0..y1).flat_map(move |yy| (x0..x1).map(move |xx| image.get(xx, yy)));
            let count = (x1 - x0) * (y1 - y0);
            let mean = pixels().sum::<Vec3>() / count as f32;
            let mean = if mean.is_finite() {
                mean
            } else {
                let sum: DVec3 = pixels().map(Vec3::as_dvec3).sum();
                (sum / f64::from(count)).as_vec3()
            };
            out.set(x, y, mean);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn dot(w: u32, h: u32, at: (u32, u32)) -> Image {
        let mut img = Image::new(w, h);
        img.set(at.0, at.1, Vec3::splat(4.0));
        img
    }

    #[test]
    fn ot_pulls_a_bright_pixel_toward_the_target_one() {
        let (img, target) = (dot(8, 8, (1, 4)), dot(8, 8, (6, 4)));
        let e = evaluate(LossKind::OtExact, &img, &target, 1.0, None).expect("loss");
        let i = 4 * 8 + 1;
        // Moving the bright pixel right (+x) lowers the loss.
        assert!(e.g_xy[i].x < 0.0, "g_xy = {:?}", e.g_xy[i]);
        assert!(e.g_xy[i].y.abs() < 1e-6);
        let m = e.matched.expect("matching")[i];
        assert!(
            (m.x - 6.5).abs() < 1e-3 && (m.y - 4.5).abs() < 1e-3,
            "{m:?}"
        );
        assert!(e.value > 0.0);
    }

    #[test]
    fn l2_gradient_matches_a_finite_difference() {
        let (img, target) = (dot(4, 4, (1, 1)), dot(4, 4, (2, 2)));
        let e = evaluate(LossKind::L2, &img, &target, 1.0, None).expect("loss");
        let h = 1e-2;
        let at = |d: f32| {
            let mut bumped = img.clone();
            bumped.pixels[5].x += d;
            evaluate(LossKind::L2, &bumped, &target, 1.0, None)
                .expect("loss")
                .value
        };
        let fd = (at(h) - at(-h)) / f64::from(2.0 * h);
        assert!((fd - f64::from(e.g_rgb[5].x)).abs() < 1e-3 * fd.abs().max(1e-3));
        assert!((rmse(&img, &img)).abs() < 1e-12);
    }

    /// A smooth blob centred at `cx` (pixels) on a dim background.
    fn blob(cx: f32) -> Image {
        let mut img = Image::new(16, 16);
        for y in 0..16 {
            for x in 0..16 {
                let d2 = (x as f32 + 0.5 - cx).powi(2) + (y as f32 + 0.5 - 8.0).powi(2);
                img.set(
                    x,
                    y,
                    Vec3::new(0.1, 0.1, 0.1) + Vec3::new(3.0, 2.0, 1.0) * (-d2 / 8.0).exp(),
                );
            }
        }
        img
    }

    #[test]
    fn colour_flow_gives_a_uniform_shift_its_finite_difference() {
        // The render is the target shifted right by `s` pixels: every pixel's
        // content moves with dp/ds = (1, 0), so dL/ds = Σ g_xy.x.
        let (target, s, h) = (blob(8.0), 1.5f32, 0.02f32);
        let at = |shift: f32| {
            evaluate(LossKind::OtExact, &blob(8.0 + shift), &target, 1.0, None).expect("loss")
        };
        let fd = (at(s + h).value - at(s - h).value) / f64::from(2.0 * h);
        let mut e = at(s);
        let ot_sum: f64 = e.g_xy.iter().map(|g| g.x).sum();
        let ot_abs: f64 = e.g_xy.iter().map(|g| g.x.abs()).sum();
        // The OT's own screen gradients cancel: blind to a uniform shift.
        assert!(ot_sum.abs() < 1e-4 * ot_abs, "{ot_sum} of {ot_abs}");
        add_flow(&blob(8.0 + s), &mut e).expect("same size");
        let flow_sum: f64 = e.g_xy.iter().map(|g| g.x).sum();
        assert!(fd > 0.0, "moving the blob away raises the loss: {fd}");
        assert!(
            (flow_sum - fd).abs() < 0.1 * fd,
            "flow {flow_sum} vs fd {fd}"
        );
        assert!(add_flow(&Image::new(3, 3), &mut e).is_err());
    }

    #[test]
    fn a_warm_exact_loss_equals_the_cold_one_along_a_moving_blob() {
        let target = blob(8.0);
        let mut state = MatchState::new();
        for step in 0..4 {
            let image = blob(5.0 + 0.3 * step as f32);
            let cold = evaluate(LossKind::OtExact, &image, &target, 1.0, None).expect("loss");
            let warm =
                evaluate(LossKind::OtExact, &image, &target, 1.0, Some(&mut state)).expect("loss");
            assert!(!state.is_empty(), "step {step}: the state is kept");
            assert!(
                (warm.value - cold.value).abs() <= 1e-12 * cold.value,
                "step {step}: {} vs {}",
                warm.value,
                cold.value
            );
            // The gradients sum alike (a different matching among ties moves no total).
            let sum = |e: &LossEval| e.g_xy.iter().map(|g| g.x).sum::<f64>();
            assert!((sum(&warm) - sum(&cold)).abs() < 1e-6, "step {step}");
        }
        // L2 leaves the state alone.
        evaluate(LossKind::L2, &target, &target, 1.0, Some(&mut state)).expect("loss");
        assert!(!state.is_empty());
    }

    #[test]
    fn a_non_finite_pixel_fails_every_loss_naming_the_pixel() {
        // OT: instead of matching it as black; L2: instead of a NaN loss.
        for bad in [f32::NAN, f32::INFINITY, f32::NEG_INFINITY] {
            assert!(tone_map(bad).is_nan(), "{bad}");
            let mut img = dot(4, 4, (1, 1));
            img.set(2, 3, Vec3::new(0.5, bad, 0.5));
            let dot2 = dot(4, 4, (2, 2));
            for (image, target, which) in [(&img, &dot2, "rendered image"), (&dot2, &img, "target")]
            {
                for kind in [LossKind::OtExact, LossKind::L2] {
                    let e = evaluate(kind, image, target, 1.0, None);
                    assert!(
                        matches!(
                            e,
                            Err(OptimizeError::NonFinitePixel {
                                image,
                                x: 2,
                                y: 3,
                                channel: "g",
                                ..
                            }) if image == which
                        ),
                        "{kind:?} {bad}: {e:?}"
                    );
                }
            }
            // The OT points alone still refuse it, by point.
            assert!(matches!(
                points(&img, 1.0),
                Err(OptimizeError::Ot(epsm_ot::OtError::NonFinite {
                    index: 14,
                    axis: "g",
                    ..
                }))
            ));
        }
        assert_eq!(
            (tone_map(-1.0), tone_map(1.0), tone_map(f32::MAX)),
            (0.0, 0.5, 1.0)
        );
    }

    #[test]
    fn l2_of_huge_finite_pixels_is_finite_and_exact() {
        // One pixel 1e20 against −1e20 in every channel of a 2x1 image (the
        // other pixel equal): d = 2e20, L = 3 d² / (3 · 2) = 2e40 and
        // ∂L/∂c = 2 d / (3 · 2) = 2e20 / 3. In f32 d² overflowed: L = +∞.
        let (mut img, mut target) = (Image::new(2, 1), Image::new(2, 1));
        img.set(0, 0, Vec3::splat(1e20));
        target.set(0, 0, Vec3::splat(-1e20));
        let e = evaluate(LossKind::L2, &img, &target, 1.0, None).expect("loss");
        let d = 2.0 * f64::from(1e20f32);
        assert!((e.value / (d * d / 2.0) - 1.0).abs() < 1e-15, "{}", e.value);
        assert!((e.value / 2e40 - 1.0).abs() < 1e-6);
        for g in e.g_rgb[0].to_array() {
            assert_eq!(g, (d / 3.0) as f32);
        }
        assert_eq!(e.g_rgb[1], Vec3::ZERO);
        let r = rmse(&img, &target);
        assert!((r / (d / 2f64.sqrt()) - 1.0).abs() < 1e-15, "{r}");
        // The extremes of f32: still finite.
        img.set(0, 0, Vec3::splat(f32::MAX));
        target.set(0, 0, Vec3::splat(-f32::MAX));
        let e = evaluate(LossKind::L2, &img, &target, 1.0, None).expect("loss");
        assert!(e.value.is_finite() && e.g_rgb[0].is_finite() && rmse(&img, &target).is_finite());
    }

    #[test]
    fn mismatched_sizes_are_an_error() {
        assert!(
            evaluate(
                LossKind::L2,
                &Image::new(2, 2),
                &Image::new(3, 2),
                1.0,
                None
            )
            .is_err()
        );
        assert_eq!(resample(&dot(4, 4, (0, 0)), 2, 2).get(0, 0), Vec3::ONE);
    }

    #[test]
    fn resample_averages_huge_finite_pixels_without_overflow() {
        // Two huge finite pixels: their f32 sum overflows, their mean does not.
        let mut huge = Image::new(2, 1);
        huge.set(0, 0, Vec3::splat(3e38));
        huge.set(1, 0, Vec3::new(3e38, 1e38, -3e38));
        assert_eq!(resample(&huge, 1, 1).get(0, 0), Vec3::new(3e38, 2e38, 0.0));
        // A non-finite pixel stays non-finite, for evaluate to report.
        huge.set(1, 0, Vec3::new(f32::NAN, 1.0, 1.0));
        assert!(resample(&huge, 1, 1).get(0, 0).x.is_nan());
    }
}
