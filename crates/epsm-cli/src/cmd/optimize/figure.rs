//! The figures of optimization runs: `report.png` of `epsm optimize`, and
//! the panels and first images `epsm compare` shares.

use std::path::Path;

use super::summary::{CurvePoint, Summary};
use crate::cmd::plots::{Figure, Panel, Series, Thumb, plot_figure};

/// Draws `report.png` of a run of `method` on the problem in
/// `problem_file` into `path`: the image RMSE and parameter error panels
/// and the target, initial, best-θ and (when it differs) last-iterate
/// images.
pub(super) fn plot_report(
    path: &Path,
    problem_file: &Path,
    method: &str,
    summary: &Summary,
) -> anyhow::Result<()> {
    let mut strip = start_images(summary);
    strip.push(Thumb {
        label: "best".into(),
        image: summary.last.clone(),
    });
    if let Some(image) = &summary.last_iterate {
        strip.push(Thumb {
            label: "last iterate".into(),
            image: image.clone(),
        });
    }
    let errors = match (
        summary.curve.first().and_then(|c| c.param_error),
        summary.param_error,
    ) {
        (Some(first), Some(last)) => format!(", parameter error {first:.3} to {last:.3}"),
        _ => String::new(),
    };
    let figure = Figure {
        title: format!(
            "{}: {method}, {} iterations in {:.1} s{errors}",
            problem_name(problem_file),
            summary.iterations,
            summary.wall_s
        ),
        panels: &panels(&[(method.to_owned(), summary)]),
        strip: &strip,
    };
    plot_figure(path, &figure)
}

/// The name of a problem in titles and tables: its file's stem.
pub fn problem_name(file: &Path) -> String {
    file.file_stem()
        .and_then(|s| s.to_str())
        .unwrap_or("problem")
        .to_owned()
}

/// The first images of a figure's strip: the target and, when known, the
/// initial render.
pub fn start_images(s: &Summary) -> Vec<Thumb> {
    let mut strip = vec![Thumb {
        label: "target".into(),
        image: s.target.clone(),
    }];
    if let Some(image) = &s.initial {
        strip.push(Thumb {
            label: "initial".into(),
            image: image.clone(),
        });
    }
    strip
}

/// The two panels of a report: image RMSE and parameter error against time.
pub fn panels(runs: &[(String, &Summary)]) -> Vec<Panel> {
    let series = |f: &dyn Fn(&CurvePoint) -> Option<f64>| {
        runs.iter()
            .map(|(name, s)| Series {
                name: name.clone(),
                points: s
                    .curve
                    .iter()
                    .filter_map(|c| f(c).map(|y| (c.wall_s, y)))
                    .collect(),
            })
            .collect()
    };
    let mut out = vec![Panel {
        title: "image RMSE".into(),
        y_label: "RMSE (linear RGB)".into(),
        series: series(&|c| Some(c.image_rmse)),
    }];
    if runs
        .iter()
        .any(|(_, s)| s.curve.iter().any(|c| c.param_error.is_some()))
    {
        out.push(Panel {
            title: "parameter error".into(),
            y_label: "RMS of θ − θ_true".into(),
            series: series(&|c| c.param_error),
        });
    }
    out
}
