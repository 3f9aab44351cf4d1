//! A tile's sample queue: its pixel samples in the scalar tile loop's order
//! (pixels row-major, each pixel's samples in order), started sixteen at a
//! time. A batch's streams and camera rays are drawn in lanes
//! ([`TileKeys::starts16`], [`film_dirs16`]) and wait in a buffer
//! until lanes free up, which take them in queue order by expanding loads.

use glam::UVec2;

use crate::bvh::Rays16;
use crate::camera::FilmRays;
use crate::sampler::BLOCK;
use crate::sampler::wide::{Streams16, TileKeys};
use crate::simd::{F32x16, LANES, Lanes, Mask16, U32x16, U64x16, Vec3x16};

/// A batch of started samples, by field and lane, for expanding loads.
#[derive(Clone, Debug)]
struct Batch {
    /// The samples' keys.
    key: [u64; LANES],
    /// Their first bounce blocks, by dimension.
    first: [[f32; LANES]; BLOCK],
    /// Their camera rays' directions, by axis.
    dir: [[f32; LANES]; 3],
    /// Samples in the batch.
    len: usize,
    /// Samples already taken.
    taken: usize,
}

/// The queue of one tile (module docs).
pub(super) struct Queue {
    /// The tile's pixels' `x` and `y` as film coordinates of their corners.
    film: [Vec<f32>; 2],
    keys: TileKeys,
    film_rays: FilmRays,
    spp: u32,
    /// Samples in the queue.
    total: u64,
    /// Samples drawn into batches so far (the next one's sequence number).
    drawn: u64,
    /// Samples started in lanes so far.
    started: u64,
    batch: Batch,
}

impl Queue {
    /// The queue of `spp ≥ 1` samples of each of `pixels` (linear index
    /// `y·width + x`) under `seed`, camera rays by `film_rays`.
    pub fn new(pixels: &[UVec2], width: u32, seed: u32, spp: u32, film_rays: FilmRays) -> Self {
        Self {
            film: [
                pixels.iter().map(|p| p.x as f32).collect(),
                pixels.iter().map(|p| p.y as f32).collect(),
            ],
            keys: TileKeys::new(seed, pixels.iter().map(|p| p.y * width + p.x), spp),
            film_rays,
            spp,
            total: pixels.len() as u64 * u64::from(spp),
            drawn: 0,
            started: 0,
            batch: Batch {
                key: [0; LANES],
                first: [[0.0; LANES]; BLOCK],
                dir: [[0.0; LANES]; 3],
                len: 0,
                taken: 0,
            },
        }
    }

    /// Samples in the queue.
    pub fn total(&self) -> u64 {
        self.total
    }

    /// Samples started so far: the next one's sequence number.
    pub fn started(&self) -> u64 {
        self.started
    }

    /// Starts the next `fill.count()` samples (at most those left) in the
    /// lanes of `fill`, in lane order: their streams and camera rays replace
    /// those lanes' in `streams` and `ray`, their sequence numbers go to
    /// `queued`.
    #[inline(always)]
    pub fn start<B: Lanes>(
        &mut self,
        k: B,
        fill: Mask16,
        streams: &mut Streams16<B>,
        ray: &mut Rays16<B>,
        queued: &mut [u64; LANES],
    ) {
        debug_assert!(u64::from(fill.count()) <= self.total - self.started);
        let mut rest = fill;
        while rest.any() {
            if self.batch.taken == self.batch.len {
                self.draw(k);
            }
            let b = &self.batch;
            let mut take = Mask16::NONE;
            for lane in rest.lanes().take(b.len - b.taken) {
                take.0 |= 1 << lane;
                queued[lane] = self.started;
                self.started += 1;
            }
            let at = b.taken;
            streams.key = streams.key.expand_from(take, &b.key[at..]);
            for (number, drawn) in streams.first.iter_mut().zip(&b.first) {
                *number = number.expand_from(take, &drawn[at..]);
            }
            // Camera rays share the camera's position.
            ray.origin = Vec3x16::select(take, k.vec3(self.film_rays.origin()), ray.origin);
            let d = &mut ray.dir;
            (d.x, d.y, d.z) = (
                d.x.expand_from(take, &b.dir[0][at..]),
                d.y.expand_from(take, &b.dir[1][at..]),
                d.z.expand_from(take, &b.dir[2][at..]),
            );
            ray.t_min = F32x16::select(take, k.f32(0.0), ray.t_min);
            ray.t_max = F32x16::select(take, k.f32(f32::INFINITY), ray.t_max);
            self.batch.taken += take.count() as usize;
            rest = rest.and_not(take);
        }
    }

    /// Draws the next (up to) sixteen samples of the queue into the batch.
    #[inline(always)]
    fn draw<B: Lanes>(&mut self, k: B) {
        let len = (self.total - self.drawn).min(LANES as u64) as usize;
        debug_assert!(len > 0);
        let spp = u64::from(self.spp);
        // One division, then the samples of the batch in order.
        let (mut p, mut s) = ((self.drawn / spp) as u32, (self.drawn % spp) as u32);
        let (mut pixel, mut sample) = ([0u32; LANES], [0u32; LANES]);
        for lane in 0..len {
            (pixel[lane], sample[lane]) = (p, s);
            s += 1;
            if s == self.spp {
                (p, s) = (p + 1, 0);
            }
        }
        self.drawn += len as u64;
        let m = Mask16::first(len);
        let pixel = U32x16::from_array(k, pixel);
        let starts = self
            .keys
            .starts16(k, pixel, U32x16::from_array(k, sample), m);
        let zero = k.f32(0.0);
        let film = [
            F32x16::gather(&self.film[0], pixel, m, zero) + starts.film[0],
            F32x16::gather(&self.film[1], pixel, m, zero) + starts.film[1],
        ];
        let dir = film_dirs16(&self.film_rays, k, film);
        let b = &mut self.batch;
        b.key = U64x16::to_array(starts.key);
        for (out, number) in b.first.iter_mut().zip(starts.first) {
            *out = number.to_array();
        }
        b.dir = [dir.x.to_array(), dir.y.to_array(), dir.z.to_array()];
        (b.len, b.taken) = (len, 0);
    }
}

/// The directions of [`FilmRays::ray`] in every lane (the same operations,
/// so the same directions bit for bit; the origin is
/// [`FilmRays::origin`]): the lanes' film positions' `x` and `y` (pixels)
/// in, unit world-space directions out.
#[inline(always)]
fn film_dirs16<B: Lanes>(rays: &FilmRays, k: B, film: [F32x16<B>; 2]) -> Vec3x16<B> {
    let sx = (k.f32(2.0) * film[0] / k.f32(rays.size.x) - k.f32(1.0)) * k.f32(rays.th_aspect);
    let sy = (k.f32(1.0) - k.f32(2.0) * film[1] / k.f32(rays.size.y)) * k.f32(rays.th);
    let dir = k.vec3(rays.forward) + k.vec3(rays.right) * sx + k.vec3(rays.up) * sy;
    dir.normalize(k)
}
