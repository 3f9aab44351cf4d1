//! Where every object, point light and the camera sits at one parameter
//! vector θ, with the derivatives of those placements with respect to the
//! parameters that drive them (DESIGN §5.2).
//!
//! A [`Motion`] is computed once per θ (per optimisation iteration, or per
//! Newton probe); per-path work then only looks up the few objects a path
//! touches. Derivatives of the transforms come from forward-mode duals over
//! the single generic placement function, one parameter at a time.

use epsm_render::scene::ObjectId;
use glam::{DAffine3, DMat3, DVec3};
use nalgebra::{Matrix3, RealField, Vector3};
use num_dual::Dual64;

use crate::params::{ParamTable, Target};
use crate::pixel::{CameraOffsets, Pose};

/// The derivative of an object's placement with respect to one parameter.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AffineGrad {
    /// Global parameter index.
    pub param: usize,
    /// `∂L/∂θ` of the linear part `L`.
    pub linear: DMat3,
    /// `∂t/∂θ` of the translation.
    pub translation: DVec3,
    /// `∂N/∂θ` of the normal matrix `N = L⁻ᵀ`.
    pub normal: DMat3,
}

/// One object's world-from-object map at θ.
#[derive(Clone, Debug, PartialEq)]
pub struct ObjectMotion {
    /// Linear part `L`.
    pub linear: DMat3,
    /// Translation.
    pub translation: DVec3,
    /// Normal matrix `L⁻ᵀ` (maps object normals to world normals, unnormalised).
    pub normal: DMat3,
    /// Derivatives with respect to the parameters driving the object.
    pub grads: Vec<AffineGrad>,
}

impl ObjectMotion {
    /// The map as an affine transform.
    pub fn affine(&self) -> DAffine3 {
        DAffine3::from_mat3_translation(self.linear, self.translation)
    }
}

/// The derivative of a point's position with respect to one parameter.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PointGrad {
    /// Global parameter index.
    pub param: usize,
    /// `∂x/∂θ`, world space.
    pub dx: DVec3,
}

/// A point light's position at θ.
#[derive(Clone, Debug, PartialEq)]
pub struct LightMotion {
    /// Position, world space.
    pub position: DVec3,
    /// Derivatives with respect to the parameters driving the light.
    pub grads: Vec<PointGrad>,
}

/// The derivative of the camera pose with respect to one parameter.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PoseGrad {
    /// Global parameter index.
    pub param: usize,
    /// Derivative of every pose vector.
    pub pose: Pose<f64>,
}

/// The camera at θ.
#[derive(Clone, Debug, PartialEq)]
pub struct CameraMotion {
    /// Eye and basis.
    pub pose: Pose<f64>,
    /// Derivatives with respect to camera parameters.
    pub grads: Vec<PoseGrad>,
}

/// Every placement of the scene at one θ.
#[derive(Clone, Debug, PartialEq)]
pub struct Motion {
    /// Per object, indexed by [`ObjectId`].
    pub objects: Vec<ObjectMotion>,
    /// Per point light.
    pub lights: Vec<LightMotion>,
    /// The camera.
    pub camera: CameraMotion,
}

impl Motion {
    /// The placement of object `id`.
    pub fn object(&self, id: ObjectId) -> &ObjectMotion {
        &self.objects[id as usize]
    }
}

/// The offsets that drive one object, in one scalar type.
struct Offsets<T> {
    translate: [T; 3],
    rotate_deg: [T; 3],
    scale: T,
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
fn place<T: RealField + Copy>(
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

fn to_glam(m: &Matrix3<f64>) -> DMat3 {
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

impl ParamTable {
    /// The scene's placements at parameter values `values` (in index order;
    /// missing entries count as the parameter's current value).
    pub fn motion(&self, values: &[f64]) -> Motion {
        let value = |i: usize| values.get(i).copied().unwrap_or(self.params()[i].value);
        let n_obj = self.base.objects.len();
        let mut object_params: Vec<Vec<usize>> = vec![Vec::new(); n_obj];
        let mut lights: Vec<LightMotion> = self
            .base
            .lights
            .iter()
            .map(|&position| LightMotion {
                position,
                grads: Vec::new(),
            })
            .collect();
        let mut camera_params = Vec::new();
        for (i, p) in self.params().iter().enumerate() {
            match p.target {
                Target::Translate { object, .. }
                | Target::Rotate { object, .. }
                | Target::Scale { object } => object_params[object as usize].push(i),
                Target::LightTranslate { light, axis } => {
                    let mut dx = DVec3::ZERO;
                    dx[axis] = 1.0;
                    lights[light].position += dx * value(i);
                    lights[light].grads.push(PointGrad { param: i, dx });
                }
                Target::CameraTranslate { .. } | Target::CameraYaw | Target::CameraPitch => {
                    camera_params.push(i)
                }
                _ => {}
            }
        }
        let objects = (0..n_obj)
            .map(|id| self.object_motion(id, &object_params[id], &value))
            .collect();
        let camera = self.camera_motion(&camera_params, &value);
        Motion {
            objects,
            lights,
            camera,
        }
    }

    /// Evaluates `f` on the offsets of `params` lifted to `T` by `lift(param, value)`.
    fn offsets<T: RealField + Copy>(
        &self,
        params: &[usize],
        value: &impl Fn(usize) -> f64,
        lift: impl Fn(usize, f64) -> T,
    ) -> Offsets<T> {
        let mut o = Offsets {
            translate: [T::zero(); 3],
            rotate_deg: [T::zero(); 3],
            scale: T::one(),
        };
        for &i in params {
            let v = lift(i, value(i));
            match self.params()[i].target {
                Target::Translate { axis, .. } | Target::CameraTranslate { axis } => {
                    o.translate[axis] += v
                }
                Target::Rotate { axis, .. } => o.rotate_deg[axis] += v,
                Target::CameraYaw => o.rotate_deg[1] += v,
                Target::CameraPitch => o.rotate_deg[0] += v,
                Target::Scale { .. } => o.scale *= v,
                _ => {}
            }
        }
        o
    }

    fn object_motion(
        &self,
        id: usize,
        params: &[usize],
        value: &impl Fn(usize) -> f64,
    ) -> ObjectMotion {
        let (file, pivot) = (&self.base.objects[id], self.base.pivots[id]);
        let (l, t) = place(file, pivot, &self.offsets(params, value, |_, v| v));
        let linear = to_glam(&l);
        let normal = linear.inverse().transpose();
        let grads = params
            .iter()
            .map(|&k| {
                let o = self.offsets(params, value, |i, v| {
                    Dual64::new(v, if i == k { 1.0 } else { 0.0 })
                });
                let (dl, dt) = place(file, pivot, &o);
                let dlin = to_glam(&dl.map(|x| x.eps));
                AffineGrad {
                    param: k,
                    linear: dlin,
                    translation: DVec3::new(dt[0].eps, dt[1].eps, dt[2].eps),
                    normal: -(normal * dlin.transpose() * normal),
                }
            })
            .collect();
        ObjectMotion {
            linear,
            translation: DVec3::new(t[0], t[1], t[2]),
            normal,
            grads,
        }
    }

    fn camera_motion(&self, params: &[usize], value: &impl Fn(usize) -> f64) -> CameraMotion {
        let base = &self.base.camera;
        let pose = Pose::driven(
            base,
            &CameraOffsets::from(self.offsets(params, value, |_, v| v)),
        );
        let grads = params
            .iter()
            .map(|&k| {
                let o = self.offsets(params, value, |i, v| {
                    Dual64::new(v, if i == k { 1.0 } else { 0.0 })
                });
                PoseGrad {
                    param: k,
                    pose: Pose::driven(base, &CameraOffsets::from(o)).map(|x| x.eps),
                }
            })
            .collect();
        CameraMotion { pose, grads }
    }
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
