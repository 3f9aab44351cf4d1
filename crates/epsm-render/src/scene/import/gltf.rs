//! glTF 2.0 meshes (`.gltf` with external or embedded buffers, and binary
//! `.glb`) through the `gltf` crate. Here glTF is a *mesh source*: every
//! triangle primitive of every mesh instanced by the default scene (or the
//! first scene) is flattened into one object-space mesh, with its node's
//! world transform applied (positions by the matrix, normals by its inverse
//! transpose, winding reversed under a mirroring transform). Cameras, lights
//! and materials are ignored (a whole glTF scene loads through
//! [`gltf_scene`](super::gltf_scene), which shares this file's reading). Texture coordinates (set 0) are flipped to
//! `v = 1 − v` so that `v = 0` is the bottom row, as
//! [`Image::lookup`](crate::film::Image::lookup) expects. Normals and uvs are
//! kept when every primitive has them. Only the `TRIANGLES` mode is accepted.
//!
//! ```toml
//! [[objects]]
//! name = "statue"
//! mesh = "meshes/statue.glb"
//! material = "white"
//! ```

use std::collections::HashSet;
use std::path::Path;

use glam::{DAffine3, DMat4, Vec2, Vec3};
use gltf::accessor::{DataType, Dimensions};

use crate::error::{Error, Result, SceneError};
use crate::scene::Mesh;

/// Reads the glTF or GLB file at `path` into one mesh (not yet validated).
pub fn load(path: &Path) -> Result<Mesh> {
    let bytes = std::fs::read(path).map_err(|source| Error::Io {
        path: path.to_owned(),
        source,
    })?;
    let file = open(&bytes, path)?;
    let mut mesh = Mesh::default();
    for placed in walk(&file.doc, path)? {
        let Some(m) = placed.node.mesh() else {
            continue;
        };
        let world = DAffine3::from_mat4(placed.world);
        let linear = world.matrix3.as_mat3();
        let normal_from_object = linear.inverse().transpose();
        for prim in m.primitives() {
            let field = format!("meshes[{}].primitives[{}]", m.index(), prim.index());
            let mut part =
                primitive(&prim, &file.buffers).map_err(|msg| SceneError::new(path, field, msg))?;
            for p in &mut part.positions {
                *p = world.transform_point3(p.as_dvec3()).as_vec3();
            }
            for n in &mut part.normals {
                *n = (normal_from_object * *n).normalize_or_zero();
            }
            if linear.determinant() < 0.0 {
                part.indices.iter_mut().for_each(|t| t.swap(1, 2));
            }
            super::append(&mut mesh, part);
        }
    }
    Ok(mesh)
}

/// A parsed and validated glTF document with its buffers loaded.
pub(crate) struct File {
    /// The document.
    pub doc: gltf::Document,
    /// Buffer contents, by buffer index.
    pub buffers: Vec<gltf::buffer::Data>,
}

/// Parses `bytes` (JSON glTF or GLB) and loads its buffers (external ones
/// relative to `file`'s directory).
pub(crate) fn open(bytes: &[u8], file: &Path) -> Result<File> {
    let fail = |field: &str, msg: String| Error::from(SceneError::new(file, field, msg));
    // The gltf crate subtracts the header size from the declared GLB length unchecked.
    if let Some(len) = bytes.strip_prefix(b"glTF").and_then(|r| r.get(4..8)) {
        let declared = u32::from_le_bytes([len[0], len[1], len[2], len[3]]);
        if declared < 12 {
            return Err(fail("glb", format!("declared length {declared} < 12")));
        }
    }
    let gltf =
        gltf::Gltf::from_slice(bytes).map_err(|e| fail("gltf", format!("malformed glTF: {e}")))?;
    let buffers = gltf::import_buffers(&gltf.document, file.parent(), gltf.blob)
        .map_err(|e| fail("buffers", format!("cannot load glTF buffers: {e}")))?;
    Ok(File {
        doc: gltf.document,
        buffers,
    })
}

/// A node of the scene with its world transform (object → world).
pub(crate) struct Placed<'a> {
    /// The node.
    pub node: gltf::Node<'a>,
    /// Product of the node's and its ancestors' local transforms.
    pub world: DMat4,
}

/// The nodes of the default scene (or the first scene), depth-first in file
/// order. Errors for a missing scene, a node reached twice (a cycle or a
/// shared child: glTF nodes form a forest) and a non-finite or singular
/// transform.
pub(crate) fn walk<'a>(doc: &'a gltf::Document, file: &Path) -> Result<Vec<Placed<'a>>> {
    let fail = |field: String, msg: &str| Error::from(SceneError::new(file, field, msg));
    let scene = doc
        .default_scene()
        .or_else(|| doc.scenes().next())
        .ok_or_else(|| fail("scenes".into(), "the file has no scene"))?;
    let mut seen = HashSet::new();
    let mut out = Vec::new();
    let mut stack: Vec<(gltf::Node, DMat4)> = scene.nodes().map(|n| (n, DMat4::IDENTITY)).collect();
    stack.reverse();
    while let Some((node, parent)) = stack.pop() {
        let field = format!("nodes[{}]", node.index());
        if !seen.insert(node.index()) {
            let msg = "reached twice: node cycles and shared children are not allowed";
            return Err(fail(field, msg));
        }
        let local = DMat4::from_cols_array_2d(&node.transform().matrix().map(|c| c.map(f64::from)));
        let world = parent * local;
        if !world.is_finite() || world.determinant() == 0.0 {
            return Err(fail(field, "non-finite or singular transform"));
        }
        let first_child = stack.len();
        stack.extend(node.children().map(|c| (c, world)));
        stack[first_child..].reverse();
        out.push(Placed { node, world });
    }
    Ok(out)
}

/// One triangle primitive in object space; errors are messages. Every
/// accessor is checked against its buffer before it is read. Normals are
/// normalized; texture coordinates (set 0) flipped to `v = 1 − v`.
pub(crate) fn primitive(
    prim: &gltf::Primitive,
    buffers: &[gltf::buffer::Data],
) -> Result<Mesh, String> {
    if prim.mode() != gltf::mesh::Mode::Triangles {
        return Err(format!(
            "primitive mode {:?} is not supported: only TRIANGLES",
            prim.mode()
        ));
    }
    let float = [DataType::F32];
    let position = prim
        .get(&gltf::Semantic::Positions)
        .ok_or("the primitive has no POSITION attribute")?;
    checked(&position, Dimensions::Vec3, &float, buffers)?;
    if let Some(a) = prim.get(&gltf::Semantic::Normals) {
        checked(&a, Dimensions::Vec3, &float, buffers)?;
    }
    if let Some(a) = prim.get(&gltf::Semantic::TexCoords(0)) {
        checked(
            &a,
            Dimensions::Vec2,
            &[DataType::F32, DataType::U8, DataType::U16],
            buffers,
        )?;
    }
    if let Some(a) = prim.indices() {
        checked(
            &a,
            Dimensions::Scalar,
            &[DataType::U8, DataType::U16, DataType::U32],
            buffers,
        )?;
    }
    let reader = prim.reader(|b| buffers.get(b.index()).map(|d| &d.0[..]));
    let missing = || "accessor data out of bounds".to_owned();
    let positions: Vec<Vec3> = reader
        .read_positions()
        .ok_or_else(missing)?
        .map(Vec3::from)
        .collect();
    let normals = match reader.read_normals() {
        Some(it) => it
            .map(|n| {
                Vec3::from(n)
                    .try_normalize()
                    .ok_or("zero or non-finite normal")
            })
            .collect::<Result<Vec<_>, _>>()?,
        None => Vec::new(),
    };
    let uvs: Vec<Vec2> = match reader.read_tex_coords(0) {
        Some(t) => t.into_f32().map(|[u, v]| Vec2::new(u, 1.0 - v)).collect(),
        None => Vec::new(),
    };
    let flat: Vec<u32> = match reader.read_indices() {
        Some(i) => i.into_u32().collect(),
        None => (0..positions.len() as u32).collect(),
    };
    if !flat.len().is_multiple_of(3) {
        return Err(format!("{} indices do not form triangles", flat.len()));
    }
    let complete = |len: usize| len == positions.len();
    Ok(Mesh {
        normals: if complete(normals.len()) {
            normals
        } else {
            Vec::new()
        },
        uvs: if complete(uvs.len()) { uvs } else { Vec::new() },
        indices: flat.chunks_exact(3).map(|t| [t[0], t[1], t[2]]).collect(),
        positions,
    })
}

/// Checks that accessor `a` has the expected shape and lies inside its
/// buffer view and buffer (the gltf crate's reader assumes both).
fn checked(
    a: &gltf::Accessor,
    dims: Dimensions,
    types: &[DataType],
    buffers: &[gltf::buffer::Data],
) -> Result<(), String> {
    let i = a.index();
    if a.sparse().is_some() {
        return Err(format!(
            "accessors[{i}]: sparse accessors are not supported"
        ));
    }
    if a.dimensions() != dims || !types.contains(&a.data_type()) {
        return Err(format!(
            "accessors[{i}]: expected {dims:?} of {types:?}, found {:?} of {:?}",
            a.dimensions(),
            a.data_type()
        ));
    }
    let view = a.view().ok_or(format!("accessors[{i}]: no buffer view"))?;
    let size = a.size();
    let stride = view.stride().unwrap_or(size);
    let need = (a.count().checked_sub(1))
        .and_then(|n| n.checked_mul(stride))
        .and_then(|n| n.checked_add(a.offset() + size));
    let view_end = view.offset().checked_add(view.length());
    let buffer_len = buffers.get(view.buffer().index()).map_or(0, |d| d.0.len());
    match (need, view_end) {
        (None, _) => Err(format!(
            "accessors[{i}]: count {} is zero or too large",
            a.count()
        )),
        _ if stride < size => Err(format!(
            "accessors[{i}]: byteStride {stride} < element size {size}"
        )),
        (Some(n), _) if n > view.length() => Err(format!(
            "accessors[{i}]: {} items need {n} bytes but bufferViews[{}] holds {}",
            a.count(),
            view.index(),
            view.length()
        )),
        (_, end) if end.is_none_or(|e| e > buffer_len) => Err(format!(
            "bufferViews[{}] ends past its buffer ({buffer_len} bytes)",
            view.index()
        )),
        _ => Ok(()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::import::load_mesh;

    /// Vertex data of one triangle: positions, normals (+z) and u16 indices.
    fn triangle_bin() -> Vec<u8> {
        let mut bin = Vec::new();
        for v in [[0f32, 0., 0.], [1., 0., 0.], [0., 1., 0.]] {
            v.iter().for_each(|x| bin.extend(x.to_le_bytes()));
        }
        for _ in 0..3 {
            [0f32, 0., 1.]
                .iter()
                .for_each(|x| bin.extend(x.to_le_bytes()));
        }
        for i in [0u16, 1, 2, 0] {
            bin.extend(i.to_le_bytes());
        }
        bin
    }

    /// A document drawing [`triangle_bin`] with primitive `mode`, instanced by
    /// a rotated and scaled child node under a translated parent; `buffer` is
    /// the buffer object's JSON.
    fn triangle_json(mode: u32, buffer: &str) -> String {
        format!(
            r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0]}}],
            "nodes":[{{"translation":[0,0,5],"children":[1]}},{{"mesh":0,"rotation":[0.70710678,0,0,0.70710678],"scale":[2,1,1]}}],
            "meshes":[{{"primitives":[{{"attributes":{{"POSITION":0,"NORMAL":1}},"indices":2,"mode":{mode}}}]}}],
            "buffers":[{buffer}],
            "bufferViews":[{{"buffer":0,"byteOffset":0,"byteLength":36}},{{"buffer":0,"byteOffset":36,"byteLength":36}},
                           {{"buffer":0,"byteOffset":72,"byteLength":6}}],
            "accessors":[{{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[1,1,0]}},
                         {{"bufferView":1,"componentType":5126,"count":3,"type":"VEC3"}},
                         {{"bufferView":2,"componentType":5123,"count":3,"type":"SCALAR"}}]}}"#
        )
    }

    /// `tri.gltf` with its buffer in `tri.bin`.
    fn write_gltf(dir: &Path, mode: u32) -> std::path::PathBuf {
        let bin = triangle_bin();
        std::fs::write(dir.join("tri.bin"), &bin).expect("write bin");
        let buffer = format!(r#"{{"uri":"tri.bin","byteLength":{}}}"#, bin.len());
        let path = dir.join("tri.gltf");
        std::fs::write(&path, triangle_json(mode, &buffer)).expect("write gltf");
        path
    }

    /// The same document as binary glTF: header, JSON chunk, BIN chunk.
    fn write_glb(dir: &Path) -> std::path::PathBuf {
        let mut bin = triangle_bin();
        bin.resize(bin.len().next_multiple_of(4), 0);
        let mut json = triangle_json(4, &format!(r#"{{"byteLength":{}}}"#, bin.len())).into_bytes();
        json.resize(json.len().next_multiple_of(4), b' ');
        let total = 12 + 8 + json.len() + 8 + bin.len();
        let mut glb = Vec::new();
        for word in [0x4654_6C67, 2, total as u32, json.len() as u32, 0x4E4F_534A] {
            glb.extend(u32::to_le_bytes(word));
        }
        glb.extend(&json);
        glb.extend(u32::to_le_bytes(bin.len() as u32));
        glb.extend(u32::to_le_bytes(0x004E_4942));
        glb.extend(&bin);
        let path = dir.join("tri.glb");
        std::fs::write(&path, glb).expect("write glb");
        path
    }

    /// The triangle after the node transforms: T(0,0,5) · Rx(90°) · S(2,1,1).
    fn assert_flattened(mesh: &Mesh) {
        assert_eq!(mesh.indices, vec![[0, 1, 2]]);
        let expected = [
            Vec3::new(0., 0., 5.),
            Vec3::new(2., 0., 5.),
            Vec3::new(0., 0., 6.),
        ];
        for (p, e) in mesh.positions.iter().zip(expected) {
            assert!(p.abs_diff_eq(e, 1e-6), "{p} != {e}");
        }
        // Normals by the inverse transpose: +z rotated to −y, agreeing with the winding.
        assert!(
            mesh.normals
                .iter()
                .all(|n| n.abs_diff_eq(Vec3::NEG_Y, 1e-6))
        );
        assert!(mesh.uvs.is_empty());
    }

    #[test]
    fn node_transforms_are_flattened_into_positions_and_normals() {
        let dir = tempfile::tempdir().expect("temp dir");
        assert_flattened(&load_mesh(&write_gltf(dir.path(), 4)).expect("valid glTF"));
    }

    #[test]
    fn binary_gltf_loads_like_text_gltf() {
        let dir = tempfile::tempdir().expect("temp dir");
        assert_flattened(&load_mesh(&write_glb(dir.path())).expect("valid GLB"));
    }

    #[test]
    fn mirroring_nodes_reverse_the_winding_to_keep_normals_and_faces_agreeing() {
        let dir = tempfile::tempdir().expect("temp dir");
        let path = write_gltf(dir.path(), 4);
        let text = std::fs::read_to_string(&path).expect("read back");
        std::fs::write(&path, text.replace("[2,1,1]", "[-2,1,1]")).expect("rewrite");
        let mesh = load_mesh(&path).expect("valid glTF");
        assert_eq!(mesh.indices, vec![[0, 2, 1]]);
        let [p0, p1, p2] = mesh.triangle(0);
        let geometric = (p1 - p0).cross(p2 - p0).normalize();
        assert!(mesh.normals.iter().all(|n| n.dot(geometric) > 0.99));
    }

    #[test]
    fn non_triangle_modes_are_rejected() {
        let dir = tempfile::tempdir().expect("temp dir");
        let msg = load_mesh(&write_gltf(dir.path(), 1))
            .expect_err("lines")
            .to_string();
        assert!(
            msg.contains("TRIANGLES") && msg.contains("meshes[0].primitives[0]"),
            "{msg}"
        );
    }

    #[test]
    fn text_that_is_not_json_is_an_error_naming_the_file() {
        let dir = tempfile::tempdir().expect("temp dir");
        let path = dir.path().join("broken.gltf");
        std::fs::write(&path, "this is not json").expect("write");
        let msg = load_mesh(&path).expect_err("not JSON").to_string();
        assert!(
            msg.contains("broken.gltf") && msg.contains("malformed glTF"),
            "{msg}"
        );
    }
}
