//! Loading scene files: TOML (here), glTF and Mitsuba XML (through
//! [`import`](super::import), see [`load_file`]). The TOML format is
//! [`desc`](super::desc), documented in `docs/scene-format.md`: parse the TOML, deserialize it with unknown keys
//! rejected, check every value against its documented range and build the
//! [`SceneParts`]. Every error is a [`FieldError`] naming the file, the dotted
//! field (`objects[2].material`) and what was expected, with the line when the
//! file has one. Relative paths (meshes, textures, environment maps) resolve
//! against the scene file's directory; each mesh or image file is read once
//! per scene and shared.
//!
//! ```toml
//! [camera]
//! origin = [0.0, 1.0, 3.8]
//! target = [0.0, 1.0, 0.0]
//! resolution = [128, 128]
//!
//! [materials.white]
//! type = "diffuse"
//!
//! [[objects]]
//! name = "floor"
//! shape = "rectangle"
//! material = "white"
//! rotate = [{ axis = [1, 0, 0], angle = -90 }]
//! ```

pub(crate) mod build;
pub(crate) mod named;
pub(crate) mod object;

use std::path::Path;

pub use build::MAX_DEPTH;

use crate::desc::SceneDesc;
use crate::error::{FieldError, Result};
use crate::fields::{self, Fields, Locator};
use crate::import::{gltf_scene, mitsuba};
use epsm_render::scene::{Scene, SceneParts};

/// Loads the scene file at `path` (any format [`load_file`] reads) and builds
/// its BVH and light tables.
pub fn load_scene(path: &Path) -> Result<Scene> {
    Ok(Scene::new(load_parts(path)?)?)
}

/// Loads the scene file at `path` into checked parts (see [`load_file`]),
/// printing its warnings, if any, to standard error.
pub fn load_parts(path: &Path) -> Result<SceneParts> {
    let loaded = load_file(path)?;
    for warning in &loaded.warnings {
        eprintln!("warning: {warning}");
    }
    Ok(loaded.parts)
}

/// A loaded scene with the located warnings of its importer (elements it
/// skipped because skipping them is safe, listed in `docs/interop.md`).
#[derive(Clone, Debug)]
pub struct Loaded {
    /// The checked parts.
    pub parts: SceneParts,
    /// What the importer skipped, located like errors.
    pub warnings: Vec<FieldError>,
}

/// Loads a scene file of any supported format, chosen by the
/// (case-insensitive) extension: `.toml` (this crate's format), `.gltf` /
/// `.glb` (a whole glTF 2.0 scene, [`gltf_scene`]) or `.xml` (Mitsuba 3,
/// [`mitsuba`]). A glTF file named by a TOML object's `mesh` stays a mesh.
pub fn load_file(path: &Path) -> Result<Loaded> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    match ext.as_deref() {
        Some("toml") => {
            let text = crate::input_file::read_to_string(path)?;
            Ok(Loaded {
                parts: parts_from_str(&text, path)?,
                warnings: Vec::new(),
            })
        }
        Some("gltf" | "glb") => gltf_scene::load(path),
        Some("xml") => mitsuba::load(path),
        _ => Err(FieldError::new(
            path,
            "document",
            "unsupported scene format: expected a .toml, .gltf, .glb or .xml file",
        )
        .into()),
    }
}

/// Builds checked parts from the text of a scene file; `file` names it in
/// errors and its directory resolves relative paths.
pub fn parts_from_str(text: &str, file: &Path) -> Result<SceneParts> {
    let (desc, locator) = fields::parse::<SceneDesc>(text, file)?;
    parts_from_desc(&desc, file, &locator, "")
}

/// Checks `desc` and builds its parts. `file` and `locator` locate errors;
/// `prefix` is the dotted path of the scene inside the file (`""` for a scene
/// file, e.g. `"scene"` for a problem file's `[scene]` table).
pub fn parts_from_desc(
    desc: &SceneDesc,
    file: &Path,
    locator: &Locator,
    prefix: &str,
) -> Result<SceneParts> {
    build::parts(desc, &Fields::new(file, locator, prefix))
}
