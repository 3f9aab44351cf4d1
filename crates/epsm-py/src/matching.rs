//! `epsm.match`: the OT matching of two images, as `epsm match` and the
//! optimizer's loss compute it ([`epsm_core::loss::match_images`]).

use epsm_core::loss::{match_images as solve, matcher_named, resample};
use epsm_ot::{MatchLimits, Matching};
use numpy::{IntoPyArray, PyArray1};
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::error::{invalid, to_py};
use crate::image::{from_array, per_pixel};

/// match(a, b, solver="exact", lam=1.0, blur=0.01, resolution=None) -> dict
///
/// Matches the RGBXY points of image `a` to those of image `b` (arrays
/// (H, W, 3), linear RGB, the same size, or both box-filtered to
/// `resolution = (W, H)`): colours tone-mapped `c / (1 + c)`, positions
/// the pixel centres over the image size times `lam`. `solver` is "exact"
/// (the optimal assignment) or "sinkhorn" (entropic, ε = blur²).
///
/// Returns a dict:
/// - `loss`: the OT loss (float);
/// - `grad_points`: ∂L/∂P per point of `a`, (H, W, 5) float32 in point
///   units (r, g, b tone-mapped; x, y scaled by `lam`);
/// - `grad_rgb`: ∂L/∂c, (H, W, 3) float32, per linear colour;
/// - `grad_xy`: ∂L/∂p, (H, W, 2) float64, per film pixel;
/// - `assignment`: exact: the row-major index of the pixel of `b` each pixel
///   of `a` is matched to, (H·W,) int64; sinkhorn: None;
/// - `targets`: the point each point of `a` is pulled toward (its partner,
///   or the plan's barycentric target), (H, W, 5) float32;
/// - `stats`: the solve's counters (iterations, pair_evaluations, ...).
#[pyfunction(name = "match")]
#[pyo3(signature = (a, b, solver = "exact", lam = 1.0, blur = 0.01, resolution = None))]
pub fn match_images<'py>(
    py: Python<'py>,
    a: &Bound<'py, PyAny>,
    b: &Bound<'py, PyAny>,
    solver: &str,
    lam: f64,
    blur: f64,
    resolution: Option<(u32, u32)>,
) -> PyResult<Bound<'py, PyDict>> {
    let (mut a, mut b) = (from_array(a, "a")?, from_array(b, "b")?);
    if let Some((w, h)) = resolution {
        if w == 0 || h == 0 {
            return Err(invalid("resolution", "expected sizes >= 1"));
        }
        a = resample(&a, w, h);
        b = resample(&b, w, h);
    }
    let matcher = matcher_named(solver, blur).map_err(to_py)?;
    matcher
        .check_size(a.pixels.len(), &MatchLimits::default())
        .map_err(|e| to_py(epsm_core::OptimizeError::from(e)))?;
    let m = py
        .detach(|| solve(&matcher, &a, &b, lam, None))
        .map_err(to_py)?;
    let (w, h) = (a.width, a.height);
    let out = PyDict::new(py);
    out.set_item("loss", m.result.loss)?;
    out.set_item(
        "grad_points",
        per_pixel(py, w, h, m.result.gradient.iter().copied()),
    )?;
    out.set_item(
        "grad_rgb",
        per_pixel(py, w, h, m.eval.g_rgb.iter().map(|g| g.to_array())),
    )?;
    out.set_item(
        "grad_xy",
        per_pixel(py, w, h, m.eval.g_xy.iter().map(|g| g.to_array())),
    )?;
    let assignment: Option<Bound<'py, PyArray1<i64>>> = match &m.result.matching {
        Matching::Permutation(perm) => Some(
            perm.iter()
                .map(|&j| j as i64)
                .collect::<Vec<_>>()
                .into_pyarray(py),
        ),
        Matching::Entropic(_) | Matching::Sliced(_) => None,
    };
    out.set_item("assignment", assignment)?;
    let points = epsm_core::loss::points(&a, lam as f32).map_err(to_py)?;
    let targets = (0..points.len()).map(|i| m.result.target(points.point(i), i));
    out.set_item("targets", per_pixel(py, w, h, targets))?;
    let s = &m.result.stats;
    let stats = PyDict::new(py);
    stats.set_item("iterations", s.iterations)?;
    stats.set_item("pair_evaluations", s.pair_evaluations)?;
    stats.set_item("candidate_pairs", s.candidate_pairs)?;
    stats.set_item("added_pairs", s.added_pairs)?;
    stats.set_item("marginal_error", s.marginal_error)?;
    for (name, count) in epsm_core::loss::MatchGuards::COLUMNS
        .iter()
        .zip(m.eval.guards.counts())
    {
        stats.set_item(*name, count)?;
    }
    let phases = PyDict::new(py);
    for (phase, seconds) in s.phases.iter() {
        phases.set_item(phase, seconds)?;
    }
    stats.set_item("phases", phases)?;
    out.set_item("stats", stats)?;
    Ok(out)
}
