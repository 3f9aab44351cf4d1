//! Settings of the entropic solver, its named presets and the ranges it
//! accepts (the smallest blur, the largest spread).

use std::sync::LazyLock;

use crate::error::OtError;

/// Smallest accepted `blur`. Below it the log-domain kernel breaks down: at
/// 1e-6 the 4096-point benchmark ends with an infinite marginal error, and at
/// 1e-300 (`ε` underflows to 0) the ε schedule never reaches its end (9 GB
/// and still running after 20 s).
///
/// It is not where solves converge. On clouds in `[0, 1]⁵` the polish
/// reaches the default tolerance at blur 0.01 always, and below that only
/// for enough points: n = 4096 uniform points at 3e-3 and not at 2e-3,
/// n = 1024 not at 3e-3; the 4096-point blobs pair at 5e-3, not at 3e-3; two
/// rendered 64×64 matches at 5e-3, one at 3e-3, neither at 1e-3
/// (`docs/performance.md`, "Sinkhorn"). Those solves are counted in
/// `SolveStats::unconverged_solves`, and a stalled polish ends early
/// (`SinkhornSettings::stall_margin`); a bound at the convergence limit would
/// depend on the clouds (their number of points, their spread against the
/// blur) and refuse solvable problems.
pub const MIN_BLUR: f64 = 1e-4;

/// The accepted range of `blur` in words, from [`MIN_BLUR`]: "must be finite and at least 1e-4".
static BLUR_RANGE: LazyLock<String> =
    LazyLock::new(|| format!("must be finite and at least {MIN_BLUR:e}"));

/// The largest accepted `diameter² / min(ε, 1)` of a solve ([`OtError::SpreadTooLarge`]),
/// with the diameter of the clouds each centred (`centre`); the distance
/// between the clouds is bounded by `exact::MAX_DIAMETER_SQ` only (the gradient's `f32`).
///
/// The kernel's `f32` scores `log w_j + (g_j − c_ij)/ε` scale with
/// `diameter² / ε`, its `f32` costs `c_ij` and differences `g_j − c_ij` with
/// `diameter²` itself; the bound holds both 8 times below `f32::MAX`, a
/// margin for centred potentials and their differences exceeding one
/// squared diameter. Without it, clouds 1e17 apart (before solves centred them) at the smallest blur (a
/// ratio of 1e42) gave non-finite potentials and a NaN loss and gradient;
/// without the `min(ε, 1)`, a large blur let costs overflow: at blur 1e20,
/// clouds 1e20 apart failed with [`OtError::EmptyKernelRow`] after seconds
/// of solving, and at blur 1e15, 300 points spread over `[0, 1e19]⁵` gave
/// a negative `OT_ε` (−4.1e37).
pub const MAX_SPREAD: f64 = f32::MAX as f64 / 8.0;

/// Settings of the entropic solver, with named presets.
#[derive(Debug, Clone, PartialEq)]
pub struct SinkhornSettings {
    /// Final length scale: `ε = blur²` (in the units of the points).
    pub blur: f64,
    /// Ratio between successive blurs of the ε-scaling schedule.
    pub scaling: f64,
    /// Return the debiased Sinkhorn divergence instead of `OT_ε`.
    pub debias: bool,
    /// Kernel truncation: block pairs whose reduced cost exceeds `truncation · ε` are dropped.
    pub truncation: f64,
    /// L1 marginal error to reach by extra iterations at the final ε.
    pub marginal_tolerance: f64,
    /// Cap on those extra iterations.
    pub max_polish_iterations: usize,
    /// The extra iterations stop early, unconverged, once even this many times
    /// the rate at which their smallest L1 marginal error fell over the second
    /// half of the iterations so far would not bring it to `marginal_tolerance`
    /// within the rest of `max_polish_iterations` (tested from the 100th
    /// iteration; with no finite error by then, they stop too). At least 1;
    /// infinite: never stop early. A slowly converging solve (2286 updates, the
    /// 1024-point blobs pair ×10 from exact prices) is not stopped even at a
    /// margin of 1 (`docs/performance.md`, "Sinkhorn").
    pub stall_margin: f64,
    /// Mixing β of the accelerated extra iterations, in `[1, 2)` (with no
    /// Anderson memory, the over-relaxation of plain Sinkhorn; 1 is plain Sinkhorn).
    pub overrelaxation: f64,
    /// Anderson memory of the extra iterations (0: none).
    pub anderson_memory: usize,
    /// Most updates per scale of the fine phase.
    pub max_scale_iterations: usize,
    /// A scale of the fine phase ends once its marginal error is below this.
    pub scale_tolerance: f64,
    /// Over-relaxation ω of the fine phase, in `[1, 2)`.
    pub annealing_overrelaxation: f64,
    /// Start the final-ε iterations from the exact assignment's dual potentials
    /// (which that solver finds by an ε-scaling Sinkhorn warm start and an
    /// auction) instead of running the fine phase of the ε-scaling schedule.
    /// Same fixed point, far fewer Sinkhorn iterations at small blur. The exact
    /// solve's safeguards are counted in `SolveStats::auction_budget_stops`
    /// and `SolveStats::cold_starts`.
    pub exact_prices: bool,
    /// Target mean points per cluster of the multiscale blocks (grid cells are
    /// widened until there are at most `2n / cluster_size` clusters; see `blocks`).
    pub cluster_size: usize,
    /// The coarse phase runs while `√ε` exceeds this many mean cluster radii.
    pub jump_radii: f64,
    /// Fine-phase updates between two coarse corrections (0: none; the target
    /// update that opens a scale is always corrected when this is not 0). A correction
    /// shifts `f, g` by one constant per cluster so that the plan's cluster
    /// marginals equal the clouds' cluster masses (two-grid Sinkhorn), removing
    /// the large-scale error that plain updates at small ε remove only slowly.
    pub coarse_period: usize,
}

impl Default for SinkhornSettings {
    fn default() -> Self {
        Self {
            blur: 0.01,
            scaling: 0.9,
            debias: false,
            truncation: 30.0,
            marginal_tolerance: 1e-3,
            max_polish_iterations: 5000,
            stall_margin: 3.0,
            overrelaxation: 1.0,
            anderson_memory: 8,
            max_scale_iterations: 30,
            scale_tolerance: 3e-2,
            annealing_overrelaxation: 1.5,
            exact_prices: false,
            cluster_size: 32,
            jump_radii: 1.75,
            coarse_period: 1,
        }
    }
}

impl SinkhornSettings {
    /// The defaults: blur 0.01, scaling 0.9, `OT_ε` (not debiased), coarse-corrected.
    ///
    /// Scaling 0.9 is the schedule the design names; with the coarse
    /// correction, 0.5 (GeomLoss's own default) also meets the marginal
    /// tolerance within 0.5 % of the exact cost on the benchmark's blob pairs,
    /// with fewer pair evaluations (see `docs/performance.md`).
    pub fn balanced() -> Self {
        Self::default()
    }

    /// The debiased Sinkhorn divergence (zero for identical clouds), three times the work.
    pub fn debiased() -> Self {
        Self {
            debias: true,
            ..Self::default()
        }
    }

    /// Faster and blurrier: blur 0.03, scaling 0.7.
    pub fn fast() -> Self {
        Self {
            blur: 0.03,
            scaling: 0.7,
            ..Self::default()
        }
    }

    /// Plain ε-scaling Sinkhorn (GeomLoss's loop plus the marginal polish): no
    /// coarse correction, no exact warm start, scaling 0.9. A reference for the
    /// default path (same fixed point).
    ///
    /// Up to 300 updates per fine scale: the coarse-to-fine jump leaves a
    /// slow large-scale error that 30 updates per scale do not remove, and
    /// the polish alone then stalls above the marginal tolerance (n = 1024,
    /// blur 0.03: L1 error 0.022 after the 5000 polish updates, against
    /// ≤ 1e-3 after ~900 updates in all with 300 per scale).
    pub fn annealed() -> Self {
        Self {
            scaling: 0.9,
            scale_tolerance: 3e-3,
            max_scale_iterations: 300,
            coarse_period: 0,
            ..Self::default()
        }
    }

    /// Checks every setting against its documented range ([`MIN_BLUR`] for
    /// `blur`).
    pub fn validate(&self) -> Result<(), OtError> {
        let bad = |key, value: f64, reason| Err(OtError::InvalidSetting { key, value, reason });
        if !self.blur.is_finite() || self.blur < MIN_BLUR {
            return bad("sinkhorn.blur", self.blur, BLUR_RANGE.as_str());
        }
        if self.scaling.is_nan() || self.scaling <= 0.0 || self.scaling >= 1.0 {
            return bad("sinkhorn.scaling", self.scaling, "must be in (0, 1)");
        }
        if self.truncation.is_nan() || self.truncation < 10.0 {
            return bad(
                "sinkhorn.truncation",
                self.truncation,
                "must be at least 10",
            );
        }
        if self.marginal_tolerance.is_nan() || self.marginal_tolerance <= 0.0 {
            return bad(
                "sinkhorn.marginal_tolerance",
                self.marginal_tolerance,
                "must be positive",
            );
        }
        if self.stall_margin.is_nan() || self.stall_margin < 1.0 {
            return bad(
                "sinkhorn.stall_margin",
                self.stall_margin,
                "must be at least 1",
            );
        }
        if !(1.0..2.0).contains(&self.overrelaxation) {
            return bad(
                "sinkhorn.overrelaxation",
                self.overrelaxation,
                "must be in [1, 2)",
            );
        }
        if !(1.0..2.0).contains(&self.annealing_overrelaxation) {
            return bad(
                "sinkhorn.annealing_overrelaxation",
                self.annealing_overrelaxation,
                "must be in [1, 2)",
            );
        }
        if self.max_scale_iterations == 0 {
            return bad("sinkhorn.max_scale_iterations", 0.0, "must be at least 1");
        }
        if self.cluster_size == 0 {
            return bad("sinkhorn.cluster_size", 0.0, "must be at least 1");
        }
        if self.jump_radii.is_nan() || self.jump_radii <= 0.0 {
            return bad("sinkhorn.jump_radii", self.jump_radii, "must be positive");
        }
        Ok(())
    }
}
