//! The forward path tracer: unidirectional, next-event estimation with
//! multiple importance sampling (power heuristic), Russian roulette, rayon
//! over tiles, and optional path recording.
//!
//! Determinism: every random number comes from a
//! [`PixelSampler`](crate::sampler::PixelSampler), keyed by
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

use glam::{UVec2, Vec3};
use rayon::prelude::*;

mod chain;
mod path;
mod tiles;
#[cfg(target_arch = "x86_64")]
mod wide;

use tiles::{camera_sample, render_tiles, trace_pixel_sample};

use crate::bvh::Portable;
use crate::film::Image;
use crate::ray::Ray;
use crate::record::{PathRecord, RecordLevel};
use crate::sampler::PixelKeys;
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
    /// image, and a record marked [`SampleDrop::NonFinite`](crate::record::SampleDrop::NonFinite)).
    pub non_finite: u64,
    /// Paths ended because the sampled direction lay on the wrong side of the
    /// geometric normal for its lobe (shading-normal light leak).
    pub leaks: u64,
    /// Manifold next-event connections through glass that reached their light.
    pub chains: u64,
    /// Manifold next-event seeds (a straight shadow segment crossing glass)
    /// whose chain was not found: Newton did not converge, or the chain
    /// changed its interfaces, reflected totally, or was blocked before the
    /// light. They add nothing.
    pub chain_misses: u64,
}

impl TraceCounters {
    fn add(&mut self, o: &TraceCounters) {
        self.rays += o.rays;
        self.shadow_rays += o.shadow_rays;
        self.non_finite += o.non_finite;
        self.leaks += o.leaks;
        self.chains += o.chains;
        self.chain_misses += o.chain_misses;
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
            Self::Avx2 => crate::bvh::Avx2::detect().map(Backend::Avx2),
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

/// [`render`] with the bounce loop `kernel` (a scene that makes connections
/// through glass, [`Scene::chains_to_lights`], renders with the scalar loop
/// whatever `kernel`).
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

struct TileOutput {
    pixels: Vec<(UVec2, Vec3)>,
    records: Vec<PathRecord>,
    counters: TraceCounters,
    /// The rays cast, when logged.
    rays: RayLog,
}
