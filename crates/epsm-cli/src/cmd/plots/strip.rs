//! The image strip below a figure's panels: where each image goes, fitted
//! into a `THUMB` square, and its copy into the figure's pixels (sRGB,
//! nearest neighbour).

use epsm_render::Image;
use epsm_scene::image_io::linear_to_srgb;

use super::{GAP, THUMB, Thumb};

/// Where an image of the strip goes in the figure, pixels.
pub(super) struct Placed {
    /// Left column.
    pub x: u32,
    /// Top row.
    pub y: u32,
    /// Width.
    pub w: u32,
    /// Height.
    pub h: u32,
}

/// Places the strip's images left to right, centred in a figure of width
/// `fig_w`, each fitted into a `THUMB` square at row `top`.
pub(super) fn place_strip(strip: &[Thumb], fig_w: u32, top: u32) -> Vec<Placed> {
    let used = (strip.len() as u32 * (THUMB + GAP)).saturating_sub(GAP);
    let left = fig_w.saturating_sub(used) / 2;
    strip
        .iter()
        .enumerate()
        .map(|(i, t)| {
            let (iw, ih) = (t.image.width.max(1), t.image.height.max(1));
            let scale = f64::from(THUMB) / f64::from(iw.max(ih));
            let w = ((f64::from(iw) * scale).round() as u32).clamp(1, THUMB);
            let h = ((f64::from(ih) * scale).round() as u32).clamp(1, THUMB);
            Placed {
                x: left + i as u32 * (THUMB + GAP) + (THUMB - w) / 2,
                y: top + (THUMB - h),
                w,
                h,
            }
        })
        .collect()
}

/// Copies `img`, sRGB-encoded and scaled by nearest neighbour, into the RGB8
/// buffer `buf` of width `buf_w` at `at`.
pub(super) fn blit(buf: &mut [u8], buf_w: u32, img: &Image, at: &Placed) {
    if img.width == 0 || img.height == 0 {
        return;
    }
    for dy in 0..at.h {
        let sy = (u64::from(dy) * u64::from(img.height) / u64::from(at.h)) as u32;
        for dx in 0..at.w {
            let sx = (u64::from(dx) * u64::from(img.width) / u64::from(at.w)) as u32;
            let c = img.get(sx, sy);
            let i = (((at.y + dy) * buf_w + at.x + dx) * 3) as usize;
            if let Some(px) = buf.get_mut(i..i + 3) {
                for (p, v) in px.iter_mut().zip([c.x, c.y, c.z]) {
                    *p = (linear_to_srgb(v) * 255.0).round() as u8;
                }
            }
        }
    }
}
