//! Distribution tests: discrete sampling and pmf, the small-table pick against the
//! binary search, and the 2D density against its table.

use super::*;

#[test]
fn discrete_sampling_skips_zero_weights_and_reports_pmf() {
    let d = Distribution1D::new(&[0.0, 1.0, 0.0, 3.0, 0.0]).expect("non-zero");
    for k in 0..=1000 {
        let s = d.sample_discrete(k as f64 / 1000.0);
        assert!(s.index == 1 || s.index == 3, "{s:?}");
        assert_eq!(s.pmf, d.pmf(s.index));
        assert!((0.0..1.0).contains(&s.u_remapped));
    }
    assert_eq!(d.sample_discrete(0.2).index, 1);
    assert_eq!(d.sample_discrete(0.3).index, 3);
    assert!((d.pmf(3) - 0.75).abs() < 1e-12);
    assert!(Distribution1D::new(&[0.0, 0.0]).is_none());
}

#[test]
fn small_tables_pick_what_the_binary_search_picks() {
    let mut rng = epsm_testkit::Rng::new(17);
    let mut small = 0;
    for n in 1..=SMALL_MAX + 2 {
        for _ in 0..40 {
            // Zero weights (leading, trailing, runs) in about a third.
            let weights: Vec<f64> = (0..n)
                .map(|_| {
                    let w = rng.f64();
                    if w < 0.35 { 0.0 } else { w }
                })
                .collect();
            let Some(d) = Distribution1D::new(&weights) else {
                continue;
            };
            assert_eq!(d.small.is_some(), n <= SMALL_MAX);
            small += usize::from(d.small.is_some());
            let bounds = d.cdf.iter().flat_map(|&c| [c, c.next_down(), c.next_up()]);
            let uniform = (0..200).map(|_| rng.f64());
            for u in bounds.chain(uniform).map(|u| u.clamp(0.0, 1.0)) {
                if let Some(small) = &d.small {
                    assert_eq!(small.pick(u), d.search(u), "{weights:?} at {u}");
                }
            }
        }
    }
    assert!(small > 400, "only {small} small tables");
}

#[test]
fn continuous_2d_density_matches_table_and_integrates_to_one() {
    let (w, h) = (4usize, 3usize);
    let table: Vec<f64> = (0..w * h).map(|i| (i % 5) as f64).collect();
    let d = Distribution2D::new(&table, w, h).expect("non-zero");
    let mean = table.iter().sum::<f64>() / (w * h) as f64;
    let mut integral = 0.0;
    for y in 0..h {
        for x in 0..w {
            let uv = Vec2::new((x as f32 + 0.5) / w as f32, (y as f32 + 0.5) / h as f32);
            let pdf = d.pdf(uv);
            assert!((pdf - table[y * w + x] / mean).abs() < 1e-9);
            integral += pdf / (w * h) as f64;
        }
    }
    assert!((integral - 1.0).abs() < 1e-12);
    let s = d.sample(Vec2::new(0.37, 0.81)).expect("sample");
    assert!((s.pdf - d.pdf(s.uv)).abs() < 1e-9 * s.pdf);
}
