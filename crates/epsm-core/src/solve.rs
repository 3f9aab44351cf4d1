//! Assembly of `A = ∂C/∂u` and `B = ∂C/∂θ`, the pivoted LU with its
//! conditioning checks, and the adjoint and forward solves (docs/design.md §5.5, §6).
//!
//! - Adjoint (one solve per path): `Aᵀλ = (gᵀ J_π ∂x1/∂u1)ᵀ` on the rows of
//!   `u1`, then `dL/dθ = −λᵀB + gᵀ(J_π ∂x1/∂θ|u + ∂π/∂θ_cam)`.
//! - Forward: `du/dθ = −A⁻¹B`, `dp/dθ = J_π(∂x1/∂u1 du1/dθ + ∂x1/∂θ|u) + ∂π/∂θ_cam`.
//!
//! `A` is factored by full-pivoting LU in `f64`. A path is dropped (and
//! counted) when the smallest pivot is below `min_pivot_ratio` times the
//! largest, when `‖A‖₁‖A⁻¹‖₁ > max_condition`, at grazing specular angles,
//! short segments, total internal reflection, reflection/refraction
//! mismatches, and on any non-finite value.
//!
//! | setting | default | meaning |
//! |---|---|---|
//! | `min_segment` | 1e-6 × scene radius | shortest allowed segment |
//! | `min_cos` | 1e-4 | smallest allowed `|cos|` at S vertices |
//! | `max_condition` | 1e8 | bound on `‖A‖₁‖A⁻¹‖₁` |
//! | `min_pivot_ratio` | 1e-12 | bound on `min |pivot| / max |pivot|` |

use glam::{DVec2, DVec3};
use nalgebra::{DMatrix, DVector};

use crate::constraints::assembly::{State, System, assemble, evaluate};
use crate::drops::{DropReason, Dropped};
use crate::motion::Motion;
use crate::paths::{DiffPath, Node};

/// Bounds of the robustness checks.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SolveSettings {
    /// Shortest allowed segment, scene units.
    pub min_segment: f64,
    /// Smallest allowed `|cos|` of `wi` or `wo` at specular and glossy vertices.
    pub min_cos: f64,
    /// Largest allowed `‖A‖₁‖A⁻¹‖₁`.
    pub max_condition: f64,
    /// Smallest allowed ratio of the smallest to the largest LU pivot.
    pub min_pivot_ratio: f64,
}

impl SolveSettings {
    /// The defaults for a scene of bounding radius `radius`.
    pub fn for_radius(radius: f64) -> Self {
        Self {
            min_segment: 1e-6 * radius,
            min_cos: 1e-4,
            max_condition: 1e8,
            min_pivot_ratio: 1e-12,
        }
    }
}

/// A sparse loss gradient `dL/dθ` of one path.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Gradient {
    /// `(global parameter index, dL/dθ)` for every parameter the path touches.
    pub entries: Vec<(usize, f64)>,
}

/// The 2×k pixel Jacobian `dp/dθ` of one path.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PixelJacobian {
    /// Global parameter indices (the path's).
    pub params: Vec<usize>,
    /// `dp/dθ_k` in pixels per user unit, one column per parameter.
    pub columns: Vec<DVec2>,
}

/// A factored `A` that passed the pivot and condition checks. The inverse is
/// formed explicitly: it gives the exact `‖A⁻¹‖₁` and the adjoint solve
/// `λ = A⁻ᵀ r`; at these sizes (2k ≤ 20) that measured faster than transposed
/// LU solves with a Hager–Higham estimate of `‖A⁻¹‖₁`.
pub(crate) struct Factored {
    lu: nalgebra::linalg::FullPivLU<f64, nalgebra::Dyn, nalgebra::Dyn>,
    inverse: DMatrix<f64>,
    /// `‖A‖₁‖A⁻¹‖₁`.
    pub(crate) condition: f64,
}

fn norm1(m: &DMatrix<f64>) -> f64 {
    m.column_iter()
        .map(|c| c.iter().map(|v| v.abs()).sum::<f64>())
        .fold(0.0, f64::max)
}

/// Factors `A` with full pivoting and checks its conditioning.
pub(crate) fn factor(a: DMatrix<f64>, settings: &SolveSettings) -> Result<Factored, DropReason> {
    let norm_a = norm1(&a);
    let lu = a.full_piv_lu();
    let pivots = lu.u().diagonal().map(f64::abs);
    let (lo, hi) = (pivots.min(), pivots.max());
    // Written so that NaN pivots fail too.
    if lo.is_nan() || lo <= settings.min_pivot_ratio * hi {
        return Err(DropReason::Singular);
    }
    let inverse = lu.try_inverse().ok_or(DropReason::Singular)?;
    let condition = norm_a * norm1(&inverse);
    if !condition.is_finite() {
        return Err(DropReason::NonFinite);
    }
    if condition > settings.max_condition {
        return Err(DropReason::IllConditioned);
    }
    Ok(Factored {
        lu,
        inverse,
        condition,
    })
}

/// The pixel vertex `x1` and, if it is unknown, its column block.
fn pixel_vertex(path: &DiffPath) -> Option<usize> {
    match path.nodes.get(1) {
        Some(Node::Surface { unknown, .. }) => *unknown,
        _ => None,
    }
}

/// `J_π dx + ∂π/∂θ_j` at the pixel vertex (camera pose derivative of global parameter `param`).
fn pixel_d(
    motion: &Motion,
    x1: DVec3,
    dx: DVec3,
    param: Option<usize>,
) -> Result<DVec2, DropReason> {
    let dpose = param
        .and_then(|p| motion.camera.grads.iter().find(|g| g.param == p))
        .map(|g| &g.pose);
    motion
        .camera
        .pose
        .pixel_derivative(x1, dx, dpose)
        .ok_or(DropReason::BehindCamera)
}

/// `∂x1/∂θ_j|u` per path-local parameter.
fn x1_theta(path: &DiffPath, state: &State) -> Vec<DVec3> {
    let mut d = vec![DVec3::ZERO; path.params.len()];
    for g in state.grads.iter().filter(|g| g.node == 1) {
        d[g.j] += g.dx;
    }
    d
}

/// Factors the system of a path at its base (`u = 0`).
fn prepare(
    path: &DiffPath,
    motion: &Motion,
    settings: &SolveSettings,
) -> Result<(State, Option<(System, Factored)>), DropReason> {
    let state = evaluate(path, motion, &[]);
    if path.unknowns() == 0 {
        return Ok((state, None));
    }
    let mut sys = assemble(path, &state, settings)?;
    let f = factor(
        std::mem::replace(&mut sys.a, DMatrix::zeros(0, 0)),
        settings,
    )?;
    Ok((state, Some((sys, f))))
}

/// The loss gradient of one path, `dL/dθ = g·dp/dθ`, by one adjoint solve.
/// `g_xy` is `∂L/∂p` (per pixel).
pub fn solve_adjoint(
    path: &DiffPath,
    g_xy: DVec2,
    motion: &Motion,
    settings: &SolveSettings,
) -> Result<Gradient, Dropped> {
    let (state, sys) = prepare(path, motion, settings)?;
    let x1 = state.nodes[1].x;
    let mut lambda = None;
    if let (Some((_, f)), Some(q)) = (&sys, pixel_vertex(path)) {
        let mut rhs = DVector::zeros(2 * path.unknowns());
        for col in 0..2 {
            rhs[2 * q + col] = g_xy.dot(pixel_d(motion, x1, state.nodes[1].dx_du[col], None)?);
        }
        lambda = Some(f.inverse.tr_mul(&rhs));
    }
    let dx1 = x1_theta(path, &state);
    let mut entries = Vec::with_capacity(path.params.len());
    for (j, &param) in path.params.iter().enumerate() {
        let mut v = g_xy.dot(pixel_d(motion, x1, dx1[j], Some(param))?);
        if let (Some(l), Some((s, _))) = (&lambda, &sys) {
            v -= l.dot(&s.b.column(j));
        }
        if !v.is_finite() {
            return Err(Dropped(DropReason::NonFinite));
        }
        entries.push((param, v));
    }
    Ok(Gradient { entries })
}

/// The pixel Jacobian `dp/dθ` of one path for all its parameters (forward mode).
pub fn solve_forward(
    path: &DiffPath,
    motion: &Motion,
    settings: &SolveSettings,
) -> Result<PixelJacobian, Dropped> {
    let (state, sys) = prepare(path, motion, settings)?;
    let n1 = &state.nodes[1];
    let mut dx1 = x1_theta(path, &state);
    if let (Some((s, f)), Some(q)) = (&sys, pixel_vertex(path)) {
        let du = f.lu.solve(&(-&s.b)).ok_or(Dropped(DropReason::Singular))?;
        for (j, d) in dx1.iter_mut().enumerate() {
            *d += n1.dx_du[0] * du[(2 * q, j)] + n1.dx_du[1] * du[(2 * q + 1, j)];
        }
    }
    let columns = dx1
        .iter()
        .zip(&path.params)
        .map(|(&d, &p)| pixel_d(motion, n1.x, d, Some(p)))
        .collect::<Result<Vec<_>, _>>()?;
    if columns.iter().any(|c| !c.is_finite()) {
        return Err(Dropped(DropReason::NonFinite));
    }
    Ok(PixelJacobian {
        params: path.params.clone(),
        columns,
    })
}

/// `‖A‖₁‖A⁻¹‖₁` of a path at its base (1 for paths without unknowns).
pub fn condition(
    path: &DiffPath,
    motion: &Motion,
    settings: &SolveSettings,
) -> Result<f64, Dropped> {
    Ok(prepare(path, motion, settings)?
        .1
        .map_or(1.0, |(_, f)| f.condition))
}
