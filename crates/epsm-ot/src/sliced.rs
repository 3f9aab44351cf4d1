//! Sliced optimal transport: an approximate matcher from random 1-D projections.
//!
//! For `K` random unit directions θ, both clouds are projected and sorted;
//! the k-th smallest source projection is matched to the k-th smallest target
//! projection (the exact 1-D optimum). With `d_i(θ) = ⟨P_i − Q_σθ(i), θ⟩`:
//! loss `L = (5/K) Σ_θ 1/n Σ_i d_i(θ)²` (the factor 5 makes it an unbiased
//! estimate of the squared distance for a pure translation) and gradient
//! `∂L/∂P_i = (10/(nK)) Σ_θ d_i(θ) θ`. This is **approximate**: it is not the
//! 5-D optimal matching, only a cheap O(K n log n) surrogate.
//!
//! | key                  | meaning                     | default |
//! |----------------------|-----------------------------|---------|
//! | `sliced.projections` | number of random directions | 64      |
//! | `sliced.seed`        | seed of the directions      | 0       |

use rayon::prelude::*;

use crate::cost::{check_spread, displacement_gradient, radius_sq};
use crate::error::OtError;
use crate::plan::{Matching, OtResult, SlicedPlan, SolveStats};
use crate::points::{DIM, Point, PointCloud, check_pair};
use crate::synthetic::Rng;

/// Settings of the sliced matcher.
#[derive(Debug, Clone, PartialEq)]
pub struct SlicedSettings {
    /// Number of random projection directions.
    pub projections: usize,
    /// Seed of the directions (same seed, same result).
    pub seed: u64,
}

impl Default for SlicedSettings {
    fn default() -> Self {
        Self {
            projections: 64,
            seed: 0,
        }
    }
}

/// The largest accepted squared norm bound of the points ([`crate::cost::radius_sq`])
/// for `projections` directions ([`OtError::SpreadTooLarge`]).
///
/// With `R` the largest point norm and unit directions θ, the `f32`
/// arithmetic holds: projections `|⟨P, θ⟩| ≤ R`, displacements `|d| ≤ 2R`,
/// the per-point sum `Σ_θ d θ_c` over `K` directions (before its `5/K`
/// scale) at most `2KR`, the target `P − (5/K) Σ_θ d θ` at most `11R` and
/// the gradient `2 (P − T) / n` at most `24R`: everything stays below
/// `2 max(K, 12) R`. The bound keeps that a factor 2 below `f32::MAX`, for
/// rounding. (The loss is summed in `f64`.) Without it, clouds 3e38 apart got
/// an infinite gradient, and clouds together near 3e38 a NaN loss.
pub fn max_radius_sq(projections: usize) -> f64 {
    let radius = f64::from(f32::MAX) / (4.0 * projections.max(12) as f64);
    radius * radius
}

fn direction(rng: &mut Rng) -> [f32; DIM] {
    loop {
        let v: [f32; DIM] = std::array::from_fn(|_| rng.range(-1.0, 1.0));
        let norm = v.iter().map(|t| t * t).sum::<f32>().sqrt();
        if norm > 0.1 && norm <= 1.0 {
            return v.map(|t| t / norm);
        }
    }
}

fn sorted_projection(cloud: &PointCloud, theta: &[f32; DIM]) -> (Vec<f32>, Vec<u32>) {
    let proj: Vec<f32> = cloud
        .points()
        .map(|p| (0..DIM).map(|d| p[d] * theta[d]).sum())
        .collect();
    let mut order: Vec<u32> = (0..cloud.len() as u32).collect();
    order.sort_unstable_by(|&a, &b| {
        proj[a as usize]
            .total_cmp(&proj[b as usize])
            .then(a.cmp(&b))
    });
    (proj, order)
}

/// Solves the sliced problem from `source` to `target`.
///
/// Fails with [`OtError::SpreadTooLarge`] when the points' squared norm bound
/// exceeds [`max_radius_sq`].
pub fn solve(
    source: &PointCloud,
    target: &PointCloud,
    settings: &SlicedSettings,
) -> Result<OtResult, OtError> {
    let n = check_pair(source, target)?;
    if settings.projections == 0 {
        return Err(OtError::InvalidSetting {
            key: "sliced.projections",
            value: 0.0,
            reason: "must be at least 1",
        });
    }
    check_spread(
        "sliced",
        radius_sq(source, target),
        1.0,
        max_radius_sq(settings.projections),
    )?;
    let mut rng = Rng::new(settings.seed);
    let thetas: Vec<[f32; DIM]> = (0..settings.projections)
        .map(|_| direction(&mut rng))
        .collect();
    // Per direction: each point's projected displacement d_i(θ).
    let per_dir: Vec<Vec<f32>> = thetas
        .par_iter()
        .map(|theta| {
            let (ps, po) = sorted_projection(source, theta);
            let (qs, qo) = sorted_projection(target, theta);
            let mut d = vec![0.0f32; n];
            for (a, b) in po.iter().zip(&qo) {
                d[*a as usize] = ps[*a as usize] - qs[*b as usize];
            }
            d
        })
        .collect();
    let k = settings.projections as f64;
    let loss = 5.0 / k
        * per_dir
            .iter()
            .map(|d| d.iter().map(|&t| f64::from(t) * f64::from(t)).sum::<f64>())
            .sum::<f64>()
        / n as f64;
    let scale = (5.0 / k) as f32;
    let targets: Vec<Point> = source
        .points()
        .enumerate()
        .map(|(i, p)| {
            std::array::from_fn(|c| {
                p[c] - scale
                    * thetas
                        .iter()
                        .zip(&per_dir)
                        .map(|(t, d)| d[i] * t[c])
                        .sum::<f32>()
            })
        })
        .collect();
    let stats = SolveStats {
        iterations: settings.projections,
        ..SolveStats::default()
    };
    Ok(OtResult {
        loss,
        gradient: displacement_gradient(source, &targets),
        matching: Matching::Sliced(SlicedPlan {
            projections: settings.projections,
            targets,
        }),
        stats,
    })
}
