//! The colour-flow term of the OT loss ([`add_flow`]).

use epsm_render::Image;

use glam::{DVec2, Vec3};

use super::LossEval;
use crate::run::{OptResult, OptimizeError};

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
