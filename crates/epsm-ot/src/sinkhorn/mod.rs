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
//! blur fixed), ×1 (score rounding 5e-4 ε) converges in 172 updates; ×3 and
//! ×10 stall (L1 errors 3.4e-3 and 8.5e-3 after 5000 polish updates; the stall
//! test of `stall_margin` ends them after 302 and 427, at 6.6e-3 and 8.8e-3), where
//! `exact_prices` still converges (4446 and 2286 updates; this close to the
//! rounding, whether it does turns on the order of the rows' sums: changes of
//! the pairs the point cut keeps have moved ×3 between 3242 updates and a stall
//! at 1.3e-3); ×100 (rounding 5 ε) stalls at
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
mod polish;
mod settings;

use crate::clusters::Clustered;
use crate::cost::{check_spread, diameter_sq};
use crate::error::{F32_RESOLUTION, OtError};
use crate::exact::MAX_DIAMETER_SQ;
use crate::plan::{EntropicPlan, Matching, OtResult, PhaseTimes, SolveStats};
use crate::points::{Point, PointCloud, check_pair};

use centre::Centred;
use dual::Guards;
pub(crate) use dual::{Dual, converged, solve_dual};
pub(crate) use polish::polish;
pub use settings::{MAX_SPREAD, MIN_BLUR, SinkhornSettings};

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
mod tests;
