//! Step 4 of `exact`: the streaming optimality check over all pairs.
//!
//! For the rows whose potential rose since the last check, every pair
//! `(i, j)` is screened in `f32` ([`screened_block`]) and tested in `f64`
//! only where the screen cannot rule out `c_ij − u_i − v_j < −tolerance`;
//! whole block pairs are skipped where the rigorous bound of `blocks` proves
//! them feasible. No violated pair is missed, so an empty result certifies
//! that `u, v` are feasible for all n² pairs.

use rayon::prelude::*;

use crate::clusters::{Clustered, fit_potentials, kept_targets};
use crate::cost::sq_dist_f64;

/// A candidate edge `(row, column, cost)`.
pub(crate) type Edge = (u32, u32, f64);

/// For each row flagged in `rows`, its `per_row` most violated pairs
/// (`c_ij − u_i − v_j < −tolerance`), and the number of pairs evaluated.
///
/// Target blocks are skipped where the block-pair bound of `blocks` proves
/// them feasible for the row's whole cluster, and then per point where the
/// distance to a block's bounding box less its largest `v_j` does
/// ([`box_feasible`]). Each remaining pair is first screened in `f32` (see
/// [`screened_block`]); only pairs the screen cannot rule out are tested in
/// `f64`, so no violation is missed.
pub(crate) fn violations(
    x: &Clustered,
    y: &Clustered,
    u: &[f64],
    v: &[f64],
    tolerance: f64,
    per_row: usize,
    rows: &[bool],
) -> (Vec<Edge>, u64) {
    let (fit_u, fit_v) = (fit_potentials(x, u), fit_potentials(y, v));
    let (u32s, v32s) = (to_f32(u), to_f32(v));
    // Potentials beyond the f32 range: no screen, every pair is tested in f64.
    let screen = u32s.iter().chain(&v32s).all(|t| t.is_finite());
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
    let parts: Vec<(Vec<Edge>, u64)> = x
        .clusters
        .par_iter()
        .zip(&fit_u)
        .map(|(ci, fi)| {
            let mut found = Vec::new();
            let mut checked = 0u64;
            if !rows[ci.range.clone()].iter().any(|&r| r) {
                return (found, checked);
            }
            let list = kept_targets(ci, fi, y, &fit_v, 0.0);
            let mut slack = [0.0f32; SCREEN_BLOCK];
            for i in ci.range.clone().filter(|&i| rows[i]) {
                let p = x.cloud.point(i);
                let mut row: Vec<(f64, u32, f64)> = Vec::new();
                for &jb in &list {
                    let cj = &y.clusters[jb as usize];
                    if box_feasible(cj.box_dist_sq(&p), u[i], max_v[jb as usize]) {
                        continue;
                    }
                    let range = cj.range.clone();
                    checked += range.len() as u64;
                    for start in range.clone().step_by(SCREEN_BLOCK) {
                        let block = start..(start + SCREEN_BLOCK).min(range.end);
                        let slack = &mut slack[..block.len()];
                        screened_block(&p, u32s[i], cols, &v32s, block.clone(), slack);
                        for (j, &s) in block.zip(slack.iter()) {
                            if screen && s >= 0.0 {
                                continue;
                            }
                            let c = sq_dist_f64(&p, &y.cloud.point(j));
                            let reduced = c - u[i] - v[j];
                            // Rounding of c, u and v is not a violation (matters for far-apart clouds).
                            if reduced
                                < -(tolerance + 4.0 * f64::EPSILON * (c + u[i].abs() + v[j].abs()))
                            {
                                row.push((reduced, j as u32, c));
                                if row.len() == 4 * per_row {
                                    keep_worst(&mut row, per_row);
                                }
                            }
                        }
                    }
                }
                keep_worst(&mut row, per_row);
                found.extend(row.into_iter().map(|(_, j, c)| (i as u32, j, c)));
            }
            (found, checked)
        })
        .collect();
    let checked = parts.iter().map(|p| p.1).sum();
    (parts.into_iter().flat_map(|p| p.0).collect(), checked)
}

/// Whether the box bound proves `c_ij − u − v_j ≥ 0` for every member `j` of a
/// target cluster, from `box_sq` (its [`crate::clusters::Cluster::box_dist_sq`]
/// from point `i`) and `max_v`, the largest `v_j` of the cluster.
///
/// `c_ij ≥ box_sq` in exact arithmetic; the computed `box_sq`, the computed
/// `c_ij` and the subtractions each round by a few units of the last place
/// relative to `box_sq + |u| + |max_v|`, so the bound is accepted only with a
/// margin of 16 of them. Non-finite values are never accepted.
fn box_feasible(box_sq: f64, u: f64, max_v: f64) -> bool {
    box_sq - u - max_v >= 16.0 * f64::EPSILON * (box_sq + u.abs() + max_v.abs())
}

/// Keeps the `per_row` most violated pairs (smallest reduced cost, ties by column) of `row`.
fn keep_worst(row: &mut Vec<(f64, u32, f64)>, per_row: usize) {
    if row.len() > per_row {
        row.select_nth_unstable_by(per_row, |a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        row.truncate(per_row);
    }
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
/// Written as one branch-free loop over SoA columns so it vectorises.
fn screened_block(
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
            screened_block(&p, u as f32, &cols, &to_f32(&v), 0..n, &mut slack);
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
        screened_block(&p, -1.0, &cols, &vec![0.0; n], 0..n, &mut slack);
        assert!(slack.iter().all(|&s| s >= 0.0));
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
            let box_sq = cj.box_dist_sq(&p);
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
