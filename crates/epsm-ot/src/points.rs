//! 5-D RGBXY point clouds stored as structure of arrays.
//!
//! A point is `(r, g, b, λx, λy)`: colour channels (tone-mapped, usually in
//! `[0, 1]`) followed by the screen position scaled by the weight λ. The cloud
//! keeps one contiguous `f32` column per coordinate so inner loops stream the
//! five coordinates and vectorise. Every point carries the same mass `1/n`.
//! A cloud is never empty and never holds NaN or infinite coordinates: the
//! constructors check both and return an [`OtError`].

use crate::error::OtError;

/// Number of coordinates of a point.
pub const DIM: usize = 5;

/// Names of the coordinates, in storage order.
pub const AXES: [&str; DIM] = ["r", "g", "b", "x", "y"];

/// A 5-D point `[r, g, b, λx, λy]`.
pub type Point = [f32; DIM];

/// A non-empty cloud of finite 5-D points with equal masses, stored as five columns.
#[derive(Debug, Clone, PartialEq)]
pub struct PointCloud {
    columns: [Vec<f32>; DIM],
}

impl PointCloud {
    /// Builds a cloud from its five columns `[r, g, b, λx, λy]`.
    ///
    /// Fails on an empty cloud, columns of different lengths, or a non-finite value.
    pub fn from_columns(columns: [Vec<f32>; DIM]) -> Result<Self, OtError> {
        let expected = columns[0].len();
        if expected == 0 {
            return Err(OtError::Empty);
        }
        for (axis, column) in AXES.iter().zip(&columns) {
            if column.len() != expected {
                return Err(OtError::RaggedColumns {
                    axis,
                    len: column.len(),
                    expected,
                });
            }
            if let Some((index, &value)) = column.iter().enumerate().find(|(_, v)| !v.is_finite()) {
                return Err(OtError::NonFinite { index, axis, value });
            }
        }
        Ok(Self { columns })
    }

    /// Builds a cloud from columns known to be non-empty, of equal length and finite
    /// (e.g. centroids of a valid cloud).
    pub(crate) fn from_trusted_columns(columns: [Vec<f32>; DIM]) -> Self {
        debug_assert!(
            !columns[0].is_empty() && columns.iter().all(|c| c.len() == columns[0].len())
        );
        debug_assert!(columns.iter().flatten().all(|v| v.is_finite()));
        Self { columns }
    }

    /// Builds a cloud from points given as `[r, g, b, λx, λy]` arrays.
    pub fn from_points(points: &[Point]) -> Result<Self, OtError> {
        let columns = std::array::from_fn(|d| points.iter().map(|p| p[d]).collect());
        Self::from_columns(columns)
    }

    /// Builds a cloud from colours and screen positions in `[0, 1]`, scaling positions by `lambda`.
    pub fn from_rgb_xy(rgb: &[[f32; 3]], xy: &[[f32; 2]], lambda: f32) -> Result<Self, OtError> {
        if rgb.len() != xy.len() {
            return Err(OtError::RaggedColumns {
                axis: "x",
                len: xy.len(),
                expected: rgb.len(),
            });
        }
        let points: Vec<Point> = rgb
            .iter()
            .zip(xy)
            .map(|(c, p)| [c[0], c[1], c[2], lambda * p[0], lambda * p[1]])
            .collect();
        Self::from_points(&points)
    }

    /// Number of points (always at least one).
    pub fn len(&self) -> usize {
        self.columns[0].len()
    }

    /// Always `false`: an empty cloud cannot be built.
    pub fn is_empty(&self) -> bool {
        self.columns[0].is_empty()
    }

    /// The `i`-th point. Panics if `i >= len()`.
    #[inline]
    pub fn point(&self, i: usize) -> Point {
        std::array::from_fn(|d| self.columns[d][i])
    }

    /// The five coordinate columns `[r, g, b, λx, λy]`.
    pub fn columns(&self) -> &[Vec<f32>; DIM] {
        &self.columns
    }

    /// Iterates over the points in order.
    pub fn points(&self) -> impl ExactSizeIterator<Item = Point> + '_ {
        (0..self.len()).map(|i| self.point(i))
    }

    /// The cloud with its points reordered: point `k` of the result is point `order[k]` of `self`.
    pub(crate) fn reordered(&self, order: &[u32]) -> Self {
        let columns =
            std::array::from_fn(|d| order.iter().map(|&i| self.columns[d][i as usize]).collect());
        Self { columns }
    }

    /// Per-coordinate minimum and maximum.
    pub fn bounds(&self) -> (Point, Point) {
        let lo = std::array::from_fn(|d| {
            self.columns[d]
                .iter()
                .copied()
                .fold(f32::INFINITY, f32::min)
        });
        let hi = std::array::from_fn(|d| {
            self.columns[d]
                .iter()
                .copied()
                .fold(f32::NEG_INFINITY, f32::max)
        });
        (lo, hi)
    }
}

/// Checks that two clouds can be matched: equal sizes.
pub(crate) fn check_pair(source: &PointCloud, target: &PointCloud) -> Result<usize, OtError> {
    if source.len() != target.len() {
        return Err(OtError::SizeMismatch {
            source_len: source.len(),
            target_len: target.len(),
        });
    }
    Ok(source.len())
}
