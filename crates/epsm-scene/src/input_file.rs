//! Opening input files: the one guard in front of every file epsm reads
//! (scene, problem and checkpoint files, meshes, glTF and Mitsuba scenes
//! and buffers, textures, environment maps, target images).
//!
//! Only a regular file is opened, after following symlinks. A path naming
//! anything else (a directory, a device such as `/dev/zero`, a FIFO, a
//! socket) is an [`Error::NotAFile`], so that reading it can neither block
//! (opening a FIFO for reading waits for a writer) nor run forever
//! (`/dev/zero` never ends). The path's metadata is looked at first, so that
//! normally nothing else is even opened (a socket cannot be); the check that
//! counts is on the opened handle (`fstat`), since the path may have been
//! replaced in between. On Unix the file is opened with `O_NONBLOCK`, so
//! that a FIFO swapped in between cannot block the open either; the flag
//! does not change reads of a regular file. A format that caps how much it
//! reads names its cap: a glTF buffer reads [`read_capped`] to its
//! `byteLength`; an image has [`crate::image_io::MAX_IMAGE_PIXELS`].

use std::fs::File;
use std::io::Read;
use std::path::Path;

use crate::error::{Error, Result, io_error};

/// Opens the regular file at `path` for reading (module docs).
pub fn open(path: &Path) -> Result<File> {
    Ok(open_sized(path)?.0)
}

/// [`open`], and the file's length in bytes from the handle's metadata.
fn open_sized(path: &Path) -> Result<(File, u64)> {
    if !std::fs::metadata(path).map_err(io_error(path))?.is_file() {
        return Err(not_a_file(path));
    }
    open_regular(path)
}

/// Opens `path` without blocking ([`open_nonblocking`]) and keeps the
/// handle only if it is a regular file, by the handle's own metadata; with
/// its length in bytes.
fn open_regular(path: &Path) -> Result<(File, u64)> {
    let file = open_nonblocking(path).map_err(io_error(path))?;
    let metadata = file.metadata().map_err(io_error(path))?;
    if !metadata.is_file() {
        return Err(not_a_file(path));
    }
    Ok((file, metadata.len()))
}

/// Opens `path` for reading with `O_NONBLOCK`: a FIFO opens at once instead
/// of waiting for a writer (open(2): the flag has no effect on regular
/// files).
#[cfg(unix)]
fn open_nonblocking(path: &Path) -> std::io::Result<File> {
    use std::os::unix::fs::OpenOptionsExt;
    std::fs::OpenOptions::new()
        .read(true)
        .custom_flags(libc::O_NONBLOCK)
        .open(path)
}

/// Opens `path` for reading (no FIFOs to block on outside Unix).
#[cfg(not(unix))]
fn open_nonblocking(path: &Path) -> std::io::Result<File> {
    File::open(path)
}

/// The [`Error::NotAFile`] of `path`.
fn not_a_file(path: &Path) -> Error {
    Error::NotAFile {
        path: path.to_owned(),
    }
}

/// The bytes of the regular file at `path`.
pub fn read(path: &Path) -> Result<Vec<u8>> {
    read_capped(path, u64::MAX)
}

/// The first `max` bytes of the regular file at `path` (all of them when it
/// is shorter).
pub fn read_capped(path: &Path, max: u64) -> Result<Vec<u8>> {
    let (file, len) = open_sized(path)?;
    let mut bytes = Vec::new();
    // Room for the whole read up front, as `File::read_to_end` makes it (a
    // size hint: a failed reservation only means growing as it goes).
    let size = len.min(max);
    let _ = bytes.try_reserve(usize::try_from(size).unwrap_or(usize::MAX));
    file.take(max)
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn read_capped_stops_at_the_cap_and_reads_a_shorter_file_whole() {
        let dir = tempfile::tempdir().expect("temp dir");
        let path = dir.path().join("data.bin");
        std::fs::write(&path, b"0123456789").expect("write");
        assert_eq!(read_capped(&path, 4).expect("read"), b"0123");
        assert_eq!(read_capped(&path, 100).expect("read"), b"0123456789");
        assert_eq!(read(&path).expect("read"), b"0123456789");
        let msg = read_capped(dir.path(), 4).expect_err("a directory");
        assert!(msg.to_string().ends_with("not a regular file"), "{msg}");
    }

    /// The check on the opened handle alone (no look at the path first, as
    /// when a FIFO or a link to `/dev/zero` is swapped in after that look)
    /// refuses each special file at once, without blocking on the FIFO.
    #[cfg(unix)]
    #[test]
    fn the_handle_check_alone_refuses_a_fifo_and_dev_zero_at_once() {
        use epsm_testkit::special::{each, refused};
        each("special.bin", |kind, _, path| {
            let msg = refused(move || open_regular(&path));
            assert!(
                msg.ends_with("special.bin: not a regular file"),
                "{kind:?}: {msg}"
            );
        });
    }

    #[cfg(unix)]
    #[test]
    fn the_handle_check_refuses_a_directory_and_reads_a_regular_file_whole() {
        let dir = tempfile::tempdir().expect("temp dir");
        let msg = open_regular(dir.path())
            .map(drop)
            .expect_err("a directory")
            .to_string();
        assert!(msg.ends_with("not a regular file"), "{msg}");
        let path = dir.path().join("data.bin");
        let bytes: Vec<u8> = (0..=255).cycle().take(100_000).collect();
        std::fs::write(&path, &bytes).expect("write");
        let mut read = Vec::new();
        let (mut file, len) = open_regular(&path).expect("a regular file opens");
        assert_eq!(len, 100_000);
        file.read_to_end(&mut read).expect("read");
        assert_eq!(read, bytes);
    }
}
