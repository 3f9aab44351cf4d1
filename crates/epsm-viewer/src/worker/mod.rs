//! The worker thread: it owns the optimization, renders and overlays, and
//! talks to the UI only through channels ([`messages`]), so no UI frame
//! ever waits on a render. Between units of work (one iteration, one render
//! pass, one overlay) it reads every pending command; when there is nothing
//! to do it blocks on the command channel. Dropping the [`Worker`] sends
//! [`Command::Shutdown`] and joins the thread (at most one unit of work
//! later).

pub mod messages;
mod session;

use std::sync::mpsc::{Receiver, Sender, TryRecvError, channel};
use std::thread::JoinHandle;

pub use messages::{Command, Loaded, Overlay, RunSettings, Stepped, Update};
pub use session::{MAX_SPP, PASS_SPP};

use epsm_core::error_chain;
use session::Session;

/// Wakes the UI when an update is sent (e.g. `egui::Context::request_repaint`).
pub type Waker = Box<dyn Fn() + Send>;

/// The UI's handle on the worker thread.
pub struct Worker {
    commands: Sender<Command>,
    updates: Receiver<Update>,
    thread: Option<JoinHandle<()>>,
}

impl Worker {
    /// Starts the worker; `wake` is called after every update it sends.
    pub fn spawn(wake: Waker) -> std::io::Result<Self> {
        let (commands, command_rx) = channel();
        let (update_tx, updates) = channel();
        let thread = std::thread::Builder::new()
            .name("epsm-viewer-worker".into())
            .spawn(move || {
                Loop {
                    commands: command_rx,
                    updates: update_tx,
                    wake,
                    session: None,
                }
                .run();
            })?;
        Ok(Self {
            commands,
            updates,
            thread: Some(thread),
        })
    }

    /// Sends a command; `false` when the worker has stopped.
    pub fn send(&self, command: Command) -> bool {
        self.commands.send(command).is_ok()
    }

    /// The updates received so far, oldest first.
    pub fn poll(&self) -> Vec<Update> {
        self.updates.try_iter().collect()
    }

    /// Whether the worker thread is still alive.
    pub fn is_alive(&self) -> bool {
        self.thread.as_ref().is_some_and(|t| !t.is_finished())
    }
}

impl Drop for Worker {
    fn drop(&mut self) {
        let _ = self.commands.send(Command::Shutdown);
        if let Some(thread) = self.thread.take() {
            // A panic on the worker was already reported on stderr; the UI
            // is closing either way.
            let _ = thread.join();
        }
    }
}

/// The worker thread's state.
struct Loop {
    commands: Receiver<Command>,
    updates: Sender<Update>,
    wake: Waker,
    session: Option<Session>,
}

impl Loop {
    fn run(mut self) {
        loop {
            let busy = self
                .session
                .as_ref()
                .is_some_and(|s| s.running || s.wants_render() || s.wants_overlay());
            let command = if busy {
                match self.commands.try_recv() {
                    Ok(c) => Some(c),
                    Err(TryRecvError::Empty) => None,
                    Err(TryRecvError::Disconnected) => return,
                }
            } else {
                match self.commands.recv() {
                    Ok(c) => Some(c),
                    Err(_) => return,
                }
            };
            match command {
                Some(Command::Shutdown) => return,
                Some(c) => self.handle(c),
                None => self.work(),
            }
        }
    }

    fn send(&self, update: Update) {
        if self.updates.send(update).is_ok() {
            (self.wake)();
        }
    }

    fn handle(&mut self, command: Command) {
        if let Command::Load(path) = command {
            self.send(Update::Loading(path.clone()));
            match Session::load(&path) {
                Ok(s) => {
                    self.send(Update::Loaded(Box::new(s.loaded())));
                    self.session = Some(s);
                }
                Err(e) => self.send(Update::LoadFailed {
                    path,
                    message: error_chain(&e),
                }),
            }
            return;
        }
        let Some(s) = self.session.as_mut() else {
            return;
        };
        let mut update = None;
        match command {
            Command::Run(steps) => s.run(steps),
            Command::Pause => s.pause(),
            Command::Reset(settings) => {
                update = Some(match s.reset(settings) {
                    Ok(()) => Update::Loaded(Box::new(s.loaded())),
                    Err(e) => Update::Error(error_chain(&e)),
                });
            }
            Command::Configure(settings) => {
                update = Some(match s.configure(settings) {
                    Ok(()) => theta_update(s),
                    Err(e) => Update::Error(error_chain(&e)),
                });
            }
            Command::SetTheta(theta) => {
                s.set_theta(&theta);
                update = Some(theta_update(s));
            }
            Command::OverlayParam(p) => s.set_overlay_param(p),
            Command::Load(_) | Command::Shutdown => {}
        }
        let running = Update::Running(s.running);
        if let Some(u) = update {
            self.send(u);
        }
        self.send(running);
    }

    /// One unit of work: the first render pass at a new θ, else an
    /// iteration, else an overlay, else a refining render pass.
    fn work(&mut self) {
        let Some(s) = self.session.as_mut() else {
            return;
        };
        let mut out = Vec::new();
        if s.running && !s.needs_first_pass() {
            match s.step() {
                Ok(stepped) => out.push(Update::Stepped(Box::new(stepped))),
                Err(e) => out.push(Update::Error(error_chain(&e))),
            }
            if !s.running {
                out.push(Update::Running(false));
            }
        } else if s.wants_overlay() && !s.render_is_coarse() {
            match s.overlay() {
                Some(Ok(o)) => out.push(Update::Overlay(Box::new(o))),
                Some(Err(e)) => out.push(Update::Error(error_chain(&e))),
                None => {}
            }
        } else if s.wants_render() {
            let (image, spp) = s.render_pass();
            out.push(Update::Render { image, spp });
        }
        for u in out {
            self.send(u);
        }
    }
}

fn theta_update(s: &Session) -> Update {
    Update::Theta {
        theta: s.theta().to_vec(),
        iteration: s.iteration(),
    }
}
