//! PNG plots (plotters, bitmap backend, text with the Ubuntu Light font
//! shipped by `epaint_default_fonts`: no system fonts needed) and atomic
//! 8-bit image writes.

use std::path::Path;

use anyhow::Context;
use plotters::prelude::*;
use plotters::style::FontStyle;

/// One curve: a name for the legend and `(x, y)` points.
pub struct Series {
    /// Legend entry.
    pub name: String,
    /// Points in x order.
    pub points: Vec<(f64, f64)>,
}

/// One panel of a figure: a title, an axis label and its curves.
pub struct Panel {
    /// Title above the panel.
    pub title: String,
    /// Label of the y axis.
    pub y_label: String,
    /// Curves.
    pub series: Vec<Series>,
}

const FONT: &str = "sans-serif";

fn register_font() {
    // Registering twice is harmless; a failure only loses text.
    let _ =
        plotters::style::register_font(FONT, FontStyle::Normal, epaint_default_fonts::UBUNTU_LIGHT);
}

/// Draws `panels` side by side against wall-clock seconds (log y) into a PNG.
pub fn plot_panels(path: &Path, panels: &[Panel]) -> anyhow::Result<()> {
    register_font();
    let (w, h) = (560 * panels.len().max(1) as u32, 420u32);
    let mut buf = vec![255u8; (w * h * 3) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut buf, (w, h)).into_drawing_area();
        let areas = root.split_evenly((1, panels.len().max(1)));
        for (panel, area) in panels.iter().zip(&areas) {
            draw_panel(area, panel)
                .map_err(|e| anyhow::anyhow!("plotting {}: {e}", panel.title))?;
        }
        root.present()
            .map_err(|e| anyhow::anyhow!("plotting: {e}"))?;
    }
    write_png(path, w, h, &buf)
}

fn draw_panel<DB: DrawingBackend>(
    area: &DrawingArea<DB, plotters::coord::Shift>,
    panel: &Panel,
) -> Result<(), String> {
    let finite = panel
        .series
        .iter()
        .flat_map(|s| &s.points)
        .filter(|(x, y)| x.is_finite() && y.is_finite() && *y > 0.0);
    let (mut x_hi, mut y_lo, mut y_hi) = (1e-3f64, f64::MAX, f64::MIN_POSITIVE);
    for &(x, y) in finite {
        x_hi = x_hi.max(x);
        y_lo = y_lo.min(y);
        y_hi = y_hi.max(y);
    }
    if y_lo > y_hi {
        (y_lo, y_hi) = (1e-3, 1.0);
    }
    let e = |e: DrawingAreaErrorKind<DB::ErrorType>| e.to_string();
    let mut chart = ChartBuilder::on(area)
        .caption(&panel.title, (FONT, 20))
        .margin(12)
        .x_label_area_size(36)
        .y_label_area_size(64)
        .build_cartesian_2d(0.0..x_hi * 1.02, (y_lo * 0.8..y_hi * 1.25).log_scale())
        .map_err(e)?;
    chart
        .configure_mesh()
        .x_desc("wall-clock seconds")
        .y_desc(&panel.y_label)
        .y_label_formatter(&|v| tick(*v))
        .label_style((FONT, 13))
        .draw()
        .map_err(e)?;
    for (i, s) in panel.series.iter().enumerate() {
        let colour = Palette99::pick(i).to_rgba();
        let pts = s
            .points
            .iter()
            .copied()
            .filter(|(x, y)| x.is_finite() && y.is_finite() && *y > 0.0);
        chart
            .draw_series(LineSeries::new(pts, colour.stroke_width(2)))
            .map_err(e)?
            .label(s.name.clone())
            .legend(move |(x, y)| {
                PathElement::new(vec![(x, y), (x + 18, y)], colour.stroke_width(2))
            });
    }
    chart
        .configure_series_labels()
        .label_font((FONT, 14))
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .draw()
        .map_err(e)?;
    Ok(())
}

/// A short tick label for a log axis.
fn tick(v: f64) -> String {
    if (1e-2..1e4).contains(&v.abs()) {
        let s = format!("{v:.3}");
        s.trim_end_matches('0').trim_end_matches('.').to_owned()
    } else {
        format!("{v:.0e}")
    }
}

/// Writes an 8-bit RGB buffer as PNG atomically, creating the folder.
pub fn write_png(path: &Path, w: u32, h: u32, rgb: &[u8]) -> anyhow::Result<()> {
    epsm_render::atomic_file::create_parent(path)
        .with_context(|| format!("creating the folder of {}", path.display()))?;
    let rgb8 = image::ExtendedColorType::Rgb8;
    Ok(epsm_render::image_io::write_png_bytes(
        path, w, h, rgb8, rgb,
    )?)
}
