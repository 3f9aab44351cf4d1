//! The viewer's panels: [`side`] (open, controls, parameters, overlay
//! settings) and [`central`] (messages, images, plot).

mod controls;
mod images;
mod inspect;
mod open;
mod params;

use eframe::egui::{self, Color32, RichText};

use crate::app::ViewerApp;

pub use open::problem_dir;

/// The left panel.
pub fn side(ui: &mut egui::Ui, app: &mut ViewerApp) {
    egui::CollapsingHeader::new("Problem files")
        .default_open(app.model.problem.is_none())
        .show(ui, |ui| open::show(ui, app));
    ui.separator();
    controls::show(ui, app);
    ui.separator();
    params::show(ui, app);
    ui.separator();
    images::overlay_settings(ui, app);
}

/// The central panel.
pub fn central(ui: &mut egui::Ui, app: &mut ViewerApp) {
    if let Some(e) = &app.model.error {
        ui.label(RichText::new(format!("Error: {e}")).color(Color32::from_rgb(230, 80, 60)));
    }
    if let Some(path) = &app.model.loading {
        ui.horizontal(|ui| {
            ui.spinner();
            ui.label(format!("Loading {} …", path.display()));
        });
    }
    if app.model.problem.is_none() {
        if app.model.loading.is_none() {
            ui.label("No problem loaded: open one in the panel on the left.");
        }
        return;
    }
    let plot_height = (ui.available_height() * 0.3).clamp(120.0, 260.0);
    images::show(ui, app);
    if let Some(p) = &app.model.problem {
        crate::plot::show(ui, &p.history, plot_height);
    }
}
