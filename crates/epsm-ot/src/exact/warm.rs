//! The exact solver's warm start from the previous solve of a sequence (see `crate::warm`).
//!
//! A solve keeps, in the clouds' input orders: the target potentials `v`, the
//! permutation, each source point's [`KEPT_PER_CANDIDATE`] × `candidates`
//! candidate targets of smallest reduced cost `c_ij − u_i − v_j`, and the
//! target's clustering. The next solve builds its candidate graph from the
//! kept targets of each source point (same input index, costs of the new
//! points) plus its previous partner, starts the sparse assignment from the
//! kept `v` (row potentials `u_i = min_j c_ij − v_j` over the graph), and
//! completes the graph by one check of all rows with the margin
//! `exact.warm_check_margin`: each row gets its pairs below or within the
//! margin of its true minimum, so the auction that follows (from the kept
//! prices, at the small first ε `exact.warm_auction_start`, raised where the
//! kept prices are far enough off to start a price war) and the
//! augmenting paths see the columns each row may turn to, and the rows'
//! floors (see `check`) spare most of them the next check. The entropic warm
//! start and the candidate search are skipped. The previous permutation is a
//! perfect matching of the graph, so the auction terminates. Optimality is
//! proven by the same check over all pairs, whatever the kept state was.

use rayon::prelude::*;

use super::finish::{Pass, VIOLATORS_PER_CANDIDATE, check_rows};
use super::sparse::SparseAssignment;
use super::{ExactSettings, SortedAssignment};
use crate::clusters::Clustered;
use crate::cost::sq_dist_f64;

/// Kept candidate targets per source point, in units of `candidates`.
const KEPT_PER_CANDIDATE: usize = 2;

/// What an exact solve leaves for the next one, in the clouds' input orders.
#[derive(Debug, Clone)]
pub(crate) struct ExactState {
    /// The target's clustering (reused while the target stays the same cloud).
    y: Clustered,
    /// Target potentials, target input order.
    v: Vec<f64>,
    /// Source point `i`'s partner (target input index).
    perm: Vec<u32>,
    /// Kept candidate targets of source point `i`: `targets[offsets[i]..offsets[i + 1]]` (input indices).
    offsets: Vec<usize>,
    targets: Vec<u32>,
}

/// The start of a warm solve: the sparse assignment, the cost evaluations it took
/// and the violated pairs its check added.
pub(crate) struct WarmGraph {
    pub assignment: SparseAssignment,
    pub pairs: u64,
    pub added: usize,
}

impl ExactState {
    /// Keeps what `solved` (on the clusterings `x`, `y`) leaves for the next solve.
    pub fn keep(x: &Clustered, y: Clustered, solved: &SortedAssignment, candidates: usize) -> Self {
        let n = x.cloud.len();
        let per_row = KEPT_PER_CANDIDATE * candidates;
        let mut v = vec![0.0; n];
        let mut perm = vec![0u32; n];
        for k in 0..n {
            v[y.order[k] as usize] = solved.v[k];
            perm[x.order[k] as usize] = y.order[solved.perm[k]];
        }
        // Each sorted row's kept targets (input indices), smallest reduced cost first.
        let kept: Vec<Vec<u32>> = solved
            .edges
            .par_iter()
            .enumerate()
            .map_init(Vec::new, |scored: &mut Vec<(f64, u32)>, (k, row)| {
                scored.clear();
                scored.extend(
                    row.iter()
                        .map(|&(j, c)| (c - solved.u[k] - solved.v[j as usize], j)),
                );
                if scored.len() > per_row {
                    scored.select_nth_unstable_by(per_row, |a, b| {
                        a.0.total_cmp(&b.0).then(a.1.cmp(&b.1))
                    });
                    scored.truncate(per_row);
                }
                scored.iter().map(|&(_, j)| y.order[j as usize]).collect()
            })
            .collect();
        let mut by_input = vec![0usize; n];
        for (k, &i) in x.order.iter().enumerate() {
            by_input[i as usize] = k;
        }
        let mut offsets = Vec::with_capacity(n + 1);
        let mut targets = Vec::with_capacity(n * per_row);
        offsets.push(0);
        for &k in &by_input {
            targets.extend_from_slice(&kept[k]);
            offsets.push(targets.len());
        }
        Self {
            y,
            v,
            perm,
            offsets,
            targets,
        }
    }

    /// The kept target potentials (target input order).
    #[cfg(test)]
    pub fn target_potentials(&self) -> &[f64] {
        &self.v
    }

    /// Whether the state comes from clouds of `n` points.
    pub fn fits(&self, n: usize) -> bool {
        self.perm.len() == n
    }

    /// The kept clustering if `target` is the cloud it was made of (bit for bit), else `None`.
    pub fn clustered_target(&self, target: &crate::PointCloud) -> Option<Clustered> {
        let y = &self.y;
        let same = target.len() == y.cloud.len()
            && y.order
                .iter()
                .enumerate()
                .all(|(k, &j)| y.cloud.point(k) == target.point(j as usize));
        same.then(|| y.clone())
    }

    /// The sparse assignment the next solve starts from, on the clusterings `x` and `y`:
    /// the kept graph, with each row's pairs of smallest reduced cost against
    /// the kept `v` added by a check with `pass`'s margin (so its `u_i` is the
    /// row minimum over all pairs, and its floor above it by the margin).
    pub fn start(
        &self,
        x: &Clustered,
        y: &Clustered,
        settings: &ExactSettings,
        pass: Pass,
        diameter_sq: f64,
    ) -> WarmGraph {
        let n = x.cloud.len();
        let mut sorted_target = vec![0u32; n];
        for (k, &j) in y.order.iter().enumerate() {
            sorted_target[j as usize] = k as u32;
        }
        let v: Vec<f64> = y.order.iter().map(|&j| self.v[j as usize]).collect();
        // Room for the pairs the check adds, so rows are allocated once.
        let room = VIOLATORS_PER_CANDIDATE * settings.candidates;
        let edges: Vec<Vec<(u32, f64)>> = x
            .order
            .par_iter()
            .enumerate()
            .map(|(k, &i)| {
                let i = i as usize;
                let p = x.cloud.point(k);
                let kept = &self.targets[self.offsets[i]..self.offsets[i + 1]];
                let mut row = Vec::with_capacity(kept.len() + 1 + room);
                for &j in kept.iter().chain([&self.perm[i]]) {
                    let jk = sorted_target[j as usize];
                    row.push((jk, sq_dist_f64(&p, &y.cloud.point(jk as usize))));
                }
                row.sort_unstable_by_key(|e| e.0);
                row.dedup_by_key(|e| e.0);
                row
            })
            .collect();
        let pairs: u64 = edges.iter().map(|r| r.len() as u64).sum();
        let mut assignment = SparseAssignment::new(edges, v);
        let check = check_rows(x, y, settings, &mut assignment, pass, diameter_sq);
        let added = assignment.add_edges(&check.found);
        WarmGraph {
            assignment,
            pairs: pairs + check.checked,
            added,
        }
    }
}
