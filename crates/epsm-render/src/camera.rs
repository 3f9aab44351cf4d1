//! Perspective pinhole camera: pixel → ray, and world point → pixel with its
//! Jacobian (the projection π of docs/design.md §5.5).
//!
//! | key | unit | default | meaning |
//! |---|---|---|---|
//! | `origin` | scene units | required | eye position |
//! | `target` | scene units | required | a point the camera looks at |
//! | `up` | — | `[0, 1, 0]` | up direction (need not be orthogonal to the view) |
//! | `fov` | degrees | `40` | vertical field of view, in (0, 180) |
//! | `resolution` | pixels | required | `[width, height]` |
//!
//! ```toml
//! [camera]
//! origin = [0, 1, 3.8]
//! target = [0, 1, 0]
//! fov = 40
//! resolution = [128, 128]
//! ```

use glam::{DMat3, DVec2, DVec3, Vec2, Vec3};

use crate::Ray;

/// A perspective camera. Geometry is kept in `f64` (it is differentiated);
/// ray generation uses a cached `f32` basis.
#[derive(Clone, Debug, PartialEq)]
pub struct Camera {
    /// Eye position, world space.
    pub origin: DVec3,
    /// The camera looks along `forward` (unit).
    pub forward: DVec3,
    /// Unit right vector of the image plane.
    pub right: DVec3,
    /// Unit up vector of the image plane (image rows grow *against* it).
    pub up: DVec3,
    /// Vertical field of view, radians.
    pub fov_y: f64,
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
}

impl Camera {
    /// A camera at `origin` looking at `target` with the given `up` hint,
    /// vertical field of view `fov_y_deg` (degrees) and resolution. Returns
    /// `None` when the view direction is zero or parallel to `up`.
    pub fn look_at(
        origin: DVec3,
        target: DVec3,
        up: DVec3,
        fov_y_deg: f64,
        width: u32,
        height: u32,
    ) -> Option<Self> {
        let forward = (target - origin).try_normalize()?;
        let right = forward.cross(up).try_normalize()?;
        let up = right.cross(forward);
        Some(Self {
            origin,
            forward,
            right,
            up,
            fov_y: fov_y_deg.to_radians(),
            width,
            height,
        })
    }

    /// Rebuilds the orthonormal basis from a new forward direction and up
    /// hint (used when orientation parameters change).
    pub fn with_orientation(&self, forward: DVec3, up_hint: DVec3) -> Option<Self> {
        Self::look_at(
            self.origin,
            self.origin + forward,
            up_hint,
            self.fov_y.to_degrees(),
            self.width,
            self.height,
        )
    }

    /// `tan(fov_y / 2)`.
    #[inline]
    fn tan_half(&self) -> f64 {
        (0.5 * self.fov_y).tan()
    }

    /// World-from-camera rotation: columns right, up, forward.
    pub fn world_from_camera(&self) -> DMat3 {
        DMat3::from_cols(self.right, self.up, self.forward)
    }

    /// The primary ray through film position `film` (pixels, see the crate's
    /// image-plane convention). The direction is unit. Tracers making many
    /// rays use [`Camera::film_rays`] once instead.
    #[inline]
    pub fn ray(&self, film: Vec2) -> Ray {
        self.film_rays().ray(film)
    }

    /// The camera's `f32` ray generator (a snapshot: remake it after changing
    /// the camera).
    pub fn film_rays(&self) -> FilmRays {
        let th = self.tan_half() as f32;
        FilmRays {
            origin: self.origin.as_vec3(),
            forward: self.forward.as_vec3(),
            right: self.right.as_vec3(),
            up: self.up.as_vec3(),
            th,
            th_aspect: th * (self.width as f32 / self.height as f32),
            size: Vec2::new(self.width as f32, self.height as f32),
        }
    }

    /// Projects a world point to film coordinates (pixels). Returns `None` for
    /// points at or behind the eye plane.
    pub fn project(&self, p: DVec3) -> Option<DVec2> {
        self.project_with_jacobian(p).map(|(pix, _)| pix)
    }

    /// Projects a world point and returns the 2×3 Jacobian `∂pixel/∂p` as two
    /// rows (`[∂x/∂p, ∂y/∂p]`).
    pub fn project_with_jacobian(&self, p: DVec3) -> Option<(DVec2, [DVec3; 2])> {
        let d = p - self.origin;
        let z = d.dot(self.forward);
        if z <= 0.0 {
            return None;
        }
        let (cx, cy) = (d.dot(self.right), d.dot(self.up));
        let th = self.tan_half();
        let aspect = self.width as f64 / self.height as f64;
        let (w, h) = (self.width as f64, self.height as f64);
        // x_pix = w/2 (1 + cx / (z th aspect)),  y_pix = h/2 (1 − cy / (z th)).
        let kx = 0.5 * w / (th * aspect);
        let ky = 0.5 * h / th;
        let pix = DVec2::new(0.5 * w + kx * cx / z, 0.5 * h - ky * cy / z);
        let jx = (self.right * z - self.forward * cx) * (kx / (z * z));
        let jy = -(self.up * z - self.forward * cy) * (ky / (z * z));
        Some((pix, [jx, jy]))
    }

    /// The cached `f32` eye position.
    #[inline]
    pub fn origin_f32(&self) -> Vec3 {
        self.origin.as_vec3()
    }
}

/// Primary rays of a [`Camera`] in `f32`, with the per-camera constants
/// (basis, `tan(fov_y/2)`, aspect) computed once.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FilmRays {
    origin: Vec3,
    pub(crate) forward: Vec3,
    pub(crate) right: Vec3,
    pub(crate) up: Vec3,
    /// `tan(fov_y / 2)`.
    pub(crate) th: f32,
    /// `tan(fov_y / 2) · width / height`.
    pub(crate) th_aspect: f32,
    /// Image size in pixels.
    pub(crate) size: Vec2,
}

impl FilmRays {
    /// The primary ray through film position `film` (pixels); unit direction.
    #[inline]
    pub fn ray(&self, film: Vec2) -> Ray {
        let sx = (2.0 * film.x / self.size.x - 1.0) * self.th_aspect;
        let sy = (1.0 - 2.0 * film.y / self.size.y) * self.th;
        let dir = self.forward + self.right * sx + self.up * sy;
        Ray::new(self.origin, dir.normalize())
    }

    /// The origin of every primary ray: the camera's position.
    #[inline]
    pub fn origin(&self) -> Vec3 {
        self.origin
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cam() -> Camera {
        Camera::look_at(
            DVec3::new(0.3, 1.0, 4.0),
            DVec3::new(0.0, 0.8, 0.0),
            DVec3::Y,
            40.0,
            160,
            120,
        )
        .expect("valid camera")
    }

    #[test]
    fn projecting_a_ray_point_returns_its_film_position() {
        let c = cam();
        for film in [
            Vec2::new(0.5, 0.5),
            Vec2::new(80.0, 60.0),
            Vec2::new(159.0, 3.0),
            Vec2::new(10.0, 117.5),
        ] {
            let r = c.ray(film);
            let p = r.at(3.7).as_dvec3();
            let back = c.project(p).expect("in front");
            assert!((back - film.as_dvec2()).length() < 1e-3, "{film} -> {back}");
        }
    }

    #[test]
    fn projection_jacobian_matches_central_differences() {
        let c = cam();
        let p = DVec3::new(0.4, 1.3, -0.7);
        let (_, j) = c.project_with_jacobian(p).expect("in front");
        let h = 1e-6;
        for (axis, e) in [DVec3::X, DVec3::Y, DVec3::Z].into_iter().enumerate() {
            let fd = (c.project(p + e * h).expect("front") - c.project(p - e * h).expect("front"))
                / (2.0 * h);
            assert!((fd.x - j[0][axis]).abs() < 1e-5 * (1.0 + fd.x.abs()));
            assert!((fd.y - j[1][axis]).abs() < 1e-5 * (1.0 + fd.y.abs()));
        }
    }

    #[test]
    fn points_behind_the_camera_do_not_project() {
        assert!(cam().project(DVec3::new(0.3, 1.0, 5.0)).is_none());
        assert!(Camera::look_at(DVec3::ZERO, DVec3::Y, DVec3::Y, 40.0, 8, 8).is_none());
    }
}
