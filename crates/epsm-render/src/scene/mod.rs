//! The scene model: camera, materials, objects (meshes with transforms),
//! lights, background and render settings, plus the acceleration structure
//! and light tables derived from them.
//!
//! Geometry that is differentiated (transforms, light positions, the camera)
//! is stored in `f64`; render-time structures derived from it are `f32`.
//! Moving one object with [`Scene::set_object_transform`] refits only the top
//! level of the BVH and that object's emitter table.

pub mod mesh;

use std::path::PathBuf;
use std::sync::Arc;

use glam::{DAffine3, DVec3, Vec3};

pub use mesh::Mesh;

use crate::bvh::Accel;
use crate::camera::Camera;
use crate::error::Error;
use crate::lights::{Background, LightTable, PointLight};
use crate::materials::Material;

/// Index of a material in [`Scene::materials`].
pub type MaterialId = u32;
/// Index of an object in [`Scene::objects`].
pub type ObjectId = u32;

/// What an object's surface is, in object space.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Surface {
    /// The triangles of [`Object::mesh`].
    #[default]
    Mesh,
    /// The exact unit sphere at the origin (outward normals), intersected
    /// analytically ([`crate::sphere`]); the object's mesh is empty. Never an
    /// emitter: [`Scene::new`] refuses an emissive one.
    Sphere,
}

/// One object: a surface (a mesh or an exact sphere) placed in the world
/// with a material, optionally emissive (an area light).
#[derive(Clone, Debug)]
pub struct Object {
    /// Unique name; parameters bind to it (`"<name>.<field>"`).
    pub name: String,
    /// The mesh, object space (empty for [`Surface::Sphere`]).
    pub mesh: Arc<Mesh>,
    /// Object → world transform (any invertible affine map).
    pub world_from_object: DAffine3,
    /// The material.
    pub material: MaterialId,
    /// Emitted radiance from the front face (the side of the geometric normal);
    /// `None` for non-emitters.
    pub emission: Option<Vec3>,
    /// The mesh's triangles, or the exact unit sphere.
    pub surface: Surface,
}

/// Render settings.
///
/// | key | unit | default | range |
/// |---|---|---|---|
/// | `spp` | samples per pixel | 16 | ≥ 1 |
/// | `max_depth` | scatterings per path (the vertex the last one reaches still adds its emission) | 8 | ≥ 1 |
/// | `rr_depth` | depth from which Russian roulette runs | 3 | ≥ 1 |
/// | `seed` | — | 0 | any `u64`... stored as `u32` |
/// | `manifold_nee` | next-event connections through glass to area lights (`tracer` module `chain`), where the scene has both | true | bool |
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct RenderSettings {
    /// Samples per pixel.
    pub spp: u32,
    /// Maximum number of scatterings on a path (the vertex the last one
    /// reaches still adds its emission, or the background).
    pub max_depth: u32,
    /// Depth at which Russian roulette starts.
    pub rr_depth: u32,
    /// Seed of the random streams.
    pub seed: u32,
    /// Whether non-delta vertices connect to area lights through dielectric
    /// refractions (manifold next-event estimation), in scenes that have
    /// both ([`Scene::chains_to_lights`]).
    pub manifold_nee: bool,
}

impl Default for RenderSettings {
    fn default() -> Self {
        Self {
            spp: 16,
            max_depth: 8,
            rr_depth: 3,
            seed: 0,
            manifold_nee: true,
        }
    }
}

/// Everything a scene is made of, before derived structures are built.
#[derive(Clone, Debug)]
pub struct SceneParts {
    /// The camera.
    pub camera: Camera,
    /// Materials; objects refer to them by index.
    pub materials: Vec<Material>,
    /// Objects.
    pub objects: Vec<Object>,
    /// Point lights.
    pub point_lights: Vec<PointLight>,
    /// What rays that leave the scene see.
    pub background: Background,
    /// Render settings.
    pub settings: RenderSettings,
    /// The file the scene came from (for messages), if any.
    pub source: Option<PathBuf>,
}

/// A scene ready to render: its parts plus the BVH and the light tables.
#[derive(Clone, Debug)]
pub struct Scene {
    parts: SceneParts,
    accel: Accel,
    lights: LightTable,
    /// Whether some object is a dielectric and some object emits.
    glass_and_area_lights: bool,
}

impl Scene {
    /// Builds the BVHs and light tables. Fails with [`Error::Invalid`] on an
    /// emissive exact sphere ([`Surface::Sphere`] is never an emitter).
    pub fn new(parts: SceneParts) -> crate::error::Result<Self> {
        if let Some(o) = parts
            .objects
            .iter()
            .find(|o| o.surface == Surface::Sphere && o.emission.is_some())
        {
            return Err(Error::Invalid(format!(
                "object \"{}\": an exact sphere cannot emit (use a tessellated sphere)",
                o.name
            )));
        }
        let accel = Accel::build(&parts.objects);
        let lights = LightTable::build(
            &parts.objects,
            &parts.point_lights,
            &parts.background,
            accel.world_bounds(),
        );
        let glass = parts.objects.iter().any(|o| {
            parts
                .materials
                .get(o.material as usize)
                .is_some_and(|m| matches!(m.bsdf, crate::materials::Bsdf::Dielectric(_)))
        });
        let glass_and_area_lights = glass && parts.objects.iter().any(|o| o.emission.is_some());
        Ok(Self {
            parts,
            accel,
            lights,
            glass_and_area_lights,
        })
    }

    /// Whether the tracer makes manifold next-event connections through
    /// glass: the setting is on and the scene has a dielectric object and an
    /// emissive one. The wide tracer has no such connections, so these
    /// scenes render with the scalar loop.
    pub fn chains_to_lights(&self) -> bool {
        self.parts.settings.manifold_nee && self.glass_and_area_lights
    }

    /// The camera.
    pub fn camera(&self) -> &Camera {
        &self.parts.camera
    }
    /// Replaces the camera.
    pub fn set_camera(&mut self, camera: Camera) {
        self.parts.camera = camera;
    }
    /// The materials.
    pub fn materials(&self) -> &[Material] {
        &self.parts.materials
    }
    /// Mutable materials (colour parameters change them in place).
    pub fn materials_mut(&mut self) -> &mut [Material] {
        &mut self.parts.materials
    }
    /// The objects.
    pub fn objects(&self) -> &[Object] {
        &self.parts.objects
    }
    /// The point lights.
    pub fn point_lights(&self) -> &[PointLight] {
        &self.parts.point_lights
    }
    /// The background.
    pub fn background(&self) -> &Background {
        &self.parts.background
    }
    /// Render settings.
    pub fn settings(&self) -> &RenderSettings {
        &self.parts.settings
    }
    /// Mutable render settings.
    pub fn settings_mut(&mut self) -> &mut RenderSettings {
        &mut self.parts.settings
    }
    /// The file the scene came from.
    pub fn source(&self) -> Option<&std::path::Path> {
        self.parts.source.as_deref()
    }
    /// The acceleration structure.
    pub fn accel(&self) -> &Accel {
        &self.accel
    }
    /// The light tables (selection and sampling of every emitter).
    pub fn lights(&self) -> &LightTable {
        &self.lights
    }

    /// The index of the object called `name`.
    pub fn object_id(&self, name: &str) -> Option<ObjectId> {
        self.parts
            .objects
            .iter()
            .position(|o| o.name == name)
            .map(|i| i as ObjectId)
    }

    /// Marks objects `ids` as moving: each gets its own instance behind the
    /// BVH's top level, so [`Scene::set_object_transform`] on it rebuilds only
    /// the top level. Call it once before moving objects (an optimiser with
    /// its driven objects); without it, the first move of each object
    /// rebuilds the BVH of the static objects once. Rendering gives the same
    /// image either way; static objects are traced faster.
    pub fn set_dynamic(&mut self, ids: &[ObjectId]) {
        self.accel.update_instances(&self.parts.objects, ids);
    }

    /// Moves object `id`: rebuilds the top level of the BVH and the light
    /// table (cheap: proportional to emissive triangles), without rebuilding
    /// any other object's BVH once `id` is dynamic (see
    /// [`Scene::set_dynamic`]).
    pub fn set_object_transform(&mut self, id: ObjectId, world_from_object: DAffine3) {
        self.parts.objects[id as usize].world_from_object = world_from_object;
        self.accel.update_instance(&self.parts.objects, id);
        if self.parts.objects[id as usize].emission.is_some() {
            self.rebuild_lights();
        }
    }

    /// Sets emission radiance of object `id` (rebuilds the light table).
    ///
    /// # Panics
    /// If `id` is out of range, or names an exact sphere and `emission` is
    /// `Some` (exact spheres never emit; [`Scene::new`] refuses them too).
    pub fn set_object_emission(&mut self, id: ObjectId, emission: Option<Vec3>) {
        let object = &mut self.parts.objects[id as usize];
        assert!(
            object.surface == Surface::Mesh || emission.is_none(),
            "object \"{}\": an exact sphere cannot emit",
            object.name
        );
        object.emission = emission;
        self.rebuild_lights();
    }

    /// Moves point light `index` (rebuilds the light table).
    pub fn set_point_light(&mut self, index: usize, light: PointLight) {
        self.parts.point_lights[index] = light;
        self.rebuild_lights();
    }

    /// A world-space bounding sphere radius of the scene's geometry (used for
    /// scene-relative tolerances and environment-light sampling).
    pub fn radius(&self) -> f64 {
        self.accel
            .world_bounds()
            .map(|(lo, hi)| 0.5 * (hi - lo).length())
            .unwrap_or(1.0)
    }

    /// World-space centre of the scene's bounds.
    pub fn center(&self) -> DVec3 {
        self.accel
            .world_bounds()
            .map(|(lo, hi)| 0.5 * (hi + lo))
            .unwrap_or(DVec3::ZERO)
    }

    fn rebuild_lights(&mut self) {
        self.lights = LightTable::build(
            &self.parts.objects,
            &self.parts.point_lights,
            &self.parts.background,
            self.accel.world_bounds(),
        );
    }
}
