//! TEMPORARY per-lane fallbacks standing in for the wide walks, materials and
//! lights until those land: each calls the scalar function per active lane.

use glam::{Vec2, Vec3};

use crate::bvh::Accel;
use crate::frame::Frames16;
use crate::hit::{Hits16, SurfacePoint, SurfacePoints16, TexCoords16};
use crate::materials::Material;
use crate::ray::Rays16;
use crate::scene::Object;
use crate::simd::{Avx512, F32x16, LANES, Mask16, U32x16, Vec3x16};

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

pub(super) struct BsdfSamples16 {
    pub found: Mask16,
    pub wo: Vec3x16,
    pub weight: Vec3x16,
    pub pdf: F32x16,
    pub eta: F32x16,
    pub delta: Mask16,
    pub transmission: Mask16,
}

pub(super) struct Materials16<'a> {
    pub materials: &'a [Material],
}

impl Materials16<'_> {
    pub fn to_local16(
        &self,
        k: Avx512,
        material: U32x16,
        frame: &Frames16,
        v: Vec3x16,
        active: Mask16,
    ) -> Vec3x16 {
        let mut out = [Vec3::ZERO; LANES];
        for lane in active.lanes() {
            let m = &self.materials[material.lane(lane) as usize];
            out[lane] = m.to_local(&frame.lane(lane), v.lane(lane));
        }
        Vec3x16::from_lanes(k, &out)
    }

    pub fn is_delta16(&self, material: U32x16, active: Mask16) -> Mask16 {
        let mut m = Mask16::NONE;
        for lane in active.lanes() {
            m.0 |= u16::from(self.materials[material.lane(lane) as usize].is_delta()) << lane;
        }
        m
    }

    #[allow(clippy::too_many_arguments)]
    pub fn sample16(
        &self,
        k: Avx512,
        material: U32x16,
        wi: Vec3x16,
        uv: &TexCoords16,
        u_lobe: F32x16,
        u: [F32x16; 2],
        active: Mask16,
    ) -> BsdfSamples16 {
        let (mut wo, mut weight, mut pdf, mut eta) = (
            [Vec3::ZERO; LANES],
            [Vec3::ZERO; LANES],
            [0.0; LANES],
            [1.0; LANES],
        );
        let (mut found, mut delta, mut transmission) = (Mask16::NONE, Mask16::NONE, Mask16::NONE);
        for lane in active.lanes() {
            let m = &self.materials[material.lane(lane) as usize];
            let Some(s) = m.sample(
                wi.lane(lane),
                uv.lane(lane),
                u_lobe.lane(lane),
                Vec2::new(u[0].lane(lane), u[1].lane(lane)),
            ) else {
                continue;
            };
            found.0 |= 1 << lane;
            delta.0 |= u16::from(s.lobe.is_delta()) << lane;
            transmission.0 |= u16::from(s.lobe.is_transmission()) << lane;
            (wo[lane], weight[lane], pdf[lane], eta[lane]) = (s.wo, s.weight, s.pdf, s.eta);
        }
        BsdfSamples16 {
            found,
            wo: Vec3x16::from_lanes(k, &wo),
            weight: Vec3x16::from_lanes(k, &weight),
            pdf: F32x16::from_array(k, pdf),
            eta: F32x16::from_array(k, eta),
            delta,
            transmission,
        }
    }

    pub fn eval16(
        &self,
        k: Avx512,
        material: U32x16,
        wi: Vec3x16,
        wo: Vec3x16,
        uv: &TexCoords16,
        active: Mask16,
    ) -> Vec3x16 {
        let mut out = [Vec3::ZERO; LANES];
        for lane in active.lanes() {
            let m = &self.materials[material.lane(lane) as usize];
            out[lane] = m.eval(wi.lane(lane), wo.lane(lane), uv.lane(lane));
        }
        Vec3x16::from_lanes(k, &out)
    }

    pub fn pdf16(
        &self,
        k: Avx512,
        material: U32x16,
        wi: Vec3x16,
        wo: Vec3x16,
        active: Mask16,
    ) -> F32x16 {
        let mut out = [0.0; LANES];
        for lane in active.lanes() {
            let m = &self.materials[material.lane(lane) as usize];
            out[lane] = m.pdf(wi.lane(lane), wo.lane(lane), Vec2::ZERO);
        }
        F32x16::from_array(k, out)
    }
}
