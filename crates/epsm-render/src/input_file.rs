//! Opening input files: the one guard in front of every file epsm reads
//! (scene, problem and checkpoint files, meshes, glTF and Mitsuba scenes
//! and buffers, textures, environment maps, target images).
//!
//! Only a regular file is opened, after following symlinks. A path naming
//! anything else (a directory, a device such as `/dev/zero`, a FIFO, a
//! socket) is an [`Error::NotAFile`] found from its metadata before it is
//! opened, so that reading it can neither block (opening a FIFO for reading
//! waits for a writer) nor run forever (`/dev/zero` never ends). Size caps,
//! where a format has one, stay with its reader (a glTF buffer's
//! `byteLength`, [`crate::image_io::MAX_IMAGE_PIXELS`]).

use std::fs::File;
use std::io::Read;
use std::path::Path;

use crate::error::{Error, Result, io_error};

/// Opens the regular file at `path` for reading (module docs).
pub fn open(path: &Path) -> Result<File> {
    let not_a_file = || Error::NotAFile {
        path: path.to_owned(),
    };
    if !std::fs::metadata(path).map_err(io_error(path))?.is_file() {
        return Err(not_a_file());
    }
    let file = File::open(path).map_err(io_error(path))?;
    // The path may have been replaced between the two looks.
    if !file.metadata().map_err(io_error(path))?.is_file() {
        return Err(not_a_file());
    }
    Ok(file)
}

/// The bytes of the regular file at `path`.
pub fn read(path: &Path) -> Result<Vec<u8>> {
    let mut bytes = Vec::new();
    open(path)?
        .read_to_end(&mut bytes)
        .map_err(io_error(path))?;
    Ok(bytes)
}

/// The text of the regular file at `path` (UTF-8).
pub fn read_to_string(path: &Path) -> Result<String> {
    let mut text = String::new();
    open(path)?
        .read_to_string(&mut text)
        .map_err(io_error(path))?;
    Ok(text)
}
