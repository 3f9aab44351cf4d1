//! Newton agreement for every path type on random configurations (docs/design.md §7):
//! random triangles or exact spheres (non-uniformly scaled: ellipsoids),
//! file transforms, orientations, IORs, roughness samples and parameter
//! kinds (translation, rotation, scale, light, camera).

mod common;

use common::{End, Rng, Spec, Vertex, build, check_kind, random_params};
use epsm_core::PathKind;
use epsm_core::check::{CheckReport, CheckSettings};

const CONFIGS: usize = 1000;

fn random_vertex(rng: &mut Rng) -> Vertex {
    match rng.below(3) {
        0 => Vertex::Mirror,
        1 => Vertex::Glass {
            ior: rng.range(1.1, 2.4),
        },
        _ => Vertex::Glossy {
            alpha: rng.range(0.02, 0.6),
        },
    }
}

fn random_spec(kind: PathKind, spheres: bool, rng: &mut Rng) -> Spec {
    let len = 1 + rng.below(3);
    let mut chain: Vec<Vertex> = (0..len).map(|_| random_vertex(rng)).collect();
    let end = match (kind, rng.below(3)) {
        (PathKind::ChainToSurface, _) => End::Surface,
        (PathKind::Shadow, e) => [End::AreaNee, End::PointNee][e % 2],
        (_, 0) => End::Emitter,
        (_, e) => {
            *chain.last_mut().expect("non-empty") = Vertex::Glossy {
                alpha: rng.range(0.02, 0.6),
            };
            [End::AreaNee, End::PointNee][e % 2]
        }
    };
    let mut spec = Spec::new(kind, chain, end);
    spec.smooth = rng.below(4) != 0;
    spec.spheres = spheres;
    spec
}

/// Builds `CONFIGS` configurations with paths of `kind` (the primary paths
/// come from caustic records), on exact spheres with `spheres`, and checks
/// them.
fn agreement(kind: PathKind, spheres: bool, seed: u64) -> CheckReport {
    let mut rng = Rng::new(seed);
    let settings = CheckSettings::for_radius(1.0);
    let mut report = CheckReport::default();
    let mut configs = 0;
    while configs < CONFIGS {
        let spec_kind = if kind == PathKind::Primary {
            PathKind::Caustic
        } else {
            kind
        };
        let spec = random_spec(spec_kind, spheres, &mut rng);
        let Some(mut s) = build(&spec, &mut rng) else {
            continue;
        };
        random_params(&mut s.table, &s.objects, &s.lights, &mut rng);
        configs += check_kind(&s, kind, &settings, &mut report).min(1);
    }
    report
}

fn assert_agreement(kind: PathKind, spheres: bool, seed: u64) {
    let report = agreement(kind, spheres, seed);
    let r = &report.kinds[&kind];
    eprintln!(
        "{}{}: checked {} median {:.2e} max {:.2e} adjoint {:.2e} ill {} dropped {:?}",
        kind.name(),
        if spheres { " (spheres)" } else { "" },
        r.checked(),
        r.median_rel_err(),
        r.max_rel_err(),
        r.max_adjoint_rel_err,
        r.ill_conditioned,
        r.dropped.nonzero().collect::<Vec<_>>()
    );
    assert!(r.checked() + r.dropped.total() as usize >= CONFIGS);
    assert!(
        r.max_rel_err() <= 1e-6,
        "{}: max relative error {:e}",
        kind.name(),
        r.max_rel_err()
    );
    assert!(
        r.max_adjoint_rel_err <= 1e-10,
        "{}: adjoint {:e}",
        kind.name(),
        r.max_adjoint_rel_err
    );
    let bad = r.ill_conditioned + r.dropped.total() as usize;
    assert!(
        bad * 50 <= CONFIGS,
        "{}: {bad} ill-conditioned or dropped",
        kind.name()
    );
}

#[test]
fn primary_paths_agree_with_newton() {
    assert_agreement(PathKind::Primary, false, 1);
}

#[test]
fn chains_to_surfaces_agree_with_newton() {
    assert_agreement(PathKind::ChainToSurface, false, 2);
}

#[test]
fn chains_to_lights_agree_with_newton() {
    assert_agreement(PathKind::ChainToLight, false, 3);
}

#[test]
fn caustics_agree_with_newton() {
    assert_agreement(PathKind::Caustic, false, 4);
}

#[test]
fn shadows_agree_with_newton() {
    assert_agreement(PathKind::Shadow, false, 5);
}

#[test]
fn primary_paths_on_spheres_agree_with_newton() {
    assert_agreement(PathKind::Primary, true, 11);
}

#[test]
fn chains_to_surfaces_on_spheres_agree_with_newton() {
    assert_agreement(PathKind::ChainToSurface, true, 12);
}

#[test]
fn chains_to_lights_on_spheres_agree_with_newton() {
    assert_agreement(PathKind::ChainToLight, true, 13);
}

#[test]
fn caustics_on_spheres_agree_with_newton() {
    assert_agreement(PathKind::Caustic, true, 14);
}

#[test]
fn shadows_on_spheres_agree_with_newton() {
    assert_agreement(PathKind::Shadow, true, 15);
}
