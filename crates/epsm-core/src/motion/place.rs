//! The driven placement of an object, `M(θ) = Tr(t) · P · R_z R_y R_x ·
//! S(s) · P⁻¹ · M_file`, generic over the scalar so that `f64` gives the
//! placement and dual numbers its exact parameter derivatives.

use glam::{DAffine3, DMat3, DVec3};
use nalgebra::{Matrix3, RealField, Vector3};

use crate::pixel::CameraOffsets;

/// The offsets that drive one object, in one scalar type.
pub(super) struct Offsets<T> {
    pub(super) translate: [T; 3],
    pub(super) rotate_deg: [T; 3],
    pub(super) scale: T,
}

fn c<T: RealField>(x: f64) -> T {
    nalgebra::convert(x)
}

/// The rotation by `angle` (radians) about the unit `axis`, Rodrigues'
/// formula `cos I + sin [k]× + (1 − cos) k kᵀ`. (nalgebra's
/// `Rotation3::from_axis_angle` returns the identity for a zero angle and so
/// loses a dual number's derivative there.)
pub(crate) fn rotation<T: RealField + Copy>(axis: DVec3, angle: T) -> Matrix3<T> {
    let k = na(axis).map(c::<T>);
    let (sin, cos) = (angle.sin(), angle.cos());
    let cross = Matrix3::new(
        T::zero(),
        -k[2],
        k[1],
        k[2],
        T::zero(),
        -k[0],
        -k[1],
        k[0],
        T::zero(),
    );
    Matrix3::identity() * cos + cross * sin + k * k.transpose() * (T::one() - cos)
}

fn na(v: DVec3) -> Vector3<f64> {
    Vector3::new(v.x, v.y, v.z)
}

/// The driven placement `Tr(t) · P · R_z R_y R_x · S(s) · P⁻¹ · M_file`.
pub(super) fn place<T: RealField + Copy>(
    file: &DAffine3,
    pivot: DVec3,
    o: &Offsets<T>,
) -> (Matrix3<T>, Vector3<T>) {
    let deg = c::<T>(std::f64::consts::PI / 180.0);
    let r = rotation(DVec3::Z, o.rotate_deg[2] * deg)
        * rotation(DVec3::Y, o.rotate_deg[1] * deg)
        * rotation(DVec3::X, o.rotate_deg[0] * deg);
    let rs = r * o.scale;
    let m = file.matrix3;
    let file_linear = Matrix3::from_fn(|i, j| c::<T>(m.col(j)[i]));
    let pivot_t = na(pivot).map(c::<T>);
    let offset = na(file.translation - pivot).map(c::<T>);
    let t = Vector3::new(o.translate[0], o.translate[1], o.translate[2]);
    (rs * file_linear, t + pivot_t + rs * offset)
}

pub(super) fn to_glam(m: &Matrix3<f64>) -> DMat3 {
    DMat3::from_cols_array(&[
        m[(0, 0)],
        m[(1, 0)],
        m[(2, 0)],
        m[(0, 1)],
        m[(1, 1)],
        m[(2, 1)],
        m[(0, 2)],
        m[(1, 2)],
        m[(2, 2)],
    ])
}

impl<T> From<Offsets<T>> for CameraOffsets<T> {
    fn from(o: Offsets<T>) -> Self {
        let [pitch, yaw, _] = o.rotate_deg;
        Self {
            translate: o.translate,
            yaw_deg: yaw,
            pitch_deg: pitch,
        }
    }
}
