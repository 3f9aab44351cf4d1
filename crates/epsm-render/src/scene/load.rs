//! Loading scene files (the format is [`desc`](super::desc), documented in
//! `docs/scene-format.md`): parse the TOML, deserialize it with unknown keys
//! rejected, check every value against its documented range and build the
//! [`SceneParts`]. Every error is a [`SceneError`](crate::error::SceneError) naming the file, the dotted
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

mod build;
mod check;
mod locate;
mod object;

use std::path::Path;

use serde::de::DeserializeOwned;

pub use locate::Locator;

use crate::error::{Error, Result};
use crate::scene::desc::SceneDesc;
use crate::scene::{Scene, SceneParts};

/// Loads the scene file at `path` and builds its BVH and light tables.
pub fn load_scene(path: &Path) -> Result<Scene> {
    Scene::new(load_parts(path)?)
}

/// Loads the scene file at `path` into checked parts.
pub fn load_parts(path: &Path) -> Result<SceneParts> {
    let text = std::fs::read_to_string(path).map_err(|source| Error::Io {
        path: path.to_owned(),
        source,
    })?;
    parts_from_str(&text, path)
}

/// Builds checked parts from the text of a scene file; `file` names it in
/// errors and its directory resolves relative paths.
pub fn parts_from_str(text: &str, file: &Path) -> Result<SceneParts> {
    let (desc, locator) = parse_toml::<SceneDesc>(text, file)?;
    parts_from_desc(&desc, file, &locator, "")
}

/// Parses `text` as TOML into `T` (any serde type, such as a problem file
/// that embeds a [`SceneDesc`]), returning it with a [`Locator`] for later
/// semantic errors. Syntax and type errors are located [`SceneError`](crate::error::SceneError)s.
pub fn parse_toml<T: DeserializeOwned>(text: &str, file: &Path) -> Result<(T, Locator)> {
    let root = toml::de::DeTable::parse(text)
        .map_err(|e| Error::from(locate::syntax_error(file, text, &e)))?;
    let locator = Locator::new(text, &root);
    let value = T::deserialize(toml::de::Deserializer::from(root))
        .map_err(|e| Error::from(locator.serde_error(file, &e)))?;
    Ok((value, locator))
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
    let ctx = check::Ctx {
        file,
        base: file.parent().unwrap_or(Path::new("")).to_owned(),
        locator,
        prefix,
    };
    build::parts(desc, &ctx)
}
