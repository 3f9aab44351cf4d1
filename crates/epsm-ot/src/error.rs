//! Typed errors for bad input and out-of-range settings.
//!
//! Every public solver entry point validates its input and returns an
//! [`OtError`] instead of panicking: empty clouds, clouds of different sizes,
//! ragged coordinate columns, non-finite coordinates, invalid settings,
//! clouds beyond a matcher's `f32` range, entropic solves that ended
//! with a non-finite loss, potential or marginal error, and a forced
//! instruction set the CPU lacks.

use thiserror::Error;

/// Why a point cloud or a solve was rejected.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum OtError {
    /// An instruction set was forced ([`crate::force_simd`]) that the running CPU lacks.
    #[error("this CPU does not support the `{simd}` instruction set")]
    SimdUnavailable {
        /// Its name: `avx512`, `avx2` or `portable`.
        simd: &'static str,
    },
    /// A point cloud with no points (n = 0).
    #[error("point cloud is empty (n = 0)")]
    Empty,
    /// The coordinate columns given to a cloud have different lengths.
    #[error("coordinate column `{axis}` has {len} entries, expected {expected}")]
    RaggedColumns {
        /// Name of the offending column (`r`, `g`, `b`, `x` or `y`).
        axis: &'static str,
        /// Its length.
        len: usize,
        /// The length of the first column.
        expected: usize,
    },
    /// A coordinate is NaN or infinite.
    #[error("point {index} has a non-finite `{axis}` coordinate ({value})")]
    NonFinite {
        /// Index of the point in the cloud.
        index: usize,
        /// Name of the coordinate (`r`, `g`, `b`, `x` or `y`).
        axis: &'static str,
        /// The offending value.
        value: f32,
    },
    /// Source and target clouds have different numbers of points.
    #[error("source has {source_len} points but target has {target_len}: equal sizes are required")]
    SizeMismatch {
        /// Number of source points.
        source_len: usize,
        /// Number of target points.
        target_len: usize,
    },
    /// A solver setting is out of its documented range.
    #[error("setting `{key}` = {value} is invalid: {reason}")]
    InvalidSetting {
        /// The setting's key, e.g. `sinkhorn.blur`.
        key: &'static str,
        /// The rejected value.
        value: f64,
        /// The accepted range.
        reason: &'static str,
    },
    /// The clouds are too large for a matcher's `f32` arithmetic: the squared
    /// extent that arithmetic scales with, over its unit, exceeds the
    /// matcher's bound (`sinkhorn::MAX_SPREAD`, `exact::MAX_DIAMETER_SQ`,
    /// `sliced::max_radius_sq`).
    #[error(
        "the clouds' squared extent {extent_sq:e} over {unit_sq:e} exceeds {limit:e}, \
         beyond the f32 range of the {matcher} matcher: rescale the points{}",
        spread_remedy(matcher)
    )]
    SpreadTooLarge {
        /// The matcher: `exact`, `sinkhorn` or `sliced`.
        matcher: &'static str,
        /// What the matcher's arithmetic scales with: the squared diameter of
        /// the two clouds together (exact; sinkhorn for its gradient), of the
        /// two clouds each centred (sinkhorn's kernel), or the squared norm
        /// bound of their points (sliced, which projects absolute coordinates).
        extent_sq: f64,
        /// The squared length the extent is measured in: `min(ε, 1)` with
        /// ε = blur² for sinkhorn, 1 for the others.
        unit_sq: f64,
        /// The largest accepted `extent_sq / unit_sq`.
        limit: f64,
    },
    /// A solve ended with a NaN or infinite value: the guard at the entropic
    /// solver's exit, so no non-finite loss, potential or gradient is returned.
    #[error("the entropic solve ended with a non-finite {quantity}{}", at_point(*index))]
    NonFiniteResult {
        /// What was not finite: `loss`, `potential f`, `potential g`,
        /// `barycentre` or `gradient`.
        quantity: &'static str,
        /// The point it belongs to (source order for `f`, barycentres and the
        /// gradient, target order for `g`); `None` for the loss.
        index: Option<usize>,
    },
    /// An entropic solve ended with a non-finite L1 marginal error: its plan is
    /// not a transport plan at all (not a slow convergence, which is counted in
    /// `SolveStats::unconverged_solves` instead).
    ///
    /// Seen where `diameter² / ε` is so large that the `f32` kernel cannot
    /// resolve ε: a score `(g_j − c_ij)/ε` is rounded by up to about
    /// `2⁻²⁴ diameter² / ε` (`rounding`), and at thousands of ε the marginal
    /// error overflows. The problem is scale-covariant (points ×s, blur ×s: the
    /// same plan), so only a larger blur relative to the spread helps.
    #[error(
        "the entropic solve did not converge: L1 marginal error {marginal_error} after \
         {iterations} updates (tolerance {tolerance:e}); the clouds' squared diameter is \
         {ratio:e} times ε = blur², so the f32 kernel rounds a score by up to {rounding:.1e} ε: \
         raise `sinkhorn.blur` relative to the clouds' spread",
        ratio = rounding * F32_RESOLUTION
    )]
    NotConverged {
        /// The L1 marginal error reached (NaN or infinite).
        marginal_error: f64,
        /// The `sinkhorn.marginal_tolerance` it should have met.
        tolerance: f64,
        /// Sinkhorn updates done.
        iterations: usize,
        /// `2⁻²⁴ diameter² / ε`: the `f32` rounding of the largest kernel scores, in units of ε.
        rounding: f64,
    },
    /// A match expected to take more time or memory than the limits allow
    /// (`crate::estimate`): refused before it runs.
    #[error(
        "matching {n} points per cloud with the {matcher} solver is estimated at {seconds:.0} s and \
         {mb:.0} MB per solve, beyond the limits of {max_seconds:.0} s and {max_mb:.0} MB: \
         use fewer points (a lower match resolution)",
        mb = bytes / 1e6,
        max_mb = max_bytes / 1e6
    )]
    MatchTooLarge {
        /// The matcher: `exact`, `sinkhorn` or `sliced`.
        matcher: &'static str,
        /// Points per cloud.
        n: usize,
        /// Estimated seconds per solve.
        seconds: f64,
        /// Estimated bytes per solve.
        bytes: f64,
        /// The limit on seconds.
        max_seconds: f64,
        /// The limit on bytes.
        max_bytes: f64,
    },
    /// A source point's row of the entropic plan has no mass (no target
    /// streamed, or no finite kernel score), so its barycentre is undefined.
    #[error("a source point's row of the entropic plan has no finite mass at ε = {eps:e}")]
    EmptyKernelRow {
        /// The ε of the plan.
        eps: f64,
    },
}

/// `2²⁴`: the resolution of an `f32` significand, which turns `diameter² / ε`
/// into [`OtError::NotConverged`]'s `rounding` and back.
pub(crate) const F32_RESOLUTION: f64 = 16_777_216.0;

/// What else, besides rescaling, brings clouds back within `matcher`'s range.
fn spread_remedy(matcher: &str) -> &'static str {
    match matcher {
        "sinkhorn" => " or raise `sinkhorn.blur` (if below 1)",
        "sliced" => " or move them toward the origin",
        _ => "",
    }
}

/// ` of point {i}`, or nothing for a quantity of the whole solve.
fn at_point(index: Option<usize>) -> String {
    index.map_or_else(String::new, |i| format!(" of point {i}"))
}
