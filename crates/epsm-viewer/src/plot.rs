//! The live plot: image RMSE and parameter error (log10) against seconds
//! since the problem was loaded, one point per iteration.

use eframe::egui;
use egui_plot::{Legend, Line, Plot};

use crate::state::HistoryPoint;

/// Draws the plot of `history` with the given height (points).
pub fn show(ui: &mut egui::Ui, history: &[HistoryPoint], height: f32) {
    let rmse: Vec<[f64; 2]> = history
        .iter()
        .filter(|p| p.image_rmse > 0.0)
        .map(|p| [p.wall_s, p.image_rmse.log10()])
        .collect();
    let error: Vec<[f64; 2]> = history
        .iter()
        .filter_map(|p| Some([p.wall_s, p.param_error.filter(|e| *e > 0.0)?.log10()]))
        .collect();
    ui.label(format!("Plot: {} points", history.len()));
    Plot::new("history")
        .height(height)
        .legend(Legend::default())
        .x_axis_label("wall clock (s)")
        .y_axis_label("log10")
        .show(ui, |plot| {
            plot.line(Line::new("image RMSE", rmse));
            if !error.is_empty() {
                plot.line(Line::new("parameter error", error));
            }
        });
}
