//! The scene file format: plain serde structures mirroring the TOML file
//! (documented in full in `docs/scene-format.md`). Every struct rejects
//! unknown keys, so a misspelled key is an error rather than a silent default.
//! Values are checked and turned into a [`SceneParts`](epsm_render::scene::SceneParts) by
//! [`load`](crate::load); problem files may embed or extend these types.
//!
//! | section | required | meaning |
//! |---|---|---|
//! | `[camera]` | yes | pinhole camera |
//! | `[render]` | no | samples, depth, seed |
//! | `[background]` | no | constant colour or environment map |
//! | `[materials.<name>]` | no | named materials |
//! | `[[objects]]` | no | meshes with transforms and materials |
//! | `[[lights]]` | no | point lights |
//!
//! ```toml
//! [camera]
//! origin = [0.0, 1.0, 3.8]
//! target = [0.0, 1.0, 0.0]
//! resolution = [128, 128]
//!
//! [materials.white]
//! type = "diffuse"
//!
//! [[objects]]
//! name = "floor"
//! shape = "rectangle"
//! material = "white"
//! ```

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

/// A whole scene file.
#[derive(Clone, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct SceneDesc {
    /// The camera.
    pub camera: CameraDesc,
    /// Render settings.
    #[serde(default)]
    pub render: RenderDesc,
    /// What rays leaving the scene see; black when absent.
    #[serde(default)]
    pub background: Option<BackgroundDesc>,
    /// Materials by unique name.
    #[serde(default)]
    pub materials: BTreeMap<String, MaterialDesc>,
    /// Objects, in file order.
    #[serde(default)]
    pub objects: Vec<ObjectDesc>,
    /// Point lights, in file order.
    #[serde(default)]
    pub lights: Vec<LightDesc>,
}

/// `[camera]`: a pinhole camera.
#[derive(Clone, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct CameraDesc {
    /// Eye position, world space.
    pub origin: [f64; 3],
    /// A point the camera looks at; must differ from `origin`.
    pub target: [f64; 3],
    /// Up hint, not parallel to the view direction.
    #[serde(default = "default_up")]
    pub up: [f64; 3],
    /// Vertical field of view, degrees, in (0, 180).
    #[serde(default = "default_fov")]
    pub fov: f64,
    /// `[width, height]` in pixels, each in [1, 16384].
    pub resolution: [u32; 2],
}

fn default_up() -> [f64; 3] {
    [0.0, 1.0, 0.0]
}

fn default_fov() -> f64 {
    40.0
}

/// `[render]`: render settings (see [`RenderSettings`](epsm_render::scene::RenderSettings)).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct RenderDesc {
    /// Samples per pixel, ≥ 1.
    pub spp: u32,
    /// Maximum number of scatterings per path, in [1, 1024].
    pub max_depth: u32,
    /// Depth at which Russian roulette starts, ≥ 1.
    pub rr_depth: u32,
    /// Seed of the random streams.
    pub seed: u32,
    /// Next-event connections through glass to area lights (manifold
    /// next-event estimation), where the scene has both.
    pub manifold_nee: bool,
}

impl Default for RenderDesc {
    fn default() -> Self {
        let s = epsm_render::scene::RenderSettings::default();
        Self {
            spp: s.spp,
            max_depth: s.max_depth,
            rr_depth: s.rr_depth,
            seed: s.seed,
            manifold_nee: s.manifold_nee,
        }
    }
}

/// `[background]`: a constant radiance or a lat-long environment map (exactly one).
#[derive(Clone, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct BackgroundDesc {
    /// Constant radiance, linear RGB, each ≥ 0.
    pub color: Option<[f64; 3]>,
    /// Environment map file (`.exr` or `.png`), relative to the scene file.
    pub envmap: Option<String>,
    /// Multiplier on the environment map, ≥ 0 (default 1).
    pub scale: Option<f64>,
    /// Rotation of the environment map about `+y`, degrees (default 0).
    pub rotate: Option<f64>,
}

/// The BSDF model of a material.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum MaterialType {
    /// Lambertian.
    Diffuse,
    /// Smooth conductor (mirror).
    Conductor,
    /// GGX conductor.
    RoughConductor,
    /// Smooth dielectric.
    Dielectric,
}

impl MaterialType {
    /// The name used in files.
    pub fn as_str(self) -> &'static str {
        match self {
            MaterialType::Diffuse => "diffuse",
            MaterialType::Conductor => "conductor",
            MaterialType::RoughConductor => "rough_conductor",
            MaterialType::Dielectric => "dielectric",
        }
    }
}

/// `[materials.<name>]`. Which keys apply depends on `type`; a key that does
/// not apply to the type is an error.
#[derive(Clone, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct MaterialDesc {
    /// The BSDF model.
    #[serde(rename = "type")]
    pub kind: MaterialType,
    /// Diffuse albedo, each in [0, 1] (default 0.5).
    pub albedo: Option<[f64; 3]>,
    /// Diffuse albedo texture (`.png` sRGB or `.exr` linear), instead of `albedo`.
    pub texture: Option<String>,
    /// Conductor reflectance, each in [0, 1] (default 1).
    pub tint: Option<[f64; 3]>,
    /// GGX roughness of a rough conductor, in [1e-4, 1]; required there.
    pub alpha: Option<f64>,
    /// Dielectric index of refraction, > 0 (default 1.5).
    pub ior: Option<f64>,
    /// Whether the back face reflects too (default false; dielectrics are
    /// always two-sided).
    pub two_sided: Option<bool>,
}

/// The built-in shapes (see [`shapes`](crate::shapes)).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Deserialize, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum ShapeKind {
    /// `[-1, 1]²` in `z = 0`, normal `+z`.
    Rectangle,
    /// `[-1, 1]³`, outward normals.
    Cube,
    /// Unit icosphere.
    Sphere,
    /// Unit disk in `z = 0`, normal `+z`.
    Disk,
}

/// A scale: one number for all axes or one per axis.
#[derive(Clone, Copy, Debug, PartialEq, Deserialize, Serialize)]
#[serde(untagged, expecting = "a number or an array [sx, sy, sz]")]
pub enum ScaleDesc {
    /// The same factor on every axis.
    Uniform(f64),
    /// `[sx, sy, sz]`.
    PerAxis([f64; 3]),
}

/// One rotation: `angle` degrees about `axis` (right-hand rule).
#[derive(Clone, Copy, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct RotationDesc {
    /// Rotation axis, non-zero (normalized on load).
    pub axis: [f64; 3],
    /// Angle, degrees.
    pub angle: f64,
}

/// `[[objects]]`: a mesh (built-in shape or file) placed in the world.
#[derive(Clone, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct ObjectDesc {
    /// Unique, non-empty name; parameters bind to it.
    pub name: String,
    /// A built-in shape (exactly one of `shape` and `mesh`).
    pub shape: Option<ShapeKind>,
    /// A mesh file (`.obj`, `.ply`, `.gltf`, `.glb`), relative to the scene file.
    pub mesh: Option<String>,
    /// Sphere: icosphere levels (default 3, ≤ 8); disk: segments (default 64, ≥ 3).
    pub subdivisions: Option<u32>,
    /// Sphere: the exact unit sphere, intersected analytically, instead of
    /// an icosphere (default false; not with `subdivisions`,
    /// `flip_normals` or `emission`).
    #[serde(default)]
    pub exact: bool,
    /// Name of a material in `[materials]`.
    pub material: String,
    /// Radiance emitted from the front face, each ≥ 0; makes the object an area light.
    pub emission: Option<[f64; 3]>,
    /// Reverses winding and normals (default false).
    #[serde(default)]
    pub flip_normals: bool,
    /// Scale, non-zero on every axis (default 1).
    pub scale: Option<ScaleDesc>,
    /// Rotations, applied in list order after the scale.
    #[serde(default)]
    pub rotate: Vec<RotationDesc>,
    /// Translation, applied last (default 0).
    pub translate: Option<[f64; 3]>,
}

/// The kind of a light in `[[lights]]`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum LightType {
    /// Isotropic point light.
    Point,
}

/// `[[lights]]`: a point light (area lights are emissive objects).
#[derive(Clone, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct LightDesc {
    /// The kind of light.
    #[serde(rename = "type")]
    pub kind: LightType,
    /// Unique, non-empty name among lights.
    pub name: String,
    /// Position, world space.
    pub position: [f64; 3],
    /// Radiant intensity, W·sr⁻¹ per channel, each ≥ 0.
    pub intensity: [f64; 3],
}
