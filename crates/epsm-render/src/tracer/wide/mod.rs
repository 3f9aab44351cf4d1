//! The wide tracer: sixteen paths at once, one per vector lane (AVX-512,
//! AVX2 or portable lanes: module `simd`), each lane
//! doing what the scalar bounce loop (`tracer::path`) does for its path, in
//! the same order and with the same operations, so the image is
//! bit-identical to the scalar tracer's (ties between two primitives hit at
//! exactly the same distance aside, whose winner depends on the walk's
//! visiting order).
//!
//! Model: the pixel samples of a tile, or of a band of its rows when its
//! pixels take many samples (module `tiles`), form a queue (pixels in
//! row-major order, each pixel's samples in order). A lane takes the next
//! sample from the queue whenever it is free, so lanes stay busy while
//! paths of different lengths end at different bounces; each step advances
//! every lane's path by one bounce (`bounce`). A finished sample's radiance
//! waits in a ring until every earlier sample of the queue has finished,
//! then is added to its pixel's sum, so each pixel sums its samples in
//! order, as the scalar tile loop does, whatever the order paths finish in.
//!
//! | constant | value | meaning |
//! |---|---|---|
//! | `RING` | 4096 | samples that may finish ahead of the oldest unfinished one; a lane waits while the ring is full |

mod bounce;
mod offset;
mod queue;

use glam::{UVec2, Vec3};

use super::{DIM_FIRST_BOUNCE, DIMS_PER_BOUNCE, RenderOptions, TileOutput};
use crate::bvh::Rays16;
use crate::materials::wide::Materials16;
use crate::sampler::STRATIFIED_DIMENSIONS;
use crate::sampler::wide::Streams16;
use crate::scene::Scene;
use crate::simd::{Backend, F32x16, LANES, Lanes, Mask16, U32x16, Vec3x16, WithLanes};
use bounce::{Paths16, bounce};
use queue::Queue;

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

/// The wide tracer of one render: the lane backend and the scene's lane
/// tables.
pub(super) struct WideTracer {
    backend: Backend,
    objects: Objects16,
    materials: Materials16,
}

impl WideTracer {
    /// The tracer for `scene` with lanes of `backend`.
    pub fn new(scene: &Scene, backend: Backend) -> Self {
        Self {
            backend,
            objects: Objects16::new(scene),
            materials: Materials16::new(scene.materials()),
        }
    }

    /// Renders `pixels` (a tile's, or a band of a tile's, in row-major
    /// order) with `opts.spp ≥ 1` samples per pixel.
    pub fn render_pixels(
        &self,
        scene: &Scene,
        opts: &RenderOptions,
        pixels: &[UVec2],
    ) -> TileOutput {
        debug_assert!(opts.spp >= 1);
        self.backend.call(Tile {
            scene,
            opts,
            tracer: self,
            pixels,
        })
    }
}

/// The pixels of one tile (or band) to render, for [`Backend::call`].
struct Tile<'a> {
    scene: &'a Scene,
    opts: &'a RenderOptions,
    tracer: &'a WideTracer,
    pixels: &'a [UVec2],
}

impl WithLanes for Tile<'_> {
    type Output = TileOutput;
    #[inline(always)]
    fn call<B: Lanes>(self, k: B) -> TileOutput {
        render_tile_lanes(k, self.scene, self.opts, self.tracer, self.pixels)
    }
}

/// Renders one tile: the sample queue, the lanes and the ring (module
/// docs). Inlined into [`Lanes::run`], so that it is compiled with the
/// backend's features and the lane types' operations are single
/// instructions.
#[inline(always)]
fn render_tile_lanes<B: Lanes>(
    k: B,
    scene: &Scene,
    opts: &RenderOptions,
    tracer: &WideTracer,
    pixels: &[UVec2],
) -> TileOutput {
    let w = scene.camera().width;
    let mut queue = Queue::new(pixels, w, opts.seed, opts.spp, scene.camera().film_rays());
    let setup = Setup {
        scene,
        opts,
        objects: &tracer.objects,
        materials: &tracer.materials,
    };
    let total = queue.total();
    let mut out = TileOutput {
        pixels: Vec::with_capacity(pixels.len()),
        records: Vec::new(),
        counters: Default::default(),
        rays: Default::default(),
    };
    let mut ring = vec![Vec3::ZERO; RING];
    let mut done = vec![false; RING];
    let mut queued = [0u64; LANES];
    let mut committed = 0u64;
    // The pixel being summed, and how many of its samples are in `sum`.
    let mut sum = Vec3::ZERO;
    let mut summed = 0u32;
    let zero3 = Vec3x16::splat(k, Vec3::ZERO);
    let zero = F32x16::splat(k, 0.0);
    let mut paths = Paths16 {
        active: Mask16::NONE,
        streams: Streams16::new(k),
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
        // Free lanes take the next samples, as far as the ring has room.
        let next_seq = queue.started();
        let room = (total - next_seq).min(committed + RING as u64 - next_seq);
        let fill = (!paths.active).first_of(room.min(LANES as u64) as u32);
        if fill.any() {
            queue.start(k, fill, &mut paths.streams, &mut paths.ray, &mut queued);
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
        let r = &paths.radiance;
        let [x, y, z] = [r.x.to_array(), r.y.to_array(), r.z.to_array()];
        for lane in ended.lanes() {
            let l = Vec3::new(x[lane], y[lane], z[lane]);
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
        while committed < queue.started() && done[(committed % RING as u64) as usize] {
            let slot = (committed % RING as u64) as usize;
            done[slot] = false;
            sum += ring[slot];
            summed += 1;
            if summed == opts.spp {
                let pixel = pixels[out.pixels.len()];
                out.pixels.push((pixel, sum / opts.spp as f32));
                (sum, summed) = (Vec3::ZERO, 0);
            }
            committed += 1;
        }
    }
    debug_assert_eq!(committed, total);
    out
}
