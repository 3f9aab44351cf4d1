//! One path vertex, split at its shadow ray: [`shade`] (emission, light
//! sample, BSDF sample, Russian roulette and recording) runs before the
//! batch's shadow rays are traced, [`Waiting::finish`] adds the next-event
//! contribution after. The estimator is the one of a plain bounce loop
//! (next-event estimation with the power heuristic against BSDF sampling,
//! roulette from `rr_depth`), with the same numbers in the same order.

use glam::Vec3;

use super::{DIMS_PER_BOUNCE, RenderOptions, SHADOW_EPS, TraceCounters};
use crate::frame::Frame;
use crate::hit::{Hit, SurfacePoint};
use crate::lights::LightSample;
use crate::materials::{Material, VertexKind};
use crate::ray::{Ray, offset_origin};
use crate::record::{
    ConnectionRecord, OccluderRecord, PathRecord, RecordLevel, TrianglePoint, VertexRecord,
};
use crate::sampler::PixelSampler;
use crate::scene::Scene;

/// The state a path carries from one vertex to the next.
#[derive(Clone, Copy, Debug)]
pub(super) struct PathState<'k> {
    /// The path's random stream.
    pub(super) sampler: PixelSampler<'k>,
    /// Throughput of the path so far.
    pub(super) beta: Vec3,
    /// Product of η² over refractions, to undo radiance scaling in roulette.
    pub(super) eta_scale: f32,
    /// The previous vertex: position and the pdf of the direction it sampled
    /// (`None` when that was a delta lobe or the camera: no MIS).
    pub(super) prev: Option<(Vec3, f32)>,
    /// Recording: set once the level's last vertex has been recorded.
    pub(super) done: bool,
}

impl<'k> PathState<'k> {
    /// A path leaving the camera, drawing from `sampler`.
    #[inline(always)]
    pub(super) fn new(sampler: PixelSampler<'k>) -> Self {
        Self {
            sampler,
            beta: Vec3::ONE,
            eta_scale: 1.0,
            prev: None,
            done: false,
        }
    }
}

/// A vertex waiting for its shadow ray: what it adds to its path's
/// radiance then.
#[derive(Clone, Copy, Debug)]
pub(super) struct Waiting {
    /// The path's slot in its batch.
    slot: u32,
    /// Radiance the vertex adds besides the connection (its emission hit by
    /// BSDF sampling, MIS-weighted).
    contribution: Vec3,
    /// What the connection adds when unblocked.
    unoccluded: Vec3,
    /// Recording: the indices of the vertex and connection records made at
    /// the vertex.
    vertex_record: Option<u32>,
    connection_record: Option<u32>,
}

/// Power heuristic (β = 2) weight of a strategy with pdf `a` against `b`.
#[inline]
fn mis(a: f32, b: f32) -> f32 {
    let (a2, b2) = (a * a, b * b);
    if a2 + b2 > 0.0 { a2 / (a2 + b2) } else { 0.0 }
}

/// The shadow rays of a batch's vertices and the vertices waiting for them
/// (index `i` of each is the same connection).
#[derive(Debug, Default)]
pub(super) struct Shadows {
    pub(super) rays: Vec<Ray>,
    pub(super) waiting: Vec<Waiting>,
}

/// Shades bounce `depth` of the path in batch slot `slot`, whose `ray`
/// found `hit`: adds the
/// background of an escaped path to `radiance`, samples a light (its shadow
/// ray pushed onto `shadows` with what it will add; with no connection the
/// vertex's contribution goes to `radiance` at once), samples the BSDF,
/// records, and replaces `ray` by the continuation. Returns whether the
/// path goes on. `record` is the path's record when the batch records.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
pub(super) fn shade(
    scene: &Scene,
    opts: &RenderOptions,
    depth: u32,
    slot: u32,
    path: &mut PathState<'_>,
    ray: &mut Ray,
    hit: Option<Hit>,
    radiance: &mut Vec3,
    record: Option<(RecordLevel, &mut PathRecord)>,
    shadows: &mut Shadows,
    counters: &mut TraceCounters,
) -> bool {
    let objects = scene.objects();
    let lights = scene.lights();
    let dims = 2 + depth * DIMS_PER_BOUNCE;
    path.sampler.set_dimension(dims);
    let mut record = record.filter(|_| !path.done);

    // Rays that leave see the background.
    let Some(hit) = hit else {
        let dir = ray.dir.normalize();
        let le = scene.background().eval(dir);
        if le != Vec3::ZERO {
            let w = path
                .prev
                .map_or(1.0, |(_, pdf)| mis(pdf, lights.pdf_background(dir)));
            *radiance += path.beta * le * w;
            if let Some((_, rec)) = record {
                rec.escaped += path.beta * le * w;
            }
        }
        return false;
    };
    let sp = scene.accel().surface_point(objects, &hit);
    let object = &objects[hit.object as usize];
    let material = &scene.materials()[object.material as usize];
    // Camera and continuation rays are unit (sampled directions mapped by
    // an orthonormal frame): no renormalisation.
    let wi_world = -ray.dir;
    let mut contribution = Vec3::ZERO;

    // Emission hit by BSDF sampling (front face only).
    if let Some(le) = object.emission
        && sp.ng.dot(wi_world) > 0.0
    {
        let w = path.prev.map_or(1.0, |(p_prev, pdf)| {
            mis(
                pdf,
                lights.pdf_area(hit.object, hit.triangle, p_prev, sp.p, sp.ng),
            )
        });
        contribution += path.beta * le * w;
    }

    // Next-event estimation toward a light (the shadow ray is traced later).
    let frame = Frame::from_normal(sp.ns);
    let wi = frame.to_local(wi_world);
    let kind = material.vertex_kind();
    let shading = Shading {
        sp: &sp,
        frame: &frame,
        wi,
        wi_world,
        material,
    };
    let light = next_event(scene, &shading, path.beta, &mut path.sampler);

    // Sample the BSDF to continue (dimensions 3–5 of the bounce's block,
    // whether or not next-event estimation drew its three).
    path.sampler.set_dimension(dims + 3);
    let u_lobe = path.sampler.next_1d();
    let u_dir = path.sampler.next_2d();
    let sample = material.sample(wi, sp.uv, u_lobe, u_dir);
    let mut next = None;
    if let Some(bs) = sample {
        let wo_world = frame.to_world(bs.wo);
        let reflect = !bs.lobe.is_transmission();
        let same_side = wo_world.dot(sp.ng) * wi_world.dot(sp.ng) > 0.0;
        if same_side == reflect {
            next = Some((bs, wo_world));
        } else {
            counters.leaks += 1;
        }
    }

    // Record the vertex and its connection (`Waiting::finish` fills in what
    // the shadow ray decides).
    let (mut vertex_record, mut connection_record) = (None, None);
    if let Some((level, rec)) = record.as_mut() {
        let at = TrianglePoint {
            object: hit.object,
            triangle: hit.triangle,
            b1: hit.b1,
            b2: hit.b2,
        };
        let (lobe, eta, m) = next.map_or((None, 1.0, sp.ns), |(bs, _)| {
            (Some(bs.lobe), bs.eta, frame.to_world(bs.m))
        });
        vertex_record = Some(rec.vertices.len() as u32);
        if let Some(c) = light.filter(|_| *level >= RecordLevel::FirstDiffuse) {
            connection_record = Some(rec.connections.len() as u32);
            rec.connections.push(ConnectionRecord {
                vertex: rec.vertices.len() as u32,
                light: c.light.source,
                light_position: c.light.position,
                light_normal: c.light.normal,
                contribution: Vec3::ZERO,
                unoccluded: c.unoccluded,
                occluder: None,
            });
        }
        rec.vertices.push(VertexRecord {
            at,
            p: sp.p,
            ng: sp.ng,
            ns: sp.ns,
            kind,
            lobe,
            eta,
            m,
            throughput: path.beta,
            contribution,
        });
        path.done = match level {
            RecordLevel::Primary => true,
            RecordLevel::FirstDiffuse => kind == VertexKind::Diffuse,
            RecordLevel::Full => false,
        };
    }
    match light {
        Some(c) => {
            shadows.rays.push(c.shadow);
            shadows.waiting.push(Waiting {
                slot,
                contribution,
                unoccluded: c.unoccluded,
                vertex_record,
                connection_record,
            });
        }
        None => *radiance += contribution,
    }

    let Some((bs, wo_world)) = next else {
        return false;
    };
    path.beta *= bs.weight;
    if bs.lobe.is_transmission() {
        path.eta_scale *= bs.eta * bs.eta;
    }
    path.prev = Some((sp.p, bs.pdf)).filter(|_| !bs.lobe.is_delta());
    let side = if wo_world.dot(sp.ng) >= 0.0 {
        sp.ng
    } else {
        -sp.ng
    };
    *ray = Ray::new(offset_origin(sp.p, side), wo_world);

    // Russian roulette on the throughput with radiance scaling undone.
    if depth + 1 >= opts.rr_depth {
        let q = (path.beta.max_element() * path.eta_scale).min(0.95);
        if q <= 0.0 || path.sampler.next_1d() >= q {
            return false;
        }
        path.beta /= q;
    }
    path.beta != Vec3::ZERO
}

impl Waiting {
    /// Adds the vertex's contribution to its path's radiance (indexed by
    /// slot) now that its shadow ray is known to be `blocked`, and completes
    /// its records.
    #[inline(always)]
    pub(super) fn finish(
        &self,
        scene: &Scene,
        shadow: &Ray,
        blocked: bool,
        radiance: &mut [Vec3],
        records: Option<&mut [PathRecord]>,
    ) {
        let nee = if blocked { Vec3::ZERO } else { self.unoccluded };
        let contribution = self.contribution + nee;
        radiance[self.slot as usize] += contribution;
        let Some(rec) = records.map(|r| &mut r[self.slot as usize]) else {
            return;
        };
        if let Some(v) = self.vertex_record {
            rec.vertices[v as usize].contribution = contribution;
        }
        if let Some(c) = self.connection_record {
            let connection = &mut rec.connections[c as usize];
            connection.contribution = nee;
            connection.occluder = blocked.then(|| first_occluder(scene, shadow)).flatten();
        }
    }
}

/// A shading point as next-event estimation sees it.
struct Shading<'a> {
    sp: &'a SurfacePoint,
    frame: &'a Frame,
    /// Direction toward the previous vertex, local frame.
    wi: Vec3,
    /// The same, world space.
    wi_world: Vec3,
    material: &'a Material,
}

/// A next-event connection waiting for its shadow ray.
#[derive(Clone, Copy)]
struct Connection {
    light: LightSample,
    /// The radiance it adds when unblocked.
    unoccluded: Vec3,
    shadow: Ray,
}

/// Samples a light, evaluates the BSDF toward it and MIS-weights against
/// BSDF sampling; `None` when nothing can arrive. Consumes three random
/// numbers, none at a delta vertex.
#[inline(always)]
fn next_event(
    scene: &Scene,
    at: &Shading<'_>,
    beta: Vec3,
    sampler: &mut PixelSampler<'_>,
) -> Option<Connection> {
    if at.material.is_delta() {
        return None;
    }
    let u_select = sampler.next_1d();
    let u_light = sampler.next_2d();
    let ls = scene.lights().sample(at.sp.p, u_select, u_light)?;
    let wo = at.frame.to_local(ls.wo);
    let f = at.material.eval(at.wi, wo, at.sp.uv);
    let same_side = ls.wo.dot(at.sp.ng) * at.wi_world.dot(at.sp.ng) > 0.0;
    if f == Vec3::ZERO || !same_side || ls.pdf <= 0.0 {
        return None;
    }
    let w = if ls.delta {
        1.0
    } else {
        mis(ls.pdf, at.material.pdf(at.wi, wo, at.sp.uv))
    };
    Some(Connection {
        light: ls,
        unoccluded: beta * f * ls.radiance * (w / ls.pdf),
        shadow: shadow_ray(at.sp, ls.wo, ls.position, ls.dist),
    })
}

/// The shadow ray from surface point `sp` toward a light point `y` (or along
/// `wo` for the background when `dist` is infinite).
#[inline(always)]
fn shadow_ray(sp: &SurfacePoint, wo: Vec3, y: Vec3, dist: f32) -> Ray {
    let side = if wo.dot(sp.ng) >= 0.0 { sp.ng } else { -sp.ng };
    let origin = offset_origin(sp.p, side);
    if dist.is_finite() {
        Ray {
            origin,
            dir: y - origin,
            t_min: 0.0,
            t_max: 1.0 - SHADOW_EPS,
        }
    } else {
        Ray::new(origin, wo)
    }
}

fn first_occluder(scene: &Scene, shadow: &Ray) -> Option<OccluderRecord> {
    let hit = scene.accel().closest_hit(shadow)?;
    let sp = scene.accel().surface_point(scene.objects(), &hit);
    Some(OccluderRecord {
        at: TrianglePoint {
            object: hit.object,
            triangle: hit.triangle,
            b1: hit.b1,
            b2: hit.b2,
        },
        p: sp.p,
    })
}
