//! Linear RGB images.

use glam::Vec3;

/// A linear-RGB image, row-major, row 0 at the top (see the crate's image-plane
/// convention).
#[derive(Clone, Debug, PartialEq)]
pub struct Image {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// `width × height` pixels, row-major.
    pub pixels: Vec<Vec3>,
}

impl Image {
    /// A black image.
    pub fn new(width: u32, height: u32) -> Self {
        Self {
            width,
            height,
            pixels: vec![Vec3::ZERO; width as usize * height as usize],
        }
    }

    /// The pixel at column `x`, row `y`.
    #[inline]
    pub fn get(&self, x: u32, y: u32) -> Vec3 {
        self.pixels[y as usize * self.width as usize + x as usize]
    }

    /// Sets the pixel at column `x`, row `y`.
    #[inline]
    pub fn set(&mut self, x: u32, y: u32, v: Vec3) {
        let w = self.width as usize;
        self.pixels[y as usize * w + x as usize] = v;
    }

    /// Mean of all pixels.
    pub fn mean(&self) -> Vec3 {
        let sum: glam::DVec3 = self.pixels.iter().map(|p| p.as_dvec3()).sum();
        (sum / self.pixels.len().max(1) as f64).as_vec3()
    }

    /// Texture lookup at `uv` in `[0, 1]²` (`v = 0` at the bottom row, as OBJ
    /// and glTF-after-flip use), bilinear, wrapping.
    pub fn lookup(&self, uv: glam::Vec2) -> Vec3 {
        let (w, h) = (self.width as i64, self.height as i64);
        let x = uv.x * w as f32 - 0.5;
        let y = (1.0 - uv.y) * h as f32 - 0.5;
        let (x0, y0) = (x.floor(), y.floor());
        let (fx, fy) = (x - x0, y - y0);
        let px = |xi: i64, yi: i64| {
            let xi = xi.rem_euclid(w) as u32;
            let yi = yi.rem_euclid(h) as u32;
            self.get(xi, yi)
        };
        let (x0, y0) = (x0 as i64, y0 as i64);
        let top = px(x0, y0) * (1.0 - fx) + px(x0 + 1, y0) * fx;
        let bottom = px(x0, y0 + 1) * (1.0 - fx) + px(x0 + 1, y0 + 1) * fx;
        top * (1.0 - fy) + bottom * fy
    }
}
