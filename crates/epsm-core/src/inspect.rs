//! Inspection functions shared by `epsm grad` and `epsm-viewer`: what one
//! gradient pass looks like per pixel, and the colour codes both draw it
//! with. Nothing here feeds the optimization.
//!
//! - [`path_kind_counts`]: how many differentiable paths of each
//!   [`PathKind`] a pixel's records hold (the paths that move with some
//!   parameter, as [`crate::backprop`] sees them);
//! - [`matching_lines`]: the OT matching as segments from a render pixel's
//!   centre to the film position it is pulled toward (subsampled);
//! - [`motion_arrows`]: a motion field ([`crate::field::motion_field`]) as a
//!   grid of arrows;
//! - [`flow_colour`] and [`signed_colour`]: the flow (hue = direction,
//!   brightness = magnitude) and signed heat-map (red = positive, blue =
//!   negative, white = zero) colour codes;
//! - [`normalized_luminance`]: a signed image's luminance scaled into
//!   `[−1, 1]` for [`signed_colour`];
//! - [`fd_step`]: the finite-difference step used for `dI/dθ` images.
//!
//! Positions are film pixels at the resolution of the image they belong to
//! (pixel `(0, 0)` top-left, `y` down, centres at `+0.5`).

use epsm_render::Scene;
use epsm_render::record::PathRecord;
use glam::{DVec2, Vec2, Vec3};
use rayon::prelude::*;

use crate::backprop::luminance;
use crate::loss::LossEval;
use crate::params::ParamTable;
use crate::paths::{PathKind, classify};
use crate::run::Optimization;
use crate::solve::SolveSettings;

/// Differentiable paths of one pixel per [`PathKind`] (index = `kind as usize`).
pub type KindCounts = [u32; PathKind::ALL.len()];

/// A line segment in film pixels.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Segment {
    /// Start (film pixels).
    pub from: Vec2,
    /// End (film pixels).
    pub to: Vec2,
}

/// Per pixel (row-major at `scene`'s camera resolution), the number of
/// differentiable paths of each kind that `records` classify into at the
/// table's current θ. Pixels whose records touch no driven object count
/// zero everywhere.
pub fn path_kind_counts(
    scene: &Scene,
    table: &ParamTable,
    records: &[PathRecord],
) -> Vec<KindCounts> {
    let cam = scene.camera();
    let motion = table.motion(&table.values());
    let settings = SolveSettings::for_radius(scene.radius());
    let per_record: Vec<(usize, KindCounts)> = records
        .par_iter()
        .map(|r| {
            let mut counts = KindCounts::default();
            for path in classify(r, scene, &motion, &settings).paths {
                counts[path.kind as usize] += 1;
            }
            ((r.pixel.y * cam.width + r.pixel.x) as usize, counts)
        })
        .collect();
    let n = (cam.width * cam.height) as usize;
    let mut out = vec![KindCounts::default(); n];
    for (px, counts) in per_record {
        if let Some(o) = out.get_mut(px) {
            for (a, b) in o.iter_mut().zip(counts) {
                *a += b;
            }
        }
    }
    out
}

/// The OT matching of `loss` as segments from every `every`-th pixel centre
/// to its matched film position, leaving out pixels that move less than
/// `min_length` pixels; empty for L2.
pub fn matching_lines(loss: &LossEval, every: usize, min_length: f32) -> Vec<Segment> {
    let Some(matched) = &loss.matched else {
        return Vec::new();
    };
    let w = loss.width.max(1);
    matched
        .iter()
        .enumerate()
        .step_by(every.max(1))
        .map(|(i, t)| Segment {
            from: Vec2::new((i as u32 % w) as f32 + 0.5, (i as u32 / w) as f32 + 0.5),
            to: *t,
        })
        .filter(|s| s.from.distance(s.to) > min_length)
        .collect()
}

/// Arrows of the motion field `field` (row-major, `width × height`) from
/// the centres of every `spacing`-th pixel in both directions, scaled so
/// that the longest vector of the whole field spans `spacing` pixels;
/// pixels that do not move get no arrow.
pub fn motion_arrows(field: &[DVec2], width: u32, height: u32, spacing: u32) -> Vec<Segment> {
    let step = spacing.max(1);
    let max = field.iter().map(|d| d.length()).fold(0.0, f64::max);
    if max <= 0.0 {
        return Vec::new();
    }
    (0..height)
        .step_by(step as usize)
        .flat_map(|y| (0..width).step_by(step as usize).map(move |x| (x, y)))
        .filter_map(|(x, y)| {
            let d = *field.get((y * width + x) as usize)?;
            let from = Vec2::new(x as f32 + 0.5, y as f32 + 0.5);
            (d != DVec2::ZERO).then(|| Segment {
                from,
                to: from + (d / max * f64::from(step)).as_vec2(),
            })
        })
        .collect()
}

/// The flow colour (display RGB in `[0, 1]`) of motion `d`:
/// hue from its direction, value `sqrt(|d| / max)`; black when `d` or
/// `max` is zero.
pub fn flow_colour(d: DVec2, max: f64) -> [f32; 3] {
    if max <= 0.0 || d == DVec2::ZERO {
        return [0.0; 3];
    }
    let hue = (d.y.atan2(d.x) / std::f64::consts::TAU).rem_euclid(1.0) as f32 * 6.0;
    let v = (d.length() / max).min(1.0).sqrt() as f32;
    let f = hue.fract();
    let (a, b) = (v * (1.0 - f), v * f);
    match hue as u32 {
        0 => [v, b, 0.0],
        1 => [a, v, 0.0],
        2 => [0.0, v, b],
        3 => [0.0, a, v],
        4 => [b, 0.0, v],
        _ => [v, 0.0, a],
    }
}

/// The signed heat-map colour (display RGB in `[0, 1]`) of `v` in `[−1, 1]`
/// (clamped): white at 0, toward red for positive and blue for negative.
pub fn signed_colour(v: f32) -> [f32; 3] {
    let v = v.clamp(-1.0, 1.0);
    if v >= 0.0 {
        [1.0, 1.0 - v, 1.0 - v]
    } else {
        [1.0 + v, 1.0 + v, 1.0]
    }
}

/// The luminance of each of `pixels` (linear RGB, e.g. a `dI/dθ` image or a
/// difference of images) over the largest absolute luminance, so in
/// `[−1, 1]` with the sign kept; all zero when every pixel is zero.
pub fn normalized_luminance(pixels: &[Vec3]) -> Vec<f32> {
    let lum: Vec<f32> = pixels.iter().map(|c| luminance(*c)).collect();
    let peak = lum.iter().fold(0.0f32, |m, v| m.max(v.abs()));
    if peak > 0.0 {
        lum.iter().map(|v| v / peak).collect()
    } else {
        lum
    }
}

/// The central-difference step (user units) for `dI/dθ` of parameter
/// `param` of `opt`: 1% of its distance to the true value (at least 1e-3),
/// or 1e-2 when the true value is unknown.
pub fn fd_step(opt: &Optimization, param: usize) -> f64 {
    let scale = opt
        .problem()
        .params
        .get(param)
        .and_then(|p| p.true_value)
        .zip(opt.theta().get(param))
        .map_or(1.0, |(t, x)| (x - t).abs().max(1e-3));
    1e-2 * scale
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::loss::MatchGuards;

    #[test]
    fn arrows_scale_to_the_spacing_and_skip_still_pixels() {
        let mut field = vec![DVec2::ZERO; 16];
        field[0] = DVec2::new(2.0, 0.0);
        field[2] = DVec2::new(0.0, -1.0);
        let arrows = motion_arrows(&field, 4, 4, 2);
        assert_eq!(arrows.len(), 2);
        assert!((arrows[0].to - arrows[0].from - Vec2::new(2.0, 0.0)).length() < 1e-6);
        assert!((arrows[1].to - arrows[1].from - Vec2::new(0.0, -1.0)).length() < 1e-6);
        assert!(motion_arrows(&[DVec2::ZERO; 16], 4, 4, 1).is_empty());
    }

    #[test]
    fn matching_lines_subsample_and_drop_short_moves() {
        let loss = LossEval {
            value: 0.0,
            width: 2,
            height: 2,
            g_rgb: Vec::new(),
            g_xy: Vec::new(),
            matched: Some(vec![
                Vec2::new(1.5, 1.5),
                Vec2::new(1.5, 0.6),
                Vec2::new(0.5, 1.5),
                Vec2::new(0.0, 0.0),
            ]),
            guards: MatchGuards::default(),
        };
        let all = matching_lines(&loss, 1, 0.5);
        assert_eq!(all.len(), 2, "pixels 1 and 2 barely move");
        assert_eq!(all[0].from, Vec2::new(0.5, 0.5));
        assert_eq!(matching_lines(&loss, 3, 0.5).len(), 2, "pixels 0 and 3");
        assert!(
            matching_lines(
                &LossEval {
                    matched: None,
                    ..loss
                },
                1,
                0.0
            )
            .is_empty()
        );
    }

    #[test]
    fn colour_codes_are_signed_and_directional() {
        assert_eq!(signed_colour(0.0), [1.0; 3]);
        assert_eq!(signed_colour(1.0), [1.0, 0.0, 0.0]);
        assert_eq!(signed_colour(-2.0), [0.0, 0.0, 1.0]);
        assert_eq!(flow_colour(DVec2::new(1.0, 0.0), 1.0), [1.0, 0.0, 0.0]);
        assert_eq!(flow_colour(DVec2::ZERO, 1.0), [0.0; 3]);
        let left = flow_colour(DVec2::new(-1.0, 0.0), 1.0);
        assert!(left[2] > 0.9 && left[0] < 0.1, "{left:?}");
        let n = normalized_luminance(&[Vec3::splat(-2.0), Vec3::splat(1.0), Vec3::ZERO]);
        assert_eq!(n, vec![-1.0, 0.5, 0.0]);
    }
}
