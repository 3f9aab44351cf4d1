//! Foreign files. Mesh files: Wavefront OBJ ([`obj`]), Stanford PLY
//! ([`ply`]) and glTF 2.0 ([`gltf`], `.gltf` and `.glb`), each flattened into
//! one object-space [`Mesh`], and the validation every mesh passes whatever
//! its source. Whole scenes: glTF 2.0 ([`gltf_scene`]) and Mitsuba 3 XML
//! ([`mitsuba`]), mapped as documented in `docs/interop.md`.
//!
//! | check | error field |
//! |---|---|
//! | at least one triangle | `triangles` |
//! | finite positions | `positions[i]` |
//! | indices in range | `triangles[t]` |
//! | normals / uvs: one per position when present, finite, normals unit | `normals[i]`, `uvs` |
//! | no zero-area triangle (sin of the smallest corner angle ≤ 1e-7, f32 precision) | `triangles[t]` |
//!
//! ```toml
//! [[objects]]
//! name = "bunny"
//! mesh = "meshes/bunny.obj"   # or .ply / .gltf / .glb
//! material = "white"
//! ```

pub mod gltf;
pub mod gltf_scene;
pub mod mitsuba;
pub mod obj;
pub mod ply;

use std::path::Path;

use crate::error::{FieldError, Result};
use epsm_render::scene::Mesh;

/// Loads and validates a mesh file, choosing the importer by extension
/// (`.obj`, `.ply`, `.gltf`, `.glb`, case-insensitive). Errors name `path`.
pub fn load_mesh(path: &Path) -> Result<Mesh> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    let mesh = match ext.as_deref() {
        Some("obj") => obj::load(path)?,
        Some("ply") => ply::load(path)?,
        Some("gltf" | "glb") => gltf::load(path)?,
        _ => {
            return Err(FieldError::new(
                path,
                "mesh",
                "unsupported mesh format: expected a .obj, .ply, .gltf or .glb file",
            )
            .into());
        }
    };
    validate(&mesh, path)?;
    Ok(mesh)
}

/// Checks the invariants every mesh must hold (see the module table);
/// `file` names the mesh in errors.
pub fn validate(mesh: &Mesh, file: &Path) -> Result<()> {
    let err = |field: String, message: String| FieldError::new(file, field, message);
    if mesh.indices.is_empty() {
        return Err(err("triangles".into(), "the mesh has no triangles".into()).into());
    }
    let n = mesh.positions.len();
    if let Some(i) = mesh.positions.iter().position(|p| !p.is_finite()) {
        return Err(err(format!("positions[{i}]"), "non-finite position".into()).into());
    }
    if !mesh.normals.is_empty() {
        if mesh.normals.len() != n {
            let msg = format!("{} normals for {n} positions", mesh.normals.len());
            return Err(err("normals".into(), msg).into());
        }
        if let Some(i) = mesh
            .normals
            .iter()
            .position(|v| !v.is_finite() || (v.length() - 1.0).abs() > 1e-3)
        {
            return Err(err(
                format!("normals[{i}]"),
                "expected a finite unit normal".into(),
            )
            .into());
        }
    }
    if !mesh.uvs.is_empty() && mesh.uvs.len() != n {
        let msg = format!("{} uvs for {n} positions", mesh.uvs.len());
        return Err(err("uvs".into(), msg).into());
    }
    if let Some(i) = mesh.uvs.iter().position(|v| !v.is_finite()) {
        return Err(err(format!("uvs[{i}]"), "non-finite uv".into()).into());
    }
    for (t, tri) in mesh.indices.iter().enumerate() {
        if let Some(&i) = tri.iter().find(|&&i| i as usize >= n) {
            let msg = format!("vertex index {i} out of range (the mesh has {n} vertices)");
            return Err(err(format!("triangles[{t}]"), msg).into());
        }
        let [p0, p1, p2] = mesh.triangle(t as u32).map(|p| p.as_dvec3());
        let (e1, e2, e3) = (p1 - p0, p2 - p0, p2 - p1);
        let longest = e1.length().max(e2.length()).max(e3.length());
        if e1.cross(e2).length() <= 1e-7 * longest * longest {
            return Err(err(format!("triangles[{t}]"), "zero-area triangle".into()).into());
        }
    }
    Ok(())
}

/// Appends `src` to `dst`, offsetting indices. Normals and uvs survive only
/// when every part has them (an empty `dst` takes `src`'s).
fn append(dst: &mut Mesh, src: Mesh) {
    let first = dst.positions.is_empty();
    let base = dst.positions.len() as u32;
    if first || (!dst.normals.is_empty() && !src.normals.is_empty()) {
        dst.normals.extend(src.normals);
    } else {
        dst.normals.clear();
    }
    if first || (!dst.uvs.is_empty() && !src.uvs.is_empty()) {
        dst.uvs.extend(src.uvs);
    } else {
        dst.uvs.clear();
    }
    dst.positions.extend(src.positions);
    dst.indices
        .extend(src.indices.iter().map(|t| t.map(|i| i + base)));
}
