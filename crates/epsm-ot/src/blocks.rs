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
//! Sinkhorn then cuts each kept block pair per source point: with the source
//! point `x_i` itself in place of its cluster (`d = x_i − c_J`),
//!
//! `c_ij − f_i − g_j ≥ ‖d‖² − ‖2d + a‖ r_J − ḡ − max r^g − f_i`,
//!
//! which is free of the source cluster's radius ([`PointCut`]). On the
//! benchmark's blob pairs at the final ε it skips about 60 % of the pairs the
//! block support keeps (n = 16384 and 65536).

use std::ops::Range;

use rayon::prelude::*;

use crate::kernel::{Simd, simd};
use crate::points::{DIM, Point, PointCloud};

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

impl Cluster {
    /// `Σ_d gap_d²` with `gap_d` the distance of `p` to the bounding box along
    /// axis `d`: at most `‖p − q‖²` for every member `q` (in `f64`, rounded
    /// down by at most 3 units of the last place).
    pub fn box_dist_sq(&self, p: &Point) -> f64 {
        (0..DIM)
            .map(|d| {
                let gap = (f64::from(self.lo[d]) - f64::from(p[d]))
                    .max(f64::from(p[d]) - f64::from(self.hi[d]))
                    .max(0.0);
                gap * gap
            })
            .sum()
    }
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

/// The point-to-block bound of the module doc for a list of target blocks, as
/// `f32` columns so the test of one point against every block vectorises.
#[derive(Debug, Clone, Default)]
pub(crate) struct PointCut {
    centroid: [Vec<f32>; DIM],
    /// Slope `a` of the target potential's fit.
    slope: [Vec<f32>; DIM],
    radius: Vec<f32>,
    /// `ḡ + max r^g`.
    offset: Vec<f32>,
    /// The blocks' point ranges.
    ranges: Vec<Range<usize>>,
    /// Bit `k`: block `k` starts where block `k − 1` ends (layout of [`Selection`]'s bits).
    continues: Vec<u64>,
}

/// What [`PointCut::select`] kept for one point.
#[derive(Debug, Clone, Default)]
pub(crate) struct Selection {
    /// Scratch: whether each block of the list is kept.
    keep: Vec<bool>,
    /// Bit `k % 64` of word `k / 64`: block `k` of the list is kept.
    bits: Vec<u64>,
    /// The kept blocks' ranges, consecutive blocks merged.
    pub ranges: Vec<Range<usize>>,
}

impl Selection {
    /// Every one of `n` blocks kept, whose merged ranges are `ranges`.
    pub fn all(n: usize, ranges: Vec<Range<usize>>) -> Self {
        let mut bits = vec![u64::MAX; n / 64];
        if !n.is_multiple_of(64) {
            bits.push((1u64 << (n % 64)) - 1);
        }
        Self {
            keep: Vec::new(),
            bits,
            ranges,
        }
    }

    /// Positions in the list of the kept blocks, in increasing order.
    pub fn kept(&self) -> impl Iterator<Item = usize> + '_ {
        set_bits(&self.bits)
    }
}

/// Positions of the set bits of a bit vector, in increasing order.
fn set_bits(words: &[u64]) -> impl Iterator<Item = usize> + '_ {
    words
        .iter()
        .enumerate()
        .flat_map(|(w, &word)| word_bits(w, word))
}

/// Positions of the set bits of `word`, the `w`-th word of a bit vector, in increasing order.
fn word_bits(w: usize, word: u64) -> impl Iterator<Item = usize> {
    let mut rest = word;
    std::iter::from_fn(move || {
        (rest != 0).then(|| {
            let k = rest.trailing_zeros() as usize;
            rest &= rest - 1;
            64 * w + k
        })
    })
}

impl PointCut {
    /// The bounds of `clustered`'s blocks listed in `list`, in that order, from the fits of its potential.
    pub fn gather(clustered: &Clustered, fits: &[PotentialFit], list: &[u32]) -> Self {
        let with = || Vec::with_capacity(list.len());
        let mut cut = Self {
            centroid: std::array::from_fn(|_| with()),
            slope: std::array::from_fn(|_| with()),
            radius: with(),
            offset: with(),
            ranges: Vec::with_capacity(list.len()),
            continues: vec![0; list.len().div_ceil(64)],
        };
        for &j in list {
            let (c, fit) = (&clustered.clusters[j as usize], &fits[j as usize]);
            for d in 0..DIM {
                cut.centroid[d].push(c.centroid[d] as f32);
                cut.slope[d].push(fit.slope[d] as f32);
            }
            // Cover the rounding of the centroid to f32.
            let shift = c.centroid.iter().fold(0.0f64, |m, v| m.max(v.abs())) * 1e-6;
            cut.radius.push((c.radius + shift) as f32);
            cut.offset.push((fit.mean + fit.max_residual) as f32);
            let k = cut.ranges.len();
            if cut.ranges.last().is_some_and(|r| r.end == c.range.start) {
                cut.continues[k / 64] |= 1 << (k % 64);
            }
            cut.ranges.push(c.range.clone());
        }
        cut
    }

    /// Keeps the blocks whose bound on `c(x, y_j) − g_j` may be at most `limit`, and
    /// returns whether there is any (the caller decides what a point that keeps none streams).
    ///
    /// Conservative under `f32` rounding: a block is dropped only if its bound
    /// exceeds `limit` by more than [`CUT_ROUNDING`] times the magnitudes
    /// involved, far above the accumulated rounding of these few operations,
    /// so potentials of any size (clouds far apart) never cut a pair they should not.
    pub fn select(&self, x: &Point, limit: f32, out: &mut Selection) -> bool {
        match simd() {
            #[cfg(target_arch = "x86_64")]
            #[allow(unsafe_code)]
            // SAFETY: `select_avx512` only requires the four AVX-512 subsets it is
            // compiled for, which `simd` detected on the running CPU; it is the same
            // safe code as `select_portable`.
            Simd::Avx512 => unsafe { self.select_avx512(x, limit, out) },
            #[cfg(target_arch = "x86_64")]
            #[allow(unsafe_code)]
            // SAFETY: `select_avx2` only requires AVX2 and FMA, which `simd` detected
            // on the running CPU; it is the same safe code as `select_portable`.
            Simd::Avx2 => unsafe { self.select_avx2(x, limit, out) },
            _ => self.select_portable(x, limit, out),
        }
        !out.ranges.is_empty()
    }

    /// [`Self::select_portable`] compiled for AVX-512 (selected at run time).
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx512f,avx512bw,avx512dq,avx512vl")]
    fn select_avx512(&self, x: &Point, limit: f32, out: &mut Selection) {
        self.select_portable(x, limit, out);
    }

    /// [`Self::select_portable`] compiled for AVX2 (selected at run time).
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma")]
    fn select_avx2(&self, x: &Point, limit: f32, out: &mut Selection) {
        self.select_portable(x, limit, out);
    }

    /// The body of [`Self::select`]: a vectorisable test, then a branch-free compaction.
    #[inline(always)]
    fn select_portable(&self, x: &Point, limit: f32, out: &mut Selection) {
        let n = self.ranges.len();
        out.keep.resize(n, false);
        let keep = &mut out.keep[..n];
        let [c0, c1, c2, c3, c4] = &self.centroid;
        let (c0, c1, c2, c3, c4) = (&c0[..n], &c1[..n], &c2[..n], &c3[..n], &c4[..n]);
        let [a0, a1, a2, a3, a4] = &self.slope;
        let (a0, a1, a2, a3, a4) = (&a0[..n], &a1[..n], &a2[..n], &a3[..n], &a4[..n]);
        let (radius, offset) = (&self.radius[..n], &self.offset[..n]);
        for k in 0..n {
            let d = [
                x[0] - c0[k],
                x[1] - c1[k],
                x[2] - c2[k],
                x[3] - c3[k],
                x[4] - c4[k],
            ];
            let t = [
                2.0 * d[0] + a0[k],
                2.0 * d[1] + a1[k],
                2.0 * d[2] + a2[k],
                2.0 * d[3] + a3[k],
                2.0 * d[4] + a4[k],
            ];
            let dd = d[0] * d[0] + d[1] * d[1] + d[2] * d[2] + d[3] * d[3] + d[4] * d[4];
            let tt = t[0] * t[0] + t[1] * t[1] + t[2] * t[2] + t[3] * t[3] + t[4] * t[4];
            let tilt = tt.sqrt() * radius[k];
            let slack = CUT_ROUNDING * (dd + tilt + offset[k].abs() + limit.abs());
            keep[k] = dd - tilt - offset[k] <= limit + slack;
        }
        // Bit masks: a kept block opens a range unless it joins the previous kept block
        // (continues it), and closes it unless the next block joins it.
        out.bits.clear();
        out.bits.extend(keep.chunks(64).map(|chunk| {
            let mut word = 0u64;
            for (k, &v) in chunk.iter().enumerate() {
                word |= u64::from(v) << k;
            }
            word
        }));
        let words = &out.bits;
        let joins = |w: usize| {
            let previous = (words[w] << 1) | if w > 0 { words[w - 1] >> 63 } else { 0 };
            words[w] & previous & self.continues[w]
        };
        let opens = |w: usize| words[w] & !joins(w);
        let closes = |w: usize| {
            let joined = (joins(w) >> 1)
                | if w + 1 < words.len() {
                    joins(w + 1) << 63
                } else {
                    0
                };
            words[w] & !joined
        };
        out.ranges.clear();
        let starts = (0..words.len()).flat_map(|w| word_bits(w, opens(w)));
        out.ranges.extend(starts.map(|k| self.ranges[k].start..0));
        let ends = (0..words.len()).flat_map(|w| word_bits(w, closes(w)));
        for (r, k) in out.ranges.iter_mut().zip(ends) {
            r.end = self.ranges[k].end;
        }
    }
}

/// Appends `r` to `out`, extending the last range instead if `r` continues it.
pub(crate) fn push_merged(out: &mut Vec<Range<usize>>, r: Range<usize>) {
    match out.last_mut() {
        Some(last) if last.end == r.start => last.end = r.end,
        _ => out.push(r),
    }
}

/// Relative slack of [`PointCut::select`]: about 60 `f32` roundings.
const CUT_ROUNDING: f32 = 4e-6;

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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::synthetic::{Rng, blobs_pair};
    use crate::tests::translated;

    /// Every block holding a pair with `c(x, y_j) − g_j ≤ limit` is kept and the ranges are
    /// the kept blocks' merged; with `drops`, most blocks are dropped (the check is not vacuous).
    fn check_cut(source: &PointCloud, target: &PointCloud, slope: f64, drops: bool) {
        let (x, y) = (Clustered::new(source, 16), Clustered::new(target, 16));
        let mut rng = Rng::new(5);
        // A smooth tilt plus noise of the size of the kernel width: the kind of potential a plan has.
        let g: Vec<f64> = (0..y.cloud.len())
            .map(|j| slope * f64::from(y.cloud.point(j)[3]) + 0.01 * f64::from(rng.uniform()))
            .collect();
        let fits = fit_potentials(&y, &g);
        let list: Vec<u32> = (0..y.clusters.len() as u32).collect();
        let cut = PointCut::gather(&y, &fits, &list);
        let mut selection = Selection::default();
        let (mut kept, mut total) = (0, 0);
        for i in (0..x.cloud.len()).step_by(7) {
            let p = x.cloud.point(i);
            let reduced = |j: usize| {
                let q = y.cloud.point(j);
                let c: f64 = (0..DIM).map(|d| f64::from(p[d] - q[d]).powi(2)).sum();
                c - g[j]
            };
            let best = (0..y.cloud.len())
                .map(reduced)
                .fold(f64::INFINITY, f64::min);
            let limit = best + 30.0 * 1e-4;
            cut.select(&p, limit as f32, &mut selection);
            let chosen: Vec<usize> = selection.kept().collect();
            for (k, c) in y.clusters.iter().enumerate() {
                let needed = c.range.clone().any(|j| reduced(j) <= limit);
                assert!(
                    !needed || chosen.contains(&k),
                    "point {i}: block {k} dropped"
                );
            }
            let mut merged = Vec::new();
            for &k in &chosen {
                push_merged(&mut merged, y.clusters[k].range.clone());
            }
            assert_eq!(selection.ranges, merged, "point {i}");
            kept += chosen.len();
            total += list.len();
        }
        assert!(
            !drops || kept * 4 < total,
            "vacuous: {kept} of {total} blocks kept"
        );
    }

    #[test]
    fn point_cut_keeps_every_block_with_a_pair_below_the_limit() {
        let (s, t) = blobs_pair(2048, 9).unwrap_or_else(|| panic!("fixture"));
        check_cut(&s, &t, 0.3, true);
        // Far apart: costs and potentials of size 1e6, whose f32 rounding alone exceeds
        // 30ε; the slack then keeps every block (no cut, but no wrong one either).
        let far = translated(&t, [0.0, 0.0, 0.0, 1000.0, 0.0]);
        check_cut(&s, &far, 2000.0, false);
    }
}
