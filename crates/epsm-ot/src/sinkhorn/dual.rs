//! The ε-scaling loop that computes Sinkhorn dual potentials, multiscale and truncated.
//!
//! Named steps, following GeomLoss's `sinkhorn_loop`:
//! 1. **Coarse phase**: clusters become weighted points (their centroids) and
//!    the symmetric updates `f ← ½(f + softmin(g))`, `g ← ½(g + softmin(f))`
//!    run densely on them while `ε` is larger than the squared cluster scale.
//! 2. **Jump**: fine potentials are extrapolated from the coarse ones with one
//!    softmin pass of fine points against the coarse measure.
//! 3. **Fine phase**: the remaining scales run on the points, on the block
//!    support whose reduced-cost bound is at most `truncation · ε` (built
//!    once per scale: refreshing it before every update gave the same plans
//!    and cost 4 % more time at n = 16384), each point streaming only the
//!    kept blocks that its own bounds on `c_ij − f_i − g_j` keep (`pass::Cut`,
//!    `clusters::PointCut`: 36 % fewer pairs at n = 16384, 37 % at 65536,
//!    with a ball bound; its box bound takes 13 % more off at 16384),
//!    with over-relaxed updates (ω = `annealing_overrelaxation`). A scale
//!    opens with a target update at its ε whose pass also sums the plan per
//!    block pair, followed by the two-grid correction of `coarse` (exact
//!    cluster marginals); source and target updates then alternate, the
//!    target half of every `coarse_period`-th update corrected too, and the
//!    scale ends on the source update that brings its marginal error to at
//!    most `scale_tolerance`. No pass is spent on a correction alone (a
//!    correction pass before each scale's first update had cost 21 % of the
//!    pairs at n = 65536). The last scale (`ε = blur²`) continues to
//!    `min(scale_tolerance, 4 · marginal_tolerance)` before handing over to
//!    the polish.
//! 4. **Polish** (`polish.rs`): full updates `g ← softmin(f)`, `f̃ ← softmin(g)` at the final
//!    `ε`, Anderson-accelerated on `f` (see `anderson`; memory
//!    `anderson_memory`, mixing `overrelaxation`), until the L1 error of the
//!    source marginal is at most the tolerance (the target marginal is exact
//!    after each `g` update; a NaN error is never within it, see [`converged`]).
//!    Anderson removes the slow large-scale modes that
//!    made over-relaxed Sinkhorn need ~200 updates at blur 0.01; if an
//!    extrapolated step blows the error up (×10 over the best) the history is
//!    dropped and the loop restarts from the best iterate. A polish that runs
//!    out of updates first, or stalls (its smallest error falls too slowly to
//!    reach the tolerance within the updates left, even `stall_margin` times
//!    faster; see `polish::stalled`), ends on one more target update, and the caller
//!    counts it (`SolveStats::unconverged_solves`) or, for a non-finite
//!    error, fails (`OtError::NotConverged`).

use rayon::prelude::*;

use super::SinkhornSettings;
use super::coarse;
use super::pass::{Cut, Level, coarse_cloud, softmin, softmin_blocks};
use super::polish::polish;
use crate::clusters::{Clustered, Support, fit_potentials};
use crate::plan::{PhaseTimes, SolveStats};

/// Dual potentials of one entropic problem, in the clusterings' orders.
#[derive(Debug, Clone)]
pub(crate) struct Dual {
    pub f: Vec<f64>,
    pub g: Vec<f64>,
    pub eps: f64,
    pub support: Support,
    pub iterations: usize,
    pub pairs: u64,
    pub marginal_error: f64,
    /// What the safeguards of the fine phase (or of the exact solve replacing it) did.
    pub guards: Guards,
    /// Wall-clock time of the coarse, fine and polish phases.
    pub phases: PhaseTimes,
}

/// Counts of the safeguards of the fine phase, or of the exact solve that
/// replaces it with `exact_prices`.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub(crate) struct Guards {
    /// Coarse corrections whose cluster scaling converged only with bridges between
    /// the support's components (each followed by a rebuild of the scale's support; see `coarse`).
    pub bridged_corrections: usize,
    /// Coarse corrections whose cluster scaling did not converge even with bridges,
    /// applied clamped (each followed by a rebuild of the scale's support).
    pub clamped_corrections: usize,
    /// Auctions of the exact solve stopped by their bid budget (see `exact`).
    pub auction_budget_stops: usize,
    /// Exact solves whose entropic warm start was replaced by the cold start (see `exact`).
    pub cold_starts: usize,
}

impl Guards {
    /// The exact solve's counts from its `stats`.
    pub fn of_exact(stats: &SolveStats) -> Self {
        Self {
            auction_budget_stops: stats.auction_budget_stops,
            cold_starts: stats.cold_starts,
            ..Self::default()
        }
    }

    /// Adds these counts to the counters of the same names in `stats`.
    pub fn add_to(self, stats: &mut SolveStats) {
        stats.bridged_corrections += self.bridged_corrections;
        stats.clamped_corrections += self.clamped_corrections;
        stats.auction_budget_stops += self.auction_budget_stops;
        stats.cold_starts += self.cold_starts;
    }
}

/// The ε schedule of GeomLoss: `diameter²` down to `blur²` with ratio `scaling²`.
pub(crate) fn schedule(diameter_sq: f64, blur: f64, scaling: f64) -> Vec<f64> {
    let last = blur * blur;
    let first = diameter_sq.max(last);
    let mut list = vec![first];
    let mut eps = first;
    while eps * scaling * scaling > last {
        eps *= scaling * scaling;
        list.push(eps);
    }
    list.push(last);
    list
}

/// What the phases of the loop share: the clouds, the settings and the
/// work done so far.
pub(super) struct Loop<'a> {
    pub(super) x: &'a Clustered,
    pub(super) y: &'a Clustered,
    pub(super) settings: &'a SinkhornSettings,
    pub(super) pairs: u64,
    pub(super) iterations: usize,
    pub(super) guards: Guards,
}

impl Loop<'_> {
    /// The block pairs whose reduced-cost bound for `f, g` is at most `threshold`.
    pub(super) fn support(&self, f: &[f64], g: &[f64], threshold: f64) -> Support {
        let (fit_f, fit_g) = (fit_potentials(self.x, f), fit_potentials(self.y, g));
        Support::truncated(self.x, &fit_f, self.y, &fit_g, threshold)
    }

    /// One Sinkhorn update: `f ← softmin(g)`, then `g ← softmin(f)`.
    fn step(
        &mut self,
        xl: &Level,
        yl: &Level,
        sup: &Support,
        f: &mut Vec<f64>,
        g: &mut Vec<f64>,
        eps: f64,
    ) {
        let (ft, p1) = softmin(xl, yl, &sup.rows, g, eps, None);
        *f = ft;
        let (gt, p2) = softmin(yl, xl, &sup.cols, f, eps, None);
        *g = gt;
        self.pairs += p1 + p2;
        self.iterations += 1;
    }

    /// Step 3 at one scale, on one support built from the potentials at entry: a corrected
    /// target update, then source updates (ending the scale once the source marginal error is
    /// at most `tolerance`, or after `max_scale_iterations`) alternating with target updates,
    /// corrected after every `coarse_period`-th (see `coarse`).
    fn fine_scale(
        &mut self,
        fx: &Level,
        fy: &Level,
        f: &mut [f64],
        g: &mut [f64],
        eps: f64,
        tolerance: f64,
    ) {
        let settings = self.settings;
        let omega = settings.annealing_overrelaxation;
        let period = settings.coarse_period;
        // Support and per-point cut keep reduced costs up to `threshold`.
        let threshold = settings.truncation * eps;
        let mut sup = self.support(f, g, threshold);
        let g_half = |sup: &Support, f: &mut [f64], g: &mut [f64], correct: bool| {
            let cut = Some(Cut { own: g, threshold });
            if correct {
                // The target update also gives the block masses; correct before the next source update.
                let next = |j: usize, t: f64| g[j] + omega * (t - g[j]);
                let pass = softmin_blocks(fy, fx, &sup.cols, f, eps, next, cut);
                relax(g, &pass.softmin, omega);
                let outcome = coarse::correct(
                    fy,
                    fx,
                    &sup.cols,
                    &pass.log_masses,
                    g,
                    f,
                    eps,
                    settings.truncation,
                );
                (pass.pairs, Some(outcome))
            } else {
                let (gt, pairs) = softmin(fy, fx, &sup.cols, f, eps, cut);
                relax(g, &gt, omega);
                (pairs, None)
            }
        };
        // ε changed: the scale opens with a target update, corrected (the previous scale
        // ended on a source update).
        let (pairs, mut outcome) = g_half(&sup, f, g, period > 0);
        self.pairs += pairs;
        for it in 1..=settings.max_scale_iterations {
            let count = match outcome {
                Some(coarse::Correction::Bridged { .. }) => {
                    Some(&mut self.guards.bridged_corrections)
                }
                Some(coarse::Correction::Clamped) => Some(&mut self.guards.clamped_corrections),
                _ => None,
            };
            if let Some(count) = count {
                // The support could not carry the cluster marginals; the shift moved the
                // clusters that lacked mass towards pairs outside it: rebuild it from the
                // shifted potentials.
                *count += 1;
                sup = self.support(f, g, threshold);
            }
            let (ft, pairs) = softmin(fx, fy, &sup.rows, g, eps, Some(Cut { own: f, threshold }));
            let err = row_marginal_error(f, &ft, eps);
            relax(f, &ft, omega);
            self.pairs += pairs;
            self.iterations += 1;
            if converged(err, tolerance) || it == settings.max_scale_iterations {
                break;
            }
            let (pairs, next) = g_half(&sup, f, g, period > 0 && it % period == 0);
            self.pairs += pairs;
            outcome = next;
        }
    }
}

/// The last scale of the fine phase hands over to the polish once its marginal
/// error is below this many `marginal_tolerance`s: corrected updates halve the
/// error per update down to a few 1e-3, below which the Anderson polish is faster.
const POLISH_HANDOFF: f64 = 4.0;

/// Potentials after the coarse phase and the jump, and where the schedule resumes.
struct Coarse {
    f: Vec<f64>,
    g: Vec<f64>,
    eps_list: Vec<f64>,
    next: usize,
    pairs: u64,
    iterations: usize,
}

/// Steps 1 and 2 of the module doc: the coarse phase and the jump to the points.
fn coarse_phase(
    x: &Clustered,
    y: &Clustered,
    diameter_sq: f64,
    settings: &SinkhornSettings,
) -> Coarse {
    let eps_list = schedule(diameter_sq, settings.blur, settings.scaling);
    let mut lp = Loop {
        x,
        y,
        settings,
        pairs: 0,
        iterations: 0,
        guards: Guards::default(),
    };
    let (cx_cloud, cx_w) = coarse_cloud(x);
    let (cy_cloud, cy_w) = coarse_cloud(y);
    let cx = Level {
        cloud: &cx_cloud,
        ranges: std::iter::once(0..cx_w.len()).collect(),
        log_w: cx_w,
        clustered: None,
    };
    let cy = Level {
        cloud: &cy_cloud,
        ranges: std::iter::once(0..cy_w.len()).collect(),
        log_w: cy_w,
        clustered: None,
    };
    let whole = Support::dense(1, 1);
    let radius = |c: &Clustered| {
        c.clusters
            .iter()
            .map(|k| k.radius * k.range.len() as f64)
            .sum::<f64>()
            / c.cloud.len() as f64
    };
    let jump_eps = (settings.jump_radii * radius(x).max(radius(y))).powi(2);
    let (mut fc, mut gc) = (vec![0.0; cx.log_w.len()], vec![0.0; cy.log_w.len()]);
    let mut k = 0;
    while k == 0 || (k < eps_list.len() && eps_list[k] > jump_eps) {
        lp.step(&cx, &cy, &whole, &mut fc, &mut gc, eps_list[k]);
        k += 1;
    }
    let eps_jump = eps_list[k - 1];
    let (fx, fy) = (Level::fine(x), Level::fine(y));
    let to_coarse = |n: usize| vec![vec![0u32]; n];
    let (f, p1) = softmin(&fx, &cy, &to_coarse(fx.ranges.len()), &gc, eps_jump, None);
    let (g, p2) = softmin(&fy, &cx, &to_coarse(fy.ranges.len()), &fc, eps_jump, None);
    Coarse {
        f,
        g,
        eps_list,
        next: k,
        pairs: lp.pairs + p1 + p2,
        iterations: lp.iterations,
    }
}

/// Runs the whole ε-scaling loop for the source `x` and target `y`.
pub(crate) fn solve_dual(
    x: &Clustered,
    y: &Clustered,
    diameter_sq: f64,
    settings: &SinkhornSettings,
) -> Dual {
    let mut phases = PhaseTimes::default();
    let Coarse {
        mut f,
        mut g,
        eps_list,
        next,
        pairs,
        iterations,
    } = phases.time("coarse", || coarse_phase(x, y, diameter_sq, settings));
    let mut lp = Loop {
        x,
        y,
        settings,
        pairs,
        iterations,
        guards: Guards::default(),
    };
    let (fx, fy) = (Level::fine(x), Level::fine(y));

    // Fine phase: truncated, over-relaxed, coarse-corrected updates at each remaining scale.
    let fine_start = std::time::Instant::now();
    for (k, &eps) in eps_list.iter().enumerate().skip(next) {
        let tolerance = if k + 1 == eps_list.len() {
            settings
                .scale_tolerance
                .min(POLISH_HANDOFF * settings.marginal_tolerance)
        } else {
            settings.scale_tolerance
        };
        lp.fine_scale(&fx, &fy, &mut f, &mut g, eps, tolerance);
    }
    phases.add("fine", fine_start.elapsed().as_secs_f64());
    let mut dual = polish(x, y, f, g, settings, lp.pairs, lp.iterations);
    dual.guards = lp.guards;
    phases.merge(&dual.phases);
    dual.phases = phases;
    dual
}

/// Whether a marginal `error` meets `tolerance`. NaN never does: a NaN error is
/// "not converged" everywhere (`NaN > tolerance` is false too, so a test written
/// as "above tolerance" would take a NaN for converged).
pub(crate) fn converged(error: f64, tolerance: f64) -> bool {
    error <= tolerance
}

/// Over-relaxed update `p ← (1 − ω) p + ω p̃` (Thibault et al. 2017; ω = 1 is plain Sinkhorn).
fn relax(p: &mut [f64], target: &[f64], omega: f64) {
    p.iter_mut()
        .zip(target)
        .for_each(|(a, &b)| *a += omega * (b - *a));
}

/// `Σ_i a_i |exp((f_i − f̃_i)/ε) − 1|` with uniform `a_i`, summed in fixed chunks for determinism.
pub(super) fn row_marginal_error(f: &[f64], ft: &[f64], eps: f64) -> f64 {
    let n = f.len() as f64;
    let parts: Vec<f64> = f
        .par_chunks(4096)
        .zip(ft.par_chunks(4096))
        .map(|(a, b)| {
            a.iter()
                .zip(b)
                .map(|(&fa, &fb)| ((fa - fb) / eps).exp_m1().abs())
                .sum::<f64>()
        })
        .collect();
    parts.iter().sum::<f64>() / n
}
