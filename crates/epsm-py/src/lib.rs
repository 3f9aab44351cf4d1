//! The Python module `epsm`: a thin layer over `epsm-core`, `epsm-render`
//! and `epsm-ot` (no mathematics of its own).
//!
//! - [`scene`] — `load_scene`, `Scene.render/set/get`;
//! - [`problem`] — `load_problem`, `Problem(scene, params, target, ...)`;
//! - [`optimization`] — `Optimization.step/gradient/loss/theta/checkpoint/restore`;
//! - [`field`] — `motion_field`; [`matching`] — `match`;
//! - [`image`] — `read_image`, `write_image` and the array conversions;
//! - [`error`] — `EpsmError`, carrying the file, line, field and message.
//!
//! ## Conventions
//! - Images are NumPy arrays `(H, W, 3)`, linear RGB, row 0 at the top;
//!   renders come back as `float32`, inputs may be `float32` or `float64`.
//! - Parameter values and gradients are in user units (`docs/problem-format.md`:
//!   scene units, degrees, factors), keyed by the problem files' keys.
//! - Screen positions and motion are in film pixels, `x` right, `y` down.
//! - The GIL is released while rendering, solving and matching: Python
//!   threads run meanwhile and rayon's workers never wait on it.
//! - Nothing is global: every object owns its state, problems and scenes
//!   pickle (to their files and settings), so worker processes (Ray,
//!   multiprocessing) rebuild them.

pub mod error;
pub mod field;
pub mod image;
pub mod matching;
pub mod optimization;
pub mod problem;
pub mod scene;

use pyo3::prelude::*;

/// epsm: a CPU differentiable renderer (extended path space manifolds and
/// an optimal-transport loss on RGBXY points), from Python.
#[pymodule]
fn epsm(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("EpsmError", m.py().get_type::<error::EpsmError>())?;
    m.add_class::<scene::Scene>()?;
    m.add_class::<problem::Problem>()?;
    m.add_class::<optimization::Optimization>()?;
    m.add_function(wrap_pyfunction!(scene::load_scene, m)?)?;
    m.add_function(wrap_pyfunction!(problem::load_problem, m)?)?;
    m.add_function(wrap_pyfunction!(field::motion_field, m)?)?;
    m.add_function(wrap_pyfunction!(matching::match_images, m)?)?;
    m.add_function(wrap_pyfunction!(image::read_image, m)?)?;
    m.add_function(wrap_pyfunction!(image::write_image, m)?)?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
