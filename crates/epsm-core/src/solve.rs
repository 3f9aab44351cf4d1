//! Assembly of `A = ∂C/∂u` and `B = ∂C/∂θ`, the pivoted LU with its
//! conditioning checks, and the adjoint and forward solves (DESIGN §5.5, §6).
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

use crate::constraints::ConstraintKind;
use crate::drops::{DropReason, Dropped};
use crate::motion::Motion;
use crate::paths::{DiffPath, Node};
use crate::pixel::glam3;
use crate::vertex::Anchor;

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

/// One node evaluated at `(u, θ)`.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct NodeEval {
    pub(crate) x: DVec3,
    pub(crate) n: DVec3,
    pub(crate) dx_du: [DVec3; 2],
    pub(crate) dn_du: [DVec3; 2],
}

/// `∂x/∂θ_j`, `∂n/∂θ_j` of one node for path-local parameter `j`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct NodeGrad {
    pub(crate) node: usize,
    pub(crate) j: usize,
    pub(crate) dx: DVec3,
    pub(crate) dn: DVec3,
}

/// Every node of a path at `(u, θ)`.
#[derive(Clone, Debug, Default, PartialEq)]
pub(crate) struct State {
    pub(crate) nodes: Vec<NodeEval>,
    pub(crate) grads: Vec<NodeGrad>,
}

/// Evaluates the nodes at unknowns `u` (`2 × unknowns` values; missing = 0).
pub(crate) fn evaluate(path: &DiffPath, motion: &Motion, u: &[f64]) -> State {
    let local = |param: usize| path.params.binary_search(&param).ok();
    let mut s = State::default();
    for (i, node) in path.nodes.iter().enumerate() {
        let mut push = |j: Option<usize>, dx: DVec3, dn: DVec3| {
            if let Some(j) = j {
                s.grads.push(NodeGrad { node: i, j, dx, dn });
            }
        };
        let eval = match node {
            Node::Camera => {
                for g in &motion.camera.grads {
                    push(local(g.param), glam3(&g.pose.origin), DVec3::ZERO);
                }
                NodeEval {
                    x: glam3(&motion.camera.pose.origin),
                    ..NodeEval::default()
                }
            }
            Node::PointLight(l) => {
                let lm = &motion.lights[*l];
                for g in &lm.grads {
                    push(local(g.param), g.dx, DVec3::ZERO);
                }
                NodeEval {
                    x: lm.position,
                    ..NodeEval::default()
                }
            }
            Node::Surface { anchor, unknown } => {
                let uq = unknown.map_or([0.0; 2], |q| {
                    [0, 1].map(|r| u.get(2 * q + r).copied().unwrap_or(0.0))
                });
                let om = motion.object(anchor.object);
                let vs = anchor.eval(om, uq);
                for g in &om.grads {
                    let [dx, dn] = Anchor::dtheta(&vs, g);
                    push(local(g.param), dx, dn);
                }
                NodeEval {
                    x: vs.x,
                    n: vs.n,
                    dx_du: vs.dx_du,
                    dn_du: vs.dn_du,
                }
            }
        };
        s.nodes.push(eval);
    }
    s
}

/// `C`, `A = ∂C/∂u` and `B = ∂C/∂θ` of a path at one state.
pub(crate) struct System {
    pub(crate) c: DVector<f64>,
    pub(crate) a: DMatrix<f64>,
    pub(crate) b: DMatrix<f64>,
}

/// Assembles the system, applying the geometric guards.
pub(crate) fn assemble(
    path: &DiffPath,
    state: &State,
    settings: &SolveSettings,
) -> Result<System, DropReason> {
    let k = path.unknowns();
    let mut sys = System {
        c: DVector::zeros(2 * k),
        a: DMatrix::zeros(2 * k, 2 * k),
        b: DMatrix::zeros(2 * k, path.params.len()),
    };
    for (r, con) in path.constraints.iter().enumerate() {
        let [ia, ix, ib] = con.nodes;
        let (na, nx, nb) = (&state.nodes[ia], &state.nodes[ix], &state.nodes[ib]);
        guard(&con.kind, na.x - nx.x, nb.x - nx.x, nx.n, settings)?;
        let local = con.local(na.x, nx.x, nb.x, nx.n);
        for row in 0..2 {
            let g = &local.grad[row];
            let rr = 2 * r + row;
            sys.c[rr] = local.value[row];
            for (slot, &node) in con.nodes.iter().enumerate() {
                let ne = &state.nodes[node];
                if let Node::Surface {
                    unknown: Some(q), ..
                } = path.nodes[node]
                {
                    for col in 0..2 {
                        let mut d = g[slot].dot(ne.dx_du[col]);
                        if slot == 1 {
                            d += g[3].dot(ne.dn_du[col]);
                        }
                        sys.a[(rr, 2 * q + col)] += d;
                    }
                }
            }
            for ng in &state.grads {
                if let Some(slot) = con.nodes.iter().position(|&n| n == ng.node) {
                    let mut d = g[slot].dot(ng.dx);
                    if slot == 1 {
                        d += g[3].dot(ng.dn);
                    }
                    sys.b[(rr, ng.j)] += d;
                }
            }
        }
    }
    if sys
        .a
        .iter()
        .chain(sys.b.iter())
        .chain(sys.c.iter())
        .all(|v| v.is_finite())
    {
        Ok(sys)
    } else {
        Err(DropReason::NonFinite)
    }
}

/// Guards of one constraint: `to_a = a − x`, `to_b = b − x`.
fn guard(
    kind: &ConstraintKind,
    to_a: DVec3,
    to_b: DVec3,
    n: DVec3,
    s: &SolveSettings,
) -> Result<(), DropReason> {
    if to_a.length() < s.min_segment || to_b.length() < s.min_segment {
        return Err(DropReason::ShortSegment);
    }
    let (ci, co) = (to_a.normalize().dot(n), to_b.normalize().dot(n));
    match *kind {
        ConstraintKind::Specular { eta, transmit } => {
            if ci.abs() < s.min_cos || co.abs() < s.min_cos {
                return Err(DropReason::Grazing);
            }
            if (ci * co < 0.0) != transmit {
                return Err(DropReason::LobeMismatch);
            }
            if transmit && 1.0 - ci * ci >= eta * eta {
                return Err(DropReason::TotalInternalReflection);
            }
        }
        ConstraintKind::Glossy { .. } => {
            if ci.abs() < s.min_cos || co.abs() < s.min_cos {
                return Err(DropReason::Grazing);
            }
            if ci * co < 0.0 {
                return Err(DropReason::LobeMismatch);
            }
        }
        _ => {}
    }
    Ok(())
}

/// A factored `A` that passed the pivot and condition checks.
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
pub(crate) fn factor(a: &DMatrix<f64>, settings: &SolveSettings) -> Result<Factored, DropReason> {
    let lu = a.clone().full_piv_lu();
    let pivots = lu.u().diagonal().map(f64::abs);
    let (lo, hi) = (pivots.min(), pivots.max());
    if !(lo > settings.min_pivot_ratio * hi) {
        return Err(DropReason::Singular);
    }
    let inverse = lu.try_inverse().ok_or(DropReason::Singular)?;
    let condition = norm1(a) * norm1(&inverse);
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
    let sys = assemble(path, &state, settings)?;
    let f = factor(&sys.a, settings)?;
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
