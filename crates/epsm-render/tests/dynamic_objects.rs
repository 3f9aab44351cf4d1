//! Static and dynamic objects: static objects are traced in one world-space
//! BVH, dynamic ones as instances; which path an object takes must not change
//! the image beyond rounding, and moving an object must give the image of a
//! scene built with it in place.

use std::path::PathBuf;

use epsm_render::Scene;
use epsm_render::tracer::{RenderOptions, render};
use epsm_scene::load::{load_parts, load_scene};
use glam::{DAffine3, DVec3};

fn caustic_box() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../scenes/caustic-box.toml")
}

fn image(scene: &Scene) -> Vec<[u32; 3]> {
    let opts = RenderOptions {
        spp: 2,
        ..RenderOptions::from_scene(scene)
    };
    let out = render(scene, &opts, &|_| {});
    out.image
        .pixels
        .iter()
        .map(|p| p.to_array().map(f32::to_bits))
        .collect()
}

#[test]
fn instanced_and_static_objects_render_the_same_image() {
    let path = caustic_box();
    let all_static = load_scene(&path).expect("scene loads");
    let mut dynamic = all_static.clone();
    let ids: Vec<u32> = ["sphere", "floor", "light"]
        .map(|n| dynamic.object_id(n).expect("object exists"))
        .to_vec();
    dynamic.set_dynamic(&ids);
    let (a, b) = (image(&all_static), image(&dynamic));
    assert_eq!(a.len(), b.len(), "pixel counts");
    // Hits agree to rounding: almost every pixel is within 1e-3 relative.
    let close = a
        .iter()
        .zip(&b)
        .filter(|(p, q)| {
            (0..3).all(|c| {
                let (x, y) = (f32::from_bits(p[c]), f32::from_bits(q[c]));
                (x - y).abs() <= 1e-3 * x.abs().max(y.abs()).max(1e-3)
            })
        })
        .count();
    assert!(
        close * 100 >= a.len() * 99,
        "{close} of {} pixels agree",
        a.len()
    );
}

#[test]
fn moving_an_object_gives_the_image_of_a_scene_built_with_it_moved() {
    let path = caustic_box();
    let mut moved = load_scene(&path).expect("scene loads");
    let sphere = moved.object_id("sphere").expect("sphere");
    let place = DAffine3::from_scale_rotation_translation(
        DVec3::splat(0.25),
        glam::DQuat::from_rotation_y(0.4),
        DVec3::new(0.3, 0.25, -0.1),
    );
    // A static object becomes dynamic on its first move.
    moved.set_object_transform(sphere, place);
    let mut parts = load_parts(&path).expect("parts load");
    parts.objects[sphere as usize].world_from_object = place;
    let mut built = Scene::new(parts).expect("scene builds");
    built.set_dynamic(&[sphere]);
    assert!(image(&moved) == image(&built), "images differ");
    assert_eq!(
        moved.accel().stats().triangles,
        built.accel().stats().triangles
    );
}
