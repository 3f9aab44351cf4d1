//! The L2 gradient of colour parameters against central finite differences
//! of the L2 loss itself, rendered at many samples per pixel.
//!
//! The analytic side is what an L2 iteration computes: recorded paths, the
//! colour model with the pixel's vertex on its camera ray
//! ([`PrimaryMotion::OnCameraRay`]), [`backprop`]. The finite difference
//! re-renders the image at `θ ± h` with the same seeds (common random
//! numbers), so the difference sees everything that changes: sampled
//! directions moving with the roughness, Fresnel weights, emission, every
//! bounce, and both next-event and BSDF-sampled light. Russian roulette is
//! off (`rr_depth` above `max_depth`) so that no path's length depends on
//! θ; each scene keeps its moving effects clear of silhouettes and shadow
//! edges, where the L2 colour derivative (an interior term) does not look.
//! The IOR acts twice: through the Fresnel weights (the glass scene, one
//! interface before a uniform emitter, where nothing else changes with
//! it) and by turning the refracted rays, which moves the vertices behind
//! the glass across a floor whose lighting varies (the slab scene). The
//! slab's background is black: a path reflected toward a bright background
//! carries the weight `(∂F/∂η)/F ≈ 3` on both sides of the difference (a
//! lobe flip under common random numbers, a large detached-sampling term
//! in the analytic sum), which makes both estimates noisy by a few percent
//! at these sample counts without changing what they estimate.
//!
//! | scene | parameters | paths |
//! |---|---|---|
//! | glossy | backdrop albedo, sphere GGX α, lamp emission | the backdrop directly and in a rough silver sphere, the lamp only in reflections, interreflection with the floor |
//! | glass | block IOR | a glass block filling the view, an emitting wall inside it: the Fresnel weights of the refraction into the block and of the reflection off it |
//! | slab | slab IOR | a thick tilted glass slab filling the view over a floor lit by a point light below it: two refractions turn with the IOR, and the floor's light reflected back to it by the slab (indirect) |
//! | mirror and glass | point light x and y | the floor directly, in a mirror and through a glass slab (vertices on the camera's scattered rays) |

use std::path::Path;

use epsm_core::ParamTable;
use epsm_core::backprop::{PassInput, backprop, record_level};
use epsm_core::colour::{ColourModel, PrimaryMotion};
use epsm_core::loss::{LossKind, evaluate};
use epsm_core::schedule::PathUse;
use epsm_render::tracer::{RenderOptions, render, render_recorded};
use epsm_render::{Image, Scene};
use epsm_scene::load::parts_from_str;

/// Independent renders (seeds) averaged into one image.
const CHUNKS: u32 = 16;

const GLOSSY: &str = r#"
[camera]
origin = [0.0, 1.0, 3.2]
target = [0.0, 0.7, 0.0]
fov = 40.0
resolution = [20, 20]

[render]
max_depth = 4
rr_depth = 16

[background]
color = [0.05, 0.05, 0.06]

[materials.backdrop]
type = "diffuse"
albedo = [0.6, 0.5, 0.4]

[materials.floor]
type = "diffuse"
albedo = [0.5, 0.5, 0.5]

[materials.silver]
type = "rough_conductor"
alpha = 0.3
tint = [0.9, 0.9, 0.9]

[materials.lamp]
type = "diffuse"
albedo = [0.0, 0.0, 0.0]

[[objects]]
name = "floor"
shape = "rectangle"
material = "floor"
scale = 4.0
rotate = [{ axis = [1, 0, 0], angle = -90 }]

[[objects]]
name = "backdrop"
shape = "rectangle"
material = "backdrop"
scale = 4.0
translate = [0.0, 2.0, -1.5]

[[objects]]
name = "sphere"
shape = "sphere"
exact = true
material = "silver"
scale = 0.6
translate = [0.0, 0.6, 0.0]

[[objects]]
name = "lamp"
shape = "rectangle"
material = "lamp"
emission = [8.0, 8.0, 8.0]
scale = 0.5
rotate = [{ axis = [1, 0, 0], angle = 90 }]
translate = [0.8, 2.5, 1.5]
"#;

const GLASS: &str = r#"
[camera]
origin = [0.0, 0.0, 3.0]
target = [0.0, 0.0, 0.0]
fov = 30.0
resolution = [20, 20]

[render]
max_depth = 8
rr_depth = 16

[background]
color = [0.2, 0.2, 0.2]

[materials.glass]
type = "dielectric"
ior = 1.5

[materials.lamp]
type = "diffuse"
albedo = [0.0, 0.0, 0.0]

[[objects]]
name = "block"
shape = "cube"
material = "glass"
scale = [4.0, 4.0, 1.0]
rotate = [{ axis = [0, 1, 0], angle = 35 }]
translate = [0.0, 0.0, -1.0]

[[objects]]
name = "wall"
shape = "rectangle"
material = "lamp"
emission = [1.0, 0.8, 0.6]
scale = 20.0
translate = [0.0, 0.0, -1.2]
"#;

const MIRROR_GLASS: &str = r#"
[camera]
origin = [0.0, 1.2, 3.0]
target = [0.0, 0.3, -0.5]
fov = 45.0
resolution = [20, 20]

[render]
max_depth = 6
rr_depth = 16

[background]
color = [0.0, 0.0, 0.0]

[materials.floor]
type = "diffuse"
albedo = [0.6, 0.6, 0.6]

[materials.mirror]
type = "conductor"
tint = [0.9, 0.9, 0.9]

[materials.glass]
type = "dielectric"
ior = 1.5

[[objects]]
name = "floor"
shape = "rectangle"
material = "floor"
scale = 6.0
rotate = [{ axis = [1, 0, 0], angle = -90 }]

[[objects]]
name = "mirror"
shape = "rectangle"
material = "mirror"
scale = [0.9, 0.6, 1.0]
rotate = [{ axis = [0, 1, 0], angle = -20 }]
translate = [0.5, 0.55, -1.2]

[[objects]]
name = "slab"
shape = "cube"
material = "glass"
scale = [0.5, 0.15, 0.05]
rotate = [{ axis = [1, 0, 0], angle = 20 }]
translate = [-0.2, 0.6, 2.0]

[[lights]]
name = "bulb"
type = "point"
position = [0.0, 1.0, 1.2]
intensity = [3.0, 3.0, 3.0]
"#;

const SLAB: &str = r#"
[camera]
origin = [0.0, 3.0, 0.8]
target = [0.0, 0.0, 0.0]
fov = 20.0
resolution = [20, 20]

[render]
max_depth = 8
rr_depth = 16

[background]
color = [0.0, 0.0, 0.0]

[materials.floor]
type = "diffuse"
albedo = [0.7, 0.7, 0.7]

[materials.glass]
type = "dielectric"
ior = 1.5

[[objects]]
name = "floor"
shape = "rectangle"
material = "floor"
scale = 20.0
rotate = [{ axis = [1, 0, 0], angle = -90 }]

[[objects]]
name = "slab"
shape = "cube"
material = "glass"
scale = [5.0, 0.6, 5.0]
rotate = [{ axis = [1, 0, 0], angle = 25 }]
translate = [0.0, 1.6, 0.0]

[[lights]]
name = "bulb"
type = "point"
position = [0.3, 0.4, -0.2]
intensity = [2.0, 2.0, 2.0]
"#;

/// A scene, its parameters at their file values, and the target's offset.
struct Case {
    name: &'static str,
    scene: &'static str,
    keys: &'static [&'static str],
    /// The target is rendered at the file values plus these.
    offsets: &'static [f64],
    /// Central-difference step of each parameter.
    steps: &'static [f64],
    spp: u32,
}

struct Setup {
    scene: Scene,
    table: ParamTable,
    base: Vec<f64>,
}

impl Setup {
    fn new(case: &Case) -> Self {
        let file = Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("{}.toml", case.name));
        let parts = parts_from_str(case.scene, &file).expect("scene parses");
        let scene = Scene::new(parts).expect("scene builds");
        let mut table = ParamTable::new(&scene);
        for key in case.keys {
            table.add(key).expect("valid key");
        }
        let base = table.values();
        Self { scene, table, base }
    }

    fn set(&mut self, theta: &[f64]) {
        for (k, v) in theta.iter().enumerate() {
            self.table.set_value(k, *v);
        }
        self.table.apply(&mut self.scene);
    }

    fn options(&self, spp: u32, chunk: u32) -> RenderOptions {
        RenderOptions {
            spp,
            seed: 0x5eed + chunk,
            ..RenderOptions::from_scene(&self.scene)
        }
    }

    /// The mean of [`CHUNKS`] independent renders at `theta`.
    fn image(&mut self, theta: &[f64], spp: u32) -> Image {
        self.set(theta);
        let chunk = |c| render(&self.scene, &self.options(spp, c), &|_| {}).image;
        let mut mean = chunk(0);
        for c in 1..CHUNKS {
            let img = chunk(c);
            assert_eq!(mean.pixels.len(), img.pixels.len());
            for (a, b) in mean.pixels.iter_mut().zip(&img.pixels) {
                *a += *b;
            }
        }
        let n = CHUNKS as f32;
        mean.pixels.iter_mut().for_each(|c| *c /= n);
        mean
    }
}

/// The optimizer's L2 loss of `image` against `target`.
fn l2(image: &Image, target: &Image) -> epsm_core::loss::LossEval {
    evaluate(LossKind::L2, image, target, 1.0, None).expect("finite images of one size")
}

/// The analytic L2 gradient at the file values and the central difference
/// of the loss, per parameter; prints both and returns the relative errors.
fn compare(case: &Case) -> Vec<f64> {
    let mut s = Setup::new(case);
    let base = s.base.clone();
    let truth: Vec<f64> = base.iter().zip(case.offsets).map(|(b, o)| b + o).collect();
    let target = s.image(&truth, 4 * case.spp);
    let image = s.image(&base, case.spp);
    s.set(&base);
    // ∂L/∂c per pixel of each chunk's image (the image is their mean).
    let mut loss = l2(&image, &target);
    let n = CHUNKS as f32;
    loss.g_rgb.iter_mut().for_each(|g| *g /= n);
    let colour = ColourModel::new(&s.table, &s.scene, Some(PrimaryMotion::OnCameraRay));
    let level = record_level(&s.table, &s.scene, &colour, PathUse::ColourOnly);
    let mut analytic = vec![0.0; base.len()];
    let (mut dropped, mut traced) = (0, 0);
    for chunk in 0..CHUNKS {
        let opts = s.options(case.spp, chunk);
        let (_, records) = render_recorded(&s.scene, &opts, level, &|_| {});
        let input = PassInput {
            scene: &s.scene,
            table: &s.table,
            colour: &colour,
            loss: &loss,
            spp: case.spp,
            use_: PathUse::ColourOnly,
        };
        let (g, stats) = backprop(&input, &records);
        assert_eq!(g.len(), analytic.len());
        analytic.iter_mut().zip(&g).for_each(|(a, b)| *a += b);
        dropped += stats.dropped.total();
        traced += stats.traced;
    }
    let mut errors = Vec::new();
    for (k, key) in case.keys.iter().enumerate() {
        let h = case.steps[k];
        let mut at = |x: f64| {
            let mut t = base.clone();
            t[k] = x;
            l2(&s.image(&t, case.spp), &target).value
        };
        let fd = (at(base[k] + h) - at(base[k] - h)) / (2.0 * h);
        let error = ((analytic[k] - fd) / fd).abs();
        eprintln!(
            "{}: {key}: analytic {:.6e}, central difference {fd:.6e}, relative error {error:.2e}",
            case.name, analytic[k]
        );
        errors.push(error);
    }
    s.set(&base);
    // Guards drop the few terms they cannot differentiate (a refraction
    // within a hair of the critical angle), and count them.
    eprintln!("{}: {dropped} of {traced} paths dropped", case.name);
    assert!(
        dropped * 1000 <= traced,
        "{}: {dropped} of {traced} paths dropped",
        case.name
    );
    errors
}

fn check(case: &Case) {
    let errors = compare(case);
    for (key, e) in case.keys.iter().zip(&errors) {
        assert!(*e < 1e-2, "{}: {key}: relative error {e:.2e}", case.name);
    }
}

#[test]
fn albedo_roughness_and_emission_through_glossy_reflection() {
    check(&Case {
        name: "glossy",
        scene: GLOSSY,
        keys: &["backdrop.albedo.r", "sphere.alpha", "lamp.emission"],
        offsets: &[-0.3, -0.15, 0.5],
        steps: &[1e-2, 3e-2, 2e-1],
        spp: 256,
    });
}

#[test]
fn ior_through_refraction_and_reflection() {
    check(&Case {
        name: "glass",
        scene: GLASS,
        keys: &["block.ior"],
        offsets: &[0.3],
        steps: &[2e-2],
        spp: 64,
    });
}

#[test]
fn ior_turning_the_rays_through_a_slab() {
    check(&Case {
        name: "slab",
        scene: SLAB,
        keys: &["slab.ior"],
        offsets: &[0.3],
        steps: &[1e-1],
        spp: 256,
    });
}

#[test]
fn point_light_motion_seen_in_a_mirror_and_through_glass() {
    check(&Case {
        name: "mirror and glass",
        scene: MIRROR_GLASS,
        keys: &["bulb.translate.x", "bulb.translate.y"],
        offsets: &[0.3, -0.2],
        steps: &[1e-3, 1e-3],
        spp: 64,
    });
}
