//! `epsm match A B`: the OT matching of two images a user already has (EXR
//! or PNG), as the optimizer's loss matches a render with its target
//! ([`epsm_core::loss::match_images`]): both are box-filtered to
//! `--resolution`, every pixel becomes an RGBXY point, and the clouds are
//! matched by the exact or the entropic solver. Prints the loss and the
//! solve's statistics as `key value` lines; with `-o`, writes a picture of
//! the matching (lines from `A`'s pixels to their matches, subsampled).

use std::path::PathBuf;
use std::time::Instant;

use anyhow::Context;
use epsm_core::inspect::matching_lines;
use epsm_core::loss::{match_images, matcher_named, resample};
use epsm_core::problem::desc::LossDesc;
use epsm_ot::{MatchLimits, Matching};
use epsm_scene::image_io::read_image;

use super::canvas::{Canvas, srgb};
use super::plots::write_png;

/// Arguments of `epsm match`.
#[derive(clap::Args, Debug)]
pub struct MatchArgs {
    /// The source image (EXR linear, or PNG sRGB): its pixels get the gradient.
    pub a: PathBuf,
    /// The target image.
    pub b: PathBuf,
    /// The solver: `exact` or `sinkhorn`.
    #[arg(long, default_value = "exact")]
    pub solver: String,
    /// Weight λ of screen position against colour (as `loss.lambda`).
    #[arg(long = "lambda", default_value_t = LossDesc::default().lambda)]
    pub lambda: f64,
    /// Blur of the Sinkhorn solver, ε = blur² (as `loss.blur`).
    #[arg(long, default_value_t = LossDesc::default().blur)]
    pub blur: f64,
    /// Matching resolution `W H` (as `loss.match_resolution`): both images
    /// are box-filtered to it.
    #[arg(long, num_args = 2, value_names = ["W", "H"], default_values_t = LossDesc::default().match_resolution)]
    pub resolution: Vec<u32>,
    /// Picture of the matching (PNG).
    #[arg(short, long)]
    pub output: Option<PathBuf>,
}

/// Runs `epsm match`.
pub fn run(args: &MatchArgs) -> anyhow::Result<()> {
    let (w, h) = match args.resolution[..] {
        [w, h] if (4..=512).contains(&w) && (4..=512).contains(&h) => (w, h),
        _ => anyhow::bail!(
            "--resolution: expected two sizes in [4, 512], found {:?}",
            args.resolution
        ),
    };
    let matcher = matcher_named(&args.solver, args.blur)?;
    matcher.check_size(w as usize * h as usize, &MatchLimits::default())?;
    let [a, b] = [&args.a, &args.b].map(|p| read_image(p).map(|img| resample(&img, w, h)));
    let (a, b) = (a?, b?);
    let t0 = Instant::now();
    let m = match_images(&matcher, &a, &b, args.lambda, None)
        .with_context(|| format!("matching {} to {}", args.a.display(), args.b.display()))?;
    let seconds = t0.elapsed().as_secs_f64();
    let s = &m.result.stats;
    println!(
        "match {} {}: {} at {w}x{h} ({} points), lambda {}",
        args.a.display(),
        args.b.display(),
        matcher.name(),
        w * h,
        args.lambda
    );
    println!("loss {}", m.result.loss);
    println!("seconds {seconds:.6}");
    println!("iterations {}", s.iterations);
    println!("pair_evaluations {}", s.pair_evaluations);
    if let Matching::Entropic(plan) = &m.result.matching {
        println!("epsilon {}", plan.epsilon);
        println!("transport_cost {}", plan.transport_cost);
        println!("marginal_error {}", plan.marginal_error);
    } else {
        println!("candidate_pairs {}", s.candidate_pairs);
        println!("added_pairs {}", s.added_pairs);
    }
    let guards = epsm_core::loss::MatchGuards::COLUMNS
        .iter()
        .zip(m.eval.guards.counts());
    for (name, count) in guards {
        println!("{name} {count}");
    }
    for (phase, secs) in s.phases.iter() {
        println!("phase_{phase} {secs:.6}");
    }
    if let Some(out) = &args.output {
        let mut picture = Canvas::new(w, h, |x, y| srgb(&a, x, y));
        let every = ((w * h) as usize / 600).max(1);
        picture.lines(
            &matching_lines(&m.eval, every, 0.5),
            plotters::style::RGBColor(255, 220, 0),
        )?;
        write_png(out, picture.w, picture.h, &picture.rgb)?;
        println!("picture {}", out.display());
    }
    Ok(())
}
