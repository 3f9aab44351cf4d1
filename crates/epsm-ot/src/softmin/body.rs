//! The per-block body of a soft-min row: scores into a stack buffer, then
//! maximum, exponentials and sum in fixed-order lanes. Plain loops only: the
//! body is inlined into each SIMD-compiled copy of the row (see the parent
//! module). The target columns are cut to one length once per row
//! ([`Columns`]), so each streamed range is checked against that one length
//! instead of once per column (a row streams many ranges of about a hundred
//! targets).

use std::ops::Range;

use super::exp::exp_nonpositive;
use super::{BLOCK, BlockSums, LANES, RowSum};
use crate::points::{DIM, Point};

/// The target columns a row streams: five coordinates, log-weights and potentials, all
/// of one length.
pub(super) struct Columns<'a> {
    pub(super) y: [&'a [f32]; DIM],
    pub(super) lw: &'a [f32],
    pub(super) g: &'a [f32],
}

impl<'a> Columns<'a> {
    /// Views of `y`, `lw` and `g` cut to the length of `lw` (a longer column is cut; a
    /// shorter one panics, an internal error): with one length, the bounds checks of a
    /// range's seven slices fold into one.
    #[inline(always)]
    pub(super) fn new(y: &'a [Vec<f32>; DIM], lw: &'a [f32], g: &'a [f32]) -> Self {
        let n = lw.len();
        Self {
            y: [&y[0][..n], &y[1][..n], &y[2][..n], &y[3][..n], &y[4][..n]],
            lw,
            g: &g[..n],
        }
    }
}

/// Scores `lw_j + (g_j − c(x, y_j))·inv_eps` of the targets `range` into `out` (as long as
/// `range`) and, if `COSTS`, the costs `c(x, y_j)` into `costs` (as long as `range`; unused
/// otherwise).
#[inline(always)]
fn score_into<const COSTS: bool>(
    x: &Point,
    cols: &Columns,
    inv_eps: f32,
    range: Range<usize>,
    out: &mut [f32],
    costs: &mut [f32],
) {
    let (c0, c1, c2, c3, c4) = (
        &cols.y[0][range.clone()],
        &cols.y[1][range.clone()],
        &cols.y[2][range.clone()],
        &cols.y[3][range.clone()],
        &cols.y[4][range.clone()],
    );
    let (lws, gs) = (&cols.lw[range.clone()], &cols.g[range]);
    for k in 0..out.len() {
        let d0 = x[0] - c0[k];
        let d1 = x[1] - c1[k];
        let d2 = x[2] - c2[k];
        let d3 = x[3] - c3[k];
        let d4 = x[4] - c4[k];
        let c = d0 * d0 + d1 * d1 + d2 * d2 + d3 * d3 + d4 * d4;
        if COSTS {
            costs[k] = c;
        }
        out[k] = lws[k] + (gs[k] - c) * inv_eps;
    }
}

/// The scores of [`score_into`] for the targets `range` into `out[..range.len()]`, rounded up
/// to whole chunks of `W` lanes (the vector width of the body): the last partial chunk is
/// computed whole from the targets after the range (its extra scores land in
/// `out[range.len()..]`, at most `W − 1` of them, for the caller to overwrite or mask), or
/// one by one where the columns end first.
///
/// A row streams many short ranges (about a hundred targets each at n = 16384), so the
/// compiled loop's scalar remainder of up to `W − 1` pairs per range would cost a fifth of
/// the scoring; with a multiple of `W` targets it never runs.
#[inline(always)]
fn score_chunks<const W: usize>(
    x: &Point,
    cols: &Columns,
    inv_eps: f32,
    range: Range<usize>,
    out: &mut [f32],
) {
    let len = range.len();
    let whole = if range.start + len.next_multiple_of(W) <= cols.lw.len() {
        len.next_multiple_of(W)
    } else {
        len - len % W
    };
    score_into::<false>(
        x,
        cols,
        inv_eps,
        range.start..range.start + whole,
        &mut out[..whole],
        &mut [],
    );
    if whole < len {
        score_into::<false>(
            x,
            cols,
            inv_eps,
            range.start + whole..range.end,
            &mut out[whole..len],
            &mut [],
        );
    }
}

/// [`stream_row`] without moments: scores of consecutive ranges fill one
/// [`BLOCK`]-long buffer, reduced (maximum, exponentials, sum) once it is
/// full, so many short ranges cost no more per pair than one long one.
/// Scores are computed in chunks of `W` lanes ([`score_chunks`]).
#[inline(always)]
pub(super) fn gathered_sum<const W: usize>(
    x: &Point,
    cols: &Columns,
    inv_eps: f32,
    ranges: &[Range<usize>],
    acc: &mut RowSum,
) -> u64 {
    // Room for a last chunk's extra scores past a full block.
    let mut scores = [f32::NEG_INFINITY; BLOCK + LANES];
    let mut fill = 0;
    let mut pairs = 0;
    for range in ranges {
        let mut start = range.start;
        while start < range.end {
            let len = (range.end - start).min(BLOCK - fill);
            score_chunks::<W>(x, cols, inv_eps, start..start + len, &mut scores[fill..]);
            fill += len;
            start += len;
            if fill == BLOCK {
                reduce_scores(&mut scores[..BLOCK], acc);
                fill = 0;
            }
        }
        pairs += range.len() as u64;
    }
    if fill > 0 {
        let padded = fill.div_ceil(LANES) * LANES;
        scores[fill..padded].fill(f32::NEG_INFINITY);
        reduce_scores(&mut scores[..padded], acc);
    }
    pairs
}

/// Adds `Σ exp(score)` of a buffer whose length is a multiple of [`LANES`] to `acc` (the buffer is overwritten).
#[inline(always)]
fn reduce_scores(scores: &mut [f32], acc: &mut RowSum) {
    acc.rescale_to(lane_max(scores));
    if acc.max == f32::NEG_INFINITY {
        return;
    }
    let m = acc.max;
    for s in scores.iter_mut() {
        *s = exp_nonpositive(*s - m);
    }
    acc.sum += f64::from(lane_sum(scores));
}

/// The body of [`stream_blocks`]: scores (in chunks of `W` lanes, [`score_chunks`]), their
/// maximum, weights, then one sum per block.
#[inline(always)]
pub(super) fn block_sums<const W: usize>(
    x: &Point,
    cols: &Columns,
    inv_eps: f32,
    ranges: &[Range<usize>],
    sums: &mut BlockSums,
) -> u64 {
    let mut len = 0;
    for range in ranges {
        score_chunks::<W>(x, cols, inv_eps, range.clone(), &mut sums.scores[len..]);
        len += range.len();
    }
    let padded = len.div_ceil(LANES) * LANES;
    let scores = &mut sums.scores[..padded];
    scores[len..].fill(f32::NEG_INFINITY);
    let m = lane_max(scores);
    sums.max = m;
    if m == f32::NEG_INFINITY {
        sums.out.fill(0.0);
        return len as u64;
    }
    for s in scores.iter_mut() {
        *s = exp_nonpositive(*s - m);
    }
    let mut start = 0;
    for (o, &l) in sums.out.iter_mut().zip(sums.lens) {
        let end = start + l as usize;
        let mut t = 0.0f32;
        for &w in &scores[start..end] {
            t += w;
        }
        *o = t;
        start = end;
    }
    len as u64
}

/// Per-block buffers of a streamed row.
pub(super) struct Scratch {
    pub(super) scores: [f32; BLOCK],
    pub(super) costs: [f32; BLOCK],
    pub(super) weights: [f32; BLOCK],
}

/// Streams one range of targets into `acc` with its moments, in blocks of [`BLOCK`];
/// returns its length.
#[inline(always)]
pub(super) fn push_range_moments(
    x: &Point,
    cols: &Columns,
    inv_eps: f32,
    range: Range<usize>,
    acc: &mut RowSum,
    scratch: &mut Scratch,
) -> u64 {
    let Scratch {
        scores,
        costs,
        weights,
    } = scratch;
    let mut start = range.start;
    while start < range.end {
        let len = (range.end - start).min(BLOCK);
        let padded = len.div_ceil(LANES) * LANES;
        score_into::<true>(
            x,
            cols,
            inv_eps,
            start..start + len,
            &mut scores[..len],
            &mut costs[..len],
        );
        scores[len..padded].fill(f32::NEG_INFINITY);
        let block_max = lane_max(&scores[..padded]);
        acc.rescale_to(block_max);
        if acc.max == f32::NEG_INFINITY {
            start += len;
            continue;
        }
        let m = acc.max;
        for (w, &sc) in weights[..padded].iter_mut().zip(&scores[..padded]) {
            *w = exp_nonpositive(sc - m);
        }
        acc.sum += f64::from(lane_sum(&weights[..padded]));
        let mut mom = [0.0f32; DIM + 1];
        for k in 0..len {
            for (m, column) in mom.iter_mut().zip(&cols.y) {
                *m += weights[k] * column[start + k];
            }
            mom[DIM] += weights[k] * costs[k];
        }
        for (a, b) in acc.moments.iter_mut().zip(mom) {
            *a += f64::from(b);
        }
        start += len;
    }
    range.len() as u64
}

/// Sum of a slice whose length is a multiple of [`LANES`], in vectorisable lanes (fixed order).
#[inline(always)]
fn lane_sum(values: &[f32]) -> f32 {
    let mut lanes = [0.0f32; LANES];
    for chunk in values.chunks_exact(LANES) {
        for l in 0..LANES {
            lanes[l] += chunk[l];
        }
    }
    lanes.iter().sum()
}

/// Maximum of a slice whose length is a multiple of [`LANES`], in vectorisable lanes.
#[inline(always)]
fn lane_max(values: &[f32]) -> f32 {
    let mut lanes = [f32::NEG_INFINITY; LANES];
    for chunk in values.chunks_exact(LANES) {
        for l in 0..LANES {
            lanes[l] = if chunk[l] > lanes[l] {
                chunk[l]
            } else {
                lanes[l]
            };
        }
    }
    lanes.iter().copied().fold(f32::NEG_INFINITY, f32::max)
}
