//! Many rays at once: [`Accel::closest_hits`] and [`Accel::occluded_rays`],
//! sixteen at a time by the wide walks (module `wide`) where the CPU has
//! AVX-512 (detected at run time), else one at a time by the scalar walks
//! ([`Accel::closest_hit`], [`Accel::occluded`]).
//!
//! Model: the answers are the scalar walks' for every ray (the wide walks
//! round every test as the scalar ones do), except that where two
//! primitives are hit at the same `t` either may be reported (module
//! `wide`). Rays are taken in order, sixteen to a packet (the last packet
//! with the lanes it has), so rays cast together, as a camera's or a
//! render's, share their packets' walks.
//!
//! No parameters.

use crate::hit::Hit;
use crate::ray::Ray;
#[cfg(target_arch = "x86_64")]
use crate::{
    ray::Rays16,
    simd::{Avx512, F32x16, LANES, Mask16, Vec3x16},
};

use super::Accel;

impl Accel {
    /// The closest hit of each ray (as [`Accel::closest_hit`]), sixteen at
    /// a time where the CPU has AVX-512 ([`Accel::batches_wide`]).
    pub fn closest_hits(&self, rays: &[Ray]) -> Vec<Option<Hit>> {
        #[cfg(target_arch = "x86_64")]
        if let Some(k) = Avx512::detect() {
            let mut out = Vec::with_capacity(rays.len());
            // SAFETY: `closest_avx512` requires only the features it
            // enables, and an `Avx512` token exists only on a CPU found to
            // have each of them.
            #[allow(unsafe_code)]
            unsafe {
                closest_avx512(self, k, rays, &mut out)
            };
            return out;
        }
        rays.iter().map(|ray| self.closest_hit(ray)).collect()
    }

    /// Whether each ray is occluded (as [`Accel::occluded`]), sixteen at a
    /// time where the CPU has AVX-512 ([`Accel::batches_wide`]).
    pub fn occluded_rays(&self, rays: &[Ray]) -> Vec<bool> {
        #[cfg(target_arch = "x86_64")]
        if let Some(k) = Avx512::detect() {
            let mut out = Vec::with_capacity(rays.len());
            // SAFETY: as in `closest_hits`.
            #[allow(unsafe_code)]
            unsafe {
                occluded_avx512(self, k, rays, &mut out)
            };
            return out;
        }
        rays.iter().map(|ray| self.occluded(ray)).collect()
    }

    /// Whether [`Accel::closest_hits`] and [`Accel::occluded_rays`] walk
    /// sixteen rays at a time on this CPU (it has AVX-512).
    pub fn batches_wide() -> bool {
        #[cfg(target_arch = "x86_64")]
        return Avx512::detect().is_some();
        #[cfg(not(target_arch = "x86_64"))]
        false
    }
}

/// [`Accel::closest_hits`] with the wide walk, appending to `out`.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f,avx512vl,avx512dq,avx512bw,avx2,bmi1,bmi2,lzcnt,popcnt")]
fn closest_avx512(accel: &Accel, k: Avx512, rays: &[Ray], out: &mut Vec<Option<Hit>>) {
    for chunk in rays.chunks(LANES) {
        let (lanes, active) = packet(k, chunk);
        let hits = accel.closest_hits16(k, &lanes, active);
        let (object, triangle) = (hits.object.to_array(), hits.triangle.to_array());
        let (b1, b2, t) = (hits.b1.to_array(), hits.b2.to_array(), hits.t.to_array());
        let world_index = hits.world_index.to_array();
        out.extend((0..chunk.len()).map(|i| {
            hits.found.test(i).then(|| Hit {
                object: object[i],
                triangle: triangle[i],
                b1: b1[i],
                b2: b2[i],
                t: t[i],
                world_index: world_index[i],
            })
        }));
    }
}

/// [`Accel::occluded_rays`] with the wide walk, appending to `out`.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f,avx512vl,avx512dq,avx512bw,avx2,bmi1,bmi2,lzcnt,popcnt")]
fn occluded_avx512(accel: &Accel, k: Avx512, rays: &[Ray], out: &mut Vec<bool>) {
    for chunk in rays.chunks(LANES) {
        let (lanes, active) = packet(k, chunk);
        let occluded = accel.occluded16(k, &lanes, active);
        out.extend((0..chunk.len()).map(|i| occluded.test(i)));
    }
}

/// The rays of `chunk` (one to sixteen) as lanes, the unused lanes copies
/// of the first, and the mask of the used ones.
#[cfg(target_arch = "x86_64")]
#[inline(always)]
fn packet(k: Avx512, chunk: &[Ray]) -> (Rays16, Mask16) {
    let ray = |i: usize| chunk.get(i).unwrap_or(&chunk[0]);
    let vector =
        |f: fn(&Ray) -> glam::Vec3| Vec3x16::from_lanes(k, &std::array::from_fn(|i| f(ray(i))));
    let float = |f: fn(&Ray) -> f32| F32x16::from_array(k, std::array::from_fn(|i| f(ray(i))));
    let rays = Rays16 {
        origin: vector(|r| r.origin),
        dir: vector(|r| r.dir),
        t_min: float(|r| r.t_min),
        t_max: float(|r| r.t_max),
    };
    (rays, Mask16::first(chunk.len()))
}
