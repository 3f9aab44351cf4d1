//! Automatic choices: the value a problem-file key takes when the file
//! leaves it out, and why. Each choice is printed at the start of a run
//! ([`Choice`]) and documented in `docs/problem-format.md`.
//!
//! | key | automatic rule |
//! |---|---|
//! | `parameters[i].lr` | [`CROSSING`] × scale / iterations; the scale is the bound width, else a quarter of the scene's bounding-box diagonal for positions, [`ANGLE_SCALE`] for angles, the key's range for albedo and alpha, the value's magnitude (at least 1) for other factors |
//! | `optimizer.decay` | `(1/`[`FINAL_LR_DIVISOR`]`)^(1/iterations)`: the last step is 1/20 of the first |
//! | `optimizer.beta1` | [`BETA1`] |
//! | `optimizer.beta2` | [`beta2`]: 0.9 when every parameter is a material value, else 0.999 |
//! | `render.late_samples` | [`late_samples`]: when every parameter is a material value, the second half of the run's gradient passes and matched renders take [`LATE_FACTOR`] times their samples |
//! | `loss.flow` | on when a camera parameter is optimized, or every geometric parameter moves a non-emissive object seen directly (`crate::run`) |
//!
//! The hybrid switch and the matched render's samples are chosen when the
//! run starts (`crate::run`).

use std::fmt;

use crate::params::Target;

/// Adam's β₁ when `optimizer.beta1` is absent: the value the caustic and
/// glass box problems needed (with 0.9 a light or a block that reaches its
/// place at full speed overshoots it and may stop at a bound;
/// `docs/suite.md`); the shipped set over seeds 1–3 is measured with it.
pub const BETA1: f64 = 0.5;

/// Adam's β₂ when `optimizer.beta2` is absent: 0.9 when every parameter is
/// a material value (`material_only`), else 0.999. A material problem runs
/// L2 throughout, whose gradient shrinks with the error; with β₂ 0.999 the
/// second moment keeps the first iterations' large gradients, so the late
/// steps shrink with the error too and the last stretch is crawled
/// (emission-reflected: 0.4 → 0.97 of a true 1.0 in 60 iterations; with
/// 0.9, 0.9996).
pub fn beta2(material_only: bool) -> f64 {
    if material_only { 0.9 } else { 0.999 }
}

/// The first iteration of the late phase, as a fraction of the iterations
/// ([`late_samples`]).
pub const LATE_FROM: f64 = 0.5;

/// How many times its samples the gradient pass and the matched render take
/// in the late phase ([`late_samples`]).
pub const LATE_FACTOR: u32 = 8;

/// A late phase of a run: from iteration `from` on, the gradient pass and
/// the matched render take `factor` times their samples
/// ([`super::Passes::at`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct LateSamples {
    /// The first iteration of the late phase.
    pub from: u32,
    /// The factor on the samples per pixel.
    pub factor: u32,
}

/// The late phase of a run of `iterations` whose parameters are all
/// material values (`material_only`), from [`LATE_FROM`] of the run on with
/// [`LATE_FACTOR`] times the samples; `None` for other runs.
///
/// A material run is L2 throughout, and near the optimum its gradient is
/// the noise of a few bright paths (small lights seen through glossy
/// panels): Adam's normalized steps then scatter θ by a few step lengths
/// per noise spike, and θ ends where the last spikes left it. More samples
/// per pass shrink the spikes once the error is small; the first half,
/// where the gradient's signal exceeds its noise, keeps the cheap passes.
/// Geometric runs are left as they are (their OT phase and switch are
/// tuned to the base samples).
pub fn late_samples(material_only: bool, iterations: u32) -> Option<LateSamples> {
    material_only.then(|| LateSamples {
        from: (f64::from(iterations) * LATE_FROM).round() as u32,
        factor: LATE_FACTOR,
    })
}

/// The first learning rate of a parameter is `CROSSING × scale /
/// iterations`: with the decay to `1 / FINAL_LR_DIVISOR`, the steps of the
/// first third of the run add up to about 0.6 × scale and those of the
/// whole run to about 0.95 × scale (Adam's step is about the learning rate
/// while the gradient's sign holds).
pub const CROSSING: f64 = 3.0;

/// The scale of an unbounded angle (degrees).
pub const ANGLE_SCALE: f64 = 60.0;

/// The scale of an unbounded position as a fraction of the scene's
/// bounding-box diagonal.
pub const POSITION_SCALE: f64 = 0.25;

/// The learning rate decays to `1 / FINAL_LR_DIVISOR` of its first value
/// over the iterations.
pub const FINAL_LR_DIVISOR: f64 = 20.0;

/// One automatic choice: the key, its value and the rule that gave it.
#[derive(Clone, Debug, PartialEq)]
pub struct Choice {
    /// The problem-file key (`optimizer.decay`, `parameters[2].lr`, …).
    pub key: String,
    /// The value, as the file would spell it.
    pub value: String,
    /// Why: the rule and its inputs.
    pub why: String,
}

impl Choice {
    /// A choice of `key`.
    pub fn new(key: impl Into<String>, value: impl Into<String>, why: impl Into<String>) -> Self {
        Self {
            key: key.into(),
            value: value.into(),
            why: why.into(),
        }
    }
}

impl fmt::Display for Choice {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "auto {} = {} ({})", self.key, self.value, self.why)
    }
}

/// What kind of quantity a parameter is, for its step size.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Scale {
    /// A position offset (scene units).
    Position,
    /// An angle (degrees).
    Angle,
    /// A material value, an emission or a scale factor.
    Material,
}

impl Scale {
    /// The kind of `target`.
    pub fn of(target: &Target) -> Self {
        match target {
            Target::Translate { .. }
            | Target::LightTranslate { .. }
            | Target::CameraTranslate { .. } => Scale::Position,
            Target::Rotate { .. } | Target::CameraYaw | Target::CameraPitch => Scale::Angle,
            Target::Scale { .. }
            | Target::Albedo { .. }
            | Target::Alpha { .. }
            | Target::Ior { .. }
            | Target::Emission { .. } => Scale::Material,
        }
    }
}

/// Whether `target` moves geometry (or the camera) rather than changing a
/// material or emission value.
pub fn is_geometric(target: &Target) -> bool {
    !matches!(
        target,
        Target::Albedo { .. } | Target::Alpha { .. } | Target::Ior { .. } | Target::Emission { .. }
    )
}

/// Whether `target` moves the camera.
pub fn is_camera(target: &Target) -> bool {
    matches!(
        target,
        Target::CameraTranslate { .. } | Target::CameraYaw | Target::CameraPitch
    )
}

/// The scale of a parameter of `target` (user units) with explicit
/// `bounds` (if any), starting at `initial`, in a scene whose bounding box
/// has diagonal `diagonal` (scene units), and the rule in words.
pub fn scale(target: &Target, bounds: Option<[f64; 2]>, initial: f64, diagonal: f64) -> Step {
    let step = |scale: f64, why: String| Step { scale, why };
    if let Some([lo, hi]) = bounds {
        return step(hi - lo, format!("the bound width {}", hi - lo));
    }
    let (domain, _) = target.domain();
    match Scale::of(target) {
        Scale::Position => step(
            diagonal * POSITION_SCALE,
            format!("a quarter of the scene's bounding-box diagonal {diagonal:.3}"),
        ),
        Scale::Angle => step(ANGLE_SCALE, "the scale of an unbounded angle".into()),
        Scale::Material if domain[1] <= 1.0 => step(
            domain[1] - domain[0],
            format!("the key's range [{}, {}]", domain[0], domain[1]),
        ),
        Scale::Material => step(
            initial.abs().max(1.0),
            "the value's magnitude (at least 1)".into(),
        ),
    }
}

/// The scale a parameter's automatic learning rate follows.
#[derive(Clone, Debug, PartialEq)]
pub struct Step {
    /// The scale, in the parameter's units.
    pub scale: f64,
    /// Where it comes from.
    pub why: String,
}

impl Step {
    /// The first learning rate (user units per step) of a run of
    /// `iterations`: [`CROSSING`] × scale / iterations.
    pub fn lr(&self, iterations: u32) -> f64 {
        CROSSING * self.scale / f64::from(iterations.max(1))
    }
}

/// The automatic decay per iteration: the learning rate falls to
/// `1 / FINAL_LR_DIVISOR` of its first value over `iterations`.
pub fn decay(iterations: u32) -> f64 {
    FINAL_LR_DIVISOR.powf(-1.0 / f64::from(iterations.max(1)))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn decay_reaches_the_final_fraction_at_the_last_iteration() {
        let d = decay(40);
        assert!((d.powi(40) - 1.0 / FINAL_LR_DIVISOR).abs() < 1e-12);
        assert!(d > 0.9 && d < 1.0);
    }

    #[test]
    fn only_material_runs_get_a_late_phase_with_more_samples() {
        assert_eq!(late_samples(false, 40), None);
        let late = late_samples(true, 40).expect("material run");
        assert_eq!(
            late,
            LateSamples {
                from: 20,
                factor: LATE_FACTOR
            }
        );
        let passes = super::super::Passes {
            spp_primal: 4,
            spp_grad: 4,
            spp_match: Some(128),
            late: Some(late),
        };
        assert_eq!(passes.at(19), passes);
        let later = passes.at(20);
        assert_eq!(
            (later.spp_primal, later.spp_grad, later.spp_match),
            (4, 4 * LATE_FACTOR, Some(128 * LATE_FACTOR))
        );
        assert_eq!(passes.at(39), later);
        // A matched render of 0 (the gradient pass's image) stays 0.
        let own = super::super::Passes {
            spp_match: Some(0),
            ..passes
        }
        .at(30);
        assert_eq!((own.spp_grad, own.spp_match), (4 * LATE_FACTOR, Some(0)));
    }

    #[test]
    fn step_sizes_follow_bounds_then_the_kind_of_quantity() {
        let yaw = Target::CameraYaw;
        let bounded = scale(&yaw, Some([-20.0, 30.0]), 0.0, 5.0);
        assert!(bounded.scale == 50.0 && bounded.why.contains("bound"));
        assert!((bounded.lr(40) - CROSSING * 50.0 / 40.0).abs() < 1e-12);
        assert_eq!(scale(&yaw, None, 0.0, 5.0).scale, ANGLE_SCALE);
        let cam = Target::CameraTranslate { axis: 0 };
        assert_eq!(scale(&cam, None, 0.0, 8.0).scale, 8.0 * POSITION_SCALE);
        assert!(is_camera(&cam) && is_camera(&yaw) && is_geometric(&cam));
        // The steps of the first third cross about 0.6 of the scale.
        let (n, d) = (60, decay(60));
        let third: f64 = (0..n / 3).map(|i| bounded.lr(n) * d.powi(i as i32)).sum();
        assert!((third / bounded.scale - 0.6).abs() < 0.1, "{third}");
    }
}
