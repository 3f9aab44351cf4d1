//! Pixel inspection: under the pointer, the render's and the target's
//! linear RGB, and from the overlay (match resolution) the pixel's
//! differentiable paths by kind, `dp/dθ` and `dI/dθ`.

use eframe::egui;
use epsm_core::PathKind;
use epsm_render::Image;

use crate::state::Problem;

/// The pixel of `img` at normalised position `uv` (`[0, 1]²`, y down).
fn pixel_at(width: u32, height: u32, uv: egui::Vec2) -> Option<(u32, u32)> {
    let (x, y) = (uv.x * width as f32, uv.y * height as f32);
    (x >= 0.0 && y >= 0.0 && x < width as f32 && y < height as f32).then_some((x as u32, y as u32))
}

fn rgb(img: &Image, uv: egui::Vec2) -> String {
    match pixel_at(img.width, img.height, uv) {
        Some((x, y)) => {
            let c = img.get(x, y);
            format!("({x}, {y}) rgb {:.3} {:.3} {:.3}", c.x, c.y, c.z)
        }
        None => "—".into(),
    }
}

/// Draws the inspection of the pixel at `uv`.
pub fn show(ui: &mut egui::Ui, p: &Problem, uv: egui::Vec2) {
    if let Some((r, _)) = &p.render {
        ui.label(format!("render {}", rgb(&r.image, uv)));
    }
    ui.label(format!("target {}", rgb(&p.target.image, uv)));
    let Some(o) = &p.overlay else {
        return;
    };
    let d = &o.data;
    let Some((x, y)) = pixel_at(d.width, d.height, uv) else {
        return;
    };
    let i = (y * d.width + x) as usize;
    let key = p.params.get(d.param).map(|s| s.key.as_str()).unwrap_or("?");
    ui.separator();
    ui.label(format!("match pixel ({x}, {y}), θ = {key}"));
    if let Some(k) = d.kinds.get(i) {
        let kinds: Vec<String> = PathKind::ALL
            .iter()
            .filter(|kind| k[**kind as usize] > 0)
            .map(|kind| format!("{} {}", kind.name(), k[*kind as usize]))
            .collect();
        let text = if kinds.is_empty() {
            "none".into()
        } else {
            kinds.join(", ")
        };
        ui.label(format!("paths: {text}"));
    }
    if let Some(m) = d.motion.get(i) {
        ui.label(format!("dp/dθ ({:.3}, {:.3}) px/unit", m.x, m.y));
    }
    if let Some(c) = d.d_image.pixels.get(i) {
        ui.label(format!("dI/dθ {:.3} {:.3} {:.3} /unit", c.x, c.y, c.z));
    }
}
