//! The image row (current render with the overlay, target, signed
//! difference render − target), the overlay status line and the overlay
//! settings.

use eframe::egui::{self, Color32, Pos2, Rect, Sense, TextureHandle, Vec2};

use crate::app::ViewerApp;
use crate::overlay::{self, Drawn};
use crate::panels::inspect;

/// Draws one texture at `size`; returns its response (hover sensing) and rect.
fn image(
    ui: &mut egui::Ui,
    caption: &str,
    tex: Option<&TextureHandle>,
    size: Vec2,
) -> egui::Response {
    ui.vertical(|ui| {
        ui.label(caption);
        let (rect, response) = ui.allocate_exact_size(size, Sense::hover());
        match tex {
            Some(t) => {
                let uv = Rect::from_min_max(Pos2::ZERO, Pos2::new(1.0, 1.0));
                ui.painter().image(t.id(), rect, uv, Color32::WHITE);
            }
            None => {
                ui.painter().rect_filled(rect, 0.0, Color32::from_gray(30));
            }
        }
        response
    })
    .inner
}

/// Draws the image row and the overlay status line.
pub fn show(ui: &mut egui::Ui, app: &mut ViewerApp) {
    let Some(p) = &app.model.problem else {
        return;
    };
    let t = &p.target.image;
    let aspect = t.height.max(1) as f32 / t.width.max(1) as f32;
    let avail = ui.available_size();
    let width = ((avail.x - 24.0) / 3.0)
        .min((avail.y * 0.62 - 24.0) / aspect)
        .max(64.0);
    let size = Vec2::new(width, width * aspect);
    let render_caption = match &p.render {
        Some((_, spp)) => format!("Render ({spp} spp)"),
        None => "Render (…)".into(),
    };
    let mut drawn = Drawn::default();
    let responses = ui
        .horizontal(|ui| {
            let r = image(
                ui,
                &render_caption,
                p.render.as_ref().map(|(s, _)| &s.texture),
                size,
            );
            if let Some(o) = &p.overlay {
                drawn = overlay::paint(ui.painter(), r.rect, o, &app.overlay);
            }
            let t = image(ui, "Target", Some(&p.target.texture), size);
            let d = image(ui, "Difference (render − target)", p.diff.as_ref(), size);
            [r, t, d]
        })
        .inner;
    for r in responses {
        if let Some(pos) = r.hover_pos() {
            let uv = (pos - r.rect.min) / r.rect.size();
            r.on_hover_ui_at_pointer(|ui| inspect::show(ui, p, uv));
        }
    }
    let status = match (&p.overlay, app.controls.overlay_param) {
        (Some(o), Some(_)) => {
            let key = p
                .params
                .get(o.data.param)
                .map(|s| s.key.as_str())
                .unwrap_or("?");
            format!(
                "Overlay: {key} (iteration {}): {} arrows, {} matching lines",
                o.data.iteration, drawn.arrows, drawn.lines
            )
        }
        (None, Some(_)) => "Overlay: computing …".into(),
        (_, None) => "Overlay: none".into(),
    };
    ui.label(status);
}

/// Draws the overlay toggles and densities.
pub fn overlay_settings(ui: &mut egui::Ui, app: &mut ViewerApp) {
    let s = &mut app.overlay;
    ui.label("Overlay of the chosen parameter:");
    ui.checkbox(&mut s.arrows, "dp/dθ arrows");
    ui.add_enabled(
        s.arrows,
        egui::Slider::new(&mut s.arrow_spacing, 1..=16).text("arrow spacing (px)"),
    );
    ui.checkbox(&mut s.flow, "dp/dθ flow colours");
    ui.checkbox(&mut s.heat, "dI/dθ heat map");
    ui.checkbox(&mut s.matching, "OT matching lines");
    ui.add_enabled(
        s.matching,
        egui::Slider::new(&mut s.matching_every, 1..=64).text("every n-th line"),
    );
}
