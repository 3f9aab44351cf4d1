//! Per-pixel gradient images for one parameter, as `epsm grad` and a viewer
//! draw them: the screen-space motion field `dp/dθ` (forward manifold
//! solves) and the image derivative `dI/dθ` (central difference of renders
//! with common random numbers, so it includes visibility changes).

use epsm_render::record::PathRecord;
use epsm_render::tracer::{RenderOptions, render};
use epsm_render::{Image, Scene};
use glam::DVec2;
use rayon::prelude::*;

use crate::backprop::luminance;
use crate::params::ParamTable;
use crate::paths::classify;
use crate::solve::{SolveSettings, solve_forward};

/// The luminance-weighted mean `dp/dθ` (pixels per user unit) of each
/// pixel's differentiable paths for parameter `param`, row-major at the
/// scene camera's resolution; zero where no path moves with `param`.
pub fn motion_field(
    scene: &Scene,
    table: &ParamTable,
    records: &[PathRecord],
    param: usize,
) -> Vec<DVec2> {
    let cam = scene.camera();
    let motion = table.motion(&table.values());
    let settings = SolveSettings::for_radius(scene.radius());
    let per_record: Vec<(usize, DVec2, f64)> = records
        .par_iter()
        .map(|r| {
            let px = (r.pixel.y * cam.width + r.pixel.x) as usize;
            let (mut sum, mut weight) = (DVec2::ZERO, 0.0);
            for path in classify(r, scene, &motion, &settings)
                .paths
                .iter()
                .filter(|p| p.params.contains(&param))
            {
                let w = f64::from(luminance(path.contribution).abs());
                if let Ok(j) = solve_forward(path, &motion, &settings)
                    && let Some(k) = j.params.iter().position(|&p| p == param)
                {
                    sum += w * j.columns[k];
                    weight += w;
                }
            }
            (px, sum, weight)
        })
        .collect();
    let n = (cam.width * cam.height) as usize;
    let (mut field, mut weights) = (vec![DVec2::ZERO; n], vec![0.0; n]);
    for (px, s, w) in per_record {
        if px < n {
            field[px] += s;
            weights[px] += w;
        }
    }
    for (f, w) in field.iter_mut().zip(weights) {
        if w > 0.0 {
            *f /= w;
        }
    }
    field
}

/// `dI/dθ` of `param` by a central difference of step `h` (user units) of
/// renders of `scene` at `spp` with the same random numbers; `table` must be
/// the table of `scene` and is restored afterwards.
pub fn image_derivative(
    scene: &mut Scene,
    table: &mut ParamTable,
    param: usize,
    h: f64,
    spp: u32,
) -> Image {
    let v = table.values().get(param).copied().unwrap_or(0.0);
    let opts = RenderOptions {
        spp,
        ..RenderOptions::from_scene(scene)
    };
    let mut at = |x: f64| {
        table.set_value(param, x);
        table.apply(scene);
        render(scene, &opts, &|_| {}).image
    };
    let (plus, minus) = (at(v + h), at(v - h));
    at(v);
    let mut out = plus.clone();
    for (o, m) in out.pixels.iter_mut().zip(&minus.pixels) {
        *o = (*o - *m) / (2.0 * h as f32);
    }
    out
}
