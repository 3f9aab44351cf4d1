//! Steps 3–4 of the solver (module doc of [`super`]): augmenting row
//! reduction and augmenting paths on the candidate graph, then optimality
//! checks over all pairs adding the violated ones, re-pricing by auction
//! when many rows are free.

use std::time::Instant;

use super::check::{Check, violations};
use super::sparse::SparseAssignment;
use super::{ExactSettings, SortedAssignment, auction};
use crate::clusters::Clustered;
use crate::cost::sq_dist_f64;
use crate::plan::SolveStats;

/// How [`finish`] re-prices and checks: the cold and the warm-started solve differ.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Pass {
    /// First ε of re-pricing auctions, × diameter².
    pub auction_start: f64,
    /// Margin of the optimality checks (see `check`), × diameter².
    pub check_margin: f64,
}

/// Steps 3–4 of the module doc from a sparse assignment: shortest augmenting
/// paths, then optimality checks adding violated pairs, until the check finds none.
///
/// Any start gives the optimal matching: the loop ends only when every row
/// is certified against the final potentials, by a check that finds no
/// violated pair or by its floor from an earlier check (see `check`).
/// `stats` carries the work done before.
pub(super) fn finish(
    x: &Clustered,
    y: &Clustered,
    diameter_sq: f64,
    settings: &ExactSettings,
    mut lsap: SparseAssignment,
    mut stats: SolveStats,
    pass: Pass,
) -> SortedAssignment {
    let n = x.cloud.len();
    let mut phases = std::mem::take(&mut stats.phases);
    let first = stats.iterations;
    loop {
        stats.iterations += 1;
        if stats.iterations > first + 1 && lsap.free_rows().len() * REPRICE_BELOW > n {
            // Many rows are free (added violated edges unmatch their rows): re-price
            // all rows by auction from the current prices, far cheaper than one
            // shortest-augmenting-path search per free row from poor potentials.
            // (Not on the first round: its prices come fresh from an auction, and
            // the rows its greedy start leaves free are matched by the row
            // reduction or a short search.)
            // The auction only raises prices (lowers v), so the floors stay valid.
            let (edges, v, floors) = lsap.into_parts();
            let (v, finished) = phases.time("auction", || {
                auction_potentials(&edges, v, diameter_sq, pass.auction_start, settings)
            });
            stats.auction_budget_stops += usize::from(!finished);
            lsap = SparseAssignment::with_floors(edges, v, floors);
        }
        let augment_start = Instant::now();
        // Cheap bids first, then one search per row still free.
        let free = lsap.free_rows().len();
        lsap.reduce_rows(REDUCTION_BIDS_PER_FREE_ROW * free);
        for i in lsap.free_rows() {
            if !lsap.augment(i) {
                let full: Vec<(u32, u32, f64)> = (0..n)
                    .map(|j| {
                        (
                            i as u32,
                            j as u32,
                            sq_dist_f64(&x.cloud.point(i), &y.cloud.point(j)),
                        )
                    })
                    .collect();
                stats.pair_evaluations += n as u64;
                lsap.add_edges(&full);
                let matched = lsap.augment(i);
                debug_assert!(
                    matched,
                    "a row with edges to every column always reaches a free column"
                );
            }
        }
        phases.add("augment", augment_start.elapsed().as_secs_f64());
        // Optimality check over all pairs of the unsettled rows; add each row's
        // worst violators (and near-tight pairs) and solve again.
        let check = phases.time("check", || {
            check_rows(x, y, settings, &mut lsap, pass, diameter_sq)
        });
        stats.pair_evaluations += check.checked;
        if check.violated == 0 {
            stats.candidate_pairs = lsap.edge_count();
            stats.phases = phases;
            let perm = lsap.permutation();
            let (edges, u, v) = lsap.into_potentials();
            return SortedAssignment {
                perm,
                u,
                v,
                edges,
                stats,
            };
        }
        stats.added_pairs += lsap.add_edges(&check.found);
    }
}

/// The optimality check of the rows of `lsap` above their floors, which it updates.
pub(crate) fn check_rows(
    x: &Clustered,
    y: &Clustered,
    settings: &ExactSettings,
    lsap: &mut SparseAssignment,
    pass: Pass,
    diameter_sq: f64,
) -> Check {
    let rows = lsap.unsettled_rows();
    let (u, v, floors) = lsap.check_view();
    violations(
        x,
        y,
        u,
        v,
        pass.check_margin * diameter_sq,
        settings.tolerance,
        VIOLATORS_PER_CANDIDATE * settings.candidates,
        &rows,
        floors,
    )
}

/// Column potentials from an ε-scaling auction on `edges` started at prices `−v`,
/// and whether the auction finished.
///
/// Its ε runs from `auction_start` to `settings.auction_end` times `diameter_sq` (1 for
/// clouds of one point repeated, whose costs are all 0).
///
/// If a phase runs out of bids the prices reached so far are returned: they
/// only rose from `−v` and are ε-complementary for every row assigned at
/// that point, and the exact finish accepts any potentials. The caller counts
/// the stop in `SolveStats::auction_budget_stops`.
pub(super) fn auction_potentials(
    edges: &[Vec<(u32, f64)>],
    v: Vec<f64>,
    diameter_sq: f64,
    auction_start: f64,
    settings: &ExactSettings,
) -> (Vec<f64>, bool) {
    let unit = if diameter_sq > 0.0 { diameter_sq } else { 1.0 };
    let mut q: Vec<f64> = v.iter().map(|&t| -t).collect();
    let finished = auction::run(
        edges,
        &mut q,
        auction_start * unit,
        settings.auction_end * unit,
        settings.auction_start.max(auction_start) * unit,
        EPS_FACTOR,
    );
    (q.iter().map(|&t| -t).collect(), finished)
}

/// Ratio between successive ε of the auctions (and `1 / EPS_FACTOR²` the
/// raise of ε in a price war). With re-pricing auctions that start at
/// `exact.reprice_auction_start` (1e-3 × diameter²) instead of
/// `exact.auction_start`, 0.3 instead of 0.2 left the bids 17–26 % fewer edge
/// scans on the 16384-point blobs pairs (seeds 0–3) and 11–13 % fewer on the
/// 4096-point ones; the check rounds and added pairs stayed about the same.
const EPS_FACTOR: f64 = 0.3;

/// Each check adds this many times `candidates` worst violators per row (fewer, costlier rounds otherwise).
pub(super) const VIOLATORS_PER_CANDIDATE: usize = 4;

/// Bids of the augmenting row reduction (`SparseAssignment::reduce_rows`) per free row.
const REDUCTION_BIDS_PER_FREE_ROW: usize = 4;

/// The sparse solve re-prices every row by auction when more than `n / REPRICE_BELOW` rows are free.
const REPRICE_BELOW: usize = 16;
