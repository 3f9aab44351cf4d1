//! Where every object, point light and the camera sits at one parameter
//! vector θ, with the derivatives of those placements with respect to the
//! parameters that drive them (docs/design.md §5.2).
//!
//! A [`Motion`] is computed once per θ (per optimisation iteration, or per
//! Newton probe); per-path work then only looks up the few objects a path
//! touches. Derivatives of the transforms come from forward-mode duals over
//! the single generic placement function, one parameter at a time.

use epsm_render::scene::ObjectId;
use glam::{DAffine3, DMat3, DVec3};
use nalgebra::RealField;
use num_dual::Dual64;

pub(crate) mod place;

use crate::params::{ParamTable, Target};
use crate::pixel::{CameraOffsets, Pose};
use place::{Offsets, place, to_glam};

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

    /// The offsets the parameters `params` apply, each value lifted to `T` by
    /// `lift(param, value)` (duals seed one parameter's derivative).
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

#[cfg(test)]
mod tests;
