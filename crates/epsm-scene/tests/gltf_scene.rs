//! Whole glTF scenes map as `docs/interop.md` documents: materials by
//! metallic, roughness, transmission and emission; the node hierarchy into
//! `world_from_object` and object names; the camera and its resolution;
//! point lights from candela; skipped features as warnings.

mod interop_util;

use epsm_render::materials::{Bsdf, Conductor, Dielectric, RoughConductor};
use epsm_scene::{Loaded, load_file, shapes};
use glam::{DAffine3, DQuat, DVec3, Vec3};
use interop_util::{Gltf, matrix};
use serde_json::{Value, json};

/// A scene of one rectangle node per material of `materials`, a camera
/// (`camera` is the camera object) and the given lights.
fn load(materials: Vec<Value>, camera: Value, lights: Vec<Value>) -> Loaded {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut g = Gltf::default();
    let rectangle = shapes::rectangle();
    for (i, m) in materials.into_iter().enumerate() {
        g.materials.push(m);
        let mesh = g.mesh(&rectangle, i);
        g.nodes.push(json!({"name": format!("panel{i}"), "mesh": mesh, "translation": [i as f32 * 3.0, 0, 0]}));
    }
    g.cameras.push(camera);
    g.nodes.push(json!({"camera": 0, "translation": [0, 0, 5]}));
    for (i, l) in lights.into_iter().enumerate() {
        g.lights.push(l);
        g.nodes.push(
            json!({"extensions": {"KHR_lights_punctual": {"light": i}}, "translation": [1, 2, 3]}),
        );
    }
    load_file(&g.write(dir.path(), "s")).expect("valid glTF scene")
}

fn camera() -> Value {
    json!({"type": "perspective", "perspective": {"yfov": 0.5, "znear": 0.1}, "extras": {"resolution": [40, 30]}})
}

fn pbr(metallic: f32, roughness: f32) -> Value {
    json!({"pbrMetallicRoughness": {"baseColorFactor": [0.8, 0.4, 0.2, 1.0], "metallicFactor": metallic, "roughnessFactor": roughness}})
}

#[test]
fn materials_map_by_metallic_roughness_transmission_and_emission() {
    let mut glass = pbr(0.0, 0.0);
    glass["extensions"] = json!({"KHR_materials_transmission": {"transmissionFactor": 1.0}, "KHR_materials_ior": {"ior": 1.33}});
    let mut lamp = pbr(0.0, 1.0);
    lamp["emissiveFactor"] = json!([1.0, 0.5, 0.25]);
    lamp["extensions"] = json!({"KHR_materials_emissive_strength": {"emissiveStrength": 4.0}});
    lamp["doubleSided"] = json!(true);
    let loaded = load(
        vec![pbr(0.0, 0.5), pbr(1.0, 0.5), pbr(1.0, 0.01), glass, lamp],
        camera(),
        vec![],
    );
    let p = &loaded.parts;
    let tint = Vec3::new(0.8, 0.4, 0.2);
    let bsdf = |i: usize| &p.materials[p.objects[i].material as usize].bsdf;
    assert!(matches!(bsdf(0), Bsdf::Diffuse(_)));
    assert_eq!(
        bsdf(1),
        &Bsdf::RoughConductor(RoughConductor { alpha: 0.25, tint })
    );
    assert_eq!(
        bsdf(2),
        &Bsdf::Conductor(Conductor { tint }),
        "α = 1e-4 is below the smooth threshold"
    );
    assert_eq!(bsdf(3), &Bsdf::Dielectric(Dielectric { ior: 1.33 }));
    assert!(matches!(bsdf(4), Bsdf::Diffuse(_)));
    assert!(p.materials[p.objects[4].material as usize].two_sided);
    assert!(!p.materials[p.objects[0].material as usize].two_sided);
    assert_eq!(p.objects[4].emission, Some(Vec3::new(4.0, 2.0, 1.0)));
    assert!(p.objects[..4].iter().all(|o| o.emission.is_none()));
    assert!(loaded.warnings.is_empty(), "{:?}", loaded.warnings);
}

#[test]
fn node_hierarchy_composes_transforms_and_names_objects_after_nodes() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut g = Gltf::default();
    g.materials.push(pbr(0.0, 1.0));
    let cube = g.mesh(&shapes::cube(), 0);
    let q = DQuat::from_rotation_y(0.5);
    g.nodes
        .push(json!({"name": "parent", "translation": [0, 1, 0], "children": [1, 2, 4]}));
    g.nodes.push(json!({"name": "child", "mesh": cube, "rotation": q.as_quat().to_array(), "scale": [2, 2, 2]}));
    g.nodes.push(
        json!({"mesh": cube, "matrix": matrix(DAffine3::from_scale(DVec3::new(-1.0, 1.0, 1.0)))}),
    );
    g.cameras.push(camera());
    g.nodes.push(json!({"camera": 0, "translation": [0, 0, 5]}));
    g.nodes
        .push(json!({"name": "twin", "mesh": cube, "translation": [3, 0, 0]}));
    g.roots = Some(vec![0, 3]);
    let loaded = load_file(&g.write(dir.path(), "h")).expect("valid glTF");
    let objects = &loaded.parts.objects;
    let names: Vec<&str> = objects.iter().map(|o| o.name.as_str()).collect();
    assert_eq!(names, ["child", "node2", "twin"]);
    let expected = DAffine3::from_translation(DVec3::Y)
        * DAffine3::from_rotation_y(0.5)
        * DAffine3::from_scale(DVec3::splat(2.0));
    assert!(objects[0].world_from_object.abs_diff_eq(expected, 1e-6));
    // The mirrored instance reverses the winding so its faces keep facing out.
    assert_eq!(objects[1].mesh.indices[0], [0, 2, 1]);
    assert_eq!(objects[0].mesh.indices[0], [0, 1, 2]);
    // One mesh per (mesh, primitive, mirrored).
    assert!(std::sync::Arc::ptr_eq(&objects[0].mesh, &objects[2].mesh));
    assert!(!std::sync::Arc::ptr_eq(&objects[0].mesh, &objects[1].mesh));
}

#[test]
fn camera_resolution_follows_extras_or_aspect_ratio_and_lights_convert_candela() {
    let light =
        json!({"type": "point", "name": "bulb", "intensity": 683.0, "color": [1.0, 0.5, 0.0]});
    let p = load(vec![pbr(0.0, 1.0)], camera(), vec![light]).parts;
    assert_eq!((p.camera.width, p.camera.height), (40, 30));
    assert!((p.camera.fov_y - 0.5).abs() < 1e-6);
    assert!(
        p.camera.forward.abs_diff_eq(DVec3::NEG_Z, 1e-12)
            && p.camera.origin == DVec3::new(0.0, 0.0, 5.0)
    );
    assert_eq!(p.point_lights[0].name, "bulb");
    assert_eq!(p.point_lights[0].position, DVec3::new(1.0, 2.0, 3.0));
    assert!(
        p.point_lights[0]
            .intensity
            .abs_diff_eq(Vec3::new(1.0, 0.5, 0.0), 1e-6)
    );
    let wide = json!({"type": "perspective", "perspective": {"yfov": 0.5, "aspectRatio": 2.0, "znear": 0.1}});
    let p = load(vec![pbr(0.0, 1.0)], wide, vec![]).parts;
    assert_eq!((p.camera.width, p.camera.height), (512, 256));
}

#[test]
fn textures_and_light_ranges_are_skipped_with_warnings() {
    let mut textured = pbr(0.0, 1.0);
    textured["pbrMetallicRoughness"]["baseColorTexture"] = json!({"index": 0});
    let light = json!({"type": "point", "intensity": 1.0, "range": 10.0});
    let dir = tempfile::tempdir().expect("temp dir");
    let mut g = Gltf::default();
    g.materials.push(textured);
    let mesh = g.mesh(&shapes::rectangle(), 0);
    g.nodes.push(json!({"name": "panel", "mesh": mesh}));
    g.cameras.push(camera());
    g.nodes.push(json!({"camera": 0, "translation": [0, 0, 5]}));
    g.lights.push(light);
    g.nodes
        .push(json!({"extensions": {"KHR_lights_punctual": {"light": 0}}}));
    let path = g.write(dir.path(), "w");
    let text = std::fs::read_to_string(&path).expect("read back");
    let mut doc: Value = serde_json::from_str(&text).expect("json");
    doc["textures"] = json!([{"source": 0}]);
    doc["images"] = json!([{"uri": "missing.png"}]);
    std::fs::write(&path, doc.to_string()).expect("rewrite");
    let loaded = load_file(&path).expect("loads despite the texture");
    let fields: Vec<&str> = loaded.warnings.iter().map(|w| w.field.as_str()).collect();
    assert_eq!(
        fields,
        [
            "materials[0]",
            "extensions.KHR_lights_punctual.lights[0].range"
        ]
    );
    assert_eq!(
        loaded.parts.point_lights[0].name, "light2",
        "unnamed light on unnamed node 2"
    );
}

#[test]
fn binary_glb_loads_like_the_json_file() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut g = Gltf::default();
    g.materials.push(pbr(1.0, 0.5));
    let mesh = g.mesh(&shapes::cube(), 0);
    g.nodes.push(json!({"name": "box", "mesh": mesh}));
    g.cameras.push(camera());
    g.nodes.push(json!({"camera": 0, "translation": [0, 0, 5]}));
    let gltf = g.write(dir.path(), "b");
    // The same JSON in a GLB container (its buffer stays the external .bin).
    let mut json = std::fs::read(&gltf).expect("read back");
    json.resize(json.len().next_multiple_of(4), b' ');
    let mut glb = Vec::new();
    for word in [
        0x4654_6C67,
        2,
        20 + json.len() as u32,
        json.len() as u32,
        0x4E4F_534A,
    ] {
        glb.extend(u32::to_le_bytes(word));
    }
    glb.extend(json);
    let glb_path = dir.path().join("b.glb");
    std::fs::write(&glb_path, glb).expect("write glb");
    let (a, b) = (
        load_file(&gltf).expect("gltf"),
        load_file(&glb_path).expect("glb"),
    );
    assert_eq!(a.parts.objects[0].name, b.parts.objects[0].name);
    assert_eq!(a.parts.objects[0].mesh, b.parts.objects[0].mesh);
    assert_eq!(a.parts.materials, b.parts.materials);
}
