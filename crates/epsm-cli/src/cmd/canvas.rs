//! Enlarged RGB8 pictures of match-resolution images with line overlays
//! (`epsm grad`, `epsm match`).

use epsm_core::inspect::Segment;
use epsm_render::Image;
use epsm_scene::image_io::linear_to_srgb;
use plotters::prelude::*;

/// An enlarged RGB8 canvas: each source pixel becomes a `scale × scale`
/// block, the longer side about 512 pixels.
pub struct Canvas {
    /// Width (canvas pixels).
    pub w: u32,
    /// Height (canvas pixels).
    pub h: u32,
    scale: u32,
    /// Row-major RGB8 bytes.
    pub rgb: Vec<u8>,
}

impl Canvas {
    /// A canvas of a `src_w × src_h` image whose pixel `(x, y)` has sRGB
    /// colour `colour(x, y)` (each channel in `[0, 1]`).
    pub fn new(src_w: u32, src_h: u32, colour: impl Fn(u32, u32) -> [f32; 3]) -> Self {
        let scale = (512 / src_w.max(src_h)).max(1);
        let (w, h) = (src_w * scale, src_h * scale);
        let mut rgb = vec![0u8; (w * h * 3) as usize];
        for y in 0..h {
            for x in 0..w {
                let c = colour(x / scale, y / scale);
                let i = ((y * w + x) * 3) as usize;
                for k in 0..3 {
                    rgb[i + k] = (c[k].clamp(0.0, 1.0) * 255.0 + 0.5) as u8;
                }
            }
        }
        Self { w, h, scale, rgb }
    }

    /// Draws `lines` (film pixels of the source image) in `colour`, each
    /// with a dot at its end.
    pub fn lines(&mut self, lines: &[Segment], colour: RGBColor) -> anyhow::Result<()> {
        let (w, h, scale) = (self.w, self.h, self.scale as f32);
        let px = |p: glam::Vec2| ((p.x * scale) as i32, (p.y * scale) as i32);
        let root = BitMapBackend::with_buffer(&mut self.rgb, (w, h)).into_drawing_area();
        for Segment { from: a, to: b } in lines {
            let e = |e: DrawingAreaErrorKind<_>| anyhow::anyhow!("drawing: {e}");
            root.draw(&PathElement::new(
                vec![px(*a), px(*b)],
                colour.stroke_width(1),
            ))
            .map_err(e)?;
            root.draw(&Circle::new(px(*b), 2, colour.filled()))
                .map_err(e)?;
        }
        root.present().map_err(|e| anyhow::anyhow!("drawing: {e}"))
    }
}

/// The sRGB colour of pixel `(x, y)` of the linear image `img`.
pub fn srgb(img: &Image, x: u32, y: u32) -> [f32; 3] {
    let c = img.get(x, y);
    [
        linear_to_srgb(c.x),
        linear_to_srgb(c.y),
        linear_to_srgb(c.z),
    ]
}
