//! The random configuration generator: paths shot from a random camera,
//! each vertex on its own one-triangle object (or, with [`Spec::spheres`],
//! its own exact sphere at non-emitting vertices) with a random file
//! transform, directions from the exact reflection / refraction / microfacet
//! laws.

use epsm_core::{ParamTable, PathKind};
use epsm_render::lights::Background;
use epsm_render::materials::{Lobe, VertexKind};
use epsm_render::record::{OccluderRecord, PathRecord};
use epsm_render::scene::{RenderSettings, SceneParts};
use epsm_render::{Camera, Scene};
use glam::{DVec3, Vec3};

use super::builder::{Builder, diffuse};

pub use epsm_testkit::Rng;

/// An S vertex.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Vertex {
    Mirror,
    Glass { ior: f64 },
    Glossy { alpha: f64 },
}

/// How a chain or caustic ends.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum End {
    Surface,
    Emitter,
    AreaNee,
    PointNee,
}

/// What to build.
#[derive(Clone, Debug, PartialEq)]
pub struct Spec {
    pub kind: PathKind,
    pub chain: Vec<Vertex>,
    pub end: End,
    pub scale: f64,
    pub smooth: bool,
    /// Second edge length relative to the first (skinny triangles: tiny).
    pub aspect: f64,
    /// Range of `cos` between `wi` and the geometric normal at S vertices.
    pub cos: (f64, f64),
    /// Force S geometric normals along this axis (sign chosen to face `wi`).
    pub axis: Option<DVec3>,
    /// Range of the angle between the triangle edges at the first vertex, radians.
    pub angle: (f64, f64),
    /// Place exact spheres (non-uniformly scaled: ellipsoids) instead of
    /// triangles at the non-emitting vertices.
    pub spheres: bool,
}

impl Spec {
    pub fn new(kind: PathKind, chain: Vec<Vertex>, end: End) -> Self {
        Self {
            kind,
            chain,
            end,
            scale: 1.0,
            smooth: true,
            aspect: 1.0,
            cos: (0.3, 1.0),
            axis: None,
            angle: (0.3 * std::f64::consts::PI, 0.7 * std::f64::consts::PI),
            spheres: false,
        }
    }
}

/// A built configuration.
pub struct Synth {
    pub scene: Scene,
    pub record: PathRecord,
    pub table: ParamTable,
    pub objects: Vec<String>,
    pub lights: Vec<String>,
}

/// Builds a random configuration; `None` when this draw was unusable.
pub fn build(spec: &Spec, rng: &mut Rng) -> Option<Synth> {
    let s = spec.scale;
    let eye = rng.unit() * 5.0 * s;
    let camera = Camera::look_at(eye, DVec3::ZERO, DVec3::Y, 40.0, 64, 64)?;
    let x1 = rng.unit() * 0.5 * s * rng.f64();
    let mut b = Builder {
        spec,
        rng,
        objects: Vec::new(),
        materials: Vec::new(),
        lights: Vec::new(),
        record: PathRecord::default(),
    };
    let wi = (eye - x1).normalize();
    match spec.kind {
        PathKind::Primary | PathKind::ChainToSurface | PathKind::ChainToLight => {
            b.chain(eye, -wi)?
        }
        PathKind::Caustic | PathKind::Shadow => {
            let ng = b.facing(wi, (0.3, 1.0));
            let (at, ns) = b.surface(x1, ng, diffuse(), false);
            b.push_vertex(
                at,
                x1,
                [ng, ns],
                VertexKind::Diffuse,
                Some(Lobe::DiffuseReflection),
                1.0,
            );
            let w = b.facing(ng, (0.2, 1.0));
            if spec.kind == PathKind::Caustic {
                b.chain(x1, w)?;
            } else {
                // The occluder lies before the nearest possible light point (0.6 s).
                let o = x1 + w * s * 0.6 * b.rng.range(0.3, 0.7);
                let ong = b.facing(w, (0.3, 1.0));
                let (oat, _) = b.surface(o, ong, diffuse(), false);
                b.light(
                    x1,
                    w,
                    0,
                    Some(OccluderRecord {
                        at: oat,
                        p: o.as_vec3(),
                    }),
                )?;
            }
        }
    }
    let film = camera.project(b.record.vertices[0].p.as_dvec3())?;
    b.record.film = film.as_vec2();
    b.record.pixel = film.as_uvec2();
    b.record.radiance = Vec3::ONE;
    let objects = b.objects.iter().map(|o| o.name.clone()).collect();
    let lights = b.lights.iter().map(|l| l.name.clone()).collect();
    let scene = Scene::new(SceneParts {
        camera,
        materials: b.materials,
        objects: b.objects,
        point_lights: b.lights,
        background: Background::Constant(Vec3::ZERO),
        settings: RenderSettings::default(),
        source: None,
    })
    .ok()?;
    let table = ParamTable::new(&scene);
    Some(Synth {
        scene,
        record: b.record,
        table,
        objects,
        lights,
    })
}
