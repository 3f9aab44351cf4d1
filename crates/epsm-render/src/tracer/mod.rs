//! The forward path tracer: unidirectional, next-event estimation with
//! multiple importance sampling (power heuristic), Russian roulette, rayon
//! over tiles, and optional path recording.
//!
//! Determinism: every random number comes from a
//! [`PixelSampler`], keyed by
//! `(seed, pixel, sample, dimension)`, and each pixel sums its samples in
//! order, so an image is bit-identical whatever the thread count.
//!
//! Random dimensions: the film position uses dimensions 0–1; bounce `k`
//! (0-based) uses the block `2 + 8k …`: light selection, light position (2),
//! lobe choice, direction (2), Russian roulette (the `DIM_*` offsets).
//!
//! Two bounce loops ([`Kernel`]): the scalar one (module `path`) traces one
//! path at a time and records paths; the wide one (module `wide`, on
//! AVX-512, AVX2 or portable lanes) traces sixteen paths at once, one per
//! vector lane, with the
//! same operations in every lane, so it renders the same image. Images
//! ([`render`]) come from the wide loop where the CPU has it; records
//! ([`render_recorded`], [`trace_samples`]) and ray logs ([`render_logged`])
//! from the scalar one, which is also the reference the wide loop is tested
//! against (`tests/wide.rs`: every shipped scene byte for byte).

use std::time::Instant;

use glam::{UVec2, Vec2, Vec3};
use rayon::prelude::*;

mod path;
#[cfg(target_arch = "x86_64")]
mod wide;

use path::{Recording, trace_path};

#[cfg(target_arch = "x86_64")]
use crate::bvh::Avx2;
use crate::bvh::{BoxTest, Portable, SpheresFirst};
use crate::camera::FilmRays;
use crate::film::Image;
use crate::ray::Ray;
use crate::record::{PathRecord, RecordLevel, SampleDrop};
use crate::sampler::{PixelKeys, PixelSampler};
use crate::scene::Scene;

/// Side of the square tiles rendered by one task.
pub const TILE: u32 = 16;
/// Dimensions per bounce: one sampler [`Block`](crate::sampler::Block).
const DIMS_PER_BOUNCE: u32 = crate::sampler::BLOCK as u32;
/// The dimension of the film position (two numbers).
const DIM_FILM: u32 = 0;
/// The first dimension of bounce 0's block.
const DIM_FIRST_BOUNCE: u32 = 2;
/// Offsets in a bounce's block: light selection.
const DIM_LIGHT_SELECT: u32 = 0;
/// Light position (two numbers).
const DIM_LIGHT: u32 = 1;
/// Lobe choice.
const DIM_LOBE: u32 = 3;
/// Direction (two numbers).
const DIM_DIRECTION: u32 = 4;
/// Russian roulette.
const DIM_ROULETTE: u32 = 6;
/// Shadow rays stop this fraction short of the light point (relative, so it
/// works at any scene scale).
const SHADOW_EPS: f32 = 1e-4;

/// What to render.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct RenderOptions {
    /// Samples per pixel.
    pub spp: u32,
    /// Seed of the random streams.
    pub seed: u32,
    /// Maximum scatterings per path (the vertex the last one reaches still
    /// adds its emission, or the background).
    pub max_depth: u32,
    /// Depth from which Russian roulette runs.
    pub rr_depth: u32,
}

impl RenderOptions {
    /// The scene's own settings.
    pub fn from_scene(scene: &Scene) -> Self {
        let s = scene.settings();
        Self {
            spp: s.spp,
            seed: s.seed,
            max_depth: s.max_depth,
            rr_depth: s.rr_depth,
        }
    }
}

/// Counters of events the tracer guards against. Each guarded sample or
/// path is dropped (its remaining contribution is zero) and counted here.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct TraceCounters {
    /// Camera and continuation rays traced (closest hit).
    pub rays: u64,
    /// Shadow rays traced.
    pub shadow_rays: u64,
    /// Samples whose radiance was NaN or infinite (dropped: zero in the
    /// image, and a record marked [`SampleDrop::NonFinite`]).
    pub non_finite: u64,
    /// Paths ended because the sampled direction lay on the wrong side of the
    /// geometric normal for its lobe (shading-normal light leak).
    pub leaks: u64,
}

impl TraceCounters {
    fn add(&mut self, o: &TraceCounters) {
        self.rays += o.rays;
        self.shadow_rays += o.shadow_rays;
        self.non_finite += o.non_finite;
        self.leaks += o.leaks;
    }
}

/// A rendered image and how it went.
#[derive(Clone, Debug)]
pub struct RenderOutput {
    /// Linear RGB, the mean of the pixel samples (box filter).
    pub image: Image,
    /// Pixel samples traced.
    pub samples: u64,
    /// Wall-clock seconds.
    pub seconds: f64,
    /// Guard and ray counters.
    pub counters: TraceCounters,
}

/// The rays a render cast, in the order each tile traced them (tiles in
/// row-major order): what [`render_logged`] returns, for measuring the BVH on
/// a scene's own rays (`epsm bench rays --scene`).
#[derive(Clone, Debug, Default)]
pub struct RayLog {
    /// Camera rays (closest hit, bounce 0): coherent, pixel by pixel.
    pub camera: Vec<Ray>,
    /// Continuation rays (closest hit, bounces 1 and later): incoherent.
    pub bounce: Vec<Ray>,
    /// Shadow rays of next-event estimation (occlusion, `t_max` short of the
    /// light point).
    pub shadow: Vec<Ray>,
}

impl RayLog {
    fn append(&mut self, other: &mut RayLog) {
        self.camera.append(&mut other.camera);
        self.bounce.append(&mut other.bounce);
        self.shadow.append(&mut other.shadow);
    }
}

/// Where the tracer reports each ray it casts: [`NoSink`] when rendering, a
/// [`RayLog`] for [`render_logged`].
trait RaySink {
    /// A closest-hit ray of bounce `depth` (0: the camera ray).
    fn closest(&mut self, depth: u32, ray: &Ray);
    /// A shadow ray.
    fn shadow(&mut self, ray: &Ray);
}

/// Reports nothing (a render's sink: its calls compile to nothing).
struct NoSink;

impl RaySink for NoSink {
    #[inline(always)]
    fn closest(&mut self, _depth: u32, _ray: &Ray) {}
    #[inline(always)]
    fn shadow(&mut self, _ray: &Ray) {}
}

impl RaySink for RayLog {
    fn closest(&mut self, depth: u32, ray: &Ray) {
        if depth == 0 {
            self.camera.push(*ray);
        } else {
            self.bounce.push(*ray);
        }
    }
    fn shadow(&mut self, ray: &Ray) {
        self.shadow.push(*ray);
    }
}

/// One pixel sample to trace.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PixelSample {
    /// The pixel.
    pub pixel: UVec2,
    /// Sample index within the pixel, `< spp`.
    pub sample: u32,
}

/// Which bounce loop renders an image.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Kernel {
    /// The fastest this CPU has: the wide tracer on AVX-512 lanes, else on
    /// AVX2 lanes, else the scalar loop. The same image whichever runs
    /// (module `wide`).
    #[default]
    Fastest,
    /// The wide tracer, sixteen paths per AVX-512 instruction.
    Avx512,
    /// The wide tracer on AVX2: sixteen lanes as two 8-lane halves.
    Avx2,
    /// The wide tracer on plain arrays (any x86-64 CPU): the reference the
    /// vector lanes are tested against.
    Portable,
    /// One path at a time, on every CPU (the reference the wide tracer is
    /// tested against).
    Scalar,
}

impl Kernel {
    /// Every kernel that names one loop (all but [`Kernel::Fastest`]).
    pub const ALL: [Kernel; 4] = [Self::Avx512, Self::Avx2, Self::Portable, Self::Scalar];

    /// The kernel's name, as `epsm bench render --kernel` takes it.
    pub fn name(self) -> &'static str {
        match self {
            Self::Fastest => "fastest",
            Self::Avx512 => "avx512",
            Self::Avx2 => "avx2",
            Self::Portable => "portable",
            Self::Scalar => "scalar",
        }
    }

    /// Whether this CPU can run it.
    pub fn available(self) -> bool {
        match self {
            Self::Fastest | Self::Scalar => true,
            #[cfg(target_arch = "x86_64")]
            _ => self.backend().is_some(),
            #[cfg(not(target_arch = "x86_64"))]
            _ => false,
        }
    }

    /// The kernel that runs for `self` on this CPU: [`Kernel::Fastest`]
    /// resolved, the others themselves.
    pub fn resolve(self) -> Kernel {
        match self {
            #[cfg(target_arch = "x86_64")]
            Self::Fastest => match crate::simd::Backend::fastest() {
                Some(crate::simd::Backend::Avx512(_)) => Self::Avx512,
                Some(crate::simd::Backend::Avx2(_)) => Self::Avx2,
                _ => Self::Scalar,
            },
            #[cfg(not(target_arch = "x86_64"))]
            Self::Fastest => Self::Scalar,
            other => other,
        }
    }

    /// The lane backend of the wide tracer for this kernel (`None`: the
    /// scalar loop).
    #[cfg(target_arch = "x86_64")]
    fn backend(self) -> Option<crate::simd::Backend> {
        use crate::simd::{Avx512, Backend, Portable};
        match self {
            Self::Fastest => Backend::fastest(),
            Self::Avx512 => Avx512::detect().map(Backend::Avx512),
            Self::Avx2 => Avx2::detect().map(Backend::Avx2),
            Self::Portable => Some(Backend::Portable(Portable)),
            Self::Scalar => None,
        }
    }
}

/// Renders the scene. `progress` is called (from worker threads) with the
/// number of pixel samples each finished tile traced.
pub fn render(
    scene: &Scene,
    opts: &RenderOptions,
    progress: &(dyn Fn(u64) + Sync),
) -> RenderOutput {
    render_with(scene, opts, Kernel::Fastest, progress)
}

/// [`render`] with the bounce loop `kernel`.
///
/// # Panics
/// If this CPU cannot run `kernel` ([`Kernel::available`]).
pub fn render_with(
    scene: &Scene,
    opts: &RenderOptions,
    kernel: Kernel,
    progress: &(dyn Fn(u64) + Sync),
) -> RenderOutput {
    assert!(
        kernel.available(),
        "kernel {} is not available on this CPU",
        kernel.name()
    );
    render_tiles(scene, opts, None, kernel, false, progress).0
}

/// Renders the scene and logs every ray it casts ([`RayLog`]). The image is
/// bit-identical to [`render`]'s; the render itself is slower (it runs the
/// portable build of the tile loop and stores each ray).
pub fn render_logged(
    scene: &Scene,
    opts: &RenderOptions,
    progress: &(dyn Fn(u64) + Sync),
) -> (RenderOutput, RayLog) {
    let (out, _, rays) = render_tiles(scene, opts, None, Kernel::Scalar, true, progress);
    (out, rays)
}

/// Renders the scene and records every pixel sample's path at `level`.
/// Records are ordered by pixel (row-major), then sample. The image is
/// bit-identical to [`render`]'s.
pub fn render_recorded(
    scene: &Scene,
    opts: &RenderOptions,
    level: RecordLevel,
    progress: &(dyn Fn(u64) + Sync),
) -> (RenderOutput, Vec<PathRecord>) {
    let (out, records, _) = render_tiles(scene, opts, Some(level), Kernel::Scalar, false, progress);
    (out, records)
}

/// Traces the given pixel samples (with the random streams of a render with
/// `opts`) and returns their records in the same order.
pub fn trace_samples(
    scene: &Scene,
    opts: &RenderOptions,
    samples: &[PixelSample],
    level: RecordLevel,
) -> Vec<PathRecord> {
    let film_rays = scene.camera().film_rays();
    samples
        .par_iter()
        .map(|s| {
            let mut counters = TraceCounters::default();
            let mut rec = PathRecord::default();
            let width = scene.camera().width;
            let keys = PixelKeys::new(opts.seed, s.pixel.y * width + s.pixel.x, opts.spp);
            trace_pixel_sample(
                scene,
                opts,
                camera_sample(&film_rays, &keys, s.pixel, s.sample),
                Some((level, &mut rec)),
                &mut counters,
                &mut NoSink,
                Portable,
            );
            rec
        })
        .collect()
}

/// Renders the tiles in parallel: the image, with the records at `level`,
/// and with `log` the rays cast; by the wide tracer where `kernel` names
/// one (images only: no records, no ray log).
fn render_tiles(
    scene: &Scene,
    opts: &RenderOptions,
    level: Option<RecordLevel>,
    kernel: Kernel,
    log: bool,
    progress: &(dyn Fn(u64) + Sync),
) -> (RenderOutput, Vec<PathRecord>, RayLog) {
    let start = Instant::now();
    let (w, h) = (scene.camera().width, scene.camera().height);
    let (tx, ty) = (w.div_ceil(TILE), h.div_ceil(TILE));
    #[cfg(target_arch = "x86_64")]
    let wide = (level.is_none() && !log && opts.spp > 0)
        .then(|| kernel.backend())
        .flatten()
        .map(|backend| wide::WideTracer::new(scene, backend));
    #[cfg(not(target_arch = "x86_64"))]
    let _ = kernel;
    let mut tiles: Vec<TileOutput> = (0..tx * ty)
        .into_par_iter()
        .map(|t| {
            let tile = UVec2::new(t % tx, t / tx);
            #[cfg(target_arch = "x86_64")]
            if let Some(wide) = &wide {
                let out = wide.render_tile(scene, opts, tile);
                progress(out.pixels.len() as u64 * opts.spp as u64);
                return out;
            }
            let out = render_tile(scene, opts, level, log, tile);
            progress(out.pixels.len() as u64 * opts.spp as u64);
            out
        })
        .collect();
    let mut image = Image::new(w, h);
    let mut counters = TraceCounters::default();
    let mut records = Vec::new();
    let mut rays = RayLog::default();
    for tile in &mut tiles {
        rays.append(&mut tile.rays);
        counters.add(&tile.counters);
        for (pixel, value) in &tile.pixels {
            image.set(pixel.x, pixel.y, *value);
        }
    }
    if level.is_some() {
        let mut all: Vec<PathRecord> = tiles.into_iter().flat_map(|t| t.records).collect();
        all.sort_by_key(|r| (r.pixel.y, r.pixel.x, r.sample));
        records = all;
    }
    let samples = w as u64 * h as u64 * opts.spp as u64;
    (
        RenderOutput {
            image,
            samples,
            seconds: start.elapsed().as_secs_f64(),
            counters,
        },
        records,
        rays,
    )
}

struct TileOutput {
    pixels: Vec<(UVec2, Vec3)>,
    records: Vec<PathRecord>,
    counters: TraceCounters,
    /// The rays cast, when logged.
    rays: RayLog,
}

/// Renders one tile, with the AVX2 build of the tracer (and AVX box tests)
/// where the CPU has it; with `log`, with the portable build and every ray
/// cast logged (the same image: module docs of `bvh::node`). A scene that
/// lists exact spheres gets the build that tests them before each walk
/// ([`SpheresFirst`]; the same hits).
#[allow(unsafe_code)]
fn render_tile(
    scene: &Scene,
    opts: &RenderOptions,
    level: Option<RecordLevel>,
    log: bool,
    tile: UVec2,
) -> TileOutput {
    if log {
        let mut rays = RayLog::default();
        let out = render_tile_body(scene, opts, level, tile, &mut rays, Portable);
        return TileOutput { rays, ..out };
    }
    let spheres = scene.accel().lists_spheres();
    #[cfg(target_arch = "x86_64")]
    if let Some(avx2) = Avx2::detect() {
        let avx = avx2.boxes();
        // SAFETY: `render_tile_avx2` only requires the CPU features it
        // enables, and an `Avx2` exists only on a CPU found to have each of
        // them (AVX2 implies the AVX and SSE levels below it).
        return unsafe {
            if spheres {
                render_tile_avx2(scene, opts, level, tile, SpheresFirst(avx))
            } else {
                render_tile_avx2(scene, opts, level, tile, avx)
            }
        };
    }
    if spheres {
        render_tile_body(
            scene,
            opts,
            level,
            tile,
            &mut NoSink,
            SpheresFirst(Portable),
        )
    } else {
        render_tile_body(scene, opts, level, tile, &mut NoSink, Portable)
    }
}

/// [`render_tile_body`] compiled for AVX2 and the bit-manipulation
/// extensions every AVX2 CPU has: the tracer's hot functions are
/// `#[inline(always)]`, so they are compiled here with VEX-encoded vector
/// instructions (three-operand forms, fewer register copies) and single
/// instructions for the traversal's bit scans and counts (about 10 % fewer
/// instructions per sample on `scenes/caustic-box.toml`). No fused
/// multiply-add is enabled, so every operation rounds as in the baseline
/// build and images are bit-identical on CPUs with and without AVX2.
/// `boxes` are the AVX tests, [`SpheresFirst`] or not.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,bmi1,bmi2,lzcnt,popcnt")]
fn render_tile_avx2(
    scene: &Scene,
    opts: &RenderOptions,
    level: Option<RecordLevel>,
    tile: UVec2,
    boxes: impl BoxTest,
) -> TileOutput {
    render_tile_body(scene, opts, level, tile, &mut NoSink, boxes)
}

/// Renders one tile, box tests by `boxes`, every ray cast reported to `sink`.
#[inline(always)]
fn render_tile_body(
    scene: &Scene,
    opts: &RenderOptions,
    level: Option<RecordLevel>,
    tile: UVec2,
    sink: &mut impl RaySink,
    boxes: impl BoxTest,
) -> TileOutput {
    let (w, h) = (scene.camera().width, scene.camera().height);
    let film_rays = scene.camera().film_rays();
    let mut out = TileOutput {
        pixels: Vec::new(),
        records: Vec::new(),
        counters: TraceCounters::default(),
        rays: RayLog::default(),
    };
    for y in tile.y * TILE..((tile.y + 1) * TILE).min(h) {
        for x in tile.x * TILE..((tile.x + 1) * TILE).min(w) {
            let pixel = UVec2::new(x, y);
            let keys = PixelKeys::new(opts.seed, y * w + x, opts.spp);
            let mut sum = Vec3::ZERO;
            let mut camera = camera_sample(&film_rays, &keys, pixel, 0);
            for s in 0..opts.spp {
                // The next sample's camera ray is made before this sample's
                // path is traced: it does not depend on the path, and made
                // after it, its latency (hashes, a normalisation) would
                // follow the path's last branch.
                let current = camera;
                if s + 1 < opts.spp {
                    camera = camera_sample(&film_rays, &keys, pixel, s + 1);
                }
                let l = match level {
                    Some(level) => {
                        let mut rec = PathRecord::default();
                        let l = trace_pixel_sample(
                            scene,
                            opts,
                            current,
                            Some((level, &mut rec)),
                            &mut out.counters,
                            sink,
                            boxes,
                        );
                        out.records.push(rec);
                        l
                    }
                    None => trace_pixel_sample(
                        scene,
                        opts,
                        current,
                        None,
                        &mut out.counters,
                        sink,
                        boxes,
                    ),
                };
                sum += l;
            }
            out.pixels.push((pixel, sum / opts.spp as f32));
        }
    }
    out
}

/// A pixel sample: which it is, its random stream, where it falls on the
/// film (pixel units) and its camera ray ([`camera_sample`]).
#[derive(Clone, Copy)]
struct CameraSample<'a> {
    pixel: UVec2,
    sample: u32,
    sampler: PixelSampler<'a>,
    film: Vec2,
    ray: Ray,
}

/// Sample `sample` of `pixel`: its stream (the pixel's `keys`), film
/// position and camera ray (by `film_rays`).
#[inline(always)]
fn camera_sample<'a>(
    film_rays: &FilmRays,
    keys: &'a PixelKeys,
    pixel: UVec2,
    sample: u32,
) -> CameraSample<'a> {
    let sampler = keys.sampler(sample);
    let film = pixel.as_vec2() + sampler.get_2d(DIM_FILM);
    CameraSample {
        pixel,
        sample,
        sampler,
        film,
        ray: film_rays.ray(film),
    }
}

/// Traces a pixel sample from its [`camera_sample`] (box tests by `boxes`,
/// rays reported to `sink`); returns its radiance (zero, counted, and its
/// record marked dropped, when it was not finite).
#[inline(always)]
fn trace_pixel_sample(
    scene: &Scene,
    opts: &RenderOptions,
    CameraSample {
        pixel,
        sample,
        sampler,
        film,
        ray,
    }: CameraSample<'_>,
    record: Option<(RecordLevel, &mut PathRecord)>,
    counters: &mut TraceCounters,
    sink: &mut impl RaySink,
    boxes: impl BoxTest,
) -> Vec3 {
    let mut rec = record.map(|(level, rec)| {
        *rec = PathRecord {
            pixel,
            sample,
            film,
            ..PathRecord::default()
        };
        Recording {
            level,
            rec,
            done: false,
        }
    });
    let l = trace_path(
        scene,
        opts,
        ray,
        &sampler,
        rec.as_mut(),
        counters,
        sink,
        boxes,
    );
    if l.is_finite() {
        if let Some(r) = rec {
            r.rec.radiance = l;
        }
        l
    } else {
        counters.non_finite += 1;
        if let Some(r) = rec {
            r.rec.drop_sample(SampleDrop::NonFinite);
        }
        Vec3::ZERO
    }
}
