//! Warm starts: what one solve leaves for the next solve of a sequence of similar problems.
//!
//! In an optimization the target cloud stays the same and the source cloud
//! (the rendered image) changes a little from one solve to the next. A
//! [`MatchState`] carries what a solve found into the next one through
//! [`Matcher::solve_warm`]:
//!
//! - **exact**: the target potentials, the permutation, each source point's
//!   best candidate targets and the target's clustering (see `exact::warm`).
//!   The next solve starts its sparse assignment from them, skipping the
//!   entropic warm start and the candidate search; its auction starts from
//!   the kept prices at the small first ε `exact.warm_auction_start`, and it
//!   ends with the same certificate (dual feasibility over all n² pairs, tightness on
//!   the matching). Its loss equals the cold solve's to rounding, and its
//!   permutation differs from the cold one's only among ties (permutations of
//!   equal cost), whatever the state held: the state only decides how fast.
//! - **sinkhorn**: the potentials `f, g` (and with `debias` those of the two
//!   self-transport problems). The next solve runs only the polish at the
//!   final ε from them, to the same marginal tolerance: the same fixed point,
//!   reached from another start, so loss and gradient agree with the cold
//!   solve's to within that tolerance, not bit for bit. A polish that stalls
//!   or runs out of updates is replaced by the cold solve. On rendered
//!   sequences with fresh Monte Carlo noise per image the polish from kept
//!   potentials took about as long as the cold solve (`epsm bench ot
//!   --sequence`): the coarse corrections of the cold loop remove the
//!   large-scale error a changed source leaves, the polish does not.
//! - **sliced**: nothing is kept.
//!
//! A state from another matcher or other settings, or from clouds of another
//! size, is dropped and the solve starts cold. Results are deterministic
//! given the same sequence of solves, whatever the number of threads.
//! `SolveStats::warm_starts` counts the solves that started warm.
//!
//! ```
//! use epsm_ot::{MatchState, Matcher, synthetic};
//! let (source, target) = synthetic::blobs_pair(1024, 1).expect("fixture");
//! let mut state = MatchState::new();
//! let matcher = Matcher::exact();
//! let cold = matcher.solve_warm(&source, &target, &mut state)?;
//! let warm = matcher.solve_warm(&source, &target, &mut state)?;
//! assert_eq!(warm.stats.warm_starts, 1);
//! assert!((warm.loss - cold.loss).abs() <= 1e-12 * cold.loss);
//! # Ok::<(), epsm_ot::OtError>(())
//! ```

use crate::Matcher;
use crate::error::OtError;
use crate::exact::ExactState;
use crate::plan::OtResult;
use crate::points::PointCloud;
use crate::sinkhorn::SinkhornState;

/// What the last solve of a sequence left for the next one (empty at first).
#[derive(Debug, Clone, Default)]
pub struct MatchState {
    kept: Option<Kept>,
}

/// The kept state and the matcher (with its settings) that made it.
#[derive(Debug, Clone)]
struct Kept {
    matcher: Matcher,
    solver: SolverState,
}

/// One matcher's kept state.
#[derive(Debug, Clone)]
enum SolverState {
    Exact(ExactState),
    Sinkhorn(SinkhornState),
}

impl MatchState {
    /// An empty state: the next solve starts cold.
    pub fn new() -> Self {
        Self::default()
    }

    /// Forgets the kept state (the next solve starts cold).
    pub fn clear(&mut self) {
        self.kept = None;
    }

    /// Whether nothing is kept.
    pub fn is_empty(&self) -> bool {
        self.kept.is_none()
    }

    /// The kept target potentials of an exact solve (target order).
    #[cfg(test)]
    pub(crate) fn exact_potentials(&self) -> Option<&[f64]> {
        match &self.kept.as_ref()?.solver {
            SolverState::Exact(e) => Some(e.target_potentials()),
            SolverState::Sinkhorn(_) => None,
        }
    }
}

impl Matcher {
    /// Like [`Matcher::solve`], started from what the previous solve left in
    /// `state`, which then holds what this solve leaves for the next (see the
    /// module doc). A failed solve leaves `state` empty.
    pub fn solve_warm(
        &self,
        source: &PointCloud,
        target: &PointCloud,
        state: &mut MatchState,
    ) -> Result<OtResult, OtError> {
        let kept = state.kept.take().filter(|k| k.matcher == *self);
        let solver = kept.map(|k| k.solver);
        let (result, solver) = match self {
            Self::Exact(s) => {
                let mut e = match solver {
                    Some(SolverState::Exact(e)) => Some(e),
                    _ => None,
                };
                let result = crate::exact::solve_from(source, target, s, Some(&mut e));
                (result, e.map(SolverState::Exact))
            }
            Self::Sinkhorn(s) => {
                let mut e = match solver {
                    Some(SolverState::Sinkhorn(e)) => Some(e),
                    _ => None,
                };
                let result = crate::sinkhorn::solve_from(source, target, s, Some(&mut e));
                (result, e.map(SolverState::Sinkhorn))
            }
            Self::Sliced(s) => (crate::sliced::solve(source, target, s), None),
        };
        state.kept = solver.map(|solver| Kept {
            matcher: self.clone(),
            solver,
        });
        result
    }
}
