//! Per-type validation of the manifold derivatives against the Newton oracle
//! (docs/design.md §7), as `epsm check` reports it.
//!
//! For each path: re-solve `C = 0` at θ₀ (the record's `f32` vertices only
//! satisfy it to ~1e-7), take the forward `dp/dθ` there, and compare with the
//! Richardson-extrapolated central difference of re-solved pixels for every
//! parameter the path touches (step [`fd_step`], shrunk so the pixel moves
//! at most `max_pixel_step`, then moved to where successive estimates agree
//! best: [`stable_difference`]). The error of a path is
//! `‖FD − AN‖_F / max(‖AN‖_F, ‖FD‖_F, floor)` over its 2×k Jacobian; the
//! adjoint gradient for a fixed `g` is compared with `g·dp/dθ` too. Paths
//! whose `‖A‖₁‖A⁻¹‖₁` exceeds `well_conditioned` are counted apart: their
//! finite differences are not trustworthy at the reported precision.

use std::collections::BTreeMap;

use glam::DVec2;
use rayon::prelude::*;

use crate::drops::{DropCounts, Dropped};
use crate::motion::Motion;
use crate::newton::{NewtonSettings, fd_step, project, stable_difference};
use crate::params::ParamTable;
use crate::paths::{DiffPath, PathKind};
use crate::solve::{SolveSettings, condition, solve_adjoint, solve_forward};

/// How the check runs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CheckSettings {
    /// Guards and bounds of the solve.
    pub solve: SolveSettings,
    /// The oracle's stopping rules.
    pub newton: NewtonSettings,
    /// Scene radius (sets the finite-difference steps).
    pub radius: f64,
    /// Paths with `‖A‖₁‖A⁻¹‖₁` above this are counted as ill-conditioned.
    pub well_conditioned: f64,
    /// Smallest Jacobian norm (pixels per unit) used as the denominator.
    pub floor: f64,
    /// The finite-difference step is shrunk until the pixel moves at most
    /// this far (pixels), keeping O(h⁴) truncation negligible on strongly
    /// magnifying paths.
    pub max_pixel_step: f64,
}

impl CheckSettings {
    /// Defaults for a scene of radius `radius`.
    pub fn for_radius(radius: f64) -> Self {
        Self {
            solve: SolveSettings::for_radius(radius),
            newton: NewtonSettings::default(),
            radius,
            well_conditioned: 1e5,
            floor: 1e-9,
            max_pixel_step: 1e-3,
        }
    }
}

/// The outcome of checking one path.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PathCheck {
    /// Relative error of the forward Jacobian against the oracle.
    pub rel_err: f64,
    /// Relative error of the adjoint gradient against `g·dp/dθ` (forward).
    pub adjoint_rel_err: f64,
    /// `‖A‖₁‖A⁻¹‖₁` (1 without unknowns).
    pub condition: f64,
}

/// Checks one path (see the module doc).
pub fn check_path(
    path: &DiffPath,
    table: &ParamTable,
    motion: &Motion,
    s: &CheckSettings,
) -> Result<PathCheck, Dropped> {
    let path = project(path, motion, &s.solve, &s.newton)?;
    let jac = solve_forward(&path, motion, &s.solve)?;
    let cond = condition(&path, motion, &s.solve)?;
    let (mut diff, mut an, mut fd_norm) = (0.0, 0.0, 0.0);
    for (&param, col) in jac.params.iter().zip(&jac.columns) {
        let h0 = fd_step(&table.params()[param].target, s.radius);
        let h = h0 * (s.max_pixel_step / (h0 * col.length())).min(1.0);
        let fd = stable_difference(&path, table, param, h, &s.solve, &s.newton)?;
        diff += (fd - *col).length_squared();
        an += col.length_squared();
        fd_norm += fd.length_squared();
    }
    let g = DVec2::new(0.6, -0.8);
    let adj = solve_adjoint(&path, g, motion, &s.solve)?;
    let (mut adiff, mut ascale) = (0.0f64, 0.0f64);
    for ((_, v), col) in adj.entries.iter().zip(&jac.columns) {
        let fwd = g.dot(*col);
        adiff = adiff.max((v - fwd).abs());
        ascale = ascale.max(fwd.abs().max(v.abs()));
    }
    Ok(PathCheck {
        rel_err: diff.sqrt() / an.sqrt().max(fd_norm.sqrt()).max(s.floor),
        adjoint_rel_err: adiff / ascale.max(s.floor),
        condition: cond,
    })
}

/// The results for one path kind.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct KindReport {
    /// Relative errors of the well-conditioned paths, ascending.
    pub errors: Vec<f64>,
    /// Largest adjoint-versus-forward relative error.
    pub max_adjoint_rel_err: f64,
    /// Paths checked but above the `well_conditioned` bound.
    pub ill_conditioned: usize,
    /// Paths dropped, by reason.
    pub dropped: DropCounts,
}

impl KindReport {
    /// Paths checked (well- and ill-conditioned).
    pub fn checked(&self) -> usize {
        self.errors.len() + self.ill_conditioned
    }
    /// Median relative error of the well-conditioned paths (0 when none).
    pub fn median_rel_err(&self) -> f64 {
        self.errors
            .get(self.errors.len() / 2)
            .copied()
            .unwrap_or(0.0)
    }
    /// Largest relative error of the well-conditioned paths (0 when none).
    pub fn max_rel_err(&self) -> f64 {
        self.errors.last().copied().unwrap_or(0.0)
    }
}

/// Per-kind results of a check.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct CheckReport {
    /// One report per kind present.
    pub kinds: BTreeMap<PathKind, KindReport>,
}

impl CheckReport {
    /// Adds one path's outcome.
    pub fn add(
        &mut self,
        kind: PathKind,
        outcome: Result<PathCheck, Dropped>,
        well_conditioned: f64,
    ) {
        let r = self.kinds.entry(kind).or_default();
        match outcome {
            Ok(c) if c.condition > well_conditioned => r.ill_conditioned += 1,
            Ok(c) => {
                let at = r.errors.partition_point(|&e| e < c.rel_err);
                r.errors.insert(at, c.rel_err);
                r.max_adjoint_rel_err = r.max_adjoint_rel_err.max(c.adjoint_rel_err);
            }
            Err(Dropped(reason)) => r.dropped.add(reason),
        }
    }
}

/// Checks many paths in parallel.
pub fn check_paths(
    paths: &[DiffPath],
    table: &ParamTable,
    motion: &Motion,
    s: &CheckSettings,
) -> CheckReport {
    let outcomes: Vec<_> = paths
        .par_iter()
        .map(|p| (p.kind, check_path(p, table, motion, s)))
        .collect();
    let mut report = CheckReport::default();
    for (kind, o) in outcomes {
        report.add(kind, o, s.well_conditioned);
    }
    report
}
