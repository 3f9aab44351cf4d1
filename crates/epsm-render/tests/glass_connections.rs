//! Next-event connections through glass (manifold next-event estimation):
//! the same image as BSDF sampling alone, in expectation, with far less
//! noise; off when the scene asks, and only where the scene has glass and
//! an area light.

use std::path::Path;

use epsm_render::Scene;
use epsm_render::film::Image;
use epsm_render::tracer::{RenderOptions, render};
use epsm_scene::load::parts_from_str;

/// A small lamp above a glass ball; the floor under the ball receives the
/// lamp's light through it as a caustic (the camera sees the floor only).
fn lens(manifold_nee: bool) -> Scene {
    let toml = format!(
        r#"
[camera]
origin = [0.0, 0.9, 2.4]
target = [0.0, 0.0, 0.0]
fov = 40.0
resolution = [32, 32]

[render]
max_depth = 6
manifold_nee = {manifold_nee}

[materials.floor_paint]
type = "diffuse"
albedo = [0.6, 0.6, 0.55]

[materials.glass]
type = "dielectric"
ior = 1.5

[materials.lamp_paint]
type = "diffuse"
albedo = [0.0, 0.0, 0.0]

[[objects]]
name = "floor"
shape = "rectangle"
material = "floor_paint"
scale = 4.0
rotate = [{{ axis = [1, 0, 0], angle = -90 }}]

[[objects]]
name = "ball"
shape = "sphere"
exact = true
material = "glass"
scale = 0.25
translate = [0.0, 1.2, 0.0]

[[objects]]
name = "lamp"
shape = "disk"
subdivisions = 32
material = "lamp_paint"
emission = [150.0, 150.0, 150.0]
scale = 0.1
rotate = [{{ axis = [1, 0, 0], angle = 90 }}]
translate = [0.0, 1.8, 0.0]
"#
    );
    Scene::new(parts_from_str(&toml, Path::new("lens.toml")).expect("valid test scene"))
        .expect("scene builds")
}

fn luminance_sum(image: &Image, keep: impl Fn(usize) -> bool) -> f64 {
    image
        .pixels
        .iter()
        .enumerate()
        .filter(|(i, _)| keep(*i))
        .map(|(_, c)| f64::from(c.x + c.y + c.z) / 3.0)
        .sum()
}

#[test]
fn connections_through_glass_give_the_image_of_bsdf_sampling() {
    let (with, without) = (lens(true), lens(false));
    assert!(with.chains_to_lights());
    assert!(!without.chains_to_lights(), "the setting turns them off");
    let chained = render(
        &with,
        &RenderOptions {
            spp: 256,
            ..RenderOptions::from_scene(&with)
        },
        &|_| {},
    );
    let reference = render(
        &without,
        &RenderOptions {
            spp: 16384,
            ..RenderOptions::from_scene(&without)
        },
        &|_| {},
    );
    assert!(chained.counters.chains > 10_000, "{:?}", chained.counters);
    assert_eq!(
        reference.counters.chains + reference.counters.chain_misses,
        0
    );
    // The caustic: the pixels brighter than twice the floor's median in the
    // reference (chosen on the noisier image, the choice would favour its
    // high draws).
    let mut sorted: Vec<f64> = reference
        .image
        .pixels
        .iter()
        .map(|c| f64::from(c.x + c.y + c.z) / 3.0)
        .collect();
    sorted.sort_by(f64::total_cmp);
    let median = sorted[sorted.len() / 2];
    let caustic = |i: usize| {
        let c = reference.image.pixels[i];
        f64::from(c.x + c.y + c.z) / 3.0 > 2.0 * median
    };
    let pixels = (0..reference.image.pixels.len())
        .filter(|i| caustic(*i))
        .count();
    let (a, b) = (
        luminance_sum(&chained.image, caustic),
        luminance_sum(&reference.image, caustic),
    );
    let (all_a, all_b) = (
        luminance_sum(&chained.image, |_| true),
        luminance_sum(&reference.image, |_| true),
    );
    eprintln!(
        "caustic ({pixels} pixels): {a:.3} against {b:.3} ({:+.2} %); image {all_a:.3} against {all_b:.3} ({:+.2} %); {:?}",
        100.0 * (a / b - 1.0),
        100.0 * (all_a / all_b - 1.0),
        chained.counters
    );
    assert!(pixels >= 8, "a caustic of {pixels} pixels");
    // The connections' weights are heavy-tailed near the caustic's folds
    // (1/det → ∞): a few percent between seeds at these sample counts.
    assert!((a / b - 1.0).abs() < 0.08, "caustic {a} against {b}");
    assert!(
        (all_a / all_b - 1.0).abs() < 0.015,
        "image {all_a} against {all_b}"
    );
}
