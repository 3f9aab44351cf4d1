//! Whole-image measures: RMSE, and box resampling to another resolution.

use epsm_render::Image;
use glam::{DVec3, Vec3};

use super::difference;

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
