//! Typed errors.

/// Errors of this crate.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A request that does not fit the scene (an emissive exact sphere, an
    /// object index out of range, a sample outside the image, ...).
    #[error("invalid request: {0}")]
    Invalid(String),
}

/// Result with this crate's [`Error`].
pub type Result<T, E = Error> = std::result::Result<T, E>;
