//! Mitsuba 3 XML scenes (in progress).
use std::path::Path;

use crate::error::{Result, SceneError};
use crate::scene::load::Loaded;

/// Loads the Mitsuba XML scene at `path`.
pub fn load(path: &Path) -> Result<Loaded> {
    Err(SceneError::new(path, "scene", "not yet").into())
}
