//! Parameter keys: what each `"<name>.<field>"` drives, and how a key is
//! resolved against the scene's objects, point lights and materials.

use std::borrow::Cow;

use epsm_render::scene::{MaterialId, ObjectId};
use epsm_scene::fields::MIN_ALPHA;

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

impl Target {
    /// The values a parameter of this target may take, `[lo, hi]`, and the
    /// range in words: material values and factors keep the scene valid,
    /// offsets and angles stay finite in the renderer's `f32`.
    pub fn domain(&self) -> ([f64; 2], Cow<'static, str>) {
        let max = f64::from(f32::MAX);
        let positive = f64::from(f32::MIN_POSITIVE);
        let (domain, words) = match self {
            Target::Albedo { .. } => ([0.0, 1.0], "an albedo in [0, 1]"),
            Target::Alpha { .. } => {
                let words = format!("a GGX roughness in [{MIN_ALPHA:e}, 1]");
                return ([MIN_ALPHA, 1.0], Cow::Owned(words));
            }
            Target::Ior { .. } => ([positive, max], "an IOR > 0"),
            Target::Scale { .. } => ([positive, max], "a scale factor > 0"),
            Target::Emission { .. } => ([0.0, max], "an emission factor >= 0"),
            Target::Translate { .. }
            | Target::Rotate { .. }
            | Target::LightTranslate { .. }
            | Target::CameraTranslate { .. }
            | Target::CameraYaw
            | Target::CameraPitch => ([-max, max], "a magnitude of at most 3.4e38"),
        };
        (domain, Cow::Borrowed(words))
    }

    /// The lowest value the optimizer steps a parameter of this target to,
    /// whatever its lower bound: `1e-3` for an albedo or an emission factor,
    /// else none (`-∞`). Both scale every path term they touch, and their
    /// colour derivative is the term times `∂ ln f/∂θ`: at exactly 0 the
    /// channel carries no radiance, so its derivative vanishes and the
    /// parameter could never leave 0. A step to the floor keeps the
    /// derivative exact (and the error of a true value of 0 at `1e-3`).
    pub fn step_floor(&self) -> f64 {
        match self {
            Target::Albedo { .. } | Target::Emission { .. } => 1e-3,
            _ => f64::NEG_INFINITY,
        }
    }
}

/// The names a key can refer to.
#[derive(Clone, Debug)]
pub(super) struct Names {
    pub(super) objects: Vec<String>,
    pub(super) lights: Vec<String>,
    pub(super) materials: Vec<String>,
    pub(super) object_materials: Vec<MaterialId>,
}

pub(super) const AXES: [&str; 3] = ["x", "y", "z"];

/// Resolves `key` against the scene's names.
pub(super) fn parse(names: &Names, key: &str) -> Result<Target> {
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
    let object = find(&names.objects).map(|i| i as ObjectId);
    let material = object
        .map(|o| names.object_materials[o as usize])
        .or_else(|| find(&names.materials).map(|i| i as MaterialId));
    let target = match (field.split('.').next(), axis, channel) {
        (Some("translate"), Some(axis), _) if name == "camera" => Target::CameraTranslate { axis },
        (Some("yaw"), ..) if name == "camera" => Target::CameraYaw,
        (Some("pitch"), ..) if name == "camera" => Target::CameraPitch,
        (Some("translate"), Some(axis), _) => match (object, find(&names.lights)) {
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

/// The fields that move or shape an object (module table of
/// [`params`](super)).
pub const OBJECT_FIELDS: [&str; 7] = [
    "translate.x",
    "translate.y",
    "translate.z",
    "rotate.x",
    "rotate.y",
    "rotate.z",
    "scale",
];

/// Every field: [`OBJECT_FIELDS`], then the camera's and the materials'.
const FIELDS: [&str; 15] = [
    OBJECT_FIELDS[0],
    OBJECT_FIELDS[1],
    OBJECT_FIELDS[2],
    OBJECT_FIELDS[3],
    OBJECT_FIELDS[4],
    OBJECT_FIELDS[5],
    OBJECT_FIELDS[6],
    "yaw",
    "pitch",
    "albedo.r",
    "albedo.g",
    "albedo.b",
    "alpha",
    "ior",
    "emission",
];
