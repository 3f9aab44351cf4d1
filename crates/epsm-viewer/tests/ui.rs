//! Headless UI tests (egui_kittest: the accessibility tree, no GPU, no
//! display). The viewer opens a tiny problem (a box on a floor at 32²,
//! written to a temporary folder) through its Open button, steps it,
//! switches the overlay's parameter, shows the errors of malformed problem
//! files from the shared corpus, and moves the scene from a parameter's
//! value box (the render restarts and refines while idle). The worker runs
//! for real, so each check polls frames until the expected state appears
//! (bounded; no timing is asserted).

use std::path::{Path, PathBuf};
use std::time::Duration;

use eframe::egui::Role;
use egui_kittest::Harness;
use egui_kittest::kittest::{NodeT, Queryable};
use epsm_testkit::problems::TINY_SETTINGS;
use epsm_viewer::worker::MAX_SPP;
use epsm_viewer::{Options, ViewerApp};

/// The tiny problem's parameters ([`TINY_SETTINGS`] over the shared tiny
/// scene): the first is a colour (no motion), the second a translation.
const TINY_PARAMETERS: &str = r#"
[[parameters]]
key = "floor.albedo.r"
initial = 0.5
true = 0.2
bounds = [0.0, 1.0]

[[parameters]]
key = "box.translate.x"
initial = 0.3
true = 0.0
bounds = [-1.0, 1.0]
"#;

fn harness() -> Harness<'static, ViewerApp> {
    let app = ViewerApp::new(Options::default());
    Harness::builder()
        .with_size([1400.0, 1000.0])
        .build_ui_state(|ui, app: &mut ViewerApp| app.show(ui), app)
}

/// Steps frames until `ok` holds (at most about a minute of polling).
fn wait_for(
    h: &mut Harness<'static, ViewerApp>,
    what: &str,
    ok: impl Fn(&Harness<'static, ViewerApp>) -> bool,
) {
    for _ in 0..6000 {
        h.step();
        if ok(h) {
            return;
        }
        std::thread::sleep(Duration::from_millis(10));
    }
    let m = &h.state().model;
    panic!(
        "gave up waiting for {what} (error: {:?}, overlay: {})",
        m.error,
        m.problem.as_ref().is_some_and(|p| p.overlay.is_some())
    );
}

fn has_label(h: &Harness<'static, ViewerApp>, text: &str) -> bool {
    h.query_all_by_label_contains(text).next().is_some()
}

/// Types `path` into the path field's state and presses Open.
fn open(h: &mut Harness<'static, ViewerApp>, path: &Path) {
    h.state_mut().controls.path_text = path.display().to_string();
    h.step();
    h.get_by_label("Open").click();
    h.step();
}

fn tiny_problem(dir: &Path) -> PathBuf {
    let path = dir.join("tiny.toml");
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tests/data/tiny-box.toml");
    let text = format!(
        "scene_file = {:?}\n{TINY_PARAMETERS}\n{TINY_SETTINGS}",
        scene.display().to_string()
    );
    std::fs::write(&path, text).expect("write the tiny problem");
    path
}

/// The arrow count of the overlay status line for `key`, once shown.
fn arrows_for(h: &Harness<'static, ViewerApp>, key: &str) -> Option<usize> {
    let prefix = format!("Overlay: {key} ");
    // A label's text is its node's label, or its text runs' values when wrapped.
    let label = h.query_all_by_label_contains(&prefix).find_map(|n| {
        let node = n.accesskit_node();
        node.label().or_else(|| {
            let runs: Vec<String> = node.children().filter_map(|c| c.value()).collect();
            (!runs.is_empty()).then(|| runs.concat())
        })
    })?;
    let (_, rest) = label.split_once("): ")?;
    rest.split_whitespace().next()?.parse().ok()
}

#[test]
fn step_advances_the_iteration_counter_and_the_plot() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = harness();
    open(&mut h, &tiny_problem(dir.path()));
    wait_for(&mut h, "the problem to load", |h| {
        has_label(h, "Iteration 0 / 10")
    });
    assert!(has_label(&h, "Plot: 0 points"));
    wait_for(&mut h, "a first render", |h| has_label(h, "spp)"));
    h.get_by_label("Step").click();
    wait_for(&mut h, "iteration 1", |h| has_label(h, "Iteration 1 / 10"));
    assert!(has_label(&h, "Plot: 1 points"));
    wait_for(&mut h, "the step to finish", |h| !h.state().model.running);
    h.get_by_label("Step").click();
    wait_for(&mut h, "iteration 2", |h| has_label(h, "Iteration 2 / 10"));
    assert!(has_label(&h, "Plot: 2 points"));
    let theta = h
        .state()
        .model
        .problem
        .as_ref()
        .expect("loaded")
        .theta
        .clone();
    assert!(
        theta[1] < 0.3,
        "the box moved toward its true x = 0: {theta:?}"
    );
    // Closing stops the worker and joins its thread.
    h.state_mut().close();
    assert!(h.state().worker.is_none());
}

#[test]
fn choosing_a_parameter_changes_the_overlay() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = harness();
    open(&mut h, &tiny_problem(dir.path()));
    wait_for(&mut h, "the colour parameter's overlay", |h| {
        arrows_for(h, "floor.albedo.r").is_some()
    });
    assert_eq!(
        arrows_for(&h, "floor.albedo.r"),
        Some(0),
        "a colour moves nothing on screen"
    );
    h.get_by_role_and_label(Role::RadioButton, "box.translate.x")
        .click();
    wait_for(&mut h, "the translation's overlay", |h| {
        arrows_for(h, "box.translate.x").is_some()
    });
    let arrows = arrows_for(&h, "box.translate.x").expect("overlay shown");
    assert!(arrows > 0, "the box's edges move with its x");
    // Hovering the render inspects the pixel under the pointer.
    let caption = h
        .get_all_by_label_contains("Render (")
        .next()
        .expect("render caption")
        .rect();
    h.hover_at(eframe::egui::pos2(
        caption.center().x,
        caption.max.y + 120.0,
    ));
    wait_for(&mut h, "the pixel inspection tooltip", |h| {
        has_label(h, "dp/dθ (")
    });
    assert!(has_label(&h, "paths: "), "path kinds are listed");
    h.remove_cursor();
    // Denser arrows: spacing 4 → 2 draws more of them.
    h.state_mut().overlay.arrow_spacing = 2;
    h.step();
    let denser = arrows_for(&h, "box.translate.x").expect("overlay shown");
    assert!(
        denser > arrows,
        "{denser} arrows at spacing 2 vs {arrows} at 4"
    );
}

#[test]
fn a_malformed_problem_shows_its_error_in_the_window() {
    let corpus = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tests/corpus/problems");
    let mut h = harness();
    open(&mut h, &corpus.join("syntax_error.toml"));
    wait_for(&mut h, "the error message", |h| {
        has_label(h, "Error: could not open")
    });
    assert!(has_label(&h, "syntax_error.toml"));
    open(&mut h, &corpus.join("unknown_object.toml"));
    wait_for(&mut h, "the second error", |h| {
        has_label(h, "unknown_object.toml")
    });
    assert!(
        has_label(&h, "parameters[0].key"),
        "the message names the field"
    );
    assert!(h.state().model.problem.is_none());
    assert!(h.state().worker.as_ref().is_some_and(|w| w.is_alive()));
}

fn render_spp(h: &Harness<'static, ViewerApp>) -> u32 {
    let p = h.state().model.problem.as_ref();
    p.and_then(|p| p.render.as_ref()).map_or(0, |(_, spp)| *spp)
}

#[test]
fn the_render_refines_while_idle_and_a_slider_moves_the_scene() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = harness();
    open(&mut h, &tiny_problem(dir.path()));
    // At the full sample count the worker renders no more at this θ, so
    // any later render is of the moved scene.
    wait_for(&mut h, "the render to refine", |h| render_spp(h) >= MAX_SPP);
    let before = h
        .state()
        .model
        .problem
        .as_ref()
        .and_then(|p| p.render.as_ref());
    let before = before.map(|(r, _)| r.image.clone()).expect("a render");
    // The value box on the translation's row (beside its slider).
    let row = h
        .get_by_role_and_label(Role::RadioButton, "box.translate.x")
        .rect();
    let value_box = h
        .get_all_by_role(Role::SpinButton)
        .find(|b| (b.rect().center().y - row.center().y).abs() < 8.0)
        .expect("a value box on the parameter's row");
    value_box.set_value_accesskit(-0.5);
    wait_for(&mut h, "the worker to take the new θ", |h| {
        let p = h.state().model.problem.as_ref();
        p.is_some_and(|p| (p.theta[1] + 0.5).abs() < 1e-9)
    });
    wait_for(&mut h, "the moved scene to render", |h| {
        let p = h.state().model.problem.as_ref();
        let r = p.and_then(|p| p.render.as_ref());
        r.is_some_and(|(r, _)| r.image != before)
    });
    wait_for(&mut h, "the moved scene to refine", |h| {
        render_spp(h) >= MAX_SPP
    });
    assert_eq!(
        h.state().model.problem.as_ref().expect("loaded").theta[0],
        0.5
    );
}
