//! Checkpoints: θ, the optimizer state and the report rows of a run,
//! written atomically as JSON, so that a killed run resumes exactly.

use std::path::Path;
use std::time::Instant;

use serde::{Deserialize, Serialize};

use super::{Best, OptResult, Optimization, OptimizeError};
use crate::drops::DropReason;
use crate::optim::Adam;
use crate::report::{Row, write_atomic};
use crate::schedule::{Method, Switch};

/// What a checkpoint holds: enough to continue a run exactly.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Checkpoint {
    /// The next iteration to run.
    pub iteration: u32,
    /// θ before that iteration.
    pub theta: Vec<f64>,
    /// Adam's state.
    pub adam: Adam,
    /// Wall seconds spent so far.
    pub wall_s: f64,
    /// The method.
    pub method: Method,
    /// The rows so far.
    pub rows: Vec<Row>,
    /// The hybrid switch: decided, or the plateau detector's state
    /// (absent from checkpoints written before it was saved: the problem's).
    #[serde(default)]
    pub switch: Option<Switch>,
    /// The best judged θ so far.
    #[serde(default)]
    pub best: Option<Best>,
    /// Whether the run stopped converged (`optimizer.stop`).
    #[serde(default)]
    pub stopped: bool,
}

impl Optimization {
    /// The state needed to resume.
    pub fn checkpoint(&self) -> Checkpoint {
        Checkpoint {
            iteration: self.iteration,
            theta: self.theta.clone(),
            adam: self.adam.clone(),
            wall_s: self.wall_before + self.started.elapsed().as_secs_f64(),
            method: self.schedule.method,
            rows: self.rows.clone(),
            switch: Some(self.schedule.switch.clone()),
            best: self.best.clone(),
            stopped: self.stopped,
        }
    }

    /// Continues from `c`, which must come from the same problem and method:
    /// an error says which field of the checkpoint does not fit.
    pub fn restore(&mut self, c: Checkpoint) -> OptResult<()> {
        self.check_checkpoint(&c).map_err(OptimizeError::Invalid)?;
        self.iteration = c.iteration;
        self.adam = c.adam;
        self.wall_before = c.wall_s;
        self.started = Instant::now();
        self.rows = c.rows;
        if let Some(switch) = c.switch {
            self.schedule.switch = switch;
        }
        self.best = c.best;
        self.stopped = c.stopped;
        self.set_theta(&c.theta);
        Ok(())
    }

    /// Continues from checkpoint `c`, read from `path` (by
    /// [`Self::load_checkpoint`]), as [`Self::restore`] does; its errors name
    /// the file.
    pub fn resume(&mut self, path: &Path, c: Checkpoint) -> OptResult<()> {
        self.restore(c).map_err(|e| match e {
            OptimizeError::Invalid(message) => OptimizeError::File {
                path: path.to_owned(),
                message,
            },
            other => other,
        })
    }

    /// Why `c` cannot continue this run, if it cannot.
    fn check_checkpoint(&self, c: &Checkpoint) -> Result<(), String> {
        let n = self.theta.len();
        if c.theta.len() != n || c.method != self.schedule.method {
            return Err(format!(
                "checkpoint has {} parameters and method {}; the problem has {} and {}",
                c.theta.len(),
                c.method.name(),
                n,
                self.schedule.method.name()
            ));
        }
        if c.adam.settings != self.adam.settings {
            return Err(format!(
                "adam.settings: {:?} differ from the problem's {:?}",
                c.adam.settings, self.adam.settings
            ));
        }
        for (key, values) in [("adam.m", &c.adam.m), ("adam.v", &c.adam.v)] {
            if values.len() != n {
                return Err(format!(
                    "{key}: {} entries for {n} parameters",
                    values.len()
                ));
            }
            if let Some(i) = values.iter().position(|v| !v.is_finite()) {
                return Err(format!("{key}[{i}]: expected a finite number"));
            }
        }
        if let Some(i) = c.adam.v.iter().position(|&v| v < 0.0) {
            return Err(format!(
                "adam.v[{i}]: expected a value >= 0 (a second moment)"
            ));
        }
        if c.adam.t > c.adam.iteration {
            return Err(format!(
                "adam.t: {} steps since the last reset but {} in all",
                c.adam.t, c.adam.iteration
            ));
        }
        let bounds = &self.adam.settings.bounds;
        if let Some((i, x)) = (c.theta.iter().zip(bounds).enumerate())
            .find(|(_, (x, [lo, hi]))| !(*lo..=*hi).contains(*x))
        {
            return Err(format!(
                "theta[{i}]: {} is outside the bounds {:?}",
                x.0, x.1
            ));
        }
        if let Some(b) = c.best.as_ref().filter(|b| b.theta.len() != n) {
            return Err(format!(
                "best.theta: {} values for {n} parameters",
                b.theta.len()
            ));
        }
        if !(c.wall_s.is_finite() && c.wall_s >= 0.0) {
            return Err(format!("wall_s: expected seconds >= 0, found {}", c.wall_s));
        }
        if c.rows.len() != c.iteration as usize {
            return Err(format!(
                "rows: {} rows for {} iterations",
                c.rows.len(),
                c.iteration
            ));
        }
        let drops = DropReason::ALL.len();
        for (i, row) in c.rows.iter().enumerate() {
            if row.theta.len() != n || row.dropped.len() != drops {
                return Err(format!(
                    "rows[{i}]: expected {n} theta values and {drops} dropped counts, found {} and {}",
                    row.theta.len(),
                    row.dropped.len()
                ));
            }
        }
        Ok(())
    }

    /// Writes the checkpoint to `path` (JSON, atomically).
    pub fn save_checkpoint(&self, path: &Path) -> OptResult<()> {
        let json =
            serde_json::to_vec_pretty(&self.checkpoint()).map_err(|e| OptimizeError::File {
                path: path.to_owned(),
                message: e.to_string(),
            })?;
        write_atomic(path, &json)
    }

    /// Reads a checkpoint written by [`Optimization::save_checkpoint`].
    pub fn load_checkpoint(path: &Path) -> OptResult<Checkpoint> {
        let err = |message: String| OptimizeError::File {
            path: path.to_owned(),
            message,
        };
        let text = epsm_scene::input_file::read_to_string(path)?;
        serde_json::from_str(&text).map_err(|e| err(e.to_string()))
    }
}
