//! `epsm.Optimization`: one optimization run, stepped from Python, with
//! the CLI's checkpoints (plus the problem's source, so that a checkpoint
//! alone restores the run).

use std::path::PathBuf;

use epsm_core::report::{param_error, write_atomic};
use epsm_core::schedule::Method;
use epsm_core::{Checkpoint, OptimizeError};
use numpy::{IntoPyArray, PyArray1, PyArray3};
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::error::{invalid, to_py};
use crate::image::to_array;
use crate::problem::{Problem, Source};

/// What `Optimization.checkpoint` writes: the problem's source, the method
/// and the run's checkpoint (as `epsm optimize` writes it).
#[derive(serde::Serialize, serde::Deserialize)]
struct Saved {
    problem: Source,
    checkpoint: Checkpoint,
}

/// A running optimization of a problem.
///
/// `Optimization(problem, method=None)` sets the run up (rendering the
/// target when the problem gives true values, and making the automatic
/// choices `epsm optimize` prints); `method` is `"epsm"`, `"drot"` or
/// `"l2"` (default: the problem's `optimizer.method`).
#[pyclass(module = "epsm")]
pub struct Optimization {
    source: Source,
    opt: epsm_core::Optimization,
}

impl Optimization {
    fn start(
        py: Python<'_>,
        source: Source,
        mut problem: epsm_core::Problem,
        method: Option<&str>,
    ) -> PyResult<Self> {
        if let Some(name) = method {
            problem.optimizer.method = Method::parse(name).ok_or_else(|| {
                invalid(
                    "method",
                    format!("unknown method `{name}`; expected epsm, drot or l2"),
                )
            })?;
        }
        let opt = py
            .detach(|| epsm_core::Optimization::new(problem))
            .map_err(to_py)?;
        Ok(Self { source, opt })
    }

    /// The true values where known, in θ's order.
    fn truth(&self) -> Vec<Option<f64>> {
        self.opt
            .problem()
            .params
            .iter()
            .map(|p| p.true_value)
            .collect()
    }

    /// The row of `row` as a Python dict (its JSON form).
    fn row_dict<'py>(py: Python<'py>, row: &epsm_core::report::Row) -> PyResult<Bound<'py, PyAny>> {
        let text = serde_json::to_string(row).map_err(|e| invalid("row", e.to_string()))?;
        py.import("json")?.call_method1("loads", (text,))
    }
}

#[pymethods]
impl Optimization {
    #[new]
    #[pyo3(signature = (problem, method = None))]
    fn new(py: Python<'_>, problem: PyRef<'_, Problem>, method: Option<&str>) -> PyResult<Self> {
        Self::start(py, problem.source.clone(), problem.problem.clone(), method)
    }

    /// step() -> dict
    ///
    /// Runs one iteration (render, gradient, Adam step) and returns its row
    /// as `epsm optimize` writes it to run.csv: iteration, wall_s, loss,
    /// image_rmse, param_error, judged_loss, theta (before the step), paths
    /// [traced, solved, skipped], dropped, guards, kinds, timings.
    fn step<'py>(&mut self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        if self.opt.is_done() {
            return Err(invalid("step", "every iteration of the run has run"));
        }
        let row = py.detach(|| self.opt.step()).map_err(to_py)?;
        Self::row_dict(py, &row)
    }

    /// gradient() -> numpy.ndarray
    ///
    /// dL/dθ (float64, one entry per parameter, user units) at the current
    /// θ for the current iteration's loss and paths, without stepping.
    fn gradient<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray1<f64>>> {
        let (g, _) = py.detach(|| self.opt.gradient()).map_err(to_py)?;
        Ok(g.grad.into_pyarray(py))
    }

    /// loss() -> float
    ///
    /// The loss that gradient() differentiates, at the current θ (the same
    /// renders: the same random streams until the next step).
    fn loss(&self, py: Python<'_>) -> PyResult<f64> {
        let (g, _) = py.detach(|| self.opt.gradient()).map_err(to_py)?;
        Ok(g.loss.value)
    }

    /// θ, the current parameter values (user units, in `keys` order).
    /// Setting it clamps to the bounds and leaves the optimizer state alone.
    #[getter]
    fn get_theta(&self) -> Vec<f64> {
        self.opt.theta().to_vec()
    }

    #[setter]
    fn set_theta(&mut self, theta: Vec<f64>) -> PyResult<()> {
        let n = self.opt.theta().len();
        if theta.len() != n {
            return Err(invalid(
                "theta",
                format!("expected {n} values, found {}", theta.len()),
            ));
        }
        self.opt.set_theta(&theta);
        Ok(())
    }

    /// The RMS error of the current θ against the true values (None
    /// without them), as the report's `param_error`.
    #[getter]
    fn param_error(&self) -> Option<f64> {
        let truth = self.truth();
        param_error(self.opt.theta(), &truth)
    }

    /// The parameter keys, in θ's order.
    #[getter]
    fn keys(&self) -> Vec<String> {
        self.opt.keys()
    }

    /// The next iteration to run.
    #[getter]
    fn iteration(&self) -> u32 {
        self.opt.iteration()
    }

    /// Whether every scheduled iteration has run (or the run stopped).
    #[getter]
    fn done(&self) -> bool {
        self.opt.is_done()
    }

    /// The rows so far, as step() returned them.
    #[getter]
    fn rows<'py>(&self, py: Python<'py>) -> PyResult<Vec<Bound<'py, PyAny>>> {
        self.opt
            .rows()
            .iter()
            .map(|r| Self::row_dict(py, r))
            .collect()
    }

    /// The automatic choices of the run, as `(key, value, why)`.
    #[getter]
    fn choices(&self) -> Vec<(String, String, String)> {
        self.opt
            .choices()
            .iter()
            .map(|c| (c.key.clone(), c.value.clone(), c.why.clone()))
            .collect()
    }

    /// The θ with the lowest judged loss so far, as `{"iteration",
    /// "theta", "judged_loss", "param_error"}` (param_error None without
    /// true values); None before the first judgement.
    #[getter]
    fn best<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyDict>>> {
        let Some(b) = self.opt.best() else {
            return Ok(None);
        };
        let truth: Vec<Option<f64>> = self
            .opt
            .problem()
            .params
            .iter()
            .map(|p| p.true_value)
            .collect();
        let out = PyDict::new(py);
        out.set_item("iteration", b.iteration)?;
        out.set_item("theta", b.theta.clone())?;
        out.set_item("judged_loss", b.loss)?;
        out.set_item("param_error", param_error(&b.theta, &truth))?;
        Ok(Some(out))
    }

    /// The target image (H, W, 3), linear RGB.
    #[getter]
    fn target<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray3<f32>> {
        to_array(py, self.opt.target())
    }

    /// render(spp=16) -> numpy.ndarray
    ///
    /// Renders the current θ at the scene resolution (linear RGB).
    #[pyo3(signature = (spp = 16))]
    fn render<'py>(&self, py: Python<'py>, spp: u32) -> PyResult<Bound<'py, PyArray3<f32>>> {
        if spp == 0 {
            return Err(invalid("spp", "expected at least 1 sample per pixel"));
        }
        let img = py.detach(|| self.opt.render(spp));
        Ok(to_array(py, &img))
    }

    /// checkpoint(path) -> None
    ///
    /// Writes the run's state (θ, Adam, rows, the switch and the best θ)
    /// and the problem's source to `path` (JSON, atomically).
    fn checkpoint(&self, path: PathBuf) -> PyResult<()> {
        let saved = Saved {
            problem: self.source.clone(),
            checkpoint: self.opt.checkpoint(),
        };
        let json = serde_json::to_vec_pretty(&saved).map_err(|e| {
            to_py(OptimizeError::File {
                path: path.clone(),
                message: e.to_string(),
            })
        })?;
        write_atomic(&path, &json).map_err(to_py)
    }

    /// Optimization.restore(path) -> Optimization
    ///
    /// The run a checkpoint() file holds, ready to continue exactly where
    /// it stopped; an error names the file and what does not fit.
    #[staticmethod]
    fn restore(py: Python<'_>, path: PathBuf) -> PyResult<Self> {
        let file_error = |message: String| {
            to_py(OptimizeError::File {
                path: path.clone(),
                message,
            })
        };
        let text = epsm_scene::input_file::read_to_string(&path)
            .map_err(|e| to_py(OptimizeError::from(e)))?;
        let saved: Saved = serde_json::from_str(&text).map_err(|e| file_error(e.to_string()))?;
        let problem = py.detach(|| saved.problem.load()).map_err(to_py)?;
        let method = saved.checkpoint.method.name();
        let mut run = Self::start(py, saved.problem, problem, Some(method))?;
        run.opt.resume(&path, saved.checkpoint).map_err(to_py)?;
        Ok(run)
    }

    fn __repr__(&self) -> String {
        format!(
            "Optimization(keys={:?}, iteration={}, theta={:?})",
            self.opt.keys(),
            self.opt.iteration(),
            self.opt.theta()
        )
    }
}
