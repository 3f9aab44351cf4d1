//! Every file of the malformed-problem corpus (`tests/corpus/problems/*.toml`
//! at the workspace root) must be rejected with an error, not a panic, whose
//! message names the file and contains the substring on its first line
//! (`# expect: <substring>`, usually the dotted field path).

use std::path::Path;

use epsm_core::load_problem;
use epsm_testkit::corpus;

#[test]
fn every_malformed_problem_is_rejected_with_a_located_message() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tests/corpus/problems");
    corpus::assert_all_rejected(
        &corpus::files(&dir, &["toml"]),
        25,
        |p| corpus::first_line_expectation(p, "# expect: ", ""),
        load_problem,
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
