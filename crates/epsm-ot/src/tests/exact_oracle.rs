//! The exact solver against brute force (n ≤ 8), the dense reference and the `lsap` crate
//! (also where the entropic solver's `exact_prices` runs it).

use super::random_cloud;
use crate::cost::{assignment_cost, diameter_sq, sq_dist_f64};
use crate::exact::{self, ExactSettings, dense};
use crate::plan::Matching;
use crate::points::PointCloud;
use crate::sinkhorn::{self, SinkhornSettings};
use crate::synthetic::{Rng, blobs_pair};

fn permutation(m: &Matching) -> Vec<usize> {
    match m {
        Matching::Permutation(p) => p.clone(),
        other => panic!("expected a permutation, got {other:?}"),
    }
}

fn brute_force(source: &PointCloud, target: &PointCloud) -> f64 {
    fn rec(k: usize, used: &mut [bool], acc: f64, cost: &[Vec<f64>], best: &mut f64) {
        if k == cost.len() {
            *best = best.min(acc);
            return;
        }
        for j in 0..cost.len() {
            if !used[j] {
                used[j] = true;
                rec(k + 1, used, acc + cost[k][j], cost, best);
                used[j] = false;
            }
        }
    }
    let cost: Vec<Vec<f64>> = source
        .points()
        .map(|p| target.points().map(|q| sq_dist_f64(&p, &q)).collect())
        .collect();
    let mut best = f64::INFINITY;
    rec(0, &mut vec![false; cost.len()], 0.0, &cost, &mut best);
    best / source.len() as f64
}

fn lsap_cost(source: &PointCloud, target: &PointCloud) -> f64 {
    let n = source.len();
    let cost: Vec<f64> = source
        .points()
        .flat_map(|p| target.points().map(move |q| sq_dist_f64(&p, &q)))
        .collect();
    let (rows, cols) = lsap::solve(n, n, &cost, false).unwrap_or_else(|e| panic!("lsap: {e:?}"));
    assert_eq!((rows.len(), cols.len()), (n, n), "lsap: one pair per row");
    rows.iter()
        .zip(&cols)
        .map(|(&i, &j)| cost[i * n + j])
        .sum::<f64>()
        / n as f64
}

fn assert_valid_permutation(perm: &[usize]) {
    let mut seen = vec![false; perm.len()];
    for &j in perm {
        assert!(!seen[j], "column {j} used twice");
        seen[j] = true;
    }
}

#[test]
fn exact_matches_brute_force_for_tiny_clouds() {
    let mut rng = Rng::new(7);
    for case in 0..300 {
        let n = 1 + case % 8;
        let (s, t) = (
            random_cloud(&mut rng, n, 1.0),
            random_cloud(&mut rng, n, 1.0),
        );
        let best = brute_force(&s, &t);
        for settings in [ExactSettings::default(), ExactSettings::sparse_only()] {
            let r = exact::solve(&s, &t, &settings).unwrap_or_else(|e| panic!("{e}"));
            let perm = permutation(&r.matching);
            assert_valid_permutation(&perm);
            assert!(
                (r.loss - best).abs() <= 1e-9,
                "case {case}: {} vs brute force {best}",
                r.loss
            );
            assert!((assignment_cost(&s, &t, &perm) - r.loss).abs() <= 1e-12);
        }
    }
}

#[test]
fn dense_reference_potentials_prove_optimality() {
    let mut rng = Rng::new(3);
    let (s, t) = (
        random_cloud(&mut rng, 60, 1.0),
        random_cloud(&mut rng, 60, 1.0),
    );
    let cost: Vec<f64> = s
        .points()
        .flat_map(|p| t.points().map(move |q| sq_dist_f64(&p, &q)))
        .collect();
    let a = dense::solve_matrix(&cost, 60);
    for i in 0..60 {
        for j in 0..60 {
            assert!(cost[i * 60 + j] - a.u[i] - a.v[j] >= -1e-12);
        }
        assert!((cost[i * 60 + a.perm[i]] - a.u[i] - a.v[a.perm[i]]).abs() <= 1e-12);
    }
}

#[test]
fn sparse_exact_matches_lsap_on_uniform_clouds() {
    let mut rng = Rng::new(11);
    for n in [65, 300, 1000] {
        let (s, t) = (
            random_cloud(&mut rng, n, 1.0),
            random_cloud(&mut rng, n, 1.0),
        );
        let r =
            exact::solve(&s, &t, &ExactSettings::sparse_only()).unwrap_or_else(|e| panic!("{e}"));
        assert_valid_permutation(&permutation(&r.matching));
        let oracle = lsap_cost(&s, &t);
        assert!(
            (r.loss - oracle).abs() <= 1e-9 * (1.0 + oracle),
            "n = {n}: {} vs lsap {oracle}",
            r.loss
        );
    }
}

#[test]
fn sparse_exact_matches_lsap_and_dense_on_blobs_up_to_2048() {
    for (n, seed) in [(256, 1), (1024, 2), (2048, 3)] {
        let (s, t) = blobs_pair(n, seed).unwrap_or_else(|| panic!("fixture"));
        let r =
            exact::solve(&s, &t, &ExactSettings::sparse_only()).unwrap_or_else(|e| panic!("{e}"));
        assert_valid_permutation(&permutation(&r.matching));
        let oracle = lsap_cost(&s, &t);
        assert!(
            (r.loss - oracle).abs() <= 1e-9 * (1.0 + oracle),
            "n = {n}: {} vs lsap {oracle}",
            r.loss
        );
        if n <= 256 {
            let d = dense::solve(&s, &t).unwrap_or_else(|e| panic!("{e}"));
            assert!((d.loss - oracle).abs() <= 1e-9 * (1.0 + oracle));
        }
    }
}

#[test]
fn sparse_exact_cold_starts_beyond_the_warm_starts_range() {
    // Clouds spread over [0, scale]⁵: the warm start (blur 0.03) is inside
    // sinkhorn::MAX_SPREAD at 1e15 and beyond it at 1e18; 3e37 is near the
    // exact matcher's own bound. The old code warm-started all three: at 1e18
    // its potentials were NaN and it returned 5.4 times the optimal cost.
    let mut rng = Rng::new(9);
    for (scale, cold_starts) in [(1e15, 0), (1e18, 1), (3e37, 1)] {
        let (s, t) = (
            random_cloud(&mut rng, 100, scale),
            random_cloud(&mut rng, 100, scale),
        );
        let r = exact::solve(&s, &t, &ExactSettings::default()).unwrap_or_else(|e| panic!("{e}"));
        let perm = permutation(&r.matching);
        assert_valid_permutation(&perm);
        let d = dense::solve(&s, &t).unwrap_or_else(|e| panic!("{e}"));
        assert!(
            (r.loss - d.loss).abs() <= 1e-9 * d.loss,
            "scale {scale:e}: sparse {:e} vs dense {:e}",
            r.loss,
            d.loss
        );
        assert!((assignment_cost(&s, &t, &perm) - r.loss).abs() <= 1e-12 * r.loss);
        assert_eq!(r.stats.cold_starts, cold_starts, "scale {scale:e}");
        assert!(r.gradient.iter().flatten().all(|g| g.is_finite()));
        if scale > 1e30 {
            assert!(diameter_sq(&s, &t) > 0.5 * exact::MAX_DIAMETER_SQ);
        }
    }
}

#[test]
fn the_auction_finishes_within_its_budget_at_any_scale() {
    // The auction's ε is relative to the squared diameter. It was absolute
    // (0.1 down to 1e-9): far below the rounding of prices near 1e30, so at
    // spreads of 1e15 every auction ran out of bids (and the blobs pair
    // already at ×1000), although the exact finish still made the matching optimal.
    let (s, t) = blobs_pair(400, 3).unwrap_or_else(|| panic!("fixture"));
    let mut rng = Rng::new(11);
    let random = (
        random_cloud(&mut rng, 200, 1.0),
        random_cloud(&mut rng, 200, 1.0),
    );
    for (name, (s, t)) in [("blobs", (s, t)), ("random", random)] {
        for scale in [1.0, 1e3, 1e15] {
            let scaled = |c: &PointCloud| {
                let points: Vec<_> = c.points().map(|p| p.map(|v| v * scale)).collect();
                PointCloud::from_points(&points).unwrap_or_else(|e| panic!("{e}"))
            };
            let (s, t) = (scaled(&s), scaled(&t));
            let r =
                exact::solve(&s, &t, &ExactSettings::default()).unwrap_or_else(|e| panic!("{e}"));
            let d = dense::solve(&s, &t).unwrap_or_else(|e| panic!("{e}"));
            assert_eq!(r.stats.auction_budget_stops, 0, "{name} ×{scale:e}");
            assert_eq!(
                permutation(&r.matching),
                permutation(&d.matching),
                "{name} ×{scale:e}"
            );
        }
    }
}

#[test]
fn sinkhorn_exact_prices_cold_starts_and_counts_it() {
    // At a blur of 0.3 % of the spread the entropic solve accepts clouds spread
    // over [0, 1e18]⁵, beyond the range of the exact solve's own warm start
    // (blur 0.03), so `exact_prices` runs that solve from the cold start; over
    // [0, 1e15]⁵ it warm-starts. The old code solved both, but dropped the exact
    // solve's counters (cold_starts and auction_budget_stops were always 0).
    // (A blur of 1 against these spreads is far beyond what the f32 kernel
    // resolves: `OtError::NotConverged`.)
    let mut rng = Rng::new(10);
    for (scale, cold_starts) in [(1e15, 0), (1e18, 1)] {
        let (s, t) = (
            random_cloud(&mut rng, 100, scale),
            random_cloud(&mut rng, 100, scale),
        );
        let ex = exact::solve(&s, &t, &ExactSettings::default()).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(ex.stats.cold_starts, cold_starts, "scale {scale:e}");
        let d = dense::solve(&s, &t).unwrap_or_else(|e| panic!("{e}"));
        for debias in [false, true] {
            let settings = SinkhornSettings {
                blur: 3e-3 * f64::from(scale),
                exact_prices: true,
                debias,
                ..SinkhornSettings::default()
            };
            let r = sinkhorn::solve(&s, &t, &settings).unwrap_or_else(|e| panic!("{e}"));
            let Matching::Entropic(plan) = &r.matching else {
                panic!("expected an entropic plan, got {:?}", r.matching);
            };
            let case = format!("scale {scale:e}, debias {debias}");
            // Three exact solves when debiased (source–target, source–source,
            // target–target): beyond the range, all three cold-start.
            let solves = if debias { 3 } else { 1 };
            assert_eq!(r.stats.cold_starts, solves * cold_starts, "{case}");
            if !debias {
                // The same exact solve as the exact matcher's, counters and all.
                assert_eq!(r.stats.auction_budget_stops, ex.stats.auction_budget_stops);
            }
            // ε = 9e-6 scale², far below the squared gaps between the points:
            // OT_ε is within 0.1 % of the optimal assignment cost.
            assert!(
                (r.loss - d.loss).abs() <= 1e-3 * d.loss,
                "{case}: {:e} vs dense {:e}",
                r.loss,
                d.loss
            );
            let finite = |v: &[f64]| v.iter().all(|t| t.is_finite());
            assert!(finite(&plan.f) && finite(&plan.g), "{case}");
            assert!(r.gradient.iter().flatten().all(|g| g.is_finite()), "{case}");
        }
    }
}

#[test]
fn exact_gradient_is_displacement_to_partner() {
    let (s, t) = blobs_pair(400, 5).unwrap_or_else(|| panic!("fixture"));
    let r = exact::solve(&s, &t, &ExactSettings::default()).unwrap_or_else(|e| panic!("{e}"));
    let perm = permutation(&r.matching);
    for (i, &j) in perm.iter().enumerate() {
        let (p, q) = (s.point(i), t.point(j));
        for d in 0..5 {
            assert!((r.gradient[i][d] - 2.0 * (p[d] - q[d]) / 400.0).abs() <= 1e-7);
        }
    }
}
