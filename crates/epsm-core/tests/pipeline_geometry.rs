//! The full-pipeline gradient of geometric parameters with the L2 loss
//! (colour derivatives only, the pixel's vertex on its camera ray) against
//! finite differences of the loss, on a smooth problem: a floor that fills
//! the view under a point light, nothing that casts a shadow or shows an
//! edge, so the interior term is the whole derivative. (An area light seen
//! by BSDF sampling makes the loss at fixed random numbers jump where its
//! edge crosses a sampled ray; the colour tests cover area lights.)

use std::path::Path;

use epsm_core::problem::problem_from_str;
use epsm_core::{Method, Optimization};

const SMOOTH: &str = r#"
[scene.camera]
origin = [0.0, 2.0, 1.5]
target = [0.0, 0.0, 0.0]
fov = 40.0
resolution = [32, 32]

[scene.render]
max_depth = 2

[scene.background]
color = [0.0, 0.0, 0.0]

[scene.materials.floor]
type = "diffuse"
albedo = [0.7, 0.6, 0.5]

[scene.materials.lamp]
type = "diffuse"
albedo = [0.0, 0.0, 0.0]

[[scene.objects]]
name = "floor"
shape = "rectangle"
material = "floor"
scale = 20.0
rotate = [{ axis = [1, 0, 0], angle = -90 }]

[[scene.lights]]
type = "point"
name = "bulb"
position = [-0.5, 1.0, 0.5]
intensity = [0.6, 0.6, 0.6]

[target]
spp = 16

[loss]
kind = "l2"
match_resolution = [32, 32]

[optimizer]
iterations = 10

[render]
spp_primal = 2
spp_grad = 32
"#;

/// `dL/dθ` from the pipeline and the central difference of the loss (its
/// render has its own random numbers, common to both sides) for `key`,
/// initial value `initial`, true value 0.
fn gradient_and_difference(key: &str, initial: f64, h: f64) -> (f64, f64) {
    let text =
        format!("{SMOOTH}\n[[parameters]]\nkey = \"{key}\"\ninitial = {initial}\ntrue = 0.0\n");
    let file = Path::new(env!("CARGO_MANIFEST_DIR")).join("smooth.toml");
    let mut p = problem_from_str(&text, &file).expect("problem loads");
    p.optimizer.method = Method::L2;
    let mut opt = Optimization::new(p).expect("setup");
    let g = opt.gradient().expect("gradient").0.grad[0];
    let mut loss_at = |v: f64| {
        opt.set_theta(&[v]);
        opt.gradient().expect("loss").0.loss.value
    };
    let fd = (loss_at(initial + h) - loss_at(initial - h)) / (2.0 * h);
    eprintln!("{key}: pipeline {g:.4e}, finite difference {fd:.4e}");
    (g, fd)
}

fn assert_agree(key: &str, initial: f64, h: f64) {
    let (g, fd) = gradient_and_difference(key, initial, h);
    assert!(
        fd.abs() > 0.0 && g.signum() == fd.signum(),
        "{key}: {g} vs {fd}"
    );
    assert!((g - fd).abs() < 0.02 * fd.abs(), "{key}: {g} vs {fd}");
}

#[test]
fn point_light_and_floor_tilt() {
    assert_agree("bulb.translate.z", -0.4, 1e-3);
    assert_agree("bulb.translate.y", 0.3, 1e-3);
    assert_agree("floor.rotate.x", 8.0, 0.05);
}

#[test]
fn camera_pose() {
    assert_agree("camera.yaw", 5.0, 0.05);
    assert_agree("camera.pitch", -4.0, 0.05);
    assert_agree("camera.translate.x", 0.3, 1e-3);
}
