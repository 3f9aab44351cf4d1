//! `epsm optimize`: run one optimization problem and write its report.
//!
//! Output folder: `run.csv` (one row per iteration, rewritten atomically each
//! iteration), `summary.csv` (one row: the last and the best θ with their
//! parameter errors, the tolerance and whether the problem is solved),
//! `target`, `initial` and `final` images (`.png` sRGB and `.exr` linear;
//! `final` at the best θ), `report.png` (image RMSE and parameter error
//! against wall-clock seconds, and the target, initial, best-θ and last-iterate images,
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

pub mod figure;
pub mod summary;

use std::path::{Path, PathBuf};

use anyhow::Context;
use epsm_core::loss::LossKind;
use epsm_core::report::{csv, mean_timings, param_error, write_atomic};
use epsm_core::{Method, Optimization, Problem, load_problem};
use epsm_render::Image;
use epsm_scene::image_io::{read_image, write_image};

use crate::progress;
use figure::plot_report;
use summary::{CurvePoint, Summary, best_origin, solved_word, summary_csv};

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
    let last_iterate = (last != best).then(|| opt.render(preview_spp));
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
        last_iterate,
    };
    let text = summary_csv(&keys, &summary, &best, &last);
    write_atomic(&out.join("summary.csv"), text.as_bytes())?;
    let method = opt.problem().optimizer.method.name();
    plot_report(&out.join("report.png"), problem_file, method, &summary)?;
    Ok(summary)
}
