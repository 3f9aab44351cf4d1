//! The configuration builder: one-triangle objects or exact spheres with
//! random file transforms, and path vertices placed by the exact scattering
//! laws.

use std::sync::Arc;

use epsm_render::frame::basis_f64;
use epsm_render::lights::{LightPoint, PointLight};
use epsm_render::materials::{
    Bsdf, Conductor, Dielectric, Diffuse, Lobe, Material, RoughConductor, Texture, VertexKind,
};
use epsm_render::record::{
    ConnectionRecord, OccluderRecord, PathRecord, TrianglePoint, VertexRecord,
};
use epsm_render::scene::{Mesh, Object, Surface};
use epsm_render::sphere::local_coords;
use glam::{DAffine3, DMat3, DQuat, DVec3, Vec3};

use super::synth::{End, Rng, Spec, Vertex};

pub struct Builder<'a> {
    pub spec: &'a Spec,
    pub rng: &'a mut Rng,
    pub objects: Vec<Object>,
    pub materials: Vec<Material>,
    pub lights: Vec<PointLight>,
    pub record: PathRecord,
}

fn material(bsdf: Bsdf) -> Material {
    Material {
        name: String::new(),
        bsdf,
        two_sided: true,
    }
}

pub fn diffuse() -> Material {
    material(Bsdf::Diffuse(Diffuse {
        albedo: Texture::Constant(Vec3::splat(0.5)),
    }))
}

impl Builder<'_> {
    /// An object through `p` with geometric normal `ng`: an exact sphere with
    /// [`Spec::spheres`] unless it emits, else one triangle. Returns where
    /// `p` lies and its shading normal.
    pub fn surface(
        &mut self,
        p: DVec3,
        ng: DVec3,
        mat: Material,
        emission: bool,
    ) -> (TrianglePoint, DVec3) {
        if self.spec.spheres && !emission {
            self.sphere(p, ng, mat)
        } else {
            self.triangle(p, ng, mat, emission)
        }
    }

    /// An exact sphere through `p` with outward normal `ng`, placed by a
    /// random rotation and per-axis scale `L = R·S` (an ellipsoid): the
    /// object point is `q = normalize(Lᵀ ng)` (where the world normal
    /// `normalize(L⁻ᵀ q)` is `ng`), the translation `p − L q`. The shading
    /// normal is `ng`.
    fn sphere(&mut self, p: DVec3, ng: DVec3, mut mat: Material) -> (TrianglePoint, DVec3) {
        let s = self.spec.scale;
        let rot = DQuat::from_axis_angle(self.rng.unit(), self.rng.range(0.0, 3.0));
        let scale = DVec3::new(
            self.rng.range(0.5, 2.0),
            self.rng.range(0.5, 2.0),
            self.rng.range(0.5, 2.0),
        ) * s;
        let linear = DMat3::from_quat(rot) * DMat3::from_diagonal(scale);
        let q = (linear.transpose() * ng).normalize();
        let m = DAffine3::from_mat3_translation(linear, p - linear * q);
        let [b1, b2] = local_coords(q);
        let id = self.objects.len() as u32;
        mat.name = format!("m{id}");
        self.materials.push(mat);
        self.objects.push(Object {
            name: format!("o{id}"),
            mesh: Arc::new(Mesh::default()),
            world_from_object: m,
            material: id,
            emission: None,
            surface: Surface::Sphere,
        });
        (
            TrianglePoint {
                object: id,
                triangle: 0,
                b1: b1 as f32,
                b2: b2 as f32,
            },
            ng,
        )
    }

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
            surface: Surface::Mesh,
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
    pub fn facing(&mut self, w: DVec3, cos: (f64, f64)) -> DVec3 {
        let c = self.rng.range(cos.0, cos.1);
        let perp = (self.rng.unit() - w * w.dot(self.rng.unit()))
            .cross(w)
            .normalize_or(basis_f64(w).0);
        (w * c + perp * (1.0 - c * c).max(0.0).sqrt()).normalize()
    }

    pub fn push_vertex(
        &mut self,
        at: TrianglePoint,
        p: DVec3,
        [ng, ns]: [DVec3; 2],
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
        let (at, ns) = self.surface(x, ng, material(bsdf), false);
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
        self.push_vertex(at, x, [ng, ns], kind, Some(lobe), eta);
        Some(wo)
    }

    /// The light at the end of direction `w` from vertex `from` (index `vertex`).
    pub fn light(
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
                let (at, _) = self.surface(y, ng, diffuse(), true);
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
            dropped: None,
        });
        Some(())
    }

    /// S chain from `x` along `w`, then its end.
    pub fn chain(&mut self, mut x: DVec3, mut w: DVec3) -> Option<()> {
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
        let (at, ns) = self.surface(x, ng, diffuse(), self.spec.end == End::Emitter);
        self.push_vertex(at, x, [ng, ns], VertexKind::Diffuse, None, 1.0);
        Some(())
    }
}
