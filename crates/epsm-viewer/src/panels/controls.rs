//! Run controls: run / pause / step / reset, the method and the
//! learning-rate factor, and the iteration counter.

use eframe::egui;
use epsm_core::Method;

use crate::app::ViewerApp;
use crate::worker::{Command, RunSettings};

/// Draws the controls.
pub fn show(ui: &mut egui::Ui, app: &mut ViewerApp) {
    let Some(p) = &app.model.problem else {
        return;
    };
    let (iteration, iterations) = (p.iteration, p.iterations);
    let done = iteration >= iterations;
    let running = app.model.running;
    ui.heading(
        p.path
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default(),
    );
    ui.label(format!("Iteration {iteration} / {iterations}"));
    let mut command = None;
    ui.horizontal(|ui| {
        if running {
            if ui.button("Pause").clicked() {
                command = Some(Command::Pause);
            }
        } else if ui.add_enabled(!done, egui::Button::new("Run")).clicked() {
            command = Some(Command::Run(None));
        }
        if ui
            .add_enabled(!running && !done, egui::Button::new("Step"))
            .clicked()
        {
            command = Some(Command::Run(Some(1)));
        }
        if ui.button("Reset").clicked() {
            app.controls.applied = settings(app);
            command = Some(Command::Reset(settings(app)));
        }
    });
    egui::ComboBox::from_label("method")
        .selected_text(app.controls.method.name())
        .show_ui(ui, |ui| {
            for m in Method::ALL {
                ui.selectable_value(&mut app.controls.method, m, m.name());
            }
        });
    let lr = ui.add(
        egui::Slider::new(&mut app.controls.lr_scale, 0.05..=20.0)
            .logarithmic(true)
            .text("learning rate ×"),
    );
    // Applied when the slider is let go (each change restarts Adam).
    let chosen = settings(app);
    if command.is_none() && chosen != app.controls.applied && !lr.dragged() {
        app.controls.applied = chosen;
        command = Some(Command::Configure(chosen));
    }
    if let Some(c) = command {
        app.send(c);
    }
}

fn settings(app: &ViewerApp) -> RunSettings {
    RunSettings {
        method: app.controls.method,
        lr_scale: app.controls.lr_scale,
    }
}
