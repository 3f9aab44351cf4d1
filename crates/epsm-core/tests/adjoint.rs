//! One adjoint solve per path equals the forward Jacobian contracted with
//! the loss gradient, `g·dp/dθ`, to 1e-10 relative, for every path type and
//! random `g`, on triangles and on exact spheres.

mod common;

use common::{End, Rng, Spec, Vertex, build, random_params};
use epsm_core::solve::condition;
use epsm_core::{PathKind, SolveSettings, classify, solve_adjoint, solve_forward};
use glam::DVec2;

#[test]
fn adjoint_equals_forward_for_random_loss_gradients_on_every_path_type() {
    adjoint_equals_forward(false, 99);
}

#[test]
fn adjoint_equals_forward_on_spheres() {
    adjoint_equals_forward(true, 98);
}

/// Compares both solves on 200 paths of each type, on exact spheres with
/// `spheres`, within `CONFIGS` configurations.
fn adjoint_equals_forward(spheres: bool, seed: u64) {
    const CONFIGS: usize = 4000;
    let mut rng = Rng::new(seed);
    let settings = SolveSettings::for_radius(1.0);
    let mut compared = [0usize; PathKind::ALL.len()];
    let mut ill = 0;
    let mut configs = 0;
    while compared.iter().any(|&c| c < 200) {
        configs += 1;
        assert!(configs <= CONFIGS, "too few paths compared: {compared:?}");
        let (kind, end) = match rng.below(4) {
            0 => (PathKind::Caustic, End::Emitter),
            1 => (PathKind::ChainToSurface, End::Surface),
            2 => (PathKind::ChainToLight, End::Emitter),
            _ => (
                PathKind::Shadow,
                [End::AreaNee, End::PointNee][rng.below(2)],
            ),
        };
        let len = 1 + rng.below(4);
        let chain = (0..len)
            .map(|_| match rng.below(3) {
                0 => Vertex::Mirror,
                1 => Vertex::Glass {
                    ior: rng.range(1.1, 2.4),
                },
                _ => Vertex::Glossy {
                    alpha: rng.range(0.01, 1.0),
                },
            })
            .collect();
        let spec = Spec {
            spheres,
            ..Spec::new(kind, chain, end)
        };
        let Some(mut s) = build(&spec, &mut rng) else {
            continue;
        };
        random_params(&mut s.table, &s.objects, &s.lights, &mut rng);
        let motion = s.table.motion(&s.table.values());
        for p in classify(&s.record, &s.scene, &motion, &settings).paths {
            let g = DVec2::new(rng.range(-1.0, 1.0), rng.range(-1.0, 1.0));
            let (Ok(adj), Ok(fwd)) = (
                solve_adjoint(&p, g, &motion, &settings),
                solve_forward(&p, &motion, &settings),
            ) else {
                continue;
            };
            // Both are exact up to κ(A)·ε; the bound applies to well-conditioned systems.
            if condition(&p, &motion, &settings).is_ok_and(|c| c > 1e5) {
                ill += 1;
                continue;
            }
            let scale = fwd
                .columns
                .iter()
                .map(|c| g.dot(*c).abs())
                .fold(1e-12, f64::max);
            assert_eq!(adj.entries.len(), fwd.params.len(), "{}", p.kind.name());
            assert_eq!(fwd.params.len(), fwd.columns.len(), "{}", p.kind.name());
            for ((param, v), (fp, col)) in
                adj.entries.iter().zip(fwd.params.iter().zip(&fwd.columns))
            {
                assert_eq!(param, fp);
                assert!(
                    (v - g.dot(*col)).abs() <= 1e-10 * scale,
                    "{}: {v} vs {}",
                    p.kind.name(),
                    g.dot(*col)
                );
            }
            compared[p.kind as usize] += 1;
        }
    }
    eprintln!("{configs} configurations: {compared:?}, {ill} ill-conditioned");
    assert!(
        ill * 100 <= compared.iter().sum::<usize>(),
        "{ill} ill-conditioned"
    );
}
