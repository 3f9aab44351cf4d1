//! Special files where a scene expects an input file (a symlink to
//! `/dev/zero`, a FIFO): each loader refuses them at once with an error
//! naming the file and the field, instead of reading forever or blocking.
#![cfg(unix)]

use std::path::Path;

use epsm_scene::import::load_mesh;
use epsm_scene::load::load_file;
use epsm_testkit::scenes::OVERHEAD_CAMERA;
use epsm_testkit::special::{each, refused};

/// Writes `dir/scene.toml`, the overhead floor plus `extra`, and returns
/// the error of loading it, checked to name the scene file and `field`.
fn scene_error(dir: &Path, extra: &str, field: &str) -> String {
    let scene = dir.join("scene.toml");
    std::fs::write(&scene, format!("{OVERHEAD_CAMERA}{extra}")).expect("write scene");
    let msg = refused(move || load_file(&scene));
    assert!(msg.contains("scene.toml") && msg.contains(field), "{msg}");
    msg
}

/// Each kind of special file named `name`, referred to by `extra`, is
/// refused at `field` as not a regular file.
fn refused_at(name: &str, extra: &str, field: &str) {
    each(name, |kind, dir, _| {
        let msg = scene_error(dir, extra, field);
        assert!(msg.contains("not a regular file"), "{kind:?} {name}: {msg}");
    });
}

#[test]
fn a_texture_that_is_dev_zero_or_a_fifo_is_refused_naming_the_field() {
    let texture = r#"
[materials.wood]
type = "diffuse"
texture = "special.png"
[[objects]]
name = "panel"
shape = "rectangle"
material = "wood"
translate = [0, 0.5, 0]
"#;
    refused_at("special.png", texture, "materials.wood.texture");
}

#[test]
fn an_environment_map_that_is_dev_zero_or_a_fifo_is_refused_naming_the_field() {
    let envmap = "[background]\nenvmap = \"special.exr\"\n";
    refused_at("special.exr", envmap, "background.envmap");
}

#[test]
fn a_mesh_that_is_dev_zero_or_a_fifo_is_refused_naming_the_field() {
    for ext in ["obj", "ply", "gltf", "glb"] {
        let name = format!("special.{ext}");
        let mesh =
            format!("[[objects]]\nname = \"bunny\"\nmesh = \"{name}\"\nmaterial = \"floor\"\n");
        each(&name, |kind, dir, path| {
            // The format comes from the name as written, not from the
            // link's target (`/dev/zero` has no extension).
            let msg = scene_error(dir, &mesh, "objects[1].mesh");
            assert!(
                msg.contains(&format!("{name}: not a regular file")),
                "{kind:?} {name}: {msg}"
            );
            let msg = refused(move || load_mesh(&path));
            assert!(
                msg.contains(&format!("{name}: not a regular file")),
                "{kind:?} {name}: {msg}"
            );
        });
    }
}

#[test]
fn a_scene_file_that_is_dev_zero_or_a_fifo_is_refused_naming_it() {
    for name in ["scene.toml", "scene.xml", "scene.gltf", "scene.glb"] {
        each(name, |kind, _, path| {
            let msg = refused(move || load_file(&path));
            assert!(
                msg.contains(&format!("{name}: not a regular file")),
                "{kind:?}: {msg}"
            );
        });
    }
}

#[test]
fn a_mitsuba_mesh_that_is_dev_zero_or_a_fifo_is_refused_naming_the_field() {
    for ext in ["obj", "ply"] {
        let name = format!("special.{ext}");
        each(&name, |kind, dir, _| {
            let scene = dir.join("scene.xml");
            let text = format!(
                "<scene version=\"3.0.0\">\n<sensor type=\"perspective\"><float name=\"fov\" value=\"40\"/></sensor>\n<shape type=\"{ext}\" id=\"s\"><string name=\"filename\" value=\"{name}\"/></shape>\n</scene>\n"
            );
            std::fs::write(&scene, text).expect("write scene");
            let msg = refused(move || load_file(&scene));
            assert!(
                msg.contains("scene.xml")
                    && msg.contains("shape[s].filename")
                    && msg.contains(&format!("{name}: not a regular file")),
                "{kind:?} {name}: {msg}"
            );
        });
    }
}
