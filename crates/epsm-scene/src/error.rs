//! Typed, located errors of scene, mesh and image files.

use std::path::{Path, PathBuf};

/// An error in a scene file (or a file it references), naming the file, the
/// field and what was expected. `field` is a dotted path such as `objects[2].material` or
/// `camera.fov`; `line` is 1-based when the parser knows it.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{}{}: {field}: {message}", file.display(), line.map(|l| format!(":{l}")).unwrap_or_default())]
pub struct FieldError {
    /// The file the error is in.
    pub file: PathBuf,
    /// 1-based line, when known.
    pub line: Option<usize>,
    /// Dotted path of the offending field.
    pub field: String,
    /// What was wrong and what was expected.
    pub message: String,
}

impl FieldError {
    /// A new error for `field` of `file`.
    pub fn new(
        file: impl Into<PathBuf>,
        field: impl Into<String>,
        message: impl Into<String>,
    ) -> Self {
        Self {
            file: file.into(),
            line: None,
            field: field.into(),
            message: message.into(),
        }
    }

    /// The same error at a 1-based line.
    pub fn at_line(mut self, line: usize) -> Self {
        self.line = Some(line);
        self
    }
}

/// A number as file errors print it ("found …"): as written for magnitudes
/// in `[1e-4, 1e16)` and zero, in scientific notation otherwise, so that
/// `1e300` does not print as 301 digits nor `1e-300` as a row of zeros.
pub fn shown(v: f64) -> String {
    if v == 0.0 || !v.is_finite() || (1e-4..1e16).contains(&v.abs()) {
        v.to_string()
    } else {
        format!("{v:e}")
    }
}

/// Errors of this crate.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A scene file (or a file it references) is malformed.
    #[error(transparent)]
    Field(#[from] FieldError),
    /// Reading or writing a file failed.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The underlying error.
        source: std::io::Error,
    },
    /// An input path that is not a regular file after following symlinks
    /// (a directory, a device such as `/dev/zero`, a FIFO, a socket):
    /// [`crate::input_file`] refuses to read it.
    #[error("{}: not a regular file", path.display())]
    NotAFile {
        /// The path.
        path: PathBuf,
    },
    /// An image could not be decoded or encoded.
    #[error("{}: {message}", path.display())]
    Image {
        /// The file.
        path: PathBuf,
        /// What went wrong.
        message: String,
    },
    /// The checked parts do not make a scene (see
    /// [`Scene::new`](epsm_render::Scene::new)).
    #[error(transparent)]
    Render(#[from] epsm_render::Error),
}

/// The [`Error::Io`] of an I/O failure on `path`.
pub(crate) fn io_error(path: &Path) -> impl Fn(std::io::Error) -> Error + '_ {
    |source| Error::Io {
        path: path.to_owned(),
        source,
    }
}

/// Result with this crate's [`Error`].
pub type Result<T, E = Error> = std::result::Result<T, E>;

#[cfg(test)]
mod tests {
    use super::shown;

    #[test]
    fn numbers_print_as_written_unless_very_large_or_small() {
        for (v, text) in [
            (0.0, "0"),
            (-1.5, "-1.5"),
            (5.0, "5"),
            (1e-4, "0.0001"),
            (1e15, "1000000000000000"),
            (1e16, "1e16"),
            (1e300, "1e300"),
            (-1e-300, "-1e-300"),
            (3e-5, "3e-5"),
            (f64::NAN, "NaN"),
            (f64::NEG_INFINITY, "-inf"),
        ] {
            assert_eq!(shown(v), text);
        }
    }
}
