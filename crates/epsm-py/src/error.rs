//! `epsm.EpsmError`: every failure of the library, with the message the
//! CLI prints (`error_chain`) and, when the error is located in a file,
//! its `file`, `line` and dotted `field` (`None` otherwise).

use epsm_core::OptimizeError;
use epsm_core::problem::ProblemError;
use epsm_scene::FieldError;
use pyo3::exceptions::PyException;
use pyo3::prelude::*;

pyo3::create_exception!(
    epsm,
    EpsmError,
    PyException,
    "An epsm error. `str(e)` is the message the CLI prints; `e.file`, \
     `e.line` and `e.field` locate it in a scene or problem file (or are \
     None), `e.message` says what was wrong."
);

/// An error of the core crates that may be located in a file.
pub trait Located: std::error::Error {
    /// The file, line and field, when known.
    fn location(&self) -> Option<&FieldError>;
    /// The dotted field, when known without a file.
    fn field(&self) -> Option<&str> {
        self.location().map(|s| s.field.as_str())
    }
}

impl Located for epsm_scene::Error {
    fn location(&self) -> Option<&FieldError> {
        match self {
            epsm_scene::Error::Field(s) => Some(s),
            _ => None,
        }
    }
}

impl Located for epsm_render::Error {
    fn location(&self) -> Option<&FieldError> {
        None
    }
}

impl Located for ProblemError {
    fn location(&self) -> Option<&FieldError> {
        match self {
            ProblemError::Field(s) => Some(s),
            ProblemError::Read(e) => e.location(),
        }
    }
}

impl Located for epsm_core::Error {
    fn location(&self) -> Option<&FieldError> {
        None
    }

    fn field(&self) -> Option<&str> {
        match self {
            epsm_core::Error::Param { key, .. } | epsm_core::Error::Duplicate(key) => Some(key),
        }
    }
}

impl Located for OptimizeError {
    fn location(&self) -> Option<&FieldError> {
        match self {
            OptimizeError::Problem(e) => e.location(),
            OptimizeError::Scene(e) => e.location(),
            _ => None,
        }
    }

    fn field(&self) -> Option<&str> {
        match self {
            OptimizeError::Problem(e) => e.field(),
            OptimizeError::Scene(e) => e.field(),
            OptimizeError::Param(e) => e.field(),
            _ => None,
        }
    }
}

/// `e` as an [`EpsmError`] with its location attached.
pub fn to_py<E: Located>(e: E) -> PyErr {
    let at = e.location();
    let text = epsm_core::error_chain(&e);
    raise(Fields {
        message: at.map_or_else(|| text.clone(), |s| s.message.clone()),
        text,
        file: at.map(|s| s.file.display().to_string()),
        line: at.and_then(|s| s.line),
        field: e.field().map(str::to_owned),
    })
}

/// An [`EpsmError`] for a bad argument `field` of a call.
pub fn invalid(field: &str, message: impl Into<String>) -> PyErr {
    let message = message.into();
    raise(Fields {
        text: format!("{field}: {message}"),
        message,
        file: None,
        line: None,
        field: Some(field.to_owned()),
    })
}

/// What an [`EpsmError`] carries.
struct Fields {
    text: String,
    message: String,
    file: Option<String>,
    line: Option<usize>,
    field: Option<String>,
}

fn raise(f: Fields) -> PyErr {
    Python::attach(|py| {
        let err = EpsmError::new_err(f.text);
        let value = err.value(py);
        let set = [
            value.setattr("file", f.file),
            value.setattr("line", f.line),
            value.setattr("field", f.field),
            value.setattr("message", f.message),
        ];
        set.into_iter().find_map(Result::err).unwrap_or(err)
    })
}
