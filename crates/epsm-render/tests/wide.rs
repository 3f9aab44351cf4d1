//! The wide tracer against the scalar one: every shipped scene's image is
//! the same, byte for byte, whatever the thread count, on every lane
//! backend this CPU has (the portable lanes always; AVX2 and AVX-512 where
//! the CPU has them, and required where `EPSM_REQUIRE_KERNELS` names them).
//! And the batch walks (`Accel::closest_hits`, `occluded_rays`,
//! `surface_points`) against the scalar walks on the rays renders of the
//! shipped scenes cast.

use std::path::Path;

use epsm_render::hit::{SurfacePoint, TexCoords};
use epsm_render::tracer::{Kernel, RenderOptions, render_logged, render_with};
use epsm_render::{Image, Ray, Scene};
use epsm_scene::image_io::write_image;
use epsm_scene::load::load_scene;
use glam::{DVec3, Vec3};

fn scene(name: &str) -> Scene {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../scenes")
        .join(name);
    load_scene(&path).expect("shipped scene loads")
}

/// The wide kernels this CPU runs: the portable one always, AVX2 and
/// AVX-512 where it has them.
fn wide_kernels() -> Vec<Kernel> {
    [Kernel::Avx512, Kernel::Avx2, Kernel::Portable]
        .into_iter()
        .filter(|k| k.available())
        .collect()
}

/// Every wide kernel this CPU advertises runs here (so the comparisons
/// below exercise it), and every kernel named in `EPSM_REQUIRE_KERNELS`
/// (comma-separated, as `avx512,avx2`: what `.ci/run` sets from the CPU's
/// flags) is among them: a machine without a required kernel fails here.
#[test]
fn every_kernel_the_cpu_advertises_runs() {
    let ran: Vec<&str> = wide_kernels().iter().map(|k| k.name()).collect();
    eprintln!("wide kernels compared with the scalar loop: {ran:?}");
    assert!(ran.contains(&"portable"));
    #[cfg(target_arch = "x86_64")]
    {
        use std::arch::is_x86_feature_detected as has;
        let avx512 = has!("avx512f") && has!("avx512vl") && has!("avx512dq") && has!("avx512bw");
        let avx2 = has!("avx2") && has!("bmi1") && has!("bmi2") && has!("lzcnt");
        assert_eq!(ran.contains(&"avx512"), avx512, "{ran:?}");
        assert_eq!(ran.contains(&"avx2"), avx2, "{ran:?}");
    }
    let required = std::env::var("EPSM_REQUIRE_KERNELS").unwrap_or_default();
    for name in required.split(',').map(str::trim).filter(|n| !n.is_empty()) {
        assert!(
            Kernel::ALL.iter().any(|k| k.name() == name),
            "EPSM_REQUIRE_KERNELS names an unknown kernel {name:?}"
        );
        assert!(
            ran.contains(&name),
            "kernel {name} required but not run: {ran:?}"
        );
    }
}

#[test]
fn shipped_scenes_render_the_same_images_wide_and_scalar() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes");
    let mut names: Vec<String> = std::fs::read_dir(&dir)
        .expect("scenes/")
        .filter_map(|e| e.ok())
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .filter(|n| n.ends_with(".toml"))
        .collect();
    names.sort();
    assert!(names.len() >= 8, "{names:?}");
    for name in &names {
        let mut s = scene(name);
        // The wide loop has no connections through glass (scenes with them
        // render with the scalar one): compare the loops without them.
        s.settings_mut().manifold_nee = false;
        assert!(!s.chains_to_lights());
        let opts = RenderOptions {
            spp: 5,
            ..RenderOptions::from_scene(&s)
        };
        let scalar = render_with(&s, &opts, Kernel::Scalar, &|_| {});
        for kernel in wide_kernels() {
            let wide = render_with(&s, &opts, kernel, &|_| {});
            let (a, b) = (&scalar.image, &wide.image);
            let name = format!("{name} ({})", kernel.name());
            assert_eq!((a.width, a.height), (b.width, b.height), "{name}");
            let mut differ = 0;
            for y in 0..a.height {
                for x in 0..a.width {
                    let (p, q) = (a.get(x, y), b.get(x, y));
                    if p.to_array().map(f32::to_bits) != q.to_array().map(f32::to_bits) {
                        if differ < 5 {
                            eprintln!("{name}: pixel ({x}, {y}) {p} scalar, {q} wide");
                        }
                        differ += 1;
                    }
                }
            }
            assert_eq!(differ, 0, "{name}: {differ} pixels differ");
            assert_eq!(scalar.counters, wide.counters, "{name}");
        }
    }
}

/// The bit patterns of a shading point's vectors and texture coordinates.
fn point_bits(p: &SurfacePoint) -> Vec<u32> {
    let uv = match p.uv {
        TexCoords::Uv(uv) => [0.0, uv.x, uv.y, 0.0],
        TexCoords::Sphere(v) => [1.0, v.x, v.y, v.z],
    };
    [p.p, p.ng, p.frame.s, p.frame.t, p.frame.n]
        .iter()
        .flat_map(|v| v.to_array())
        .chain(uv)
        .map(f32::to_bits)
        .collect()
}

/// On the rays of a render of each of two shipped scenes (camera and
/// continuation rays for closest hits, shadow rays for occlusion), the batch
/// walks give the scalar walks' answers: the same occlusion, the same
/// shading points bit for bit, and the same closest hits but for ties (none
/// in the Cornell box, whose static BVH is one node; at most one in 10 000
/// rays in the caustic box).
#[test]
fn shipped_scenes_batched_walks_match_the_scalar_walks() {
    for (name, tie_free) in [("cornell-box.toml", true), ("caustic-box.toml", false)] {
        let scene = scene(name);
        let opts = RenderOptions {
            spp: 1,
            ..RenderOptions::from_scene(&scene)
        };
        let (_, log) = render_logged(&scene, &opts, &|_| {});
        let accel = scene.accel();
        let closest: Vec<Ray> = log.camera.iter().chain(&log.bounce).copied().collect();
        let batched = accel.closest_hits(&closest);
        let hits = batched.iter().flatten().count();
        assert!(
            closest.len() > 50_000 && hits > closest.len() / 2,
            "{name}: {hits} hits of {} rays",
            closest.len()
        );
        let differ = closest
            .iter()
            .zip(&batched)
            .filter(|(ray, hit)| accel.closest_hit(ray) != **hit)
            .count();
        eprintln!(
            "{name}: {} closest-hit rays, {hits} hits, {differ} batched hits differ, {} shadow rays",
            closest.len(),
            log.shadow.len()
        );
        let ties = if tie_free { 0 } else { closest.len() / 10_000 };
        assert!(differ <= ties, "{name}: {differ} batched hits differ");
        let hits: Vec<_> = batched.into_iter().flatten().collect();
        let points = accel.surface_points(scene.objects(), &hits);
        for (hit, point) in hits.iter().zip(&points) {
            let scalar = accel.surface_point(scene.objects(), hit);
            assert_eq!(point_bits(point), point_bits(&scalar), "{name}: {hit:?}");
        }
        assert!(
            log.shadow.len() > 30_000,
            "{name}: {} shadow rays",
            log.shadow.len()
        );
        let occluded = accel.occluded_rays(&log.shadow);
        let differ = (log.shadow.iter().zip(&occluded))
            .filter(|(r, o)| accel.occluded(r) != **o)
            .count();
        assert_eq!(differ, 0, "{name}: {differ} batched occlusions differ");
    }
}

/// Renders `scene` with the scalar and every wide kernel at each of `spps`
/// and asserts the images and counters are the same, byte for byte.
fn assert_same_images(name: &str, scene: &Scene, spps: &[u32]) {
    for &spp in spps {
        let opts = RenderOptions {
            spp,
            ..RenderOptions::from_scene(scene)
        };
        let scalar = render_with(scene, &opts, Kernel::Scalar, &|_| {});
        assert!(scalar.counters.rays > 0);
        for kernel in wide_kernels() {
            let wide = render_with(scene, &opts, kernel, &|_| {});
            let name = format!("{name} ({})", kernel.name());
            assert_eq!(scalar.image.pixels.len(), wide.image.pixels.len(), "{name}");
            let differ = scalar
                .image
                .pixels
                .iter()
                .zip(&wide.image.pixels)
                .filter(|(p, q)| p.to_array().map(f32::to_bits) != q.to_array().map(f32::to_bits))
                .count();
            assert_eq!(differ, 0, "{name}, {spp} spp: {differ} pixels differ");
            assert_eq!(scalar.counters, wide.counters, "{name}, {spp} spp");
        }
    }
}

/// Every material (both sidednesses), light and background kind, textures,
/// interpolated normals, an odd image size (partial tiles), several depths,
/// and objects behind the BVH's top level (dynamic ones and more exact
/// spheres than are listed), moved: the same image from both kernels.
#[test]
fn every_feature_renders_the_same_image_wide_and_scalar() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut sky = Image::new(16, 8);
    for y in 0..8 {
        for x in 0..16 {
            sky.set(
                x,
                y,
                Vec3::new(x as f32 * 0.3, 1.0 + y as f32, 0.5 * (x ^ y) as f32),
            );
        }
    }
    write_image(&dir.path().join("sky.exr"), &sky).expect("env map written");
    let mut checker = Image::new(4, 4);
    for y in 0..4 {
        for x in 0..4 {
            let v = if (x + y) % 2 == 0 { 0.9 } else { 0.1 };
            checker.set(x, y, Vec3::new(v, 0.5, 1.0 - v));
        }
    }
    write_image(&dir.path().join("checker.png"), &checker).expect("texture written");
    for (background, max_depth) in [
        ("envmap = \"sky.exr\"\nscale = 0.5\nrotate = 30", 12),
        ("color = [0.2, 0.3, 0.4]", 1),
        ("color = [0, 0, 0]", 3),
    ] {
        let toml = format!(
            r#"
            [camera]
            origin = [0.3, 0.4, 4]
            target = [0, 0, 0]
            fov = 50
            resolution = [37, 23]
            [render]
            max_depth = {max_depth}
            rr_depth = 2
            seed = 7
            [background]
            {background}
            [materials.white]
            type = "diffuse"
            albedo = [0.8, 0.7, 0.6]
            [materials.both]
            type = "diffuse"
            albedo = [0.3, 0.6, 0.3]
            two_sided = true
            [materials.checker]
            type = "diffuse"
            texture = "checker.png"
            [materials.mirror]
            type = "conductor"
            tint = [0.9, 0.8, 0.7]
            two_sided = true
            [materials.brushed]
            type = "rough_conductor"
            alpha = 0.25
            tint = [0.9, 0.6, 0.3]
            [materials.glass]
            type = "dielectric"
            ior = 1.45
            [[objects]]
            name = "floor"
            shape = "rectangle"
            material = "checker"
            scale = 3
            rotate = [{{ axis = [1, 0, 0], angle = -90 }}]
            translate = [0, -1, 0]
            [[objects]]
            name = "wall"
            shape = "rectangle"
            material = "both"
            scale = 3
            translate = [0, 0, -1.5]
            [[objects]]
            name = "ball"
            shape = "sphere"
            subdivisions = 2
            material = "brushed"
            scale = 0.5
            translate = [-1, -0.4, 0]
            [[objects]]
            name = "glass1"
            shape = "sphere"
            exact = true
            material = "glass"
            scale = [0.4, 0.5, 0.4]
            translate = [0.6, -0.5, 0.3]
            [[objects]]
            name = "glass2"
            shape = "sphere"
            exact = true
            material = "mirror"
            scale = 0.3
            translate = [0, 0.6, 0]
            [[objects]]
            name = "glass3"
            shape = "sphere"
            exact = true
            material = "white"
            scale = 0.2
            translate = [1.2, 0.3, -0.5]
            [[objects]]
            name = "box"
            shape = "cube"
            material = "mirror"
            scale = 0.3
            rotate = [{{ axis = [0, 1, 0], angle = 30 }}]
            translate = [-0.2, -0.7, 0.8]
            [[objects]]
            name = "disk"
            shape = "disk"
            subdivisions = 40
            material = "white"
            emission = [4, 4, 3]
            scale = 0.4
            rotate = [{{ axis = [1, 0, 0], angle = 90 }}]
            translate = [0, 1.4, 0]
            [[objects]]
            name = "panel"
            shape = "rectangle"
            material = "white"
            emission = [2, 1, 1]
            scale = 0.3
            rotate = [{{ axis = [0, 1, 0], angle = 90 }}]
            translate = [-1.8, 0, 0]
            [[lights]]
            type = "point"
            name = "bulb"
            position = [1, 1, 1]
            intensity = [2, 2, 2]
            "#
        );
        let path = dir.path().join("features.toml");
        std::fs::write(&path, toml).expect("scene written");
        let mut scene = load_scene(&path).expect("feature scene loads");
        assert_same_images("features", &scene, &[1, 3, 17]);
        // Objects behind the top level, moved.
        let ids: Vec<_> = ["ball", "box", "panel"]
            .map(|n| scene.object_id(n).expect("object"))
            .to_vec();
        scene.set_dynamic(&ids);
        for (i, &id) in ids.iter().enumerate() {
            let mut t = scene.objects()[id as usize].world_from_object;
            t.translation += DVec3::new(0.1 * i as f64, 0.05, -0.1);
            scene.set_object_transform(id, t);
        }
        assert_same_images("features, moved", &scene, &[4]);
    }
}

/// Many samples per pixel cut each tile into bands of rows, each traced
/// alone (module `tracer::tiles`); an odd image size leaves partial tiles
/// whose last bands hold no pixels: the same image from every kernel.
#[test]
fn tiles_cut_into_bands_render_the_same_image_wide_and_scalar() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/mirror.toml");
    let mut parts = epsm_scene::load::load_parts(&path).expect("shipped scene loads");
    (parts.camera.width, parts.camera.height) = (18, 21);
    let scene = Scene::new(parts).expect("scene builds");
    assert_same_images("mirror, 18x21", &scene, &[128]);
}
