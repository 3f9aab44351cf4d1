//! Typed errors of problem loading and optimization runs.

use std::path::PathBuf;

/// Errors of loading a problem or running an optimization.
#[derive(Debug, thiserror::Error)]
pub enum OptimizeError {
    /// The problem file cannot be loaded (located: file, line, field).
    #[error(transparent)]
    Problem(#[from] crate::problem::ProblemError),
    /// A file of the run (a checkpoint read, an image or table written)
    /// failed in `epsm-scene`'s file layer.
    #[error(transparent)]
    Scene(#[from] epsm_scene::Error),
    /// The renderer refused a scene (an emissive exact sphere, ...).
    #[error(transparent)]
    Render(#[from] epsm_render::Error),
    /// A parameter key does not fit the scene.
    #[error(transparent)]
    Param(#[from] crate::Error),
    /// The matching failed.
    #[error("optimal transport: {0}")]
    Ot(#[from] epsm_ot::OtError),
    /// An image given to a loss holds a NaN or infinite value.
    #[error("loss: the {image} has a non-finite `{channel}` value ({value}) at pixel ({x}, {y})")]
    NonFinitePixel {
        /// Which image: "rendered image" or "target".
        image: &'static str,
        /// Column, from the left.
        x: u32,
        /// Row, from the top.
        y: u32,
        /// The channel: `r`, `g` or `b`.
        channel: &'static str,
        /// The value.
        value: f32,
    },
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
