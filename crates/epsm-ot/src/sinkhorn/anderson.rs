//! Anderson acceleration of a fixed-point iteration `x ← F(x)` (type II, Walker & Ni 2011).
//!
//! Keeps the last `memory` iterates `x_k` and residuals `r_k = F(x_k) − x_k`
//! and proposes `x' = x_m + β r_m − (ΔX + β ΔR) γ`, where `ΔX, ΔR` hold the
//! differences of successive iterates and residuals and `γ` minimises
//! `‖r_m − ΔR γ‖₂` (normal equations with a small Tikhonov term, solved in
//! `f64`). With `memory = 0` it is the relaxed iteration `x + β r`.
//! Every reduction is a sequential sum, so the step does not depend on the
//! number of threads. Used by the Sinkhorn polish, where `F` is one full
//! Sinkhorn update of the source potential and Anderson removes the slow,
//! large-scale modes that plain (or over-relaxed) Sinkhorn leaves at small ε.

use std::collections::VecDeque;

/// History of iterates and residuals of one accelerated iteration.
#[derive(Debug, Clone)]
pub(crate) struct Anderson {
    memory: usize,
    mixing: f64,
    iterates: VecDeque<Vec<f64>>,
    residuals: VecDeque<Vec<f64>>,
}

impl Anderson {
    /// An empty history keeping up to `memory` differences, with mixing `β`.
    pub(crate) fn new(memory: usize, mixing: f64) -> Self {
        Self {
            memory,
            mixing,
            iterates: VecDeque::new(),
            residuals: VecDeque::new(),
        }
    }

    /// Forgets the history (the next step is a plain relaxed step).
    pub(crate) fn reset(&mut self) {
        self.iterates.clear();
        self.residuals.clear();
    }

    /// Records `x` and `F(x)` and returns the next iterate.
    pub(crate) fn step(&mut self, x: &[f64], fx: &[f64]) -> Vec<f64> {
        let r: Vec<f64> = fx.iter().zip(x).map(|(a, b)| a - b).collect();
        self.iterates.push_back(x.to_vec());
        self.residuals.push_back(r);
        while self.iterates.len() > self.memory + 1 {
            self.iterates.pop_front();
            self.residuals.pop_front();
        }
        let m = self.iterates.len() - 1;
        let (xm, rm) = (&self.iterates[m], &self.residuals[m]);
        let beta = self.mixing;
        let mut next: Vec<f64> = xm.iter().zip(rm).map(|(a, b)| a + beta * b).collect();
        if m == 0 {
            return next;
        }
        let dr: Vec<Vec<f64>> = (0..m)
            .map(|k| diff(&self.residuals[k + 1], &self.residuals[k]))
            .collect();
        let mut gram = vec![vec![0.0; m]; m];
        for p in 0..m {
            for q in p..m {
                let v = dot(&dr[p], &dr[q]);
                gram[p][q] = v;
                gram[q][p] = v;
            }
        }
        let rhs: Vec<f64> = dr.iter().map(|d| dot(d, rm)).collect();
        let Some(gamma) = solve_regularised(gram, rhs) else {
            return next;
        };
        for (k, &gk) in gamma.iter().enumerate() {
            let (x1, x0) = (&self.iterates[k + 1], &self.iterates[k]);
            for (i, v) in next.iter_mut().enumerate() {
                *v -= gk * ((x1[i] - x0[i]) + beta * dr[k][i]);
            }
        }
        next
    }
}

/// [`Anderson`] with a restart safeguard, for iterations that measure an error per iterate.
///
/// It keeps the iterate of smallest error so far. When an error is not finite or more than
/// ten times that smallest one, the extrapolation has gone astray: the history is dropped and
/// the iteration restarts from the best iterate with plain relaxed steps, which it keeps
/// until an iterate improves on the best. (Resuming the extrapolation at once could
/// repeat the same excursion and restart forever: a cluster scaling stalled at its best
/// error that way on a blob pair, seed 1 of `epsm bench ot`.)
#[derive(Debug, Clone)]
pub(crate) struct Guarded {
    anderson: Anderson,
    best_error: f64,
    best: Vec<f64>,
    /// Plain steps since the last restart, until an iterate beats the best.
    plain: bool,
}

impl Guarded {
    /// Guards `anderson`; `start` is the iterate to restart from until one has a finite error.
    pub(crate) fn new(anderson: Anderson, start: &[f64]) -> Self {
        Self {
            anderson,
            best_error: f64::INFINITY,
            best: start.to_vec(),
            plain: false,
        }
    }

    /// The next iterate from `x`, `F(x)` and the error of `x`, and whether it is a restart
    /// from the best iterate (`F(x)` unused then).
    pub(crate) fn step(&mut self, x: &[f64], fx: &[f64], error: f64) -> (Vec<f64>, bool) {
        if error < self.best_error {
            self.best_error = error;
            self.best = x.to_vec();
            self.plain = false;
        } else if !error.is_finite() || (!self.plain && error > 10.0 * self.best_error) {
            self.anderson.reset();
            self.plain = true;
            return (self.best.clone(), true);
        }
        if self.plain {
            // No history: the relaxed step `x + β (F(x) − x)`.
            self.anderson.reset();
        }
        (self.anderson.step(x, fx), false)
    }
}

fn diff(a: &[f64], b: &[f64]) -> Vec<f64> {
    a.iter().zip(b).map(|(x, y)| x - y).collect()
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// Solves `(A + 1e-10 tr(A) I) γ = b` by Gaussian elimination with partial pivoting; `None` if singular.
fn solve_regularised(mut a: Vec<Vec<f64>>, mut b: Vec<f64>) -> Option<Vec<f64>> {
    let m = b.len();
    let trace: f64 = (0..m).map(|k| a[k][k]).sum();
    if !(trace > 0.0 && trace.is_finite()) {
        return None;
    }
    (0..m).for_each(|k| a[k][k] += 1e-10 * trace);
    for k in 0..m {
        let p = (k..m).max_by(|&i, &j| a[i][k].abs().total_cmp(&a[j][k].abs()))?;
        a.swap(k, p);
        b.swap(k, p);
        if a[k][k] == 0.0 {
            return None;
        }
        let pivot_row = a[k].clone();
        for r in k + 1..m {
            let f = a[r][k] / pivot_row[k];
            for (entry, p) in a[r].iter_mut().zip(&pivot_row).skip(k) {
                *entry -= f * p;
            }
            b[r] -= f * b[k];
        }
    }
    let mut x = vec![0.0; m];
    for k in (0..m).rev() {
        let s: f64 = (k + 1..m).map(|c| a[k][c] * x[c]).sum();
        x[k] = (b[k] - s) / a[k][k];
    }
    x.iter().all(|v| v.is_finite()).then_some(x)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A linear contraction `F(x) = A x + c` with a slow mode (eigenvalue 0.995).
    fn apply(x: &[f64]) -> Vec<f64> {
        let n = x.len();
        (0..n)
            .map(|i| {
                let rate = 0.5 + 0.495 * (i as f64 / (n - 1) as f64);
                let coupling = 0.01 * (x[(i + 1) % n] - x[i]);
                rate * x[i] + coupling + 1.0
            })
            .collect()
    }

    fn iterations_to_converge(memory: usize) -> usize {
        let mut acc = Anderson::new(memory, 1.0);
        let mut x = vec![0.0; 50];
        for k in 0..5000 {
            let fx = apply(&x);
            let res = fx
                .iter()
                .zip(&x)
                .map(|(a, b)| (a - b).abs())
                .fold(0.0, f64::max);
            if res < 1e-9 {
                return k;
            }
            x = acc.step(&x, &fx);
        }
        5000
    }

    #[test]
    fn anderson_reaches_the_fixed_point_much_faster_than_plain_iteration() {
        let plain = iterations_to_converge(0);
        let accelerated = iterations_to_converge(6);
        assert!(plain > 1000, "plain iteration took {plain}");
        assert!(accelerated < plain / 10, "{accelerated} vs {plain}");
    }

    #[test]
    fn regularised_solve_inverts_a_small_system() {
        let a = vec![vec![4.0, 1.0], vec![1.0, 3.0]];
        let x = solve_regularised(a, vec![1.0, 2.0]).expect("non-singular");
        assert!((x[0] - 1.0 / 11.0).abs() < 1e-8 && (x[1] - 7.0 / 11.0).abs() < 1e-8);
        assert!(solve_regularised(vec![vec![0.0]], vec![1.0]).is_none());
    }

    #[test]
    fn guarded_restarts_from_the_best_iterate_when_the_error_blows_up() {
        let mut guarded = Guarded::new(Anderson::new(4, 1.0), &[0.0, 0.0]);
        // A non-finite first error: back to the start, history dropped.
        assert_eq!(
            guarded.step(&[5.0, 5.0], &[6.0, 6.0], f64::NAN),
            (vec![0.0, 0.0], true)
        );
        // Improving errors: plain (relaxed) steps, and [1, 1] becomes the best iterate.
        assert_eq!(
            guarded.step(&[1.0, 1.0], &[2.0, 2.0], 0.5),
            (vec![2.0, 2.0], false)
        );
        let (_, restarted) = guarded.step(&[2.0, 2.0], &[2.5, 2.5], 0.4);
        assert!(!restarted);
        // Worse but within ten times the best (0.4): no restart.
        assert!(!guarded.step(&[3.0, 3.0], &[3.0, 3.0], 3.9).1);
        // More than ten times the best: restart from the best iterate, [2, 2].
        assert_eq!(
            guarded.step(&[9.0, 9.0], &[9.0, 9.0], 4.1),
            (vec![2.0, 2.0], true)
        );
        // After a restart: plain relaxed steps, with no new restart even above ten times
        // the best, until an iterate beats the best.
        assert_eq!(
            guarded.step(&[2.0, 2.0], &[3.0, 3.0], 0.4),
            (vec![3.0, 3.0], false)
        );
        assert_eq!(
            guarded.step(&[3.0, 3.0], &[5.0, 5.0], 5.0),
            (vec![5.0, 5.0], false)
        );
        assert!(!guarded.step(&[5.0, 5.0], &[5.5, 5.5], 0.3).1);
        // Extrapolating again: a blow-up restarts from the new best, [5, 5].
        assert_eq!(
            guarded.step(&[7.0, 7.0], &[7.0, 7.0], 3.1),
            (vec![5.0, 5.0], true)
        );
    }
}
