//! What a solve returns: the loss, the per-point gradient and the matching itself.
//!
//! Every matcher returns an [`OtResult`]. Its [`Matching`] says how the source
//! points were matched so a viewer can draw it: a permutation for the exact
//! solver, potentials plus barycentric targets for the entropic one, and
//! per-point displacement targets for the approximate sliced matcher. Whatever
//! the matcher, [`OtResult::target`] gives the point each source point is
//! pulled toward, and `gradient[i] = 2 (P_i − target(i)) / n` (for the
//! debiased divergence, the target includes the self-transport correction).

use crate::points::Point;

/// Result of matching a source cloud to a target cloud.
#[derive(Debug, Clone, PartialEq)]
pub struct OtResult {
    /// The loss value (see each matcher for its exact definition).
    pub loss: f64,
    /// `∂L/∂P_i` for every source point, in source order.
    pub gradient: Vec<Point>,
    /// How the points were matched.
    pub matching: Matching,
    /// Work counters of the solve.
    pub stats: SolveStats,
}

impl OtResult {
    /// The point source point `i` is pulled toward: `P_i − (n/2) ∂L/∂P_i`.
    pub fn target(&self, source_point: Point, i: usize) -> Point {
        let half_n = self.gradient.len() as f32 / 2.0;
        std::array::from_fn(|d| source_point[d] - half_n * self.gradient[i][d])
    }
}

/// The matching found by a solver.
#[derive(Debug, Clone, PartialEq)]
pub enum Matching {
    /// Exact assignment: source point `i` is matched to target point `perm[i]`.
    Permutation(Vec<usize>),
    /// Entropic plan: dual potentials and each source point's barycentric target.
    Entropic(EntropicPlan),
    /// Sliced (approximate) matching: each source point's displacement target.
    Sliced(SlicedPlan),
}

/// An entropic transport plan `π_ij = a_i b_j exp((f_i + g_j − c_ij) / ε)`, stored through its potentials.
#[derive(Debug, Clone, PartialEq)]
pub struct EntropicPlan {
    /// The final regularisation ε (the squared blur).
    pub epsilon: f64,
    /// Source potential `f_i`, in source order.
    pub f: Vec<f64>,
    /// Target potential `g_j`, in target order.
    pub g: Vec<f64>,
    /// Barycentric projection `T(P_i) = Σ_j π_ij Q_j / Σ_j π_ij` of each source point.
    pub barycentres: Vec<Point>,
    /// Primal transport cost `Σ_ij π_ij c_ij` of the (row-normalised) plan.
    pub transport_cost: f64,
    /// L1 error of the plan's source marginal (the target marginal is exact after the last update).
    pub marginal_error: f64,
}

impl EntropicPlan {
    /// The barycentric target of source point `i`.
    pub fn barycentric_target(&self, i: usize) -> Point {
        self.barycentres[i]
    }
}

/// A sliced matching: the average, over random 1-D projections, of each point's sorted partner.
#[derive(Debug, Clone, PartialEq)]
pub struct SlicedPlan {
    /// Number of random projections used.
    pub projections: usize,
    /// The point each source point is pulled toward, in source order.
    pub targets: Vec<Point>,
}

/// Work counters, for benchmarks and reports.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct SolveStats {
    /// Sinkhorn updates (each a pass over source and target), or sparse re-solves for the exact solver.
    pub iterations: usize,
    /// Number of `(i, j)` cost/kernel evaluations.
    pub pair_evaluations: u64,
    /// Candidate pairs in the sparse graph at the end (exact solver).
    pub candidate_pairs: usize,
    /// Pairs the optimality checks added to the graph: violated ones, and in a
    /// warm-started solve also those within `exact.warm_check_margin` of tight (exact solver).
    pub added_pairs: usize,
    /// Auctions stopped by their bid budget, whose prices were used as reached
    /// (exact solver, and the exact solves of the entropic solver's `exact_prices`).
    pub auction_budget_stops: usize,
    /// Warm starts replaced by the cold start (zero potentials, candidates
    /// searched among all pairs) because the clouds were beyond the entropic
    /// warm start's range or its potentials were not finite (exact solver, and
    /// the exact solves of the entropic solver's `exact_prices`).
    pub cold_starts: usize,
    /// Solves started from the state a previous solve left (`crate::MatchState`):
    /// 1 for a warm-started exact or entropic solve (per entropic problem: up
    /// to 3 with `debias`), 0 for a cold one.
    pub warm_starts: usize,
    /// L1 marginal error of the plan (entropic solver).
    pub marginal_error: Option<f64>,
    /// Entropic solves (the plan's, and with `debias` the two self-transport
    /// ones) whose polish ran out of `max_polish_iterations`, or stalled (see
    /// `SinkhornSettings::stall_margin`), with a finite L1 marginal error still
    /// above `marginal_tolerance`: results returned, but not converged
    /// (entropic solver; a non-finite error is `OtError::NotConverged` instead).
    pub unconverged_solves: usize,
    /// Coarse corrections whose cluster scaling converged only once lumped per
    /// connected component of the support with bridges between the components,
    /// before the scale's support was rebuilt (entropic solver).
    pub bridged_corrections: usize,
    /// Coarse corrections whose cluster scaling did not converge even lumped,
    /// applied clamped before the scale's support was rebuilt (entropic solver).
    pub clamped_corrections: usize,
    /// Wall-clock seconds of the named phases of the solve, in the order they first ran.
    pub phases: PhaseTimes,
}

/// Wall-clock seconds spent in each named phase of a solve (for benchmarks).
///
/// Two values are equal when the same phases ran in the same order: the
/// durations are measurements, not results, so they never make two otherwise
/// identical solves differ (results are deterministic, timings are not).
#[derive(Debug, Clone, Default)]
pub struct PhaseTimes(Vec<(&'static str, f64)>);

impl PhaseTimes {
    /// Runs `work` and adds its wall-clock time to the phase `name`.
    pub fn time<T>(&mut self, name: &'static str, work: impl FnOnce() -> T) -> T {
        let start = std::time::Instant::now();
        let out = work();
        self.add(name, start.elapsed().as_secs_f64());
        out
    }

    /// Adds `seconds` to the phase `name` (appended if it is new).
    pub fn add(&mut self, name: &'static str, seconds: f64) {
        match self.0.iter_mut().find(|(n, _)| *n == name) {
            Some((_, s)) => *s += seconds,
            None => self.0.push((name, seconds)),
        }
    }

    /// Adds every phase of `other` to this one.
    pub fn merge(&mut self, other: &Self) {
        other.0.iter().for_each(|&(name, s)| self.add(name, s));
    }

    /// The phases and their seconds, in the order they first ran.
    pub fn iter(&self) -> impl Iterator<Item = (&'static str, f64)> + '_ {
        self.0.iter().copied()
    }
}

impl PartialEq for PhaseTimes {
    fn eq(&self, other: &Self) -> bool {
        self.0.len() == other.0.len() && self.0.iter().zip(&other.0).all(|(a, b)| a.0 == b.0)
    }
}
