//! Located TOML documents: the API for any file that is TOML with dotted
//! fields, scene files and the files that embed a scene (problem files).
//!
//! 1. [`parse`] reads the text into any serde type, with unknown keys
//!    rejected by the type, and returns a [`Locator`] (field → line) beside
//!    it; syntax and type errors come back located.
//! 2. [`Fields`] checks values one dotted field at a time (`finite`, `check`,
//!    `within`, `count`, colours, names) and turns a message into a
//!    [`FieldError`] naming the file, the line and the field.
//!
//! ```
//! use std::path::Path;
//! use epsm_scene::fields::{Fields, parse};
//!
//! #[derive(serde::Deserialize)]
//! struct Settings {
//!     iterations: u32,
//! }
//!
//! let file = Path::new("settings.toml");
//! let (settings, locator) = parse::<Settings>("iterations = 0\n", file)?;
//! let fields = Fields::new(file, &locator, "");
//! let err = fields.count("iterations", settings.iterations, 1, 100).unwrap_err();
//! assert_eq!(err.to_string(), "settings.toml:1: iterations: expected an integer in [1, 100], found 0");
//! # Ok::<(), epsm_scene::FieldError>(())
//! ```

mod locate;

use std::collections::HashSet;
use std::path::{Path, PathBuf};

use glam::{DVec3, Vec3};
use serde::de::DeserializeOwned;

use crate::error::{Error, FieldError, shown};
pub use locate::Locator;

/// Parses `text` as TOML into `T` (any serde type, such as a problem file
/// that embeds a [`SceneDesc`](crate::desc::SceneDesc)), returning it with a
/// [`Locator`] for later checks. `file` names the file in errors. Syntax and
/// type errors are located [`FieldError`]s.
pub fn parse<T: DeserializeOwned>(text: &str, file: &Path) -> Result<(T, Locator), FieldError> {
    let root = toml::de::DeTable::parse(text).map_err(|e| locate::syntax_error(file, text, &e))?;
    let locator = Locator::new(text, &root);
    let value = T::deserialize(toml::de::Deserializer::from(root))
        .map_err(|e| locator.serde_error(file, &e))?;
    Ok((value, locator))
}

/// Smallest accepted GGX roughness `alpha` (smoother surfaces are conductors).
pub const MIN_ALPHA: f64 = 1e-4;

/// The checks of one file's fields: the file, its locator, and the dotted
/// prefix of the checked table inside the file (empty for the whole file,
/// `scene` for a problem file's `[scene]` table).
pub struct Fields<'a> {
    /// The file, as given.
    pub file: &'a Path,
    /// Where relative paths resolve: the file's directory.
    pub base: PathBuf,
    /// Lines of fields.
    pub locator: &'a Locator,
    /// Dotted prefix of the scene's fields in the file.
    pub prefix: &'a str,
}

impl<'a> Fields<'a> {
    /// The context of `file` (relative paths resolve against its directory),
    /// with its fields under the dotted `prefix` (`""` for a whole file).
    pub fn new(file: &'a Path, locator: &'a Locator, prefix: &'a str) -> Self {
        Self {
            file,
            base: file.parent().unwrap_or(Path::new("")).to_owned(),
            locator,
            prefix,
        }
    }

    /// The full dotted path of `field`.
    fn path(&self, field: &str) -> String {
        if self.prefix.is_empty() {
            field.to_owned()
        } else {
            format!("{}.{field}", self.prefix)
        }
    }

    /// An error at `field`, with its line when the file has it.
    pub fn err(&self, field: &str, message: impl Into<String>) -> Error {
        self.located(field, message).into()
    }

    /// The located report of `message` at `field` (an error or a warning).
    pub fn located(&self, field: &str, message: impl Into<String>) -> FieldError {
        let path = self.path(field);
        let line = self.locator.line(&path);
        let mut e = FieldError::new(self.file, path, message);
        e.line = line;
        e
    }

    /// A path from the file, resolved against the file's directory.
    pub fn resolve(&self, relative: &str) -> PathBuf {
        self.base.join(relative)
    }

    /// A finite number that stays finite in the renderer's `f32`.
    pub fn finite(&self, field: &str, v: f64) -> Result<f64, FieldError> {
        if !v.is_finite() {
            Err(self.located(
                field,
                format!("expected a finite number, found {}", shown(v)),
            ))
        } else if v.abs() > f64::from(f32::MAX) {
            let msg = format!(
                "expected a magnitude of at most {:e} (single precision), found {}",
                f32::MAX,
                shown(v)
            );
            Err(self.located(field, msg))
        } else {
            Ok(v)
        }
    }

    /// A finite number for which `ok` (the caller's range test of it) holds;
    /// `what` names the range in the message.
    pub fn check(&self, field: &str, v: f64, ok: bool, what: &str) -> Result<f64, FieldError> {
        let v = self.finite(field, v)?;
        if ok {
            Ok(v)
        } else {
            Err(self.located(field, format!("expected {what}, found {}", shown(v))))
        }
    }

    /// A number in `[lo, hi]`; `what` names the range in the message.
    pub fn within(
        &self,
        field: &str,
        v: f64,
        lo: f64,
        hi: f64,
        what: &str,
    ) -> Result<f64, FieldError> {
        self.check(field, v, (lo..=hi).contains(&v), what)
    }

    /// A vector of finite numbers.
    pub fn vec3(&self, field: &str, v: [f64; 3]) -> Result<DVec3, FieldError> {
        for (i, x) in v.into_iter().enumerate() {
            self.finite(&format!("{field}[{i}]"), x)?;
        }
        Ok(DVec3::from_array(v))
    }

    /// A linear RGB colour, each channel in `[0, max]`.
    pub fn color(&self, field: &str, v: [f64; 3], max: f64) -> Result<Vec3, FieldError> {
        let what = if max.is_finite() {
            format!("a value in [0, {max}]")
        } else {
            "a value >= 0".to_owned()
        };
        for (i, x) in v.into_iter().enumerate() {
            self.within(&format!("{field}[{i}]"), x, 0.0, max, &what)?;
        }
        Ok(DVec3::from_array(v).as_vec3())
    }

    /// A GGX roughness `alpha` in `[MIN_ALPHA, 1]`.
    pub fn alpha(&self, field: &str, v: f64) -> Result<f32, FieldError> {
        let what = format!("a value in [{MIN_ALPHA:e}, 1]");
        Ok(self.within(field, v, MIN_ALPHA, 1.0, &what)? as f32)
    }

    /// A (relative) index of refraction, finite and `> 0`.
    pub fn ior(&self, field: &str, v: f64) -> Result<f32, FieldError> {
        Ok(self.check(field, v, v > 0.0, "a value > 0")? as f32)
    }

    /// A count in `[lo, hi]`.
    pub fn count(&self, field: &str, v: u32, lo: u32, hi: u32) -> Result<u32, FieldError> {
        if (lo..=hi).contains(&v) {
            Ok(v)
        } else if hi == u32::MAX {
            Err(self.located(field, format!("expected an integer >= {lo}, found {v}")))
        } else {
            Err(self.located(
                field,
                format!("expected an integer in [{lo}, {hi}], found {v}"),
            ))
        }
    }

    /// Checks that `name` is non-empty and not in `seen`, then adds it
    /// (`what` is "object", "light", ...).
    pub fn unique_name<'n>(
        &self,
        field: &str,
        name: &'n str,
        seen: &mut HashSet<&'n str>,
        what: &str,
    ) -> Result<(), FieldError> {
        if name.trim().is_empty() {
            return Err(self.located(field, format!("{what} name must not be empty")));
        }
        if !seen.insert(name) {
            return Err(self.located(field, format!("duplicate {what} name \"{name}\"")));
        }
        Ok(())
    }

    /// Wraps an error from a referenced file (an image, a mesh) at `field`.
    pub fn nested(&self, field: &str, inner: &Error) -> Error {
        self.err(field, inner.to_string())
    }
}
