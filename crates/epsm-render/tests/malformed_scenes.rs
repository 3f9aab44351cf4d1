//! Every file of the malformed-scene corpus (`tests/corpus/scenes/` at the
//! workspace root: `.toml`, `.xml` (Mitsuba), `.gltf` and `.glb` scenes) must
//! be rejected with an error, not a panic, whose message names the file and
//! contains the expected substring, usually the field path:
//!
//! | format | where the expectation is |
//! |---|---|
//! | TOML | first line `# expect: <substring>` |
//! | Mitsuba XML | first line `<!-- expect: <substring> -->` |
//! | glTF, GLB | sidecar file `NAME.expect` holding the substring |
//!
//! Broken meshes and images (OBJ, PLY, glTF meshes, EXR) live in `assets/` and
//! are referenced by scenes of the corpus.

use std::path::{Path, PathBuf};

use epsm_render::scene::load_parts;

fn corpus_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tests/corpus/scenes")
}

/// The expected substring of corpus file `path` (see the module table).
fn expectation(path: &Path) -> Result<String, String> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .unwrap_or_default();
    if matches!(ext, "gltf" | "glb") {
        let sidecar = path.with_extension("expect");
        let text = std::fs::read_to_string(&sidecar)
            .map_err(|e| format!("no {}: {e}", sidecar.display()))?;
        return Ok(text.trim().to_owned());
    }
    let text = std::fs::read_to_string(path).map_err(|e| format!("unreadable: {e}"))?;
    let first = text.lines().next().unwrap_or_default();
    let expect = match ext {
        "xml" => first
            .strip_prefix("<!-- expect: ")
            .and_then(|l| l.strip_suffix(" -->")),
        _ => first.strip_prefix("# expect: "),
    };
    expect
        .map(|e| e.trim().to_owned())
        .ok_or_else(|| "first line does not give the expectation".to_owned())
}

/// Checks one corpus file; `Err` describes how it failed the contract.
fn check(path: &Path) -> Result<(), String> {
    let expect = expectation(path)?;
    let name = path
        .file_name()
        .and_then(|n| n.to_str())
        .ok_or("file name is not UTF-8")?
        .to_owned();
    let loaded = std::panic::catch_unwind(|| load_parts(path))
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
fn every_malformed_scene_is_rejected_with_a_located_message() {
    let mut files: Vec<PathBuf> = std::fs::read_dir(corpus_dir())
        .expect("corpus directory exists")
        .map(|e| e.expect("directory entry").path())
        .filter(|p| {
            let ext = p.extension().and_then(|e| e.to_str());
            matches!(ext, Some("toml" | "xml" | "gltf" | "glb"))
        })
        .collect();
    files.sort();
    assert!(files.len() >= 150, "only {} corpus files", files.len());
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
