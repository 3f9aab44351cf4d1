//! Block-pair bounds on reduced costs (the first inequality of the parent
//! module) and the supports they keep: the target clusters of each source
//! cluster; the point-to-box distances of a list of clusters ([`Boxes`]).

use rayon::prelude::*;

use super::{Cluster, Clustered, PotentialFit};
use crate::points::{DIM, Point};

/// `gap²` with `gap` the distance of the coordinate `p` to the interval `[lo, hi]` (0 inside).
#[inline(always)]
fn gap_sq(lo: f64, hi: f64, p: f64) -> f64 {
    let gap = (lo - p).max(p - hi).max(0.0);
    gap * gap
}

/// The bounding boxes of a list of clusters, one `f64` column per axis and
/// bound (structure of arrays), so the distances of a point to all of them
/// are one loop the compiler vectorises.
#[derive(Debug, Clone, Default)]
pub(crate) struct Boxes {
    lo: [Vec<f64>; DIM],
    hi: [Vec<f64>; DIM],
}

impl Boxes {
    /// The boxes of `clusters[list[k]]`, in the order of `list`.
    pub fn gather(clusters: &[Cluster], list: &[u32]) -> Self {
        let column = |f: &dyn Fn(&Cluster) -> f64| -> Vec<f64> {
            list.iter().map(|&c| f(&clusters[c as usize])).collect()
        };
        Self {
            lo: std::array::from_fn(|d| column(&|c| f64::from(c.lo[d]))),
            hi: std::array::from_fn(|d| column(&|c| f64::from(c.hi[d]))),
        }
    }

    /// Number of boxes.
    pub fn len(&self) -> usize {
        self.lo[0].len()
    }

    /// Writes to `out[k]` `Σ_d gap_d²`, with `gap_d` the distance of `p` to box `k`
    /// along axis `d`: at most `‖p − q‖²` for every member `q` of the cluster
    /// (in `f64`, rounded down by at most 3 units of the last place).
    #[inline(always)]
    pub fn dist_sq(&self, p: &Point, out: &mut [f64]) {
        let len = self.len();
        let out = &mut out[..len];
        out.fill(0.0);
        for ((lo, hi), &q) in self.lo.iter().zip(&self.hi).zip(p) {
            let (lo, hi, q) = (&lo[..len], &hi[..len], f64::from(q));
            for k in 0..len {
                out[k] += gap_sq(lo[k], hi[k], q);
            }
        }
    }
}

/// Lower bound on `c_ij − f_i − g_j` over all `i ∈ I`, `j ∈ J` (see the module doc).
pub(crate) fn pair_bound(ci: &Cluster, fi: &PotentialFit, cj: &Cluster, gj: &PotentialFit) -> f64 {
    let delta: [f64; DIM] = std::array::from_fn(|d| ci.centroid[d] - cj.centroid[d]);
    let norm = |v: [f64; DIM]| v.iter().map(|t| t * t).sum::<f64>().sqrt();
    let dist_sq: f64 = delta.iter().map(|t| t * t).sum();
    let src_tilt = norm(std::array::from_fn(|d| 2.0 * delta[d] - fi.slope[d]));
    let dst_tilt = norm(std::array::from_fn(|d| 2.0 * delta[d] + gj.slope[d]));
    dist_sq
        - fi.mean
        - gj.mean
        - src_tilt * ci.radius
        - dst_tilt * cj.radius
        - fi.max_residual
        - gj.max_residual
}

/// The target clusters whose reduced-cost bound against source cluster `ci` is at most `threshold`.
///
/// If every bound exceeds the threshold the best target cluster is kept, so
/// no row of a plan is ever empty.
pub(crate) fn kept_targets(
    ci: &Cluster,
    fi: &PotentialFit,
    dst: &Clustered,
    g: &[PotentialFit],
    threshold: f64,
) -> Vec<u32> {
    let bounds = dst
        .clusters
        .iter()
        .zip(g)
        .map(|(cj, gj)| pair_bound(ci, fi, cj, gj));
    let kept: Vec<u32> = bounds
        .clone()
        .enumerate()
        .filter(|(_, b)| *b <= threshold)
        .map(|(j, _)| j as u32)
        .collect();
    if kept.is_empty() {
        let best = bounds
            .enumerate()
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .map_or(0, |(j, _)| j as u32);
        vec![best]
    } else {
        kept
    }
}

/// [`kept_targets`] for every source cluster.
fn kept_pairs(
    src: &Clustered,
    f: &[PotentialFit],
    dst: &Clustered,
    g: &[PotentialFit],
    threshold: f64,
) -> Vec<Vec<u32>> {
    src.clusters
        .par_iter()
        .zip(f)
        .map(|(ci, fi)| kept_targets(ci, fi, dst, g, threshold))
        .collect()
}

/// Block support of a truncated plan: per source cluster its target clusters, and the transpose.
///
/// Built from [`kept_pairs`]; a target cluster no source cluster kept gets its
/// best source cluster added, so no column of the plan is empty either.
#[derive(Debug, Clone)]
pub(crate) struct Support {
    pub rows: Vec<Vec<u32>>,
    pub cols: Vec<Vec<u32>>,
}

impl Support {
    /// Every block pair: the dense plan.
    pub fn dense(sources: usize, targets: usize) -> Self {
        Self {
            rows: vec![(0..targets as u32).collect(); sources],
            cols: vec![(0..sources as u32).collect(); targets],
        }
    }

    /// The block pairs whose reduced-cost bound is at most `threshold`.
    pub fn truncated(
        src: &Clustered,
        f: &[PotentialFit],
        dst: &Clustered,
        g: &[PotentialFit],
        threshold: f64,
    ) -> Self {
        let mut rows = kept_pairs(src, f, dst, g, threshold);
        let mut cols = transpose(&rows, dst.clusters.len());
        let mut patched = false;
        let empty: Vec<usize> = cols
            .iter()
            .enumerate()
            .filter(|(_, c)| c.is_empty())
            .map(|(j, _)| j)
            .collect();
        for j in empty {
            let best = src
                .clusters
                .iter()
                .zip(f)
                .map(|(ci, fi)| pair_bound(ci, fi, &dst.clusters[j], &g[j]))
                .enumerate()
                .min_by(|a, b| a.1.total_cmp(&b.1))
                .map_or(0, |(i, _)| i);
            rows[best].push(j as u32);
            rows[best].sort_unstable();
            patched = true;
        }
        if patched {
            cols = transpose(&rows, dst.clusters.len());
        }
        Self { rows, cols }
    }
}

fn transpose(lists: &[Vec<u32>], targets: usize) -> Vec<Vec<u32>> {
    let mut out = vec![Vec::new(); targets];
    for (i, list) in lists.iter().enumerate() {
        for &j in list {
            out[j as usize].push(i as u32);
        }
    }
    out
}
