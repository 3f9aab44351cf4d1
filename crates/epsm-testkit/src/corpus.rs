//! The malformed-input corpus runner: every file of a corpus must be
//! rejected by its loader with an error (not a panic) whose message names
//! the file and contains the expected substring (usually the dotted field
//! path) the corpus records for it.

use std::fmt::Display;
use std::panic::{RefUnwindSafe, catch_unwind};
use std::path::{Path, PathBuf};

/// The files of `dir` whose extension is one of `extensions`, sorted.
///
/// # Panics
/// When the folder cannot be read (a test set-up error).
pub fn files(dir: &Path, extensions: &[&str]) -> Vec<PathBuf> {
    let mut out: Vec<PathBuf> = std::fs::read_dir(dir)
        .unwrap_or_else(|e| panic!("corpus folder {}: {e}", dir.display()))
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| {
            p.extension()
                .and_then(|e| e.to_str())
                .is_some_and(|e| extensions.contains(&e))
        })
        .collect();
    out.sort();
    out
}

/// The expectation written on a text file's first line after `prefix`
/// (and before `suffix`, e.g. `" -->"` for XML comments), trimmed.
pub fn first_line_expectation(path: &Path, prefix: &str, suffix: &str) -> Result<String, String> {
    let text = std::fs::read_to_string(path).map_err(|e| format!("unreadable: {e}"))?;
    text.lines()
        .next()
        .and_then(|l| l.strip_prefix(prefix))
        .and_then(|l| l.strip_suffix(suffix))
        .map(|e| e.trim().to_owned())
        .ok_or_else(|| format!("first line is not `{prefix}<substring>{suffix}`"))
}

/// Checks one corpus file: `load` must return an error, not panic, and its
/// message must name the file and contain `expect`. `Err` says how the file
/// failed that contract.
pub fn check_rejected<T, E: Display>(
    path: &Path,
    expect: &str,
    load: impl Fn(&Path) -> Result<T, E> + RefUnwindSafe,
) -> Result<(), String> {
    let name = path
        .file_name()
        .and_then(|n| n.to_str())
        .ok_or("file name is not UTF-8")?;
    let message = match catch_unwind(|| load(path).map(|_| ())) {
        Err(_) => return Err("the loader panicked".into()),
        Ok(Ok(())) => return Err("loaded without error".into()),
        Ok(Err(e)) => e.to_string(),
    };
    if !message.contains(name) {
        return Err(format!("message does not name the file: {message}"));
    }
    if !message.contains(expect) {
        return Err(format!("message does not contain `{expect}`: {message}"));
    }
    Ok(())
}

/// Runs [`check_rejected`] over `files` (at least `min_files` of them, so a
/// moved corpus cannot pass vacuously) with each file's expectation from
/// `expectation`, and panics listing every failure.
pub fn assert_all_rejected<T, E: Display>(
    files: &[PathBuf],
    min_files: usize,
    expectation: impl Fn(&Path) -> Result<String, String>,
    load: impl Fn(&Path) -> Result<T, E> + RefUnwindSafe + Copy,
) {
    assert!(
        files.len() >= min_files,
        "only {} corpus files (expected at least {min_files})",
        files.len()
    );
    let failures: Vec<String> = files
        .iter()
        .filter_map(|p| {
            expectation(p)
                .and_then(|expect| check_rejected(p, &expect, load))
                .err()
                .map(|e| format!("{}: {e}", p.display()))
        })
        .collect();
    assert!(
        failures.is_empty(),
        "{} of {} corpus files failed:\n{}",
        failures.len(),
        files.len(),
        failures.join("\n")
    );
}

#[cfg(test)]
mod tests {
    use super::*;

    fn loader(path: &Path) -> Result<(), String> {
        let name = path.file_name().and_then(|n| n.to_str()).unwrap_or("");
        match name {
            "ok.txt" => Ok(()),
            "panics.txt" => panic!("boom"),
            "unnamed.txt" => Err("field `x`: bad".into()),
            _ => Err(format!("{name}: field `x`: bad")),
        }
    }

    #[test]
    fn check_rejected_enforces_every_part_of_the_contract() {
        let err = |name: &str, expect: &str| {
            check_rejected(&PathBuf::from(name), expect, loader)
                .expect_err("the contract is broken")
        };
        assert!(check_rejected(&PathBuf::from("good.txt"), "field `x`", loader).is_ok());
        assert!(err("ok.txt", "x").contains("without error"));
        assert!(err("panics.txt", "x").contains("panicked"));
        assert!(err("unnamed.txt", "x").contains("name the file"));
        assert!(err("good.txt", "field `y`").contains("does not contain"));
    }
}
