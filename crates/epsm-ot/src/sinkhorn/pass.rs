//! One kernel pass over a block support: softmin updates and barycentres.
//!
//! A pass streams, for every point of one measure, the listed target blocks
//! (consecutive blocks merged into one range) through `kernel::stream_row`,
//! in parallel over source blocks with a fixed partition, so results do not
//! depend on the number of threads.

use std::ops::Range;

use rayon::prelude::*;

use super::dual::Dual;
use crate::blocks::Clustered;
use crate::kernel::{RowSum, stream_row};
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
