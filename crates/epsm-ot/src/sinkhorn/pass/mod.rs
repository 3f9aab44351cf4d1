//! One kernel pass over a block support: softmin updates, block masses and barycentres.
//!
//! A pass streams, for every point of one measure, the listed target blocks
//! (consecutive blocks merged into one range) through `softmin::stream_row`,
//! in parallel over source blocks with a fixed partition, so results do not
//! depend on the number of threads. With a [`Cut`], each point streams only
//! the listed blocks its own bound keeps (`clusters::PointCut`): the bounds of
//! every target block are computed once per pass, and each source block copies
//! those of its list into scratch that a worker reuses from block to block
//! (allocating and filling them per source block had been 10 % of the
//! instructions at n = 16384).

use std::ops::Range;

use rayon::prelude::*;

use super::dual::Dual;
use crate::OtError;
use crate::clusters::{Bound, Clustered, PointCut, Selection, fit_potentials};
use crate::points::{Point, PointCloud};
use crate::softmin::{BlockSums, RowSum, stream_blocks, stream_row};

/// A measure as the kernel sees it: points, their blocks and log-weights.
pub(super) struct Level<'a> {
    pub cloud: &'a PointCloud,
    pub ranges: Vec<Range<usize>>,
    pub log_w: Vec<f32>,
    /// The clustering the blocks are the clusters of (points, not centroids): what a [`Cut`] needs.
    pub clustered: Option<&'a Clustered>,
}

impl<'a> Level<'a> {
    pub(super) fn fine(c: &'a Clustered) -> Self {
        let n = c.cloud.len();
        Self {
            cloud: &c.cloud,
            ranges: c.ranges(),
            log_w: vec![-(n as f32).ln(); n],
            clustered: Some(c),
        }
    }
}

/// Per-point kernel truncation of a pass from `x` to `y`: point `i` skips the listed
/// target blocks whose bound on `c_ij − own_i − g_j` exceeds `threshold`.
///
/// Applies where the target level has a clustering (a fine level); a point whose
/// every block would be skipped streams them all.
#[derive(Debug, Clone, Copy)]
pub(super) struct Cut<'a> {
    /// The source potential the truncation is measured with (before the update).
    pub own: &'a [f64],
    /// `truncation · ε`.
    pub threshold: f64,
}

/// A [`Cut`] with the bounds of every target block, made once per pass.
struct Fitted<'a> {
    /// The bounds of all target blocks, in order, for the target potential.
    blocks: PointCut,
    cut: Cut<'a>,
}

impl<'a> Fitted<'a> {
    fn new(y: &Level<'a>, g: &[f64], cut: Option<Cut<'a>>, bound: Bound) -> Option<Self> {
        let (clustered, cut) = (y.clustered?, cut?);
        let all: Vec<u32> = (0..clustered.clusters.len() as u32).collect();
        Some(Self {
            blocks: PointCut::gather(clustered, &fit_potentials(clustered, g), &all, bound),
            cut,
        })
    }
}

/// The target ranges one source block streams, cut per point when the pass has a [`Cut`].
///
/// Scratch reused from source block to source block ([`Self::load`]).
#[derive(Default)]
struct Targets {
    /// The bounds of the listed blocks (with a [`Cut`]).
    cut: PointCut,
    /// Every listed block, for a pass without a cut and for a point whose cut keeps none.
    all: Selection,
    /// The current point's blocks.
    now: Selection,
}

impl Targets {
    /// Loads the blocks of `list`.
    fn load(&mut self, y: &Level, list: &[u32], fitted: Option<&Fitted>) {
        self.all.set_all(&y.ranges, list);
        self.now.copy_from(&self.all);
        if let Some(f) = fitted {
            f.blocks.subset_into(list, &mut self.cut);
        }
    }

    /// Selects the blocks source point `i` at `x` streams: those its cut keeps, or
    /// every block if it keeps none.
    fn point(&mut self, fitted: Option<&Fitted>, i: usize, x: &Point) {
        if let Some(f) = fitted {
            let limit = (f.cut.own[i] + f.cut.threshold) as f32;
            if !self.cut.select(x, limit, &mut self.now) {
                self.now.copy_from(&self.all);
            }
        }
    }

    fn ranges(&self) -> &[Range<usize>] {
        &self.now.ranges
    }

    /// Positions in the list of the blocks streamed for the current point, in increasing
    /// order, into `out`.
    fn kept_into(&self, out: &mut Vec<usize>) {
        self.now.kept_into(out);
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

/// `out_i = −ε log Σ_j exp(log w_j + (g_j − c(x_i, y_j))/ε)` over the listed blocks, with the pair count.
pub(super) fn softmin(
    x: &Level,
    y: &Level,
    lists: &[Vec<u32>],
    g: &[f64],
    eps: f64,
    cut: Option<Cut>,
) -> (Vec<f64>, u64) {
    let inv_eps = (1.0 / eps) as f32;
    let cols = y.cloud.columns();
    let (g32, kappa) = centred(g);
    let fitted = Fitted::new(y, g, cut, Bound::Box);
    let fitted = fitted.as_ref();
    let parts: Vec<(Vec<f64>, u64)> = x
        .ranges
        .par_iter()
        .zip(lists)
        .map_init(Targets::default, |targets, (rows, list)| {
            let mut pairs = 0;
            targets.load(y, list, fitted);
            let out = rows
                .clone()
                .map(|i| {
                    let point = x.cloud.point(i);
                    targets.point(fitted, i, &point);
                    let mut acc = RowSum::new();
                    pairs += stream_row::<false>(
                        &point,
                        cols,
                        &y.log_w,
                        &g32,
                        inv_eps,
                        targets.ranges(),
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

/// The barycentric projection of a plan, per source point in the clustered order.
pub(crate) struct Barycentres {
    /// `Σ_j π_ij y_j / Σ_j π_ij`.
    pub points: Vec<Point>,
    /// The mean cost `Σ_j π_ij c_ij / Σ_j π_ij`.
    pub costs: Vec<f64>,
    /// Kernel pairs evaluated.
    pub pairs: u64,
}

/// Per-source-point barycentre `Σ_j π_ij y_j / Σ_j π_ij` and mean cost, in the clustered order.
///
/// Pairs whose reduced cost bound exceeds `threshold` are cut per point (see [`Cut`]).
/// Fails with [`OtError::EmptyKernelRow`] when a point's row has no mass
/// (`RowSum::barycentre`).
pub(crate) fn barycentres(
    x: &Clustered,
    y: &Clustered,
    dual: &Dual,
    threshold: f64,
) -> Result<Barycentres, OtError> {
    let (fx, fy) = (Level::fine(x), Level::fine(y));
    let (g32, _) = centred(&dual.g);
    let cut = Cut {
        own: &dual.f,
        threshold,
    };
    let fitted = Fitted::new(&fy, &dual.g, Some(cut), Bound::Box);
    let fitted = fitted.as_ref();
    let inv_eps = (1.0 / dual.eps) as f32;
    let cols = y.cloud.columns();
    let parts: Option<Vec<Barycentres>> = fx
        .ranges
        .par_iter()
        .zip(&dual.support.rows)
        .map_init(Targets::default, |targets, (rows, list)| {
            let mut part = Barycentres {
                points: Vec::with_capacity(rows.len()),
                costs: Vec::with_capacity(rows.len()),
                pairs: 0,
            };
            targets.load(&fy, list, fitted);
            for i in rows.clone() {
                let point = x.cloud.point(i);
                targets.point(fitted, i, &point);
                let mut acc = RowSum::new();
                part.pairs += stream_row::<true>(
                    &point,
                    cols,
                    &fy.log_w,
                    &g32,
                    inv_eps,
                    targets.ranges(),
                    &mut acc,
                );
                let (t, c) = acc.barycentre()?;
                part.points.push(t);
                part.costs.push(c);
            }
            Some(part)
        })
        .collect();
    let parts = parts.ok_or(OtError::EmptyKernelRow { eps: dual.eps })?;
    let mut all = Barycentres {
        points: Vec::with_capacity(x.cloud.len()),
        costs: Vec::with_capacity(x.cloud.len()),
        pairs: 0,
    };
    for part in parts {
        all.points.extend(part.points);
        all.costs.extend(part.costs);
        all.pairs += part.pairs;
    }
    Ok(all)
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
/// The kernel sums each target block separately (`softmin::stream_blocks`), so
/// one pass gives both the update and the coarse correction's matrix.
pub(super) fn softmin_blocks(
    x: &Level,
    y: &Level,
    lists: &[Vec<u32>],
    g: &[f64],
    eps: f64,
    next: impl Fn(usize, f64) -> f64 + Sync,
    cut: Option<Cut>,
) -> BlockPass {
    let inv_eps = (1.0 / eps) as f32;
    let cols = y.cloud.columns();
    let (g32, kappa) = centred(g);
    // The ball bound: the block masses keep the weak links the correction needs.
    let fitted = Fitted::new(y, g, cut, Bound::Ball);
    let fitted = fitted.as_ref();
    let parts: Vec<(Vec<f64>, Vec<f64>, u64)> = x
        .ranges
        .par_iter()
        .zip(lists)
        .map_init(Targets::default, |targets, (rows, list)| {
            let mut pairs = 0;
            targets.load(y, list, fitted);
            let lens: Vec<u32> = list
                .iter()
                .map(|&j| y.ranges[j as usize].len() as u32)
                .collect();
            let total: usize = targets.ranges().iter().map(Range::len).sum();
            let mut scores = vec![0.0f32; total.div_ceil(16) * 16 + 16];
            let mut kept = Vec::with_capacity(list.len());
            let mut kept_lens = Vec::with_capacity(list.len());
            let mut block = vec![0.0f32; list.len()];
            // Block masses relative to one shared reference `exp(top)`, rescaled when it grows.
            let mut masses = vec![0.0f64; list.len()];
            let mut top = f64::NEG_INFINITY;
            let mut out = Vec::with_capacity(rows.len());
            for i in rows.clone() {
                let point = x.cloud.point(i);
                targets.point(fitted, i, &point);
                targets.kept_into(&mut kept);
                kept_lens.clear();
                kept_lens.extend(kept.iter().map(|&k| lens[k]));
                let block = &mut block[..kept_lens.len()];
                let mut row = BlockSums {
                    lens: &kept_lens,
                    scores: &mut scores,
                    out: block,
                    max: f32::NEG_INFINITY,
                };
                pairs += stream_blocks(
                    &point,
                    cols,
                    &y.log_w,
                    &g32,
                    inv_eps,
                    targets.ranges(),
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
                for (&k, &b) in kept.iter().zip(block.iter()) {
                    masses[k] += scale * f64::from(b);
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

#[cfg(test)]
mod tests;
