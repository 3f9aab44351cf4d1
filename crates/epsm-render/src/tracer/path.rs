//! One path: the bounce loop of the forward tracer (emission, next-event
//! estimation, BSDF sampling, Russian roulette) and its recording.

use glam::Vec3;

use super::chain::{ChainOrigin, ChainState, chain_event};
use super::{
    DIM_DIRECTION, DIM_FIRST_BOUNCE, DIM_LIGHT, DIM_LIGHT_SELECT, DIM_LOBE, DIM_ROULETTE,
    DIMS_PER_BOUNCE, RaySink, RenderOptions, SHADOW_EPS, TraceCounters,
};
use crate::bvh::BoxTest;
use crate::hit::SurfacePoint;
use crate::materials::{Material, VertexKind};
use crate::ray::{Ray, offset_origin};
use crate::record::{
    ChainRecord, ConnectionRecord, OccluderRecord, PathRecord, RecordLevel, SampleDrop,
    TrianglePoint, VertexRecord,
};
use crate::sampler::{Block, PixelSampler};
use crate::scene::Scene;

/// The recording state of one path.
pub(super) struct Recording<'a> {
    pub(super) level: RecordLevel,
    pub(super) rec: &'a mut PathRecord,
    /// Set once the level's last vertex has been recorded.
    pub(super) done: bool,
}

/// Power heuristic (β = 2) weight of a strategy with pdf `a` against `b`.
#[inline]
fn mis(a: f32, b: f32) -> f32 {
    let (a2, b2) = (a * a, b * b);
    if a2 + b2 > 0.0 { a2 / (a2 + b2) } else { 0.0 }
}

/// Traces a path from a camera ray (box tests by `boxes`, every ray cast
/// reported to `sink`); returns its radiance. Always inlined, as are the BVH
/// queries it makes, so the AVX2 build of the tile loop compiles them too.
#[inline(always)]
#[allow(clippy::too_many_arguments)] // the path's inputs, what observes it, the box test
pub(super) fn trace_path(
    scene: &Scene,
    opts: &RenderOptions,
    mut ray: Ray,
    sampler: &PixelSampler<'_>,
    mut rec: Option<&mut Recording<'_>>,
    counters: &mut TraceCounters,
    sink: &mut impl RaySink,
    boxes: impl BoxTest,
) -> Vec3 {
    let objects = scene.objects();
    let lights = scene.lights();
    let mut radiance = Vec3::ZERO;
    let mut beta = Vec3::ONE;
    // Product of η² over refractions, to undo radiance scaling in roulette.
    let mut eta_scale = 1.0f32;
    // The previous vertex: position and the pdf of the direction it sampled
    // (`None` when that was a delta lobe or the camera: no MIS).
    let mut prev: Option<(Vec3, f32)> = None;
    // Whether an emitter hit now was estimated by manifold next-event
    // estimation at an earlier vertex (and adds nothing here).
    let chains = scene.chains_to_lights();
    let mut chain_state = ChainState::Outside;

    // A path scatters at most `max_depth` times; the vertex its last
    // scattering reaches still adds what it emits (or the background seen),
    // so both strategies of that scattering's direct light are counted, as
    // their MIS weights assume (pbrt-v4's and Mitsuba 3's depth rule).
    for depth in 0..=opts.max_depth {
        let scatters = depth < opts.max_depth;
        let numbers = sampler.block(DIM_FIRST_BOUNCE + depth * DIMS_PER_BOUNCE);
        counters.rays += 1;
        sink.closest(depth, &ray);

        // Find the next vertex; rays that leave see the background.
        let Some(hit) = scene.accel().closest_hit_with(&ray, boxes) else {
            let dir = ray.dir.normalize();
            let le = scene.background().eval(dir);
            if le != Vec3::ZERO {
                let w = prev.map_or(1.0, |(_, pdf)| mis(pdf, lights.pdf_background(dir)));
                radiance += beta * le * w;
                if let Some(r) = rec.as_deref_mut().filter(|r| !r.done) {
                    r.rec.escaped += beta * le * w;
                    r.rec.escape_dir = dir;
                }
            }
            break;
        };
        let sp = scene.accel().surface_point(objects, &hit);
        let object = &objects[hit.object as usize];
        let material = &scene.materials()[object.material as usize];
        // Camera and continuation rays are unit (sampled directions mapped by
        // an orthonormal frame): no renormalisation.
        let wi_world = -ray.dir;
        // Its cosine with the geometric normal, for the side tests.
        let wi_ng = wi_world.dot(sp.ng);
        let mut contribution = Vec3::ZERO;

        // Emission hit by BSDF sampling (front face only), unless manifold
        // next-event estimation counted this path.
        if let Some(le) = object.emission
            && wi_ng > 0.0
            && !chain_state.counted(scene, &sp, hit.object, boxes)
        {
            let w = prev.map_or(1.0, |(p_prev, pdf)| {
                mis(
                    pdf,
                    lights.pdf_area(hit.object, hit.triangle, p_prev, sp.p, sp.ng),
                )
            });
            contribution += beta * le * w;
        }

        let frame = &sp.frame;
        let wi = material.to_local(frame, wi_world);
        let kind = material.vertex_kind();

        // Sample the BSDF to continue, before next-event estimation: the
        // continuation's direction does not depend on it, and computed first
        // its latency (the direction map, the frame) overlaps the shadow
        // ray's walk instead of following it.
        let u_lobe = numbers.get_1d(DIM_LOBE);
        let u_dir = numbers.get_2d(DIM_DIRECTION);
        let sample = scatters
            .then(|| material.sample(wi, sp.uv, u_lobe, u_dir))
            .flatten();
        let mut next = None;
        if let Some(bs) = sample {
            let wo_world = frame.to_world(bs.wo);
            let wo_ng = wo_world.dot(sp.ng);
            let reflect = !bs.lobe.is_transmission();
            let same_side = wo_ng * wi_ng > 0.0;
            if same_side == reflect {
                next = Some((bs, wo_world, wo_ng));
            } else {
                counters.leaks += 1;
            }
        }

        // Next-event estimation toward a light.
        let record_at = rec
            .as_deref()
            .filter(|r| !r.done && r.level >= RecordLevel::FirstDiffuse)
            .map(|r| r.rec.vertices.len() as u32);
        let shading = Shading {
            sp: &sp,
            wi,
            wi_ng,
            material,
        };
        // Manifold next-event estimation reaches a light through at most
        // this many refractions within the depth limit.
        let interfaces = if chains && scatters && !material.is_delta() {
            (opts.max_depth - depth - 1) as usize
        } else {
            0
        };
        let nee = if scatters {
            next_event(
                scene, &shading, beta, &numbers, interfaces, record_at, counters, sink, boxes,
            )
        } else {
            NextEvent::NONE
        };
        contribution += nee.contribution;
        let connection = nee.connection;
        let chain = nee.chain;
        radiance += contribution;

        if let Some(r) = rec.as_deref_mut().filter(|r| !r.done) {
            let at = TrianglePoint::from(&hit);
            let (lobe, eta, m) = next.map_or((None, 1.0, sp.ns()), |(bs, _, _)| {
                (Some(bs.lobe), bs.eta, frame.to_world(bs.m))
            });
            r.rec.vertices.push(VertexRecord {
                at,
                p: sp.p,
                ng: sp.ng,
                ns: sp.ns(),
                kind,
                lobe,
                eta,
                m,
                throughput: beta,
                contribution,
            });
            r.rec.connections.extend(connection);
            r.rec.chains.extend(chain);
            r.done = match r.level {
                RecordLevel::Primary => true,
                RecordLevel::FirstDiffuse => kind == VertexKind::Diffuse,
                RecordLevel::Full => false,
            };
        }

        let Some((bs, wo_world, wo_ng)) = next else {
            break;
        };
        let origin = (interfaces > 0).then_some(ChainOrigin {
            sp,
            wi_ng,
            dir: wo_world,
            interfaces,
        });
        chain_state = chain_state.after(material, bs.lobe, origin);
        beta *= bs.weight;
        if bs.lobe.is_transmission() {
            eta_scale *= bs.eta * bs.eta;
        }
        prev = Some((sp.p, bs.pdf)).filter(|_| !bs.lobe.is_delta());
        ray = Ray::new(leaving_origin(&sp, wo_ng), wo_world);

        // Russian roulette on the throughput with radiance scaling undone.
        if depth + 1 >= opts.rr_depth {
            let q = (beta.max_element() * eta_scale).min(0.95);
            if q <= 0.0 || numbers.get_1d(DIM_ROULETTE) >= q {
                break;
            }
            beta /= q;
        }
        if beta == Vec3::ZERO {
            break;
        }
    }
    radiance
}

/// A shading point as next-event estimation sees it.
pub(super) struct Shading<'a> {
    pub(super) sp: &'a SurfacePoint,
    /// Direction toward the previous vertex, local frame (as far as the
    /// material reads it: [`Material::to_local`]).
    pub(super) wi: Vec3,
    /// `wi · ng` in world space: its cosine with the geometric normal.
    pub(super) wi_ng: f32,
    pub(super) material: &'a Material,
}

/// What next-event estimation at one vertex added.
struct NextEvent {
    /// Radiance added (zero when blocked or no light was sampled).
    contribution: Vec3,
    /// The connection, when recording at vertex index `record_at`.
    connection: Option<ConnectionRecord>,
    /// The manifold connection through glass, when one was made and recorded.
    chain: Option<ChainRecord>,
}

impl NextEvent {
    /// Nothing added, no connection.
    const NONE: Self = Self {
        contribution: Vec3::ZERO,
        connection: None,
        chain: None,
    };
}

/// Samples a light, evaluates the BSDF toward it, MIS-weights against BSDF
/// sampling and traces the shadow ray (box tests by `boxes`, reported to
/// `sink`). Draws three random numbers of the bounce's block `numbers`, none
/// at a delta vertex. When the shadow ray is blocked and `interfaces > 0`,
/// tries the connection through at most that many refractions (module
/// `chain`) with the same light point.
///
/// The walk is not passed in as a closure: a closure is compiled as a
/// function of its own, without the AVX2 tile loop's target features, and
/// was not inlined (3.5 % more instructions per sample on
/// `scenes/caustic-box.toml`, its box tests called out of line).
#[inline(always)]
#[allow(clippy::too_many_arguments)] // the vertex, what observes it, the box test
fn next_event(
    scene: &Scene,
    at: &Shading<'_>,
    beta: Vec3,
    numbers: &Block,
    interfaces: usize,
    record_at: Option<u32>,
    counters: &mut TraceCounters,
    sink: &mut impl RaySink,
    boxes: impl BoxTest,
) -> NextEvent {
    let mut out = NextEvent::NONE;
    if at.material.is_delta() {
        return out;
    }
    let u_select = numbers.get_1d(DIM_LIGHT_SELECT);
    let u_light = numbers.get_2d(DIM_LIGHT);
    let Some(ls) = scene.lights().sample(at.sp.p, u_select, u_light) else {
        return out;
    };
    let wo = at.material.to_local(&at.sp.frame, ls.wo);
    let f = at.material.eval(at.wi, wo, at.sp.uv);
    let wo_ng = ls.wo.dot(at.sp.ng);
    let same_side = wo_ng * at.wi_ng > 0.0;
    if f == Vec3::ZERO || !same_side || ls.pdf <= 0.0 {
        // The chain through glass leaves in its own direction.
        add_chain(
            scene, at, beta, &ls, interfaces, record_at, counters, sink, boxes, &mut out,
        );
        return out;
    }
    let w = if ls.delta {
        1.0
    } else {
        mis(ls.pdf, at.material.pdf(at.wi, wo, at.sp.uv))
    };
    let unoccluded = beta * f * ls.radiance * (w / ls.pdf);
    let shadow = shadow_ray(at.sp, ls.wo, wo_ng, ls.position, ls.dist);
    counters.shadow_rays += 1;
    sink.shadow(&shadow);
    let blocked = scene.accel().occluded_with(&shadow, boxes);
    if !blocked {
        out.contribution = unoccluded;
    } else {
        add_chain(
            scene, at, beta, &ls, interfaces, record_at, counters, sink, boxes, &mut out,
        );
    }
    out.connection = record_at.map(|vertex| {
        // Unblocked, a non-finite strength is the contribution and drops
        // the whole sample; blocked, only the record holds it.
        let dropped = (blocked && !unoccluded.is_finite()).then_some(SampleDrop::NonFinite);
        ConnectionRecord {
            vertex,
            light: ls.source,
            light_position: ls.position,
            light_normal: ls.normal,
            contribution: out.contribution,
            unoccluded: if dropped.is_some() {
                Vec3::ZERO
            } else {
                unoccluded
            },
            occluder: blocked.then(|| first_occluder(scene, &shadow)).flatten(),
            dropped,
        }
    });
    out
}

/// Adds the manifold connection toward `ls`'s light point to `out`, through
/// at most `interfaces` refractions (none when 0).
#[allow(clippy::too_many_arguments)] // the vertex, the light sample, what observes it
fn add_chain(
    scene: &Scene,
    at: &Shading<'_>,
    beta: Vec3,
    ls: &crate::lights::LightSample,
    interfaces: usize,
    record_at: Option<u32>,
    counters: &mut TraceCounters,
    sink: &mut impl RaySink,
    boxes: impl BoxTest,
    out: &mut NextEvent,
) {
    if interfaces == 0 {
        return;
    }
    if let Some((c, chain)) = chain_event(
        scene, at, beta, ls, interfaces, record_at, counters, sink, boxes,
    ) {
        out.contribution += c;
        out.chain = chain;
    }
}

/// The origin of a ray leaving surface point `sp` in a direction whose
/// cosine with the geometric normal is `wo_ng`: offset to that side.
#[inline(always)]
pub(super) fn leaving_origin(sp: &SurfacePoint, wo_ng: f32) -> Vec3 {
    let side = if wo_ng >= 0.0 { sp.ng } else { -sp.ng };
    offset_origin(sp.p, side)
}

/// The shadow ray from surface point `sp` toward a light point `y` (or along
/// `wo` for the background when `dist` is infinite); `wo_ng = wo · ng`.
fn shadow_ray(sp: &SurfacePoint, wo: Vec3, wo_ng: f32, y: Vec3, dist: f32) -> Ray {
    let origin = leaving_origin(sp, wo_ng);
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
        at: TrianglePoint::from(&hit),
        p: sp.p,
    })
}
