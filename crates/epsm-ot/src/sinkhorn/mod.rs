//! Entropic optimal transport: symmetric log-domain Sinkhorn with ε-scaling, computed online.
//!
//! Model (Feydy et al. 2019, GeomLoss's `"blur"/"scaling"` parameterisation):
//! `OT_ε(α, β) = min_π ⟨π, C⟩ + ε KL(π | α⊗β)` with `c(P, Q) = ‖P − Q‖²`,
//! `ε = blur²`, uniform masses `1/n`. The dual potentials `f, g` are computed
//! by log-domain Sinkhorn while ε decreases geometrically from the squared
//! diameter to `blur²` with ratio `scaling²`; the n×n kernel is never stored
//! (see `kernel` for the streamed rows, `blocks` for kernel truncation).
//!
//! | key                        | meaning                                   | default | range      |
//! |----------------------------|-------------------------------------------|---------|------------|
//! | `sinkhorn.blur`            | final length scale, `ε = blur²`           | 0.01    | ≥ 1e-4     |
//! | `sinkhorn.scaling`         | per-step ratio of blur                    | 0.9     | (0, 1)     |
//! | `sinkhorn.debias`          | return the Sinkhorn divergence `S_ε`      | false   | bool       |
//! | `sinkhorn.truncation`      | drop pairs with `c − f − g > t·ε`         | 30      | ≥ 10       |
//! | `sinkhorn.marginal_tolerance` | L1 marginal error to reach at final ε | 1e-3    | > 0        |
//! | `sinkhorn.max_polish_iterations` | most updates at the final ε         | 5000    | ≥ 0        |
//! | `sinkhorn.stall_margin`    | end a polish that cannot reach the tolerance at this × its recent rate | 3 | ≥ 1 |
//! | `sinkhorn.overrelaxation`  | mixing β of the final-ε updates           | 1       | [1, 2)     |
//! | `sinkhorn.anderson_memory` | Anderson memory of the final-ε updates    | 8       | ≥ 0        |
//! | `sinkhorn.max_scale_iterations` | most updates per fine scale          | 30      | ≥ 1        |
//! | `sinkhorn.scale_tolerance` | marginal error ending a fine scale        | 3e-2    | > 0        |
//! | `sinkhorn.annealing_overrelaxation` | ω of the fine-phase updates      | 1.5     | [1, 2)     |
//! | `sinkhorn.exact_prices`    | warm-start the final ε from exact duals   | false   | bool       |
//! | `sinkhorn.cluster_size`    | mean points per block (see `blocks`)      | 32      | ≥ 1        |
//! | `sinkhorn.jump_radii`      | coarse phase while `√ε` > this × mean cluster radius | 1.75 | > 0 |
//! | `sinkhorn.coarse_period`   | fine updates per coarse correction (0: none) | 1    | ≥ 0        |
//!
//! **Loss**: `OT_ε = ⟨α, f⟩ + ⟨β, g⟩` (or, debiased,
//! `S_ε = OT_ε(α, β) − ½ OT_ε(α, α) − ½ OT_ε(β, β)`).
//! **Gradient**: `∂L/∂P_i = 2 (P_i − T(P_i)) / n` where
//! `T(P_i) = Σ_j π_ij Q_j / Σ_j π_ij` is the barycentric projection of the
//! plan. By the envelope theorem this is the gradient of the transport cost
//! `⟨π, C⟩` with respect to the source points, the optimal plan held fixed
//! (the entropy term does not depend on the points). Debiased, the gradient
//! is `2 (T_αα(P_i) − T_αβ(P_i)) / n`.
//!
//! **Centring**: each cloud is moved to the origin before the solve and the
//! results moved back (`centre`): translations leave the plan unchanged, so
//! clouds far apart are solved as accurately as clouds that overlap.
//!
//! **Convergence and the `f32` kernel**: the problem is scale-covariant
//! (points and blur ×s give the same plan, costs and potentials ×s²), so
//! what limits the kernel is `diameter² / ε`, not the spread itself. The
//! kernel scores `(g_j − c_ij)/ε` in `f32`; the potentials span about
//! `diameter²`, so a score is rounded by up to about `2⁻²⁴ diameter²/ε`
//! (in units of ε), and the polish's marginal error stalls near that
//! rounding. On the 1024-point blobs pair at blur 0.01 (the clouds scaled,
//! blur fixed), ×1 (score rounding 5e-4 ε) converges in 174 updates; ×3 and
//! ×10 stall (L1 errors 3e-3 and 8e-3 after 5000 polish updates; the stall
//! test of `stall_margin` ends them after 826 and 198, at 6e-3 and 8e-3), where
//! `exact_prices` still converges (4795 and 2819 updates); ×100 (rounding 5 ε) stalls at
//! 0.2 (`exact_prices`: 1.1); at ×1000 the error overflows in both. The
//! outcomes: a converged solve; a solve whose polish stops (out of updates,
//! or stalled) with a finite error above `marginal_tolerance`, returned and counted in
//! `SolveStats::unconverged_solves`; a non-finite error,
//! [`OtError::NotConverged`] (no plan is returned). Every convergence test
//! treats a NaN error as not converged (`dual::converged`).
//!
//! ```toml
//! [ot.sinkhorn]
//! blur = 0.01
//! scaling = 0.9
//! debias = false
//! ```

mod anderson;
mod bridges;
mod centre;
mod coarse;
mod dual;
mod pass;

use std::sync::LazyLock;

use crate::clusters::Clustered;
use crate::cost::{check_spread, diameter_sq};
use crate::error::{F32_RESOLUTION, OtError};
use crate::exact::MAX_DIAMETER_SQ;
use crate::plan::{EntropicPlan, Matching, OtResult, PhaseTimes, SolveStats};
use crate::points::{Point, PointCloud, check_pair};

use centre::Centred;
use dual::Guards;
pub(crate) use dual::{Dual, converged, polish, solve_dual};

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
    /// infinite: never stop early. The slowest converging solve measured (4795
    /// updates) would be stopped by a margin below 1.2 (`docs/performance.md`,
    /// "Sinkhorn").
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

/// One entropic problem solved: potentials, barycentres (clustered order) and costs.
struct Solved {
    dual: Dual,
    barycentres: Vec<Point>,
    value: f64,
    transport_cost: f64,
    pairs: u64,
    /// Whether the solve started from kept potentials.
    warm: bool,
}

/// Source and target potentials of one entropic problem.
#[derive(Debug, Clone)]
pub(crate) struct Potentials {
    f: Vec<f64>,
    g: Vec<f64>,
}

/// What an entropic solve leaves for the next one (see `crate::warm`), in the clouds' input orders.
#[derive(Debug, Clone)]
pub(crate) struct SinkhornState {
    /// The plan's potentials, of the clouds as given (not centred).
    plan: Potentials,
    /// With `debias`: the self-transport potentials of the source, then of
    /// the target (the same for the clouds centred or not).
    selves: Option<[Potentials; 2]>,
}

impl SinkhornState {
    /// Whether the state comes from clouds of `n` points, with the self-transport potentials iff `debias`.
    fn fits(&self, n: usize, debias: bool) -> bool {
        self.plan.f.len() == n && self.selves.is_some() == debias
    }
}

/// Solves one entropic problem, by the polish alone when `start` gives potentials
/// (clustered orders) and that polish converges, else from scratch.
fn solve_one(
    x: &Clustered,
    y: &Clustered,
    diam2: f64,
    settings: &SinkhornSettings,
    start: Option<Potentials>,
) -> Result<Solved, OtError> {
    let kept = start.map(|Potentials { f, g }| polish(x, y, f, g, settings, 0, 0));
    // A polish from kept potentials that did not converge (a stall, or out of
    // updates) is replaced by the cold solve, its work still counted.
    let (warm, mut dual) = match kept {
        Some(d) if converged(d.marginal_error, settings.marginal_tolerance) => (true, d),
        kept => {
            let mut dual = cold_dual(x, y, diam2, settings);
            if let Some(k) = kept {
                dual.pairs += k.pairs;
                dual.iterations += k.iterations;
                let mut phases = k.phases;
                phases.merge(&dual.phases);
                dual.phases = phases;
            }
            (false, dual)
        }
    };
    if !dual.marginal_error.is_finite() {
        // Not a plan at all: no barycentres from it (`rounding` says why, see the error).
        return Err(OtError::NotConverged {
            marginal_error: dual.marginal_error,
            tolerance: settings.marginal_tolerance,
            iterations: dual.iterations,
            rounding: diam2 / dual.eps / F32_RESOLUTION,
        });
    }
    let start = std::time::Instant::now();
    let bary = pass::barycentres(x, y, &dual, settings.truncation * dual.eps)?;
    dual.phases
        .add("barycentres", start.elapsed().as_secs_f64());
    let n = x.cloud.len() as f64;
    let mean = |v: &[f64]| v.iter().sum::<f64>() / n;
    let value = mean(&dual.f) + mean(&dual.g);
    let transport_cost = bary.costs.iter().sum::<f64>() / n;
    let pairs = dual.pairs + bary.pairs;
    Ok(Solved {
        dual,
        barycentres: bary.points,
        value,
        transport_cost,
        pairs,
        warm,
    })
}

/// The dual potentials of one entropic problem solved from scratch: the
/// ε-scaling loop, or with `exact_prices` the polish from the exact duals.
fn cold_dual(x: &Clustered, y: &Clustered, diam2: f64, settings: &SinkhornSettings) -> Dual {
    if settings.exact_prices {
        // Start the final-ε iterations from the optimal assignment's dual potentials.
        let ex = crate::exact::solve_sorted(x, y, diam2, &crate::ExactSettings::default());
        let guards = Guards::of_exact(&ex.stats);
        let mut phases = ex.stats.phases;
        let mut dual = polish(x, y, ex.u, ex.v, settings, ex.stats.pair_evaluations, 0);
        dual.guards = guards;
        phases.merge(&dual.phases);
        dual.phases = phases;
        dual
    } else {
        solve_dual(x, y, diam2, settings)
    }
}

/// The spread check of an entropic solve: [`OtError::SpreadTooLarge`] when the
/// squared diameter `diameter_sq` over `min(blur², 1)` exceeds [`MAX_SPREAD`].
pub(crate) fn check_range(diameter_sq: f64, settings: &SinkhornSettings) -> Result<(), OtError> {
    let eps = settings.blur * settings.blur;
    check_spread("sinkhorn", diameter_sq, eps.min(1.0), MAX_SPREAD)
}

/// Solves the entropic problem from `source` to `target`.
///
/// Solves it for the clouds each moved to the origin (`centre`: the same plan,
/// exactly). Fails with [`OtError::SpreadTooLarge`] when the centred clouds'
/// squared diameter over `min(blur², 1)` exceeds [`MAX_SPREAD`], or the
/// clouds' own squared diameter exceeds [`crate::exact::MAX_DIAMETER_SQ`].
/// Never returns a non-finite loss, potential or gradient
/// ([`OtError::NonFiniteResult`] instead), nor the plan of a solve whose
/// marginal error is not finite ([`OtError::NotConverged`]); a solve whose
/// finite marginal error stays above `marginal_tolerance` is returned and
/// counted in `SolveStats::unconverged_solves`.
pub fn solve(
    source: &PointCloud,
    target: &PointCloud,
    settings: &SinkhornSettings,
) -> Result<OtResult, OtError> {
    solve_from(source, target, settings, None)
}

/// [`solve`] started from the potentials the previous solve left in `state`
/// (see `crate::warm`): each entropic problem runs only the polish from them.
/// The state is replaced by this solve's, or emptied when it fails (`None`:
/// a cold solve that keeps nothing); a state from clouds of another size (or
/// without the self-transport potentials `debias` needs) starts cold.
pub(crate) fn solve_from(
    source: &PointCloud,
    target: &PointCloud,
    settings: &SinkhornSettings,
    mut state: Option<&mut Option<SinkhornState>>,
) -> Result<OtResult, OtError> {
    let previous = state.as_mut().and_then(|s| s.take());
    settings.validate()?;
    let n = check_pair(source, target)?;
    let previous = previous.filter(|p| p.fits(n, settings.debias));
    // The gradient includes the distance between the clouds: the exact matcher's bound.
    check_spread(
        "sinkhorn",
        diameter_sq(source, target),
        1.0,
        MAX_DIAMETER_SQ,
    )?;
    let centred = Centred::new(source, target);
    let (source, target) = (&centred.source, &centred.target);
    let diam2 = centred.diameter_sq();
    check_range(diam2, settings)?;
    let mut phases = PhaseTimes::default();
    let (x, y) = phases.time("cluster", || {
        (
            Clustered::new(source, settings.cluster_size),
            Clustered::new(target, settings.cluster_size),
        )
    });
    let start = |a: &Clustered, b: &Clustered, p: &Potentials| Potentials {
        f: a.sorted(&p.f),
        g: b.sorted(&p.g),
    };
    let plan_start = previous.as_ref().map(|p| {
        let mut kept = p.plan.clone();
        centred.centre_potentials(&mut kept.f, &mut kept.g);
        start(&x, &y, &kept)
    });
    let xy = solve_one(&x, &y, diam2, settings, plan_start)?;
    phases.merge(&xy.dual.phases);
    let bary = x.unsort(&xy.barycentres);
    let mut stats = SolveStats {
        marginal_error: Some(xy.dual.marginal_error),
        ..SolveStats::default()
    };
    tally(&xy, settings, &mut stats);
    let mut selves = None;
    let (loss, pull) = if settings.debias {
        let kept = previous.as_ref().and_then(|p| p.selves.as_ref());
        let xx_start = kept.map(|[s, _]| start(&x, &x, s));
        let yy_start = kept.map(|[_, t]| start(&y, &y, t));
        let xx = solve_one(&x, &x, diameter_sq(source, source), settings, xx_start)?;
        let yy = solve_one(&y, &y, diameter_sq(target, target), settings, yy_start)?;
        tally(&xx, settings, &mut stats);
        tally(&yy, settings, &mut stats);
        phases.merge(&xx.dual.phases);
        phases.merge(&yy.dual.phases);
        let self_bary = x.unsort(&xx.barycentres);
        let pull: Vec<Point> = source
            .points()
            .zip(bary.iter().zip(&self_bary))
            .map(|(p, (t_xy, t_xx))| std::array::from_fn(|d| p[d] - t_xx[d] + t_xy[d]))
            .collect();
        let unsorted = |a: &Clustered, s: &Solved| Potentials {
            f: a.unsort(&s.dual.f),
            g: a.unsort(&s.dual.g),
        };
        selves = Some([unsorted(&x, &xx), unsorted(&y, &yy)]);
        (xy.value - 0.5 * (xx.value + yy.value), pull)
    } else {
        (xy.value, bary.clone())
    };
    let mut plan = EntropicPlan {
        epsilon: xy.dual.eps,
        f: x.unsort(&xy.dual.f),
        g: y.unsort(&xy.dual.g),
        barycentres: bary,
        transport_cost: xy.transport_cost,
        marginal_error: xy.dual.marginal_error,
    };
    centred.restore_plan(&mut plan);
    let loss = loss + centred.value_shift();
    stats.phases = phases;
    let gradient = centred.gradient(&pull);
    check_finite(loss, &plan, &gradient)?;
    if let Some(state) = state {
        *state = Some(SinkhornState {
            plan: Potentials {
                f: plan.f.clone(),
                g: plan.g.clone(),
            },
            selves,
        });
    }
    Ok(OtResult {
        loss,
        gradient,
        matching: Matching::Entropic(plan),
        stats,
    })
}

/// Adds one entropic solve's work and safeguard counts to `stats`, counting it in
/// `unconverged_solves` when its marginal error is above the tolerance.
fn tally(solved: &Solved, settings: &SinkhornSettings, stats: &mut SolveStats) {
    let dual = &solved.dual;
    stats.iterations += dual.iterations;
    stats.pair_evaluations += solved.pairs;
    stats.warm_starts += usize::from(solved.warm);
    dual.guards.add_to(stats);
    stats.unconverged_solves +=
        usize::from(!converged(dual.marginal_error, settings.marginal_tolerance));
}

/// The solver's exit guard: [`OtError::NonFiniteResult`] naming the first
/// NaN or infinite loss, potential, barycentre or gradient entry (one O(n)
/// pass after the solve).
///
/// A softmin row whose sum is zero (no streamed target with a finite score)
/// gives an infinite potential. The only such rows found reachable (costs
/// beyond the `f32` range at a large blur) are now refused by the spread
/// check ([`MAX_SPREAD`]); this guard makes sure no path returns such a
/// potential, or what follows from it.
fn check_finite(loss: f64, plan: &EntropicPlan, gradient: &[Point]) -> Result<(), OtError> {
    let bad = |quantity, index| Err(OtError::NonFiniteResult { quantity, index });
    if !loss.is_finite() {
        return bad("loss", None);
    }
    let not_finite = |p: &Point| !p.iter().all(|v| v.is_finite());
    let checks = [
        ("potential f", plan.f.iter().position(|v| !v.is_finite())),
        ("potential g", plan.g.iter().position(|v| !v.is_finite())),
        ("barycentre", plan.barycentres.iter().position(not_finite)),
        ("gradient", gradient.iter().position(not_finite)),
    ];
    match checks.into_iter().find(|(_, index)| index.is_some()) {
        Some((quantity, index)) => bad(quantity, index),
        None => Ok(()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_exit_guard_names_the_first_non_finite_value() {
        let a = PointCloud::from_points(&[[0.1, 0.2, 0.3, 0.4, 0.5], [0.9, 0.8, 0.7, 0.6, 0.5]])
            .unwrap_or_else(|e| panic!("{e}"));
        let b = PointCloud::from_points(&[[0.5, 0.2, 0.3, 0.4, 0.0], [0.1, 0.9, 0.7, 0.6, 0.5]])
            .unwrap_or_else(|e| panic!("{e}"));
        let r = solve(&a, &b, &SinkhornSettings::default()).unwrap_or_else(|e| panic!("{e}"));
        let Matching::Entropic(plan) = &r.matching else {
            panic!("not an entropic plan");
        };
        assert_eq!(check_finite(r.loss, plan, &r.gradient), Ok(()));
        let expect = |quantity, index| Err(OtError::NonFiniteResult { quantity, index });
        for bad in [f64::INFINITY, f64::NEG_INFINITY, f64::NAN] {
            assert_eq!(check_finite(bad, plan, &r.gradient), expect("loss", None));
            let mut p = plan.clone();
            p.f[1] = bad;
            assert_eq!(
                check_finite(r.loss, &p, &r.gradient),
                expect("potential f", Some(1))
            );
            let mut p = plan.clone();
            p.g[0] = bad;
            assert_eq!(
                check_finite(r.loss, &p, &r.gradient),
                expect("potential g", Some(0))
            );
            let mut p = plan.clone();
            p.barycentres[1][2] = bad as f32;
            assert_eq!(
                check_finite(r.loss, &p, &r.gradient),
                expect("barycentre", Some(1))
            );
            let mut gradient = r.gradient.clone();
            gradient[1][3] = bad as f32;
            assert_eq!(
                check_finite(r.loss, plan, &gradient),
                expect("gradient", Some(1))
            );
        }
    }
}
