//! One scene written as TOML, glTF and Mitsuba XML renders the same image
//! with the same seed; every shipped scene's Mitsuba twin
//! (`scenes/mitsuba/NAME.xml`) has the same objects, materials and lights
//! as `scenes/NAME.toml` and renders the same image.

mod interop_util;

use std::path::{Path, PathBuf};

use epsm_render::Image;
use epsm_render::materials::{Bsdf, Texture};
use epsm_render::scene::{Mesh, Scene, SceneParts};
use epsm_render::tracer::{RenderOptions, render};
use epsm_scene::load_file;
use glam::{DAffine3, DMat3};
use interop_util::{Gltf, matrix};
use serde_json::json;

const TOML: &str = r#"
[camera]
origin = [0.0, 1.0, 4.0]
target = [0.0, 1.0, 0.0]
fov = 40
resolution = [32, 24]

[materials.white]
type = "diffuse"
albedo = [0.7, 0.7, 0.7]

[materials.metal]
type = "rough_conductor"
alpha = 0.09
tint = [0.9, 0.6, 0.3]

[materials.mirror]
type = "conductor"
tint = [0.8, 0.8, 0.8]

[materials.lamp]
type = "diffuse"
albedo = [0.0, 0.0, 0.0]

[[objects]]
name = "floor"
shape = "rectangle"
material = "white"
scale = 3.0
rotate = [{ axis = [1, 0, 0], angle = -90 }]

[[objects]]
name = "box"
shape = "cube"
material = "metal"
scale = 0.4
rotate = [{ axis = [0, 1, 0], angle = 30 }]
translate = [-0.6, 0.4, 0.0]

[[objects]]
name = "wall"
shape = "rectangle"
material = "mirror"
scale = [2.0, 1.0, 1.0]
translate = [0.0, 1.0, -1.5]

[[objects]]
name = "light"
shape = "rectangle"
material = "lamp"
emission = [8.0, 8.0, 8.0]
scale = 0.3
rotate = [{ axis = [1, 0, 0], angle = 90 }]
translate = [0.0, 2.5, 0.0]

[[lights]]
type = "point"
name = "bulb"
position = [1.0, 2.0, 1.0]
intensity = [2.0, 2.0, 2.0]
"#;

const XML: &str = r#"<scene version="3.0.0">
    <default name="res" value="32"/>
    <sensor type="perspective">
        <float name="fov" value="40"/>
        <string name="fov_axis" value="y"/>
        <transform name="to_world"><lookat origin="0, 1, 4" target="0, 1, 0" up="0, 1, 0"/></transform>
        <film type="hdrfilm"><integer name="width" value="$res"/><integer name="height" value="24"/></film>
    </sensor>
    <bsdf type="diffuse" id="white"><rgb name="reflectance" value="0.7"/></bsdf>
    <bsdf type="diffuse" id="lamp"><rgb name="reflectance" value="0"/></bsdf>
    <shape type="rectangle" id="floor">
        <transform name="to_world"><scale value="3"/><rotate x="1" angle="-90"/></transform>
        <ref id="white"/>
    </shape>
    <shape type="cube" id="box">
        <transform name="to_world"><scale value="0.4"/><rotate y="1" angle="30"/><translate x="-0.6" y="0.4"/></transform>
        <bsdf type="roughconductor" id="metal">
            <string name="distribution" value="ggx"/>
            <float name="alpha" value="0.09"/>
            <rgb name="specular_reflectance" value="0.9, 0.6, 0.3"/>
        </bsdf>
    </shape>
    <shape type="rectangle" id="wall">
        <transform name="to_world"><scale x="2"/><translate y="1" z="-1.5"/></transform>
        <bsdf type="conductor" id="mirror"><rgb name="specular_reflectance" value="0.8"/></bsdf>
    </shape>
    <shape type="rectangle" id="light">
        <transform name="to_world"><scale value="0.3"/><rotate x="1" angle="90"/><translate y="2.5"/></transform>
        <ref id="lamp"/>
        <emitter type="area"><rgb name="radiance" value="8"/></emitter>
    </shape>
    <emitter type="point" id="bulb">
        <point name="position" x="1" y="2" z="1"/>
        <rgb name="intensity" value="2"/>
    </emitter>
</scene>
"#;

/// The glTF equivalent of `parts`: one node per object (its mesh and
/// matrix), materials mapped back through the documented table, the camera
/// on a node, the point lights in candela.
fn gltf_of(parts: &SceneParts, dir: &Path) -> PathBuf {
    let mut g = Gltf::default();
    for (i, o) in parts.objects.iter().enumerate() {
        let m = &parts.materials[o.material as usize];
        let (base, metallic, roughness) = match &m.bsdf {
            Bsdf::Diffuse(d) => match &d.albedo {
                Texture::Constant(c) => (*c, 0.0, 1.0),
                Texture::Image(_) => unreachable!("no textures here"),
            },
            Bsdf::RoughConductor(r) => (r.tint, 1.0, r.alpha.sqrt()),
            Bsdf::Conductor(c) => (c.tint, 1.0, 0.0),
            Bsdf::Dielectric(_) => unreachable!("no dielectrics here"),
        };
        let emission = o.emission.unwrap_or_default();
        let strength = emission.max_element().max(1.0);
        g.materials.push(json!({
            "name": m.name,
            "pbrMetallicRoughness": {"baseColorFactor": [base.x, base.y, base.z, 1.0],
                                     "metallicFactor": metallic, "roughnessFactor": roughness},
            "emissiveFactor": (emission / strength).to_array(),
            "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": strength}},
        }));
        let mesh = g.mesh(&o.mesh, i);
        g.nodes
            .push(json!({"name": o.name, "mesh": mesh, "matrix": matrix(o.world_from_object)}));
    }
    let c = &parts.camera;
    let world_from_camera =
        DAffine3::from_mat3_translation(DMat3::from_cols(c.right, c.up, -c.forward), c.origin);
    g.cameras.push(
        json!({"type": "perspective", "perspective": {"yfov": c.fov_y, "znear": 0.01},
                          "extras": {"resolution": [c.width, c.height]}}),
    );
    g.nodes
        .push(json!({"name": "camera", "camera": 0, "matrix": matrix(world_from_camera)}));
    for (i, l) in parts.point_lights.iter().enumerate() {
        let candela = l.intensity.max_element() * 683.0;
        g.lights.push(
            json!({"type": "point", "name": l.name, "intensity": candela,
                             "color": (l.intensity / l.intensity.max_element()).to_array()}),
        );
        g.nodes.push(json!({"name": format!("light node {i}"), "extensions": {"KHR_lights_punctual": {"light": i}},
                            "translation": l.position.as_vec3().to_array()}));
    }
    g.write(dir, "scene")
}

/// Renders `parts` with fixed options (the formats' own settings differ).
fn image(parts: SceneParts, spp: u32) -> Image {
    let scene = Scene::new(parts).expect("scene builds");
    let opts = RenderOptions {
        spp,
        seed: 7,
        max_depth: 5,
        rr_depth: 3,
    };
    render(&scene, &opts, &|_| {}).image
}

/// Asserts `a` and `b` agree within floating-point tolerance: the means to
/// 1e-4 relative, and 99 % of pixels to 1e-3 relative (the rest may differ
/// where a ray grazes an edge that moved by an f32 rounding).
fn assert_same(a: &Image, b: &Image, what: &str) {
    assert_eq!((a.width, a.height), (b.width, b.height), "{what}");
    assert_eq!(a.pixels.len(), b.pixels.len(), "{what}: pixel counts");
    let (ma, mb) = (a.mean(), b.mean());
    assert!(ma.max_element() > 1e-3, "{what}: the image is black");
    assert!(
        (ma - mb).abs().max_element() <= 1e-4 * ma.max_element().max(1e-2),
        "{what}: means {ma} vs {mb}"
    );
    let close = a
        .pixels
        .iter()
        .zip(&b.pixels)
        .filter(|(p, q)| (**p - **q).abs().max_element() <= 1e-3 * p.max(**q).max_element() + 1e-5)
        .count();
    assert!(
        close * 100 >= 99 * a.pixels.len(),
        "{what}: only {close} of {} pixels agree",
        a.pixels.len()
    );
}

#[test]
fn one_scene_as_toml_gltf_and_mitsuba_renders_the_same_image() {
    let dir = tempfile::tempdir().expect("temp dir");
    let write = |name: &str, text: &str| {
        let path = dir.path().join(name);
        std::fs::write(&path, text).expect("write scene");
        path
    };
    let toml = load_file(&write("scene.toml", TOML)).expect("TOML loads");
    let xml = load_file(&write("scene.xml", XML)).expect("XML loads");
    let gltf = load_file(&gltf_of(&toml.parts, dir.path())).expect("glTF loads");
    assert!(
        xml.warnings.is_empty() && gltf.warnings.is_empty(),
        "{:?} {:?}",
        xml.warnings,
        gltf.warnings
    );
    for other in [&xml.parts, &gltf.parts] {
        let names = |p: &SceneParts| p.objects.iter().map(|o| o.name.clone()).collect::<Vec<_>>();
        assert_eq!(names(other), names(&toml.parts));
    }
    let reference = image(toml.parts, 8);
    assert_same(&reference, &image(xml.parts, 8), "Mitsuba XML");
    assert_same(&reference, &image(gltf.parts, 8), "glTF");
}

/// Asserts two meshes are the same: positions, texture coordinates and
/// triangles bit for bit, normals to `f32` rounding (mesh files store unit
/// normals that the importers normalise again).
fn assert_same_mesh(a: &Mesh, b: &Mesh, what: &str) {
    assert_eq!(
        (&a.positions, &a.uvs, &a.indices),
        (&b.positions, &b.uvs, &b.indices),
        "{what}"
    );
    assert_eq!(a.normals.len(), b.normals.len(), "{what}: normals");
    for (i, (n, m)) in a.normals.iter().zip(&b.normals).enumerate() {
        assert!(
            (*n - *m).abs().max_element() <= 2e-7,
            "{what}: normal {i}: {n} vs {m}"
        );
    }
}

fn scenes_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes")
}

#[test]
fn every_shipped_scene_has_a_mitsuba_twin_that_renders_the_same() {
    let mut tomls: Vec<PathBuf> = std::fs::read_dir(scenes_dir())
        .expect("scenes/")
        .map(|e| e.expect("entry").path())
        .filter(|p| p.extension().is_some_and(|e| e == "toml"))
        .collect();
    tomls.sort();
    assert!(tomls.len() >= 5);
    for toml in tomls {
        let stem = toml
            .file_stem()
            .and_then(|s| s.to_str())
            .expect("UTF-8 name");
        let twin = scenes_dir().join("mitsuba").join(format!("{stem}.xml"));
        let a = load_file(&toml).expect("TOML scene loads");
        let b = load_file(&twin).unwrap_or_else(|e| panic!("{stem}: twin does not load: {e}"));
        assert!(b.warnings.is_empty(), "{stem}: {:?}", b.warnings);
        let (a, mut b) = (a.parts, b.parts);
        assert_eq!(a.settings.spp, b.settings.spp, "{stem}");
        assert_eq!(a.settings.max_depth, b.settings.max_depth, "{stem}");
        let sorted = |p: &SceneParts| {
            let mut m = p.materials.clone();
            m.sort_by(|x, y| x.name.cmp(&y.name));
            m
        };
        assert_eq!(sorted(&a), sorted(&b), "{stem}: materials");
        assert_eq!(a.point_lights.len(), b.point_lights.len(), "{stem}");
        assert_eq!(a.objects.len(), b.objects.len(), "{stem}");
        for (x, y) in a.objects.iter().zip(&b.objects) {
            let (mx, my) = (
                &a.materials[x.material as usize],
                &b.materials[y.material as usize],
            );
            assert_eq!(
                (&x.name, mx, x.emission),
                (&y.name, my, y.emission),
                "{stem}"
            );
            assert_eq!(x.surface, y.surface, "{stem}: {}", x.name);
            assert_same_mesh(&x.mesh, &y.mesh, &format!("{stem}: {}", x.name));
            assert!(
                x.world_from_object.abs_diff_eq(y.world_from_object, 1e-12),
                "{stem}: {}",
                x.name
            );
        }
        assert!(
            a.camera.forward.abs_diff_eq(b.camera.forward, 1e-12),
            "{stem}"
        );
        assert!((a.camera.fov_y - b.camera.fov_y).abs() < 1e-12, "{stem}");
        // Render small: 40 × 40 at 2 spp.
        let mut small = a.camera.clone();
        (small.width, small.height) = (40, 40);
        b.camera = small.clone();
        let a = SceneParts { camera: small, ..a };
        assert_same(&image(a, 2), &image(b, 2), stem);
    }
}
