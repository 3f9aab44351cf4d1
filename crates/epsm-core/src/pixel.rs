//! The camera projection π in any scalar type, so that one function gives
//! pixels in `f64` and, with dual numbers, `∂π/∂x` and `∂π/∂θ_camera`
//! (docs/design.md §5.5: `dp/dθ = J_π (∂x1/∂u1 · du1/dθ + ∂x1/∂θ) + ∂π/∂θ_cam`).
//!
//! The formula is `epsm_render::Camera::project_with_jacobian`'s:
//! `x_pix = w/2 + k_x (d·right)/(d·forward)`, `y_pix = h/2 − k_y (d·up)/(d·forward)`
//! with `d = x − eye`, `k_x = w / (2 tan(fov/2) aspect)`, `k_y = h / (2 tan(fov/2))`.
//! Camera parameters: translation (world axes), yaw about world `+y`, pitch
//! about the file camera's right axis, applied as `R_y(yaw) · R_right(pitch)`.

use epsm_render::Camera;
use glam::{DVec2, DVec3};
use nalgebra::{RealField, Vector3};

use crate::motion::place::rotation;
use num_dual::Dual64;

/// Camera eye and orthonormal basis in scalar type `T`, with the film
/// constants of the projection.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pose<T: nalgebra::Scalar> {
    /// Eye position, world space.
    pub origin: Vector3<T>,
    /// Right vector.
    pub right: Vector3<T>,
    /// Up vector of the image plane.
    pub up: Vector3<T>,
    /// View direction.
    pub forward: Vector3<T>,
    /// Film constants `[w/2, h/2, k_x, k_y]` (pixels).
    pub film: [f64; 4],
}

/// The camera offsets of a parameter vector, in scalar type `T`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CameraOffsets<T> {
    /// Translation along world x, y, z (scene units).
    pub translate: [T; 3],
    /// Yaw about world `+y`, degrees.
    pub yaw_deg: T,
    /// Pitch about the file camera's right axis, degrees.
    pub pitch_deg: T,
}

fn v3<T: RealField>(v: DVec3) -> Vector3<T> {
    Vector3::new(v.x, v.y, v.z).map(nalgebra::convert)
}

/// A glam vector from an `f64` nalgebra vector.
pub(crate) fn glam3(v: &Vector3<f64>) -> DVec3 {
    DVec3::new(v[0], v[1], v[2])
}

impl<T: RealField + Copy> Pose<T> {
    /// The pose of `base` moved by `o`.
    pub fn driven(base: &Camera, o: &CameraOffsets<T>) -> Self {
        let deg: T = nalgebra::convert(std::f64::consts::PI / 180.0);
        let r = rotation(DVec3::Y, o.yaw_deg * deg) * rotation(base.right, o.pitch_deg * deg);
        let th = (0.5 * base.fov_y).tan();
        let (w, h) = (f64::from(base.width), f64::from(base.height));
        Self {
            origin: v3::<T>(base.origin)
                + Vector3::new(o.translate[0], o.translate[1], o.translate[2]),
            right: r * v3::<T>(base.right),
            up: r * v3::<T>(base.up),
            forward: r * v3::<T>(base.forward),
            film: [0.5 * w, 0.5 * h, 0.5 * w / (th * w / h), 0.5 * h / th],
        }
    }

    /// Film position (pixels) of world point `x`; `None` at or behind the eye plane.
    pub fn project(&self, x: &Vector3<T>) -> Option<[T; 2]> {
        let d = x - self.origin;
        let z = d.dot(&self.forward);
        if z <= T::zero() {
            return None;
        }
        let [cx, cy, kx, ky] = self.film.map(nalgebra::convert::<f64, T>);
        Some([
            cx + kx * d.dot(&self.right) / z,
            cy - ky * d.dot(&self.up) / z,
        ])
    }

    /// Applies `f` to every vector component (film constants kept).
    pub fn map<U: RealField + Copy>(&self, f: impl Fn(T) -> U) -> Pose<U> {
        Pose {
            origin: self.origin.map(&f),
            right: self.right.map(&f),
            up: self.up.map(&f),
            forward: self.forward.map(&f),
            film: self.film,
        }
    }
}

impl Pose<f64> {
    /// The `epsm-render` camera with this pose (fov and resolution of `base`).
    pub fn to_camera(&self, base: &Camera) -> Camera {
        Camera {
            origin: glam3(&self.origin),
            forward: glam3(&self.forward),
            right: glam3(&self.right),
            up: glam3(&self.up),
            ..base.clone()
        }
    }

    /// Film position of `x` (pixels), `None` behind the camera.
    pub fn pixel(&self, x: DVec3) -> Option<DVec2> {
        self.project(&v3(x)).map(|[px, py]| DVec2::new(px, py))
    }

    /// The directional derivative of the film position of `x` when `x` moves
    /// by `dx` and the pose by `dpose` (`None` for a fixed camera).
    pub fn pixel_derivative(
        &self,
        x: DVec3,
        dx: DVec3,
        dpose: Option<&Pose<f64>>,
    ) -> Option<DVec2> {
        let lift = |a: &Vector3<f64>, b: Option<&Vector3<f64>>| {
            Vector3::from_fn(|i, _| Dual64::new(a[i], b.map_or(0.0, |b| b[i])))
        };
        let pose = Pose {
            origin: lift(&self.origin, dpose.map(|p| &p.origin)),
            right: lift(&self.right, dpose.map(|p| &p.right)),
            up: lift(&self.up, dpose.map(|p| &p.up)),
            forward: lift(&self.forward, dpose.map(|p| &p.forward)),
            film: self.film,
        };
        let [px, py] = pose.project(&lift(&v3(x), Some(&v3(dx))))?;
        Some(DVec2::new(px.eps, py.eps))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn projection_and_jacobian_match_the_render_camera() {
        let cam = Camera::look_at(
            DVec3::new(0.3, 1.0, 4.0),
            DVec3::new(0.0, 0.8, 0.0),
            DVec3::Y,
            40.0,
            160,
            120,
        )
        .expect("valid camera");
        let pose = Pose::driven(
            &cam,
            &CameraOffsets {
                translate: [0.0; 3],
                yaw_deg: 0.0,
                pitch_deg: 0.0,
            },
        );
        let x = DVec3::new(0.4, 1.3, -0.7);
        let (pix, j) = cam.project_with_jacobian(x).expect("in front");
        assert!((pose.pixel(x).expect("in front") - pix).length() < 1e-9);
        for (axis, e) in [DVec3::X, DVec3::Y, DVec3::Z].into_iter().enumerate() {
            let d = pose.pixel_derivative(x, e, None).expect("in front");
            assert!((d - DVec2::new(j[0][axis], j[1][axis])).length() < 1e-9 * (1.0 + d.length()));
        }
        assert!(pose.pixel(DVec3::new(0.3, 1.0, 5.0)).is_none());
    }
}
