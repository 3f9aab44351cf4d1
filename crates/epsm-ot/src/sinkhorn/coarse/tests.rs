//! Coarse-correction tests: exact cluster marginals after a correction, bounded
//! shifts on a short support, and imbalances carried across bridges.

use super::super::pass::softmin_blocks;
use super::*;
use crate::SinkhornSettings;
use crate::clusters::{Clustered, Support, fit_potentials};
use crate::cost::diameter_sq;
use crate::points::PointCloud;
use crate::sinkhorn::solve_dual;
use crate::synthetic::blobs_pair;

/// L1 distances of the plan's source and target cluster marginals from the clouds' cluster masses.
fn cluster_marginal_errors(
    x: &Level,
    y: &Level,
    sup: &Support,
    f: &[f64],
    g: &[f64],
    eps: f64,
) -> (f64, f64) {
    let pass = softmin_blocks(x, y, &sup.rows, g, eps, |i, _| f[i], None);
    let (a, b) = (cluster_log_masses(x), cluster_log_masses(y));
    let mut cols = vec![0.0; b.len()];
    let mut row_error = 0.0;
    for ((masses, list), la) in pass.log_masses.iter().zip(&sup.rows).zip(&a) {
        row_error += (masses.iter().map(|m| m.exp()).sum::<f64>() - la.exp()).abs();
        for (m, &j) in masses.iter().zip(list) {
            cols[j as usize] += m.exp();
        }
    }
    let col_error = cols
        .iter()
        .zip(&b)
        .map(|(c, lb)| (c - lb.exp()).abs())
        .sum();
    (row_error, col_error)
}

#[test]
fn a_support_that_cannot_carry_the_marginals_gives_bounded_shifts_towards_the_missing_pairs() {
    // Two source and two target clusters of equal mass; both source clusters keep
    // only target cluster 0, so target 1 can receive nothing.
    let lists = vec![vec![0u32], vec![0]];
    let log_k = vec![vec![(0.25f64).ln()], vec![(0.25f64).ln()]];
    let half = (0.5f64).ln();
    let scaling = scale(
        &log_k,
        &lists,
        &[half, half],
        &[half, half],
        SCALING_ITERATIONS,
    );
    assert!(!scaling.converged, "not a test: the scaling converged");
    let clamp = 30.0;
    let (u, v) = bounded(scaling, clamp);
    assert!(u.iter().chain(&v).all(|t| t.abs() <= clamp), "{u:?} {v:?}");
    assert!(u.iter().sum::<f64>().abs() < 1e-9, "gauge: {u:?}");
    // Target 0 holds all the mass: its potential drops against target 1's, so
    // reduced costs towards target 1 fall and a rebuilt support reaches it.
    assert!(v[1] - v[0] > 1.0, "{v:?}");
}

#[test]
fn bridges_carry_an_imbalance_between_components_the_support_does_not_join() {
    // Black and white points on the unit square: the source is 60 % black, the
    // target 50 %. At ε = 3/80 the support (30ε) keeps no black–white pair, so
    // the support graph has two components with unequal masses.
    let mut rng = crate::synthetic::Rng::new(7);
    let mut cloud = |black: usize, n: usize| {
        let points: Vec<[f32; 5]> = (0..n)
            .map(|i| {
                let c = if i < black { 0.0 } else { 1.0 };
                [c, c, c, rng.uniform(), rng.uniform()]
            })
            .collect();
        PointCloud::from_points(&points).unwrap_or_else(|e| panic!("{e}"))
    };
    let (s, t) = (cloud(600, 1000), cloud(500, 1000));
    let (cx, cy) = (Clustered::new(&s, 16), Clustered::new(&t, 16));
    let (x, y) = (Level::fine(&cx), Level::fine(&cy));
    let eps = 3.0 / 80.0;
    let threshold = 30.0 * eps;
    let (mut f, mut g) = (vec![0.0; 1000], vec![0.0; 1000]);
    let support = |f: &[f64], g: &[f64]| {
        Support::truncated(
            &cx,
            &fit_potentials(&cx, f),
            &cy,
            &fit_potentials(&cy, g),
            threshold,
        )
    };
    let black = |c: &Clustered, k: usize| c.cloud.point(c.clusters[k].range.start)[0] == 0.0;
    let crosses = |sup: &Support| {
        sup.rows
            .iter()
            .enumerate()
            .flat_map(|(i, list)| list.iter().map(move |&j| (i, j as usize)))
            .filter(|&(i, j)| black(&cx, i) != black(&cy, j))
            .count()
    };
    let correct_on = |sup: &Support, f: &mut [f64], g: &mut [f64]| {
        let pass = softmin_blocks(&x, &y, &sup.rows, g, eps, |i, _| f[i], None);
        correct(&x, &y, &sup.rows, &pass.log_masses, f, g, eps, 30.0)
    };
    let sup = support(&f, &g);
    assert_eq!(
        crosses(&sup),
        0,
        "not a test: the support joins the colours"
    );
    let outcome = correct_on(&sup, &mut f, &mut g);
    assert!(matches!(outcome, Correction::Bridged { .. }), "{outcome:?}");
    // The shifted potentials give a support that joins the colours and carries the
    // cluster marginals: the next correction converges on it.
    let sup = support(&f, &g);
    assert!(
        crosses(&sup) > 0,
        "the rebuilt support does not join the colours"
    );
    let outcome = correct_on(&sup, &mut f, &mut g);
    assert!(matches!(outcome, Correction::Applied { .. }), "{outcome:?}");
    let (row, col) = cluster_marginal_errors(&x, &y, &sup, &f, &g, eps);
    assert!(row <= 1.5 * SCALING_TOLERANCE && col <= 1e-5, "{row} {col}");
}

#[test]
fn correction_makes_the_cluster_marginals_exact() {
    let (s, t) = blobs_pair(1024, 3).unwrap_or_else(|| panic!("fixture"));
    let (cx, cy) = (Clustered::new(&s, 32), Clustered::new(&t, 32));
    let (x, y) = (Level::fine(&cx), Level::fine(&cy));
    let blur = 0.05;
    let eps = blur * blur;
    // Converged potentials plus a smooth tilt: a large-scale imbalance of the kind
    // plain updates at small ε remove slowly.
    let settings = SinkhornSettings {
        blur,
        ..SinkhornSettings::default()
    };
    let dual = solve_dual(&cx, &cy, diameter_sq(&s, &t), &settings);
    let tilt = |i: usize| 0.5 * eps * f64::from(cx.cloud.point(i)[3]);
    let mut f: Vec<f64> = dual
        .f
        .iter()
        .enumerate()
        .map(|(i, v)| v + tilt(i))
        .collect();
    let mut g = dual.g;
    let sup = Support::truncated(
        &cx,
        &fit_potentials(&cx, &f),
        &cy,
        &fit_potentials(&cy, &g),
        settings.truncation * eps,
    );
    let (row0, col0) = cluster_marginal_errors(&x, &y, &sup, &f, &g, eps);
    assert!(
        row0 > 0.05 && col0 > 0.05,
        "not a test: errors {row0}, {col0}"
    );
    let pass = softmin_blocks(&x, &y, &sup.rows, &g, eps, |i, _| f[i], None);
    let outcome = correct(
        &x,
        &y,
        &sup.rows,
        &pass.log_masses,
        &mut f,
        &mut g,
        eps,
        settings.truncation,
    );
    assert!(matches!(outcome, Correction::Applied { .. }), "{outcome:?}");
    let (row, col) = cluster_marginal_errors(&x, &y, &sup, &f, &g, eps);
    // Rows to the scaling tolerance; columns exact up to f32 kernel rounding.
    assert!(
        row <= 1.5 * SCALING_TOLERANCE,
        "source cluster marginals off by {row}"
    );
    assert!(col <= 1e-5, "target cluster marginals off by {col}");
}
