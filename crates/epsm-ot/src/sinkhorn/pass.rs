//! One kernel pass over a block support: softmin updates, block masses and barycentres.
//!
//! A pass streams, for every point of one measure, the listed target blocks
//! (consecutive blocks merged into one range) through `kernel::stream_row`,
//! in parallel over source blocks with a fixed partition, so results do not
//! depend on the number of threads.

use std::ops::Range;

use rayon::prelude::*;

use super::dual::Dual;
use crate::blocks::Clustered;
use crate::kernel::{BlockSums, RowSum, stream_blocks, stream_row};
use crate::points::{Point, PointCloud};

/// A measure as the kernel sees it: points, their blocks and log-weights.
pub(super) struct Level<'a> {
    pub cloud: &'a PointCloud,
    pub ranges: Vec<Range<usize>>,
    pub log_w: Vec<f32>,
}

impl<'a> Level<'a> {
    pub(super) fn fine(c: &'a Clustered) -> Self {
        let n = c.cloud.len();
        Self {
            cloud: &c.cloud,
            ranges: c.ranges(),
            log_w: vec![-(n as f32).ln(); n],
        }
    }
}

/// The centroid cloud of a clustering and its log-weights.
pub(super) fn coarse_cloud(c: &Clustered) -> (PointCloud, Vec<f32>) {
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
pub(super) fn softmin(
    x: &Level,
    y: &Level,
    lists: &[Vec<u32>],
    g: &[f64],
    eps: f64,
) -> (Vec<f64>, u64) {
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
                    pairs += stream_row::<false>(
                        &x.cloud.point(i),
                        cols,
                        &y.log_w,
                        &g32,
                        inv_eps,
                        &targets,
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
    let parts: Vec<(Vec<(Point, f64)>, u64)> = fx
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
                    pairs += stream_row::<true>(
                        &x.cloud.point(i),
                        cols,
                        &fy.log_w,
                        &g32,
                        inv_eps,
                        &targets,
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

/// A softmin pass that also returns the plan's mass on every kept block pair.
pub(super) struct BlockPass {
    /// `softmin_i` of [`softmin`].
    pub softmin: Vec<f64>,
    /// `log_masses[I][k] = log Σ_{i∈I, j∈J} a_i b_j exp((f_i + g_j − c_ij)/ε)` for
    /// `J = lists[I][k]`, with `f_i = next(i, softmin_i)`.
    pub log_masses: Vec<Vec<f64>>,
    pub pairs: u64,
}

/// [`softmin`] of `g`, plus the block masses of the plan whose source potential is `next(i, softmin_i)`.
///
/// The kernel sums each target block separately (`kernel::stream_blocks`), so
/// one pass gives both the update and the coarse correction's matrix.
pub(super) fn softmin_blocks(
    x: &Level,
    y: &Level,
    lists: &[Vec<u32>],
    g: &[f64],
    eps: f64,
    next: impl Fn(usize, f64) -> f64 + Sync,
) -> BlockPass {
    let inv_eps = (1.0 / eps) as f32;
    let cols = y.cloud.columns();
    let (g32, kappa) = centred(g);
    let parts: Vec<(Vec<f64>, Vec<f64>, u64)> = x
        .ranges
        .par_iter()
        .zip(lists)
        .map(|(rows, list)| {
            let mut pairs = 0;
            let targets = merged_ranges(&y.ranges, list);
            let lens: Vec<u32> = list
                .iter()
                .map(|&j| y.ranges[j as usize].len() as u32)
                .collect();
            let total: usize = targets.iter().map(Range::len).sum();
            let mut scores = vec![0.0f32; total.div_ceil(16) * 16];
            let mut block = vec![0.0f32; list.len()];
            // Block masses relative to one shared reference `exp(top)`, rescaled when it grows.
            let mut masses = vec![0.0f64; list.len()];
            let mut top = f64::NEG_INFINITY;
            let mut out = Vec::with_capacity(rows.len());
            for i in rows.clone() {
                let mut row = BlockSums {
                    lens: &lens,
                    scores: &mut scores,
                    out: &mut block,
                    max: f32::NEG_INFINITY,
                };
                pairs += stream_blocks(
                    &x.cloud.point(i),
                    cols,
                    &y.log_w,
                    &g32,
                    inv_eps,
                    &targets,
                    &mut row,
                );
                let row_max = f64::from(row.max);
                let empty = row.max == f32::NEG_INFINITY;
                let row_sum: f64 = block.iter().map(|&b| f64::from(b)).sum();
                let softmin = -kappa - eps * (row_max + row_sum.ln());
                out.push(softmin);
                if empty {
                    continue;
                }
                let v = f64::from(x.log_w[i]) + (next(i, softmin) + kappa) / eps + row_max;
                if v > top {
                    let s = (top - v).exp();
                    masses.iter_mut().for_each(|t| *t *= s);
                    top = v;
                }
                let scale = (v - top).exp();
                for (t, &b) in masses.iter_mut().zip(&block) {
                    *t += scale * f64::from(b);
                }
            }
            let log_masses = masses.iter().map(|&t| top + t.ln()).collect();
            (out, log_masses, pairs)
        })
        .collect();
    let pairs = parts.iter().map(|p| p.2).sum();
    let (softmin, log_masses) = parts
        .into_iter()
        .map(|p| (p.0, p.1))
        .unzip::<_, _, Vec<_>, _>();
    BlockPass {
        softmin: softmin.into_iter().flatten().collect(),
        log_masses,
        pairs,
    }
}

/// Running `log Σ exp(v)` in `f64`.
#[derive(Debug, Clone, Copy)]
pub(super) struct LogSum {
    max: f64,
    sum: f64,
}

impl Default for LogSum {
    fn default() -> Self {
        Self {
            max: f64::NEG_INFINITY,
            sum: 0.0,
        }
    }
}

impl LogSum {
    pub(super) fn push(&mut self, v: f64) {
        if v > self.max {
            self.sum = self.sum * (self.max - v).exp() + 1.0;
            self.max = v;
        } else if v > f64::NEG_INFINITY {
            self.sum += (v - self.max).exp();
        }
    }

    pub(super) fn value(&self) -> f64 {
        self.max + self.sum.ln()
    }
}
