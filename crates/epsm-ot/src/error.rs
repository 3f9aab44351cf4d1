//! Typed errors for bad input and out-of-range settings.
//!
//! Every public solver entry point validates its input and returns an
//! [`OtError`] instead of panicking: empty clouds, clouds of different sizes,
//! ragged coordinate columns, non-finite coordinates, invalid settings, and
//! clouds the entropic kernel cannot represent.

use thiserror::Error;

/// Why a point cloud or a solve was rejected.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum OtError {
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
    /// The clouds are too spread for the entropic kernel at this blur: its
    /// `f32` scores, up to a small multiple of `diameter_sq / ε`, would
    /// overflow.
    #[error(
        "the clouds' squared diameter {diameter_sq:e} over ε = blur² = {eps:e} exceeds {limit:e}, \
         beyond the entropic kernel's f32 range: rescale the points or raise `sinkhorn.blur`"
    )]
    SpreadTooLarge {
        /// Squared diameter of the two clouds together.
        diameter_sq: f64,
        /// The final ε, `blur²`.
        eps: f64,
        /// The largest accepted `diameter_sq / ε`.
        limit: f64,
    },
    /// A source point's row of the entropic plan has no mass (no target
    /// streamed, or no finite kernel score), so its barycentre is undefined.
    #[error("a source point's row of the entropic plan has no finite mass at ε = {eps:e}")]
    EmptyKernelRow {
        /// The ε of the plan.
        eps: f64,
    },
}
