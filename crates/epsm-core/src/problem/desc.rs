//! The problem file format: plain serde structures mirroring the TOML file
//! (documented field by field in `docs/problem-format.md`). Every struct
//! rejects unknown keys. Values are checked and turned into a
//! [`Problem`](super::Problem) by [`load_problem`](super::load_problem).
//!
//! | section | required | meaning |
//! |---|---|---|
//! | `scene_file` or `[scene]` | exactly one | the scene: a path relative to the problem file, or an embedded scene table |
//! | `[[parameters]]` | yes (≥ 1) | what is optimized |
//! | `[target]` | no | target image file, or the scene rendered at the true values |
//! | `[loss]` | no | OT (exact or Sinkhorn) or L2, λ, match resolution |
//! | `[optimizer]` | no | Adam settings, iterations, hybrid switch, method |
//! | `[render]` | no | samples of the primal render and the gradient pass |
//! | `[output]` | no | output folder and checkpoint interval |
//! | `tolerance` | no | the parameter error that counts as solved |
//!
//! A key left out takes its automatic value ([`super::auto`]): step sizes
//! from each parameter's scale, the decay from the iteration count, the
//! hybrid switch from progress, the matched render's samples from measured
//! noise, the colour-flow term when the camera moves.
//!
//! ```toml
//! scene_file = "../caustic-box.toml"
//!
//! [[parameters]]
//! key = "light.translate.x"
//! initial = -1.1
//! true = 0.0
//! bounds = [-1.5, 0.3]
//! ```

use epsm_scene::desc::SceneDesc;
use serde::{Deserialize, Serialize};

/// A whole problem file.
#[derive(Clone, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct ProblemDesc {
    /// Path of the scene file, relative to the problem file.
    pub scene_file: Option<String>,
    /// An embedded scene (the scene file format).
    pub scene: Option<SceneDesc>,
    /// The optimized parameters.
    pub parameters: Vec<ParamDesc>,
    /// What the render is compared with.
    #[serde(default)]
    pub target: TargetDesc,
    /// The loss.
    #[serde(default)]
    pub loss: LossDesc,
    /// The optimizer and schedule.
    #[serde(default)]
    pub optimizer: OptimizerDesc,
    /// Samples per pixel of the two renders of an iteration.
    #[serde(default)]
    pub render: RenderPassDesc,
    /// Where results go.
    #[serde(default)]
    pub output: OutputDesc,
    /// The parameter error (RMS of `θ − θ_true`, the parameters' units) at
    /// or below which the problem counts as solved.
    pub tolerance: Option<f64>,
}

/// `[[parameters]]`: one optimized scalar.
#[derive(Clone, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct ParamDesc {
    /// Parameter key, `"<name>.<field>"` (see `epsm_core::params`).
    pub key: String,
    /// Starting value in user units (default: the scene file's value).
    pub initial: Option<f64>,
    /// The true value, when known (renders the target; gives `param_error`).
    #[serde(rename = "true")]
    pub true_value: Option<f64>,
    /// `[lo, hi]` the value is kept in.
    pub bounds: Option<[f64; 2]>,
    /// Learning rate of this parameter (default: `optimizer.lr`, else
    /// automatic from its scale).
    pub lr: Option<f64>,
}

/// `[target]`: an image file, or the scene rendered at the true values.
#[derive(Clone, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct TargetDesc {
    /// Target image (`.exr` or `.png`), relative to the problem file, at the
    /// scene camera's resolution. When absent every parameter needs `true`.
    pub image: Option<String>,
    /// Samples per pixel of the rendered target.
    pub spp: u32,
    /// Seed of the rendered target.
    pub seed: u32,
}

impl Default for TargetDesc {
    fn default() -> Self {
        Self {
            image: None,
            spp: 256,
            seed: 7,
        }
    }
}

/// `[loss]`.
#[derive(Clone, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct LossDesc {
    /// `"ot_exact"`, `"ot_sinkhorn"` or `"l2"`.
    pub kind: String,
    /// Weight λ of screen position against colour in the OT points.
    pub lambda: f64,
    /// `[width, height]` of the matching and the gradient pass.
    pub match_resolution: [u32; 2],
    /// Blur (ε = blur²) of the Sinkhorn solver.
    pub blur: f64,
    /// Whether the OT's screen-position gradients get the colour-flow term
    /// ([`crate::loss::add_flow`]); absent: on when a camera parameter is
    /// optimized.
    pub flow: Option<bool>,
}

impl Default for LossDesc {
    fn default() -> Self {
        Self {
            kind: "ot_exact".into(),
            lambda: 1.0,
            match_resolution: [64, 64],
            blur: 0.01,
            flow: None,
        }
    }
}

/// `[optimizer]`.
#[derive(Clone, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct OptimizerDesc {
    /// `"epsm"`, `"drot"` or `"l2"`.
    pub method: String,
    /// Iterations.
    pub iterations: u32,
    /// Adam learning rate of every parameter, in user units per step
    /// (absent: automatic per parameter).
    pub lr: Option<f64>,
    /// Multiplicative learning-rate decay per iteration, in (0, 1] (absent:
    /// automatic from the iteration count).
    pub decay: Option<f64>,
    /// Adam β₁.
    pub beta1: f64,
    /// Adam β₂ (absent: automatic, 0.9 when every parameter is a material
    /// value, else 0.999).
    pub beta2: Option<f64>,
    /// Fraction of the iterations run with L2 at the end (hybrid schedule;
    /// absent: switch when the OT phase stops improving).
    pub l2_fraction: Option<f64>,
    /// Stop once the independent loss has not improved for a window of
    /// iterations in the L2 phase.
    pub stop: bool,
    /// Seed of the optimization's random streams.
    pub seed: u32,
}

impl Default for OptimizerDesc {
    fn default() -> Self {
        Self {
            method: "epsm".into(),
            iterations: 60,
            lr: None,
            decay: None,
            beta1: super::auto::BETA1,
            beta2: None,
            l2_fraction: None,
            stop: false,
            seed: 1,
        }
    }
}

/// `[render]`: samples per pixel of an iteration's two renders.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct RenderPassDesc {
    /// Primal render at the scene resolution (the report's image RMSE), ≥ 1.
    pub spp_primal: u32,
    /// Gradient pass at the match resolution (records paths), ≥ 1.
    pub spp_grad: u32,
    /// The image the loss compares at the match resolution: an independent
    /// render with this many samples per pixel (≥ 1), or 0 for none (OT
    /// compares the gradient pass's own image, L2 an independent render at
    /// `spp_grad`); absent: automatic from the measured noise.
    pub spp_match: Option<u32>,
}

impl Default for RenderPassDesc {
    fn default() -> Self {
        Self {
            spp_primal: 4,
            spp_grad: 4,
            spp_match: None,
        }
    }
}

/// `[output]`.
#[derive(Clone, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct OutputDesc {
    /// Output folder, relative to the working directory.
    pub dir: String,
    /// Write a checkpoint every this many iterations (0: never).
    pub checkpoint_every: u32,
}

impl Default for OutputDesc {
    fn default() -> Self {
        Self {
            dir: "out".into(),
            checkpoint_every: 10,
        }
    }
}
