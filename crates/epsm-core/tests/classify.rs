//! What `classify` makes of each record pattern (docs/design.md §5.4), including
//! the unknown/fixed layout, parameter selection and background endings.

mod common;

use common::{End, Rng, Spec, Synth, Vertex, build, random_params};
use epsm_core::backprop::{PassInput, PassStats, backprop};
use epsm_core::colour::ColourModel;
use epsm_core::loss::{LossEval, MatchGuards};
use epsm_core::paths::{Classified, Node};
use epsm_core::schedule::PathUse;
use epsm_core::{DropReason, PathKind, SolveSettings, classify};
use epsm_render::record::PathRecord;
use glam::{DVec2, Vec3};

fn kinds(spec: &Spec, seed: u64) -> Vec<(PathKind, usize, usize)> {
    let mut rng = Rng::new(seed);
    let mut s = synth(spec, &mut rng);
    random_params(&mut s.table, &s.objects, &s.lights, &mut rng);
    let c = classified(&s);
    assert_eq!(c.skipped.total(), 0);
    c.paths
        .iter()
        .map(|p| {
            let unknown = p
                .nodes
                .iter()
                .filter(|n| {
                    matches!(
                        n,
                        Node::Surface {
                            unknown: Some(_),
                            ..
                        }
                    )
                })
                .count();
            assert_eq!(unknown, p.unknowns(), "one constraint per unknown");
            (p.kind, p.nodes.len(), unknown)
        })
        .collect()
}

#[test]
fn each_record_pattern_yields_its_paths_with_the_right_unknowns() {
    let chain = vec![Vertex::Mirror, Vertex::Glass { ior: 1.5 }];
    let glossy = vec![Vertex::Mirror, Vertex::Glossy { alpha: 0.2 }];
    // camera → S S → D: chain to surface (2 unknowns, D fixed) and the primary path.
    assert_eq!(
        kinds(
            &Spec::new(PathKind::ChainToSurface, chain.clone(), End::Surface),
            1
        ),
        vec![(PathKind::ChainToSurface, 4, 2), (PathKind::Primary, 2, 0)]
    );
    // camera → S S → emitter: chain to a light.
    assert_eq!(
        kinds(
            &Spec::new(PathKind::ChainToLight, chain.clone(), End::Emitter),
            2
        ),
        vec![(PathKind::ChainToLight, 4, 2), (PathKind::Primary, 2, 0)]
    );
    // camera → S S(glossy) ⇢ point light: chain to light through next-event estimation.
    assert_eq!(
        kinds(
            &Spec::new(PathKind::ChainToLight, glossy.clone(), End::PointNee),
            3
        ),
        vec![(PathKind::ChainToLight, 4, 2), (PathKind::Primary, 2, 0)]
    );
    // camera → D → S S → emitter: caustic with D and both S unknown.
    assert_eq!(
        kinds(&Spec::new(PathKind::Caustic, chain, End::Emitter), 4),
        vec![(PathKind::Caustic, 5, 3), (PathKind::Primary, 2, 0)]
    );
    // camera → D → S S(glossy) ⇢ area light.
    assert_eq!(
        kinds(&Spec::new(PathKind::Caustic, glossy, End::AreaNee), 5),
        vec![(PathKind::Caustic, 5, 3), (PathKind::Primary, 2, 0)]
    );
    // camera → D ⇢ occluder ⇢ light: shadow (camera, D, occluder, light).
    assert_eq!(
        kinds(&Spec::new(PathKind::Shadow, Vec::new(), End::PointNee), 6),
        vec![(PathKind::Shadow, 4, 1), (PathKind::Primary, 2, 0)]
    );
}

#[test]
fn background_endings_are_counted_and_untouched_paths_are_not_returned() {
    let mut s = escaping_chain();
    let c = classified(&s);
    assert!(
        c.paths.is_empty(),
        "no parameter is bound: nothing is returned"
    );
    assert_eq!(c.skipped.get(DropReason::NotDifferentiable), 1);
    s.table.add("o0.translate.x").expect("valid key");
    let c = classified(&s);
    assert_eq!(
        c.paths.iter().map(|p| p.kind).collect::<Vec<_>>(),
        vec![PathKind::Primary]
    );
}

#[test]
fn a_path_carries_only_the_parameters_of_what_it_touches() {
    let mut s = synth(
        &Spec::new(PathKind::ChainToSurface, vec![Vertex::Mirror], End::Surface),
        &mut Rng::new(11),
    );
    // Every axis of every object and the camera yaw are bound; the primary
    // path touches one object, the chain three.
    for name in &s.objects {
        for axis in ["x", "y", "z"] {
            s.table
                .add(&format!("{name}.translate.{axis}"))
                .expect("valid key");
        }
    }
    s.table.add("camera.yaw").expect("valid key");
    for p in classified(&s).paths {
        let objects: std::collections::BTreeSet<u32> = p
            .nodes
            .iter()
            .filter_map(|n| match n {
                Node::Surface { anchor, .. } => Some(anchor.object),
                _ => None,
            })
            .collect();
        assert_eq!(p.params.len(), 3 * objects.len() + 1, "{}", p.kind.name());
        for &param in &p.params {
            let key = &s.table.params()[param].key;
            assert!(
                key == "camera.yaw" || objects.iter().any(|o| key.starts_with(&format!("o{o}."))),
                "{key}"
            );
        }
    }
}

#[test]
fn a_record_whose_only_path_is_dropped_still_counts_the_drop_in_the_pass() {
    let mut s = escaping_chain();
    // The parameter drives the surface the chain no longer reaches.
    s.table.add("o1.translate.x").expect("valid key");
    let c = classified(&s);
    assert!(c.paths.is_empty());
    assert_eq!(c.skipped.get(DropReason::NotDifferentiable), 1);
    let (_, stats) = backprop_alone(&s);
    assert_eq!(stats.dropped.get(DropReason::NotDifferentiable), 1);
}

#[test]
fn a_non_finite_shadow_is_dropped_without_silencing_its_pixel() {
    let mut s = synth(
        &Spec::new(PathKind::Shadow, Vec::new(), End::PointNee),
        &mut Rng::new(3),
    );
    s.table.add("o0.translate.x").expect("valid key");
    // A second sample of the pixel reaches the light unblocked: the shadow
    // is a penumbra's, which the umbra guard keeps.
    let mut lit = s.record.clone();
    for c in &mut lit.connections {
        c.occluder = None;
    }
    for c in &mut s.record.connections {
        c.unoccluded = Vec3::NAN;
    }
    let (grad, stats) = backprop_records(&s, &[s.record.clone(), lit]);
    assert_eq!(stats.dropped.get(DropReason::NonFinite), 1);
    assert_eq!(
        stats.solved, 2,
        "both samples' primary paths are still solved"
    );
    assert!(grad.iter().all(|g| g.is_finite()));
}

#[test]
fn a_shadow_deep_in_an_umbra_is_dropped_and_counted() {
    let mut s = synth(
        &Spec::new(PathKind::Shadow, Vec::new(), End::PointNee),
        &mut Rng::new(3),
    );
    s.table.add("o0.translate.x").expect("valid key");
    let shadows = |s: &Synth| {
        let c = classified(s);
        c.paths
            .iter()
            .filter(|p| p.kind == PathKind::Shadow)
            .count()
    };
    assert_eq!(shadows(&s), 1, "the record holds a shadow path");
    // No sample within two pixels reaches the light unblocked: the shadow
    // path is dropped and counted, the primary path still solved.
    let (_, alone) = backprop_alone(&s);
    assert_eq!(alone.dropped.get(DropReason::NotDifferentiable), 1);
    assert_eq!(alone.solved, 1);
    // With a lit sample in the pixel, it is solved.
    let mut lit = s.record.clone();
    for c in &mut lit.connections {
        c.occluder = None;
    }
    let (_, penumbra) = backprop_records(&s, &[s.record.clone(), lit]);
    assert_eq!(penumbra.dropped.get(DropReason::NotDifferentiable), 0);
    assert_eq!(penumbra.solved, 3, "two primary paths and the shadow");
}

/// Backpropagates `s`'s record alone through a loss whose screen-space
/// gradient is one in every pixel (and zero in colour).
fn backprop_alone(s: &Synth) -> (Vec<f64>, PassStats) {
    backprop_records(s, std::slice::from_ref(&s.record))
}

/// Backpropagates `records` (of `s`'s scene) through a loss whose
/// screen-space gradient is one in every pixel (and zero in colour).
fn backprop_records(s: &Synth, records: &[PathRecord]) -> (Vec<f64>, PassStats) {
    let (w, h) = (s.scene.camera().width, s.scene.camera().height);
    let n = (w * h) as usize;
    let loss = LossEval {
        value: 1.0,
        width: w,
        height: h,
        g_rgb: vec![Vec3::ZERO; n],
        g_xy: vec![DVec2::ONE; n],
        matched: None,
        guards: MatchGuards::default(),
    };
    let colour = ColourModel::default();
    let input = PassInput {
        scene: &s.scene,
        table: &s.table,
        colour: &colour,
        loss: &loss,
        spp: 1,
        use_: PathUse::All,
    };
    backprop(&input, records)
}

/// The first path `spec` builds with `rng` (building retries until one fits).
fn synth(spec: &Spec, rng: &mut Rng) -> Synth {
    loop {
        if let Some(s) = build(spec, rng) {
            return s;
        }
    }
}

/// A camera → mirror → surface chain whose record escapes after the mirror
/// instead of reaching the surface D.
fn escaping_chain() -> Synth {
    let mut s = synth(
        &Spec::new(PathKind::ChainToSurface, vec![Vertex::Mirror], End::Surface),
        &mut Rng::new(7),
    );
    s.record.vertices.pop();
    s.record.escaped = Vec3::ONE;
    s
}

/// `s`'s record classified at the table's current values (unit scene radius).
fn classified(s: &Synth) -> Classified {
    let motion = s.table.motion(&s.table.values());
    classify(
        &s.record,
        &s.scene,
        &motion,
        &SolveSettings::for_radius(1.0),
    )
}
