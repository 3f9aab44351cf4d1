//! `epsm-viewer [problem.toml]`: opens the viewer window (eframe, glow
//! renderer). Flags: `--autorun N` runs N iterations once the problem is
//! loaded; `--screenshot PATH` then saves a PNG of the window and quits;
//! `--overlay arrows,flow,heat,matching` chooses the overlay layers shown.

use std::path::PathBuf;

use clap::Parser;
use eframe::egui;
use epsm_viewer::overlay::OverlaySettings;
use epsm_viewer::recent::Recent;
use epsm_viewer::{Options, ViewerApp};

/// Interactive viewer for epsm problems.
#[derive(Parser, Debug)]
#[command(name = "epsm-viewer", version)]
struct Args {
    /// The problem file to open (TOML); others can be opened in the window.
    problem: Option<PathBuf>,
    /// Run this many iterations as soon as the problem is loaded.
    #[arg(long)]
    autorun: Option<u32>,
    /// After the autorun, once the render has refined, save a screenshot of
    /// the window to this PNG file and quit.
    #[arg(long)]
    screenshot: Option<PathBuf>,
    /// Overlay layers shown at start, comma-separated: arrows, flow, heat,
    /// matching (default: arrows).
    #[arg(long, value_delimiter = ',', default_value = "arrows")]
    overlay: Vec<String>,
    /// Window size in points, `WIDTHxHEIGHT`.
    #[arg(long, default_value = "1400x860", value_parser = parse_size)]
    size: [f32; 2],
}

fn parse_size(s: &str) -> Result<[f32; 2], String> {
    let (w, h) = s
        .split_once('x')
        .ok_or("expected WIDTHxHEIGHT, e.g. 1400x860")?;
    let n = |v: &str| v.trim().parse::<f32>().map_err(|e| format!("{v}: {e}"));
    Ok([n(w)?, n(h)?])
}

fn main() -> anyhow::Result<()> {
    let args = Args::parse();
    let options = Options {
        problem: args.problem,
        autorun: args.autorun,
        screenshot: args.screenshot,
        recent_file: Recent::default_store(),
        overlay: OverlaySettings::default()
            .with_layers(&args.overlay)
            .map_err(|e| anyhow::anyhow!("--overlay: {e}"))?,
    };
    let native = eframe::NativeOptions {
        viewport: egui::ViewportBuilder::default()
            .with_title("epsm-viewer")
            .with_inner_size(args.size),
        ..Default::default()
    };
    eframe::run_native(
        "epsm-viewer",
        native,
        Box::new(|_| Ok(Box::new(ViewerApp::new(options)))),
    )
    .map_err(|e| anyhow::anyhow!("epsm-viewer: {e}"))
}
