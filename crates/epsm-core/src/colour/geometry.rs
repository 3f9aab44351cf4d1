//! Colour derivatives of a recorded path for geometric parameters (DESIGN
//! §5.6, the interior term): how the path's radiance changes while its
//! vertices move with θ and visibility stays as recorded.
//!
//! Vertex motion comes from the motion model ([`crate::motion`] through
//! [`Anchor`]): every surface vertex and area-light point keeps its local
//! coordinates on its object (area measure, `x = M(θ)·p_obj`, the shading
//! normal turning with `M`); the camera eye and point lights move with
//! their parameters. The vertex the pixel sees moves in one of two ways
//! ([`PrimaryMotion`]): attached to its object (with the OT loss, whose
//! screen-position gradient `g_xy·dp/dθ` carries its motion across the
//! film), or along the pixel's fixed camera ray (with L2, the conventional
//! renderer's interior term: the pixel keeps looking through the same film
//! point and sees another point of the moving surface).
//!
//! A term of the path (an emission hit by BSDF sampling, a next-event
//! connection, the escaped radiance) is a product of factors over fixed
//! sampling densities (pdfs and MIS weights detached); its derivative is
//! the term times the sum of the factors' `∂ ln/∂θ`:
//!
//! | factor | where | `∂ ln` |
//! |---|---|---|
//! | `f_j(wi, wo)·|cos_j,o|` ([`Material::eval`]) | every non-delta vertex `j` | diffuse: `∂ ln|n·wo|`; glossy: central difference along the motion |
//! | `|cos_{j+1}|/r²` | segment to a BSDF-sampled vertex or an area-light point | `∂ ln|n·w| − 2 ∂ ln r` |
//! | `1/r²` | connection to a point light | `−2 ∂ ln r` |
//! | `s²` (area) | a vertex or light point on an object of scale `s` | `2 ∂s/s` |
//!
//! Camera importance and emitted radiance (Lambertian emitters) are
//! constant; for the escaped radiance the last non-delta vertex's own
//! factor (its escape direction is not recorded) and the background are
//! held fixed. Delta (specular) vertices: with the camera-ray convention the
//! vertex after a mirror or glass interface stays on the scattered ray and
//! the lobe's Fresnel weight changes with `cos θi` ([`chain`]); with the
//! attached convention their motion is the manifold's (carried by `dp/dθ`),
//! so terms past a delta vertex whose neighbourhood moves are left out for
//! that parameter and counted ([`DropReason::NotDifferentiable`]).

use epsm_render::Scene;
use epsm_render::lights::LightPoint;
use epsm_render::materials::{Bsdf, Lobe, Material};
use epsm_render::record::{PathRecord, TrianglePoint, VertexRecord};
use glam::{DVec2, DVec3, Vec2, Vec3};

use crate::drops::{DropCounts, DropReason};
use crate::motion::Motion;
use crate::vertex::Anchor;

use super::chain;

/// How the vertex a pixel sees moves with θ.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PrimaryMotion {
    /// With its object, at fixed local coordinates (its screen motion is
    /// differentiated separately, through `dp/dθ`).
    Attached,
    /// Along the pixel's fixed film position: the conventional renderer's
    /// camera ray.
    OnCameraRay,
}

/// A node's position and normal at θ and their derivatives.
#[derive(Clone, Debug, Default)]
struct Placed {
    x: DVec3,
    /// Unit normal (zero for the camera and point lights).
    n: DVec3,
    /// `(param, ∂x/∂θ, ∂n/∂θ)`.
    grads: Vec<(usize, DVec3, DVec3)>,
    /// `(param, ∂ ln(area)/∂θ)` of the object's area measure.
    area: Vec<(usize, f64)>,
    /// `∂x/∂u`, `∂n/∂u` of a surface point's tangent parameterisation.
    dx_du: [DVec3; 2],
    dn_du: [DVec3; 2],
}

impl Placed {
    fn d(&self, k: usize) -> Moving {
        let (dx, dn) = self
            .grads
            .iter()
            .filter(|g| g.0 == k)
            .fold((DVec3::ZERO, DVec3::ZERO), |a, g| (a.0 + g.1, a.1 + g.2));
        Moving {
            x: self.x,
            dx,
            n: self.n,
            dn,
        }
    }

    /// The gradient entry of parameter `k` after the tangent step `du`.
    fn stepped(&self, k: usize, m: &Moving, du: DVec2) -> (usize, DVec3, DVec3) {
        (
            k,
            m.dx + self.dx_du[0] * du.x + self.dx_du[1] * du.y,
            m.dn + self.dn_du[0] * du.x + self.dn_du[1] * du.y,
        )
    }

    fn area_rate(&self, k: usize) -> f64 {
        self.area.iter().filter(|a| a.0 == k).map(|a| a.1).sum()
    }
}

/// One node moving along one parameter.
#[derive(Clone, Copy, Debug)]
struct Moving {
    x: DVec3,
    dx: DVec3,
    n: DVec3,
    dn: DVec3,
}

impl Moving {
    fn still(&self) -> bool {
        self.dx == DVec3::ZERO && self.dn == DVec3::ZERO
    }
}

/// A unit direction and its derivative.
#[derive(Clone, Copy, Debug)]
struct Dir {
    w: DVec3,
    dw: DVec3,
}

/// The direction from `a` to `b` and the segment's `∂ ln r`.
fn toward(a: &Moving, b: &Moving) -> (Dir, f64) {
    let (d, dd) = (b.x - a.x, b.dx - a.dx);
    let len = d.length();
    let w = d / len;
    (
        Dir {
            w,
            dw: (dd - w * w.dot(dd)) / len,
        },
        w.dot(dd) / len,
    )
}

/// `(cos, ∂cos)` of `n·w`.
fn cos(m: &Moving, w: &Dir) -> (f64, f64) {
    (m.n.dot(w.w), m.dn.dot(w.w) + m.n.dot(w.dw))
}

/// `∂ ln(f(wi, wo)·|cos_o|)` per channel at a non-delta vertex.
fn bsdf_rate(material: &Material, m: &Moving, wi: &Dir, wo: &Dir) -> Vec3 {
    let (co, dco) = cos(m, wo);
    match &material.bsdf {
        Bsdf::RoughConductor(r) => {
            let (ci, dci) = cos(m, wi);
            let (cio, dcio) = (wi.w.dot(wo.w), wi.dw.dot(wo.w) + wi.w.dot(wo.dw));
            let speed = dci.abs().max(dco.abs()).max(dcio.abs());
            if speed == 0.0 {
                return Vec3::ZERO;
            }
            let h = 1e-3 * f64::from(r.alpha).max(1e-2) / speed;
            let at = |t: f64| {
                let [wi_l, wo_l] = local_pair(ci + t * dci, co + t * dco, cio + t * dcio);
                material.eval(wi_l, wo_l, Vec2::ZERO)
            };
            let (p, q) = (at(h), at(-h));
            let ok = p.cmpgt(Vec3::ZERO) & q.cmpgt(Vec3::ZERO);
            let rate = (p.max(Vec3::splat(f32::MIN_POSITIVE)).ln()
                - q.max(Vec3::splat(f32::MIN_POSITIVE)).ln())
                / (2.0 * h as f32);
            Vec3::select(ok, rate, Vec3::ZERO)
        }
        _ => Vec3::splat((dco / co) as f32),
    }
}

/// Local directions with `cos θi = ci`, `cos θo = co` and `wi·wo = cio`
/// (isotropic BSDFs depend on nothing else).
fn local_pair(ci: f64, co: f64, cio: f64) -> [Vec3; 2] {
    let si = (1.0 - ci * ci).max(0.0).sqrt();
    let a = if si > 1e-12 {
        (cio - ci * co) / si
    } else {
        0.0
    };
    let b = (1.0 - co * co - a * a).max(0.0).sqrt();
    [
        DVec3::new(si, 0.0, ci).as_vec3(),
        DVec3::new(a, b, co).as_vec3(),
    ]
}

/// The anchored point `at` with the derivatives of its placement.
fn surface(
    scene: &Scene,
    motion: &Motion,
    at: &TrianglePoint,
    scales: &[(usize, f64)],
) -> Option<Placed> {
    let object = scene.objects().get(at.object as usize)?;
    let om = motion.objects.get(at.object as usize)?;
    let anchor = Anchor::new(
        object,
        at.object,
        at.triangle,
        f64::from(at.b1),
        f64::from(at.b2),
        om,
    )?;
    let vs = anchor.eval(om, [0.0; 2]);
    let grads = om
        .grads
        .iter()
        .map(|g| {
            let [dx, dn] = Anchor::dtheta(&vs, g);
            (g.param, dx, dn)
        })
        .collect();
    let area = om
        .grads
        .iter()
        .filter_map(|g| {
            scales
                .iter()
                .find(|s| s.0 == g.param)
                .map(|s| (g.param, 2.0 / s.1))
        })
        .collect();
    Some(Placed {
        x: vs.x,
        n: vs.n,
        grads,
        area,
        dx_du: vs.dx_du,
        dn_du: vs.dn_du,
    })
}

/// Moves the pixel's vertex `x1` along its camera ray: at each parameter,
/// the tangent step `du` that keeps its film position, `J_π ∂x/∂u du =
/// −dp/dθ`. Fails when the ray grazes the surface.
fn on_camera_ray(x1: &mut Placed, motion: &Motion) -> Result<(), DropReason> {
    let pose = &motion.camera.pose;
    let cols = x1.dx_du.map(|t| pose.pixel_derivative(x1.x, t, None));
    let [Some(c0), Some(c1)] = cols else {
        return Err(DropReason::BehindCamera);
    };
    let det = c0.perp_dot(c1);
    if det.abs() < 1e-9 * c0.length_squared().max(c1.length_squared()) {
        return Err(DropReason::Grazing);
    }
    let mut params: Vec<usize> = x1.grads.iter().map(|g| g.0).collect();
    params.extend(motion.camera.grads.iter().map(|g| g.param));
    let mut grads = Vec::with_capacity(params.len());
    for k in sorted(params) {
        let m = x1.d(k);
        let dpose = motion
            .camera
            .grads
            .iter()
            .find(|g| g.param == k)
            .map(|g| &g.pose);
        let dp = pose
            .pixel_derivative(x1.x, m.dx, dpose)
            .ok_or(DropReason::BehindCamera)?;
        // Solve [c0 c1] du = −dp.
        let du = DVec2::new(-dp.perp_dot(c1), -c0.perp_dot(dp)) / det;
        grads.push(x1.stepped(k, &m, du));
    }
    x1.grads = grads;
    Ok(())
}

/// Moves vertex `next` along the ray a delta vertex `at` (reached from
/// `prev`) scatters toward (see [`chain`]). Fails under total internal
/// reflection or when the ray grazes `next`'s surface.
fn on_scattered_ray(
    next: &mut Placed,
    at: &Placed,
    prev: &Placed,
    eta: f64,
    transmit: bool,
) -> Result<(), DropReason> {
    let params = [prev, at, &*next]
        .iter()
        .flat_map(|p| p.grads.iter().map(|g| g.0))
        .collect();
    let mut grads = Vec::new();
    for k in sorted(params) {
        let (a, b, c) = (prev.d(k), at.d(k), next.d(k));
        let (wi, _) = toward(&b, &a);
        let [r, dr] = chain::scattered(wi.w, wi.dw, b.n, b.dn, eta, transmit)
            .ok_or(DropReason::TotalInternalReflection)?;
        let du = chain::ray_step(c.x - b.x, r, dr, c.dx - b.dx, next.dx_du)
            .ok_or(DropReason::Grazing)?;
        grads.push(next.stepped(k, &c, du));
    }
    next.grads = grads;
    next.area.clear();
    Ok(())
}

fn sorted(mut v: Vec<usize>) -> Vec<usize> {
    v.sort_unstable();
    v.dedup();
    v
}

/// The delta lobe that scattered at `v`, if any.
fn delta_lobe(v: &VertexRecord) -> Option<Lobe> {
    v.lobe.filter(|l| l.is_delta())
}

/// The geometric colour derivatives of one record.
pub(super) struct Geometric<'a> {
    pub(super) scene: &'a Scene,
    pub(super) motion: &'a Motion,
    pub(super) primary: PrimaryMotion,
    /// `(param, scale value)` of every scale parameter.
    pub(super) scales: &'a [(usize, f64)],
}

impl Geometric<'_> {
    /// Whether anything on the record moves (camera, a vertex's object, a
    /// light).
    fn moves(&self, record: &PathRecord) -> bool {
        let driven = |o: u32| {
            self.motion
                .objects
                .get(o as usize)
                .is_some_and(|m| !m.grads.is_empty())
        };
        !self.motion.camera.grads.is_empty()
            || record.vertices.iter().any(|v| driven(v.at.object))
            || record.connections.iter().any(|c| match c.light {
                LightPoint::Area { object, .. } => driven(object),
                LightPoint::Point { index } => self
                    .motion
                    .lights
                    .get(index as usize)
                    .is_some_and(|l| !l.grads.is_empty()),
                LightPoint::Background => false,
            })
    }

    /// The nodes of `record` (camera, vertices) and of its connections'
    /// light points (`None` for the background).
    fn place(&self, record: &PathRecord) -> Result<(Vec<Placed>, Vec<Option<Placed>>), DropReason> {
        let cam = &self.motion.camera;
        let mut nodes = vec![Placed {
            x: crate::pixel::glam3(&cam.pose.origin),
            grads: cam
                .grads
                .iter()
                .map(|g| (g.param, crate::pixel::glam3(&g.pose.origin), DVec3::ZERO))
                .collect(),
            ..Placed::default()
        }];
        let on_rays = self.primary == PrimaryMotion::OnCameraRay;
        for (i, v) in record.vertices.iter().enumerate() {
            let mut p = surface(self.scene, self.motion, &v.at, self.scales)
                .ok_or(DropReason::DegenerateTriangle)?;
            if i == 0 {
                p.area.clear();
                if on_rays {
                    on_camera_ray(&mut p, self.motion)?;
                }
            } else if let (true, Some(lobe)) = (on_rays, delta_lobe(&record.vertices[i - 1])) {
                let eta = f64::from(record.vertices[i - 1].eta);
                on_scattered_ray(
                    &mut p,
                    &nodes[i],
                    &nodes[i - 1],
                    eta,
                    lobe.is_transmission(),
                )?;
            }
            nodes.push(p);
        }
        let mut lights = Vec::with_capacity(record.connections.len());
        for c in &record.connections {
            lights.push(match c.light {
                LightPoint::Area {
                    object,
                    triangle,
                    b1,
                    b2,
                } => Some(
                    surface(
                        self.scene,
                        self.motion,
                        &TrianglePoint {
                            object,
                            triangle,
                            b1,
                            b2,
                        },
                        self.scales,
                    )
                    .ok_or(DropReason::DegenerateTriangle)?,
                ),
                LightPoint::Point { index } => {
                    let l = self
                        .motion
                        .lights
                        .get(index as usize)
                        .ok_or(DropReason::NotDifferentiable)?;
                    Some(Placed {
                        x: l.position,
                        grads: l
                            .grads
                            .iter()
                            .map(|g| (g.param, g.dx, DVec3::ZERO))
                            .collect(),
                        ..Placed::default()
                    })
                }
                LightPoint::Background => None,
            });
        }
        Ok((nodes, lights))
    }

    /// Adds `(param, ∂c/∂θ)` entries of `record` to `out`; counts the terms
    /// left out in `skipped`.
    pub(super) fn gradient(
        &self,
        record: &PathRecord,
        out: &mut Vec<(usize, Vec3)>,
        skipped: &mut DropCounts,
    ) {
        if !self.moves(record) {
            return;
        }
        let (nodes, lights) = match self.place(record) {
            Ok(placed) => placed,
            Err(reason) => {
                skipped.add(reason);
                return;
            }
        };
        let mut params: Vec<usize> = nodes
            .iter()
            .chain(lights.iter().flatten())
            .flat_map(|p| p.grads.iter().map(|g| g.0))
            .collect();
        params.sort_unstable();
        params.dedup();
        for k in params {
            self.one(record, &nodes, &lights, k, out, skipped);
        }
    }

    /// The derivative along parameter `k`.
    fn one(
        &self,
        record: &PathRecord,
        nodes: &[Placed],
        lights: &[Option<Placed>],
        k: usize,
        out: &mut Vec<(usize, Vec3)>,
        skipped: &mut DropCounts,
    ) {
        let v = &record.vertices;
        let m: Vec<Moving> = nodes.iter().map(|p| p.d(k)).collect();
        let material = |i: usize| {
            self.scene
                .objects()
                .get(v[i].at.object as usize)
                .and_then(|o| self.scene.materials().get(o.material as usize))
        };
        let mut sum = Vec3::ZERO;
        // `∂ ln` of the factors before vertex `j`'s own BSDF.
        let mut prefix = Vec3::ZERO;
        let mut valid = true;
        for j in 1..nodes.len() {
            let i = j - 1;
            let conns = || {
                record
                    .connections
                    .iter()
                    .zip(lights)
                    .filter(move |(c, _)| c.vertex as usize == i)
            };
            // Emission hit here.
            let own = v[i].contribution - conns().map(|(c, _)| c.contribution).sum::<Vec3>();
            let Some(mat) = material(i) else {
                skipped.add(DropReason::DegenerateTriangle);
                return;
            };
            let delta = delta_lobe(&v[i]);
            let on_rays = self.primary == PrimaryMotion::OnCameraRay;
            if delta.is_some()
                && !on_rays
                && m[j - 1..nodes.len().min(j + 2)].iter().any(|n| !n.still())
            {
                valid = false;
            }
            if !valid {
                let left = own + conns().map(|(c, _)| c.contribution).sum::<Vec3>();
                if left != Vec3::ZERO || j + 1 < nodes.len() || record.escaped != Vec3::ZERO {
                    skipped.add(DropReason::NotDifferentiable);
                }
                break;
            }
            sum += own * prefix;
            let (wi, _) = toward(&m[j], &m[j - 1]);
            // Next-event connections made here.
            for (c, light) in conns() {
                let rate = match light {
                    Some(l) => {
                        let y = l.d(k);
                        let (wo, dr) = toward(&m[j], &y);
                        let mut r = bsdf_rate(mat, &m[j], &wi, &wo) - Vec3::splat(2.0 * dr as f32);
                        if l.n != DVec3::ZERO {
                            let (cl, dcl) = cos(&y, &wo);
                            r += Vec3::splat((dcl / cl + l.area_rate(k)) as f32);
                        }
                        r
                    }
                    None => {
                        let wo = Dir {
                            w: c.light_position.as_dvec3(),
                            dw: DVec3::ZERO,
                        };
                        bsdf_rate(mat, &m[j], &wi, &wo)
                    }
                };
                sum += c.contribution * (prefix + rate);
            }
            // The segment to the next vertex: the lobe's weight at a delta
            // vertex (the next vertex lies on its ray), else the BSDF and
            // the area-measure geometry.
            match (m.get(j + 1), delta) {
                (_, Some(lobe)) => {
                    let (c, dc) = cos(&m[j], &wi);
                    let rate = chain::weight_rate(mat, lobe, v[i].eta, c, dc);
                    prefix += Vec3::splat(rate as f32);
                }
                (Some(next), None) => {
                    let (wo, dr) = toward(&m[j], next);
                    let (cn, dcn) = cos(next, &wo);
                    prefix += bsdf_rate(mat, &m[j], &wi, &wo)
                        + Vec3::splat((dcn / cn - 2.0 * dr + nodes[j + 1].area_rate(k)) as f32);
                }
                (None, _) => {}
            }
        }
        if valid {
            sum += record.escaped * prefix;
        }
        if sum.is_finite() {
            if sum != Vec3::ZERO {
                out.push((k, sum));
            }
        } else {
            skipped.add(DropReason::NonFinite);
        }
    }
}
