//! Every file of the malformed-problem corpus (`tests/corpus/problems/*.toml`
//! at the workspace root) must be rejected with an error, not a panic, whose
//! message names the file and contains the substring on its first line
//! (`# expect: <substring>`, usually the dotted field path).

use std::path::{Path, PathBuf};

use epsm_core::load_problem;

fn corpus_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tests/corpus/problems")
}

/// Checks one corpus file; `Err` describes how it failed the contract.
fn check(path: &Path) -> Result<(), String> {
    let text = std::fs::read_to_string(path).map_err(|e| format!("unreadable: {e}"))?;
    let expect = text
        .lines()
        .next()
        .and_then(|l| l.strip_prefix("# expect: "))
        .ok_or("first line is not `# expect: <substring>`")?
        .trim()
        .to_owned();
    let name = path
        .file_name()
        .and_then(|n| n.to_str())
        .ok_or("file name is not UTF-8")?
        .to_owned();
    let loaded = std::panic::catch_unwind(|| load_problem(path))
        .map_err(|_| "the loader panicked".to_owned())?;
    let message = match loaded {
        Ok(_) => return Err("loaded without error".into()),
        Err(e) => e.to_string(),
    };
    if !message.contains(&name) {
        return Err(format!("message does not name the file: {message}"));
    }
    if !message.contains(&expect) {
        return Err(format!("message does not contain `{expect}`: {message}"));
    }
    Ok(())
}

#[test]
fn every_malformed_problem_is_rejected_with_a_located_message() {
    let mut files: Vec<PathBuf> = std::fs::read_dir(corpus_dir())
        .expect("corpus directory exists")
        .map(|e| e.expect("directory entry").path())
        .filter(|p| p.extension().is_some_and(|e| e == "toml"))
        .collect();
    files.sort();
    assert!(files.len() >= 25, "only {} corpus files", files.len());
    let failures: Vec<String> = files
        .iter()
        .filter_map(|p| check(p).err().map(|e| format!("{}: {e}", p.display())))
        .collect();
    assert!(
        failures.is_empty(),
        "{} failures:\n{}",
        failures.len(),
        failures.join("\n")
    );
}

#[test]
fn every_shipped_problem_loads() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/problems");
    for entry in std::fs::read_dir(dir).expect("problems folder") {
        let path = entry.expect("entry").path();
        if path.extension().is_some_and(|e| e == "toml") {
            load_problem(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        }
    }
}
