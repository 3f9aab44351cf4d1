//! Warm-started solves (`crate::warm`): the same optimum as cold solves along a
//! sequence of perturbed clouds, after unrelated or mismatched states, and
//! bit-identical whatever the number of threads.

use super::random_cloud;
use crate::cost::{assignment_cost, sq_dist_f64};
use crate::exact::{ExactSettings, dense};
use crate::plan::{Matching, OtResult};
use crate::points::{Point, PointCloud};
use crate::synthetic::{Rng, blobs_pair};
use crate::warm::MatchState;
use crate::{Matcher, SinkhornSettings};

/// `cloud` with every coordinate moved by up to `±amount` (and kept in `[0, 1]`).
fn jittered(cloud: &PointCloud, rng: &mut Rng, amount: f32) -> PointCloud {
    let points: Vec<Point> = cloud
        .points()
        .map(|p| p.map(|v| (v + amount * (2.0 * rng.uniform() - 1.0)).clamp(0.0, 1.0)))
        .collect();
    PointCloud::from_points(&points).unwrap_or_else(|e| panic!("{e}"))
}

fn ok(r: Result<OtResult, crate::OtError>) -> OtResult {
    r.unwrap_or_else(|e| panic!("{e}"))
}

/// Checks a warm exact result against the cold solve and the dense optimum, and its
/// kept potentials as a certificate: `u_i = c_iσ(i) − v_σ(i)` feasible for all pairs.
fn check_exact(source: &PointCloud, target: &PointCloud, warm: &OtResult, state: &MatchState) {
    let cold = ok(Matcher::Exact(ExactSettings::sparse_only()).solve(source, target));
    let oracle = ok(dense::solve(source, target));
    let Matching::Permutation(perm) = &warm.matching else {
        panic!("not a permutation");
    };
    let mut seen = vec![false; perm.len()];
    perm.iter().for_each(|&j| seen[j] = true);
    assert!(seen.iter().all(|&s| s), "a permutation");
    assert_eq!(assignment_cost(source, target, perm), warm.loss);
    let scale = 1e-12 * oracle.loss.max(1e-300);
    assert!(
        (warm.loss - cold.loss).abs() <= scale,
        "{} {}",
        warm.loss,
        cold.loss
    );
    assert!(
        (warm.loss - oracle.loss).abs() <= scale,
        "{} {}",
        warm.loss,
        oracle.loss
    );
    let v = state
        .exact_potentials()
        .unwrap_or_else(|| panic!("an exact state"));
    for (i, p) in source.points().enumerate() {
        let u = sq_dist_f64(&p, &target.point(perm[i])) - v[perm[i]];
        for (j, q) in target.points().enumerate() {
            let reduced = sq_dist_f64(&p, &q) - u - v[j];
            assert!(reduced >= -1e-10, "pair ({i}, {j}) violated by {reduced}");
        }
    }
}

#[test]
fn warm_exact_solves_equal_cold_ones_along_a_perturbed_sequence_and_after_a_jump() {
    let matcher = Matcher::Exact(ExactSettings::sparse_only());
    let (mut source, target) = blobs_pair(400, 3).unwrap_or_else(|| panic!("fixture"));
    let mut rng = Rng::new(11);
    let mut state = MatchState::new();
    for step in 0..5 {
        let warm = ok(matcher.solve_warm(&source, &target, &mut state));
        assert_eq!(warm.stats.warm_starts, usize::from(step > 0), "step {step}");
        check_exact(&source, &target, &warm, &state);
        source = jittered(&source, &mut rng, 0.02);
    }
    // A large change: a state from an unrelated cloud still gives the optimum.
    let unrelated = random_cloud(&mut rng, 400, 1.0);
    let warm = ok(matcher.solve_warm(&unrelated, &target, &mut state));
    assert_eq!(warm.stats.warm_starts, 1);
    check_exact(&unrelated, &target, &warm, &state);
    // And so does a new target with the state of the old one.
    let other_target = random_cloud(&mut rng, 400, 1.0);
    let warm = ok(matcher.solve_warm(&source, &other_target, &mut state));
    assert_eq!(warm.stats.warm_starts, 1);
    check_exact(&source, &other_target, &warm, &state);
}

#[test]
fn a_state_of_another_size_or_matcher_starts_cold_and_a_failed_solve_empties_it() {
    let matcher = Matcher::Exact(ExactSettings::sparse_only());
    let mut rng = Rng::new(4);
    let (a, b) = (
        random_cloud(&mut rng, 200, 1.0),
        random_cloud(&mut rng, 200, 1.0),
    );
    let mut state = MatchState::new();
    ok(matcher.solve_warm(&a, &b, &mut state));
    assert!(!state.is_empty());
    let (c, d) = (
        random_cloud(&mut rng, 150, 1.0),
        random_cloud(&mut rng, 150, 1.0),
    );
    let r = ok(matcher.solve_warm(&c, &d, &mut state));
    assert_eq!(r.stats.warm_starts, 0, "another n: cold");
    check_exact(&c, &d, &r, &state);
    // Other settings: cold.
    let other = Matcher::Exact(ExactSettings {
        candidates: 4,
        ..ExactSettings::sparse_only()
    });
    assert_eq!(
        ok(other.solve_warm(&c, &d, &mut state)).stats.warm_starts,
        0
    );
    assert_eq!(
        ok(other.solve_warm(&c, &d, &mut state)).stats.warm_starts,
        1
    );
    // Another matcher: cold, and its own state is kept.
    let sinkhorn = Matcher::sinkhorn();
    assert_eq!(
        ok(sinkhorn.solve_warm(&c, &d, &mut state))
            .stats
            .warm_starts,
        0
    );
    assert!(state.exact_potentials().is_none() && !state.is_empty());
    // A failed solve (sizes differ) leaves the state empty.
    assert!(sinkhorn.solve_warm(&a, &d, &mut state).is_err());
    assert!(state.is_empty());
    // The sliced matcher keeps nothing.
    ok(Matcher::sliced().solve_warm(&c, &d, &mut state));
    assert!(state.is_empty());
}

#[test]
fn warm_sinkhorn_reaches_the_cold_fixed_point_within_its_tolerance() {
    for debias in [false, true] {
        let matcher = Matcher::Sinkhorn(SinkhornSettings {
            debias,
            ..SinkhornSettings::default()
        });
        let (mut source, target) = blobs_pair(256, 5).unwrap_or_else(|| panic!("fixture"));
        let mut rng = Rng::new(2);
        let mut state = MatchState::new();
        let mut warm_starts = Vec::new();
        for step in 0..3 {
            let warm = ok(matcher.solve_warm(&source, &target, &mut state));
            let cold = ok(matcher.solve(&source, &target));
            warm_starts.push(warm.stats.warm_starts);
            // A polish that did not converge from the kept potentials was replaced by the cold solve.
            assert_eq!(warm.stats.unconverged_solves, 0);
            let Matching::Entropic(plan) = &warm.matching else {
                panic!("not entropic");
            };
            assert!(plan.marginal_error <= 1e-3, "{}", plan.marginal_error);
            assert!(
                (warm.loss - cold.loss).abs() <= 1e-2 * cold.loss.abs(),
                "debias {debias} step {step}: {} vs {}",
                warm.loss,
                cold.loss
            );
            source = jittered(&source, &mut rng, 0.01);
        }
        let solves = if debias { 3 } else { 1 };
        assert_eq!(
            warm_starts[0], 0,
            "debias {debias}: the first solve is cold"
        );
        assert!(
            warm_starts[1..].iter().all(|&w| w <= solves)
                && warm_starts[1..].iter().sum::<usize>() > 0,
            "debias {debias}: {warm_starts:?}"
        );
    }
}

#[test]
fn warm_sequences_are_bit_identical_whatever_the_thread_count() {
    let (source, target) = blobs_pair(900, 7).unwrap_or_else(|| panic!("fixture"));
    let sequence = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap_or_else(|e| panic!("{e}"));
        pool.install(|| {
            let mut rng = Rng::new(9);
            let mut state = MatchState::new();
            let mut source = source.clone();
            let mut out = Vec::new();
            for _ in 0..3 {
                for matcher in [Matcher::exact(), Matcher::sinkhorn()] {
                    out.push(ok(matcher.solve_warm(&source, &target, &mut state)));
                }
                source = jittered(&source, &mut rng, 0.01);
            }
            out
        })
    };
    assert_eq!(sequence(1), sequence(3));
}
