//! The losses' checks.

use super::*;

fn dot(w: u32, h: u32, at: (u32, u32)) -> Image {
    let mut img = Image::new(w, h);
    img.set(at.0, at.1, Vec3::splat(4.0));
    img
}

#[test]
fn ot_pulls_a_bright_pixel_toward_the_target_one() {
    let (img, target) = (dot(8, 8, (1, 4)), dot(8, 8, (6, 4)));
    let e = evaluate(LossKind::OtExact, &img, &target, 1.0, None).expect("loss");
    let i = 4 * 8 + 1;
    // Moving the bright pixel right (+x) lowers the loss.
    assert!(e.g_xy[i].x < 0.0, "g_xy = {:?}", e.g_xy[i]);
    assert!(e.g_xy[i].y.abs() < 1e-6);
    let m = e.matched.expect("matching")[i];
    assert!(
        (m.x - 6.5).abs() < 1e-3 && (m.y - 4.5).abs() < 1e-3,
        "{m:?}"
    );
    assert!(e.value > 0.0);
}

#[test]
fn a_target_firefly_pulls_the_match_until_it_is_replaced() {
    // The same blob in both images; the target also has a firefly.
    let img = blob(8.0);
    let mut target = blob(8.0);
    target.set(13, 3, Vec3::splat(40.0));
    let raw = evaluate(LossKind::OtExact, &img, &target, 1.0, None).expect("loss");
    let (clean, replaced) = despeckle(&target);
    assert_eq!(replaced.iter().filter(|&&r| r).count(), 1);
    assert!(replaced[3 * 16 + 13]);
    let e = evaluate(LossKind::OtExact, &img, &clean, 1.0, None).expect("loss");
    assert!(raw.value > 1e-4, "raw loss {}", raw.value);
    assert!(
        e.value < 1e-3 * raw.value,
        "{} against {}",
        e.value,
        raw.value
    );
    let pull = |l: &LossEval| l.g_xy.iter().map(|g| g.length()).fold(0.0, f64::max);
    assert!(
        pull(&e) < 1e-3 * pull(&raw),
        "{} against {}",
        pull(&e),
        pull(&raw)
    );
}

#[test]
fn l2_gradient_matches_a_finite_difference() {
    let (img, target) = (dot(4, 4, (1, 1)), dot(4, 4, (2, 2)));
    let e = evaluate(LossKind::L2, &img, &target, 1.0, None).expect("loss");
    let h = 1e-2;
    let at = |d: f32| {
        let mut bumped = img.clone();
        bumped.pixels[5].x += d;
        evaluate(LossKind::L2, &bumped, &target, 1.0, None)
            .expect("loss")
            .value
    };
    let fd = (at(h) - at(-h)) / f64::from(2.0 * h);
    assert!((fd - f64::from(e.g_rgb[5].x)).abs() < 1e-3 * fd.abs().max(1e-3));
    assert!((rmse(&img, &img)).abs() < 1e-12);
}

/// A smooth blob centred at `cx` (pixels) on a dim background.
fn blob(cx: f32) -> Image {
    let mut img = Image::new(16, 16);
    for y in 0..16 {
        for x in 0..16 {
            let d2 = (x as f32 + 0.5 - cx).powi(2) + (y as f32 + 0.5 - 8.0).powi(2);
            img.set(
                x,
                y,
                Vec3::new(0.1, 0.1, 0.1) + Vec3::new(3.0, 2.0, 1.0) * (-d2 / 8.0).exp(),
            );
        }
    }
    img
}

#[test]
fn colour_flow_gives_a_uniform_shift_its_finite_difference() {
    // The render is the target shifted right by `s` pixels: every pixel's
    // content moves with dp/ds = (1, 0), so dL/ds = Σ g_xy.x.
    let (target, s, h) = (blob(8.0), 1.5f32, 0.02f32);
    let at = |shift: f32| {
        evaluate(LossKind::OtExact, &blob(8.0 + shift), &target, 1.0, None).expect("loss")
    };
    let fd = (at(s + h).value - at(s - h).value) / f64::from(2.0 * h);
    let mut e = at(s);
    let ot_sum: f64 = e.g_xy.iter().map(|g| g.x).sum();
    let ot_abs: f64 = e.g_xy.iter().map(|g| g.x.abs()).sum();
    // The OT's own screen gradients cancel: blind to a uniform shift.
    assert!(ot_sum.abs() < 1e-4 * ot_abs, "{ot_sum} of {ot_abs}");
    add_flow(&blob(8.0 + s), &mut e).expect("same size");
    let flow_sum: f64 = e.g_xy.iter().map(|g| g.x).sum();
    assert!(fd > 0.0, "moving the blob away raises the loss: {fd}");
    assert!(
        (flow_sum - fd).abs() < 0.1 * fd,
        "flow {flow_sum} vs fd {fd}"
    );
    assert!(add_flow(&Image::new(3, 3), &mut e).is_err());
}

#[test]
fn a_warm_exact_loss_equals_the_cold_one_along_a_moving_blob() {
    let target = blob(8.0);
    let mut state = MatchState::new();
    for step in 0..4 {
        let image = blob(5.0 + 0.3 * step as f32);
        let cold = evaluate(LossKind::OtExact, &image, &target, 1.0, None).expect("loss");
        let warm =
            evaluate(LossKind::OtExact, &image, &target, 1.0, Some(&mut state)).expect("loss");
        assert!(!state.is_empty(), "step {step}: the state is kept");
        assert!(
            (warm.value - cold.value).abs() <= 1e-12 * cold.value,
            "step {step}: {} vs {}",
            warm.value,
            cold.value
        );
        // The gradients sum alike (a different matching among ties moves no total).
        let sum = |e: &LossEval| e.g_xy.iter().map(|g| g.x).sum::<f64>();
        assert!((sum(&warm) - sum(&cold)).abs() < 1e-6, "step {step}");
    }
    // L2 leaves the state alone.
    evaluate(LossKind::L2, &target, &target, 1.0, Some(&mut state)).expect("loss");
    assert!(!state.is_empty());
}

#[test]
fn a_non_finite_pixel_fails_every_loss_naming_the_pixel() {
    // OT: instead of matching it as black; L2: instead of a NaN loss.
    for bad in [f32::NAN, f32::INFINITY, f32::NEG_INFINITY] {
        assert!(tone_map(bad).is_nan(), "{bad}");
        let mut img = dot(4, 4, (1, 1));
        img.set(2, 3, Vec3::new(0.5, bad, 0.5));
        let dot2 = dot(4, 4, (2, 2));
        for (image, target, which) in [(&img, &dot2, "rendered image"), (&dot2, &img, "target")] {
            for kind in [LossKind::OtExact, LossKind::L2] {
                let e = evaluate(kind, image, target, 1.0, None);
                assert!(
                    matches!(
                        e,
                        Err(OptimizeError::NonFinitePixel {
                            image,
                            x: 2,
                            y: 3,
                            channel: "g",
                            ..
                        }) if image == which
                    ),
                    "{kind:?} {bad}: {e:?}"
                );
            }
        }
        // The OT points alone still refuse it, by point.
        assert!(matches!(
            points(&img, 1.0),
            Err(OptimizeError::Ot(epsm_ot::OtError::NonFinite {
                index: 14,
                axis: "g",
                ..
            }))
        ));
    }
    assert_eq!(
        (tone_map(-1.0), tone_map(1.0), tone_map(f32::MAX)),
        (0.0, 0.5, 1.0)
    );
}

#[test]
fn l2_of_huge_finite_pixels_is_finite_and_exact() {
    // One pixel 1e20 against −1e20 in every channel of a 2x1 image (the
    // other pixel equal): d = 2e20, L = 3 d² / (3 · 2) = 2e40 and
    // ∂L/∂c = 2 d / (3 · 2) = 2e20 / 3. In f32 d² overflowed: L = +∞.
    let (mut img, mut target) = (Image::new(2, 1), Image::new(2, 1));
    img.set(0, 0, Vec3::splat(1e20));
    target.set(0, 0, Vec3::splat(-1e20));
    let e = evaluate(LossKind::L2, &img, &target, 1.0, None).expect("loss");
    let d = 2.0 * f64::from(1e20f32);
    assert!((e.value / (d * d / 2.0) - 1.0).abs() < 1e-15, "{}", e.value);
    assert!((e.value / 2e40 - 1.0).abs() < 1e-6);
    for g in e.g_rgb[0].to_array() {
        assert_eq!(g, (d / 3.0) as f32);
    }
    assert_eq!(e.g_rgb[1], Vec3::ZERO);
    let r = rmse(&img, &target);
    assert!((r / (d / 2f64.sqrt()) - 1.0).abs() < 1e-15, "{r}");
    // The extremes of f32: still finite.
    img.set(0, 0, Vec3::splat(f32::MAX));
    target.set(0, 0, Vec3::splat(-f32::MAX));
    let e = evaluate(LossKind::L2, &img, &target, 1.0, None).expect("loss");
    assert!(e.value.is_finite() && e.g_rgb[0].is_finite() && rmse(&img, &target).is_finite());
}

#[test]
fn mismatched_sizes_are_an_error() {
    assert!(
        evaluate(
            LossKind::L2,
            &Image::new(2, 2),
            &Image::new(3, 2),
            1.0,
            None
        )
        .is_err()
    );
    assert_eq!(resample(&dot(4, 4, (0, 0)), 2, 2).get(0, 0), Vec3::ONE);
}

#[test]
fn resample_averages_huge_finite_pixels_without_overflow() {
    // Two huge finite pixels: their f32 sum overflows, their mean does not.
    let mut huge = Image::new(2, 1);
    huge.set(0, 0, Vec3::splat(3e38));
    huge.set(1, 0, Vec3::new(3e38, 1e38, -3e38));
    assert_eq!(resample(&huge, 1, 1).get(0, 0), Vec3::new(3e38, 2e38, 0.0));
    // A non-finite pixel stays non-finite, for evaluate to report.
    huge.set(1, 0, Vec3::new(f32::NAN, 1.0, 1.0));
    assert!(resample(&huge, 1, 1).get(0, 0).x.is_nan());
}
