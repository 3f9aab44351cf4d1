//! How a run ended: the [`Summary`] of `epsm optimize` (and of each method
//! of `epsm compare`), its `summary.csv` and the words the printed lines use.

use std::fmt::Write as _;

use epsm_core::report::Timings;
use epsm_render::Image;

/// How a run ended.
pub struct Summary {
    /// Parameter error at the best θ (when true values are known): what
    /// the run delivers.
    pub param_error: Option<f64>,
    /// Parameter error at the last θ.
    pub last_param_error: Option<f64>,
    /// The iteration whose θ was judged best.
    pub best_iteration: u32,
    /// How many iterates the best θ is the mean of (0: one iterate).
    pub best_averaged: u32,
    /// The problem's tolerance on the parameter error.
    pub tolerance: Option<f64>,
    /// Whether the best θ's parameter error is within the tolerance (when
    /// both are known).
    pub solved: Option<bool>,
    /// RMSE of the final render (best θ) against the target.
    pub image_rmse: f64,
    /// Iterations run.
    pub iterations: u32,
    /// Wall seconds of the optimization.
    pub wall_s: f64,
    /// Mean seconds per iteration of the primal render, the gradient-pass
    /// trace, the matching and the solves.
    pub per_iteration: Timings,
    /// One point per iteration.
    pub curve: Vec<CurvePoint>,
    /// The target image.
    pub target: Image,
    /// The render at the initial θ (absent when a resumed run's
    /// `initial.exr` cannot be read).
    pub initial: Option<Image>,
    /// The render at the best θ (`final.exr`).
    pub last: Image,
    /// The render at the last iterate, when it differs from the best θ
    /// (shown in `report.png` only).
    pub last_iterate: Option<Image>,
}

/// One iteration's errors, for plots.
pub struct CurvePoint {
    /// Wall seconds since the start.
    pub wall_s: f64,
    /// Image RMSE against the target.
    pub image_rmse: f64,
    /// Parameter error, when known.
    pub param_error: Option<f64>,
}

/// Where the best θ comes from: `iteration 12`, or `mean of the last 10
/// iterates`.
pub fn best_origin(iteration: u32, averaged: u32) -> String {
    if averaged > 0 {
        format!("mean of the last {averaged} iterates")
    } else {
        format!("iteration {iteration}")
    }
}

/// `yes`, `no` or `n/a` (no tolerance or no true values).
pub fn solved_word(solved: Option<bool>) -> &'static str {
    match solved {
        Some(true) => "yes",
        Some(false) => "no",
        None => "n/a",
    }
}

/// `summary.csv`: one header line and one row (see the module doc).
pub(super) fn summary_csv(keys: &[String], s: &Summary, best: &[f64], last: &[f64]) -> String {
    let number = |x: Option<f64>| x.map(|e| format!("{e:e}")).unwrap_or_default();
    let mut out = String::from(
        "iterations,wall_s,image_rmse,best_iteration,best_averaged,best_param_error,last_param_error,tolerance,solved",
    );
    for k in keys {
        let _ = write!(out, ",best {k},last {k}");
    }
    let _ = write!(
        out,
        "\n{},{:.3},{:e},{},{},{},{},{},{}",
        s.iterations,
        s.wall_s,
        s.image_rmse,
        s.best_iteration,
        s.best_averaged,
        number(s.param_error),
        number(s.last_param_error),
        number(s.tolerance),
        solved_word(s.solved)
    );
    for (b, l) in best.iter().zip(last) {
        let _ = write!(out, ",{b},{l}");
    }
    out.push('\n');
    out
}
