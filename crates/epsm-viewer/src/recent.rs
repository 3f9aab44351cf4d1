//! The recent-files list: the last few problem files opened, newest first,
//! kept one path per line in a small text file (written atomically) when a
//! location is given, else for the session only. The file is read through
//! [`epsm_scene::input_file`]: anything but a regular file there (a FIFO,
//! a device, a folder) counts as no list, like a missing file.

use std::path::{Path, PathBuf};

/// At most this many files are remembered.
const KEEP: usize = 8;

/// Recent problem files.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Recent {
    /// Newest first.
    pub files: Vec<PathBuf>,
    store: Option<PathBuf>,
}

impl Recent {
    /// The list kept at `store` (missing, unreadable or not a regular
    /// file: empty).
    pub fn load(store: Option<PathBuf>) -> Self {
        let files = store
            .as_deref()
            .and_then(|s| read(s).ok())
            .unwrap_or_default();
        Self { files, store }
    }

    /// The default location: `$XDG_CONFIG_HOME/epsm-viewer/recent` or
    /// `$HOME/.config/epsm-viewer/recent`.
    pub fn default_store() -> Option<PathBuf> {
        let base = std::env::var_os("XDG_CONFIG_HOME")
            .map(PathBuf::from)
            .or_else(|| std::env::var_os("HOME").map(|h| Path::new(&h).join(".config")))?;
        Some(base.join("epsm-viewer").join("recent"))
    }

    /// Puts `path` first and saves the list (a failed save is ignored: the
    /// list is a convenience). The path is kept as given, made absolute
    /// against the working directory but with its symlinks not resolved:
    /// reopened, a problem reached through a symlink finds the files it
    /// names relative to itself where the CLI would, next to the link.
    pub fn add(&mut self, path: &Path) {
        let path = std::path::absolute(path).unwrap_or_else(|_| path.to_owned());
        self.files.retain(|f| *f != path);
        self.files.insert(0, path);
        self.files.truncate(KEEP);
        if let Some(store) = &self.store {
            let text: String = self
                .files
                .iter()
                .map(|f| format!("{}\n", f.display()))
                .collect();
            let _ = epsm_core::report::write_atomic(store, text.as_bytes());
        }
    }
}

/// The paths listed in the regular file `store`, one a line.
fn read(store: &Path) -> Result<Vec<PathBuf>, epsm_scene::Error> {
    let text = epsm_scene::input_file::read_to_string(store)?;
    Ok(text
        .lines()
        .filter(|l| !l.is_empty())
        .map(PathBuf::from)
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn newest_first_without_duplicates_and_kept_across_loads() {
        let dir = tempfile::tempdir().expect("temp dir");
        let store = dir.path().join("sub").join("recent");
        let mut r = Recent::load(Some(store.clone()));
        assert!(r.files.is_empty());
        r.add(Path::new("/nowhere/a.toml"));
        r.add(Path::new("/nowhere/b.toml"));
        r.add(Path::new("/nowhere/a.toml"));
        let names: Vec<_> = r.files.iter().map(|f| f.display().to_string()).collect();
        assert_eq!(names, ["/nowhere/a.toml", "/nowhere/b.toml"]);
        assert_eq!(Recent::load(Some(store)).files, r.files);
    }

    #[test]
    fn a_folder_in_place_of_the_list_is_no_list() {
        let dir = tempfile::tempdir().expect("temp dir");
        let msg = read(dir.path()).expect_err("a folder").to_string();
        assert!(msg.ends_with("not a regular file"), "{msg}");
        assert!(Recent::load(Some(dir.path().to_owned())).files.is_empty());
    }

    /// A FIFO (or a link to `/dev/zero`) at the list's place is refused at
    /// once instead of blocking (or reading forever) the viewer's start.
    #[cfg(unix)]
    #[test]
    fn a_fifo_or_dev_zero_in_place_of_the_list_is_refused_at_once() {
        use epsm_testkit::special::{each, refused};
        each("recent", |kind, _, path| {
            let msg = refused(move || read(&path));
            assert!(
                msg.ends_with("recent: not a regular file"),
                "{kind:?}: {msg}"
            );
        });
    }

    #[cfg(unix)]
    #[test]
    fn a_symlinked_path_is_kept_as_given_not_resolved() {
        let dir = tempfile::tempdir().expect("temp dir");
        let real = dir.path().join("real");
        std::fs::create_dir(&real).expect("mkdir");
        std::fs::write(real.join("problem.toml"), "").expect("write");
        let link = dir.path().join("link.toml");
        std::os::unix::fs::symlink(real.join("problem.toml"), &link).expect("symlink");
        let mut r = Recent::load(None);
        r.add(&link);
        r.add(&dir.path().join(".").join("link.toml"));
        assert_eq!(r.files, std::slice::from_ref(&link));
        // A relative path is made absolute against the working directory.
        r.add(Path::new("relative.toml"));
        let cwd = std::env::current_dir().expect("working directory");
        assert_eq!(r.files, [cwd.join("relative.toml"), link]);
    }
}
