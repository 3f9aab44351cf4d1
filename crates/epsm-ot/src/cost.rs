//! The ground cost `c(P, Q) = ‖P − Q‖²` and the loss and gradient built from it.
//!
//! All solvers share these functions: a matching assigns each source point `P_i`
//! a target `T_i` (a matched point for the exact solver, a barycentre for the
//! entropic one), the loss is `1/n Σ ‖P_i − T_i‖²`-like and the gradient with
//! respect to `P_i` is `2 (P_i − T_i) / n`.

use crate::error::OtError;
use crate::points::{DIM, Point, PointCloud};

/// Squared Euclidean distance in `f32`.
#[inline]
pub fn sq_dist(a: &Point, b: &Point) -> f32 {
    (0..DIM).map(|d| (a[d] - b[d]) * (a[d] - b[d])).sum()
}

/// Squared Euclidean distance evaluated in `f64` (exact differences of `f32` inputs).
#[inline]
pub fn sq_dist_f64(a: &Point, b: &Point) -> f64 {
    (0..DIM)
        .map(|d| {
            let t = f64::from(a[d]) - f64::from(b[d]);
            t * t
        })
        .sum()
}

/// `out[t] = ‖p − y_{start + t}‖²` in `f64` for the target columns `cols`:
/// the same sum, in the same order, as [`sq_dist_f64`], a column at a time so
/// the loops vectorise. Kept out of line: inlined into the exact solver's
/// candidate search it was no faster, in some runs a few percent slower.
#[inline(never)]
pub(crate) fn sq_dists_f64(p: &Point, cols: &[Vec<f32>; DIM], start: usize, out: &mut [f64]) {
    let end = start + out.len();
    for (d, col) in cols.iter().enumerate() {
        let pd = f64::from(p[d]);
        for (o, &t) in out.iter_mut().zip(&col[start..end]) {
            let diff = pd - f64::from(t);
            *o = if d == 0 {
                diff * diff
            } else {
                *o + diff * diff
            };
        }
    }
}

/// Squared diameter of the union of two clouds: the squared diagonal of their joint bounding box.
pub fn diameter_sq(source: &PointCloud, target: &PointCloud) -> f64 {
    let (lo_s, hi_s) = source.bounds();
    let (lo_t, hi_t) = target.bounds();
    (0..DIM)
        .map(|d| {
            let t = f64::from(hi_s[d].max(hi_t[d])) - f64::from(lo_s[d].min(lo_t[d]));
            t * t
        })
        .sum()
}

/// Squared norm bound of the points of two clouds: `Σ_d max(|lo_d|, |hi_d|)²`
/// over their joint bounding box, at least the squared norm of every point.
pub fn radius_sq(source: &PointCloud, target: &PointCloud) -> f64 {
    let (lo_s, hi_s) = source.bounds();
    let (lo_t, hi_t) = target.bounds();
    (0..DIM)
        .map(|d| {
            let t = [lo_s[d], hi_s[d], lo_t[d], hi_t[d]]
                .iter()
                .fold(0.0f64, |m, &v| m.max(f64::from(v).abs()));
            t * t
        })
        .sum()
}

/// The range check every matcher makes before solving: fails with
/// [`OtError::SpreadTooLarge`] when `extent_sq / unit_sq` exceeds `limit`.
///
/// Each matcher passes the extent, unit and bound its own `f32` arithmetic
/// needs (see the error's fields).
pub(crate) fn check_spread(
    matcher: &'static str,
    extent_sq: f64,
    unit_sq: f64,
    limit: f64,
) -> Result<(), OtError> {
    if extent_sq / unit_sq > limit {
        return Err(OtError::SpreadTooLarge {
            matcher,
            extent_sq,
            unit_sq,
            limit,
        });
    }
    Ok(())
}

/// Mean cost `1/n Σ_i ‖P_i − Q_σ(i)‖²` of an assignment σ, accumulated in `f64`.
pub fn assignment_cost(source: &PointCloud, target: &PointCloud, perm: &[usize]) -> f64 {
    let n = source.len() as f64;
    perm.iter()
        .enumerate()
        .map(|(i, &j)| sq_dist_f64(&source.point(i), &target.point(j)))
        .sum::<f64>()
        / n
}

/// Gradient `2 (P_i − T_i) / n` of the loss for per-point targets `T_i`.
pub fn displacement_gradient(source: &PointCloud, targets: &[Point]) -> Vec<Point> {
    let scale = 2.0 / source.len() as f32;
    source
        .points()
        .zip(targets)
        .map(|(p, t)| std::array::from_fn(|d| scale * (p[d] - t[d])))
        .collect()
}
