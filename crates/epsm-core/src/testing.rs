//! A small scene shared by unit tests.

use std::sync::Arc;

use epsm_render::lights::{Background, PointLight};
use epsm_render::materials::{Bsdf, Diffuse, Material, Texture};
use epsm_render::scene::{Mesh, Object, RenderSettings, SceneParts, Surface};
use epsm_render::{Camera, Scene};
use glam::{DAffine3, DQuat, DVec3, Vec3};

/// One triangle `box` (diffuse material `paint`, a scaled and rotated file
/// transform), a point light `lamp` and a camera.
pub(crate) fn scene() -> Scene {
    let mesh = Arc::new(Mesh {
        positions: vec![Vec3::ZERO, Vec3::X, Vec3::Y],
        indices: vec![[0, 1, 2]],
        ..Mesh::default()
    });
    let m = DAffine3::from_scale_rotation_translation(
        DVec3::splat(1.5),
        DQuat::from_axis_angle(DVec3::new(1.0, 2.0, 3.0).normalize(), 0.7),
        DVec3::new(0.3, -0.2, 1.0),
    );
    Scene::new(SceneParts {
        camera: Camera::look_at(
            DVec3::new(0.0, 1.0, 4.0),
            DVec3::ZERO,
            DVec3::Y,
            40.0,
            32,
            24,
        )
        .expect("camera"),
        materials: vec![Material {
            name: "paint".into(),
            bsdf: Bsdf::Diffuse(Diffuse {
                albedo: Texture::Constant(Vec3::splat(0.5)),
            }),
            two_sided: false,
        }],
        objects: vec![Object {
            name: "box".into(),
            mesh,
            world_from_object: m,
            material: 0,
            emission: None,
            surface: Surface::Mesh,
        }],
        point_lights: vec![PointLight {
            name: "lamp".into(),
            position: DVec3::ONE,
            intensity: Vec3::ONE,
        }],
        background: Background::Constant(Vec3::ZERO),
        settings: RenderSettings::default(),
        source: None,
    })
    .expect("scene")
}
