//! One optimization (docs/design.md §3): θ → scene → primal render and gradient
//! pass → loss → `dL/dθ` → Adam, one [`Row`] per iteration, checkpoints of
//! θ and the optimizer state, and resume.
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
//! let scene = epsm_render::scene::load_parts("scenes/layout.toml".as_ref())?;
//! let params = vec![ParamSpec::new("table.translate.x", -0.5, 0.04).with_true(0.0)];
//! let mut opt = Optimization::new(Problem::new(scene, params))?;
//! while !opt.is_done() {
//!     let row = opt.step()?;
//!     println!("{} {:.3e} {:?}", row.iteration, row.loss, row.theta);
//! }
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

mod checkpoint;
mod error;

use std::time::Instant;

use epsm_render::record::PathRecord;
use epsm_render::tracer::{RenderOptions, render, render_recorded};
use epsm_render::{Image, Scene};

pub use checkpoint::Checkpoint;
pub use error::{OptResult, OptimizeError};

use crate::backprop::{PassInput, PassStats, backprop, record_level};
use crate::colour::{ColourModel, PrimaryMotion};
use crate::loss::{LossEval, add_flow, evaluate, resample, rmse};
use crate::optim::{Adam, AdamSettings};
use crate::params::ParamTable;
use crate::problem::{LossImage, Problem, Target};
use crate::report::{Row, Timings, param_error};
use crate::schedule::Schedule;

/// A scene and its parameter table (one per resolution).
#[derive(Clone, Debug)]
struct View {
    scene: Scene,
    table: ParamTable,
}

impl View {
    fn new(problem: &Problem, width: u32, height: u32) -> OptResult<Self> {
        let mut parts = problem.scene.clone();
        parts.camera.width = width;
        parts.camera.height = height;
        let mut scene = Scene::new(parts)?;
        let mut table = ParamTable::new(&scene);
        for p in &problem.params {
            table.add(&p.key)?;
        }
        // Driven objects get their own BVH instances now, so moving them
        // rebuilds only the top level (not the static objects' BVH).
        scene.set_dynamic(&table.moving_objects());
        Ok(Self { scene, table })
    }

    fn set(&mut self, theta: &[f64]) {
        for (k, v) in theta.iter().enumerate() {
            self.table.set_value(k, *v);
        }
        self.table.apply(&mut self.scene);
    }
}

/// The gradient at the current θ and what produced it.
#[derive(Clone, Debug)]
pub struct GradientEval {
    /// `dL/dθ`, index order.
    pub grad: Vec<f64>,
    /// The loss at the match resolution, with its per-pixel gradients.
    pub loss: LossEval,
    /// The gradient-pass image (match resolution).
    pub image: Image,
    /// Path counts.
    pub stats: PassStats,
    /// Seconds of the trace, matching and solve parts.
    pub timings: Timings,
}

/// A running optimization.
pub struct Optimization {
    problem: Problem,
    schedule: Schedule,
    primal: View,
    grad: View,
    target: Image,
    target_match: Image,
    theta: Vec<f64>,
    adam: Adam,
    iteration: u32,
    wall_before: f64,
    started: Instant,
    rows: Vec<Row>,
}

impl Optimization {
    /// Sets up `problem` (renders the target when it is given by true values).
    pub fn new(problem: Problem) -> OptResult<Self> {
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
        primal.set(&theta);
        grad.set(&theta);
        let o = &problem.optimizer;
        let adam = Adam::new(AdamSettings {
            lr: problem.params.iter().map(|p| p.lr).collect(),
            bounds: problem.params.iter().map(|p| p.bounds).collect(),
            decay: o.decay,
            beta1: o.beta1,
            beta2: o.beta2,
            epsilon: 1e-12,
        });
        let schedule = Schedule {
            method: o.method,
            loss: problem.loss.kind,
            iterations: o.iterations,
            l2_fraction: o.l2_fraction,
        };
        Ok(Self {
            problem,
            schedule,
            primal,
            grad,
            target,
            target_match,
            theta,
            adam,
            iteration: 0,
            wall_before: 0.0,
            started: Instant::now(),
            rows: Vec::new(),
        })
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

    /// Whether every scheduled iteration has run.
    pub fn is_done(&self) -> bool {
        self.iteration >= self.schedule.iterations
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
        self.problem.optimizer.seed.wrapping_mul(0x9E37_79B9)
            ^ self.iteration.wrapping_mul(7919)
            ^ salt
    }

    /// `dL/dθ` at the current θ for the current iteration's loss and paths,
    /// and the records it used.
    pub fn gradient(&self) -> OptResult<(GradientEval, Vec<PathRecord>)> {
        let use_ = self.schedule.paths_at(self.iteration);
        let l2 = !self.schedule.loss_at(self.iteration).is_ot();
        let colour = ColourModel::new(
            &self.grad.table,
            &self.grad.scene,
            l2.then_some(PrimaryMotion::OnCameraRay),
        );
        let level = record_level(&self.grad.table, &self.grad.scene, &colour, use_);
        let spp = self.problem.passes.spp_grad;
        let t0 = Instant::now();
        let opts = RenderOptions {
            spp,
            seed: self.seed(0),
            ..RenderOptions::from_scene(&self.grad.scene)
        };
        let (out, records) = render_recorded(&self.grad.scene, &opts, level, &|_| {});
        let image = match self.problem.passes.loss_image(!l2) {
            LossImage::GradientPass => out.image.clone(),
            LossImage::Independent(spp) => render_image(&self.grad.scene, spp, self.seed(2)),
        };
        let t1 = Instant::now();
        let kind = self.schedule.loss_at(self.iteration);
        let mut loss = evaluate(kind, &image, &self.target_match, self.problem.loss.lambda)?;
        if self.problem.loss.flow && kind.is_ot() {
            add_flow(&image, &mut loss)?;
        }
        let t2 = Instant::now();
        let input = PassInput {
            scene: &self.grad.scene,
            table: &self.grad.table,
            colour: &colour,
            loss: &loss,
            spp,
            use_,
        };
        let (grad, stats) = backprop(&input, &records);
        let timings = Timings {
            primal: 0.0,
            trace: (t1 - t0).as_secs_f64(),
            matching: (t2 - t1).as_secs_f64(),
            solve: t2.elapsed().as_secs_f64(),
        };
        Ok((
            GradientEval {
                grad,
                loss,
                image: out.image,
                stats,
                timings,
            },
            records,
        ))
    }

    /// Runs one iteration and returns its row.
    pub fn step(&mut self) -> OptResult<Row> {
        let t0 = Instant::now();
        let image = render_image(
            &self.primal.scene,
            self.problem.passes.spp_primal,
            self.seed(1),
        );
        let primal = t0.elapsed().as_secs_f64();
        let (g, _) = self.gradient()?;
        if self.schedule.resets_at(self.iteration) {
            self.adam.reset();
        }
        let truth: Vec<Option<f64>> = self.problem.params.iter().map(|p| p.true_value).collect();
        let row = Row {
            iteration: self.iteration,
            wall_s: self.wall_before + self.started.elapsed().as_secs_f64(),
            loss: g.loss.value,
            image_rmse: rmse(&image, &self.target),
            param_error: param_error(&self.theta, &truth),
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
        self.iteration += 1;
        self.rows.push(row.clone());
        Ok(row)
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
