//! The OT loss: images as RGBXY point clouds, matched by epsm-ot.

use epsm_ot::{MatchState, Matcher, OtResult, PointCloud};
use epsm_render::Image;
use glam::{DVec2, Vec2, Vec3};

use super::{LossEval, LossKind, MatchGuards, check_pair, tone_map, tone_map_slope};
use crate::run::{OptResult, OptimizeError};

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
