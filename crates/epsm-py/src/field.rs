//! `epsm.motion_field`: dp/dθ per pixel for one parameter of a scene, as
//! `epsm grad` draws it ([`epsm_core::field::motion_field`]), with the
//! differentiable paths counted by kind ([`epsm_core::inspect::path_kind_counts`]).

use std::collections::BTreeMap;

use epsm_core::PathKind;
use epsm_core::field::motion_field as field_of;
use epsm_core::inspect::path_kind_counts;
use epsm_render::record::RecordLevel;
use epsm_render::tracer::{RenderOptions, render_recorded};
use numpy::PyArray3;
use pyo3::prelude::*;

use crate::error::{invalid, to_py};
use crate::image::per_pixel;
use crate::scene::Scene;

/// The motion field `(H, W, 2)` and the path counts by kind.
type Field<'py> = (Bound<'py, PyArray3<f64>>, BTreeMap<&'static str, u64>);

/// motion_field(scene, key, spp=16, seed=None) -> (numpy.ndarray, dict)
///
/// The screen-space motion dp/dθ of parameter `key` at the scene's current
/// values: a float64 array (H, W, 2) in film pixels per user unit (x right,
/// y down), the luminance-weighted mean over each pixel's differentiable
/// paths from `spp` samples (zero where nothing moves with `key`); and the
/// number of differentiable paths of each kind (`{"primary": n,
/// "chain_surface": n, ...}`) over the image.
#[pyfunction]
#[pyo3(signature = (scene, key, spp = 16, seed = None))]
pub fn motion_field<'py>(
    py: Python<'py>,
    scene: PyRef<'_, Scene>,
    key: &str,
    spp: u32,
    seed: Option<u32>,
) -> PyResult<Field<'py>> {
    if spp == 0 {
        return Err(invalid("spp", "expected at least 1 sample per pixel"));
    }
    let mut table = scene.table.clone();
    let param = match table.index(key) {
        Some(i) => i,
        None => table.add(key).map_err(to_py)?,
    };
    let scene = &scene.scene;
    let opts = RenderOptions {
        spp,
        seed: seed.unwrap_or(scene.settings().seed),
        ..RenderOptions::from_scene(scene)
    };
    let (field, counts) = py.detach(|| {
        let (_, records) = render_recorded(scene, &opts, RecordLevel::Full, &|_| {});
        let field = field_of(scene, &table, &records, param);
        let mut counts = [0u64; PathKind::ALL.len()];
        for pixel in path_kind_counts(scene, &table, &records) {
            for (total, n) in counts.iter_mut().zip(pixel) {
                *total += u64::from(n);
            }
        }
        (field, counts)
    });
    let cam = scene.camera();
    let array = per_pixel(
        py,
        cam.width,
        cam.height,
        field.iter().map(|d| d.to_array()),
    );
    let counts = PathKind::ALL
        .iter()
        .map(|k| (k.name(), counts[*k as usize]))
        .collect();
    Ok((array, counts))
}
