//! Dense reference assignment solver (the oracle for the fast sparse solver).
//!
//! The O(n³) shortest-augmenting-path Hungarian algorithm with row and column
//! potentials on the full n×n cost matrix, in `f64`. Simple enough to trust,
//! too slow and too memory-hungry for large n (the matrix alone is 2 GB at
//! n = 16384): the production solver (`exact::solve`) uses it only for small
//! clouds, and tests use it to check the sparse solver.

use crate::cost::{assignment_cost, displacement_gradient, sq_dist_f64};
use crate::error::OtError;
use crate::plan::{Matching, OtResult, SolveStats};
use crate::points::{PointCloud, check_pair};

/// An optimal assignment with dual potentials proving it: `c_ij ≥ u_i + v_j`, equality on `(i, perm[i])`.
#[derive(Debug, Clone, PartialEq)]
pub struct Assignment {
    /// Row `i` is assigned to column `perm[i]`.
    pub perm: Vec<usize>,
    /// Row potentials.
    pub u: Vec<f64>,
    /// Column potentials.
    pub v: Vec<f64>,
}

/// Solves the square assignment problem for the row-major `n × n` matrix `cost`.
pub fn solve_matrix(cost: &[f64], n: usize) -> Assignment {
    debug_assert_eq!(cost.len(), n * n);
    let inf = f64::INFINITY;
    // 1-based arrays; column 0 is the virtual start of each search.
    let (mut u, mut v) = (vec![0.0; n + 1], vec![0.0; n + 1]);
    let (mut row_of, mut way) = (vec![0usize; n + 1], vec![0usize; n + 1]);
    for i in 1..=n {
        row_of[0] = i;
        let mut j0 = 0;
        let mut minv = vec![inf; n + 1];
        let mut used = vec![false; n + 1];
        // Grow the shortest-path tree until it reaches a free column.
        loop {
            used[j0] = true;
            let i0 = row_of[j0];
            let (mut delta, mut j1) = (inf, 0);
            for j in 1..=n {
                if !used[j] {
                    let cur = cost[(i0 - 1) * n + j - 1] - u[i0] - v[j];
                    if cur < minv[j] {
                        minv[j] = cur;
                        way[j] = j0;
                    }
                    if minv[j] < delta {
                        delta = minv[j];
                        j1 = j;
                    }
                }
            }
            for j in 0..=n {
                if used[j] {
                    u[row_of[j]] += delta;
                    v[j] -= delta;
                } else {
                    minv[j] -= delta;
                }
            }
            j0 = j1;
            if row_of[j0] == 0 {
                break;
            }
        }
        // Flip the augmenting path.
        while j0 != 0 {
            let j1 = way[j0];
            row_of[j0] = row_of[j1];
            j0 = j1;
        }
    }
    let mut perm = vec![0; n];
    for j in 1..=n {
        perm[row_of[j] - 1] = j - 1;
    }
    Assignment {
        perm,
        u: u[1..].to_vec(),
        v: v[1..].to_vec(),
    }
}

/// Exact matching through the dense matrix (reference; O(n²) memory, O(n³) time).
///
/// Fails like `exact::solve` on clouds beyond [`super::MAX_DIAMETER_SQ`].
pub fn solve(source: &PointCloud, target: &PointCloud) -> Result<OtResult, OtError> {
    let n = check_pair(source, target)?;
    super::checked_diameter_sq(source, target)?;
    let cost: Vec<f64> = source
        .points()
        .flat_map(|p| target.points().map(move |q| sq_dist_f64(&p, &q)))
        .collect();
    let assignment = solve_matrix(&cost, n);
    Ok(permutation_result(
        source,
        target,
        assignment.perm,
        SolveStats {
            pair_evaluations: (n * n) as u64,
            ..SolveStats::default()
        },
    ))
}

/// Builds the result of an exact matching: loss, gradient `2(P_i − Q_σ(i))/n`, permutation.
pub(crate) fn permutation_result(
    source: &PointCloud,
    target: &PointCloud,
    perm: Vec<usize>,
    stats: SolveStats,
) -> OtResult {
    let targets: Vec<_> = perm.iter().map(|&j| target.point(j)).collect();
    OtResult {
        loss: assignment_cost(source, target, &perm),
        gradient: displacement_gradient(source, &targets),
        matching: Matching::Permutation(perm),
        stats,
    }
}
