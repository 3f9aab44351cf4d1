//! Conversions from epsm images and per-pixel values to egui textures:
//! linear RGB to sRGB bytes for the renders, and the shared colour codes
//! of [`epsm_core::inspect`] for the signed maps and the flow.

use eframe::egui::{self, Color32, ColorImage, TextureHandle, TextureOptions};
use epsm_core::inspect::{flow_colour, signed_colour};
use epsm_render::Image;
use epsm_scene::image_io::linear_to_srgb;
use glam::DVec2;

fn byte(v: f32) -> u8 {
    (v.clamp(0.0, 1.0) * 255.0 + 0.5) as u8
}

fn size(width: u32, height: u32) -> [usize; 2] {
    [width as usize, height as usize]
}

/// A linear-RGB image as an opaque sRGB texture.
pub fn srgb_image(img: &Image) -> ColorImage {
    let pixels = img
        .pixels
        .iter()
        .map(|c| {
            Color32::from_rgb(
                byte(linear_to_srgb(c.x)),
                byte(linear_to_srgb(c.y)),
                byte(linear_to_srgb(c.z)),
            )
        })
        .collect();
    ColorImage::new(size(img.width, img.height), pixels)
}

/// Values in `[−1, 1]` as a signed heat map; `alpha` makes zero transparent
/// (for drawing over an image) instead of white.
pub fn signed_map(values: &[f32], width: u32, height: u32, alpha: bool) -> ColorImage {
    let pixels = values
        .iter()
        .map(|v| {
            let [r, g, b] = signed_colour(*v);
            if alpha {
                let a = byte(v.abs().sqrt() * 0.85);
                Color32::from_rgba_unmultiplied(byte(r), byte(g), byte(b), a)
            } else {
                Color32::from_rgb(byte(r), byte(g), byte(b))
            }
        })
        .collect();
    ColorImage::new(size(width, height), pixels)
}

/// The motion field as a translucent flow-coloured texture (transparent
/// where nothing moves).
pub fn flow_map(field: &[DVec2], width: u32, height: u32) -> ColorImage {
    let max = field.iter().map(|d| d.length()).fold(0.0, f64::max);
    let pixels = field
        .iter()
        .map(|d| {
            let [r, g, b] = flow_colour(*d, max);
            let a = if *d == DVec2::ZERO { 0 } else { 180 };
            Color32::from_rgba_unmultiplied(byte(r), byte(g), byte(b), a)
        })
        .collect();
    ColorImage::new(size(width, height), pixels)
}

/// Uploads `image` as a texture named `name` (nearest filtering: pixels stay sharp).
pub fn upload(ctx: &egui::Context, name: &str, image: ColorImage) -> TextureHandle {
    ctx.load_texture(name, image, TextureOptions::NEAREST)
}
