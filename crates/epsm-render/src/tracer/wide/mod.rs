//! The wide tracer: sixteen paths at once, one per AVX-512 lane, each lane
//! doing what the scalar bounce loop (`tracer::path`) does for its path, in
//! the same order and with the same operations, so the image is
//! bit-identical to the scalar tracer's (ties between two primitives hit at
//! exactly the same distance aside, whose winner depends on the walk's
//! visiting order).
//!
//! Model: a tile's pixel samples form a queue (pixels in row-major order,
//! each pixel's samples in order). A lane takes the next sample from the
//! queue whenever it is free, so lanes stay busy while paths of different
//! lengths end at different bounces; each step advances every lane's path
//! by one bounce (`bounce`). A finished sample's radiance waits in a ring
//! until every earlier sample of the tile has finished, then is added to its
//! pixel's sum, so each pixel sums its samples in order, as the scalar tile
//! loop does, whatever the order paths finish in.
//!
//! | constant | value | meaning |
//! |---|---|---|
//! | `RING` | 4096 | samples that may finish ahead of the oldest unfinished one; a lane waits while the ring is full |

mod bounce;

use glam::{UVec2, Vec3};

use super::{DIM_FIRST_BOUNCE, DIMS_PER_BOUNCE, RenderOptions, TILE, TileOutput, camera_sample};
use crate::materials::wide::Materials16;
use crate::ray::Rays16;
use crate::sampler::wide::Streams16;
use crate::sampler::{PixelKeys, STRATIFIED_DIMENSIONS};
use crate::scene::Scene;
use crate::simd::{Avx512, F32x16, LANES, Mask16, U32x16, Vec3x16};
use bounce::{Paths16, bounce};

/// Entries of the ring of finished samples (module docs).
const RING: usize = 4096;

// A path's first bounce block is its last stratified one (`Streams16`).
const _: () = assert!(DIM_FIRST_BOUNCE + DIMS_PER_BOUNCE == STRATIFIED_DIMENSIONS);

/// Per-object tables the lanes gather from by object index.
#[derive(Clone, Debug)]
pub(super) struct Objects16 {
    /// Material index.
    material: Vec<u32>,
    /// 1 for emitters, 0 for other objects.
    emitter: Vec<u32>,
    /// Emitted radiance by channel (0 for other objects).
    emission: [Vec<f32>; 3],
}

impl Objects16 {
    fn new(scene: &Scene) -> Self {
        let objects = scene.objects();
        let channel = |c: usize| {
            objects
                .iter()
                .map(|o| o.emission.map_or(0.0, |e| e[c]))
                .collect()
        };
        Self {
            material: objects.iter().map(|o| o.material).collect(),
            emitter: objects
                .iter()
                .map(|o| u32::from(o.emission.is_some()))
                .collect(),
            emission: [channel(0), channel(1), channel(2)],
        }
    }
}

/// What every step of a tile reads.
struct Setup<'a> {
    scene: &'a Scene,
    opts: &'a RenderOptions,
    objects: &'a Objects16,
    materials: &'a Materials16,
}

/// The wide tracer of one render: the CPU token and the scene's lane
/// tables.
pub(super) struct WideTracer {
    k: Avx512,
    objects: Objects16,
    materials: Materials16,
}

impl WideTracer {
    /// The tracer for `scene`, when the CPU has AVX-512.
    pub fn new(scene: &Scene) -> Option<Self> {
        Some(Self {
            k: Avx512::detect()?,
            objects: Objects16::new(scene),
            materials: Materials16::new(scene.materials()),
        })
    }

    /// Renders tile `tile` (in units of [`TILE`] pixels) with `opts.spp ≥ 1`
    /// samples per pixel.
    #[allow(unsafe_code)]
    pub fn render_tile(&self, scene: &Scene, opts: &RenderOptions, tile: UVec2) -> TileOutput {
        debug_assert!(opts.spp >= 1);
        // SAFETY: `render_tile_avx512` requires only the CPU features it
        // enables, and `self.k` (an `Avx512` token) exists only on a CPU
        // found to have each of them.
        unsafe { render_tile_avx512(self.k, scene, opts, self, tile) }
    }
}

/// Renders one tile: the sample queue, the lanes and the ring (module
/// docs), compiled for AVX-512 so that the lane types' operations are
/// single instructions.
#[target_feature(enable = "avx512f,avx512vl,avx512dq,avx512bw,avx2,bmi1,bmi2,lzcnt,popcnt")]
fn render_tile_avx512(
    k: Avx512,
    scene: &Scene,
    opts: &RenderOptions,
    tracer: &WideTracer,
    tile: UVec2,
) -> TileOutput {
    let (w, h) = (scene.camera().width, scene.camera().height);
    let pixels: Vec<UVec2> = (tile.y * TILE..((tile.y + 1) * TILE).min(h))
        .flat_map(|y| (tile.x * TILE..((tile.x + 1) * TILE).min(w)).map(move |x| UVec2::new(x, y)))
        .collect();
    let keys: Vec<PixelKeys> = pixels
        .iter()
        .map(|p| PixelKeys::new(opts.seed, p.y * w + p.x, opts.spp))
        .collect();
    let film_rays = scene.camera().film_rays();
    let setup = Setup {
        scene,
        opts,
        objects: &tracer.objects,
        materials: &tracer.materials,
    };
    let spp = u64::from(opts.spp);
    let total = pixels.len() as u64 * spp;
    let mut out = TileOutput {
        pixels: Vec::with_capacity(pixels.len()),
        records: Vec::new(),
        counters: Default::default(),
        rays: Default::default(),
    };
    let mut ring = vec![Vec3::ZERO; RING];
    let mut done = vec![false; RING];
    let mut queued = [0u64; LANES];
    let (mut next_seq, mut committed) = (0u64, 0u64);
    let mut next = (0u32, 0u32);
    let mut sum = Vec3::ZERO;
    let zero3 = Vec3x16::splat(k, Vec3::ZERO);
    let zero = F32x16::splat(k, 0.0);
    let mut paths = Paths16 {
        active: Mask16::NONE,
        streams: Streams16::new(),
        ray: Rays16 {
            origin: zero3,
            dir: zero3,
            t_min: zero,
            t_max: zero,
        },
        beta: zero3,
        radiance: zero3,
        eta_scale: zero,
        prev_p: zero3,
        prev_pdf: zero,
        has_prev: Mask16::NONE,
        depth: U32x16::splat(k, 0),
    };
    loop {
        // Free lanes take the next samples, as far as the ring has room;
        // their streams and camera rays are those of the scalar tile loop.
        let room = (total - next_seq).min(committed + RING as u64 - next_seq);
        let mut fill = Mask16::NONE;
        let (mut origins, mut dirs) = ([Vec3::ZERO; LANES], [Vec3::ZERO; LANES]);
        for lane in (!paths.active).lanes().take(room as usize) {
            fill.0 |= 1 << lane;
            queued[lane] = next_seq;
            next_seq += 1;
            let (pixel, sample) = next;
            next = if sample + 1 < opts.spp {
                (pixel, sample + 1)
            } else {
                (pixel + 1, 0)
            };
            let pixel = pixel as usize;
            let camera = camera_sample(&film_rays, &keys[pixel], pixels[pixel], sample);
            paths.streams.start(lane, &camera.sampler, DIM_FIRST_BOUNCE);
            (origins[lane], dirs[lane]) = (camera.ray.origin, camera.ray.dir);
        }
        if fill.any() {
            let (origin, dir) = (
                Vec3x16::from_lanes(k, &origins),
                Vec3x16::from_lanes(k, &dirs),
            );
            paths.ray = Rays16 {
                origin: Vec3x16::select(fill, origin, paths.ray.origin),
                dir: Vec3x16::select(fill, dir, paths.ray.dir),
                t_min: F32x16::select(fill, zero, paths.ray.t_min),
                t_max: F32x16::select(fill, F32x16::splat(k, f32::INFINITY), paths.ray.t_max),
            };
            paths.beta = Vec3x16::select(fill, Vec3x16::splat(k, Vec3::ONE), paths.beta);
            paths.radiance = Vec3x16::select(fill, zero3, paths.radiance);
            paths.eta_scale = F32x16::select(fill, F32x16::splat(k, 1.0), paths.eta_scale);
            paths.has_prev = paths.has_prev.and_not(fill);
            paths.depth = U32x16::select(fill, U32x16::splat(k, 0), paths.depth);
            paths.active = paths.active | fill;
        }
        if !paths.active.any() {
            break;
        }
        let ended = bounce(k, &setup, &mut paths, &mut out.counters);
        paths.active = paths.active.and_not(ended);
        if !ended.any() {
            continue;
        }
        let radiance = paths.radiance.to_lanes();
        for lane in ended.lanes() {
            let l = radiance[lane];
            let slot = (queued[lane] % RING as u64) as usize;
            ring[slot] = if l.is_finite() {
                l
            } else {
                out.counters.non_finite += 1;
                Vec3::ZERO
            };
            done[slot] = true;
        }
        // Samples finished in queue order join their pixel's sum.
        while committed < next_seq && done[(committed % RING as u64) as usize] {
            let slot = (committed % RING as u64) as usize;
            done[slot] = false;
            sum += ring[slot];
            if committed % spp == spp - 1 {
                let pixel = pixels[(committed / spp) as usize];
                out.pixels.push((pixel, sum / opts.spp as f32));
                sum = Vec3::ZERO;
            }
            committed += 1;
        }
    }
    debug_assert_eq!(committed, total);
    out
}
