//! Shipped scene files for this crate's own unit tests.
//!
//! This crate reads no files: `epsm-scene` loads scenes. A unit test is
//! compiled into a second copy of this crate, whose types differ from those
//! of the copy `epsm-scene` links against, so [`load_scene`] loads a file
//! through `epsm-scene` and carries each part over into this copy's types,
//! field by field (nothing is computed: the scene is the same bit for bit).

use std::path::Path;
use std::sync::Arc;

use epsm_scene::epsm_render as loaded;

use crate::camera::Camera;
use crate::film::Image;
use crate::lights::{Background, EnvMap, PointLight};
use crate::materials::{Bsdf, Conductor, Dielectric, Diffuse, Material, RoughConductor, Texture};
use crate::scene::{Mesh, Object, RenderSettings, Scene, SceneParts, Surface};

/// Loads the scene file at `path` with `epsm-scene` and builds it here.
pub(crate) fn load_scene(path: &Path) -> Result<Scene, String> {
    let parts = epsm_scene::load_parts(path).map_err(|e| e.to_string())?;
    let c = &parts.camera;
    let s = &parts.settings;
    Scene::new(SceneParts {
        camera: Camera {
            origin: c.origin,
            forward: c.forward,
            right: c.right,
            up: c.up,
            fov_y: c.fov_y,
            width: c.width,
            height: c.height,
        },
        materials: parts.materials.iter().map(material).collect(),
        objects: parts.objects.iter().map(object).collect(),
        point_lights: (parts.point_lights.iter())
            .map(|l| PointLight {
                name: l.name.clone(),
                position: l.position,
                intensity: l.intensity,
            })
            .collect(),
        background: match &parts.background {
            loaded::lights::Background::Constant(c) => Background::Constant(*c),
            loaded::lights::Background::EnvMap(map) => Background::EnvMap(Arc::new(EnvMap::new(
                image(map.image()),
                map.scale,
                map.rotate_y,
            ))),
        },
        settings: RenderSettings {
            spp: s.spp,
            max_depth: s.max_depth,
            rr_depth: s.rr_depth,
            seed: s.seed,
        },
        source: parts.source.clone(),
    })
    .map_err(|e| e.to_string())
}

fn image(i: &loaded::Image) -> Image {
    Image {
        width: i.width,
        height: i.height,
        pixels: i.pixels.clone(),
    }
}

fn texture(t: &loaded::materials::Texture) -> Texture {
    match t {
        loaded::materials::Texture::Constant(c) => Texture::Constant(*c),
        loaded::materials::Texture::Image(i) => Texture::Image(Arc::new(image(i))),
    }
}

fn material(m: &loaded::materials::Material) -> Material {
    use loaded::materials::Bsdf as B;
    Material {
        name: m.name.clone(),
        bsdf: match &m.bsdf {
            B::Diffuse(d) => Bsdf::Diffuse(Diffuse {
                albedo: texture(&d.albedo),
            }),
            B::Conductor(c) => Bsdf::Conductor(Conductor { tint: c.tint }),
            B::RoughConductor(c) => Bsdf::RoughConductor(RoughConductor {
                alpha: c.alpha,
                tint: c.tint,
            }),
            B::Dielectric(d) => Bsdf::Dielectric(Dielectric { ior: d.ior }),
        },
        two_sided: m.two_sided,
    }
}

fn object(o: &loaded::scene::Object) -> Object {
    Object {
        name: o.name.clone(),
        mesh: Arc::new(Mesh {
            positions: o.mesh.positions.clone(),
            normals: o.mesh.normals.clone(),
            uvs: o.mesh.uvs.clone(),
            indices: o.mesh.indices.clone(),
        }),
        world_from_object: o.world_from_object,
        material: o.material,
        emission: o.emission,
        surface: match o.surface {
            loaded::scene::Surface::Mesh => Surface::Mesh,
            loaded::scene::Surface::Sphere => Surface::Sphere,
        },
    }
}
