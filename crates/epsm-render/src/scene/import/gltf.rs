//! glTF 2.0 meshes (`.gltf` with external or embedded buffers, and binary
//! `.glb`) through the `gltf` crate. Here glTF is a *mesh source*: every
//! triangle primitive of every mesh instanced by the default scene (or the
//! first scene) is flattened into one object-space mesh, with its node's
//! world transform applied (positions by the matrix, normals by its inverse
//! transpose, winding reversed under a mirroring transform). Cameras, lights
//! and materials are ignored. Texture coordinates (set 0) are flipped to
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

use std::path::Path;

use glam::{Mat3, Mat4, Vec2, Vec3};

use crate::error::{Result, SceneError};
use crate::scene::Mesh;

/// Reads the glTF or GLB file at `path` into one mesh (not yet validated).
pub fn load(path: &Path) -> Result<Mesh> {
    let fail = |field: &str, e: &dyn std::fmt::Display| SceneError::new(path, field, e.to_string());
    let gltf = gltf::Gltf::open(path).map_err(|e| fail("gltf", &format!("malformed glTF: {e}")))?;
    let base = path.parent();
    let buffers = gltf::import_buffers(&gltf.document, base, gltf.blob)
        .map_err(|e| fail("buffers", &format!("cannot load glTF buffers: {e}")))?;
    let doc = &gltf.document;
    let scene = doc
        .default_scene()
        .or_else(|| doc.scenes().next())
        .ok_or_else(|| fail("scenes", &"the file has no scene"))?;
    let mut mesh = Mesh::default();
    let mut stack: Vec<(gltf::Node, Mat4)> = scene.nodes().map(|n| (n, Mat4::IDENTITY)).collect();
    while let Some((node, parent)) = stack.pop() {
        let world = parent * Mat4::from_cols_array_2d(&node.transform().matrix());
        if let Some(m) = node.mesh() {
            for prim in m.primitives() {
                let field = format!("meshes[{}].primitives[{}]", m.index(), prim.index());
                let part = primitive(&prim, &buffers, world)
                    .map_err(|msg| SceneError::new(path, field, msg))?;
                super::append(&mut mesh, part);
            }
        }
        stack.extend(node.children().map(|c| (c, world)));
    }
    Ok(mesh)
}

/// One triangle primitive, transformed by `world`; errors are messages.
fn primitive(
    prim: &gltf::Primitive,
    buffers: &[gltf::buffer::Data],
    world: Mat4,
) -> Result<Mesh, String> {
    if prim.mode() != gltf::mesh::Mode::Triangles {
        return Err(format!(
            "primitive mode {:?} is not supported: only TRIANGLES",
            prim.mode()
        ));
    }
    let reader = prim.reader(|b| buffers.get(b.index()).map(|d| &d.0[..]));
    let positions: Vec<Vec3> = reader
        .read_positions()
        .ok_or("the primitive has no POSITION attribute")?
        .map(|p| world.transform_point3(Vec3::from(p)))
        .collect();
    let linear = Mat3::from_mat4(world);
    let normal_from_object = linear.inverse().transpose();
    let normals = match reader.read_normals() {
        Some(it) => it
            .map(|n| normal_from_object * Vec3::from(n))
            .map(|n| n.try_normalize().ok_or("zero or non-finite normal"))
            .collect::<Result<Vec<_>, _>>()?,
        None => Vec::new(),
    };
    let uvs: Vec<Vec2> = reader
        .read_tex_coords(0)
        .map(|t| t.into_f32().map(|[u, v]| Vec2::new(u, 1.0 - v)).collect())
        .unwrap_or_default();
    let flat: Vec<u32> = match reader.read_indices() {
        Some(i) => i.into_u32().collect(),
        None => (0..positions.len() as u32).collect(),
    };
    if !flat.len().is_multiple_of(3) {
        return Err(format!("{} indices do not form triangles", flat.len()));
    }
    let mirror = linear.determinant() < 0.0;
    let indices = flat
        .chunks_exact(3)
        .map(|t| {
            if mirror {
                [t[0], t[2], t[1]]
            } else {
                [t[0], t[1], t[2]]
            }
        })
        .collect();
    let complete = |len: usize| len == positions.len();
    Ok(Mesh {
        normals: if complete(normals.len()) {
            normals
        } else {
            Vec::new()
        },
        uvs: if complete(uvs.len()) { uvs } else { Vec::new() },
        positions,
        indices,
    })
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
