//! Sixteen paths' state and one bounce of each: the steps of the scalar
//! bounce loop (`tracer::path::trace_path`) in lanes, in the same order and
//! with the same operations, so every lane computes what the scalar loop
//! computes for its path.

use super::offset::offset_origins16;
use super::{Objects16, Setup};
use crate::bvh::Rays16;
use crate::sampler::wide::{Block16, Streams16};
use crate::simd::{F32x16, Lanes, Mask16, U32x16, Vec3x16};
use crate::tracer::{
    DIM_DIRECTION, DIM_FIRST_BOUNCE, DIM_LIGHT, DIM_LIGHT_SELECT, DIM_LOBE, DIM_ROULETTE,
    DIMS_PER_BOUNCE, SHADOW_EPS, TraceCounters,
};

/// Sixteen paths in flight, one per lane: what the scalar bounce loop keeps
/// in its local variables.
#[derive(Clone, Copy, Debug)]
pub(super) struct Paths16<B: Lanes> {
    /// Lanes holding a path.
    pub active: Mask16,
    /// Each lane's random stream.
    pub streams: Streams16<B>,
    /// The ray each path traces next (camera or continuation ray).
    pub ray: Rays16<B>,
    /// Path throughput.
    pub beta: Vec3x16<B>,
    /// Radiance gathered so far.
    pub radiance: Vec3x16<B>,
    /// Product of η² over refractions (undone in Russian roulette).
    pub eta_scale: F32x16<B>,
    /// The previous vertex's position (for MIS), where `has_prev`.
    pub prev_p: Vec3x16<B>,
    /// The pdf of the direction the previous vertex sampled, where `has_prev`.
    pub prev_pdf: F32x16<B>,
    /// Lanes whose previous vertex sampled a non-delta direction (not the
    /// camera, not a delta lobe): MIS applies.
    pub has_prev: Mask16,
    /// Scatterings so far (the bounce index).
    pub depth: U32x16<B>,
}

/// Power heuristic (β = 2) weight of a strategy with pdf `a` against `b`,
/// as `tracer::path::mis`.
#[inline(always)]
fn mis<B: Lanes>(k: B, a: F32x16<B>, b: F32x16<B>) -> F32x16<B> {
    let (a2, b2) = (a * a, b * b);
    let sum = a2 + b2;
    let zero = k.f32(0.0);
    F32x16::select(sum.gt(zero), a2 / sum, zero)
}

/// `a + b` in the lanes of `m`, `a` in the others.
#[inline(always)]
fn add_where<B: Lanes>(m: Mask16, a: Vec3x16<B>, b: Vec3x16<B>) -> Vec3x16<B> {
    Vec3x16::select(m, a + b, a)
}

/// Advances every active path by one bounce; returns the lanes whose path
/// ended (their `radiance` is final).
#[inline(always)]
pub(super) fn bounce<B: Lanes>(
    k: B,
    setup: &Setup<'_>,
    paths: &mut Paths16<B>,
    counters: &mut TraceCounters,
) -> Mask16 {
    let scene = setup.scene;
    let (accel, lights) = (scene.accel(), scene.lights());
    let zero = k.f32(0.0);
    let active = paths.active;
    let depth = paths.depth;
    let scatters = active & depth.lt(k.u32(setup.opts.max_depth));
    let first = k.u32(DIM_FIRST_BOUNCE) + depth * k.u32(DIMS_PER_BOUNCE);
    let first_bounce = depth.eq(k.u32(0));
    let numbers: Block16<B> = paths.streams.block16(k, first, first_bounce);
    counters.rays += u64::from(active.count());

    // Find the next vertex; rays that leave see the background.
    let hits = accel.closest_hits16(k, &paths.ray, active);
    let missed = active.and_not(hits.found);
    let hit = active & hits.found;
    if missed.any() {
        let dir = paths.ray.dir.normalize(k);
        let le = scene.background().eval16(k, dir, missed);
        let lit = missed.and_not(le.is_zero(k));
        if lit.any() {
            let weighted = paths.has_prev & lit;
            let w = if weighted.any() {
                let pdf = lights.pdf_background16(k, dir, weighted);
                F32x16::select(paths.has_prev, mis(k, paths.prev_pdf, pdf), k.f32(1.0))
            } else {
                k.f32(1.0)
            };
            paths.radiance = add_where(lit, paths.radiance, paths.beta * le * w);
        }
    }
    if !hit.any() {
        return active;
    }
    let sp = accel.surface_points16(k, scene.objects(), &hits);
    let objects: &Objects16 = setup.objects;
    let material = U32x16::gather(&objects.material, hits.object, hit, k.u32(0));
    let wi_world = -paths.ray.dir;
    let wi_ng = wi_world.dot(sp.ng);
    let mut contribution = k.vec3(glam::Vec3::ZERO);

    // Emission hit by BSDF sampling (front face only).
    let emitter = U32x16::gather(&objects.emitter, hits.object, hit, k.u32(0));
    let emits = hit.and_not(emitter.eq(k.u32(0))) & wi_ng.gt(zero);
    if emits.any() {
        let le = Vec3x16::new(
            F32x16::gather(&objects.emission[0], hits.object, emits, zero),
            F32x16::gather(&objects.emission[1], hits.object, emits, zero),
            F32x16::gather(&objects.emission[2], hits.object, emits, zero),
        );
        let weighted = emits & paths.has_prev;
        let w = if weighted.any() {
            let pdf = lights.pdf_area16(
                k,
                hits.object,
                hits.triangle,
                paths.prev_p,
                sp.p,
                sp.ng,
                weighted,
            );
            F32x16::select(weighted, mis(k, paths.prev_pdf, pdf), k.f32(1.0))
        } else {
            k.f32(1.0)
        };
        contribution = add_where(emits, contribution, paths.beta * le * w);
    }

    let materials = setup.materials;
    let frame = &sp.frame;
    let wi = materials.to_local16(k, material, frame, wi_world, hit);

    // Sample the BSDF to continue.
    let bs = materials.sample16(
        k,
        material,
        wi,
        &sp.uv,
        numbers.get_1d(DIM_LOBE),
        numbers.get_2d(DIM_DIRECTION),
        scatters & hit,
    );
    let wo_world = frame.to_world(bs.wo);
    let wo_ng = wo_world.dot(sp.ng);
    let same_side = (wo_ng * wi_ng).gt(zero);
    // Reflection needs `wo` on the side of `wi`, transmission the other.
    let right_side = !(same_side ^ !bs.transmission);
    let next = bs.found & right_side;
    counters.leaks += u64::from(bs.found.and_not(right_side).count());

    // Next-event estimation toward a light (what it adds is zero in the
    // lanes it does not reach, and added to every hit lane's contribution,
    // as in the scalar loop).
    let nee = (scatters & hit).and_not(materials.is_delta16(k, material, scatters & hit));
    let mut nee_contribution = k.vec3(glam::Vec3::ZERO);
    if nee.any() {
        let ls = lights.sample16(
            k,
            sp.p,
            numbers.get_1d(DIM_LIGHT_SELECT),
            numbers.get_2d(DIM_LIGHT),
            nee,
        );
        let sampled = nee & ls.found;
        let wo = materials.to_local16(k, material, frame, ls.wo, sampled);
        let f = materials.eval16(k, material, wi, wo, &sp.uv, sampled);
        let lwo_ng = ls.wo.dot(sp.ng);
        let lit = sampled.and_not(f.is_zero(k)) & (lwo_ng * wi_ng).gt(zero);
        let lit = lit.and_not(ls.pdf.le(zero));
        if lit.any() {
            let mis_lanes = lit.and_not(ls.delta);
            let w = if mis_lanes.any() {
                let pdf = materials.pdf16(k, material, wi, wo, mis_lanes);
                F32x16::select(ls.delta, k.f32(1.0), mis(k, ls.pdf, pdf))
            } else {
                k.f32(1.0)
            };
            let unoccluded = paths.beta * f * ls.radiance * (w / ls.pdf);
            let origin = offset_origins16(k, sp.p, Vec3x16::select(lwo_ng.ge(zero), sp.ng, -sp.ng));
            let finite = ls.dist.is_finite();
            let shadow = Rays16 {
                origin,
                dir: Vec3x16::select(finite, ls.position - origin, ls.wo),
                t_min: zero,
                t_max: F32x16::select(finite, k.f32(1.0 - SHADOW_EPS), k.f32(f32::INFINITY)),
            };
            counters.shadow_rays += u64::from(lit.count());
            let blocked = accel.occluded16(k, &shadow, lit);
            nee_contribution = Vec3x16::select(lit.and_not(blocked), unoccluded, nee_contribution);
        }
    }
    let contribution = contribution + nee_contribution;
    paths.radiance = add_where(hit, paths.radiance, contribution);

    // Continue: throughput, η², the previous vertex, the next ray.
    let beta = Vec3x16::select(next, paths.beta * bs.weight, paths.beta);
    let refracted = next & bs.transmission;
    let eta_scale = F32x16::select(
        refracted,
        paths.eta_scale * (bs.eta * bs.eta),
        paths.eta_scale,
    );
    paths.prev_p = Vec3x16::select(next, sp.p, paths.prev_p);
    paths.prev_pdf = F32x16::select(next, bs.pdf, paths.prev_pdf);
    paths.has_prev = (paths.has_prev.and_not(next)) | next.and_not(bs.delta);
    let origin = offset_origins16(k, sp.p, Vec3x16::select(wo_ng.ge(zero), sp.ng, -sp.ng));
    paths.ray = Rays16 {
        origin: Vec3x16::select(next, origin, paths.ray.origin),
        dir: Vec3x16::select(next, wo_world, paths.ray.dir),
        t_min: zero,
        t_max: k.f32(f32::INFINITY),
    };

    // Russian roulette on the throughput with radiance scaling undone.
    let roulette = next & (depth + k.u32(1)).ge(k.u32(setup.opts.rr_depth));
    let q = (beta.max_element() * eta_scale).min(k.f32(0.95));
    let killed = roulette & (q.le(zero) | numbers.get_1d(DIM_ROULETTE).ge(q));
    let survives = roulette.and_not(killed);
    let beta = Vec3x16::select(survives, beta.div(q), beta);
    let black = next & beta.is_zero(k);
    paths.beta = beta;
    paths.eta_scale = eta_scale;
    paths.depth = depth + k.u32(1);
    let continues = next.and_not(killed).and_not(black);
    active.and_not(continues)
}
