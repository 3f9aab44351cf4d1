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

use std::path::Path;

use epsm_scene::load_parts;
use epsm_testkit::corpus;

/// The expected substring of corpus file `path` (see the module table).
fn expectation(path: &Path) -> Result<String, String> {
    match path.extension().and_then(|e| e.to_str()) {
        Some("gltf" | "glb") => {
            let sidecar = path.with_extension("expect");
            let text = std::fs::read_to_string(&sidecar)
                .map_err(|e| format!("no {}: {e}", sidecar.display()))?;
            Ok(text.trim().to_owned())
        }
        Some("xml") => corpus::first_line_expectation(path, "<!-- expect: ", " -->"),
        _ => corpus::first_line_expectation(path, "# expect: ", ""),
    }
}

#[test]
fn every_malformed_scene_is_rejected_with_a_located_message() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tests/corpus/scenes");
    corpus::assert_all_rejected(
        &corpus::files(&dir, &["toml", "xml", "gltf", "glb"]),
        150,
        expectation,
        load_parts,
    );
}
