//! Newton agreement on paths traced by the renderer in the shipped scenes
//! (translations and rotations about x and y of every object, point-light and camera
//! moves), per path type; and in one with an exact (ellipsoidal) glass sphere.

use std::path::{Path, PathBuf};

use epsm_core::check::{CheckSettings, check_paths};
use epsm_core::paths::Node;
use epsm_core::{ParamTable, PathKind, classify};
use epsm_render::Scene;
use epsm_render::record::RecordLevel;
use epsm_render::scene::Surface;
use epsm_render::tracer::{PixelSample, RenderOptions, trace_samples};
use epsm_scene::load::load_scene;
use glam::UVec2;

const PER_TYPE: usize = 80;

fn shipped(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../scenes")
        .join(name)
}

fn check_scene(name: &str, expected: &[PathKind]) {
    let scene = load_scene(&shipped(name)).expect("shipped scene loads");
    check_loaded(name, &scene, expected);
}

/// Checks up to `PER_TYPE` paths of each type traced in `scene`, that
/// every `expected` type is there and agrees; returns the paths checked.
fn check_loaded(name: &str, scene: &Scene, expected: &[PathKind]) -> Vec<epsm_core::DiffPath> {
    let mut table = ParamTable::new(scene);
    table.add_default_geometry().expect("default parameters");
    for o in scene.objects() {
        for axis in ["x", "y"] {
            table
                .add(&format!("{}.rotate.{axis}", o.name))
                .expect("rotation");
        }
    }
    table.add("camera.yaw").expect("camera yaw");
    let opts = RenderOptions::from_scene(scene);
    let (w, h) = (scene.camera().width, scene.camera().height);
    let samples: Vec<PixelSample> = (0..3000u32)
        .map(|i| {
            let k = u64::from(i).wrapping_mul(0x9E37_79B9_7F4A_7C15) >> 20;
            PixelSample {
                pixel: UVec2::new((k % u64::from(w)) as u32, ((k >> 16) % u64::from(h)) as u32),
                sample: i % opts.spp,
            }
        })
        .collect();
    let motion = table.motion(&table.values());
    let settings = CheckSettings::for_radius(scene.radius());
    let mut paths = Vec::new();
    let mut count = [0usize; PathKind::ALL.len()];
    for record in trace_samples(scene, &opts, &samples, RecordLevel::Full) {
        for p in classify(&record, scene, &motion, &settings.solve).paths {
            if count[p.kind as usize] < PER_TYPE {
                count[p.kind as usize] += 1;
                paths.push(p);
            }
        }
    }
    let report = check_paths(&paths, &table, &motion, &settings);
    for kind in expected {
        let r = report
            .kinds
            .get(kind)
            .unwrap_or_else(|| panic!("{name}: no {} paths", kind.name()));
        let bad = r.ill_conditioned + r.dropped.total() as usize;
        eprintln!(
            "{name} {}: {} checked, max {:.1e}, bad {bad}",
            kind.name(),
            r.checked(),
            r.max_rel_err()
        );
        assert!(
            r.max_rel_err() <= 1e-6,
            "{name} {}: {:e}",
            kind.name(),
            r.max_rel_err()
        );
        assert!(
            r.max_adjoint_rel_err <= 1e-10,
            "{name} {}: adjoint {:e}",
            kind.name(),
            r.max_adjoint_rel_err
        );
        assert!(
            bad * 20 <= r.checked().max(1),
            "{name} {}: {bad} ill-conditioned or dropped",
            kind.name()
        );
    }
    paths
}

#[test]
fn traced_highlight_paths_agree_with_newton() {
    check_scene(
        "highlight.toml",
        &[
            PathKind::Primary,
            PathKind::ChainToLight,
            PathKind::Caustic,
            PathKind::Shadow,
        ],
    );
}

#[test]
fn traced_mirror_and_glass_paths_agree_with_newton() {
    check_scene(
        "mirror.toml",
        &[PathKind::Primary, PathKind::ChainToSurface],
    );
    check_scene(
        "caustic-box.toml",
        &[
            PathKind::Primary,
            PathKind::ChainToSurface,
            PathKind::Shadow,
        ],
    );
}

#[test]
fn traced_shadow_paths_agree_with_newton() {
    check_scene("shadows.toml", &[PathKind::Primary, PathKind::Shadow]);
}

/// The caustic box with its glass sphere exact, scaled per axis and turned
/// (an ellipsoid): the renderer's sphere records (octahedral coordinates)
/// anchor and differentiate like triangles.
#[test]
fn traced_paths_through_an_exact_glass_ellipsoid_agree_with_newton() {
    let shipped_toml = std::fs::read_to_string(shipped("caustic-box.toml")).expect("readable");
    let tessellated = "shape = \"sphere\"\nsubdivisions = 4\nmaterial = \"glass\"\nscale = 0.3\n";
    assert!(
        shipped_toml.contains(tessellated),
        "caustic-box.toml changed"
    );
    let toml = shipped_toml.replace(
        tessellated,
        "shape = \"sphere\"\nexact = true\nmaterial = \"glass\"\n\
         scale = [0.3, 0.24, 0.36]\nrotate = [{ axis = [1, 1, 0], angle = 35 }]\n",
    );
    let dir = tempfile::tempdir().expect("temporary directory");
    let path = dir.path().join("exact-box.toml");
    std::fs::write(&path, toml).expect("writable");
    let scene = load_scene(&path).expect("the exact scene loads");
    let sphere = scene
        .objects()
        .iter()
        .position(|o| o.surface == Surface::Sphere)
        .expect("an exact sphere") as u32;
    let paths = check_loaded(
        "exact-box",
        &scene,
        &[
            PathKind::Primary,
            PathKind::ChainToSurface,
            PathKind::Shadow,
        ],
    );
    let on_sphere = paths
        .iter()
        .filter(|p| {
            p.nodes
                .iter()
                .any(|n| matches!(n, Node::Surface { anchor, .. } if anchor.object == sphere))
        })
        .count();
    eprintln!(
        "exact-box: {on_sphere} of {} paths touch the sphere",
        paths.len()
    );
    assert!(on_sphere >= 80, "{on_sphere} paths on the sphere");
}

/// The lens: the lamp reaches the floor only through a glass ball, by
/// next-event connections through glass; the caustic paths built from
/// them agree with Newton like those BSDF sampling finds.
#[test]
fn traced_connections_through_glass_agree_with_newton() {
    let scene = load_scene(&shipped("lens-caustic.toml")).expect("shipped scene loads");
    assert!(
        scene.chains_to_lights(),
        "the lens scene connects through glass"
    );
    let opts = RenderOptions::from_scene(&scene);
    let samples: Vec<PixelSample> = (0..2000u32)
        .map(|i| PixelSample {
            pixel: UVec2::new(44 + i % 40, 50 + (i / 40) % 20),
            sample: i % opts.spp,
        })
        .collect();
    let records = trace_samples(&scene, &opts, &samples, RecordLevel::FirstDiffuse);
    let chains: Vec<_> = records.iter().flat_map(|r| &r.chains).collect();
    eprintln!("lens-caustic: {} connections through glass", chains.len());
    assert!(
        chains.len() >= 200,
        "{} connections through glass",
        chains.len()
    );
    for c in &chains {
        assert_eq!(c.connection.vertex, 0, "made at the floor");
        assert_eq!(c.specular.len(), 2, "into the ball and out");
        assert!(c.connection.contribution.max_element() > 0.0);
    }
    check_loaded("lens-caustic", &scene, &[PathKind::Caustic]);
}
