//! Typed errors of problem loading and optimization runs.

use std::path::PathBuf;

/// Errors of loading a problem or running an optimization.
#[derive(Debug, thiserror::Error)]
pub enum OptimizeError {
    /// The scene, a problem field, an image or a file write failed in the
    /// renderer's loaders (located: file, line, field).
    #[error(transparent)]
    Render(#[from] epsm_render::Error),
    /// A parameter key does not fit the scene.
    #[error(transparent)]
    Param(#[from] crate::Error),
    /// The matching failed, or an image given to a loss (L2 too) holds a
    /// NaN or infinite pixel ([`epsm_ot::OtError::NonFinite`]).
    #[error("optimal transport: {0}")]
    Ot(#[from] epsm_ot::OtError),
    /// Reading or writing a run file failed.
    #[error("{}: {message}", path.display())]
    File {
        /// The file.
        path: PathBuf,
        /// What went wrong.
        message: String,
    },
    /// A request that does not fit the problem.
    #[error("{0}")]
    Invalid(String),
    /// The summed gradient of a parameter was NaN or infinite. Path guards
    /// drop and count such paths, so this is a bug; the step is refused
    /// rather than taken with the entry zeroed.
    #[error("the gradient of parameter `{0}` is not finite")]
    NonFiniteGradient(String),
}

/// Result with [`OptimizeError`].
pub type OptResult<T> = std::result::Result<T, OptimizeError>;
