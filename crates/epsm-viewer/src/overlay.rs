//! Drawing the gradient overlay of the chosen parameter over the current
//! render: the flow colours and the `dI/dθ` heat map as translucent
//! textures, `dp/dθ` arrows ([`motion_arrows`]) and the OT matching lines,
//! each behind its own toggle. Overlay positions are match-resolution film
//! pixels, mapped onto the image's screen rectangle.

use eframe::egui::{self, Color32, Pos2, Rect, Stroke};
use epsm_core::inspect::{Segment, motion_arrows};

use crate::state::ShownOverlay;

/// Which overlay layers are drawn, and how densely.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OverlaySettings {
    /// Flow colours (hue = direction of dp/dθ, brightness = magnitude).
    pub flow: bool,
    /// dp/dθ arrows.
    pub arrows: bool,
    /// dI/dθ as a signed heat map.
    pub heat: bool,
    /// OT matching lines.
    pub matching: bool,
    /// Arrow spacing (match-resolution pixels).
    pub arrow_spacing: u32,
    /// Draw every n-th matching line.
    pub matching_every: usize,
}

impl Default for OverlaySettings {
    fn default() -> Self {
        Self {
            flow: false,
            arrows: true,
            heat: false,
            matching: false,
            arrow_spacing: 4,
            matching_every: 7,
        }
    }
}

impl OverlaySettings {
    /// The layer names [`Self::with_layers`] accepts.
    pub const LAYERS: [&str; 4] = ["arrows", "flow", "heat", "matching"];

    /// These settings with exactly the named layers on (`arrows`, `flow`,
    /// `heat`, `matching`); an unknown name is an error naming it.
    pub fn with_layers(self, names: &[String]) -> Result<Self, String> {
        let mut s = Self {
            arrows: false,
            flow: false,
            heat: false,
            matching: false,
            ..self
        };
        for n in names {
            match n.as_str() {
                "arrows" => s.arrows = true,
                "flow" => s.flow = true,
                "heat" => s.heat = true,
                "matching" => s.matching = true,
                other => {
                    return Err(format!(
                        "unknown overlay layer `{other}` (expected one of {})",
                        Self::LAYERS.join(", ")
                    ));
                }
            }
        }
        Ok(s)
    }
}

/// What one frame of the overlay drew (shown in the UI and checked by tests).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Drawn {
    /// Arrows drawn.
    pub arrows: usize,
    /// Matching lines drawn.
    pub lines: usize,
}

/// The segments the arrows and matching layers draw under `settings`.
pub fn segments(o: &ShownOverlay, settings: &OverlaySettings) -> (Vec<Segment>, Vec<Segment>) {
    let d = &o.data;
    let arrows = if settings.arrows {
        motion_arrows(&d.motion, d.width, d.height, settings.arrow_spacing)
    } else {
        Vec::new()
    };
    let lines = if settings.matching {
        d.matching
            .iter()
            .step_by(settings.matching_every.max(1))
            .copied()
            .collect()
    } else {
        Vec::new()
    };
    (arrows, lines)
}

/// Paints the overlay over the image drawn in `rect`.
pub fn paint(
    painter: &egui::Painter,
    rect: Rect,
    o: &ShownOverlay,
    settings: &OverlaySettings,
) -> Drawn {
    let uv = Rect::from_min_max(Pos2::ZERO, Pos2::new(1.0, 1.0));
    if settings.flow {
        painter.image(o.flow.id(), rect, uv, Color32::WHITE);
    }
    if settings.heat {
        painter.image(o.heat.id(), rect, uv, Color32::WHITE);
    }
    let (w, h) = (o.data.width.max(1) as f32, o.data.height.max(1) as f32);
    let to_screen = |p: glam::Vec2| {
        Pos2::new(
            rect.min.x + p.x / w * rect.width(),
            rect.min.y + p.y / h * rect.height(),
        )
    };
    let (arrows, lines) = segments(o, settings);
    let arrow_stroke = Stroke::new(1.5, Color32::WHITE);
    for s in &arrows {
        let from = to_screen(s.from);
        painter.arrow(from, to_screen(s.to) - from, arrow_stroke);
    }
    let line_colour = Color32::from_rgb(255, 220, 0);
    for s in &lines {
        let to = to_screen(s.to);
        painter.line_segment([to_screen(s.from), to], Stroke::new(1.0, line_colour));
        painter.circle_filled(to, 1.5, line_colour);
    }
    Drawn {
        arrows: arrows.len(),
        lines: lines.len(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn layers_are_chosen_by_name() {
        let names = ["flow".to_owned(), "matching".to_owned()];
        let s = OverlaySettings::default()
            .with_layers(&names)
            .expect("known layers");
        assert!(s.flow && s.matching && !s.arrows && !s.heat);
        let err = OverlaySettings::default()
            .with_layers(&["arows".to_owned()])
            .expect_err("typo");
        assert!(err.contains("arows") && err.contains("arrows"), "{err}");
    }
}
