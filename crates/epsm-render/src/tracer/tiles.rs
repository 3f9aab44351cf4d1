//! The tile loop: tiles of [`TILE`]² pixels in parallel, each pixel's
//! samples in order; one pixel sample from its camera ray through
//! [`trace_path`] (the scalar tracer), or a tile (or a band of its rows,
//! `bands`) by the wide tracer.

use std::time::Instant;

use glam::{UVec2, Vec2, Vec3};
use rayon::prelude::*;

use super::path::{Recording, trace_path};
#[cfg(target_arch = "x86_64")]
use super::wide;
use super::{
    DIM_FILM, Kernel, NoSink, RayLog, RaySink, RenderOptions, RenderOutput, TILE, TileOutput,
    TraceCounters,
};
#[cfg(target_arch = "x86_64")]
use crate::bvh::Avx2;
use crate::bvh::{BoxTest, Portable, SpheresFirst};
use crate::camera::FilmRays;
use crate::film::Image;
use crate::ray::Ray;
use crate::record::{PathRecord, RecordLevel, SampleDrop};
use crate::sampler::{PixelKeys, PixelSampler};
use crate::scene::Scene;

/// Renders the tiles in parallel: the image, with the records at `level`,
/// and with `log` the rays cast; by the wide tracer where `kernel` names
/// one (images only: no records, no ray log) and the scene makes no
/// manifold next-event connections ([`Scene::chains_to_lights`]).
pub(super) fn render_tiles(
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
    let wide = (level.is_none() && !log && opts.spp > 0 && !scene.chains_to_lights())
        .then(|| kernel.backend())
        .flatten()
        .map(|backend| wide::WideTracer::new(scene, backend));
    #[cfg(target_arch = "x86_64")]
    let bands = if wide.is_some() { bands(opts.spp) } else { 1 };
    #[cfg(not(target_arch = "x86_64"))]
    let (bands, _) = (1, kernel);
    let mut tiles: Vec<TileOutput> = (0..tx * ty * bands)
        .into_par_iter()
        .map(|unit| {
            let t = unit / bands;
            let tile = UVec2::new(t % tx, t / tx);
            #[cfg(target_arch = "x86_64")]
            if let Some(wide) = &wide {
                let rows = TILE / bands;
                let y0 = tile.y * TILE + unit % bands * rows;
                let pixels: Vec<UVec2> = (y0..(y0 + rows).min(h))
                    .flat_map(|y| {
                        (tile.x * TILE..((tile.x + 1) * TILE).min(w)).map(move |x| UVec2::new(x, y))
                    })
                    .collect();
                let out = wide.render_pixels(scene, opts, &pixels);
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

/// Samples a band of a tile holds at least: a band smaller than this would
/// spend a larger share of its steps with lanes waiting for the last paths.
const BAND_SAMPLES: u64 = 16384;

/// Bands of rows each tile is cut into for the wide tracer at `spp` samples
/// per pixel: a power of two up to [`TILE`], each band holding at least
/// [`BAND_SAMPLES`] samples. A render with few tiles of many samples (the
/// 64² matched render at 256 samples per pixel: 16 tiles) gets enough
/// pieces that no thread waits long for the last one. Each pixel's samples
/// stay in one band and are summed in order, so the image does not depend
/// on the cut.
#[cfg(target_arch = "x86_64")]
fn bands(spp: u32) -> u32 {
    let tile = u64::from(TILE * TILE) * u64::from(spp);
    let most = (tile / BAND_SAMPLES).clamp(1, u64::from(TILE));
    1 << most.ilog2()
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
pub(super) struct CameraSample<'a> {
    pixel: UVec2,
    sample: u32,
    sampler: PixelSampler<'a>,
    film: Vec2,
    ray: Ray,
}

/// Sample `sample` of `pixel`: its stream (the pixel's `keys`), film
/// position and camera ray (by `film_rays`).
#[inline(always)]
pub(super) fn camera_sample<'a>(
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
pub(super) fn trace_pixel_sample(
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
