//! `epsm.Problem`: an optimization problem, from a problem file or built
//! in Python as the same file would be written (docs/problem-format.md),
//! so that both are checked by the same code with the same located errors.

use std::path::PathBuf;

use epsm_render::Image;
use numpy::PyArray3;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList, PyTuple};

use crate::error::{invalid, to_py};
use crate::image::{from_array, to_array};
use crate::scene::Scene;

/// The name problems built in Python carry in error messages.
const BUILT: &str = "<python problem>";

/// Where a problem comes from: enough to build it again in another
/// process (pickling, checkpoints).
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub enum Source {
    /// A problem file.
    File(PathBuf),
    /// Problem-file text and a target image.
    Text {
        /// The TOML text.
        text: String,
        /// The file it names in errors and resolves relative paths against.
        file: PathBuf,
        /// The target, row-major linear RGB `[width, height, r, g, b, ...]`.
        target: Option<(u32, u32, Vec<f32>)>,
    },
}

impl Source {
    /// Loads and checks the problem.
    pub fn load(&self) -> epsm_core::OptResult<epsm_core::Problem> {
        match self {
            Source::File(path) => epsm_core::load_problem(path).map_err(Into::into),
            Source::Text {
                text,
                file,
                target: None,
            } => epsm_core::problem_from_str(text, file).map_err(Into::into),
            Source::Text {
                text,
                file,
                target: Some((width, height, values)),
            } => {
                let pixels = values.chunks_exact(3).map(glam::Vec3::from_slice).collect();
                let image = Image {
                    width: *width,
                    height: *height,
                    pixels,
                };
                epsm_core::problem_with_target(text, file, image).map_err(Into::into)
            }
        }
    }
}

/// An optimization problem: a scene, the parameters to recover, the target
/// and the settings of docs/problem-format.md.
///
/// `Problem(scene, params, target=None, **sections)` writes the problem
/// file for you: `params` is a list of keys or of `[[parameters]]` tables
/// as dicts (`{"key": ..., "initial": ..., "true": ..., "lr": ...,
/// "bounds": [lo, hi]}`; a key set on `scene` starts at that value);
/// `target` is an image (H, W, 3) at the scene's resolution, or None (or
/// a `[target]` table as a dict, `{"spp": 64}`) to render the true values;
/// `sections` are further tables of the file
/// (`loss={"kind": "ot_sinkhorn"}`, `optimizer={"iterations": 20}`,
/// `render={"spp_grad": 4}`, ...). A problem pickles as its file path, or
/// as that text and the target.
#[pyclass(module = "epsm")]
pub struct Problem {
    pub(crate) source: Source,
    pub(crate) problem: epsm_core::Problem,
}

impl Problem {
    /// Builds the problem of `source`.
    pub(crate) fn from_source(py: Python<'_>, source: Source) -> PyResult<Self> {
        let problem = py.detach(|| source.load()).map_err(to_py)?;
        Ok(Self { source, problem })
    }
}

/// load_problem(path) -> Problem
///
/// Reads and checks a problem file (TOML, docs/problem-format.md). A
/// malformed field raises EpsmError naming the file, line and field.
#[pyfunction]
pub fn load_problem(py: Python<'_>, path: PathBuf) -> PyResult<Problem> {
    Problem::from_source(py, Source::File(path))
}

/// `value` as JSON, through Python's `json` module.
fn json(py: Python<'_>, value: &Bound<'_, PyAny>, what: &str) -> PyResult<serde_json::Value> {
    let text: String = py
        .import("json")?
        .call_method1("dumps", (value,))?
        .extract()?;
    serde_json::from_str(&text).map_err(|e| invalid(what, e.to_string()))
}

#[pymethods]
impl Problem {
    #[new]
    #[pyo3(signature = (scene, params, target = None, **sections))]
    fn new(
        py: Python<'_>,
        scene: PyRef<'_, Scene>,
        params: &Bound<'_, PyList>,
        target: Option<&Bound<'_, PyAny>>,
        sections: Option<&Bound<'_, PyDict>>,
    ) -> PyResult<Self> {
        let mut file = serde_json::Map::new();
        if let Some(s) = sections
            && let serde_json::Value::Object(map) = json(py, s.as_any(), "sections")?
        {
            file.extend(map);
        }
        let path = std::path::absolute(&scene.path).map_err(|e| invalid("scene", e.to_string()))?;
        file.insert("scene_file".into(), path.display().to_string().into());
        let mut entries = Vec::new();
        for (i, p) in params.iter().enumerate() {
            let mut entry = match p.extract::<String>() {
                Ok(key) => serde_json::json!({ "key": key }),
                Err(_) => json(py, &p, &format!("params[{i}]"))?,
            };
            let key = entry.get("key").and_then(|k| k.as_str()).map(str::to_owned);
            if let (Some(key), Some(map)) = (key, entry.as_object_mut())
                && !map.contains_key("initial")
                && scene.sets.iter().any(|(k, _)| *k == key)
            {
                map.insert("initial".into(), scene.value(&key)?.into());
            }
            entries.push(entry);
        }
        if let Some((key, _)) = scene.sets.iter().find(|(k, _)| {
            !entries
                .iter()
                .any(|e| e.get("key").and_then(|v| v.as_str()) == Some(k))
        }) {
            let msg = "a value set on the scene is carried into a problem only as a parameter's \
                       initial value: add the key to `params`";
            return Err(invalid(key, msg));
        }
        file.insert("parameters".into(), entries.into());
        let (image, section) = match target {
            Some(t) if t.is_instance_of::<PyDict>() => (None, Some(t)),
            other => (other, None),
        };
        if let Some(t) = section {
            file.insert("target".into(), json(py, t, "target")?);
        }
        let value: toml::Value = serde_json::from_value(serde_json::Value::Object(file))
            .map_err(|e| invalid("sections", e.to_string()))?;
        let text = toml::to_string(&value).map_err(|e| invalid("sections", e.to_string()))?;
        let target = image
            .map(|t| from_array(t, "target"))
            .transpose()?
            .map(|img| {
                let values = img.pixels.iter().flat_map(|p| p.to_array()).collect();
                (img.width, img.height, values)
            });
        let file = PathBuf::from(BUILT);
        Problem::from_source(py, Source::Text { text, file, target })
    }

    /// with_settings(**sections) -> Problem
    ///
    /// The same problem with tables of the file replaced key by key:
    /// `problem.with_settings(optimizer={"seed": 2, "method": "drot"})`.
    /// Errors name the problem's file.
    #[pyo3(signature = (**sections))]
    fn with_settings(
        &self,
        py: Python<'_>,
        sections: Option<&Bound<'_, PyDict>>,
    ) -> PyResult<Self> {
        let (text, file, target) = match &self.source {
            Source::File(path) => {
                let text = epsm_scene::input_file::read_to_string(path).map_err(to_py)?;
                (text, path.clone(), None)
            }
            Source::Text { text, file, target } => (text.clone(), file.clone(), target.clone()),
        };
        let mut table: toml::Table = text
            .parse()
            .map_err(|e: toml::de::Error| invalid("problem", e.to_string()))?;
        if let Some(s) = sections {
            let changes: toml::Table = serde_json::from_value(json(py, s.as_any(), "sections")?)
                .map_err(|e| invalid("sections", e.to_string()))?;
            for (name, value) in changes {
                match (table.get_mut(&name), value) {
                    (Some(toml::Value::Table(old)), toml::Value::Table(new)) => old.extend(new),
                    (_, value) => {
                        table.insert(name, value);
                    }
                }
            }
        }
        let text = toml::to_string(&table).map_err(|e| invalid("sections", e.to_string()))?;
        Problem::from_source(py, Source::Text { text, file, target })
    }

    /// The parameter keys, in order.
    #[getter]
    fn keys(&self) -> Vec<String> {
        self.problem.params.iter().map(|p| p.key.clone()).collect()
    }

    /// The true parameter values where known (None elsewhere).
    #[getter]
    fn true_values(&self) -> Vec<Option<f64>> {
        self.problem.params.iter().map(|p| p.true_value).collect()
    }

    /// The iteration count.
    #[getter]
    fn iterations(&self) -> u32 {
        self.problem.optimizer.iterations
    }

    /// The parameter error at or below which the problem counts as solved.
    #[getter]
    fn tolerance(&self) -> Option<f64> {
        self.problem.tolerance
    }

    /// The problem-file text of a problem built in Python (None for a file).
    #[getter]
    fn text(&self) -> Option<String> {
        match &self.source {
            Source::File(_) => None,
            Source::Text { text, .. } => Some(text.clone()),
        }
    }

    /// The given target image (None when it is rendered from true values).
    #[getter]
    fn target<'py>(&self, py: Python<'py>) -> Option<Bound<'py, PyArray3<f32>>> {
        match &self.problem.target {
            epsm_core::problem::Target::Image(img) => Some(to_array(py, img)),
            epsm_core::problem::Target::Render { .. } => None,
        }
    }

    fn __repr__(&self) -> String {
        match &self.source {
            Source::File(path) => format!("load_problem({:?})", path.display().to_string()),
            Source::Text { .. } => format!("Problem(keys={:?})", self.keys()),
        }
    }

    /// Pickles as the problem's source (file path, or text and target).
    fn __reduce__<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyTuple>> {
        let state =
            serde_json::to_string(&self.source).map_err(|e| invalid("problem", e.to_string()))?;
        let restore = py
            .import("epsm")?
            .getattr("Problem")?
            .getattr("_from_state")?;
        (restore, (state,)).into_pyobject(py)
    }

    /// The problem of a pickled state (see `__reduce__`).
    #[staticmethod]
    fn _from_state(py: Python<'_>, state: &str) -> PyResult<Self> {
        let source: Source =
            serde_json::from_str(state).map_err(|e| invalid("state", e.to_string()))?;
        Problem::from_source(py, source)
    }
}
