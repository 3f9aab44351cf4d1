//! Automatic choices: the value a problem-file key takes when the file
//! leaves it out, and why. Each choice is printed at the start of a run
//! ([`Choice`]) and documented in `docs/problem-format.md`.
//!
//! | key | automatic rule |
//! |---|---|
//! | `parameters[i].lr` | [`STEP_FRACTION`] of the bound width; unbounded: that fraction of the scene's bounding-box diagonal for positions, [`STEP_DEGREES`] for angles, of the key's range for materials |
//! | `optimizer.decay` | `(1/`[`FINAL_LR_DIVISOR`]`)^(1/iterations)`: the last step is 1/20 of the first |
//! | `optimizer.beta1` | [`BETA1`] (a constant measured over the shipped problems) |
//! | `loss.flow` | on when a camera parameter is optimized |
//!
//! The hybrid switch and the matched render's samples are chosen when the
//! run starts (`crate::run`).

use std::fmt;

use crate::params::Target;

/// Adam's β₁ when `optimizer.beta1` is absent. Chosen over the shipped
/// problems on three seeds each: with 0.9 a light or a block that reaches
/// its place at full speed overshoots it and may stop at a bound.
pub const BETA1: f64 = 0.5;

/// The first step of a parameter as a fraction of its scale (bound width,
/// scene diagonal or key range).
pub const STEP_FRACTION: f64 = 1.0 / 25.0;

/// The first step of an unbounded angle (degrees).
pub const STEP_DEGREES: f64 = 2.0;

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

/// The automatic learning rate (user units per step) of a parameter of
/// `target` with explicit `bounds` (if any), starting at `initial`, in a
/// scene whose bounding box has diagonal `diagonal` (scene units), and the
/// rule in words.
///
/// Adam's step is about the learning rate whatever the gradient's size, so
/// the rate is a step length: [`STEP_FRACTION`] of the parameter's scale.
pub fn step_size(
    target: &Target,
    bounds: Option<[f64; 2]>,
    initial: f64,
    diagonal: f64,
) -> (f64, String) {
    if let Some([lo, hi]) = bounds {
        let lr = (hi - lo) * STEP_FRACTION;
        return (
            lr,
            format!(
                "1/{:.0} of the bound width {}",
                1.0 / STEP_FRACTION,
                hi - lo
            ),
        );
    }
    let (domain, _) = target.domain();
    match Scale::of(target) {
        Scale::Position => (
            diagonal * STEP_FRACTION,
            format!(
                "1/{:.0} of the scene's bounding-box diagonal {diagonal:.3}",
                1.0 / STEP_FRACTION
            ),
        ),
        Scale::Angle => (STEP_DEGREES, "degrees per step of an angle".into()),
        Scale::Material if domain[1] <= 1.0 => (
            (domain[1] - domain[0]) * STEP_FRACTION,
            format!(
                "1/{:.0} of the key's range [{}, {}]",
                1.0 / STEP_FRACTION,
                domain[0],
                domain[1]
            ),
        ),
        Scale::Material => (
            initial.abs().max(1.0) * STEP_FRACTION,
            format!(
                "1/{:.0} of the value's magnitude (at least 1)",
                1.0 / STEP_FRACTION
            ),
        ),
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
    fn step_sizes_follow_bounds_then_the_kind_of_quantity() {
        let yaw = Target::CameraYaw;
        let (lr, why) = step_size(&yaw, Some([-20.0, 30.0]), 0.0, 5.0);
        assert!((lr - 50.0 * STEP_FRACTION).abs() < 1e-12 && why.contains("bound"));
        assert_eq!(step_size(&yaw, None, 0.0, 5.0).0, STEP_DEGREES);
        let cam = Target::CameraTranslate { axis: 0 };
        assert!((step_size(&cam, None, 0.0, 5.0).0 - 5.0 * STEP_FRACTION).abs() < 1e-12);
        assert!(is_camera(&cam) && is_camera(&yaw) && is_geometric(&cam));
    }
}
