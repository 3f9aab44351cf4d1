//! Errors of problem files.

use epsm_scene::FieldError;

/// A problem file that cannot be loaded. Each error names the problem file;
/// a malformed value also names its line and dotted field
/// (`parameters[1].initial`, `loss.blur`, `scene.objects[0].material` for an
/// embedded `[scene]` table).
#[derive(Debug, thiserror::Error)]
pub enum ProblemError {
    /// A field is malformed or out of range, or the file it names (the
    /// scene file, the target image) cannot be used: what was expected.
    #[error(transparent)]
    Field(#[from] FieldError),
    /// The problem file itself cannot be read (missing, unreadable, not a
    /// regular file).
    #[error(transparent)]
    Read(epsm_scene::Error),
}
