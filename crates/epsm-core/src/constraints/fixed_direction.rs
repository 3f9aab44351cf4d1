//! The caustic receiver's constraint (docs/design.md §5.3): `C = [F·wo]_xy − c`.
//!
//! The first diffuse vertex `D` of a caustic path camera → D → S⁺ → L keeps
//! receiving light from the same direction in its own transported frame; `c`
//! is the value at the base configuration. The alternative, "the last chain
//! segment toward the light keeps its world direction" (`segment`, tests
//! only), gives the same `dp/dθ` when the light moves or the receiver
//! translates (a fixed specular chain maps the direction at one end one to
//! one onto the direction at the other), and a different one when the
//! receiver rotates (here the incoming direction turns with the receiver's
//! frame) or the chain itself moves (here the direction arriving at D is
//! kept, there the one leaving L). See `receiver_tests.rs` for the
//! measurement.

use nalgebra::{RealField, Vector3};

use crate::frame::BaseFrame;

fn lift<T: RealField>(c: f64) -> T {
    nalgebra::convert(c)
}

/// `[F(n)·wo]_xy − c`.
pub(crate) fn receiver<T: RealField + Copy>(
    frame: &BaseFrame,
    n: &Vector3<T>,
    wo: &Vector3<T>,
    c: [f64; 2],
) -> [T; 2] {
    let [x, y] = frame.project(n, wo);
    [x - lift::<T>(c[0]), y - lift::<T>(c[1])]
}

/// `[F₀·normalize(b − a)]_xy − c` in the constant world frame `F₀` of the
/// base segment direction: the segment `a → b` keeps its world direction.
#[cfg(test)]
pub(crate) fn segment<T: RealField + Copy>(
    frame: &BaseFrame,
    a: &Vector3<T>,
    b: &Vector3<T>,
    c: [f64; 2],
) -> [T; 2] {
    let n0 = Vector3::new(frame.n0.x, frame.n0.y, frame.n0.z).map(lift::<T>);
    receiver(frame, &n0, &(b - a).normalize(), c)
}
