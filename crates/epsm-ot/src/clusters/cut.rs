//! The per-point cut of a kept block pair (the box inequality of the parent
//! module): which target blocks one source point keeps, as merged ranges.

use std::ops::Range;

use super::{Clustered, PotentialFit};
use crate::cpu::{Simd, active_simd};
use crate::points::{DIM, Point};

/// Which point-to-block bound a [`PointCut`] tests (see the parent module).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub(crate) enum Bound {
    /// `‖d‖² − ‖2d + a‖ r_J − ḡ − max r^g`: looser, keeps the weak links between
    /// blocks that the coarse correction's block masses must see (with the box
    /// bound, seed 2 of the 16384-point benchmark needs a second bridged
    /// correction and 17 % more pair evaluations).
    Ball,
    /// `box(x + a/2)² − ⟨a, x − c⟩ − ‖a‖²/4 − ḡ − max r^g`: 13 % fewer pairs at n = 16384.
    #[default]
    Box,
}

/// The point-to-block bound of the parent module (box or ball) for a list of target
/// blocks, as `f32` columns so the test of one point against every block vectorises.
///
/// Per block, with the fit `g_j = ḡ + ⟨a, y_j − c⟩ + r_j`: for every `j` in it,
/// `c(x, y_j) − g_j ≥ box(x + a/2)² − ⟨a, x⟩ − K` with `K = ‖a‖²/4 + ḡ + max r − ⟨a, c⟩`
/// (taken in `f64`, so the centroid's rounding does not enter).
#[derive(Debug, Clone, Default)]
pub(crate) struct PointCut {
    bound: Bound,
    /// Ball bound: the blocks' centroids.
    centroid: [Vec<f32>; DIM],
    /// Ball bound: the blocks' radii, widened by the rounding of the centroid to `f32`.
    radius: Vec<f32>,
    /// Ball bound: `ḡ + max r^g`.
    ball_offset: Vec<f32>,
    /// Half the slope of the target potential's fit, `a/2`.
    half_slope: [Vec<f32>; DIM],
    /// Bounding boxes of the blocks' points: smallest coordinates.
    lo: [Vec<f32>; DIM],
    /// Bounding boxes of the blocks' points: largest coordinates.
    hi: [Vec<f32>; DIM],
    /// `K` of the bound.
    offset: Vec<f32>,
    /// The block's part of the rounding slack: [`CUT_ROUNDING`] `(‖a‖² + |K|)`.
    slack: Vec<f32>,
    /// The blocks' point ranges.
    ranges: Vec<Range<usize>>,
    /// Bit `k`: block `k` starts where block `k − 1` ends (layout of [`Selection`]'s bits).
    continues: Vec<u64>,
    /// Every column's entry per block, for [`Self::subset_into`] (filled by
    /// [`Self::gather`]; a subset leaves it empty).
    records: Vec<Record>,
}

/// One block's entries of a [`PointCut`]'s columns, together so a list of blocks is
/// copied out of a whole table one block at a time.
#[derive(Debug, Clone, Copy, Default)]
struct Record {
    half_slope: [f32; DIM],
    lo: Point,
    hi: Point,
    offset: f32,
    slack: f32,
    centroid: [f32; DIM],
    radius: f32,
    ball_offset: f32,
}

/// What [`PointCut::select`] kept for one point.
#[derive(Debug, Clone, Default)]
pub(crate) struct Selection {
    /// Scratch: whether each block of the list is kept (0 or 1), zero-padded to a multiple of 64.
    keep: Vec<u8>,
    /// Bit `k % 64` of word `k / 64`: block `k` of the list is kept.
    bits: Vec<u64>,
    /// The kept blocks' ranges, consecutive blocks merged.
    pub ranges: Vec<Range<usize>>,
}

impl Selection {
    /// Every block of `list` kept (`ranges`: every block's range), reusing the buffers.
    pub fn set_all(&mut self, ranges: &[Range<usize>], list: &[u32]) {
        let n = list.len();
        self.bits.clear();
        self.bits.resize(n / 64, u64::MAX);
        if !n.is_multiple_of(64) {
            self.bits.push((1u64 << (n % 64)) - 1);
        }
        self.ranges.clear();
        for &j in list {
            push_merged(&mut self.ranges, ranges[j as usize].clone());
        }
    }

    /// Positions in the list of the kept blocks, in increasing order, into `out` (cleared first).
    pub fn kept_into(&self, out: &mut Vec<usize>) {
        out.clear();
        for (w, &word) in self.bits.iter().enumerate() {
            let mut rest = word;
            while rest != 0 {
                out.push(64 * w + rest.trailing_zeros() as usize);
                rest &= rest - 1;
            }
        }
    }

    /// Makes this selection a copy of `other`, reusing its buffers.
    pub fn copy_from(&mut self, other: &Self) {
        self.bits.clone_from(&other.bits);
        self.ranges.clone_from(&other.ranges);
    }
}

impl PointCut {
    /// The bounds of `clustered`'s blocks listed in `list`, in that order, from the fits of its potential.
    pub fn gather(
        clustered: &Clustered,
        fits: &[PotentialFit],
        list: &[u32],
        bound: Bound,
    ) -> Self {
        let with = || Vec::with_capacity(list.len());
        let mut cut = Self {
            bound,
            centroid: std::array::from_fn(|_| Vec::new()),
            radius: Vec::new(),
            ball_offset: Vec::new(),
            half_slope: std::array::from_fn(|_| with()),
            lo: std::array::from_fn(|_| with()),
            hi: std::array::from_fn(|_| with()),
            offset: with(),
            slack: with(),
            ranges: Vec::with_capacity(list.len()),
            continues: vec![0; list.len().div_ceil(64)],
            records: Vec::with_capacity(list.len()),
        };
        for &j in list {
            let (c, fit) = (&clustered.clusters[j as usize], &fits[j as usize]);
            let mut slope_sq = 0.0;
            let mut slope_centroid = 0.0;
            for d in 0..DIM {
                cut.half_slope[d].push((0.5 * fit.slope[d]) as f32);
                cut.lo[d].push(c.lo[d]);
                cut.hi[d].push(c.hi[d]);
                slope_sq += fit.slope[d] * fit.slope[d];
                slope_centroid += fit.slope[d] * c.centroid[d];
            }
            if bound == Bound::Ball {
                for d in 0..DIM {
                    cut.centroid[d].push(c.centroid[d] as f32);
                }
                // Cover the rounding of the centroid to f32.
                let shift = c.centroid.iter().fold(0.0f64, |m, v| m.max(v.abs())) * 1e-6;
                cut.radius.push((c.radius + shift) as f32);
                cut.ball_offset.push((fit.mean + fit.max_residual) as f32);
            }
            let offset = 0.25 * slope_sq + fit.mean + fit.max_residual - slope_centroid;
            cut.offset.push(offset as f32);
            cut.slack
                .push((f64::from(CUT_ROUNDING) * (slope_sq + offset.abs())) as f32);
            let k = cut.offset.len() - 1;
            let ball = bound == Bound::Ball;
            cut.records.push(Record {
                half_slope: std::array::from_fn(|d| cut.half_slope[d][k]),
                lo: c.lo,
                hi: c.hi,
                offset: cut.offset[k],
                slack: cut.slack[k],
                centroid: std::array::from_fn(|d| if ball { cut.centroid[d][k] } else { 0.0 }),
                radius: if ball { cut.radius[k] } else { 0.0 },
                ball_offset: if ball { cut.ball_offset[k] } else { 0.0 },
            });
            let k = cut.ranges.len();
            if cut.ranges.last().is_some_and(|r| r.end == c.range.start) {
                cut.continues[k / 64] |= 1 << (k % 64);
            }
            cut.ranges.push(c.range.clone());
        }
        cut
    }

    /// The blocks at positions `list` of this cut, in that order, into `out` (whose buffers
    /// are reused): a pass gathers every block's bound once ([`Self::gather`] over all
    /// blocks) and each source block copies the ones it lists.
    pub fn subset_into(&self, list: &[u32], out: &mut Self) {
        /// `v` cleared and refilled with `len` zeros, as a slice of length `len` (cut to
        /// `len` explicitly, so the copy below knows every column's length and checks no index).
        fn sized(v: &mut Vec<f32>, len: usize) -> &mut [f32] {
            v.clear();
            v.resize(len, 0.0);
            &mut v[..len]
        }
        let n = list.len();
        out.bound = self.bound;
        let ball = self.bound == Bound::Ball;
        let ball_n = if ball { n } else { 0 };
        let half = out.half_slope.each_mut().map(|v| sized(v, n));
        let lo = out.lo.each_mut().map(|v| sized(v, n));
        let hi = out.hi.each_mut().map(|v| sized(v, n));
        let (offset, slack) = (sized(&mut out.offset, n), sized(&mut out.slack, n));
        let mut centroid = out.centroid.each_mut().map(|v| sized(v, ball_n));
        let radius = sized(&mut out.radius, ball_n);
        let ball_offset = sized(&mut out.ball_offset, ball_n);
        // One record per listed block: its columns' entries side by side.
        for (k, &j) in list.iter().enumerate() {
            let r = &self.records[j as usize];
            for d in 0..DIM {
                half[d][k] = r.half_slope[d];
                lo[d][k] = r.lo[d];
                hi[d][k] = r.hi[d];
            }
            offset[k] = r.offset;
            slack[k] = r.slack;
            if ball {
                for (column, &v) in centroid.iter_mut().zip(&r.centroid) {
                    column[k] = v;
                }
                radius[k] = r.radius;
                ball_offset[k] = r.ball_offset;
            }
        }
        out.records.clear();
        out.ranges.clear();
        out.ranges
            .extend(list.iter().map(|&j| self.ranges[j as usize].clone()));
        out.continues.clear();
        out.continues.resize(n.div_ceil(64), 0);
        for k in 1..n {
            if out.ranges[k - 1].end == out.ranges[k].start {
                out.continues[k / 64] |= 1 << (k % 64);
            }
        }
    }

    /// Keeps the blocks whose bound on `c(x, y_j) − g_j` may be at most `limit`, and
    /// returns whether there is any (the caller decides what a point that keeps none streams).
    ///
    /// Conservative under `f32` rounding: a block is dropped only if its bound
    /// exceeds `limit` by more than [`CUT_ROUNDING`] times the magnitudes
    /// involved, far above the accumulated rounding of these few operations,
    /// so potentials of any size (clouds far apart) never cut a pair they should not.
    pub fn select(&self, x: &Point, limit: f32, out: &mut Selection) -> bool {
        self.select_with(active_simd(), x, limit, out)
    }

    /// [`Self::select`] with the body compiled for `simd`, or the portable one if the running CPU lacks it.
    fn select_with(&self, simd: Simd, x: &Point, limit: f32, out: &mut Selection) -> bool {
        simd.run(
            #[inline(always)]
            |_| self.select_portable(x, limit, out),
        );
        !out.ranges.is_empty()
    }

    /// The body of [`Self::select`]: a vectorisable test, then a branch-free compaction.
    #[inline(always)]
    fn select_portable(&self, x: &Point, limit: f32, out: &mut Selection) {
        // A copy, kept in registers (see `softmin::stream_portable`).
        let x = &{ *x };
        let n = self.ranges.len();
        out.keep.resize(n.next_multiple_of(64), 0);
        let (keep, pad) = out.keep.split_at_mut(n);
        pad.fill(0);
        match self.bound {
            Bound::Box => self.box_test(x, limit, keep),
            Bound::Ball => self.ball_test(x, limit, keep),
        }
        // Bit masks: a kept block opens a range unless it joins the previous kept block
        // (continues it), and closes it unless the next block joins it.
        out.bits.clear();
        out.bits.extend(out.keep.chunks_exact(64).map(pack_word));
        let words = &out.bits;
        let joins = |w: usize| {
            let previous = (words[w] << 1) | if w > 0 { words[w - 1] >> 63 } else { 0 };
            words[w] & previous & self.continues[w]
        };
        // Plain loops over the set bits: iterator adapters here were calls per range.
        let ranges = &mut out.ranges;
        ranges.clear();
        for (w, &word) in words.iter().enumerate() {
            let mut opens = word & !joins(w);
            while opens != 0 {
                let k = 64 * w + opens.trailing_zeros() as usize;
                opens &= opens - 1;
                ranges.push(self.ranges[k].start..0);
            }
        }
        let mut r = 0;
        for w in 0..words.len() {
            let next = if w + 1 < words.len() {
                joins(w + 1) << 63
            } else {
                0
            };
            let mut closes = words[w] & !((joins(w) >> 1) | next);
            while closes != 0 {
                let k = 64 * w + closes.trailing_zeros() as usize;
                closes &= closes - 1;
                ranges[r].end = self.ranges[k].end;
                r += 1;
            }
        }
    }
}

impl PointCut {
    /// The box bound of every block for the point `x` into `keep` (see [`Self::select`]).
    #[inline(always)]
    fn box_test(&self, x: &Point, limit: f32, keep: &mut [u8]) {
        let n = keep.len();
        let [h0, h1, h2, h3, h4] = &self.half_slope;
        let (h0, h1, h2, h3, h4) = (&h0[..n], &h1[..n], &h2[..n], &h3[..n], &h4[..n]);
        let [l0, l1, l2, l3, l4] = &self.lo;
        let (l0, l1, l2, l3, l4) = (&l0[..n], &l1[..n], &l2[..n], &l3[..n], &l4[..n]);
        let [u0, u1, u2, u3, u4] = &self.hi;
        let (u0, u1, u2, u3, u4) = (&u0[..n], &u1[..n], &u2[..n], &u3[..n], &u4[..n]);
        let (offset, block_slack) = (&self.offset[..n], &self.slack[..n]);
        // Rounding of `p = x + a/2` (within a few `u (gg + ‖p‖²)` on `gg`, `‖p‖² ≤ 2‖x‖² +
        // ‖a‖²/2`), of `⟨a, x⟩` (within a few `u ‖a‖ ‖x‖ ≤ u (‖a‖² + ‖x‖²)`), of `K` and of the
        // limit: the point's part here, the block's in `slack`, `gg`'s in the loop.
        let xx = x[0] * x[0] + x[1] * x[1] + x[2] * x[2] + x[3] * x[3] + x[4] * x[4];
        let bar = limit + CUT_ROUNDING * (3.0 * xx + limit.abs());
        for k in 0..n {
            let p = [
                x[0] + h0[k],
                x[1] + h1[k],
                x[2] + h2[k],
                x[3] + h3[k],
                x[4] + h4[k],
            ];
            let gap = [
                box_gap(l0[k], u0[k], p[0]),
                box_gap(l1[k], u1[k], p[1]),
                box_gap(l2[k], u2[k], p[2]),
                box_gap(l3[k], u3[k], p[3]),
                box_gap(l4[k], u4[k], p[4]),
            ];
            let gg = gap[0] * gap[0]
                + gap[1] * gap[1]
                + gap[2] * gap[2]
                + gap[3] * gap[3]
                + gap[4] * gap[4];
            let hx = h0[k] * x[0] + h1[k] * x[1] + h2[k] * x[2] + h3[k] * x[3] + h4[k] * x[4];
            keep[k] =
                u8::from(gg - 2.0 * hx - offset[k] <= bar + CUT_ROUNDING * gg + block_slack[k]);
        }
    }

    /// The ball bound of every block for the point `x` into `keep` (see [`Self::select`]).
    #[inline(always)]
    fn ball_test(&self, x: &Point, limit: f32, keep: &mut [u8]) {
        let n = keep.len();
        let [c0, c1, c2, c3, c4] = &self.centroid;
        let (c0, c1, c2, c3, c4) = (&c0[..n], &c1[..n], &c2[..n], &c3[..n], &c4[..n]);
        let [h0, h1, h2, h3, h4] = &self.half_slope;
        let (h0, h1, h2, h3, h4) = (&h0[..n], &h1[..n], &h2[..n], &h3[..n], &h4[..n]);
        let (radius, offset) = (&self.radius[..n], &self.ball_offset[..n]);
        for k in 0..n {
            let d = [
                x[0] - c0[k],
                x[1] - c1[k],
                x[2] - c2[k],
                x[3] - c3[k],
                x[4] - c4[k],
            ];
            // `2d + a`.
            let t = [
                2.0 * (d[0] + h0[k]),
                2.0 * (d[1] + h1[k]),
                2.0 * (d[2] + h2[k]),
                2.0 * (d[3] + h3[k]),
                2.0 * (d[4] + h4[k]),
            ];
            let dd = d[0] * d[0] + d[1] * d[1] + d[2] * d[2] + d[3] * d[3] + d[4] * d[4];
            let tt = t[0] * t[0] + t[1] * t[1] + t[2] * t[2] + t[3] * t[3] + t[4] * t[4];
            let tilt = tt.sqrt() * radius[k];
            let slack = CUT_ROUNDING * (dd + tilt + offset[k].abs() + limit.abs());
            keep[k] = u8::from(dd - tilt - offset[k] <= limit + slack);
        }
    }
}

/// Bit `k` set iff byte `k` of a 64-byte chunk of 0/1 flags is 1.
///
/// Eight flags at a time: the multiplication moves byte `b`'s low bit to bit `56 + b`
/// (the partial products never overlap, so nothing carries into the top byte).
#[inline(always)]
fn pack_word(chunk: &[u8]) -> u64 {
    const GATHER: u64 = 0x0102_0408_1020_4080;
    let mut word = 0u64;
    for (b, eight) in chunk.chunks_exact(8).enumerate() {
        let mut bytes = [0u8; 8];
        bytes.copy_from_slice(eight);
        word |= (u64::from_le_bytes(bytes).wrapping_mul(GATHER) >> 56) << (8 * b);
    }
    word
}

/// Distance from `p` to the interval `[lo, hi]` along one axis, as comparisons and selects
/// (`f32::max` is not vectorised here: its NaN rule adds a scalar test per lane).
#[inline(always)]
fn box_gap(lo: f32, hi: f32, p: f32) -> f32 {
    let (below, above) = (lo - p, p - hi);
    let gap = if below > above { below } else { above };
    if gap > 0.0 { gap } else { 0.0 }
}

/// Appends `r` to `out`, extending the last range instead if `r` continues it.
fn push_merged(out: &mut Vec<Range<usize>>, r: Range<usize>) {
    match out.last_mut() {
        Some(last) if last.end == r.start => last.end = r.end,
        _ => out.push(r),
    }
}

/// Relative slack of [`PointCut::select`]: about 60 `f32` roundings.
const CUT_ROUNDING: f32 = 4e-6;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::clusters::fit_potentials;
    use crate::points::PointCloud;
    use crate::synthetic::{Rng, blobs_pair};
    use crate::tests::translated;

    /// Every block holding a pair with `c(x, y_j) − g_j ≤ limit` is kept and the ranges are
    /// the kept blocks' merged; with `drops`, most blocks are dropped (the check is not vacuous).
    fn check_cut(source: &PointCloud, target: &PointCloud, slope: f64, drops: bool, bound: Bound) {
        let (x, y) = (Clustered::new(source, 16), Clustered::new(target, 16));
        let mut rng = Rng::new(5);
        // A smooth tilt plus noise of the size of the kernel width: the kind of potential a plan has.
        let g: Vec<f64> = (0..y.cloud.len())
            .map(|j| slope * f64::from(y.cloud.point(j)[3]) + 0.01 * f64::from(rng.uniform()))
            .collect();
        let fits = fit_potentials(&y, &g);
        let list: Vec<u32> = (0..y.clusters.len() as u32).collect();
        let cut = PointCut::gather(&y, &fits, &list, bound);
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
            // Every body the CPU has (the portable one on any CPU) keeps the same blocks.
            let bodies = Simd::supported();
            let body = bodies[(i / 7) % bodies.len()];
            cut.select_with(body, &p, limit as f32, &mut selection);
            let mut chosen = Vec::new();
            selection.kept_into(&mut chosen);
            for &other in &bodies {
                let mut again = Selection::default();
                cut.select_with(other, &p, limit as f32, &mut again);
                assert_eq!(
                    again.ranges, selection.ranges,
                    "point {i}: {other:?} vs {body:?}"
                );
            }
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
    fn packed_words_hold_each_flag_in_its_bit() {
        let mut rng = Rng::new(3);
        for _ in 0..200 {
            let flags: Vec<u8> = (0..64).map(|_| u8::from(rng.uniform() < 0.5)).collect();
            let want = flags
                .iter()
                .enumerate()
                .fold(0u64, |w, (k, &f)| w | (u64::from(f) << k));
            assert_eq!(pack_word(&flags), want);
        }
        assert_eq!(pack_word(&[1; 64]), u64::MAX);
        assert_eq!(pack_word(&[0; 64]), 0);
    }

    #[test]
    fn a_subset_of_the_whole_cut_is_the_cut_of_the_list() {
        let (_, t) = blobs_pair(1024, 3).unwrap_or_else(|| panic!("fixture"));
        let y = Clustered::new(&t, 16);
        let g: Vec<f64> = (0..t.len())
            .map(|j| 0.2 * f64::from(t.point(j)[4]))
            .collect();
        let fits = fit_potentials(&y, &g);
        let all: Vec<u32> = (0..y.clusters.len() as u32).collect();
        let list: Vec<u32> = all.iter().copied().filter(|j| j % 3 != 1).collect();
        let mut out = PointCut::default();
        for bound in [Bound::Box, Bound::Ball] {
            PointCut::gather(&y, &fits, &all, bound).subset_into(&list, &mut out);
            let mut direct = PointCut::gather(&y, &fits, &list, bound);
            // A subset keeps no records of its own.
            direct.records.clear();
            assert_eq!(format!("{out:?}"), format!("{direct:?}"), "{bound:?}");
        }
    }

    #[test]
    fn point_cut_keeps_every_block_with_a_pair_below_the_limit() {
        let (s, t) = blobs_pair(2048, 9).unwrap_or_else(|| panic!("fixture"));
        for bound in [Bound::Box, Bound::Ball] {
            check_cut(&s, &t, 0.3, true, bound);
            // Far apart: costs and potentials of size 1e6, whose f32 rounding alone exceeds
            // 30ε; the slack then keeps every block (no cut, but no wrong one either).
            let far = translated(&t, [0.0, 0.0, 0.0, 1000.0, 0.0]);
            check_cut(&s, &far, 2000.0, false, bound);
        }
    }
}
