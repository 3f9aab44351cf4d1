//! Sinkhorn tests: the exit guard on non-finite values.

use super::*;

#[test]
fn the_exit_guard_names_the_first_non_finite_value() {
    let a = PointCloud::from_points(&[[0.1, 0.2, 0.3, 0.4, 0.5], [0.9, 0.8, 0.7, 0.6, 0.5]])
        .unwrap_or_else(|e| panic!("{e}"));
    let b = PointCloud::from_points(&[[0.5, 0.2, 0.3, 0.4, 0.0], [0.1, 0.9, 0.7, 0.6, 0.5]])
        .unwrap_or_else(|e| panic!("{e}"));
    let r = solve(&a, &b, &SinkhornSettings::default()).unwrap_or_else(|e| panic!("{e}"));
    let Matching::Entropic(plan) = &r.matching else {
        panic!("not an entropic plan");
    };
    assert_eq!(check_finite(r.loss, plan, &r.gradient), Ok(()));
    let expect = |quantity, index| Err(OtError::NonFiniteResult { quantity, index });
    for bad in [f64::INFINITY, f64::NEG_INFINITY, f64::NAN] {
        assert_eq!(check_finite(bad, plan, &r.gradient), expect("loss", None));
        let mut p = plan.clone();
        p.f[1] = bad;
        assert_eq!(
            check_finite(r.loss, &p, &r.gradient),
            expect("potential f", Some(1))
        );
        let mut p = plan.clone();
        p.g[0] = bad;
        assert_eq!(
            check_finite(r.loss, &p, &r.gradient),
            expect("potential g", Some(0))
        );
        let mut p = plan.clone();
        p.barycentres[1][2] = bad as f32;
        assert_eq!(
            check_finite(r.loss, &p, &r.gradient),
            expect("barycentre", Some(1))
        );
        let mut gradient = r.gradient.clone();
        gradient[1][3] = bad as f32;
        assert_eq!(
            check_finite(r.loss, plan, &gradient),
            expect("gradient", Some(1))
        );
    }
}
