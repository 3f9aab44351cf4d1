//! The messages between the UI thread and the worker: [`Command`]s in,
//! [`Update`]s out. Images are linear RGB at the resolution noted on each
//! field; the overlay is at the problem's match resolution.

use std::path::PathBuf;

use epsm_core::inspect::{KindCounts, Segment};
use epsm_core::report::Row;
use epsm_core::{Method, ParamSpec};
use epsm_render::Image;
use glam::DVec2;

/// How the optimization runs (applied on top of the problem file's settings).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RunSettings {
    /// The method.
    pub method: Method,
    /// Factor on every parameter's learning rate (1: the file's rates).
    pub lr_scale: f64,
}

/// What the UI asks of the worker.
#[derive(Clone, Debug, PartialEq)]
pub enum Command {
    /// Load a problem file (the current one stays if it fails).
    Load(PathBuf),
    /// Run iterations: `Some(n)` at most `n` more, `None` until done or paused.
    Run(Option<u32>),
    /// Stop running after the current iteration.
    Pause,
    /// Restart from the problem's initial θ with `settings`; the history restarts.
    Reset(RunSettings),
    /// Change the method or learning rate and continue from the current θ.
    Configure(RunSettings),
    /// Move the parameters (user units; clamped to their bounds).
    SetTheta(Vec<f64>),
    /// Compute the gradient overlay for this parameter index (`None`: none).
    OverlayParam(Option<usize>),
    /// Stop the worker.
    Shutdown,
}

/// A freshly loaded (or reset) problem.
#[derive(Clone, Debug)]
pub struct Loaded {
    /// The problem file.
    pub path: PathBuf,
    /// The parameters as the file gives them.
    pub params: Vec<ParamSpec>,
    /// The starting θ (user units).
    pub theta: Vec<f64>,
    /// The settings in force.
    pub settings: RunSettings,
    /// Iterations the schedule runs.
    pub iterations: u32,
    /// The target (scene resolution).
    pub target: Image,
}

/// One finished iteration.
#[derive(Clone, Debug)]
pub struct Stepped {
    /// The iteration's report row (θ is the value the loss was measured at).
    pub row: Row,
    /// Seconds since the problem was loaded, when the iteration ended.
    pub wall_s: f64,
    /// θ after the update.
    pub theta: Vec<f64>,
    /// The next iteration to run.
    pub iteration: u32,
    /// Whether every scheduled iteration has run.
    pub done: bool,
}

/// The gradient overlay of one parameter at one θ (match resolution).
#[derive(Clone, Debug)]
pub struct Overlay {
    /// Parameter index.
    pub param: usize,
    /// The iteration whose θ it shows.
    pub iteration: u32,
    /// Width (pixels).
    pub width: u32,
    /// Height (pixels).
    pub height: u32,
    /// `dp/dθ` per pixel (pixels per user unit), zero where nothing moves.
    pub motion: Vec<DVec2>,
    /// `dI/dθ` per pixel (linear RGB per user unit).
    pub d_image: Image,
    /// The OT matching, one segment per moving pixel (empty for L2).
    pub matching: Vec<Segment>,
    /// Differentiable paths per pixel and kind.
    pub kinds: Vec<KindCounts>,
    /// `dL/dθ` of every parameter.
    pub gradient: Vec<f64>,
}

/// What the worker reports.
#[derive(Clone, Debug)]
pub enum Update {
    /// A problem file is being loaded.
    Loading(PathBuf),
    /// A problem was loaded or reset.
    Loaded(Box<Loaded>),
    /// Loading a problem failed (the message names file and field).
    LoadFailed {
        /// The file.
        path: PathBuf,
        /// The error and its causes.
        message: String,
    },
    /// An iteration ran.
    Stepped(Box<Stepped>),
    /// θ changed without an iteration (sliders, configure).
    Theta {
        /// θ (clamped).
        theta: Vec<f64>,
        /// The next iteration to run.
        iteration: u32,
    },
    /// Whether the optimization is running.
    Running(bool),
    /// The current render, refined progressively (scene resolution).
    Render {
        /// The mean of the passes so far.
        image: Image,
        /// Samples per pixel so far.
        spp: u32,
    },
    /// A gradient overlay.
    Overlay(Box<Overlay>),
    /// An iteration or overlay failed.
    Error(String),
}
