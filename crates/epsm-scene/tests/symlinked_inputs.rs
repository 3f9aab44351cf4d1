//! A file a scene names through a symlink is read as the name says: a
//! correctly named link to a file without an extension (as data stores such
//! as DVC, Nix or git-annex make) loads like the file itself, in TOML and
//! Mitsuba scenes.
#![cfg(unix)]

use std::os::unix::fs::symlink;
use std::path::{Path, PathBuf};

use epsm_render::film::Image;
use epsm_render::scene::Object;
use epsm_render::tracer::{RenderOptions, render};
use epsm_scene::image_io::write_image;
use epsm_scene::load::{load_file, load_scene};
use epsm_testkit::scenes::OVERHEAD_CAMERA;
use glam::Vec3;

/// One triangle, as OBJ text.
const TRIANGLE_OBJ: &str = "v 0 0 0\nv 1 0 0\nv 0 0 -1\nf 1 2 3\n";

/// Writes `bytes` to `dir/store/<digest>`, a name without an extension as
/// a content-addressed store gives it, and returns that path.
fn stored(dir: &Path, bytes: &[u8]) -> PathBuf {
    let store = dir.join("store");
    std::fs::create_dir_all(&store).expect("store dir");
    let blob = store.join("5f1a9c0e7b3d2468");
    std::fs::write(&blob, bytes).expect("write blob");
    blob
}

/// `dir/scene.toml`: the overhead floor, lit, and a small panel under the
/// camera textured with `texture`.
fn textured_scene(dir: &Path, texture: &str) -> PathBuf {
    let scene = dir.join("scene.toml");
    let extra = format!(
        r#"
[materials.wood]
type = "diffuse"
texture = "{texture}"
[[objects]]
name = "panel"
shape = "rectangle"
material = "wood"
scale = 0.15
rotate = [{{ axis = [1, 0, 0], angle = -90 }}]
translate = [0, 0.5, 0]
[[lights]]
type = "point"
name = "p"
position = [0, 2, 0]
intensity = [10, 10, 10]
"#
    );
    std::fs::write(&scene, format!("{OVERHEAD_CAMERA}{extra}")).expect("write scene");
    scene
}

/// The scene at `path` rendered with its own settings at 4 samples.
fn rendered(path: &Path) -> Image {
    let scene = load_scene(path).unwrap_or_else(|e| panic!("{e}"));
    let opts = RenderOptions {
        spp: 4,
        ..RenderOptions::from_scene(&scene)
    };
    render(&scene, &opts, &|_| {}).image
}

#[test]
fn a_texture_named_through_a_link_to_an_extensionless_blob_renders_as_the_file() {
    let root = tempfile::tempdir().expect("temp dir");
    let pixels = (0..16)
        .map(|i| Vec3::new(i as f32 / 15.0, 1.0 - i as f32 / 15.0, 0.25))
        .collect();
    let texture = Image {
        width: 4,
        height: 4,
        pixels,
    };
    let direct = root.path().join("direct");
    std::fs::create_dir(&direct).expect("dir");
    write_image(&direct.join("tex.png"), &texture).expect("write png");
    let linked = root.path().join("linked");
    std::fs::create_dir(&linked).expect("dir");
    let png = std::fs::read(direct.join("tex.png")).expect("read png");
    symlink(stored(root.path(), &png), linked.join("tex.png")).expect("symlink");

    let expected = rendered(&textured_scene(&direct, "tex.png"));
    // The grey floor has r = g; the panel's texture shows where r != g.
    assert!(expected.pixels.iter().any(|p| p.x != p.y));
    assert_eq!(rendered(&textured_scene(&linked, "tex.png")), expected);
}

/// The objects of scene file `dir/<name>` holding `text`, beside
/// `mesh.obj`, a link to one triangle stored without an extension.
fn objects_beside_a_linked_triangle(name: &str, text: &str) -> Vec<Object> {
    let dir = tempfile::tempdir().expect("temp dir");
    let blob = stored(dir.path(), TRIANGLE_OBJ.as_bytes());
    symlink(blob, dir.path().join("mesh.obj")).expect("symlink");
    let scene = dir.path().join(name);
    std::fs::write(&scene, text).expect("write scene");
    load_file(&scene)
        .unwrap_or_else(|e| panic!("{e}"))
        .parts
        .objects
}

#[test]
fn a_mesh_named_through_a_link_to_an_extensionless_blob_loads() {
    let extra = "[[objects]]\nname = \"tri\"\nmesh = \"mesh.obj\"\nmaterial = \"floor\"\n";
    let objects =
        objects_beside_a_linked_triangle("scene.toml", &format!("{OVERHEAD_CAMERA}{extra}"));
    assert_eq!(objects[1].mesh.indices.len(), 1);
}

#[test]
fn a_mitsuba_mesh_named_through_a_link_to_an_extensionless_blob_loads() {
    let text = r#"<scene version="3.0.0">
<sensor type="perspective"><float name="fov" value="40"/></sensor>
<shape type="obj"><string name="filename" value="mesh.obj"/></shape>
</scene>
"#;
    let objects = objects_beside_a_linked_triangle("scene.xml", text);
    assert_eq!(objects[0].mesh.indices.len(), 1);
}
