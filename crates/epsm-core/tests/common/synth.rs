//! The random configuration generator: paths shot from a random camera,
//! each vertex on its own one-triangle object with a random file transform,
//! directions from the exact reflection / refraction / microfacet laws.

use std::sync::Arc;

use epsm_core::{ParamTable, PathKind};
use epsm_render::frame::basis_f64;
use epsm_render::lights::{Background, LightPoint, PointLight};
use epsm_render::materials::{
    Bsdf, Conductor, Dielectric, Diffuse, Lobe, Material, RoughConductor, Texture, VertexKind,
};
use epsm_render::record::{
    ConnectionRecord, OccluderRecord, PathRecord, TrianglePoint, VertexRecord,
};
use epsm_render::scene::{Mesh, Object, RenderSettings, SceneParts};
use epsm_render::{Camera, Scene};
use glam::{DAffine3, DMat3, DQuat, DVec3, Vec3};

/// SplitMix64.
pub struct Rng(pub u64);

impl Rng {
    pub fn u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    pub fn f64(&mut self) -> f64 {
        (self.u64() >> 11) as f64 / (1u64 << 53) as f64
    }
    pub fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.f64()
    }
    pub fn below(&mut self, n: usize) -> usize {
        (self.u64() % n as u64) as usize
    }
    pub fn unit(&mut self) -> DVec3 {
        loop {
            let v = DVec3::new(
                self.range(-1.0, 1.0),
                self.range(-1.0, 1.0),
                self.range(-1.0, 1.0),
            );
            if (0.01..1.0).contains(&v.length_squared()) {
                return v.normalize();
            }
        }
    }
}

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

struct Builder<'a> {
    spec: &'a Spec,
    rng: &'a mut Rng,
    objects: Vec<Object>,
    materials: Vec<Material>,
    lights: Vec<PointLight>,
    record: PathRecord,
}

fn material(bsdf: Bsdf) -> Material {
    Material {
        name: String::new(),
        bsdf,
        two_sided: true,
    }
}

fn diffuse() -> Material {
    material(Bsdf::Diffuse(Diffuse {
        albedo: Texture::Constant(Vec3::splat(0.5)),
    }))
}

impl Builder<'_> {
    /// A one-triangle object through `p` with geometric normal `ng`; returns
    /// where `p` lies and its shading normal.
    fn triangle(
        &mut self,
        p: DVec3,
        ng: DVec3,
        mut mat: Material,
        emission: bool,
    ) -> (TrianglePoint, DVec3) {
        let s = self.spec.scale;
        let (ts, tt) = basis_f64(ng);
        let a = self.rng.range(0.0, std::f64::consts::TAU);
        let beta = self.rng.range(self.spec.angle.0, self.spec.angle.1);
        let size = s * self.rng.range(0.2, 0.6);
        let e1 = (ts * a.cos() + tt * a.sin()) * size;
        let e2 = (ts * (a + beta).cos() + tt * (a + beta).sin()) * size * self.spec.aspect;
        let (b1, b2) = (self.rng.range(0.15, 0.45), self.rng.range(0.15, 0.45));
        let q0 = p - e1 * b1 - e2 * b2;
        let world = [q0, q0 + e1, q0 + e2];
        let rot = DQuat::from_axis_angle(self.rng.unit(), self.rng.range(0.0, 3.0));
        let linear = DMat3::from_quat(rot) * self.rng.range(0.5, 2.0);
        let m = DAffine3::from_mat3_translation(linear, self.rng.unit() * s);
        let obj = m.inverse();
        let normals: Vec<Vec3> = if self.spec.smooth {
            world
                .iter()
                .map(|_| {
                    (linear.transpose() * (ng + self.rng.unit() * 0.25).normalize())
                        .normalize()
                        .as_vec3()
                })
                .collect()
        } else {
            Vec::new()
        };
        let ns = if self.spec.smooth {
            let n = normals[0].as_dvec3() * (1.0 - b1 - b2)
                + normals[1].as_dvec3() * b1
                + normals[2].as_dvec3() * b2;
            (linear.inverse().transpose() * n).normalize()
        } else {
            ng
        };
        let id = self.objects.len() as u32;
        mat.name = format!("m{id}");
        self.materials.push(mat);
        self.objects.push(Object {
            name: format!("o{id}"),
            mesh: Arc::new(Mesh {
                positions: world
                    .iter()
                    .map(|w| obj.transform_point3(*w).as_vec3())
                    .collect(),
                normals,
                uvs: Vec::new(),
                indices: vec![[0, 1, 2]],
            }),
            world_from_object: m,
            material: id,
            emission: emission.then_some(Vec3::ONE),
        });
        (
            TrianglePoint {
                object: id,
                triangle: 0,
                b1: b1 as f32,
                b2: b2 as f32,
            },
            ns,
        )
    }

    /// A normal making cosine in `cos` with `w`.
    fn facing(&mut self, w: DVec3, cos: (f64, f64)) -> DVec3 {
        let c = self.rng.range(cos.0, cos.1);
        let perp = (self.rng.unit() - w * w.dot(self.rng.unit()))
            .cross(w)
            .normalize_or(basis_f64(w).0);
        (w * c + perp * (1.0 - c * c).max(0.0).sqrt()).normalize()
    }

    fn push_vertex(
        &mut self,
        at: TrianglePoint,
        p: DVec3,
        ng: DVec3,
        ns: DVec3,
        kind: VertexKind,
        lobe: Option<Lobe>,
        eta: f64,
    ) {
        self.record.vertices.push(VertexRecord {
            at,
            p: p.as_vec3(),
            ng: ng.as_vec3(),
            ns: ns.as_vec3(),
            kind,
            lobe,
            eta: eta as f32,
            m: ns.as_vec3(),
            throughput: Vec3::ONE,
            contribution: Vec3::splat(0.1),
        });
    }

    /// One S vertex at `x` seen along `wi`; returns the continuation direction.
    fn specular(&mut self, v: Vertex, x: DVec3, wi: DVec3, last_nee: bool) -> Option<DVec3> {
        let ng = match self.spec.axis {
            Some(axis) if axis.dot(wi).abs() > 0.2 => axis * axis.dot(wi).signum(),
            Some(_) => return None,
            None => self.facing(wi, self.spec.cos),
        };
        let (bsdf, kind) = match v {
            Vertex::Mirror => (
                Bsdf::Conductor(Conductor { tint: Vec3::ONE }),
                VertexKind::Specular,
            ),
            Vertex::Glass { ior } => (
                Bsdf::Dielectric(Dielectric { ior: ior as f32 }),
                VertexKind::Specular,
            ),
            Vertex::Glossy { alpha } => (
                Bsdf::RoughConductor(RoughConductor {
                    alpha: alpha as f32,
                    tint: Vec3::ONE,
                }),
                VertexKind::Glossy,
            ),
        };
        let (at, ns) = self.triangle(x, ng, material(bsdf), false);
        let ci = wi.dot(ns);
        if ci.abs() < 1e-6 {
            return None;
        }
        let (wo, lobe, eta) = match v {
            Vertex::Mirror => (ns * 2.0 * ci - wi, Lobe::SpecularReflection, 1.0),
            Vertex::Glass { ior } => {
                let eta = if self.rng.f64() < 0.5 { ior } else { 1.0 / ior };
                let n = ns * ci.signum();
                let c = ci.abs();
                let sin2 = (1.0 - c * c) / (eta * eta);
                if sin2 >= 1.0 {
                    return None;
                }
                (
                    -wi / eta + n * (c / eta - (1.0 - sin2).sqrt()),
                    Lobe::SpecularTransmission,
                    eta,
                )
            }
            Vertex::Glossy { alpha } => {
                let (s, t) = basis_f64(ns);
                let m = (ns
                    + (s * self.rng.range(-1.0, 1.0) + t * self.rng.range(-1.0, 1.0))
                        * alpha.min(0.5))
                .normalize();
                let wo = m * 2.0 * wi.dot(m) - wi;
                if wo.dot(ns) * ci <= 0.0 {
                    return None;
                }
                (wo, Lobe::GlossyReflection, 1.0)
            }
        };
        let wo = if last_nee {
            self.facing(ns * ci.signum(), (0.3, 1.0))
        } else {
            wo
        };
        if wo.dot(ns).abs() < self.spec.cos.0.min(0.05) {
            return None;
        }
        self.push_vertex(at, x, ng, ns, kind, Some(lobe), eta);
        Some(wo)
    }

    /// The light at the end of direction `w` from vertex `from` (index `vertex`).
    fn light(
        &mut self,
        from: DVec3,
        w: DVec3,
        vertex: u32,
        occluder: Option<OccluderRecord>,
    ) -> Option<()> {
        let y = from + w * self.spec.scale * self.rng.range(0.6, 1.8);
        let (light, normal) = match self.spec.end {
            End::PointNee => {
                self.lights.push(PointLight {
                    name: format!("l{}", self.lights.len()),
                    position: y,
                    intensity: Vec3::ONE,
                });
                (
                    LightPoint::Point {
                        index: self.lights.len() as u32 - 1,
                    },
                    Vec3::ZERO,
                )
            }
            _ => {
                let ng = self.facing(-w, (0.3, 1.0));
                let (at, _) = self.triangle(y, ng, diffuse(), true);
                (
                    LightPoint::Area {
                        object: at.object,
                        triangle: 0,
                        b1: at.b1,
                        b2: at.b2,
                    },
                    ng.as_vec3(),
                )
            }
        };
        self.record.connections.push(ConnectionRecord {
            vertex,
            light,
            light_position: y.as_vec3(),
            light_normal: normal,
            contribution: if occluder.is_some() {
                Vec3::ZERO
            } else {
                Vec3::splat(0.2)
            },
            unoccluded: Vec3::splat(0.2),
            occluder,
        });
        Some(())
    }

    /// S chain from `x` along `w`, then its end.
    fn chain(&mut self, mut x: DVec3, mut w: DVec3) -> Option<()> {
        let s = self.spec.scale;
        let nee = matches!(self.spec.end, End::AreaNee | End::PointNee);
        let chain = self.spec.chain.clone();
        for (i, v) in chain.iter().enumerate() {
            x += w * s * self.rng.range(0.6, 1.8);
            w = self.specular(*v, x, -w, nee && i + 1 == chain.len())?;
        }
        if nee {
            return self.light(x, w, self.record.vertices.len() as u32 - 1, None);
        }
        x += w * s * self.rng.range(0.6, 1.8);
        let ng = self.facing(-w, (0.3, 1.0));
        let (at, ns) = self.triangle(x, ng, diffuse(), self.spec.end == End::Emitter);
        self.push_vertex(at, x, ng, ns, VertexKind::Diffuse, None, 1.0);
        Some(())
    }
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
            let (at, ns) = b.triangle(x1, ng, diffuse(), false);
            b.push_vertex(
                at,
                x1,
                ng,
                ns,
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
                let (oat, _) = b.triangle(o, ong, diffuse(), false);
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
