//! Step 4 of `exact`: the streaming optimality check over all pairs.
//!
//! For the rows that need it, every pair `(i, j)` is screened in `f32`
//! ([`screened_block`]) and tested in `f64` only where the screen cannot rule
//! out `c_ij − u_i − v_j < margin − tolerance`; whole block pairs are skipped
//! where the rigorous bound of `blocks` proves them above the margin. No
//! violated pair is missed, so a check that finds none certifies its rows.
//!
//! Each checked row leaves a **floor**: a lower bound on `c_ij − v_j` over
//! every pair the check did not return. Column potentials only fall
//! afterwards (augmenting paths lower them, auctions raise prices), so the
//! bound holds for the rest of the solve, and a row whose `u_i` has not
//! risen above its floor cannot have gained a violated pair outside the
//! candidate graph (whose edges the sparse solve keeps feasible): it needs
//! no new check (see `sparse::SparseAssignment::unsettled_rows`). A margin
//! above 0 returns each row's near-tight pairs too and raises the floor by
//! it, so the next rises of `u_i` by less than the margin need no check.

use rayon::prelude::*;

use crate::clusters::{Boxes, Clustered, fit_potentials, kept_targets};
use crate::cost::sq_dist_f64;
use crate::cpu::{Simd, active_simd};

/// A candidate edge `(row, column, cost)`.
pub(crate) type Edge = (u32, u32, f64);

/// What one check found.
pub(crate) struct Check {
    /// Each checked row's `per_row` pairs of smallest `c_ij − u_i − v_j`
    /// among those below `margin − tolerance`.
    pub found: Vec<Edge>,
    /// How many of `found` are violated (below `−tolerance`).
    pub violated: usize,
    /// Pairs evaluated.
    pub checked: u64,
}

/// Checks the rows flagged in `rows` against `u, v`: returns for each its
/// `per_row` pairs of smallest reduced cost `c_ij − u_i − v_j` among those
/// below `margin − tolerance`, and writes each checked row's floor (see the
/// module doc) to `floors`: `u_i + margin`, or `u_i` plus the largest
/// returned reduced cost when the row had more than `per_row` such pairs.
///
/// Target blocks are skipped where the block-pair bound of `blocks` proves
/// them above the margin for the row's whole cluster, and then per point where the
/// distance to a block's bounding box less its largest `v_j` does
/// ([`box_feasible`], tested against all the cluster's blocks in one
/// vectorised pass, [`far_boxes`]). Each remaining pair is first screened in `f32` (see
/// [`screened_block`]); only pairs the screen cannot rule out are tested in
/// `f64`, so no pair below the margin is missed.
#[allow(clippy::too_many_arguments)]
pub(crate) fn violations(
    x: &Clustered,
    y: &Clustered,
    u: &[f64],
    v: &[f64],
    margin: f64,
    tolerance: f64,
    per_row: usize,
    rows: &[bool],
    floors: &mut [f64],
) -> Check {
    // Bounds and screens test against the raised row potentials `u + margin`.
    let raised: Vec<f64> = u.iter().map(|&t| t + margin).collect();
    let (fit_u, fit_v) = (fit_potentials(x, &raised), fit_potentials(y, v));
    let (u32s, v32s) = (to_f32(&raised), to_f32(v));
    // Potentials beyond the f32 range: no screen, every pair is tested in f64.
    let screen = u32s.iter().chain(&v32s).all(|t| t.is_finite());
    let simd = active_simd();
    let cols = y.cloud.columns();
    let max_v: Vec<f64> = y
        .clusters
        .iter()
        .map(|c| {
            v[c.range.clone()]
                .iter()
                .copied()
                .fold(f64::NEG_INFINITY, f64::max)
        })
        .collect();
    let mut floor_parts = Vec::with_capacity(x.clusters.len());
    let mut rest = floors;
    for c in &x.clusters {
        let (part, tail) = rest.split_at_mut(c.range.len());
        floor_parts.push(part);
        rest = tail;
    }
    let parts: Vec<(Vec<Edge>, usize, u64)> = x
        .clusters
        .par_iter()
        .zip(&fit_u)
        .zip(floor_parts)
        .map(|((ci, fi), floors)| {
            let mut found = Vec::new();
            let mut violated = 0;
            let mut checked = 0u64;
            if !rows[ci.range.clone()].iter().any(|&r| r) {
                return (found, violated, checked);
            }
            let list = kept_targets(ci, fi, y, &fit_v, 0.0);
            let boxes = Boxes::gather(&y.clusters, &list);
            let list_max_v: Vec<f64> = list.iter().map(|&jb| max_v[jb as usize]).collect();
            let (mut box_sq, mut far) = (vec![0.0; list.len()], vec![false; list.len()]);
            let mut slack = [0.0f32; SCREEN_BLOCK];
            let mut row: Vec<Found> = Vec::new();
            for i in ci.range.clone().filter(|&i| rows[i]) {
                let p = x.cloud.point(i);
                simd.run(
                    #[inline(always)]
                    |_| far_boxes(&boxes, &p, raised[i], &list_max_v, &mut box_sq, &mut far),
                );
                let mut dropped = false;
                // Once pairs were dropped, only pairs up to the largest kept
                // reduced cost (`bar`) can still be among the row's `per_row`
                // smallest; the screen rules out `s ≥ bar − margin` (its `s` is
                // below the exact `c − u − v − margin`). Skipping the others
                // leaves the returned pairs and the floor as they were.
                let (mut bar, mut screen_limit) = (f64::INFINITY, 0.0);
                for (&jb, _) in list.iter().zip(&far).filter(|(_, far)| !**far) {
                    let cj = &y.clusters[jb as usize];
                    let range = cj.range.clone();
                    checked += range.len() as u64;
                    for start in range.clone().step_by(SCREEN_BLOCK) {
                        let block = start..(start + SCREEN_BLOCK).min(range.end);
                        let slack = &mut slack[..block.len()];
                        screened_block(simd, &p, u32s[i], cols, &v32s, block.clone(), slack);
                        for (j, &s) in block.zip(slack.iter()) {
                            if screen && f64::from(s) >= screen_limit {
                                continue;
                            }
                            let c = sq_dist_f64(&p, &y.cloud.point(j));
                            let reduced = c - u[i] - v[j];
                            // Rounding of c, u and v is not a violation (matters for far-apart clouds).
                            let rounding =
                                tolerance + 4.0 * f64::EPSILON * (c + u[i].abs() + v[j].abs());
                            if reduced < margin - rounding && reduced <= bar {
                                row.push((reduced, j as u32, c, reduced < -rounding));
                                if row.len() == 4 * per_row {
                                    dropped |= keep_worst(&mut row, per_row);
                                    bar = row.iter().map(|e| e.0).fold(f64::NEG_INFINITY, f64::max);
                                    screen_limit = bar - margin;
                                }
                            }
                        }
                    }
                }
                dropped |= keep_worst(&mut row, per_row);
                row.sort_unstable_by_key(|e| e.1);
                let rise = if dropped {
                    row.iter().map(|e| e.0).fold(f64::NEG_INFINITY, f64::max)
                } else {
                    margin
                };
                floors[i - ci.range.start] = u[i] + rise;
                violated += row.iter().filter(|e| e.3).count();
                found.extend(row.drain(..).map(|(_, j, c, _)| (i as u32, j, c)));
            }
            (found, violated, checked)
        })
        .collect();
    Check {
        violated: parts.iter().map(|p| p.1).sum(),
        checked: parts.iter().map(|p| p.2).sum(),
        found: parts.into_iter().flat_map(|p| p.0).collect(),
    }
}

/// Marks in `far[k]` the boxes `k` of `boxes` whose bound proves every pair
/// of point `p` (row potential `u`) with their cluster feasible
/// ([`box_feasible`], `max_v[k]` the cluster's largest `v_j`); `box_sq` takes
/// the distances. One branch-free pass over the boxes, so it vectorises.
#[inline(always)]
fn far_boxes(
    boxes: &Boxes,
    p: &crate::Point,
    u: f64,
    max_v: &[f64],
    box_sq: &mut [f64],
    far: &mut [bool],
) {
    boxes.dist_sq(p, box_sq);
    for ((far, &b), &m) in far.iter_mut().zip(box_sq.iter()).zip(max_v) {
        *far = box_feasible(b, u, m);
    }
}

/// Whether the box bound proves `c_ij − u − v_j ≥ 0` for every member `j` of a
/// target cluster, from `box_sq` (its [`Boxes::dist_sq`]
/// from point `i`) and `max_v`, the largest `v_j` of the cluster.
///
/// `c_ij ≥ box_sq` in exact arithmetic; the computed `box_sq`, the computed
/// `c_ij` and the subtractions each round by a few units of the last place
/// relative to `box_sq + |u| + |max_v|`, so the bound is accepted only with a
/// margin of 16 of them. Non-finite values are never accepted.
#[inline(always)]
fn box_feasible(box_sq: f64, u: f64, max_v: f64) -> bool {
    box_sq - u - max_v >= 16.0 * f64::EPSILON * (box_sq + u.abs() + max_v.abs())
}

/// A pair a check returns: reduced cost, column, cost, and whether it is violated.
type Found = (f64, u32, f64, bool);

/// Keeps the `per_row` most violated pairs (smallest reduced cost, ties by column) of `row`,
/// and returns whether any was dropped.
fn keep_worst(row: &mut Vec<Found>, per_row: usize) -> bool {
    if row.len() > per_row {
        row.select_nth_unstable_by(per_row, |a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        row.truncate(per_row);
        return true;
    }
    false
}

/// Targets screened per call of [`screened_block`].
const SCREEN_BLOCK: usize = 64;

/// Relative margin of the `f32` screen: four times its worst rounding error (see [`screened_block`]).
const SCREEN_MARGIN: f32 = 4e-6;

/// Absolute margin of the `f32` screen, above the error of squares that underflow (< 10⁻³⁷).
const SCREEN_FLOOR: f32 = 1e-36;

/// Potentials rounded to `f32` (infinite where out of range).
fn to_f32(p: &[f64]) -> Vec<f32> {
    p.iter().map(|&t| t as f32).collect()
}

/// `f32` screen of the reduced costs of point `p` (row potential `u`) against the targets `block`.
///
/// Writes `s_j = r_j − m_j` with `r_j = c_ij − u − v_j` computed in `f32` and
/// the margin `m_j = 4·10⁻⁶ (c_ij + |v_j| + |u|) + 10⁻³⁶`. The `f32` cost of `f32`
/// inputs is within `4.2·10⁻⁷ c_ij` of the exact one (exactly rounded
/// differences, squares and a sum of five non-negative terms), the rounded
/// potentials within `6·10⁻⁸` of theirs, and the two subtractions add at most
/// `6·10⁻⁸ (c + |v| + |u|)` each, so `|r_j − (c − u − v)| < 10⁻⁶ (c + |v| + |u|)`
/// (plus under 10⁻³⁷ where squares underflow):
/// `s_j ≥ 0` proves `c − u − v > 0`, not a violation. (With finite `f32`
/// potentials an infinite cost gives `s_j = NaN`, which the caller tests in `f64`.)
/// Written as one branch-free loop over SoA columns so it vectorises; the body
/// is compiled for `simd` (see [`crate::cpu`]), the portable one where the running
/// CPU lacks it, and every body computes the same operations in the same order.
#[allow(clippy::too_many_arguments)]
fn screened_block(
    simd: Simd,
    p: &crate::Point,
    u: f32,
    cols: &[Vec<f32>; crate::DIM],
    v: &[f32],
    block: std::ops::Range<usize>,
    out: &mut [f32],
) {
    simd.run(
        #[inline(always)]
        |_| screened_portable(p, u, cols, v, block, out),
    );
}

/// The body of [`screened_block`].
#[inline(always)]
fn screened_portable(
    p: &crate::Point,
    u: f32,
    cols: &[Vec<f32>; crate::DIM],
    v: &[f32],
    block: std::ops::Range<usize>,
    out: &mut [f32],
) {
    let len = out.len();
    let start = block.start;
    // Equal-length slices, so the loop runs without bounds checks and vectorises.
    let (c0, c1, c2, c3, c4) = (
        &cols[0][start..start + len],
        &cols[1][start..start + len],
        &cols[2][start..start + len],
        &cols[3][start..start + len],
        &cols[4][start..start + len],
    );
    let v = &v[start..start + len];
    for k in 0..len {
        let d0 = p[0] - c0[k];
        let d1 = p[1] - c1[k];
        let d2 = p[2] - c2[k];
        let d3 = p[3] - c3[k];
        let d4 = p[4] - c4[k];
        let c = d0 * d0 + d1 * d1 + d2 * d2 + d3 * d3 + d4 * d4;
        out[k] = (c - v[k] - u) - (SCREEN_MARGIN * (c + v[k].abs() + u.abs()) + SCREEN_FLOOR);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::synthetic::Rng;

    #[test]
    fn f32_screen_never_rules_out_a_negative_reduced_cost() {
        // Potentials chosen so reduced costs straddle zero by less than f32 rounding.
        let mut rng = Rng::new(5);
        let n = 200;
        let cols: [Vec<f32>; crate::DIM] =
            std::array::from_fn(|_| (0..n).map(|_| 3.0 * rng.uniform() - 1.0).collect());
        for case in 0..50 {
            let p: crate::Point = std::array::from_fn(|_| 3.0 * rng.uniform() - 1.0);
            let u = 10.0 * f64::from(rng.uniform()) - 5.0;
            let v: Vec<f64> = (0..n)
                .map(|j| {
                    let c = sq_dist_f64(&p, &std::array::from_fn(|d| cols[d][j]));
                    c - u + 1e-7 * (f64::from(rng.uniform()) - 0.5)
                })
                .collect();
            let mut slack = vec![0.0f32; n];
            screened_block(
                Simd::Portable,
                &p,
                u as f32,
                &cols,
                &to_f32(&v),
                0..n,
                &mut slack,
            );
            // Every body the CPU supports gives the same slack, bit for bit.
            for simd in Simd::supported() {
                let mut other = vec![0.0f32; n];
                screened_block(simd, &p, u as f32, &cols, &to_f32(&v), 0..n, &mut other);
                let same = slack
                    .iter()
                    .zip(&other)
                    .all(|(a, b)| a.to_bits() == b.to_bits());
                assert!(same, "case {case}: {} differs", simd.name());
            }
            let mut ruled_out = 0;
            for (j, &s) in slack.iter().enumerate() {
                let c = sq_dist_f64(&p, &std::array::from_fn(|d| cols[d][j]));
                if s >= 0.0 {
                    ruled_out += 1;
                    assert!(c - u - v[j] >= 0.0, "case {case}, target {j}");
                }
            }
            assert!(ruled_out < n, "case {case}: near-tight pairs must be kept");
        }
        // Clearly positive reduced costs are ruled out.
        let p = [0.0; crate::DIM];
        let mut slack = vec![0.0f32; n];
        screened_block(
            Simd::Portable,
            &p,
            -1.0,
            &cols,
            &vec![0.0; n],
            0..n,
            &mut slack,
        );
        assert!(slack.iter().all(|&s| s >= 0.0));
    }

    #[test]
    fn every_pair_a_check_does_not_return_lies_above_its_rows_floor() {
        // Potentials near optimal (u_i = row minimum − noise), so rows have
        // violated, near-tight and far pairs; margins 0 (cold) and positive (warm),
        // per-row caps small enough to drop pairs (floor from the kept ones) and not.
        let mut rng = Rng::new(11);
        let n = 600;
        let x = Clustered::new(&crate::tests::random_cloud(&mut rng, n, 1.0), 16);
        let y = Clustered::new(&crate::tests::random_cloud(&mut rng, n, 1.0), 16);
        let v: Vec<f64> = (0..n).map(|_| 0.05 * f64::from(rng.uniform())).collect();
        let cost = |i: usize, j: usize| sq_dist_f64(&x.cloud.point(i), &y.cloud.point(j));
        let u: Vec<f64> = (0..n)
            .map(|i| {
                let best = (0..n)
                    .map(|j| cost(i, j) - v[j])
                    .fold(f64::INFINITY, f64::min);
                best + 0.01 * f64::from(rng.uniform())
            })
            .collect();
        let rows: Vec<bool> = (0..n).map(|i| i % 3 != 0).collect();
        for (margin, per_row) in [(0.0, 32), (0.02, 32), (0.02, 2)] {
            let mut floors = vec![f64::NEG_INFINITY; n];
            let check = violations(&x, &y, &u, &v, margin, 0.0, per_row, &rows, &mut floors);
            let mut returned = vec![false; n * n];
            for &(i, j, c) in &check.found {
                returned[i as usize * n + j as usize] = true;
                assert_eq!(c, cost(i as usize, j as usize));
            }
            let mut violated = 0;
            let mut returned_violated = 0;
            let mut dropped = 0;
            for i in 0..n {
                if !rows[i] {
                    assert_eq!(
                        floors[i],
                        f64::NEG_INFINITY,
                        "unchecked row {i} keeps its floor"
                    );
                    continue;
                }
                assert!(floors[i] <= u[i] + margin, "row {i}");
                dropped += usize::from(floors[i] < u[i] + margin);
                for j in 0..n {
                    let c = cost(i, j);
                    let reduced = c - u[i] - v[j];
                    let rounding = 4.0 * f64::EPSILON * (c + u[i].abs() + v[j].abs());
                    violated += usize::from(reduced < -rounding);
                    if returned[i * n + j] {
                        returned_violated += usize::from(reduced < -rounding);
                    } else {
                        assert!(
                            c - v[j] >= floors[i] - rounding,
                            "margin {margin}: pair ({i}, {j}) below the floor"
                        );
                    }
                }
            }
            assert_eq!(check.violated, returned_violated);
            assert!(violated > 0 && check.violated > 0);
            assert!(check.found.len() > rows.iter().filter(|&&r| r).count());
            assert_eq!(dropped > 0, per_row == 2, "margin {margin}, cap {per_row}");
        }
    }

    #[test]
    fn the_box_bound_never_skips_a_violated_pair() {
        // Potentials at the edge: v_j = c_ij − u ± 1e-9 for the point nearest the box.
        let mut rng = Rng::new(8);
        let cloud = crate::tests::random_cloud(&mut rng, 512, 1.0);
        let y = Clustered::new(&cloud, 16);
        let mut skipped = 0;
        for case in 0..200 {
            let p: crate::Point = std::array::from_fn(|_| 1.4 * rng.uniform() - 0.2);
            let cj = &y.clusters[case % y.clusters.len()];
            let u = f64::from(rng.uniform()) - 0.5;
            let v: Vec<f64> = cj
                .range
                .clone()
                .map(|_| 0.3 * f64::from(rng.uniform()) - u + 1e-9 * f64::from(rng.uniform() - 0.5))
                .collect();
            let max_v = v.iter().copied().fold(f64::NEG_INFINITY, f64::max);
            let mut box_sq = [0.0];
            Boxes::gather(&y.clusters, &[(case % y.clusters.len()) as u32])
                .dist_sq(&p, &mut box_sq);
            let box_sq = box_sq[0];
            for (k, j) in cj.range.clone().enumerate() {
                let c = sq_dist_f64(&p, &y.cloud.point(j));
                assert!(
                    box_sq <= c,
                    "case {case}: the box is nearer than its members"
                );
                if box_feasible(box_sq, u, max_v) {
                    assert!(c - u - v[k] >= 0.0, "case {case}, target {j}");
                }
            }
            skipped += usize::from(box_feasible(box_sq, u, max_v));
        }
        assert!(skipped > 0 && skipped < 200, "{skipped}");
        assert!(!box_feasible(f64::NAN, 0.0, 0.0) && !box_feasible(1.0, 0.0, f64::INFINITY));
    }
}
