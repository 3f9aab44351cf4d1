//! The rays of renders of the shipped scenes (`render_logged` at one
//! sample per pixel): camera and continuation rays (closest hits and their
//! shading points), shadow rays (occlusion), through the lane functions and
//! through the batch API.

use std::path::Path;

use super::{Tally, compare, point_bits};
use crate::ray::Ray;
use crate::scene::Scene;
use crate::simd::{LANES, Lanes, Mask16};
use crate::tracer::{RenderOptions, render_logged};

fn shipped(name: &str) -> Scene {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../scenes")
        .join(name);
    crate::scene::load::load_scene(&path).expect("shipped scene loads")
}

/// `rays` by sixteen (the last packet with fewer lanes active).
fn compare_all<B: Lanes>(k: B, scene: &Scene, rays: &[Ray], tally: &mut Tally) {
    for chunk in rays.chunks(LANES) {
        let lanes = std::array::from_fn(|i| chunk[i.min(chunk.len() - 1)]);
        let active = Mask16::first(chunk.len());
        compare(k, scene.accel(), scene.objects(), &lanes, active, tally);
    }
}

#[test]
fn shipped_scenes_rays_match_the_scalar_walks() {
    fn on<B: Lanes>(k: B) {
        // The Cornell box's static BVH is one node: no ties at all.
        for (name, one_node) in [("cornell-box.toml", true), ("caustic-box.toml", false)] {
            let scene = shipped(name);
            let opts = RenderOptions {
                spp: 1,
                ..RenderOptions::from_scene(&scene)
            };
            let (_, log) = render_logged(&scene, &opts, &|_| {});
            let world = scene.accel().world.as_deref().expect("a static BVH");
            assert_eq!(world.wide.tree.nodes.len() == 1, one_node, "{name}");
            let mut tally = Tally::default();
            let closest: Vec<Ray> = log.camera.iter().chain(&log.bounce).copied().collect();
            compare_all(k, &scene, &closest, &mut tally);
            compare_all(k, &scene, &log.shadow, &mut tally);
            eprintln!("{name}: {tally:?}");
            assert!(
                tally.rays > 30_000 && tally.hits > tally.rays / 2,
                "{name}: {tally:?}"
            );
            assert!(!one_node || tally.sphere_hits > 1000, "{name}: {tally:?}");
            let ties = if one_node { 0 } else { tally.rays / 10_000 };
            assert!(tally.ties <= ties, "{name}: {tally:?}");
            // The batch API, on the same rays.
            let accel = scene.accel();
            let batched = accel.closest_hits(&closest);
            let differ = closest
                .iter()
                .zip(&batched)
                .filter(|(ray, hit)| accel.closest_hit(ray) != **hit)
                .count();
            assert!(differ <= tally.ties, "{name}: {differ} batched hits differ");
            let hits: Vec<_> = batched.into_iter().flatten().collect();
            let points = accel.surface_points(scene.objects(), &hits);
            for (hit, point) in hits.iter().zip(&points) {
                let scalar = accel.surface_point(scene.objects(), hit);
                assert_eq!(point_bits(point), point_bits(&scalar), "{name}: {hit:?}");
            }
            let occluded = accel.occluded_rays(&log.shadow);
            assert!(
                log.shadow
                    .iter()
                    .zip(&occluded)
                    .all(|(r, &o)| accel.occluded(r) == o)
            );
        }
    }
    crate::simd::each_backend!(on);
}
