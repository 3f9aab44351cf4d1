//! Optimal-transport matching of 5-D RGBXY point clouds: loss, gradient and the matching itself.
//!
//! This is the loss of Xing et al. 2022 ("Differentiable rendering using RGBXY
//! derivatives and optimal transport"): every pixel of the rendered image and
//! of the target image becomes a point, the two clouds are matched by optimal
//! transport, and each rendered pixel gets a gradient for its colour *and* its
//! screen position.
//!
//! # Conventions
//! - **Point**: `P = (r, g, b, λx, λy)`, `f32`. Colours are tone-mapped and
//!   clamped (usually `[0, 1]`); `x, y` are screen positions in `[0, 1]`
//!   scaled by the user's λ (the weight of position against colour).
//!   Stored as five SoA columns in a [`PointCloud`]. Clouds are non-empty,
//!   finite, and matched only when of equal size; every point has mass `1/n`.
//!   Each matcher refuses clouds beyond the range of its `f32` arithmetic
//!   ([`OtError::SpreadTooLarge`]).
//! - **Cost**: `c(P, Q) = ‖P − Q‖²`, the squared Euclidean distance in 5-D.
//! - **Loss**: exact: `L = 1/n Σ_i ‖P_i − Q_σ(i)‖²` for the optimal permutation σ;
//!   entropic: `OT_ε` (or the debiased `S_ε`), see [`sinkhorn`]; sliced: see [`sliced`].
//! - **Gradient**: `∂L/∂P_i`, a 5-vector per source point, always of the form
//!   `2 (P_i − T_i) / n` where `T_i` is what `P_i` is matched to (its partner,
//!   or its barycentric target). Only the source cloud gets a gradient.
//! - **Determinism**: the same input gives bit-identical output whatever the
//!   number of rayon threads (fixed chunks, reductions in a fixed order).
//!
//! # Solvers
//! All behind [`Matcher`], all returning an [`OtResult`] (loss, gradient, [`Matching`]):
//! - [`exact`]: the optimal permutation, with a certificate: dual potentials
//!   feasible for *all* n² pairs (checked by a streaming pass with rigorous
//!   block pruning) and tight on the matching. Sparse candidate graph from a
//!   Sinkhorn warm start, ε-scaling auction, shortest augmenting paths; never
//!   builds the n×n matrix. [`exact::dense`] is the O(n³) reference.
//! - [`sinkhorn`]: entropic OT, log-domain, ε-scaling, multiscale with kernel
//!   truncation, computed online; iterates at the final ε until the L1
//!   marginal error is below the tolerance (1e-3 by default), or counts the
//!   solve in `SolveStats::unconverged_solves` when the cap of updates stops
//!   it first; a non-finite marginal error is [`OtError::NotConverged`].
//! - [`sliced`]: approximate sliced OT (random 1-D projections).
//!
//! [`synthetic::blobs_pair`] is the benchmark fixture (`epsm bench ot`).
//!
//! # Example
//! ```
//! use epsm_ot::{Matcher, PointCloud};
//! let source = PointCloud::from_points(&[[0.1, 0.2, 0.3, 0.0, 0.0], [0.9, 0.8, 0.7, 1.0, 1.0]])?;
//! let target = PointCloud::from_points(&[[0.9, 0.8, 0.7, 1.0, 0.9], [0.1, 0.2, 0.3, 0.0, 0.1]])?;
//! let result = Matcher::exact().solve(&source, &target)?;
//! assert!((result.loss - 0.01).abs() < 1e-6);
//! // The first source point moves toward the second target point (−y).
//! assert!(result.gradient[0][4] < 0.0);
//! # Ok::<(), epsm_ot::OtError>(())
//! ```

mod clusters;
pub mod cost;
mod cpu;
mod disjoint_sets;
pub mod error;
pub mod estimate;
pub mod exact;
pub mod plan;
pub mod points;
pub mod sinkhorn;
pub mod sliced;
mod softmin;
pub mod synthetic;
pub mod warm;

#[cfg(test)]
mod tests;

pub use cpu::{Simd, active_simd, force_simd};
pub use error::OtError;
pub use estimate::{MatchEstimate, MatchLimits};
pub use exact::ExactSettings;
pub use plan::{EntropicPlan, Matching, OtResult, PhaseTimes, SlicedPlan, SolveStats};
pub use points::{DIM, Point, PointCloud};
pub use sinkhorn::{MAX_SPREAD, MIN_BLUR, SinkhornSettings};
pub use sliced::SlicedSettings;
pub use warm::MatchState;

/// Which solver to use, with its settings: one interface for all of them.
#[derive(Debug, Clone, PartialEq)]
pub enum Matcher {
    /// Exact assignment (verified optimal).
    Exact(ExactSettings),
    /// Entropic OT by ε-scaling Sinkhorn.
    Sinkhorn(SinkhornSettings),
    /// Approximate sliced OT.
    Sliced(SlicedSettings),
}

impl Matcher {
    /// The exact solver with default settings.
    pub fn exact() -> Self {
        Self::Exact(ExactSettings::default())
    }

    /// The entropic solver with GeomLoss's defaults (blur 0.01, scaling 0.9).
    pub fn sinkhorn() -> Self {
        Self::Sinkhorn(SinkhornSettings::default())
    }

    /// The sliced matcher with 64 projections.
    pub fn sliced() -> Self {
        Self::Sliced(SlicedSettings::default())
    }

    /// Short name: `exact`, `sinkhorn` or `sliced`.
    pub fn name(&self) -> &'static str {
        match self {
            Self::Exact(_) => "exact",
            Self::Sinkhorn(_) => "sinkhorn",
            Self::Sliced(_) => "sliced",
        }
    }

    /// Matches `source` to `target` and returns loss, gradient and matching.
    pub fn solve(&self, source: &PointCloud, target: &PointCloud) -> Result<OtResult, OtError> {
        match self {
            Self::Exact(s) => exact::solve(source, target, s),
            Self::Sinkhorn(s) => sinkhorn::solve(source, target, s),
            Self::Sliced(s) => sliced::solve(source, target, s),
        }
    }
}
