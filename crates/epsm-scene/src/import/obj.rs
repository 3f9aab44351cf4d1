//! Wavefront OBJ meshes through `tobj`: polygons are fan-triangulated,
//! vertices are de-duplicated to a single index per vertex, and every model
//! (`o`/`g` group) of the file is merged into one mesh. Normals and texture
//! coordinates are kept when every model has them for every vertex (a zero
//! normal counts as missing); normals are normalized. Materials (`mtllib`, `usemtl`) are ignored: the scene file
//! assigns the material. OBJ's `v = 0` is the bottom row, as
//! [`Image::lookup`](epsm_render::film::Image::lookup) expects.
//!
//! ```toml
//! [[objects]]
//! name = "bunny"
//! mesh = "meshes/bunny.obj"
//! material = "white"
//! ```

use std::path::Path;

use glam::{Vec2, Vec3};

use crate::error::{FieldError, Result};
use epsm_render::scene::Mesh;

/// Reads the OBJ file at `path` into one mesh (not yet validated).
pub fn load(path: &Path) -> Result<Mesh> {
    parse(&crate::input_file::read(path)?, path)
}

/// Parses OBJ text into one mesh (not yet validated); `file` names it in
/// errors. Material libraries are not opened.
pub fn parse(bytes: &[u8], file: &Path) -> Result<Mesh> {
    let path = file;
    let options = tobj::LoadOptions {
        single_index: true,
        triangulate: true,
        ignore_points: true,
        ignore_lines: true,
    };
    let (models, _materials) =
        tobj::load_obj_buf(&mut std::io::BufReader::new(bytes), &options, |_| {
            Err(tobj::LoadError::OpenFileFailed)
        })
        .map_err(|e| FieldError::new(path, "obj", format!("malformed OBJ: {e}")))?;
    let mut mesh = Mesh::default();
    for model in models {
        super::append(&mut mesh, convert(model.mesh, path, &model.name)?);
    }
    Ok(mesh)
}

/// One tobj mesh as a [`Mesh`], keeping normals and uvs only when complete.
fn convert(m: tobj::Mesh, path: &Path, name: &str) -> Result<Mesh> {
    let n = m.positions.len() / 3;
    let positions = m.positions.chunks_exact(3).map(Vec3::from_slice).collect();
    // Zero normals stand for vertices the file gave none: the set is incomplete.
    let normals = if m.normals.len() == 3 * n {
        m.normals
            .chunks_exact(3)
            .map(|v| Vec3::from_slice(v).try_normalize())
            .collect::<Option<Vec<_>>>()
            .unwrap_or_default()
    } else {
        Vec::new()
    };
    let uvs = if m.texcoords.len() == 2 * n {
        m.texcoords.chunks_exact(2).map(Vec2::from_slice).collect()
    } else {
        Vec::new()
    };
    if !m.indices.len().is_multiple_of(3) {
        let msg = format!("{} indices do not form triangles", m.indices.len());
        return Err(FieldError::new(path, name.to_owned(), msg).into());
    }
    let indices = m
        .indices
        .chunks_exact(3)
        .map(|t| [t[0], t[1], t[2]])
        .collect();
    Ok(Mesh {
        positions,
        normals,
        uvs,
        indices,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::import::load_mesh;

    fn write(dir: &Path, name: &str, text: &str) -> std::path::PathBuf {
        let path = dir.join(name);
        std::fs::write(&path, text).expect("write test file");
        path
    }

    #[test]
    fn merges_models_and_keeps_complete_normals_and_uvs() {
        let dir = tempfile::tempdir().expect("temp dir");
        let text = "o a\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n\
                    vn 0 0 2\nf 1/1/1 2/2/1 3/3/1 4/4/1\n\
                    o b\nv 0 0 1\nv 1 0 1\nv 0 1 1\nvt 0 0\nvn 0 0 1\nf 5/5/2 6/5/2 7/5/2\n";
        let mesh = load_mesh(&write(dir.path(), "two.obj", text)).expect("valid OBJ");
        assert_eq!(mesh.len(), 3, "a quad (2 triangles) and a triangle");
        assert_eq!(mesh.positions.len(), 7);
        assert_eq!(mesh.normals.len(), 7);
        assert!(mesh.normals.iter().all(|n| n.abs_diff_eq(Vec3::Z, 1e-6)));
        assert_eq!(mesh.uvs.len(), 7);
        // The second model's indices are offset past the first model's vertices.
        assert!(mesh.indices[2].iter().all(|&i| i >= 4));
        assert_eq!(mesh.triangle(2)[0], Vec3::new(0.0, 0.0, 1.0));
    }

    #[test]
    fn drops_normals_missing_in_one_model() {
        let dir = tempfile::tempdir().expect("temp dir");
        let text = "o a\nv 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nf 1//1 2//1 3//1\n\
                    o b\nv 0 0 1\nv 1 0 1\nv 0 1 1\nf 4 5 6\n";
        let mesh = load_mesh(&write(dir.path(), "mixed.obj", text)).expect("valid OBJ");
        assert_eq!(mesh.len(), 2);
        assert!(mesh.normals.is_empty() && mesh.uvs.is_empty());
    }

    #[test]
    fn faces_without_normals_make_the_normals_incomplete() {
        let dir = tempfile::tempdir().expect("temp dir");
        let text = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nvn 0 0 1\nf 1//1 2//1 3//1\nf 2 4 3\n";
        let mesh = load_mesh(&write(dir.path(), "partial.obj", text)).expect("valid OBJ");
        assert_eq!(mesh.len(), 2);
        assert!(mesh.normals.is_empty(), "{:?}", mesh.normals);
    }

    #[test]
    fn zero_area_triangle_is_named_by_index() {
        let dir = tempfile::tempdir().expect("temp dir");
        let text = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 2 0 0\nf 1 2 3\nf 1 2 4\n";
        let path = write(dir.path(), "flat.obj", text);
        let msg = load_mesh(&path).expect_err("degenerate").to_string();
        assert!(
            msg.contains("triangles[1]") && msg.contains("flat.obj"),
            "{msg}"
        );
    }
}
