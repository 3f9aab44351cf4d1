//! Run reports (docs/design.md §8): one row per iteration, written as `run.csv`.
//!
//! Columns: `iteration,wall_s,loss,image_rmse,param_error,judged_loss`
//! (`judged_loss`: the loss of θ on the independent judged render,
//! [`crate::run::best`], empty in iterations not judged), then one column
//! per parameter (its value, in user units, headed by its key), then
//! `paths_traced,paths_solved,paths_skipped`, one `dropped_<reason>` column
//! per [`DropReason`], the matcher's guard counts
//! `ot_unconverged_solves,ot_auction_budget_stops,ot_cold_starts,ot_bridged_corrections,ot_clamped_corrections`
//! ([`MatchGuards`]; zero for L2), `path_kinds` (the kinds seen,
//! `+`-separated) and the seconds of the iteration's parts:
//! `t_primal,t_trace,t_match,t_solve`.
//! `param_error` is the RMS of `θ − θ_true` in the parameters' units, empty
//! when true values are unknown.

use std::fmt::Write as _;
use std::path::Path;

use serde::{Deserialize, Serialize};

use crate::drops::DropReason;
use crate::loss::MatchGuards;
use crate::run::{OptResult, OptimizeError};

/// Seconds spent in the parts of one iteration.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Timings {
    /// Primal render at the scene resolution.
    pub primal: f64,
    /// The gradient pass's renders: the trace with path records and, when
    /// the loss compares one, the matched render (each timed alone).
    pub trace: f64,
    /// Loss and matching.
    pub matching: f64,
    /// Classification, manifold solves and colour derivatives.
    pub solve: f64,
}

/// One iteration of a run.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Row {
    /// Iteration (0-based); θ is the value the loss was measured at.
    pub iteration: u32,
    /// Wall-clock seconds since the run started (excluding target rendering).
    pub wall_s: f64,
    /// Loss value.
    pub loss: f64,
    /// RMSE of the primal render against the target (linear RGB).
    pub image_rmse: f64,
    /// RMS of `θ − θ_true`, when true values are known.
    pub param_error: Option<f64>,
    /// The loss of θ on the independent judged render, in the iterations
    /// that judge θ ([`crate::run::best`]).
    #[serde(default)]
    pub judged_loss: Option<f64>,
    /// θ.
    pub theta: Vec<f64>,
    /// Paths traced, solved, skipped.
    pub paths: [u64; 3],
    /// Dropped paths per [`DropReason::ALL`] entry.
    pub dropped: Vec<u64>,
    /// The loss's matcher guard counts (absent from checkpoints written
    /// before they were reported: zero).
    #[serde(default)]
    pub guards: MatchGuards,
    /// Kinds of differentiable paths seen.
    pub kinds: String,
    /// Time split.
    pub timings: Timings,
}

/// The CSV header for parameters `keys`.
pub fn header(keys: &[String]) -> String {
    let mut h = String::from("iteration,wall_s,loss,image_rmse,param_error,judged_loss");
    for k in keys {
        let _ = write!(h, ",{k}");
    }
    h.push_str(",paths_traced,paths_solved,paths_skipped");
    for r in DropReason::ALL {
        let _ = write!(h, ",dropped_{}", r.name());
    }
    for c in MatchGuards::COLUMNS {
        let _ = write!(h, ",{c}");
    }
    h.push_str(",path_kinds,t_primal,t_trace,t_match,t_solve");
    h
}

/// One CSV line (no newline).
pub fn csv_line(row: &Row) -> String {
    let number = |x: Option<f64>| x.map(|e| format!("{e:e}")).unwrap_or_default();
    let mut s = format!(
        "{},{:.3},{:e},{:e},{},{}",
        row.iteration,
        row.wall_s,
        row.loss,
        row.image_rmse,
        number(row.param_error),
        number(row.judged_loss)
    );
    for v in &row.theta {
        let _ = write!(s, ",{v}");
    }
    for v in row
        .paths
        .iter()
        .chain(&row.dropped)
        .chain(&row.guards.counts())
    {
        let _ = write!(s, ",{v}");
    }
    let t = &row.timings;
    let _ = write!(
        s,
        ",{},{:.4},{:.4},{:.4},{:.4}",
        row.kinds, t.primal, t.trace, t.matching, t.solve
    );
    s
}

/// The whole CSV of `rows`.
pub fn csv(keys: &[String], rows: &[Row]) -> String {
    let mut out = header(keys);
    out.push('\n');
    for r in rows {
        out.push_str(&csv_line(r));
        out.push('\n');
    }
    out
}

/// Writes `bytes` to `path` atomically
/// ([`epsm_scene::atomic_file::write_atomic`]), creating the parent folder.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> OptResult<()> {
    let err = |e: std::io::Error| OptimizeError::File {
        path: path.to_owned(),
        message: e.to_string(),
    };
    epsm_scene::atomic_file::create_parent(path).map_err(err)?;
    epsm_scene::atomic_file::write_atomic(path, err, |out| {
        std::io::Write::write_all(out, bytes).map_err(err)
    })
}

/// RMS of `theta − truth` over the parameters with a true value (`None`
/// when some parameter has none).
pub fn param_error(theta: &[f64], truth: &[Option<f64>]) -> Option<f64> {
    let mut sum = 0.0;
    for (x, t) in theta.iter().zip(truth) {
        sum += (x - (*t)?).powi(2);
    }
    (!theta.is_empty()).then(|| (sum / theta.len() as f64).sqrt())
}

/// Mean seconds per iteration of each part over `rows` (zero for no rows).
pub fn mean_timings(rows: &[Row]) -> Timings {
    let n = rows.len().max(1) as f64;
    let sum = |f: fn(&Timings) -> f64| rows.iter().map(|r| f(&r.timings)).sum::<f64>() / n;
    Timings {
        primal: sum(|t| t.primal),
        trace: sum(|t| t.trace),
        matching: sum(|t| t.matching),
        solve: sum(|t| t.solve),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn header_and_rows_have_the_same_number_of_columns() {
        let keys = vec!["a.translate.x".to_owned(), "b.alpha".to_owned()];
        let row = Row {
            iteration: 3,
            wall_s: 1.5,
            loss: 0.25,
            image_rmse: 0.1,
            param_error: param_error(&[1.0, 2.0], &[Some(0.0), Some(2.0)]),
            judged_loss: Some(0.125),
            theta: vec![1.0, 2.0],
            paths: [10, 5, 2],
            dropped: vec![0; DropReason::ALL.len()],
            guards: MatchGuards {
                unconverged_solves: 2,
                clamped_corrections: 7,
                ..MatchGuards::default()
            },
            kinds: "primary".into(),
            timings: Timings::default(),
        };
        let text = csv(&keys, &[row]);
        let lines: Vec<&str> = text.lines().collect();
        assert!(
            lines[0].starts_with(
                "iteration,wall_s,loss,image_rmse,param_error,judged_loss,a.translate.x"
            )
        );
        assert_eq!(lines[0].split(',').count(), lines[1].split(',').count());
        let cell = |name: &str| {
            let column = lines[0].split(',').position(|c| c == name);
            column.and_then(|i| lines[1].split(',').nth(i))
        };
        assert_eq!(cell("ot_unconverged_solves"), Some("2"));
        assert_eq!(cell("ot_auction_budget_stops"), Some("0"));
        assert_eq!(cell("ot_clamped_corrections"), Some("7"));
        assert_eq!(cell("path_kinds"), Some("primary"));
        assert_eq!(cell("judged_loss"), Some("1.25e-1"));
        let err: f64 = lines[1]
            .split(',')
            .nth(4)
            .expect("column")
            .parse()
            .expect("number");
        assert!((err - 0.5f64.sqrt()).abs() < 1e-12);
        assert_eq!(param_error(&[1.0], &[None]), None);
    }

    #[test]
    fn rows_of_checkpoints_without_guard_counts_read_as_zero() {
        let json = r#"{"iteration":0,"wall_s":0.5,"loss":1.0,"image_rmse":0.1,"param_error":null,
            "theta":[0.5],"paths":[1,1,0],"dropped":[],"kinds":"primary",
            "timings":{"primal":0.0,"trace":0.0,"matching":0.0,"solve":0.0}}"#;
        let row: Row = serde_json::from_str(json).expect("a row of an older checkpoint");
        assert_eq!(row.guards, MatchGuards::default());
    }

    #[test]
    fn mean_timings_average_each_part() {
        let row = |primal, solve| Row {
            iteration: 0,
            wall_s: 0.0,
            loss: 0.0,
            image_rmse: 0.0,
            param_error: None,
            judged_loss: None,
            theta: Vec::new(),
            paths: [0; 3],
            dropped: Vec::new(),
            guards: MatchGuards::default(),
            kinds: String::new(),
            timings: Timings {
                primal,
                trace: 1.0,
                matching: 2.0,
                solve,
            },
        };
        let m = mean_timings(&[row(1.0, 0.0), row(3.0, 4.0)]);
        assert_eq!(
            m,
            Timings {
                primal: 2.0,
                trace: 1.0,
                matching: 2.0,
                solve: 2.0
            }
        );
        assert_eq!(mean_timings(&[]), Timings::default());
    }
}
