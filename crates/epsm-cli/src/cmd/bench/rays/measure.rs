//! One timed measurement of `epsm bench rays`: a ray set walked in parallel
//! chunks, ray by ray or through the batch walks, again until
//! [`MIN_RUN_SECONDS`] have passed; wall and CPU seconds per pass and hits.

use std::time::Instant;

use epsm_render::Ray;
use epsm_render::bvh::Accel;
use rayon::prelude::*;

use crate::cmd::bench::cpu_seconds;

/// Shortest timed run: a run walks its ray set again until this long
/// has passed, and reports the time per pass.
const MIN_RUN_SECONDS: f64 = 0.2;

/// One timed pass over a ray set.
#[derive(Clone, Copy)]
pub(super) struct Run {
    /// Wall-clock seconds per pass.
    pub seconds: f64,
    /// CPU-seconds of the process per pass (Linux; absent when the kernel's
    /// total did not advance).
    pub cpu_seconds: Option<f64>,
    /// Hits in a pass.
    pub hits: usize,
}

/// How a set of rays is walked.
#[derive(Clone, Copy)]
pub(super) struct Walk {
    /// Occlusion (`true`) or closest hit.
    pub occlusion: bool,
    /// Through the batch walks (`Accel::closest_hits`,
    /// `Accel::occluded_rays`) rather than ray by ray.
    pub batched: bool,
}

/// The hits among `chunk` by `walk`.
fn hits_of(accel: &Accel, chunk: &[Ray], walk: Walk) -> usize {
    match (walk.occlusion, walk.batched) {
        (true, false) => chunk.iter().filter(|ray| accel.occluded(ray)).count(),
        (false, false) => chunk
            .iter()
            .filter(|ray| accel.closest_hit(ray).is_some())
            .count(),
        (true, true) => accel.occluded_rays(chunk).iter().filter(|&&o| o).count(),
        (false, true) => accel.closest_hits(chunk).iter().flatten().count(),
    }
}

/// Traces all rays in parallel chunks, in passes over the whole set until
/// [`MIN_RUN_SECONDS`] have passed (a set of a few milliseconds, such as a
/// small render's camera rays, would otherwise time thread start-up more
/// than walks).
pub(super) fn measure(accel: &Accel, rays: &[Ray], walk: Walk) -> Run {
    let cpu_start = cpu_seconds();
    let start = Instant::now();
    let (mut passes, mut hits) = (0u32, 0);
    while passes == 0 || start.elapsed().as_secs_f64() < MIN_RUN_SECONDS {
        hits = rays
            .par_chunks(1024)
            .map(|chunk| hits_of(accel, chunk, walk))
            .sum();
        passes += 1;
    }
    let seconds = start.elapsed().as_secs_f64() / f64::from(passes);
    // The kernel updates a running thread's total at scheduler ticks (a few
    // ms), so very short runs may read zero: report nothing then.
    let cpu_seconds = cpu_seconds()
        .zip(cpu_start)
        .map(|(end, start)| (end - start) / f64::from(passes))
        .filter(|&c| c > 0.0);
    Run {
        seconds,
        cpu_seconds,
        hits,
    }
}
