//! Files a scene names (meshes, textures, environment maps), read through
//! the path as written, resolved against the scene file's directory. That
//! path's extension gives the format and its directory is where the file's
//! own relative references resolve (a glTF file's buffers), so a correctly
//! named symlink to a file without an extension (as data stores such as DVC,
//! Nix or git-annex make) reads like the file itself, and a symlink to a
//! device or a FIFO reaches [`input_file::open`](crate::input_file::open),
//! which refuses it as not a regular file. Symlinks are resolved only to
//! tell when two names read the same file the same way, so that it loads
//! once per scene.

use std::ffi::OsString;
use std::hash::{Hash, Hasher};
use std::path::{Path, PathBuf};

use crate::error::Result;
use crate::fields::Fields;

/// A file named by a field of a scene. Two are equal when they read the
/// same file (symlinks resolved) as the same format with references
/// resolving in the same directory, so that they load to the same thing.
#[derive(Clone, Debug)]
pub(crate) struct NamedFile {
    /// The path as written, joined to the scene file's directory: the one
    /// read.
    pub path: PathBuf,
    /// What equality compares: the file and the directory of `path`, their
    /// symlinks resolved, and `path`'s extension in lower case.
    key: (PathBuf, PathBuf, Option<OsString>),
}

impl NamedFile {
    /// The file at `path` (resolved from field `field`); an error at `field`
    /// when it or its directory does not exist.
    pub fn new(path: PathBuf, field: &str, ctx: &Fields) -> Result<Self> {
        let cannot_open =
            |e: std::io::Error| ctx.err(field, format!("cannot open {}: {e}", path.display()));
        let target = path.canonicalize().map_err(cannot_open)?;
        let dir = match path.parent() {
            Some(dir) if !dir.as_os_str().is_empty() => dir,
            _ => Path::new("."),
        };
        let dir = dir.canonicalize().map_err(cannot_open)?;
        let format = path.extension().map(|e| e.to_ascii_lowercase());
        Ok(Self {
            key: (target, dir, format),
            path,
        })
    }
}

impl PartialEq for NamedFile {
    fn eq(&self, other: &Self) -> bool {
        self.key == other.key
    }
}

impl Eq for NamedFile {}

impl Hash for NamedFile {
    fn hash<H: Hasher>(&self, state: &mut H) {
        self.key.hash(state);
    }
}
