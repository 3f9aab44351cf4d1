//! `epsm render`: render a scene file.

use std::path::PathBuf;

use anyhow::Context;
use epsm_render::tracer::{RenderOptions, render};
use epsm_scene::image_io::write_image;
use epsm_scene::load::load_scene;

use crate::progress;

/// Arguments of `epsm render`.
#[derive(clap::Args, Debug)]
pub struct RenderArgs {
    /// The scene file: TOML, glTF (`.gltf`, `.glb`) or Mitsuba 3 (`.xml`).
    pub scene: PathBuf,
    /// Output image: `.exr` (linear float) or `.png` (sRGB, 8-bit).
    #[arg(short, long, default_value = "render.exr")]
    pub output: PathBuf,
    /// Samples per pixel (default: the scene's `render.spp`).
    #[arg(long)]
    pub spp: Option<u32>,
    /// Seed of the random streams (default: the scene's `render.seed`).
    #[arg(long)]
    pub seed: Option<u32>,
    /// Worker threads (default: all cores). The image does not depend on it.
    #[arg(long)]
    pub threads: Option<usize>,
}

/// Runs `epsm render`.
pub fn run(args: &RenderArgs) -> anyhow::Result<()> {
    let scene = load_scene(&args.scene)?;
    let mut opts = RenderOptions::from_scene(&scene);
    if let Some(spp) = args.spp {
        anyhow::ensure!(spp >= 1, "--spp must be at least 1");
        opts.spp = spp;
    }
    if let Some(seed) = args.seed {
        opts.seed = seed;
    }
    let cam = scene.camera();
    let bar = progress::bar(
        cam.width as u64 * cam.height as u64 * opts.spp as u64,
        "samples",
    );
    let out = super::with_threads(args.threads, || render(&scene, &opts, &|n| bar.inc(n)))?;
    bar.finish_and_clear();
    write_image(&args.output, &out.image)
        .with_context(|| format!("writing {}", args.output.display()))?;
    let c = out.counters;
    println!(
        "{}: {}x{} at {} spp in {:.3} s, {:.2} M samples/s, {:.2} M rays/s{}{}{} -> {}",
        args.scene.display(),
        cam.width,
        cam.height,
        opts.spp,
        out.seconds,
        out.samples as f64 / out.seconds / 1e6,
        (c.rays + c.shadow_rays) as f64 / out.seconds / 1e6,
        if c.non_finite > 0 {
            format!(", {} non-finite samples dropped", c.non_finite)
        } else {
            String::new()
        },
        if c.leaks > 0 {
            format!(", {} paths ended by normal-leak guard", c.leaks)
        } else {
            String::new()
        },
        if c.chains + c.chain_misses > 0 {
            format!(
                ", {} connections through glass ({} seeds not solved)",
                c.chains, c.chain_misses
            )
        } else {
            String::new()
        },
        args.output.display()
    );
    Ok(())
}
