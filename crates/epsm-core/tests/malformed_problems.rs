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

#[test]
fn a_problem_error_names_the_file_line_and_field() {
    use epsm_core::problem::{ProblemError, problem_from_str};
    let file = Path::new("problems/bad.toml");
    let scene = "[scene.camera]\norigin = [0, 0, 5]\ntarget = [0, 0, 0]\nresolution = [8, 8]\n\
                 [scene.materials.w]\ntype = \"diffuse\"\n\
                 [[scene.objects]]\nname = \"a\"\nshape = \"cube\"\nmaterial = \"w\"\n";
    let located = |text: &str| match problem_from_str(text, file) {
        Err(ProblemError::Field(e)) => (e.file, e.line, e.field),
        other => panic!("expected a field error, got {other:?}"),
    };
    let params = "[[parameters]]\nkey = \"a.translate.x\"\ninitial = 0.1\ntrue = 0.0\n";
    let text = format!("{params}[loss]\nlambda = -1.0\n{scene}");
    assert_eq!(
        located(&text),
        (file.to_owned(), Some(6), "loss.lambda".to_owned())
    );
    // A field of the embedded scene keeps its `scene.` prefix and its line.
    let text = format!("{params}{scene}scale = 0\n");
    assert_eq!(
        located(&text),
        (
            file.to_owned(),
            Some(15),
            "scene.objects[0].scale".to_owned()
        )
    );
    let missing = epsm_core::load_problem(Path::new("/nonexistent/problem.toml"));
    assert!(matches!(missing, Err(ProblemError::Read(_))), "{missing:?}");
}
