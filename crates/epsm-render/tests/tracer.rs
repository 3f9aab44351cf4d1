//! Path tracer correctness: furnace tests, analytic irradiance, determinism
//! and the recording contract.

use std::path::Path;

use epsm_render::Scene;
use epsm_render::record::{RecordLevel, SampleDrop};
use epsm_render::tracer::{RenderOptions, render, render_logged, render_recorded};
use epsm_scene::load::parts_from_str;
use epsm_testkit::scenes::{OVERFLOWING_LIGHT, OVERHEAD_CAMERA, WALL_BESIDE_THE_LIGHT};
use glam::{UVec2, Vec3};

fn scene(toml: &str) -> Scene {
    Scene::new(parts_from_str(toml, Path::new("test.toml")).expect("valid test scene"))
        .expect("scene builds")
}

fn opts(scene: &Scene, spp: u32) -> RenderOptions {
    RenderOptions {
        spp,
        ..RenderOptions::from_scene(scene)
    }
}

fn in_pool<T: Send>(threads: usize, f: impl FnOnce() -> T + Send) -> T {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .expect("thread pool")
        .install(f)
}

/// How the furnace's sphere is made: tessellated, and exact.
const SPHERES: [&str; 2] = ["subdivisions = 4", "exact = true"];

/// A unit-radius object at the origin inside a uniform environment of
/// radiance 0.5, seen from z = 4; `sphere` holds the object's extra keys: its
/// tessellation (one of [`SPHERES`]), maybe a transform.
fn furnace(material: &str, max_depth: u32, sphere: &str) -> Scene {
    scene(&format!(
        r#"
        [camera]
        origin = [0, 0, 4]
        target = [0, 0, 0]
        fov = 30
        resolution = [24, 24]
        [render]
        max_depth = {max_depth}
        [background]
        color = [0.5, 0.5, 0.5]
        [materials.m]
        {material}
        [[objects]]
        name = "ball"
        shape = "sphere"
        {sphere}
        material = "m"
        "#
    ))
}

fn assert_uniform(img: &epsm_render::Image, value: f32, tol: f32) {
    let mean = img.mean();
    for c in [mean.x, mean.y, mean.z] {
        assert!((c - value).abs() <= tol * value, "mean {mean} vs {value}");
    }
}

/// A white diffuse object returns the environment's radiance with any
/// number of scatterings: it is convex, so with one scattering it sees only
/// the environment, and that light counts whether next-event estimation or
/// BSDF sampling after the last scattering finds it (their MIS weights add
/// up to one only if both count).
#[test]
fn furnace_diffuse_white_object_returns_the_environment() {
    for (max_depth, sphere) in [1, 16].into_iter().flat_map(|d| SPHERES.map(|s| (d, s))) {
        let s = furnace("type = \"diffuse\"\nalbedo = [1, 1, 1]", max_depth, sphere);
        let out = render(&s, &opts(&s, 64), &|_| {});
        assert_uniform(&out.image, 0.5, 0.01);
        for p in &out.image.pixels {
            assert!(
                (p.x - 0.5).abs() < 0.05,
                "max depth {max_depth}, {sphere}: pixel {p}"
            );
        }
        assert_eq!(out.counters.non_finite, 0);
    }
}

#[test]
fn furnace_smooth_dielectric_sphere_conserves_energy() {
    for sphere in SPHERES {
        let s = furnace("type = \"dielectric\"\nior = 1.5", 64, sphere);
        let out = render(&s, &opts(&s, 64), &|_| {});
        assert_uniform(&out.image, 0.5, 0.01);
        for p in &out.image.pixels {
            assert!((p.x - 0.5).abs() < 0.06, "{sphere}: pixel {p}");
        }
        assert_eq!(out.counters.non_finite, 0);
    }
}

/// Directional albedo `E(μ = 1, α) = ∫ f·cos dω` of a unit-tint GGX
/// conductor at normal incidence by midpoint quadrature of `eval`.
fn ggx_albedo_at_normal_incidence(alpha: f32) -> f64 {
    use epsm_render::materials::{Bsdf, Material, RoughConductor};
    let m = Material {
        name: "m".into(),
        bsdf: Bsdf::RoughConductor(RoughConductor {
            alpha,
            tint: Vec3::ONE,
        }),
        two_sided: false,
    };
    let (n_theta, n_phi) = (400, 64);
    let mut sum = 0.0f64;
    for i in 0..n_theta {
        let cos_o = (i as f64 + 0.5) / n_theta as f64;
        let sin_o = (1.0 - cos_o * cos_o).sqrt();
        for j in 0..n_phi {
            let phi = std::f64::consts::TAU * (j as f64 + 0.5) / n_phi as f64;
            let wo = glam::DVec3::new(sin_o * phi.cos(), sin_o * phi.sin(), cos_o).as_vec3();
            sum += m.eval(Vec3::Z, wo, glam::Vec2::ZERO).x as f64;
        }
    }
    sum * std::f64::consts::TAU / (n_theta * n_phi) as f64
}

#[test]
fn furnace_ggx_conductor_with_unit_fresnel_stays_below_one_and_matches_the_albedo_table() {
    for alpha in [0.3f32, 0.6, 1.0] {
        let s = furnace(
            &format!("type = \"rough_conductor\"\nalpha = {alpha}\ntint = [1, 1, 1]"),
            16,
            SPHERES[0],
        );
        let out = render(&s, &opts(&s, 256), &|_| {});
        let mean = out.image.mean().x;
        assert!(
            mean <= 0.5 * 1.005,
            "α {alpha}: mean {mean} exceeds the environment"
        );
        // The four centre pixels see the sphere at normal incidence (μ > 0.998).
        let centre = [(11, 11), (12, 11), (11, 12), (12, 12)]
            .iter()
            .map(|&(x, y)| out.image.get(x, y).x as f64)
            .sum::<f64>()
            / 4.0;
        let expected = 0.5 * ggx_albedo_at_normal_incidence(alpha);
        assert!(
            (centre - expected).abs() < 0.02 * expected,
            "α {alpha}: centre {centre} vs table {expected}"
        );
    }
}

/// `G(a, b)`: form factor from a differential area to the rectangle
/// `[0, a] × [0, b]` parallel to it at height `h` (odd in `a` and `b`).
fn corner_form_factor(a: f64, b: f64, h: f64) -> f64 {
    let (ra, rb) = ((a * a + h * h).sqrt(), (b * b + h * h).sqrt());
    (a / ra * (b / ra).atan() + b / rb * (a / rb).atan()) / (2.0 * std::f64::consts::PI)
}

/// Radiance of the floor point below pixel `(x, y)`'s centre for a camera
/// straight above the origin.
fn floor_point(scene: &Scene, x: u32, y: u32) -> Vec3 {
    let r = scene
        .camera()
        .ray(glam::Vec2::new(x as f32 + 0.5, y as f32 + 0.5));
    r.at(-r.origin.y / r.dir.y)
}

#[test]
fn diffuse_plane_under_a_point_light_matches_analytic_irradiance() {
    let s = scene(&format!(
        "{OVERHEAD_CAMERA}\n[[lights]]\ntype = \"point\"\nname = \"p\"\nposition = [0.3, 1.0, 0.2]\nintensity = [2, 2, 2]\n"
    ));
    let out = render(&s, &opts(&s, 16), &|_| {});
    let light = Vec3::new(0.3, 1.0, 0.2);
    for (x, y) in [(0, 0), (8, 8), (15, 3), (4, 12)] {
        let p = floor_point(&s, x, y);
        let d = light - p;
        let expected = 0.5 / std::f32::consts::PI * 2.0 * (d.y / d.length()) / d.length_squared();
        let got = out.image.get(x, y).x;
        assert!(
            (got - expected).abs() < 0.01 * expected,
            "pixel ({x},{y}): {got} vs {expected}"
        );
    }
}

/// The lamp sits off the camera's view axis so that it does not hide the
/// floor points under test.
const LAMP_X: f64 = 0.5;

#[test]
fn small_square_area_light_over_a_plane_matches_the_form_factor() {
    let (half, h, radiance) = (0.1f64, 1.0f64, 20.0f64);
    let s = scene(&format!(
        "{OVERHEAD_CAMERA}\n[[objects]]\nname = \"lamp\"\nshape = \"rectangle\"\nmaterial = \"black\"\nemission = [{radiance}, {radiance}, {radiance}]\nscale = {half}\nrotate = [{{ axis = [1, 0, 0], angle = 90 }}]\ntranslate = [{LAMP_X}, {h}, 0]\n"
    ));
    let out = render(&s, &opts(&s, 256), &|_| {});
    for (x, y) in [(8, 8), (2, 13), (14, 1)] {
        let p = floor_point(&s, x, y).as_dvec3();
        let (x0, x1, z0, z1) = (
            LAMP_X - half - p.x,
            LAMP_X + half - p.x,
            -half - p.z,
            half - p.z,
        );
        let f = corner_form_factor(x1, z1, h)
            - corner_form_factor(x0, z1, h)
            - corner_form_factor(x1, z0, h)
            + corner_form_factor(x0, z0, h);
        let expected = 0.5 * radiance * f;
        let got = out.image.get(x, y).x as f64;
        assert!(
            (got - expected).abs() < 0.01 * expected,
            "pixel ({x},{y}): {got} vs {expected}"
        );
    }
}

fn shipped(name: &str) -> Scene {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../scenes")
        .join(name);
    epsm_scene::load::load_scene(&path).expect("shipped scene loads")
}

#[test]
fn same_seed_gives_bit_identical_images_with_one_and_two_threads() {
    let s = shipped("caustic-box.toml");
    let o = RenderOptions {
        spp: 4,
        ..RenderOptions::from_scene(&s)
    };
    let one = in_pool(1, || render(&s, &o, &|_| {}));
    let two = in_pool(2, || render(&s, &o, &|_| {}));
    assert_eq!(one.image.pixels.len(), two.image.pixels.len());
    assert!(
        one.image
            .pixels
            .iter()
            .zip(&two.image.pixels)
            .all(|(a, b)| a.to_array().map(f32::to_bits) == b.to_array().map(f32::to_bits))
    );
    let other_seed = render(&s, &RenderOptions { seed: 1, ..o }, &|_| {});
    assert_ne!(one.image, other_seed.image);
}

#[test]
fn recording_paths_does_not_change_the_image() {
    for name in ["caustic-box.toml", "shadows.toml", "highlight.toml"] {
        let s = shipped(name);
        let o = RenderOptions {
            spp: 2,
            ..RenderOptions::from_scene(&s)
        };
        let plain = render(&s, &o, &|_| {});
        for level in [
            RecordLevel::Primary,
            RecordLevel::FirstDiffuse,
            RecordLevel::Full,
        ] {
            let (rec, paths) = render_recorded(&s, &o, level, &|_| {});
            assert_eq!(plain.image, rec.image, "{name} at {level:?}");
            assert_eq!(paths.len() as u64, plain.samples);
            // Each record's radiance is what the pixel accumulated.
            let w = s.camera().width;
            let px = |p: UVec2| (p.y * w + p.x) as usize;
            let mut sums = vec![Vec3::ZERO; plain.image.pixels.len()];
            for p in &paths {
                sums[px(p.pixel)] += p.radiance;
            }
            for (sum, pixel) in sums.iter().zip(&plain.image.pixels) {
                assert_eq!(*sum / o.spp as f32, *pixel);
            }
        }
    }
}

#[test]
fn records_hold_what_each_level_promises() {
    let s = shipped("shadows.toml");
    let o = RenderOptions {
        spp: 1,
        ..RenderOptions::from_scene(&s)
    };
    let (_, primary) = render_recorded(&s, &o, RecordLevel::Primary, &|_| {});
    assert!(
        primary
            .iter()
            .all(|p| p.vertices.len() <= 1 && p.connections.is_empty())
    );
    let (_, first) = render_recorded(&s, &o, RecordLevel::FirstDiffuse, &|_| {});
    let blocked: Vec<_> = first
        .iter()
        .flat_map(|p| &p.connections)
        .filter(|c| c.occluder.is_some())
        .collect();
    assert!(
        !blocked.is_empty(),
        "the shadow scene must record blocked connections"
    );
    for c in &blocked {
        let occ = c.occluder.expect("blocked");
        let name = &s.objects()[occ.at.object as usize].name;
        assert!(name.starts_with("occluder_"), "occluder {name}");
        assert_eq!(c.contribution, Vec3::ZERO);
        assert!(c.unoccluded.max_element() > 0.0);
    }
    for p in &first {
        let diffuse_at = p
            .vertices
            .iter()
            .position(|v| v.kind == epsm_render::materials::VertexKind::Diffuse);
        if let Some(i) = diffuse_at {
            assert_eq!(
                i + 1,
                p.vertices.len(),
                "recording stops at the first diffuse vertex"
            );
        }
    }
    let c = shipped("caustic-box.toml");
    let (_, full) = render_recorded(
        &c,
        &RenderOptions {
            spp: 2,
            ..RenderOptions::from_scene(&c)
        },
        RecordLevel::Full,
        &|_| {},
    );
    let caustic = full.iter().any(|p| {
        let kinds: Vec<_> = p.vertices.iter().map(|v| v.kind).collect();
        kinds.first() == Some(&epsm_render::materials::VertexKind::Diffuse)
            && kinds.get(1) == Some(&epsm_render::materials::VertexKind::Specular)
    });
    assert!(
        caustic,
        "full records of the caustic box must contain camera → D → S paths"
    );
}

#[test]
fn a_dropped_sample_has_a_record_that_says_so_and_holds_nothing_else() {
    let s = scene(&format!("{OVERHEAD_CAMERA}{OVERFLOWING_LIGHT}"));
    let o = opts(&s, 2);
    let plain = render(&s, &o, &|_| {});
    let dropped = plain.counters.non_finite;
    assert!(
        dropped > 0 && dropped < plain.samples,
        "the scene must drop some samples and keep others: {dropped} of {}",
        plain.samples
    );
    for level in [
        RecordLevel::Primary,
        RecordLevel::FirstDiffuse,
        RecordLevel::Full,
    ] {
        let (rec, paths) = render_recorded(&s, &o, level, &|_| {});
        assert_eq!(rec.image, plain.image, "{level:?}");
        let marked: Vec<_> = paths.iter().filter(|p| p.dropped.is_some()).collect();
        assert_eq!(marked.len() as u64, dropped, "{level:?}");
        for p in marked {
            assert_eq!(p.dropped, Some(SampleDrop::NonFinite));
            assert!(p.vertices.is_empty() && p.connections.is_empty());
            assert_eq!((p.radiance, p.escaped), (Vec3::ZERO, Vec3::ZERO));
        }
        for p in &paths {
            assert!(p.radiance.is_finite() && p.escaped.is_finite());
            assert!(p.vertices.iter().all(|v| v.contribution.is_finite()));
            assert!(p.connections.iter().all(|c| c.contribution.is_finite()));
        }
    }
}

#[test]
fn a_blocked_connection_whose_strength_is_not_finite_is_marked_and_holds_zero() {
    let s = scene(&format!(
        "{OVERHEAD_CAMERA}{OVERFLOWING_LIGHT}{WALL_BESIDE_THE_LIGHT}"
    ));
    let o = opts(&s, 2);
    let plain = render(&s, &o, &|_| {});
    for level in [RecordLevel::FirstDiffuse, RecordLevel::Full] {
        let (rec, paths) = render_recorded(&s, &o, level, &|_| {});
        assert_eq!(rec.image, plain.image, "{level:?}");
        let connections: Vec<_> = paths.iter().flat_map(|p| &p.connections).collect();
        let marked: Vec<_> = connections.iter().filter(|c| c.dropped.is_some()).collect();
        assert!(
            !marked.is_empty(),
            "{level:?}: the wall must block overflowing shadows"
        );
        for c in marked {
            assert_eq!(c.dropped, Some(SampleDrop::NonFinite));
            assert!(c.occluder.is_some());
            assert_eq!((c.contribution, c.unoccluded), (Vec3::ZERO, Vec3::ZERO));
        }
        assert!(
            connections
                .iter()
                .any(|c| c.occluder.is_some() && c.dropped.is_none())
        );
        assert!(
            connections.iter().all(|c| c.unoccluded.is_finite()),
            "{level:?}"
        );
    }
}

#[test]
fn logging_rays_does_not_change_the_image_and_logs_every_ray_the_render_counts() {
    let s = shipped("caustic-box.toml");
    let o = RenderOptions {
        spp: 2,
        ..RenderOptions::from_scene(&s)
    };
    let plain = render(&s, &o, &|_| {});
    let (logged, log) = render_logged(&s, &o, &|_| {});
    assert_eq!(plain.image, logged.image);
    assert_eq!(plain.counters, logged.counters);
    // One camera ray per sample; the other closest-hit rays are
    // continuations, each starting where a path's previous ray ended.
    assert_eq!(log.camera.len() as u64, plain.samples);
    assert_eq!(
        (log.camera.len() + log.bounce.len()) as u64,
        plain.counters.rays
    );
    assert_eq!(log.shadow.len() as u64, plain.counters.shadow_rays);
    assert!(log.bounce.len() > log.camera.len());
    let camera_origin = s.camera().film_rays().ray(glam::Vec2::splat(64.0)).origin;
    assert!(log.camera.iter().all(|r| r.origin == camera_origin));
    // The box is closed: every camera and continuation ray hits something,
    // and shadow rays end short of the light (t_max < 1 along y − origin).
    let accel = s.accel();
    assert!(
        log.bounce
            .iter()
            .take(2000)
            .all(|r| accel.closest_hit(r).is_some())
    );
    assert!(log.shadow.iter().all(|r| r.t_max < 1.0 && r.t_max > 0.99));
    // Shadow rays start on surfaces inside the box and mostly reach the light.
    let blocked = log.shadow.iter().filter(|r| accel.occluded(r)).count();
    assert!(
        blocked * 10 < log.shadow.len(),
        "{blocked} of {}",
        log.shadow.len()
    );
}

/// A vertex recorded on an exact sphere names its point by octahedral
/// coordinates (triangle 0) that place it where the path scattered, and its
/// normals are the placed sphere's.
#[test]
fn records_on_exact_spheres_name_the_scattering_point() {
    let s = furnace(
        "type = \"dielectric\"",
        8,
        "exact = true\nscale = [1.0, 0.7, 0.5]\nrotate = [{ axis = [1, 1, 0], angle = 40 }]\n\
         translate = [0.1, 0.0, 0.2]",
    );
    let o = RenderOptions {
        spp: 2,
        ..RenderOptions::from_scene(&s)
    };
    let (_, paths) = render_recorded(&s, &o, RecordLevel::Full, &|_| {});
    let w = s.objects()[0].world_from_object;
    let normal_from_object = w.matrix3.inverse().transpose();
    let mut checked = 0;
    for v in paths.iter().flat_map(|p| &p.vertices) {
        assert_eq!((v.at.object, v.at.triangle), (0, 0));
        let local = epsm_render::sphere::point([f64::from(v.at.b1), f64::from(v.at.b2)]);
        let p = w.transform_point3(local);
        assert!(p.distance(v.p.as_dvec3()) < 1e-5, "{p} vs {}", v.p);
        let n = (normal_from_object * local).normalize();
        assert!(n.dot(v.ns.as_dvec3()) > 1.0 - 1e-6 && n.dot(v.ng.as_dvec3()) > 1.0 - 1e-6);
        checked += 1;
    }
    assert!(checked > 500, "{checked} vertices on the sphere");
}
