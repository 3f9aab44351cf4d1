//! Bad input and degenerate clouds, for every matcher.

use super::{random_cloud, translated};
use crate::points::PointCloud;
use crate::synthetic::Rng;
use crate::{ExactSettings, Matcher, OtError, SinkhornSettings};

fn matchers() -> Vec<Matcher> {
    vec![
        Matcher::exact(),
        Matcher::Exact(ExactSettings::sparse_only()),
        Matcher::sinkhorn(),
        Matcher::Sinkhorn(SinkhornSettings::debiased()),
        Matcher::sliced(),
    ]
}

fn all_finite(r: &crate::OtResult) -> bool {
    r.loss.is_finite() && r.gradient.iter().flatten().all(|g| g.is_finite())
}

#[test]
fn bad_input_is_a_typed_error() {
    assert_eq!(PointCloud::from_points(&[]), Err(OtError::Empty));
    let nan = PointCloud::from_points(&[[0.0, f32::NAN, 0.0, 0.0, 0.0]]);
    assert!(matches!(
        nan,
        Err(OtError::NonFinite {
            index: 0,
            axis: "g",
            ..
        })
    ));
    let inf = PointCloud::from_points(&[[0.0; 5], [0.0, 0.0, 0.0, f32::INFINITY, 0.0]]);
    assert!(matches!(
        inf,
        Err(OtError::NonFinite {
            index: 1,
            axis: "x",
            ..
        })
    ));
    let ragged = PointCloud::from_columns([
        vec![0.0; 3],
        vec![0.0; 3],
        vec![0.0; 2],
        vec![0.0; 3],
        vec![0.0; 3],
    ]);
    assert!(matches!(
        ragged,
        Err(OtError::RaggedColumns {
            axis: "b",
            len: 2,
            expected: 3
        })
    ));
    let mut rng = Rng::new(1);
    let (a, b) = (
        random_cloud(&mut rng, 5, 1.0),
        random_cloud(&mut rng, 6, 1.0),
    );
    for m in matchers() {
        assert_eq!(
            m.solve(&a, &b),
            Err(OtError::SizeMismatch {
                source_len: 5,
                target_len: 6
            })
        );
    }
    // 1e-300: ε = blur² underflows to 0 and the ε schedule never ended.
    for blur in [-1.0, 1e-300] {
        let bad = Matcher::Sinkhorn(SinkhornSettings {
            blur,
            ..SinkhornSettings::default()
        });
        assert_eq!(
            rejected(&bad, &a),
            Some(("sinkhorn.blur", "must be finite and at least 1e-4"))
        );
    }
    for stall_margin in [f64::NAN, 0.5] {
        let bad = Matcher::Sinkhorn(SinkhornSettings {
            stall_margin,
            ..SinkhornSettings::default()
        });
        assert_eq!(
            rejected(&bad, &a).map(|e| e.0),
            Some("sinkhorn.stall_margin")
        );
    }
    // Below the last ε of the auction, or not a number.
    for reprice_auction_start in [f64::NAN, 1e-12] {
        let bad = Matcher::Exact(ExactSettings {
            reprice_auction_start,
            ..ExactSettings::default()
        });
        assert_eq!(
            rejected(&bad, &a).map(|e| e.0),
            Some("exact.reprice_auction_start")
        );
    }
}

/// The key and reason of the invalid setting `matcher` reports when solving `cloud`
/// against itself, or `None` if it reports none.
fn rejected(matcher: &Matcher, cloud: &PointCloud) -> Option<(&'static str, &'static str)> {
    match matcher.solve(cloud, cloud) {
        Err(OtError::InvalidSetting { key, reason, .. }) => Some((key, reason)),
        _ => None,
    }
}

#[test]
fn single_point_clouds() {
    let a = PointCloud::from_points(&[[0.1, 0.2, 0.3, 0.4, 0.5]]).unwrap_or_else(|e| panic!("{e}"));
    let b = PointCloud::from_points(&[[0.5, 0.2, 0.3, 0.4, 0.0]]).unwrap_or_else(|e| panic!("{e}"));
    for m in matchers() {
        let r = m.solve(&a, &b).unwrap_or_else(|e| panic!("{e}"));
        assert!(all_finite(&r), "{}", m.name());
        if matches!(m, Matcher::Sliced(_)) {
            // Approximate: only the dominant directions are reliable.
            assert!(
                r.gradient[0][0] < 0.0 && r.gradient[0][4] > 0.0,
                "sliced: {:?}",
                r.gradient
            );
            continue;
        }
        assert!(
            (r.gradient[0][0] - 2.0 * (0.1 - 0.5)).abs() < 1e-4,
            "{}: {:?}",
            m.name(),
            r.gradient
        );
        assert!(
            (r.gradient[0][4] - 2.0 * 0.5).abs() < 1e-4,
            "{}: {:?}",
            m.name(),
            r.gradient
        );
    }
}

#[test]
fn identical_clouds_give_zero_loss_and_gradient() {
    let mut rng = Rng::new(2);
    let a = random_cloud(&mut rng, 300, 1.0);
    for m in [
        Matcher::exact(),
        Matcher::Exact(ExactSettings::sparse_only()),
        Matcher::Sinkhorn(SinkhornSettings::debiased()),
    ] {
        let r = m.solve(&a, &a).unwrap_or_else(|e| panic!("{e}"));
        assert!(r.loss.abs() <= 1e-12, "{}: loss {}", m.name(), r.loss);
        assert!(
            r.gradient.iter().flatten().all(|&g| g == 0.0),
            "{}",
            m.name()
        );
    }
    // OT_ε (not debiased) has a zero gradient at its fixed point; the polish stops
    // at the marginal tolerance, so the residual gradient shrinks with it.
    for (tolerance, bound) in [(1e-3, 1e-4), (1e-6, 1e-5)] {
        let settings = SinkhornSettings {
            marginal_tolerance: tolerance,
            ..SinkhornSettings::default()
        };
        let r = Matcher::Sinkhorn(settings)
            .solve(&a, &a)
            .unwrap_or_else(|e| panic!("{e}"));
        let gmax = r
            .gradient
            .iter()
            .flatten()
            .fold(0.0f32, |m, g| m.max(g.abs()));
        assert!(
            all_finite(&r) && gmax < bound,
            "tolerance {tolerance}: gradient {gmax}"
        );
    }
}

#[test]
fn duplicate_points_far_apart_clouds_and_tiny_epsilon() {
    let dup = PointCloud::from_points(&vec![[0.5; 5]; 100]).unwrap_or_else(|e| panic!("{e}"));
    let mut rng = Rng::new(3);
    let other = random_cloud(&mut rng, 100, 1.0);
    let far = translated(&other, [0.0, 0.0, 0.0, 1000.0, -1000.0]);
    let tiny = Matcher::Sinkhorn(SinkhornSettings {
        blur: 1e-3,
        ..SinkhornSettings::default()
    });
    for m in matchers().into_iter().chain([tiny]) {
        for (s, t) in [(&dup, &other), (&other, &dup), (&other, &far), (&dup, &dup)] {
            let r = m.solve(s, t).unwrap_or_else(|e| panic!("{e}"));
            assert!(all_finite(&r), "{} produced non-finite output", m.name());
        }
        let r = m.solve(&other, &far).unwrap_or_else(|e| panic!("{e}"));
        let mean_x = r.gradient.iter().map(|g| g[3]).sum::<f32>() / 100.0;
        let tolerance = if matches!(m, Matcher::Sliced(_)) {
            5.0
        } else {
            0.5
        };
        assert!(
            (mean_x + 2000.0 / 100.0).abs() < tolerance,
            "{}: far-apart mean x gradient {mean_x}",
            m.name()
        );
    }
}

#[test]
fn the_smallest_allowed_blur_handles_every_degenerate_cloud() {
    let tiny = |debias| {
        Matcher::Sinkhorn(SinkhornSettings {
            blur: crate::MIN_BLUR,
            debias,
            ..SinkhornSettings::default()
        })
    };
    let mut rng = Rng::new(4);
    let other = random_cloud(&mut rng, 100, 1.0);
    let far = translated(&other, [0.0, 0.0, 0.0, 1000.0, -1000.0]);
    let dup = PointCloud::from_points(&vec![[0.5; 5]; 100]).unwrap_or_else(|e| panic!("{e}"));
    let a = PointCloud::from_points(&[[0.1, 0.2, 0.3, 0.4, 0.5]]).unwrap_or_else(|e| panic!("{e}"));
    let b = PointCloud::from_points(&[[0.5, 0.2, 0.3, 0.4, 0.0]]).unwrap_or_else(|e| panic!("{e}"));
    for debias in [false, true] {
        let m = tiny(debias);
        for (s, t) in [
            (&other, &other),
            (&dup, &dup),
            (&dup, &other),
            (&other, &dup),
            (&other, &far),
            (&a, &b),
            (&a, &a),
        ] {
            let r = m.solve(s, t).unwrap_or_else(|e| panic!("{e}"));
            assert!(all_finite(&r), "debias {debias}: non-finite output");
        }
        let r = m.solve(&a, &b).unwrap_or_else(|e| panic!("{e}"));
        assert!(
            (r.gradient[0][0] - 2.0 * (0.1 - 0.5)).abs() < 1e-4
                && (r.gradient[0][4] - 2.0 * 0.5).abs() < 1e-4,
            "debias {debias}: single point {:?}",
            r.gradient
        );
        let r = m.solve(&other, &far).unwrap_or_else(|e| panic!("{e}"));
        let mean_x = r.gradient.iter().map(|g| g[3]).sum::<f32>() / 100.0;
        assert!(
            (mean_x + 2000.0 / 100.0).abs() < 0.5,
            "debias {debias}: far-apart mean x gradient {mean_x}"
        );
    }
    let r = tiny(true)
        .solve(&other, &other)
        .unwrap_or_else(|e| panic!("{e}"));
    assert!(r.loss.abs() <= 1e-12, "debiased identical loss {}", r.loss);
}

#[test]
fn sliced_identical_clouds_give_zero_loss_and_gradient() {
    let mut rng = Rng::new(5);
    let a = random_cloud(&mut rng, 300, 1.0);
    let r = Matcher::sliced()
        .solve(&a, &a)
        .unwrap_or_else(|e| panic!("{e}"));
    assert!(r.loss.abs() <= 1e-12, "loss {}", r.loss);
    assert!(r.gradient.iter().flatten().all(|&g| g == 0.0));
}

#[test]
fn clouds_too_spread_for_the_kernel_are_a_typed_error() {
    let mut rng = Rng::new(6);
    let near = random_cloud(&mut rng, 50, 1.0);
    // The entropic solve centres each cloud first, so a translation only bounds
    // the gradient (the exact matcher's bound: 3e38 is beyond it), while the
    // clouds' own spread is bounded by MAX_SPREAD ≈ 4.3e37 in units of
    // min(ε, 1): diameter²/ε ≈ 5e38 for these spreads. The old code refused
    // translations of 1e17 and more at the smallest blur, and solved those
    // below with an infinite marginal error.
    for (blur, spread) in [
        (crate::MIN_BLUR, 1e15),
        (0.01, 1e17),
        (1e10, 1e19),
        (1e20, 1e19),
    ] {
        for debias in [false, true] {
            let m = SinkhornSettings {
                blur,
                debias,
                ..SinkhornSettings::default()
            };
            for shift in [6e14, 1e20, 1e37] {
                let far = translated(&near, [0.0, 0.0, 0.0, shift, 0.0]);
                let r = crate::sinkhorn::solve(&near, &far, &m).unwrap_or_else(|e| panic!("{e}"));
                let mean_x = r.gradient.iter().map(|g| f64::from(g[3])).sum::<f64>() / 50.0;
                assert!(
                    all_finite(&r)
                        && (mean_x / (-2.0 * f64::from(shift) / 50.0) - 1.0).abs() < 1e-3
                        && r.stats.unconverged_solves == 0,
                    "blur {blur} debias {debias}: shift {shift:e}, mean x gradient {mean_x:e}"
                );
            }
            let far = translated(&near, [0.0, 0.0, 0.0, 3e38, 0.0]);
            let wide = random_cloud(&mut rng, 50, spread);
            for (case, r) in [
                ("shift 3e38", crate::sinkhorn::solve(&near, &far, &m)),
                ("spread", crate::sinkhorn::solve(&near, &wide, &m)),
            ] {
                assert!(
                    matches!(r, Err(OtError::SpreadTooLarge { .. })),
                    "blur {blur} debias {debias}: {case} gave {r:?}"
                );
            }
        }
    }
    // Costs beyond f32 for some pairs only: the old code returned Ok, with those
    // pairs' kernel weights lost (for other clouds like these, a negative OT_ε).
    let wide = random_cloud(&mut rng, 300, 1e19);
    let m = SinkhornSettings {
        blur: 1e15,
        ..SinkhornSettings::default()
    };
    let r = crate::sinkhorn::solve(&wide, &random_cloud(&mut rng, 300, 1e19), &m);
    assert!(
        matches!(r, Err(OtError::SpreadTooLarge { .. })),
        "spread over 1e19 at blur 1e15 gave {:?}",
        r.map(|r| r.loss)
    );
}

#[test]
fn exact_and_sliced_refuse_clouds_beyond_their_f32_range() {
    let mut rng = Rng::new(7);
    // 1, 2 and 50 points take the dense exact path, 100 the sparse one.
    for n in [1, 2, 50, 100] {
        let near = random_cloud(&mut rng, n, 1.0);
        for m in [Matcher::exact(), Matcher::sliced()] {
            // A pure translation: the mean x gradient is −2 shift / n (sliced: approximately).
            let tolerance = if matches!(m, Matcher::Sliced(_)) {
                0.25
            } else {
                1e-3
            };
            for shift in [1e17, 1e20] {
                let far = translated(&near, [0.0, 0.0, 0.0, shift, 0.0]);
                let r = m.solve(&near, &far).unwrap_or_else(|e| panic!("{e}"));
                let mean_x = r.gradient.iter().map(|g| f64::from(g[3])).sum::<f64>() / n as f64;
                let expected = -2.0 * f64::from(shift) / n as f64;
                assert!(
                    all_finite(&r) && (mean_x / expected - 1.0).abs() < tolerance,
                    "{} n {n}: shift {shift:e}, mean x gradient {mean_x:e}",
                    m.name()
                );
            }
            let far = translated(&near, [0.0, 0.0, 0.0, 3e38, 0.0]);
            let r = m.solve(&near, &far);
            assert!(
                matches!(r, Err(OtError::SpreadTooLarge { matcher, .. }) if matcher == m.name()),
                "{} n {n}: shift 3e38 gave {r:?}",
                m.name()
            );
        }
    }
    // Sliced projects absolute coordinates: two small clouds together near 3e38 too.
    let near = random_cloud(&mut rng, 10, 1.0);
    let (a, b) = (
        translated(&near, [3e38; 5]),
        translated(&near, [3e38, 3e38, 3e38, 3e38, 2.9e38]),
    );
    let r = Matcher::sliced().solve(&a, &b);
    assert!(
        matches!(
            r,
            Err(OtError::SpreadTooLarge {
                matcher: "sliced",
                ..
            })
        ),
        "sliced near 3e38 gave {r:?}"
    );
    let r = Matcher::exact()
        .solve(&a, &b)
        .unwrap_or_else(|e| panic!("{e}"));
    assert!(all_finite(&r), "exact near 3e38: {r:?}");
}

#[test]
fn entropic_solves_the_f32_kernel_cannot_resolve_are_an_error_or_counted() {
    // Points and blur scale together (the same plan): what limits the kernel is
    // diameter²/ε. Spread over 1e6 at blur 0.01 (diameter²/ε ≈ 3e16) both paths
    // returned Ok with an infinite marginal error.
    let mut rng = Rng::new(8);
    let (a, b) = (
        random_cloud(&mut rng, 100, 1e6),
        random_cloud(&mut rng, 100, 1e6),
    );
    for exact_prices in [false, true] {
        let m = SinkhornSettings {
            exact_prices,
            ..SinkhornSettings::default()
        };
        let r = crate::sinkhorn::solve(&a, &b, &m);
        assert!(
            matches!(
                r,
                Err(OtError::NotConverged { marginal_error, rounding, .. })
                    if marginal_error.is_infinite() && rounding > 1e9
            ),
            "exact_prices {exact_prices}: {:?}",
            r.map(|r| r.stats.marginal_error)
        );
    }
    // Spread over 100 (score rounding 0.02 ε): a finite error (0.25) above the
    // tolerance when the polish stops, counted.
    let mut rng = Rng::new(8);
    let (a, b) = (
        random_cloud(&mut rng, 100, 100.0),
        random_cloud(&mut rng, 100, 100.0),
    );
    let r = crate::sinkhorn::solve(&a, &b, &SinkhornSettings::default())
        .unwrap_or_else(|e| panic!("{e}"));
    let error = r.stats.marginal_error.unwrap_or(f64::NAN);
    assert!(
        all_finite(&r) && error.is_finite() && error > 1e-3,
        "{error}"
    );
    assert_eq!(r.stats.unconverged_solves, 1);
    // Converged solves count nothing.
    let near = random_cloud(&mut rng, 100, 1.0);
    let other = random_cloud(&mut rng, 100, 1.0);
    let r = crate::sinkhorn::solve(&near, &other, &SinkhornSettings::debiased());
    let r = r.unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(r.stats.unconverged_solves, 0);
}

#[test]
fn a_stalled_polish_stops_early_and_is_still_counted_or_an_error() {
    // The clouds of the test above: spread over 100 the polish's error stays
    // near 0.25; over 1e6 it is infinite throughout. Both ran all 5000 polish
    // updates before they were counted (or failed).
    let patient = SinkhornSettings {
        stall_margin: f64::INFINITY,
        ..SinkhornSettings::default()
    };
    let mut rng = Rng::new(8);
    let (a, b) = (
        random_cloud(&mut rng, 100, 1e6),
        random_cloud(&mut rng, 100, 1e6),
    );
    let updates = |settings| match crate::sinkhorn::solve(&a, &b, settings) {
        Err(OtError::NotConverged {
            marginal_error,
            iterations,
            ..
        }) if marginal_error.is_infinite() => iterations,
        r => panic!("{:?}", r.map(|r| r.stats.marginal_error)),
    };
    // The settings differ in the polish only: the patient one runs all its
    // 5000 updates, so the other's polish ran `stopped − (full − 5000)`.
    let polished = |full: usize, stopped: usize| stopped + 5000 - full;
    let (full, stopped) = (updates(&patient), updates(&SinkhornSettings::default()));
    assert!(
        full >= 5000 && polished(full, stopped) <= 500,
        "non-finite error: {stopped} updates against {full}"
    );
    let mut rng = Rng::new(8);
    let (a, b) = (
        random_cloud(&mut rng, 100, 100.0),
        random_cloud(&mut rng, 100, 100.0),
    );
    let solve = |settings| {
        let r = crate::sinkhorn::solve(&a, &b, settings).unwrap_or_else(|e| panic!("{e}"));
        let error = r.stats.marginal_error.unwrap_or(f64::NAN);
        assert!(
            all_finite(&r) && error.is_finite() && error > 1e-3,
            "{error}"
        );
        assert_eq!(r.stats.unconverged_solves, 1);
        r.stats.iterations
    };
    let (full, stopped) = (solve(&patient), solve(&SinkhornSettings::default()));
    assert!(
        full >= 5000 && polished(full, stopped) <= 500,
        "finite error: {stopped} updates against {full}"
    );
}
