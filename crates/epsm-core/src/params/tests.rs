//! Keys resolve to what they name, bad keys are located errors, and values
//! reach the scene.

use epsm_render::materials::{Bsdf, Texture};
use glam::DVec3;

use super::*;
use crate::testing::scene;

#[test]
fn keys_resolve_and_bad_keys_are_errors_naming_the_key() {
    let s = scene();
    let mut t = ParamTable::new(&s);
    let cases = [
        ("box.translate.z", Target::Translate { object: 0, axis: 2 }),
        ("box.rotate.x", Target::Rotate { object: 0, axis: 0 }),
        ("box.scale", Target::Scale { object: 0 }),
        (
            "lamp.translate.y",
            Target::LightTranslate { light: 0, axis: 1 },
        ),
        ("camera.translate.x", Target::CameraTranslate { axis: 0 }),
        ("camera.pitch", Target::CameraPitch),
        (
            "box.albedo.g",
            Target::Albedo {
                material: 0,
                channel: 1,
            },
        ),
        (
            "paint.albedo.b",
            Target::Albedo {
                material: 0,
                channel: 2,
            },
        ),
    ];
    for (i, (key, target)) in cases.iter().enumerate() {
        assert_eq!(t.add(key), Ok(i));
        assert_eq!(t.params()[i].target, *target, "{key}");
        assert_eq!(t.index(key), Some(i));
    }
    assert_eq!(t.params()[2].value, 1.0, "scale starts at 1");
    assert_eq!(t.params()[6].value, 0.5, "albedo starts at the file value");
    assert_eq!(
        t.add("box.scale"),
        Err(Error::Duplicate("box.scale".into()))
    );
    for bad in [
        "teapot.translate.x",
        "box.wobble",
        "camera.scale",
        "lamp.rotate.x",
        "box",
    ] {
        match t.add(bad) {
            Err(Error::Param { key, .. }) => assert_eq!(key, bad),
            other => panic!("{bad}: {other:?}"),
        }
    }
    let mut d = ParamTable::new(&s);
    d.add_default_geometry().expect("defaults");
    let keys: Vec<&str> = d.params().iter().map(|p| p.key.as_str()).collect();
    assert_eq!(keys.len(), 9);
    assert!(keys.contains(&"lamp.translate.z") && keys.contains(&"camera.translate.y"));
}

#[test]
fn material_and_emission_keys_that_drive_nothing_are_errors() {
    // `box` and `paint` are a diffuse, non-emissive object and material:
    // roughness, IOR and emission keys would be accepted and then ignored.
    let s = scene();
    let mut t = ParamTable::new(&s);
    for (bad, expected) in [
        ("box.alpha", "rough conductor"),
        ("paint.ior", "dielectric"),
        ("box.emission", "emissive"),
    ] {
        match t.add(bad) {
            Err(Error::Param { key, message }) => {
                assert_eq!(key, bad);
                assert!(message.contains(expected), "{bad}: {message}");
            }
            other => panic!("{bad}: {other:?}"),
        }
    }
    assert!(t.is_empty());
}

#[test]
fn apply_writes_transforms_lights_camera_and_colours_into_the_scene() {
    let mut s = scene();
    let mut t = ParamTable::new(&s);
    for key in [
        "box.translate.x",
        "box.rotate.y",
        "lamp.translate.z",
        "camera.translate.y",
        "box.albedo.r",
    ] {
        t.add(key).expect("valid key");
    }
    for (i, v) in [0.25, 30.0, -0.5, 0.125, 0.75].into_iter().enumerate() {
        t.set_value(i, v);
    }
    let eye = s.camera().origin;
    let lamp = s.point_lights()[0].position;
    t.apply(&mut s);
    let m = t.motion(&t.values());
    assert!(
        s.objects()[0]
            .world_from_object
            .abs_diff_eq(m.objects[0].affine(), 1e-15)
    );
    assert!(
        s.point_lights()[0]
            .position
            .abs_diff_eq(lamp + DVec3::new(0.0, 0.0, -0.5), 1e-15)
    );
    assert!(
        s.camera()
            .origin
            .abs_diff_eq(eye + DVec3::new(0.0, 0.125, 0.0), 1e-15)
    );
    let Bsdf::Diffuse(d) = &s.materials()[0].bsdf else {
        panic!("diffuse")
    };
    assert_eq!(d.albedo, Texture::Constant(glam::Vec3::new(0.75, 0.5, 0.5)));
    // The pivot is the centre of the file bounds: rotating keeps it fixed.
    let pivot = t.base.pivots[0];
    assert!(
        m.objects[0]
            .affine()
            .transform_point3(t.base.objects[0].inverse().transform_point3(pivot))
            .abs_diff_eq(pivot + DVec3::X * 0.25, 1e-12)
    );
}

#[test]
fn moving_objects_are_those_with_geometric_parameters() {
    let s = scene();
    let mut t = ParamTable::new(&s);
    t.add("box.albedo.g").expect("colour key");
    t.add("lamp.translate.y").expect("point light key");
    t.add("camera.yaw").expect("camera key");
    assert!(
        t.moving_objects().is_empty(),
        "colours, lights and the camera move no object"
    );
    t.add("box.rotate.y").expect("rotation key");
    assert_eq!(t.moving_objects(), vec![0]);
}
