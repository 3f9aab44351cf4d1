//! Atomic file writes: the one writer behind every file epsm produces
//! (images, CSV, checkpoints, plots, screenshots).
//!
//! The bytes go to a temporary file in the target's folder (`.epsm-*.tmp`,
//! a unique name, so concurrent writers of one path do not collide), which
//! is flushed, synced and renamed over the target: a reader never sees a
//! half-written file, and a failed write removes the temporary file and
//! leaves the target as it was. The file is created with mode `0o666`
//! restricted by the process's umask (on Unix), as `std::fs::write` would
//! create it, not with the temporary file's private `0o600`.

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::Path;

/// Writes the file at `path` atomically (module docs) with `write`, which
/// gets a buffered writer to the temporary file (`Write + Seek`). The folder
/// must exist. `io_error` turns an I/O failure of the temporary file into the
/// caller's error type.
pub fn write_atomic<E>(
    path: &Path,
    io_error: impl Fn(std::io::Error) -> E,
    write: impl FnOnce(&mut BufWriter<&mut File>) -> Result<(), E>,
) -> Result<(), E> {
    let dir = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    let mut builder = tempfile::Builder::new();
    builder.prefix(".epsm-").suffix(".tmp");
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        builder.permissions(std::fs::Permissions::from_mode(0o666));
    }
    let mut tmp = builder.tempfile_in(dir).map_err(&io_error)?;
    {
        let mut out = BufWriter::new(tmp.as_file_mut());
        write(&mut out)?;
        out.flush().map_err(&io_error)?;
    }
    tmp.as_file().sync_all().map_err(&io_error)?;
    tmp.persist(path).map_err(|e| io_error(e.error))?;
    Ok(())
}

/// Creates the folder `path` lies in, with its parents, unless `path` has
/// none (a bare file name) or it exists. For writers that may create their
/// output folder; [`write_atomic`] does not.
pub fn create_parent(path: &Path) -> std::io::Result<()> {
    match path.parent() {
        Some(dir) if !dir.as_os_str().is_empty() => std::fs::create_dir_all(dir),
        _ => Ok(()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn write(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
        write_atomic(path, |e| e, |out| out.write_all(bytes))
    }

    #[test]
    fn a_failed_write_keeps_the_old_file_and_leaves_no_temporary_behind() {
        let dir = tempfile::tempdir().expect("temp dir");
        let path = dir.path().join("out.csv");
        write(&path, b"old").expect("first write");
        let failed = write_atomic(
            &path,
            |e| e,
            |out| {
                out.write_all(b"partial")?;
                Err(std::io::Error::other("encoder failed"))
            },
        );
        assert!(failed.is_err());
        assert_eq!(std::fs::read(&path).expect("read"), b"old");
        assert_eq!(std::fs::read_dir(dir.path()).expect("list").count(), 1);
    }

    /// The written file has the permissions `std::fs::write` gives a new
    /// file under this process's umask (readable by others under the usual
    /// umask 022), not the temporary file's private 0o600.
    #[cfg(unix)]
    #[test]
    fn the_file_gets_the_permissions_of_a_plainly_created_file() {
        use std::os::unix::fs::PermissionsExt;
        let dir = tempfile::tempdir().expect("temp dir");
        let plain = dir.path().join("plain.txt");
        std::fs::write(&plain, b"x").expect("plain write");
        let atomic = dir.path().join("atomic.txt");
        write(&atomic, b"x").expect("atomic write");
        let mode = |p: &Path| std::fs::metadata(p).expect("metadata").permissions().mode() & 0o777;
        assert_eq!(mode(&atomic), mode(&plain));
    }
}
