//! The parameter list: per parameter its key, a slider over its bounds
//! (moving it re-renders the scene), the bounds, the true value, `dL/dθ`
//! from the latest overlay, and the radio button choosing the overlay's
//! parameter.

use eframe::egui;

use crate::app::ViewerApp;
use crate::worker::Command;

/// The slider range of a parameter: its bounds when finite, else a span
/// around its current and true values.
fn range(bounds: [f64; 2], value: f64, truth: Option<f64>) -> std::ops::RangeInclusive<f64> {
    if bounds[0].is_finite() && bounds[1].is_finite() && bounds[1] - bounds[0] < 1e6 {
        return bounds[0]..=bounds[1];
    }
    let t = truth.unwrap_or(value);
    let span = (value - t).abs().max(value.abs() * 0.5).max(1.0);
    let lo = value.min(t) - span;
    let hi = value.max(t) + span;
    lo.max(bounds[0])..=hi.min(bounds[1])
}

fn bound_text(b: f64) -> String {
    if b.abs() >= f64::MAX / 2.0 {
        "∞".into()
    } else {
        format!("{b}")
    }
}

/// Draws the parameter list.
pub fn show(ui: &mut egui::Ui, app: &mut ViewerApp) {
    let Some(p) = app.model.problem.as_mut() else {
        return;
    };
    ui.label("Parameters (the selected one gets the overlay):");
    let mut overlay = app.controls.overlay_param;
    let mut moved = false;
    let gradient = p.overlay.as_ref().map(|o| o.data.gradient.clone());
    egui::Grid::new("params").striped(true).show(ui, |ui| {
        ui.label("");
        ui.label("value");
        ui.label("true");
        ui.label("dL/dθ");
        ui.end_row();
        for (i, spec) in p.params.iter().enumerate() {
            let name = ui.radio_value(&mut overlay, Some(i), &spec.key);
            let Some(value) = p.theta.get_mut(i) else {
                continue;
            };
            let r = range(spec.bounds, *value, spec.true_value);
            moved |= ui
                .add(egui::Slider::new(value, r))
                .labelled_by(name.id)
                .changed();
            ui.label(
                spec.true_value
                    .map(|t| format!("{t}"))
                    .unwrap_or_else(|| "?".into()),
            );
            let g = gradient.as_ref().and_then(|g| g.get(i));
            ui.label(g.map(|g| format!("{g:.3e}")).unwrap_or_default());
            ui.end_row();
            ui.label("");
            ui.small(format!(
                "bounds [{}, {}], lr {}",
                bound_text(spec.bounds[0]),
                bound_text(spec.bounds[1]),
                spec.lr * app.controls.lr_scale
            ));
            ui.end_row();
        }
    });
    let theta = p.theta.clone();
    if moved {
        app.send(Command::SetTheta(theta));
    }
    if overlay != app.controls.overlay_param {
        app.controls.overlay_param = overlay;
        app.send(Command::OverlayParam(overlay));
    }
}
