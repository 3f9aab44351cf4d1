//! Two-grid coarse correction of Sinkhorn potentials: exact cluster marginals in one pass.
//!
//! At small ε, Sinkhorn corrects a mass imbalance between distant parts of the
//! clouds only diffusively (a mismatch at distance `D` decays at a rate
//! ~`ε/D²` per update), so after the coarse-to-fine jump a smooth,
//! large-scale error mode takes hundreds of fine updates. The correction
//! removes every error that is constant per cluster at once:
//! 1. **Block masses**: the plan's mass on each kept block pair,
//!    `K_IJ = Σ_{i∈I, j∈J} π_ij`, comes with a source update
//!    (`pass::softmin_blocks`), so a correction costs no extra kernel pass.
//! 2. **Cluster scaling**: log-domain Sinkhorn on the small sparse matrix `K`
//!    finds `u_I, v_J` with `Σ_J K_IJ e^{u_I + v_J} = A_I` (source cluster mass)
//!    and `Σ_I K_IJ e^{u_I + v_J} = B_J` (target cluster mass), iterated to
//!    [`SCALING_TOLERANCE`] (L1), Anderson-accelerated.
//! 3. **Shift**: `f_i += ε u_{I(i)}`, `g_j += ε v_{J(j)}`. The plan's cluster
//!    marginals are then those of the two clouds; what is left is the error
//!    inside clusters, which fine updates remove quickly.
//!
//! If the scaling has not converged within [`SCALING_ITERATIONS`] updates,
//! the kept block pairs cannot carry the cluster marginals: the potentials
//! the support was built from are off by more than its width somewhere. On
//! the benchmark pairs this happens after the coarse-to-fine jump, when the
//! support graph falls into components whose source and target masses differ
//! (one blob grew between the images), joined by no block pair or only by
//! weak ones (plan mass `e^−9` to `e^−80` of a cluster's, where the links
//! inside components carry more than `e^−4.5`). Mass then has to cross a
//! bottleneck, and the scaling's potentials drift apart per component without
//! converging. Two fallbacks:
//! 1. **Bridged** (`bridges`): the problem is lumped per component of the
//!    graph of strong links (mass at least `e^−WEAK_LINK` of the smaller
//!    cluster's), with bridges across components: block pairs outside the
//!    support, each with the upper bound `A_I B_J e^{−b_IJ/ε}` on its mass
//!    from the block bound `b_IJ` on reduced costs (see `blocks`), for every
//!    ordered pair of components those up to `BRIDGE_MARGIN · ε` above the
//!    cheapest bound between them. Newton's method on the small lumped
//!    problem gives one shift per component (1–8 steps on the benchmark
//!    pairs); applied, it moves the components' relative potentials so the
//!    bridges carry the imbalance. Since a bridge's mass is over-estimated,
//!    the shift errs short of the exact one, never past it.
//! 2. **Clamped**, if Newton's method does not converge either: the cluster
//!    scaling's last iterate, with the gauge `u + c, v − c` fixed by a zero
//!    mean of `u` and each entry clamped to `±clamp` (the caller passes the
//!    support's width in units of ε), is applied anyway: that moves the
//!    clusters that lack mass towards the block pairs just outside the
//!    support.
//!
//! Either way the caller rebuilds the support from the shifted potentials.
//! (On seed 1 of the benchmark pair at n = 16384 with `jump_radii` 2, clamped
//! corrections alone needed seven rebuilds in a row, the shift overshooting
//! by ±30ε each time, 3.0 G pairs; one bridged correction: 2.2 G pairs. Seed
//! 4's components are joined by one block pair of mass `e^−73` of a
//! cluster's: 1.91 G pairs with one clamped correction, 1.66 G bridged.)
//!
//! Everything runs in a fixed order (the pass over fixed source blocks, the
//! cluster scaling sequentially), so results do not depend on the thread count.

use rayon::prelude::*;

use super::anderson::{Anderson, Guarded};
use super::bridges::Lumped;
use super::pass::{Level, LogSum};

/// L1 error of the cluster marginals at which the cluster scaling stops.
pub(super) const SCALING_TOLERANCE: f64 = 1e-4;
/// Most updates of the cluster scaling.
pub(super) const SCALING_ITERATIONS: usize = 500;
/// Anderson memory of the cluster scaling.
const SCALING_MEMORY: usize = 8;

/// Shifts `f` and `g` per cluster so the plan's cluster marginals are exact (steps 2–3 of the module doc).
///
/// `log_masses[I][k]` is the plan's mass on the block pair `(I, lists[I][k])`
/// for these `f, g` (from `pass::softmin_blocks`); each `lists[I]` is sorted, as
/// [`Support`](crate::clusters::Support) keeps them. The roles of the two
/// measures are symmetric: a pass over target blocks corrects with `x, f` the
/// targets. If the cluster scaling does not converge, the problem is lumped per
/// component of the support graph with bridges between components ([`Lumped`],
/// see the module doc); if Newton's method does not solve that either, the
/// cluster scaling's last iterate is applied with every entry clamped to
/// `±clamp` (units of ε).
#[allow(clippy::too_many_arguments)]
pub(super) fn correct(
    x: &Level,
    y: &Level,
    lists: &[Vec<u32>],
    log_masses: &[Vec<f64>],
    f: &mut [f64],
    g: &mut [f64],
    eps: f64,
    clamp: f64,
) -> Correction {
    let (log_a, log_b) = (cluster_log_masses(x), cluster_log_masses(y));
    let scaling = scale(log_masses, lists, &log_a, &log_b, SCALING_ITERATIONS);
    let (u, v, outcome) = if scaling.converged {
        let updates = scaling.updates;
        (scaling.u, scaling.v, Correction::Applied { updates })
    } else if let Some(solved) =
        Lumped::new(x, y, lists, log_masses, f, g, eps, (&log_a, &log_b)).and_then(|l| l.solve())
    {
        let updates = solved.steps;
        (solved.u, solved.v, Correction::Bridged { updates })
    } else {
        let (u, v) = bounded(scaling, clamp);
        (u, v, Correction::Clamped)
    };
    shift(f, &x.ranges, &u, eps);
    shift(g, &y.ranges, &v, eps);
    outcome
}

/// A scaling's `u, v` in the gauge where `u` has zero mean, each entry clamped to
/// `±clamp` (non-finite entries count as 0).
fn bounded(scaling: Scaling, clamp: f64) -> (Vec<f64>, Vec<f64>) {
    let finite = |t: f64| if t.is_finite() { t } else { 0.0 };
    let mean = scaling.u.iter().map(|&t| finite(t)).sum::<f64>() / scaling.u.len() as f64;
    let shifted = |p: Vec<f64>, by: f64| -> Vec<f64> {
        p.into_iter()
            .map(|t| (finite(t) + by).clamp(-clamp, clamp))
            .collect()
    };
    (shifted(scaling.u, -mean), shifted(scaling.v, mean))
}

/// Outcome of one coarse correction.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Correction {
    /// The cluster marginals are exact; the cluster scaling took `updates` updates.
    Applied { updates: usize },
    /// The support's cluster scaling did not converge; lumped per component with
    /// bridges between components it did, in `updates` Newton steps.
    Bridged { updates: usize },
    /// The cluster scaling did not converge; its last iterate was applied clamped.
    Clamped,
}

/// `log Σ_{i∈I} w_i` per cluster.
fn cluster_log_masses(level: &Level) -> Vec<f64> {
    level
        .ranges
        .iter()
        .map(|r| {
            let mut sum = LogSum::default();
            r.clone().for_each(|i| sum.push(f64::from(level.log_w[i])));
            sum.value()
        })
        .collect()
}

fn shift(potential: &mut [f64], ranges: &[std::ops::Range<usize>], by: &[f64], eps: f64) {
    for (r, &b) in ranges.iter().zip(by) {
        potential[r.clone()].iter_mut().for_each(|p| *p += eps * b);
    }
}

/// The cluster matrix `K_IJ = exp(log_k)` stored by rows and by columns, each scaled by its largest entry.
struct ClusterMatrix {
    /// Per source cluster: `(J, exp(log K_IJ − row_max_I))`.
    rows: Vec<Vec<(u32, f64)>>,
    row_max: Vec<f64>,
    /// Per target cluster: `(I, exp(log K_IJ − col_max_J))`.
    cols: Vec<Vec<(u32, f64)>>,
    col_max: Vec<f64>,
}

impl ClusterMatrix {
    fn new(log_k: &[Vec<f64>], lists: &[Vec<u32>], targets: usize) -> Self {
        let mut log_cols: Vec<Vec<(u32, f64)>> = vec![Vec::new(); targets];
        for (i, (row, list)) in log_k.iter().zip(lists).enumerate() {
            for (&lk, &j) in row.iter().zip(list) {
                log_cols[j as usize].push((i as u32, lk));
            }
        }
        let scaled = |entries: Vec<(u32, f64)>| {
            let m = entries
                .iter()
                .map(|e| e.1)
                .fold(f64::NEG_INFINITY, f64::max);
            let weight = |lk: f64| {
                if m > f64::NEG_INFINITY {
                    (lk - m).exp()
                } else {
                    0.0
                }
            };
            let list = entries.into_iter().map(|(k, lk)| (k, weight(lk))).collect();
            (list, m)
        };
        let (rows, row_max) = log_k
            .par_iter()
            .zip(lists)
            .map(|(row, list)| scaled(list.iter().copied().zip(row.iter().copied()).collect()))
            .unzip();
        let (cols, col_max) = log_cols.into_par_iter().map(scaled).unzip();
        Self {
            rows,
            row_max,
            cols,
            col_max,
        }
    }
}

/// `log_target − log Σ_k K_k exp(p_k)` per entry list: one half-update of the cluster scaling.
///
/// Sums are taken relative to `max p` so they neither overflow nor (in practice) underflow;
/// a list whose sum vanishes keeps its old value and is counted (returned): its
/// marginal is not met, however small the change of the others. Sequential: with a few
/// hundred to a few thousand clusters, rayon's fork–join per half-update cost more than the sums (n = 4096:
/// 0.14 s of corrections per solve in parallel, 0.055 s sequentially).
fn half_update(
    lists: &[Vec<(u32, f64)>],
    list_max: &[f64],
    log_target: &[f64],
    p: &[f64],
    out: &mut [f64],
) -> usize {
    let top = p.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let ep: Vec<f64> = p.iter().map(|&v| (v - top).exp()).collect();
    let mut vanished = 0;
    out.iter_mut()
        .zip(lists)
        .zip(list_max.iter().zip(log_target))
        .for_each(|((o, list), (m, lt))| {
            let s: f64 = list.iter().map(|&(k, kv)| kv * ep[k as usize]).sum();
            let new = lt - m - top - s.ln();
            if new.is_finite() {
                *o = new;
            } else {
                vanished += 1;
            }
        });
    vanished
}

/// The cluster scaling's result: per-cluster shifts in units of ε.
struct Scaling {
    /// Per source cluster.
    u: Vec<f64>,
    /// Per target cluster.
    v: Vec<f64>,
    /// Updates taken.
    updates: usize,
    /// Whether the cluster marginals reached [`SCALING_TOLERANCE`] (`u, v` are
    /// the last iterate otherwise).
    converged: bool,
}

/// Anderson-accelerated Sinkhorn on the sparse cluster matrix `log_k` (rows listed by `lists`),
/// for at most [`SCALING_ITERATIONS`] updates (a block with no numerically
/// representable mass, or a support that cannot carry the marginals, makes
/// [`SCALING_TOLERANCE`] unreachable).
fn scale(
    log_k: &[Vec<f64>],
    lists: &[Vec<u32>],
    log_a: &[f64],
    log_b: &[f64],
    most: usize,
) -> Scaling {
    let k = ClusterMatrix::new(log_k, lists, log_b.len());
    let mut u = vec![0.0; log_a.len()];
    let mut v = vec![0.0; log_b.len()];
    let mut ut = u.clone();
    let mut guarded = Guarded::new(Anderson::new(SCALING_MEMORY, 1.0), &u);
    let finite = |p: &[f64]| p.iter().all(|t| t.is_finite());
    let mut updates = 0;
    while updates < most {
        // Column update (targets exact), then the row update; its size is the row error.
        let vanished = half_update(&k.cols, &k.col_max, log_b, &u, &mut v)
            + half_update(&k.rows, &k.row_max, log_a, &v, &mut ut);
        updates += 1;
        let error: f64 = u
            .iter()
            .zip(&ut)
            .zip(log_a)
            .map(|((a, b), la)| la.exp() * (a - b).exp_m1().abs())
            .sum();
        if error <= SCALING_TOLERANCE && vanished == 0 && finite(&u) && finite(&v) {
            return Scaling {
                u,
                v,
                updates,
                converged: true,
            };
        }
        u = guarded.step(&u, &ut, error).0;
    }
    Scaling {
        u,
        v,
        updates,
        converged: false,
    }
}

#[cfg(test)]
mod tests;
