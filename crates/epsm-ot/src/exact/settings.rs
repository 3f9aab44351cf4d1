//! Settings of the exact solver and the largest spread it accepts.

use crate::cost::{check_spread, diameter_sq};
use crate::error::OtError;
use crate::points::PointCloud;
use crate::sinkhorn::SinkhornSettings;

/// The largest accepted squared diameter of the two clouds together ([`OtError::SpreadTooLarge`]).
///
/// Costs, potentials and the loss are `f64`, finite for any `f32` input
/// (squared differences of `f32` values stay below 5e77). The gradient
/// `2 (P_i − Q_σ(i)) / n` is `f32`: `P − Q` is at most the diameter and
/// `n = 1` doubles it, so it is finite below a diameter of `f32::MAX / 2`;
/// the bound, `f32::MAX / 4`, leaves a factor 2 for rounding. Without it a
/// single point 3e38 from its partner got an infinite gradient.
pub const MAX_DIAMETER_SQ: f64 = (f32::MAX as f64 / 4.0) * (f32::MAX as f64 / 4.0);

/// The clouds' squared diameter, or [`OtError::SpreadTooLarge`] beyond [`MAX_DIAMETER_SQ`].
pub(crate) fn checked_diameter_sq(
    source: &PointCloud,
    target: &PointCloud,
) -> Result<f64, OtError> {
    let diam2 = diameter_sq(source, target);
    check_spread("exact", diam2, 1.0, MAX_DIAMETER_SQ)?;
    Ok(diam2)
}

/// Settings of the exact solver.
#[derive(Debug, Clone, PartialEq)]
pub struct ExactSettings {
    /// Clouds smaller than this go to the dense reference solver.
    pub dense_below: usize,
    /// Candidate partners per point in the initial sparse graph.
    pub candidates: usize,
    /// Violation threshold of the optimality check.
    pub tolerance: f64,
    /// The entropic solve that provides potentials and candidates.
    pub warm_start: SinkhornSettings,
    /// First ε of the auction, in units of the clouds' squared diameter.
    pub auction_start: f64,
    /// Last ε of the auction, before the exact finish, in units of the clouds' squared diameter.
    pub auction_end: f64,
    /// First ε of the auctions that re-price all rows after an optimality
    /// check of a cold solve added violated pairs (see `finish`), in units of
    /// the clouds' squared diameter. Their prices are feasible on the graph
    /// before the check, so a start far below `auction_start` suffices; a
    /// price war still raises ε up to `auction_start` (see `auction`).
    pub reprice_auction_start: f64,
    /// First ε of the auctions of a warm-started solve (`crate::warm`), whose
    /// prices start near the optimum, in units of the clouds' squared diameter.
    pub warm_auction_start: f64,
    /// Margin of a warm-started solve's optimality checks (see `check`), in
    /// units of the clouds' squared diameter: each checked row also gets its
    /// pairs within this margin of its potential, so the auctions and
    /// augmenting paths that follow see the columns it may turn to, and its
    /// potential may rise by the margin before it needs another check.
    pub warm_check_margin: f64,
}

impl Default for ExactSettings {
    fn default() -> Self {
        Self {
            dense_below: 64,
            candidates: 8,
            tolerance: 1e-11,
            warm_start: SinkhornSettings {
                blur: 0.03,
                scaling: 0.9,
                marginal_tolerance: 1e-2,
                max_polish_iterations: 10,
                max_scale_iterations: 1,
                annealing_overrelaxation: 1.0,
                coarse_period: 0,
                ..SinkhornSettings::default()
            },
            // 0.1 and 1e-9 in cost units on clouds of squared diameter 4 (the
            // benchmark's blobs pairs: 4.4).
            auction_start: 0.025,
            auction_end: 2.5e-10,
            reprice_auction_start: 1e-3,
            warm_auction_start: 1e-4,
            warm_check_margin: 5e-4,
        }
    }
}

impl ExactSettings {
    /// Always use the sparse solver with its optimality check (used by tests on tiny clouds).
    pub fn sparse_only() -> Self {
        Self {
            dense_below: 0,
            ..Self::default()
        }
    }

    /// Checks every setting against its documented range.
    pub fn validate(&self) -> Result<(), OtError> {
        if self.candidates == 0 {
            return Err(OtError::InvalidSetting {
                key: "exact.candidates",
                value: 0.0,
                reason: "must be at least 1",
            });
        }
        if !self.tolerance.is_finite() || self.tolerance < 0.0 {
            return Err(OtError::InvalidSetting {
                key: "exact.tolerance",
                value: self.tolerance,
                reason: "must be finite and non-negative",
            });
        }
        let auction_ok = self.auction_end > 0.0
            && self.auction_start >= self.auction_end
            && self.auction_start.is_finite();
        if !auction_ok {
            return Err(OtError::InvalidSetting {
                key: "exact.auction_start",
                value: self.auction_start,
                reason: "need auction_start >= auction_end > 0",
            });
        }
        if !(self.reprice_auction_start >= self.auction_end
            && self.reprice_auction_start.is_finite())
        {
            return Err(OtError::InvalidSetting {
                key: "exact.reprice_auction_start",
                value: self.reprice_auction_start,
                reason: "need reprice_auction_start >= auction_end > 0",
            });
        }
        if !(self.warm_auction_start >= self.auction_end && self.warm_auction_start.is_finite()) {
            return Err(OtError::InvalidSetting {
                key: "exact.warm_auction_start",
                value: self.warm_auction_start,
                reason: "need warm_auction_start >= auction_end > 0",
            });
        }
        if !(self.warm_check_margin >= 0.0 && self.warm_check_margin.is_finite()) {
            return Err(OtError::InvalidSetting {
                key: "exact.warm_check_margin",
                value: self.warm_check_margin,
                reason: "must be finite and non-negative",
            });
        }
        self.warm_start.validate()
    }
}
