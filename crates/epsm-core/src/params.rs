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
//! An object's driven transform is
//! `M(θ) = Tr(t) · P · R_z R_y R_x · S(s) · P⁻¹ · M_file` with `P` the
//! translation to the pivot (default: the centre of the object's world bounds
//! in the file placement; see [`ParamTable::set_pivot`]).
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

/// What one parameter drives.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Target {
    /// Translation of an object along world axis `0..3`.
    Translate {
        /// The object.
        object: ObjectId,
        /// World axis: 0 = x, 1 = y, 2 = z.
        axis: usize,
    },
    /// Rotation of an object about world axis `0..3` through its pivot (degrees).
    Rotate {
        /// The object.
        object: ObjectId,
        /// World axis: 0 = x, 1 = y, 2 = z.
        axis: usize,
    },
    /// Uniform scale of an object about its pivot.
    Scale {
        /// The object.
        object: ObjectId,
    },
    /// Translation of a point light along a world axis.
    LightTranslate {
        /// Index in the scene's point lights.
        light: usize,
        /// World axis.
        axis: usize,
    },
    /// Translation of the camera along a world axis.
    CameraTranslate {
        /// World axis.
        axis: usize,
    },
    /// Camera yaw about world `+y` (degrees).
    CameraYaw,
    /// Camera pitch about the file camera's right axis (degrees).
    CameraPitch,
    /// One channel (0 = r) of a diffuse material's constant albedo.
    Albedo {
        /// The material.
        material: MaterialId,
        /// Channel 0..3.
        channel: usize,
    },
    /// GGX roughness of a rough conductor.
    Alpha {
        /// The material.
        material: MaterialId,
    },
    /// IOR of a dielectric.
    Ior {
        /// The material.
        material: MaterialId,
    },
    /// Scale of an object's emitted radiance.
    Emission {
        /// The object.
        object: ObjectId,
    },
}

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

#[derive(Clone, Debug)]
struct Names {
    objects: Vec<String>,
    lights: Vec<String>,
    materials: Vec<String>,
    object_materials: Vec<MaterialId>,
}

const AXES: [&str; 3] = ["x", "y", "z"];

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
        let target = self.parse(key)?;
        let value = self.default_value(target);
        self.params.push(Param {
            key: key.to_owned(),
            target,
            value,
        });
        Ok(self.params.len() - 1)
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

    fn default_value(&self, target: Target) -> f64 {
        let material = |m: MaterialId| &self.base.materials[m as usize].bsdf;
        match target {
            Target::Scale { .. } | Target::Emission { .. } => 1.0,
            Target::Albedo {
                material: m,
                channel,
            } => match material(m) {
                Bsdf::Diffuse(d) => match &d.albedo {
                    Texture::Constant(c) => f64::from(c[channel]),
                    Texture::Image(_) => 0.0,
                },
                _ => 0.0,
            },
            Target::Alpha { material: m } => match material(m) {
                Bsdf::RoughConductor(r) => f64::from(r.alpha),
                _ => 0.0,
            },
            Target::Ior { material: m } => match material(m) {
                Bsdf::Dielectric(d) => f64::from(d.ior),
                _ => 1.0,
            },
            _ => 0.0,
        }
    }

    fn parse(&self, key: &str) -> Result<Target> {
        let err = |message: &str| Error::Param {
            key: key.to_owned(),
            message: message.to_owned(),
        };
        let (name, field) = FIELDS
            .iter()
            .find_map(|f| {
                key.strip_suffix(f)
                    .and_then(|n| n.strip_suffix('.'))
                    .map(|n| (n, *f))
            })
            .ok_or_else(|| {
                err(&format!(
                    "unknown field; expected one of {}",
                    FIELDS.join(", ")
                ))
            })?;
        let axis = AXES.iter().position(|a| field.ends_with(&format!(".{a}")));
        let channel = ["r", "g", "b"]
            .iter()
            .position(|c| field.ends_with(&format!(".{c}")));
        let find = |list: &[String]| list.iter().position(|n| n == name);
        let object = find(&self.names.objects).map(|i| i as ObjectId);
        let material = object
            .map(|o| self.base_material(o))
            .or_else(|| find(&self.names.materials).map(|i| i as MaterialId));
        let target = match (field.split('.').next(), axis, channel) {
            (Some("translate"), Some(axis), _) if name == "camera" => {
                Target::CameraTranslate { axis }
            }
            (Some("yaw"), ..) if name == "camera" => Target::CameraYaw,
            (Some("pitch"), ..) if name == "camera" => Target::CameraPitch,
            (Some("translate"), Some(axis), _) => match (object, find(&self.names.lights)) {
                (Some(object), _) => Target::Translate { object, axis },
                (None, Some(light)) => Target::LightTranslate { light, axis },
                _ => return Err(err("no object or point light has this name")),
            },
            (Some("rotate"), Some(axis), _) => Target::Rotate {
                object: object.ok_or_else(|| err("no object has this name"))?,
                axis,
            },
            (Some("scale"), ..) => Target::Scale {
                object: object.ok_or_else(|| err("no object has this name"))?,
            },
            (Some("emission"), ..) => Target::Emission {
                object: object.ok_or_else(|| err("no object has this name"))?,
            },
            (Some("albedo"), _, Some(channel)) => Target::Albedo {
                material: material.ok_or_else(|| err("no object or material has this name"))?,
                channel,
            },
            (Some("alpha"), ..) => Target::Alpha {
                material: material.ok_or_else(|| err("no object or material has this name"))?,
            },
            (Some("ior"), ..) => Target::Ior {
                material: material.ok_or_else(|| err("no object or material has this name"))?,
            },
            _ => return Err(err("this field does not apply to this name")),
        };
        Ok(target)
    }

    fn base_material(&self, object: ObjectId) -> MaterialId {
        self.names.object_materials[object as usize]
    }
}

const FIELDS: [&str; 15] = [
    "translate.x",
    "translate.y",
    "translate.z",
    "rotate.x",
    "rotate.y",
    "rotate.z",
    "scale",
    "yaw",
    "pitch",
    "albedo.r",
    "albedo.g",
    "albedo.b",
    "alpha",
    "ior",
    "emission",
];
