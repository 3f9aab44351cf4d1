//! Spatial blocks of a cloud and rigorous lower bounds on reduced costs between blocks.
//!
//! A cloud is cut into clusters by a 5-D grid (cells of equal width chosen so
//! a cluster holds about `cluster_size` points) and reordered so each
//! cluster is a contiguous range of the SoA columns. The first width assumes
//! the points spread over 2 of the 5 dimensions (an image's xy); a cloud that
//! also spreads in colour fills many more, smaller cells (65 536 blob points:
//! 16 597 cells of 4 points), so cells are widened by 1.25 until there are at
//! most `2n / cluster_size` of them. Given dual potentials
//! `f` (source) and `g` (target), each cluster gets a least-squares linear fit
//! of its potential, `f_i = f̄ + ⟨b, δ_i⟩ + r_i`, with the exact largest
//! residual. Expanding `c_ij = ‖Δ + δ_i − δ_j‖²` with `Δ` the centroid offset
//! gives, for every `i ∈ I`, `j ∈ J`,
//!
//! `c_ij − f_i − g_j ≥ ‖Δ‖² − f̄ − ḡ − ‖2Δ − b‖ r_I − ‖2Δ + a‖ r_J − max r^f − max r^g`,
//!
//! a bound that is tight for the blocks a plan actually uses (there
//! `b ≈ 2Δ ≈ −a`). Sinkhorn drops block pairs whose bound exceeds `30ε`
//! (kernel truncation); the exact solver's optimality check skips block
//! pairs whose bound is positive, without missing a violated pair.
//!
//! Sinkhorn then cuts each kept block pair per source point, with the point
//! `x_i` itself in place of its cluster and the target block's bounding box
//! in place of its ball: with the target fit `g_j = ḡ + ⟨a, y_j − c_J⟩ + r_j`
//! and `p = x_i + a/2` (completing the square),
//!
//! `c_ij − g_j = ‖y_j − p‖² − ⟨a, x_i − c_J⟩ − ‖a‖²/4 − ḡ − r_j ≥ box(p)² − ⟨a, x_i − c_J⟩ − ‖a‖²/4 − ḡ − max r^g`
//!
//! with `box(p)` the distance from `p` to the bounding box of `J`'s points
//! ([`PointCut`], [`Bound::Box`]). The box is much tighter than a ball in the
//! colour axes, where a cluster of an image is thin: on the benchmark's blob
//! pair at n = 16384 it keeps 36 of the 89 listed blocks per point, where the
//! ball bound `‖d‖² − ‖2d + a‖ r_J − ḡ − max r^g` (`d = x_i − c_J`,
//! [`Bound::Ball`]) keeps 44; 62 % of the pairs it keeps are within the
//! truncation. The passes that also sum the plan per block pair (the coarse
//! correction's masses) keep the ball bound: the correction needs the weak
//! links between blocks that the box cuts (with the box there, seed 2 of the
//! benchmark needs a second bridged correction and 17 % more pairs). Box
//! and ball: 1.91 G pair evaluations in the whole seed-0 solve, against
//! 2.11 G with the ball alone.
mod bounds;
mod cut;

use std::ops::Range;

use rayon::prelude::*;

use crate::points::{DIM, Point, PointCloud};
pub(crate) use bounds::{Boxes, Support, kept_targets, pair_bound};
pub(crate) use cut::{Bound, PointCut, Selection};

/// A contiguous run of points of a reordered cloud with its centroid and radius.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Cluster {
    pub range: Range<usize>,
    pub centroid: [f64; DIM],
    /// Largest distance of a member to the centroid.
    pub radius: f64,
    /// Bounding box of the members: smallest coordinates.
    pub lo: Point,
    /// Bounding box of the members: largest coordinates.
    pub hi: Point,
}

/// A cloud reordered by cluster.
#[derive(Debug, Clone)]
pub(crate) struct Clustered {
    /// The reordered cloud: point `k` is point `order[k]` of the input.
    pub cloud: PointCloud,
    pub order: Vec<u32>,
    pub clusters: Vec<Cluster>,
}

impl Clustered {
    /// Groups `cloud` into grid cells holding about `cluster_size` points each.
    pub fn new(cloud: &PointCloud, cluster_size: usize) -> Self {
        let n = cloud.len();
        let (lo, hi) = cloud.bounds();
        let extent = (0..DIM).map(|d| hi[d] - lo[d]).fold(0.0f32, f32::max);
        let cols = cloud.columns();
        let keys_for = |width: f32| -> Vec<u64> {
            (0..n)
                .map(|i| {
                    (0..DIM).fold(0u64, |k, d| {
                        let q = if width > 0.0 {
                            ((cols[d][i] - lo[d]) / width) as u64
                        } else {
                            0
                        };
                        (k << 12) | q.min(4095)
                    })
                })
                .collect()
        };
        // Cells sized for a 2-D spread first; widened while the cloud fills more
        // dimensions than that and the cells come out much smaller than asked.
        let most = 2 * n.div_ceil(cluster_size.max(1));
        let mut width = extent * (cluster_size.max(1) as f32 / n as f32).sqrt();
        let mut keys = keys_for(width);
        for _ in 0..MAX_WIDENINGS {
            if distinct(&keys) <= most {
                break;
            }
            width *= WIDENING;
            keys = keys_for(width);
        }
        let mut order: Vec<u32> = (0..n as u32).collect();
        order.sort_unstable_by_key(|&i| (keys[i as usize], i));
        let cloud = cloud.reordered(&order);
        let mut clusters = Vec::new();
        let mut start = 0;
        while start < n {
            let k = keys[order[start] as usize];
            let end = start
                + order[start..]
                    .iter()
                    .take_while(|&&i| keys[i as usize] == k)
                    .count();
            clusters.push(make_cluster(&cloud, start..end));
            start = end;
        }
        Self {
            cloud,
            order,
            clusters,
        }
    }

    /// Ranges of all clusters, in order.
    pub fn ranges(&self) -> Vec<Range<usize>> {
        self.clusters.iter().map(|c| c.range.clone()).collect()
    }

    /// Copies values given in the input order into the reordered indexing (the inverse of [`Self::unsort`]).
    pub fn sorted<T: Copy>(&self, values: &[T]) -> Vec<T> {
        self.order.iter().map(|&i| values[i as usize]).collect()
    }

    /// Copies values given in the reordered indexing back to the input order.
    pub fn unsort<T: Copy + Default>(&self, values: &[T]) -> Vec<T> {
        let mut out = vec![T::default(); values.len()];
        for (k, &i) in self.order.iter().enumerate() {
            out[i as usize] = values[k];
        }
        out
    }
}

/// Most times the grid cells are widened by [`WIDENING`] to bring the cluster count down.
const MAX_WIDENINGS: usize = 24;
/// Factor by which the grid cells are widened at a time.
const WIDENING: f32 = 1.25;

/// Number of distinct values.
fn distinct(keys: &[u64]) -> usize {
    let mut sorted = keys.to_vec();
    sorted.sort_unstable();
    sorted.dedup();
    sorted.len()
}

fn make_cluster(cloud: &PointCloud, range: Range<usize>) -> Cluster {
    let cols = cloud.columns();
    let len = range.len() as f64;
    let centroid: [f64; DIM] = std::array::from_fn(|d| {
        cols[d][range.clone()]
            .iter()
            .map(|&v| f64::from(v))
            .sum::<f64>()
            / len
    });
    let radius = range
        .clone()
        .map(|i| {
            (0..DIM)
                .map(|d| (f64::from(cols[d][i]) - centroid[d]).powi(2))
                .sum::<f64>()
                .sqrt()
        })
        .fold(0.0, f64::max);
    let lo = std::array::from_fn(|d| {
        cols[d][range.clone()]
            .iter()
            .copied()
            .fold(f32::INFINITY, f32::min)
    });
    let hi = std::array::from_fn(|d| {
        cols[d][range.clone()]
            .iter()
            .copied()
            .fold(f32::NEG_INFINITY, f32::max)
    });
    Cluster {
        range,
        lo,
        hi,
        centroid,
        radius: radius * (1.0 + 1e-9) + 1e-12,
    }
}

/// Linear model of a potential over one cluster with its largest residual.
#[derive(Debug, Clone, Copy)]
pub(crate) struct PotentialFit {
    mean: f64,
    slope: [f64; DIM],
    max_residual: f64,
}

/// Fits every cluster's potential (`potential` in the reordered indexing).
pub(crate) fn fit_potentials(clustered: &Clustered, potential: &[f64]) -> Vec<PotentialFit> {
    let cols = clustered.cloud.columns();
    clustered
        .clusters
        .par_iter()
        .map(|c| {
            let delta = |i: usize, d: usize| f64::from(cols[d][i]) - c.centroid[d];
            let len = c.range.len() as f64;
            let mean = c.range.clone().map(|i| potential[i]).sum::<f64>() / len;
            let mut a = [[0.0f64; DIM]; DIM];
            let mut rhs = [0.0f64; DIM];
            for i in c.range.clone() {
                let d: [f64; DIM] = std::array::from_fn(|k| delta(i, k));
                for (p, row) in a.iter_mut().enumerate() {
                    rhs[p] += d[p] * (potential[i] - mean);
                    for (q, entry) in row.iter_mut().enumerate() {
                        *entry += d[p] * d[q];
                    }
                }
            }
            let trace: f64 = (0..DIM).map(|p| a[p][p]).sum();
            (0..DIM).for_each(|p| a[p][p] += 1e-9 * trace + 1e-300);
            let slope = solve_spd(a, rhs);
            let max_residual = c
                .range
                .clone()
                .map(|i| {
                    potential[i] - mean - (0..DIM).map(|d| slope[d] * delta(i, d)).sum::<f64>()
                })
                .fold(f64::NEG_INFINITY, f64::max);
            PotentialFit {
                mean,
                slope,
                max_residual,
            }
        })
        .collect()
}

/// Solves a small symmetric positive definite system by Gaussian elimination (zero on breakdown).
fn solve_spd(mut a: [[f64; DIM]; DIM], mut b: [f64; DIM]) -> [f64; DIM] {
    for k in 0..DIM {
        let pivot = a[k][k];
        if pivot == 0.0 || !pivot.is_finite() {
            return [0.0; DIM];
        }
        let pivot_row = a[k];
        for r in k + 1..DIM {
            let m = a[r][k] / pivot;
            for (entry, p) in a[r].iter_mut().zip(pivot_row).skip(k) {
                *entry -= m * p;
            }
            b[r] -= m * b[k];
        }
    }
    let mut x = [0.0; DIM];
    for k in (0..DIM).rev() {
        let s: f64 = (k + 1..DIM).map(|c| a[k][c] * x[c]).sum();
        x[k] = (b[k] - s) / a[k][k];
    }
    if x.iter().all(|v| v.is_finite()) {
        x
    } else {
        [0.0; DIM]
    }
}
