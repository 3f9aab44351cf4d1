//! `epsm bench iteration`: the seconds of one optimization iteration of a
//! problem and their split into stages, with the pipeline's overlap on and
//! off.
//!
//! ```text
//! epsm bench iteration <PROBLEM> [--iterations N] [--threads N] [--json]
//! ```
//!
//! The problem runs `--iterations` iterations (from its start, with its
//! automatic settings) twice: once with independent stages run one after
//! the other, once overlapped (the recorded trace, the primal render and
//! the judged renders beside the matching; `Optimization::set_overlap`). Both runs follow the same θ bit for bit.
//! Per iteration it reports the mean wall-clock seconds and the mean
//! seconds of each stage (primal render, gradient-pass trace, loss and
//! matching, solves): with overlap the stages add up to more than the wall
//! clock. The first iteration (a cold matching) is reported apart.

use std::path::PathBuf;
use std::time::Instant;

use epsm_core::report::{Timings, mean_timings};
use epsm_core::{Optimization, load_problem};

/// Arguments of `epsm bench iteration`.
#[derive(clap::Args, Debug)]
pub struct IterationBenchArgs {
    /// The problem file (TOML).
    pub problem: PathBuf,
    /// Iterations timed per mode (the first is reported apart).
    #[arg(long, default_value_t = 8)]
    pub iterations: u32,
    /// Worker threads (default: all cores).
    #[arg(long)]
    pub threads: Option<usize>,
    /// Print one JSON object per mode instead of text.
    #[arg(long)]
    pub json: bool,
}

/// The timings of one mode.
struct Measured {
    first_s: f64,
    wall_s: f64,
    stages: Timings,
}

/// Runs `epsm bench iteration`.
pub fn run(args: &IterationBenchArgs) -> anyhow::Result<()> {
    anyhow::ensure!(
        (2..=10_000).contains(&args.iterations),
        "--iterations must be in [2, 10000], got {}",
        args.iterations
    );
    crate::cmd::check_threads(args.threads)?;
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(args.threads.unwrap_or(0))
        .build()?;
    let problem = load_problem(&args.problem)?;
    let (w, h) = (problem.scene.camera.width, problem.scene.camera.height);
    let [mw, mh] = problem.loss.match_resolution;
    for overlap in [false, true] {
        let mut p = problem.clone();
        p.optimizer.iterations = p.optimizer.iterations.max(args.iterations);
        let m = pool.install(|| measure(p, overlap, args.iterations))?;
        let mode = if overlap { "overlapped" } else { "serial" };
        let t = &m.stages;
        if args.json {
            println!(
                "{{\"problem\":{:?},\"mode\":\"{mode}\",\"render\":[{w},{h}],\"match\":[{mw},{mh}],\
                 \"first_s\":{:.4},\"iteration_s\":{:.4},\"primal_s\":{:.4},\"trace_s\":{:.4},\
                 \"matching_s\":{:.4},\"solve_s\":{:.4}}}",
                args.problem.display().to_string(),
                m.first_s,
                m.wall_s,
                t.primal,
                t.trace,
                t.matching,
                t.solve
            );
        } else {
            println!(
                "{} ({w}x{h} render, {mw}x{mh} match), {mode}: {:.4} s per iteration \
                 (first {:.4} s); primal {:.4}, trace {:.4}, matching {:.4}, solves {:.4}",
                args.problem.display(),
                m.wall_s,
                m.first_s,
                t.primal,
                t.trace,
                t.matching,
                t.solve
            );
        }
    }
    Ok(())
}

/// Runs `iterations` iterations of `problem` and averages all but the first.
fn measure(
    problem: epsm_core::Problem,
    overlap: bool,
    iterations: u32,
) -> anyhow::Result<Measured> {
    let mut opt = Optimization::new(problem)?;
    opt.set_overlap(overlap);
    let mut seconds = Vec::with_capacity(iterations as usize);
    for _ in 0..iterations {
        let t0 = Instant::now();
        opt.step()?;
        seconds.push(t0.elapsed().as_secs_f64());
    }
    let later = &seconds[1..];
    Ok(Measured {
        first_s: seconds[0],
        wall_s: later.iter().sum::<f64>() / later.len() as f64,
        stages: mean_timings(&opt.rows()[1..]),
    })
}
