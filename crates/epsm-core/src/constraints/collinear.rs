//! The shadow receiver's constraint (docs/design.md §5.3):
//! `C = [F·(normalize(o − x) − normalize(y − x))]_xy`.
//!
//! A shadow path camera → D ⇢ o ⇢ y keeps `D` on the line from the light
//! point `y` through the occluder point `o` (both fixed points that move
//! rigidly with their objects): the shadow boundary moves as the occluder or
//! the light moves. Zero exactly when the two unit directions agree (the
//! normal component of their difference vanishes with the tangential one on
//! the unit sphere, for directions in the same hemisphere).

use nalgebra::{RealField, Vector3};

use crate::frame::BaseFrame;

/// `[F(n)·(w_o − w_y)]_xy` with `w_o`, `w_y` the unit directions to the
/// occluder and the light.
pub(crate) fn collinear<T: RealField + Copy>(
    frame: &BaseFrame,
    n: &Vector3<T>,
    to_occluder: &Vector3<T>,
    to_light: &Vector3<T>,
) -> [T; 2] {
    frame.project(n, &(to_occluder - to_light))
}
