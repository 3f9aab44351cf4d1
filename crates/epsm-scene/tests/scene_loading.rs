//! Valid scenes load into the documented values: the complete example of
//! `docs/scene-format.md`, and a scene using every kind of referenced file
//! (OBJ used twice, glTF, PNG texture, EXR environment map).

use std::path::{Path, PathBuf};
use std::sync::Arc;

use epsm_render::film::Image;
use epsm_render::lights::Background;
use epsm_render::materials::{Bsdf, Texture};
use epsm_render::scene::{RenderSettings, Scene, Surface};
use epsm_scene::image_io::write_image;
use epsm_scene::{load_scene, parts_from_str};
use glam::{DVec3, Vec3};

fn doc_path() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../docs/scene-format.md")
}

/// The ```toml block that follows the "## Complete example" heading.
fn doc_example() -> String {
    let doc = std::fs::read_to_string(doc_path()).expect("docs/scene-format.md exists");
    let section = doc
        .split("## Complete example")
        .nth(1)
        .expect("the doc has a complete example");
    let start = section.find("```toml\n").expect("a toml block") + "```toml\n".len();
    let len = section[start..].find("```").expect("a closed block");
    section[start..start + len].to_owned()
}

#[test]
fn docs_example_loads() {
    let parts = parts_from_str(&doc_example(), &doc_path()).expect("the documented example loads");
    assert_eq!(parts.objects.len(), 6);
    assert_eq!(parts.materials.len(), 4);
    assert_eq!(parts.point_lights.len(), 1);
    assert_eq!(parts.settings, RenderSettings::default());
    let light = parts
        .objects
        .iter()
        .find(|o| o.name == "light")
        .expect("light");
    assert_eq!(light.emission, Some(Vec3::splat(10.0)));
    // The light faces down: +z of the rectangle rotated +90° about x.
    let down = light
        .world_from_object
        .transform_vector3(DVec3::Z)
        .normalize();
    assert!(down.abs_diff_eq(DVec3::NEG_Y, 1e-12), "{down}");
    let scene = Scene::new(parts).expect("scene builds");
    assert_eq!(scene.object_id("ball"), Some(2));
}

fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
    let path = dir.join(name);
    std::fs::create_dir_all(path.parent().expect("parent")).expect("mkdir");
    std::fs::write(&path, text).expect("write test file");
    path
}

const TRIANGLE_GLTF: &str = r#"{"asset":{"version":"2.0"},"scene":0,"scenes":[{"nodes":[0]}],
"nodes":[{"mesh":0,"translation":[0,3,0]}],
"meshes":[{"primitives":[{"attributes":{"POSITION":0}}]}],
"buffers":[{"uri":"data:application/octet-stream;base64,AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAA","byteLength":36}],
"bufferViews":[{"buffer":0,"byteLength":36}],
"accessors":[{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[1,1,0]}]}"#;

fn full_scene(dir: &Path) -> PathBuf {
    write(
        dir,
        "meshes/quad.obj",
        "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n",
    );
    write(dir, "meshes/tri.gltf", TRIANGLE_GLTF);
    std::fs::create_dir_all(dir.join("tex")).expect("mkdir");
    let mut tex = Image::new(2, 2);
    tex.set(1, 0, Vec3::ONE);
    write_image(&dir.join("tex/checker.png"), &tex).expect("write texture");
    write_image(&dir.join("sky.exr"), &Image::new(8, 4)).expect("write envmap");
    write(
        dir,
        "scene.toml",
        r#"
[camera]
origin = [0, 0, 5]
target = [0, 0, 0]
resolution = [64, 32]

[render]
spp = 4
seed = 7

[background]
envmap = "sky.exr"
scale = 2.0
rotate = 90

[materials.wood]
type = "diffuse"
texture = "tex/checker.png"

[materials.metal]
type = "rough_conductor"
alpha = 0.3

[[objects]]
name = "a"
mesh = "meshes/quad.obj"
material = "wood"
scale = 2
rotate = [{ axis = [0, 1, 0], angle = 90 }]
translate = [1, 2, 3]

[[objects]]
name = "b"
mesh = "meshes/../meshes/quad.obj"
material = "metal"
emission = [1, 2, 3]

[[objects]]
name = "c"
mesh = "meshes/quad.obj"
material = "metal"
flip_normals = true

[[objects]]
name = "d"
mesh = "meshes/tri.gltf"
material = "wood"
"#,
    )
}

#[test]
fn full_scene_loads_with_shared_meshes_and_documented_values() {
    let dir = tempfile::tempdir().expect("temp dir");
    let scene = load_scene(&full_scene(dir.path())).expect("scene loads");
    let objects = scene.objects();
    assert_eq!(objects.len(), 4);
    // One file, two spellings of its path: one mesh.
    assert!(Arc::ptr_eq(&objects[0].mesh, &objects[1].mesh));
    assert_eq!(objects[0].mesh.len(), 2, "the quad is triangulated");
    // Flipped: same positions, reversed winding, not shared.
    assert!(!Arc::ptr_eq(&objects[0].mesh, &objects[2].mesh));
    assert_eq!(objects[2].mesh.positions, objects[0].mesh.positions);
    assert_eq!(objects[2].mesh.indices[0], [0, 2, 1]);
    // translate · rotate · scale: (1,0,0) → (2,0,0) → (0,0,−2) → (1,2,1).
    let p = objects[0].world_from_object.transform_point3(DVec3::X);
    assert!(p.abs_diff_eq(DVec3::new(1.0, 2.0, 1.0), 1e-12), "{p}");
    assert_eq!(objects[1].emission, Some(Vec3::new(1.0, 2.0, 3.0)));
    assert_eq!(objects[0].emission, None);
    // glTF node translation is baked into the object-space mesh.
    assert_eq!(objects[3].mesh.positions[2], Vec3::new(0.0, 4.0, 0.0));
    // Materials are ordered by name; objects refer to them by index.
    let names: Vec<&str> = scene.materials().iter().map(|m| m.name.as_str()).collect();
    assert_eq!(names, ["metal", "wood"]);
    assert_eq!(objects[0].material, 1);
    match &scene.materials()[1].bsdf {
        Bsdf::Diffuse(d) => match &d.albedo {
            Texture::Image(img) => {
                assert_eq!((img.width, img.height), (2, 2));
                assert!(img.get(1, 0).abs_diff_eq(Vec3::ONE, 1e-6));
            }
            other => panic!("expected a texture, got {other:?}"),
        },
        other => panic!("expected diffuse, got {other:?}"),
    }
    match scene.background() {
        Background::EnvMap(env) => {
            assert_eq!(env.scale, 2.0);
            assert!((env.rotate_y - std::f32::consts::FRAC_PI_2).abs() < 1e-6);
            assert_eq!((env.image().width, env.image().height), (8, 4));
        }
        other => panic!("expected an envmap, got {other:?}"),
    }
    let s = scene.settings();
    assert_eq!((s.spp, s.max_depth, s.rr_depth, s.seed), (4, 8, 3, 7));
    let cam = scene.camera();
    assert_eq!((cam.width, cam.height), (64, 32));
    assert!((cam.fov_y - 40f64.to_radians()).abs() < 1e-12);
    assert!(cam.up.abs_diff_eq(DVec3::Y, 1e-12));
}

#[test]
fn semantic_errors_carry_the_line_of_their_field() {
    let text = "[camera]\norigin = [0, 0, 5]\ntarget = [0, 0, 0]\nresolution = [8, 8]\n\
                [materials.w]\ntype = \"diffuse\"\n\
                [[objects]]\nname = \"a\"\nshape = \"cube\"\nmaterial = \"w\"\n\
                [[objects]]\nname = \"b\"\nshape = \"cube\"\nmaterial = \"nope\"\n";
    let err = parts_from_str(text, Path::new("dir/s.toml")).expect_err("unknown material");
    let epsm_scene::Error::Field(e) = err else {
        panic!("expected a field error, got {err}")
    };
    assert_eq!(e.field, "objects[1].material");
    assert_eq!(e.line, Some(14));
    assert_eq!(e.file, Path::new("dir/s.toml"));
}

/// A problem file embedding a scene under `[scene]`, as `epsm-core` does.
#[derive(serde::Deserialize)]
#[serde(deny_unknown_fields)]
struct Problem {
    scene: epsm_scene::desc::SceneDesc,
    iterations: u32,
}

#[test]
fn an_embedded_scene_reports_prefixed_fields_and_file_lines() {
    use epsm_scene::fields::parse;
    use epsm_scene::load::parts_from_desc;
    let text = "iterations = 10\n[scene.camera]\norigin = [0, 0, 5]\ntarget = [0, 0, 0]\n\
                resolution = [8, 8]\n[scene.materials.w]\ntype = \"diffuse\"\n\
                [[scene.objects]]\nname = \"a\"\nshape = \"cube\"\nmaterial = \"w\"\nscale = 0\n";
    let file = Path::new("problem.toml");
    let (problem, locator) = parse::<Problem>(text, file).expect("valid TOML");
    assert_eq!(problem.iterations, 10);
    let err = parts_from_desc(&problem.scene, file, &locator, "scene").expect_err("zero scale");
    let epsm_scene::Error::Field(e) = err else {
        panic!("expected a field error, got {err}")
    };
    assert_eq!(
        (e.field.as_str(), e.line),
        ("scene.objects[0].scale", Some(12))
    );
}

#[test]
fn scene_descriptions_survive_a_toml_round_trip() {
    use epsm_scene::desc::SceneDesc;
    use epsm_scene::fields::parse;
    let (desc, _) =
        parse::<SceneDesc>(&doc_example(), Path::new("example.toml")).expect("the example parses");
    let text = toml::to_string(&desc).expect("serializes");
    let (back, _) = parse::<SceneDesc>(&text, Path::new("again.toml")).expect("reparses");
    assert_eq!(back, desc);
}

/// An exact sphere loads as `Surface::Sphere` with an empty mesh; made
/// emissive in code, [`Scene::new`] refuses it (it has no triangles to
/// sample), naming the object.
#[test]
fn exact_spheres_load_and_never_emit() {
    let text = r#"
        [camera]
        origin = [0, 0, 4]
        target = [0, 0, 0]
        resolution = [8, 8]
        [materials.m]
        type = "diffuse"
        [[objects]]
        name = "ball"
        shape = "sphere"
        exact = true
        material = "m"
        scale = 0.5
    "#;
    let mut parts = parts_from_str(text, Path::new("s.toml")).expect("an exact sphere loads");
    let ball = &parts.objects[0];
    assert_eq!(ball.surface, Surface::Sphere);
    assert!(ball.mesh.is_empty());
    let scene = Scene::new(parts.clone()).expect("a non-emitting sphere is a scene");
    assert_eq!(scene.radius(), 0.5 * 3f64.sqrt());
    parts.objects[0].emission = Some(Vec3::ONE);
    let err = Scene::new(parts).expect_err("an emissive exact sphere");
    assert!(err.to_string().contains("\"ball\""), "{err}");
}
