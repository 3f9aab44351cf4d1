//! Samples the tracer drops (non-finite radiance) reach the derivative side
//! as records marked dropped: nothing of them is differentiated, and each
//! is counted once, as `non_finite`, in classification and in the gradient
//! pass alike.

use std::path::Path;

use epsm_core::backprop::{PassInput, backprop};
use epsm_core::colour::{ColourModel, PrimaryMotion};
use epsm_core::loss::LossEval;
use epsm_core::schedule::PathUse;
use epsm_core::{DropReason, ParamTable, SolveSettings, classify};
use epsm_render::Scene;
use epsm_render::record::{PathRecord, RecordLevel};
use epsm_render::scene::load::parts_from_str;
use epsm_render::tracer::{RenderOptions, render_recorded};
use epsm_testkit::scenes::{OVERFLOWING_LIGHT, OVERHEAD_CAMERA};
use glam::{DVec2, Vec3};

/// The scene, the parameter table (a material, the light and the camera)
/// and its records at 2 spp with the number of samples the tracer dropped.
fn traced() -> (Scene, ParamTable, Vec<PathRecord>, u64) {
    let toml = format!("{OVERHEAD_CAMERA}{OVERFLOWING_LIGHT}");
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
    let (scene, table, records, dropped) = traced();
    let motion = table.motion(&table.values());
    let settings = SolveSettings::for_radius(scene.radius());
    let mut non_finite = 0;
    for r in &records {
        let c = classify(r, &scene, &motion, &settings);
        non_finite += c.skipped.get(DropReason::NonFinite);
        assert!(c.paths.iter().all(|p| p.contribution.is_finite()));
    }
    assert_eq!(non_finite, dropped);
}

#[test]
fn the_gradient_pass_counts_each_dropped_sample_once() {
    let (scene, table, records, dropped) = traced();
    let colour = ColourModel::new(&table, &scene, Some(PrimaryMotion::OnCameraRay));
    let (w, h) = (scene.camera().width, scene.camera().height);
    let n = (w * h) as usize;
    let loss = LossEval {
        value: 1.0,
        width: w,
        height: h,
        g_rgb: vec![Vec3::splat(1e-38); n],
        g_xy: vec![DVec2::ONE; n],
        matched: None,
    };
    let input = PassInput {
        scene: &scene,
        table: &table,
        colour: &colour,
        loss: &loss,
        spp: 2,
        use_: PathUse::All,
    };
    let (grad, stats) = backprop(&input, &records);
    assert_eq!(stats.dropped.get(DropReason::NonFinite), dropped);
    assert!(grad.iter().all(|g| g.is_finite()), "{grad:?}");
}
