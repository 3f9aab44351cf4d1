//! Streaming log-sum-exp rows of the Gibbs kernel, written so the compiler vectorises them.
//!
//! One row of a log-domain Sinkhorn update is
//! `softmin_i = −ε log Σ_j exp(h_j − c(x_i, y_j)/ε)` with `h_j = log b_j + g_j/ε`.
//! We never store the kernel: targets are streamed in blocks of [`BLOCK`]
//! from the five SoA columns, scores go to a stack buffer, and each block is
//! reduced in two vectorisable passes (maximum, then sum of exponentials with
//! a portable polynomial `exp`). Block sums are `f32`; the running sum across
//! blocks is `f64`, rescaled when the running maximum grows.
//!
//! The one portable body is compiled three times: plain x86-64 (SSE2), AVX2 +
//! FMA (8 lanes) and AVX-512 F/BW/DQ/VL (16 lanes); [`stream_row`] picks the
//! widest the running CPU supports (runtime detection, so the binary still
//! runs on any x86-64). [`stream_blocks`] is the same pass with one sum per
//! target range instead of one per row. The paths compute the same operations in the same
//! order (no reassociation, no FMA contraction), so they agree to rounding.

mod body;
mod exp;

use std::ops::Range;

use crate::cpu::{Simd, active_simd};
use crate::points::{DIM, Point};
use body::{Columns, Scratch, block_sums, gathered_sum, push_range_moments};
pub(crate) use exp::exp_nonpositive;

/// Targets processed per block of a row.
pub(crate) const BLOCK: usize = 256;
const LANES: usize = 16;

/// Running state of one streamed row: log-sum-exp and optional weighted moments.
#[derive(Debug, Clone, Copy)]
pub(crate) struct RowSum {
    max: f32,
    sum: f64,
    /// `Σ w_j y_j` (five coordinates) then `Σ w_j c_ij`, relative to `exp(max)`.
    moments: [f64; DIM + 1],
}

impl RowSum {
    pub(crate) fn new() -> Self {
        Self {
            max: f32::NEG_INFINITY,
            sum: 0.0,
            moments: [0.0; DIM + 1],
        }
    }

    /// `log Σ_j exp(score_j)` over everything pushed so far.
    pub(crate) fn log_sum(&self) -> f64 {
        f64::from(self.max) + self.sum.ln()
    }

    /// The weighted mean target `Σ w_j y_j / Σ w_j` and mean cost (valid after a `moments` pass),
    /// or `None` when the row has no usable mass.
    ///
    /// Whenever a block with a finite score is pushed, its largest score is (or becomes) the
    /// running maximum and adds `exp(0) = 1` to a sum of non-negative terms, so a row with any
    /// finite score has `sum ≥ 1`. `None` is thus the row that streamed no target, or whose
    /// scores were all `−∞` (a zero weight, or a cost beyond `f32` range at this ε) or `NaN`
    /// (non-finite potentials): the row's barycentre is undefined and the caller fails with a
    /// typed error instead of dividing by 0.
    pub(crate) fn barycentre(&self) -> Option<(Point, f64)> {
        if self.sum.is_nan() || self.sum < 1.0 {
            return None;
        }
        Some((
            std::array::from_fn(|d| (self.moments[d] / self.sum) as f32),
            self.moments[DIM] / self.sum,
        ))
    }

    fn rescale_to(&mut self, new_max: f32) {
        if new_max > self.max {
            let s = f64::from(exp_nonpositive(self.max - new_max));
            self.sum *= s;
            self.moments.iter_mut().for_each(|m| *m *= s);
            self.max = new_max;
        }
    }
}

/// Where a streamed row goes: one running sum over all ranges, or one sum per block.
pub(crate) enum Sink<'a, 'b> {
    /// Accumulate every range into one [`RowSum`].
    Row(&'a mut RowSum),
    /// One sum per block of consecutive targets (the block masses of the coarse correction).
    Blocks(&'a mut BlockSums<'b>),
}

/// Per-block sums of one row, all relative to the row's largest score.
pub(crate) struct BlockSums<'a> {
    /// Lengths of the blocks, in order; together they are the streamed ranges.
    pub lens: &'a [u32],
    /// Scratch for the row's scores: at least the blocks' total length rounded up to 16, plus 16.
    pub scores: &'a mut [f32],
    /// `out[k] = Σ_{j ∈ block k} exp(score_j − max)`.
    pub out: &'a mut [f32],
    /// The row's largest score (`−∞` if there is none).
    pub max: f32,
}

/// Streams the targets in `ranges` against the point `x`.
///
/// Scores are `lw_j + (g_j − c(x, y_j))·inv_eps`: the potential and the cost are
/// subtracted before scaling by `1/ε`, so relevant (nearly cancelling) pairs keep their precision. With `MOMENTS` the weighted target
/// coordinates and costs are accumulated too (for barycentres). Returns the
/// number of pairs evaluated.
pub(crate) fn stream_row<const MOMENTS: bool>(
    x: &Point,
    y: &[Vec<f32>; DIM],
    lw: &[f32],
    g: &[f32],
    inv_eps: f32,
    ranges: &[Range<usize>],
    acc: &mut RowSum,
) -> u64 {
    stream::<MOMENTS>(x, y, lw, g, inv_eps, ranges, Sink::Row(acc))
}

/// [`stream_row`] with one sum per block (`sums.lens`) of the targets in `ranges`.
///
/// Scores are written to `sums.scores`, then exponentiated relative to their
/// maximum and summed block by block, so short blocks cost no more per pair
/// than one long range.
pub(crate) fn stream_blocks(
    x: &Point,
    y: &[Vec<f32>; DIM],
    lw: &[f32],
    g: &[f32],
    inv_eps: f32,
    ranges: &[Range<usize>],
    sums: &mut BlockSums,
) -> u64 {
    stream::<false>(x, y, lw, g, inv_eps, ranges, Sink::Blocks(sums))
}

/// Runs the SIMD body the kernels use ([`active_simd`]).
fn stream<const MOMENTS: bool>(
    x: &Point,
    y: &[Vec<f32>; DIM],
    lw: &[f32],
    g: &[f32],
    inv_eps: f32,
    ranges: &[Range<usize>],
    sink: Sink,
) -> u64 {
    stream_with::<MOMENTS>(active_simd(), x, y, lw, g, inv_eps, ranges, sink)
}

/// Runs the body compiled for `simd`, or the portable one if the running CPU lacks it,
/// scoring in chunks of one register (AVX2, AVX-512) or two ([`PORTABLE_CHUNK`], SSE2).
#[allow(clippy::too_many_arguments)]
fn stream_with<const MOMENTS: bool>(
    simd: Simd,
    x: &Point,
    y: &[Vec<f32>; DIM],
    lw: &[f32],
    g: &[f32],
    inv_eps: f32,
    ranges: &[Range<usize>],
    sink: Sink,
) -> u64 {
    simd.run(
        #[inline(always)]
        |simd| match simd {
            Simd::Avx512 => stream_portable::<MOMENTS, 16>(x, y, lw, g, inv_eps, ranges, sink),
            Simd::Avx2 => stream_portable::<MOMENTS, 8>(x, y, lw, g, inv_eps, ranges, sink),
            Simd::Portable => {
                stream_portable::<MOMENTS, PORTABLE_CHUNK>(x, y, lw, g, inv_eps, ranges, sink)
            }
        },
    )
}

/// Lanes per chunk of scores in the portable body (two 128-bit SSE2 registers).
const PORTABLE_CHUNK: usize = 8;

/// The portable body of [`stream_row`] and [`stream_blocks`] (SSE2 on any x86_64), scoring
/// targets in chunks of `W` lanes (one or two registers of the body's instruction set; the
/// chunk width changes no score, only how many are computed past a range's end).
#[inline(always)]
fn stream_portable<const MOMENTS: bool, const W: usize>(
    x: &Point,
    y: &[Vec<f32>; DIM],
    lw: &[f32],
    g: &[f32],
    inv_eps: f32,
    ranges: &[Range<usize>],
    sink: Sink,
) -> u64 {
    let mut scratch = Scratch {
        scores: [f32::NEG_INFINITY; BLOCK],
        costs: [0.0; BLOCK],
        weights: [0.0; BLOCK],
    };
    // Plain loops, no closures or iterator adapters: those are separate generic
    // functions that would not inherit the caller's SIMD target features.
    // The point is copied: read through the reference captured by `Simd::run`'s
    // closure, it would be loaded and broadcast again for every range.
    let x = &{ *x };
    let cols = &Columns::new(y, lw, g);
    let mut pairs = 0;
    match sink {
        Sink::Row(acc) if !MOMENTS => {
            pairs = gathered_sum::<W>(x, cols, inv_eps, ranges, acc);
        }
        Sink::Row(acc) => {
            for r in ranges {
                pairs += push_range_moments(x, cols, inv_eps, r.clone(), acc, &mut scratch);
            }
        }
        Sink::Blocks(sums) => pairs = block_sums::<W>(x, cols, inv_eps, ranges, sums),
    }
    pairs
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fast_exp_matches_std_exp() {
        for k in 0..=20_000 {
            let x = -(k as f32) * 0.005;
            let (a, b) = (exp_nonpositive(x), x.exp());
            assert!((a - b).abs() <= 5e-6 * b + 1e-37, "x = {x}: {a} vs {b}");
        }
        assert_eq!(exp_nonpositive(f32::NEG_INFINITY), 0.0);
        assert_eq!(exp_nonpositive(-200.0), 0.0);
    }

    #[test]
    fn every_simd_row_equals_the_portable_row() {
        // The SIMD paths run the portable code in wider registers with no
        // reassociation and no FMA contraction, so they agree to rounding (in
        // practice bit for bit); the stated tolerance is 1e-6 relative. Every
        // body the CPU has runs (the portable one on any CPU).
        let mut rng = crate::synthetic::Rng::new(7);
        let bodies = Simd::supported();
        for case in 0..20 * bodies.len() {
            let body = bodies[case % bodies.len()];
            let n = 1 + rng.index(700);
            let y: [Vec<f32>; DIM] =
                std::array::from_fn(|_| (0..n).map(|_| rng.uniform()).collect());
            let lw: Vec<f32> = (0..n).map(|_| -5.0 * rng.uniform()).collect();
            let g: Vec<f32> = (0..n).map(|_| 0.1 * rng.uniform()).collect();
            let x: Point = std::array::from_fn(|_| rng.uniform());
            let inv_eps = 10.0f32.powf(1.0 + 3.0 * rng.uniform());
            let split = rng.index(n + 1);
            let ranges = [0..split, split..n];
            let (mut a, mut b) = (RowSum::new(), RowSum::new());
            let pa =
                stream_with::<true>(body, &x, &y, &lw, &g, inv_eps, &ranges, Sink::Row(&mut a));
            let pb = stream_portable::<true, PORTABLE_CHUNK>(
                &x,
                &y,
                &lw,
                &g,
                inv_eps,
                &ranges,
                Sink::Row(&mut b),
            );
            assert_eq!(pa, pb);
            let (la, lb) = (a.log_sum(), b.log_sum());
            assert!(
                (la - lb).abs() <= 1e-6 * lb.abs().max(1.0),
                "case {case}: {la} vs {lb}"
            );
            let ((ta, ca), (tb, cb)) = match (a.barycentre(), b.barycentre()) {
                (Some(a), Some(b)) => (a, b),
                other => panic!("case {case}: a row of finite scores has no mass: {other:?}"),
            };
            for d in 0..DIM {
                assert!((ta[d] - tb[d]).abs() <= 1e-6, "case {case}: barycentre {d}");
            }
            assert!(
                (ca - cb).abs() <= 1e-6 * cb.abs().max(1e-3),
                "case {case}: cost"
            );
        }
    }

    #[test]
    fn short_ranges_match_direct_sums_in_every_body() {
        // Many short ranges, of every length modulo the chunk widths, the last one ending
        // at the columns' end (where a chunk cannot be completed past the range), so the
        // scores computed past a range's end must be overwritten or masked in both sinks.
        let mut rng = crate::synthetic::Rng::new(11);
        for body in Simd::supported() {
            for case in 0..12 {
                let n = 40 + rng.index(600);
                let y: [Vec<f32>; DIM] =
                    std::array::from_fn(|_| (0..n).map(|_| rng.uniform()).collect());
                let lw: Vec<f32> = (0..n).map(|_| -3.0 * rng.uniform()).collect();
                let g: Vec<f32> = (0..n).map(|_| 0.05 * rng.uniform()).collect();
                let x: Point = std::array::from_fn(|_| rng.uniform());
                let inv_eps = 10.0f32.powf(1.0 + 2.0 * rng.uniform());
                // Ranges with gaps between them (skipped targets must not count).
                let mut ranges = Vec::new();
                let mut start = rng.index(5);
                while start < n {
                    let end = (start + 1 + rng.index(40)).min(n);
                    ranges.push(start..end);
                    start = end + rng.index(3);
                }
                if let Some(last) = ranges.last_mut() {
                    last.end = n;
                }
                let score = |j: usize| {
                    let c: f64 = (0..DIM).map(|d| f64::from(x[d] - y[d][j]).powi(2)).sum();
                    f64::from(lw[j]) + (f64::from(g[j]) - c) * f64::from(inv_eps)
                };
                let block_scores: Vec<Vec<f64>> = ranges
                    .iter()
                    .map(|r| r.clone().map(score).collect())
                    .collect();
                let m = block_scores
                    .iter()
                    .flatten()
                    .copied()
                    .fold(f64::NEG_INFINITY, f64::max);
                let direct: Vec<f64> = block_scores
                    .iter()
                    .map(|b| b.iter().map(|v| (v - m).exp()).sum())
                    .collect();
                let total: f64 = direct.iter().sum();
                let mut acc = RowSum::new();
                let pairs = stream_with::<false>(
                    body,
                    &x,
                    &y,
                    &lw,
                    &g,
                    inv_eps,
                    &ranges,
                    Sink::Row(&mut acc),
                );
                let expected: usize = ranges.iter().map(Range::len).sum();
                assert_eq!(pairs, expected as u64);
                let (got, want) = (acc.log_sum(), m + total.ln());
                assert!(
                    (got - want).abs() < 1e-4,
                    "{body:?} case {case}: {got} vs {want}"
                );
                let lens: Vec<u32> = ranges.iter().map(|r| r.len() as u32).collect();
                let mut scores = vec![0.0f32; expected.div_ceil(16) * 16 + 16];
                let mut out = vec![0.0f32; ranges.len()];
                let mut sums = BlockSums {
                    lens: &lens,
                    scores: &mut scores,
                    out: &mut out,
                    max: f32::NEG_INFINITY,
                };
                let pairs = stream_with::<false>(
                    body,
                    &x,
                    &y,
                    &lw,
                    &g,
                    inv_eps,
                    &ranges,
                    Sink::Blocks(&mut sums),
                );
                assert_eq!(pairs, expected as u64);
                let shift = (f64::from(sums.max) - m).exp();
                for (k, (&o, d)) in out.iter().zip(&direct).enumerate() {
                    let o = f64::from(o) * shift;
                    assert!(
                        (o - d).abs() <= 1e-4 * d.max(1e-6),
                        "{body:?} case {case} block {k}: {o} vs {d}"
                    );
                }
            }
        }
    }

    #[test]
    fn streamed_row_matches_direct_log_sum_exp() {
        let n = 150;
        let y: [Vec<f32>; DIM] =
            std::array::from_fn(|d| (0..n).map(|j| ((j * (d + 3)) % 17) as f32 / 17.0).collect());
        let h: Vec<f32> = (0..n).map(|j| -(j as f32) * 0.01).collect();
        let g = vec![0.0f32; n];
        let x = [0.3, 0.1, 0.7, 0.2, 0.9];
        let inv_eps = 20.0;
        let mut acc = RowSum::new();
        let pairs = stream_row::<true>(&x, &y, &h, &g, inv_eps, &[0..40, 40..n], &mut acc);
        assert_eq!(pairs, n as u64);
        let scores: Vec<f64> = (0..n)
            .map(|j| {
                let c: f64 = (0..DIM).map(|d| f64::from(x[d] - y[d][j]).powi(2)).sum();
                f64::from(h[j]) - c * f64::from(inv_eps)
            })
            .collect();
        let m = scores.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        let s: f64 = scores.iter().map(|v| (v - m).exp()).sum();
        assert!((acc.log_sum() - (m + s.ln())).abs() < 1e-5);
        let bary0: f64 = (0..n)
            .map(|j| (scores[j] - m).exp() * f64::from(y[0][j]))
            .sum::<f64>()
            / s;
        let bary = acc.barycentre().map(|(t, _)| f64::from(t[0]));
        assert!(bary.is_some_and(|b| (b - bary0).abs() < 1e-5), "{bary:?}");
    }

    #[test]
    fn a_row_without_a_finite_score_has_no_barycentre() {
        // The row's largest score weighs exactly 1: a row with mass has sum ≥ 1.
        assert_eq!(exp_nonpositive(0.0), 1.0);
        let n = 40;
        let y: [Vec<f32>; DIM] = std::array::from_fn(|d| (0..n).map(|j| (j + d) as f32).collect());
        let g = vec![0.0f32; n];
        let x = [0.5; DIM];
        let row = |lw: &[f32], inv_eps: f32, ranges: &[Range<usize>]| {
            let mut acc = RowSum::new();
            stream_row::<true>(&x, &y, lw, &g, inv_eps, ranges, &mut acc);
            acc.barycentre()
        };
        let uniform = vec![-(n as f32).ln(); n];
        let all = [0..n / 2, n / 2..n];
        // Nothing streamed.
        assert_eq!(row(&uniform, 1.0, &[]), None);
        assert_eq!(row(&uniform, 1.0, &[3..3, 5..5]), None);
        // Zero weights: every score is −∞.
        assert_eq!(row(&vec![f32::NEG_INFINITY; n], 1.0, &all), None);
        // Costs over ε beyond f32 range: every score is −∞.
        assert_eq!(row(&uniform, f32::MAX, &all), None);
        // The same row with one finite score left is a point mass on it.
        let mut one = vec![f32::NEG_INFINITY; n];
        one[7] = 0.0;
        let (t, c) = row(&one, 1.0, &all).expect("one finite score");
        assert_eq!(t, std::array::from_fn(|d| y[d][7]));
        assert!(
            (c - (0..DIM)
                .map(|d| f64::from(x[d] - y[d][7]).powi(2))
                .sum::<f64>())
            .abs()
                < 1e-9
        );
    }
}
