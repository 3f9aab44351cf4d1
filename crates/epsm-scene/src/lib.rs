//! # epsm-scene
//!
//! Scene files for epsm: everything that reads or writes a file format, so
//! that `epsm-render` holds none.
//!
//! - [`desc`]: the TOML scene format (`docs/scene-format.md`) as serde
//!   structures, unknown keys rejected;
//! - [`load`]: checks a description value by value and builds
//!   [`SceneParts`](epsm_render::scene::SceneParts) and the render-ready
//!   [`Scene`](epsm_render::Scene) ([`load_scene`]); located errors;
//! - [`import`]: foreign files: OBJ, PLY and glTF meshes, whole glTF and
//!   Mitsuba 3 XML scenes (`docs/interop.md`);
//! - [`shapes`]: the built-in shapes (`rectangle`, `cube`, `sphere`, `disk`);
//! - [`image_io`]: EXR and PNG reading and writing of linear-RGB
//!   [`Image`](epsm_render::Image)s;
//! - [`input_file`], [`atomic_file`]: the one guard in front of every input
//!   file and the one writer of every output file of epsm;
//! - [`fields`]: located TOML documents: parsing into serde types and value
//!   checks by dotted field, for scene files and the files that embed one;
//! - [`error`]: [`FieldError`] (file, line, dotted field) and [`Error`].
//!
//! ## Conventions
//! The scene model's conventions (units, angles, colour, frames) are
//! `epsm-render`'s. Files add: angles in degrees, paths relative to the
//! file that names them, PNG sRGB-encoded and EXR linear.
//!
//! ```no_run
//! let scene = epsm_scene::load_scene("scenes/cornell-box.toml".as_ref())?;
//! assert!(scene.objects().len() > 1);
//! # Ok::<(), epsm_scene::Error>(())
//! ```

pub mod atomic_file;
pub mod desc;
pub mod error;
pub mod fields;
pub mod image_io;
pub mod import;
pub mod input_file;
pub mod load;
pub mod shapes;

/// The renderer whose types this crate builds (re-exported so that a user
/// names them at the same version).
pub use epsm_render;
pub use error::{Error, FieldError, Result};
pub use load::{Loaded, load_file, load_parts, load_scene, parts_from_str};
