//! `epsm compare`: run several methods on one problem with the same
//! iteration count and seed (and, with `--time-budget`, the same cap on
//! wall-clock seconds), and draw their error-versus-time curves in one
//! plot (`compare.png`, with the target, the initial render and each
//! method's final render below) with `compare.csv` beside it; each method's own run
//! folder (`<out>/<method>/`) holds its full report. Each method's row gives
//! the seed, the parameter error of its best θ and of its last, the
//! problem's tolerance and whether it is solved.

use std::fmt::Write as _;
use std::path::PathBuf;

use epsm_core::load_problem;
use epsm_core::report::write_atomic;

use super::optimize::figure::{panels, problem_name, start_images};
use super::optimize::summary::{Summary, solved_word};
use super::optimize::{apply_overrides, optimize};
use super::plots::{Figure, Thumb, plot_figure};

/// Arguments of `epsm compare`.
#[derive(clap::Args, Debug)]
pub struct CompareArgs {
    /// The problem file (TOML).
    pub problem: PathBuf,
    /// Comma-separated methods (epsm, drot, l2, prdpt).
    #[arg(long, default_value = "epsm,drot,l2,prdpt", value_delimiter = ',')]
    pub methods: Vec<String>,
    /// Output folder (default: the problem's `output.dir` + `-compare`).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Iterations of every method (default: the problem's).
    #[arg(long)]
    pub iterations: Option<u32>,
    /// Seed (default: the problem's).
    #[arg(long)]
    pub seed: Option<u32>,
    /// Give every method the same wall-clock budget: each stops once its
    /// run reaches this many seconds (or its iterations end; raise
    /// `--iterations` so that fast methods use the whole budget).
    #[arg(long, value_name = "SECONDS")]
    pub time_budget: Option<f64>,
    /// Print the results as Markdown table rows instead of CSV (for
    /// docs/results.md).
    #[arg(long)]
    pub markdown: bool,
}

/// Runs `epsm compare`.
pub fn run(args: &CompareArgs) -> anyhow::Result<()> {
    let base = load_problem(&args.problem)?;
    let out = args.out.clone().unwrap_or_else(|| {
        let mut d = base.out_dir.clone().into_os_string();
        d.push("-compare");
        d.into()
    });
    let name = problem_name(&args.problem);
    // Every method's problem first, so that a bad `--methods` entry fails
    // before any run. A method listed twice would run twice into one folder.
    for (i, m) in args.methods.iter().enumerate() {
        if let Some(j) = args.methods[..i].iter().position(|x| x == m) {
            anyhow::bail!(
                "--methods: `{m}` is listed twice (entries {} and {})",
                j + 1,
                i + 1
            );
        }
    }
    let problems = args
        .methods
        .iter()
        .map(|method| {
            let mut p = base.clone();
            apply_overrides(&mut p, args.iterations, Some(method), args.seed)?;
            Ok((method, p))
        })
        .collect::<anyhow::Result<Vec<_>>>()?;
    let mut runs: Vec<(String, Summary)> = Vec::new();
    for (method, p) in problems {
        eprintln!("{name}: running {method}");
        let s = optimize(p, &args.problem, &out.join(method), false, args.time_budget)?;
        runs.push((method.clone(), s));
    }
    let mut csv = String::from(
        "problem,method,seed,param_error,last_param_error,tolerance,solved,image_rmse,iterations,wall_s,primal_s,trace_s,matching_s,solve_s\n",
    );
    let mut md = String::new();
    let seed = args.seed.unwrap_or(base.optimizer.seed);
    for (m, s) in &runs {
        let number = |x: Option<f64>| x.map(|e| format!("{e:.5}")).unwrap_or_default();
        let pe = number(s.param_error);
        let (last, tol) = (number(s.last_param_error), number(s.tolerance));
        let solved = solved_word(s.solved);
        let t = &s.per_iteration;
        let parts = [t.primal, t.trace, t.matching, t.solve];
        let _ = writeln!(
            csv,
            "{name},{m},{seed},{pe},{last},{tol},{solved},{:.5},{},{:.1},{}",
            s.image_rmse,
            s.iterations,
            s.wall_s,
            // Microseconds: a tiny problem's iteration can take well under a millisecond.
            parts.map(|x| format!("{x:.6}")).join(",")
        );
        let na = |x: String| if x.is_empty() { "n/a".into() } else { x };
        let (pe, last, tol) = (na(pe), na(last), na(tol));
        let _ = writeln!(
            md,
            "| {name} | {m} | {seed} | {pe} | {last} | {tol} | {solved} | {:.5} | {} | {:.1} | {} |",
            s.image_rmse,
            s.iterations,
            s.wall_s,
            parts.map(|x| format!("{x:.3}")).join(" | ")
        );
    }
    write_atomic(&out.join("compare.csv"), csv.as_bytes())?;
    let refs: Vec<(String, &Summary)> = runs.iter().map(|(m, s)| (m.clone(), s)).collect();
    let mut strip = runs
        .first()
        .map(|(_, s)| start_images(s))
        .unwrap_or_default();
    strip.extend(runs.iter().map(|(m, s)| Thumb {
        label: format!("{m} final"),
        image: s.last.clone(),
    }));
    let methods: Vec<&str> = runs.iter().map(|(m, _)| m.as_str()).collect();
    let figure = Figure {
        title: format!("{name}: {}", methods.join(" vs ")),
        panels: &panels(&refs),
        strip: &strip,
    };
    plot_figure(&out.join("compare.png"), &figure)?;
    if args.markdown {
        print!("{md}");
    } else {
        print!("{csv}");
    }
    Ok(())
}
