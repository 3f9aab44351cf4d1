//! Crate tests: each solver gets the same battery (oracles, properties, bad input, determinism).

mod edge_cases;
mod exact_oracle;
mod sinkhorn_props;
mod warm;

use crate::points::{Point, PointCloud};
use crate::synthetic::Rng;

/// `n` random points with coordinates in `[0, scale)`.
pub(crate) fn random_cloud(rng: &mut Rng, n: usize, scale: f32) -> PointCloud {
    let points: Vec<Point> = (0..n)
        .map(|_| std::array::from_fn(|_| scale * rng.uniform()))
        .collect();
    PointCloud::from_points(&points).unwrap_or_else(|e| panic!("test cloud: {e}"))
}

/// The cloud shifted by `t`.
pub(crate) fn translated(cloud: &PointCloud, t: Point) -> PointCloud {
    let points: Vec<Point> = cloud
        .points()
        .map(|p| std::array::from_fn(|d| p[d] + t[d]))
        .collect();
    PointCloud::from_points(&points).unwrap_or_else(|e| panic!("test cloud: {e}"))
}
