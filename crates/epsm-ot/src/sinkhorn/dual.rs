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
use crate::kernel::{RowSum, exp_nonpositive, stream_row};
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
        Self { cloud: &c.cloud, ranges: c.ranges(), log_w: vec![-(n as f32).ln(); n] }
    }
}

/// The centroid cloud of a clustering and its log-weights.
fn coarse_cloud(c: &Clustered) -> (PointCloud, Vec<f32>) {
    let n = c.cloud.len() as f32;
    let columns = std::array::from_fn(|d| c.clusters.iter().map(|k| k.centroid[d] as f32).collect());
    let log_w = c.clusters.iter().map(|k| (k.range.len() as f32 / n).ln()).collect();
    (PointCloud::from_trusted_columns(columns), log_w)
}

/// Dual potentials of one entropic problem, in the clusterings' orders.
#[derive(Debug, Clone)]
pub(crate) struct Dual {
    pub f: Vec<f32>,
    pub g: Vec<f32>,
    pub eps: f64,
    pub support: Support,
    pub iterations: usize,
    pub pairs: u64,
    pub marginal_error: f64,
}

/// `h_j = log w_j + g_j / ε`.
fn offsets(log_w: &[f32], g: &[f32], eps: f64) -> Vec<f32> {
    let inv = 1.0 / eps;
    log_w.iter().zip(g).map(|(&w, &g)| (f64::from(w) + f64::from(g) * inv) as f32).collect()
}

/// `out_i = −ε log Σ_j exp(h_j − c(x_i, y_j)/ε)` over the listed blocks, with the pair count.
fn softmin(x: &Level, y: &Level, lists: &[Vec<u32>], h: &[f32], eps: f64) -> (Vec<f32>, u64) {
    let inv_eps = (1.0 / eps) as f32;
    let cols = y.cloud.columns();
    let parts: Vec<(Vec<f32>, u64)> = x
        .ranges
        .par_iter()
        .zip(lists)
        .map(|(rows, list)| {
            let mut pairs = 0;
            let out = rows
                .clone()
                .map(|i| {
                    let mut acc = RowSum::new();
                    let blocks = list.iter().map(|&j| y.ranges[j as usize].clone());
                    pairs += stream_row::<false>(&x.cloud.point(i), cols, h, inv_eps, blocks, &mut acc);
                    (-eps * acc.log_sum()) as f32
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
    fn support(&self, f: &[f32], g: &[f32], eps: f64) -> Support {
        let widen = |v: &[f32]| v.iter().map(|&t| f64::from(t)).collect::<Vec<_>>();
        let fit_f = fit_potentials(self.x, &widen(f));
        let fit_g = fit_potentials(self.y, &widen(g));
        Support::truncated(self.x, &fit_f, self.y, &fit_g, self.settings.truncation * eps)
    }

    fn symmetric_step(&mut self, xl: &Level, yl: &Level, sup: &Support, f: &mut [f32], g: &mut [f32], eps: f64) {
        let (ft, p1) = softmin(xl, yl, &sup.rows, &offsets(&yl.log_w, g, eps), eps);
        let (gt, p2) = softmin(yl, xl, &sup.cols, &offsets(&xl.log_w, f, eps), eps);
        f.iter_mut().zip(&ft).for_each(|(a, b)| *a = 0.5 * (*a + b));
        g.iter_mut().zip(&gt).for_each(|(a, b)| *a = 0.5 * (*a + b));
        self.pairs += p1 + p2;
        self.iterations += 1;
    }
}

/// Runs the whole ε-scaling loop for the source `x` and target `y`.
pub(crate) fn solve_dual(x: &Clustered, y: &Clustered, diameter_sq: f64, settings: &SinkhornSettings) -> Dual {
    let eps_list = schedule(diameter_sq, settings.blur, settings.scaling);
    let mut lp = Loop { x, y, settings, pairs: 0, iterations: 0 };

    // Coarse phase: dense Sinkhorn on cluster centroids.
    let (cx_cloud, cx_w) = coarse_cloud(x);
    let (cy_cloud, cy_w) = coarse_cloud(y);
    let cx = Level { cloud: &cx_cloud, ranges: vec![0..cx_w.len()], log_w: cx_w };
    let cy = Level { cloud: &cy_cloud, ranges: vec![0..cy_w.len()], log_w: cy_w };
    let whole = Support::dense(1, 1);
    let radius = |c: &Clustered| c.clusters.iter().map(|k| k.radius * k.range.len() as f64).sum::<f64>() / c.cloud.len() as f64;
    let jump_eps = (settings.jump_radii * radius(x).max(radius(y))).powi(2);
    let eps0 = eps_list[0];
    let (mut fc, p1) = softmin(&cx, &cy, &whole.rows, &cy.log_w, eps0);
    let (mut gc, p2) = softmin(&cy, &cx, &whole.cols, &cx.log_w, eps0);
    lp.pairs += p1 + p2;
    let mut k = 1;
    while k < eps_list.len() && eps_list[k] > jump_eps {
        lp.symmetric_step(&cx, &cy, &whole, &mut fc, &mut gc, eps_list[k]);
        k += 1;
    }

    // Jump: extrapolate fine potentials from the coarse ones.
    let eps_jump = eps_list[k - 1];
    let (fx, fy) = (Level::fine(x), Level::fine(y));
    let to_coarse = |n: usize| vec![vec![0u32]; n];
    let (mut f, p1) = softmin(&fx, &cy, &to_coarse(fx.ranges.len()), &offsets(&cy.log_w, &gc, eps_jump), eps_jump);
    let (mut g, p2) = softmin(&fy, &cx, &to_coarse(fy.ranges.len()), &offsets(&cx.log_w, &fc, eps_jump), eps_jump);
    lp.pairs += p1 + p2;

    // Fine phase: truncated symmetric updates down the rest of the schedule.
    for &eps in &eps_list[k..] {
        let sup = lp.support(&f, &g, eps);
        lp.symmetric_step(&fx, &fy, &sup, &mut f, &mut g, eps);
    }

    // Polish: alternating updates at the final ε until the source marginal is within tolerance.
    let eps = settings.blur * settings.blur;
    let mut support = lp.support(&f, &g, eps);
    let mut marginal_error = f64::INFINITY;
    for _ in 0..settings.max_polish_iterations {
        let (gn, p1) = softmin(&fy, &fx, &support.cols, &offsets(&fx.log_w, &f, eps), eps);
        g = gn;
        let (ft, p2) = softmin(&fx, &fy, &support.rows, &offsets(&fy.log_w, &g, eps), eps);
        lp.pairs += p1 + p2;
        lp.iterations += 1;
        marginal_error = row_marginal_error(&f, &ft, eps);
        if marginal_error <= settings.marginal_tolerance {
            break;
        }
        f = ft;
        support = lp.support(&f, &g, eps);
    }
    Dual { f, g, eps, support, iterations: lp.iterations, pairs: lp.pairs, marginal_error }
}

/// `Σ_i a_i |exp((f_i − f̃_i)/ε) − 1|` with uniform `a_i`, summed in fixed chunks for determinism.
fn row_marginal_error(f: &[f32], ft: &[f32], eps: f64) -> f64 {
    let n = f.len() as f64;
    let parts: Vec<f64> = f
        .par_chunks(4096)
        .zip(ft.par_chunks(4096))
        .map(|(a, b)| {
            a.iter()
                .zip(b)
                .map(|(&fa, &fb)| {
                    let d = (f64::from(fa) - f64::from(fb)) / eps;
                    if d <= 0.0 { 1.0 - f64::from(exp_nonpositive(d as f32)) } else { d.exp() - 1.0 }
                })
                .sum::<f64>()
        })
        .collect();
    parts.iter().sum::<f64>() / n
}

/// Per-source-point barycentre `Σ_j π_ij y_j / Σ_j π_ij` and mean cost, in the clustered order.
pub(crate) fn barycentres(x: &Clustered, y: &Clustered, dual: &Dual) -> (Vec<[f32; 5]>, Vec<f64>, u64) {
    let (fx, fy) = (Level::fine(x), Level::fine(y));
    let h = offsets(&fy.log_w, &dual.g, dual.eps);
    let inv_eps = (1.0 / dual.eps) as f32;
    let cols = y.cloud.columns();
    let parts: Vec<(Vec<([f32; 5], f64)>, u64)> = fx
        .ranges
        .par_iter()
        .zip(&dual.support.rows)
        .map(|(rows, list)| {
            let mut pairs = 0;
            let out = rows
                .clone()
                .map(|i| {
                    let mut acc = RowSum::new();
                    let blocks = list.iter().map(|&j| fy.ranges[j as usize].clone());
                    pairs += stream_row::<true>(&x.cloud.point(i), cols, &h, inv_eps, blocks, &mut acc);
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
