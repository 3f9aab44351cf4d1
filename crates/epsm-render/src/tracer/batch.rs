//! A batch of paths traced in stages (wavefront order): all live paths find
//! their next vertex, then all are shaded, then all shadow rays are traced,
//! then all vertices are finished and the ended paths leave the batch. Each
//! loop holds one kind of work, so the BVH walk runs with the registers and
//! instruction cache to itself, and the shading code without it.
//!
//! Every path consumes the same random numbers and adds the same terms in
//! the same order as one traced alone, so a sample's radiance does not
//! depend on the batch it is traced in.

use glam::{UVec2, Vec3};

use super::loops::RayLoops;
use super::path::{PathState, Shadows, shade};
use super::{RenderOptions, TraceCounters};
use crate::camera::FilmRays;
use crate::hit::Hit;
use crate::ray::Ray;
use crate::record::{PathRecord, RecordLevel};
use crate::sampler::PixelKeys;
use crate::scene::Scene;

/// One pixel sample to start: the pixel's keys, the pixel, the sample index.
pub(super) type Start<'k> = (&'k PixelKeys, UVec2, u32);

/// The working arrays of a batch (kept between batches to reuse their
/// memory). `paths`, `rays` and the caller's radiance and records are
/// indexed by slot (the path's start index); `live` lists the slots of the
/// paths still going, and `hits[i]` belongs to slot `live[i]`.
#[derive(Default)]
pub(super) struct Batch<'k> {
    paths: Vec<PathState<'k>>,
    rays: Vec<Ray>,
    live: Vec<u32>,
    hits: Vec<Option<Hit>>,
    shadows: Shadows,
    blocked: Vec<bool>,
}

impl<'k> Batch<'k> {
    /// Traces one path per start, rays by `loops`. Path `i`'s radiance
    /// goes to `radiance[i]` (zero, and counted, when it was not finite) and,
    /// when `records` is given, its record at that level to `records.1[i]`.
    #[inline(always)]
    #[allow(clippy::too_many_arguments)]
    pub(super) fn trace(
        &mut self,
        scene: &Scene,
        opts: &RenderOptions,
        film_rays: &FilmRays,
        starts: impl IntoIterator<Item = Start<'k>>,
        mut records: Option<(RecordLevel, &mut [PathRecord])>,
        radiance: &mut [Vec3],
        counters: &mut TraceCounters,
        loops: impl RayLoops,
    ) {
        // Camera rays.
        self.paths.clear();
        self.rays.clear();
        self.live.clear();
        for (slot, (keys, pixel, sample)) in (0..).zip(starts) {
            let mut sampler = keys.sampler(sample);
            let film = pixel.as_vec2() + sampler.next_2d();
            self.rays.push(film_rays.ray(film));
            self.paths.push(PathState::new(sampler));
            self.live.push(slot);
            radiance[slot as usize] = Vec3::ZERO;
            if let Some((_, recs)) = records.as_mut() {
                recs[slot as usize] = PathRecord {
                    pixel,
                    sample,
                    film,
                    ..PathRecord::default()
                };
            }
        }
        let started = self.paths.len();

        for depth in 0..opts.max_depth {
            if self.live.is_empty() {
                break;
            }
            // Closest hits of all live paths.
            counters.rays += self.live.len() as u64;
            self.hits.resize(self.live.len(), None);
            loops.closest_hits(scene.accel(), &self.rays, &self.live, &mut self.hits);

            // Shade every vertex up to its shadow ray; ended paths leave.
            self.shadows.rays.clear();
            self.shadows.waiting.clear();
            let mut kept = 0;
            for i in 0..self.live.len() {
                let slot = self.live[i];
                let s = slot as usize;
                let record = records.as_mut().map(|(level, recs)| (*level, &mut recs[s]));
                if shade(
                    scene,
                    opts,
                    depth,
                    slot,
                    &mut self.paths[s],
                    &mut self.rays[s],
                    self.hits[i],
                    &mut radiance[s],
                    record,
                    &mut self.shadows,
                    counters,
                ) {
                    self.live[kept] = slot;
                    kept += 1;
                }
            }
            self.live.truncate(kept);

            // Shadow rays, and what their vertices add.
            counters.shadow_rays += self.shadows.rays.len() as u64;
            self.blocked.resize(self.shadows.rays.len(), false);
            loops.occlusions(scene.accel(), &self.shadows.rays, &mut self.blocked);
            for ((shadow, waiting), &blocked) in
                (self.shadows.rays.iter().zip(&self.shadows.waiting)).zip(&self.blocked)
            {
                let recs = records.as_mut().map(|(_, recs)| &mut **recs);
                waiting.finish(scene, shadow, blocked, radiance, recs);
            }
        }

        // Non-finite samples are dropped and counted.
        for (slot, l) in radiance[..started].iter_mut().enumerate() {
            if !l.is_finite() {
                counters.non_finite += 1;
                *l = Vec3::ZERO;
            }
            if let Some((_, recs)) = records.as_mut() {
                recs[slot].radiance = *l;
            }
        }
    }
}
