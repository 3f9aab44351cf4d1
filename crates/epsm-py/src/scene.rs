//! `epsm.Scene`: a loaded scene, its renders and its parameters by key.

use std::path::PathBuf;

use epsm_core::ParamTable;
use epsm_render::tracer::{RenderOptions, render};
use numpy::PyArray3;
use pyo3::prelude::*;
use pyo3::types::PyTuple;

use crate::error::{invalid, to_py};
use crate::image::to_array;

/// A scene read from a TOML, glTF 2.0 or Mitsuba 3 XML file, with the
/// parameter values set on it since.
///
/// Parameters use the problem files' keys (`"<object>.translate.x"`,
/// `"<light>.translate.y"`, `"camera.yaw"`, `"<material>.albedo.r"`, ...;
/// docs/problem-format.md), in user units, as offsets from (or values
/// replacing) the file's placement. A scene pickles as its file path and
/// the values set.
#[pyclass(module = "epsm")]
pub struct Scene {
    pub(crate) path: PathBuf,
    pub(crate) sets: Vec<(String, f64)>,
    pub(crate) scene: epsm_render::Scene,
    pub(crate) table: ParamTable,
}

impl Scene {
    fn open(path: PathBuf) -> PyResult<Self> {
        let scene = epsm_core::load_scene(&path).map_err(to_py)?;
        let table = ParamTable::new(&scene);
        Ok(Self {
            path,
            sets: Vec::new(),
            scene,
            table,
        })
    }

    /// The value of `key` now: set, or the file's.
    pub(crate) fn value(&self, key: &str) -> PyResult<f64> {
        match self.table.index(key) {
            Some(i) => Ok(self.table.values()[i]),
            None => Ok(self.table.resolve(key).map_err(to_py)?.value),
        }
    }
}

/// load_scene(path) -> Scene
///
/// Reads a scene file: TOML (docs/scene-format.md), glTF 2.0 (.gltf, .glb)
/// or Mitsuba 3 XML (.xml). Importer warnings go to standard error.
#[pyfunction]
pub fn load_scene(py: Python<'_>, path: PathBuf) -> PyResult<Scene> {
    py.detach(|| Scene::open(path))
}

#[pymethods]
impl Scene {
    /// render(spp=None, seed=None) -> numpy.ndarray
    ///
    /// Renders the scene at its current parameter values: a float32 array
    /// (H, W, 3) in linear RGB, bit for bit what `epsm render --spp --seed`
    /// writes to an EXR. `spp` and `seed` default to the scene's
    /// `render.spp` and `render.seed`.
    #[pyo3(signature = (spp = None, seed = None))]
    fn render<'py>(
        &self,
        py: Python<'py>,
        spp: Option<u32>,
        seed: Option<u32>,
    ) -> PyResult<Bound<'py, PyArray3<f32>>> {
        let mut opts = RenderOptions::from_scene(&self.scene);
        if let Some(spp) = spp {
            if spp == 0 {
                return Err(invalid("spp", "expected at least 1 sample per pixel"));
            }
            opts.spp = spp;
        }
        if let Some(seed) = seed {
            opts.seed = seed;
        }
        let out = py.detach(|| render(&self.scene, &opts, &|_| {}));
        Ok(to_array(py, &out.image))
    }

    /// set(key, value) -> None
    ///
    /// Sets parameter `key` to `value` (user units) and moves the scene.
    fn set(&mut self, key: &str, value: f64) -> PyResult<()> {
        let param = self.table.resolve(key).map_err(to_py)?;
        let ([lo, hi], range) = param.target.domain();
        if !(lo..=hi).contains(&value) {
            return Err(invalid(key, format!("expected {range}, found {value}")));
        }
        let i = match self.table.index(key) {
            Some(i) => i,
            None => self.table.add(key).map_err(to_py)?,
        };
        self.table.set_value(i, value);
        self.table.apply(&mut self.scene);
        self.sets.retain(|(k, _)| k != key);
        self.sets.push((key.to_owned(), value));
        Ok(())
    }

    /// get(key) -> float
    ///
    /// The current value of parameter `key` (user units): the value set, or
    /// the file's.
    fn get(&self, key: &str) -> PyResult<f64> {
        self.value(key)
    }

    /// The scene file.
    #[getter]
    fn path(&self) -> PathBuf {
        self.path.clone()
    }

    /// Image width in pixels.
    #[getter]
    fn width(&self) -> u32 {
        self.scene.camera().width
    }

    /// Image height in pixels.
    #[getter]
    fn height(&self) -> u32 {
        self.scene.camera().height
    }

    /// The values set so far, as `[(key, value)]` in the order set.
    #[getter]
    fn values(&self) -> Vec<(String, f64)> {
        self.sets.clone()
    }

    fn __repr__(&self) -> String {
        format!(
            "Scene({:?}, {}x{}, set={:?})",
            self.path.display().to_string(),
            self.width(),
            self.height(),
            self.sets
        )
    }

    /// Pickles as `load_scene(path)` followed by the values set.
    fn __reduce__<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyTuple>> {
        let load = py.import("epsm")?.getattr("load_scene")?;
        (load, (self.path.clone(),), self.sets.clone()).into_pyobject(py)
    }

    fn __setstate__(&mut self, state: Vec<(String, f64)>) -> PyResult<()> {
        for (key, value) in state {
            self.set(&key, value)?;
        }
        Ok(())
    }
}
