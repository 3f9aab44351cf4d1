//! PNG figures of optimization runs (`report.png` of `epsm optimize`,
//! `compare.png` of `epsm compare`) and atomic 8-bit image writes.
//!
//! A figure reads top to bottom: a title (the problem and the methods), one
//! legend for every panel (outside the data), the panels side by side (an
//! error against wall-clock seconds each, on a log axis labelled at
//! `1…9 × 10^k`, `1, 2, 5 × 10^k` or `10^k` over its whole range, whichever
//! keeps the labels few), then a strip of images (sRGB, each scaled to fit a
//! 256-pixel square by nearest neighbour) with their names below them.
//!
//! Drawn with plotters' bitmap backend; text in the Ubuntu Light font shipped
//! by `epaint_default_fonts`, so no system fonts are needed.

mod axis;
mod strip;

use std::path::Path;

use anyhow::Context;
use epsm_render::Image;
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::FontStyle;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use axis::{LogAxis, tick};
use strip::{blit, place_strip};

/// One curve: a name for the legend and `(x, y)` points.
pub struct Series {
    /// Legend entry (curves of the same name share a colour across panels).
    pub name: String,
    /// Points in x order; points with a non-finite or non-positive y are
    /// left out (the y axis is logarithmic).
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

/// One image of a figure's strip.
pub struct Thumb {
    /// Name written below the image.
    pub label: String,
    /// The image (linear RGB, shown sRGB-encoded and clamped).
    pub image: Image,
}

/// A whole figure: title, panels and image strip.
pub struct Figure<'a> {
    /// Title at the top (the problem and the methods).
    pub title: String,
    /// Panels, side by side.
    pub panels: &'a [Panel],
    /// Images, left to right, below the panels (may be empty).
    pub strip: &'a [Thumb],
}

const FONT: &str = "sans-serif";
/// Size of one panel, pixels.
const PANEL: (u32, u32) = (600, 440);
/// Heights of the title and legend bands, pixels.
const TITLE_H: u32 = 44;
const LEGEND_H: u32 = 30;
/// Side of the square an image of the strip is fitted into, its label's
/// band below it and the gap around images, pixels.
const THUMB: u32 = 256;
const THUMB_LABEL_H: u32 = 28;
const GAP: u32 = 12;

fn register_font() {
    // Registering twice is harmless; a failure only loses text.
    let _ =
        plotters::style::register_font(FONT, FontStyle::Normal, epaint_default_fonts::UBUNTU_LIGHT);
}

/// Draws `figure` into a PNG at `path` (written atomically).
pub fn plot_figure(path: &Path, figure: &Figure) -> anyhow::Result<()> {
    register_font();
    let n_panels = figure.panels.len().max(1) as u32;
    let strip_w = figure.strip.len() as u32 * (THUMB + GAP) + GAP;
    let strip_h = if figure.strip.is_empty() {
        0
    } else {
        THUMB + THUMB_LABEL_H + 2 * GAP
    };
    let w = (n_panels * PANEL.0).max(strip_w);
    let h = TITLE_H + LEGEND_H + PANEL.1 + strip_h;
    let mut buf = vec![255u8; (w * h * 3) as usize];
    let names = legend_names(figure.panels);
    let placed = place_strip(figure.strip, w, TITLE_H + LEGEND_H + PANEL.1 + GAP);
    {
        let root = BitMapBackend::with_buffer(&mut buf, (w, h)).into_drawing_area();
        let e = |e: DrawingAreaErrorKind<_>| anyhow::anyhow!("plotting {}: {e}", path.display());
        let centre = Pos::new(HPos::Center, VPos::Center);
        root.draw(&Text::new(
            figure.title.clone(),
            ((w / 2) as i32, (TITLE_H / 2) as i32),
            (FONT, 24).into_font().color(&BLACK).pos(centre),
        ))
        .map_err(e)?;
        draw_legend(&root, &names, w, TITLE_H).map_err(e)?;
        let (_, rest) = root.split_vertically(TITLE_H + LEGEND_H);
        let (panel_row, _) = rest.split_vertically(PANEL.1);
        for (panel, area) in figure
            .panels
            .iter()
            .zip(panel_row.split_evenly((1, n_panels as usize)))
        {
            draw_panel(&area, panel, &names).map_err(e)?;
        }
        for (thumb, at) in figure.strip.iter().zip(&placed) {
            let x = (at.x + at.w / 2) as i32;
            let y = (at.y + at.h + THUMB_LABEL_H / 2) as i32;
            root.draw(&Text::new(
                thumb.label.clone(),
                (x, y),
                (FONT, 17).into_font().color(&BLACK).pos(centre),
            ))
            .map_err(e)?;
        }
        root.present().map_err(e)?;
    }
    for (thumb, at) in figure.strip.iter().zip(&placed) {
        blit(&mut buf, w, &thumb.image, at);
    }
    write_png(path, w, h, &buf)
}

/// Every series name of the panels, once each, in order of appearance.
fn legend_names(panels: &[Panel]) -> Vec<String> {
    let mut names: Vec<String> = Vec::new();
    for s in panels.iter().flat_map(|p| &p.series) {
        if !names.contains(&s.name) {
            names.push(s.name.clone());
        }
    }
    names
}

/// Curve colours, distinct and dark enough to read on white (the
/// "tableau" palette), repeated beyond ten curves.
const PALETTE: [RGBColor; 10] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(127, 127, 127),
    RGBColor(188, 189, 34),
    RGBColor(23, 190, 207),
];

fn colour(names: &[String], name: &str) -> RGBAColor {
    let i = names.iter().position(|n| n == name).unwrap_or(0);
    PALETTE[i % PALETTE.len()].to_rgba()
}

/// The legend band below the title: a line and the name per series,
/// centred.
fn draw_legend<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    names: &[String],
    w: u32,
    top: u32,
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    const ENTRY: i32 = 150;
    let total = ENTRY * names.len() as i32;
    let y = (top + LEGEND_H / 2) as i32;
    let left = (w as i32 - total) / 2;
    for (i, name) in names.iter().enumerate() {
        let x = left + i as i32 * ENTRY;
        let c = colour(names, name);
        root.draw(&PathElement::new(
            vec![(x, y), (x + 28, y)],
            c.stroke_width(3),
        ))?;
        root.draw(&Text::new(
            name.clone(),
            (x + 36, y),
            (FONT, 17)
                .into_font()
                .color(&BLACK)
                .pos(Pos::new(HPos::Left, VPos::Center)),
        ))?;
    }
    Ok(())
}

fn draw_panel<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    panel: &Panel,
    names: &[String],
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    let plotted = |s: &Series| -> Vec<(f64, f64)> {
        s.points
            .iter()
            .copied()
            .filter(|(x, y)| x.is_finite() && y.is_finite() && *y > 0.0)
            .collect()
    };
    let curves: Vec<(&Series, Vec<(f64, f64)>)> =
        panel.series.iter().map(|s| (s, plotted(s))).collect();
    let all = curves.iter().flat_map(|(_, p)| p);
    let x_hi = all.clone().map(|p| p.0).fold(1e-3, f64::max);
    let y_lo = all.clone().map(|p| p.1).fold(f64::INFINITY, f64::min);
    let y_hi = all.map(|p| p.1).fold(0.0, f64::max);
    let axis = LogAxis::new(y_lo, y_hi);
    let y_range = (axis.lo..axis.hi)
        .log_scale()
        .with_key_points(axis.labels.clone())
        .with_light_points(axis.minor.clone());
    let mut chart = ChartBuilder::on(area)
        .caption(&panel.title, (FONT, 20))
        .margin(14)
        .x_label_area_size(44)
        .y_label_area_size(78)
        .build_cartesian_2d(0.0..x_hi * 1.02, y_range)?;
    chart
        .configure_mesh()
        .x_desc("wall-clock seconds")
        .y_desc(&panel.y_label)
        .x_labels(8)
        .x_max_light_lines(2)
        .x_label_formatter(&|v| {
            format!("{v:.3}")
                .trim_end_matches('0')
                .trim_end_matches('.')
                .to_owned()
        })
        .y_label_formatter(&|v| tick(*v))
        .label_style((FONT, 15))
        .axis_desc_style((FONT, 16))
        .light_line_style(BLACK.mix(0.06))
        .bold_line_style(BLACK.mix(0.18))
        .draw()?;
    for (s, points) in curves {
        let c = colour(names, &s.name);
        chart.draw_series(LineSeries::new(points, c.stroke_width(2)))?;
    }
    Ok(())
}

/// Writes an 8-bit RGB buffer as PNG atomically, creating the folder.
pub fn write_png(path: &Path, w: u32, h: u32, rgb: &[u8]) -> anyhow::Result<()> {
    epsm_scene::atomic_file::create_parent(path)
        .with_context(|| format!("creating the folder of {}", path.display()))?;
    let rgb8 = image::ExtendedColorType::Rgb8;
    Ok(epsm_scene::image_io::write_png_bytes(
        path, w, h, rgb8, rgb,
    )?)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_figure_with_a_strip_is_written() {
        let path = std::env::temp_dir().join(format!("epsm-plots-{}.png", std::process::id()));
        let series = |name: &str, k: f64| Series {
            name: name.into(),
            points: (0..20)
                .map(|i| (f64::from(i), k / f64::from(i + 1)))
                .collect(),
        };
        let panels = [Panel {
            title: "image RMSE".into(),
            y_label: "RMSE".into(),
            series: vec![series("epsm", 0.3), series("l2", 0.5)],
        }];
        let mut img = Image::new(64, 32);
        img.set(3, 4, glam::Vec3::ONE);
        let strip = [
            Thumb {
                label: "target".into(),
                image: img.clone(),
            },
            Thumb {
                label: "final".into(),
                image: img,
            },
        ];
        let fig = Figure {
            title: "test — epsm".into(),
            panels: &panels,
            strip: &strip,
        };
        plot_figure(&path, &fig).expect("plot");
        let png = image::open(&path).expect("readable PNG").into_rgb8();
        std::fs::remove_file(&path).expect("removing the test figure");
        assert_eq!(png.width(), PANEL.0.max(2 * (THUMB + GAP) + GAP));
        assert_eq!(
            png.height(),
            TITLE_H + LEGEND_H + PANEL.1 + THUMB + THUMB_LABEL_H + 2 * GAP
        );
        // The white pixel (3, 4) of the 64×32 target, scaled ×4, is white
        // in the strip; its neighbours are black.
        let placed = place_strip(&strip, png.width(), TITLE_H + LEGEND_H + PANEL.1 + GAP);
        let at = &placed[0];
        assert_eq!((at.w, at.h), (256, 128));
        assert_eq!(
            png.get_pixel(at.x + 3 * 4 + 1, at.y + 4 * 4 + 1).0,
            [255, 255, 255]
        );
        assert_eq!(png.get_pixel(at.x + 1, at.y + 1).0, [0, 0, 0]);
    }
}
