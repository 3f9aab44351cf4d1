//! Optimization problems (docs/design.md §4): a scene, the parameters to recover,
//! the target, the loss, the optimizer and the output settings, loaded from
//! a TOML problem file ([`desc`], `docs/problem-format.md`) or built in code.
//!
//! Every malformed field gives a [`ProblemError`] naming the file, the line
//! and the dotted field; nothing panics.
//!
//! ```toml
//! scene_file = "../layout.toml"
//!
//! [[parameters]]
//! key = "table.translate.x"
//! initial = 0.6
//! true = 0.0
//!
//! [loss]
//! kind = "ot_exact"
//! match_resolution = [64, 64]
//! ```

pub mod auto;
pub mod desc;
mod error;
mod validate;

use std::path::{Path, PathBuf};

use epsm_render::Image;
use epsm_render::scene::SceneParts;

use crate::loss::LossKind;
use crate::schedule::Method;
pub use desc::ProblemDesc;
pub use error::ProblemError;

/// One optimized parameter.
#[derive(Clone, Debug, PartialEq)]
pub struct ParamSpec {
    /// Parameter key (see [`crate::params`]).
    pub key: String,
    /// Starting value (user units); `None`: the scene file's value.
    pub initial: Option<f64>,
    /// The true value when known.
    pub true_value: Option<f64>,
    /// `[lo, hi]` (`±f64::MAX` when unbounded).
    pub bounds: [f64; 2],
    /// Learning rate (user units per step); with `step`, the value for the
    /// problem file's iteration count, set again for the run's.
    pub lr: f64,
    /// The scale of an automatic learning rate (`None`: `lr` was given).
    pub step: Option<auto::Step>,
}

impl ParamSpec {
    /// An unbounded parameter starting at `initial` with learning rate `lr`.
    pub fn new(key: &str, initial: f64, lr: f64) -> Self {
        Self {
            key: key.to_owned(),
            initial: Some(initial),
            true_value: None,
            bounds: [-f64::MAX, f64::MAX],
            lr,
            step: None,
        }
    }

    /// The same parameter with a known true value.
    pub fn with_true(mut self, value: f64) -> Self {
        self.true_value = Some(value);
        self
    }
}

/// What the render is compared with.
#[derive(Clone, Debug, PartialEq)]
pub enum Target {
    /// A given image at the scene camera's resolution (linear RGB).
    Image(Image),
    /// The scene rendered at the true parameter values.
    Render {
        /// Samples per pixel.
        spp: u32,
        /// Seed.
        seed: u32,
    },
}

/// The loss settings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LossSettings {
    /// The loss used before the hybrid switch.
    pub kind: LossKind,
    /// Weight λ of screen position against colour.
    pub lambda: f64,
    /// `[width, height]` of the matching and the gradient pass.
    pub match_resolution: [u32; 2],
    /// Whether the OT's screen-position gradients get the colour-flow term
    /// ([`crate::loss::add_flow`]; for camera moves); `None`: automatic, on
    /// when a camera parameter is optimized.
    pub flow: Option<bool>,
}

/// The optimizer and schedule settings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OptimizerSettings {
    /// The method.
    pub method: Method,
    /// Iterations.
    pub iterations: u32,
    /// Multiplicative learning-rate decay per iteration; `None`: automatic
    /// ([`auto::decay`] of the iteration count).
    pub decay: Option<f64>,
    /// Adam β₁.
    pub beta1: f64,
    /// Adam β₂; `None`: automatic ([`auto::beta2`]).
    pub beta2: Option<f64>,
    /// Fraction of iterations run with L2 at the end; `None`: switch when
    /// the OT phase stops improving ([`crate::schedule::Plateau`]).
    pub l2_fraction: Option<f64>,
    /// Stop once the independent loss has not improved for a window of
    /// iterations in the L2 phase.
    pub stop: bool,
    /// Seed of the iterations' random streams.
    pub seed: u32,
}

/// Samples per pixel of an iteration's two renders.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Passes {
    /// Primal render at the scene resolution (image RMSE in the report).
    pub spp_primal: u32,
    /// Gradient pass at the match resolution.
    pub spp_grad: u32,
    /// Samples per pixel of an independent render at the match resolution
    /// that the loss compares with the target, 0 for none (see
    /// [`Passes::loss_image`]); `None`: automatic, from the noise measured
    /// when the run starts.
    pub spp_match: Option<u32>,
    /// The late phase's extra samples ([`Passes::at`]); `None` until the
    /// run's automatic choices are made, and for runs without one
    /// ([`auto::late_samples`]).
    pub late: Option<auto::LateSamples>,
}

/// Which image an iteration's loss compares with the target.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LossImage {
    /// The gradient pass's own image (its paths are differentiated).
    GradientPass,
    /// An independent render at the match resolution with this many
    /// samples per pixel.
    Independent(u32),
}

impl Passes {
    /// The image the loss compares, for an OT (`ot = true`) or L2 iteration,
    /// once `spp_match` is resolved (`None` and `Some(0)` both read as no
    /// matched render here).
    ///
    /// L2 always takes an independent render (`spp_match`, else
    /// `spp_grad`): its gradient `2(c − c*)·dc/dθ` is biased when `c` and
    /// `dc/dθ` share samples. OT takes the gradient pass's image unless
    /// `spp_match` is set: the matching of a noisy image to a clean target
    /// is biased (noisy pixels trade places with similar-coloured
    /// neighbours across edges, and when the neighbour does not move with θ
    /// the trade pulls the moving side one way), a bias that falls with the
    /// matched image's variance, not with the number of differentiated
    /// paths.
    pub fn loss_image(&self, ot: bool) -> LossImage {
        match (self.spp_match.filter(|&s| s > 0), ot) {
            (Some(spp), _) => LossImage::Independent(spp),
            (None, true) => LossImage::GradientPass,
            (None, false) => LossImage::Independent(self.spp_grad),
        }
    }

    /// The samples of iteration `iteration`: these passes, with the
    /// gradient pass's and the matched render's samples multiplied by the
    /// late phase's factor from its first iteration on.
    pub fn at(&self, iteration: u32) -> Passes {
        match self.late {
            Some(late) if iteration >= late.from => Passes {
                spp_grad: self.spp_grad.saturating_mul(late.factor),
                spp_match: self.spp_match.map(|s| s.saturating_mul(late.factor)),
                ..*self
            },
            _ => *self,
        }
    }
}

/// A complete optimization problem.
#[derive(Clone, Debug)]
pub struct Problem {
    /// The scene at its file placement, at the render resolution.
    pub scene: SceneParts,
    /// The optimized parameters.
    pub params: Vec<ParamSpec>,
    /// The target.
    pub target: Target,
    /// The loss.
    pub loss: LossSettings,
    /// The optimizer.
    pub optimizer: OptimizerSettings,
    /// The renders of an iteration.
    pub passes: Passes,
    /// Default output folder.
    pub out_dir: PathBuf,
    /// Checkpoint interval in iterations (0: never).
    pub checkpoint_every: u32,
    /// The parameter error at or below which the problem counts as solved.
    pub tolerance: Option<f64>,
}

impl Problem {
    /// A problem over `scene` with default settings (OT exact at 64², 60
    /// iterations of `epsm`, target rendered at the true values with 256 spp,
    /// the automatic choices of a problem file that leaves the tuning keys
    /// out; the step sizes are the parameters' own).
    pub fn new(scene: SceneParts, params: Vec<ParamSpec>) -> Self {
        let (target, loss) = (desc::TargetDesc::default(), desc::LossDesc::default());
        let (opt, render) = (
            desc::OptimizerDesc::default(),
            desc::RenderPassDesc::default(),
        );
        let output = desc::OutputDesc::default();
        Self {
            scene,
            params,
            target: Target::Render {
                spp: target.spp,
                seed: target.seed,
            },
            loss: LossSettings {
                kind: LossKind::OtExact,
                lambda: loss.lambda,
                match_resolution: loss.match_resolution,
                flow: loss.flow,
            },
            optimizer: OptimizerSettings {
                method: Method::Epsm,
                iterations: opt.iterations,
                decay: opt.decay,
                beta1: opt.beta1,
                beta2: opt.beta2,
                l2_fraction: opt.l2_fraction,
                stop: opt.stop,
                seed: opt.seed,
            },
            passes: Passes {
                spp_primal: render.spp_primal,
                spp_grad: render.spp_grad,
                spp_match: render.spp_match,
                late: None,
            },
            out_dir: PathBuf::from(output.dir),
            checkpoint_every: output.checkpoint_every,
            tolerance: None,
        }
    }
}

/// Loads and checks the problem file at `path`.
pub fn load_problem(path: &Path) -> Result<Problem, ProblemError> {
    let text = epsm_scene::input_file::read_to_string(path).map_err(ProblemError::Read)?;
    problem_from_str(&text, path)
}

/// Checks the text of a problem file; `file` names it in errors and its
/// directory resolves relative paths.
pub fn problem_from_str(text: &str, file: &Path) -> Result<Problem, ProblemError> {
    let (desc, locator) = epsm_scene::fields::parse::<ProblemDesc>(text, file)?;
    validate::problem(&desc, file, &locator, None)
}

/// As [`problem_from_str`], with the target given as an image (linear RGB
/// at the scene camera's resolution) in place of a `target.image` file
/// (which the text must then leave out): checked as that field is, with
/// errors naming `target.image`.
pub fn problem_with_target(
    text: &str,
    file: &Path,
    target: Image,
) -> Result<Problem, ProblemError> {
    let (desc, locator) = epsm_scene::fields::parse::<ProblemDesc>(text, file)?;
    validate::problem(&desc, file, &locator, Some(target))
}
