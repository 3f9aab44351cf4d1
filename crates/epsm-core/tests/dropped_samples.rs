//! Samples the tracer drops (non-finite radiance) reach the derivative side
//! as records marked dropped, and blocked connections whose strength it
//! drops as connections marked so: nothing of them is differentiated, and
//! each is counted once, as `non_finite`, in classification and in the
//! gradient pass alike.

use std::path::Path;

use epsm_core::backprop::{PassInput, PassStats, backprop};
use epsm_core::colour::{ColourModel, PrimaryMotion};
use epsm_core::loss::{LossEval, MatchGuards};
use epsm_core::schedule::PathUse;
use epsm_core::{DropReason, ParamTable, SolveSettings, classify};
use epsm_render::Scene;
use epsm_render::record::{PathRecord, RecordLevel};
use epsm_render::tracer::{RenderOptions, render_recorded};
use epsm_scene::load::parts_from_str;
use epsm_testkit::scenes::{OVERFLOWING_LIGHT, OVERHEAD_CAMERA, WALL_BESIDE_THE_LIGHT};
use glam::{DVec2, Vec3};

/// The scene of the overflowing light with `extra`, the parameter table (a
/// material, the light and the camera) and its records at 2 spp with the
/// number of samples the tracer dropped.
fn traced(extra: &str) -> (Scene, ParamTable, Vec<PathRecord>, u64) {
    let toml = format!("{OVERHEAD_CAMERA}{OVERFLOWING_LIGHT}{extra}");
    let parts = parts_from_str(&toml, Path::new("overflowing.toml")).expect("valid test scene");
    let scene = Scene::new(parts).expect("scene builds");
    let mut table = ParamTable::new(&scene);
    for key in ["floor.albedo.r", "p.translate.x", "camera.translate.y"] {
        table.add(key).expect("valid key");
    }
    let opts = RenderOptions {
        spp: 2,
        ..RenderOptions::from_scene(&scene)
    };
    let (out, records) = render_recorded(&scene, &opts, RecordLevel::Full, &|_| {});
    let dropped = out.counters.non_finite;
    assert!(
        dropped > 0 && dropped < out.samples,
        "some samples dropped, some kept: {dropped} of {}",
        out.samples
    );
    (scene, table, records, dropped)
}

#[test]
fn classify_counts_each_dropped_sample_once_and_builds_nothing_from_it() {
    let (scene, table, records, dropped) = traced("");
    let non_finite = classified_non_finite(&scene, &table, &records);
    assert_eq!(non_finite, dropped);
}

#[test]
fn the_gradient_pass_counts_each_dropped_sample_once() {
    let (scene, table, records, dropped) = traced("");
    let (grad, stats) = gradient_pass(&scene, &table, &records);
    assert_eq!(stats.dropped.get(DropReason::NonFinite), dropped);
    assert!(grad.iter().all(|g| g.is_finite()), "{grad:?}");
}

/// Shadows whose strength overflowed (blocked by the wall) are counted
/// once each, as `non_finite`, by classification and the gradient pass
/// alike, beside the dropped samples, and no classified path holds a
/// non-finite strength.
#[test]
fn shadows_whose_strength_the_tracer_dropped_are_counted_once() {
    let (scene, table, records, dropped) = traced(WALL_BESIDE_THE_LIGHT);
    let non_finite = classified_non_finite(&scene, &table, &records);
    assert!(
        non_finite > dropped,
        "the wall must block overflowing shadows"
    );
    let (grad, stats) = gradient_pass(&scene, &table, &records);
    assert_eq!(stats.dropped.get(DropReason::NonFinite), non_finite);
    assert!(grad.iter().all(|g| g.is_finite()), "{grad:?}");
}

/// How many paths classifying `records` counts as `non_finite`, checking
/// that no path it builds holds a non-finite contribution.
fn classified_non_finite(scene: &Scene, table: &ParamTable, records: &[PathRecord]) -> u64 {
    let motion = table.motion(&table.values());
    let settings = SolveSettings::for_radius(scene.radius());
    let mut non_finite = 0;
    for r in records {
        let c = classify(r, scene, &motion, &settings);
        non_finite += c.skipped.get(DropReason::NonFinite);
        assert!(c.paths.iter().all(|p| p.contribution.is_finite()));
    }
    non_finite
}

/// The gradient pass over `records` with a colour and a position gradient
/// in every pixel.
fn gradient_pass(
    scene: &Scene,
    table: &ParamTable,
    records: &[PathRecord],
) -> (Vec<f64>, PassStats) {
    let colour = ColourModel::new(table, scene, Some(PrimaryMotion::OnCameraRay));
    let (w, h) = (scene.camera().width, scene.camera().height);
    let n = (w * h) as usize;
    let loss = LossEval {
        value: 1.0,
        width: w,
        height: h,
        g_rgb: vec![Vec3::splat(1e-38); n],
        g_xy: vec![DVec2::ONE; n],
        matched: None,
        guards: MatchGuards::default(),
    };
    let input = PassInput {
        scene,
        table,
        colour: &colour,
        loss: &loss,
        spp: 2,
        use_: PathUse::All,
    };
    backprop(&input, records)
}
