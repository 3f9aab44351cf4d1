//! Typed errors of the parameter table (the only user-facing input here).

/// Errors of this crate.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum Error {
    /// A parameter key names nothing in the scene.
    #[error("parameter `{key}`: {message}")]
    Param {
        /// The offending key.
        key: String,
        /// What was wrong and what is accepted.
        message: String,
    },
    /// The same key was added twice.
    #[error("parameter `{0}` is already in the table")]
    Duplicate(String),
}

/// Result with this crate's [`Error`].
pub type Result<T, E = Error> = std::result::Result<T, E>;
