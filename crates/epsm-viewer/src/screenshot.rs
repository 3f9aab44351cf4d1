//! `--screenshot PATH`: once the autorun has finished, the render has
//! refined and the overlay has arrived, ask the window for a screenshot,
//! save it as PNG and close the window (used by
//! `scripts/viewer-screenshot.sh` under Xvfb).

use std::path::PathBuf;
use std::sync::Arc;
use std::sync::mpsc::{Receiver, channel};

use eframe::egui;

use crate::state::Model;

/// The render must have at least this many samples per pixel first.
const MIN_SPP: u32 = 32;

/// Where the screenshot request stands.
#[derive(Debug)]
enum Stage {
    Waiting,
    Requested(Receiver<Arc<egui::ColorImage>>),
    Done,
}

/// A pending screenshot.
#[derive(Debug)]
pub struct Screenshot {
    path: PathBuf,
    iterations: usize,
    stage: Stage,
}

impl Screenshot {
    /// A screenshot to be saved at `path` once `iterations` have run.
    pub fn new(path: PathBuf, iterations: u32) -> Self {
        Self {
            path,
            iterations: iterations as usize,
            stage: Stage::Waiting,
        }
    }

    /// Advances the request by one frame.
    pub fn update(&mut self, ctx: &egui::Context, model: &Model) {
        match &self.stage {
            Stage::Waiting => {
                if ready(model, self.iterations) {
                    let (tx, rx) = channel();
                    let callback = egui::ScreenshotCallback::new(move |image| {
                        let _ = tx.send(image);
                    });
                    ctx.send_viewport_cmd(egui::ViewportCommand::Screenshot(callback));
                    self.stage = Stage::Requested(rx);
                }
                ctx.request_repaint();
            }
            Stage::Requested(rx) => {
                if let Ok(image) = rx.try_recv() {
                    match save(&self.path, &image) {
                        Ok(()) => {
                            eprintln!("epsm-viewer: screenshot saved to {}", self.path.display())
                        }
                        Err(e) => eprintln!("epsm-viewer: screenshot: {e}"),
                    }
                    self.stage = Stage::Done;
                    ctx.send_viewport_cmd(egui::ViewportCommand::Close);
                }
                ctx.request_repaint();
            }
            Stage::Done => {}
        }
    }
}

fn ready(model: &Model, iterations: usize) -> bool {
    if model.error.is_some() && model.problem.is_none() {
        return true;
    }
    model.problem.as_ref().is_some_and(|p| {
        !model.running
            && p.history.len() >= iterations.min(p.iterations as usize)
            && p.render.as_ref().is_some_and(|(_, spp)| *spp >= MIN_SPP)
            && (p.overlay.is_some() || p.params.is_empty())
    })
}

fn save(path: &std::path::Path, image: &egui::ColorImage) -> anyhow::Result<()> {
    let [w, h] = image.size;
    let rgba: Vec<u8> = image.pixels.iter().flat_map(|c| c.to_array()).collect();
    epsm_scene::atomic_file::create_parent(path)?;
    let rgba8 = image::ExtendedColorType::Rgba8;
    Ok(epsm_scene::image_io::write_png_bytes(
        path, w as u32, h as u32, rgba8, &rgba,
    )?)
}
