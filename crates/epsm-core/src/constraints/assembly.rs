//! Assembly of a path's system at one `(u, θ)`: every node's position,
//! normal and their derivatives (`evaluate`), then `C`, `A = ∂C/∂u` (2k × 2k,
//! constraint `r` on rows `2r, 2r+1`, unknown `q` on columns `2q, 2q+1`) and
//! `B = ∂C/∂θ` (2k × |θ_path|) by chaining each constraint's 2×12 local
//! Jacobian with `∂x/∂u`, `∂n/∂u`, `∂x/∂θ`, `∂n/∂θ` (`assemble`), with the
//! geometric guards of docs/design.md §6 (grazing angles, short segments, total
//! internal reflection, reflection/refraction mismatch, non-finite values).

use glam::DVec3;
use nalgebra::{DMatrix, DVector};

use super::ConstraintKind;
use crate::drops::DropReason;
use crate::motion::Motion;
use crate::paths::{DiffPath, Node};
use crate::pixel::glam3;
use crate::solve::SolveSettings;
use crate::vertex::Anchor;
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
    let mut s = State {
        nodes: Vec::with_capacity(path.nodes.len()),
        grads: Vec::with_capacity(2 * path.nodes.len()),
    };
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
