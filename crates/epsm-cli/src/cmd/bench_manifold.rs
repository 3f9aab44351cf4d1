//! `epsm bench manifold`: adjoint manifold solves per second on traced
//! paths, by path type and path length, with all threads.
//!
//! ```text
//! epsm bench manifold <SCENE>... [--samples N] [--seconds S] [--threads N] [--json]
//! ```
//!
//! Each scene is traced at `--samples` random pixel samples (full records),
//! every parameter default-bound (translations of objects, point lights and
//! the camera), and the classified paths are grouped by type and length (the
//! vertices after the camera, the light point included). Each group is
//! solved in adjoint mode (`epsm_core::solve_adjoint`, one loss gradient per
//! path) repeatedly for at least `--seconds`; the rate counts every attempted
//! solve, dropped ones included (their share is reported).

use std::collections::BTreeMap;
use std::path::PathBuf;
use std::time::Instant;

use epsm_core::{DiffPath, Motion, ParamTable, PathKind, SolveSettings, classify, solve_adjoint};
use epsm_render::record::RecordLevel;
use epsm_render::scene::load::load_scene;
use epsm_render::tracer::{PixelSample, RenderOptions, trace_samples};
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
        let mut groups = Groups::new();
        for record in &records {
            for p in classify(record, &scene, &motion).paths {
                groups
                    .entry((p.kind, p.nodes.len() - 1))
                    .or_default()
                    .push(p);
            }
        }
        let settings = SolveSettings::for_radius(scene.radius());
        for ((kind, len), paths) in &groups {
            let (rate, dropped) = super::with_threads(args.threads, || {
                measure(paths, &motion, &settings, args.seconds)
            })?;
            let row = serde_json::json!({
                "scene": path.display().to_string(),
                "type": kind.name(),
                "length": len,
                "paths": paths.len(),
                "threads": args.threads.unwrap_or_else(rayon::current_num_threads),
                "paths_per_s": rate,
                "dropped_fraction": dropped,
            });
            if args.json {
                println!("{row}");
            } else {
                println!(
                    "{}  {:<18} length {:>2}  {:>7} paths  {:>12.0} paths/s  dropped {:.2}%",
                    path.display(),
                    kind.name(),
                    len,
                    paths.len(),
                    rate,
                    100.0 * dropped
                );
            }
        }
    }
    Ok(())
}

/// Solves `paths` repeatedly for at least `seconds`; returns (solves per
/// second, fraction dropped).
fn measure(
    paths: &[DiffPath],
    motion: &Motion,
    settings: &SolveSettings,
    seconds: f64,
) -> (f64, f64) {
    let g = DVec2::new(1.0, 0.5);
    let start = Instant::now();
    let (mut solves, mut dropped) = (0usize, 0usize);
    while solves == 0 || start.elapsed().as_secs_f64() < seconds {
        dropped += paths
            .par_iter()
            .filter(|p| solve_adjoint(p, g, motion, settings).is_err())
            .count();
        solves += paths.len();
    }
    (
        solves as f64 / start.elapsed().as_secs_f64(),
        dropped as f64 / solves.max(1) as f64,
    )
}
