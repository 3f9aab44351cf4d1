//! Every lane of the wide walks and shading points against the scalar
//! functions, bit for bit, on random scenes (module `random`), on every
//! backend the CPU has (the portable one always). The shipped scenes are
//! checked from outside the crate, where their loader is (`tests/wide.rs`:
//! their images per backend, and the batch walks on their rays).
//!
//! A lane's closest hit may differ from the scalar one only by a tie: both
//! hits on different primitives at the same `t` to within a few ULPs
//! (module docs of `wide`). Ties are counted, and the tests bound them.

mod random;

use super::Hits16;
use super::Rays16;
use super::walk::Policy;
use crate::bvh::Accel;
use crate::hit::{Hit, SurfacePoint, TexCoords};
use crate::ray::Ray;
use crate::scene::Object;
use crate::simd::{F32x16, LANES, Lanes, Mask16, Vec3x16};
use glam::Vec3;

/// What a comparison saw.
#[derive(Clone, Copy, Debug, Default)]
struct Tally {
    /// Active lanes compared.
    rays: usize,
    /// Lanes with a closest hit.
    hits: usize,
    /// Lanes whose closest hit is an exact sphere.
    sphere_hits: usize,
    /// Lanes occluded.
    occluded: usize,
    /// Lanes whose closest hit differs from the scalar one by a tie (with
    /// any policy).
    ties: usize,
    /// Shading points compared.
    points: usize,
}

/// The rays as lanes.
fn packet<B: Lanes>(k: B, rays: &[Ray; LANES]) -> Rays16<B> {
    Rays16 {
        origin: Vec3x16::from_lanes(k, &rays.map(|r| r.origin)),
        dir: Vec3x16::from_lanes(k, &rays.map(|r| r.dir)),
        t_min: F32x16::from_array(k, rays.map(|r| r.t_min)),
        t_max: F32x16::from_array(k, rays.map(|r| r.t_max)),
    }
}

/// Bit patterns of a hit's fields.
fn hit_bits(h: &Hit) -> (u32, u32, u32, u32, u32, u32) {
    let bits = (h.b1.to_bits(), h.b2.to_bits(), h.t.to_bits());
    (h.object, h.triangle, bits.0, bits.1, bits.2, h.world_index)
}

/// Whether the hits are the same, or a tie: both on different primitives
/// at `t` within four ULPs.
fn same_or_tie(wide: &Option<Hit>, scalar: &Option<Hit>) -> Result<bool, ()> {
    match (wide, scalar) {
        (None, None) => Ok(false),
        (Some(w), Some(s)) if hit_bits(w) == hit_bits(s) => Ok(false),
        (Some(w), Some(s)) => {
            let apart = (w.t - s.t).abs() <= 4.0 * f32::EPSILON * w.t.abs().max(s.t.abs());
            let other = (w.object, w.triangle) != (s.object, s.triangle);
            if apart && other { Ok(true) } else { Err(()) }
        }
        _ => Err(()),
    }
}

/// Bit patterns of a shading point's fields.
fn point_bits(p: &SurfacePoint) -> Vec<u32> {
    let uv = match p.uv {
        TexCoords::Uv(uv) => [0.0, uv.x, uv.y, 0.0],
        TexCoords::Sphere(v) => [1.0, v.x, v.y, v.z],
    };
    let vectors: [Vec3; 5] = [p.p, p.ng, p.frame.s, p.frame.t, p.frame.n];
    vectors
        .iter()
        .flat_map(|v| v.to_array())
        .chain(uv)
        .map(f32::to_bits)
        .collect()
}

/// Compares the lanes `active` of the wide closest hits, occlusion and
/// shading points of `rays`, with the static BVH walked by each
/// [`Policy`], with the scalar functions; panics on a difference other
/// than a tie, and returns the lanes with a tie.
fn compare<B: Lanes>(
    k: B,
    accel: &Accel,
    objects: &[Object],
    rays: &[Ray; LANES],
    active: Mask16,
    tally: &mut Tally,
) -> Mask16 {
    let mut ties = Mask16::NONE;
    let lanes = packet(k, rays);
    let scalar = rays.map(|ray| (accel.closest_hit(&ray), accel.occluded(&ray)));
    for policy in POLICIES {
        let hits = accel.closest_hits16_by(k, &lanes, active, policy);
        let occluded = accel.occluded16_by(k, &lanes, active, policy);
        for (i, ray) in rays.iter().enumerate() {
            if !active.test(i) {
                assert!(
                    !hits.found.test(i) && !occluded.test(i),
                    "inactive lane {i}"
                );
                continue;
            }
            let (wide, (closest, occludes)) = (hits.lane(i), scalar[i]);
            let tie = same_or_tie(&wide, &closest).unwrap_or_else(|()| {
                panic!("{policy:?} lane {i} {ray:?}: wide {wide:?}, scalar {closest:?}")
            });
            assert_eq!(occluded.test(i), occludes, "{policy:?} lane {i} {ray:?}");
            ties.0 |= u16::from(tie) << i;
        }
        if policy == Policy::MEASURED {
            compare_points(k, accel, objects, &hits, tally);
        }
    }
    for (i, (closest, occludes)) in scalar.iter().enumerate() {
        if active.test(i) {
            tally.rays += 1;
            tally.ties += usize::from(ties.test(i));
            tally.hits += usize::from(closest.is_some());
            tally.occluded += usize::from(*occludes);
            let on_sphere = closest.is_some_and(|h| {
                objects[h.object as usize].surface == crate::scene::Surface::Sphere
            });
            tally.sphere_hits += usize::from(on_sphere);
        }
    }
    ties
}

/// The walks compared: the measured one, and each way forced.
const POLICIES: [Policy; 4] = [
    Policy::MEASURED,
    Policy::TRIANGLES,
    Policy::ROUNDS,
    Policy::HALF_SCALAR,
];

/// Compares every found lane of the wide shading points of `hits` with the
/// scalar ones, and again with some static hits' shading-table index
/// pointing at another triangle (a stale index: the scalar code then
/// computes the point from the object).
fn compare_points<B: Lanes>(
    k: B,
    accel: &Accel,
    objects: &[Object],
    hits: &Hits16<B>,
    tally: &mut Tally,
) {
    let lanes: [Option<Hit>; LANES] = std::array::from_fn(|i| hits.lane(i));
    let stale = lanes.map(|h| {
        h.map(|mut h| {
            if h.world_index != u32::MAX && h.triangle % 3 == 0 {
                h.world_index = h.world_index.wrapping_add(1 + h.triangle % 5);
            }
            h
        })
    });
    for lanes in [lanes, stale] {
        let points = accel.surface_points16(k, objects, &Hits16::from_lanes(k, &lanes));
        for (i, hit) in lanes.iter().enumerate() {
            if let Some(hit) = hit {
                let scalar = accel.surface_point(objects, hit);
                let wide = points.lane(i);
                assert_eq!(
                    point_bits(&wide),
                    point_bits(&scalar),
                    "lane {i} {hit:?}: wide {wide:?}, scalar {scalar:?}"
                );
                tally.points += 1;
            }
        }
    }
}
