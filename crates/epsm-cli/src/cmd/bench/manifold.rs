//! `epsm bench manifold`: adjoint manifold solves per second on traced
//! paths, by path type and path length, with all threads.
//!
//! ```text
//! epsm bench manifold <SCENE>... [--samples N] [--seconds S] [--threads N] [--json]
//! ```
//!
//! Each scene is traced at `--samples` random pixel samples (full records),
//! every parameter default-bound (translations of objects, point lights and
//! the camera); the classification itself (with each path's projection onto
//! its manifold) is timed once, and the classified paths are grouped by type and length (the
//! vertices after the camera, the light point included). Each group is
//! solved in adjoint mode (`epsm_core::solve_adjoint`, one loss gradient per
//! path) repeatedly for at least `--seconds` (small groups are cycled into
//! batches of at least 4096 solves so that thread start-up does not count);
//! the rate counts every attempted solve, dropped ones included (their share
//! is reported). Besides wall-clock solves per second it reports solves per
//! CPU-second of the process (Linux: from `/proc/self/stat`),
//! which times the number of threads is the rate on an otherwise idle machine.

use std::collections::BTreeMap;
use std::path::PathBuf;
use std::time::Instant;

use epsm_core::{DiffPath, Motion, ParamTable, PathKind, SolveSettings, classify, solve_adjoint};
use epsm_render::record::RecordLevel;
use epsm_render::tracer::{PixelSample, RenderOptions, trace_samples};
use epsm_scene::load::load_scene;
use glam::{DVec2, UVec2};
use rayon::prelude::*;

/// Arguments of `epsm bench manifold`.
#[derive(clap::Args, Debug)]
pub struct ManifoldBenchArgs {
    /// Scene files whose traced paths are solved.
    #[arg(required = true)]
    pub scenes: Vec<PathBuf>,
    /// Pixel samples traced per scene (random pixels).
    #[arg(long, default_value_t = 20000)]
    pub samples: u32,
    /// Minimum timed seconds per group.
    #[arg(long, default_value_t = 0.5)]
    pub seconds: f64,
    /// Worker threads (default: all cores).
    #[arg(long)]
    pub threads: Option<usize>,
    /// Print one JSON object per group instead of text.
    #[arg(long)]
    pub json: bool,
}

/// Paths of one type and length.
type Groups = BTreeMap<(PathKind, usize), Vec<DiffPath>>;

/// Runs `epsm bench manifold`.
pub fn run(args: &ManifoldBenchArgs) -> anyhow::Result<()> {
    anyhow::ensure!(
        (1..=crate::cmd::check::MAX_SAMPLES).contains(&args.samples),
        "--samples must be in [1, {}], got {}",
        crate::cmd::check::MAX_SAMPLES,
        args.samples
    );
    anyhow::ensure!(
        args.seconds.is_finite() && args.seconds > 0.0,
        "--seconds must be a positive number, got {}",
        args.seconds
    );
    crate::cmd::check_threads(args.threads)?;
    for path in &args.scenes {
        let scene = load_scene(path)?;
        let mut table = ParamTable::new(&scene);
        table.add_default_geometry()?;
        let opts = RenderOptions::from_scene(&scene);
        let (w, h) = (scene.camera().width, scene.camera().height);
        let samples: Vec<PixelSample> = (0..args.samples)
            .map(|i| {
                let k = u64::from(i).wrapping_mul(0x9E37_79B9_7F4A_7C15) >> 16;
                PixelSample {
                    pixel: UVec2::new(
                        (k % u64::from(w)) as u32,
                        ((k / u64::from(w)) % u64::from(h)) as u32,
                    ),
                    sample: i % opts.spp.max(1),
                }
            })
            .collect();
        let records = trace_samples(&scene, &opts, &samples, RecordLevel::Full);
        let motion = table.motion(&table.values());
        let settings = SolveSettings::for_radius(scene.radius());
        // Classification (with the projection onto the manifold), timed once.
        let (start, cpu0) = (Instant::now(), cpu_seconds());
        let classified: Vec<_> = crate::cmd::with_threads(args.threads, || {
            records
                .par_iter()
                .map(|r| classify(r, &scene, &motion, &settings).paths)
                .collect()
        })?;
        let (wall, cpu) = (
            start.elapsed().as_secs_f64(),
            cpu_seconds().zip(cpu0).map(|(b, a)| b - a),
        );
        let mut groups = Groups::new();
        for p in classified.into_iter().flatten() {
            groups
                .entry((p.kind, p.nodes.len() - 1))
                .or_default()
                .push(p);
        }
        let n_paths: usize = groups.values().map(Vec::len).sum();
        let row = serde_json::json!({
            "scene": path.display().to_string(),
            "type": "classify",
            "records": records.len(),
            "paths": n_paths,
            "records_per_s": records.len() as f64 / wall,
            "records_per_cpu_s": cpu.filter(|c| *c > 0.0).map(|c| records.len() as f64 / c),
        });
        if args.json {
            println!("{row}");
        } else {
            println!(
                "{}  classify + project: {} records -> {} paths, {:.0} records/s",
                path.display(),
                records.len(),
                n_paths,
                records.len() as f64 / wall
            );
        }
        for ((kind, len), paths) in &groups {
            let m = crate::cmd::with_threads(args.threads, || {
                measure(paths, &motion, &settings, args.seconds)
            })?;
            let row = serde_json::json!({
                "scene": path.display().to_string(),
                "type": kind.name(),
                "length": len,
                "paths": paths.len(),
                "threads": args.threads.unwrap_or_else(rayon::current_num_threads),
                "paths_per_s": m.per_second,
                "paths_per_cpu_s": m.per_cpu_second,
                "dropped_fraction": m.dropped,
            });
            if args.json {
                println!("{row}");
            } else {
                println!(
                    "{}  {:<18} length {:>2}  {:>7} paths  {:>10.0} paths/s  {:>10.0} per cpu-s  dropped {:.2}%",
                    path.display(),
                    kind.name(),
                    len,
                    paths.len(),
                    m.per_second,
                    m.per_cpu_second.unwrap_or(f64::NAN),
                    100.0 * m.dropped
                );
            }
        }
    }
    Ok(())
}

/// Throughput of one group.
struct Measured {
    /// Solves per wall-clock second.
    per_second: f64,
    /// Solves per CPU-second of this process's threads, when the OS tells.
    per_cpu_second: Option<f64>,
    /// Fraction of solves dropped.
    dropped: f64,
}

/// User + system CPU time of this process, all threads (Linux
/// `/proc/self/stat`, in `USER_HZ` = 100 ticks per second).
fn cpu_seconds() -> Option<f64> {
    let stat = std::fs::read_to_string("/proc/self/stat").ok()?;
    let fields: Vec<&str> = stat.rsplit(')').next()?.split_whitespace().collect();
    let ticks = fields.get(11)?.parse::<f64>().ok()? + fields.get(12)?.parse::<f64>().ok()?;
    Some(ticks / 100.0)
}

/// Solves `paths` (cycled into batches of at least 4096) repeatedly for at
/// least `seconds`.
fn measure(
    paths: &[DiffPath],
    motion: &Motion,
    settings: &SolveSettings,
    seconds: f64,
) -> Measured {
    let g = DVec2::new(1.0, 0.5);
    let batch: Vec<&DiffPath> = paths.iter().cycle().take(paths.len().max(4096)).collect();
    let (start, cpu0) = (Instant::now(), cpu_seconds());
    let (mut solves, mut dropped) = (0usize, 0usize);
    while solves == 0 || start.elapsed().as_secs_f64() < seconds {
        dropped += batch
            .par_iter()
            .filter(|p| solve_adjoint(p, g, motion, settings).is_err())
            .count();
        solves += batch.len();
    }
    let wall = start.elapsed().as_secs_f64();
    let cpu = cpu_seconds()
        .zip(cpu0)
        .map(|(b, a)| b - a)
        .filter(|c| *c > 0.0);
    Measured {
        per_second: solves as f64 / wall,
        per_cpu_second: cpu.map(|c| solves as f64 / c),
        dropped: dropped as f64 / solves as f64,
    }
}
