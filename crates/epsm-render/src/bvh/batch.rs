//! Many rays or hits at once: [`Accel::closest_hits`],
//! [`Accel::occluded_rays`] and [`Accel::surface_points`], sixteen at a
//! time by the wide functions (module `wide`) where the CPU has AVX-512 or
//! AVX2 (detected at run time), else one at a time by the scalar ones
//! ([`Accel::closest_hit`], [`Accel::occluded`], [`Accel::surface_point`]).
//!
//! Model: the answers are the scalar walks' for every ray (the wide walks
//! round every test as the scalar ones do), except that where two
//! primitives are hit at the same `t` either may be reported (module
//! `wide`); the shading points are the scalar ones bit for bit. Rays are
//! taken in order, sixteen to a packet (the last packet with the lanes it
//! has), so rays cast together, as a camera's or a render's, share their
//! packets' walks.
//!
//! No parameters.

use super::Accel;
use crate::hit::{Hit, SurfacePoint};
use crate::ray::Ray;
use crate::scene::Object;
#[cfg(target_arch = "x86_64")]
use {
    super::{Hits16, Rays16},
    crate::frame::Frame,
    crate::hit::TexCoords,
    crate::simd::{Backend, F32x16, LANES, Lanes, Mask16, Vec3x16, WithLanes},
    glam::{Vec2, Vec3},
};

impl Accel {
    /// The closest hit of each ray (as [`Accel::closest_hit`]), sixteen at
    /// a time where the CPU has vector lanes ([`Accel::batches_wide`]).
    pub fn closest_hits(&self, rays: &[Ray]) -> Vec<Option<Hit>> {
        #[cfg(target_arch = "x86_64")]
        if let Some(b) = Backend::fastest() {
            return b.call(Closest { accel: self, rays });
        }
        rays.iter().map(|ray| self.closest_hit(ray)).collect()
    }

    /// Whether each ray is occluded (as [`Accel::occluded`]), sixteen at a
    /// time where the CPU has vector lanes ([`Accel::batches_wide`]).
    pub fn occluded_rays(&self, rays: &[Ray]) -> Vec<bool> {
        #[cfg(target_arch = "x86_64")]
        if let Some(b) = Backend::fastest() {
            return b.call(Occluded { accel: self, rays });
        }
        rays.iter().map(|ray| self.occluded(ray)).collect()
    }

    /// The shading point of each hit (as [`Accel::surface_point`]; `objects`
    /// the scene's, as the hits were traced), sixteen at a time where the
    /// CPU has vector lanes ([`Accel::batches_wide`]).
    pub fn surface_points(&self, objects: &[Object], hits: &[Hit]) -> Vec<SurfacePoint> {
        #[cfg(target_arch = "x86_64")]
        if let Some(b) = Backend::fastest() {
            return b.call(Points {
                accel: self,
                objects,
                hits,
            });
        }
        hits.iter()
            .map(|hit| self.surface_point(objects, hit))
            .collect()
    }

    /// Whether [`Accel::closest_hits`], [`Accel::occluded_rays`] and
    /// [`Accel::surface_points`] work sixteen at a time on this CPU (it has
    /// AVX-512 or AVX2).
    pub fn batches_wide() -> bool {
        #[cfg(target_arch = "x86_64")]
        return Backend::fastest().is_some();
        #[cfg(not(target_arch = "x86_64"))]
        false
    }
}

/// [`Accel::closest_hits`] with the wide walk.
#[cfg(target_arch = "x86_64")]
struct Closest<'a> {
    accel: &'a Accel,
    rays: &'a [Ray],
}

#[cfg(target_arch = "x86_64")]
impl WithLanes for Closest<'_> {
    type Output = Vec<Option<Hit>>;
    #[inline(always)]
    fn call<B: Lanes>(self, k: B) -> Self::Output {
        let mut out = Vec::with_capacity(self.rays.len());
        for chunk in self.rays.chunks(LANES) {
            let (lanes, active) = packet(k, chunk);
            let hits = self.accel.closest_hits16(k, &lanes, active).to_lanes();
            out.extend_from_slice(&hits[..chunk.len()]);
        }
        out
    }
}

/// [`Accel::occluded_rays`] with the wide walk.
#[cfg(target_arch = "x86_64")]
struct Occluded<'a> {
    accel: &'a Accel,
    rays: &'a [Ray],
}

#[cfg(target_arch = "x86_64")]
impl WithLanes for Occluded<'_> {
    type Output = Vec<bool>;
    #[inline(always)]
    fn call<B: Lanes>(self, k: B) -> Self::Output {
        let mut out = Vec::with_capacity(self.rays.len());
        for chunk in self.rays.chunks(LANES) {
            let (lanes, active) = packet(k, chunk);
            let occluded = self.accel.occluded16(k, &lanes, active);
            out.extend((0..chunk.len()).map(|i| occluded.test(i)));
        }
        out
    }
}

/// [`Accel::surface_points`] with the wide points.
#[cfg(target_arch = "x86_64")]
struct Points<'a> {
    accel: &'a Accel,
    objects: &'a [Object],
    hits: &'a [Hit],
}

#[cfg(target_arch = "x86_64")]
impl WithLanes for Points<'_> {
    type Output = Vec<SurfacePoint>;
    #[inline(always)]
    fn call<B: Lanes>(self, k: B) -> Self::Output {
        let mut out = Vec::with_capacity(self.hits.len());
        points(self.accel, k, self.objects, self.hits, &mut out);
        out
    }
}

/// [`Accel::surface_points`] with the wide points, appending to `out`.
#[cfg(target_arch = "x86_64")]
#[inline(always)]
fn points<B: Lanes>(
    accel: &Accel,
    k: B,
    objects: &[Object],
    hits: &[Hit],
    out: &mut Vec<SurfacePoint>,
) {
    for chunk in hits.chunks(LANES) {
        let points = accel.surface_points16(k, objects, &hit_packet(k, chunk));
        // By field: p, ng, frame s, t, n (x, y, z each), then texture
        // coordinates.
        let vectors = [
            points.p,
            points.ng,
            points.frame.s,
            points.frame.t,
            points.frame.n,
        ];
        let mut fields = [[0.0f32; LANES]; 18];
        for (i, v) in vectors.iter().enumerate() {
            (fields[3 * i], fields[3 * i + 1], fields[3 * i + 2]) =
                (v.x.to_array(), v.y.to_array(), v.z.to_array());
        }
        let uv = &points.uv.a;
        (fields[15], fields[16], fields[17]) = (uv.x.to_array(), uv.y.to_array(), uv.z.to_array());
        out.extend((0..chunk.len()).map(|i| {
            let v = |f: usize| Vec3::new(fields[f][i], fields[f + 1][i], fields[f + 2][i]);
            SurfacePoint {
                p: v(0),
                ng: v(3),
                uv: if points.uv.sphere.test(i) {
                    TexCoords::Sphere(v(15))
                } else {
                    TexCoords::Uv(Vec2::new(fields[15][i], fields[16][i]))
                },
                frame: Frame {
                    s: v(6),
                    t: v(9),
                    n: v(12),
                },
            }
        }));
    }
}

/// The hits of `chunk` (one to sixteen) as lanes, the unused lanes not
/// found.
#[cfg(target_arch = "x86_64")]
#[inline(always)]
fn hit_packet<B: Lanes>(k: B, chunk: &[Hit]) -> Hits16<B> {
    let mut hits = [None; LANES];
    for (lane, hit) in hits.iter_mut().zip(chunk) {
        *lane = Some(*hit);
    }
    Hits16::from_lanes(k, &hits)
}

/// The rays of `chunk` (one to sixteen) as lanes, the unused lanes copies
/// of the first, and the mask of the used ones.
#[cfg(target_arch = "x86_64")]
#[inline(always)]
fn packet<B: Lanes>(k: B, chunk: &[Ray]) -> (Rays16<B>, Mask16) {
    // By field: origin x, y, z, direction x, y, z, t_min, t_max.
    let mut fields = [[0.0f32; LANES]; 8];
    for lane in 0..LANES {
        let ray = chunk.get(lane).unwrap_or(&chunk[0]);
        let values = [
            ray.origin.x,
            ray.origin.y,
            ray.origin.z,
            ray.dir.x,
            ray.dir.y,
            ray.dir.z,
            ray.t_min,
            ray.t_max,
        ];
        for (field, value) in fields.iter_mut().zip(values) {
            field[lane] = value;
        }
    }
    let [ox, oy, oz, dx, dy, dz, t_min, t_max] = fields;
    let rays = Rays16 {
        origin: Vec3x16::new(
            F32x16::from_array(k, ox),
            F32x16::from_array(k, oy),
            F32x16::from_array(k, oz),
        ),
        dir: Vec3x16::new(
            F32x16::from_array(k, dx),
            F32x16::from_array(k, dy),
            F32x16::from_array(k, dz),
        ),
        t_min: F32x16::from_array(k, t_min),
        t_max: F32x16::from_array(k, t_max),
    };
    (rays, Mask16::first(chunk.len()))
}
