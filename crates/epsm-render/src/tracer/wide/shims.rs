//! TEMPORARY per-lane fallbacks standing in for the wide walks, materials and
//! lights until those land: each calls the scalar function per active lane.

use glam::{Vec2, Vec3};

use crate::bvh::Accel;
use crate::hit::{Hits16, SurfacePoint, SurfacePoints16};
use crate::ray::Rays16;
use crate::scene::Object;
use crate::simd::{Avx512, LANES, Mask16};

pub(super) fn closest_hits16(accel: &Accel, k: Avx512, rays: &Rays16, active: Mask16) -> Hits16 {
    let mut hits = [None; LANES];
    for lane in active.lanes() {
        hits[lane] = accel.closest_hit(&rays.lane(lane));
    }
    Hits16::from_lanes(k, &hits)
}

pub(super) fn occluded16(accel: &Accel, rays: &Rays16, active: Mask16) -> Mask16 {
    let mut m = Mask16::NONE;
    for lane in active.lanes() {
        m.0 |= u16::from(accel.occluded(&rays.lane(lane))) << lane;
    }
    m
}

pub(super) fn surface_points16(
    accel: &Accel,
    k: Avx512,
    objects: &[Object],
    hits: &Hits16,
) -> SurfacePoints16 {
    let mut points = [SurfacePoint {
        p: Vec3::ZERO,
        ng: Vec3::Z,
        uv: Vec2::ZERO.into(),
        frame: crate::Frame::from_normal(Vec3::Z),
    }; LANES];
    for lane in hits.found.lanes() {
        points[lane] = accel.surface_point(objects, &hits.lane(lane).expect("found"));
    }
    SurfacePoints16::from_lanes(k, &points)
}
