//! Special files where a loader expects an input file: a symlink to
//! `/dev/zero` (reading it never ends) and a FIFO (opening it for reading
//! waits for a writer), and a check that a loader refuses them in time.

use std::fmt::Display;
use std::path::{Path, PathBuf};
use std::sync::mpsc;
use std::time::Duration;

/// How long a loader may take to refuse a special file.
pub const LIMIT: Duration = Duration::from_secs(10);

/// A special file.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Special {
    /// A symlink to `/dev/zero`.
    DevZero,
    /// A FIFO (made by `mkfifo`).
    Fifo,
}

/// Makes `path` a special file of `kind`. `false` when `mkfifo` is not
/// available (the caller skips its FIFO case).
///
/// # Panics
/// When the symlink cannot be made (a test set-up error).
#[cfg(unix)]
pub fn make(kind: Special, path: &Path) -> bool {
    match kind {
        Special::DevZero => {
            std::os::unix::fs::symlink("/dev/zero", path)
                .unwrap_or_else(|e| panic!("symlink {} -> /dev/zero: {e}", path.display()));
            true
        }
        Special::Fifo => std::process::Command::new("mkfifo")
            .arg(path)
            .status()
            .is_ok_and(|s| s.success()),
    }
}

/// Runs `load` on a thread of its own and returns its error message.
///
/// # Panics
/// When `load` succeeds, panics, or has not returned within [`LIMIT`] (its
/// thread is then left blocked or reading).
pub fn refused<T, E: Display>(load: impl FnOnce() -> Result<T, E> + Send + 'static) -> String {
    let (tx, rx) = mpsc::channel();
    std::thread::spawn(move || {
        let outcome = load().err().map(|e| e.to_string());
        // The receiver is gone only when the limit has passed.
        let _ = tx.send(outcome);
    });
    match rx.recv_timeout(LIMIT) {
        Ok(Some(message)) => message,
        Ok(None) => panic!("loaded a special file without error"),
        Err(mpsc::RecvTimeoutError::Timeout) => {
            panic!("no answer within {LIMIT:?}: the loader blocked or kept reading")
        }
        Err(mpsc::RecvTimeoutError::Disconnected) => panic!("the loader panicked"),
    }
}

/// Calls `check(kind, dir, path)` for each kind of special file, with
/// `path = dir/name` made that kind in a fresh temporary folder `dir`;
/// a kind that cannot be made (no `mkfifo`) is skipped with a note.
#[cfg(unix)]
pub fn each(name: &str, mut check: impl FnMut(Special, &Path, PathBuf)) {
    for kind in [Special::DevZero, Special::Fifo] {
        let dir = tempfile::tempdir().expect("temp dir");
        let path = dir.path().join(name);
        if make(kind, &path) {
            check(kind, dir.path(), path);
        } else {
            eprintln!("mkfifo unavailable: the FIFO case of {name} is skipped");
        }
    }
}
