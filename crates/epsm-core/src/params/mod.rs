//! The parameter table: the only way anything names a scene parameter.
//!
//! Keys are `"<name>.<field>"`, `name` an object, a point light, a material or
//! `camera`. Geometric values are offsets from the scene file's placement
//! (θ = 0, or 1 for `scale`); material values are absolute, starting at the
//! file's value.
//!
//! | field | applies to | unit | default | meaning |
//! |---|---|---|---|---|
//! | `translate.x` / `.y` / `.z` | object, point light, camera | scene units | 0 | offset along a world axis |
//! | `rotate.x` / `.y` / `.z` | object | degrees | 0 | rotation about a world axis through the pivot |
//! | `scale` | object | factor | 1 | uniform scale about the pivot |
//! | `yaw` / `pitch` | camera | degrees | 0 | about world `+y` / the file camera's right axis |
//! | `albedo.r` / `.g` / `.b` | object (its material) or material | — | file value | diffuse albedo |
//! | `alpha` | object or material | — | file value | GGX roughness |
//! | `ior` | object or material | — | file value | dielectric IOR |
//! | `emission` | object | factor | 1 | emitted radiance scale |
//!
//! A material or emission key whose material or object has no such value
//! (`alpha` of a diffuse material, `emission` of a non-emissive object) is
//! an [`Error::Param`]: it would drive nothing.
//!
//! An object's driven transform is
//! `M(θ) = Tr(t) · P · R_z R_y R_x · S(s) · P⁻¹ · M_file` with `P` the
//! translation to the pivot (default: the centre of the object's world bounds
//! in the file placement; for an exact sphere, whose mesh is empty, the
//! placement's translation: its centre; see [`ParamTable::set_pivot`]).
//!
//! ```toml
//! [[parameters]]
//! key = "bunny.translate.x"
//! ```

use epsm_render::Scene;
use epsm_render::materials::{Bsdf, Material, Texture};
use epsm_render::scene::{MaterialId, ObjectId};
use glam::{DAffine3, DVec3, Vec3};

use crate::error::{Error, Result};

mod target;

use target::{AXES, Names, parse};
pub use target::{OBJECT_FIELDS, Target};

/// One named parameter and its current value.
#[derive(Clone, Debug, PartialEq)]
pub struct Param {
    /// The key, `"<name>.<field>"`.
    pub key: String,
    /// What it drives.
    pub target: Target,
    /// Current value in user units.
    pub value: f64,
}

/// The scene as the file placed it: what parameter values are offsets from.
#[derive(Clone, Debug)]
pub(crate) struct Base {
    pub(crate) objects: Vec<DAffine3>,
    pub(crate) pivots: Vec<DVec3>,
    pub(crate) lights: Vec<DVec3>,
    pub(crate) camera: epsm_render::Camera,
    pub(crate) materials: Vec<Material>,
    pub(crate) emission: Vec<Option<Vec3>>,
}

/// The named parameters of a scene, their values, and the file placement
/// they are offsets from.
#[derive(Clone, Debug)]
pub struct ParamTable {
    params: Vec<Param>,
    pub(crate) base: Base,
    names: Names,
}

impl ParamTable {
    /// An empty table over `scene`, whose current state becomes the file
    /// placement (θ = 0).
    pub fn new(scene: &Scene) -> Self {
        let objects = scene.objects();
        let pivots = objects
            .iter()
            .map(|o| {
                let (lo, hi) = o.mesh.positions.iter().fold(
                    (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
                    |(lo, hi), p| {
                        let w = o.world_from_object.transform_point3(p.as_dvec3());
                        (lo.min(w), hi.max(w))
                    },
                );
                if lo.is_finite() && hi.is_finite() {
                    0.5 * (lo + hi)
                } else {
                    o.world_from_object.translation
                }
            })
            .collect();
        Self {
            params: Vec::new(),
            base: Base {
                objects: objects.iter().map(|o| o.world_from_object).collect(),
                pivots,
                lights: scene.point_lights().iter().map(|l| l.position).collect(),
                camera: scene.camera().clone(),
                materials: scene.materials().to_vec(),
                emission: objects.iter().map(|o| o.emission).collect(),
            },
            names: Names {
                objects: objects.iter().map(|o| o.name.clone()).collect(),
                lights: scene
                    .point_lights()
                    .iter()
                    .map(|l| l.name.clone())
                    .collect(),
                materials: scene.materials().iter().map(|m| m.name.clone()).collect(),
                object_materials: objects.iter().map(|o| o.material).collect(),
            },
        }
    }

    /// Adds the parameter `key` at its default value and returns its index.
    pub fn add(&mut self, key: &str) -> Result<usize> {
        if self.index(key).is_some() {
            return Err(Error::Duplicate(key.to_owned()));
        }
        let param = self.resolve(key)?;
        self.params.push(param);
        Ok(self.params.len() - 1)
    }

    /// The parameter `key` at its default value, without adding it: fails
    /// as [`ParamTable::add`] does on a key that does not fit the scene
    /// (but not on one already in the table).
    pub fn resolve(&self, key: &str) -> Result<Param> {
        let target = parse(&self.names, key)?;
        let value = self.default_value(target).map_err(|message| Error::Param {
            key: key.to_owned(),
            message,
        })?;
        Ok(Param {
            key: key.to_owned(),
            target,
            value,
        })
    }

    /// Adds the default set: translation x/y/z of every object and point
    /// light, and the camera position.
    pub fn add_default_geometry(&mut self) -> Result<()> {
        let names: Vec<String> = self
            .names
            .objects
            .iter()
            .chain(&self.names.lights)
            .cloned()
            .collect();
        for name in names.iter().map(String::as_str).chain(["camera"]) {
            for axis in AXES {
                self.add(&format!("{name}.translate.{axis}"))?;
            }
        }
        Ok(())
    }

    /// The index of `key`.
    pub fn index(&self, key: &str) -> Option<usize> {
        self.params.iter().position(|p| p.key == key)
    }

    /// The parameters, in index order.
    pub fn params(&self) -> &[Param] {
        &self.params
    }

    /// Number of parameters.
    pub fn len(&self) -> usize {
        self.params.len()
    }

    /// Whether the table is empty.
    pub fn is_empty(&self) -> bool {
        self.params.is_empty()
    }

    /// The current values, in index order.
    pub fn values(&self) -> Vec<f64> {
        self.params.iter().map(|p| p.value).collect()
    }

    /// Sets the value of parameter `index` (ignored when out of range).
    pub fn set_value(&mut self, index: usize, value: f64) {
        if let Some(p) = self.params.get_mut(index) {
            p.value = value;
        }
    }

    /// Sets the world-space pivot of object `object`'s rotation and scale.
    pub fn set_pivot(&mut self, object: ObjectId, pivot: DVec3) {
        if let Some(p) = self.base.pivots.get_mut(object as usize) {
            *p = pivot;
        }
    }

    /// The objects some parameter moves (translation, rotation or scale):
    /// the ones [`ParamTable::apply`] sets a transform on.
    pub fn moving_objects(&self) -> Vec<ObjectId> {
        self.motion(&self.values())
            .objects
            .iter()
            .enumerate()
            .filter(|(_, om)| !om.grads.is_empty())
            .map(|(id, _)| id as ObjectId)
            .collect()
    }

    /// Writes the current values into `scene` (transforms, point lights,
    /// camera, materials, emission). `scene` must be the scene the table was
    /// made from.
    pub fn apply(&self, scene: &mut Scene) {
        let motion = self.motion(&self.values());
        for (id, om) in motion.objects.iter().enumerate() {
            if !om.grads.is_empty() {
                scene.set_object_transform(id as ObjectId, om.affine());
            }
        }
        for (i, lm) in motion.lights.iter().enumerate() {
            if !lm.grads.is_empty() {
                let mut light = scene.point_lights()[i].clone();
                light.position = lm.position;
                scene.set_point_light(i, light);
            }
        }
        if !motion.camera.grads.is_empty() {
            scene.set_camera(motion.camera.pose.to_camera(&self.base.camera));
        }
        self.apply_colour(scene);
    }

    fn apply_colour(&self, scene: &mut Scene) {
        for p in &self.params {
            let v = p.value as f32;
            match p.target {
                Target::Albedo { material, channel } => {
                    if let Bsdf::Diffuse(d) = &mut scene.materials_mut()[material as usize].bsdf
                        && let Texture::Constant(c) = &mut d.albedo
                    {
                        c[channel] = v;
                    }
                }
                Target::Alpha { material } => {
                    if let Bsdf::RoughConductor(r) =
                        &mut scene.materials_mut()[material as usize].bsdf
                    {
                        r.alpha = v;
                    }
                }
                Target::Ior { material } => {
                    if let Bsdf::Dielectric(d) = &mut scene.materials_mut()[material as usize].bsdf
                    {
                        d.ior = v;
                    }
                }
                Target::Emission { object } => {
                    let e = self.base.emission[object as usize].map(|e| e * v);
                    scene.set_object_emission(object, e);
                }
                _ => {}
            }
        }
    }

    /// The value `target` starts at: the file's value, or the identity of
    /// an offset or factor. A material or emission target that the scene
    /// gives no such value (roughness of a diffuse material, emission of an
    /// object that emits nothing) is an error, since the parameter would
    /// drive nothing.
    fn default_value(&self, target: Target) -> std::result::Result<f64, String> {
        let material = |m: MaterialId| &self.base.materials[m as usize];
        let mismatch = |m: MaterialId, what: &str| {
            format!(
                "material `{}` is not {what}, so this parameter would change nothing",
                material(m).name
            )
        };
        match target {
            Target::Scale { .. } => Ok(1.0),
            Target::Emission { object } => match self.base.emission[object as usize] {
                Some(_) => Ok(1.0),
                None => Err(format!(
                    "object `{}` is not emissive, so this parameter would change nothing",
                    self.names.objects[object as usize]
                )),
            },
            Target::Albedo {
                material: m,
                channel,
            } => match &material(m).bsdf {
                Bsdf::Diffuse(d) => match &d.albedo {
                    Texture::Constant(c) => Ok(f64::from(c[channel])),
                    Texture::Image(_) => Err(mismatch(m, "diffuse with a constant albedo")),
                },
                _ => Err(mismatch(m, "diffuse with a constant albedo")),
            },
            Target::Alpha { material: m } => match &material(m).bsdf {
                Bsdf::RoughConductor(r) => Ok(f64::from(r.alpha)),
                _ => Err(mismatch(m, "a rough conductor")),
            },
            Target::Ior { material: m } => match &material(m).bsdf {
                Bsdf::Dielectric(d) => Ok(f64::from(d.ior)),
                _ => Err(mismatch(m, "a dielectric")),
            },
            _ => Ok(0.0),
        }
    }
}

#[cfg(test)]
mod tests;
