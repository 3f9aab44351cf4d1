//! The UI's model of the worker's state, built only from [`Update`]s: the
//! loaded problem, θ, the history of iterations, the images (kept as data
//! for pixel inspection and as textures for drawing) and the overlay.

use std::path::PathBuf;

use eframe::egui::{self, TextureHandle};
use epsm_core::ParamSpec;
use epsm_core::inspect::normalized_luminance;
use epsm_render::Image;

use crate::textures::{flow_map, signed_map, srgb_image, upload};
use crate::worker::{Loaded, Overlay, RunSettings, Update};

/// One point of the live plot.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HistoryPoint {
    /// Seconds since the problem was loaded or reset.
    pub wall_s: f64,
    /// The iteration.
    pub iteration: u32,
    /// Image RMSE (linear RGB).
    pub image_rmse: f64,
    /// RMS parameter error, when true values are known.
    pub param_error: Option<f64>,
}

/// An image with its texture.
pub struct Shown {
    /// The image (linear RGB).
    pub image: Image,
    /// Its texture.
    pub texture: TextureHandle,
}

/// The overlay with its textures and its normalised `dI/dθ`.
pub struct ShownOverlay {
    /// The overlay data.
    pub data: Overlay,
    /// The flow texture.
    pub flow: TextureHandle,
    /// The `dI/dθ` heat map texture (transparent at zero).
    pub heat: TextureHandle,
}

/// Everything the UI knows about the loaded problem.
pub struct Problem {
    /// The problem file.
    pub path: PathBuf,
    /// Its parameters.
    pub params: Vec<ParamSpec>,
    /// Current θ.
    pub theta: Vec<f64>,
    /// The settings in force.
    pub settings: RunSettings,
    /// The next iteration.
    pub iteration: u32,
    /// Iterations of the schedule.
    pub iterations: u32,
    /// The plot's points.
    pub history: Vec<HistoryPoint>,
    /// The target.
    pub target: Shown,
    /// The current render and its samples per pixel.
    pub render: Option<(Shown, u32)>,
    /// The signed difference render − target (luminance, normalised).
    pub diff: Option<TextureHandle>,
    /// The latest overlay.
    pub overlay: Option<ShownOverlay>,
}

/// The UI's model.
#[derive(Default)]
pub struct Model {
    /// The loaded problem.
    pub problem: Option<Problem>,
    /// The file being loaded.
    pub loading: Option<PathBuf>,
    /// The last error (load failure, failed iteration).
    pub error: Option<String>,
    /// Whether the worker is running iterations.
    pub running: bool,
}

impl Model {
    /// Applies one update from the worker.
    pub fn apply(&mut self, ctx: &egui::Context, update: Update) {
        match update {
            Update::Loading(path) => self.loading = Some(path),
            Update::Loaded(l) => {
                self.loading = None;
                self.error = None;
                self.running = false;
                self.problem = Some(Problem::new(ctx, *l));
            }
            Update::LoadFailed { path, message } => {
                self.loading = None;
                self.error = Some(format!("could not open {}: {message}", path.display()));
            }
            Update::Error(message) => self.error = Some(message),
            Update::Running(r) => self.running = r,
            Update::Stepped(s) => {
                if let Some(p) = self.problem.as_mut() {
                    p.history.push(HistoryPoint {
                        wall_s: s.wall_s,
                        iteration: s.row.iteration,
                        image_rmse: s.row.image_rmse,
                        param_error: s.row.param_error,
                    });
                    p.theta = s.theta;
                    p.iteration = s.iteration;
                }
            }
            Update::Theta { theta, iteration } => {
                if let Some(p) = self.problem.as_mut() {
                    p.theta = theta;
                    p.iteration = iteration;
                }
            }
            Update::Render { image, spp } => {
                if let Some(p) = self.problem.as_mut() {
                    p.set_render(ctx, image, spp);
                }
            }
            Update::Overlay(o) => {
                if let Some(p) = self.problem.as_mut() {
                    let (w, h) = (o.width, o.height);
                    let heat = normalized_luminance(&o.d_image.pixels);
                    p.overlay = Some(ShownOverlay {
                        flow: upload(ctx, "flow", flow_map(&o.motion, w, h)),
                        heat: upload(ctx, "heat", signed_map(&heat, w, h, true)),
                        data: *o,
                    });
                }
            }
        }
    }
}

impl Problem {
    fn new(ctx: &egui::Context, l: Loaded) -> Self {
        let target = Shown {
            texture: upload(ctx, "target", srgb_image(&l.target)),
            image: l.target,
        };
        Self {
            path: l.path,
            params: l.params,
            theta: l.theta,
            settings: l.settings,
            iteration: 0,
            iterations: l.iterations,
            history: Vec::new(),
            target,
            render: None,
            diff: None,
            overlay: None,
        }
    }

    fn set_render(&mut self, ctx: &egui::Context, image: Image, spp: u32) {
        let t = &self.target.image;
        if (image.width, image.height) == (t.width, t.height) {
            let d: Vec<_> = image
                .pixels
                .iter()
                .zip(&t.pixels)
                .map(|(a, b)| *a - *b)
                .collect();
            let values = normalized_luminance(&d);
            let map = signed_map(&values, image.width, image.height, false);
            self.diff = Some(upload(ctx, "diff", map));
        }
        let texture = upload(ctx, "render", srgb_image(&image));
        self.render = Some((Shown { image, texture }, spp));
    }
}
