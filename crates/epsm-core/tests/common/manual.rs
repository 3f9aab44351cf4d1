//! Hand-built scenes for the closed-form and fold tests: objects made of
//! world-space triangles (identity transforms) or placed exact spheres, and
//! records placed on them.

use std::sync::Arc;

use epsm_render::lights::{Background, PointLight};
use epsm_render::materials::{
    Bsdf, Conductor, Dielectric, Diffuse, Lobe, Material, Texture, VertexKind,
};
use epsm_render::record::{TrianglePoint, VertexRecord};
use epsm_render::scene::{self, Mesh, Object, RenderSettings, SceneParts};
use epsm_render::sphere::local_coords;
use epsm_render::{Camera, Scene};
use glam::{DAffine3, DVec3, Vec3};

/// Materials by vertex role.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Surface {
    Diffuse,
    Mirror,
    Glass(f32),
}

/// Objects of world triangles, optionally with per-vertex normals.
#[derive(Default)]
pub struct Manual {
    pub objects: Vec<Object>,
    pub materials: Vec<Material>,
    pub lights: Vec<PointLight>,
}

impl Manual {
    /// Adds an object; returns its id. Normals are stored as given (the
    /// interpolated normal is normalised after interpolation).
    pub fn object(
        &mut self,
        triangles: &[[DVec3; 3]],
        normals: Option<&[[DVec3; 3]]>,
        surface: Surface,
    ) -> u32 {
        let id = self.material(surface);
        let positions = triangles.iter().flatten().map(|p| p.as_vec3()).collect();
        let normals = normals.map_or(Vec::new(), |n| {
            n.iter().flatten().map(|v| v.as_vec3()).collect()
        });
        let indices = (0..triangles.len() as u32)
            .map(|t| [3 * t, 3 * t + 1, 3 * t + 2])
            .collect();
        self.objects.push(Object {
            name: format!("o{id}"),
            mesh: Arc::new(Mesh {
                positions,
                normals,
                uvs: Vec::new(),
                indices,
            }),
            world_from_object: DAffine3::IDENTITY,
            material: id,
            emission: None,
            surface: scene::Surface::Mesh,
        });
        id
    }

    /// Adds an exact sphere placed by `world_from_object`; returns its id.
    pub fn sphere(&mut self, world_from_object: DAffine3, surface: Surface) -> u32 {
        let id = self.material(surface);
        self.objects.push(Object {
            name: format!("o{id}"),
            mesh: Arc::new(Mesh::default()),
            world_from_object,
            material: id,
            emission: None,
            surface: scene::Surface::Sphere,
        });
        id
    }

    /// Adds the material of the next object; returns the object's id.
    fn material(&mut self, surface: Surface) -> u32 {
        let id = self.objects.len() as u32;
        let bsdf = match surface {
            Surface::Diffuse => Bsdf::Diffuse(Diffuse {
                albedo: Texture::Constant(Vec3::splat(0.5)),
            }),
            Surface::Mirror => Bsdf::Conductor(Conductor { tint: Vec3::ONE }),
            Surface::Glass(ior) => Bsdf::Dielectric(Dielectric { ior }),
        };
        self.materials.push(Material {
            name: format!("m{id}"),
            bsdf,
            two_sided: true,
        });
        id
    }

    /// Where world point `p` (in the plane of triangle `tri`, or on the
    /// sphere) lies.
    pub fn at(&self, object: u32, tri: u32, p: DVec3) -> TrianglePoint {
        let o = &self.objects[object as usize];
        if o.surface == scene::Surface::Sphere {
            let [b1, b2] = local_coords(o.world_from_object.inverse().transform_point3(p));
            return TrianglePoint {
                object,
                triangle: 0,
                b1: b1 as f32,
                b2: b2 as f32,
            };
        }
        let [a, b, c] = o.mesh.triangle(tri).map(|v| v.as_dvec3());
        let (e1, e2, d) = (b - a, c - a, p - a);
        let (g11, g12, g22) = (e1.dot(e1), e1.dot(e2), e2.dot(e2));
        let det = g11 * g22 - g12 * g12;
        let (r1, r2) = (e1.dot(d), e2.dot(d));
        let b1 = (g22 * r1 - g12 * r2) / det;
        let b2 = (g11 * r2 - g12 * r1) / det;
        TrianglePoint {
            object,
            triangle: tri,
            b1: b1 as f32,
            b2: b2 as f32,
        }
    }

    /// A record vertex at `p` on `object`.
    pub fn vertex(
        &self,
        object: u32,
        tri: u32,
        p: DVec3,
        lobe: Option<Lobe>,
        eta: f32,
    ) -> VertexRecord {
        let kind = match self.materials[object as usize].bsdf {
            Bsdf::Diffuse(_) => VertexKind::Diffuse,
            _ => VertexKind::Specular,
        };
        VertexRecord {
            at: self.at(object, tri, p),
            p: p.as_vec3(),
            ng: Vec3::Z,
            ns: Vec3::Z,
            kind,
            lobe,
            eta,
            m: Vec3::Z,
            throughput: Vec3::ONE,
            contribution: Vec3::ZERO,
        }
    }

    /// The scene seen by `camera`.
    pub fn scene(self, camera: Camera) -> Scene {
        Scene::new(SceneParts {
            camera,
            materials: self.materials,
            objects: self.objects,
            point_lights: self.lights,
            background: Background::Constant(Vec3::ZERO),
            settings: RenderSettings::default(),
            source: None,
        })
        .expect("valid scene")
    }
}

/// A triangle in the plane through `c` spanned by `u`, `v`, with `c` at
/// barycentrics (1/4, 1/4): exact in `f32` when `c`, `u`, `v` and `size` are
/// dyadic.
pub fn quad_triangle(c: DVec3, u: DVec3, v: DVec3, size: f64) -> [DVec3; 3] {
    [
        c - (u + v) * size,
        c + u * 3.0 * size - v * size,
        c - u * size + v * 3.0 * size,
    ]
}
