//! Manifold next-event estimation (Hanika, Droske and Fascione 2015):
//! next-event connections to an area light through refracting surfaces.
//!
//! A light seen from a diffuse or glossy vertex `x` only through glass (a
//! lamp behind a lens, a caustic under a glass ball) is out of reach of
//! ordinary next-event estimation, whose straight shadow ray the glass
//! blocks, and BSDF sampling finds it only when a sampled direction happens
//! to refract onto the small light. Here, when next-event estimation sampled
//! a point `y` on an area light and the straight segment `x → y` crosses
//! dielectric surfaces `k ≥ 1` times, those crossings seed a search for the
//! direction `ω` at `x` whose path, refracted at `k` dielectric
//! interfaces, reaches `y`:
//!
//! - The *shot* of `ω` traces it through the interfaces (the dielectric's
//!   own refraction, [`Material::sample`] on its transmission lobe) and
//!   meets the light's tangent plane at `y`; the residual is that point
//!   minus `y`, in two tangent coordinates of the plane.
//! - Newton's method on `ω` (two tangent coordinates around the current
//!   direction): the 2×2 Jacobian by forward differences of shots, the step
//!   halved until the residual falls, converged below
//!   [`TOLERANCE`] × `|y − x|`; at the solution the Jacobian again, by
//!   central differences, for the geometry term.
//!
//! The estimate is the chain's path contribution over the light sample's
//! area density:
//!
//! `f(x, ω)·cos θ · Π (1 − F)/η² · L_e(y) / (p_A(y) · |det ∂y/∂ω|)`,
//!
//! where `|det ∂y/∂ω|` is the area the chain's end sweeps per solid angle at
//! `x` (the generalized geometry term's inverse: with no interface it is
//! `d²/cos θ_y`, and the estimate becomes ordinary next-event estimation).
//! `Π (1 − F)/η²` is the refraction lobes' weight times their
//! probability: the same factors BSDF sampling multiplies along the chain.
//!
//! No path counts twice, and none is lost: the chain found for `(x, y)` is
//! a function of `x` and `y` alone (seed, Newton, checks), so when BSDF
//! sampling from a vertex that made manifold next-event estimation reaches
//! an emitter point `y` through dielectric refractions only, it asks
//! whether that chain leaves `x` along its own direction ([`covers`]). If
//! so, the path was counted here and BSDF sampling adds no emission for it;
//! if not (the straight segment did not seed it, Newton found another
//! chain or none), BSDF sampling counts it, with weight 1. Random numbers:
//! none of its own (it reuses the next-event light sample), so images stay
//! deterministic. Seeds that did not give a chain (no solution, Newton did
//! not converge, total internal reflection, the wrong side, a blocked last
//! segment) are counted ([`TraceCounters::chain_misses`]); what they would
//! have found is left to BSDF sampling.

use glam::{DVec2, Vec3};

use super::path::{Shading, leaving_origin};
use super::{RaySink, TraceCounters};
use crate::bvh::BoxTest;
use crate::hit::SurfacePoint;
use crate::lights::{LightPoint, LightSample};
use crate::materials::{Bsdf, Lobe, Material, VertexKind};
use crate::ray::Ray;
use crate::record::{ChainRecord, ConnectionRecord, TrianglePoint, VertexRecord};
use crate::scene::{ObjectId, Scene};

/// Most dielectric interfaces a chain crosses (and most crossings a seed
/// counts).
pub(super) const MAX_INTERFACES: usize = 8;
/// Newton converges when the shot lands within this fraction of `|y − x|` of `y`.
pub(super) const TOLERANCE: f32 = 2e-6;
/// Newton iterations before a seed counts as a miss.
const MAX_ITERATIONS: usize = 12;
/// Halvings of a Newton step before the seed counts as a miss.
const HALVINGS: usize = 6;
/// The residual must fall at least to this fraction of its value per step.
const PROGRESS: f64 = 0.99;
/// Step of the central differences of the Jacobian, in tangent units of the
/// unit direction (radians, to first order).
const FD_STEP: f32 = 1e-3;
/// `1 − cos` of the largest angle between a BSDF-sampled direction and the
/// chain's for both to be the same path (about 4.5 mrad): far above what
/// Newton's tolerance leaves, far below the angle between distinct chains.
const SAME_DIRECTION: f32 = 1e-5;

/// A non-delta vertex that made manifold next-event estimation, and the
/// direction its BSDF sample left along.
#[derive(Clone, Copy, Debug)]
pub(super) struct ChainOrigin {
    /// The vertex.
    pub(super) sp: SurfacePoint,
    /// Cosine of its incoming direction with its geometric normal.
    pub(super) wi_ng: f32,
    /// The unit world direction sampled there.
    pub(super) dir: Vec3,
    /// The most refractions its connections took (the depth limit's).
    pub(super) interfaces: usize,
}

/// Where a path stands with respect to the paths manifold next-event
/// estimation covers: a non-delta vertex that made it, then dielectric
/// refractions only.
#[derive(Clone, Copy, Debug)]
pub(super) enum ChainState {
    /// Not on such a path.
    Outside,
    /// After such a vertex, through this many refractions (0: the vertex
    /// itself scattered last).
    Refracting(ChainOrigin, usize),
}

impl ChainState {
    /// The state after a vertex of `material` scattered by `lobe`; `origin`
    /// when the vertex made manifold next-event estimation.
    #[inline(always)]
    pub(super) fn after(
        self,
        material: &Material,
        lobe: Lobe,
        origin: Option<ChainOrigin>,
    ) -> Self {
        match (origin, self) {
            (Some(o), _) => Self::Refracting(o, 0),
            (None, Self::Refracting(o, k))
                if lobe == Lobe::SpecularTransmission
                    && matches!(material.bsdf, Bsdf::Dielectric(_)) =>
            {
                Self::Refracting(o, k + 1)
            }
            _ => Self::Outside,
        }
    }

    /// Whether an emitter hit now (at `sp` on `object`) is the path manifold
    /// next-event estimation counted at the origin, so BSDF sampling adds no
    /// emission for it.
    #[inline(always)]
    pub(super) fn counted(
        &self,
        scene: &Scene,
        sp: &SurfacePoint,
        object: ObjectId,
        boxes: impl BoxTest,
    ) -> bool {
        match self {
            Self::Refracting(o, k) if *k > 0 => covers(
                scene,
                &o.sp,
                o.wi_ng,
                o.dir,
                *k,
                sp.p,
                sp.ng,
                object,
                o.interfaces,
                boxes,
            ),
            _ => false,
        }
    }
}

/// One refraction of a shot chain.
#[derive(Clone, Copy, Debug)]
struct Interface {
    sp: SurfacePoint,
    at: TrianglePoint,
    /// The transmission lobe's `pdf · weight`: `(1 − F)/η²`.
    factor: f32,
    /// `η(wo side)/η(wi side)`.
    eta: f32,
}

/// A shot: the interfaces crossed and where the last ray meets the plane.
struct Shot {
    interfaces: [Option<Interface>; MAX_INTERFACES],
    /// The last ray (leaving the last interface).
    last: Ray,
    /// Where it meets the light's tangent plane.
    end: Vec3,
}

/// The light's tangent plane at the sampled point: origin and two unit
/// tangents, and the normal.
struct Plane {
    y: Vec3,
    u: Vec3,
    v: Vec3,
    n: Vec3,
}

impl Plane {
    fn coords(&self, p: Vec3) -> DVec2 {
        let d = p - self.y;
        DVec2::new(d.dot(self.u) as f64, d.dot(self.v) as f64)
    }
}

/// Counts the dielectric surfaces the segment from `sp` to `y` crosses
/// (passing through any other surface), up to [`MAX_INTERFACES`] + 1; `wo_ng`
/// is the segment direction's cosine with `sp`'s geometric normal.
fn seed_interfaces(
    scene: &Scene,
    sp: &SurfacePoint,
    wo_ng: f32,
    y: Vec3,
    boxes: impl BoxTest,
) -> usize {
    let mut origin = leaving_origin(sp, wo_ng);
    let mut k = 0;
    for _ in 0..2 * MAX_INTERFACES + 2 {
        let ray = Ray {
            origin,
            dir: y - origin,
            t_min: 0.0,
            t_max: 1.0 - super::SHADOW_EPS,
        };
        let Some(hit) = scene.accel().closest_hit_with(&ray, boxes) else {
            return k;
        };
        let object = &scene.objects()[hit.object as usize];
        if matches!(
            scene.materials()[object.material as usize].bsdf,
            Bsdf::Dielectric(_)
        ) {
            k += 1;
            if k > MAX_INTERFACES {
                return k;
            }
        }
        let hp = scene.accel().surface_point(scene.objects(), &hit);
        origin = leaving_origin(&hp, ray.dir.dot(hp.ng));
    }
    MAX_INTERFACES + 1
}

/// Shoots `dir` (unit) from `sp` through `k` dielectric refractions and onto
/// `plane`; `None` when a ray misses, meets something else first, reflects
/// totally, or leaves on the wrong side.
fn shoot(
    scene: &Scene,
    sp: &SurfacePoint,
    dir: Vec3,
    k: usize,
    plane: &Plane,
    boxes: impl BoxTest,
) -> Option<Shot> {
    let mut ray = Ray::new(leaving_origin(sp, dir.dot(sp.ng)), dir);
    let mut interfaces = [None; MAX_INTERFACES];
    for slot in interfaces.iter_mut().take(k) {
        let hit = scene.accel().closest_hit_with(&ray, boxes)?;
        let object = &scene.objects()[hit.object as usize];
        let material = &scene.materials()[object.material as usize];
        if !matches!(material.bsdf, Bsdf::Dielectric(_)) {
            return None;
        }
        let hp = scene.accel().surface_point(scene.objects(), &hit);
        let wi_world = -ray.dir;
        let wi = material.to_local(&hp.frame, wi_world);
        // `u_lobe = 1`: the transmission lobe unless reflection is total.
        let bs = material.sample(wi, hp.uv, 1.0, glam::Vec2::ZERO)?;
        if bs.lobe != Lobe::SpecularTransmission {
            return None;
        }
        let wo_world = hp.frame.to_world(bs.wo);
        let wo_ng = wo_world.dot(hp.ng);
        if wo_ng * wi_world.dot(hp.ng) >= 0.0 {
            return None;
        }
        *slot = Some(Interface {
            sp: hp,
            at: TrianglePoint::from(&hit),
            factor: bs.pdf * bs.weight.x,
            eta: bs.eta,
        });
        ray = Ray::new(leaving_origin(&hp, wo_ng), wo_world);
    }
    let denom = ray.dir.dot(plane.n);
    if denom.abs() < 1e-12 {
        return None;
    }
    let t = (plane.y - ray.origin).dot(plane.n) / denom;
    (t > 0.0).then(|| Shot {
        interfaces,
        last: ray,
        end: ray.origin + ray.dir * t,
    })
}

/// The residual of `dir` in the plane's coordinates.
fn residual(
    scene: &Scene,
    sp: &SurfacePoint,
    dir: Vec3,
    k: usize,
    plane: &Plane,
    boxes: impl BoxTest,
) -> Option<DVec2> {
    shoot(scene, sp, dir, k, plane, boxes).map(|s| plane.coords(s.end))
}

/// `∂(plane coordinates)/∂(a, b)` at `dir = normalize(dir + a·s + b·t)`
/// with the tangents `(s, t)` of `dir`, as columns: by forward differences
/// from the residual `r0` at `dir` (Newton's steps), or by central ones
/// (`central`: the geometry term of the solution).
#[allow(clippy::too_many_arguments)] // the shot's inputs, the difference kind
fn jacobian(
    scene: &Scene,
    sp: &SurfacePoint,
    dir: Vec3,
    k: usize,
    plane: &Plane,
    r0: DVec2,
    central: bool,
    boxes: impl BoxTest,
) -> Option<(DVec2, DVec2, Vec3, Vec3)> {
    let f = crate::frame::Frame::from_normal(dir);
    let at = |d: Vec3| residual(scene, sp, d.normalize(), k, plane, boxes);
    let h = FD_STEP;
    let column = |t: Vec3| -> Option<DVec2> {
        if central {
            Some((at(dir + t * h)? - at(dir - t * h)?) / (2.0 * h as f64))
        } else {
            Some((at(dir + t * h)? - r0) / h as f64)
        }
    };
    Some((column(f.s)?, column(f.t)?, f.s, f.t))
}

/// Solves for the chain from `sp`, starting along the unit `seed` toward the
/// light point at distance `dist`, through `k` dielectric interfaces.
/// Returns the unit direction at `sp`, the Jacobian's determinant (area at
/// `y` per solid angle at `x`) and the shot along that direction, or `None`
/// (a miss).
#[allow(clippy::too_many_arguments)] // the vertex, the seed, the plane, the box test
fn solve(
    scene: &Scene,
    sp: &SurfacePoint,
    seed: Vec3,
    dist: f32,
    k: usize,
    plane: &Plane,
    boxes: impl BoxTest,
) -> Option<(Vec3, f64, Shot)> {
    let tol = f64::from(TOLERANCE * dist);
    let mut dir = seed;
    let mut shot = shoot(scene, sp, dir, k, plane, boxes)?;
    let mut r = plane.coords(shot.end);
    for _ in 0..MAX_ITERATIONS {
        let converged = r.length() < tol;
        let (ja, jb, s, t) = jacobian(scene, sp, dir, k, plane, r, converged, boxes)?;
        let det = ja.x * jb.y - jb.x * ja.y;
        if converged {
            return (det.is_finite() && det != 0.0).then_some((dir, det.abs(), shot));
        }
        if !det.is_finite() || det == 0.0 {
            return None;
        }
        // δ = −J⁻¹ r.
        let da = -(jb.y * r.x - jb.x * r.y) / det;
        let db = -(-ja.y * r.x + ja.x * r.y) / det;
        // The step, halved until the residual falls to at most
        // `PROGRESS` of its value (a seed without a chain stops here).
        let mut scale = 1.0;
        let mut stepped = None;
        for _ in 0..HALVINGS {
            let d = (dir + s * (da * scale) as f32 + t * (db * scale) as f32).normalize();
            if let Some(sn) = shoot(scene, sp, d, k, plane, boxes) {
                let rn = plane.coords(sn.end);
                if rn.length() < PROGRESS * r.length() {
                    stepped = Some((d, sn, rn));
                    break;
                }
            }
            scale *= 0.5;
        }
        (dir, shot, r) = stepped?;
    }
    None
}

/// A chain found from a vertex to a light point.
struct Found {
    /// Unit direction at the vertex.
    dir: Vec3,
    /// `|det ∂y/∂ω|`: area at the light point per solid angle at the vertex.
    det: f64,
    /// The refractions and the last ray.
    shot: Shot,
    /// Where the last ray meets the light, and the point there.
    hit: crate::hit::Hit,
    light: SurfacePoint,
}

impl Found {
    fn interfaces(&self) -> impl Iterator<Item = &Interface> {
        self.shot.interfaces.iter().flatten()
    }
}

/// The chain from the surface point `sp` (whose incoming direction has
/// cosine `wi_ng` with its geometric normal) to the point `y` of the light
/// `object`, with normal `n_y`, through the `k ≤ max_interfaces` dielectric
/// surfaces the segment `sp → y` crosses (seeded by that segment):
/// `Ok(None)` when it crosses none (next-event estimation counts the light,
/// or an opaque surface blocks it) or too many, `Err(())` when seeded but not
/// found. A function of `(sp, y)` alone, so that BSDF sampling can tell
/// whether a path it found is this one ([`covers`]).
#[allow(clippy::too_many_arguments)] // the vertex, the light point, the box test
fn connect(
    scene: &Scene,
    sp: &SurfacePoint,
    wi_ng: f32,
    y: Vec3,
    n_y: Vec3,
    object: ObjectId,
    max_interfaces: usize,
    boxes: impl BoxTest,
) -> Result<Option<Found>, ()> {
    let to_y = y - sp.p;
    let dist = to_y.length();
    let Some(seed) = to_y.try_normalize() else {
        return Ok(None);
    };
    let k = seed_interfaces(scene, sp, seed.dot(sp.ng), y, boxes);
    if k == 0 || k > max_interfaces.min(MAX_INTERFACES) {
        return Ok(None);
    }
    let f = crate::frame::Frame::from_normal(n_y);
    let plane = Plane {
        y,
        u: f.s,
        v: f.t,
        n: n_y,
    };
    solve_chain(scene, sp, wi_ng, seed, dist, k, &plane, object, boxes)
        .map(Some)
        .ok_or(())
}

/// One chain from `seed`, checked: it leaves on the side `wi_ng` says and
/// its last segment reaches the front face of the light `object`.
#[allow(clippy::too_many_arguments)] // the vertex, the seed, the light, the box test
fn solve_chain(
    scene: &Scene,
    sp: &SurfacePoint,
    wi_ng: f32,
    seed: Vec3,
    dist: f32,
    k: usize,
    plane: &Plane,
    object: ObjectId,
    boxes: impl BoxTest,
) -> Option<Found> {
    let (dir, det, shot) = solve(scene, sp, seed, dist, k, plane, boxes)?;
    if dir.dot(sp.ng) * wi_ng <= 0.0 {
        return None;
    }
    let hit = scene.accel().closest_hit_with(&shot.last, boxes)?;
    let light = scene.accel().surface_point(scene.objects(), &hit);
    if hit.object != object || shot.last.dir.dot(light.ng) >= 0.0 {
        return None;
    }
    Some(Found {
        dir,
        det,
        shot,
        hit,
        light,
    })
}

/// Whether the chain [`connect`] finds from `sp` to the emitter
/// point `y` (normal `n_y`, on `object`) leaves `sp` along `dir` through `k`
/// refractions: then manifold next-event estimation at `sp` counted the
/// path BSDF sampling found along `dir`, and BSDF sampling adds nothing.
#[allow(clippy::too_many_arguments)] // the vertex, the path found, the box test
pub(super) fn covers(
    scene: &Scene,
    sp: &SurfacePoint,
    wi_ng: f32,
    dir: Vec3,
    k: usize,
    y: Vec3,
    n_y: Vec3,
    object: ObjectId,
    max_interfaces: usize,
    boxes: impl BoxTest,
) -> bool {
    matches!(
        connect(scene, sp, wi_ng, y, n_y, object, max_interfaces, boxes),
        Ok(Some(c)) if c.interfaces().count() == k && c.dir.dot(dir) > 1.0 - SAME_DIRECTION
    )
}

/// Manifold next-event estimation at the shading point `at` toward the
/// light point of `ls` (sampled by next-event estimation, whose straight
/// shadow ray was blocked), through at most `max_interfaces` dielectric
/// refractions. Returns the radiance added (`beta` included) and, when
/// recording at vertex `record_at`, the chain's record.
#[allow(clippy::too_many_arguments)] // the vertex, the light sample, what observes it
pub(super) fn chain_event(
    scene: &Scene,
    at: &Shading<'_>,
    beta: Vec3,
    ls: &LightSample,
    max_interfaces: usize,
    record_at: Option<u32>,
    counters: &mut TraceCounters,
    sink: &mut impl RaySink,
    boxes: impl BoxTest,
) -> Option<(Vec3, Option<ChainRecord>)> {
    let LightPoint::Area { object: light, .. } = ls.source else {
        return None;
    };
    if ls.delta || !ls.dist.is_finite() || ls.pdf <= 0.0 {
        return None;
    }
    let sp = at.sp;
    let c = match connect(
        scene,
        sp,
        at.wi_ng,
        ls.position,
        ls.normal,
        light,
        max_interfaces,
        boxes,
    ) {
        Ok(found) => found?,
        Err(()) => {
            counters.chain_misses += 1;
            return None;
        }
    };
    let le = scene.objects()[light as usize].emission?;
    // The light sample's area density (selection included).
    let cos_y = ls.normal.dot(ls.wo).abs();
    let p_area = ls.pdf * cos_y / (ls.dist * ls.dist);
    counters.rays += 1;
    sink.closest(1, &c.shot.last);
    let f_x = at
        .material
        .eval(at.wi, at.material.to_local(&sp.frame, c.dir), sp.uv);
    let transmittance: f32 = c.interfaces().map(|i| i.factor).product();
    let contribution = beta * f_x * le * (transmittance / (p_area * c.det as f32));
    if !contribution.is_finite() {
        counters.chain_misses += 1;
        return None;
    }
    counters.chains += 1;
    let record = record_at.map(|vertex| record(&c, vertex, beta * f_x, contribution));
    Some((contribution, record))
}

/// The record of chain `c` made at vertex `vertex`, arriving with
/// `throughput` and adding `contribution`.
fn record(c: &Found, vertex: u32, mut throughput: Vec3, contribution: Vec3) -> ChainRecord {
    let specular = c
        .interfaces()
        .map(|i| {
            let v = VertexRecord {
                at: i.at,
                p: i.sp.p,
                ng: i.sp.ng,
                ns: i.sp.ns(),
                kind: VertexKind::Specular,
                lobe: Some(Lobe::SpecularTransmission),
                eta: i.eta,
                m: i.sp.ns(),
                throughput,
                contribution: Vec3::ZERO,
            };
            throughput *= i.factor;
            v
        })
        .collect();
    ChainRecord {
        connection: ConnectionRecord {
            vertex,
            light: LightPoint::Area {
                object: c.hit.object,
                triangle: c.hit.triangle,
                b1: c.hit.b1,
                b2: c.hit.b2,
            },
            light_position: c.light.p,
            light_normal: c.light.ng,
            contribution,
            unoccluded: contribution,
            occluder: None,
            dropped: None,
        },
        specular,
    }
}
