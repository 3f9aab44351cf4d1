//! glTF files as mesh sources (`mesh = "x.gltf"` in a TOML scene): node
//! transforms flattened into the positions and normals, GLB like text glTF,
//! mirroring nodes keeping faces and normals agreeing, errors for non-triangle
//! primitives and for text that is not JSON, external buffers read safely.

use std::path::Path;

use epsm_render::scene::Mesh;
use epsm_scene::import::load_mesh;
use glam::Vec3;

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
    assert_eq!(mesh.positions.len(), expected.len());
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

#[test]
fn external_buffers_are_read_up_to_their_byte_length_from_regular_files_only() {
    let dir = tempfile::tempdir().expect("temp dir");
    let path = write_gltf(dir.path(), 4);
    let text = std::fs::read_to_string(&path).expect("read back");
    // A longer file is read only up to byteLength; a percent-encoded name
    // is decoded.
    let mut long = triangle_bin();
    long.extend([7u8; 1000]);
    std::fs::write(dir.path().join("tri long.bin"), &long).expect("write bin");
    std::fs::write(&path, text.replace("\"tri.bin\"", "\"tri%20long.bin\"")).expect("rewrite");
    assert_eq!(load_mesh(&path).expect("valid glTF").len(), 1);
    let mut cases = vec![
        (
            "\"%FF.bin\"",
            "buffers[0]: uri: \"%FF.bin\" does not decode to UTF-8",
        ),
        ("\"missing.bin\"", "buffers[0]: uri: "),
        (
            "\"http://example.com/tri.bin\"",
            "buffers[0]: uri: unsupported scheme",
        ),
    ];
    // A device never ends: reading it whole ran until memory ran out.
    // Opening a FIFO for reading waits for a writer.
    #[cfg(unix)]
    {
        use epsm_testkit::special::{Special, make};
        cases.push((
            "\"file:///dev/zero\"",
            "buffers[0]: uri: /dev/zero: not a regular file",
        ));
        if make(Special::Fifo, &dir.path().join("fifo.bin")) {
            cases.push(("\"fifo.bin\"", "fifo.bin: not a regular file"));
        }
    }
    for (uri, expected) in cases {
        std::fs::write(&path, text.replace("\"tri.bin\"", uri)).expect("rewrite");
        let path = path.clone();
        let msg = epsm_testkit::special::refused(move || load_mesh(&path));
        assert!(msg.contains("tri.gltf") && msg.contains(expected), "{msg}");
    }
}

/// As a data store lays files out: each name a symlink to a blob without an
/// extension in a store of its own. A scene naming `tri.gltf` reads it as
/// glTF, and its buffer `tri.bin` resolves beside the link, not the blob.
#[cfg(unix)]
#[test]
fn a_gltf_named_through_a_link_reads_its_buffers_beside_the_link() {
    use std::os::unix::fs::symlink;
    let store = tempfile::tempdir().expect("temp dir");
    let gltf = write_gltf(store.path(), 4);
    let blobs = [
        ("tri.gltf", gltf),
        ("tri.bin", store.path().join("tri.bin")),
    ];
    let dir = tempfile::tempdir().expect("temp dir");
    for (i, (name, file)) in blobs.into_iter().enumerate() {
        let blob = store.path().join(format!("blob{i}"));
        std::fs::rename(file, &blob).expect("rename");
        symlink(&blob, dir.path().join(name)).expect("symlink");
    }
    let scene = dir.path().join("scene.toml");
    let extra = "[[objects]]\nname = \"tri\"\nmesh = \"tri.gltf\"\nmaterial = \"floor\"\n";
    let text = format!("{}{extra}", epsm_testkit::scenes::OVERHEAD_CAMERA);
    std::fs::write(&scene, text).expect("write scene");
    let parts = epsm_scene::load::load_file(&scene)
        .unwrap_or_else(|e| panic!("{e}"))
        .parts;
    assert_flattened(&parts.objects[1].mesh);
}
