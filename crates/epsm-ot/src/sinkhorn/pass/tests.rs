//! Kernel-pass tests: points that keep nothing, and cut passes against uncut ones.

use super::*;
use crate::SinkhornSettings;
use crate::clusters::Support;
use crate::cost::diameter_sq;
use crate::sinkhorn::solve_dual;
use crate::synthetic::blobs_pair;

#[test]
fn a_point_that_keeps_nothing_streams_every_block() {
    let (s, t) = blobs_pair(512, 2).unwrap_or_else(|| panic!("fixture"));
    let (cx, cy) = (Clustered::new(&s, 16), Clustered::new(&t, 16));
    let y = Level::fine(&cy);
    let own = vec![-1.0; s.len()];
    let cut = Cut {
        own: &own,
        threshold: 0.0,
    };
    let list: Vec<u32> = (0..cy.clusters.len() as u32).collect();
    for bound in [Bound::Box, Bound::Ball] {
        let fitted = Fitted::new(&y, &vec![0.0; t.len()], Some(cut), bound);
        let mut targets = Targets::default();
        targets.load(&y, &list, fitted.as_ref());
        targets.point(fitted.as_ref(), 0, &cx.cloud.point(0));
        let mut kept = Vec::new();
        targets.kept_into(&mut kept);
        assert_eq!(kept, (0..list.len()).collect::<Vec<_>>());
        assert_eq!(targets.ranges().to_vec(), vec![0..t.len()]);
    }
}

#[test]
fn cut_passes_match_uncut_passes_with_fewer_pairs() {
    let (s, t) = blobs_pair(2048, 4).unwrap_or_else(|| panic!("fixture"));
    let (cx, cy) = (Clustered::new(&s, 32), Clustered::new(&t, 32));
    let settings = SinkhornSettings {
        blur: 0.02,
        ..SinkhornSettings::default()
    };
    let eps = settings.blur * settings.blur;
    let dual = solve_dual(&cx, &cy, diameter_sq(&s, &t), &settings);
    let (x, y) = (Level::fine(&cx), Level::fine(&cy));
    let (f, g) = (&dual.f, &dual.g);
    let sup = Support::truncated(
        &cx,
        &fit_potentials(&cx, f),
        &cy,
        &fit_potentials(&cy, g),
        settings.truncation * eps,
    );
    let cut = Some(Cut {
        own: f,
        threshold: settings.truncation * eps,
    });
    let (whole, whole_pairs) = softmin(&x, &y, &sup.rows, g, eps, None);
    let (part, part_pairs) = softmin(&x, &y, &sup.rows, g, eps, cut);
    assert!(
        2 * part_pairs < whole_pairs,
        "cut {part_pairs} of {whole_pairs} pairs"
    );
    assert_eq!(whole.len(), part.len());
    for (i, (a, b)) in whole.iter().zip(&part).enumerate() {
        assert!((a - b).abs() <= 1e-5 * eps, "point {i}: {a} vs {b}");
    }
    let blocks = |cut| softmin_blocks(&x, &y, &sup.rows, g, eps, |i, _| f[i], cut);
    let (whole, part) = (blocks(None), blocks(cut));
    assert_eq!(whole.pairs, whole_pairs);
    // Block passes cut by the looser ball bound: more pairs than the box, fewer than none.
    assert!(
        part_pairs < part.pairs && part.pairs < whole_pairs,
        "block pass: {} pairs, box {part_pairs}, uncut {whole_pairs}",
        part.pairs
    );
    let mass = |m: &[Vec<f64>]| m.iter().flatten().map(|v| v.exp()).sum::<f64>();
    assert!((mass(&whole.log_masses) - mass(&part.log_masses)).abs() <= 1e-6);
    assert_eq!(whole.softmin.len(), part.softmin.len());
    for (a, b) in whole.softmin.iter().zip(&part.softmin) {
        assert!((a - b).abs() <= 1e-5 * eps, "{a} vs {b}");
    }
}
