//! Reading and writing linear-RGB [`Image`]s.
//!
//! | format | read | write |
//! |---|---|---|
//! | `.png` | 8- or 16-bit, decoded from sRGB to linear; alpha ignored | 8-bit RGB, values clamped to [0, 1] (+∞ → 1, −∞ → 0) and sRGB-encoded; NaN → 0 |
//! | `.exr` | first RGB(A) layer, linear; alpha ignored | 32-bit float RGB, exact (non-finite values kept); RLE tiles of 64², written in increasing order so the bytes depend only on the pixels |
//!
//! The format is chosen by the (case-insensitive) extension; anything else is
//! an error. A read image has at most [`MAX_IMAGE_PIXELS`] pixels: an EXR
//! declaring more is rejected from its header, before anything is allocated
//! (PNG decoding has the `image` crate's memory limit). Writes are atomic
//! ([`crate::atomic_file`]): a reader never sees a half-written file and a
//! failed write leaves nothing behind.
//! sRGB transfer functions follow IEC 61966-2-1.

use std::fs::File;
use std::io::{Seek, Write};
use std::path::Path;

use glam::Vec3;
use image::ImageEncoder;

use crate::atomic_file::write_atomic;
use crate::error::{Error, Result, io_error};
use epsm_render::film::Image;

/// Most pixels of an image read by [`read_image`] (16384 × 8192).
pub const MAX_IMAGE_PIXELS: usize = 1 << 27;

/// The image formats this module reads and writes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Format {
    Png,
    Exr,
}

fn format_of(path: &Path) -> Result<Format> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    match ext.as_deref() {
        Some("png") => Ok(Format::Png),
        Some("exr") => Ok(Format::Exr),
        _ => Err(image_error(
            path,
            "unsupported image format: expected .png or .exr",
        )),
    }
}

fn image_error(path: &Path, message: impl std::fmt::Display) -> Error {
    Error::Image {
        path: path.to_owned(),
        message: message.to_string(),
    }
}

/// Whether `path`'s extension names a format this module reads and writes.
pub fn is_supported(path: &Path) -> bool {
    format_of(path).is_ok()
}

/// Reads a PNG (sRGB → linear) or EXR (linear) file as linear RGB.
pub fn read_image(path: &Path) -> Result<Image> {
    let file = crate::input_file::open(path)?;
    match format_of(path)? {
        Format::Png => read_png(path, file),
        Format::Exr => read_exr(path, file),
    }
}

/// Checks that every channel of every pixel of `img`, read from `path`, is
/// finite and in `[0, max]` (`max` may be infinite); the error names the
/// first pixel that is not.
pub fn check_values(path: &Path, img: &Image, max: f32) -> Result<()> {
    let bad = img.pixels.iter().enumerate().find_map(|(i, p)| {
        p.to_array()
            .into_iter()
            .zip(["r", "g", "b"])
            .find(|(v, _)| !(v.is_finite() && (0.0..=max).contains(v)))
            .map(|(v, channel)| (i, channel, v))
    });
    let Some((i, channel, v)) = bad else {
        return Ok(());
    };
    let (x, y) = (i % img.width as usize, i / img.width as usize);
    let range = if max.is_finite() {
        format!("finite values in [0, {max}]")
    } else {
        "finite values >= 0".to_owned()
    };
    let msg = format!("pixel ({x}, {y}) has {channel} = {v}; expected {range}");
    Err(image_error(path, msg))
}

/// Writes `img` as PNG (sRGB, 8-bit, clamped) or EXR (32-bit float RGB),
/// chosen by `path`'s extension, atomically. The directory must exist.
pub fn write_image(path: &Path, img: &Image) -> Result<()> {
    let format = format_of(path)?;
    if img.pixels.len() != img.width as usize * img.height as usize || img.pixels.is_empty() {
        return Err(image_error(
            path,
            "image has no pixels or a wrong pixel count",
        ));
    }
    write_atomic(path, io_error(path), |out| match format {
        Format::Png => write_png(path, img, out),
        Format::Exr => write_exr(path, img, out),
    })
}

/// sRGB-encoded value in [0, 1] → linear.
pub fn srgb_to_linear(v: f32) -> f32 {
    if v <= 0.04045 {
        v / 12.92
    } else {
        ((v + 0.055) / 1.055).powf(2.4)
    }
}

/// Linear value → sRGB-encoded, clamped to [0, 1] first: +∞ encodes as
/// 1 (white) and −∞ as 0, like any value beyond the range; NaN, which has
/// no place in it, encodes as 0 (black).
pub fn linear_to_srgb(v: f32) -> f32 {
    let v = if v.is_nan() { 0.0 } else { v.clamp(0.0, 1.0) };
    if v <= 0.0031308 {
        v * 12.92
    } else {
        1.055 * v.powf(1.0 / 2.4) - 0.055
    }
}

fn read_png(path: &Path, file: File) -> Result<Image> {
    let decoded = image::load(std::io::BufReader::new(file), image::ImageFormat::Png)
        .map_err(|e| image_error(path, e))?
        .into_rgb32f();
    let (width, height) = decoded.dimensions();
    let pixels = decoded
        .pixels()
        .map(|p| Vec3::from_array(p.0.map(srgb_to_linear)))
        .collect();
    Ok(Image {
        width,
        height,
        pixels,
    })
}

/// Writes 8-bit pixels as a PNG at `path`, atomically (the folder must
/// exist): `width × height` pixels of layout `color` (for example `Rgb8` or
/// `Rgba8`, rows top first) in `bytes`, which must hold exactly that many.
/// For images made for viewing (plots, screenshots); renders go through
/// [`write_image`].
pub fn write_png_bytes(
    path: &Path,
    width: u32,
    height: u32,
    color: image::ExtendedColorType,
    bytes: &[u8],
) -> Result<()> {
    let expected = u64::from(width) * u64::from(height) * u64::from(color.bits_per_pixel() / 8);
    if bytes.len() as u64 != expected || expected == 0 {
        let msg = format!(
            "{width}x{height} pixels of {color:?} need {expected} bytes, got {}",
            bytes.len()
        );
        return Err(image_error(path, msg));
    }
    write_atomic(path, io_error(path), |out| {
        encode_png(path, width, height, color, bytes, out)
    })
}

fn write_png(path: &Path, img: &Image, out: impl Write) -> Result<()> {
    let bytes: Vec<u8> = img
        .pixels
        .iter()
        .flat_map(|p| p.to_array())
        .map(|v| (linear_to_srgb(v) * 255.0).round() as u8)
        .collect();
    encode_png(
        path,
        img.width,
        img.height,
        image::ExtendedColorType::Rgb8,
        &bytes,
        out,
    )
}

/// PNG-encodes `bytes` (their length checked by the caller) into `out`.
fn encode_png(
    path: &Path,
    width: u32,
    height: u32,
    color: image::ExtendedColorType,
    bytes: &[u8],
    out: impl Write,
) -> Result<()> {
    image::codecs::png::PngEncoder::new(out)
        .write_image(bytes, width, height, color)
        .map_err(|e| image_error(path, e))
}

fn read_exr(path: &Path, mut file: File) -> Result<Image> {
    use exr::prelude::{ReadChannels, ReadLayers};
    let meta = exr::meta::MetaData::read_from_unbuffered(&file, false)
        .map_err(|e| image_error(path, e))?;
    for header in &meta.headers {
        let (w, h) = (header.layer_size.width(), header.layer_size.height());
        if w.checked_mul(h).is_none_or(|n| n > MAX_IMAGE_PIXELS) {
            let msg = format!("declares a {w}x{h} layer, more than {MAX_IMAGE_PIXELS} pixels");
            return Err(image_error(path, msg));
        }
    }
    file.rewind().map_err(io_error(path))?;
    let read = exr::prelude::read()
        .no_deep_data()
        .largest_resolution_level()
        .rgba_channels(
            |size, _| Image::new(size.width() as u32, size.height() as u32),
            |img: &mut Image, pos: exr::math::Vec2<usize>, (r, g, b, _a): (f32, f32, f32, f32)| {
                img.set(pos.x() as u32, pos.y() as u32, Vec3::new(r, g, b));
            },
        )
        .first_valid_layer()
        .all_attributes()
        .from_unbuffered(file)
        .map_err(|e| image_error(path, e))?;
    Ok(read.layer_data.channel_data.pixels)
}

fn write_exr(path: &Path, img: &Image, mut out: impl Write + Seek) -> Result<()> {
    use exr::prelude::WritableImage;
    let size = (img.width as usize, img.height as usize);
    let channels = exr::image::SpecificChannels::rgb(|pos: exr::math::Vec2<usize>| {
        let p = img.get(pos.x() as u32, pos.y() as u32);
        (p.x, p.y, p.z)
    });
    // The exr crate compresses blocks on several threads; with its default
    // unspecified line order it writes them as they finish, so the same
    // image could give different files. Increasing order sorts them.
    let encoding = exr::image::Encoding {
        line_order: exr::meta::attribute::LineOrder::Increasing,
        ..exr::image::Encoding::FAST_LOSSLESS
    };
    exr::image::Image::from_encoded_channels(size, encoding, channels)
        .write()
        .to_buffered(&mut out)
        .map_err(|e| image_error(path, e))?;
    out.flush().map_err(io_error(path))
}

#[cfg(test)]
mod tests;
