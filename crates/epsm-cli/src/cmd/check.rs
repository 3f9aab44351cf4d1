//! `epsm check`: validates the manifold derivatives of a scene's traced
//! paths against the Newton re-solve oracle (docs/design.md §7), per path type.
//!
//! ```text
//! epsm check <SCENE> [--json] [--samples N] [--param KEY ...] [--max-per-type N] [--seed N]
//! ```
//!
//! Without `--param`, every object's and point light's translation x/y/z and
//! the camera position are bound. For each path type present it prints the
//! paths checked, the median and largest relative error of `dp/dθ` against
//! the oracle (well-conditioned paths), the ill-conditioned count and the
//! drops by reason. `--json` prints one object keyed by path type with
//! `checked`, `median_rel_err`, `max_rel_err`, `dropped` (and
//! `ill_conditioned`, `max_adjoint_rel_err`), plus `not_classified`: the
//! paths dropped before any check (while building or projecting them), by
//! reason, as the text form's last line (a sample the tracer dropped for a
//! non-finite radiance counts there once, as `non_finite`, and so does a
//! shadow whose blocked connection's strength was not finite).

use std::path::PathBuf;

use anyhow::Context;
use epsm_core::check::{CheckReport, CheckSettings, check_paths};
use epsm_core::{DropCounts, ParamTable, PathKind, classify};
use epsm_render::record::RecordLevel;
use epsm_render::tracer::{PixelSample, RenderOptions, trace_samples};
use epsm_scene::load::load_scene;
use glam::UVec2;

/// Arguments of `epsm check`.
#[derive(clap::Args, Debug)]
pub struct CheckArgs {
    /// The scene file.
    pub scene: PathBuf,
    /// Print one JSON object keyed by path type.
    #[arg(long)]
    pub json: bool,
    /// Pixel samples traced (random pixels).
    #[arg(long, default_value_t = 4096)]
    pub samples: u32,
    /// Parameters to bind (`<name>.<field>`); default: translations of every
    /// object and point light, and the camera position.
    #[arg(long = "param", value_name = "KEY")]
    pub params: Vec<String>,
    /// At most this many paths are checked per type.
    #[arg(long, default_value_t = 400)]
    pub max_per_type: usize,
    /// Seed of the pixel choice.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
}

/// Most pixel samples `epsm check` traces: each keeps its whole path record
/// (about 0.6 kB), so 2^20 of them take about 0.7 GB.
pub(crate) const MAX_SAMPLES: u32 = 1 << 20;

/// Runs `epsm check`.
pub fn run(args: &CheckArgs) -> anyhow::Result<()> {
    anyhow::ensure!(
        (1..=MAX_SAMPLES).contains(&args.samples),
        "--samples must be in [1, {MAX_SAMPLES}], got {}",
        args.samples
    );
    let scene = load_scene(&args.scene)?;
    let mut table = ParamTable::new(&scene);
    if args.params.is_empty() {
        table.add_default_geometry()?;
    }
    for key in &args.params {
        table
            .add(key)
            .with_context(|| format!("{}: --param", args.scene.display()))?;
    }
    let opts = RenderOptions::from_scene(&scene);
    let cam = scene.camera();
    let mut state = args.seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1;
    let mut next = |n: u32| {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state % u64::from(n.max(1))) as u32
    };
    let samples: Vec<PixelSample> = (0..args.samples)
        .map(|_| PixelSample {
            pixel: UVec2::new(next(cam.width), next(cam.height)),
            sample: next(opts.spp),
        })
        .collect();
    let records = trace_samples(&scene, &opts, &samples, RecordLevel::Full);
    let motion = table.motion(&table.values());
    let settings = CheckSettings::for_radius(scene.radius());
    let mut paths = Vec::new();
    let mut skipped = DropCounts::default();
    let mut per_kind = [0usize; PathKind::ALL.len()];
    for record in &records {
        let c = classify(record, &scene, &motion, &settings.solve);
        skipped.merge(&c.skipped);
        for p in c.paths {
            let n = &mut per_kind[p.kind as usize];
            if *n < args.max_per_type {
                *n += 1;
                paths.push(p);
            }
        }
    }
    let report = check_paths(&paths, &table, &motion, &settings);
    if args.json {
        println!("{}", to_json(&report, &skipped));
    } else {
        print_text(&args.scene, &table, &report, &skipped);
    }
    Ok(())
}

fn drops_json(d: &DropCounts) -> serde_json::Value {
    d.nonzero()
        .map(|(r, c)| (r.name().to_owned(), serde_json::json!(c)))
        .collect::<serde_json::Map<_, _>>()
        .into()
}

fn to_json(report: &CheckReport, skipped: &DropCounts) -> serde_json::Value {
    let mut out: serde_json::Map<_, _> = report
        .kinds
        .iter()
        .map(|(kind, r)| {
            let v = serde_json::json!({
                "checked": r.checked(),
                "median_rel_err": r.median_rel_err(),
                "max_rel_err": r.max_rel_err(),
                "ill_conditioned": r.ill_conditioned,
                "max_adjoint_rel_err": r.max_adjoint_rel_err,
                "dropped": drops_json(&r.dropped),
            });
            (kind.name().to_owned(), v)
        })
        .collect();
    out.insert("not_classified".to_owned(), drops_json(skipped));
    out.into()
}

fn print_text(
    scene: &std::path::Path,
    table: &ParamTable,
    report: &CheckReport,
    skipped: &DropCounts,
) {
    println!("{}: {} parameters", scene.display(), table.len());
    println!(
        "{:<18} {:>8} {:>14} {:>14} {:>6}  dropped",
        "path type", "checked", "median rel err", "max rel err", "ill"
    );
    for (kind, r) in &report.kinds {
        let drops: Vec<String> = r
            .dropped
            .nonzero()
            .map(|(d, c)| format!("{}={c}", d.name()))
            .collect();
        println!(
            "{:<18} {:>8} {:>14.2e} {:>14.2e} {:>6}  {}",
            kind.name(),
            r.checked(),
            r.median_rel_err(),
            r.max_rel_err(),
            r.ill_conditioned,
            if drops.is_empty() {
                "-".to_owned()
            } else {
                drops.join(" ")
            }
        );
    }
    if skipped.total() > 0 {
        let s: Vec<String> = skipped
            .nonzero()
            .map(|(d, c)| format!("{}={c}", d.name()))
            .collect();
        println!("not classified: {}", s.join(" "));
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use epsm_core::DropReason;

    #[test]
    fn json_reports_the_drops_made_before_any_check() {
        let mut skipped = DropCounts::default();
        skipped.add(DropReason::NewtonFailed);
        skipped.add(DropReason::NewtonFailed);
        let json = to_json(&CheckReport::default(), &skipped);
        assert_eq!(json["not_classified"]["newton_failed"], 2);
    }
}
