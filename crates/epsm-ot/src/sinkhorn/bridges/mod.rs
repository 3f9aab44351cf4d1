//! Lumped cluster problems for coarse corrections whose support falls into components.
//!
//! See the module doc of `coarse` for when this runs. The cluster scaling there
//! fails when the support graph's strong links leave components whose source
//! and target masses differ: the mass must cross between components through
//! weak or missing links, and the scaling can only move it a factor
//! `1 + imbalance` per update. [`Lumped`] sums the plan per component, adds
//! bridges (block pairs outside the support with an upper bound on their mass),
//! and [`Lumped::solve`] finds one shift per component by Newton's method, which
//! sees the bottleneck directly: on the components' Laplacian, whose weights are
//! the flows between components, the step across a bridge carrying `w` for an
//! imbalance `δ` is `δ/w`, taken in log scale as `ln(1 + δ/w)` (exact for two
//! components with one-way flow).

use rayon::prelude::*;

use super::coarse::SCALING_TOLERANCE;
use super::pass::{Level, LogSum};
use crate::clusters::{fit_potentials, pair_bound};
use crate::disjoint_sets::DisjointSets;

/// A block pair links two clusters strongly if its plan mass is at least `exp(−WEAK_LINK)` times
/// the smaller cluster's mass. On the benchmark pairs the links that hold a failing scaling's
/// components together are above `e^−4.5`, and the ones it could not move mass through were
/// `e^−9` (4096, seed 1, `jump_radii` 1.75) to `e^−80`. A strong link counted as weak costs
/// little: its mass is still summed into the lumped flows.
const WEAK_LINK: f64 = 6.0;

/// Bridges from one component to another are kept up to this far (units of ε) above the
/// cheapest bound between them (see [`Lumped`]), so that several block pairs share the flow
/// and no single loose bound sets the shift.
const BRIDGE_MARGIN: f64 = 10.0;

/// The cluster problem lumped per connected component of the graph of strong links, with bridges.
///
/// The graph joins source cluster `I` and target cluster `J` where the plan's mass on
/// `(I, J)` is at least `e^−WEAK_LINK` of the smaller cluster's. A bridge is a block pair
/// `(I, J)` across components with the upper bound `A_I B_J exp(−b_IJ/ε)` on its mass, where
/// `b_IJ` is the block bound on reduced costs (`clusters::pair_bound` for the fits of `f, g`)
/// and `A_I, B_J` the cluster masses. Kept are
/// the pairs with `b_IJ ≤ b*_ab + BRIDGE_MARGIN · ε`, where `b*_ab` is the cheapest bound
/// from component `a`'s sources to component `b`'s targets: every ordered pair of components
/// gets its cheapest bridges, so mass can take any direction between them (bridges chosen
/// to connect the components without regard to direction, a spanning tree, left seed 2 at
/// 16384 with `jump_radii` 1.75 a lumped problem with no feasible plan: a component whose
/// sources had no way out).
pub(super) struct Lumped {
    components: usize,
    /// Component of each source / target cluster.
    src: Vec<usize>,
    dst: Vec<usize>,
    /// `log` of the plan's mass between two components (bridges included), `[a][b]`.
    log_flows: Vec<Vec<f64>>,
    /// `log` of each component's source / target mass.
    log_a: Vec<f64>,
    log_b: Vec<f64>,
}

impl Lumped {
    /// `None` if the graph is connected, falls into more than [`MAX_COMPONENTS`] components,
    /// or the levels are not clusterings.
    ///
    /// Arguments as for `coarse::correct`, with the cluster masses `log_a, log_b` (log).
    #[allow(clippy::too_many_arguments)]
    pub(super) fn new(
        x: &Level,
        y: &Level,
        lists: &[Vec<u32>],
        log_masses: &[Vec<f64>],
        f: &[f64],
        g: &[f64],
        eps: f64,
        (log_a, log_b): (&[f64], &[f64]),
    ) -> Option<Self> {
        let (cx, cy) = (x.clustered?, y.clustered?);
        let (na, nb) = (log_a.len(), log_b.len());
        let mut sets = DisjointSets::new(na + nb);
        for (i, (list, row)) in lists.iter().zip(log_masses).enumerate() {
            for (&j, &lk) in list.iter().zip(row) {
                if lk >= log_a[i].min(log_b[j as usize]) - WEAK_LINK {
                    sets.union(i, na + j as usize);
                }
            }
        }
        let (labels, components) = sets.labels();
        if !(2..=MAX_COMPONENTS).contains(&components) {
            return None;
        }
        let (src, dst) = labels.split_at(na);
        let (fit_f, fit_g) = (fit_potentials(cx, f), fit_potentials(cy, g));
        let bound =
            |i: usize, j: usize| pair_bound(&cx.clusters[i], &fit_f[i], &cy.clusters[j], &fit_g[j]);
        // The cheapest bound from each source cluster into each other component.
        let cheapest: Vec<Vec<f64>> = (0..na)
            .into_par_iter()
            .map(|i| {
                let mut best = vec![f64::INFINITY; components];
                for (j, &c) in dst.iter().enumerate() {
                    if c != src[i] {
                        best[c] = best[c].min(bound(i, j));
                    }
                }
                best
            })
            .collect();
        // Per ordered pair of components, the cheapest bound from one's sources to the other's
        // targets.
        let mut limit = vec![vec![f64::INFINITY; components]; components];
        for (best, &a) in cheapest.iter().zip(src) {
            for (l, b) in limit[a].iter_mut().zip(best) {
                *l = l.min(*b);
            }
        }
        limit
            .iter_mut()
            .flatten()
            .for_each(|l| *l += BRIDGE_MARGIN * eps);
        // Per source cluster, its mass into each component: support entries and bridges.
        let rows: Vec<Vec<LogSum>> = (0..na)
            .into_par_iter()
            .map(|i| {
                let mut sums = vec![LogSum::default(); components];
                for (&j, &lk) in lists[i].iter().zip(&log_masses[i]) {
                    sums[dst[j as usize]].push(lk);
                }
                let kept = |j: usize| lists[i].binary_search(&(j as u32)).is_ok();
                for (j, &c) in dst.iter().enumerate() {
                    if c != src[i] && !kept(j) {
                        let b = bound(i, j);
                        if b <= limit[src[i]][c] {
                            sums[c].push(log_a[i] + log_b[j] - b / eps);
                        }
                    }
                }
                sums
            })
            .collect();
        let mut flows = vec![vec![LogSum::default(); components]; components];
        for (sums, &a) in rows.iter().zip(src) {
            for (flow, sum) in flows[a].iter_mut().zip(sums) {
                flow.push(sum.value());
            }
        }
        let lumped = |labels: &[usize], log_m: &[f64]| {
            let mut sums = vec![LogSum::default(); components];
            labels
                .iter()
                .zip(log_m)
                .for_each(|(&c, &m)| sums[c].push(m));
            sums.iter().map(LogSum::value).collect()
        };
        Some(Self {
            components,
            log_a: lumped(src, log_a),
            log_b: lumped(dst, log_b),
            log_flows: flows
                .iter()
                .map(|row| row.iter().map(LogSum::value).collect())
                .collect(),
            src: src.to_vec(),
            dst: dst.to_vec(),
        })
    }
}

/// Solves `(diag(ground + W1) − W) x = rhs` for symmetric non-negative weights `W` (zero
/// diagonal) by Gaussian elimination in the GTH form (Grassmann, Taksar and Heyman 1985):
/// each pivot is recomputed as the sum of its node's remaining weights, never as a
/// difference, so weights `e^−80` beside weights of 1 keep their relative accuracy (LU on
/// the assembled matrix loses them: its pivots are differences that round to zero). `None`
/// if a pivot is zero (a node not connected to the ground).
fn grounded_laplacian_solve(
    mut w: Vec<Vec<f64>>,
    mut ground: Vec<f64>,
    mut rhs: Vec<f64>,
) -> Option<Vec<f64>> {
    let n = rhs.len();
    let mut pivots = vec![0.0; n];
    for k in 0..n {
        let pivot = ground[k] + w[k][k + 1..].iter().sum::<f64>();
        if pivot <= 0.0 || !pivot.is_finite() {
            return None;
        }
        pivots[k] = pivot;
        for i in k + 1..n {
            let share = w[i][k] / pivot;
            if share == 0.0 {
                continue;
            }
            ground[i] += share * ground[k];
            rhs[i] += share * rhs[k];
            let (done, rest) = w.split_at_mut(i);
            let row = done[k].iter().zip(rest[0].iter_mut()).enumerate();
            for (j, (wk, wi)) in row.skip(k + 1) {
                if j != i {
                    *wi += share * wk;
                }
            }
        }
    }
    let mut x = vec![0.0; n];
    for k in (0..n).rev() {
        let coupled: f64 = (k + 1..n).map(|j| w[k][j] * x[j]).sum();
        x[k] = (rhs[k] + coupled) / pivots[k];
    }
    Some(x)
}

/// Most Newton steps of [`Lumped::solve`].
const NEWTON_STEPS: usize = 60;
/// Most halvings of one Newton step before [`Lumped::solve`] gives up.
const HALVINGS: usize = 60;
/// Lumped problems with more components than this are not built (a dense elimination,
/// `O(k³)`, per Newton step; the benchmark pairs have 2–4 components at default settings).
const MAX_COMPONENTS: usize = 256;

/// Per-cluster shifts (units of ε) from [`Lumped::solve`].
pub(super) struct Solved {
    /// Per source cluster: its component's `u`.
    pub u: Vec<f64>,
    /// Per target cluster: its component's `v`.
    pub v: Vec<f64>,
    /// Newton steps taken.
    pub steps: usize,
}

/// A lumped plan `P_ab = exp(log_flow_ab + u_a + v_b)` after the target update (`v` exact).
struct Balanced {
    v: Vec<f64>,
    plan: Vec<Vec<f64>>,
    /// Row sums of `plan`.
    rows: Vec<f64>,
    /// `Σ_a |A_a − rows_a|`.
    error: f64,
    /// The dual objective `Σ_a A_a u_a + Σ_b B_b v_b` (over non-zero masses), which Newton's
    /// steps increase (the plan's total is 1 after the target update).
    dual: f64,
}

impl Lumped {
    /// Shifts `u_a, v_b` per component with `Σ_b P_ab = A_a`, `Σ_a P_ab = B_b` to
    /// [`SCALING_TOLERANCE`] (L1), expanded to the clusters; `None` if Newton's method
    /// does not get there.
    ///
    /// Each step: `v` from the target update, then `S δu = A − P1` on the components with
    /// source mass (one, the heaviest, held at 0 for the gauge), where `S = diag(P1) −
    /// P diag(1ᵀP)⁻¹ Pᵀ` is a Laplacian with weights `Σ_c P_ac P_bc / c_c` (its rows sum to
    /// zero), solved from the weights alone ([`grounded_laplacian_solve`]) so that flows of
    /// `e^−80` next to flows of 1 are not lost to cancellation. The step `δu` is shortened
    /// to length `ln(1 + m)` when its largest entry `m` exceeds 1 and halved until the dual
    /// objective rises (Armijo without a slope factor: the objective is concave and `δu` its
    /// Newton direction).
    pub(super) fn solve(&self) -> Option<Solved> {
        let k = self.components;
        let free: Vec<usize> = (0..k)
            .filter(|&a| self.log_a[a] > f64::NEG_INFINITY)
            .collect();
        let anchor = *free
            .iter()
            .max_by(|&&a, &&b| self.log_a[a].total_cmp(&self.log_a[b]))?;
        let unknowns: Vec<usize> = free.into_iter().filter(|&a| a != anchor).collect();
        let mut u: Vec<f64> = self
            .log_a
            .iter()
            .map(|&la| {
                if la > f64::NEG_INFINITY {
                    0.0
                } else {
                    f64::NEG_INFINITY
                }
            })
            .collect();
        let mut now = self.balance(&u);
        for steps in 0..NEWTON_STEPS {
            if now.error <= SCALING_TOLERANCE {
                return Some(Solved {
                    u: self.src.iter().map(|&c| u[c]).collect(),
                    v: self.dst.iter().map(|&c| now.v[c]).collect(),
                    steps,
                });
            }
            let du = self.newton_step(&now, &unknowns)?;
            let m = du.iter().fold(0.0f64, |m, d| m.max(d.abs()));
            let mut t = if m > 1.0 { m.ln_1p() / m } else { 1.0 };
            let mut accepted = None;
            for _ in 0..HALVINGS {
                let mut trial = u.clone();
                unknowns
                    .iter()
                    .zip(&du)
                    .for_each(|(&a, d)| trial[a] += t * d);
                let next = self.balance(&trial);
                if next.dual > now.dual {
                    accepted = Some((trial, next));
                    break;
                }
                t *= 0.5;
            }
            (u, now) = accepted?;
        }
        None
    }

    /// The target update for `u` and the resulting plan and row error.
    fn balance(&self, u: &[f64]) -> Balanced {
        let k = self.components;
        let v: Vec<f64> = (0..k)
            .map(|b| {
                let mut sum = LogSum::default();
                (0..k).for_each(|a| sum.push(self.log_flows[a][b] + u[a]));
                let v = self.log_b[b] - sum.value();
                if v.is_nan() { f64::NEG_INFINITY } else { v }
            })
            .collect();
        let plan: Vec<Vec<f64>> = (0..k)
            .map(|a| {
                (0..k)
                    .map(|b| {
                        let p = (self.log_flows[a][b] + u[a] + v[b]).exp();
                        if p.is_nan() { 0.0 } else { p }
                    })
                    .collect()
            })
            .collect();
        let rows: Vec<f64> = plan.iter().map(|row| row.iter().sum()).collect();
        let error = rows
            .iter()
            .zip(&self.log_a)
            .map(|(r, la)| (la.exp() - r).abs())
            .sum();
        let weighted = |log_m: &[f64], p: &[f64]| -> f64 {
            log_m
                .iter()
                .zip(p)
                .filter(|(lm, _)| **lm > f64::NEG_INFINITY)
                .map(|(lm, p)| lm.exp() * p)
                .sum()
        };
        Balanced {
            dual: weighted(&self.log_a, u) + weighted(&self.log_b, &v),
            v,
            plan,
            rows,
            error,
        }
    }

    /// Newton's `δu` on `unknowns` (see [`Lumped::solve`]); `None` if the system is singular.
    fn newton_step(&self, now: &Balanced, unknowns: &[usize]) -> Option<Vec<f64>> {
        let k = self.components;
        let cols: Vec<f64> = (0..k)
            .map(|b| now.plan.iter().map(|row| row[b]).sum())
            .collect();
        // The Laplacian's weights `Σ_c P_ac P_bc / c_c` between the unknowns, and to the
        // rest (the anchor; components without source mass have none).
        let weight = |a: usize, b: usize| -> f64 {
            (0..k)
                .filter(|&c| cols[c] > 0.0)
                .map(|c| now.plan[a][c] * now.plan[b][c] / cols[c])
                .sum()
        };
        let weights: Vec<Vec<f64>> = unknowns
            .iter()
            .map(|&a| {
                unknowns
                    .iter()
                    .map(|&b| if a == b { 0.0 } else { weight(a, b) })
                    .collect()
            })
            .collect();
        let ground: Vec<f64> = unknowns
            .iter()
            .map(|&a| {
                (0..k)
                    .filter(|b| !unknowns.contains(b))
                    .map(|b| weight(a, b))
                    .sum()
            })
            .collect();
        let rhs: Vec<f64> = unknowns
            .iter()
            .map(|&a| self.log_a[a].exp() - now.rows[a])
            .collect();
        let du = grounded_laplacian_solve(weights, ground, rhs)?;
        du.iter().all(|d| d.is_finite()).then_some(du)
    }
}

#[cfg(test)]
mod tests;
