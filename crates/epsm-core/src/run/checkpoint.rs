//! Checkpoints: θ, the optimizer state and the report rows of a run,
//! written atomically as JSON, so that a killed run resumes exactly.

use std::path::Path;
use std::time::Instant;

use serde::{Deserialize, Serialize};

use super::{OptResult, Optimization, OptimizeError};
use crate::optim::Adam;
use crate::report::{Row, write_atomic};
use crate::schedule::Method;

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
        }
    }

    /// Continues from `c` (which must come from the same problem and method).
    pub fn restore(&mut self, c: Checkpoint) -> OptResult<()> {
        if c.theta.len() != self.theta.len() || c.method != self.schedule.method {
            return Err(OptimizeError::Invalid(format!(
                "checkpoint has {} parameters and method {}; the problem has {} and {}",
                c.theta.len(),
                c.method.name(),
                self.theta.len(),
                self.schedule.method.name()
            )));
        }
        self.iteration = c.iteration;
        self.adam = c.adam;
        self.wall_before = c.wall_s;
        self.started = Instant::now();
        self.rows = c.rows;
        self.set_theta(&c.theta);
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
        let text = std::fs::read_to_string(path).map_err(|e| err(e.to_string()))?;
        serde_json::from_str(&text).map_err(|e| err(e.to_string()))
    }
}
