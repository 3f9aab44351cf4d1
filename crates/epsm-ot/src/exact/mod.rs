//! Exact optimal assignment of equal-size clouds, verified optimal over all pairs.
//!
//! Minimises `Σ_i ‖P_i − Q_σ(i)‖²` over permutations σ. Loss `1/n Σ ‖P_i − Q_σ(i)‖²`,
//! gradient `2 (P_i − Q_σ(i)) / n`.
//!
//! Named steps of [`solve`] (for `n ≥ dense_below`; smaller problems go to the
//! [`dense`] reference solver):
//! 1. **Warm start**: entropic potentials `f, g` from `sinkhorn` at `warm_start.blur`,
//!    or a **cold start** (`f = g = 0`, candidates searched among all pairs,
//!    counted in `SolveStats::cold_starts`) when the clouds are beyond the
//!    entropic solver's range at that blur (`sinkhorn::MAX_SPREAD`, far below
//!    [`MAX_DIAMETER_SQ`]) or its potentials are not all finite. Warm-started
//!    beyond that range, 100 points spread over `[0, 1e18]⁵` got NaN
//!    potentials, whose reduced costs no optimality check flags, and the solve
//!    returned a matching of over 5 times the optimal cost.
//! 2. **Candidate graph**: for each source point the `candidates` targets of
//!    smallest `c_ij − g_j`, and for each target the sources of smallest `c_ij − f_i`,
//!    searched only inside the truncated plan's block support, plus one
//!    perfect matching (grid order) so the graph always has one.
//! 3. **Sparse solve**: an ε-scaling auction from prices `−g` finds near-optimal
//!    potentials (`auction`; a phase that runs out of its bid budget keeps the
//!    prices it reached, counted in `SolveStats::auction_budget_stops`; a
//!    phase that turns into a price war starts again at a larger ε). Its ε
//!    is relative: the settings times the clouds' squared diameter, the scale
//!    of costs and prices. (An absolute ε of 1e-9 fell below the rounding of
//!    prices near 1e30, so at spreads of 1e15 every auction ran out of bids,
//!    and on the blobs pair already at ×1000, though the exact finish still
//!    found the optimum.) Then an augmenting row reduction (exact bids that
//!    only lower column potentials) matches most free rows and shortest
//!    augmenting paths the rest, making the matching exactly
//!    complementary-slack with the potentials (`sparse`). Whenever
//!    more than 1/16 of the rows are unmatched (after step 4 added violated
//!    pairs), the auction first re-prices all rows from the current potentials,
//!    starting at the smaller ε `exact.reprice_auction_start`: those prices
//!    are feasible on the graph before the check.
//! 4. **Optimality check**: a streaming pass over all pairs of the rows whose
//!    potential rose above their **floor** (a lower bound on `c_ij − v_j` over
//!    the pairs outside the graph, left by the row's last check and kept
//!    valid because column potentials only fall; the other rows cannot have
//!    gained a violation, see `check`; each pair is screened in `f32` first and
//!    tested in `f64` only if the screen cannot rule it out; block pairs are
//!    skipped only when a rigorous bound proves `c_ij − u_i − v_j ≥ 0` for
//!    all of them, see `clusters`) collects every pair with reduced cost below
//!    `−tolerance`; each row's 4 × `candidates` worst violators are added to the
//!    graph and the augmenting-path solve resumes. When none
//!    remain, `u, v` are feasible for the full problem and tight on the
//!    matching, so the matching is optimal (to within `n · tolerance` in total cost).
//!    A warm-started solve checks with a margin (`exact.warm_check_margin`):
//!    it also adds each row's pairs within the margin of tight and raises the
//!    row's floor by it.
//!
//! | key                    | meaning                                    | default |
//! |------------------------|--------------------------------------------|---------|
//! | `exact.dense_below`    | use the dense O(n³) solver below this n    | 64      |
//! | `exact.candidates`     | candidate targets per point (and sources per target) | 8 |
//! | `exact.tolerance`      | reduced cost counted as a violation below −tolerance | 1e-11 |
//! | `exact.auction_start`  | first ε of the auction, × diameter²        | 0.025   |
//! | `exact.auction_end`    | last ε of the auction, × diameter²         | 2.5e-10 |
//! | `exact.reprice_auction_start` | first ε of a cold solve's re-pricing auctions, × diameter² | 1e-3 |
//! | `exact.warm_auction_start` | first ε of a warm-started solve's auctions, × diameter² | 1e-4 |
//! | `exact.warm_check_margin` | margin of a warm-started solve's checks, × diameter² | 5e-4 |
//! | `exact.warm_start`     | Sinkhorn settings of the warm start        | blur 0.03, one update per scale, ≤ 10 polish updates |

mod auction;
mod check;
pub mod dense;
mod finish;
mod settings;
mod sparse;
pub(crate) mod warm;

use std::time::Instant;

use rayon::prelude::*;

use crate::clusters::{Clustered, Support};
use crate::cost::{sq_dist_f64, sq_dists_f64};
use crate::error::OtError;
use crate::plan::{OtResult, PhaseTimes, SolveStats};
use crate::points::{PointCloud, check_pair};
use crate::sinkhorn::{SinkhornSettings, check_range, solve_dual};
use finish::{Pass, auction_potentials, finish};
use settings::checked_diameter_sq;
pub use settings::{ExactSettings, MAX_DIAMETER_SQ};
use sparse::SparseAssignment;
pub(crate) use warm::ExactState;

/// Solves the exact assignment problem from `source` to `target`.
///
/// Fails with [`OtError::SpreadTooLarge`] when the clouds' squared diameter
/// exceeds [`MAX_DIAMETER_SQ`].
pub fn solve(
    source: &PointCloud,
    target: &PointCloud,
    settings: &ExactSettings,
) -> Result<OtResult, OtError> {
    solve_from(source, target, settings, None)
}

/// [`solve`] started from what the previous solve left in `state` (see [`warm`]),
/// which it replaces with what this one leaves for the next; `None`: a cold
/// solve that keeps nothing.
///
/// An empty state, or one from clouds of another size, starts cold. The
/// state is emptied when the solve fails, and left empty by the dense solver.
pub(crate) fn solve_from(
    source: &PointCloud,
    target: &PointCloud,
    settings: &ExactSettings,
    mut state: Option<&mut Option<ExactState>>,
) -> Result<OtResult, OtError> {
    let previous = state.as_mut().and_then(|s| s.take());
    settings.validate()?;
    let n = check_pair(source, target)?;
    if n < settings.dense_below.max(2) {
        return dense::solve(source, target);
    }
    let diam2 = checked_diameter_sq(source, target)?;
    let mut phases = PhaseTimes::default();
    let previous = previous.filter(|p| p.fits(n));
    let (x, y) = phases.time("cluster", || {
        let cluster_size = settings.warm_start.cluster_size;
        let y = previous
            .as_ref()
            .and_then(|p| p.clustered_target(target))
            .unwrap_or_else(|| Clustered::new(target, cluster_size));
        (Clustered::new(source, cluster_size), y)
    });
    let mut solved = match &previous {
        Some(p) => {
            // Kept graph and potentials, completed by a check; then the auction
            // from the kept prices at a small ε, and the same finish as a cold
            // solve, checking with a margin.
            let pass = Pass {
                auction_start: settings.warm_auction_start,
                check_margin: settings.warm_check_margin,
            };
            let warm = phases.time("warm_graph", || p.start(&x, &y, settings, pass, diam2));
            let mut stats = SolveStats {
                warm_starts: 1,
                pair_evaluations: warm.pairs,
                added_pairs: warm.added,
                ..SolveStats::default()
            };
            // The auction only raises prices (lowers v), so the floors stay valid.
            let (edges, v, floors) = warm.assignment.into_parts();
            let (v, finished) = phases.time("auction", || {
                auction_potentials(&edges, v, diam2, pass.auction_start, settings)
            });
            stats.auction_budget_stops += usize::from(!finished);
            let lsap = SparseAssignment::with_floors(edges, v, floors);
            finish(&x, &y, diam2, settings, lsap, stats, pass)
        }
        None => solve_sorted(&x, &y, diam2, settings),
    };
    phases.merge(&solved.stats.phases);
    let mut perm = vec![0usize; n];
    for (k, &j) in solved.perm.iter().enumerate() {
        perm[x.order[k] as usize] = y.order[j] as usize;
    }
    if let Some(state) = state {
        phases.time("warm_keep", || {
            *state = Some(ExactState::keep(&x, y, &solved, settings.candidates));
        });
    }
    solved.stats.phases = phases;
    Ok(dense::permutation_result(
        source,
        target,
        perm,
        solved.stats,
    ))
}

/// A verified optimal assignment between two clustered clouds, in their sorted orders.
pub(crate) struct SortedAssignment {
    /// Sorted source `k` is matched to sorted target `perm[k]`.
    pub perm: Vec<usize>,
    /// Row potentials (feasible for all pairs, tight on the matching).
    pub u: Vec<f64>,
    /// Column potentials.
    pub v: Vec<f64>,
    /// The final candidate graph: per sorted source, (sorted target, cost).
    pub edges: Vec<Vec<(u32, f64)>>,
    /// Work counters.
    pub stats: SolveStats,
}

/// Near-optimal prices from steps 1–3 of the module doc: the candidate graph and the auction's prices.
pub(crate) struct Prices {
    /// Candidate edges per sorted source point: (sorted target, cost).
    pub edges: Vec<Vec<(u32, f64)>>,
    /// Column potentials (the negated auction prices).
    pub v: Vec<f64>,
    /// Work counters and phase times so far.
    pub stats: SolveStats,
}

/// Step 1 of the module doc: potentials `f, g` and the block support the candidates are searched in.
struct WarmStart {
    f: Vec<f64>,
    g: Vec<f64>,
    support: Support,
    /// Kernel pairs the entropic solve evaluated (also when its potentials were dropped).
    pairs: u64,
    /// Whether the entropic potentials were replaced by zeros on the dense support.
    cold: bool,
}

/// The entropic warm start at `settings.blur`, or the cold start: zero potentials
/// and every block pair, when the clouds are beyond the entropic solver's range
/// ([`check_range`]) or its potentials are not all finite.
///
/// Any finite potentials give the optimal matching (the optimality check of
/// step 4 proves it); non-finite ones would not: a NaN reduced cost is never a
/// violation. No input inside the range has been found to give a non-finite
/// potential; the check costs one pass over them.
fn warm_start(
    x: &Clustered,
    y: &Clustered,
    diameter_sq: f64,
    settings: &SinkhornSettings,
) -> WarmStart {
    let mut pairs = 0;
    if check_range(diameter_sq, settings).is_ok() {
        let dual = solve_dual(x, y, diameter_sq, settings);
        if dual.f.iter().chain(&dual.g).all(|t| t.is_finite()) {
            return WarmStart {
                f: dual.f,
                g: dual.g,
                support: dual.support,
                pairs: dual.pairs,
                cold: false,
            };
        }
        pairs = dual.pairs;
    }
    WarmStart {
        f: vec![0.0; x.cloud.len()],
        g: vec![0.0; y.cloud.len()],
        support: Support::dense(x.clusters.len(), y.clusters.len()),
        pairs,
        cold: true,
    }
}

/// Steps 1–3 of the module doc without the optimality check: the warm start,
/// the candidate graph and the auction's prices (feasible on the graph only).
fn sparse_prices(
    x: &Clustered,
    y: &Clustered,
    diameter_sq: f64,
    settings: &ExactSettings,
) -> Prices {
    // Warm start and candidate graph.
    let mut phases = PhaseTimes::default();
    let WarmStart {
        f,
        g,
        support,
        pairs,
        cold,
    } = phases.time("warm_start", || {
        warm_start(x, y, diameter_sq, &settings.warm_start)
    });
    let mut stats = SolveStats {
        pair_evaluations: pairs,
        cold_starts: usize::from(cold),
        ..SolveStats::default()
    };
    let k = settings.candidates;
    let candidates_start = Instant::now();
    let mut edges = best_partners(x, y, &support.rows, &g, k);
    for (j, row) in best_partners(y, x, &support.cols, &f, k)
        .into_iter()
        .enumerate()
    {
        for (i, c) in row {
            edges[i as usize].push((j as u32, c));
        }
    }
    // A perfect matching (sorted source k to sorted target k, both in grid order)
    // guarantees the graph has one, so the auction terminates.
    for (k, row) in edges.iter_mut().enumerate() {
        row.push((k as u32, sq_dist_f64(&x.cloud.point(k), &y.cloud.point(k))));
    }
    for row in &mut edges {
        row.sort_unstable_by_key(|e| e.0);
        row.dedup_by_key(|e| e.0);
    }
    phases.add("candidates", candidates_start.elapsed().as_secs_f64());
    // Price discovery by auction, then an exact shortest-augmenting-path finish.
    let (v, finished) = phases.time("auction", || {
        auction_potentials(&edges, g, diameter_sq, settings.auction_start, settings)
    });
    stats.auction_budget_stops += usize::from(!finished);
    stats.phases = phases;
    Prices { edges, v, stats }
}

/// Steps 1–4 of the module doc on clustered clouds.
pub(crate) fn solve_sorted(
    x: &Clustered,
    y: &Clustered,
    diameter_sq: f64,
    settings: &ExactSettings,
) -> SortedAssignment {
    let Prices { edges, v, stats } = sparse_prices(x, y, diameter_sq, settings);
    let pass = Pass {
        auction_start: settings.reprice_auction_start,
        check_margin: 0.0,
    };
    finish(
        x,
        y,
        diameter_sq,
        settings,
        SparseAssignment::new(edges, v),
        stats,
        pass,
    )
}

/// For each point of `x`, the `k` points of `y` with the smallest `c_ij − pot_j` inside the listed blocks.
fn best_partners(
    x: &Clustered,
    y: &Clustered,
    lists: &[Vec<u32>],
    pot: &[f64],
    k: usize,
) -> Vec<Vec<(u32, f64)>> {
    x.clusters
        .par_iter()
        .zip(lists)
        .flat_map_iter(|(ci, list)| {
            ci.range.clone().map(move |i| {
                let p = x.cloud.point(i);
                let order = |a: &(f64, u32, f64), b: &(f64, u32, f64)| {
                    a.0.total_cmp(&b.0).then(a.1.cmp(&b.1))
                };
                // The k smallest so far are kept whenever 4k pile up; after
                // that only scores up to the largest kept one can still enter.
                let mut scored: Vec<(f64, u32, f64)> = Vec::with_capacity(4 * k);
                let mut bar = f64::INFINITY;
                let mut costs = [0.0; DIST_BLOCK];
                for &jb in list {
                    let range = y.clusters[jb as usize].range.clone();
                    for start in range.clone().step_by(DIST_BLOCK) {
                        let block = start..(start + DIST_BLOCK).min(range.end);
                        let costs = &mut costs[..block.len()];
                        sq_dists_f64(&p, y.cloud.columns(), block.start, costs);
                        for (j, &c) in block.zip(costs.iter()) {
                            let score = c - pot[j];
                            if score <= bar {
                                scored.push((score, j as u32, c));
                                if scored.len() == 4 * k {
                                    scored.select_nth_unstable_by(k - 1, order);
                                    scored.truncate(k);
                                    bar = scored[k - 1].0;
                                }
                            }
                        }
                    }
                }
                let keep = k.min(scored.len());
                if keep < scored.len() {
                    scored.select_nth_unstable_by(keep, order);
                    scored.truncate(keep);
                }
                // A fresh vector: collecting in place would keep the large buffer alive.
                let mut partners = Vec::with_capacity(scored.len());
                partners.extend(scored.iter().map(|&(_, j, c)| (j, c)));
                partners
            })
        })
        .collect()
}

/// Targets whose costs [`best_partners`] computes per call of [`sq_dists_f64`].
const DIST_BLOCK: usize = 64;
