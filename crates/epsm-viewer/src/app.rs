//! The viewer application: the [`Worker`] handle, the [`Model`] built from
//! its updates, and the UI's own settings. [`ViewerApp::show`] draws one
//! frame into any [`egui::Ui`] (eframe's window, or a test harness).
//!
//! Layout: a left panel (open, controls, parameters, overlay settings), and
//! the central panel (error banner, the three images, the live plot).

use std::path::PathBuf;

use eframe::egui;

use crate::overlay::OverlaySettings;
use crate::panels;
use crate::recent::Recent;
use crate::screenshot::Screenshot;
use crate::state::Model;
use crate::worker::{Command, RunSettings, Worker};

/// How the viewer starts.
#[derive(Clone, Debug, Default)]
pub struct Options {
    /// The problem to open first.
    pub problem: Option<PathBuf>,
    /// Run this many iterations as soon as the problem is loaded.
    pub autorun: Option<u32>,
    /// After the autorun (and a refined render), save a screenshot here and quit.
    pub screenshot: Option<PathBuf>,
    /// Where the recent-files list is kept (`None`: not kept).
    pub recent_file: Option<PathBuf>,
    /// The overlay layers shown at start.
    pub overlay: OverlaySettings,
}

/// The UI-side state of the controls panel.
#[derive(Clone, Debug, PartialEq)]
pub struct Controls {
    /// The path typed in the open field.
    pub path_text: String,
    /// The method chosen in the controls.
    pub method: epsm_core::Method,
    /// The learning-rate factor chosen in the controls.
    pub lr_scale: f64,
    /// The settings last sent to the worker.
    pub applied: RunSettings,
    /// The parameter whose overlay is shown.
    pub overlay_param: Option<usize>,
}

/// The viewer.
pub struct ViewerApp {
    /// The worker (started on the first frame; `None` before, after closing,
    /// or if the thread could not be started).
    pub worker: Option<Worker>,
    /// Whether the worker was started (it is never restarted).
    started: bool,
    /// The problem to open once the worker runs.
    pending_open: Option<PathBuf>,
    /// What the worker reported.
    pub model: Model,
    /// The controls' state.
    pub controls: Controls,
    /// Overlay toggles and densities.
    pub overlay: OverlaySettings,
    /// Recent problem files.
    pub recent: Recent,
    /// Pending autorun (sent once the problem is loaded).
    autorun: Option<u32>,
    /// The screenshot request, if any.
    pub screenshot: Option<Screenshot>,
}

impl ViewerApp {
    /// A viewer that will open `options.problem`; the worker starts on the
    /// first frame (it wakes that frame's context on every update).
    pub fn new(options: Options) -> Self {
        Self {
            worker: None,
            started: false,
            pending_open: options.problem,
            model: Model::default(),
            controls: Controls {
                path_text: String::new(),
                method: epsm_core::Method::Epsm,
                lr_scale: 1.0,
                applied: RunSettings {
                    method: epsm_core::Method::Epsm,
                    lr_scale: 1.0,
                },
                overlay_param: None,
            },
            overlay: options.overlay,
            recent: Recent::load(options.recent_file),
            autorun: options.autorun,
            screenshot: options
                .screenshot
                .map(|p| Screenshot::new(p, options.autorun.unwrap_or(0))),
        }
    }

    fn start(&mut self, ctx: &egui::Context) {
        if self.started {
            return;
        }
        self.started = true;
        let wake_ctx = ctx.clone();
        match Worker::spawn(Box::new(move || wake_ctx.request_repaint())) {
            Ok(w) => self.worker = Some(w),
            Err(e) => self.model.error = Some(format!("could not start the worker thread: {e}")),
        }
        if let Some(p) = self.pending_open.take() {
            self.open(p);
        }
    }

    /// Sends `command` to the worker; reports a stopped worker in the window.
    pub fn send(&mut self, command: Command) {
        let sent = self.worker.as_ref().is_some_and(|w| w.send(command));
        if !sent {
            self.model.error = Some("the worker thread has stopped".into());
        }
    }

    /// Opens the problem file at `path` (on the worker; it joins the recent
    /// files once loaded).
    pub fn open(&mut self, path: PathBuf) {
        self.controls.path_text = path.display().to_string();
        self.send(Command::Load(path));
    }

    /// Stops the worker and waits for its thread to end.
    pub fn close(&mut self) {
        self.worker = None;
    }

    /// Reads the worker's updates into the model.
    pub fn poll(&mut self, ctx: &egui::Context) {
        let updates = self.worker.as_ref().map(Worker::poll).unwrap_or_default();
        for u in updates {
            let loaded = matches!(u, crate::worker::Update::Loaded(_));
            self.model.apply(ctx, u);
            if loaded {
                self.on_loaded();
            }
        }
        if self.worker.as_ref().is_some_and(|w| !w.is_alive()) {
            self.model.error = Some("the worker thread stopped unexpectedly".into());
        }
    }

    fn on_loaded(&mut self) {
        let Some(p) = &self.model.problem else {
            return;
        };
        self.recent.add(&p.path);
        self.controls.method = p.settings.method;
        self.controls.lr_scale = p.settings.lr_scale;
        self.controls.applied = p.settings;
        let n = p.params.len();
        let param = self
            .controls
            .overlay_param
            .filter(|i| *i < n)
            .or((n > 0).then_some(0));
        self.controls.overlay_param = param;
        self.send(Command::OverlayParam(param));
        if let Some(steps) = self.autorun.take() {
            self.send(Command::Run(Some(steps)));
        }
    }

    /// Draws one frame.
    pub fn show(&mut self, ui: &mut egui::Ui) {
        let ctx = ui.ctx().clone();
        self.start(&ctx);
        self.poll(&ctx);
        egui::Panel::left("controls")
            .resizable(true)
            .default_size(320.0)
            .show(ui, |ui| {
                egui::ScrollArea::vertical().show(ui, |ui| panels::side(ui, self));
            });
        egui::CentralPanel::default().show(ui, |ui| panels::central(ui, self));
        if let Some(shot) = self.screenshot.as_mut() {
            shot.update(&ctx, &self.model);
        }
    }
}

impl eframe::App for ViewerApp {
    fn ui(&mut self, ui: &mut egui::Ui, _frame: &mut eframe::Frame) {
        self.show(ui);
    }

    fn on_exit(&mut self, _gl: Option<&eframe::glow::Context>) {
        self.close();
    }
}
