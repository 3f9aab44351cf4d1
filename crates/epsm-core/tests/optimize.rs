//! End-to-end optimization on a tiny scene (32² match resolution): the
//! parameter error falls with `epsm`, the pipeline gradient agrees with
//! finite differences of the loss, and a resumed run repeats the
//! uninterrupted trajectory exactly.

use std::path::Path;

use epsm_core::problem::problem_from_str;
use epsm_core::{Optimization, Problem};
use epsm_testkit::problems::TINY_SETTINGS;

/// The tiny problem's scene file, relative to this crate.
const TINY_SCENE: &str = "../../tests/data/tiny-box.toml";

fn tiny(params: &str) -> Problem {
    let text = format!("scene_file = {TINY_SCENE:?}\n{TINY_SETTINGS}\n{params}");
    problem_from_str(
        &text,
        Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("tiny.toml")
            .as_path(),
    )
    .expect("tiny problem loads")
}

const TRANSLATE: &str = r#"
[[parameters]]
key = "box.translate.x"
initial = 0.7
true = 0.0
bounds = [-1.0, 1.0]
"#;

#[test]
fn epsm_reduces_the_parameter_error_at_least_threefold() {
    let mut opt = Optimization::new(tiny(TRANSLATE)).expect("setup");
    while !opt.is_done() {
        opt.step().expect("iteration");
    }
    let first = opt.rows()[0].param_error.expect("true values known");
    let last = opt.theta()[0].abs();
    assert!((first - 0.7).abs() < 1e-12);
    assert!(last < first / 3.0, "error {first} -> {last}");
    let ot = opt.switch() as usize;
    assert!(ot > 0, "the OT phase ran");
    assert!(
        opt.rows()[..ot].iter().all(|r| r.paths[1] > 0),
        "every OT iteration solved paths"
    );
}

#[test]
fn pipeline_gradient_agrees_with_finite_differences_of_the_loss() {
    // Smooth problem: L2 on an albedo (colour derivatives only). The L2
    // loss is evaluated on a render independent of the differentiated paths
    // (unbiased), so the two agree within Monte Carlo error: 5 % at 32 spp.
    let albedo = r#"
[[parameters]]
key = "box.albedo.r"
initial = 0.5
true = 0.8
"#;
    let mut p = tiny(albedo);
    p.optimizer.method = epsm_core::Method::L2;
    p.passes.spp_grad = 32;
    let mut opt = Optimization::new(p).expect("setup");
    let g = opt.gradient().expect("gradient").0.grad[0];
    let h = 0.01;
    let mut loss_at = |v: f64| {
        opt.set_theta(&[v]);
        opt.gradient().expect("loss").0.loss.value
    };
    let fd = (loss_at(0.5 + h) - loss_at(0.5 - h)) / (2.0 * h);
    assert!(
        g < 0.0,
        "raising the albedo toward its true value lowers the loss: {g}"
    );
    assert!(
        (g - fd).abs() < 0.05 * fd.abs(),
        "analytic {g} vs finite difference {fd}"
    );

    // Geometry with the OT loss: the sign agrees.
    let mut opt = Optimization::new(tiny(TRANSLATE)).expect("setup");
    let g = opt.gradient().expect("gradient").0.grad[0];
    let mut loss_at = |v: f64| {
        opt.set_theta(&[v]);
        opt.gradient().expect("loss").0.loss.value
    };
    let fd = (loss_at(0.8) - loss_at(0.6)) / 0.2;
    assert!(g > 0.0 && fd > 0.0, "analytic {g}, finite difference {fd}");
}

#[test]
fn spp_match_gives_the_loss_its_own_render() {
    // With `spp_match` the OT loss compares an independent render: the loss
    // no longer depends on the gradient pass's sample count, the gradient
    // (its differentiated paths) still does. Without it the loss is the
    // gradient pass's own image (`spp_match = 0`).
    let eval = |spp_grad: u32, spp_match: Option<u32>| {
        let mut p = tiny(TRANSLATE);
        p.passes.spp_grad = spp_grad;
        p.passes.spp_match = spp_match;
        let opt = Optimization::new(p).expect("setup");
        let (g, records) = opt.gradient().expect("gradient");
        assert_eq!(records.len() as u32, 32 * 32 * spp_grad);
        (g.loss.value, g.grad[0])
    };
    let (a, b) = (eval(2, Some(8)), eval(4, Some(8)));
    assert_eq!(a.0, b.0, "the loss follows the matched render only");
    assert_ne!(a.1, b.1, "the gradient follows the recorded paths");
    let (c, d) = (eval(2, Some(0)), eval(4, Some(0)));
    assert_ne!(c.0, d.0, "without spp_match the loss is the pass's image");
    assert!(a.1 > 0.0 && b.1 > 0.0, "{a:?} {b:?}");
}

#[test]
fn a_resumed_run_follows_the_uninterrupted_trajectory() {
    let mut p = tiny(TRANSLATE);
    p.optimizer.iterations = 4;
    let mut whole = Optimization::new(p.clone()).expect("setup");
    while !whole.is_done() {
        whole.step().expect("iteration");
    }
    let mut first = Optimization::new(p.clone()).expect("setup");
    for _ in 0..2 {
        first.step().expect("iteration");
    }
    let json = serde_json::to_string(&first.checkpoint()).expect("serialise");
    let mut resumed = Optimization::new(p).expect("setup");
    resumed
        .restore(serde_json::from_str(&json).expect("parse"))
        .expect("restore");
    while !resumed.is_done() {
        resumed.step().expect("iteration");
    }
    let thetas = |o: &Optimization| o.rows().iter().map(|r| r.theta.clone()).collect::<Vec<_>>();
    assert_eq!(thetas(&whole), thetas(&resumed));
    assert_eq!(whole.theta(), resumed.theta());
    assert_eq!(
        (whole.best(), whole.switch()),
        (resumed.best(), resumed.switch())
    );
    assert!(whole.best().is_some() && whole.switch() <= 3);
}

/// A problem without tuning keys: every automatic choice is made, printed
/// with its reason, and the run recovers the parameter.
#[test]
fn a_problem_without_tuning_keys_gets_every_automatic_choice() {
    let text = format!(
        "{}\n{TRANSLATE}",
        r#"
scene_file = "../../tests/data/tiny-box.toml"
tolerance = 0.1
[target]
spp = 16
[loss]
match_resolution = [32, 32]
[optimizer]
iterations = 12
"#
    );
    let file = Path::new(env!("CARGO_MANIFEST_DIR")).join("tiny.toml");
    let p = problem_from_str(&text, &file).expect("loads");
    assert_eq!(p.tolerance, Some(0.1));
    // Bounds [-1, 1]: the first step is 3 × their width / 12 iterations.
    assert!((p.params[0].lr - 3.0 * 2.0 / 12.0).abs() < 1e-12);
    let mut opt = Optimization::new(p).expect("setup");
    let keys: Vec<&str> = opt.choices().iter().map(|c| c.key.as_str()).collect();
    for key in [
        "parameters[0].lr",
        "loss.flow",
        "optimizer.decay",
        "render.spp_match",
        "optimizer.l2_fraction",
        "best",
    ] {
        assert!(keys.contains(&key), "{key} missing from {keys:?}");
    }
    assert!(opt.choices().iter().all(|c| !c.why.is_empty()));
    let decay = opt.problem().optimizer.decay.expect("resolved");
    assert!((decay.powi(12) - 0.05).abs() < 1e-9);
    while !opt.is_done() {
        opt.step().expect("iteration");
    }
    let best = opt.best().expect("judged");
    assert!(best.theta[0].abs() < 0.7 / 3.0, "best {best:?}");
    assert!(opt.rows().iter().any(|r| r.judged_loss.is_some()));
}

/// With `optimizer.stop` an L2 run whose judged loss stops improving ends
/// before its iteration count.
#[test]
fn stop_ends_a_run_whose_judged_loss_no_longer_improves() {
    let albedo = r#"
[[parameters]]
key = "box.albedo.r"
initial = 0.8
true = 0.8
"#;
    let mut p = tiny(albedo);
    p.optimizer.method = epsm_core::Method::L2;
    p.optimizer.iterations = 60;
    p.optimizer.stop = true;
    let mut opt = Optimization::new(p.clone()).expect("setup");
    while !opt.is_done() {
        opt.step().expect("iteration");
    }
    assert!(opt.iteration() < 60, "ran {} iterations", opt.iteration());
    p.optimizer.stop = false;
    let mut full = Optimization::new(p).expect("setup");
    for _ in 0..opt.iteration() {
        full.step().expect("iteration");
    }
    assert!(!full.is_done(), "without stop the run goes on");
}

#[test]
fn a_checkpoint_file_gives_back_every_value_bit_for_bit() {
    // θ, Adam's moments and the rows go through JSON text: a value parsed to
    // a neighbouring double (by one unit in the last place, as
    // -0.9666738456654929 was) moves the resumed run off the uninterrupted
    // trajectory.
    let opt = Optimization::new(tiny(TRANSLATE)).expect("setup");
    let mut c = opt.checkpoint();
    let mut rng = epsm_testkit::Rng::new(7);
    let mut values = vec![-0.9666738456654929, 0.1 + 0.2, 1e-300, 5e-324];
    while values.len() < 20_000 {
        // Random bit patterns: every exponent, subnormals included.
        let v = f64::from_bits(rng.u64());
        if v.is_finite() {
            values.push(v);
        }
    }
    c.theta = values.clone();
    c.adam.m = values.iter().map(|v| v * 0.5).collect();
    let path = std::env::temp_dir().join(format!("epsm-checkpoint-{}.json", std::process::id()));
    std::fs::write(&path, serde_json::to_vec_pretty(&c).expect("serialise")).expect("write");
    let back = Optimization::load_checkpoint(&path).expect("load");
    std::fs::remove_file(&path).expect("remove");
    for (name, read, written) in [
        ("theta", &back.theta, &c.theta),
        ("adam.m", &back.adam.m, &c.adam.m),
    ] {
        assert_eq!(read.len(), written.len(), "{name}: values read and written");
        let changed: Vec<(f64, f64)> = written
            .iter()
            .zip(read)
            .filter(|(w, r)| w.to_bits() != r.to_bits())
            .map(|(w, r)| (*w, *r))
            .take(3)
            .collect();
        assert!(changed.is_empty(), "{name}: written, read: {changed:?}");
    }
}

#[test]
fn a_checkpoint_that_does_not_fit_the_problem_is_rejected_naming_the_field() {
    let mut p = tiny(TRANSLATE);
    p.optimizer.iterations = 2;
    let mut run = Optimization::new(p.clone()).expect("setup");
    run.step().expect("iteration");
    let good = run.checkpoint();
    type Edit = fn(&mut epsm_core::Checkpoint);
    let cases: [(&str, Edit); 8] = [
        ("adam.m: 0 entries", |c| c.adam.m.clear()),
        ("adam.v: 0 entries", |c| c.adam.v.clear()),
        ("adam.settings", |c| c.adam.settings.lr.clear()),
        ("adam.settings", |c| c.adam.settings.beta1 = 1.0),
        ("adam.t", |c| c.adam.t = c.adam.iteration + 1),
        ("theta[0]: 50 is outside the bounds", |c| c.theta[0] = 50.0),
        ("wall_s", |c| c.wall_s = -1.0),
        ("rows: 0 rows for 1 iterations", |c| c.rows.clear()),
    ];
    let dir = tempfile::tempdir().expect("temp dir");
    let path = dir.path().join("checkpoint.json");
    for (expected, edit) in cases {
        let mut c = good.clone();
        edit(&mut c);
        std::fs::write(&path, serde_json::to_vec(&c).expect("serialise")).expect("write");
        let mut resumed = Optimization::new(p.clone()).expect("setup");
        let read = Optimization::load_checkpoint(&path).expect("read");
        let err = resumed.resume(&path, read).expect_err(expected).to_string();
        assert!(
            err.contains("checkpoint.json") && err.contains(expected),
            "{expected}: {err}"
        );
    }
    std::fs::write(&path, serde_json::to_vec(&good).expect("serialise")).expect("write");
    let mut resumed = Optimization::new(p).expect("setup");
    let read = Optimization::load_checkpoint(&path).expect("read");
    resumed
        .resume(&path, read)
        .expect("the unedited checkpoint resumes");
}

#[test]
fn overlapped_and_serial_iterations_follow_the_same_trajectory() {
    let mut p = tiny(TRANSLATE);
    p.passes.spp_match = Some(4);
    p.optimizer.iterations = 4;
    let run = |overlap: bool| {
        let mut opt = Optimization::new(p.clone()).expect("setup");
        opt.set_overlap(overlap);
        let mut rows = Vec::new();
        while !opt.is_done() {
            let r = opt.step().expect("iteration");
            rows.push((r.loss.to_bits(), r.image_rmse.to_bits(), r.theta));
        }
        rows
    };
    let (serial, overlapped) = (run(false), run(true));
    assert_eq!(serial.len(), 4);
    assert_eq!(serial, overlapped);
}

#[test]
fn prdpt_moves_a_translation_toward_the_truth() {
    // Starting where the box still overlaps its target: PRDPT's smoothing
    // (0.1 of the scale its step size implies, 0.4 here) reaches it.
    let mut p = tiny(&TRANSLATE.replace("initial = 0.7", "initial = 0.3"));
    p.optimizer.method = epsm_core::Method::Prdpt;
    p.optimizer.iterations = 12;
    let mut opt = Optimization::new(p).expect("setup");
    while !opt.is_done() {
        let row = opt.step().expect("iteration");
        assert_eq!(row.paths[1], 0, "no manifold solves");
    }
    let last = opt.theta()[0].abs();
    assert!(last < 0.3 * 0.5, "error 0.3 -> {last}");
}

/// A camera translation with the colour-flow term (on by default for
/// camera parameters): in the OT phase and in the L2 phase the gradient
/// points toward the truth and has the sign and order of the central
/// difference of the phase's loss; at the truth it is small against the
/// gradient at the offset (the loss compares a render independent of the
/// differentiated paths, so its noise does not bias the flow term).
#[test]
fn camera_gradient_with_flow_follows_the_loss_in_both_phases() {
    let camera = r#"
[[parameters]]
key = "camera.translate.x"
initial = 0.15
true = 0.0
bounds = [-0.5, 0.5]
"#;
    for l2_fraction in [0.0, 1.0] {
        let mut p = tiny(camera);
        p.loss.flow = None;
        p.passes.spp_match = None;
        p.passes.spp_grad = 16;
        p.optimizer.l2_fraction = Some(l2_fraction);
        let mut opt = Optimization::new(p).expect("setup");
        assert_eq!(opt.problem().loss.flow, Some(true));
        assert!(opt.problem().passes.spp_match.unwrap_or(0) > 0);
        let mut at = |v: f64| {
            opt.set_theta(&[v]);
            let (g, _) = opt.gradient().expect("gradient");
            (g.grad[0], g.loss.value)
        };
        let (g, _) = at(0.15);
        let (g0, _) = at(0.0);
        let h = 0.03;
        let fd = (at(0.15 + h).1 - at(0.15 - h).1) / (2.0 * h);
        assert!(
            g > 0.0 && fd > 0.0,
            "gradient {g:e}, finite difference {fd:e}"
        );
        assert!(
            g < 1.5 * fd && g > 0.5 * fd,
            "gradient {g:e}, finite difference {fd:e}"
        );
        assert!(g0.abs() < 0.25 * g, "at the truth {g0:e} against {g:e}");
    }
}

/// The colour-flow term is on by default when every moving object is seen
/// directly, and off when a light moves or a moving object is out of view.
#[test]
fn the_flow_term_follows_what_the_camera_sees() {
    let case = |key: &str, initial: f64| {
        let text = format!(
            "[[parameters]]\nkey = \"{key}\"\ninitial = {initial}\ntrue = 0.0\nbounds = [-6.0, 6.0]\n"
        );
        let mut p = tiny(&text);
        p.loss.flow = None;
        let opt = Optimization::new(p).expect("setup");
        let choice = opt
            .choices()
            .iter()
            .find(|c| c.key == "loss.flow")
            .expect("flow chosen")
            .clone();
        (opt.problem().loss.flow, choice.why)
    };
    let (seen, why) = case("box.translate.x", 0.2);
    assert_eq!(seen, Some(true), "{why}");
    let (light, why) = case("lamp.translate.x", 0.2);
    assert_eq!(light, Some(false), "{why}");
    assert!(why.contains("light"), "{why}");
    let (hidden, why) = case("box.translate.x", 5.5);
    assert_eq!(hidden, Some(false), "{why}");
    assert!(why.contains("not seen directly"), "{why}");
}
