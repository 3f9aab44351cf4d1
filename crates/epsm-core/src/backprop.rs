//! The gradient pass of one iteration (docs/design.md §3): from recorded paths and
//! the loss's per-pixel gradients to `dL/dθ`.
//!
//! For every recorded path sample of a pixel with a non-zero gradient:
//! - **colour**: `dL/dθ += g_rgb · dc/dθ / spp` ([`ColourModel`]; terms it
//!   cannot differentiate are counted with the drops);
//! - **position**: the record is classified into differentiable paths
//!   ([`classify`]); the pixel's `g_xy` is shared among them in proportion
//!   to each path's share of the pixel's luminance (a shadow counts with the
//!   luminance its blocked connection removes), and each path adds
//!   `(w·g_xy)·dp/dθ` by one adjoint manifold solve ([`solve_adjoint`]).
//!
//! A record of a sample the tracer dropped ([`PathRecord::dropped`]) gives
//! nothing and is counted once, by its reason, whatever its pixel's
//! gradient. Paths touching no driven object are never built, and when every
//! parameter is a material or emitter value no manifold work is done at
//! all. Work runs on rayon over records; per-record results are reduced in
//! record order, so the gradient is bit-identical for a seed whatever the
//! thread count. Every path is counted: traced, solved, skipped, dropped by
//! reason, and by kind.

use epsm_render::Scene;
use epsm_render::record::{PathRecord, RecordLevel};
use glam::{DVec2, Vec3};
use rayon::prelude::*;

use crate::colour::ColourModel;
use crate::drops::{DropCounts, DropReason, Dropped};
use crate::loss::LossEval;
use crate::params::{ParamTable, Target};
use crate::paths::{Classified, DiffPath, PathKind, classify};
use crate::schedule::PathUse;
use crate::solve::{SolveSettings, solve_adjoint};

/// Path counts of one gradient pass.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct PassStats {
    /// Path samples traced (records).
    pub traced: u64,
    /// Differentiable paths solved.
    pub solved: u64,
    /// Records skipped: zero pixel gradient, or nothing driven on them.
    pub skipped: u64,
    /// Paths dropped (or not buildable), by reason.
    pub dropped: DropCounts,
    /// Differentiable paths seen, per [`PathKind`] (index = `kind as usize`).
    pub kinds: [u64; PathKind::ALL.len()],
}

impl PassStats {
    fn merge(&mut self, o: &PassStats) {
        self.traced += o.traced;
        self.solved += o.solved;
        self.skipped += o.skipped;
        self.dropped.merge(&o.dropped);
        for (a, b) in self.kinds.iter_mut().zip(o.kinds) {
            *a += b;
        }
    }

    /// Names of the path kinds seen, `+`-separated (`primary+caustic`).
    pub fn kinds_seen(&self) -> String {
        let names: Vec<&str> = PathKind::ALL
            .iter()
            .filter(|k| self.kinds[**k as usize] > 0)
            .map(|k| k.name())
            .collect();
        names.join("+")
    }
}

/// Whether any parameter moves geometry (objects, lights, camera).
pub fn has_geometry(table: &ParamTable) -> bool {
    table.params().iter().any(|p| {
        !matches!(
            p.target,
            Target::Albedo { .. }
                | Target::Alpha { .. }
                | Target::Ior { .. }
                | Target::Emission { .. }
        )
    })
}

/// The least record level the pass needs: primary vertices for primary
/// paths, the first diffuse vertex for chains and shadows, everything for
/// caustics (scenes with specular or glossy materials) and colour terms.
pub fn record_level(
    table: &ParamTable,
    scene: &Scene,
    colour: &ColourModel,
    use_: PathUse,
) -> RecordLevel {
    let caustics = scene
        .materials()
        .iter()
        .any(|m| !matches!(m.bsdf, epsm_render::materials::Bsdf::Diffuse(_)));
    match use_ {
        _ if !colour.is_empty() => RecordLevel::Full,
        PathUse::ColourOnly | PathUse::PrimaryOnly => RecordLevel::Primary,
        PathUse::All if !has_geometry(table) => RecordLevel::Primary,
        PathUse::All if caustics => RecordLevel::Full,
        PathUse::All => RecordLevel::FirstDiffuse,
    }
}

/// Everything the pass reads.
pub struct PassInput<'a> {
    /// The scene at θ, at the match resolution.
    pub scene: &'a Scene,
    /// The parameter table of `scene`, at θ.
    pub table: &'a ParamTable,
    /// Colour-derivative model at θ.
    pub colour: &'a ColourModel,
    /// Per-pixel loss gradients at the match resolution.
    pub loss: &'a LossEval,
    /// Samples per pixel of the records.
    pub spp: u32,
    /// Which paths give position gradients.
    pub use_: PathUse,
}

struct RecordOut {
    entries: Vec<(usize, f64)>,
    stats: PassStats,
}

/// `dL/dθ` (index order of the table) and the pass's counts.
pub fn backprop(input: &PassInput<'_>, records: &[PathRecord]) -> (Vec<f64>, PassStats) {
    let n = input.table.len();
    let motion = input.table.motion(&input.table.values());
    let settings = SolveSettings::for_radius(input.scene.radius());
    let positions = input.use_ != PathUse::ColourOnly && has_geometry(input.table);
    let pixel_of = |r: &PathRecord| (r.pixel.y * input.loss.width + r.pixel.x) as usize;
    // Classify, then sum each pixel's luminance mass (its samples' radiance
    // plus the radiance its shadows remove).
    let classified: Vec<Option<Classified>> = records
        .par_iter()
        .map(|r| {
            let g = input
                .loss
                .g_xy
                .get(pixel_of(r))
                .copied()
                .unwrap_or(DVec2::ZERO);
            (positions && g != DVec2::ZERO && r.dropped.is_none()).then(|| {
                let mut c = classify(r, input.scene, &motion, &settings);
                if input.use_ == PathUse::PrimaryOnly {
                    c.paths.retain(|p| p.kind == PathKind::Primary);
                }
                c
            })
        })
        .collect();
    let classified = drop_umbra(records, classified, input.loss.width, pixel_of);
    let mut mass = vec![0.0f64; input.loss.g_xy.len()];
    for (r, c) in records.iter().zip(&classified) {
        if let Some(m) = mass.get_mut(pixel_of(r)) {
            *m += f64::from(luminance(r.radiance).abs());
            let shadows = c
                .iter()
                .flat_map(|c| &c.paths)
                .filter(|p| p.kind == PathKind::Shadow);
            // A non-finite shadow is dropped (and counted) in `solve_one`;
            // it must not poison the mass of the pixel's other paths.
            *m += shadows
                .map(path_weight)
                .filter(|w| w.is_finite())
                .sum::<f64>();
        }
    }
    let outs: Vec<RecordOut> = records
        .par_iter()
        .zip(&classified)
        .map(|(r, c)| {
            let px = pixel_of(r);
            let mut out = RecordOut {
                entries: Vec::new(),
                stats: PassStats {
                    traced: 1,
                    ..Default::default()
                },
            };
            if let Some(d) = r.dropped {
                out.stats.dropped.add(d.into());
                return out;
            }
            let g_rgb = input.loss.g_rgb.get(px).copied().unwrap_or(Vec3::ZERO);
            if g_rgb != Vec3::ZERO {
                let scale = 1.0 / input.spp as f32;
                for (k, dc) in
                    input
                        .colour
                        .gradient(r, input.scene, &motion, &mut out.stats.dropped)
                {
                    out.entries.push((k, f64::from(g_rgb.dot(dc) * scale)));
                }
            }
            if let Some(c) = c {
                out.stats.dropped.merge(&c.skipped);
            }
            match (c, mass.get(px)) {
                (Some(c), Some(&m)) if m > 0.0 && !c.paths.is_empty() => {
                    let g = input.loss.g_xy[px] / m;
                    for path in &c.paths {
                        solve_one(path, g, &motion, &settings, &mut out);
                    }
                }
                _ if out.entries.is_empty() => out.stats.skipped = 1,
                _ => {}
            }
            out
        })
        .collect();
    let mut grad = vec![0.0; n];
    let mut stats = PassStats::default();
    for o in &outs {
        for &(k, v) in &o.entries {
            if let Some(x) = grad.get_mut(k) {
                *x += v;
            }
        }
        stats.merge(&o.stats);
    }
    (grad, stats)
}

/// A light as the shadows' visibility test tells lights apart: an emissive
/// object, or a point light.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
enum LightKey {
    Area(u32),
    Point(u32),
}

/// The light a recorded connection reached.
fn connection_light(c: &epsm_render::record::ConnectionRecord) -> Option<LightKey> {
    match c.light {
        epsm_render::lights::LightPoint::Area { object, .. } => Some(LightKey::Area(object)),
        epsm_render::lights::LightPoint::Point { index } => Some(LightKey::Point(index)),
        epsm_render::lights::LightPoint::Background => None,
    }
}

/// The light a shadow path ends at.
fn shadow_light(path: &DiffPath) -> Option<LightKey> {
    match path.nodes.last()? {
        crate::paths::Node::Surface { anchor, .. } => Some(LightKey::Area(anchor.object)),
        crate::paths::Node::PointLight(i) => Some(LightKey::Point(*i as u32)),
        crate::paths::Node::Camera => None,
    }
}

/// Pixels (match resolution) within this many of an unblocked connection
/// to a light keep their shadow paths toward it.
const UMBRA_RADIUS: i64 = 2;

/// Drops (and counts, as `not_differentiable`) the shadow paths of pixels
/// deep in an umbra: no sample within [`UMBRA_RADIUS`] pixels reached the
/// same light unblocked from its first vertex. Moving such a shadow changes
/// no pixel near it, yet its path would take the pixel's OT gradient.
fn drop_umbra(
    records: &[PathRecord],
    mut classified: Vec<Option<Classified>>,
    width: u32,
    pixel_of: impl Fn(&PathRecord) -> usize,
) -> Vec<Option<Classified>> {
    let shadows = classified
        .iter()
        .flatten()
        .any(|c| c.paths.iter().any(|p| p.kind == PathKind::Shadow));
    if !shadows {
        return classified;
    }
    let mut lit = std::collections::HashSet::new();
    for r in records {
        for c in r
            .connections
            .iter()
            .filter(|c| c.vertex == 0 && c.occluder.is_none())
        {
            if let Some(l) = connection_light(c) {
                lit.insert((pixel_of(r), l));
            }
        }
    }
    let w = i64::from(width);
    let near_lit = |px: usize, l: LightKey| {
        let (x, y) = (px as i64 % w, px as i64 / w);
        (-UMBRA_RADIUS..=UMBRA_RADIUS).any(|dy| {
            (-UMBRA_RADIUS..=UMBRA_RADIUS).any(|dx| {
                let (nx, ny) = (x + dx, y + dy);
                nx >= 0 && nx < w && ny >= 0 && lit.contains(&((ny * w + nx) as usize, l))
            })
        })
    };
    for (r, c) in records.iter().zip(classified.iter_mut()) {
        let Some(c) = c else { continue };
        let px = pixel_of(r);
        let before = c.paths.len();
        c.paths.retain(|p| {
            p.kind != PathKind::Shadow || shadow_light(p).is_none_or(|l| near_lit(px, l))
        });
        for _ in c.paths.len()..before {
            c.skipped.add(DropReason::NotDifferentiable);
        }
    }
    classified
}

/// One adjoint solve with `g_xy` pre-divided by the pixel's mass.
fn solve_one(
    path: &DiffPath,
    g: DVec2,
    motion: &crate::Motion,
    settings: &SolveSettings,
    out: &mut RecordOut,
) {
    out.stats.kinds[path.kind as usize] += 1;
    let w = path_weight(path);
    if !w.is_finite() {
        out.stats.dropped.add(DropReason::NonFinite);
        return;
    }
    if w == 0.0 {
        return;
    }
    match solve_adjoint(path, g * w, motion, settings) {
        Ok(gr) => {
            out.stats.solved += 1;
            out.entries.extend(gr.entries);
        }
        Err(Dropped(reason)) => out.stats.dropped.add(reason),
    }
}

/// A path's share of its pixel's luminance mass.
fn path_weight(path: &DiffPath) -> f64 {
    f64::from(luminance(path.contribution).abs())
}

/// Rec. 709 luminance of a linear colour.
pub fn luminance(c: Vec3) -> f32 {
    0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z
}
