//! Textures: a colour that is constant or looked up in an image.
//!
//! | key | unit | default | range |
//! |---|---|---|---|
//! | constant colour | linear RGB | — | per channel ≥ 0 |
//! | image | sRGB PNG or linear EXR file | — | any size ≥ 1×1 |
//!
//! Images are sampled bilinearly with wrapping ([`Image::lookup`]), `v = 0` at
//! the bottom row.
//!
//! ```toml
//! albedo = [0.8, 0.8, 0.8]        # constant
//! # albedo = "textures/wood.png"  # image
//! ```

use std::sync::Arc;

use glam::Vec3;

use crate::film::Image;
use crate::hit::TexCoords;

/// A colour that is constant or looked up in an image by texture coordinates.
#[derive(Clone, Debug, PartialEq)]
pub enum Texture {
    /// The same linear RGB everywhere.
    Constant(Vec3),
    /// A linear-RGB image (decoded from sRGB PNG or linear EXR), bilinear, wrapping.
    Image(Arc<Image>),
}

impl Texture {
    /// The linear-RGB value at texture coordinates `uv` (evaluated only
    /// for an image).
    #[inline]
    pub fn eval(&self, uv: impl Into<TexCoords>) -> Vec3 {
        match self {
            Texture::Constant(c) => *c,
            Texture::Image(image) => image.lookup(uv.into().get()),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec2;

    #[test]
    fn constant_texture_ignores_uv_and_image_texture_reads_pixels() {
        let c = Texture::Constant(Vec3::new(0.1, 0.2, 0.3));
        assert_eq!(c.eval(Vec2::new(0.7, 0.2)), Vec3::new(0.1, 0.2, 0.3));
        let mut image = Image::new(2, 1);
        image.set(0, 0, Vec3::X);
        image.set(1, 0, Vec3::Y);
        let t = Texture::Image(Arc::new(image));
        // Pixel centres: u = 0.25 (left, X) and u = 0.75 (right, Y).
        assert!(t.eval(Vec2::new(0.25, 0.5)).distance(Vec3::X) < 1e-6);
        assert!(t.eval(Vec2::new(0.75, 0.5)).distance(Vec3::Y) < 1e-6);
    }
}
