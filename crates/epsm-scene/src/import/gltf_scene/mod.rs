//! Whole glTF 2.0 scenes (`.gltf`, `.glb`) as [`SceneParts`]: the default
//! scene's node hierarchy, its first perspective camera, metallic-roughness
//! materials, emissive materials as area lights and `KHR_lights_punctual`
//! point lights. Meshes are read by [`gltf`](super::gltf) (checked accessors)
//! and validated by [`validate`](super::validate); values go through the TOML
//! loader's checks. The full mapping is the table in `docs/interop.md`.
//!
//! | glTF | epsm | rule |
//! |---|---|---|
//! | node with a mesh | one [`Object`] per primitive | named after the node (`node<i>` if unnamed; `<name>_<p>` for meshes of several primitives); `world_from_object` = the node's world matrix |
//! | `NORMAL` absent | flat shading | the geometric normal, as the glTF spec asks |
//! | first node with a perspective camera | camera | `yfov`; resolution from camera `extras.resolution = [w, h]`, else width [`DEFAULT_WIDTH`] and height `width / aspectRatio` (square without it) |
//! | `transmissionFactor ≥ 0.5` | dielectric | `ior` from `KHR_materials_ior` (1.5) |
//! | `metallicFactor ≥ 0.5` | conductor, tint = base colour | `α = roughness²`; smooth below [`SMOOTH_ALPHA`] |
//! | otherwise | diffuse, albedo = base colour | |
//! | `emissiveFactor × emissive_strength` | `Object.emission` (radiance) | when non-zero |
//! | `doubleSided` | `two_sided` | |
//! | point light | point light | `I [W/sr] = color × intensity [cd] / 683` |
//! | textures, animations, skins | skipped with a warning | factors and the rest pose are used |
//!
//! ```toml
//! # a glTF scene loads like a TOML scene: epsm render scene.glb
//! ```

mod material;

use std::collections::{HashMap, HashSet};
use std::path::Path;
use std::sync::Arc;

use glam::{DAffine3, DVec3, Vec3};

pub use material::SMOOTH_ALPHA;

use super::gltf::{File, Placed, open, primitive, walk};
use crate::error::{Error, FieldError, Result};
use crate::fields::Fields;
use crate::fields::Locator;
use crate::load::Loaded;
use crate::load::build::{View, checked_camera};
use epsm_render::camera::Camera;
use epsm_render::lights::{Background, PointLight};
use epsm_render::materials::Material;
use epsm_render::scene::{Mesh, Object, RenderSettings, SceneParts, Surface};

/// Image width when the camera's extras give no resolution, pixels.
pub const DEFAULT_WIDTH: u32 = 512;
/// Luminous efficacy converting candela to W/sr (the SI definition at 555 nm).
pub const LUMENS_PER_WATT: f64 = 683.0;

/// Loads the glTF or GLB scene at `path`.
pub fn load(path: &Path) -> Result<Loaded> {
    from_slice(&crate::input_file::read(path)?, path)
}

/// Builds a scene from the bytes of a glTF or GLB file; `file` names it in
/// errors and its directory resolves external buffers.
pub fn from_slice(bytes: &[u8], file: &Path) -> Result<Loaded> {
    let gltf = open(bytes, file)?;
    let locator = Locator::default();
    let ctx = Fields::new(file, &locator, "");
    let placed = walk(&gltf.doc, file)?;
    let mut importer = Importer {
        ctx: &ctx,
        warnings: Vec::new(),
        materials: Vec::new(),
        emission: Vec::new(),
    };
    for m in gltf.doc.materials() {
        importer.material(&m)?;
    }
    let camera = importer.camera(&placed)?;
    let objects = importer.objects(&gltf, &placed)?;
    let point_lights = importer.lights(&placed)?;
    if gltf.doc.animations().next().is_some() || gltf.doc.skins().next().is_some() {
        importer.warn(
            "animations",
            "animations and skins are skipped: the rest pose is used",
        );
    }
    if objects.is_empty() && point_lights.is_empty() {
        return Err(ctx.err(
            "nodes",
            "scene has nothing to render: no meshes and no lights",
        ));
    }
    Ok(Loaded {
        parts: SceneParts {
            camera,
            materials: importer.materials,
            objects,
            point_lights,
            background: Background::Constant(Vec3::ZERO),
            settings: RenderSettings::default(),
            source: Some(file.to_owned()),
        },
        warnings: importer.warnings,
    })
}

/// The state of one import: materials so far, with the emission each gives
/// its objects, and warnings.
struct Importer<'a> {
    ctx: &'a Fields<'a>,
    warnings: Vec<FieldError>,
    materials: Vec<Material>,
    emission: Vec<Option<Vec3>>,
}

impl Importer<'_> {
    fn warn(&mut self, field: &str, message: &str) {
        self.warnings.push(self.ctx.located(field, message));
    }

    /// The first perspective camera in node order, placed by its node.
    fn camera(&mut self, placed: &[Placed]) -> Result<Camera> {
        let ctx = self.ctx;
        let found = placed.iter().find_map(|p| {
            let c = p.node.camera()?;
            match c.projection() {
                gltf::camera::Projection::Perspective(persp) => Some(Perspective {
                    world: p.world,
                    index: c.index(),
                    yfov: persp.yfov(),
                    aspect: persp.aspect_ratio(),
                    extras: c.extras(),
                }),
                gltf::camera::Projection::Orthographic(_) => None,
            }
        });
        let Some(Perspective {
            world,
            index,
            yfov,
            aspect,
            extras,
        }) = found
        else {
            return Err(ctx.err("cameras", "no node holds a perspective camera"));
        };
        let field = format!("cameras[{index}]");
        let resolution = match extras {
            Some(raw) => {
                serde_json::from_str::<CameraExtras>(raw.get())
                    .map_err(|e| ctx.err(&format!("{field}.extras.resolution"), e.to_string()))?
                    .resolution
            }
            None => None,
        };
        let resolution = match (resolution, aspect) {
            (Some(r), _) => r,
            (None, None) => [DEFAULT_WIDTH; 2],
            (None, Some(aspect)) => {
                let a = ctx.within(
                    &format!("{field}.aspectRatio"),
                    f64::from(aspect),
                    1e-3,
                    1e3,
                    "a value in [1e-3, 1e3]",
                )?;
                [
                    DEFAULT_WIDTH,
                    (f64::from(DEFAULT_WIDTH) / a).round().max(1.0) as u32,
                ]
            }
        };
        let world = DAffine3::from_mat4(world);
        let origin = world.translation;
        let view = View {
            origin,
            target: origin - world.matrix3.z_axis,
            up: world.matrix3.y_axis,
            fov_y: ctx
                .finite(&format!("{field}.yfov"), f64::from(yfov))?
                .to_degrees(),
            resolution,
        };
        checked_camera(&view, &field, ctx)
    }

    /// One object per triangle primitive of every mesh node.
    fn objects(&mut self, gltf: &File, placed: &[Placed]) -> Result<Vec<Object>> {
        let ctx = self.ctx;
        let mut meshes: HashMap<(usize, usize, bool), Arc<Mesh>> = HashMap::new();
        let mut names = HashSet::new();
        let mut objects = Vec::new();
        for p in placed {
            let Some(m) = p.node.mesh() else { continue };
            let node = p.node.index();
            let base = p
                .node
                .name()
                .map_or_else(|| format!("node{node}"), str::to_owned);
            let world_from_object = DAffine3::from_mat4(p.world);
            let mirror = world_from_object.matrix3.determinant() < 0.0;
            let count = m.primitives().len();
            for prim in m.primitives() {
                let field = format!("meshes[{}].primitives[{}]", m.index(), prim.index());
                let key = (m.index(), prim.index(), mirror);
                let mesh = match meshes.get(&key) {
                    Some(mesh) => mesh.clone(),
                    None => {
                        let mesh = Arc::new(self.mesh(&prim, &gltf.buffers, &field, mirror)?);
                        meshes.insert(key, mesh.clone());
                        mesh
                    }
                };
                let material = match prim.material().index() {
                    Some(i) => i as u32,
                    None => self.default_material()?,
                };
                let name = if count == 1 {
                    base.clone()
                } else {
                    format!("{base}_{}", prim.index())
                };
                if !names.insert(name.clone()) {
                    let msg =
                        format!("duplicate object name \"{name}\": parameters bind to node names");
                    return Err(ctx.err(&format!("nodes[{node}].name"), msg));
                }
                objects.push(Object {
                    name,
                    mesh,
                    world_from_object,
                    material,
                    emission: self.emission.get(material as usize).copied().flatten(),
                    surface: Surface::Mesh,
                });
            }
        }
        Ok(objects)
    }

    /// One primitive's object-space mesh, validated; winding reversed under
    /// a mirroring node so front faces stay front faces (glTF §3.7.4).
    fn mesh(
        &self,
        prim: &gltf::Primitive,
        buffers: &[gltf::buffer::Data],
        field: &str,
        mirror: bool,
    ) -> Result<Mesh> {
        let file = self.ctx.file;
        let mut mesh = primitive(prim, buffers).map_err(|msg| FieldError::new(file, field, msg))?;
        if mirror {
            mesh.indices.iter_mut().for_each(|t| t.swap(1, 2));
        }
        super::validate(&mesh, file).map_err(|e| match e {
            Error::Field(mut s) => {
                s.field = format!("{field}.{}", s.field);
                Error::Field(s)
            }
            other => other,
        })?;
        Ok(mesh)
    }

    /// `KHR_lights_punctual` point lights at their nodes' world positions.
    fn lights(&mut self, placed: &[Placed]) -> Result<Vec<PointLight>> {
        let ctx = self.ctx;
        let mut lights = Vec::new();
        let mut names = HashSet::new();
        for p in placed {
            let Some(light) = p.node.light() else {
                continue;
            };
            let field = format!("extensions.KHR_lights_punctual.lights[{}]", light.index());
            if !matches!(light.kind(), gltf::khr_lights_punctual::Kind::Point) {
                let msg = "only point lights are supported (spot and directional are not)";
                return Err(ctx.err(&field, msg));
            }
            if light.range().is_some() {
                self.warn(
                    &format!("{field}.range"),
                    "light range is skipped: lights reach infinitely far",
                );
            }
            let node = p.node.index();
            let name = light
                .name()
                .or(p.node.name())
                .map_or_else(|| format!("light{node}"), str::to_owned);
            let scale = f64::from(light.intensity()) / LUMENS_PER_WATT;
            let intensity = light.color().map(|c| f64::from(c) * scale);
            let intensity = ctx.color(&format!("{field}.intensity"), intensity, f64::INFINITY)?;
            if !names.insert(name.clone()) {
                let msg = format!("duplicate light name \"{name}\"");
                return Err(ctx.err(&format!("{field}.name"), msg));
            }
            let position: DVec3 = DAffine3::from_mat4(p.world).translation;
            lights.push(PointLight {
                name,
                position,
                intensity,
            });
        }
        Ok(lights)
    }
}

/// A perspective camera found on a node.
struct Perspective<'a> {
    world: glam::DMat4,
    index: usize,
    yfov: f32,
    aspect: Option<f32>,
    extras: &'a gltf::json::Extras,
}

/// The camera `extras` this importer reads (other keys are ignored).
#[derive(serde::Deserialize)]
struct CameraExtras {
    /// `[width, height]`, pixels.
    resolution: Option<[u32; 2]>,
}
