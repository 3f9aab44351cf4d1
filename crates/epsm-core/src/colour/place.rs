//! Where each node of a recorded path is at θ and how it moves: surface
//! vertices and area-light points through the motion model ([`Anchor`]),
//! the camera eye and point lights with their parameters, the pixel's
//! vertex on its camera ray and the vertex after a delta interface on its
//! scattered ray ([`PrimaryMotion::OnCameraRay`]).

use epsm_render::Scene;
use epsm_render::lights::LightPoint;
use epsm_render::materials::{Bsdf, Lobe};
use epsm_render::record::{PathRecord, TrianglePoint, VertexRecord};
use glam::{DVec2, DVec3};

use super::chain;
use super::geometry::{Geometric, PrimaryMotion};
use super::moving::{Placed, toward};
use crate::drops::DropReason;
use crate::motion::Motion;
use crate::vertex::Anchor;

/// The anchored point `at` with the derivatives of its placement.
fn surface(
    scene: &Scene,
    motion: &Motion,
    at: &TrianglePoint,
    scales: &[(usize, f64)],
) -> Option<Placed> {
    let om = motion.objects.get(at.object as usize)?;
    let anchor = Anchor::at_point(scene, motion, at)?;
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
/// `prev`) scatters toward (see [`chain`]), with the relative IOR `eta`;
/// `ior` is `(param, ∂eta/∂θ)` when a parameter sets the interface's IOR
/// (the refracted ray then turns with it). Fails under total internal
/// reflection or when the ray grazes `next`'s surface.
fn on_scattered_ray(
    next: &mut Placed,
    at: &Placed,
    prev: &Placed,
    eta: f64,
    ior: Option<(usize, f64)>,
    transmit: bool,
) -> Result<(), DropReason> {
    let params = [prev, at, &*next]
        .iter()
        .flat_map(|p| p.grads.iter().map(|g| g.0))
        .chain(ior.map(|(k, _)| k))
        .collect();
    let mut grads = Vec::new();
    for k in sorted(params) {
        let (a, b, c) = (prev.d(k), at.d(k), next.d(k));
        let (wi, _) = toward(&b, &a);
        let deta = ior.filter(|(p, _)| *p == k).map_or(0.0, |(_, d)| d);
        let [r, dr] = chain::scattered(wi.w, wi.dw, b.n, b.dn, [eta, deta], transmit)
            .ok_or(DropReason::TotalInternalReflection)?;
        let du = chain::ray_step(c.x - b.x, r, dr, c.dx - b.dx, next.dx_du)
            .ok_or(DropReason::Grazing)?;
        grads.push(next.stepped(k, &c, du));
    }
    next.grads = grads;
    next.area.clear();
    Ok(())
}

pub(super) fn sorted(mut v: Vec<usize>) -> Vec<usize> {
    v.sort_unstable();
    v.dedup();
    v
}

/// The delta lobe that scattered at `v`, if any.
pub(super) fn delta_lobe(v: &VertexRecord) -> Option<Lobe> {
    v.lobe.filter(|l| l.is_delta())
}

impl Geometric<'_> {
    /// `(param, ∂eta/∂θ)` at a refraction through `object` with relative
    /// IOR `eta`, when a parameter sets the object's dielectric IOR `n`:
    /// entering, `eta = n` and the rate is 1; leaving, `eta = 1/n` and the
    /// rate is `−eta²`.
    fn ior_rate(&self, object: u32, eta: f64) -> Option<(usize, f64)> {
        let m = self.scene.objects().get(object as usize)?.material;
        let param = (*self.iors.get(m as usize)?)?;
        let Bsdf::Dielectric(d) = &self.scene.materials().get(m as usize)?.bsdf else {
            return None;
        };
        let n = f64::from(d.ior);
        let entering = (eta - n).abs() <= (eta - 1.0 / n).abs();
        Some((param, if entering { 1.0 } else { -eta * eta }))
    }

    /// Whether anything on the record moves (camera, a vertex's object, a
    /// light, a refracted ray whose IOR is a parameter).
    pub(super) fn moves(&self, record: &PathRecord) -> bool {
        let driven = |o: u32| {
            self.motion
                .objects
                .get(o as usize)
                .is_some_and(|m| !m.grads.is_empty())
        };
        let refracts_with_ior = |v: &VertexRecord| {
            v.lobe.is_some_and(|l| l.is_delta() && l.is_transmission())
                && self.ior_rate(v.at.object, f64::from(v.eta)).is_some()
        };
        !self.motion.camera.grads.is_empty()
            || record.vertices.iter().any(|v| driven(v.at.object))
            || record.vertices.iter().any(refracts_with_ior)
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
    pub(super) fn place(
        &self,
        record: &PathRecord,
    ) -> Result<(Vec<Placed>, Vec<Option<Placed>>), DropReason> {
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
                let at = &record.vertices[i - 1];
                let eta = f64::from(at.eta);
                let ior = self.ior_rate(at.at.object, eta);
                on_scattered_ray(
                    &mut p,
                    &nodes[i],
                    &nodes[i - 1],
                    eta,
                    ior.filter(|_| lobe.is_transmission()),
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
}
