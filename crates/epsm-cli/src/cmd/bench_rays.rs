//! `epsm bench rays`: BVH build and ray throughput on a bumpy sphere.
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
//! | option | unit | default | range |
//! |---|---|---|---|
//! | `--triangles` | triangles in the sphere | 100000 | [20, 2²²] |
//! | `--rays` | rays per measurement | 1000000 | [1, 2²⁵] |
//! | `--threads` | rayon threads (one run) | 1 and 2 | ≥ 1 |
//! | `--repeat` | runs per measurement, fastest reported | 3 | ≥ 1 |
//! | `--json` | print one JSON object | off | — |
//!
//! `cargo run --release -p epsm-cli -- bench rays --json`

mod scene;

use std::sync::Arc;
use std::time::Instant;

use anyhow::Context;
use epsm_render::bvh::Accel;
use epsm_render::scene::Object;
use epsm_render::{Camera, Ray};
use glam::{DVec3, Vec2};
use rayon::prelude::*;
use serde::Serialize;

/// Most triangles of the sphere (about 1.5 GB with its BVH).
const MAX_TRIANGLES: usize = 1 << 22;
/// Most rays per measurement (two sets of 32-byte rays: 2 GB).
const MAX_RAYS: usize = 1 << 25;

/// Options of `epsm bench rays`.
#[derive(clap::Args, Debug)]
pub struct RaysBenchArgs {
    /// Triangles in the bumpy sphere (rounded to 20·k²).
    #[arg(long, default_value_t = 100_000)]
    pub triangles: usize,
    /// Rays per measurement.
    #[arg(long, default_value_t = 1_000_000)]
    pub rays: usize,
    /// Rayon threads (default: measure 1 and 2).
    #[arg(long)]
    pub threads: Option<usize>,
    /// Runs of each measurement; the fastest counts (the machine may be shared).
    #[arg(long, default_value_t = 3)]
    pub repeat: usize,
    /// Print one JSON object instead of text.
    #[arg(long)]
    pub json: bool,
}

/// Throughput of one ray set on one thread count.
#[derive(Serialize)]
struct Throughput {
    threads: usize,
    rays: &'static str,
    query: &'static str,
    mrays_per_s: f64,
    /// Rays per CPU-second of the process (Linux only): the rate per busy
    /// core, insensitive to other processes taking the cores.
    mrays_per_cpu_s: Option<f64>,
    hit_fraction: f64,
}

/// Everything measured.
#[derive(Serialize)]
struct Report {
    triangles: usize,
    instances: usize,
    build_seconds: f64,
    tlas_update_seconds: f64,
    accel_bytes: usize,
    throughput: Vec<Throughput>,
}

/// Runs the benchmark.
pub fn run(args: &RaysBenchArgs) -> anyhow::Result<()> {
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
    super::check_threads(args.threads)?;
    anyhow::ensure!(args.repeat >= 1, "--repeat must be at least 1");
    let mesh = Arc::new(scene::bumpy_sphere(args.triangles));
    let objects = scene::scene(&mesh);
    let mut accel = Accel::build(&objects);
    let build_seconds = accel.stats().build_seconds;
    let tlas_update_seconds = tlas_update(&mut accel, objects);

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

    let thread_counts = args.threads.map_or(vec![1, 2], |n| vec![n]);
    // All pools live to the end: a thread exiting mid-measurement would take
    // its CPU time out of the process total.
    let pools = thread_counts
        .iter()
        .map(|&n| rayon::ThreadPoolBuilder::new().num_threads(n).build())
        .collect::<Result<Vec<_>, _>>()?;
    let mut throughput = Vec::new();
    for (&threads, pool) in thread_counts.iter().zip(&pools) {
        for (name, rays) in [("coherent", &coherent), ("incoherent", &incoherent)] {
            for query in ["closest", "occluded"] {
                let runs = (0..args.repeat.max(1))
                    .map(|_| pool.install(|| measure(&accel, rays, query == "occluded")));
                let best = runs.fold(None, |best: Option<Run>, run| match best {
                    Some(b) if b.seconds <= run.seconds => Some(b),
                    _ => Some(run),
                });
                let Run {
                    seconds,
                    cpu_seconds,
                    hits,
                } = best.context("no run")?;
                throughput.push(Throughput {
                    threads,
                    rays: name,
                    query,
                    mrays_per_s: rays.len() as f64 / seconds / 1e6,
                    mrays_per_cpu_s: cpu_seconds.map(|c| rays.len() as f64 / c / 1e6),
                    hit_fraction: hits as f64 / rays.len() as f64,
                });
            }
        }
    }
    let stats = accel.stats();
    let report = Report {
        triangles: mesh.len(),
        instances: stats.objects,
        build_seconds,
        tlas_update_seconds,
        accel_bytes: stats.bytes,
        throughput,
    };
    print(&report, args.json)
}

fn print(report: &Report, json: bool) -> anyhow::Result<()> {
    if json {
        println!("{}", serde_json::to_string(report)?);
        return Ok(());
    }
    println!(
        "{} triangles, {} instances: build {:.1} ms, TLAS update {:.1} µs, {:.1} MB",
        report.triangles,
        report.instances,
        report.build_seconds * 1e3,
        report.tlas_update_seconds * 1e6,
        report.accel_bytes as f64 / 1e6
    );
    for t in &report.throughput {
        println!(
            "{} thread(s) {:>10} {:>8}: {:6.2} Mrays/s, {:6.2} Mrays/CPU-s ({:.0}% hit)",
            t.threads,
            t.rays,
            t.query,
            t.mrays_per_s,
            t.mrays_per_cpu_s.unwrap_or(f64::NAN),
            t.hit_fraction * 100.0
        );
    }
    Ok(())
}

/// One timed pass over a ray set.
#[derive(Clone, Copy)]
struct Run {
    seconds: f64,
    cpu_seconds: Option<f64>,
    hits: usize,
}

/// CPU time used so far by all threads of this process, seconds (Linux:
/// the first field of each `/proc/self/task/*/schedstat`, nanoseconds).
pub(super) fn cpu_seconds() -> Option<f64> {
    let mut total = 0u64;
    for task in std::fs::read_dir("/proc/self/task").ok()? {
        let stat = std::fs::read_to_string(task.ok()?.path().join("schedstat")).ok()?;
        total += stat.split_whitespace().next()?.parse::<u64>().ok()?;
    }
    Some(total as f64 * 1e-9)
}

/// Traces all rays in parallel chunks.
fn measure(accel: &Accel, rays: &[Ray], occlusion: bool) -> Run {
    let cpu_start = cpu_seconds();
    let start = Instant::now();
    let hits = rays
        .par_chunks(1024)
        .map(|chunk| {
            chunk
                .iter()
                .filter(|ray| {
                    if occlusion {
                        accel.occluded(ray)
                    } else {
                        accel.closest_hit(ray).is_some()
                    }
                })
                .count()
        })
        .sum();
    let seconds = start.elapsed().as_secs_f64();
    // The kernel updates a running thread's total at scheduler ticks (a few
    // ms), so very short runs may read zero: report nothing then.
    let cpu_seconds = cpu_seconds()
        .zip(cpu_start)
        .map(|(end, start)| end - start)
        .filter(|&c| c > 0.0);
    Run {
        seconds,
        cpu_seconds,
        hits,
    }
}

/// Mean time of moving one instance and updating the top level, seconds.
fn tlas_update(accel: &mut Accel, mut objects: Vec<Object>) -> f64 {
    const MOVES: usize = 200;
    let start = Instant::now();
    for k in 0..MOVES {
        let angle = k as f64 * 0.01;
        objects[1].world_from_object =
            scene::placement(DVec3::new(2.5 * angle.cos(), 0.0, 2.5 * angle.sin()), 0.4);
        accel.update_instance(&objects, 1);
    }
    start.elapsed().as_secs_f64() / MOVES as f64
}
