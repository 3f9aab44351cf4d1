//! ε-scaling forward auction on the sparse candidate graph: fast price discovery.
//!
//! Bertsekas' auction in minimisation form: every unassigned row `i` bids for
//! the column `j₁` minimising `c_ij + q_j`, raising its price `q_j₁` by the gap
//! to the second-best column plus ε, and evicting the previous owner. At the
//! end of a phase every row holds a column within ε of its best (ε-complementary
//! slackness); ε then shrinks by `factor` and all rows bid again from the
//! current prices. The prices (as column potentials `v = −q`) warm-start the
//! exact shortest-augmenting-path finish, whose searches then stay tiny.
//! The caller gives ε in cost units, scaled with the costs (see `exact`):
//! a bid raises a price by at least ε, so an ε below the rounding of the
//! prices raises nothing and the phase runs out of bids.
//!
//! The prices are the auction's only output: a row that bid last holds a
//! column ε above its best, so the finish's greedy start leaves about a
//! quarter of the rows free, and its augmenting row reduction
//! (`sparse::SparseAssignment::reduce_rows`) matches most of them with a few
//! exact bids each.
//!
//! The graph is copied into compressed rows first (contiguous edges per row,
//! columns and costs in separate arrays), which made the auctions of the
//! 16384-point blobs pairs 10–20 % faster than reading the per-row vectors.
//! A bid scans its row as four interleaved best/second-best chains merged at
//! the end, so their compares overlap: a quarter less auction time on the
//! 16384-point blobs pairs than one chain.
//!
//! The bids run on one thread, in a fixed order: a bulk-synchronous variant
//! (every free row bidding against the same prices, in parallel, conflicts
//! resolved by the highest offer, so the same result on any number of
//! threads) took about 30 % more work on the 16384-point blobs pair and was
//! slower on two shared cores, also when only rounds of over 1024 free rows
//! ran in parallel.

const NONE: u32 = u32::MAX;

/// The candidate graph in compressed rows: row `i`'s edges are `start[i]..start[i + 1]`.
struct Rows {
    start: Vec<usize>,
    cols: Vec<u32>,
    costs: Vec<f64>,
}

impl Rows {
    fn new(edges: &[Vec<(u32, f64)>]) -> Self {
        let mut start = Vec::with_capacity(edges.len() + 1);
        start.push(0);
        let total = edges.iter().map(Vec::len).sum();
        let (mut cols, mut costs) = (Vec::with_capacity(total), Vec::with_capacity(total));
        for row in edges {
            cols.extend(row.iter().map(|e| e.0));
            costs.extend(row.iter().map(|e| e.1));
            start.push(cols.len());
        }
        Self { start, cols, costs }
    }

    /// Row `i`'s bid at prices `q`: its best column `j₁` and the rise of its
    /// price, the gap to the second-best column plus `eps` (`lone` instead of
    /// the gap when the row has one edge); column `NONE` when it has no edge.
    ///
    /// A tie for the best column goes to the earlier edge within one of the
    /// [`LANES`] interleaved scans, and to the lower column between scans.
    fn bid(&self, i: usize, q: &[f64], eps: f64, lone: f64) -> (u32, f64) {
        let range = self.start[i]..self.start[i + 1];
        let (cols, costs) = (&self.cols[range.clone()], &self.costs[range]);
        // Best and second-best per lane of LANES independent scans (their
        // compare chains overlap), written without branches (selects) so
        // unpredictable comparisons cost no mispredictions; then merged.
        let mut best = [Best::EMPTY; LANES];
        let (col_chunks, cost_chunks) = (cols.chunks_exact(LANES), costs.chunks_exact(LANES));
        let (col_rest, cost_rest) = (col_chunks.remainder(), cost_chunks.remainder());
        for (cj, cc) in col_chunks.zip(cost_chunks) {
            for l in 0..LANES {
                best[l].push(cj[l], cc[l] + q[cj[l] as usize]);
            }
        }
        for (l, (&j, &c)) in col_rest.iter().zip(cost_rest).enumerate() {
            best[l].push(j, c + q[j as usize]);
        }
        let b = best.iter().fold(Best::EMPTY, |a, b| a.merge(b));
        if b.j1 == NONE {
            return (NONE, 0.0);
        }
        let gap = if b.r2.is_finite() { b.r2 - b.r1 } else { lone };
        (b.j1, gap + eps)
    }
}

/// Independent scans per bid.
const LANES: usize = 4;

/// The best column `j1` of a scan, its value `r1` and the second-best value `r2`.
#[derive(Clone, Copy)]
struct Best {
    j1: u32,
    r1: f64,
    r2: f64,
}

impl Best {
    const EMPTY: Self = Self {
        j1: NONE,
        r1: f64::INFINITY,
        r2: f64::INFINITY,
    };

    /// Adds column `j` of value `r` (ties for the best to the lower column).
    #[inline(always)]
    fn push(&mut self, j: u32, r: f64) {
        let better = r < self.r1;
        let low = if r < self.r2 { r } else { self.r2 };
        self.r2 = if better { self.r1 } else { low };
        self.j1 = if better { j } else { self.j1 };
        self.r1 = if better { r } else { self.r1 };
    }

    /// The best and second best of two scans together.
    fn merge(self, other: &Self) -> Self {
        let (win, lose) = if other.r1 < self.r1 || (other.r1 == self.r1 && other.j1 < self.j1) {
            (*other, self)
        } else {
            (self, *other)
        };
        Self {
            j1: win.j1,
            r1: win.r1,
            r2: win.r2.min(lose.r1),
        }
    }
}

/// Runs the auction from prices `q`, raising them in place; `false` if a phase ran out
/// of its bid budget (a price war, or a graph without a perfect matching).
///
/// A phase whose bids pass [`WAR_BIDS_PER_ROW`] per row, a price war (rows
/// outbidding each other by ε for columns too few for them), starts again
/// from the prices it reached at ε raised by `1 / factor²`, up to
/// `eps_max` and at most [`MAX_RAISES`] times: a war's bids fall with ε,
/// and the phases that follow bring ε back down. A start near the optimum (a warm solve's kept prices) fights
/// its wars where the kept prices are far off; the other rows move little.
///
/// The prices only rise, and every bid leaves its bidder within ε of its best
/// column, so the prices reached when the budget runs out are still a better
/// start for the exact finish than the ones the auction began with.
pub(crate) fn run(
    edges: &[Vec<(u32, f64)>],
    q: &mut [f64],
    eps_start: f64,
    eps_end: f64,
    eps_max: f64,
    factor: f64,
) -> bool {
    let n = edges.len();
    let rows = Rows::new(edges);
    let budget = 200 * n + 10_000;
    let war = WAR_BIDS_PER_ROW * n + 10_000;
    let mut raises = MAX_RAISES;
    let mut eps = eps_start.max(eps_end);
    let mut owner = vec![NONE; n];
    'phase: loop {
        owner.fill(NONE);
        let mut queue: Vec<u32> = (0..n as u32).rev().collect();
        let mut bids = 0usize;
        while let Some(i) = queue.pop() {
            bids += 1;
            if bids > war && eps < eps_max && raises > 0 {
                raises -= 1;
                eps = (eps / (factor * factor)).min(eps_max);
                continue 'phase;
            }
            // A lone edge: any rise keeps the row on it; the first ε scales with the costs.
            let (j, rise) = rows.bid(i as usize, q, eps, eps_start);
            if bids > budget || j == NONE {
                return false;
            }
            q[j as usize] += rise;
            let previous = owner[j as usize];
            if previous != NONE {
                queue.push(previous);
            }
            owner[j as usize] = i;
        }
        if eps <= eps_end {
            return true;
        }
        eps = (eps * factor).max(eps_end);
    }
}

/// Bids per row after which a phase counts as a price war (see [`run`]).
const WAR_BIDS_PER_ROW: usize = 20;

/// Most raises of ε in one auction (see [`run`]): a war that comes back
/// after them runs to the phase's budget instead of raising ε again.
const MAX_RAISES: usize = 2;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn prices_reach_complementary_slackness_or_the_budget_stops_a_price_war() {
        // Two rows, two columns, a unique optimum 0 → 0, 1 → 1.
        let edges = vec![vec![(0, 0.0), (1, 1.0)], vec![(0, 0.5), (1, 0.6)]];
        let mut q = vec![0.0; 2];
        assert!(run(&edges, &mut q, 0.1, 1e-9, 0.1, 0.2));
        // ε-complementary slackness of the optimum at the final ε.
        assert!(edges[0][0].1 + q[0] <= edges[0][1].1 + q[1] + 1e-9);
        assert!(edges[1][1].1 + q[1] <= edges[1][0].1 + q[0] + 1e-9);
        // Three rows that all want column 0 only: no perfect matching, so the
        // bids run out; the prices rose from where they started and stay finite.
        let edges = vec![
            vec![(0, 0.0)],
            vec![(0, 0.1)],
            vec![(0, 0.2), (1, 5.0), (2, 5.0)],
        ];
        let mut q = vec![0.0; 3];
        assert!(!run(&edges, &mut q, 0.1, 1e-9, 0.1, 0.2));
        assert!(q[0] > 0.0 && q.iter().all(|p| p.is_finite()));
    }

    #[test]
    fn a_price_war_raises_eps_up_to_its_ceiling_and_finishes() {
        // 50 rows want columns 0 and 1 (cost 0); all but two must settle for
        // their own column at cost 1. At ε = 1e-5 the prices of columns 0 and 1
        // climb to 1 by about ε per bid: more bids than the budget.
        let edges: Vec<Vec<(u32, f64)>> = (0..50u32)
            .map(|i| {
                let mut row = vec![(0, 0.0), (1, 0.0)];
                if i >= 2 {
                    row.push((i, 1.0));
                }
                row
            })
            .collect();
        let mut q = vec![0.0; 50];
        assert!(!run(&edges, &mut q, 1e-5, 1e-9, 1e-5, 0.2));
        let mut q = vec![0.0; 50];
        assert!(run(&edges, &mut q, 1e-5, 1e-9, 0.1, 0.2));
        // Rows 0 and 1 hold columns 0 and 1 (their only edges), the others
        // their own: ε-complementary slackness at the last ε for those.
        let cheap = q[0].min(q[1]);
        assert!((2..50).all(|i| 1.0 + q[i] <= cheap + 1e-8));
    }
}
