//! Images between NumPy and epsm: `(H, W, 3)` linear-RGB arrays and
//! [`epsm_render::Image`], and `read_image` / `write_image` (EXR linear
//! float, PNG sRGB 8-bit), the files the CLI reads and writes.

use std::path::PathBuf;

use epsm_render::Image;
use glam::Vec3;
use numpy::ndarray::Array3;
use numpy::{IntoPyArray, PyArray3, PyReadonlyArray3, PyUntypedArrayMethods};
use pyo3::prelude::*;

use crate::error::{invalid, to_py};

/// `img` as a `float32` array `(H, W, 3)`.
pub fn to_array<'py>(py: Python<'py>, img: &Image) -> Bound<'py, PyArray3<f32>> {
    per_pixel(
        py,
        img.width,
        img.height,
        img.pixels.iter().map(|p| p.to_array()),
    )
}

/// Rows of `N` values per pixel as an array `(H, W, N)`.
pub fn per_pixel<'py, T: numpy::Element, const N: usize>(
    py: Python<'py>,
    width: u32,
    height: u32,
    values: impl IntoIterator<Item = [T; N]>,
) -> Bound<'py, PyArray3<T>> {
    let flat: Vec<T> = values.into_iter().flatten().collect();
    let shape = (height as usize, width as usize, N);
    match Array3::from_shape_vec(shape, flat) {
        Ok(a) => a.into_pyarray(py),
        Err(_) => PyArray3::zeros(py, [0, 0, N], false),
    }
}

/// The array `array` (`(H, W, 3)`, `float32` or `float64`, linear RGB) as an
/// image; `what` names the argument in errors.
pub fn from_array(array: &Bound<'_, PyAny>, what: &str) -> PyResult<Image> {
    let values: Vec<f32>;
    let shape: [usize; 3];
    if let Ok(a) = array.extract::<PyReadonlyArray3<'_, f32>>() {
        shape = dims(a.shape());
        values = a.as_array().iter().copied().collect();
    } else if let Ok(a) = array.extract::<PyReadonlyArray3<'_, f64>>() {
        shape = dims(a.shape());
        values = a.as_array().iter().map(|&v| v as f32).collect();
    } else {
        return Err(invalid(
            what,
            "expected a float32 or float64 array of shape (H, W, 3)",
        ));
    }
    let [h, w, c] = shape;
    if c != 3 || h == 0 || w == 0 {
        return Err(invalid(
            what,
            format!("expected shape (H, W, 3) with H, W >= 1, found ({h}, {w}, {c})"),
        ));
    }
    let (Ok(width), Ok(height)) = (u32::try_from(w), u32::try_from(h)) else {
        return Err(invalid(what, format!("{w}x{h} pixels is too large")));
    };
    let pixels = values.chunks_exact(3).map(Vec3::from_slice).collect();
    Ok(Image {
        width,
        height,
        pixels,
    })
}

fn dims(shape: &[usize]) -> [usize; 3] {
    [0, 1, 2].map(|i| shape.get(i).copied().unwrap_or(0))
}

/// read_image(path) -> numpy.ndarray
///
/// Reads an EXR (linear) or PNG (sRGB, converted to linear) file as a
/// float32 array (H, W, 3) in linear RGB.
#[pyfunction]
pub fn read_image<'py>(py: Python<'py>, path: PathBuf) -> PyResult<Bound<'py, PyArray3<f32>>> {
    let img = py
        .detach(|| epsm_scene::image_io::read_image(&path))
        .map_err(to_py)?;
    Ok(to_array(py, &img))
}

/// write_image(path, image) -> None
///
/// Writes a linear-RGB array (H, W, 3) as EXR (float, exact) or PNG (sRGB,
/// 8-bit), by the file's extension.
#[pyfunction]
pub fn write_image(py: Python<'_>, path: PathBuf, image: &Bound<'_, PyAny>) -> PyResult<()> {
    let img = from_array(image, "image")?;
    py.detach(|| epsm_scene::image_io::write_image(&path, &img))
        .map_err(to_py)
}
