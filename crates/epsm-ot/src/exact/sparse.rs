//! Shortest-augmenting-path assignment on a sparse candidate graph, with warm-started potentials.
//!
//! Jonker–Volgenant style: row potentials `u` and column potentials `v` keep
//! every candidate edge dual feasible (`c_ij − u_i − v_j ≥ 0`) and every
//! matched edge tight. Each free row is matched by a Dijkstra search over
//! reduced costs (a binary heap, so a search touches only the few columns a
//! good warm start leaves within reach), after which the potentials of the
//! scanned columns are shifted so feasibility and tightness still hold.
//! Before the searches, Jonker–Volgenant's augmenting row reduction
//! ([`SparseAssignment::reduce_rows`]) matches free rows by exact bids (a
//! column's potential falls until the bidder's second-best column ties), a
//! few per row where an auction left the prices.
//! Edges can be added at any time: an edge that violates feasibility lowers
//! its row's potential and frees that row for another search. Column
//! potentials only fall, so each row's floor from the last optimality check
//! (see `check`) stays a valid bound.

use std::cmp::Ordering;
use std::collections::BinaryHeap;

const NONE: u32 = u32::MAX;

/// The cost of edge `(·, j)` in a row's edges.
fn c_of(row: &[(u32, f64)], j: u32) -> f64 {
    row.iter().find(|e| e.0 == j).map_or(f64::INFINITY, |e| e.1)
}

/// Candidate edges per row: (column, cost).
pub(crate) type Edges = Vec<Vec<(u32, f64)>>;

/// A heap entry ordered by smallest distance first, ties by column.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Entry {
    dist: f64,
    col: u32,
}

impl Eq for Entry {}

impl Ord for Entry {
    fn cmp(&self, other: &Self) -> Ordering {
        other
            .dist
            .total_cmp(&self.dist)
            .then(other.col.cmp(&self.col))
    }
}

impl PartialOrd for Entry {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}

/// The sparse assignment state: candidate edges, potentials and the (partial) matching.
#[derive(Debug, Clone)]
pub(crate) struct SparseAssignment {
    edges: Vec<Vec<(u32, f64)>>,
    pub u: Vec<f64>,
    pub v: Vec<f64>,
    col_of: Vec<u32>,
    row_of: Vec<u32>,
    dist: Vec<f64>,
    pred: Vec<u32>,
    scanned: Vec<bool>,
    /// Per row, a lower bound on `c_ij − v_j` over the pairs outside the graph
    /// (`−∞` before its first check; see `check`).
    floors: Vec<f64>,
    /// The buffers of [`Self::augment`], kept between searches.
    search: Search,
}

/// A search's heap, the columns it gave a distance and those it settled.
#[derive(Debug, Clone, Default)]
struct Search {
    heap: BinaryHeap<Entry>,
    touched: Vec<u32>,
    scanned: Vec<u32>,
}

impl SparseAssignment {
    /// Starts from candidate edges (per row) and column potentials `v`; rows take `u_i = min_j c_ij − v_j`
    /// and are greedily matched along a tight edge when its column is free.
    /// Every row needs a check.
    pub fn new(edges: Vec<Vec<(u32, f64)>>, v: Vec<f64>) -> Self {
        let n = edges.len();
        Self::with_floors(edges, v, vec![f64::NEG_INFINITY; n])
    }

    /// [`Self::new`] keeping the rows' floors from an earlier check on the
    /// same edges (or fewer), valid if `v` is at most the potentials they were found with.
    pub fn with_floors(edges: Vec<Vec<(u32, f64)>>, v: Vec<f64>, floors: Vec<f64>) -> Self {
        let n = edges.len();
        let mut s = Self {
            u: vec![f64::INFINITY; n],
            v,
            col_of: vec![NONE; n],
            row_of: vec![NONE; n],
            dist: vec![f64::INFINITY; n],
            pred: vec![NONE; n],
            scanned: vec![false; n],
            floors,
            edges,
            search: Search::default(),
        };
        for i in 0..n {
            let best = s.edges[i]
                .iter()
                .map(|&(j, c)| (c - s.v[j as usize], j))
                .min_by(|a, b| a.0.total_cmp(&b.0));
            if let Some((red, j)) = best {
                s.u[i] = red;
                if s.row_of[j as usize] == NONE {
                    s.row_of[j as usize] = i as u32;
                    s.col_of[i] = j;
                }
            }
        }
        s
    }

    /// The candidate edges, the column potentials and the rows' floors (see [`Self::with_floors`]).
    pub fn into_parts(self) -> (Edges, Vec<f64>, Vec<f64>) {
        (self.edges, self.v, self.floors)
    }

    /// The candidate edges and both potentials (the matching is [`Self::permutation`]).
    pub fn into_potentials(self) -> (Edges, Vec<f64>, Vec<f64>) {
        (self.edges, self.u, self.v)
    }

    /// Number of candidate edges.
    pub fn edge_count(&self) -> usize {
        self.edges.iter().map(Vec::len).sum()
    }

    /// Adds edges `(row, col, cost)` not already in the graph and returns how
    /// many it added; rows whose potential must drop to stay feasible are unmatched.
    pub fn add_edges(&mut self, added: &[(u32, u32, f64)]) -> usize {
        let mut count = 0;
        for &(i, j, c) in added {
            let (i, ju) = (i as usize, j as usize);
            if self.edges[i].iter().any(|e| e.0 == j) {
                continue;
            }
            count += 1;
            self.edges[i].push((j, c));
            let red = c - self.v[ju];
            if red < self.u[i] {
                self.u[i] = red;
                let old = self.col_of[i];
                if old != NONE {
                    self.row_of[old as usize] = NONE;
                    self.col_of[i] = NONE;
                }
            }
        }
        count
    }

    /// Which rows need an optimality check: those whose potential is above
    /// their floor (all rows at first).
    ///
    /// The others cannot have a violated pair: the graph's edges are kept
    /// feasible, and every other pair has `c_ij − v_j ≥ floor_i ≥ u_i`.
    pub fn unsettled_rows(&self) -> Vec<bool> {
        self.u
            .iter()
            .zip(&self.floors)
            .map(|(u, f)| u > f)
            .collect()
    }

    /// The potentials `u, v` and the rows' floors, for a check to update.
    pub fn check_view(&mut self) -> (&[f64], &[f64], &mut [f64]) {
        (&self.u, &self.v, &mut self.floors)
    }

    /// Rows without a column.
    pub fn free_rows(&self) -> Vec<usize> {
        (0..self.col_of.len())
            .filter(|&i| self.col_of[i] == NONE)
            .collect()
    }

    /// The matching as a permutation (every row must be matched).
    pub fn permutation(&self) -> Vec<usize> {
        self.col_of.iter().map(|&j| j as usize).collect()
    }

    /// Jonker–Volgenant's augmenting row reduction: each free row takes its
    /// best column, whose potential falls until the row's second-best column
    /// ties with it (so the row is tight on it and feasible on the rest),
    /// evicting the column's owner, which bids in turn; at most `budget`
    /// bids. Column potentials only fall and the invariants hold, so the rows
    /// it leaves free go to [`Self::augment`].
    ///
    /// An auction's prices leave each row within its last ε of its best
    /// column, so many rows share a best column: the greedy start of
    /// [`Self::with_floors`] leaves about a quarter of the rows free, and
    /// these bids match most of them without a search.
    pub fn reduce_rows(&mut self, budget: usize) -> usize {
        let mut queue: Vec<u32> = (0..self.col_of.len() as u32)
            .rev()
            .filter(|&i| self.col_of[i as usize] == NONE)
            .collect();
        let mut bids = 0;
        while let Some(i) = queue.pop() {
            if bids == budget {
                break;
            }
            bids += 1;
            let i = i as usize;
            let (mut j1, mut r1, mut j2, mut r2) = (NONE, f64::INFINITY, NONE, f64::INFINITY);
            for &(j, c) in &self.edges[i] {
                let r = c - self.v[j as usize];
                if r < r1 {
                    (j2, r2) = (j1, r1);
                    (j1, r1) = (j, r);
                } else if r < r2 {
                    (j2, r2) = (j, r);
                }
            }
            if j1 == NONE {
                continue;
            }
            let mut j = j1 as usize;
            if r1 < r2 && r2.is_finite() {
                self.v[j] -= r2 - r1;
                self.u[i] = (c_of(&self.edges[i], j1) - self.v[j]).min(r2);
            } else {
                // A tie: no potential can fall, so the row takes a free
                // column among the tied ones or stays free (no eviction
                // without a fall, which could cycle).
                self.u[i] = r1;
                if self.row_of[j] != NONE {
                    if j2 == NONE || self.row_of[j2 as usize] != NONE {
                        continue;
                    }
                    j = j2 as usize;
                }
            }
            let previous = self.row_of[j];
            self.row_of[j] = i as u32;
            self.col_of[i] = j as u32;
            if previous != NONE {
                self.col_of[previous as usize] = NONE;
                queue.push(previous);
            }
        }
        bids
    }

    /// Matches the free row `i0` along a shortest augmenting path; `false` if no free column is reachable.
    pub fn augment(&mut self, i0: usize) -> bool {
        let Search {
            mut heap,
            mut touched,
            mut scanned,
        } = std::mem::take(&mut self.search);
        heap.clear();
        touched.clear();
        scanned.clear();
        self.relax(i0, 0.0, &mut heap, &mut touched);
        let mut found = None;
        // Dijkstra over columns until a free one is settled.
        while let Some(Entry { dist, col }) = heap.pop() {
            let j = col as usize;
            if self.scanned[j] || dist > self.dist[j] {
                continue;
            }
            self.scanned[j] = true;
            scanned.push(col);
            if self.row_of[j] == NONE {
                found = Some((j, dist));
                break;
            }
            self.relax(self.row_of[j] as usize, dist, &mut heap, &mut touched);
        }
        if let Some((sink, dmin)) = found {
            // Shift potentials: settled columns and their rows move by dmin − d_j.
            self.u[i0] += dmin;
            for &j in &scanned {
                let j = j as usize;
                if j != sink {
                    let shift = dmin - self.dist[j];
                    let i = self.row_of[j] as usize;
                    self.u[i] += shift;
                    self.v[j] -= shift;
                }
            }
            // Flip the path back to i0.
            let mut j = sink;
            loop {
                let i = self.pred[j] as usize;
                let prev = self.col_of[i];
                self.col_of[i] = j as u32;
                self.row_of[j] = i as u32;
                if i == i0 {
                    break;
                }
                j = prev as usize;
            }
        }
        for &j in &touched {
            self.dist[j as usize] = f64::INFINITY;
            self.scanned[j as usize] = false;
        }
        self.search = Search {
            heap,
            touched,
            scanned,
        };
        found.is_some()
    }

    fn relax(&mut self, i: usize, base: f64, heap: &mut BinaryHeap<Entry>, touched: &mut Vec<u32>) {
        for &(j, c) in &self.edges[i] {
            let ju = j as usize;
            if self.scanned[ju] {
                continue;
            }
            let d = base + (c - self.u[i] - self.v[ju]).max(0.0);
            if d < self.dist[ju] {
                if self.dist[ju] == f64::INFINITY {
                    touched.push(j);
                }
                self.dist[ju] = d;
                self.pred[ju] = i as u32;
                heap.push(Entry { dist: d, col: j });
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every edge feasible and every matched edge tight, to rounding.
    fn assert_invariants(s: &SparseAssignment) {
        for (i, row) in s.edges.iter().enumerate() {
            for &(j, c) in row {
                let reduced = c - s.u[i] - s.v[j as usize];
                assert!(reduced >= -1e-12, "edge ({i}, {j}) infeasible: {reduced}");
                if s.col_of[i] == j {
                    assert!(reduced.abs() <= 1e-12, "matched edge ({i}, {j}) not tight");
                }
            }
        }
    }

    #[test]
    fn row_reduction_matches_rows_keeping_feasibility_and_tightness() {
        // Rows 0 and 1 both prefer column 0 (row 1 by less), row 2 prefers column 1.
        let edges = vec![
            vec![(0, 0.0), (1, 1.0), (2, 3.0)],
            vec![(0, 0.0), (1, 0.5), (2, 0.7)],
            vec![(1, 0.0), (2, 0.4)],
        ];
        let mut s = SparseAssignment::new(edges, vec![0.0; 3]);
        assert_eq!(s.free_rows(), vec![1]);
        let v0 = s.v.clone();
        assert!(s.reduce_rows(10) >= 1);
        assert!(s.free_rows().is_empty());
        assert_invariants(&s);
        assert!(
            s.v.iter().zip(&v0).all(|(a, b)| a <= b),
            "column potentials only fall"
        );
        // The optimum 0 → 0, 1 → 2, 2 → 1 (cost 0.7) is what the rows hold.
        assert_eq!(s.permutation(), vec![0, 2, 1]);
    }

    #[test]
    fn row_reduction_leaves_a_row_free_on_a_tie_between_taken_columns() {
        // Row 2 ties between columns 0 and 1, both taken at equal potentials:
        // no potential can fall, so it stays free for a search (no eviction cycle).
        let edges = vec![
            vec![(0, 0.0)],
            vec![(1, 0.0)],
            vec![(0, 1.0), (1, 1.0), (2, 5.0)],
        ];
        let mut s = SparseAssignment::new(edges, vec![0.0; 3]);
        assert_eq!(s.free_rows(), vec![2]);
        s.reduce_rows(10);
        assert_eq!(s.free_rows(), vec![2]);
        assert_invariants(&s);
        assert!(s.augment(2));
        assert_invariants(&s);
        assert_eq!(s.permutation(), vec![0, 1, 2]);
    }
}
