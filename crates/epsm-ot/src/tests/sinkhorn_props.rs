//! Properties of the entropic solver: marginals, convergence to exact, gradients, determinism.

use super::{random_cloud, translated};
use crate::plan::{EntropicPlan, Matching, OtResult};
use crate::points::PointCloud;
use crate::synthetic::{Rng, blobs_pair};
use crate::{ExactSettings, Matcher, SinkhornSettings, SlicedSettings, exact, sinkhorn};

fn plan(r: &OtResult) -> &EntropicPlan {
    match &r.matching {
        Matching::Entropic(p) => p,
        other => panic!("expected an entropic plan, got {other:?}"),
    }
}

fn solve(s: &PointCloud, t: &PointCloud, settings: &SinkhornSettings) -> OtResult {
    sinkhorn::solve(s, t, settings).unwrap_or_else(|e| panic!("{e}"))
}

#[test]
fn default_annealed_and_exact_prices_reach_the_same_plan() {
    let (s, t) = blobs_pair(1024, 4).unwrap_or_else(|| panic!("fixture"));
    let blur = |settings: SinkhornSettings| SinkhornSettings {
        blur: 0.03,
        ..settings
    };
    let default = solve(&s, &t, &blur(SinkhornSettings::default()));
    let annealed = solve(&s, &t, &blur(SinkhornSettings::annealed()));
    let warm = solve(
        &s,
        &t,
        &blur(SinkhornSettings {
            exact_prices: true,
            ..SinkhornSettings::default()
        }),
    );
    for (name, r, exact_solve) in [
        ("default", &default, false),
        ("annealed", &annealed, false),
        ("exact_prices", &warm, true),
    ] {
        let phases: Vec<&str> = r.stats.phases.iter().map(|(name, _)| name).collect();
        assert_eq!(
            phases.contains(&"auction"),
            exact_solve,
            "{name}: {phases:?}"
        );
        assert_eq!(phases.contains(&"fine"), !exact_solve, "{name}: {phases:?}");
        assert!(
            plan(r).marginal_error <= 1e-3,
            "{name}: marginal error {} after {} iterations",
            plan(r).marginal_error,
            r.stats.iterations
        );
        let rel = (r.loss - default.loss).abs() / default.loss;
        assert!(
            rel < 1e-3,
            "{name}: {} against default {}",
            r.loss,
            default.loss
        );
    }
}

#[test]
fn default_meets_the_tolerance_and_the_exact_cost_at_blur_001() {
    let (s, t) = blobs_pair(4096, 2).unwrap_or_else(|| panic!("fixture"));
    let exact = exact::solve(&s, &t, &ExactSettings::default())
        .unwrap_or_else(|e| panic!("{e}"))
        .loss;
    let r = solve(&s, &t, &SinkhornSettings::default());
    let p = plan(&r);
    assert!(
        p.marginal_error <= 1e-3,
        "marginal error {}",
        p.marginal_error
    );
    let gap = (p.transport_cost - exact).abs() / exact;
    assert!(
        gap < 0.05,
        "transport cost {} against exact {exact} ({gap})",
        p.transport_cost
    );
}

#[test]
fn marginals_are_within_tolerance() {
    let (s, t) = blobs_pair(1024, 4).unwrap_or_else(|| panic!("fixture"));
    let r = solve(
        &s,
        &t,
        &SinkhornSettings {
            blur: 0.03,
            ..SinkhornSettings::default()
        },
    );
    let p = plan(&r);
    assert!(
        p.marginal_error <= 1e-3,
        "marginal error {}",
        p.marginal_error
    );
    assert!(r.loss.is_finite() && r.gradient.iter().flatten().all(|g| g.is_finite()));
}

#[test]
fn cost_converges_to_exact_as_blur_shrinks() {
    let (s, t) = blobs_pair(1024, 8).unwrap_or_else(|| panic!("fixture"));
    let exact = exact::solve(&s, &t, &ExactSettings::default())
        .unwrap_or_else(|e| panic!("{e}"))
        .loss;
    let mut previous = f64::INFINITY;
    for blur in [0.2, 0.1, 0.05, 0.03] {
        let r = solve(
            &s,
            &t,
            &SinkhornSettings {
                blur,
                ..SinkhornSettings::default()
            },
        );
        let gap = (plan(&r).transport_cost - exact).abs() / exact;
        assert!(
            gap < previous + 1e-3,
            "blur {blur}: gap {gap} did not shrink from {previous}"
        );
        previous = gap;
    }
    assert!(
        previous < 0.05,
        "blur 0.03: transport cost {previous} relative to exact"
    );
}

#[test]
fn gradient_matches_finite_differences() {
    let mut rng = Rng::new(21);
    let (s, t) = (
        random_cloud(&mut rng, 12, 1.0),
        random_cloud(&mut rng, 12, 1.0),
    );
    let settings = SinkhornSettings {
        blur: 0.2,
        marginal_tolerance: 1e-7,
        ..SinkhornSettings::default()
    };
    for debias in [false, true] {
        let settings = SinkhornSettings {
            debias,
            ..settings.clone()
        };
        let r = solve(&s, &t, &settings);
        let h = 1e-3f32;
        for (i, d) in [(0, 0), (3, 4), (7, 2), (11, 3)] {
            let shifted = |delta: f32| {
                let pts: Vec<_> = s
                    .points()
                    .enumerate()
                    .map(|(k, mut p)| {
                        if k == i {
                            p[d] += delta;
                        }
                        p
                    })
                    .collect();
                solve(
                    &PointCloud::from_points(&pts).unwrap_or_else(|e| panic!("{e}")),
                    &t,
                    &settings,
                )
                .loss
            };
            let fd = (shifted(h) - shifted(-h)) / (2.0 * f64::from(h));
            let g = f64::from(r.gradient[i][d]);
            assert!(
                (fd - g).abs() <= 2e-3 * g.abs().max(0.01),
                "debias {debias}, point {i} axis {d}: fd {fd} vs {g}"
            );
        }
    }
}

#[test]
fn translated_target_gives_translation_as_gradient() {
    let (s, _) = blobs_pair(400, 9).unwrap_or_else(|| panic!("fixture"));
    let shift = [0.0, 0.0, 0.0, 0.3, -0.2];
    let t = translated(&s, shift);
    let n = 400.0f32;
    for matcher in [
        Matcher::Sinkhorn(SinkhornSettings::default()),
        Matcher::Sinkhorn(SinkhornSettings::debiased()),
        Matcher::Exact(ExactSettings::default()),
    ] {
        let r = matcher.solve(&s, &t).unwrap_or_else(|e| panic!("{e}"));
        let mean: Vec<f32> = (0..5)
            .map(|d| r.gradient.iter().map(|g| g[d]).sum::<f32>() / n)
            .collect();
        for d in 0..5 {
            let want = -2.0 * shift[d] / n;
            assert!(
                (mean[d] - want).abs() <= 0.02 * 2.0 * 0.3 / n,
                "{}: axis {d}: {} vs {want}",
                matcher.name(),
                mean[d]
            );
        }
    }
    let r = Matcher::Sliced(SlicedSettings {
        projections: 256,
        seed: 1,
    })
    .solve(&s, &t)
    .unwrap_or_else(|e| panic!("{e}"));
    let mean_x = r.gradient.iter().map(|g| g[3]).sum::<f32>() / n;
    assert!(
        (mean_x - (-0.6 / n)).abs() <= 0.25 * 0.6 / n,
        "sliced: {mean_x}"
    );
}

#[test]
fn same_result_with_one_and_two_threads() {
    let (s, t) = blobs_pair(700, 12).unwrap_or_else(|| panic!("fixture"));
    let entropic = SinkhornSettings {
        blur: 0.05,
        ..SinkhornSettings::default()
    };
    let debiased = SinkhornSettings {
        debias: true,
        ..entropic.clone()
    };
    for matcher in [
        Matcher::Sinkhorn(entropic),
        Matcher::Sinkhorn(debiased),
        Matcher::exact(),
        Matcher::sliced(),
    ] {
        let run = |threads: usize| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap_or_else(|e| panic!("{e}"));
            pool.install(|| matcher.solve(&s, &t))
                .unwrap_or_else(|e| panic!("{e}"))
        };
        assert_eq!(
            run(1),
            run(2),
            "{} differs between 1 and 2 threads",
            matcher.name()
        );
    }
}

/// Seeds 1 and 4 of the benchmark pair at n = 16384: the support built from the
/// jump's potentials falls into components with unequal masses, joined by no
/// block pair or only by weak ones, so the corrections' cluster scalings do not
/// converge; bridged corrections fix that without a clamped one. Before any such
/// fallback seed 1 took 1969 updates (69 s); with clamped corrections alone, seven
/// rebuilds of the first fine scale's support.
#[test]
fn bridged_corrections_rebuild_the_support_and_still_converge() {
    // Exact costs from `epsm bench ot --n 16384 --seed S --solver exact`.
    for (seed, exact) in [(1, 0.035063), (4, 0.029463)] {
        let (s, t) = blobs_pair(16384, seed).unwrap_or_else(|| panic!("fixture"));
        let r = solve(&s, &t, &SinkhornSettings::default());
        let p = plan(&r);
        let stats = &r.stats;
        assert!(
            stats.bridged_corrections > 0 && stats.clamped_corrections == 0,
            "seed {seed}: {stats:?}"
        );
        assert!(
            p.marginal_error <= 1e-3,
            "seed {seed}: marginal error {}",
            p.marginal_error
        );
        assert!(
            stats.iterations < 200,
            "seed {seed}: {} updates",
            stats.iterations
        );
        assert!(
            (p.transport_cost - exact).abs() < 0.05 * exact,
            "seed {seed}: transport cost {}",
            p.transport_cost
        );
    }
}

/// The slowest converging polish measured: the 1024-point benchmark pair scaled
/// ×10 (the `f32` kernel's rounding near its limit) from the exact prices,
/// reaching the tolerance at update 2286. The stall test must leave it running,
/// even at the strictest `stall_margin` (1). (×3 converges more slowly still, 4446
/// updates, but whether it converges at all turns on the order of the kernel's sums.)
#[test]
fn the_slowest_converging_polish_is_not_stopped_as_stalled() {
    let (s, t) = blobs_pair(1024, 0).unwrap_or_else(|| panic!("fixture"));
    let scaled = |c: &PointCloud| {
        let points: Vec<_> = c.points().map(|p| p.map(|v| 10.0 * v)).collect();
        PointCloud::from_points(&points).unwrap_or_else(|e| panic!("{e}"))
    };
    let settings = SinkhornSettings {
        exact_prices: true,
        stall_margin: 1.0,
        ..SinkhornSettings::default()
    };
    let r = solve(&scaled(&s), &scaled(&t), &settings);
    assert_eq!(r.stats.unconverged_solves, 0, "{:?}", r.stats);
    assert!(r.stats.iterations > 2000, "{} updates", r.stats.iterations);
}
