//! The batch's two ray loops, closest hits and shadow rays: the BVH walk
//! and nothing else, so that on AVX2 CPUs each is a function of its own
//! with its own registers and stack frame (inlined into the shading loop's
//! function, the walk's state is spilled around the shading code's).

#[cfg(target_arch = "x86_64")]
use crate::bvh::Avx;
use crate::bvh::{Accel, BoxTest, Portable};
use crate::hit::Hit;
use crate::ray::Ray;

/// How a batch runs its ray loops.
pub(super) trait RayLoops: Copy {
    /// `hits[i]` ← the closest hit of `rays[live[i]]`, for every `i` (rays
    /// with `t` in `[0, ∞)`).
    fn closest_hits(self, accel: &Accel, rays: &[Ray], live: &[u32], hits: &mut [Option<Hit>]);

    /// `blocked[i]` ← whether `rays[i]` is occluded, for every `i` (rays
    /// with `t_min = 0`).
    fn occlusions(self, accel: &Accel, rays: &[Ray], blocked: &mut [bool]);
}

/// Both loops, box tests by `boxes`.
#[inline(always)]
fn closest_hits_with(
    accel: &Accel,
    rays: &[Ray],
    live: &[u32],
    hits: &mut [Option<Hit>],
    boxes: impl BoxTest,
) {
    for (hit, &slot) in hits.iter_mut().zip(live) {
        // Rebuilt so that the walk's set-up sees the constant `t` range.
        let ray = &rays[slot as usize];
        debug_assert!(ray.t_min == 0.0 && ray.t_max == f32::INFINITY);
        *hit = accel.closest_hit_with(&Ray::new(ray.origin, ray.dir), boxes);
    }
}

#[inline(always)]
fn occlusions_with(accel: &Accel, rays: &[Ray], blocked: &mut [bool], boxes: impl BoxTest) {
    for (blocked, ray) in blocked.iter_mut().zip(rays) {
        debug_assert!(ray.t_min == 0.0);
        *blocked = accel.occluded_with(&Ray { t_min: 0.0, ..*ray }, boxes);
    }
}

/// Portable box tests, the loops inlined.
impl RayLoops for Portable {
    #[inline(always)]
    fn closest_hits(self, accel: &Accel, rays: &[Ray], live: &[u32], hits: &mut [Option<Hit>]) {
        closest_hits_with(accel, rays, live, hits, self);
    }

    #[inline(always)]
    fn occlusions(self, accel: &Accel, rays: &[Ray], blocked: &mut [bool]) {
        occlusions_with(accel, rays, blocked, self);
    }
}

/// Proof that the CPU has AVX2, BMI1/2, LZCNT and POPCNT (so AVX box tests
/// and the tracer's AVX2 builds run); its loops are functions compiled with
/// those features.
#[cfg(target_arch = "x86_64")]
#[derive(Clone, Copy, Debug)]
pub(super) struct Avx2 {
    avx: Avx,
}

#[cfg(target_arch = "x86_64")]
impl Avx2 {
    /// The token, when the CPU has every feature it stands for.
    pub(super) fn detect() -> Option<Self> {
        let avx = Avx::detect()?;
        (std::arch::is_x86_feature_detected!("avx2")
            && std::arch::is_x86_feature_detected!("bmi1")
            && std::arch::is_x86_feature_detected!("bmi2")
            && std::arch::is_x86_feature_detected!("lzcnt")
            && std::arch::is_x86_feature_detected!("popcnt"))
        .then_some(Self { avx })
    }
}

#[cfg(target_arch = "x86_64")]
#[allow(unsafe_code)]
impl RayLoops for Avx2 {
    #[inline(always)]
    fn closest_hits(self, accel: &Accel, rays: &[Ray], live: &[u32], hits: &mut [Option<Hit>]) {
        // SAFETY: the function requires only the features an `Avx2` proves
        // (it is made only by `Avx2::detect` after finding each of them).
        unsafe { closest_hits_avx2(accel, rays, live, hits, self.avx) }
    }

    #[inline(always)]
    fn occlusions(self, accel: &Accel, rays: &[Ray], blocked: &mut [bool]) {
        // SAFETY: as in `closest_hits`.
        unsafe { occlusions_avx2(accel, rays, blocked, self.avx) }
    }
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,bmi1,bmi2,lzcnt,popcnt")]
#[inline(never)]
fn closest_hits_avx2(
    accel: &Accel,
    rays: &[Ray],
    live: &[u32],
    hits: &mut [Option<Hit>],
    avx: Avx,
) {
    closest_hits_with(accel, rays, live, hits, avx);
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,bmi1,bmi2,lzcnt,popcnt")]
#[inline(never)]
fn occlusions_avx2(accel: &Accel, rays: &[Ray], blocked: &mut [bool], avx: Avx) {
    occlusions_with(accel, rays, blocked, avx);
}
