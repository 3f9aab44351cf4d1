//! One optimization (docs/design.md §3): θ → scene → primal render and gradient
//! pass → loss → `dL/dθ` → Adam, one [`Row`] per iteration, checkpoints of
//! θ and the optimizer state, and resume.
//!
//! When the run starts, the settings the problem left automatic are chosen
//! ([`Optimization::choices`]): the colour-flow term, the learning-rate
//! decay, the matched render's samples ([`noise`]), the hybrid switch
//! ([`crate::schedule::Plateau`]) and, for material-only runs, the late
//! phase's extra samples ([`crate::problem::auto::late_samples`]). Every
//! few iterations θ is judged on an independent render and the best is
//! kept ([`best`]); with `optimizer.stop` the run ends once that judgement
//! stops improving in the L2 phase.
//!
//! Every random stream is keyed by the problem's seed and the iteration, so
//! a run resumed from a checkpoint follows the same θ trajectory as one that
//! was never interrupted.
//!
//! ## Library use
//! Build a [`Problem`] (from a file with [`crate::load_problem`], or in code
//! with [`Problem::new`] and [`crate::ParamSpec`]), then step an
//! [`Optimization`]: each [`Optimization::step`] returns the iteration's
//! [`Row`] (loss, image RMSE, parameter error, θ, path counts, timings);
//! [`Optimization::gradient`] gives `dL/dθ` at the current θ without
//! stepping; [`Optimization::checkpoint`] / [`Optimization::restore`] save
//! and resume.
//!
//! ```no_run
//! use epsm_core::{Optimization, ParamSpec, Problem};
//! let scene = epsm_scene::load_parts("scenes/layout.toml".as_ref())?;
//! let params = vec![ParamSpec::new("table.translate.x", -0.5, 0.04).with_true(0.0)];
//! let mut opt = Optimization::new(Problem::new(scene, params))?;
//! while !opt.is_done() {
//!     let row = opt.step()?;
//!     println!("{} {:.3e} {:?}", row.iteration, row.loss, row.theta);
//! }
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

pub mod best;
mod checkpoint;
mod choose;
mod error;
mod gradient;
pub mod noise;
pub mod prdpt;
mod view;

use std::sync::Mutex;
use std::time::Instant;

use epsm_ot::MatchState;
use epsm_render::tracer::{RenderOptions, render};
use epsm_render::{Image, Scene};

pub use best::{Best, Judge};
pub use checkpoint::Checkpoint;
use choose::choose;
pub use error::{OptResult, OptimizeError};
pub use gradient::GradientEval;

use crate::loss::{OUTLIER_RATIO, despeckle, resample, rmse};
use crate::optim::{Adam, AdamSettings};
use crate::params::ParamTable;
use crate::problem::auto::{self, Choice};
use crate::problem::{Problem, Target};
use crate::report::{Row, Timings, param_error};
use crate::schedule::{Method, Schedule};
use prdpt::Smoothing;
use view::View;

/// A running optimization.
pub struct Optimization {
    problem: Problem,
    schedule: Schedule,
    primal: View,
    grad: View,
    target: Image,
    target_match: Image,
    /// The OT loss's target: `target` without its isolated outlier pixels
    /// ([`despeckle`]), at the match resolution.
    target_ot: Image,
    theta: Vec<f64>,
    adam: Adam,
    iteration: u32,
    wall_before: f64,
    started: Instant,
    rows: Vec<Row>,
    /// What the last exact match left for the next ([`MatchState`]; a
    /// resumed run starts without it, which changes its matchings only among ties).
    warm: Mutex<MatchState>,
    choices: Vec<Choice>,
    judge: Judge,
    best: Option<Best>,
    stopped: bool,
    /// The `prdpt` method's smoothing (`None` for the other methods).
    smoothing: Option<Smoothing>,
    /// Whether independent stages run at the same time ([`Optimization::set_overlap`]).
    overlap: bool,
}

/// Iterations without progress that end the OT phase or (with
/// `optimizer.stop`) the run: an eighth of the run, at least 4.
fn window(iterations: u32) -> u32 {
    (iterations / 8).max(4)
}

/// The latest iteration that may still run OT: three quarters of the run.
fn latest_switch(iterations: u32) -> u32 {
    (f64::from(iterations) * 0.75).round() as u32
}

/// The seed of a random stream of iteration `iteration` of a run seeded
/// `seed`, told apart by `salt`.
fn stream_seed(seed: u32, iteration: u32, salt: u32) -> u32 {
    seed.wrapping_mul(0x9E37_79B9) ^ iteration.wrapping_mul(7919) ^ salt
}

/// Salt of the `prdpt` method's perturbations; pair `i`'s renders use
/// `PRDPT_SALT + 1 + i`.
const PRDPT_SALT: u32 = 0x09D0_0000;

impl Optimization {
    /// Sets up `problem` (renders the target when it is given by true
    /// values) and makes the automatic choices it leaves open.
    pub fn new(mut problem: Problem) -> OptResult<Self> {
        let cam = &problem.scene.camera;
        let mut primal = View::new(&problem, cam.width, cam.height)?;
        let [mw, mh] = problem.loss.match_resolution;
        let mut grad = View::new(&problem, mw, mh)?;
        let file_values = primal.table.values();
        let theta: Vec<f64> = problem
            .params
            .iter()
            .zip(&file_values)
            .map(|(p, f)| p.initial.unwrap_or(*f).clamp(p.bounds[0], p.bounds[1]))
            .collect();
        let target = match &problem.target {
            Target::Image(img) => img.clone(),
            Target::Render { spp, seed } => {
                let truth: Vec<f64> = problem
                    .params
                    .iter()
                    .zip(&theta)
                    .map(|(p, t)| p.true_value.unwrap_or(*t))
                    .collect();
                primal.set(&truth);
                render_image(&primal.scene, *spp, *seed)
            }
        };
        let target_match = resample(&target, mw, mh);
        let (clean, outliers) = despeckle(&target);
        let target_ot = resample(&clean, mw, mh);
        primal.set(&theta);
        grad.set(&theta);
        let mut choices = Vec::new();
        let (schedule, judge) = choose(&mut problem, &grad, &target_match, &mut choices);
        let outliers = outliers.iter().filter(|&&o| o).count();
        if outliers > 0 && schedule.loss_at(0).is_ot() {
            choices.push(Choice::new(
                "target.outliers",
                outliers.to_string(),
                format!(
                    "isolated target pixels more than {OUTLIER_RATIO} times as bright as each \
                     neighbour (fireflies): the OT loss matches a target with each replaced by \
                     its neighbours' median"
                ),
            ));
        }
        let o = &problem.optimizer;
        let smoothing = (o.method == Method::Prdpt)
            .then(|| Smoothing::new(&problem.params, o.iterations, o.decay.unwrap_or(1.0)));
        let adam = Adam::new(AdamSettings {
            lr: problem.params.iter().map(|p| p.lr).collect(),
            bounds: problem
                .params
                .iter()
                .zip(primal.table.params())
                .map(|(p, t)| {
                    let [lo, hi] = p.bounds;
                    [lo.max(t.target.step_floor()).min(hi), hi]
                })
                .collect(),
            decay: o.decay.unwrap_or(1.0),
            beta1: o.beta1,
            beta2: o.beta2.unwrap_or(auto::beta2(false)),
            epsilon: 1e-12,
        });
        Ok(Self {
            problem,
            schedule,
            primal,
            grad,
            target,
            target_match,
            target_ot,
            theta,
            adam,
            iteration: 0,
            wall_before: 0.0,
            started: Instant::now(),
            rows: Vec::new(),
            warm: Mutex::default(),
            choices,
            judge,
            best: None,
            stopped: false,
            smoothing,
            overlap: true,
        })
    }

    /// Every automatic choice of the problem and the run, in the order
    /// made (print them at the start of a run).
    pub fn choices(&self) -> &[Choice] {
        &self.choices
    }

    /// The θ with the lowest judged loss so far ([`best`]).
    pub fn best(&self) -> Option<&Best> {
        self.best.as_ref()
    }

    /// The first L2 iteration (the iteration count when none is, or while
    /// the switch is not decided).
    pub fn switch(&self) -> u32 {
        self.schedule.switch()
    }

    /// The problem.
    pub fn problem(&self) -> &Problem {
        &self.problem
    }

    /// Parameter keys, index order.
    pub fn keys(&self) -> Vec<String> {
        self.problem.params.iter().map(|p| p.key.clone()).collect()
    }

    /// Current θ (user units).
    pub fn theta(&self) -> &[f64] {
        &self.theta
    }

    /// The next iteration to run.
    pub fn iteration(&self) -> u32 {
        self.iteration
    }

    /// Whether every scheduled iteration has run, or the run stopped
    /// converged (`optimizer.stop`).
    pub fn is_done(&self) -> bool {
        self.iteration >= self.schedule.iterations || self.stopped
    }

    /// The rows so far.
    pub fn rows(&self) -> &[Row] {
        &self.rows
    }

    /// The target at the scene resolution.
    pub fn target(&self) -> &Image {
        &self.target
    }

    /// The scene at the current θ (scene resolution).
    pub fn scene(&self) -> &Scene {
        &self.primal.scene
    }

    /// The parameter table at the match resolution (for `dp/dθ` queries).
    pub fn match_view(&self) -> (&Scene, &ParamTable) {
        (&self.grad.scene, &self.grad.table)
    }

    /// The match-resolution scene and table, mutably (for probes such as
    /// [`crate::field::image_derivative`], which restore θ).
    pub fn match_view_mut(&mut self) -> (&mut Scene, &mut ParamTable) {
        (&mut self.grad.scene, &mut self.grad.table)
    }

    /// Renders the current θ at the scene resolution.
    pub fn render(&self, spp: u32) -> Image {
        render_image(&self.primal.scene, spp, self.seed(0x5eed))
    }

    /// Sets θ (clamped to the bounds) without touching the optimizer.
    pub fn set_theta(&mut self, theta: &[f64]) {
        self.theta = theta.to_vec();
        self.adam.clamp(&mut self.theta);
        self.primal.set(&self.theta);
        self.grad.set(&self.theta);
    }

    fn seed(&self, salt: u32) -> u32 {
        stream_seed(self.problem.optimizer.seed, self.iteration, salt)
    }

    /// Whether independent stages of an iteration run at the same time
    /// (default on): the recorded trace, the primal render and the judged
    /// renders beside the matching, which runs mostly on one thread.
    /// Either way the results are the
    /// same bit for bit (every stream is seeded); off, the stages run one
    /// after the other, as `epsm bench iteration` compares.
    pub fn set_overlap(&mut self, on: bool) {
        self.overlap = on;
    }

    /// Runs `a` and `b`, at the same time when overlap is on.
    fn maybe_join<A: Send, B: Send>(
        &self,
        a: impl FnOnce() -> A + Send,
        b: impl FnOnce() -> B + Send,
    ) -> (A, B) {
        if self.overlap {
            rayon::join(a, b)
        } else {
            (a(), b())
        }
    }

    /// Runs one iteration and returns its row.
    pub fn step(&mut self) -> OptResult<Row> {
        // The primal render and the judged renders (of the same θ) fill
        // the cores while the gradient pass's matching runs.
        let judges = self.judge.judges(self.iteration, false);
        let (g, _, (image, primal, judged)) = self.gradient_beside(|| {
            let t0 = Instant::now();
            let image = render_image(
                &self.primal.scene,
                self.problem.passes.spp_primal,
                self.seed(1),
            );
            let primal = t0.elapsed().as_secs_f64();
            (image, primal, judges.then(|| self.judged()))
        })?;
        if self.schedule.resets_at(self.iteration) {
            self.adam.reset();
        }
        if let Some(loss) = judged {
            Best::offer(&mut self.best, self.iteration, &self.theta, loss);
        }
        let ot = self.schedule.loss_at(self.iteration).is_ot();
        let truth: Vec<Option<f64>> = self.problem.params.iter().map(|p| p.true_value).collect();
        let row = Row {
            iteration: self.iteration,
            wall_s: self.wall_before + self.started.elapsed().as_secs_f64(),
            loss: g.loss.value,
            image_rmse: rmse(&image, &self.target),
            param_error: param_error(&self.theta, &truth),
            judged_loss: judged,
            theta: self.theta.clone(),
            paths: [g.stats.traced, g.stats.solved, g.stats.skipped],
            dropped: crate::drops::DropReason::ALL
                .iter()
                .map(|r| g.stats.dropped.get(*r))
                .collect(),
            guards: g.loss.guards,
            kinds: g.stats.kinds_seen(),
            timings: Timings {
                primal,
                ..g.timings
            },
        };
        let mut theta = self.theta.clone();
        self.adam.step(&mut theta, &g.grad).map_err(|e| {
            let key = self.problem.params.get(e.param).map(|p| p.key.clone());
            OptimizeError::NonFiniteGradient(key.unwrap_or_else(|| e.param.to_string()))
        })?;
        self.set_theta(&theta);
        if ot {
            self.schedule.observe(self.iteration, g.loss.value);
        }
        self.iteration += 1;
        self.stopped = self.converged();
        self.rows.push(row.clone());
        if self.is_done() {
            let loss = self.judged();
            Best::offer(&mut self.best, self.iteration, &self.theta, loss);
            self.offer_tail_mean();
        }
        Ok(row)
    }

    /// Whether `optimizer.stop` ends the run now: the judged loss has not
    /// improved for a window of iterations since the L2 phase began.
    fn converged(&self) -> bool {
        let switch = self.schedule.switch();
        if !self.problem.optimizer.stop || self.iteration < switch {
            return false;
        }
        let since = self.best.as_ref().map_or(0, |b| b.iteration).max(switch);
        self.iteration - since >= window(self.schedule.iterations)
    }
}

fn render_image(scene: &Scene, spp: u32, seed: u32) -> Image {
    let opts = RenderOptions {
        spp,
        seed,
        ..RenderOptions::from_scene(scene)
    };
    render(scene, &opts, &|_| {}).image
}
