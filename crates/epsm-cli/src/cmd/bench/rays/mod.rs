//! `epsm bench rays`: BVH build and ray throughput on a bumpy sphere, or on
//! the rays a render of a scene file casts.
//!
//! The scene is a displaced geodesic sphere (an icosahedron whose faces are
//! split into `k²` triangles each, projected to the unit sphere and displaced
//! radially by a few sines) as one object, plus four smaller instances of the
//! same mesh around it (one shared bottom-level BVH). Measured: the build, the
//! top-level update after moving one instance, and rays per second for
//! closest hit and occlusion on coherent rays (a camera's pixel grid, in
//! scanline order) and incoherent rays (uniform origins in the scene's box,
//! uniform directions), on 1 and 2 rayon threads.
//!
//! With `--scene`, the scene file is rendered once at `--spp` with every ray
//! logged (`epsm_render::tracer::render_logged`), and its camera rays
//! (closest hit), continuation rays (closest hit) and shadow rays
//! (occlusion) are each walked back to back, in the order the render cast
//! them: the walks without the shading between them, on the ray
//! distribution of the path tracer itself. The walks are compiled as the
//! render's tile loop is (`Accel::closest_hit`: AVX2 where the CPU has it).
//! Each set is then walked again by the batch walks (`Accel::closest_hits`,
//! `Accel::occluded_rays`: sixteen rays at a time where the CPU has
//! AVX-512), reported beside the scalar rate.
//!
//! Each run walks its ray set again until 0.2 s have passed and reports
//! the time per pass (a render's camera rays alone take a few
//! milliseconds).
//!
//! | option | unit | default | range |
//! |---|---|---|---|
//! | `--triangles` | triangles in the sphere | 100000 | [20, 2²²] |
//! | `--rays` | rays per measurement | 1000000 | [1, 2²⁵] |
//! | `--scene` | a scene file (TOML, Mitsuba XML, glTF) instead of the sphere | — | — |
//! | `--spp` | samples per pixel of the logged render (with `--scene`) | 16 | [1, 4096] |
//! | `--threads` | rayon threads (one run) | 1 and 2 | ≥ 1 |
//! | `--repeat` | runs per measurement, fastest reported | 3 | ≥ 1 |
//! | `--json` | print one JSON object | off | — |
//! | `--dump` | a folder: write the sphere's triangles and ray sets there (below) | — | — |
//!
//! With `--dump DIR` (the sphere only), the benchmark also writes what it
//! walks, for another ray tracer to walk the same rays
//! (`scripts/embree-compare.py`): `triangles.f32`, every object's triangles
//! in world space (`f32` little-endian, nine per triangle: three vertices of
//! `x, y, z`), and `coherent.f32` and `incoherent.f32`, six `f32` per ray
//! (origin, then direction; `t` in `[0, ∞)`).
//!
//! `cargo run --release -p epsm-cli -- bench rays --json`
//! `cargo run --release -p epsm-cli -- bench rays --scene scenes/caustic-box.toml`

mod dump;
mod measure;
mod report;
mod scene;

use std::path::PathBuf;
use std::sync::Arc;
use std::time::Instant;

use anyhow::Context;
use epsm_render::bvh::Accel;
use epsm_render::scene::Object;
use epsm_render::tracer::{RenderOptions, render_logged};
use epsm_render::{Camera, Ray};
use epsm_scene::load::load_scene;
use glam::{DVec3, Vec2};
use measure::{Run, Walk, measure};
use report::{Report, Throughput, print};

/// Most triangles of the sphere (about 1.5 GB with its BVH).
const MAX_TRIANGLES: usize = 1 << 22;
/// Most rays per measurement (two sets of 32-byte rays: 2 GB).
const MAX_RAYS: usize = 1 << 25;
/// Most samples per pixel of a logged render (`--scene`).
const MAX_SPP: u32 = 4096;
/// Most rays a logged render may cast (32 bytes each: 4 GB).
const MAX_LOGGED_RAYS: u64 = 1 << 27;

/// Options of `epsm bench rays`.
#[derive(clap::Args, Debug)]
pub struct RaysBenchArgs {
    /// Triangles in the bumpy sphere (rounded to 20·k²).
    #[arg(long, default_value_t = 100_000, conflicts_with = "scene")]
    pub triangles: usize,
    /// Rays per measurement.
    #[arg(long, default_value_t = 1_000_000, conflicts_with = "scene")]
    pub rays: usize,
    /// Walk the rays a render of this scene file casts instead (camera,
    /// continuation and shadow rays).
    #[arg(long)]
    pub scene: Option<PathBuf>,
    /// Samples per pixel of the logged render (with --scene).
    #[arg(long, default_value_t = 16, requires = "scene")]
    pub spp: u32,
    /// Rayon threads (default: measure 1 and 2).
    #[arg(long)]
    pub threads: Option<usize>,
    /// Runs of each measurement; the fastest counts (the machine may be shared).
    #[arg(long, default_value_t = 3)]
    pub repeat: usize,
    /// Print one JSON object instead of text.
    #[arg(long)]
    pub json: bool,
    /// Write the sphere's world-space triangles and the ray sets to this
    /// folder (`triangles.f32`, `coherent.f32`, `incoherent.f32`).
    #[arg(long, conflicts_with = "scene")]
    pub dump: Option<PathBuf>,
}

/// One set of rays to walk, and how.
struct RaySet {
    /// What the rays are (`coherent`, `camera`, ...).
    name: &'static str,
    rays: Vec<Ray>,
    /// The walks to time, in order: occlusion (`true`) or closest hit.
    queries: &'static [bool],
}

/// Runs the benchmark.
pub fn run(args: &RaysBenchArgs) -> anyhow::Result<()> {
    crate::cmd::check_threads(args.threads)?;
    anyhow::ensure!(args.repeat >= 1, "--repeat must be at least 1");
    match &args.scene {
        Some(path) => {
            anyhow::ensure!(
                (1..=MAX_SPP).contains(&args.spp),
                "--spp must be in [1, {MAX_SPP}], got {}",
                args.spp
            );
            let scene = load_scene(path)?;
            let sets = scene_rays(&scene, args.spp)?;
            let stats = scene.accel().stats();
            let report = Report {
                scene: Some(path.display().to_string()),
                spp: Some(args.spp),
                triangles: stats.triangles,
                spheres: stats.spheres,
                instances: stats.objects,
                build_seconds: stats.build_seconds,
                tlas_update_seconds: None,
                accel_bytes: stats.bytes,
                batched_wide: Some(Accel::batches_wide()),
                throughput: throughputs(scene.accel(), &sets, args, true)?,
            };
            print(&report, args.json)
        }
        None => sphere(args),
    }
}

/// The rays a render of `scene` at `spp` samples per pixel casts: camera and
/// continuation rays (closest hit), shadow rays (occlusion).
fn scene_rays(scene: &epsm_render::Scene, spp: u32) -> anyhow::Result<Vec<RaySet>> {
    let opts = RenderOptions {
        spp,
        ..RenderOptions::from_scene(scene)
    };
    let camera = scene.camera();
    // A sample casts at most `max_depth + 1` closest-hit rays and
    // `max_depth` shadow rays.
    let bound = u64::from(camera.width)
        * u64::from(camera.height)
        * u64::from(spp)
        * (2 * u64::from(opts.max_depth) + 1);
    anyhow::ensure!(
        bound <= MAX_LOGGED_RAYS,
        "--spp {spp}: the render could cast {bound} rays, more than the {MAX_LOGGED_RAYS} \
         a logged render may hold; use a smaller --spp"
    );
    let (_, log) = render_logged(scene, &opts, &|_| {});
    Ok(vec![
        RaySet {
            name: "camera",
            rays: log.camera,
            queries: &[false],
        },
        RaySet {
            name: "bounce",
            rays: log.bounce,
            queries: &[false],
        },
        RaySet {
            name: "shadow",
            rays: log.shadow,
            queries: &[true],
        },
    ])
}

/// The bumpy sphere's benchmark.
fn sphere(args: &RaysBenchArgs) -> anyhow::Result<()> {
    anyhow::ensure!(
        (20..=MAX_TRIANGLES).contains(&args.triangles),
        "--triangles must be in [20, {MAX_TRIANGLES}], got {}",
        args.triangles
    );
    anyhow::ensure!(
        (1..=MAX_RAYS).contains(&args.rays),
        "--rays must be in [1, {MAX_RAYS}], got {}",
        args.rays
    );
    let mesh = Arc::new(scene::bumpy_sphere(args.triangles));
    let mut objects = scene::scene(&mesh);
    let mut accel = Accel::build(&objects);
    let build_seconds = accel.stats().build_seconds;
    let tlas_update_seconds = tlas_update(&mut accel, &mut objects);

    let (lo, hi) = accel.world_bounds().context("empty scene")?;
    let camera = Camera::look_at(
        DVec3::new(0.0, 0.5, 4.5),
        DVec3::ZERO,
        DVec3::Y,
        40.0,
        1000,
        1000,
    )
    .context("camera")?;
    let side = (args.rays as f64).sqrt().ceil() as u32;
    let coherent: Vec<Ray> = (0..args.rays as u32)
        .map(|i| {
            let film = Vec2::new((i % side) as f32 + 0.5, (i / side) as f32 + 0.5)
                * (1000.0 / side as f32);
            camera.ray(film)
        })
        .collect();
    let incoherent = scene::random_rays(args.rays, lo, hi);
    if let Some(dir) = &args.dump {
        dump::write(dir, &objects, &coherent, &incoherent)?;
    }
    let sets = [("coherent", coherent), ("incoherent", incoherent)].map(|(name, rays)| RaySet {
        name,
        rays,
        queries: &[false, true],
    });
    let stats = accel.stats();
    let report = Report {
        scene: None,
        spp: None,
        triangles: mesh.len(),
        spheres: stats.spheres,
        instances: stats.objects,
        build_seconds,
        tlas_update_seconds: Some(tlas_update_seconds),
        accel_bytes: stats.bytes,
        batched_wide: None,
        throughput: throughputs(&accel, &sets, args, false)?,
    };
    print(&report, args.json)
}

/// Each ray set's throughput on one and two threads (or `--threads`), the
/// fastest of `--repeat` runs; with `batched`, also through the batch walks.
fn throughputs(
    accel: &Accel,
    sets: &[RaySet],
    args: &RaysBenchArgs,
    batched: bool,
) -> anyhow::Result<Vec<Throughput>> {
    let thread_counts = args.threads.map_or(vec![1, 2], |n| vec![n]);
    // All pools live to the end: a thread exiting mid-measurement would take
    // its CPU time out of the process total.
    let pools = thread_counts
        .iter()
        .map(|&n| rayon::ThreadPoolBuilder::new().num_threads(n).build())
        .collect::<Result<Vec<_>, _>>()?;
    let mut throughput = Vec::new();
    for (&threads, pool) in thread_counts.iter().zip(&pools) {
        let walks = sets
            .iter()
            .filter(|s| !s.rays.is_empty())
            .flat_map(|s| s.queries.iter().map(move |&occlusion| (s, occlusion)));
        for (set, occlusion) in walks {
            let fastest = |walk: Walk| {
                let runs = (0..args.repeat.max(1))
                    .map(|_| pool.install(|| measure(accel, &set.rays, walk)));
                runs.fold(None, |best: Option<Run>, run| match best {
                    Some(b) if b.seconds <= run.seconds => Some(b),
                    _ => Some(run),
                })
                .context("no run")
            };
            let Run {
                seconds,
                cpu_seconds,
                hits,
            } = fastest(Walk {
                occlusion,
                batched: false,
            })?;
            let batch = if batched {
                Some(fastest(Walk {
                    occlusion,
                    batched: true,
                })?)
            } else {
                None
            };
            let rays = set.rays.len() as f64;
            throughput.push(Throughput {
                threads,
                rays: set.name,
                count: set.rays.len(),
                query: if occlusion { "occluded" } else { "closest" },
                mrays_per_s: rays / seconds / 1e6,
                mrays_per_cpu_s: cpu_seconds.map(|c| rays / c / 1e6),
                hit_fraction: hits as f64 / rays,
                batched_mrays_per_s: batch.map(|b| rays / b.seconds / 1e6),
                batched_mrays_per_cpu_s: batch.and_then(|b| b.cpu_seconds).map(|c| rays / c / 1e6),
                batched_hit_fraction: batch.map(|b| b.hits as f64 / rays),
            });
        }
    }
    Ok(throughput)
}

/// Mean time of moving one instance and updating the top level, seconds.
fn tlas_update(accel: &mut Accel, objects: &mut [Object]) -> f64 {
    const MOVES: usize = 200;
    let start = Instant::now();
    for k in 0..MOVES {
        let angle = k as f64 * 0.01;
        objects[1].world_from_object =
            scene::placement(DVec3::new(2.5 * angle.cos(), 0.0, 2.5 * angle.sin()), 0.4);
        accel.update_instance(objects, 1);
    }
    start.elapsed().as_secs_f64() / MOVES as f64
}
