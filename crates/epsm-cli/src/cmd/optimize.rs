//! `epsm optimize`: run one optimization problem and write its report.
//!
//! Output folder: `run.csv` (one row per iteration, rewritten atomically each
//! iteration), `summary.csv` (one row: the last and the best θ with their
//! parameter errors, the tolerance and whether the problem is solved),
//! `target`, `initial` and `final` images (`.png` sRGB and `.exr` linear;
//! `final` at the best θ), `report.png` (image RMSE and parameter error
//! against wall-clock seconds, and the target, initial and final images,
//! titled with the problem and the method), `checkpoint.json` every
//! `output.checkpoint_every` iterations and at the end (`--resume DIR`
//! continues from it).
//!
//! The run prints every automatic choice on standard error first (`auto
//! KEY = VALUE (why)`), and at the end one line on standard output: the
//! iterations, seconds, image RMSE, the parameter error of the best θ, the
//! last θ's beside it and `solved: yes/no` against the problem's
//! `tolerance`.
//!
//! The first iteration whose entropic OT solves stopped above their marginal
//! tolerance (`ot_unconverged_solves` in `run.csv`) prints a warning on
//! standard error, once per run, naming the problem's `loss.blur`.

use std::path::{Path, PathBuf};

use anyhow::Context;
use epsm_core::loss::LossKind;
use std::fmt::Write as _;

use epsm_core::report::{Timings, csv, mean_timings, param_error, write_atomic};
use epsm_core::{Method, Optimization, Problem, load_problem};
use epsm_render::Image;
use epsm_scene::image_io::{read_image, write_image};

use super::plots::{Figure, Panel, Series, Thumb, plot_figure};
use crate::progress;

/// Arguments of `epsm optimize`.
#[derive(clap::Args, Debug)]
pub struct OptimizeArgs {
    /// The problem file (TOML, see docs/problem-format.md).
    pub problem: PathBuf,
    /// Output folder (default: the problem's `output.dir`).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Iterations (default: the problem's `optimizer.iterations`).
    #[arg(long)]
    pub iterations: Option<u32>,
    /// Method: epsm, drot, l2 or prdpt (default: the problem's `optimizer.method`).
    #[arg(long)]
    pub method: Option<String>,
    /// Seed of the iterations' random streams (default: `optimizer.seed`).
    #[arg(long)]
    pub seed: Option<u32>,
    /// Continue the run whose output folder is DIR from its checkpoint.
    #[arg(long, value_name = "DIR")]
    pub resume: Option<PathBuf>,
    /// Stop once the optimization has run this many wall-clock seconds
    /// (checked after each iteration; the iteration count still caps it).
    #[arg(long, value_name = "SECONDS")]
    pub time_budget: Option<f64>,
}

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
    /// The render at the final θ.
    pub last: Image,
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

/// Applies the command-line overrides to a loaded problem.
pub fn apply_overrides(
    problem: &mut Problem,
    iterations: Option<u32>,
    method: Option<&str>,
    seed: Option<u32>,
) -> anyhow::Result<()> {
    if let Some(n) = iterations {
        anyhow::ensure!(n >= 1, "--iterations must be at least 1");
        problem.optimizer.iterations = n;
    }
    if let Some(m) = method {
        problem.optimizer.method = Method::parse(m)
            .with_context(|| format!("--method `{m}`: expected epsm, drot, l2 or prdpt"))?;
    }
    if let Some(s) = seed {
        problem.optimizer.seed = s;
    }
    Ok(())
}

/// Runs `epsm optimize`.
pub fn run(args: &OptimizeArgs) -> anyhow::Result<()> {
    let mut problem = load_problem(&args.problem)?;
    apply_overrides(
        &mut problem,
        args.iterations,
        args.method.as_deref(),
        args.seed,
    )?;
    let out = args
        .resume
        .clone()
        .or_else(|| args.out.clone())
        .unwrap_or_else(|| problem.out_dir.clone());
    let s = optimize(
        problem,
        &args.problem,
        &out,
        args.resume.is_some(),
        args.time_budget,
    )?;
    let error = |e: Option<f64>| e.map_or("n/a".into(), |e| format!("{e:.4}"));
    println!(
        "{}: {} iterations in {:.1} s, image RMSE {:.4}, parameter error {} \
         (best θ, {}; last θ {}), tolerance {}, solved: {} -> {}",
        args.problem.display(),
        s.iterations,
        s.wall_s,
        s.image_rmse,
        error(s.param_error),
        best_origin(s.best_iteration, s.best_averaged),
        error(s.last_param_error),
        error(s.tolerance),
        solved_word(s.solved),
        out.display()
    );
    Ok(())
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
fn summary_csv(keys: &[String], s: &Summary, best: &[f64], last: &[f64]) -> String {
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

fn save(out: &Path, name: &str, img: &Image) -> anyhow::Result<()> {
    for ext in ["png", "exr"] {
        let p = out.join(format!("{name}.{ext}"));
        write_image(&p, img).with_context(|| format!("writing {}", p.display()))?;
    }
    Ok(())
}

/// The warning of the first iteration with `count` unconverged entropic
/// solves, naming the blur of `kind` (the loss of the problem file `file`).
fn unconverged_warning(file: &Path, kind: LossKind, iteration: u32, count: u64) -> String {
    let blur = match kind {
        LossKind::OtSinkhorn { blur } => format!("blur = {blur}"),
        _ => "its blur".to_owned(),
    };
    format!(
        "warning: iteration {iteration}: {count} entropic OT solve(s) stopped above the \
         marginal tolerance, so the matching and its gradient are approximate. \
         The Sinkhorn solver cannot resolve [loss] {blur} ({}) for these images: \
         raise it (0.01, the default, converges on the 64x64 matches measured; \
         see docs/problem-format.md) or use kind = \"ot_exact\". run.csv counts \
         such solves per iteration (ot_unconverged_solves); this warning is shown once.",
        file.display()
    )
}

/// Runs (or resumes) `problem`, loaded from `problem_file`, writing into
/// `out`, stopping after the problem's iterations or, when `budget_s` is
/// given, once the run's wall-clock seconds reach it, whichever comes first.
pub fn optimize(
    problem: Problem,
    problem_file: &Path,
    out: &Path,
    resume: bool,
    budget_s: Option<f64>,
) -> anyhow::Result<Summary> {
    if let Some(b) = budget_s {
        anyhow::ensure!(
            b.is_finite() && b > 0.0,
            "--time-budget must be a positive number of seconds, got {b}"
        );
    }
    let every = problem.checkpoint_every;
    let preview_spp = problem.passes.spp_primal.max(16);
    let checkpoint = out.join("checkpoint.json");
    // Read the checkpoint before the target render and before creating the
    // folder: a wrong `--resume DIR` fails at once and leaves nothing behind.
    let resumed = resume
        .then(|| Optimization::load_checkpoint(&checkpoint))
        .transpose()?;
    std::fs::create_dir_all(out).with_context(|| format!("creating {}", out.display()))?;
    let mut opt = Optimization::new(problem)?;
    for choice in opt.choices() {
        eprintln!("{choice}");
    }
    let initial = if let Some(c) = resumed {
        opt.resume(&checkpoint, c)?;
        let file = out.join("initial.exr");
        read_image(&file)
            .inspect_err(|e| {
                eprintln!("warning: report.png shows no initial image: {e}");
            })
            .ok()
    } else {
        save(out, "target", opt.target())?;
        let image = opt.render(preview_spp);
        save(out, "initial", &image)?;
        Some(image)
    };
    let keys = opt.keys();
    let total = u64::from(opt.problem().optimizer.iterations);
    let bar = progress::bar(total, "iterations");
    bar.set_position(u64::from(opt.iteration()));
    let within_budget =
        |o: &Optimization| budget_s.is_none_or(|b| o.rows().last().is_none_or(|r| r.wall_s < b));
    let mut warned = false;
    while !opt.is_done() && within_budget(&opt) {
        let row = opt.step()?;
        let unconverged = row.guards.unconverged_solves;
        if unconverged > 0 && !warned {
            warned = true;
            let kind = opt.problem().loss.kind;
            let text = unconverged_warning(problem_file, kind, row.iteration, unconverged);
            bar.suspend(|| eprintln!("{text}"));
        }
        bar.set_message(format!("loss {:.3e}", row.loss));
        bar.inc(1);
        write_atomic(&out.join("run.csv"), csv(&keys, opt.rows()).as_bytes())?;
        if every > 0 && opt.iteration() % every == 0 {
            opt.save_checkpoint(&checkpoint)?;
        }
    }
    bar.finish_and_clear();
    opt.save_checkpoint(&checkpoint)?;
    let last = opt.theta().to_vec();
    let (best, best_iteration, best_averaged) =
        opt.best().map_or((last.clone(), opt.iteration(), 0), |b| {
            (b.theta.clone(), b.iteration, b.averaged)
        });
    let wall_s = opt.checkpoint().wall_s;
    opt.set_theta(&best);
    let final_image = opt.render(preview_spp);
    save(out, "final", &final_image)?;
    let truth: Vec<Option<f64>> = opt.problem().params.iter().map(|p| p.true_value).collect();
    let curve = opt
        .rows()
        .iter()
        .map(|r| CurvePoint {
            wall_s: r.wall_s,
            image_rmse: r.image_rmse,
            param_error: r.param_error,
        })
        .collect();
    let best_error = param_error(&best, &truth);
    let tolerance = opt.problem().tolerance;
    let summary = Summary {
        param_error: best_error,
        last_param_error: param_error(&last, &truth),
        best_iteration,
        best_averaged,
        tolerance,
        solved: best_error.zip(tolerance).map(|(e, t)| e <= t),
        image_rmse: epsm_core::loss::rmse(&final_image, opt.target()),
        iterations: opt.iteration(),
        wall_s,
        per_iteration: mean_timings(opt.rows()),
        curve,
        target: opt.target().clone(),
        initial,
        last: final_image,
    };
    let text = summary_csv(&keys, &summary, &best, &last);
    write_atomic(&out.join("summary.csv"), text.as_bytes())?;
    let method = opt.problem().optimizer.method.name();
    let mut strip = start_images(&summary);
    strip.push(Thumb {
        label: "final".into(),
        image: summary.last.clone(),
    });
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
        panels: &panels(&[(method.to_owned(), &summary)]),
        strip: &strip,
    };
    plot_figure(&out.join("report.png"), &figure)?;
    Ok(summary)
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
