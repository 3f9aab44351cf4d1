//! `epsm bench render`: samples and rays per second on scene files, with
//! 1 and all threads (per wall-clock and per CPU second), BVH build time
//! and peak memory. The unidirectional path tracer is measured, as
//! Mitsuba's `path` integrator is: connections through glass
//! (`render.manifold_nee`) are off, so every kernel runs.

use std::path::PathBuf;
use std::time::Instant;

use epsm_render::tracer::{Kernel, RenderOptions, render_with};
use epsm_scene::load::{MAX_DEPTH, load_scene};

use super::cpu_seconds;

/// Arguments of `epsm bench render`.
#[derive(clap::Args, Debug)]
pub struct RenderBenchArgs {
    /// Scene files to measure.
    #[arg(required = true)]
    pub scenes: Vec<PathBuf>,
    /// Samples per pixel (default: the scene's).
    #[arg(long)]
    pub spp: Option<u32>,
    /// Maximum depth (default: the scene's).
    #[arg(long)]
    pub max_depth: Option<u32>,
    /// Timed repetitions per thread count (the best is reported).
    #[arg(long, default_value_t = 3)]
    pub repeats: u32,
    /// The bounce loops to time, comma-separated, alternating run by run:
    /// `fastest` (the wide tracer on the widest lanes the CPU has, else the
    /// scalar loop), `avx512`, `avx2`, `portable` (the wide tracer on those
    /// lanes) or `scalar` (one path at a time).
    #[arg(long, value_enum, value_delimiter = ',', default_value = "fastest")]
    pub kernel: Vec<KernelArg>,
    /// Print one JSON object per scene instead of text.
    #[arg(long)]
    pub json: bool,
}

/// `--kernel` values.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum KernelArg {
    /// The widest lanes the CPU has, else the scalar loop.
    Fastest,
    /// The wide tracer on AVX-512.
    Avx512,
    /// The wide tracer on AVX2.
    Avx2,
    /// The wide tracer on plain arrays.
    Portable,
    /// One path at a time.
    Scalar,
}

impl KernelArg {
    /// The tracer's kernel, resolved to the one that runs on this CPU, or
    /// an error naming the kernel this CPU cannot run.
    fn kernel(self) -> anyhow::Result<Kernel> {
        let kernel = match self {
            KernelArg::Fastest => Kernel::Fastest,
            KernelArg::Avx512 => Kernel::Avx512,
            KernelArg::Avx2 => Kernel::Avx2,
            KernelArg::Portable => Kernel::Portable,
            KernelArg::Scalar => Kernel::Scalar,
        };
        anyhow::ensure!(
            kernel.available(),
            "--kernel {}: this CPU cannot run it (it lacks the instructions)",
            kernel.name()
        );
        Ok(kernel.resolve())
    }
}

/// Runs `epsm bench render`.
pub fn run(args: &RenderBenchArgs) -> anyhow::Result<()> {
    anyhow::ensure!(args.spp != Some(0), "--spp must be at least 1");
    if let Some(d) = args.max_depth {
        anyhow::ensure!(
            (1..=MAX_DEPTH).contains(&d),
            "--max-depth must be in [1, {MAX_DEPTH}], got {d}"
        );
    }
    anyhow::ensure!(args.repeats >= 1, "--repeats must be at least 1");
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    let kernels = args
        .kernel
        .iter()
        .map(|k| k.kernel())
        .collect::<anyhow::Result<Vec<_>>>()?;
    for path in &args.scenes {
        let t0 = Instant::now();
        let mut scene = load_scene(path)?;
        scene.settings_mut().manifold_nee = false;
        let load_s = t0.elapsed().as_secs_f64();
        let mut opts = RenderOptions::from_scene(&scene);
        opts.spp = args.spp.unwrap_or(opts.spp);
        opts.max_depth = args.max_depth.unwrap_or(opts.max_depth);
        let thread_counts = [1, cores];
        // All pools live to the end: a thread exiting mid-measurement would
        // take its CPU time out of the process total.
        let pools = thread_counts
            .iter()
            .map(|&n| rayon::ThreadPoolBuilder::new().num_threads(n).build())
            .collect::<Result<Vec<_>, _>>()?;
        // Per kernel, per thread count: the fastest run and its CPU time.
        type Best = Option<(epsm_render::tracer::RenderOutput, Option<f64>)>;
        let mut best: Vec<Vec<Best>> = vec![vec![None; thread_counts.len()]; kernels.len()];
        for (t, pool) in pools.iter().enumerate() {
            // Kernels alternate run by run, so a change of machine load
            // affects them alike.
            for _ in 0..args.repeats.max(1) {
                for (k, &kernel) in kernels.iter().enumerate() {
                    let start = cpu_seconds();
                    let out = pool.install(|| render_with(&scene, &opts, kernel, &|_| {}));
                    let cpu = cpu_seconds()
                        .zip(start)
                        .map(|(end, start)| end - start)
                        .filter(|&c| c > 0.0);
                    let slot = &mut best[k][t];
                    if slot.as_ref().is_none_or(|(b, _)| out.seconds < b.seconds) {
                        *slot = Some((out, cpu));
                    }
                }
            }
        }
        let cam = scene.camera();
        for (kernel, runs) in kernels.iter().zip(best) {
            let results: Vec<_> = thread_counts
                .iter()
                .zip(runs)
                .filter_map(|(&threads, run)| {
                    let (b, cpu) = run?;
                    let rays = (b.counters.rays + b.counters.shadow_rays) as f64;
                    Some(serde_json::json!({
                        "threads": threads,
                        "seconds": b.seconds,
                        "samples_per_s": b.samples as f64 / b.seconds,
                        "samples_per_cpu_s": cpu.map(|c| b.samples as f64 / c),
                        "rays_per_s": rays / b.seconds,
                        "rays_per_sample": rays / b.samples as f64,
                    }))
                })
                .collect();
            let report = serde_json::json!({
                "scene": path.display().to_string(),
                "resolution": [cam.width, cam.height],
                "spp": opts.spp,
                "max_depth": opts.max_depth,
                "kernel": kernel.name(),
                "load_and_build_s": load_s,
                "runs": results,
                "peak_rss_mb": crate::cmd::peak_rss_mb(),
            });
            if args.json {
                println!("{report}");
            } else {
                println!("{}", serde_json::to_string_pretty(&report)?);
            }
        }
    }
    Ok(())
}
