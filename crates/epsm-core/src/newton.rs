//! The Newton re-solve oracle (docs/design.md §7).
//!
//! Given θ₀ + δ, start from `u = 0` and iterate `u ← u − t A⁻¹C(u, θ)` with
//! the step `t` halved until `‖C‖∞` decreases, to `‖C‖∞ < tolerance` (C is
//! dimensionless: tangent components of unit vectors). Projecting the
//! re-solved pixel vertex at θ₀ ± h and taking the central difference,
//! Richardson-extrapolated from steps `h` and `h/2` (error O(h⁴)), gives an
//! independent `dp/dθ` free of Monte Carlo noise.

use glam::DVec2;
use nalgebra::DVector;

use crate::constraints::assembly::{assemble, evaluate};
use crate::drops::{DropReason, Dropped};
use crate::motion::Motion;
use crate::params::{ParamTable, Target};
use crate::paths::{DiffPath, Node};
use crate::solve::{SolveSettings, factor};

/// Stopping rules of the re-solve.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NewtonSettings {
    /// Converged when `‖C‖∞` is below this.
    pub tolerance: f64,
    /// Give up after this many iterations.
    pub max_iterations: usize,
    /// After reaching the tolerance, take one more step (to the rounding
    /// floor): the oracle needs it for accurate finite differences.
    pub polish: bool,
}

impl NewtonSettings {
    /// The oracle's rules: `‖C‖∞ < 1e-13`, then one polishing step.
    pub fn oracle() -> Self {
        Self {
            tolerance: 1e-13,
            max_iterations: 50,
            polish: true,
        }
    }

    /// Projecting a recorded path onto its manifold (`classify`): the record's
    /// `f32` vertices satisfy `C = 0` to ~1e-7, one or two steps reach 1e-12.
    pub fn projection() -> Self {
        Self {
            tolerance: 1e-12,
            max_iterations: 8,
            polish: false,
        }
    }
}

impl Default for NewtonSettings {
    fn default() -> Self {
        Self::oracle()
    }
}

/// A converged re-solve.
#[derive(Clone, Debug, PartialEq)]
pub struct NewtonSolution {
    /// The unknowns (2 per unknown vertex) relative to the path's anchors.
    pub u: Vec<f64>,
    /// Iterations taken.
    pub iterations: usize,
    /// Final `‖C‖∞`.
    pub residual: f64,
}

fn residual(
    path: &DiffPath,
    motion: &Motion,
    u: &[f64],
    s: &SolveSettings,
) -> Result<(f64, DVector<f64>, nalgebra::DMatrix<f64>), DropReason> {
    let sys = assemble(path, &evaluate(path, motion, u), s)?;
    Ok((sys.c.amax(), sys.c, sys.a))
}

/// Solves `C(u, θ) = 0` in the placements `motion`, starting from `u = 0`.
pub fn resolve(
    path: &DiffPath,
    motion: &Motion,
    settings: &SolveSettings,
    newton: &NewtonSettings,
) -> Result<NewtonSolution, Dropped> {
    let mut u = vec![0.0; 2 * path.unknowns()];
    if u.is_empty() {
        return Ok(NewtonSolution {
            u,
            iterations: 0,
            residual: 0.0,
        });
    }
    let (mut r, mut c, mut a) = residual(path, motion, &u, settings)?;
    if !newton.polish && r < newton.tolerance {
        return Ok(NewtonSolution {
            u,
            iterations: 0,
            residual: r,
        });
    }
    for iteration in 0..newton.max_iterations {
        let step = a
            .clone()
            .full_piv_lu()
            .solve(&c)
            .ok_or(Dropped(DropReason::Singular))?;
        let mut t = 1.0;
        let next = loop {
            let trial: Vec<f64> = u.iter().zip(step.iter()).map(|(x, d)| x - t * d).collect();
            match residual(path, motion, &trial, settings) {
                Ok((rt, ct, at)) if rt < r => break Some((trial, rt, ct, at)),
                _ if t < 1e-6 => break None,
                _ => t *= 0.5,
            }
        };
        match next {
            Some((trial, rt, ct, at)) => {
                let polished = rt < newton.tolerance && (r < newton.tolerance || !newton.polish);
                (u, r, c, a) = (trial, rt, ct, at);
                if polished || (r < newton.tolerance * 1e-3) {
                    return Ok(NewtonSolution {
                        u,
                        iterations: iteration + 1,
                        residual: r,
                    });
                }
            }
            None if r < newton.tolerance => {
                return Ok(NewtonSolution {
                    u,
                    iterations: iteration,
                    residual: r,
                });
            }
            None => break,
        }
    }
    if r < newton.tolerance {
        Ok(NewtonSolution {
            u,
            iterations: newton.max_iterations,
            residual: r,
        })
    } else {
        Err(Dropped(failure_reason(a, settings)))
    }
}

/// Why Newton stalled with system matrix `a` at its last iterate: `A`
/// singular or ill-conditioned there (a fold, where two solutions merge and
/// vanish: a nearby configuration has none), by the checks of the adjoint
/// solve, else [`DropReason::NewtonFailed`].
fn failure_reason(a: nalgebra::DMatrix<f64>, settings: &SolveSettings) -> DropReason {
    match factor(a, settings) {
        Err(reason @ (DropReason::Singular | DropReason::IllConditioned)) => reason,
        _ => DropReason::NewtonFailed,
    }
}

/// The pixel of the path's first vertex at unknowns `u`.
pub fn pixel(path: &DiffPath, motion: &Motion, u: &[f64]) -> Result<DVec2, Dropped> {
    let state = evaluate(path, motion, u);
    motion
        .camera
        .pose
        .pixel(state.nodes[1].x)
        .ok_or(Dropped(DropReason::BehindCamera))
}

/// The path with every unknown vertex's anchor moved to the re-solved point
/// at the current θ (so `C(0, θ₀) = 0` to the Newton tolerance; the
/// constraints are unchanged).
pub fn project(
    path: &DiffPath,
    motion: &Motion,
    settings: &SolveSettings,
    newton: &NewtonSettings,
) -> Result<DiffPath, Dropped> {
    let sol = resolve(path, motion, settings, newton)?;
    let mut out = path.clone();
    for node in &mut out.nodes {
        if let Node::Surface {
            anchor,
            unknown: Some(q),
        } = node
        {
            *anchor = anchor.shifted([sol.u[2 * *q], sol.u[2 * *q + 1]]);
        }
    }
    Ok(out)
}

/// The central-difference step for a parameter in a scene of radius `radius`.
pub fn fd_step(target: &Target, radius: f64) -> f64 {
    match target {
        Target::Translate { .. }
        | Target::LightTranslate { .. }
        | Target::CameraTranslate { .. } => 1e-3 * radius,
        Target::Rotate { .. } | Target::CameraYaw | Target::CameraPitch => 0.05,
        _ => 1e-3,
    }
}

/// `dp/dθ` of global parameter `param` by re-solving at `θ ± h` and
/// `θ ± h/2` (Richardson extrapolation of the central differences).
pub fn central_difference(
    path: &DiffPath,
    table: &ParamTable,
    param: usize,
    h: f64,
    settings: &SolveSettings,
    newton: &NewtonSettings,
) -> Result<DVec2, Dropped> {
    let base = table.values();
    let probe = |delta: f64| -> Result<DVec2, Dropped> {
        let mut v = base.clone();
        v[param] += delta;
        let motion = table.motion(&v);
        let sol = resolve(path, &motion, settings, newton)?;
        pixel(path, &motion, &sol.u)
    };
    let d = |h: f64| -> Result<DVec2, Dropped> { Ok((probe(h)? - probe(-h)?) / (2.0 * h)) };
    let (d1, d2) = (d(h)?, d(0.5 * h)?);
    Ok((4.0 * d2 - d1) / 3.0)
}

/// How closely (relative) the closest pair of a [`stable_difference`] with
/// a failed step must agree: a hundredth of the tests' 1e-6 tolerance,
/// so the oracle's own spread cannot pass or fail a derivative.
pub const SKIPPED_STEPS_AGREEMENT: f64 = 1e-8;

/// [`central_difference`] at the step where it is most stable: estimates at
/// `4h, h, h/4, h/16, h/64` are compared pairwise (neighbours), and the
/// smaller-step estimate of the closest pair is returned. Truncation error
/// shrinks with the step and the re-solves' rounding noise grows as it
/// shrinks; the closest neighbours sit where both are small, so strongly
/// curved paths get small steps and flat ones keep large steps.
///
/// A step whose re-solves fail before any smaller one succeeded is skipped:
/// on a strongly curved path (long chains over spheres) `θ ± 4h` can leave
/// Newton's basin of the path, or the configuration space, while the
/// smaller steps stay in it; a failure after a success ends the search.
/// A path with any failed step is near a fold, where the estimates of
/// neighbouring steps can disagree, so its estimate is kept only when the
/// closest pair agrees to [`SKIPPED_STEPS_AGREEMENT`] (relative);
/// otherwise, or when fewer than two neighbouring steps succeed, the path
/// is dropped with the first failed step's reason.
pub fn stable_difference(
    path: &DiffPath,
    table: &ParamTable,
    param: usize,
    h: f64,
    settings: &SolveSettings,
    newton: &NewtonSettings,
) -> Result<DVec2, Dropped> {
    let mut best: Option<(f64, DVec2)> = None;
    let mut prev: Option<DVec2> = None;
    let mut first_failure = None;
    let mut step = 4.0 * h;
    for _ in 0..5 {
        match central_difference(path, table, param, step, settings, newton) {
            Ok(next) => {
                if let Some(prev) = prev {
                    let gap = (next - prev).length();
                    if best.is_none_or(|(g, _)| gap < g) {
                        best = Some((gap, next));
                    }
                }
                prev = Some(next);
            }
            Err(e) => {
                first_failure.get_or_insert(e);
                // Past a success, a failure ends the search (smaller steps
                // than one that fails only add rounding noise).
                if prev.is_some() {
                    break;
                }
            }
        }
        step *= 0.25;
    }
    match (best, first_failure) {
        (Some((_, d)), None) => Ok(d),
        (Some((gap, d)), Some(_)) if gap <= SKIPPED_STEPS_AGREEMENT * d.length() => Ok(d),
        (_, Some(e)) => Err(e),
        // Five steps without a failure leave a closest pair.
        (None, None) => unreachable!("five successful steps compare four pairs"),
    }
}
