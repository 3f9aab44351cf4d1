//! `epsm bench ot`: time one optimal-transport solve on the synthetic blobs pair.
//!
//! Generates `epsm_ot::synthetic::blobs_pair(n, seed)` (two images of moved,
//! resized and recoloured blobs, points `(r, g, b, x, y)` with λ = 1), solves
//! it with the chosen matcher and prints one human-readable line, or with
//! `--json` exactly one JSON object:
//!
//! | field              | meaning                                                     |
//! |--------------------|-------------------------------------------------------------|
//! | `n`                | points per cloud                                            |
//! | `solver`           | `exact`, `sinkhorn` or `sliced`                             |
//! | `seconds`          | wall time of the solve (fixture generation excluded)        |
//! | `loss`             | the matcher's loss                                          |
//! | `transport_cost`   | primal cost `⟨π, C⟩` (sinkhorn), the loss otherwise         |
//! | `marginal_error`   | L1 source-marginal error (sinkhorn), else null              |
//! | `unconverged_solves` | entropic solves whose polish stopped with the marginal error above its tolerance (sinkhorn) |
//! | `iterations`       | Sinkhorn updates / exact re-solve rounds / projections      |
//! | `pair_evaluations` | kernel or cost evaluations                                  |
//! | `pair_evals_per_s` | `pair_evaluations / seconds` (sinkhorn), else null          |
//! | `bridged_corrections` | coarse corrections whose cluster scaling converged only lumped per component of the support, with bridges between components, before the scale's support was rebuilt (sinkhorn) |
//! | `clamped_corrections` | coarse corrections whose cluster scaling did not converge even lumped, applied clamped before the scale's support was rebuilt (sinkhorn) |
//! | `auction_budget_stops` | auctions stopped by their bid budget, prices used as reached (exact) |
//! | `cold_starts`      | entropic warm starts replaced by zero potentials on all pairs: clouds beyond the warm start's range or non-finite potentials (exact) |
//! | `peak_rss_mb`      | peak resident memory of the process (VmHWM)                 |
//! | `threads`          | rayon threads                                               |
//! | `simd`             | instruction set of the OT kernels: `avx512`, `avx2` or `portable` (`--simd`, default the widest the CPU has) |
//! | `phases`           | seconds per named phase of the solve (see below)            |
//!
//! Phases: `cluster` (grid clustering of both clouds); Sinkhorn: `coarse`
//! (ε-scaling on cluster centroids and the jump to the points), `fine`
//! (truncated updates at the remaining scales), `polish` (final-ε updates to
//! the marginal tolerance), `barycentres`; exact: `warm_start` (the entropic
//! solve), `candidates` (the sparse graph), `auction`, `augment` (shortest
//! augmenting paths), `check` (optimality checks over all pairs), `warm_keep`
//! (what a solve keeps for a warm start, see `epsm_ot::MatchState`).
//!
//! ```text
//! epsm bench ot --n 4096 --solver exact --json
//! ```
//!
//! With `--sequence K` it instead times cold against warm-started solves
//! along a rendered sequence ([`sequence`]).

use std::collections::BTreeMap;
use std::time::Instant;

mod sequence;

use anyhow::{Context, bail};
use epsm_ot::{Matcher, Matching, SinkhornSettings, synthetic};
use serde::Serialize;

/// Which matcher to benchmark.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum OtSolver {
    /// Exact assignment (verified optimal).
    Exact,
    /// Entropic OT (ε-scaling Sinkhorn).
    Sinkhorn,
    /// Approximate sliced OT.
    Sliced,
}

/// An instruction set of the OT kernels (`epsm_ot::Simd`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum OtSimd {
    /// AVX-512 F/BW/DQ/VL (16 lanes).
    Avx512,
    /// AVX2 + FMA (8 lanes).
    Avx2,
    /// Baseline x86-64 (SSE2).
    Portable,
}

impl From<OtSimd> for epsm_ot::Simd {
    fn from(s: OtSimd) -> Self {
        match s {
            OtSimd::Avx512 => Self::Avx512,
            OtSimd::Avx2 => Self::Avx2,
            OtSimd::Portable => Self::Portable,
        }
    }
}

/// Arguments of `epsm bench ot`.
#[derive(Debug, Clone, clap::Args)]
pub struct OtBenchArgs {
    /// Points per cloud (the image side is ⌈√n⌉).
    #[arg(long, default_value_t = 4096)]
    pub n: usize,
    /// Matcher to time.
    #[arg(long, value_enum, default_value_t = OtSolver::Exact)]
    pub solver: OtSolver,
    /// Print exactly one JSON object instead of a human line.
    #[arg(long)]
    pub json: bool,
    /// Seed of the synthetic blobs pair.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Sinkhorn blur (ε = blur²).
    #[arg(long, default_value_t = 0.01)]
    pub blur: f64,
    /// Sinkhorn ratio between successive blurs of the ε-scaling schedule.
    #[arg(long, default_value_t = 0.9)]
    pub scaling: f64,
    /// Force the OT kernels' instruction set (default: the widest the CPU has);
    /// an error when the CPU lacks it.
    #[arg(long, value_enum)]
    pub simd: Option<OtSimd>,
    /// Cold against warm-started matching along a rendered sequence (see `bench_ot::sequence`).
    #[command(flatten)]
    pub sequence: sequence::SequenceArgs,
}

/// One benchmark measurement, as printed with `--json`.
#[derive(Debug, Serialize)]
struct Report {
    n: usize,
    solver: &'static str,
    seconds: f64,
    loss: f64,
    transport_cost: f64,
    marginal_error: Option<f64>,
    unconverged_solves: usize,
    iterations: usize,
    pair_evaluations: u64,
    pair_evals_per_s: Option<f64>,
    bridged_corrections: usize,
    clamped_corrections: usize,
    auction_budget_stops: usize,
    cold_starts: usize,
    peak_rss_mb: Option<f64>,
    threads: usize,
    simd: &'static str,
    phases: BTreeMap<&'static str, f64>,
}

/// Most points per cloud.
const MAX_POINTS: usize = 1 << 22;

/// Runs the benchmark and prints its report.
pub fn run(args: &OtBenchArgs) -> anyhow::Result<()> {
    if !(1..=MAX_POINTS).contains(&args.n) {
        bail!("--n must be in [1, {MAX_POINTS}], got {}", args.n);
    }
    let matcher = match args.solver {
        OtSolver::Exact => Matcher::exact(),
        OtSolver::Sinkhorn => Matcher::Sinkhorn(SinkhornSettings {
            blur: args.blur,
            scaling: args.scaling,
            ..SinkhornSettings::default()
        }),
        OtSolver::Sliced => Matcher::sliced(),
    };
    epsm_ot::force_simd(args.simd.map(Into::into)).context("--simd")?;
    if let Some(steps) = args.sequence.sequence {
        return sequence::run(&args.sequence, steps, args.n, &matcher, args.json);
    }
    let (source, target) =
        synthetic::blobs_pair(args.n, args.seed).context("generating the blobs pair")?;
    let start = Instant::now();
    let result = matcher
        .solve(&source, &target)
        .with_context(|| format!("solving with {}", matcher.name()))?;
    let seconds = start.elapsed().as_secs_f64();
    let (transport_cost, marginal_error) = match &result.matching {
        Matching::Entropic(plan) => (plan.transport_cost, Some(plan.marginal_error)),
        _ => (result.loss, None),
    };
    let pairs = result.stats.pair_evaluations;
    let report = Report {
        n: args.n,
        solver: matcher.name(),
        seconds,
        loss: result.loss,
        transport_cost,
        marginal_error,
        unconverged_solves: result.stats.unconverged_solves,
        iterations: result.stats.iterations,
        pair_evaluations: pairs,
        pair_evals_per_s: (args.solver == OtSolver::Sinkhorn).then(|| pairs as f64 / seconds),
        bridged_corrections: result.stats.bridged_corrections,
        clamped_corrections: result.stats.clamped_corrections,
        auction_budget_stops: result.stats.auction_budget_stops,
        cold_starts: result.stats.cold_starts,
        peak_rss_mb: crate::cmd::peak_rss_mb(),
        threads: rayon::current_num_threads(),
        simd: epsm_ot::active_simd().name(),
        phases: result.stats.phases.iter().collect(),
    };
    if args.json {
        println!("{}", serde_json::to_string(&report)?);
    } else {
        println!(
            "ot {} n={} {:.3}s loss={:.6} cost={:.6} marginal_error={} pairs/s={} cold_starts={} simd={} peak={} MB",
            report.solver,
            report.n,
            report.seconds,
            report.loss,
            report.transport_cost,
            report
                .marginal_error
                .map_or("-".into(), |e| format!("{e:.2e}")),
            report
                .pair_evals_per_s
                .map_or("-".into(), |p| format!("{p:.3e}")),
            report.cold_starts,
            report.simd,
            report.peak_rss_mb.map_or("?".into(), |m| format!("{m:.1}")),
        );
    }
    Ok(())
}
