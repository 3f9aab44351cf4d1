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

/// An error and its chain of causes on one line (`error: cause: cause`), as
/// the binaries print it. A cause whose message the line already holds is
/// left out: errors such as `epsm_scene::Error::Io` write their source
/// into their own message and also return it as their source.
pub fn error_chain(e: &dyn std::error::Error) -> String {
    let mut line = e.to_string();
    let mut source = e.source();
    while let Some(cause) = source {
        let message = cause.to_string();
        if !line.contains(&message) {
            line.push_str(": ");
            line.push_str(&message);
        }
        source = cause.source();
    }
    line
}

#[cfg(test)]
mod tests {
    use super::error_chain;

    /// An error with a message and an optional source.
    #[derive(Debug)]
    struct Layer(String, Option<Box<Layer>>);

    impl std::fmt::Display for Layer {
        fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
            f.write_str(&self.0)
        }
    }

    impl std::error::Error for Layer {
        fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
            self.1.as_deref().map(|l| l as _)
        }
    }

    #[test]
    fn causes_are_joined_once_each() {
        let io = Layer("No such file or directory (os error 2)".into(), None);
        let file = Layer(format!("a.toml: {io}"), Some(Box::new(io)));
        let top = Layer("loading the problem".into(), Some(Box::new(file)));
        assert_eq!(
            error_chain(&top),
            "loading the problem: a.toml: No such file or directory (os error 2)"
        );
        let plain = Layer("solo".into(), None);
        assert_eq!(error_chain(&plain), "solo");
    }

    #[test]
    fn a_scene_io_error_names_its_cause_once() {
        let e = epsm_scene::load::load_scene("/nonexistent/scene.toml".as_ref())
            .expect_err("no such file");
        let line = error_chain(&e);
        assert_eq!(
            line.matches("No such file or directory").count(),
            1,
            "{line}"
        );
        assert!(line.starts_with("/nonexistent/scene.toml"), "{line}");
    }
}
