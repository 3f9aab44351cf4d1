//! The ε-scaling loop that computes Sinkhorn dual potentials, multiscale and truncated.
//!
//! Named steps, following GeomLoss's `sinkhorn_loop`:
//! 1. **Coarse phase**: clusters become weighted points (their centroids) and
//!    the symmetric updates `f ← ½(f + softmin(g))`, `g ← ½(g + softmin(f))`
//!    run densely on them while `ε` is larger than the squared cluster scale.
//! 2. **Jump**: fine potentials are extrapolated from the coarse ones with one
//!    softmin pass of fine points against the coarse measure.
//! 3. **Fine phase**: the remaining scales run on the points, on the block
//!    support whose reduced-cost bound is at most `truncation · ε` (refreshed
//!    at every update).
//! 4. **Polish**: alternating updates at the final `ε` until the L1 error of
//!    the source marginal is at most the tolerance (the target marginal is
//!    exact after each `g` update).

use std::ops::Range;

use rayon::prelude::*;

use super::SinkhornSettings;
use crate::blocks::{Clustered, Support, fit_potentials};
use crate::kernel::{RowSum, stream_row};
use crate::points::PointCloud;

/// A measure as the kernel sees it: points, their blocks and log-weights.
struct Level<'a> {
    cloud: &'a PointCloud,
    ranges: Vec<Range<usize>>,
    log_w: Vec<f32>,
}

impl<'a> Level<'a> {
    fn fine(c: &'a Clustered) -> Self {
        let n = c.cloud.len();
        Self {
            cloud: &c.cloud,
            ranges: c.ranges(),
            log_w: vec![-(n as f32).ln(); n],
        }
    }
}

/// The centroid cloud of a clustering and its log-weights.
fn coarse_cloud(c: &Clustered) -> (PointCloud, Vec<f32>) {
    let n = c.cloud.len() as f32;
    let columns =
        std::array::from_fn(|d| c.clusters.iter().map(|k| k.centroid[d] as f32).collect());
    let log_w = c
        .clusters
        .iter()
        .map(|k| (k.range.len() as f32 / n).ln())
        .collect();
    (PointCloud::from_trusted_columns(columns), log_w)
}

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
}

/// A potential shifted by its mean (summed in a fixed order) and rounded to `f32` for the kernel.
///
/// Potentials are only defined up to `f + κ, g − κ`; centring keeps `g_j − c_ij`
/// small where it matters, so `f32` scores stay accurate even at tiny ε.
fn centred(g: &[f64]) -> (Vec<f32>, f64) {
    let kappa = g.iter().sum::<f64>() / g.len() as f64;
    (g.iter().map(|&v| (v - kappa) as f32).collect(), kappa)
}

/// The target ranges of a block list, with consecutive blocks merged into one range.
fn merged_ranges(ranges: &[Range<usize>], list: &[u32]) -> Vec<Range<usize>> {
    let mut out: Vec<Range<usize>> = Vec::with_capacity(list.len());
    for &j in list {
        let r = ranges[j as usize].clone();
        match out.last_mut() {
            Some(last) if last.end == r.start => last.end = r.end,
            _ => out.push(r),
        }
    }
    out
}

/// `out_i = −ε log Σ_j exp(log w_j + (g_j − c(x_i, y_j))/ε)` over the listed blocks, with the pair count.
fn softmin(x: &Level, y: &Level, lists: &[Vec<u32>], g: &[f64], eps: f64) -> (Vec<f64>, u64) {
    let inv_eps = (1.0 / eps) as f32;
    let cols = y.cloud.columns();
    let (g32, kappa) = centred(g);
    let parts: Vec<(Vec<f64>, u64)> = x
        .ranges
        .par_iter()
        .zip(lists)
        .map(|(rows, list)| {
            let mut pairs = 0;
            let targets = merged_ranges(&y.ranges, list);
            let out = rows
                .clone()
                .map(|i| {
                    let mut acc = RowSum::new();
                    let blocks = targets.iter().cloned();
                    pairs += stream_row::<false>(
                        &x.cloud.point(i),
                        cols,
                        &y.log_w,
                        &g32,
                        inv_eps,
                        blocks,
                        &mut acc,
                    );
                    -kappa - eps * acc.log_sum()
                })
                .collect();
            (out, pairs)
        })
        .collect();
    let pairs = parts.iter().map(|p| p.1).sum();
    (parts.into_iter().flat_map(|p| p.0).collect(), pairs)
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

struct Loop<'a> {
    x: &'a Clustered,
    y: &'a Clustered,
    settings: &'a SinkhornSettings,
    pairs: u64,
    iterations: usize,
}

impl Loop<'_> {
    fn support(&self, f: &[f64], g: &[f64], eps: f64) -> Support {
        let (fit_f, fit_g) = (fit_potentials(self.x, f), fit_potentials(self.y, g));
        Support::truncated(
            self.x,
            &fit_f,
            self.y,
            &fit_g,
            self.settings.truncation * eps,
        )
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
        let (ft, p1) = softmin(xl, yl, &sup.rows, g, eps);
        *f = ft;
        let (gt, p2) = softmin(yl, xl, &sup.cols, f, eps);
        *g = gt;
        self.pairs += p1 + p2;
        self.iterations += 1;
    }
}

/// Runs the whole ε-scaling loop for the source `x` and target `y`.
pub(crate) fn solve_dual(
    x: &Clustered,
    y: &Clustered,
    diameter_sq: f64,
    settings: &SinkhornSettings,
) -> Dual {
    let eps_list = schedule(diameter_sq, settings.blur, settings.scaling);
    let mut lp = Loop {
        x,
        y,
        settings,
        pairs: 0,
        iterations: 0,
    };

    // Coarse phase: dense Sinkhorn on cluster centroids.
    let (cx_cloud, cx_w) = coarse_cloud(x);
    let (cy_cloud, cy_w) = coarse_cloud(y);
    let cx = Level {
        cloud: &cx_cloud,
        ranges: vec![0..cx_w.len()],
        log_w: cx_w,
    };
    let cy = Level {
        cloud: &cy_cloud,
        ranges: vec![0..cy_w.len()],
        log_w: cy_w,
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

    // Jump: extrapolate fine potentials from the coarse ones.
    let eps_jump = eps_list[k - 1];
    let (fx, fy) = (Level::fine(x), Level::fine(y));
    let to_coarse = |n: usize| vec![vec![0u32]; n];
    let (mut f, p1) = softmin(&fx, &cy, &to_coarse(fx.ranges.len()), &gc, eps_jump);
    let (mut g, p2) = softmin(&fy, &cx, &to_coarse(fy.ranges.len()), &fc, eps_jump);
    lp.pairs += p1 + p2;

    // Fine phase: truncated updates down the rest of the schedule.
    for &eps in &eps_list[k..] {
        let sup = lp.support(&f, &g, eps);
        lp.step(&fx, &fy, &sup, &mut f, &mut g, eps);
    }

    // Polish: over-relaxed updates at the final ε until the source marginal is within tolerance.
    let eps = settings.blur * settings.blur;
    let mut omega = settings.overrelaxation;
    let mut support = lp.support(&f, &g, eps);
    let mut marginal_error = f64::INFINITY;
    let mut best_error = f64::INFINITY;
    for round in 0..settings.max_polish_iterations {
        let (ft, pairs) = softmin(&fx, &fy, &support.rows, &g, eps);
        lp.pairs += pairs;
        marginal_error = row_marginal_error(&f, &ft, eps);
        if marginal_error <= settings.marginal_tolerance {
            break;
        }
        // Safeguard: back off toward plain Sinkhorn (ω = 1) if the error blows up.
        if !marginal_error.is_finite() || marginal_error > 10.0 * best_error {
            omega = 1.0 + 0.5 * (omega - 1.0);
        }
        best_error = best_error.min(marginal_error);
        relax(&mut f, &ft, omega);
        let (gt, pairs) = softmin(&fy, &fx, &support.cols, &f, eps);
        relax(&mut g, &gt, omega);
        lp.pairs += pairs;
        lp.iterations += 1;
        if round % SUPPORT_REFRESH == SUPPORT_REFRESH - 1 {
            support = lp.support(&f, &g, eps);
        }
    }
    // Leave the target marginal exact: one plain g update on the final f.
    let (gt, pairs) = softmin(&fy, &fx, &support.cols, &f, eps);
    lp.pairs += pairs;
    g = gt;
    Dual {
        f,
        g,
        eps,
        support,
        iterations: lp.iterations,
        pairs: lp.pairs,
        marginal_error,
    }
}

/// Polish iterations between two refreshes of the truncated support.
const SUPPORT_REFRESH: usize = 8;

/// Over-relaxed update `p ← (1 − ω) p + ω p̃` (Thibault et al. 2017; ω = 1 is plain Sinkhorn).
fn relax(p: &mut [f64], target: &[f64], omega: f64) {
    p.iter_mut()
        .zip(target)
        .for_each(|(a, &b)| *a += omega * (b - *a));
}

/// `Σ_i a_i |exp((f_i − f̃_i)/ε) − 1|` with uniform `a_i`, summed in fixed chunks for determinism.
fn row_marginal_error(f: &[f64], ft: &[f64], eps: f64) -> f64 {
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

/// Per-source-point barycentre `Σ_j π_ij y_j / Σ_j π_ij` and mean cost, in the clustered order.
pub(crate) fn barycentres(
    x: &Clustered,
    y: &Clustered,
    dual: &Dual,
) -> (Vec<[f32; 5]>, Vec<f64>, u64) {
    let (fx, fy) = (Level::fine(x), Level::fine(y));
    let (g32, _) = centred(&dual.g);
    let inv_eps = (1.0 / dual.eps) as f32;
    let cols = y.cloud.columns();
    let parts: Vec<(Vec<([f32; 5], f64)>, u64)> = fx
        .ranges
        .par_iter()
        .zip(&dual.support.rows)
        .map(|(rows, list)| {
            let mut pairs = 0;
            let targets = merged_ranges(&fy.ranges, list);
            let out = rows
                .clone()
                .map(|i| {
                    let mut acc = RowSum::new();
                    let blocks = targets.iter().cloned();
                    pairs += stream_row::<true>(
                        &x.cloud.point(i),
                        cols,
                        &fy.log_w,
                        &g32,
                        inv_eps,
                        blocks,
                        &mut acc,
                    );
                    acc.barycentre()
                })
                .collect();
            (out, pairs)
        })
        .collect();
    let pairs = parts.iter().map(|p| p.1).sum();
    let (bary, cost) = parts.into_iter().flat_map(|p| p.0).unzip();
    (bary, cost, pairs)
}
