//! The worker's state for one loaded problem: the [`Optimization`], the
//! run state, the progressive render accumulator and the overlay request.
//! Each method does one unit of work (an iteration, a render pass, an
//! overlay) so the worker can read commands between units.

use std::path::{Path, PathBuf};
use std::time::Instant;

use epsm_core::field::{image_derivative, motion_field};
use epsm_core::inspect::{fd_step, matching_lines, path_kind_counts};
use epsm_core::problem::Target;
use epsm_core::{OptResult, Optimization, Problem, load_problem};
use epsm_render::Image;
use epsm_render::tracer::{RenderOptions, render};
use glam::Vec3;

use super::messages::{Loaded, Overlay, RunSettings, Stepped};

/// Samples per pixel of one progressive render pass.
pub const PASS_SPP: u32 = 2;
/// The progressive render stops refining at this many samples per pixel.
pub const MAX_SPP: u32 = 64;
/// Samples per pixel of the `dI/dθ` renders of an overlay.
const OVERLAY_SPP: u32 = 4;
/// Shortest OT matching segment kept in an overlay (pixels).
const MIN_MATCH_MOVE: f32 = 0.5;

/// A running mean of render passes at one θ.
#[derive(Clone, Debug, Default)]
struct Accumulator {
    sum: Vec<Vec3>,
    spp: u32,
    passes: u32,
}

/// One loaded problem on the worker.
pub struct Session {
    path: PathBuf,
    base: Problem,
    opt: Optimization,
    settings: RunSettings,
    /// Iterations still to run (`Some(0)` or `None` with `running == false`: paused).
    budget: Option<u32>,
    /// Whether iterations are being run.
    pub running: bool,
    accum: Accumulator,
    overlay_param: Option<usize>,
    overlay_stale: bool,
    loaded_at: Instant,
}

impl Session {
    /// Loads the problem at `path` and sets it up with its own settings.
    pub fn load(path: &Path) -> OptResult<Self> {
        let mut base = load_problem(path)?;
        let settings = RunSettings {
            method: base.optimizer.method,
            lr_scale: 1.0,
        };
        let opt = Optimization::new(configured(&base, settings))?;
        // Keep the rendered target: reset and configure then skip its render.
        base.target = Target::Image(opt.target().clone());
        Ok(Self {
            path: path.to_owned(),
            base,
            opt,
            settings,
            budget: None,
            running: false,
            accum: Accumulator::default(),
            overlay_param: None,
            overlay_stale: true,
            loaded_at: Instant::now(),
        })
    }

    /// What the UI needs to show the problem from scratch.
    pub fn loaded(&self) -> Loaded {
        Loaded {
            path: self.path.clone(),
            params: self.base.params.clone(),
            theta: self.opt.theta().to_vec(),
            settings: self.settings,
            iterations: self.base.optimizer.iterations,
            target: self.opt.target().clone(),
        }
    }

    /// Current θ.
    pub fn theta(&self) -> &[f64] {
        self.opt.theta()
    }

    /// The next iteration.
    pub fn iteration(&self) -> u32 {
        self.opt.iteration()
    }

    /// Starts running at most `steps` iterations (`None`: until done).
    pub fn run(&mut self, steps: Option<u32>) {
        self.budget = steps;
        self.running = steps != Some(0) && !self.opt.is_done();
    }

    /// Stops running.
    pub fn pause(&mut self) {
        self.running = false;
    }

    /// Restarts from the initial θ with `settings`.
    pub fn reset(&mut self, settings: RunSettings) -> OptResult<()> {
        self.opt = Optimization::new(configured(&self.base, settings))?;
        self.settings = settings;
        self.running = false;
        self.loaded_at = Instant::now();
        self.invalidate();
        Ok(())
    }

    /// Applies `settings` and continues from the current θ (the schedule
    /// restarts at iteration 0).
    pub fn configure(&mut self, settings: RunSettings) -> OptResult<()> {
        let theta = self.opt.theta().to_vec();
        let mut opt = Optimization::new(configured(&self.base, settings))?;
        opt.set_theta(&theta);
        self.opt = opt;
        self.settings = settings;
        self.invalidate();
        Ok(())
    }

    /// Moves the parameters (clamped to their bounds).
    pub fn set_theta(&mut self, theta: &[f64]) {
        self.opt.set_theta(theta);
        self.invalidate();
    }

    /// Selects the overlay's parameter.
    pub fn set_overlay_param(&mut self, param: Option<usize>) {
        self.overlay_param = param.filter(|p| *p < self.base.params.len());
        self.overlay_stale = true;
    }

    fn invalidate(&mut self) {
        self.accum = Accumulator::default();
        self.overlay_stale = true;
    }

    /// Runs one iteration (the caller checks [`Self::running`]).
    pub fn step(&mut self) -> OptResult<Stepped> {
        let result = self.opt.step();
        self.invalidate();
        if let Some(b) = self.budget.as_mut() {
            *b = b.saturating_sub(1);
        }
        if result.is_err() || self.opt.is_done() || self.budget == Some(0) {
            self.running = false;
        }
        result.map(|row| Stepped {
            row,
            wall_s: self.loaded_at.elapsed().as_secs_f64(),
            theta: self.opt.theta().to_vec(),
            iteration: self.opt.iteration(),
            done: self.opt.is_done(),
        })
    }

    /// Whether the render wants another pass: always right after θ moved,
    /// and while idle until [`MAX_SPP`].
    pub fn wants_render(&self) -> bool {
        self.accum.spp == 0 || (!self.running && self.accum.spp < MAX_SPP)
    }

    /// Whether the overlay is out of date (computed while not running).
    pub fn wants_overlay(&self) -> bool {
        !self.running && self.overlay_stale && self.overlay_param.is_some()
    }

    /// Whether θ moved since the last render pass.
    pub fn needs_first_pass(&self) -> bool {
        self.accum.spp == 0
    }

    /// Whether the first render passes are still missing (they go before an overlay).
    pub fn render_is_coarse(&self) -> bool {
        self.accum.spp < 4 * PASS_SPP
    }

    /// Adds one render pass at the current θ; returns the mean so far and its spp.
    pub fn render_pass(&mut self) -> (Image, u32) {
        let scene = self.opt.scene();
        let opts = RenderOptions {
            spp: PASS_SPP,
            seed: self.accum.passes.wrapping_mul(0x9E37_79B9) ^ 0x00C0_FFEE,
            ..RenderOptions::from_scene(scene)
        };
        let pass = render(scene, &opts, &|_| {}).image;
        let a = &mut self.accum;
        if a.sum.len() != pass.pixels.len() {
            a.sum = vec![Vec3::ZERO; pass.pixels.len()];
        }
        let w = PASS_SPP as f32;
        for (s, p) in a.sum.iter_mut().zip(&pass.pixels) {
            *s += *p * w;
        }
        a.spp += PASS_SPP;
        a.passes += 1;
        let inv = 1.0 / a.spp as f32;
        let mean = Image {
            width: pass.width,
            height: pass.height,
            pixels: a.sum.iter().map(|s| *s * inv).collect(),
        };
        (mean, a.spp)
    }

    /// Computes the overlay of the selected parameter at the current θ.
    pub fn overlay(&mut self) -> Option<OptResult<Overlay>> {
        let param = self.overlay_param?;
        self.overlay_stale = false;
        Some(self.compute_overlay(param))
    }

    fn compute_overlay(&mut self, param: usize) -> OptResult<Overlay> {
        let (g, records) = self.opt.gradient()?;
        let (scene, table) = self.opt.match_view();
        let motion = motion_field(scene, table, &records, param);
        let kinds = path_kind_counts(scene, table, &records);
        let h = fd_step(&self.opt, param);
        let iteration = self.opt.iteration();
        let (scene, table) = self.opt.match_view_mut();
        let d_image = image_derivative(scene, table, param, h, OVERLAY_SPP);
        Ok(Overlay {
            param,
            iteration,
            width: g.image.width,
            height: g.image.height,
            motion,
            d_image,
            matching: matching_lines(&g.loss, 1, MIN_MATCH_MOVE),
            kinds,
            gradient: g.grad,
        })
    }
}

/// `base` with the method and learning-rate factor of `settings`.
fn configured(base: &Problem, settings: RunSettings) -> Problem {
    let mut p = base.clone();
    p.optimizer.method = settings.method;
    for spec in &mut p.params {
        spec.lr *= settings.lr_scale;
    }
    p
}
