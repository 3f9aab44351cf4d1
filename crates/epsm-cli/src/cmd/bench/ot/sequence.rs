//! `epsm bench ot --sequence K`: cold against warm-started matching along a rendered sequence.
//!
//! Renders a scene (`--scene`, default `scenes/layout.toml`) at the match
//! resolution `√n × √n` (`--n` a square) with one parameter (`--param`,
//! default `table.translate.x`, the table sliding along x) moved by `--step`
//! (scene units per step) over K steps, starting `--offset` from the scene
//! file's value; each step has its own sample seed, as the iterations of an
//! optimization do. The target is the scene at the file's value (16 × `--spp`
//! samples per pixel). Each step's image is matched to the target twice:
//! cold (`Matcher::solve`) and warm (`Matcher::solve_warm`, the state carried
//! from the previous step). Rendering is not timed. `--json` prints one object:
//!
//! | field               | meaning                                                    |
//! |---------------------|------------------------------------------------------------|
//! | `scene`, `param`    | the scene file and the moved parameter's key               |
//! | `n`, `side`         | points per cloud and the image side (pixels)               |
//! | `solver`            | `exact` or `sinkhorn`                                       |
//! | `spp`               | samples per pixel of each step's image                      |
//! | `steps`             | per step: `step`, `value` (the parameter), `cold_s`, `warm_s`, `speedup` (`cold_s / warm_s`), `cold_loss`, `warm_loss`, `warm_started` (the state was used), `warm_iterations` (exact: rounds of augmenting and checking; sinkhorn: updates), `warm_added_pairs` (exact: violated pairs the checks added), `warm_pair_evaluations`, `warm_phases` (seconds per phase of the warm solve) |
//! | `cold_median_s`     | median cold seconds over the steps after the first          |
//! | `warm_median_s`     | median warm seconds over the steps after the first (the first has no state) |
//! | `speedup`           | `cold_median_s / warm_median_s`                             |
//! | `max_loss_rel_diff` | largest `|warm_loss − cold_loss| / cold_loss` over the steps (exact: rounding only) |
//! | `peak_rss_mb`, `threads` | as for the single solve                                |
//!
//! ```text
//! epsm bench ot --sequence 10 --n 4096 --solver exact --json
//! ```

use std::collections::BTreeMap;
use std::path::PathBuf;
use std::time::Instant;

use anyhow::{Context, bail};
use epsm_core::ParamTable;
use epsm_core::loss::points;
use epsm_ot::{MatchState, Matcher, PointCloud};
use epsm_render::tracer::{RenderOptions, render};
use epsm_render::{Image, Scene};
use serde::Serialize;

/// Arguments of the sequence benchmark (besides `--n`, `--solver`, `--json`, `--blur`, `--scaling`).
#[derive(Debug, Clone, clap::Args)]
pub struct SequenceArgs {
    /// Run the sequence benchmark over this many steps (at least 2).
    #[arg(long)]
    pub sequence: Option<usize>,
    /// Scene of the sequence.
    #[arg(long, default_value = "scenes/layout.toml")]
    pub scene: PathBuf,
    /// Parameter key moved along the sequence.
    #[arg(long, default_value = "table.translate.x")]
    pub param: String,
    /// Parameter change per step (scene units).
    #[arg(long, default_value_t = 0.01)]
    pub step: f64,
    /// The first step's parameter value minus the scene file's.
    #[arg(long, default_value_t = -0.2, allow_hyphen_values = true)]
    pub offset: f64,
    /// Samples per pixel of each step's image.
    #[arg(long, default_value_t = 4)]
    pub spp: u32,
}

/// One step of the sequence, as printed with `--json`.
#[derive(Debug, Serialize)]
struct Step {
    step: usize,
    value: f64,
    cold_s: f64,
    warm_s: f64,
    speedup: f64,
    cold_loss: f64,
    warm_loss: f64,
    warm_started: bool,
    warm_iterations: usize,
    warm_added_pairs: usize,
    warm_pair_evaluations: u64,
    warm_phases: BTreeMap<&'static str, f64>,
}

/// The sequence benchmark's report.
#[derive(Debug, Serialize)]
struct Report {
    scene: String,
    param: String,
    n: usize,
    side: u32,
    solver: &'static str,
    spp: u32,
    steps: Vec<Step>,
    cold_median_s: f64,
    warm_median_s: f64,
    speedup: f64,
    max_loss_rel_diff: f64,
    peak_rss_mb: Option<f64>,
    threads: usize,
}

/// The scene at the match resolution with its one-parameter table.
struct Sequence {
    scene: Scene,
    table: ParamTable,
}

impl Sequence {
    fn load(args: &SequenceArgs, side: u32) -> anyhow::Result<Self> {
        let mut parts = epsm_scene::load_parts(&args.scene)
            .with_context(|| format!("loading {}", args.scene.display()))?;
        parts.camera.width = side;
        parts.camera.height = side;
        let mut scene = Scene::new(parts)?;
        let mut table = ParamTable::new(&scene);
        table
            .add(&args.param)
            .with_context(|| format!("--param `{}`", args.param))?;
        scene.set_dynamic(&table.moving_objects());
        Ok(Self { scene, table })
    }

    /// The image at parameter value `value`, `spp` samples per pixel, sample seed `seed`.
    fn render(&mut self, value: f64, spp: u32, seed: u32) -> Image {
        self.table.set_value(0, value);
        self.table.apply(&mut self.scene);
        let opts = RenderOptions {
            spp,
            seed,
            ..RenderOptions::from_scene(&self.scene)
        };
        render(&self.scene, &opts, &|_| {}).image
    }
}

/// Runs the sequence benchmark of `matcher` over `steps` steps and prints its report.
pub fn run(
    args: &SequenceArgs,
    steps: usize,
    n: usize,
    matcher: &Matcher,
    json: bool,
) -> anyhow::Result<()> {
    if steps < 2 {
        bail!("--sequence must be at least 2, got {steps}");
    }
    if matches!(matcher, Matcher::Sliced(_)) {
        bail!("--sequence needs --solver exact or sinkhorn (sliced keeps no state)");
    }
    if args.spp == 0 {
        bail!("--spp must be at least 1");
    }
    let side = n.isqrt();
    if side * side != n || side < 2 {
        bail!("--n must be a square of at least 4 with --sequence (the image is √n × √n), got {n}");
    }
    let side = u32::try_from(side).context("--n too large")?;
    let mut seq = Sequence::load(args, side)?;
    let start_value = seq.table.values()[0];
    let cloud = |image: &Image| -> anyhow::Result<PointCloud> { Ok(points(image, 1.0)?) };
    let target = cloud(&seq.render(start_value, 16 * args.spp, 0x7a59))?;
    let mut state = MatchState::new();
    let mut out = Vec::with_capacity(steps);
    for step in 0..steps {
        let value = start_value + args.offset + step as f64 * args.step;
        let source = cloud(&seq.render(value, args.spp, step as u32 + 1))?;
        let t0 = Instant::now();
        let cold = matcher.solve(&source, &target).context("cold solve")?;
        let cold_s = t0.elapsed().as_secs_f64();
        let t1 = Instant::now();
        let warm = matcher
            .solve_warm(&source, &target, &mut state)
            .context("warm solve")?;
        let warm_s = t1.elapsed().as_secs_f64();
        out.push(Step {
            step,
            value,
            cold_s,
            warm_s,
            speedup: cold_s / warm_s,
            cold_loss: cold.loss,
            warm_loss: warm.loss,
            warm_started: warm.stats.warm_starts > 0,
            warm_iterations: warm.stats.iterations,
            warm_added_pairs: warm.stats.added_pairs,
            warm_pair_evaluations: warm.stats.pair_evaluations,
            warm_phases: warm.stats.phases.iter().collect(),
        });
    }
    let median = |pick: fn(&Step) -> f64| {
        let mut v: Vec<f64> = out[1..].iter().map(pick).collect();
        v.sort_by(f64::total_cmp);
        v[v.len() / 2]
    };
    let (cold_median_s, warm_median_s) = (median(|s| s.cold_s), median(|s| s.warm_s));
    let max_loss_rel_diff = out
        .iter()
        .map(|s| (s.warm_loss - s.cold_loss).abs() / s.cold_loss.abs().max(f64::MIN_POSITIVE))
        .fold(0.0, f64::max);
    let report = Report {
        scene: args.scene.display().to_string(),
        param: args.param.clone(),
        n,
        side,
        solver: matcher.name(),
        spp: args.spp,
        steps: out,
        cold_median_s,
        warm_median_s,
        speedup: cold_median_s / warm_median_s,
        max_loss_rel_diff,
        peak_rss_mb: crate::cmd::peak_rss_mb(),
        threads: rayon::current_num_threads(),
    };
    if json {
        println!("{}", serde_json::to_string(&report)?);
        return Ok(());
    }
    for s in &report.steps {
        println!(
            "step {:3} {}={:.4} cold {:.4}s warm {:.4}s ×{:.1} loss {:.6e} / {:.6e}{}",
            s.step,
            report.param,
            s.value,
            s.cold_s,
            s.warm_s,
            s.speedup,
            s.cold_loss,
            s.warm_loss,
            if s.warm_started { "" } else { " (cold start)" },
        );
    }
    println!(
        "ot {} sequence n={} medians after the first step: cold {:.4}s warm {:.4}s speedup ×{:.1}, max loss rel diff {:.1e}",
        report.solver, n, cold_median_s, warm_median_s, report.speedup, max_loss_rel_diff,
    );
    Ok(())
}
